//! The reading options of every log format, in one place: the command line's `--format
//! --rate --topic --time --resample` and Python's `read_log(format=, rate=, topic=,
//! time_source=, resample=)` are both mapped onto [`ReadOptions`], so a log read by one
//! front end is the log read by the other.

use std::path::Path;

use dvrk_model::Model;

#[allow(unused_imports)] // McapOptions: the docs' link without `recordings`
use super::mcap::{McapOptions, TimeSource};
use super::{LogError, LogFormat};

/// A processing of logs that may resample them ([`ReadOptions::for_processing`]):
/// dvrk-ident's `signal::Processing`, or the rate itself.
pub trait Resampling {
    /// The uniform rate the logs are resampled to, Hz; `None`: not resampled.
    fn resample_hz(&self) -> Option<f64>;
}

impl Resampling for Option<f64> {
    fn resample_hz(&self) -> Option<f64> {
        *self
    }
}

/// How to read a log, whatever its format.
///
/// ```rust
/// use dvrk_logs::log::{write_wpi, LogFormat, ReadOptions};
/// use dvrk_logs::{Coordinates, JointLog, uniform_time};
/// use nalgebra::DMatrix;
///
/// let path = std::env::temp_dir().join(format!("dvrk-ident-doc-options-{}.csv", std::process::id()));
/// let log = JointLog {
///     time: uniform_time(4, 200.0),
///     q: DMatrix::from_element(4, 2, 0.5),
///     dq: Some(DMatrix::zeros(4, 2)),
///     tau: DMatrix::from_element(4, 2, -1.25),
///     joint_names: vec!["q1".into(), "q2".into()],
///     coordinates: Coordinates::Model,
///     source: "doc".into(),
/// };
/// write_wpi(&path, &log).unwrap();
/// let options = ReadOptions { rate_hz: Some(200.0), ..ReadOptions::default() };
/// assert_eq!(options.read(&path).unwrap().len(), 4);
/// // A recording's option on a CSV log is refused, naming the file.
/// let topics = ReadOptions { topics: vec!["/PSM1/measured_js".into()], ..options.clone() };
/// let err = topics.read(&path).unwrap_err().to_string();
/// assert!(err.contains("applies to recordings") && err.contains("dvrk-ident-doc-options"), "{err}");
/// // The 2019 layout checked against the expected number of joints.
/// let three = ReadOptions { dof: Some(3), ..options };
/// assert!(three.read(&path).is_err());
/// std::fs::remove_file(&path).unwrap();
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// The layout; `None`: recognized from the file's content ([`super::detect_format`]).
    pub format: Option<LogFormat>,
    /// Sampling rate of the 2019 layout, which has no time stamps, Hz (the dVRK logs
    /// are 200 Hz); ignored by formats with time stamps.
    pub rate_hz: Option<f64>,
    /// Recordings: the `sensor_msgs/msg/JointState` topics to merge, the first being the
    /// clock; empty: chosen automatically (see [`McapOptions::topics`]). Refused for other
    /// formats.
    pub topics: Vec<String>,
    /// Recordings: where the sample times come from; `None`: the header stamps. Refused
    /// for other formats.
    pub time_source: Option<TimeSource>,
    /// Resample every format to this uniform rate, Hz, by linear interpolation while
    /// reading (bridges gaps and jitter, which are refused otherwise).
    pub resample_hz: Option<f64>,
    /// The robot's measured joints: they guide the automatic topic choice (a dVRK 2.x
    /// PSM's arm and jaw topics are paired). Set by [`ReadOptions::for_model`].
    pub joints: Vec<String>,
    /// The 2019 layout: the number of joints its rows must hold (3 columns each);
    /// `None`: columns / 3. Set by [`ReadOptions::for_model`].
    pub dof: Option<usize>,
    /// [`ReadOptions::rate_hz`] is for the 2019-layout logs among several read together,
    /// so the others (with time stamps) do not refuse it. Set by
    /// [`ReadOptions::for_logs`].
    pub rate_for_some_logs: bool,
    /// Recordings: the largest size a compressed sqlite3 or ROS 1 file may decompress
    /// to, MiB ([`McapOptions::max_unpacked_mib`]); `None`: the default bound.
    pub max_unpacked_mib: Option<u64>,
}

impl ReadOptions {
    /// These options for `model`'s logs: its measured joints guide the topic choice and
    /// a 2019-layout log must have its number of model coordinates.
    pub fn for_model(&self, model: &Model) -> ReadOptions {
        ReadOptions {
            joints: model.measured.joints.clone(),
            dof: Some(model.dof()),
            ..self.clone()
        }
    }

    /// These options for the logs of a processing: a processing that resamples
    /// (`resample_hz`) reads at that rate, unless these options resample already. A
    /// recording with gaps, which the readers refuse unless they resample, then reads
    /// as it will be processed; resampling it again at the same rate changes nothing,
    /// the grid's times being the samples' own. So `fit --resample` (a processing
    /// setting, recorded in the result) reads the recordings that need it, as Python's
    /// `fit(resample=)` does.
    ///
    /// ```rust
    /// use dvrk_logs::log::ReadOptions;
    ///
    /// // dvrk-ident's `signal::Processing` or just the rate it resamples to
    /// let processing = Some(250.0);
    /// assert_eq!(ReadOptions::default().for_processing(&processing).resample_hz, Some(250.0));
    /// let read_at_200 = ReadOptions { resample_hz: Some(200.0), ..ReadOptions::default() };
    /// assert_eq!(read_at_200.for_processing(&processing).resample_hz, Some(200.0));
    /// ```
    pub fn for_processing(&self, processing: &impl Resampling) -> ReadOptions {
        ReadOptions {
            resample_hz: self.resample_hz.or(processing.resample_hz()),
            ..self.clone()
        }
    }

    /// These options for reading `paths` together (a fit's training and test logs):
    /// a rate given for the 2019-layout logs among them is not refused for the others,
    /// which carry their own time stamps; with no such log it is (it would change
    /// nothing).
    pub fn for_logs<'a>(&self, paths: impl IntoIterator<Item = &'a Path>) -> ReadOptions {
        let some_wpi = self.rate_hz.is_some()
            && self.format.is_none()
            && paths
                .into_iter()
                .any(|p| matches!(super::detect_format(p), Ok(LogFormat::Wpi)));
        ReadOptions {
            rate_for_some_logs: some_wpi,
            ..self.clone()
        }
    }

    /// The recording reader's options.
    #[cfg(feature = "recordings")]
    pub(super) fn recording(&self) -> McapOptions {
        McapOptions {
            topics: self.topics.clone(),
            time_source: self.time_source.unwrap_or_default(),
            resample_hz: self.resample_hz,
            joints: self.joints.clone(),
            max_unpacked_mib: self.max_unpacked_mib,
        }
    }

    /// Refuses a recording's option for a log of another format, and a sampling rate for
    /// a log with time stamps (both would change nothing the user asked for).
    pub(super) fn check_format(&self, path: &Path, format: LogFormat) -> Result<(), LogError> {
        if self.rate_hz.is_some() && format != LogFormat::Wpi && !self.rate_for_some_logs {
            return Err(LogError::RateNotApplicable {
                path: path.to_path_buf(),
                format,
            });
        }
        let option = if !self.topics.is_empty() {
            "a topic"
        } else if self.time_source.is_some() {
            "a time source"
        } else {
            return Ok(());
        };
        if format.has_topics() {
            return Ok(());
        }
        Err(LogError::NotARecording {
            path: path.to_path_buf(),
            format,
            option,
        })
    }
}
