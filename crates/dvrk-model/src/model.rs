//! The immutable model: a tree of frames whose joint values are affine in the
//! generalized coordinates, with per-frame elements and the parameter layout.
//!
//! It is built once (from a description file or a URDF) and shared read-only; every
//! per-sample algorithm takes it by reference together with a mutable
//! [`Workspace`](crate::Workspace).

use nalgebra::{DMatrix, Vector3};

use crate::element::{Element, Friction, KnownForce, MotorInertia, Spring, Stribeck};
use crate::expr::{Affine, Expr, ExprError, Scope};
pub use crate::param::*;
pub use crate::spatial::Transform;
use crate::ModelError;

mod plan;
mod position_torque;
pub(crate) use plan::{Axis, Body, ElementPlan, RegressorPlan};

/// How a frame moves relative to its parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the joint axis by the joint value (rad).
    Revolute,
    /// Translation along the joint axis by the joint value (m).
    Prismatic,
    /// No motion: the frame is rigidly attached to its parent.
    Fixed,
}

/// A limit on an affine combination of coordinates (excitation or joint limit).
#[derive(Clone, Debug)]
pub struct Limit {
    /// The source text (e.g. `1.2177*(q7 - q6)`), for messages.
    pub label: String,
    /// The limited combination `a·q + b` of the coordinates (rad or m), which the
    /// ranges below apply to.
    pub expr: Affine,
    /// rad or m
    pub position: Option<[f64; 2]>,
    /// rad/s or m/s
    pub velocity: Option<[f64; 2]>,
    /// rad/s² or m/s²
    pub acceleration: Option<[f64; 2]>,
}

/// A box the origin of a frame must stay in, in base-frame coordinates (an excitation
/// limit: e.g. keep the wrist away from the table or the other arm). Unlike [`Limit`] it
/// is nonlinear in the coordinates, so the optimizer treats it through the frame-origin
/// Jacobian.
#[derive(Clone, Debug, PartialEq)]
pub struct CartesianLimit {
    /// Frame index (1-based; the base never moves, so it cannot be limited).
    pub frame: usize,
    /// The frame's name, for messages.
    pub frame_name: String,
    /// Lower corner `[x, y, z]`, m; `-inf` leaves an axis unbounded below.
    pub min: [f64; 3],
    /// Upper corner `[x, y, z]`, m; `inf` leaves an axis unbounded above.
    pub max: [f64; 3],
}

impl CartesianLimit {
    /// Checks a box on frame `frame` (a name of `frame_names`, base first as in
    /// [`Model::frame_names`]). The error is `(field, message)` so that each caller can
    /// name its own file and entry.
    pub fn new(
        frame_names: &[String],
        frame: &str,
        min: [f64; 3],
        max: [f64; 3],
    ) -> Result<CartesianLimit, (&'static str, String)> {
        let index = match frame_names.iter().position(|f| f == frame) {
            Some(0) => {
                return Err((
                    "frame",
                    "the base frame does not move: limit a frame of [[frames]]".into(),
                ))
            }
            Some(i) => i,
            None => {
                return Err((
                    "frame",
                    format!(
                        "no frame named `{frame}` (frames: {})",
                        frame_names[1..].join(", ")
                    ),
                ))
            }
        };
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let (lo, hi) = (min[k], max[k]);
            if lo.is_nan() || lo == f64::INFINITY {
                return Err(("min", format!("{axis}: {lo} is not a lower bound")));
            }
            if hi.is_nan() || hi == f64::NEG_INFINITY {
                return Err(("max", format!("{axis}: {hi} is not an upper bound")));
            }
            if lo > hi {
                return Err((
                    "min",
                    format!("{axis}: lower bound {lo} is above upper bound {hi}"),
                ));
            }
        }
        Ok(CartesianLimit {
            frame: index,
            frame_name: frame.to_string(),
            min,
            max,
        })
    }
}

