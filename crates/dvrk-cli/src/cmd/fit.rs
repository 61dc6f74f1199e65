//! `dvrk-ident fit LOG --robot ROBOT ...`: identification from a log.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Context, Result};
use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::fit::delay::DelayOption;
use dvrk_ident::fit::stream::{fit_stream_logs, BLOCK_SAMPLES};
use dvrk_ident::fit::{fit_logs, LogData};
use dvrk_ident::log::mcap::{McapOptions, TimeSource};
use dvrk_ident::log::{self, LogFormat, LogReader};
use dvrk_ident::output::Outputs;
use dvrk_ident::signal::Cutoff;
use dvrk_ident::state::ObservationState;
use dvrk_ident::{BoundsSet, FitResult, FitSettings, Method, Trajectory};
use dvrk_model::Model;

use super::emit;

/// MCAP reading options, and resampling for every format.
#[derive(clap::Args, Clone, Default)]
pub struct McapArgs {
    /// MCAP: sensor_msgs/msg/JointState topic to read; repeat to merge topics (the first
    /// is the clock, e.g. --topic /PSM1/measured_js --topic /PSM1/jaw/measured_js).
    /// Default: the topic with positions and efforts (ending in measured_js if several)
    #[arg(long = "topic", value_name = "TOPIC")]
    pub topics: Vec<String>,
    /// Recordings: sample times from the JointState header stamps (when the controller
    /// measured the joints), or the recorder's log times or the publish times
    #[arg(long, value_parser = super::named::<TimeSource>(), default_value = "header")]
    pub time: TimeSource,
    /// Resample to this uniform rate (Hz) by linear interpolation before anything else
    /// (bridges gaps and jitter; without it such logs are refused)
    #[arg(long, value_name = "HZ")]
    pub resample: Option<f64>,
    /// The robot's measured joints, for the automatic topic choice (set by the commands
    /// that know the robot, see [`LogArgs::for_robot`]).
    #[arg(skip)]
    pub joints: Vec<String>,
}

impl McapArgs {
    pub fn options(&self) -> McapOptions {
        McapOptions {
            topics: self.topics.clone(),
            time_source: self.time,
            resample_hz: self.resample,
            joints: self.joints.clone(),
        }
    }
}

/// The format of `path` (given, or from its content); `--topic` only for recordings.
fn log_format(path: &str, format: Option<LogFormat>, mcap: &McapArgs) -> Result<LogFormat> {
    let format = match format {
        Some(f) => f,
        None => log::detect_format(path)?,
    };
    if !mcap.topics.is_empty() && !format.has_topics() {
        bail!("{path}: --topic applies to recordings (MCAP, rosbag2, sqlite3, ROS 1 bags) only, this is a {format} log");
    }
    Ok(format)
}

/// Reads a log in `format` (default: from its content) with the recording options of
/// `mcap`; `--resample` applies to every format (recordings while reading).
pub fn read_log(
    path: &str,
    format: Option<LogFormat>,
    rate: Option<f64>,
    mcap: &McapArgs,
) -> Result<dvrk_ident::Trajectory> {
    let format = log_format(path, format, mcap)?;
    let traj = crate::progress::Bars::new().spin(&format!("reading {path}"), || {
        log::read_with(path, Some(format), rate, &mcap.options())
    })?;
    Ok(traj)
}

/// Options shared by every command that reads logs.
#[derive(clap::Args, Clone)]
pub struct LogArgs {
    /// Log format (default: from the file's content); wpi is the 2019 headerless CSV
    #[arg(long, value_parser = super::named::<LogFormat>())]
    pub format: Option<LogFormat>,
    /// Sampling rate of logs without time stamps (Hz)
    #[arg(long)]
    pub rate: Option<f64>,
    /// Low-pass cut-off (Hz) of the positions, velocities and accelerations, zero-phase
    /// 6th-order Butterworth; one value or one per coordinate, comma-separated, or
    /// `none` (no filter). The 2019 PSM/MTM fits effectively used 16.965/5.655.
    #[arg(long)]
    pub cutoff: Option<String>,
    /// Also low-pass the torques, as the 2019 protocol did (it smooths the Coulomb
    /// friction steps on the measured side only, which biases the friction estimates)
    #[arg(long)]
    pub filter_torque: bool,
    /// Samples trimmed at each end after filtering
    #[arg(long)]
    pub trim: Option<usize>,
    #[command(flatten)]
    pub mcap: McapArgs,
}

