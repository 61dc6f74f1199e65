//! A payload: a rigid body (a tool, a weight, a grasped object) fixed to one frame of the
//! robot. Its barycentric parameters add to that frame's link parameters, so the model
//! with its load is the same model with other numbers: inverse dynamics, simulation,
//! the residual and every export use it unchanged.

use crate::error::ModelError;
use crate::inertia::{barycentric_from_standard, pseudo_inertia_min_eigenvalue};
use crate::input::MAX_VALUE;
use crate::model::Model;
use crate::param::{FrameBounds, Nominal, Param};

/// A rigid payload fixed to frame `frame`.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Payload {
    /// The frame it is fixed to (a frame that carries link parameters).
    pub frame: String,
    /// Mass, kg (positive).
    pub mass: f64,
    /// Centre of mass, m, in the frame's axes and from its origin.
    pub com: [f64; 3],
    /// Inertia about the centre of mass in the frame's axes, kg·m²: `xx yy zz xy xz yz`
    /// (zeros: a point mass).
    pub inertia: [f64; 6],
}

impl Payload {
    /// The payload's barycentric parameters in its frame, `[Lxx, Lxy, Lxz, Lyy, Lyz,
    /// Lzz, lx, ly, lz, m]` (the link parameters' order).
    pub fn barycentric(&self) -> [f64; 10] {
        let [xx, yy, zz, xy, xz, yz] = self.inertia;
        barycentric_from_standard(self.mass, self.com, [xx, xy, xz, yy, yz, zz])
    }

    /// Checks the payload against `model`; returns the index of its frame's first link
    /// parameter (`L{i}xx`). `file` names where the payload came from in the errors.
    pub fn check(&self, model: &Model, file: &str) -> Result<usize, ModelError> {
        let field =
            |field: &str, message: String| ModelError::field(file, "payload", field, message);
        if !(self.mass.is_finite() && self.mass > 0.0 && self.mass <= MAX_VALUE) {
            return Err(field(
                "mass",
                format!("must be positive and finite (kg), got {}", self.mass),
            ));
        }
        if let Some(c) = self
            .com
            .iter()
            .find(|c| !(c.is_finite() && c.abs() <= MAX_VALUE))
        {
            return Err(field("com", format!("must be finite (m), got {c}")));
        }
        if let Some(c) = self
            .inertia
            .iter()
            .find(|c| !(c.is_finite() && c.abs() <= MAX_VALUE))
        {
            return Err(field("inertia", format!("must be finite (kg·m²), got {c}")));
        }
        // A density can realize it: the pseudo-inertia is positive semidefinite (to
        // rounding; a point mass is exactly on the boundary).
        let p = self.barycentric();
        let scale = p.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if pseudo_inertia_min_eigenvalue(&p) < -1e-12 * scale {
            return Err(field(
                "inertia",
                "is not that of a physical body (the moments must be non-negative and \
                 satisfy the triangle inequalities; xx yy zz xy xz yz)"
                    .into(),
            ));
        }
        link_frame(model, &self.frame, file).map(|(_, p0)| p0)
    }

    /// Adds the payload to the link parameters of its frame in `params` (the model's
    /// order). Errors as [`Payload::check`].
    pub fn add_to(&self, model: &Model, params: &mut [f64], file: &str) -> Result<(), ModelError> {
        let p0 = self.check(model, file)?;
        assert_eq!(params.len(), model.n_params(), "parameter vector length");
        for (p, b) in params[p0..p0 + 10].iter_mut().zip(self.barycentric()) {
            *p += b;
        }
        Ok(())
    }

    /// The payload alone as a parameter vector of `model` (zeros except its frame's
    /// link parameters): the inverse dynamics of it is the torque the payload adds.
    pub fn params(&self, model: &Model, file: &str) -> Result<Vec<f64>, ModelError> {
        let mut params = vec![0.0; model.n_params()];
        self.add_to(model, &mut params, file)?;
        Ok(params)
    }
}

/// The frame named `frame` that carries link parameters: its index in `model.frames`
/// and the index of its first link parameter (`L{i}xx`). The error names the robot's
/// frames that do; `file` names where the frame's name came from.
fn link_frame(model: &Model, frame: &str, file: &str) -> Result<(usize, usize), ModelError> {
    let error = |message: String| ModelError::field(file, "payload", "frame", message);
    let frames = || {
        model
            .link_frames()
            .iter()
            .map(|&j| model.frame(j).name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some(j) = model.frames.iter().position(|f| f.name == frame) else {
        return Err(error(format!(
            "robot {} has no frame `{frame}` (frames with link parameters: {})",
            model.name,
            frames()
        )));
    };
    match model.frames[j].inertia {
        Some(p0) => Ok((j, p0)),
        None => Err(error(format!(
            "frame `{frame}` carries no link parameters; fix the payload to one that does: {}",
            frames()
        ))),
    }
}

impl Model {
    /// This robot carrying nothing but a rigid body fixed to frame `frame`: the same
    /// kinematics, gravity and coordinates, one link (the body) with the 10 barycentric
    /// parameters of that frame (named as its link parameters, `L{i}xx … m{i}`), and no
    /// other link, element, known force, nominal value or frame bound. Its regressor is
    /// the torque such a body adds to the arm (`τ = H·π_payload`), so identifying a
    /// payload is a fit of this model to what the arm's model leaves unexplained, with
    /// the estimators, base parameters and consistency constraints of any fit. `frame`
    /// must carry link parameters (as for [`Payload::check`]); `file` names where its
    /// name came from in the error.
    ///
    /// ```
    /// let psm = dvrk_model::Model::builtin("psm").unwrap();
    /// let body = psm.payload_model("main_insertion", "--frame").unwrap();
    /// assert_eq!(body.n_params(), 10);
    /// assert_eq!(body.dof(), psm.dof());
    /// assert!(psm.payload_model("nowhere", "--frame").is_err());
    /// ```
    pub fn payload_model(&self, frame: &str, file: &str) -> Result<Model, ModelError> {
        let (j, _) = link_frame(self, frame, file)?;
        let mut model = self.clone();
        for (i, f) in model.frames.iter_mut().enumerate() {
            f.inertia = (i == j).then_some(0);
            f.elements.clear();
            f.nominal = Nominal::default();
            f.bounds = FrameBounds::default();
        }
        model.params = Param::inertia_block(j + 1).collect();
        Ok(model.finish())
    }
}