/// One frame of the tree (frame index = position in [`Model::frames`] + 1; 0 is the base).
#[derive(Clone, Debug)]
pub struct Frame {
    /// The frame's name in the description (a URDF link name for URDF models).
    pub name: String,
    /// Parent frame index (0 = base); always smaller than this frame's index.
    pub parent: usize,
    /// How the frame moves relative to its parent: about z, along z, or not at all.
    pub kind: JointKind,
    /// Joint value `s = a·q + b` (rad or m); constant for fixed frames.
    pub value: Affine,
    /// Transform parent → joint frame (before the motion).
    pub pre: Transform,
    /// Transform joint frame after the motion → this frame. The joint moves along/about
    /// the z axis of the joint frame.
    pub post: Transform,
    /// Parameter index of `L{i}xx` when the frame carries a rigid link.
    pub inertia: Option<usize>,
    /// What acts on the joint value besides the links (friction, springs...), in
    /// parameter order (see [`Element`]).
    pub elements: Vec<Element>,
    /// Prior values of the frame's parameters, from the description.
    pub nominal: Nominal,
    /// The frame's own bounds for the physically consistent fit.
    pub bounds: FrameBounds,
}

impl Frame {
    /// The friction element, if any.
    pub fn friction(&self) -> Option<&Friction> {
        self.elements.iter().find_map(|e| match e {
            Element::Friction(x) => Some(x),
            _ => None,
        })
    }

    /// The Stribeck term of the friction, if any.
    pub fn stribeck(&self) -> Option<&Stribeck> {
        self.friction().and_then(|f| f.stribeck.as_ref())
    }

    /// The motor inertia, if any.
    pub fn motor_inertia(&self) -> Option<&MotorInertia> {
        self.elements.iter().find_map(|e| match e {
            Element::MotorInertia(x) => Some(x),
            _ => None,
        })
    }

    /// The spring, if any.
    pub fn spring(&self) -> Option<&Spring> {
        self.elements.iter().find_map(|e| match e {
            Element::Spring(x) => Some(x),
            _ => None,
        })
    }

    /// The known force, if any.
    pub fn known_force(&self) -> Option<&KnownForce> {
        self.elements.iter().find_map(|e| match e {
            Element::KnownForce(x) => Some(x),
            _ => None,
        })
    }
}

/// The measured (e.g. dVRK/ROS) joint space.
#[derive(Clone, Debug)]
pub struct Measured {
    /// Measured joint names, one per coordinate, in measured order.
    pub joints: Vec<String>,
    /// `q_measured = M · q_model`, n×n.
    pub coupling: DMatrix<f64>,
    /// The physical range of each measured joint, `[min, max]` (rad or m), where the
    /// description gives one (the dVRK's `qmin`/`qmax`, a URDF's `<limit>`): a log that
    /// leaves it clearly is of another arm, or given with the wrong robot.
    pub ranges: Vec<Option<[f64; 2]>>,
}

impl Measured {
    /// Whether measured joint `k` is a length (m): its coupling row combines only
    /// coordinates that are lengths (`coordinate_is_length`, per model coordinate).
    pub fn is_length(&self, k: usize, coordinate_is_length: &[bool]) -> bool {
        let row = self.coupling.row(k);
        row.iter()
            .zip(coordinate_is_length)
            .all(|(&c, &is_length)| c == 0.0 || is_length)
    }

    /// An affine function of the model coordinates from `text`, which may name model
    /// coordinates and measured joints: a measured joint stands for its row of the
    /// coupling (`q_measured,i = Σ_j M_ij q_j`), so that a limit on the dVRK jaw reads
    /// `jaw` rather than `1.2177*(q7 - q6)`. A measured joint named like a coordinate is
    /// that coordinate.
    ///
    /// ```
    /// use dvrk_model::Model;
    /// let psm = Model::builtin("psm").unwrap();
    /// let jaw = psm.measured.affine("jaw", &[], &psm.coordinates).unwrap();
    /// assert_eq!(jaw.terms, vec![(5, -1.2177), (6, 1.2177)]);
    /// ```
    pub fn affine(
        &self,
        text: &str,
        constants: &[(String, f64)],
        coordinates: &[String],
    ) -> Result<Affine, ExprError> {
        let n = coordinates.len();
        let extra: Vec<usize> = (0..self.joints.len())
            .filter(|&i| !coordinates.contains(&self.joints[i]))
            .collect();
        let mut names = coordinates.to_vec();
        names.extend(extra.iter().map(|&i| self.joints[i].clone()));
        let scope = Scope {
            constants,
            coordinates: &names,
        };
        let a = Expr::parse(text, &scope)?.affine(names.len())?;
        let mut q = vec![0.0; n];
        for (k, c) in a.terms {
            if k < n {
                q[k] += c;
            } else {
                let i = extra[k - n];
                for (j, qj) in q.iter_mut().enumerate() {
                    *qj += c * self.coupling[(i, j)];
                }
            }
        }
        Ok(Affine {
            terms: q
                .into_iter()
                .enumerate()
                .filter(|&(_, c)| c != 0.0)
                .collect(),
            offset: a.offset,
        })
    }
}

