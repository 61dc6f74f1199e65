//! The joints a fit's results are shown in ([`Joints`]): the estimator works in model
//! coordinates, while a user of a coupled arm thinks in its measured joints (the
//! PSM's `q5..q7` are motor-side angles; its wrist is `outer_wrist_pitch`,
//! `outer_wrist_yaw`, `jaw`). Errors, figures and predictions go through one
//! [`JointMap`], so the metrics, the report and Python's `predict` agree.

use std::borrow::Cow;

use dvrk_model::Model;
use nalgebra::DMatrix;

use super::prepare::Prepared;
use crate::error::IdentError;
use crate::settings::Joints;

/// Units of a coordinate or joint: (position, velocity, acceleration, effort).
pub fn units(is_length: bool) -> [&'static str; 4] {
    if is_length {
        ["m", "m/s", "m/s²", "N"]
    } else {
        ["rad", "rad/s", "rad/s²", "N·m"]
    }
}

/// Model-coordinate samples shown in the joints asked for. Motions map through the
/// coupling, `q_measured = M·q` (velocities and accelerations alike: `M` is constant);
/// torques through `M⁻ᵀ`, because the model's torques are `τ = Mᵀ·τ_measured` (the same
/// power `τᵀ·q̇ = τ_measuredᵀ·q̇_measured`), as [`super::to_model_coordinates`] maps a log
/// the other way. Known forces stay subtracted, as in the model-coordinate torques.
///
/// ```
/// use dvrk_ident::validate::JointMap;
/// use dvrk_ident::Joints;
/// use nalgebra::DMatrix;
///
/// let psm = dvrk_model::Model::builtin("psm").unwrap();
/// let map = JointMap::new(&psm, Joints::Measured).unwrap();
/// assert_eq!(map.names[4], "outer_wrist_pitch");
/// // One sample: the model's torques and velocities shown in the measured joints keep
/// // the power τᵀ·q̇.
/// let dq = DMatrix::from_row_slice(1, 7, &[0.1, -0.2, 0.03, 0.4, 0.5, -0.6, 0.7]);
/// let tau = DMatrix::from_row_slice(1, 7, &[1.0, 2.0, -3.0, 0.1, 0.2, 0.3, -0.4]);
/// let power = (dq.row(0) * tau.row(0).transpose())[0];
/// let shown = (map.motion(&dq).row(0) * map.torque(&tau).row(0).transpose())[0];
/// assert!((power - shown).abs() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct JointMap {
    /// The joints shown.
    pub joints: Joints,
    /// The robot's name, for titles.
    pub robot: String,
    /// The shown joints' names: the model coordinates or the measured joints.
    pub names: Vec<String>,
    /// Whether each shown joint is a length (m, N) rather than an angle (rad, N·m).
    pub is_length: Vec<bool>,
    /// `(M, M⁻ᵀ)`; `None` where the joints are the model coordinates themselves (an
    /// identity coupling), so their numbers are the model's to the last bit.
    maps: Option<(DMatrix<f64>, DMatrix<f64>)>,
}

impl JointMap {
    /// The map of `model` to `joints`. Errors for a singular coupling (which no log
    /// could have been mapped through either).
    pub fn new(model: &Model, joints: Joints) -> Result<JointMap, IdentError> {
        let n = model.dof();
        let (names, is_length, maps) = match joints {
            Joints::Model => (
                model.coordinates.clone(),
                model.coordinate_is_length.clone(),
                None,
            ),
            Joints::Measured => {
                let m = &model.measured.coupling;
                let maps = if *m == DMatrix::identity(n, n) {
                    None
                } else {
                    let minv =
                        model
                            .measured_to_model_matrix()
                            .ok_or_else(|| IdentError::Setting {
                                name: crate::options::Setting::Joints.into(),
                                message: format!(
                                    "robot {}'s coupling matrix is singular: its measured \
                                     joints cannot be shown",
                                    model.name
                                ),
                            })?;
                    Some((m.clone(), minv.transpose()))
                };
                (
                    model.measured.joints.clone(),
                    (0..n)
                        .map(|k| model.measured.is_length(k, &model.coordinate_is_length))
                        .collect(),
                    maps,
                )
            }
        };
        Ok(JointMap {
            joints,
            robot: model.name.clone(),
            names,
            is_length,
            maps,
        })
    }

    /// Number of joints (the model's coordinate count).
    pub fn dof(&self) -> usize {
        self.names.len()
    }

    /// Whether the shown numbers are the model coordinates' own (no coupling to apply).
    pub fn is_identity(&self) -> bool {
        self.maps.is_none()
    }

    /// Units of shown joint `j`: (position, velocity, acceleration, effort).
    pub fn units(&self, j: usize) -> [&'static str; 4] {
        units(self.is_length.get(j).copied().unwrap_or(false))
    }

    /// Positions, velocities or accelerations (samples × coordinates) in the shown
    /// joints; `x` itself, not a copy, for the model coordinates.
    pub fn motion<'a>(&self, x: &'a DMatrix<f64>) -> Cow<'a, DMatrix<f64>> {
        match &self.maps {
            None => Cow::Borrowed(x),
            Some((m, _)) => Cow::Owned(x * m.transpose()),
        }
    }

    /// Torques (samples × coordinates, N·m or N) in the shown joints; `x` itself for the
    /// model coordinates.
    pub fn torque<'a>(&self, x: &'a DMatrix<f64>) -> Cow<'a, DMatrix<f64>> {
        match &self.maps {
            None => Cow::Borrowed(x),
            Some((_, w)) => Cow::Owned(x * w.transpose()),
        }
    }

    /// A torque second-moment matrix `Σ τ·τᵀ` (coordinates × coordinates) in the shown
    /// joints, `W·G·Wᵀ`: the metrics' sums of squares in any joints from one pass.
    pub fn torque_gram(&self, g: &DMatrix<f64>) -> DMatrix<f64> {
        match &self.maps {
            None => g.clone(),
            Some((_, w)) => w * g * w.transpose(),
        }
    }

    /// The processed samples in the shown joints (for figures and Python); `p` itself
    /// for the model coordinates. The estimator and the inverse dynamics read only
    /// model coordinates.
    pub fn prepared<'a>(&self, p: &'a Prepared) -> Cow<'a, Prepared> {
        if self.is_identity() {
            return Cow::Borrowed(p);
        }
        Cow::Owned(Prepared {
            source: p.source.clone(),
            time: p.time.clone(),
            q: self.motion(&p.q).into_owned(),
            dq: self.motion(&p.dq).into_owned(),
            ddq: self.motion(&p.ddq).into_owned(),
            tau: self.torque(&p.tau).into_owned(),
        })
    }
}
