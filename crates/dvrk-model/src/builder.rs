//! The pure-numeric constructor of a [`Model`]: frames given by numbers (DH parameters or
//! transforms), joint values affine in the coordinates (the couplings), elements, and no
//! file or parser, so a controller can build its model without the `description`
//! feature. The description loader builds through the same steps, so a model built by
//! hand is checked like a description and its errors read the same (`source` stands for
//! the file: `numeric:{name}`).
//!
//! ```
//! use dvrk_model::{Affine, Convention, ElementSpec, FrameSpec, Joint, ModelBuilder, Workspace};
//! // A pendulum: one revolute joint q1 about z, a 0.5 m link along x, friction on it.
//! let mut b = ModelBuilder::new("pendulum", &["q1"]).unwrap();
//! b.set_gravity([0.0, -9.81, 0.0]).unwrap();
//! let joint = Joint::Dh {
//!     convention: Convention::Modified,
//!     a: 0.0,
//!     alpha: 0.0,
//!     theta: Affine::coordinate(0),
//!     d: Affine::constant(0.0),
//! };
//! let mut link = FrameSpec::new("link", "base", joint);
//! link.link = true;
//! link.elements.push(ElementSpec::Friction { stribeck_velocity: None });
//! b.add_frame(link).unwrap();
//! let model = b.build().unwrap();
//! assert_eq!(model.param_names()[9..], ["m1", "Fc1", "Fv1", "Fo1"]);
//!
//! // 2 kg at 0.5 m along x: the gravity torque at q = 0 is −m·g·x = −9.81 N·m.
//! let mut params = vec![0.0; model.n_params()];
//! params[6] = 2.0 * 0.5; // first moment l1x (kg·m)
//! params[9] = 2.0; // mass m1 (kg)
//! let mut ws = Workspace::new(&model);
//! let mut tau = [0.0];
//! model.gravity_torque(&mut ws, &params, &[0.0], &mut tau);
//! assert!((tau[0] - 9.81).abs() < 1e-12);
//! ```

use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::element::{ElementSpec, FrameContext, FrameElements};
use crate::error::ModelError;
use crate::expr::Affine;
use crate::input;
use crate::limits::Limits;
use crate::model::{Frame, JointKind, Measured, Model};
use crate::param::{FrameBounds, GlobalBounds, Nominal, Param};
use crate::spatial::Transform;

mod check;
mod joint;
use check::{check_frame_bounds, check_frame_count, check_nominal, check_range};
// For the description loader; the builder uses it inside `joint`.
#[cfg(feature = "description")]
pub(crate) use joint::dh_geometry;

/// How a DH frame's `a`, `alpha`, `theta`, `d` compose into the transform from the
/// parent frame (the description's `convention` field).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Deserialize),
    serde(rename_all = "lowercase")
)]
pub enum Convention {
    /// Craig: `RotX(alpha)·TransX(a)·RotZ(theta)·TransZ(d)`
    Modified,
    /// `RotZ(theta)·TransZ(d)·TransX(a)·RotX(alpha)`
    Standard,
}

/// Where a frame sits relative to its parent and how it moves.
#[derive(Clone, Debug)]
pub enum Joint {
    /// DH parameters: `a` (m), `alpha` (rad), and `theta` (rad), `d` (m) affine in the
    /// coordinates, at most one of them not constant (that one is the joint value).
    Dh {
        /// How the four compose.
        convention: Convention,
        /// Link length (m).
        a: f64,
        /// Link twist (rad).
        alpha: f64,
        /// Joint angle (rad), e.g. `Affine::coordinate(0)` or a coupling `q3 − q2`.
        theta: Affine,
        /// Link offset (m).
        d: Affine,
    },
    /// A general frame: `pre`, then the motion of `kind` by `value` about (along) z,
    /// then `post` (as [`Frame`]).
    Transform {
        /// Revolute, prismatic or fixed.
        kind: JointKind,
        /// The joint value `s = a·q + b` (rad or m); constant exactly when fixed.
        value: Affine,
        /// Parent → joint frame, before the motion.
        pre: Transform,
        /// Joint frame after the motion → this frame.
        post: Transform,
    },
}

/// A frame's pose and motion as [`Frame`] holds them.
pub(crate) struct Geometry {
    pub kind: JointKind,
    pub value: Affine,
    pub pre: Transform,
    pub post: Transform,
}