/// The gravitational acceleration the dVRK's controller uses, m/s² (the magnitude of
/// [`Model::mounting_pitch_gravity`]).
pub const STANDARD_GRAVITY: f64 = 9.81;

/// Elements a description recommends for the identification preset (its `[preset]`
/// table), measured on real logs; the model as described does not have them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PresetElements {
    /// A position-dependent torque of this order on these frames (by name; see
    /// [`Model::with_position_torque_on`]), e.g. the MTM's cable torques of the shoulder
    /// and elbow pitch.
    pub position_torque: Option<(usize, Vec<String>)>,
}

/// The robot model. Build it from numbers with [`ModelBuilder`](crate::ModelBuilder), or,
/// with the `description` feature (default), from a file with `Model::load`,
/// `Model::builtin`, `Model::from_toml_str` or `Model::from_urdf_str`.
#[derive(Clone, Debug)]
pub struct Model {
    /// The robot's name, e.g. `psm` (the description's `name`, or the URDF robot's name).
    pub name: String,
    /// Where the model came from (file path or `builtin:psm`), for error messages.
    pub source: String,
    /// Generalized coordinate names, in order.
    pub coordinates: Vec<String>,
    /// Whether each coordinate is a length (m) rather than an angle (rad).
    pub coordinate_is_length: Vec<bool>,
    /// Frames of the tree in order (frame `i` at index `i - 1`; parents come first).
    pub frames: Vec<Frame>,
    /// Gravity in the base frame (m/s²).
    pub gravity: Vector3<f64>,
    /// The measured (e.g. dVRK/ROS) joint names and their coupling to the model coordinates.
    pub measured: Measured,
    /// The `[[limits]]` of the description: ranges on affine combinations of coordinates.
    pub limits: Vec<Limit>,
    /// Boxes on frame origins (`[[cartesian_limits]]`).
    pub cartesian_limits: Vec<CartesianLimit>,
    /// Lower bounds applied to every element by the physically consistent fit.
    pub bounds: GlobalBounds,
    /// What the description recommends adding to the model for the identification
    /// preset (`--preset dvrk`), which the model as described leaves out so that it
    /// stays the published one (the 2019 fits reproduce it): the description's
    /// `[preset]` table.
    pub preset: PresetElements,
    /// Every parameter's name, kind and frame, in regressor column order.
    pub params: Vec<Param>,
    // Derived, for the per-sample algorithms.
    /// Frames (1-based) carrying link inertia, in order.
    pub(crate) links: Vec<usize>,
    /// Frames (1-based, increasing) with at least one link in their subtree: the only
    /// ones whose motion matters to the link dynamics, so the per-sample passes skip the
    /// rest (e.g. the PSM's massless tool and virtual motor frames).
    pub(crate) active: Vec<usize>,
    /// Motion subspace of each frame in its own coordinates: `[ω; v]` for unit joint rate.
    pub(crate) motion: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Transform parent → frame for fixed frames (precomputed).
    pub(crate) fixed: Vec<Transform>,
    /// Whether each frame's `post` rotation is the identity, and its translation zero
    /// (then skipped per sample).
    pub(crate) post_identity: Vec<(bool, bool)>,
    /// The moving frames that carry link dynamics, parents first (see [`Body`]).
    pub(crate) bodies: Vec<Body>,
    /// The regressor's link blocks (see [`RegressorPlan`]).
    pub(crate) regressor_plan: RegressorPlan,
    /// The elements in the order the per-sample passes visit them (see [`ElementPlan`]).
    pub(crate) element_plan: ElementPlan,
}

impl Model {
    /// Number of generalized coordinates.
    pub fn dof(&self) -> usize {
        self.coordinates.len()
    }

    /// Number of parameters (columns of the full regressor).
    pub fn n_params(&self) -> usize {
        self.params.len()
    }