impl LogArgs {
    pub fn read(&self, path: &str) -> Result<dvrk_ident::Trajectory> {
        read_log(path, self.format, self.rate, &self.mcap)
    }

    /// Opens a log for reading block by block (the checks of [`LogArgs::read`]).
    pub fn open(&self, path: &str) -> Result<LogReader> {
        let format = log_format(path, self.format, &self.mcap)?;
        Ok(LogReader::open(
            path,
            Some(format),
            self.rate,
            &self.mcap.options(),
        )?)
    }

    /// These options for reading `model`'s logs: its measured joints guide the
    /// automatic topic choice (a dVRK 2.x PSM's arm and jaw topics are paired).
    pub fn for_robot(&self, model: &Model) -> LogArgs {
        let mut args = self.clone();
        args.mcap.joints.clone_from(&model.measured.joints);
        args
    }

    pub fn settings(&self, base: FitSettings) -> Result<FitSettings> {
        let mut s = base;
        if let Some(c) = &self.cutoff {
            let cutoff = Cutoff::parse_flag(c).map_err(|e| anyhow::anyhow!("--cutoff: {e}"))?;
            s.processing.set_cutoff(cutoff);
        }
        if let Some(t) = self.trim {
            s.processing.trim = t;
        }
        if self.filter_torque {
            s.processing.filter_torque = true;
        }
        Ok(s)
    }
}

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Training logs: files (2019 CSV, headered CSV, MCAP, sqlite3 .db3, ROS 1 .bag) or
    /// rosbag2 folders, recognized by content. Each is processed on its own (filters
    /// and trimming never cross from one to the next), their observations merged
    #[arg(required_unless_present = "from", num_args = 1.., value_name = "LOG")]
    pub logs: Vec<String>,
    /// Observation states of `dvrk-ident observe` (the reduce): merged in order and
    /// fitted, with their processing settings and robot; the same document as the fit
    /// of their logs
    #[arg(long, num_args = 1.., value_name = "STATE", conflicts_with_all = ["logs", "stream", "report", "stribeck", "delay"])]
    pub from: Vec<String>,
    /// Built-in robot (psm, psm_simplified, mtm) or a description/URDF path (with
    /// --from: default the states' robot, and it must be the robot they were observed with)
    #[arg(long, required_unless_present = "from")]
    pub robot: Option<String>,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// Estimator
    #[arg(long, value_parser = super::named::<Method>(), default_value = "sdp")]
    pub method: Method,
    /// Lower bounds of the semidefinite fit on friction and motor inertias, in place of
    /// the robot description's: `physical` (friction ≥ 0, motor inertia ≥ 1e-6) or `2019` (≥ 0.001, to reproduce the
    /// 2019 fit). Default: the description's (the built-in robots: physical)
    #[arg(long, value_parser = super::named::<BoundsSet>(), value_name = "SET")]
    pub bounds: Option<BoundsSet>,
    /// Measurement delay of the torques: `auto` (estimated per coordinate within
    /// 0–0.150 s with the parameters, recorded in the result), `0` (none, the default)
    /// or seconds, one for all coordinates or one per coordinate `d1,d2,...`
    #[arg(long, value_name = "auto|D|D1,D2,...")]
    pub delay: Option<String>,
    /// Test (validation) logs: `--test a b` or `--test a --test b`
    #[arg(long, num_args = 1.., value_name = "LOG")]
    pub test: Vec<String>,
    /// Metrics on the first N processed samples of each test log only (N ≥ 1)
    #[arg(long, value_parser = super::at_least_one)]
    pub test_window: Option<usize>,
    /// The excitation trajectory the logs follow (JSON of `dvrk-ident excite`): drawn in
    /// --report, and with --test but no --test-window the test metrics cover its first
    /// period (the 2019 protocol)
    #[arg(long, value_name = "TRAJ.json")]
    pub excitation: Option<String>,
    /// Write the result document here (atomically)
    #[arg(long)]
    pub out: Option<String>,
    /// Also write the parameters in the 2019 package's params.json layout (atomically)
    #[arg(long)]
    pub wpi_json: Option<String>,
    /// Add a Stribeck friction term Fs·sign(v)·exp(-(v/VS)²) with this velocity (rad/s
    /// or m/s) to every friction element (parameters Fs<frame>)
    #[arg(long, value_name = "VS")]
    pub stribeck: Option<f64>,
    /// Also write figures and report.html into this folder (see `dvrk-ident report`)
    #[arg(long, value_name = "DIR")]
    pub report: Option<String>,
    /// Print the result document to stdout instead of the table
    #[arg(long)]
    pub json: bool,
    /// Read the logs from disk block by block, in memory independent of their length,
    /// instead of loading them (several passes over the files; the same result).
    /// Automatic for a log larger than 256 MiB
    #[arg(long)]
    pub stream: bool,
}

