//! Reports people look at: the figures of a fit and one self-contained `report.html`.
//!
//! [`build`] computes everything in memory (predictions, figures as SVG and PNG, the
//! HTML page with the SVGs inlined) and [`Report::write`] writes the files atomically
//! afterwards, so a failure half-way never leaves a half-written report.

pub mod base_chart;
pub mod curves;
mod document;
pub mod draw;
mod error;
pub mod figures;
pub mod html;
pub mod plot;
pub mod residual;

use dvrk_model::Model;

use crate::excite::FourierTrajectory;
use crate::fit::{joint_metrics, predict, prepare, to_model_coordinates, JointMap, Prepared};
use crate::log::ReadOptions;
use crate::result::FitResult;
use crate::settings::FitSettings;
use crate::JointLog;
pub use document::{LogSummary, Report};
pub use error::ReportError;
pub use plot::{figure_bytes, render_both, write_figure, RenderedFigure};

/// One log shown in the report.
#[derive(Clone, Copy, Debug)]
pub struct ReportLog<'a> {
    /// Shown in titles and tables, e.g. `training` or `test`.
    pub role: &'a str,
    /// The log as read (measured joints), processed here with the result's settings.
    pub trajectory: &'a JointLog,
    /// Metrics on the first N processed samples only (the 2019 test protocol).
    pub window: Option<usize>,
}

/// What a report is made from.
#[derive(Clone, Debug)]
pub struct ReportInput<'a> {
    /// The robot as loaded, without the fit's Stribeck terms (the result's settings add them).
    pub model: &'a Model,
    /// The fit whose parameters predict the logs.
    pub result: &'a FitResult,
    /// The logs to draw and to compute metrics on, in order; the first also poses the
    /// kinematic drawing.
    pub logs: Vec<ReportLog<'a>>,
    /// Excitation trajectory to plot against the model's limits.
    pub excitation: Option<&'a FourierTrajectory>,
    /// How the result's logs were read (`--format`, `--rate`, ...), which the result does
    /// not record: the page's command line includes them; `None` says they are unknown.
    pub read: Option<&'a ReadOptions>,
    /// The settings the logs are processed and shown with where they differ from the
    /// result's (`report`'s processing flags, `--joints`): the page lists what differs,
    /// and keeps the result's own for the fit's numbers and command line. `None`: the
    /// result's.
    pub settings: Option<&'a FitSettings>,
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
/// low-pass filter, so both line up), with [`ReportInput::settings`]. The tree is drawn at the first sample of the
/// first log (at zero without logs).
pub fn build(input: &ReportInput<'_>) -> Result<Report, ReportError> {
    let result = input.result;
    let model_cow = result.settings.model(input.model)?;
    let model: &Model = &model_cow;
    let params = result.params_for(model)?;
    let shown = input.settings.unwrap_or(&result.settings);
    let processing = &shown.processing;
    let joints = JointMap::new(model, shown.joints)?;
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
        let metrics = joint_metrics(model, &params, &data, log.window, &joints)?;
        let label = format!("{} ({})", log.role, data.source);
        let stem = format!("{}_{}", k + 1, slug(log.role));
        let (shown, shown_raw, shown_predicted) = (
            joints.prepared(&data),
            joints.prepared(&raw),
            joints.torque(&predicted),
        );
        let zoom = figures::zoom_window(&shown.time, &shown.tau);
        let zoom_words = figures::zoom_caption(&shown.time, zoom);
        figures.push(render_both(
            &figures::torque_figure(&joints, &label, &shown, &shown_predicted, &metrics, zoom),
            &format!("torque_{stem}"),
            &format!("Measured vs predicted torque and their difference, {label}. {zoom_words}"),
        )?);
        figures.push(render_both(
            &figures::processing_figure(&joints, &label, &shown_raw, &shown, zoom),
            &format!("processing_{stem}"),
            &format!("Raw vs processed q, dq, ddq and tau, {label}. {zoom_words}"),
        )?);
        figures.push(render_both(
            &figures::friction_figure(
                &joints,
                &label,
                &curves::friction_curves(model, &params, &data, &joints),
            ),
            &format!("friction_{stem}"),
            &format!(
                "Friction against velocity, {label}: the measured torque minus the fitted \
                 model without its friction terms (links, motor inertias, springs), median \
                 and quartiles over {} velocity bins (0 is a bin edge; bins with fewer than \
                 {} samples left out), and the fitted friction terms' torque on the same \
                 samples (median per bin).",
                curves::BINS,
                curves::MIN_BIN_SAMPLES
            ),
        )?);
        figures.push(render_both(
            &figures::residual_figure(
                &joints,
                &label,
                &curves::residual_curves(
                    &joints,
                    &shown,
                    &shown_predicted,
                    curves::Against::Velocity,
                ),
                &curves::residual_curves(
                    &joints,
                    &shown,
                    &shown_predicted,
                    curves::Against::Position,
                ),
            ),
            &format!("residuals_{stem}"),
            &format!(
                "Prediction error τ − τ̂ against each coordinate's velocity and position, \
                 {label}: median and quartiles over {} bins (bins with fewer than {} samples \
                 left out). A trend is what the model misses: friction shapes against \
                 velocity, gravity or cable terms against position.",
                curves::BINS,
                curves::MIN_BIN_SAMPLES
            ),
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
            &format!(
                "Base parameters by name (a long expression shows its leading name and its \
                 number of terms; the Base parameters table has every expression): value ± 2σ on a \
                 symmetric logarithmic axis, linear within ±{:e}, and the relative standard \
                 deviation on a logarithmic axis.",
                base_chart::BaseParameterChart::new(result).linear_threshold()
            ),
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
            });
        }
        figures.push(render_both(
            &figures::excitation_figure(model, traj, &model.limits, 200.0),
            "excitation",
            "Excitation trajectory over one period, with the position limits (dashed).",
        )?);
    }
    let drawing = draw::kinematic_drawing(model, &q_draw).map_err(|e| ReportError::Format {
        file: "kinematic drawing".into(),
        message: e.to_string(),
    })?;
    figures.push(render_both(
        &drawing,
        "kinematics",
        "Kinematic tree at the first sample of the first log.",
    )?);
    let differences = shown.differences(&result.settings);
    let html = html::page(
        model,
        result,
        &html::Shown {
            joints: &joints,
            differences: &differences,
        },
        &logs,
        &figures,
        input.read,
    );
    Ok(Report {
        figures,
        logs,
        html,
    })
}
