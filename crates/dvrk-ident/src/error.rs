//! The error type of the identification pipeline: every failure names its input (file,
//! joint, setting) so that the CLI and Python can show it as is.

use thiserror::Error;

use crate::options::Setting;
/// The settings a message suggests, spelled by each front end its own way
/// (`--rate HZ`, `rate=HZ`, with [`dvrk_logs::hint::spelled`]).
use dvrk_logs::hint::Hint;

/// What a refused setting is: fit options by identity (several when they are refused
/// together), or another argument of a call by its name (`wrench`, `observer_gain`).
/// The message names it neutrally (`cutoff`); each front end spells it its own way
/// (`--cutoff`, `cutoff`) from this.
#[derive(Clone, Debug, PartialEq)]
pub enum SettingName {
    /// Fit options.
    Options(Vec<Setting>),
    /// Another argument, by its name (Python's keyword).
    Argument(&'static str),
}

impl From<Setting> for SettingName {
    fn from(s: Setting) -> SettingName {
        SettingName::Options(vec![s])
    }
}

impl std::fmt::Display for SettingName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SettingName::Options(settings) => {
                let names: Vec<&str> = settings.iter().map(|s| s.name()).collect();
                f.write_str(&names.join(", "))
            }
            SettingName::Argument(name) => f.write_str(name),
        }
    }
}

