//! The flag groups every command that reads logs shares (reading options, processing
//! overrides), mapped onto the library's [`ReadOptions`] and
//! [`dvrk_ident::request::Overrides`]. A leaf of the command modules.

use anyhow::Result;
use dvrk_ident::log::mcap::TimeSource;
use dvrk_ident::log::{LogFormat, ReadOptions};
use dvrk_ident::request::Overrides;
use dvrk_ident::signal::Cutoff;
use dvrk_ident::{FitSettings, JointLog};

/// Recording options, and resampling for every format (mapped onto
/// [`ReadOptions`]).
#[derive(clap::Args, Clone, Default)]
pub struct McapArgs {
    /// MCAP: sensor_msgs/msg/JointState topic to read; repeat to merge topics (the first
    /// is the clock, e.g. --topic /PSM1/measured_js --topic /PSM1/jaw/measured_js).
    /// Default: the topic with positions and efforts (ending in measured_js if several)
    #[arg(long = "topic", value_name = "TOPIC")]
    pub topics: Vec<String>,
    /// Recordings: sample times from the JointState header stamps (when the controller
    /// measured the joints), or the recorder's log times or the publish times. Default:
    /// header
    #[arg(long, value_parser = super::named::<TimeSource>())]
    pub time: Option<TimeSource>,
    /// Resample to this uniform rate (Hz) by linear interpolation before anything else
    /// (bridges gaps and jitter; without it such logs are refused)
    #[arg(long, value_name = "HZ")]
    pub resample: Option<f64>,
}

/// The reading options of `--format`, `--rate` and the recording flags.
pub fn read_options(format: Option<LogFormat>, rate: Option<f64>, mcap: &McapArgs) -> ReadOptions {
    ReadOptions {
        format,
        rate_hz: rate,
        topics: mcap.topics.clone(),
        time_source: mcap.time,
        resample_hz: mcap.resample,
        ..ReadOptions::default()
    }
}

/// Reads a log into memory, with a spinner.
pub fn read(options: &ReadOptions, path: &str) -> Result<JointLog> {
    let traj =
        crate::progress::Bars::new().spin(&format!("reading {path}"), || options.read(path))?;
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
    /// Keep every N-th processed sample (after filtering; N ≥ 1)
    #[arg(long, value_parser = super::at_least_one, value_name = "N")]
    pub decimate: Option<usize>,
    /// Drop processed samples where some joint moves slower than this (rad/s or m/s):
    /// the sign of its Coulomb friction is noise there
    #[arg(long, value_name = "SPEED")]
    pub min_speed: Option<f64>,
    #[command(flatten)]
    pub mcap: McapArgs,
}

impl LogArgs {
    /// How these flags read logs (the robot's joints added by
    /// [`ReadOptions::for_model`]). `--resample` is a processing setting here (see
    /// [`LogArgs::overrides`]): the library reads at its rate
    /// ([`ReadOptions::for_processing`]).
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            resample_hz: None,
            ..read_options(self.format, self.rate, &self.mcap)
        }
    }

    /// The processing flags as settings overrides.
    pub fn overrides(&self) -> Result<Overrides> {
        let cutoff = match &self.cutoff {
            Some(c) => Some(Cutoff::parse_flag(c).map_err(|e| anyhow::anyhow!("--cutoff: {e}"))?),
            None => None,
        };
        Ok(Overrides {
            cutoff,
            trim: self.trim,
            filter_torque: self.filter_torque.then_some(true),
            decimate: self.decimate,
            min_speed: self.min_speed,
            resample_hz: self.mcap.resample,
            ..Overrides::default()
        })
    }

    /// `base` with the processing flags applied.
    pub fn settings(&self, base: FitSettings) -> Result<FitSettings> {
        Ok(self.overrides()?.apply(base))
    }
}
