//! The figures the 2019 notebooks showed, as data ready to render: measured vs
//! predicted torques, raw vs processed signals, base parameters with their
//! uncertainty, and an excitation trajectory against its limits.

use dvrk_model::{Limit, Model};
use nalgebra::DMatrix;

use super::plot::{colors, Panel, PanelGrid, Series, SeriesStyle};
use crate::excite::fourier::FourierTrajectory;
use crate::fit::Prepared;
use crate::result::{FitResult, JointMetrics};

/// Units of coordinate `j`: (position, velocity, acceleration, effort).
pub fn units(model: &Model, j: usize) -> [&'static str; 4] {
    if model.coordinate_is_length.get(j).copied().unwrap_or(false) {
        ["m", "m/s", "m/s²", "N"]
    } else {
        ["rad", "rad/s", "rad/s²", "N·m"]
    }
}

/// Seconds since the first sample, so panels of different logs share an origin.
fn relative_time(time: &[f64]) -> Vec<f64> {
    let t0 = time.first().copied().unwrap_or(0.0);
    time.iter().map(|t| t - t0).collect()
}

fn column(m: &DMatrix<f64>, j: usize) -> Vec<f64> {
    m.column(j).iter().copied().collect()
}

/// Measured vs predicted torque with the error trace, one panel per coordinate.
/// `label` names the log (e.g. `training: one.csv`); `metrics` gives the per-joint
/// relative error shown in the titles.
pub fn torque_figure(
    model: &Model,
    label: &str,
    data: &Prepared,
    predicted: &DMatrix<f64>,
    metrics: &JointMetrics,
) -> PanelGrid {
    let t = relative_time(&data.time);
    let panels = (0..model.dof())
        .map(|j| {
            let measured = column(&data.tau, j);
            let pred = column(predicted, j);
            let error: Vec<f64> = measured.iter().zip(&pred).map(|(m, p)| m - p).collect();
            let rel = metrics.relative_error.get(j).copied().unwrap_or(f64::NAN);
            Panel {
                title: format!("{}  (relative error {rel:.4})", model.coordinates[j]),
                x_label: "time (s)".into(),
                y_label: format!("torque ({})", units(model, j)[3]),
                series: vec![
                    Series::line("measured", colors::MEASURED, t.clone(), measured),
                    Series::line("predicted", colors::PREDICTED, t.clone(), pred),
                    Series::line("error", colors::ERROR, t.clone(), error),
                ],
                hlines: Vec::new(),
            }
        })
        .collect();
    PanelGrid {
        title: format!("{} — measured vs predicted torque, {label}", model.name),
        columns: 2,
        panel_size: (640, 260),
        panels,
    }
}

/// Raw vs processed q, q̇, q̈ and τ: one row per coordinate, one column per signal.
/// `raw` is the same log prepared without the low-pass filter (same trimming and
/// differentiation), so the two line up sample by sample.
pub fn processing_figure(
    model: &Model,
    label: &str,
    raw: &Prepared,
    processed: &Prepared,
) -> PanelGrid {
    let t_raw = relative_time(&raw.time);
    let t = relative_time(&processed.time);
    let signals: [(&str, &DMatrix<f64>, &DMatrix<f64>, usize); 4] = [
        ("q", &raw.q, &processed.q, 0),
        ("dq", &raw.dq, &processed.dq, 1),
        ("ddq", &raw.ddq, &processed.ddq, 2),
        ("tau", &raw.tau, &processed.tau, 3),
    ];
    let mut panels = Vec::new();
    for j in 0..model.dof() {
        let u = units(model, j);
        for (name, r, p, unit) in signals {
            panels.push(Panel {
                title: format!("{} {name}", model.coordinates[j]),
                x_label: "time (s)".into(),
                y_label: format!("{name} ({})", u[unit]),
                series: vec![
                    Series::line("raw", colors::RAW, t_raw.clone(), column(r, j)),
                    Series::line("processed", colors::FILTERED, t.clone(), column(p, j)),
                ],
                hlines: Vec::new(),
            });
        }
    }
    PanelGrid {
        title: format!("{} — raw vs processed signals, {label}", model.name),
        columns: 4,
        panel_size: (420, 220),
        panels,
    }
}

/// Relative standard deviations above this are drawn at the cap (%).
pub const RELATIVE_STD_CAP_PERCENT: f64 = 100.0;

