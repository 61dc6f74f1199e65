//! The report's error: the drawing library's, a format's, or the identification's.

use thiserror::Error;

use crate::error::IdentError;

/// Errors of figure and report output.
#[derive(Debug, Error)]
pub enum ReportError {
    /// The drawing library failed (should not happen with in-memory backends).
    #[error("drawing a figure failed: {0}")]
    Draw(String),
    /// A requested output format or figure input is not usable.
    #[error("{file}: {message}")]
    Format {
        /// The file, or the input it stands for (e.g. `excitation trajectory`).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// What the report runs of the identification (the result's model, processing,
    /// prediction) or writing its files failed. The report depends on the pipeline's
    /// error, never the reverse.
    #[error(transparent)]
    Ident(#[from] IdentError),
}
