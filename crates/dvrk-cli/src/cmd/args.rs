//! The flag groups every command that reads logs shares (reading options), mapped onto
//! the library's [`ReadOptions`], and the help's headings and shown defaults (the fit
//! options' flags are in [`super::settings`]). A leaf of the command modules.

use anyhow::Result;
use clap::builder::StyledStr;
use dvrk_ident::log::mcap::TimeSource;
use dvrk_ident::log::{LogFormat, ReadOptions, Resampling};
use dvrk_ident::JointLog;
use dvrk_ident::Joints;
use dvrk_ident::Named;
use dvrk_ident::Setting;

/// Help headings: every subcommand groups its options under these (those it has).
pub const INPUT: &str = "Input";
/// Filtering, trimming and resampling of the logs.
pub const PROCESSING: &str = "Processing";
/// The robot and what is added to its model.
pub const MODEL: &str = "Model";
/// The estimator and its settings.
pub const ESTIMATOR: &str = "Estimator";
/// Files written and what is printed.
pub const OUTPUT: &str = "Output";

/// Recording options, and resampling for every format (mapped onto
/// [`ReadOptions`]).
#[derive(clap::Args, Clone, Default)]
pub struct McapArgs {
    /// Recordings (MCAP, rosbag2 folders and .db3 files, ROS 1 .bag): the
    /// sensor_msgs/JointState topic to read; repeat to merge topics (the first is the
    /// clock, e.g. --topic /PSM1/measured_js --topic /PSM1/jaw/measured_js). Refused for
    /// CSV logs. [default: the topic with positions and efforts, the one ending in
    /// measured_js if several, or a dVRK arm and its jaw]
    #[arg(long = "topic", value_name = "TOPIC", help_heading = INPUT)]
    pub topics: Vec<String>,
    /// Recordings: sample times from the JointState header stamps (when the controller
    /// measured the joints), the recorder's log times or the publish times
    #[arg(long, value_parser = super::named::<TimeSource>(), help_heading = INPUT)]
    pub time: Option<TimeSource>,
    /// The fit option `resample` (its help is the library's): a processing setting
    /// where a fit's options are taken ([`super::settings::SettingFlags`] reads it), a
    /// reading option elsewhere.
    #[arg(long, value_name = "HZ", help_heading = PROCESSING,
          help = dvrk_ident::Setting::Resample.doc())]
    pub resample: Option<f64>,
    /// Recordings: the largest size (MiB) a zstd- or lz4-compressed sqlite3 .db3 or ROS 1
    /// .bag may decompress to in the temporary folder [default: 100 times its compressed
    /// size, at least 64 MiB, at most 16 GiB]
    #[arg(long, value_name = "MIB", help_heading = INPUT)]
    pub max_unpacked_mib: Option<u64>,
}

/// The reading options of `--format`, `--rate` and the recording flags.
pub fn read_options(format: Option<LogFormat>, rate: Option<f64>, mcap: &McapArgs) -> ReadOptions {
    ReadOptions {
        format,
        rate_hz: rate,
        topics: mcap.topics.clone(),
        time_source: mcap.time,
        resample_hz: mcap.resample,
        max_unpacked_mib: mcap.max_unpacked_mib,
        ..ReadOptions::default()
    }
}

/// Reads a log into memory, with a spinner.
pub fn read(options: &ReadOptions, path: &str) -> Result<JointLog> {
    let log =
        crate::progress::Bars::new().spin(&format!("reading {path}"), || options.read(path))?;
    Ok(log)
}

/// Options shared by every command that reads logs.
#[derive(clap::Args, Clone)]
pub struct LogArgs {
    /// Log format; wpi is the 2019 headerless CSV [default: recognized from the file's
    /// content]
    #[arg(long, value_parser = super::named::<LogFormat>(), help_heading = INPUT)]
    pub format: Option<LogFormat>,
    /// Sampling rate of logs without time stamps (the 2019 layout), Hz
    #[arg(long, value_name = "HZ", help_heading = INPUT)]
    pub rate: Option<f64>,
    #[command(flatten)]
    pub mcap: McapArgs,
}

