//! The figures the 2019 notebooks showed, as data ready to render: measured vs
//! predicted torques, raw vs processed signals, base parameters with their
//! uncertainty, and an excitation trajectory against its limits.

use dvrk_model::{Limit, Model};
use nalgebra::DMatrix;

use super::curves::Curve;
use super::plot::{colors, Panel, PanelGrid, Series, SeriesStyle};
use crate::excite::FourierTrajectory;
use crate::fit::{JointMap, Prepared};
use crate::result::{FitResult, JointMetrics};

/// Units of model coordinate `j`: (position, velocity, acceleration, effort).
pub fn units(model: &Model, j: usize) -> [&'static str; 4] {
    crate::fit::units(model.coordinate_is_length.get(j).copied().unwrap_or(false))
}

/// Seconds since the first sample, so panels of different logs share an origin.
fn relative_time(time: &[f64]) -> Vec<f64> {
    let t0 = time.first().copied().unwrap_or(0.0);
    time.iter().map(|t| t - t0).collect()
}

fn column(m: &DMatrix<f64>, j: usize) -> Vec<f64> {
    m.column(j).iter().copied().collect()
}

/// Longest zoomed window of a log, s.
pub const ZOOM_SECONDS: f64 = 4.0;

/// The zoomed window of a log, samples `[a, b)`: the [`ZOOM_SECONDS`] (at most a quarter
/// of the log) in which the measured torques vary most, i.e. the window that maximizes
/// the sum over coordinates of the torque's variance in the window divided by its
/// variance over the whole log (each coordinate counts alike, whatever its unit), over
/// starts every eighth of a window; the earliest on ties. The same window serves every
/// coordinate and every figure of the log, so they line up.
pub fn zoom_window(time: &[f64], tau: &DMatrix<f64>) -> (usize, usize) {
    let n = time.len().min(tau.nrows());
    if n < 8 {
        return (0, n);
    }
    let duration = time[n - 1] - time[0];
    let step = duration / (n - 1) as f64;
    let seconds = ZOOM_SECONDS.min(duration / 4.0);
    let w = if step > 0.0 {
        ((seconds / step).round() as usize).clamp(2, n)
    } else {
        n
    };
    // Prefix sums of τ and τ² per coordinate.
    let cols = tau.ncols();
    let mut s1 = vec![vec![0.0; n + 1]; cols];
    let mut s2 = vec![vec![0.0; n + 1]; cols];
    for j in 0..cols {
        for k in 0..n {
            let v = tau[(k, j)];
            s1[j][k + 1] = s1[j][k] + v;
            s2[j][k + 1] = s2[j][k] + v * v;
        }
    }
    let variance = |j: usize, a: usize, b: usize| {
        let m = (b - a) as f64;
        let mean = (s1[j][b] - s1[j][a]) / m;
        ((s2[j][b] - s2[j][a]) / m - mean * mean).max(0.0)
    };
    let total: Vec<f64> = (0..cols).map(|j| variance(j, 0, n)).collect();
    let score = |a: usize| -> f64 {
        (0..cols)
            .filter(|&j| total[j] > 0.0)
            .map(|j| variance(j, a, a + w) / total[j])
            .sum()
    };
    let mut best = (0, score(0));
    let mut a = 0;
    while a + w <= n {
        let s = score(a);
        if s > best.1 {
            best = (a, s);
        }
        a += (w / 8).max(1);
    }
    (best.0, best.0 + w)
}

/// The caption's words for the zoom of a log.
pub fn zoom_caption(time: &[f64], window: (usize, usize)) -> String {
    let t = relative_time(time);
    let (a, b) = window;
    if b == 0 || t.is_empty() {
        return String::new();
    }
    format!(
        "The narrow panels zoom on t = {:.1}–{:.1} s (shaded in the whole-log panels): the \
         {ZOOM_SECONDS:.0} s (at most a quarter of the log) where the measured torques vary \
         most, each coordinate's variance in the window relative to the whole log's, summed.",
        t[a],
        t[b - 1]
    )
}

fn slice(v: &[f64], (a, b): (usize, usize)) -> Vec<f64> {
    v[a.min(v.len())..b.min(v.len())].to_vec()
}

