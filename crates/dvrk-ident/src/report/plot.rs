//! Drawing figures to SVG or PNG in memory with plotters.
//!
//! Figures are plain data ([`PanelGrid`] and the kinematic drawing) rendered by one
//! generic routine per figure type, so the same figure comes out as SVG (embedded in
//! the HTML report) or PNG without two drawing codes. Text uses the DejaVu Sans shipped
//! in `assets/fonts` (registered once through ab_glyph), so figures render identically
//! on a bare machine with no fontconfig. Everything is rendered into memory first: the
//! caller writes files atomically only once every figure has been drawn.

use std::error::Error;
use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::error::ReportError;

/// The font every figure uses, registered under plotters' `sans-serif` family.
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Result of drawing on a backend; boxed so one routine serves SVG and bitmap backends.
pub type DrawResult = Result<(), Box<dyn Error>>;

/// Output encoding of a figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// Scalable vector graphics (text), for documents and the HTML report.
    Svg,
    /// An RGB bitmap, 8 bits per channel.
    Png,
}

impl ImageFormat {
    /// The format a path asks for by its extension (`.svg` or `.png`).
    pub fn from_path(path: &Path) -> Result<ImageFormat, ReportError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("svg") => Ok(ImageFormat::Svg),
            Some("png") => Ok(ImageFormat::Png),
            _ => Err(ReportError::Format {
                file: path.display().to_string(),
                message: "figures are written as .svg or .png (by extension)".into(),
            }),
        }
    }

    /// The file extension of the format, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            ImageFormat::Svg => "svg",
            ImageFormat::Png => "png",
        }
    }
}

/// Something that can be drawn on any plotters backend.
pub trait Figure {
    /// Pixel size (SVG user units for SVG).
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `root` (already cleared to white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled file is a valid TrueType font; a failure here is a build defect.
        if plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_err() {
            panic!("the bundled DejaVu Sans font does not parse");
        }
    });
}

/// Renders `figure` to the bytes of an SVG document or a PNG file.
pub fn render(figure: &impl Figure, format: ImageFormat) -> Result<Vec<u8>, ReportError> {
    register_font();
    let (w, h) = figure.size();
    let failed = |e: Box<dyn Error>| ReportError::Draw(e.to_string());
    match format {
        ImageFormat::Svg => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(|e| failed(e.into()))?;
                figure.draw(&root).map_err(failed)?;
                root.present().map_err(|e| failed(e.into()))?;
            }
            Ok(text.into_bytes())
        }
        ImageFormat::Png => {
            let mut rgb = vec![0u8; w as usize * h as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(|e| failed(e.into()))?;
                figure.draw(&root).map_err(failed)?;
                root.present().map_err(|e| failed(e.into()))?;
            }
            encode_png(&rgb, w, h)
        }
    }
}

fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, ReportError> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let failed = |e: png::EncodingError| ReportError::Draw(format!("PNG encoding: {e}"));
    let mut writer = encoder.write_header().map_err(failed)?;
    writer.write_image_data(rgb).map_err(failed)?;
    writer.finish().map_err(failed)?;
    Ok(out)
}

/// How a series is drawn.
#[derive(Clone, Debug, PartialEq)]
pub enum SeriesStyle {
    /// A solid line through the points.
    Line,
    /// A dashed line through the points.
    Dashed,
    /// A filled circle at each point, no line.
    Points,
    /// Points with vertical bars from `lower[i]` to `upper[i]`.
    ErrorBars {
        /// Lower end of each bar, in y units (absolute, not an offset).
        lower: Vec<f64>,
        /// Upper end of each bar, in y units (absolute, not an offset).
        upper: Vec<f64>,
    },
}

/// One curve of a panel.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// The curve's colour.
    pub color: RGBColor,
    /// How the points are drawn.
    pub style: SeriesStyle,
    /// Abscissae, in the panel's x units (e.g. s).
    pub x: Vec<f64>,
    /// Ordinates, one per abscissa, in the panel's y units.
    pub y: Vec<f64>,
}

impl Series {
    /// A solid line through `(x[i], y[i])`.
    pub fn line(label: &str, color: RGBColor, x: Vec<f64>, y: Vec<f64>) -> Series {
        Series {
            label: label.into(),
            color,
            style: SeriesStyle::Line,
            x,
            y,
        }
    }
}

/// One chart of a grid: title, axis descriptions (with units) and curves.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    /// Text above the chart.
    pub title: String,
    /// The x axis' description with its unit, e.g. `time (s)`.
    pub x_label: String,
    /// The y axis' description with its unit, e.g. `torque (N·m)`.
    pub y_label: String,
    /// The curves, drawn in order (later ones on top).
    pub series: Vec<Series>,
    /// Horizontal reference lines (value, colour), e.g. limits; drawn dashed.
    pub hlines: Vec<(f64, RGBColor)>,
    /// Shaded x intervals `(from, to)`, e.g. the part of a log a zoomed panel shows.
    pub vspans: Vec<(f64, f64)>,
}

