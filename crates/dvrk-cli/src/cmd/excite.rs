//! `dvrk-ident excite --robot ROBOT ...`: optimize an excitation trajectory (Fourier
//! coefficients minimizing the condition number of the base regressor under the
//! description's limits), or evaluate one with `--evaluate TRAJ.json`.
//!
//! The setpoint CSV (`--csv`) is `time,<measured joint names>`: one period at `--rate`,
//! positions in the MEASURED joint space (`q_meas = M q`; rad or m), no effort columns.

use anyhow::{bail, Context, Result};
use clap::{Arg, ArgAction, ArgMatches, Command};
use dvrk_ident::excite::optimize::{
    self, Criterion, Evaluation, ExciteOption, ExciteOptions, Limits,
};
use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::report::figure_bytes;
use dvrk_ident::report::figures::excitation_figure;
use dvrk_logs::output::Outputs;
use dvrk_model::{BaseParameters, Limit, Model};
use std::path::Path;

use super::args::{MountingArgs, MODEL, OUTPUT};
use super::{emit, emit_summary};

/// Help headings of `excite`'s own groups.
const TRAJECTORY: &str = "Trajectory";
const OPTIMIZER: &str = "Optimizer";
const EVALUATION: &str = "Evaluation";

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Built-in robot (psm, psm_simplified, mtm, ecm, psm_si, psm_si_tool, ecm_si) or a description/URDF path
    #[arg(long, help_heading = MODEL)]
    pub robot: String,
    #[command(flatten)]
    pub mounting: MountingArgs,
    /// Limits file, replacing the description's ([[limits]] tables: expr of model
    /// coordinates or measured joints, position, velocity, acceleration;
    /// [[cartesian_limits]] tables: frame, min = [x, y, z], max = [x, y, z] in metres, base
    /// frame) [default: the description's]
    #[arg(long, value_name = "FILE", help_heading = MODEL)]
    pub limits: Option<String>,
    /// The optimizer's and the evaluation's options (the library's list).
    #[command(flatten)]
    pub options: ExciteFlags,
    /// Output trajectory JSON [default: stdout]
    #[arg(long, value_name = "FILE", help_heading = OUTPUT)]
    pub out: Option<String>,
    /// Setpoint CSV (time,<measured joints>; one period at --rate, measured joint space)
    #[arg(long, value_name = "FILE", help_heading = OUTPUT)]
    pub csv: Option<String>,
    /// Setpoint rate (Hz)
    #[arg(long, default_value_t = dvrk_ident::excite::setpoints::DEFAULT_RATE_HZ, value_name = "HZ", help_heading = OUTPUT)]
    pub rate: f64,
    /// Warm start: refine this trajectory (Fourier JSON; with --init-pick, a 2019 file)
    #[arg(long, value_name = "TRAJ.json", help_heading = OPTIMIZER)]
    pub init: Option<String>,
    /// Take the warm start (e.g. mtm_one) from a 2019-layout coefficient file
    #[arg(long, value_name = "NAME", requires = "init", help_heading = OPTIMIZER)]
    pub init_pick: Option<String>,
    /// Evaluate this trajectory file instead of optimizing
    #[arg(long, value_name = "TRAJ.json", help_heading = EVALUATION)]
    pub evaluate: Option<String>,
    /// Write a preview plot of the trajectory (one period, with the position limits):
    /// .svg or .png
    #[arg(long, value_name = "FILE", help_heading = OUTPUT)]
    pub plot: Option<String>,
    /// With --evaluate: take this trajectory (e.g. psm_one) from a 2019 coefficient file
    #[arg(long, value_name = "NAME", requires = "evaluate", help_heading = EVALUATION)]
    pub pick: Option<String>,
    /// With --evaluate: print JSON
    #[arg(long, help_heading = OUTPUT)]
    pub json: bool,
}

