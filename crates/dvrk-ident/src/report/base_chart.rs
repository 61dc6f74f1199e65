//! The base parameters by name: one row per base parameter, its name (or its short
//! expression) on the left, its value ± 2σ on a symmetric logarithmic axis (values of a
//! few kg and of micro-kg·m² side by side) and its relative standard deviation on a
//! logarithmic axis.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{colors, DrawResult, Figure};
use crate::result::FitResult;

/// Decades the value axis shows on each side of its linear part.
pub const DECADES: i32 = 6;

/// Relative standard deviations are drawn within `[0.01, 1000]` %.
pub const RELATIVE_RANGE_PERCENT: (f64, f64) = (0.01, 1000.0);

/// Longest expression shown whole as a row's label; longer ones show their leading name.
pub const LABEL_CHARS: usize = 34;

/// One base parameter as drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseRow {
    /// The row's label: the expression when short, else the leading name and the
    /// number of terms.
    pub label: String,
    /// Value (SI units of its kind).
    pub value: f64,
    /// Standard deviation.
    pub std: f64,
}

/// The chart of a result's base parameters.
#[derive(Clone, Debug)]
pub struct BaseParameterChart {
    /// Text above the chart.
    pub title: String,
    /// Rows from top to bottom, in the result's order.
    pub rows: Vec<BaseRow>,
}

/// The label of a base parameter: its expression when at most [`LABEL_CHARS`] long,
/// else `name + … (k terms)`.
pub fn row_label(name: &str, expression: &str) -> String {
    if expression.chars().count() <= LABEL_CHARS {
        return expression.to_string();
    }
    let terms = expression
        .split(" + ")
        .map(|t| t.split(" - ").count())
        .sum::<usize>();
    format!("{name} + … ({terms} terms)")
}

impl BaseParameterChart {
    /// The chart of `result`'s base parameters.
    pub fn new(result: &FitResult) -> BaseParameterChart {
        BaseParameterChart {
            title: format!(
                "{} — {} base parameters ({}): value ± 2σ and relative standard deviation",
                result.robot,
                result.base_parameters.len(),
                result.method
            ),
            rows: result
                .base_parameters
                .iter()
                .map(|b| BaseRow {
                    label: row_label(&b.name, &b.expression),
                    value: b.value,
                    std: b.std,
                })
                .collect(),
        }
    }

    /// The linear half-width `t` of the value axis: [`DECADES`] decades below the
    /// largest |value| + 2σ.
    pub fn linear_threshold(&self) -> f64 {
        let top = self
            .rows
            .iter()
            .map(|r| r.value.abs() + 2.0 * r.std)
            .filter(|v| v.is_finite() && *v > 0.0)
            .fold(0.0f64, f64::max);
        let top = if top > 0.0 { top } else { 1.0 };
        10f64.powi(top.log10().ceil() as i32 - DECADES)
    }
}

/// `10^e` as a tick label: plain from 0.001 to 1000, `1e-5` style outside.
fn decade(e: i32) -> String {
    if (-3..=3).contains(&e) {
        format!("{}", 10f64.powi(e))
    } else {
        format!("1e{e}")
    }
}

/// The symmetric logarithm with linear part `[-t, t]`: `x/t` there, `±(1 + log10(|x|/t))`
/// outside, so integer positions `k ≠ 0` stand for `±t·10^(|k|−1)`.
pub fn symlog(x: f64, t: f64) -> f64 {
    if x.abs() <= t {
        x / t
    } else {
        x.signum() * (1.0 + (x.abs() / t).log10())
    }
}

const ROW_HEIGHT: u32 = 15;
const TITLE: u32 = 36;
const AXES: u32 = 78;
const WIDTH: u32 = 1200;
const NAMES: u32 = 240;

