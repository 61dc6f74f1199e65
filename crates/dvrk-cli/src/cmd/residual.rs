//! `dvrk-ident residual RESULT LOG...`: the joint torques the identified model does not
//! explain (`τ_measured − τ_model`), per sample, beside the fit's noise floor and the
//! momentum observer's estimate; the computation is `dvrk_ident::residual`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Result};
use dvrk_ident::output::Outputs;
use dvrk_ident::residual::{external_torque, ResidualOptions, DEFAULT_OBSERVER_GAIN};
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
    /// Write the residual per processed sample as CSV (time, then one column per joint:
    /// the `simulate --external-torque` layout); one log only
    #[arg(long, value_name = "FILE.csv", help_heading = OUTPUT)]
    pub out: Option<String>,
    /// Write the momentum observer's estimate as CSV, in the same layout; one log only
    #[arg(long, value_name = "FILE.csv", help_heading = OUTPUT)]
    pub observer_out: Option<String>,
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
        &[],
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
    let options = ResidualOptions {
        joints: args.joints.joints,
        observer_gain: args.observer_gain,
    };
    let read = args
        .log_args
        .read_options()
        .for_model(&model)
        .for_processing(&result.settings.processing)
        .for_logs(args.logs.iter().map(Path::new));
    let (mut text, mut reports, mut outputs) = (String::new(), Vec::new(), Outputs::new());
    for path in &args.logs {
        let traj = super::args::read(&read, path)?;
        let r = external_torque(&model, &params, &result, &traj, &options)?;
        let observer_rms: Vec<f64> = (0..r.joints.len())
            .map(|j| (r.observer.column(j).norm_squared() / r.time.len().max(1) as f64).sqrt())
            .collect();
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
        if let Some(out) = &args.out {
            outputs.add(Path::new(out), r.external_series().to_csv(&r.joints))?;
        }
        if let Some(out) = &args.observer_out {
            outputs.add(Path::new(out), r.observer_series().to_csv(&r.joints))?;
        }
        reports.push(json!({
            "log": path,
            "samples": r.time.len(),
            "joints": r.joints,
            "rms": r.rms,
            "observer_rms": observer_rms,
            "noise_floor": r.noise_floor,
        }));
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
