//! A drawing of the kinematic tree at a configuration, like the 2019 geometry figures:
//! every frame's origin and axes, a segment from each parent origin to its child's,
//! in two orthographic views of the 3D scene side by side.
//!
//! The serial chain to the deepest frame is drawn in black; every other branch (the
//! parallelogram's closing links, counterweights, motor frames) in orange, so the
//! closed-chain frames stay visible instead of hiding behind the main chain.

use dvrk_model::{Model, Transform};
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{colors, DrawResult, Figure};

/// A viewing direction: azimuth and elevation of the camera (degrees, matplotlib's
/// convention: azimuth about the base z axis from x, elevation above the x–y plane).
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// The view's caption in the figure, e.g. `front view (x–z plane)`.
    pub name: String,
    /// Camera azimuth about the base z axis from x, degrees.
    pub azimuth_deg: f64,
    /// Camera elevation above the base x–y plane, degrees.
    pub elevation_deg: f64,
}

impl View {
    /// Screen axes (right, up) of this view in the base frame.
    fn basis(&self) -> (Vector3<f64>, Vector3<f64>) {
        let (az, el) = (
            self.azimuth_deg.to_radians(),
            self.elevation_deg.to_radians(),
        );
        let right = Vector3::new(-az.sin(), az.cos(), 0.0);
        let up = Vector3::new(-az.cos() * el.sin(), -az.sin() * el.sin(), el.cos());
        (right, up)
    }

    /// The two views of a drawing: a 3D view (matplotlib's default angles) and the
    /// front view looking along +y onto the x–z plane.
    pub fn default_pair() -> Vec<View> {
        vec![
            View {
                name: "3D view (azimuth -60°, elevation 30°)".into(),
                azimuth_deg: -60.0,
                elevation_deg: 30.0,
            },
            View {
                name: "front view (x–z plane)".into(),
                azimuth_deg: -90.0,
                elevation_deg: 0.0,
            },
        ]
    }
}

/// One frame of the drawing.
#[derive(Clone, Debug)]
pub struct DrawnFrame {
    /// 1-based frame index (0 is the base).
    pub index: usize,
    /// The frame's name in the description (`base` for index 0).
    pub name: String,
    /// The parent frame's index (0: the base; the base is its own parent).
    pub parent: usize,
    /// Pose in the base frame (m).
    pub pose: Transform,
    /// Off the main serial chain (closed-chain, counterweight or motor frame).
    pub branch: bool,
}

/// The kinematic tree of a model at one configuration, ready to render.
#[derive(Clone, Debug)]
pub struct KinematicDrawing {
    /// Text above the views (the robot and the configuration).
    pub title: String,
    /// Base first (index 0), then every frame in model order.
    pub frames: Vec<DrawnFrame>,
    /// The views drawn side by side, in order.
    pub views: Vec<View>,
    /// Length of the drawn axes, m.
    pub axis_length: f64,
    /// Pixel size of one view.
    pub view_size: (u32, u32),
}

/// Coordinates a kinematic drawing refuses.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DrawingError {
    /// Not one value per coordinate of the robot.
    #[error("{given} values given for the {} coordinates of {robot} ({})", coordinates.len(), coordinates.join(", "))]
    Count {
        /// Values given.
        given: usize,
        /// The robot's name.
        robot: String,
        /// Its coordinates' names.
        coordinates: Vec<String>,
    },
    /// A value that is NaN or infinite.
    #[error("coordinate {coordinate} is not finite")]
    NotFinite {
        /// The coordinate's name.
        coordinate: String,
    },
}

