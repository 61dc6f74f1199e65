//! The `dvrk-ident` binary: the command line of [`dvrk_cli::run`].

// No unsafe code: the workspace's unsafe code is in crates/lapack-faer (the Fortran-ABI
// BLAS/LAPACK Clarabel calls) and crates/dvrk-model-c (the C ABI).
#![forbid(unsafe_code)]

use std::process::ExitCode;

fn main() -> ExitCode {
    // An interrupted run (Ctrl-C, `kill`, a closed terminal) removes its temporary files
    // (decompressed recordings, outputs not yet in place) and exits with 128 + the
    // signal's number, as a shell reports a process the signal ended; without this the
    // signal would end the process with them left behind. If the signals cannot be
    // taken, the run goes on as before.
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
        std::thread::spawn(move || {
            if let Some(signal) = signals.forever().next() {
                dvrk_logs::temporary::remove_all();
                eprintln!("dvrk-ident: interrupted (its temporary files are removed)");
                std::process::exit(128 + signal);
            }
        });
    }
    ExitCode::from(dvrk_cli::run(std::env::args_os()))
}
