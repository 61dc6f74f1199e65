//! The page of `dvrk-ident residual --report DIR`: per log, the torque the model does not
//! explain per joint over time (`τ_measured − τ_model` and the momentum observer's
//! estimate) against the fit's noise floor, and a table of their RMS; with `--wrench`,
//! the wrench at the frame over time in the frame's own axes and its RMS per component.

use std::fmt::Write as _;

use super::document::Report;
use super::error::ReportError;
use super::html::{escape, inline_svg, number, STYLE};
use super::plot::{colors, Panel, PanelGrid, Series};
use super::plot::{render_both, RenderedFigure};
use crate::fit::JointMap;
use crate::residual::{Residual, TipWrench, WRENCH_COMPONENTS};

/// Multiple of the noise floor the page counts samples beyond: about 5 % of a Gaussian
/// residual whose RMS is the floor lies beyond twice it.
pub const FLOOR_MULTIPLE: f64 = 2.0;

/// The residual of one log, one panel per joint over time (s from the first processed
/// sample): `τ_measured − τ_model`, the observer's estimate, and the noise floor as
/// dashed lines at `±floor` (none without one).
pub fn residual_figure(joints: &JointMap, label: &str, r: &Residual, gain: f64) -> PanelGrid {
    let t = since_start(&r.time);
    let panels = (0..r.joints.len())
        .map(|j| {
            let floor = r.noise_floor.as_ref().map(|f| f[j]);
            let title = match floor {
                Some(f) => format!(
                    "{}  (RMS {} vs noise floor {}: {:.2}×)",
                    r.joints[j],
                    number(r.rms[j]),
                    number(f),
                    r.rms[j] / f
                ),
                None => format!(
                    "{}  (RMS {}, no noise floor)",
                    r.joints[j],
                    number(r.rms[j])
                ),
            };
            Panel {
                title,
                x_label: "time (s)".into(),
                y_label: format!("τ_ext ({})", joints.units(j)[3]),
                series: vec![
                    Series::line(
                        "τ_measured − τ_model",
                        colors::ERROR,
                        t.clone(),
                        r.external.column(j).iter().copied().collect(),
                    ),
                    Series::line(
                        &format!("momentum observer ({gain} /s)"),
                        colors::MEASURED,
                        t.clone(),
                        r.observer.column(j).iter().copied().collect(),
                    ),
                ],
                hlines: floor
                    .map(|f| vec![(f, colors::LIMIT), (-f, colors::LIMIT)])
                    .unwrap_or_default(),
                vspans: Vec::new(),
            }
        })
        .collect();
    one_column(
        format!("{}: τ_measured − τ_model, {label}", joints.robot),
        200,
        panels,
    )
}

/// Times (s) from the first one: the figures' x axis.
fn since_start(time: &[f64]) -> Vec<f64> {
    let t0 = time.first().copied().unwrap_or(0.0);
    time.iter().map(|t| t - t0).collect()
}

/// The panels one below the other, each 1100 px wide and `height` px high.
fn one_column(title: String, height: u32, panels: Vec<Panel>) -> PanelGrid {
    PanelGrid {
        title,
        columns: 1,
        panel_size: (1100, height),
        column_weights: Vec::new(),
        panels,
    }
}

/// The wrench of one log over time (s from the first processed sample) in the tip
/// frame's axes: the force (N) and the moment (N·m), x, y, z each.
pub fn wrench_figure(robot: &str, label: &str, time: &[f64], w: &TipWrench) -> PanelGrid {
    let t = since_start(time);
    let axes = [colors::AXIS_X, colors::AXIS_Y, colors::AXIS_Z];
    let panels = [("force", "N", 0), ("moment", "N·m", 3)]
        .into_iter()
        .map(|(what, unit, first)| Panel {
            title: format!("{what} at {} in its own axes", w.frame),
            x_label: "time (s)".into(),
            y_label: format!("{what} ({unit})"),
            series: (0..3)
                .map(|c| {
                    Series::line(
                        WRENCH_COMPONENTS[first + c],
                        axes[c],
                        t.clone(),
                        w.in_tip.column(first + c).iter().copied().collect(),
                    )
                })
                .collect(),
            hlines: Vec::new(),
            vspans: Vec::new(),
        })
        .collect();
    one_column(
        format!("{robot}: wrench at {}, {label}", w.frame),
        240,
        panels,
    )
}

