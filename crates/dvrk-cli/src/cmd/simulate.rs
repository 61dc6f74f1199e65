//! `dvrk-ident simulate ROBOT --params P --excitation T --out LOG ...`: a simulated log
//! of a robot with known parameters running a Fourier excitation trajectory.

use std::path::Path;

use anyhow::{bail, Context, Result};
use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::log::{self, mcap, LogFormat};
use dvrk_ident::simulate::ExternalTorque;
use dvrk_ident::simulate::{simulate, Simulation};
use dvrk_ident::DelayOption;
use dvrk_model::Model;

use super::args::{MountingArgs, INPUT, MODEL, OUTPUT};
use super::{emit_summary, read_params};

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Built-in robot (psm, psm_simplified, mtm, ecm, psm_si, psm_si_tool, ecm_si) or a description/URDF path
    pub robot: String,
    /// Parameters: a result file ({"parameters": {name: value}}), a {name: value} object,
    /// or `nominal` (the description's nominal parameters)
    #[arg(long, value_name = "FILE|nominal", help_heading = MODEL)]
    pub params: String,
    #[command(flatten)]
    pub mounting: MountingArgs,
    /// Excitation trajectory: Fourier JSON (order, base_frequency_hz, q0, a, b in model
    /// coordinates; `dvrk-ident excite`), or the 2019 coefficient file with --pick
    #[arg(long, alias = "trajectory", value_name = "TRAJ.json", help_heading = INPUT)]
    pub excitation: String,
    /// Take this trajectory (e.g. psm_one) from a 2019-layout coefficient file
    #[arg(long, value_name = "NAME", help_heading = INPUT)]
    pub pick: Option<String>,
    /// Sampling rate (Hz)
    #[arg(long, default_value_t = 200.0, value_name = "HZ", help_heading = INPUT)]
    pub rate: f64,
    /// Duration (s) [default: one period of the trajectory]
    #[arg(long, value_name = "S", conflicts_with = "periods", help_heading = INPUT)]
    pub duration: Option<f64>,
    /// Duration as a number of periods of the trajectory
    #[arg(long, value_name = "N", help_heading = INPUT)]
    pub periods: Option<f64>,
    /// Torque noise standard deviation (N·m or N), added in model coordinates: one value
    /// or one per coordinate, comma-separated
    #[arg(long, default_value = "0", value_name = "STD", help_heading = MEASUREMENT)]
    pub noise: String,
    /// Seed of the noise generator
    #[arg(long, default_value_t = 0, help_heading = MEASUREMENT)]
    pub seed: u64,
    /// Measurement delay of the torques (s): the torque logged at t is the one of the
    /// motion at t − d. One value or one per coordinate, comma-separated [default: 0]
    #[arg(long, value_name = "D", help_heading = MEASUREMENT)]
    pub delay: Option<String>,
    /// A rigid payload fixed to a frame (TOML: frame, mass kg, com m in that frame,
    /// optional inertia kg·m² about the com: xx yy zz xy xz yz), added to the parameters
    #[arg(long, value_name = "PAYLOAD.toml", help_heading = MODEL)]
    pub payload: Option<String>,
    /// External torque added to the simulated torques: CSV with time (s), then one
    /// column per model coordinate (N·m or N); linear between rows, zero outside them
    #[arg(long, value_name = "FILE.csv", help_heading = MEASUREMENT)]
    pub external_torque: Option<String>,
    /// Output log (written atomically; `-` for stdout)
    #[arg(long, value_name = "LOG", help_heading = OUTPUT)]
    pub out: String,
    /// Output format; wpi is in model coordinates [default: mcap for a .mcap file,
    /// otherwise csv (headered)]
    #[arg(long, alias = "format", value_parser = super::writable(), value_name = "FORMAT", help_heading = OUTPUT)]
    pub out_format: Option<LogFormat>,
    /// Topic of the written MCAP
    #[arg(long, alias = "topic", default_value = mcap::DEFAULT_TOPIC, value_name = "TOPIC", help_heading = OUTPUT)]
    pub out_topic: String,
}

/// The heading of `simulate`'s noise, seed and delay: what the simulated sensor adds.
const MEASUREMENT: &str = "Measurement";

