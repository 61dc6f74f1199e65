//! `dvrk-ident convert IN OUT ...`: a log from one layout and joint space to another
//! (ROS 2 MCAP, headered CSV, the 2019 CSV layout).

use anyhow::{bail, Result};
use dvrk_ident::log::{mcap, LogFormat};
use dvrk_ident::simulate::to_measured_coordinates;
use dvrk_ident::Coordinates;
use dvrk_model::Model;

use super::args::{read, read_options, McapArgs, INPUT, MODEL, OUTPUT};
use super::emit_summary;
use super::simulate::{output_format, write_log};

#[derive(clap::Args)]
// A negative number is a value (`--f0 -1`, `--rate -5`), refused by the checks with a
// message, not an unknown flag.
#[command(allow_negative_numbers = true, mut_args = super::args::library_defaults)]
pub struct Args {
    /// Input log (any format `fit` reads)
    #[arg(value_name = "IN")]
    pub input: String,
    /// Output log (written atomically; `-` for stdout)
    #[arg(value_name = "OUT")]
    pub output: String,
    /// Input format [default: recognized from the file's content]
    #[arg(long, alias = "from", value_parser = super::named::<LogFormat>(), value_name = "FORMAT", help_heading = INPUT)]
    pub in_format: Option<LogFormat>,
    /// Sampling rate of an input without time stamps (the 2019 layout), Hz
    #[arg(long, value_name = "HZ", help_heading = INPUT)]
    pub rate: Option<f64>,
    #[command(flatten)]
    pub mcap: McapArgs,
    /// Robot (built-in name or description path): needed to change coordinates
    #[arg(long, help_heading = MODEL)]
    pub robot: Option<String>,
    /// Output format [default: mcap for a .mcap file, otherwise csv (headered)]
    #[arg(long, alias = "format", value_parser = super::writable(), value_name = "FORMAT", help_heading = OUTPUT)]
    pub out_format: Option<LogFormat>,
    /// Output coordinates; changing them needs --robot [default: model for wpi, measured
    /// for mcap, the input's for csv]
    #[arg(long, value_parser = super::named::<Coordinates>(), help_heading = OUTPUT)]
    pub coordinates: Option<Coordinates>,
    /// Topic of the written MCAP
    #[arg(long, default_value = mcap::DEFAULT_TOPIC, value_name = "TOPIC", help_heading = OUTPUT)]
    pub out_topic: String,
}

pub fn run(args: Args) -> Result<()> {
    let inputs = super::inputs(&[&args.input], &[("the robot", args.robot.as_deref())]);
    let stdout_taken = super::check_outputs(&[("OUT", Some(&args.output))], &[], &inputs)?;
    let model = args.robot.as_deref().map(Model::load).transpose()?;
    let log = read(
        &read_options(args.in_format, args.rate, &args.mcap),
        &args.input,
    )?;
    log.validate()?;
    let format = output_format(&args.output, args.out_format);
    let target = match (args.coordinates, format) {
        (Some(Coordinates::Measured), LogFormat::Wpi) => {
            bail!("the 2019 (wpi-csv) layout holds model coordinates, not measured joints")
        }
        (Some(Coordinates::Model), LogFormat::Mcap) => {
            bail!("MCAP JointState logs hold measured joints, not model coordinates")
        }
        (Some(Coordinates::Model), _) => Coordinates::Model,
        (Some(Coordinates::Measured), _) => Coordinates::Measured,
        (None, LogFormat::Wpi) => Coordinates::Model,
        (None, LogFormat::Mcap) => Coordinates::Measured,
        (None, _) => log.coordinates,
    };
    let out = match (target, &model) {
        (Coordinates::Model, Some(m)) => dvrk_ident::simulate::to_model_coordinates(m, &log)?,
        (Coordinates::Measured, Some(m)) => to_measured_coordinates(m, &log)?,
        (t, None) if t == log.coordinates => log,
        (t, None) => bail!(
            "{}: the log is in {} coordinates; converting to {t} coordinates needs --robot",
            args.input,
            log.coordinates
        ),
    };
    if format == LogFormat::Wpi {
        if let Err(e) = out.check_uniform(mcap::JITTER_TOLERANCE) {
            bail!("the 2019 (wpi) layout has no time stamps: {e}");
        }
    }
    write_log(model.as_ref(), &out, &args.output, format, &args.out_topic)?;
    let rate = out.rate_hz().unwrap_or(f64::NAN);
    emit_summary(
        &format!(
            "wrote {} ({format}, {} coordinates, {} samples at {} Hz, joints {})",
            args.output,
            out.coordinates,
            out.len(),
            dvrk_model::input::show_approx(rate),
            out.joint_names.join(" ")
        ),
        stdout_taken,
    )
}
