//! A report in memory (figures, per-log numbers, the page) and how its files are
//! written: all of them or none.

use std::path::{Path, PathBuf};

use super::error::ReportError;
use super::plot::RenderedFigure;
use crate::error::IdentError;
use crate::result::JointMetrics;

/// Per-log numbers computed for the report.
#[derive(Clone, Debug)]
pub struct LogSummary {
    /// The log's role, as in [`ReportLog::role`](super::ReportLog::role).
    pub role: String,
    /// The log's source (file, or name given in Python).
    pub source: String,
    /// The fitted model's errors on the log (over its window, if any).
    pub metrics: JointMetrics,
}

/// A report in memory.
#[derive(Clone, Debug)]
pub struct Report {
    /// Every figure, in page order.
    pub figures: Vec<RenderedFigure>,
    /// The numbers of each log, in the order given.
    pub logs: Vec<LogSummary>,
    /// The self-contained page `report.html`: tables, and the figures inlined as SVG.
    pub html: String,
}

impl Report {
    /// The files of the report: every figure as SVG and PNG, then `report.html`.
    pub fn files(&self) -> Vec<(String, &[u8])> {
        let mut files = Vec::with_capacity(2 * self.figures.len() + 1);
        for f in &self.figures {
            files.push((format!("{}.svg", f.stem), f.svg.as_bytes()));
            files.push((format!("{}.png", f.stem), f.png.as_slice()));
        }
        files.push(("report.html".into(), self.html.as_bytes()));
        files
    }

    /// Stages the report's files into `dir` among a command's other outputs (see
    /// [`crate::output::Outputs::add_dir`]: a new `dir` is created at the commit, its
    /// parent folder must exist); returns the paths, the page last.
    pub fn stage(
        &self,
        outputs: &mut crate::output::Outputs,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, ReportError> {
        Ok(outputs
            .add_dir(dir, &self.files())
            .map_err(IdentError::from)?)
    }

    /// Writes `report.html` and every figure as SVG and PNG into `dir` (created if
    /// missing, but not its parent), all of them or none; returns the paths written,
    /// the page last.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, ReportError> {
        let mut outputs = crate::output::Outputs::new();
        let written = self.stage(&mut outputs, dir)?;
        outputs.commit().map_err(IdentError::from)?;
        Ok(written)
    }
}
