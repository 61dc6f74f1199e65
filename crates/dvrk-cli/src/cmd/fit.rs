//! `dvrk-ident fit LOG --robot ROBOT ...`: identification from a log.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::ObservationState;
use dvrk_ident::{FitOutcome, FitRequest, LogSource, PriorSource, Streaming, Training};
use dvrk_ident::{FitResult, JointLog};
use dvrk_ident::{LinkResult, ParameterStatus};
use dvrk_logs::output::Outputs;
use dvrk_model::Model;

use super::args::{LogArgs, INPUT, MODEL, OUTPUT};
use super::emit;
use super::settings::{Fit, SettingFlags};

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true, mut_args = super::args::library_defaults)]
pub struct Args {
    /// Training logs: files (2019 CSV, headered CSV, MCAP, sqlite3 .db3, ROS 1 .bag) or
    /// rosbag2 folders, recognized by content. Each is processed on its own (filters
    /// and trimming never cross from one to the next), their observations merged
    #[arg(required_unless_present = "states", num_args = 1.., value_name = "LOG")]
    pub logs: Vec<String>,
    /// Observation states of `dvrk-ident observe` instead of logs: merged in order and
    /// fitted, with their processing settings and robot; the same document as the fit
    /// of their logs
    #[arg(long, alias = "from", num_args = 1.., value_name = "STATE", help_heading = INPUT,
          conflicts_with_all = ["logs", "stream", "report", "stribeck", "dahl", "position_torque", "load_friction", "mounting_pitch", "delay"])]
    pub states: Vec<String>,
    /// Test (validation) logs: `--test a b` or `--test a --test b`
    #[arg(long, num_args = 1.., value_name = "LOG", help_heading = INPUT)]
    pub test: Vec<String>,
    /// The excitation trajectory the logs follow (JSON of `dvrk-ident excite`): drawn in
    /// --report, and with --test but no --test-window the test metrics cover its first
    /// period (the 2019 protocol)
    #[arg(long, value_name = "TRAJ.json", help_heading = INPUT)]
    pub excitation: Option<String>,
    /// Read the logs from disk block by block, in memory independent of their length,
    /// instead of loading them (several passes over the files; the same result).
    /// Automatic for a log larger than 256 MiB
    #[arg(long, help_heading = INPUT)]
    pub stream: bool,
    /// Built-in robot (psm, psm_simplified, mtm, ecm, psm_si, psm_si_tool, ecm_si) or a description/URDF path (with
    /// --states: default the states' robot, and it must be the robot they were observed
    /// with)
    #[arg(long, required_unless_present = "states", help_heading = MODEL)]
    pub robot: Option<String>,
    // The fit options (`--method`, `--cutoff`, ...: every library `Setting`), before
    // `log_args`: they read `--resample`, which `log_args` declares and takes.
    #[command(flatten)]
    pub settings: SettingFlags<Fit>,
    #[command(flatten)]
    pub log_args: LogArgs,
    /// Write the result document here (atomically; `-` for stdout)
    #[arg(long, value_name = "FILE", help_heading = OUTPUT)]
    pub out: Option<String>,
    /// Also write the parameters in the 2019 package's params.json layout (atomically)
    #[arg(long, value_name = "FILE", help_heading = OUTPUT)]
    pub wpi_json: Option<String>,
    /// Also write figures and report.html into this folder (see `dvrk-ident report`)
    #[arg(long, value_name = "DIR", help_heading = OUTPUT)]
    pub report: Option<String>,
    /// Print the result document to stdout instead of the table
    #[arg(long, help_heading = OUTPUT)]
    pub json: bool,
}

/// The files the fit reads, which no output may replace: logs (training and test),
/// states, the excitation, the prior, the robot.
fn inputs(args: &Args) -> super::Inputs {
    let logs: Vec<&str> = args
        .logs
        .iter()
        .chain(&args.test)
        .map(String::as_str)
        .collect();
    // A prior refused here is reported by `request`.
    let prior = match args.settings.overrides().map(|o| o.prior) {
        Ok(Some(PriorSource::File(path))) => path.to_str().map(String::from),
        _ => None,
    };
    let mut files: Vec<(&str, Option<&str>)> = vec![
        ("the robot", args.robot.as_deref()),
        ("the excitation", args.excitation.as_deref()),
        ("the prior", prior.as_deref()),
    ];
    files.extend(args.states.iter().map(|s| ("the state", Some(s.as_str()))));
    super::inputs(&logs, &files)
}