/// One frame for [`ModelBuilder::add_frame`].
#[derive(Clone, Debug)]
pub struct FrameSpec {
    /// The frame's name (unique; `base` is the base's).
    pub name: String,
    /// `base` or the name of an earlier frame.
    pub parent: String,
    /// Pose and motion.
    pub joint: Joint,
    /// Whether the frame carries a rigid link (10 inertial parameters `L{i}xx … m{i}`).
    pub link: bool,
    /// What acts on the joint value besides the links, parameters in this order.
    pub elements: Vec<ElementSpec>,
    /// Prior values of the frame's parameters.
    pub nominal: Nominal,
    /// The frame's own bounds for the physically consistent fit.
    pub bounds: FrameBounds,
}

impl FrameSpec {
    /// A frame without link, element, nominal values or bounds.
    pub fn new(name: &str, parent: &str, joint: Joint) -> FrameSpec {
        FrameSpec {
            name: name.to_string(),
            parent: parent.to_string(),
            joint,
            link: false,
            elements: Vec::new(),
            nominal: Nominal::default(),
            bounds: FrameBounds::default(),
        }
    }
}

/// A frame as the loaders give it to [`ModelBuilder::frame_with`]: the parts that need
/// parsing come as closures, run in the order the checks of a description run.
pub(crate) struct FrameInput<'a, G, E> {
    pub name: &'a str,
    pub parent: &'a str,
    /// The pose and motion, from the frame's place (`frame 3 (name)`).
    pub geometry: G,
    pub link: bool,
    /// The elements, their parameters pushed onto the given vector.
    pub elements: E,
    pub nominal: Nominal,
    pub bounds: FrameBounds,
}

/// Builds a [`Model`] from numbers (see the module documentation).
#[derive(Clone, Debug)]
pub struct ModelBuilder {
    name: String,
    source: String,
    coordinates: Vec<String>,
    gravity: Vector3<f64>,
    measured: Option<Measured>,
    limits: Limits,
    bounds: GlobalBounds,
    /// Frame names, base first.
    names: Vec<String>,
    frames: Vec<Frame>,
    params: Vec<Param>,
    /// `(frame, velocity)` of the Stribeck terms, added after every frame.
    stribeck: Vec<(usize, f64)>,
}

impl ModelBuilder {
    /// A model named `name` with these generalized coordinates (at least one, distinct),
    /// gravity −9.81 m/s² along z, measured joints the coordinates themselves.
    pub fn new(name: &str, coordinates: &[&str]) -> Result<ModelBuilder, ModelError> {
        let coordinates = coordinates.iter().map(|c| c.to_string()).collect();
        ModelBuilder::start(name.to_string(), &format!("numeric:{name}"), coordinates, 0)
    }

    /// As [`ModelBuilder::new`], `source` naming the origin in messages; `n_frames`, the
    /// number of frames to come, is checked against the size limit with the coordinates.
    pub(crate) fn start(
        name: String,
        source: &str,
        coordinates: Vec<String>,
        n_frames: usize,
    ) -> Result<ModelBuilder, ModelError> {
        let n = coordinates.len();
        if n > input::MAX_COORDINATES {
            return Err(ModelError::field(
                source,
                "top level",
                "coordinates",
                format!(
                    "{n} coordinates; at most {} are accepted",
                    input::MAX_COORDINATES
                ),
            ));
        }
        check_frame_count(source, n_frames)?;
        if n == 0 {
            return Err(ModelError::field(
                source,
                "top level",
                "coordinates",
                "no coordinate",
            ));
        }
        for (i, c) in coordinates.iter().enumerate() {
            if coordinates[..i].contains(c) {
                return Err(ModelError::field(
                    source,
                    "top level",
                    "coordinates",
                    format!("`{c}` appears twice"),
                ));
            }
        }
        Ok(ModelBuilder {
            name,
            source: source.to_string(),
            coordinates,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            measured: None,
            limits: Limits::default(),
            bounds: GlobalBounds::default(),
            names: vec!["base".into()],
            frames: Vec::new(),
            params: Vec::new(),
            stribeck: Vec::new(),
        })
    }

    /// The names of the frames added so far, base first (as [`Model::frame_names`] of the
    /// built model), which the limits' Cartesian boxes refer to.
    pub fn frame_names(&self) -> &[String] {
        &self.names
    }

    /// The measured joints and coupling (the coordinates themselves unless set).
    pub(crate) fn measured(&self) -> Measured {
        self.measured.clone().unwrap_or_else(|| {
            let n = self.coordinates.len();
            Measured {
                joints: self.coordinates.clone(),
                coupling: DMatrix::identity(n, n),
                ranges: vec![None; n],
            }
        })
    }

    /// Gravity in the base frame (m/s², each component finite and within
    /// ±[`input::MAX_GRAVITY`]).
    pub fn set_gravity(&mut self, gravity: [f64; 3]) -> Result<(), ModelError> {
        for g in gravity {
            input::check_magnitude(g, input::MAX_GRAVITY, "m/s²")
                .map_err(|m| ModelError::field(&self.source, "top level", "gravity", m))?;
        }
        self.gravity = Vector3::from(gravity);
        Ok(())
    }