/// Measured vs predicted torque with the error trace, one row per coordinate: the whole
/// log, and beside it the window `zoom` (samples, from [`zoom_window`]). `label` names
/// the log (e.g. `training: one.csv`); `metrics` gives the per-joint relative error shown
/// in the titles.
pub fn torque_figure(
    joints: &JointMap,
    label: &str,
    data: &Prepared,
    predicted: &DMatrix<f64>,
    metrics: &JointMetrics,
    zoom: (usize, usize),
) -> PanelGrid {
    let t = relative_time(&data.time);
    let span = zoom_span(&t, zoom);
    let mut panels = Vec::new();
    for j in 0..joints.dof() {
        let measured = column(&data.tau, j);
        let pred = column(predicted, j);
        let error: Vec<f64> = measured.iter().zip(&pred).map(|(m, p)| m - p).collect();
        let rel = metrics.relative_error.get(j).copied().unwrap_or(f64::NAN);
        let y_label = format!("torque ({})", joints.units(j)[3]);
        let series = |part: Option<(usize, usize)>| {
            let cut = |v: &Vec<f64>| part.map_or_else(|| v.clone(), |w| slice(v, w));
            vec![
                Series::line("measured", colors::MEASURED, cut(&t), cut(&measured)),
                Series::line("predicted", colors::PREDICTED, cut(&t), cut(&pred)),
                Series::line("measured − predicted", colors::ERROR, cut(&t), cut(&error)),
            ]
        };
        panels.push(Panel {
            title: format!("{}  (relative error {rel:.4})", joints.names[j]),
            x_label: "time (s)".into(),
            y_label: y_label.clone(),
            series: series(None),
            hlines: Vec::new(),
            vspans: span.into_iter().collect(),
        });
        panels.push(Panel {
            title: format!("{}  zoom", joints.names[j]),
            x_label: "time (s)".into(),
            y_label,
            series: series(Some(zoom)),
            hlines: Vec::new(),
            vspans: Vec::new(),
        });
    }
    PanelGrid {
        title: format!("{} — measured vs predicted torque, {label}", joints.robot),
        columns: 2,
        panel_size: (600, 230),
        column_weights: vec![2, 1],
        panels,
    }
}

/// The zoomed window in seconds, for the shading of the whole-log panels.
fn zoom_span(t: &[f64], (a, b): (usize, usize)) -> Option<(f64, f64)> {
    (b > a && b <= t.len()).then(|| (t[a], t[b - 1]))
}

/// Raw vs processed q, q̇, q̈ and τ: two rows per coordinate (q and q̇, then q̈ and τ),
/// each signal over the whole log and beside it the window `zoom` (samples of
/// `processed`, from [`zoom_window`]). `raw` is the same log prepared without the
/// low-pass filter (same trimming and differentiation), so the two line up sample by
/// sample.
pub fn processing_figure(
    joints: &JointMap,
    label: &str,
    raw: &Prepared,
    processed: &Prepared,
    zoom: (usize, usize),
) -> PanelGrid {
    let t_raw = relative_time(&raw.time);
    let t = relative_time(&processed.time);
    let span = zoom_span(&t, zoom);
    // The raw samples inside the window, by time (the two logs share their clock).
    let raw_zoom = span.map_or((0, 0), |(a, b)| {
        let first = t_raw.partition_point(|&s| s < a);
        (first, t_raw.partition_point(|&s| s <= b))
    });
    let signals: [(&str, &DMatrix<f64>, &DMatrix<f64>, usize); 4] = [
        ("q", &raw.q, &processed.q, 0),
        ("dq", &raw.dq, &processed.dq, 1),
        ("ddq", &raw.ddq, &processed.ddq, 2),
        ("tau", &raw.tau, &processed.tau, 3),
    ];
    let mut panels = Vec::new();
    for j in 0..joints.dof() {
        let u = joints.units(j);
        for (name, r, p, unit) in signals {
            let (r, p) = (column(r, j), column(p, j));
            let y_label = format!("{name} ({})", u[unit]);
            panels.push(Panel {
                title: format!("{} {name}", joints.names[j]),
                x_label: "time (s)".into(),
                y_label: y_label.clone(),
                series: vec![
                    Series::line("raw", colors::RAW, t_raw.clone(), r.clone()),
                    Series::line("processed", colors::FILTERED, t.clone(), p.clone()),
                ],
                hlines: Vec::new(),
                vspans: span.into_iter().collect(),
            });
            panels.push(Panel {
                title: format!("{} {name} zoom", joints.names[j]),
                x_label: "time (s)".into(),
                y_label,
                series: vec![
                    Series::line(
                        "raw",
                        colors::RAW,
                        slice(&t_raw, raw_zoom),
                        slice(&r, raw_zoom),
                    ),
                    Series::line(
                        "processed",
                        colors::FILTERED,
                        slice(&t, zoom),
                        slice(&p, zoom),
                    ),
                ],
                hlines: Vec::new(),
                vspans: Vec::new(),
            });
        }
    }
    PanelGrid {
        title: format!("{} — raw vs processed signals, {label}", joints.robot),
        columns: 4,
        panel_size: (400, 210),
        column_weights: vec![2, 1, 2, 1],
        panels,
    }
}