    /// Parameter names in column order (2019 convention: `L1xx`, ..., `m1`, `Fc1`, ...).
    pub fn param_names(&self) -> Vec<String> {
        self.params.iter().map(|p| p.name.clone()).collect()
    }

    /// Index of a parameter by name.
    pub fn param_index(&self, name: &str) -> Option<usize> {
        self.params.iter().position(|p| p.name == name)
    }

    /// Frame by index (1-based; the base has no [`Frame`]).
    pub fn frame(&self, index: usize) -> &Frame {
        &self.frames[index - 1]
    }

    /// Frame indices that carry link inertia.
    pub fn link_frames(&self) -> &[usize] {
        &self.links
    }

    /// Every linear bound of the physically consistent fit, each with the index of its
    /// frame in [`Model::frames`] (0-based): per link, with `use_frame`, the frame's
    /// mass range (`m_min ≤ m ≤ m_max`) and centre-of-mass box (`m·r_min ≤ l ≤ m·r_max`
    /// per axis), then each element's bounds ([`Element::bound_rows`]: the global lower
    /// bounds always, the frame's maxima and ranges with `use_frame`). Each row lists the
    /// parameter it bounds first ([`crate::BoundRow::bound_on_first`]).
    pub fn bound_rows(&self, use_frame: bool) -> Vec<(usize, crate::BoundRow)> {
        use crate::{BoundOrigin, BoundRow, BoundsContext};
        let mut out = Vec::new();
        for (fi, f) in self.frames.iter().enumerate() {
            let b = &f.bounds;
            if let (Some(p0), true) = (f.inertia, use_frame) {
                let m = p0 + 9;
                if let Some([lo, hi]) = b.mass {
                    out.push((fi, BoundRow::at_least(m, lo, BoundOrigin::Frame("mass"))));
                    out.push((fi, BoundRow::at_most(m, hi, BoundOrigin::Frame("mass"))));
                }
                for (k, [lo, hi]) in b.com.into_iter().flatten().enumerate() {
                    let l = p0 + 6 + k;
                    let row = |coefficients, origin| BoundRow {
                        coefficients,
                        limit: 0.0,
                        origin,
                    };
                    // m·lo ≤ l and l ≤ m·hi
                    out.push((fi, row(vec![(l, -1.0), (m, lo)], BoundOrigin::Frame("com"))));
                    out.push((fi, row(vec![(l, 1.0), (m, -hi)], BoundOrigin::Frame("com"))));
                }
            }
            let context = BoundsContext {
                global: &self.bounds,
                frame: b,
                use_frame,
            };
            let mut rows = Vec::new();
            for e in &f.elements {
                e.bound_rows(&context, &mut rows);
            }
            out.extend(rows.into_iter().map(|r| (fi, r)));
        }
        out
    }

    /// Frame names with the base first, indexed like frame indices.
    pub fn frame_names(&self) -> Vec<String> {
        std::iter::once("base".to_string())
            .chain(self.frames.iter().map(|f| f.name.clone()))
            .collect()
    }

    /// The constraint Jacobian `A` (N×n, one row per frame, base excluded): `ṡ = A·q̇`.
    pub fn constraint_jacobian(&self) -> DMatrix<f64> {
        let n = self.dof();
        let mut a = DMatrix::zeros(self.frames.len(), n);
        for (i, f) in self.frames.iter().enumerate() {
            if f.kind != JointKind::Fixed {
                for &(k, c) in &f.value.terms {
                    a[(i, k)] = c;
                }
            }
        }
        a
    }

    /// The nominal parameter vector from the description's `nominal` entries; `None` if
    /// any parameter has no nominal value.
    pub fn nominal_parameters(&self) -> Option<Vec<f64>> {
        let mut pi = vec![f64::NAN; self.n_params()];
        for f in &self.frames {
            let nom = &f.nominal;
            if let Some(p0) = f.inertia {
                let m = nom.mass?;
                let c = nom.com.unwrap_or([0.0; 3]);
                let ic = nom.inertia.unwrap_or([0.0; 6]);
                let bary = crate::inertia::barycentric_from_standard(m, c, ic);
                pi[p0..p0 + 10].copy_from_slice(&bary);
            }
            for e in &f.elements {
                e.nominal(nom, &mut pi)?;
            }
        }
        Some(pi)
    }