    /// Lower bounds applied to every element by the physically consistent fit.
    pub fn set_bounds(&mut self, bounds: GlobalBounds) {
        self.bounds = bounds;
    }

    /// The measured (e.g. ROS) joint names, one per coordinate, the coupling rows
    /// `q_measured = M·q` (`None`: the identity; `M` must be invertible) and the joints'
    /// physical ranges `[min, max]` (rad or m; `None`: unknown).
    pub fn set_measured(
        &mut self,
        joints: Vec<String>,
        coupling: Option<Vec<Vec<f64>>>,
        ranges: Option<Vec<[f64; 2]>>,
    ) -> Result<(), ModelError> {
        let n = self.coordinates.len();
        let err = |field: &str, m: String| ModelError::field(&self.source, "measured", field, m);
        if joints.len() != n {
            return Err(err(
                "joints",
                format!("{} names for {n} coordinates", joints.len()),
            ));
        }
        let coupling = match coupling {
            Some(rows) => {
                if rows.len() != n || rows.iter().any(|r| r.len() != n) {
                    return Err(err("coupling", format!("must be {n} rows of {n} numbers")));
                }
                for (r, row) in rows.iter().enumerate() {
                    for (c, &x) in row.iter().enumerate() {
                        input::check_magnitude(x, input::MAX_ANGLE_RAD, "").map_err(|m| {
                            err("coupling", format!("row {}, column {}: {m}", r + 1, c + 1))
                        })?;
                    }
                }
                DMatrix::from_fn(n, n, |r, c| rows[r][c])
            }
            None => DMatrix::identity(n, n),
        };
        if coupling.clone().try_inverse().is_none() {
            return Err(err("coupling", "the matrix is singular".into()));
        }
        let ranges = match ranges {
            None => vec![None; n],
            Some(ranges) => {
                if ranges.len() != n {
                    return Err(err(
                        "ranges",
                        format!("{} ranges for {n} joints", ranges.len()),
                    ));
                }
                for (k, &[lo, hi]) in ranges.iter().enumerate() {
                    for x in [lo, hi] {
                        input::check_magnitude(x, input::MAX_VALUE, "")
                            .map_err(|m| err("ranges", format!("joint {}: {m}", joints[k])))?;
                    }
                    if lo >= hi {
                        return Err(err(
                            "ranges",
                            format!(
                                "joint {}: the minimum {lo} is not below the maximum {hi}",
                                joints[k]
                            ),
                        ));
                    }
                }
                ranges.into_iter().map(Some).collect()
            }
        };
        self.measured = Some(Measured {
            joints,
            coupling,
            ranges,
        });
        Ok(())
    }

    /// Joint limits and Cartesian boxes (excitation limits), after the frames. Each joint
    /// limit's expression must name existing coordinates, its ranges be ordered and
    /// finite; each box's frame must be one of the frames added.
    pub fn set_limits(&mut self, limits: Limits) -> Result<(), ModelError> {
        let n = self.coordinates.len();
        for (i, l) in limits.joint.iter().enumerate() {
            let place = format!("limits[{i}] ({})", l.label);
            if let Some(&(k, _)) = l.expr.terms.iter().find(|t| t.0 >= n) {
                return Err(ModelError::field(
                    &self.source,
                    &place,
                    "expr",
                    format!("coordinate {k} does not exist ({n} coordinates)"),
                ));
            }
            for (field, r) in [
                ("position", l.position),
                ("velocity", l.velocity),
                ("acceleration", l.acceleration),
            ] {
                check_range(&self.source, &place, field, r)?;
            }
        }
        for (i, c) in limits.cartesian.iter().enumerate() {
            if c.frame == 0 || c.frame >= self.names.len() {
                return Err(ModelError::field(
                    &self.source,
                    format!("cartesian_limits[{i}] ({})", c.frame_name),
                    "frame",
                    format!("no frame {} among the frames added so far", c.frame),
                ));
            }
        }
        self.limits = limits;
        Ok(())
    }

    /// Adds a frame; returns its index (1-based; the base is 0).
    pub fn add_frame(&mut self, spec: FrameSpec) -> Result<usize, ModelError> {
        check_frame_count(&self.source, self.frames.len() + 1)?;
        let n = self.coordinates.len();
        let source = self.source.clone();
        let FrameSpec {
            name,
            parent,
            joint,
            link,
            elements,
            nominal,
            bounds,
        } = spec;
        self.frame_with(FrameInput {
            name: &name,
            parent: &parent,
            geometry: |place: &str| joint.geometry(&source, place, n),
            link,
            elements: |fx: &FrameContext, params: &mut Vec<Param>| {
                let mut out = FrameElements::default();
                for e in &elements {
                    e.build(fx, params, &mut out)?;
                }
                Ok(out)
            },
            nominal,
            bounds,
        })
    }