/// Logs larger than this are fitted streamed (`--stream`): about a tenth of this
/// machine's memory in samples and their processed copies.
pub const STREAM_ABOVE_BYTES: u64 = 256 << 20;

/// Whether a log (its files, for a rosbag2 folder) is large enough to be streamed (a
/// log that cannot be examined is read the usual way, which reports the problem).
pub fn is_large(path: &str) -> bool {
    log::files_of(path).is_ok_and(|files| {
        files
            .iter()
            .filter_map(|f| std::fs::metadata(f).ok())
            .map(|m| m.len())
            .sum::<u64>()
            > STREAM_ABOVE_BYTES
    })
}

/// The logs read from `paths`, for the fit and its provenance.
pub fn log_data<'a>(data: &'a [dvrk_ident::Trajectory], paths: &'a [String]) -> Vec<LogData<'a>> {
    data.iter()
        .zip(paths)
        .map(|(samples, path)| LogData {
            samples,
            file: Some(Path::new(path)),
        })
        .collect()
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(
        &[
            ("--out", args.out.as_deref()),
            ("--wpi-json", args.wpi_json.as_deref()),
        ],
        &[("--report", args.report.as_deref())],
    )?;
    if stdout_taken && args.json {
        bail!("--json prints the result to stdout, and so does an output `-`: give one of them");
    }
    let excitation = match &args.excitation {
        Some(p) => Some(
            dvrk_ident::excite::FourierTrajectory::from_json_file(p)
                .with_context(|| format!("{p}: excitation"))?,
        ),
        None => None,
    };
    let bars = crate::progress::Bars::new();
    let (model, settings, result, in_memory) = if args.from.is_empty() {
        fit_logs_arg(&args, excitation.as_ref(), &bars)?
    } else {
        fit_states(&args, excitation.as_ref(), &bars)?
    };
    if result.solver.converged {
        // Every output built and staged before the first is put in place.
        let mut outputs = Outputs::new();
        let mut report_note = None;
        if let Some(out) = &args.out {
            outputs.add(Path::new(out), result.to_json())?;
        }
        if let Some(out) = &args.wpi_json {
            let params = result.params_for(&model)?;
            let doc = dvrk_ident::result::wpi_params_json(&model, &params);
            outputs.add(Path::new(out), serde_json::to_string_pretty(&doc)?)?;
        }
        if let (Some(dir), Some((train, test))) = (&args.report, &in_memory) {
            let roles = |role: &str, count: usize| -> Vec<String> {
                (1..=count)
                    .map(|k| {
                        if count == 1 {
                            role.to_string()
                        } else {
                            format!("{role} {k}")
                        }
                    })
                    .collect()
            };
            let train_roles = roles("training", train.len());
            let test_roles = roles("test", test.len());
            let mut logs: Vec<(&str, &dvrk_ident::Trajectory, Option<usize>)> = Vec::new();
            for (role, t) in train_roles.iter().zip(train) {
                logs.push((role, t, None));
            }
            for (role, t) in test_roles.iter().zip(test) {
                logs.push((role, t, settings.test_window));
            }
            let built = super::report::build(&model, &result, &logs, excitation.as_ref())?;
            let written = built.stage(&mut outputs, Path::new(dir))?;
            report_note = Some(format!(
                "report: {} ({} files)",
                Path::new(dir).join("report.html").display(),
                written.len()
            ));
        }
        outputs.commit()?;
        if let Some(note) = report_note {
            eprintln!("{note}");
        }
    }
    if args.json {
        emit(&result.to_json())?;
    } else {
        super::emit_summary(&table(&result), stdout_taken)?;
    }
    if !result.solver.converged {
        bail!(
            "the solver did not converge (status {}): the parameters are not a result",
            result.solver.status
        );
    }
    Ok(())
}

/// The estimator settings of the command line (method, test window).
fn estimator(args: &Args) -> FitSettings {
    FitSettings {
        method: args.method,
        test_window: args.test_window,
        bounds: args.bounds,
        ..FitSettings::default()
    }
}