    /// Known generalized forces (e.g. a cable) at `q`, added into `tau` (N·m or N).
    pub fn add_known_forces(&self, q: &[f64], tau: &mut [f64]) {
        for f in &self.frames {
            for e in &f.elements {
                e.add_known(q, tau);
            }
        }
    }

    /// Adds a Stribeck term of velocity `velocity` (rad/s or m/s) to the friction
    /// element of frame `frame` (1-based); its `Fs{frame}` parameter is appended to the
    /// parameter vector. Errors if the frame has no friction, already has a Stribeck
    /// term, or the velocity is not positive and finite.
    pub fn add_stribeck(&mut self, frame: usize, velocity: f64) -> Result<(), ModelError> {
        let numeric = |message: String| ModelError::Numeric {
            model: self.name.clone(),
            message,
        };
        if !(velocity > 0.0 && velocity.is_finite()) {
            return Err(numeric(format!(
                "Stribeck velocity must be positive and finite, got {velocity}"
            )));
        }
        let p = self.params.len();
        let Some(f) = frame.checked_sub(1).and_then(|i| self.frames.get_mut(i)) else {
            return Err(numeric(format!("no frame {frame}")));
        };
        let name = f.name.clone();
        let Some(fr) = f.elements.iter_mut().find_map(|e| match e {
            Element::Friction(x) => Some(x),
            _ => None,
        }) else {
            return Err(numeric(format!(
                "frame {frame} ({name}) has no friction to add a Stribeck term to"
            )));
        };
        if fr.stribeck.is_some() {
            return Err(numeric(format!(
                "frame {frame} ({name}) already has a Stribeck term"
            )));
        }
        fr.stribeck = Some(Stribeck { param: p, velocity });
        self.params.push(Param {
            name: format!("Fs{frame}"),
            kind: ParamKind::Stribeck,
            frame,
        });
        self.element_plan = self.derive_element_plan();
        Ok(())
    }

    /// This model with a Stribeck term of velocity `velocity` (rad/s or m/s) on every
    /// friction element that has none (e.g. `dvrk-ident fit --stribeck 0.1`).
    ///
    /// ```
    /// let psm = dvrk_model::Model::builtin("psm").unwrap();
    /// let with = psm.with_stribeck(0.1).unwrap();
    /// // One Fs per friction element (10 on the PSM), appended after the others.
    /// assert_eq!(with.n_params(), psm.n_params() + 10);
    /// assert_eq!(with.param_names()[psm.n_params()], "Fs1");
    /// ```
    pub fn with_stribeck(&self, velocity: f64) -> Result<Model, ModelError> {
        let mut m = self.clone();
        let frames: Vec<usize> = (1..=m.frames.len())
            .filter(|&i| {
                let f = &m.frames[i - 1];
                f.friction().is_some() && f.stribeck().is_none()
            })
            .collect();
        for i in frames {
            m.add_stribeck(i, velocity)?;
        }
        Ok(m)
    }

    /// Gravity of a dVRK arm mounted at pitch `pitch_deg` (degrees), in its base frame:
    /// `(0, −g·sin p, −g·cos p)` with `g` = [`STANDARD_GRAVITY`]. The dVRK controller
    /// turns its `mounting_pitch` (rad) into the "up" vector `(0, g·sin p, g·cos p)` it
    /// passes to its gravity compensation (sawIntuitiveResearchKit,
    /// `mtsIntuitiveResearchKitArm.cpp`); gravity is its opposite. The dVRK mounts the
    /// PSMs on the patient cart at −45° (PSM1, PSM2) and −15° (PSM3), the ECM at −70°
    /// (Si) or −45° (Classic). Refuses a pitch that is not finite or beyond ±180°.
    ///
    /// ```
    /// let g = dvrk_model::Model::mounting_pitch_gravity(-45.0).unwrap();
    /// assert!((g[1] - 9.81 * 0.5f64.sqrt()).abs() < 1e-12 && (g[2] + 9.81 * 0.5f64.sqrt()).abs() < 1e-12);
    /// assert!(dvrk_model::Model::mounting_pitch_gravity(f64::NAN).is_err());
    /// ```
    pub fn mounting_pitch_gravity(
        pitch_deg: f64,
    ) -> Result<Vector3<f64>, crate::input::InputError> {
        if !(pitch_deg.is_finite() && pitch_deg.abs() <= 180.0) {
            return Err(crate::input::InputError::MountingPitch { pitch_deg });
        }
        let p = pitch_deg.to_radians();
        Ok(Vector3::new(
            0.0,
            -STANDARD_GRAVITY * p.sin(),
            -STANDARD_GRAVITY * p.cos(),
        ))
    }