/// Base parameters: value ± 2σ, and the relative standard deviation 100·σ/|β| (capped
/// at [`RELATIVE_STD_CAP_PERCENT`]), by base-parameter index (names in the report's
/// table).
pub fn base_parameter_figure(result: &FitResult) -> PanelGrid {
    let x: Vec<f64> = (1..=result.base_parameters.len())
        .map(|i| i as f64)
        .collect();
    let value: Vec<f64> = result.base_parameters.iter().map(|b| b.value).collect();
    let lower = result
        .base_parameters
        .iter()
        .map(|b| b.value - 2.0 * b.std)
        .collect();
    let upper = result
        .base_parameters
        .iter()
        .map(|b| b.value + 2.0 * b.std)
        .collect();
    let relative: Vec<f64> = result
        .base_parameters
        .iter()
        .map(|b| {
            let r = 100.0 * b.std / b.value.abs();
            if r.is_finite() {
                r.min(RELATIVE_STD_CAP_PERCENT)
            } else {
                RELATIVE_STD_CAP_PERCENT
            }
        })
        .collect();
    PanelGrid {
        title: format!(
            "{} — {} base parameters ({})",
            result.robot,
            result.base_parameters.len(),
            result.method
        ),
        columns: 1,
        panel_size: (1100, 300),
        panels: vec![
            Panel {
                title: "value ± 2σ".into(),
                x_label: "base parameter index".into(),
                y_label: "value (SI)".into(),
                series: vec![Series {
                    label: "β ± 2σ".into(),
                    color: colors::MEASURED,
                    style: SeriesStyle::ErrorBars { lower, upper },
                    x: x.clone(),
                    y: value,
                }],
                hlines: vec![(0.0, colors::ERROR)],
            },
            Panel {
                title: format!(
                    "relative standard deviation (capped at {RELATIVE_STD_CAP_PERCENT} %)"
                ),
                x_label: "base parameter index".into(),
                y_label: "100·σ/|β| (%)".into(),
                series: vec![Series {
                    label: String::new(),
                    color: colors::PREDICTED,
                    style: SeriesStyle::Points,
                    x,
                    y: relative,
                }],
                hlines: Vec::new(),
            },
        ],
    }
}

/// One period of an excitation trajectory sampled at `rate_hz`: one panel per
/// coordinate, plus one per limit on a combination of coordinates (e.g. the PSM jaw
/// opening), with the position limits of `limits` (usually `model.limits`) as dashed
/// lines.
pub fn excitation_figure(
    model: &Model,
    traj: &FourierTrajectory,
    limits: &[Limit],
    rate_hz: f64,
) -> PanelGrid {
    let count = ((traj.period_s() * rate_hz).round() as usize).max(2);
    let time: Vec<f64> = (0..=count)
        .map(|k| k as f64 * traj.period_s() / count as f64)
        .collect();
    let (q, _, _) = traj.sample(&time);
    let n = traj.dof();
    let name = |j: usize| {
        traj.coordinates
            .get(j)
            .or(model.coordinates.get(j))
            .cloned()
            .unwrap_or_else(|| format!("q{}", j + 1))
    };
    let mut panels: Vec<Panel> = (0..n)
        .map(|j| Panel {
            title: name(j),
            x_label: "time (s)".into(),
            y_label: format!("position ({})", units(model, j)[0]),
            series: vec![Series::line(
                "",
                colors::CYCLE[j % colors::CYCLE.len()],
                time.clone(),
                column(&q, j),
            )],
            hlines: Vec::new(),
        })
        .collect();
    for limit in limits {
        let Some([lo, hi]) = limit.position else {
            continue;
        };
        let bounds = vec![(lo, colors::LIMIT), (hi, colors::LIMIT)];
        let single = limit.expr.terms.len() == 1
            && limit.expr.terms[0].1 == 1.0
            && limit.expr.offset == 0.0
            && limit.expr.terms[0].0 < n;
        if single {
            panels[limit.expr.terms[0].0].hlines.extend(bounds);
            continue;
        }
        if limit.expr.terms.iter().any(|&(j, _)| j >= n) {
            continue;
        }
        let mut row = vec![0.0; n];
        let values: Vec<f64> = (0..q.nrows())
            .map(|k| {
                for (j, r) in row.iter_mut().enumerate() {
                    *r = q[(k, j)];
                }
                limit.expr.eval(&row)
            })
            .collect();
        let length = limit
            .expr
            .terms
            .iter()
            .all(|&(j, _)| model.coordinate_is_length.get(j).copied().unwrap_or(false));
        panels.push(Panel {
            title: limit.label.clone(),
            x_label: "time (s)".into(),
            y_label: format!("position ({})", if length { "m" } else { "rad" }),
            series: vec![Series::line("", colors::ERROR, time.clone(), values)],
            hlines: bounds,
        });
    }
    PanelGrid {
        title: format!(
            "{} — excitation trajectory (order {}, f0 = {} Hz), one period",
            model.name, traj.order, traj.base_frequency_hz
        ),
        columns: 2,
        panel_size: (560, 220),
        panels,
    }
}