/// The median and quartiles of a binned curve as an error-bar series.
fn quartile_series(label: &str, color: plotters::style::RGBColor, curve: &Curve) -> Series {
    Series {
        label: label.into(),
        color,
        style: SeriesStyle::ErrorBars {
            lower: curve.bins.iter().map(|b| b.measured.lower).collect(),
            upper: curve.bins.iter().map(|b| b.measured.upper).collect(),
        },
        x: curve.bins.iter().map(|b| b.x).collect(),
        y: curve.bins.iter().map(|b| b.measured.median).collect(),
    }
}

/// The friction of each coordinate against its velocity (one panel per coordinate):
/// the measured torque minus the model without friction, median and quartiles per
/// velocity bin, and the fitted friction (the model's friction torque, median over the
/// same samples) as a line. `curves` from [`super::curves::friction_curves`].
pub fn friction_figure(joints: &JointMap, label: &str, curves: &[Curve]) -> PanelGrid {
    let panels = curves
        .iter()
        .enumerate()
        .map(|(j, c)| {
            let u = joints.units(j);
            let fitted: Vec<f64> = c.bins.iter().filter_map(|b| b.model).collect();
            let mut series = vec![quartile_series(
                "measured τ − model without friction (median and quartiles per bin)",
                colors::MEASURED,
                c,
            )];
            if fitted.len() == c.bins.len() {
                series.push(Series::line(
                    "fitted friction model (median per bin)",
                    colors::PREDICTED,
                    c.bins.iter().map(|b| b.x).collect(),
                    fitted,
                ));
            }
            Panel {
                title: format!("{} friction", c.coordinate),
                x_label: format!("velocity ({})", u[1]),
                y_label: format!("torque ({})", u[3]),
                series,
                hlines: vec![(0.0, colors::ERROR)],
                vspans: Vec::new(),
            }
        })
        .collect();
    PanelGrid {
        title: format!("{} — friction against velocity, {label}", joints.robot),
        columns: 4,
        panel_size: (400, 280),
        column_weights: Vec::new(),
        panels,
    }
}

/// The prediction error of each coordinate against its velocity and against its
/// position (two panels per coordinate), median and quartiles per bin; curves from
/// [`super::curves::residual_curves`].
pub fn residual_figure(
    joints: &JointMap,
    label: &str,
    by_velocity: &[Curve],
    by_position: &[Curve],
) -> PanelGrid {
    let mut panels = Vec::new();
    for (j, (v, p)) in by_velocity.iter().zip(by_position).enumerate() {
        let u = joints.units(j);
        for (c, what, unit) in [(v, "velocity", u[1]), (p, "position", u[0])] {
            panels.push(Panel {
                title: format!("{} error vs {what}", c.coordinate),
                x_label: format!("{what} ({unit})"),
                y_label: format!("τ − τ̂ ({})", u[3]),
                series: vec![quartile_series(
                    "measured − predicted (median and quartiles per bin)",
                    colors::ERROR,
                    c,
                )],
                hlines: vec![(0.0, colors::PREDICTED)],
                vspans: Vec::new(),
            });
        }
    }
    PanelGrid {
        title: format!(
            "{} — prediction error against velocity and position, {label}",
            joints.robot
        ),
        columns: 4,
        panel_size: (380, 240),
        column_weights: Vec::new(),
        panels,
    }
}

/// Base parameters by name: value ± 2σ and relative standard deviation, one row each
/// (see [`super::base_chart`]).
pub fn base_parameter_figure(result: &FitResult) -> super::base_chart::BaseParameterChart {
    super::base_chart::BaseParameterChart::new(result)
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
            vspans: Vec::new(),
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
            vspans: Vec::new(),
        });
    }
    PanelGrid {
        title: format!(
            "{} — excitation trajectory (order {}, f0 = {} Hz), one period",
            model.name, traj.order, traj.base_frequency_hz
        ),
        columns: 2,
        panel_size: (560, 220),
        column_weights: Vec::new(),
        panels,
    }
}