    /// Sets [`Model::gravity`] to that of the arm mounted at `pitch_deg` (degrees, see
    /// [`Model::mounting_pitch_gravity`]).
    pub fn set_mounting_pitch(&mut self, pitch_deg: f64) -> Result<(), ModelError> {
        self.gravity =
            Model::mounting_pitch_gravity(pitch_deg).map_err(|e| ModelError::Numeric {
                model: self.name.clone(),
                message: e.to_string(),
            })?;
        Ok(())
    }

    /// True if the model has known forces to subtract before fitting.
    pub fn has_known_forces(&self) -> bool {
        self.frames
            .iter()
            .any(|f| f.elements.iter().any(Element::is_known))
    }

    /// Maps measured joint positions to model coordinates: `q = M⁻¹ q_measured`.
    pub fn measured_to_model_matrix(&self) -> Option<DMatrix<f64>> {
        self.measured.coupling.clone().try_inverse()
    }

    /// A model with nothing in it, for the loaders to fill the description's fields of
    /// (`Model { name, frames, .., ..Model::unassembled() }`) before [`Model::finish`]
    /// derives the rest. Gravity −9.81 m/s² along z and no limits or bounds, as a
    /// description that does not set them.
    pub(crate) fn unassembled() -> Model {
        Model {
            name: String::new(),
            source: String::new(),
            coordinates: Vec::new(),
            coordinate_is_length: Vec::new(),
            frames: Vec::new(),
            gravity: Vector3::new(0.0, 0.0, -9.81),
            measured: Measured {
                joints: Vec::new(),
                coupling: DMatrix::zeros(0, 0),
                ranges: Vec::new(),
            },
            limits: Vec::new(),
            cartesian_limits: Vec::new(),
            bounds: GlobalBounds::default(),
            preset: PresetElements::default(),
            params: Vec::new(),
            links: Vec::new(),
            active: Vec::new(),
            motion: Vec::new(),
            fixed: Vec::new(),
            post_identity: Vec::new(),
            bodies: Vec::new(),
            regressor_plan: RegressorPlan::default(),
            element_plan: ElementPlan::default(),
        }
    }
}

impl Model {
    /// A parameter vector from values by name (e.g. a result file's `parameters`).
    /// Every parameter of the model must be present; unknown names are an error too,
    /// since they usually mean the values belong to another robot.
    pub fn params_from_named<'a>(
        &self,
        values: impl IntoIterator<Item = (&'a str, f64)>,
        source: &str,
    ) -> Result<Vec<f64>, crate::ModelError> {
        let mut pi = vec![f64::NAN; self.n_params()];
        let mut unknown = Vec::new();
        for (name, v) in values {
            match self.param_index(name) {
                Some(k) => pi[k] = v,
                None => unknown.push(name.to_string()),
            }
        }
        let missing: Vec<&str> = self
            .params
            .iter()
            .zip(&pi)
            .filter(|(_, v)| v.is_nan())
            .map(|(p, _)| p.name.as_str())
            .collect();
        if !unknown.is_empty() || !missing.is_empty() {
            let mut msg = String::new();
            if !missing.is_empty() {
                msg += &format!("missing parameters: {}", missing.join(", "));
            }
            if !unknown.is_empty() {
                if !msg.is_empty() {
                    msg += "; ";
                }
                msg += &format!(
                    "parameters not in model {}: {}",
                    self.name,
                    unknown.join(", ")
                );
            }
            return Err(crate::ModelError::Syntax {
                file: source.to_string(),
                message: msg,
            });
        }
        if let Some((p, v)) = self.params.iter().zip(&pi).find(|(_, v)| !v.is_finite()) {
            return Err(crate::ModelError::Syntax {
                file: source.to_string(),
                message: format!("parameter {} is not finite ({v})", p.name),
            });
        }
        Ok(pi)
    }
}