    /// Adds a frame from `input`: name and parent, then the geometry, the link's
    /// parameters, the elements, the nominal values and the bounds, each checked in turn.
    /// A frame refused adds nothing (the builder stays usable).
    pub(crate) fn frame_with<G, E>(
        &mut self,
        input: FrameInput<'_, G, E>,
    ) -> Result<usize, ModelError>
    where
        G: FnOnce(&str) -> Result<Geometry, ModelError>,
        E: FnOnce(&FrameContext, &mut Vec<Param>) -> Result<FrameElements, ModelError>,
    {
        let n_params = self.params.len();
        let added = self.push_frame(input);
        if added.is_err() {
            self.params.truncate(n_params);
        }
        added
    }

    /// [`ModelBuilder::frame_with`], leaving the parameters of a refused frame behind.
    fn push_frame<G, E>(&mut self, input: FrameInput<'_, G, E>) -> Result<usize, ModelError>
    where
        G: FnOnce(&str) -> Result<Geometry, ModelError>,
        E: FnOnce(&FrameContext, &mut Vec<Param>) -> Result<FrameElements, ModelError>,
    {
        let idx = self.frames.len() + 1;
        let file = self.source.as_str();
        let place = format!("frame {idx} ({})", input.name);
        if self.names.iter().any(|n| n == input.name) {
            return Err(ModelError::field(
                file,
                &place,
                "name",
                "duplicate frame name",
            ));
        }
        let parent = self
            .names
            .iter()
            .position(|n| n == input.parent)
            .ok_or_else(|| {
                ModelError::field(
                    file,
                    &place,
                    "parent",
                    format!("`{}` is not the base nor an earlier frame", input.parent),
                )
            })?;
        let Geometry {
            kind,
            value,
            pre,
            post,
        } = (input.geometry)(&place)?;
        let inertia = input.link.then(|| {
            let p0 = self.params.len();
            self.params.extend(Param::inertia_block(idx));
            p0
        });
        let fx = FrameContext {
            file,
            place: &place,
            index: idx,
            value: &value,
            moving: kind != JointKind::Fixed,
            revolute: kind == JointKind::Revolute,
            n_coordinates: self.coordinates.len(),
        };
        let FrameElements {
            elements,
            stribeck_velocity,
        } = (input.elements)(&fx, &mut self.params)?;
        check_nominal(&input.nominal).map_err(|m| ModelError::field(file, &place, "nominal", m))?;
        check_frame_bounds(file, &place, &input.bounds, inertia.is_some())?;
        if let Some(v) = stribeck_velocity {
            self.stribeck.push((idx, v));
        }
        self.frames.push(Frame {
            name: input.name.to_string(),
            parent,
            kind,
            value,
            pre,
            post,
            inertia,
            elements,
            nominal: input.nominal,
            bounds: input.bounds,
        });
        self.names.push(input.name.to_string());
        Ok(idx)
    }

    /// The model has parameters, and not too many (Stribeck terms included).
    pub(crate) fn check_parameters(&self) -> Result<(), ModelError> {
        if self.params.is_empty() {
            return Err(ModelError::field(
                &self.source,
                "frames",
                "",
                "the model has no parameter",
            ));
        }
        input::check_parameter_count(self.params.len() + self.stribeck.len())
            .map_err(|m| ModelError::field(&self.source, "frames", "", m))
    }

    /// The model, its Stribeck parameters last (as [`Model::with_stribeck`] adds them).
    pub fn build(self) -> Result<Model, ModelError> {
        self.check_parameters()?;
        let measured = self.measured();
        let n = self.coordinates.len();
        let coordinate_is_length = (0..n)
            .map(|k| {
                self.frames.iter().any(|f| {
                    f.kind == JointKind::Prismatic && f.value.terms.iter().any(|t| t.0 == k)
                })
            })
            .collect();
        let mut model = Model {
            name: self.name,
            source: self.source,
            coordinates: self.coordinates,
            coordinate_is_length,
            frames: self.frames,
            gravity: self.gravity,
            measured,
            limits: self.limits.joint,
            cartesian_limits: self.limits.cartesian,
            bounds: self.bounds,
            params: self.params,
            ..Model::unassembled()
        }
        .finish();
        for (frame, v) in self.stribeck {
            model.add_stribeck(frame, v)?;
        }
        Ok(model)
    }
}