/// Panels on a grid under a common title.
#[derive(Clone, Debug)]
pub struct PanelGrid {
    /// Text above the whole grid.
    pub title: String,
    /// Panels per row; the rows follow from the number of panels.
    pub columns: usize,
    /// Size of one panel in pixels (the mean width, with [`PanelGrid::column_weights`]).
    pub panel_size: (u32, u32),
    /// Relative widths of the columns (e.g. `[2, 1]`: a whole log and its zoomed
    /// window); empty: equal widths.
    pub column_weights: Vec<u32>,
    /// The charts, row by row.
    pub panels: Vec<Panel>,
}

/// Most points a drawn series keeps; longer series are reduced to their min/max
/// envelope per bucket, which keeps every peak visible at a fraction of the file size.
pub const MAX_POINTS: usize = 2000;

/// The min/max envelope of `(x, y)` in at most `max_points` points, in x order. Short
/// series are returned unchanged.
pub fn envelope(x: &[f64], y: &[f64], max_points: usize) -> Vec<(f64, f64)> {
    let n = x.len().min(y.len());
    if n <= max_points || max_points < 2 {
        return (0..n).map(|i| (x[i], y[i])).collect();
    }
    let buckets = max_points / 2;
    let mut out = Vec::with_capacity(2 * buckets);
    for b in 0..buckets {
        let (s, e) = (
            b * n / buckets,
            ((b + 1) * n / buckets).max(b * n / buckets + 1),
        );
        let (mut lo, mut hi) = (s, s);
        for i in s..e.min(n) {
            if y[i] < y[lo] {
                lo = i;
            }
            if y[i] > y[hi] {
                hi = i;
            }
        }
        let (a, b2) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        out.push((x[a], y[a]));
        if b2 != a {
            out.push((x[b2], y[b2]));
        }
    }
    out
}

/// An axis label for the tick at `v` on an axis spanning `span`: the digits the tick
/// spacing (about a sixth of the span) needs, trailing zeros dropped, never `-0`.
pub fn tick_label(v: f64, span: f64) -> String {
    let step = span / 6.0;
    let digits = if step > 0.0 && step.is_finite() {
        (2 - step.log10().floor() as i32).clamp(0, 12) as usize
    } else {
        3
    };
    let mut text = format!("{v:.digits$}");
    if text.contains('.') {
        text = text.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    if text == "-0" {
        text = "0".into();
    }
    text
}

fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    (lo <= hi).then_some((lo, hi))
}

/// A range with a margin, never empty (a constant signal gets ±1 % or ±1).
fn padded(range: Option<(f64, f64)>, margin: f64) -> (f64, f64) {
    let (lo, hi) = range.unwrap_or((0.0, 1.0));
    let span = hi - lo;
    if span > 0.0 {
        (lo - margin * span, hi + margin * span)
    } else {
        let d = if lo != 0.0 { 0.01 * lo.abs() } else { 1.0 };
        (lo - d, hi + d)
    }
}

impl Panel {
    fn x_range(&self) -> (f64, f64) {
        // Markers need room at the ends; curves use the whole width.
        let markers = self
            .series
            .iter()
            .any(|s| !matches!(s.style, SeriesStyle::Line | SeriesStyle::Dashed));
        padded(
            finite_range(self.series.iter().flat_map(|s| s.x.iter().copied())),
            if markers { 0.02 } else { 0.0 },
        )
    }