/// Error of the identification pipeline.
#[derive(Debug, Error)]
pub enum IdentError {
    /// A robot description that could not be loaded, or parameters that do not fit it.
    #[error(transparent)]
    Model(#[from] dvrk_model::ModelError),
    /// A log that could not be read or parsed (any format).
    #[error(transparent)]
    Log(#[from] crate::log::LogError),
    /// Samples that do not form a trajectory (sizes, time not increasing, not finite).
    #[error(transparent)]
    JointLog(#[from] crate::JointLogError),
    /// The semidefinite program could not be built or solved.
    #[error(transparent)]
    Sdp(#[from] crate::estimate::sdp::SdpError),
    /// An export (URDF, gravity compensation, params.json, CSV) could not be written.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// An excitation trajectory could not be optimized, read or checked.
    #[error(transparent)]
    Excite(#[from] crate::excite::ExciteError),
    /// Filtering or differentiating one log's signals failed (e.g. a cut-off above Nyquist,
    /// too few samples for the filter).
    #[error("{}", prefixed(source_name, error))]
    Signal {
        /// The log (file or Python data) whose signals failed.
        source_name: String,
        /// What failed.
        error: crate::signal::SignalError,
    },
    /// The log does not fit the robot (joints, sizes).
    #[error("{source_name}: {message}")]
    Mismatch {
        /// The log that does not fit.
        source_name: String,
        /// What differs (a missing joint, a column count).
        message: String,
    },
    /// As [`IdentError::Mismatch`], for a reason that suggests a setting (a robot or
    /// links the dVRK's kinematic gravity compensation cannot hold): kept as the error
    /// itself so that its hints are spelled when shown.
    #[error("{source_name}: {reason}")]
    Unsuited {
        /// What does not fit (`robot `psm``).
        source_name: String,
        /// Why, with the setting it suggests.
        reason: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A log whose measured velocities contradict its clock: a wrong sampling rate
    /// scales every derivative (the accelerations by its square).
    #[error("{source_name}: the measured velocities of joint {joint} are {} times the rate of change of its positions on the log's clock{}: give the log's real sampling rate ({}, or time stamps), or velocities in the positions' units per second", dvrk_model::input::show_significant(*ratio, 3), clock_text(clock_hz), Hint::Rate)]
    WrongClock {
        /// The log.
        source_name: String,
        /// The first joint whose velocities contradict the clock.
        joint: String,
        /// Its measured velocities over the rate of change of its positions.
        ratio: f64,
        /// The log's rate and the rate the velocities match, Hz (`None`: a log
        /// without a uniform rate).
        clock_hz: Option<[f64; 2]>,
    },
    /// Nothing is left of a log once processed (trimmed, decimated).
    #[error(
        "{source_name}: no processed sample is left (a longer log or a smaller {})",
        Hint::Trim
    )]
    NoSampleLeft {
        /// The log.
        source_name: String,
    },
    /// A number of a fit's result that is not finite: no result is written.
    #[error("{robot}: the fit gives {place} = {value}{cause}: no result is written")]
    NotFinite {
        /// The result's robot.
        robot: String,
        /// The number's place in the result (`metrics.test.rms.q1`).
        place: String,
        /// The number.
        value: f64,
        /// Why, where the usual causes tell.
        cause: NotFiniteCause,
    },
    /// A result evaluated on a log that failed (its processing, its metrics).
    #[error("{result}: evaluated on {error}")]
    Evaluated {
        /// The result (its file, or what stands for it).
        result: String,
        /// What failed, kept as the error itself so that its hints are spelled
        /// when shown.
        #[source]
        error: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The data do not determine the parameters (too few or unexciting samples).
    #[error("{source_name}: {message}")]
    RankDeficient {
        /// The log (or `fit` for several) whose regressor lacks rank.
        source_name: String,
        /// Which parameters or why.
        message: String,
    },
    /// A result used with a robot it was not fitted for.
    #[error("{result} was fitted for {fitted}, not {given}")]
    WrongRobot {
        /// The result (its file, or what stands for it).
        result: String,
        /// The robot the result records.
        fitted: String,
        /// The robot it was given with.
        given: String,
    },
    /// A setting is out of range.
    #[error("invalid setting {name}: {message}")]
    Setting {
        /// The setting (e.g. the option `delay`, the argument `wrench`).
        name: SettingName,
        /// The value and the range it should be in.
        message: String,
    },
    /// A file that could not be read (its cause kept: Python maps a missing file to
    /// `FileNotFoundError`).
    #[error("{file}: {source}")]
    Io {
        /// The path that failed.
        file: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A file whose content is not what it should be (not JSON, not a result, a value
    /// out of range).
    #[error("{file}: {message}")]
    Format {
        /// The file, or what stands for it (e.g. `result`).
        file: String,
        /// What is wrong and where.
        message: String,
    },
    /// Two results compared that were fitted for different robots.
    #[error("{a} was fitted for {a_robot}, {b} for {b_robot}: results of different robots do not compare")]
    DifferentRobots {
        /// The first result (its file, or what stands for it).
        a: String,
        /// The robot it records.
        a_robot: String,
        /// The second result.
        b: String,
        /// The robot it records.
        b_robot: String,
    },
    /// An observation state file that is not one, or not of this format version.
    #[error("{file}: {message}")]
    State {
        /// The state file.
        file: String,
        /// What is wrong (version, robot, content).
        message: String,
    },
}

impl IdentError {
    /// A model's refusal of a value a caller gave as a setting (`--frame`,
    /// `--position-torque-frames`): a [`dvrk_model::ModelError::Field`] becomes the
    /// setting's error, so that each front end names the setting its own way; the field
    /// is named in the message unless it is the setting itself (a payload's `frame`), and
    /// any other model error passes unchanged.
    pub(crate) fn of_setting(
        name: impl Into<SettingName>,
    ) -> impl Fn(dvrk_model::ModelError) -> Self {
        let name = name.into();
        move |error| match error {
            dvrk_model::ModelError::Field { field, message, .. } => IdentError::Setting {
                message: if field == name.to_string() {
                    message
                } else {
                    format!("{field}: {message}")
                },
                name: name.clone(),
            },
            other => other.into(),
        }
    }
}

/// Why a number of a result is not finite ([`IdentError::NotFinite`]), shown as a
/// parenthesis after the number (nothing for [`NotFiniteCause::Unknown`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotFiniteCause {
    /// A metric of a role (training, test) with no processed sample.
    NoSample,
    /// A relative error of a joint whose torques are all zero.
    ZeroTorques,
    /// A parameter or its statistics: the data overflow the estimator.
    Overflow,
    /// A metric of none of the usual causes.
    Unknown,
}

impl std::fmt::Display for NotFiniteCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NotFiniteCause::NoSample => write!(
                f,
                " (no processed sample is left for these metrics: a longer log, a smaller {} \
                 or a larger {})",
                Hint::Trim,
                Hint::TestWindow
            ),
            NotFiniteCause::ZeroTorques => f.write_str(
                " (the torques of this joint are all zero, so an error relative to them is \
                 undefined)",
            ),
            NotFiniteCause::Overflow => f.write_str(
                " (the data overflow the estimator: check the log's units and magnitudes)",
            ),
            NotFiniteCause::Unknown => Ok(()),
        }
    }
}

/// ` at RATE Hz; they match a clock of CLOCK Hz` of [`IdentError::WrongClock`].
fn clock_text(clock_hz: &Option<[f64; 2]>) -> String {
    match clock_hz {
        Some([rate, matched]) => format!(
            " at {} Hz; they match a clock of {} Hz",
            dvrk_model::input::show_approx(*rate),
            dvrk_model::input::show_significant(*matched, 3)
        ),
        None => String::new(),
    }
}

/// `source: error`, unless the error already starts with the source (errors of one
/// column name the log themselves).
fn prefixed(source: &str, error: &impl std::fmt::Display) -> String {
    let text = error.to_string();
    if text.starts_with(source) {
        text
    } else {
        format!("{source}: {text}")
    }
}
