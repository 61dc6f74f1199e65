//! Errors of model construction. Every error names where it comes from (file, frame,
//! field) because a robot description is hand-written and the user must find the line.

use thiserror::Error;

/// Error while loading or building a robot model.
#[derive(Debug, Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The path (or name) of the file that could not be read.
        file: String,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid TOML or does not follow the description schema.
    #[error("{file}: {message}")]
    Syntax {
        /// The file (robot description or limits file) that failed to parse.
        file: String,
        /// The TOML parser's message (with line and column), or what the schema expected.
        message: String,
    },
    /// A field of a frame (or of another section) is wrong.
    #[error("{file}: {place}: field `{field}`: {message}")]
    Field {
        /// The description or limits file the field is in.
        file: String,
        /// Where in the file: `frame 3 (name)`, `constants`, `limits[0] (expr)`,
        /// `cartesian_limits[0] (frame)`.
        place: String,
        /// The field's name, e.g. `mass`, `bounds.fc_max`, or a constant's name.
        field: String,
        /// What is wrong with its value.
        message: String,
    },
    /// The URDF could not be parsed or uses something not supported.
    #[error("{file}: URDF: {message}")]
    Urdf {
        /// The URDF file (or its name).
        file: String,
        /// What could not be parsed or is not supported.
        message: String,
    },
    /// A built-in robot name that does not exist.
    #[error("unknown robot `{0}` (built-in robots: psm, psm_simplified, mtm, ecm, psm_si, psm_si_tool, ecm_si; or give a path to a .toml or .urdf file)")]
    UnknownRobot(String),
    /// A numerical problem while building the model (e.g. no identifiable parameter).
    #[error("{model}: {message}")]
    Numeric {
        /// The model's name, e.g. `psm`.
        model: String,
        /// What went wrong, e.g. that no parameter is identifiable.
        message: String,
    },
}

impl ModelError {
    /// A [`ModelError::Field`]; `message` is a text or a typed error such as
    /// [`crate::input::InputError`].
    pub(crate) fn field(
        file: &str,
        place: impl Into<String>,
        field: &str,
        message: impl std::fmt::Display,
    ) -> Self {
        ModelError::Field {
            file: file.to_string(),
            place: place.into(),
            field: field.to_string(),
            message: message.to_string(),
        }
    }
}