fn print_evaluation(ev: &Evaluation, json: bool, stdout_taken: bool) -> Result<()> {
    if json {
        let doc = ev.to_json_value();
        return emit_summary(&serde_json::to_string_pretty(&doc)?, stdout_taken);
    }
    let mut s = format!(
        "criterion: {} = {:.6}\nfeasible: {} (dense check: {} samples at {} Hz)\n",
        ev.criterion.name,
        ev.criterion.value,
        ev.feasibility.feasible,
        ev.feasibility.samples,
        ev.feasibility.rate_hz
    );
    if let Some(w) = &ev.feasibility.worst {
        s += &format!(
            "worst {}: {} {} = {:.6} vs bound {} ({} {:.3e}) at t = {:.3} s\n",
            if w.excess > 0.0 {
                "violation"
            } else {
                "margin"
            },
            w.limit,
            w.quantity,
            w.value,
            w.bound,
            if w.excess > 0.0 {
                "excess"
            } else {
                "inside by"
            },
            w.excess.abs(),
            w.time_s
        );
    }
    if ev.feasibility.violated.len() > 1 {
        s += "violated limits:\n";
        for w in &ev.feasibility.violated {
            s += &format!(
                "  {} {}: {:.6} vs {} (excess {:.3e}) at t = {:.3} s\n",
                w.limit, w.quantity, w.value, w.bound, w.excess, w.time_s
            );
        }
    }
    emit_summary(&s, stdout_taken)
}

pub fn run(args: Args) -> Result<()> {
    // Refuse bad outputs before minutes of optimization, not after.
    let stdout_taken = super::check_outputs(
        &[
            ("--out", args.out.as_deref()),
            ("--csv", args.csv.as_deref()),
            ("--plot", args.plot.as_deref()),
        ],
        &[],
        &inputs(&args),
    )?;
    if stdout_taken && args.out.is_none() && args.evaluate.is_none() {
        bail!("the trajectory goes to stdout without --out, and so does an output `-`: give --out");
    }
    if let Some(path) = &args.plot {
        dvrk_ident::report::plot::ImageFormat::from_path(std::path::Path::new(path))?;
    }
    let mut model = Model::load(&args.robot)?;
    args.mounting.apply(&mut model)?;
    let base = model.base_parameters()?;
    let limits = LimitsOf::load(&args, &model)?;
    match &args.evaluate {
        Some(path) => evaluate(&args, path, &model, &base, &limits, stdout_taken),
        None => search(&args, &model, &base, &limits),
    }
}

/// The limits of a run and where they come from, so that a limit error found while
/// optimizing names the file (or the description) that set it.
struct LimitsOf {
    limits: Limits,
    source: String,
}

impl LimitsOf {
    fn load(args: &Args, model: &Model) -> Result<LimitsOf> {
        Ok(match &args.limits {
            Some(path) => {
                let text = dvrk_model::input::read_text(Path::new(path))
                    .with_context(|| format!("{path}: cannot read"))?;
                LimitsOf {
                    limits: Limits::from_toml_str(model, &text, path)?,
                    source: path.clone(),
                }
            }
            None => LimitsOf {
                limits: Limits::of_model(model),
                source: format!("{} (limits of the description)", model.source),
            },
        })
    }

    fn name(&self, e: dvrk_ident::excite::ExciteError) -> anyhow::Error {
        match e {
            dvrk_ident::excite::ExciteError::ImpossibleLimits(m)
                if !m.starts_with(&self.source) =>
            {
                anyhow::anyhow!("{}: impossible limits: {m}", self.source)
            }
            other => other.into(),
        }
    }
}

