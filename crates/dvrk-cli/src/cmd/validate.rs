//! `dvrk-ident validate RESULT LOG...`: errors of an identified model on other logs.

use std::fmt::Write as _;

use anyhow::Result;
use dvrk_ident::validate::{joint_metrics, prepare, JointMap};
use serde_json::json;

use super::args::{JointsArgs, INPUT, OUTPUT};
use super::settings::ResultOnLogs;
use super::{emit, LoadedResult};

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(
    allow_negative_numbers = true,
    mut_args = super::args::result_defaults,
    mut_arg("logs", |a| a.help("Logs to validate on"))
)]
pub struct Args {
    /// Metrics on the first N processed samples only (N ≥ 1) [default: every sample]
    #[arg(long, value_parser = super::at_least_one, value_name = "N", help_heading = INPUT)]
    pub test_window: Option<usize>,
    #[command(flatten)]
    pub on_logs: ResultOnLogs,
    #[command(flatten)]
    pub joints: JointsArgs,
    /// Print JSON
    #[arg(long, help_heading = OUTPUT)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    // The processing the result was fitted with, unless overridden on the command line.
    let (
        LoadedResult {
            result,
            model,
            params,
            ..
        },
        mut settings,
    ) = args.on_logs.load()?;
    // Flags that change the processing make this log's column differ from the fit's
    // columns beside it for a reason other than the model: said first. (Other joints
    // only leave the fit's columns out.)
    let changed = settings.differences(&result.settings);
    if let Some(j) = args.joints.joints {
        settings.joints = j;
    }
    let joints = JointMap::new(&model, settings.joints)?;
    let mut reports = Vec::new();
    let mut text = String::new();
    if let Some(note) = super::settings_note(&changed) {
        let _ = writeln!(text, "{note}");
    }
    if let Some(note) = result.offset_note() {
        let _ = writeln!(text, "{note}");
    }
    let read = args.on_logs.read_options(&model, &settings.processing);
    for path in &args.on_logs.logs {
        let log = super::args::read(&read, path)?;
        let data = prepare(&model, &log, &settings.processing)?;
        let m = joint_metrics(&model, &params, &data, args.test_window, &joints)?;
        m.check_finite(path)?;
        // Beside the fit's own training (and test) errors, so a held-out log reads
        // against them joint by joint (when they are in the same joints).
        let mut sets = vec![("fit train", &result.metrics.train)];
        if let Some(t) = &result.metrics.test {
            sets.push(("fit test", t));
        }
        sets.retain(|(_, s)| s.joints == m.joints);
        sets.push(("this log", &m));
        let width = super::joint_width(&m.joints);
        let _ = writeln!(text, "{path} ({} samples)", m.samples);
        let _ = write!(text, "{:<width$}", "joint");
        for (name, _) in &sets {
            let _ = write!(text, " {:>14} {:>10}", format!("{name} rel"), "rms");
        }
        let _ = writeln!(text);
        for (j, name) in m.joints.iter().enumerate() {
            let _ = write!(text, "{name:<width$}");
            for (_, s) in &sets {
                let _ = write!(text, " {:>14.4} {:>10.4}", s.relative_error[j], s.rms[j]);
            }
            let _ = writeln!(text);
        }
        reports.push(json!({"log": path, "metrics": m}));
    }
    if args.json {
        emit(&serde_json::to_string_pretty(&json!({
            "result": args.on_logs.result,
            "fit": result.metrics,
            "settings_differences": changed,
            "validations": reports,
        }))?)
    } else {
        emit(&text)
    }
}
