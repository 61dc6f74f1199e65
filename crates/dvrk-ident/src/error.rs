//! The error type of the identification pipeline: every failure names its input (file,
//! joint, setting) so that the CLI and Python can show it as is.

use thiserror::Error;

use crate::options::Setting;

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
    JointLog(#[from] crate::joint_log::JointLogError),
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