/// `--evaluate`: the criterion and the dense feasibility check of a given trajectory.
fn evaluate(
    args: &Args,
    path: &str,
    model: &Model,
    base: &BaseParameters,
    limits: &LimitsOf,
    stdout_taken: bool,
) -> Result<()> {
    let traj = match &args.pick {
        Some(name) => FourierTrajectory::from_wpi_file(path, name)?,
        None => FourierTrajectory::from_json_file(path)?,
    };
    if let Some(warning) = traj.robot_mismatch(model, path) {
        super::warn(warning);
    }
    let opts = args.options.options()?;
    let ev = optimize::evaluate(
        model,
        base,
        &traj,
        &limits.limits,
        opts.criterion,
        opts.samples_per_harmonic,
        opts.check_rate_hz,
    )
    .map_err(|e| limits.name(e))?;
    if let Some(path) = &args.plot {
        let mut outputs = Outputs::protecting(inputs(args));
        outputs.add(
            Path::new(path),
            plot(model, &traj, &limits.limits.joint, path)?,
        )?;
        outputs.commit()?;
    }
    print_evaluation(&ev, args.json, stdout_taken)
}

/// The files the command reads, which no output may replace.
fn inputs(args: &Args) -> super::Inputs {
    super::inputs(
        &[],
        &[
            ("the robot", Some(&args.robot)),
            ("the limits", args.limits.as_deref()),
            ("the initial trajectory", args.init.as_deref()),
            ("the evaluated trajectory", args.evaluate.as_deref()),
        ],
    )
}

/// The optimizer's settings from the flags (the warm start read from its file).
fn options(args: &Args) -> Result<ExciteOptions> {
    Ok(ExciteOptions {
        init: match (&args.init, &args.init_pick) {
            (Some(path), Some(name)) => Some(FourierTrajectory::from_wpi_file(path, name)?),
            (Some(path), None) => Some(FourierTrajectory::from_json_file(path)?),
            _ => None,
        },
        ..args.options.options()?
    })
}

/// The search for a new trajectory, its outputs and a one-line summary on stderr.
fn search(args: &Args, model: &Model, base: &BaseParameters, limits: &LimitsOf) -> Result<()> {
    if limits.limits.is_empty() {
        super::warn("no limits (the motion is unconstrained)");
    }
    let opts = options(args)?;
    if args.rate <= 0.0 || !args.rate.is_finite() {
        bail!("--rate must be positive");
    }
    let started = std::time::Instant::now();
    let result = optimize::optimize(
        model,
        base,
        &limits.limits,
        &opts,
        &crate::progress::Bars::new(),
    )
    .map_err(|e| limits.name(e))?;
    let doc = serde_json::to_string_pretty(&result.to_json_value())?;
    // Every output built before the first is written.
    let mut outputs = Outputs::protecting(inputs(args));
    if let Some(path) = &args.out {
        outputs.add(Path::new(path), doc.clone() + "\n")?;
    }
    if let Some(path) = &args.csv {
        let csv =
            dvrk_ident::excite::setpoints::setpoints_csv(model, &result.trajectory, args.rate)?;
        outputs.add(Path::new(path), csv)?;
    }
    if let Some(path) = &args.plot {
        outputs.add(
            Path::new(path),
            plot(model, &result.trajectory, &limits.limits.joint, path)?,
        )?;
    }
    outputs.commit()?;
    if args.out.is_none() {
        emit(&doc)?;
    }
    eprintln!("{}", summary(&result, started.elapsed().as_secs_f64()));
    Ok(())
}

/// The one-line summary of a search that took `seconds`.
fn summary(result: &optimize::Excitation, seconds: f64) -> String {
    let ev = &result.evaluation;
    let w = ev.feasibility.worst.as_ref();
    format!(
        "excite: {} = {:.6} ({} starts, refined: {}), feasible on {} samples at {} Hz{}, {:.1} s",
        ev.criterion.name,
        ev.criterion.value,
        result.starts.len(),
        result
            .starts
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.map(|v| format!("#{i} {v:.4}")))
            .collect::<Vec<_>>()
            .join(", "),
        ev.feasibility.samples,
        ev.feasibility.rate_hz,
        w.map_or(String::new(), |w| format!(
            "; tightest: {} {} inside by {:.3e}",
            w.limit, w.quantity, -w.excess
        )),
        seconds
    )
}

