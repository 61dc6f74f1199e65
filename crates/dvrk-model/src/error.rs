//! Errors of model construction. Every error names where it comes from (file, frame,
//! field) because a robot description is hand-written and the user must find the line.

use thiserror::Error;

/// Error while loading or building a robot model.
#[derive(Debug, Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid TOML or does not follow the description schema.
    #[error("{file}: {message}")]
    Syntax { file: String, message: String },
    /// A field of a frame (or of another section) is wrong.
    #[error("{file}: {place}: field `{field}`: {message}")]
    Field {
        file: String,
        place: String,
        field: String,
        message: String,
    },
    /// The URDF could not be parsed or uses something not supported.
    #[error("{file}: URDF: {message}")]
    Urdf { file: String, message: String },
    /// A built-in robot name that does not exist.
    #[error("unknown robot `{0}` (built-in robots: psm, psm_simplified, mtm; or give a path to a .toml or .urdf file)")]
    UnknownRobot(String),
    /// A numerical problem while building the model (e.g. no identifiable parameter).
    #[error("{model}: {message}")]
    Numeric { model: String, message: String },
}

impl ModelError {
    pub(crate) fn field(
        file: &str,
        place: impl Into<String>,
        field: &str,
        message: impl Into<String>,
    ) -> Self {
        ModelError::Field {
            file: file.to_string(),
            place: place.into(),
            field: field.to_string(),
            message: message.into(),
        }
    }
}
