//! `dvrk-ident residual RESULT LOG...`: the joint torques the identified model does not
//! explain (`τ_measured − τ_model`), per sample, beside the fit's noise floor and the
//! momentum observer's estimate; the computation is `dvrk_ident::residual`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Result};
use dvrk_ident::fit::JointMap;
use dvrk_ident::joint_log::Coordinates;
use dvrk_ident::log::mcap;
use dvrk_ident::output::Outputs;
use dvrk_ident::report::residual::residual_report;
use dvrk_ident::residual::{external_torque, ResidualOptions, DEFAULT_OBSERVER_GAIN};
use dvrk_ident::settings::Joints;
use serde_json::json;

use super::args::{JointsArgs, LogArgs, MODEL, OUTPUT};
use super::settings::{Processing, SettingFlags};
use super::{emit_summary, load_result, LoadedResult};

#[derive(clap::Args)]
#[command(allow_negative_numbers = true, mut_args = super::args::result_defaults)]
pub struct Args {
    /// Result file written by `dvrk-ident fit --out`
    pub result: String,
    /// Logs whose external torques to estimate
    #[arg(required = true, value_name = "LOG")]
    pub logs: Vec<String>,
    /// Robot [default: the one the result was fitted for]
    #[arg(long, help_heading = MODEL)]
    pub robot: Option<String>,
    /// Gain of the momentum observer (1/s, every joint; its time constant is 1/gain)
    #[arg(long, default_value_t = DEFAULT_OBSERVER_GAIN, value_name = "PER_S", help_heading = MODEL)]
    pub observer_gain: f64,
    // The processing flags default to the result's own settings, as for validate.
    // The fit options (`--method`, `--cutoff`, ...: every library `Setting`), before
    // `log_args`: they read `--resample`, which `log_args` declares and takes.
    #[command(flatten)]
    pub settings: SettingFlags<Processing>,
    #[command(flatten)]
    pub log_args: LogArgs,
    #[command(flatten)]
    pub joints: JointsArgs,
    /// Write the residual per processed sample: CSV (time, then one column per joint:
    /// the `simulate --external-torque` layout), or for a `.mcap` file a ROS 2 MCAP of
    /// `sensor_msgs/JointState` on /residual (the processed positions and velocities,
    /// the residual as the effort; measured joints only, `--joints measured`); one log
    /// only
    #[arg(long, value_name = "FILE.csv|FILE.mcap", help_heading = OUTPUT)]
    pub out: Option<String>,
    /// Write the momentum observer's estimate in the same layouts (MCAP topic
    /// /residual_observer); one log only
    #[arg(long, value_name = "FILE.csv|FILE.mcap", help_heading = OUTPUT)]
    pub observer_out: Option<String>,
    /// Write a report into this folder: report.html with each log's residual and
    /// observer per joint against the fit's noise floor, and the figures as SVG and PNG
    #[arg(long, value_name = "DIR", help_heading = OUTPUT)]
    pub report: Option<String>,
    /// Print JSON
    #[arg(long, help_heading = OUTPUT)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(
        &[
            ("--out", args.out.as_deref()),
            ("--observer-out", args.observer_out.as_deref()),
        ],
        &[("--report", args.report.as_deref())],
        &super::inputs(
            &args.logs.iter().map(String::as_str).collect::<Vec<_>>(),
            &[
                ("the result", Some(&args.result)),
                ("the robot", args.robot.as_deref()),
            ],
        ),
    )?;
    if (args.out.is_some() || args.observer_out.is_some()) && args.logs.len() != 1 {
        bail!(
            "--out and --observer-out take one log ({} given)",
            args.logs.len()
        );
    }
    let LoadedResult {
        result,
        model,
        params,
        ..
    } = load_result(&args.result, args.robot.as_deref())?;
    let mut result = result;
    result.settings = args.settings.settings(result.settings.clone())?;
    let joints = args.joints.joints.unwrap_or(result.settings.joints);
    for (flag, path) in [("--out", &args.out), ("--observer-out", &args.observer_out)] {
        if let Some(path) = path {
            if is_mcap(path) && joints != Joints::Measured {
                bail!(
                    "{flag} {path}: an MCAP JointState holds measured joints, but the residual \
                     is in the model coordinates: add --joints measured (or write CSV)"
                );
            }
        }
    }
    let options = ResidualOptions {
        joints: args.joints.joints,
        observer_gain: args.observer_gain,
    };
    let read = args.log_args.read_options_for(
        &model,
        &result.settings.processing,
        args.logs.iter().map(String::as_str),
    );
    let (mut text, mut reports, mut outputs) = (String::new(), Vec::new(), Outputs::new());
    if let Some(note) = result.offset_note() {
        let _ = writeln!(text, "{note}");
    }
    let mut residuals = Vec::new();
    for path in &args.logs {
        let traj = super::args::read(&read, path)?;
        let r = external_torque(&model, &params, &result, &traj, &options)?;
        let observer_rms = r.observer_rms();
        let width = super::joint_width(&r.joints);
        let _ = writeln!(
            text,
            "{path} ({} samples): RMS of τ_measured − τ_model",
            r.time.len()
        );
        let _ = writeln!(
            text,
            "{:<width$} {:>12} {:>12} {:>12}",
            "joint", "residual", "observer", "noise floor"
        );
        for (j, name) in r.joints.iter().enumerate() {
            let floor = match &r.noise_floor {
                Some(f) => format!("{:.5}", f[j]),
                None => "n/a".into(),
            };
            let _ = writeln!(
                text,
                "{name:<width$} {:>12.5} {:>12.5} {floor:>12}",
                r.rms[j], observer_rms[j]
            );
        }
        if r.noise_floor.is_none() {
            let _ = writeln!(
                text,
                "(no noise floor: the fit's errors are in its own joints; --joints {} shows it)",
                result.settings.joints.name()
            );
        }
        for (out, observer, topic) in [
            (&args.out, false, "/residual"),
            (&args.observer_out, true, "/residual_observer"),
        ] {
            let Some(out) = out else { continue };
            let bytes = if is_mcap(out) {
                mcap_bytes(&r.to_log(Coordinates::Measured, observer), topic)?
            } else if observer {
                r.observer_series().to_csv(&r.joints).into_bytes()
            } else {
                r.external_series().to_csv(&r.joints).into_bytes()
            };
            outputs.add(Path::new(out), bytes)?;
        }
        reports.push(json!({
            "log": path,
            "samples": r.time.len(),
            "joints": r.joints,
            "rms": r.rms,
            "observer_rms": observer_rms,
            "noise_floor": r.noise_floor,
        }));
        residuals.push(r);
    }
    if let Some(dir) = &args.report {
        let map = JointMap::new(&model, joints)?;
        let report = residual_report(&map, &args.result, &residuals, args.observer_gain)?;
        report.stage(&mut outputs, Path::new(dir))?;
        let _ = writeln!(
            text,
            "report: {}",
            Path::new(dir).join("report.html").display()
        );
    }
    outputs.commit()?;
    if args.json {
        emit_summary(
            &serde_json::to_string_pretty(&json!({
                "result": args.result,
                "observer_gain": args.observer_gain,
                "residuals": reports,
            }))?,
            stdout_taken,
        )
    } else {
        emit_summary(&text, stdout_taken)
    }
}

/// Whether `path` names an MCAP file (by its extension).
fn is_mcap(path: &str) -> bool {
    Path::new(path)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

/// `log` as the bytes of an MCAP file on `topic`, written by the log writer (which
/// needs a seekable file: a scratch file in the temporary folder, removed after), so
/// that it is staged with the command's other outputs.
fn mcap_bytes(log: &dvrk_ident::JointLog, topic: &str) -> Result<Vec<u8>> {
    static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let scratch = std::env::temp_dir().join(format!(
        "dvrk-ident-residual-{}-{}.mcap",
        std::process::id(),
        COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    let written = mcap::write_mcap(&scratch, log, topic, &mcap::McapWriteOptions::default())
        .map_err(anyhow::Error::from)
        .and_then(|()| Ok(std::fs::read(&scratch)?));
    let _ = std::fs::remove_file(&scratch);
    written
}