/// The preview figure of `traj` against `limits`, 500 samples per second, rendered for
/// `path` (.svg or .png).
fn plot(model: &Model, traj: &FourierTrajectory, limits: &[Limit], path: &str) -> Result<Vec<u8>> {
    let figure = excitation_figure(model, traj, limits, 500.0);
    Ok(figure_bytes(&figure, Path::new(path))?)
}

/// How the command line spells an excitation option: its flag (`--check-rate`,
/// `--no-smooth`).
pub fn flag(o: ExciteOption) -> String {
    match o {
        ExciteOption::Smooth => "--no-smooth".into(),
        o => format!("--{}", o.name().replace('_', "-")),
    }
}

/// The flag of an excitation option: name, help and default from the library's list
/// ([`ExciteOption`]), the heading, value name and parser here.
fn arg(o: ExciteOption) -> Arg {
    // clap takes a flag's name as a `&'static str`; the command is built once per
    // process (a dozen short names and defaults).
    let long: &'static str = Box::leak(flag(o)[2..].to_string().into_boxed_str());
    let a = Arg::new(o.name()).long(long).help(o.doc());
    let a = match o.default_text() {
        Some(default) => {
            let default: &'static str = Box::leak(default.into_boxed_str());
            a.action(ArgAction::Set).default_value(default)
        }
        None => a.action(ArgAction::SetTrue),
    };
    let usize = clap::value_parser!(usize);
    let f64 = clap::value_parser!(f64);
    match o {
        ExciteOption::Order => a
            .value_parser(usize)
            .value_name("L")
            .help_heading(TRAJECTORY),
        ExciteOption::F0 => a
            .value_parser(f64)
            .value_name("HZ")
            .help_heading(TRAJECTORY),
        ExciteOption::Criterion => a
            .value_parser(super::named::<Criterion>())
            .value_name("CRITERION")
            .help_heading(OPTIMIZER),
        ExciteOption::Seed => a
            .value_parser(clap::value_parser!(u64))
            .value_name("SEED")
            .help_heading(OPTIMIZER),
        ExciteOption::Starts
        | ExciteOption::Refine
        | ExciteOption::Iterations
        | ExciteOption::RefineIterations
        | ExciteOption::SamplesPerHarmonic => a
            .value_parser(usize)
            .value_name("N")
            .help_heading(OPTIMIZER),
        ExciteOption::Rest => a.help_heading(TRAJECTORY),
        ExciteOption::Smooth => a.help_heading(OPTIMIZER),
        ExciteOption::CheckRate => a.value_parser(f64).value_name("HZ").help_heading(OPTIMIZER),
    }
}

/// `excite`'s option flags (`#[command(flatten)]`), one per [`ExciteOption`], and the
/// values given.
#[derive(Clone, Debug, Default)]
pub struct ExciteFlags {
    values: Vec<(ExciteOption, serde_json::Value)>,
}

impl ExciteFlags {
    /// The library's defaults with the flags given, through its one conversion
    /// ([`ExciteOptions::from_values`]); an error names the flag.
    pub fn options(&self) -> Result<ExciteOptions> {
        ExciteOptions::from_values(self.values.iter().cloned())
            .map_err(|e| anyhow::anyhow!("{}: {}", flag(e.option), e.message))
    }
}

impl clap::FromArgMatches for ExciteFlags {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let switch = |o| match o {
            ExciteOption::Smooth => Some(false),
            ExciteOption::Rest => Some(true),
            _ => None,
        };
        let values = ExciteOption::ALL
            .iter()
            .filter_map(|&o| super::settings::given(m, o.name(), switch(o)).map(|v| (o, v)))
            .collect();
        Ok(ExciteFlags { values })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for ExciteFlags {
    fn augment_args(cmd: Command) -> Command {
        cmd.args(ExciteOption::ALL.iter().map(|o| arg(*o)))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}
