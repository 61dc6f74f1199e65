//! `dvrk-ident simulate ROBOT --params P --trajectory T --out LOG ...`: a simulated log
//! of a robot with known parameters running a Fourier excitation trajectory.

use std::path::Path;

use anyhow::{bail, Context, Result};
use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::fit::delay::DelayOption;
use dvrk_ident::log::{self, mcap, LogFormat};
use dvrk_ident::simulate::{simulate, Simulation};
use dvrk_model::Model;

use super::{emit_summary, read_params};

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Built-in robot (psm, psm_simplified, mtm) or a description/URDF path
    pub robot: String,
    /// Parameters: a result file ({"parameters": {name: value}}) or a {name: value} object
    #[arg(long)]
    pub params: String,
    /// Excitation trajectory: Fourier JSON (order, base_frequency_hz, q0, a, b in model
    /// coordinates), or the 2019 coefficient file with --pick
    #[arg(long)]
    pub trajectory: String,
    /// Take this trajectory (e.g. psm_one) from a 2019-layout coefficient file
    #[arg(long, value_name = "NAME")]
    pub pick: Option<String>,
    /// Output log (written atomically)
    #[arg(long)]
    pub out: String,
    /// Output format (default: mcap for a .mcap file, otherwise headered csv; wpi-csv is
    /// in model coordinates)
    #[arg(long, value_parser = super::named::<LogFormat>())]
    pub format: Option<LogFormat>,
    /// Torque noise standard deviation (N·m or N), added in model coordinates: one value
    /// or one per coordinate, comma-separated
    #[arg(long, default_value = "0", value_name = "STD")]
    pub noise: String,
    /// Measurement delay of the torques (s): the torque logged at t is the one of the
    /// motion at t − d. One value or one per coordinate, comma-separated
    #[arg(long, value_name = "D")]
    pub delay: Option<String>,
    /// Sampling rate (Hz)
    #[arg(long, default_value_t = 200.0, value_name = "HZ")]
    pub rate: f64,
    /// Duration (s); default: one period of the trajectory
    #[arg(long, value_name = "S", conflicts_with = "periods")]
    pub duration: Option<f64>,
    /// Duration as a number of periods of the trajectory
    #[arg(long, value_name = "N")]
    pub periods: Option<f64>,
    /// Seed of the noise generator
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// MCAP topic of the sensor_msgs/msg/JointState messages
    #[arg(long, default_value = mcap::DEFAULT_TOPIC)]
    pub topic: String,
}

/// The output format: `--format`, else `.mcap` is MCAP and anything else headered CSV.
pub fn output_format(path: &str, format: Option<LogFormat>) -> Result<LogFormat> {
    Ok(match format {
        Some(f) if !f.is_writable() => {
            bail!("--format {f}: logs are written as wpi, csv or mcap ({f} is read only)")
        }
        Some(f) => f,
        None if Path::new(path)
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mcap")) =>
        {
            LogFormat::Mcap
        }
        None => LogFormat::Csv,
    })
}

/// Writes `traj` in `format`: MCAP on `topic`, the 2019 layout in model coordinates.
pub fn write_log(
    model: Option<&Model>,
    traj: &dvrk_ident::JointLog,
    path: &str,
    format: LogFormat,
    topic: &str,
) -> Result<()> {
    match format {
        LogFormat::Mcap => mcap::write_mcap(path, traj, topic, &mcap::McapWriteOptions::default())?,
        LogFormat::Wpi => {
            let model_traj = match model {
                Some(m) => dvrk_ident::fit::to_model_coordinates(m, traj)?,
                None => traj.clone(),
            };
            log::write(path, &model_traj, LogFormat::Wpi)?
        }
        _ => log::write(path, traj, format)?,
    }
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let stdout_taken = super::check_outputs(&[("--out", Some(&args.out))], &[])?;
    let robot = Model::load(&args.robot)?;
    // A result is simulated with the model it was fitted with (e.g. its Stribeck terms).
    let (model, params) = read_params(&robot, &args.params)?;
    let model: &Model = &model;
    let traj = match &args.pick {
        Some(name) => FourierTrajectory::from_wpi_file(&args.trajectory, name)?,
        None => FourierTrajectory::from_json_file(&args.trajectory)?,
    };
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
    };
    let format = output_format(&args.out, args.format)?;
    let log = simulate(model, &params, &traj, &sim)?;
    write_log(Some(model), &log, &args.out, format, &args.topic)?;
    let bytes = match dvrk_ident::output::Destination::of(Path::new(&args.out)) {
        Ok(dvrk_ident::output::Destination::File(p)) => std::fs::metadata(p)
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
