//! `dvrk-ident report RESULT [LOG...] --out DIR` (and `fit --report DIR`): the figures of a
//! result and a self-contained `report.html`.

use std::path::Path;

use anyhow::{bail, Context, Result};
use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::log::ReadOptions;
use dvrk_ident::report::{self, ReportInput, ReportLog};
use dvrk_ident::InputInfo;
use dvrk_ident::{FitResult, FitSettings, JointLog};
use dvrk_logs::output::Outputs;
use dvrk_model::Model;

use super::args::{JointsArgs, INPUT, OUTPUT};
use super::emit;
use super::settings::ResultOnLogs;

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(
    allow_negative_numbers = true,
    mut_args = super::args::result_defaults,
    mut_arg("logs", |a| a.required(false).help(
        "Logs to show [default: the result's own training and test logs, if they exist \
         unchanged]"
    ))
)]
pub struct Args {
    /// Excitation trajectory (JSON of `dvrk-ident excite`) to plot against the limits
    #[arg(long, value_name = "TRAJ.json", help_heading = INPUT)]
    pub excitation: Option<String>,
    #[command(flatten)]
    pub on_logs: ResultOnLogs,
    /// Folder to write report.html and the figures (SVG and PNG) into
    #[arg(long, value_name = "DIR", help_heading = OUTPUT)]
    pub out: String,
    #[command(flatten)]
    pub joints: JointsArgs,
}

/// Builds the report of `result` on `logs` (role, trajectory, metric window) in memory,
/// under a spinner; nothing is written. `read`: how the result's logs were read, for the
/// page's command line.
pub fn build(
    model: &Model,
    result: &FitResult,
    settings: &FitSettings,
    logs: &[(&str, &JointLog, Option<usize>)],
    excitation: Option<&FourierTrajectory>,
    read: &ReadOptions,
) -> Result<report::Report> {
    let input = ReportInput {
        model,
        result,
        logs: logs
            .iter()
            .map(|&(role, trajectory, window)| ReportLog {
                role,
                trajectory,
                window,
            })
            .collect(),
        excitation,
        read: Some(read),
        settings: Some(settings),
    };
    Ok(crate::progress::Bars::new().spin("rendering the report", || report::build(&input))?)
}

pub fn run(args: Args) -> Result<()> {
    let excitation_file = [("the excitation", args.excitation.as_deref())];
    let mut inputs = args.on_logs.inputs(&excitation_file);
    super::check_outputs(&[], &[("--out", Some(&args.out))], &inputs)?;
    let (super::LoadedResult { result, model, .. }, mut settings) = args.on_logs.load()?;
    settings.test_window = result.settings.test_window;
    if let Some(note) = super::settings_note(&settings.differences(&result.settings)) {
        eprintln!("{note}");
    }
    if let Some(j) = args.joints.joints {
        settings.joints = j;
    }
    let sources: Vec<(String, String)> = if args.on_logs.logs.is_empty() {
        // The result's own logs, as they were when fitted: a missing one or one whose
        // content changed is an error, not a figure silently dropped or drawn from other
        // data.
        for i in &result.inputs {
            let now = InputInfo::from_file(&i.role, Path::new(&i.path)).with_context(|| {
                format!(
                    "{}: the result's {} log is not readable: give the logs to draw \
                     (dvrk-ident report RESULT LOG...)",
                    args.on_logs.result, i.role
                )
            })?;
            if now.sha256 != i.sha256 {
                bail!(
                    "{}: the result's {} log {} changed since the fit (SHA-256 {} instead of \
                     {}): give the logs to draw explicitly to draw it anyway",
                    args.on_logs.result,
                    i.role,
                    i.path,
                    now.sha256,
                    i.sha256
                );
            }
        }
        result
            .inputs
            .iter()
            .map(|i| (i.role.clone(), i.path.clone()))
            .collect()
    } else {
        args.on_logs
            .logs
            .iter()
            .enumerate()
            .map(|(k, p)| (format!("log {}", k + 1), p.clone()))
            .collect()
    };
    // The result's own logs are inputs too.
    for (_, p) in &sources {
        inputs.add_log(Path::new(p));
    }
    let read = args.on_logs.log_args.read_options_for(
        &model,
        &settings.processing,
        sources.iter().map(|(_, p)| p.as_str()),
    );
    let mut trajectories = Vec::new();
    for (role, path) in &sources {
        trajectories.push((role.clone(), super::args::read(&read, path)?));
    }
    let logs: Vec<(&str, &JointLog, Option<usize>)> = trajectories
        .iter()
        .map(|(role, t)| {
            let window = if role == "test" {
                result.settings.test_window
            } else {
                None
            };
            (role.as_str(), t, window)
        })
        .collect();
    let excitation = match &args.excitation {
        Some(p) => {
            Some(FourierTrajectory::from_json_file(p).with_context(|| format!("{p}: excitation"))?)
        }
        None => None,
    };
    let built = build(
        &model,
        &result,
        &settings,
        &logs,
        excitation.as_ref(),
        &args.on_logs.log_args.read_options(),
    )?;
    let mut outputs = Outputs::protecting(inputs);
    let written = built.stage(&mut outputs, Path::new(&args.out))?;
    outputs.commit()?;
    eprintln!("report: {} files", written.len());
    emit(
        &Path::new(&args.out)
            .join("report.html")
            .display()
            .to_string(),
    )
}