    fn y_range(&self) -> (f64, f64) {
        let values = self.series.iter().flat_map(|s| {
            let extra: Vec<f64> = match &s.style {
                SeriesStyle::ErrorBars { lower, upper } => {
                    lower.iter().chain(upper.iter()).copied().collect()
                }
                _ => Vec::new(),
            };
            s.y.iter().copied().chain(extra)
        });
        padded(
            finite_range(values.chain(self.hlines.iter().map(|h| h.0))),
            0.05,
        )
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (x0, x1) = self.x_range();
        let (y0, y1) = self.y_range();
        // Two points (a minimum and a maximum) per pixel column keep every peak.
        let max_points = MAX_POINTS.min(2 * area.dim_in_pixel().0 as usize).max(100);
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(225, 225, 225))
            .x_label_formatter(&|v| tick_label(*v, x1 - x0))
            .y_label_formatter(&|v| tick_label(*v, y1 - y0))
            .x_desc(self.x_label.as_str())
            .y_desc(self.y_label.as_str())
            .label_style(("sans-serif", 12))
            .axis_desc_style(("sans-serif", 13))
            .x_labels(6)
            .y_labels(6)
            .draw()?;
        for &(a, b) in &self.vspans {
            chart.draw_series(std::iter::once(Rectangle::new(
                [(a.max(x0), y0), (b.min(x1), y1)],
                RGBColor(255, 244, 214).filled(),
            )))?;
        }
        for &(v, color) in &self.hlines {
            chart.draw_series(DashedLineSeries::new(
                vec![(x0, v), (x1, v)],
                6,
                4,
                color.stroke_width(1),
            ))?;
        }
        for s in &self.series {
            let color = s.color;
            match &s.style {
                SeriesStyle::Line => {
                    chart.draw_series(LineSeries::new(
                        envelope(&s.x, &s.y, max_points),
                        color.stroke_width(1),
                    ))?;
                }
                SeriesStyle::Dashed => {
                    chart.draw_series(DashedLineSeries::new(
                        envelope(&s.x, &s.y, max_points),
                        6,
                        4,
                        color.stroke_width(1),
                    ))?;
                }
                SeriesStyle::Points => {
                    chart.draw_series(
                        s.x.iter()
                            .zip(&s.y)
                            .map(|(&x, &y)| Circle::new((x, y), 3, color.filled())),
                    )?;
                }
                SeriesStyle::ErrorBars { lower, upper } => {
                    chart.draw_series(
                        s.x.iter()
                            .zip(lower.iter().zip(upper))
                            .map(|(&x, (&lo, &hi))| {
                                PathElement::new(vec![(x, lo), (x, hi)], color)
                            }),
                    )?;
                    chart.draw_series(
                        s.x.iter()
                            .zip(&s.y)
                            .map(|(&x, &y)| Circle::new((x, y), 3, color.filled())),
                    )?;
                }
            }
        }
        Ok(())
    }
}

/// One entry of a figure's legend: a series' label, colour and style.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    /// The text.
    pub label: String,
    /// The series' colour.
    pub color: RGBColor,
    /// Drawn as a marker with a bar (points, error bars) rather than a line.
    pub marker: bool,
}

/// Every labelled series of `panels` once (by label and colour), in order of first
/// appearance: the legend drawn above the panels, outside the data.
pub fn legend_entries(panels: &[Panel]) -> Vec<LegendEntry> {
    let mut out: Vec<LegendEntry> = Vec::new();
    for s in panels.iter().flat_map(|p| &p.series) {
        if s.label.is_empty() || out.iter().any(|e| e.label == s.label && e.color == s.color) {
            continue;
        }
        out.push(LegendEntry {
            label: s.label.clone(),
            color: s.color,
            marker: !matches!(s.style, SeriesStyle::Line | SeriesStyle::Dashed),
        });
    }
    out
}

/// Draws `entries` in one row on `area` (a strip above the panels), from the left.
pub fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let mut x = 64;
    let y = (LEGEND_HEIGHT / 2) as i32;
    for e in entries {
        if e.marker {
            area.draw(&Circle::new((x + 10, y), 3, e.color.filled()))?;
            area.draw(&PathElement::new(
                vec![(x + 10, y - 7), (x + 10, y + 7)],
                e.color,
            ))?;
        } else {
            area.draw(&PathElement::new(
                vec![(x, y), (x + 20, y)],
                e.color.stroke_width(2),
            ))?;
        }
        area.draw(&Text::new(
            e.label.clone(),
            (x + 26, y - 7),
            ("sans-serif", 13).into_font(),
        ))?;
        // DejaVu Sans at 13 px: about 7.5 px per character.
        x += 26 + (e.label.chars().count() as f64 * 7.5) as i32 + 24;
    }
    Ok(())
}

/// Height of the legend strip above a figure's panels, px.
pub const LEGEND_HEIGHT: u32 = 26;

impl PanelGrid {
    fn legend_height(&self) -> u32 {
        if legend_entries(&self.panels).is_empty() {
            0
        } else {
            LEGEND_HEIGHT
        }
    }

    /// The pixel x of each boundary between columns, from the weights.
    fn column_breaks(&self, width: u32) -> Vec<i32> {
        let cols = self.columns.max(1);
        let weights: Vec<u32> = if self.column_weights.len() == cols {
            self.column_weights.iter().map(|w| (*w).max(1)).collect()
        } else {
            vec![1; cols]
        };
        let total: u32 = weights.iter().sum();
        let mut acc = 0;
        weights[..cols - 1]
            .iter()
            .map(|w| {
                acc += w;
                (u64::from(width) * u64::from(acc) / u64::from(total)) as i32
            })
            .collect()
    }
}