/// The output format: `--out-format` (a writable one, see [`super::writable`]), else
/// `.mcap` is MCAP and anything else headered CSV.
pub fn output_format(path: &str, format: Option<LogFormat>) -> LogFormat {
    match format {
        Some(f) => f,
        None if Path::new(path)
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mcap")) =>
        {
            LogFormat::Mcap
        }
        None => LogFormat::Csv,
    }
}

/// Writes `log` in `format`: MCAP on `topic`, the 2019 layout in model coordinates.
pub fn write_log(
    model: Option<&Model>,
    log: &dvrk_ident::JointLog,
    path: &str,
    format: LogFormat,
    topic: &str,
) -> Result<()> {
    match format {
        LogFormat::Mcap => mcap::write_mcap(path, log, topic, &mcap::McapWriteOptions::default())?,
        LogFormat::Wpi => {
            let in_model = match model {
                Some(m) => dvrk_ident::simulate::to_model_coordinates(m, log)?,
                None => log.clone(),
            };
            log::write(path, &in_model, LogFormat::Wpi)?
        }
        _ => log::write(path, log, format)?,
    }
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let inputs = super::inputs(
        &[],
        &[
            ("the robot", Some(&args.robot)),
            ("the parameters", Some(&args.params)),
            ("the excitation", Some(&args.excitation)),
        ],
    );
    let stdout_taken = super::check_outputs(&[("--out", Some(&args.out))], &[], &inputs)?;
    let robot = Model::load(&args.robot)?;
    let traj = match &args.pick {
        Some(name) => FourierTrajectory::from_wpi_file(&args.excitation, name)?,
        None => FourierTrajectory::from_json_file(&args.excitation)?,
    };
    if let Some(warning) = traj.robot_mismatch(&robot, &args.excitation) {
        super::warn(warning);
    }
    // A result is simulated with the model it was fitted with (e.g. its Stribeck terms).
    let (mut model, params) = read_params(&robot, &args.params)?;
    if args.mounting.mounting_pitch.is_some() {
        args.mounting.apply(model.to_mut())?;
    }
    let model: &Model = &model;
    let noise: Vec<f64> = args
        .noise
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .with_context(|| format!("--noise: `{t}` is not a number"))
        })
        .collect::<Result<_>>()?;
    if noise.len() != 1 && noise.len() != model.dof() {
        bail!(
            "--noise: expected one value or {} (one per coordinate), got {}",
            model.dof(),
            noise.len()
        );
    }
    let delay_s = match args.delay.as_deref().map(str::parse::<DelayOption>) {
        None => Vec::new(),
        Some(Ok(DelayOption::Fixed(d))) => d,
        Some(Ok(DelayOption::Auto)) => bail!("--delay: simulate takes delays in seconds"),
        Some(Err(e)) => bail!("--delay: {e}"),
    };
    let sim = Simulation {
        duration_s: args.duration.or(args.periods.map(|p| p * traj.period_s())),
        rate_hz: args.rate,
        noise_std: noise,
        seed: args.seed,
        delay_s,
        payload: args
            .payload
            .as_deref()
            .map(|p| dvrk_model::Payload::load(model, p))
            .transpose()?,
        external_torque: args
            .external_torque
            .as_deref()
            .map(|p| ExternalTorque::read_csv(Path::new(p), &model.coordinates))
            .transpose()?,
    };
    let format = output_format(&args.out, args.out_format);
    let log = simulate(model, &params, &traj, &sim)?;
    write_log(Some(model), &log, &args.out, format, &args.out_topic)?;
    let bytes = match dvrk_logs::output::Destination::of(Path::new(&args.out)) {
        Ok(dvrk_logs::output::Destination::File(p)) => std::fs::metadata(p)
            .map(|m| format!(", {} bytes", m.len()))
            .unwrap_or_default(),
        _ => String::new(),
    };
    emit_summary(
        &format!(
            "wrote {} ({format}, {} samples, {:.4} s at {} Hz, {} joints{bytes})",
            args.out,
            log.len(),
            log.time.last().copied().unwrap_or(0.0) + 1.0 / args.rate,
            args.rate,
            log.dof(),
        ),
        stdout_taken,
    )
}