/// Logs read into memory, in order.
fn read_all(readers: &[LogReader], bars: &crate::progress::Bars) -> Result<Vec<Trajectory>> {
    readers
        .iter()
        .map(|r| {
            let name = format!("reading {}", r.path().display());
            Ok(bars.spin(&name, || r.read_all())?)
        })
        .collect()
}

/// With --excitation and test logs but no --test-window: the samples of one period of
/// the trajectory at the first test log's rate, as in 2019.
fn excitation_window(
    args: &Args,
    excitation: Option<&FourierTrajectory>,
    test: &[Trajectory],
    settings: &FitSettings,
) -> Result<Option<usize>> {
    if let (None, Some(traj), Some(t)) = (args.test_window, excitation, test.first()) {
        let rate = t
            .rate_hz()
            .context("the test log has no usable time stamps")?;
        // int(rate / f0) as in 2019 (1111 samples for the PSM at 200 Hz, 0.18 Hz).
        let samples = (traj.period_s() * rate + 1e-9).floor() as usize;
        return Ok(Some(samples / settings.processing.decimate.max(1)));
    }
    Ok(settings.test_window)
}

/// The logs in memory (for --report) when the fit read them so.
type InMemory = Option<(Vec<Trajectory>, Vec<Trajectory>)>;

/// `fit LOG...`: the model, the settings, the result and the logs if held in memory.
fn fit_logs_arg(
    args: &Args,
    excitation: Option<&FourierTrajectory>,
    bars: &crate::progress::Bars,
) -> Result<(Model, FitSettings, FitResult, InMemory)> {
    let robot = args
        .robot
        .as_deref()
        .expect("clap requires --robot without --from");
    let model = Model::load(robot)?;
    let mut settings = args.log_args.settings(estimator(args))?;
    settings.stribeck_velocity = args.stribeck;
    if let Some(d) = &args.delay {
        d.parse::<DelayOption>()
            .and_then(|d| d.apply(&mut settings, model.dof()))
            .map_err(|e| anyhow::anyhow!("--delay: {e}"))?;
    }
    let model = settings.model(&model)?.into_owned();
    let stream = args.stream || args.logs.iter().chain(&args.test).any(|p| is_large(p));
    if stream && args.report.is_some() {
        bail!(
            "--report draws the logs, which a streamed fit does not hold in memory: \
             fit with --out, then run `dvrk-ident report RESULT LOG` on a shorter log"
        );
    }
    if stream && excitation.is_some() && !args.test.is_empty() && args.test_window.is_none() {
        bail!("a streamed fit with --excitation needs --test-window (samples of one period)");
    }
    let log_args = args.log_args.for_robot(&model);
    let open = |paths: &[String]| -> Result<Vec<LogReader>> {
        paths.iter().map(|p| log_args.open(p)).collect()
    };
    let train = open(&args.logs)?;
    let test = open(&args.test)?;
    if stream {
        let result = fit_stream_logs(
            &model,
            &train.iter().collect::<Vec<_>>(),
            &test.iter().collect::<Vec<_>>(),
            &settings,
            BLOCK_SAMPLES,
            bars,
        )?;
        return Ok((model, settings, result, None));
    }
    let train_data = read_all(&train, bars)?;
    let test_data = read_all(&test, bars)?;
    settings.test_window = excitation_window(args, excitation, &test_data, &settings)?;
    let result = fit_logs(
        &model,
        &log_data(&train_data, &args.logs),
        &log_data(&test_data, &args.test),
        &settings,
        bars,
    )?;
    Ok((model, settings, result, Some((train_data, test_data))))
}

/// `fit --from STATE...`: the states merged in order, fitted, validated on the test
/// logs (read in memory, processed with the states' settings).
fn fit_states(
    args: &Args,
    excitation: Option<&FourierTrajectory>,
    bars: &crate::progress::Bars,
) -> Result<(Model, FitSettings, FitResult, InMemory)> {
    let l = &args.log_args;
    if l.cutoff.is_some() || l.trim.is_some() || l.filter_torque {
        bail!(
            "--from: the processing (--cutoff, --trim, --filter-torque) is the states' own, \
             set when they were observed: give those options to `dvrk-ident observe`"
        );
    }
    let mut state: Option<ObservationState> = None;
    for path in &args.from {
        let s = ObservationState::read(Path::new(path))?;
        match &mut state {
            None => state = Some(s),
            Some(total) => total.merge(&s).with_context(|| path.clone())?,
        }
    }
    let state = state.expect("clap requires a state");
    let robot = match &args.robot {
        Some(r) => r.clone(),
        None => state
            .robot_source
            .strip_prefix("builtin:")
            .unwrap_or(&state.robot_source)
            .to_string(),
    };
    let base = Model::load(&robot).with_context(|| format!("robot of {}", args.from[0]))?;
    let model = state.model(&base).with_context(|| args.from.join(", "))?;
    let mut settings = state.settings(&estimator(args));
    let log_args = args.log_args.for_robot(&model);
    let test = args
        .test
        .iter()
        .map(|p| log_args.open(p))
        .collect::<Result<Vec<_>>>()?;
    let test_data = read_all(&test, bars)?;
    settings.test_window = excitation_window(args, excitation, &test_data, &settings)?;
    let result = state.fit(&base, &settings, &log_data(&test_data, &args.test), bars)?;
    Ok((model, settings, result, None))
}