/// The request of these flags: everything but the outputs.
fn request(args: &Args) -> Result<FitRequest> {
    let train = if args.states.is_empty() {
        Training::Logs(
            args.logs
                .iter()
                .map(|p| LogSource::File(p.into()))
                .collect(),
        )
    } else {
        let mut states = Vec::new();
        for path in &args.states {
            states.push((
                Arc::new(ObservationState::read(Path::new(path))?),
                Some(path.into()),
            ));
        }
        Training::Observations(states)
    };
    let excitation = match &args.excitation {
        Some(p) => {
            Some(FourierTrajectory::from_json_file(p).with_context(|| format!("{p}: excitation"))?)
        }
        None => None,
    };
    let overrides = args.settings.overrides()?;
    Ok(FitRequest {
        test: args
            .test
            .iter()
            .map(|p| LogSource::File(p.into()))
            .collect(),
        read: args.log_args.read_options(),
        overrides,
        excitation,
        streaming: if args.stream {
            Streaming::Always
        } else {
            Streaming::Auto
        },
        ..FitRequest::new(train)
    })
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(
        &[
            ("--out", args.out.as_deref()),
            ("--wpi-json", args.wpi_json.as_deref()),
        ],
        &[("--report", args.report.as_deref())],
        &inputs(&args),
    )?;
    if stdout_taken && args.json {
        bail!("--json prints the result to stdout, and so does an output `-`: give one of them");
    }
    let request = request(&args)?;
    if request.streams() && args.report.is_some() {
        bail!(
            "--report draws the logs, which a streamed fit does not hold in memory: \
             fit with --out, then run `dvrk-ident report RESULT LOG` on a shorter log"
        );
    }
    let robot = args.robot.as_deref().map(Model::load).transpose()?;
    let bars = crate::progress::Bars::new();
    let FitOutcome {
        model,
        settings,
        result,
        logs,
    } = request.run(robot.as_ref(), &bars)?;
    if result.solver.converged {
        // Every output built and staged before the first is put in place.
        let mut outputs = Outputs::protecting(inputs(&args));
        let mut report_note = None;
        let mut export_warnings = Vec::new();
        if let Some(out) = &args.out {
            outputs.add(Path::new(out), result.to_json())?;
        }
        if let Some(out) = &args.wpi_json {
            let params = result.params_for(&model)?;
            let wpi = dvrk_ident::export::Export::WpiParams.build_for(&model, &params, &result)?;
            outputs.add(Path::new(out), wpi.document.to_text())?;
            for line in &wpi.undetermined {
                export_warnings.push(format!("{out}: {line}"));
            }
        }
        if let (Some(dir), Some((train, test))) = (&args.report, &logs) {
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
            let mut drawn: Vec<(&str, &JointLog, Option<usize>)> = Vec::new();
            for (role, t) in train_roles.iter().zip(train) {
                drawn.push((role, &**t, None));
            }
            for (role, t) in test_roles.iter().zip(test) {
                drawn.push((role, &**t, settings.test_window));
            }
            let built = super::report::build(
                &model,
                &result,
                &result.settings,
                &drawn,
                request.excitation.as_ref(),
                &request.read,
            )?;
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
        for warning in export_warnings {
            super::warn(warning);
        }
    }
    for warning in result.repeated_inputs() {
        super::warn(warning);
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

/// The human summary: solver, consistency and per-joint errors.
pub fn table(r: &FitResult) -> String {
    let mut s = String::new();
    parameters(&mut s, r);
    solver(&mut s, r);
    delays_and_prior(&mut s, r);
    if let Some(sel) = &r.selection {
        s.push_str(&sel.table());
    }
    errors(&mut s, r);
    logs(&mut s, r);
    s
}

/// The base parameters and each link's mass and centre of mass.
fn parameters(s: &mut String, r: &FitResult) {
    let _ = writeln!(s, "base parameters (value ± std):");
    for b in &r.base_parameters {
        let _ = writeln!(s, "  {:>12.6} ± {:<10.2e} {}", b.value, b.std, b.expression);
    }
    let known = !r.parameter_status.is_empty();
    let _ = writeln!(
        s,
        "links (mass kg, centre of mass m in the link frame{}):",
        if known {
            "; determined by the data: mass, first moment, inertia"
        } else {
            ""
        }
    );
    for l in &r.links {
        let _ = write!(
            s,
            "  {:>2} {:<24} {:>9.4}  [{:>8.4} {:>8.4} {:>8.4}]",
            l.frame, l.link, l.mass, l.com[0], l.com[1], l.com[2]
        );
        match link_marks(r, l) {
            Some([m, f, i]) => {
                let _ = writeln!(s, "  {m:<5} {f:<5} {i:<5}");
            }
            None => s.push('\n'),
        }
    }
    if known {
        let identified = r
            .parameter_status
            .values()
            .filter(|v| v.identified())
            .count();
        let at_bound: Vec<String> = r
            .parameter_status
            .iter()
            .filter(|(_, v)| {
                matches!(
                    v,
                    ParameterStatus::AtLowerBound | ParameterStatus::AtUpperBound
                )
            })
            .map(|(k, v)| format!("{k} {}", v.name()))
            .collect();
        let _ = writeln!(
            s,
            "parameters identified by the data: {identified} of {} (the others are set by the \
             bounds, the regularization or a prior; see parameter_status)",
            r.parameter_status.len()
        );
        if !at_bound.is_empty() {
            let _ = writeln!(s, "at a bound: {}", at_bound.join(", "));
        }
    }
}

/// A link's marks in the summary: its mass's status (`yes`, `no`, `lower`, `upper`
/// bound) and whether its first moment and its inertia are determined (`yes`, `no`, or
/// `bound` when a component sits on a bound); `None` for a result without statuses.
fn link_marks(r: &FitResult, l: &LinkResult) -> Option<[&'static str; 3]> {
    let d = l.determined?;
    let block = r.link_status(l)?;
    let group = |range: std::ops::Range<usize>, ok: bool| {
        if ok {
            "yes"
        } else if block[range].iter().any(|(_, s)| {
            matches!(
                s,
                ParameterStatus::AtLowerBound | ParameterStatus::AtUpperBound
            )
        }) {
            "bound"
        } else {
            "no"
        }
    };
    let mass = match block[9].1 {
        ParameterStatus::Identified => "yes",
        ParameterStatus::AtLowerBound => "lower",
        ParameterStatus::AtUpperBound => "upper",
        ParameterStatus::Unidentified => "no",
    };
    Some([mass, group(6..9, d.first_moment), group(0..6, d.inertia)])
}

/// The problem's size, the solver's outcome and the links that are not consistent.
fn solver(s: &mut String, r: &FitResult) {
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
}

/// The torque delays (given or estimated, ms) and the prior, when the fit has them.
fn delays_and_prior(s: &mut String, r: &FitResult) {
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
    if let Some(p) = &r.settings.prior {
        let divergence = r
            .prior_divergence
            .map_or(String::new(), |d| format!(", divergence from it {d:.4e}"));
        let _ = writeln!(
            s,
            "prior {} ({} metric, weight {}){divergence}",
            p.source,
            p.metric.name(),
            dvrk_model::input::show(p.weight)
        );
    }
}

/// Per joint, the training and test errors.
fn errors(s: &mut String, r: &FitResult) {
    let names = &r.metrics.train.joints;
    let width = super::joint_width(names);
    let _ = writeln!(
        s,
        "{:<width$} {:>12} {:>12} {:>12} {:>12}",
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
        let _ = writeln!(
            s,
            "{name:<width$} {tr:>12.4} {trms:>12.4} {te:>12} {terms:>12}"
        );
    }
}

/// Each log with what was read of it (a recording's topics) and, when there are several,
/// its own errors.
fn logs(s: &mut String, r: &FitResult) {
    let _ = writeln!(s, "logs (samples after processing, sha256):");
    let logs: Vec<_> = r.inputs.iter().filter(|i| i.role != "prior").collect();
    for i in &logs {
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
        if let (true, Some(m)) = (logs.len() > 1, &i.metrics) {
            let errors: Vec<String> = m.relative_error.iter().map(|e| format!("{e:.4}")).collect();
            let _ = writeln!(s, "        relative error {}", errors.join(" "));
        }
        if let Some(o) = &i.offset {
            let o: Vec<String> = o.iter().map(|v| format!("{v:+.4}")).collect();
            let _ = writeln!(
                s,
                "        own torque offset over the model's {}",
                o.join(" ")
            );
        }
    }
}
