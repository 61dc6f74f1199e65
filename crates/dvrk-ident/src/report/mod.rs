//! Reports people look at: the figures of a fit and one self-contained `report.html`.
//!
//! [`build`] computes everything in memory (predictions, figures as SVG and PNG, the
//! HTML page with the SVGs inlined) and [`Report::write`] writes the files atomically
//! afterwards, so a failure half-way never leaves a half-written report.

pub mod draw;
pub mod figures;
pub mod html;
pub mod plot;

use std::path::{Path, PathBuf};

use dvrk_model::Model;
use thiserror::Error;

use crate::error::IdentError;
use crate::excite::fourier::FourierTrajectory;
use crate::fit::{joint_metrics, predict, prepare, to_model_coordinates, Prepared};
use crate::result::{FitResult, JointMetrics};
use crate::trajectory::Trajectory;
use plot::{render, Figure, ImageFormat};

/// Errors of figure and report output.
#[derive(Debug, Error)]
pub enum ReportError {
    /// The drawing library failed (should not happen with in-memory backends).
    #[error("drawing a figure failed: {0}")]
    Draw(String),
    /// A requested output format or figure input is not usable.
    #[error("{file}: {message}")]
    Format { file: String, message: String },
}

/// One log shown in the report.
#[derive(Clone, Copy, Debug)]
pub struct ReportLog<'a> {
    /// Shown in titles and tables, e.g. `training` or `test`.
    pub role: &'a str,
    pub trajectory: &'a Trajectory,
    /// Metrics on the first N processed samples only (the 2019 test protocol).
    pub window: Option<usize>,
}

/// What a report is made from.
#[derive(Clone, Debug)]
pub struct ReportInput<'a> {
    pub model: &'a Model,
    pub result: &'a FitResult,
    pub logs: Vec<ReportLog<'a>>,
    /// Excitation trajectory to plot against the model's limits.
    pub excitation: Option<&'a FourierTrajectory>,
}

/// A figure of the report, rendered in both formats.
#[derive(Clone, Debug)]
pub struct RenderedFigure {
    /// File stem, e.g. `torque_1_training`.
    pub stem: String,
    pub caption: String,
    pub svg: String,
    pub png: Vec<u8>,
}

/// Per-log numbers computed for the report.
#[derive(Clone, Debug)]
pub struct LogSummary {
    pub role: String,
    pub source: String,
    pub metrics: JointMetrics,
}

/// A report in memory.
#[derive(Clone, Debug)]
pub struct Report {
    pub figures: Vec<RenderedFigure>,
    pub logs: Vec<LogSummary>,
    pub html: String,
}

/// Renders `figure` in both formats under `stem`.
pub fn render_both(
    figure: &impl Figure,
    stem: &str,
    caption: &str,
) -> Result<RenderedFigure, ReportError> {
    let svg = String::from_utf8(render(figure, ImageFormat::Svg)?)
        .map_err(|e| ReportError::Draw(format!("SVG is not UTF-8: {e}")))?;
    Ok(RenderedFigure {
        stem: stem.into(),
        caption: caption.into(),
        svg,
        png: render(figure, ImageFormat::Png)?,
    })
}

/// Renders one figure to `path` (SVG or PNG by extension), atomically.
pub fn write_figure(figure: &impl Figure, path: &Path) -> Result<(), IdentError> {
    let bytes = render(figure, ImageFormat::from_path(path)?)?;
    crate::log::write_atomic(path, |w| w.write_all(&bytes)).map_err(IdentError::from)
}

/// A file-name-safe version of a role (`test 2` → `test_2`).
fn slug(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect()
}

