//! `dvrk-ident`: the command-line front of the dvrk-ident crates. Each subcommand lives in
//! its own module under `cmd/`, parses its flags, calls the libraries and prints; no
//! algorithm lives here.
//!
//! A library as well as a binary so that the Python wheel carries the same command
//! (`dvrk-ident` and `python -m dvrk_ident` call [`run`] inside the extension module):
//! one behaviour, whichever way it was installed.

// No unsafe code: the workspace's unsafe code is in crates/lapack-faer (the Fortran-ABI
// BLAS/LAPACK Clarabel calls) and crates/dvrk-model-c (the C ABI).
#![forbid(unsafe_code)]

use std::ffi::OsString;

use clap::{CommandFactory, Parser, Subcommand};

mod cmd;
mod progress;

#[derive(Parser)]
#[command(
    name = "dvrk-ident",
    version,
    about = "Dynamic identification of robot arms (dVRK PSM/MTM, DH tables, URDF)"
)]
struct Cli {
    /// No progress bars (they are also hidden when stderr is not a terminal)
    #[arg(long, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Summarize a robot model, or evaluate its regressor or inverse dynamics.
    Model(cmd::model::Args),
    /// Identify the parameters from logs or observation states (OLS, WLS, IRLS or the
    /// physically consistent SDP).
    Fit(cmd::fit::Args),
    /// Reduce logs to an observation state file, the map of a fit over many machines
    /// (`fit --states` merges and fits the states).
    Observe(cmd::observe::Args),
    /// Errors of an identified model on other logs, processed with the result's own
    /// settings (processing flags replace them; the output names what differs).
    Validate(cmd::validate::Args),
    /// Two results side by side: the settings that differ, the parameters with their
    /// uncertainty, and each one's errors on test logs.
    Compare(cmd::compare::Args),
    /// External joint torques of logs: what the identified model does not explain
    /// (τ_measured − τ_model), with the fit's noise floor and the momentum observer's
    /// estimate.
    Residual(cmd::residual::Args),
    /// Identify a rigid payload fixed to a frame (mass, centre of mass, inertia) from logs
    /// of the arm carrying it, the rest of the model held at a result.
    Payload(cmd::payload::Args),
    /// Fit a known-force polynomial (e.g. the MTM joint-4 cable) to a slow two-way sweep.
    CableFit(cmd::cable_fit::Args),
    /// Simulate a log of a robot with known parameters along a Fourier trajectory.
    Simulate(cmd::simulate::Args),
    /// Convert a log between MCAP, headered CSV and the 2019 CSV layout.
    Convert(cmd::convert::Args),
    /// Optimize an excitation trajectory under the limits, or evaluate one.
    Excite(cmd::excite::Args),
    /// Figures and a self-contained HTML report of a result on its logs.
    Report(cmd::report::Args),
    /// Write an identified model as URDF (and/or the 2019 params.json layout).
    Export(cmd::export::Args),
    /// Print the completion script of a shell (bash, zsh, fish, powershell, elvish).
    Completions(cmd::shell::CompletionsArgs),
    /// Print a manual page (roff), or write them all into a folder.
    Man(cmd::shell::ManArgs),
}

/// Runs the command line `args` (the program name first, as `std::env::args_os`
/// gives it) and returns the process's exit status: 0 on success (also when a reader
/// closed the pipe early), 1 with the message on stderr on an error, and clap's own
/// status (2) for a usage error; `--help` and `--version` print and return 0.
pub fn run<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout with status 0, usage errors to stderr.
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    progress::set_quiet(cli.quiet);
    let result = match cli.command {
        Command::Model(args) => cmd::model::run(args),
        Command::Fit(args) => cmd::fit::run(args),
        Command::Observe(args) => cmd::observe::run(args),
        Command::Validate(args) => cmd::validate::run(args),
        Command::Compare(args) => cmd::compare::run(args),
        Command::Residual(args) => cmd::residual::run(args),
        Command::Payload(args) => cmd::payload::run(args),
        Command::CableFit(args) => cmd::cable_fit::run(args),
        Command::Simulate(args) => cmd::simulate::run(args),
        Command::Convert(args) => cmd::convert::run(args),
        Command::Excite(args) => cmd::excite::run(args),
        Command::Report(args) => cmd::report::run(args),
        Command::Export(args) => cmd::export::run(args),
        Command::Completions(args) => cmd::shell::completions(args, Cli::command()),
        Command::Man(args) => cmd::shell::man(args, Cli::command()),
    };
    match result {
        Ok(()) => 0,
        Err(e) if is_broken_pipe(&e) => 0,
        Err(e) => {
            eprintln!("dvrk-ident: error: {}", message(&e));
            1
        }
    }
}

/// The error and its causes, `: `-separated, each cause only when the text so far does
/// not already say it (errors that print their source, e.g. `file: No such file or
/// directory (os error 2)`, would otherwise repeat it).
fn message(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cmd::settings::error_text(cause);
        if text.contains(&c) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&c);
    }
    text
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