/// The drawing of `model` at coordinates `q` (rad or m, model coordinates).
///
/// ```
/// use dvrk_ident::report::draw::kinematic_drawing;
/// let model = dvrk_model::Model::builtin("psm").unwrap();
/// let drawing = kinematic_drawing(&model, &[0.0, 0.0, 0.12, 0.0, 0.0, 0.0, 0.0]).unwrap();
/// // Base plus one entry per frame; the parallelogram branches are flagged.
/// assert_eq!(drawing.frames.len(), model.frames.len() + 1);
/// assert!(drawing.frames.iter().any(|f| f.branch));
/// ```
pub fn kinematic_drawing(model: &Model, q: &[f64]) -> Result<KinematicDrawing, DrawingError> {
    if q.len() != model.dof() {
        return Err(DrawingError::Count {
            given: q.len(),
            robot: model.name.clone(),
            coordinates: model.coordinates.clone(),
        });
    }
    if let Some(j) = q.iter().position(|v| !v.is_finite()) {
        return Err(DrawingError::NotFinite {
            coordinate: model.coordinates[j].clone(),
        });
    }
    let poses = model.frame_poses(q);
    let count = model.frames.len() + 1;
    let parent = |i: usize| {
        if i == 0 {
            0
        } else {
            model.frames[i - 1].parent
        }
    };
    let mut depth = vec![0usize; count];
    for i in 1..count {
        depth[i] = depth[parent(i)] + 1;
    }
    // The main chain: ancestors of the deepest frame (the last one on ties).
    let tip = (0..count).max_by_key(|&i| (depth[i], i)).unwrap_or(0);
    let mut on_chain = vec![false; count];
    let mut i = tip;
    loop {
        on_chain[i] = true;
        if i == 0 {
            break;
        }
        i = parent(i);
    }
    let frames: Vec<DrawnFrame> = (0..count)
        .map(|i| DrawnFrame {
            index: i,
            name: if i == 0 {
                "base".into()
            } else {
                model.frames[i - 1].name.clone()
            },
            parent: parent(i),
            pose: poses[i],
            branch: !on_chain[i],
        })
        .collect();
    let extent = frames
        .iter()
        .flat_map(|a| {
            frames
                .iter()
                .map(move |b| (a.pose.translation - b.pose.translation).norm())
        })
        .fold(0.0f64, f64::max);
    let values: Vec<String> = model
        .coordinates
        .iter()
        .zip(q)
        .map(|(n, v)| format!("{n}={v:.3}"))
        .collect();
    Ok(KinematicDrawing {
        title: format!("{} at {}", model.name, values.join(" ")),
        frames,
        views: View::default_pair(),
        axis_length: (0.08 * extent).max(0.01),
        view_size: (640, 640),
    })
}

impl KinematicDrawing {
    /// Equal-scale bounds of the projected scene in one view, with a margin.
    fn bounds(&self, right: &Vector3<f64>, up: &Vector3<f64>) -> ((f64, f64), (f64, f64)) {
        let mut pts = Vec::new();
        for f in &self.frames {
            let o = f.pose.translation;
            pts.push(o);
            for k in 0..3 {
                pts.push(o + f.pose.rotation.column(k) * self.axis_length);
            }
        }
        let xs = pts.iter().map(|p| p.dot(right));
        let ys = pts.iter().map(|p| p.dot(up));
        let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let (y0, y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let half = 0.5 * (x1 - x0).max(y1 - y0).max(1e-3) * 1.1;
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        ((cx - half, cx + half), (cy - half, cy + half))
    }

    fn draw_view<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        view: &View,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (right, up) = view.basis();
        let ((x0, x1), (y0, y1)) = self.bounds(&right, &up);
        let mut chart = ChartBuilder::on(area)
            .caption(&view.name, ("sans-serif", 15))
            .margin(10)
            .x_label_area_size(34)
            .y_label_area_size(54)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .bold_line_style(RGBColor(235, 235, 235))
            .x_desc("screen right (m)")
            .y_desc("screen up (m)")
            .label_style(("sans-serif", 11))
            .draw()?;
        let project = |p: Vector3<f64>| (p.dot(&right), p.dot(&up));
        let branch_color = RGBColor(255, 127, 14);
        // Links first, so the axes and origins stay on top.
        for f in self.frames.iter().skip(1) {
            let a = project(self.frames[f.parent].pose.translation);
            let b = project(f.pose.translation);
            let style = if f.branch {
                branch_color.stroke_width(2)
            } else {
                BLACK.stroke_width(3)
            };
            chart.draw_series(std::iter::once(PathElement::new(vec![a, b], style)))?;
        }
        for f in &self.frames {
            let o = f.pose.translation;
            for (k, color) in [colors::AXIS_X, colors::AXIS_Y, colors::AXIS_Z]
                .into_iter()
                .enumerate()
            {
                let tip = o + f.pose.rotation.column(k) * self.axis_length;
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![project(o), project(tip)],
                    color.stroke_width(1),
                )))?;
            }
            let color = if f.branch { branch_color } else { BLACK };
            chart.draw_series(std::iter::once(Circle::new(project(o), 3, color.filled())))?;
        }
        // One label per distinct origin: frames sharing an origin (common in DH trees)
        // are listed together instead of printed on top of each other.
        let mut labels: Vec<(Vector3<f64>, Vec<String>)> = Vec::new();
        for f in &self.frames {
            let o = f.pose.translation;
            match labels
                .iter_mut()
                .find(|(p, _)| (p - o).norm() < 1e-3 * self.axis_length)
            {
                Some((_, names)) => names.push(f.index.to_string()),
                None => labels.push((o, vec![f.index.to_string()])),
            }
        }
        // Labels of nearby origins are moved apart on screen: each takes the first place
        // around its origin that no earlier label covers (a leader line joins a moved
        // label to its origin).
        let mut placed: Vec<(i32, i32, i32, i32)> = Vec::new();
        for (o, names) in labels {
            let (x, y) = project(o);
            let anchor = chart.backend_coord(&(x, y));
            let text = names.join(",");
            let (w, h) = (label_width(&text), 12);
            let offset = label_offset(anchor, (w, h), &placed);
            placed.push((
                anchor.0 + offset.0,
                anchor.1 + offset.1,
                anchor.0 + offset.0 + w,
                anchor.1 + offset.1 + h,
            ));
            if offset != LABEL_OFFSETS[0] {
                let end = (
                    offset.0 + if offset.0 < 0 { w } else { 0 },
                    offset.1 + h / 2,
                );
                chart.draw_series(std::iter::once(
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), end], RGBColor(170, 170, 170)),
                ))?;
            }
            chart.draw_series(std::iter::once(
                EmptyElement::at((x, y))
                    + Text::new(
                        text,
                        offset,
                        ("sans-serif", 11).into_font().color(&RGBColor(60, 60, 60)),
                    ),
            ))?;
        }
        Ok(())
    }
}

