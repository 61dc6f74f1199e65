//! `dvrk-ident residual RESULT LOG...`: the joint torques the identified model does not
//! explain (`τ_measured − τ_model`), per sample, beside the fit's noise floor and the
//! momentum observer's estimate; the computation is `dvrk_ident::residual`.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Result};
use dvrk_ident::log::mcap;
use dvrk_ident::report::residual::residual_report;
use dvrk_ident::residual::{
    external_torque, ResidualOptions, TipWrench, DEFAULT_OBSERVER_GAIN, DEFAULT_WRENCH_RCOND,
    WRENCH_COMPONENTS,
};
use dvrk_ident::validate::JointMap;
use dvrk_ident::Coordinates;
use dvrk_ident::Joints;
use dvrk_logs::output::Outputs;
use serde_json::json;

use super::args::{JointsArgs, MODEL, OUTPUT};
use super::settings::ResultOnLogs;
use super::{emit_summary, LoadedResult};

#[derive(clap::Args)]
#[command(
    allow_negative_numbers = true,
    mut_args = super::args::result_defaults,
    mut_arg("logs", |a| a.help("Logs whose external torques to estimate"))
)]
pub struct Args {
    #[command(flatten)]
    pub on_logs: ResultOnLogs,
    /// Gain of the momentum observer (1/s, every joint; its time constant is 1/gain)
    #[arg(long, default_value_t = DEFAULT_OBSERVER_GAIN, value_name = "PER_S", help_heading = MODEL)]
    pub observer_gain: f64,
    /// Also express the residual as a Cartesian wrench (force N, moment N·m) at this
    /// frame's origin (the PSM's `tool_tip`), in the base frame's and in its own axes:
    /// the least-squares solution of τ_ext = Jᵀ·F, the directions the joints cannot
    /// sense at a pose reported, not estimated
    #[arg(long, value_name = "FRAME", help_heading = MODEL)]
    pub wrench: Option<String>,
    /// Relative threshold of --wrench: a wrench direction whose joint torques are below
    /// this fraction of the best-sensed direction's is unsensed (raise it to drop the
    /// weakly sensed ones near a singular pose)
    #[arg(long, default_value_t = DEFAULT_WRENCH_RCOND, value_name = "RATIO", help_heading = MODEL)]
    pub wrench_rcond: f64,
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
    /// Write the --wrench per processed sample as CSV: time, fx_base … mz_base (base
    /// frame axes), fx_tip … mz_tip (the frame's own axes), rank (the directions sensed,
    /// out of 6); one log only
    #[arg(long, value_name = "FILE.csv", requires = "wrench", help_heading = OUTPUT)]
    pub wrench_out: Option<String>,
    /// Write a report into this folder: report.html with each log's residual and
    /// observer per joint against the fit's noise floor (and the --wrench over time),
    /// and the figures as SVG and PNG
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
            ("--wrench-out", args.wrench_out.as_deref()),
        ],
        &[("--report", args.report.as_deref())],
        &args.on_logs.inputs(&[]),
    )?;
    if (args.out.is_some() || args.observer_out.is_some() || args.wrench_out.is_some())
        && args.on_logs.logs.len() != 1
    {
        bail!(
            "--out, --observer-out and --wrench-out take one log ({} given)",
            args.on_logs.logs.len()
        );
    }
    if let Some(path) = &args.wrench_out {
        if is_mcap(path) {
            bail!("--wrench-out {path}: the wrench is written as CSV (FILE.csv)");
        }
    }
    let LoadedResult {
        result,
        model,
        params,
        ..
    } = args.on_logs.load_with_settings()?;
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
        wrench: args.wrench.clone(),
        wrench_rcond: args.wrench_rcond,
    };
    let read = args
        .on_logs
        .read_options(&model, &result.settings.processing);
    let (mut text, mut reports, mut outputs) = (String::new(), Vec::new(), Outputs::new());
    if let Some(note) = result.offset_note() {
        let _ = writeln!(text, "{note}");
    }
    let mut residuals = Vec::new();
    for path in &args.on_logs.logs {
        let log = super::args::read(&read, path)?;
        let r = external_torque(&model, &params, &result, &log, &options)?;
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
        if let Some(w) = &r.wrench {
            wrench_text(&mut text, w);
            if let Some(out) = &args.wrench_out {
                outputs.add(Path::new(out), w.to_csv(&r.time).into_bytes())?;
            }
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
            "wrench": r.wrench.as_ref().map(|w| json!({
                "frame": w.frame,
                "rcond": w.rcond,
                "components": WRENCH_COMPONENTS,
                "rms_base": TipWrench::rms(&w.in_base),
                "rms_tip": TipWrench::rms(&w.in_tip),
                "min_rank": w.min_rank(),
                "rank_deficient_samples": w.rank_deficient_samples(),
            })),
        }));
        residuals.push(r);
    }
    if let Some(dir) = &args.report {
        let map = JointMap::new(&model, joints)?;
        let report = residual_report(&map, &args.on_logs.result, &residuals, args.observer_gain)?;
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
                "result": args.on_logs.result,
                "observer_gain": args.observer_gain,
                "residuals": reports,
            }))?,
            stdout_taken,
        )
    } else {
        emit_summary(&text, stdout_taken)
    }
}

/// The wrench's RMS per component in both frames' axes and where it was not fully sensed.
fn wrench_text(text: &mut String, w: &TipWrench) {
    let _ = writeln!(text, "wrench at {} (RMS; force N, moment N·m):", w.frame);
    let _ = writeln!(
        text,
        "{:<6} {}",
        "axes",
        WRENCH_COMPONENTS.map(|c| format!("{c:>10}")).join(" ")
    );
    for (axes, m) in [("base", &w.in_base), ("tip", &w.in_tip)] {
        let rms = TipWrench::rms(m);
        let _ = writeln!(
            text,
            "{axes:<6} {}",
            rms.iter()
                .map(|v| format!("{v:>10.5}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    match w.rank_deficient_samples() {
        0 => {
            let _ = writeln!(text, "all six directions sensed at every sample");
        }
        k => {
            let _ = writeln!(
                text,
                "{k} of {} samples sense fewer than six directions (fewest: {}); the \
                 wrench there has no component along the unsensed ones",
                w.rank.len(),
                w.min_rank()
            );
        }
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