/// The report of `residuals` (one per log, in `joints`): a figure per log (SVG and PNG,
/// `residual_<k>`) and the page `report.html` with, per log and joint, the RMS of the
/// residual and of the observer's estimate, the noise floor, their ratio and the share
/// of samples beyond [`FLOOR_MULTIPLE`] floors. `result` names the fit in the page.
pub fn residual_report(
    joints: &JointMap,
    result: &str,
    residuals: &[Residual],
    gain: f64,
) -> Result<Report, ReportError> {
    let mut figures = Vec::new();
    let mut o = String::new();
    let _ = write!(
        o,
        "<!DOCTYPE html><html lang=en><head><meta charset=utf-8>\
         <title>dvrk-ident residual: {robot}</title><style>{STYLE}</style></head><body>\
         <h1>External torques: {robot}</h1>\
         <p>The torque the model of <code>{result}</code> does not explain, \
         τ_ext = τ_measured − τ_model(q, q̇, q̈) per processed sample (the result's \
         processing, friction, springs and known forces), and the momentum observer's \
         estimate of the same torque (gain {gain} /s: a first-order lag of {tau} s, no \
         acceleration needed). The noise floor is the fit's RMS error on its own training \
         logs: a residual whose RMS stays near it shows nothing the fit did not already \
         leave unexplained; one well above it is a force, a load or a model that no longer \
         fits. A Gaussian residual at the floor has about 5 % of its samples beyond \
         {FLOOR_MULTIPLE}× the floor.</p>",
        robot = escape(&joints.robot),
        result = escape(result),
        tau = number(1.0 / gain),
    );
    for (k, r) in residuals.iter().enumerate() {
        // The file name: the whole path would not fit the figure's title.
        let name = std::path::Path::new(&r.source)
            .file_name()
            .map_or(r.source.clone(), |n| n.to_string_lossy().into_owned());
        let label = format!("{name} ({} samples)", r.time.len());
        let observer_rms = r.observer_rms();
        let _ = write!(
            o,
            "<h2>{}</h2><p>{}</p><table><tr><th class=l>joint</th><th>residual RMS</th>\
             <th>observer RMS</th><th>noise floor</th><th>RMS / floor</th>\
             <th>samples beyond {FLOOR_MULTIPLE}× floor</th><th class=l>unit</th></tr>",
            escape(&label),
            escape(&r.source)
        );
        for (j, name) in r.joints.iter().enumerate() {
            let floor = r.noise_floor.as_ref().map(|f| f[j]);
            let (floor_text, ratio, beyond) = match floor {
                Some(f) => {
                    let count = r
                        .external
                        .column(j)
                        .iter()
                        .filter(|x| x.abs() > FLOOR_MULTIPLE * f)
                        .count();
                    let share = 100.0 * count as f64 / r.time.len().max(1) as f64;
                    let ratio = r.rms[j] / f;
                    let class = if ratio > 1.5 { " class=bad" } else { "" };
                    (
                        number(f),
                        format!("<td{class}>{ratio:.2}</td>"),
                        format!("{share:.1} %"),
                    )
                }
                None => ("n/a".into(), "<td>n/a</td>".into(), "n/a".into()),
            };
            let _ = write!(
                o,
                "<tr><td class=l>{}</td><td>{}</td><td>{}</td><td>{floor_text}</td>{ratio}\
                 <td>{beyond}</td><td class=l>{}</td></tr>",
                escape(name),
                number(r.rms[j]),
                number(observer_rms[j]),
                joints.units(j)[3]
            );
        }
        o.push_str("</table>");
        if r.noise_floor.is_none() {
            o.push_str(
                "<p>No noise floor: the fit's errors are in other joints than these (run \
                 with the fit's own <code>--joints</code>).</p>",
            );
        }
        let figure = render_both(
            &residual_figure(joints, &label, r, gain),
            &format!("residual_{}", k + 1),
            &format!(
                "τ_measured − τ_model (grey) and the momentum observer's estimate (blue) per \
                 joint, {label}; dashed: ± the fit's noise floor."
            ),
        )?;
        embed(&mut o, &mut figures, figure);
        if let Some(w) = &r.wrench {
            let (base, tip) = (TipWrench::rms(&w.in_base), TipWrench::rms(&w.in_tip));
            let _ = write!(
                o,
                "<p>The residual as a wrench at <code>{frame}</code> (least squares of \
                 τ_ext = Jᵀ·F; force N, moment N·m about the frame's origin): {sensed}</p>\
                 <table><tr><th class=l>component</th><th>RMS, base axes</th>\
                 <th>RMS, {frame} axes</th><th class=l>unit</th></tr>",
                frame = escape(&w.frame),
                sensed = match w.rank_deficient_samples() {
                    0 => "all six directions sensed at every sample.".to_string(),
                    n => format!(
                        "{n} of {} samples sense fewer than six directions (fewest {}); the \
                         wrench has no component along the others there.",
                        w.rank.len(),
                        w.min_rank()
                    ),
                },
            );
            for (c, name) in WRENCH_COMPONENTS.iter().enumerate() {
                let _ = write!(
                    o,
                    "<tr><td class=l>{name}</td><td>{}</td><td>{}</td><td class=l>{}</td></tr>",
                    number(base[c]),
                    number(tip[c]),
                    if c < 3 { "N" } else { "N·m" }
                );
            }
            o.push_str("</table>");
            let figure = render_both(
                &wrench_figure(&joints.robot, &label, &r.time, w),
                &format!("wrench_{}", k + 1),
                &format!(
                    "The wrench at {} in its own axes (x red, y green, z blue), {label}.",
                    w.frame
                ),
            )?;
            embed(&mut o, &mut figures, figure);
        }
    }
    o.push_str("</body></html>\n");
    Ok(Report {
        figures,
        logs: Vec::new(),
        html: o,
    })
}

/// Writes `figure` into the page `o` (inline SVG and caption) and keeps it for the files.
fn embed(o: &mut String, figures: &mut Vec<RenderedFigure>, figure: RenderedFigure) {
    let _ = write!(
        o,
        "<figure>{}<figcaption>{}</figcaption></figure>",
        inline_svg(&figure.svg),
        escape(&figure.caption)
    );
    figures.push(figure);
}
