//! The error type of the identification pipeline: every failure names its input (file,
//! joint, setting) so that the CLI and Python can show it as is.

use thiserror::Error;

/// Error of the identification pipeline.
#[derive(Debug, Error)]
pub enum IdentError {
    #[error(transparent)]
    Model(#[from] dvrk_model::ModelError),
    #[error(transparent)]
    Log(#[from] crate::log::LogError),
    #[error(transparent)]
    Trajectory(#[from] crate::trajectory::TrajectoryError),
    #[error(transparent)]
    Sdp(#[from] crate::estimate::sdp::SdpError),
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    #[error(transparent)]
    Excite(#[from] crate::excite::ExciteError),
    #[error("{}", prefixed(source_name, error))]
    Signal {
        source_name: String,
        error: crate::signal::SignalError,
    },
    /// The log does not fit the robot (joints, sizes).
    #[error("{source_name}: {message}")]
    Mismatch {
        source_name: String,
        message: String,
    },
    /// The data do not determine the parameters (too few or unexciting samples).
    #[error("{source_name}: {message}")]
    RankDeficient {
        source_name: String,
        message: String,
    },
    /// A setting is out of range.
    #[error("invalid setting {name}: {message}")]
    Setting { name: String, message: String },
    /// A file that could not be read (its cause kept: Python maps a missing file to
    /// `FileNotFoundError`).
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// A file whose content is not what it should be (not JSON, not a result, a value
    /// out of range).
    #[error("{file}: {message}")]
    Format { file: String, message: String },
    /// An observation state file that is not one, or not of this format version.
    #[error("{file}: {message}")]
    State { file: String, message: String },
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