/// Builds the whole report in memory.
///
/// Each log is processed with the result's own settings, predicted with its parameters
/// and drawn (torques, and raw vs processed signals: the same processing without the
/// low-pass filter, so both line up). The tree is drawn at the first sample of the
/// first log (at zero without logs).
pub fn build(input: &ReportInput<'_>) -> Result<Report, IdentError> {
    let model = input.model;
    let result = input.result;
    let params = result.params_for(model)?;
    let processing = &result.settings.processing;
    let mut unfiltered = processing.clone();
    unfiltered.filter = None;

    let mut figures = Vec::new();
    let mut logs = Vec::new();
    let mut q_draw = vec![0.0; model.dof()];
    for (k, log) in input.logs.iter().enumerate() {
        let data: Prepared = prepare(model, log.trajectory, processing)?;
        let raw = prepare(model, log.trajectory, &unfiltered)?;
        if k == 0 {
            let t = to_model_coordinates(model, log.trajectory)?;
            if !t.is_empty() {
                for (j, v) in q_draw.iter_mut().enumerate() {
                    *v = t.q[(0, j)];
                }
            }
        }
        let predicted = predict(model, &params, &data);
        let metrics = joint_metrics(model, &params, &data, log.window);
        let label = format!("{} ({})", log.role, data.source);
        let stem = format!("{}_{}", k + 1, slug(log.role));
        figures.push(render_both(
            &figures::torque_figure(model, &label, &data, &predicted, &metrics),
            &format!("torque_{stem}"),
            &format!("Measured vs predicted torque and error, {label}."),
        )?);
        figures.push(render_both(
            &figures::processing_figure(model, &label, &raw, &data),
            &format!("processing_{stem}"),
            &format!("Raw vs processed q, dq, ddq and tau, {label}."),
        )?);
        logs.push(LogSummary {
            role: log.role.into(),
            source: data.source.clone(),
            metrics,
        });
    }
    if !result.base_parameters.is_empty() {
        figures.push(render_both(
            &figures::base_parameter_figure(result),
            "base_parameters",
            "Base parameters with two standard deviations, and relative standard deviations.",
        )?);
    }
    if let Some(traj) = input.excitation {
        traj.validate("excitation trajectory")
            .map_err(|e| ReportError::Format {
                file: "excitation trajectory".into(),
                message: e.to_string(),
            })?;
        if traj.dof() != model.dof() {
            return Err(ReportError::Format {
                file: "excitation trajectory".into(),
                message: format!(
                    "{} coordinates, but {} has {}",
                    traj.dof(),
                    model.name,
                    model.dof()
                ),
            }
            .into());
        }
        figures.push(render_both(
            &figures::excitation_figure(model, traj, &model.limits, 200.0),
            "excitation",
            "Excitation trajectory over one period, with the position limits (dashed).",
        )?);
    }
    let drawing =
        draw::kinematic_drawing(model, &q_draw).map_err(|message| ReportError::Format {
            file: "kinematic drawing".into(),
            message,
        })?;
    figures.push(render_both(
        &drawing,
        "kinematics",
        "Kinematic tree at the first sample of the first log.",
    )?);
    let html = html::page(model, result, &logs, &figures);
    Ok(Report {
        figures,
        logs,
        html,
    })
}

impl Report {
    /// Writes `report.html` and every figure as SVG and PNG into `dir` (created if
    /// missing), each file atomically; returns the paths written, the page last.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, IdentError> {
        std::fs::create_dir_all(dir).map_err(|e| IdentError::Io {
            file: dir.display().to_string(),
            message: format!("cannot create the report folder: {e}"),
        })?;
        let mut written = Vec::new();
        let mut put = |name: String, bytes: &[u8]| -> Result<(), IdentError> {
            let path = dir.join(name);
            crate::log::write_atomic(&path, |w| w.write_all(bytes))?;
            written.push(path);
            Ok(())
        };
        for f in &self.figures {
            put(format!("{}.svg", f.stem), f.svg.as_bytes())?;
            put(format!("{}.png", f.stem), &f.png)?;
        }
        put("report.html".into(), self.html.as_bytes())?;
        Ok(written)
    }
}