/// The human summary: solver, consistency and per-joint errors.
pub fn table(r: &FitResult) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "base parameters (value ± std):");
    for b in &r.base_parameters {
        let _ = writeln!(s, "  {:>12.6} ± {:<10.2e} {}", b.value, b.std, b.expression);
    }
    let _ = writeln!(s, "links (mass kg, centre of mass m in the link frame):");
    for l in &r.links {
        let _ = writeln!(
            s,
            "  {:>2} {:<24} {:>9.4}  [{:>8.4} {:>8.4} {:>8.4}]",
            l.frame, l.link, l.mass, l.com[0], l.com[1], l.com[2]
        );
    }
    let _ = writeln!(
        s,
        "robot {}  method {}  rows {}  condition number {:.1}",
        r.robot, r.method, r.rows, r.condition_number
    );
    let _ = writeln!(
        s,
        "solver {} status {} converged {} in {:.3} s",
        r.solver.name, r.solver.status, r.solver.converged, r.solver.seconds
    );
    let bad: Vec<&str> = r
        .consistency
        .iter()
        .filter(|c| !c.consistent)
        .map(|c| c.link.as_str())
        .collect();
    let _ = writeln!(
        s,
        "physically consistent: {}{}",
        r.physically_consistent,
        if bad.is_empty() {
            String::new()
        } else {
            format!(" (not: {})", bad.join(", "))
        }
    );
    let delays = &r.settings.processing.delay_s;
    if !delays.is_empty() {
        let ms: Vec<String> = match &r.delay {
            Some(d) => d
                .delay_s
                .iter()
                .zip(&d.std_s)
                .map(|(v, e)| format!("{:.1}±{:.1}", v * 1e3, e * 1e3))
                .collect(),
            None => delays.iter().map(|v| format!("{:.1}", v * 1e3)).collect(),
        };
        let how = if r.delay.is_some() {
            "estimated"
        } else {
            "given"
        };
        let _ = writeln!(s, "torque delays ({how}, ms): {}", ms.join(" "));
    }
    let _ = writeln!(
        s,
        "{:<8} {:>12} {:>12} {:>12} {:>12}",
        "joint", "train rel", "train rms", "test rel", "test rms"
    );
    for (j, name) in r.metrics.train.joints.iter().enumerate() {
        let (tr, trms) = (r.metrics.train.relative_error[j], r.metrics.train.rms[j]);
        let (te, terms) = match &r.metrics.test {
            Some(t) => (
                format!("{:.4}", t.relative_error[j]),
                format!("{:.4}", t.rms[j]),
            ),
            None => ("-".into(), "-".into()),
        };
        let _ = writeln!(s, "{name:<8} {tr:>12.4} {trms:>12.4} {te:>12} {terms:>12}");
    }
    // Each log with what was read of it (a recording's topics) and, when there are
    // several, its own errors.
    let _ = writeln!(s, "logs (samples after processing, sha256):");
    for i in &r.inputs {
        let name = if i.source.is_empty() {
            &i.path
        } else {
            &i.source
        };
        let _ = writeln!(
            s,
            "  {:<5} {name} ({} samples, {})",
            i.role,
            i.metrics.as_ref().map_or(0, |m| m.samples),
            &i.sha256[..12.min(i.sha256.len())]
        );
        if let (true, Some(m)) = (r.inputs.len() > 1, &i.metrics) {
            let errors: Vec<String> = m.relative_error.iter().map(|e| format!("{e:.4}")).collect();
            let _ = writeln!(s, "        relative error {}", errors.join(" "));
        }
    }
    s
}