impl Figure for KinematicDrawing {
    fn size(&self) -> (u32, u32) {
        let (w, h) = self.view_size;
        (w * self.views.len().max(1) as u32, h + LEGEND_HEIGHT + 36)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, rest) = root.split_vertically(36);
        title.titled(&self.title, ("sans-serif", 18))?;
        let (body, legend) = rest.split_vertically(self.view_size.1);
        let areas = body.split_evenly((1, self.views.len().max(1)));
        for (view, area) in self.views.iter().zip(areas.iter()) {
            self.draw_view(area, view)?;
        }
        let text = format!(
            "black: serial chain to frame {}; orange: other branches (closed chains, counterweights, motors); \
             axes x red, y green, z blue ({:.3} m); numbers: frame indices",
            self.frames.iter().rev().find(|f| !f.branch).map(|f| f.index).unwrap_or(0),
            self.axis_length
        );
        legend.draw(&Text::new(text, (10, 8), ("sans-serif", 12).into_font()))?;
        let names: Vec<String> = self
            .frames
            .iter()
            .map(|f| format!("{} {}", f.index, f.name))
            .collect();
        legend.draw(&Text::new(
            names.join(", "),
            (10, 28),
            ("sans-serif", 11).into_font(),
        ))?;
        Ok(())
    }
}

/// Where a frame label may go relative to its origin (pixels, text's top-left corner),
/// in order of preference: up right, then further up or down, then to the left.
const LABEL_OFFSETS: [(i32, i32); 11] = [
    (5, -14),
    (5, 2),
    (5, -28),
    (5, 16),
    (5, -42),
    (5, 30),
    (-5, -14),
    (5, -56),
    (5, 44),
    (5, -70),
    (5, 58),
];

/// Width of a label in the drawing's 11 px font (DejaVu Sans, about 6.5 px a character).
fn label_width(text: &str) -> i32 {
    (text.chars().count() as f64 * 6.5).ceil() as i32
}

/// The first of [`LABEL_OFFSETS`] where a `size` label at `anchor` overlaps none of
/// `placed` (boxes `x0, y0, x1, y1`); the first one when all overlap. A negative x
/// offset puts the label's right end there.
fn label_offset(
    anchor: (i32, i32),
    size: (i32, i32),
    placed: &[(i32, i32, i32, i32)],
) -> (i32, i32) {
    let (w, h) = size;
    LABEL_OFFSETS
        .iter()
        .map(|&(dx, dy)| if dx < 0 { (dx - w, dy) } else { (dx, dy) })
        .find(|&(dx, dy)| {
            let (x0, y0) = (anchor.0 + dx, anchor.1 + dy);
            placed
                .iter()
                .all(|&(a0, b0, a1, b1)| x0 + w <= a0 || x0 >= a1 || y0 + h <= b0 || y0 >= b1)
        })
        .unwrap_or(LABEL_OFFSETS[0])
}

/// Height of the legend strip under the views, px.
const LEGEND_HEIGHT: u32 = 52;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_of_one_spot_are_placed_apart() {
        let mut placed = Vec::new();
        for _ in 0..4 {
            let o = label_offset((100, 100), (40, 12), &placed);
            placed.push((100 + o.0, 100 + o.1, 140 + o.0, 112 + o.1));
        }
        for (i, a) in placed.iter().enumerate() {
            for b in &placed[..i] {
                assert!(
                    a.2 <= b.0 || a.0 >= b.2 || a.3 <= b.1 || a.1 >= b.3,
                    "{placed:?}"
                );
            }
        }
        assert_eq!(placed[0], (105, 86, 145, 98));
    }

    #[test]
    fn view_bases_are_orthonormal_and_front_view_is_x_z() {
        for v in View::default_pair() {
            let (r, u) = v.basis();
            assert!((r.norm() - 1.0).abs() < 1e-12 && (u.norm() - 1.0).abs() < 1e-12);
            assert!(r.dot(&u).abs() < 1e-12);
        }
        let (r, u) = View::default_pair()[1].basis();
        assert!((r - Vector3::x()).norm() < 1e-12);
        assert!((u - Vector3::z()).norm() < 1e-12);
    }
}