impl Figure for BaseParameterChart {
    fn size(&self) -> (u32, u32) {
        (
            WIDTH,
            TITLE + AXES + ROW_HEIGHT * self.rows.len().max(1) as u32,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, body) = root.split_vertically(TITLE);
        title.titled(&self.title, ("sans-serif", 18))?;
        let (left, right) = body.split_horizontally(760);
        let n = self.rows.len().max(1);
        // Segments 0..=last, one per row: row i from the top is segment n-1-i.
        let last = n.saturating_sub(1).max(1);
        let at = |i: usize| SegmentValue::CenterOf(n - 1 - i);
        let t = self.linear_threshold();
        let ends = self.rows.iter().flat_map(|r| {
            [
                symlog(r.value - 2.0 * r.std, t),
                symlog(r.value + 2.0 * r.std, t),
            ]
        });
        let (lo, hi) = ends
            .filter(|v| v.is_finite())
            .fold((-1.0f64, 1.0f64), |(a, b), v| (a.min(v), b.max(v)));
        let (lo, hi) = (lo.floor() - 0.3, hi.ceil() + 0.3);
        let labels: Vec<&str> = self.rows.iter().map(|r| r.label.as_str()).collect();
        let name_of = |v: &SegmentValue<usize>| match v {
            SegmentValue::CenterOf(k) if *k < n => labels
                .get(n - 1 - k)
                .map(|s| s.to_string())
                .unwrap_or_default(),
            _ => String::new(),
        };
        let mut chart = ChartBuilder::on(&left)
            .caption(
                format!("value ± 2σ (SI; linear within ±{t:e}, logarithmic outside)"),
                ("sans-serif", 14),
            )
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(NAMES)
            .build_cartesian_2d(lo..hi, (0..last).into_segmented())?;
        let t_exp = t.log10().round() as i32;
        let tick = |v: &f64| {
            let k = v.round();
            if (v - k).abs() > 1e-9 {
                String::new()
            } else if k == 0.0 {
                "0".into()
            } else {
                let sign = if k < 0.0 { "−" } else { "" };
                format!("{sign}{}", decade(t_exp + k.abs() as i32 - 1))
            }
        };
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(232, 232, 232))
            .x_labels((hi - lo).ceil() as usize + 1)
            .x_label_formatter(&tick)
            .y_labels(n + 1)
            .y_label_formatter(&name_of)
            .label_style(("sans-serif", 11))
            .x_desc("value (symmetric log scale)")
            .axis_desc_style(("sans-serif", 12))
            .draw()?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(0.0, SegmentValue::Exact(0)), (0.0, SegmentValue::Last)],
            colors::ERROR,
        )))?;
        for (i, r) in self.rows.iter().enumerate() {
            let (a, b) = (
                symlog(r.value - 2.0 * r.std, t),
                symlog(r.value + 2.0 * r.std, t),
            );
            if a.is_finite() && b.is_finite() {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(a, at(i)), (b, at(i))],
                    colors::MEASURED.stroke_width(2),
                )))?;
            }
            let v = symlog(r.value, t);
            if v.is_finite() {
                chart.draw_series(std::iter::once(Circle::new(
                    (v, at(i)),
                    3,
                    colors::MEASURED.filled(),
                )))?;
            }
        }

        let (rlo, rhi) = RELATIVE_RANGE_PERCENT;
        let mut chart = ChartBuilder::on(&right)
            .caption(
                "relative standard deviation 100·σ/|value| (%)",
                ("sans-serif", 14),
            )
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(8)
            .build_cartesian_2d((rlo..rhi).log_scale(), (0..last).into_segmented())?;
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(232, 232, 232))
            .x_labels(6)
            .x_label_formatter(&|v: &f64| format!("{v}"))
            .y_labels(n + 1)
            .y_label_formatter(&|_| String::new())
            .label_style(("sans-serif", 11))
            .x_desc("% (clipped to 0.01–1000; dashed: 100 %, σ = |value|)")
            .axis_desc_style(("sans-serif", 12))
            .draw()?;
        chart.draw_series(DashedLineSeries::new(
            vec![(100.0, SegmentValue::Exact(0)), (100.0, SegmentValue::Last)],
            5,
            4,
            colors::ERROR.stroke_width(1),
        ))?;
        chart.draw_series(self.rows.iter().enumerate().map(|(i, r)| {
            let p = 100.0 * r.std / r.value.abs();
            let p = if p.is_nan() { rhi } else { p.clamp(rlo, rhi) };
            Circle::new((p, at(i)), 3, colors::PREDICTED.filled())
        }))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symlog_is_continuous_odd_and_decades_are_integers() {
        let t = 1e-4;
        assert_eq!(symlog(t, t), 1.0);
        assert_eq!(symlog(-t, t), -1.0);
        assert!((symlog(1e-2, t) - 3.0).abs() < 1e-12);
        assert_eq!(symlog(-0.5, t), -symlog(0.5, t));
        assert_eq!(symlog(0.0, t), 0.0);
    }

    #[test]
    fn long_expressions_show_their_name_and_term_count() {
        assert_eq!(row_label("l8x", "l8x + l9x"), "l8x + l9x");
        let long = "L2xz - 0.04009*l4z - 0.04009*l5z - L6xz - 0.04009*l6z + L7xz";
        assert_eq!(row_label("L2xz", long), "L2xz + … (6 terms)");
    }
}