impl LogArgs {
    /// How these flags read logs (the robot's joints added by
    /// [`ReadOptions::for_model`]). `--resample` is a processing setting here (see
    /// [`super::settings::SettingFlags`]): the library reads at its rate
    /// ([`ReadOptions::for_processing`]).
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            resample_hz: None,
            ..read_options(self.format, self.rate, &self.mcap)
        }
    }

    /// How the commands that evaluate a result on logs (validate, report, residual,
    /// payload) read them: these flags, the model's measured joints, the processing's
    /// resampling, and the checks across the files (`ReadOptions::for_logs`).
    pub fn read_options_for<'a>(
        &self,
        model: &dvrk_model::Model,
        processing: &impl Resampling,
        logs: impl IntoIterator<Item = &'a str>,
    ) -> ReadOptions {
        self.read_options()
            .for_model(model)
            .for_processing(processing)
            .for_logs(logs.into_iter().map(std::path::Path::new))
    }
}

/// `--joints`, of the commands that show a result's errors (fit, validate, report).
#[derive(clap::Args, Clone)]
pub struct JointsArgs {
    /// Show the errors and figures in the `model` coordinates (q1..qn, the estimator's)
    /// or in the arm's `measured` joints by name (the PSM's outer_wrist_pitch,
    /// outer_wrist_yaw and jaw rather than its motor-side q5..q7); the fit is the same
    #[arg(long, value_parser = super::named::<Joints>(), value_name = "model|measured", help_heading = OUTPUT)]
    pub joints: Option<Joints>,
}

/// The default of each optional flag whose default is the library's: a fit option's
/// ([`Setting::default_text`]) or [`TimeSource::default`], by the flag's id: what the
/// help shows, taken from the library so it cannot drift.
fn library_default(id: &str) -> Option<String> {
    match id {
        "time" => Some(TimeSource::default().name().into()),
        id => Setting::from_name(id).and_then(Setting::default_text),
    }
}

/// Whether a flag is a processing option with a default, which a command that reads a
/// result (`validate`, `report`) takes from the result's settings.
fn result_setting(id: &str) -> bool {
    Setting::from_name(id).is_some_and(|s| {
        (Setting::PROCESSING.contains(&s) || s == Setting::Joints) && s.default_text().is_some()
    })
}

/// Appends `[default: text]` to an argument's help (and long help), as clap does for a
/// `default_value`.
fn with_default(arg: clap::Arg, text: &str) -> clap::Arg {
    let add = |h: &StyledStr| StyledStr::from(format!("{h} [default: {text}]"));
    let help = arg.get_help().map(add);
    let long = arg.get_long_help().map(add);
    let arg = match help {
        Some(h) => arg.help(h),
        None => arg,
    };
    match long {
        Some(h) => arg.long_help(h),
        None => arg,
    }
}

/// `#[command(mut_args = args::library_defaults)]`: the help of the flags whose
/// default is the library's shows it (`fit`, `observe`).
pub fn library_defaults(arg: clap::Arg) -> clap::Arg {
    match library_default(arg.get_id().as_str()) {
        Some(text) => with_default(arg, &text),
        None => arg,
    }
}

/// `#[command(mut_args = args::result_defaults)]`: the processing flags of a command
/// that reads a result (`validate`, `report`) default to the result's settings; the
/// others show the library's default.
pub fn result_defaults(arg: clap::Arg) -> clap::Arg {
    match arg.get_id().as_str() {
        id if result_setting(id) => with_default(arg, "the result's"),
        "time" => library_defaults(arg),
        _ => arg,
    }
}

/// `--mounting-pitch DEG`, for every command that builds a robot's model: the arm's
/// mounting angle, the gravity of [`dvrk_model::Model::mounting_pitch_gravity`]
/// (where a fit is made, the fit option of the same name, [`super::settings`]).
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct MountingArgs {
    /// The arm's mounting pitch, degrees, as the dVRK's `mounting_pitch` (which is in
    /// radians): gravity in the base frame becomes (0, −9.81·sin p, −9.81·cos p) m/s²
    /// (the dVRK mounts PSM1 and PSM2 at −45°, PSM3 at −15°, the ECM at −70° (Si) or
    /// −45° (Classic)). A fit records it and every use of its result applies it
    /// [default: the description's gravity (a result's: its own)]
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, help_heading = MODEL)]
    pub mounting_pitch: Option<f64>,
}

impl MountingArgs {
    /// `model` mounted at the pitch given, if one is.
    pub fn apply(&self, model: &mut dvrk_model::Model) -> Result<()> {
        if let Some(p) = self.mounting_pitch {
            model
                .set_mounting_pitch(p)
                .map_err(|e| anyhow::anyhow!("--mounting-pitch: {e}"))?;
        }
        Ok(())
    }
}