impl Figure for PanelGrid {
    fn size(&self) -> (u32, u32) {
        let cols = self.columns.max(1);
        let rows = self.panels.len().div_ceil(cols).max(1);
        (
            self.panel_size.0 * cols as u32,
            self.panel_size.1 * rows as u32 + TITLE_HEIGHT + self.legend_height(),
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, body) = root.split_vertically(TITLE_HEIGHT);
        title.titled(&self.title, ("sans-serif", 20))?;
        let (legend, body) = body.split_vertically(self.legend_height());
        draw_legend(&legend, &legend_entries(&self.panels))?;
        let cols = self.columns.max(1);
        let rows = self.panels.len().div_ceil(cols).max(1);
        let breaks = self.column_breaks(self.panel_size.0 * cols as u32);
        let areas: Vec<_> = body
            .split_evenly((rows, 1))
            .iter()
            .flat_map(|row| row.split_by_breakpoints(&breaks[..], &[] as &[i32]))
            .collect();
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            panel.draw(area)?;
        }
        Ok(())
    }
}

/// Height of a figure's title strip, px.
const TITLE_HEIGHT: u32 = 36;

/// A palette that stays readable in print: measured, predicted, error, then extras.
pub mod colors {
    use plotters::style::RGBColor;
    /// Measured values (the log's torque), and the main series of other figures.
    pub const MEASURED: RGBColor = RGBColor(31, 119, 180);
    /// The model's prediction.
    pub const PREDICTED: RGBColor = RGBColor(214, 39, 40);
    /// Measured minus predicted, and zero reference lines.
    pub const ERROR: RGBColor = RGBColor(127, 127, 127);
    /// Signals before processing.
    pub const RAW: RGBColor = RGBColor(170, 170, 170);
    /// Signals after processing (filtered, differentiated).
    pub const FILTERED: RGBColor = RGBColor(31, 119, 180);
    /// Limits drawn against a trajectory.
    pub const LIMIT: RGBColor = RGBColor(214, 39, 40);
    /// A frame's x axis in a kinematic drawing.
    pub const AXIS_X: RGBColor = RGBColor(214, 39, 40);
    /// A frame's y axis in a kinematic drawing.
    pub const AXIS_Y: RGBColor = RGBColor(44, 160, 44);
    /// A frame's z axis in a kinematic drawing.
    pub const AXIS_Z: RGBColor = RGBColor(31, 119, 180);
    /// One colour per coordinate (tab10).
    pub const CYCLE: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_keeps_extremes_and_order() {
        let n = 10_000;
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut y: Vec<f64> = x.iter().map(|t| (t * 0.01).sin()).collect();
        y[4321] = 7.0;
        y[8000] = -5.0;
        let e = envelope(&x, &y, 500);
        assert!(e.len() <= 500);
        assert!(e.iter().any(|p| p == &(4321.0, 7.0)));
        assert!(e.iter().any(|p| p == &(8000.0, -5.0)));
        assert!(e.windows(2).all(|w| w[0].0 < w[1].0));
        assert_eq!(envelope(&x[..10], &y[..10], 500).len(), 10);
    }

    #[test]
    fn tick_labels_have_the_spacings_digits_and_no_negative_zero() {
        assert_eq!(tick_label(-0.0, 0.6), "0");
        assert_eq!(tick_label(-1e-17, 0.6), "0");
        assert_eq!(tick_label(0.25, 1.5), "0.25");
        assert_eq!(tick_label(0.30000000000000004, 1.5), "0.3");
        assert_eq!(tick_label(25.0, 28.0), "25");
        assert_eq!(tick_label(-0.002, 0.012), "-0.002");
    }

    #[test]
    fn constant_and_empty_ranges_are_not_degenerate() {
        assert_eq!(padded(Some((2.0, 2.0)), 0.05), (1.98, 2.02));
        assert_eq!(padded(Some((0.0, 0.0)), 0.05), (-1.0, 1.0));
        assert_eq!(padded(None, 0.0), (0.0, 1.0));
    }
}

/// A figure of the report, rendered in both formats.
#[derive(Clone, Debug)]
pub struct RenderedFigure {
    /// File stem, e.g. `torque_1_training`.
    pub stem: String,
    /// The caption under the figure in the page.
    pub caption: String,
    /// The SVG document.
    pub svg: String,
    /// The PNG file's bytes.
    pub png: Vec<u8>,
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

/// Renders one figure for `path` (SVG or PNG by its extension).
pub fn figure_bytes(figure: &impl Figure, path: &Path) -> Result<Vec<u8>, ReportError> {
    render(figure, ImageFormat::from_path(path)?)
}

/// Renders one figure to `path` (SVG or PNG by extension), atomically.
pub fn write_figure(figure: &impl Figure, path: &Path) -> Result<(), ReportError> {
    let bytes = figure_bytes(figure, path)?;
    crate::log::write_atomic(path, |w| w.write_all(&bytes))
        .map_err(|e| ReportError::Ident(e.into()))
}
