//! The model's side of the position-dependent torque ([`crate::element::PositionTorque`]),
//! beside the model because the element knows nothing of the model's joints.

use std::f64::consts::TAU;

use crate::element::{Element, PositionTorque};
use crate::error::ModelError;

use super::{Frame, JointKind, Model};

/// The model's side of the position-dependent torque: adding it to the frames with
/// friction (`--position-torque`).
impl Model {
    /// This model with a position-dependent torque of order `order` (1 to 3) and period
    /// one turn (2π rad) on every revolute frame with friction and no position torque yet
    /// (e.g. `dvrk-ident fit --position-torque 2`), its coefficients appended in frame
    /// order. Prismatic frames are left out: their series needs a period in metres,
    /// which only a description gives (`position_torque = { order = 1, period = 0.5 }`).
    ///
    /// ```
    /// let psm = dvrk_model::Model::builtin("psm").unwrap();
    /// let with = psm.with_position_torque(2).unwrap();
    /// // Nine revolute friction frames (the insertion slides), four coefficients each.
    /// assert_eq!(with.n_params(), psm.n_params() + 36);
    /// assert_eq!(with.param_names()[psm.n_params()..][..4], ["Pca1", "Psa1", "Pcb1", "Psb1"]);
    /// assert!(psm.with_position_torque(0).is_err() && psm.with_position_torque(4).is_err());
    /// ```
    pub fn with_position_torque(&self, order: usize) -> Result<Model, ModelError> {
        self.with_position_torque_on(order, &[])
    }

    /// As [`Model::with_position_torque`], on the named frames only (each revolute with
    /// friction; one that has a position torque already keeps it); no names: every such
    /// frame. A description's `[preset]` names the frames whose joints carry a cable
    /// torque (the MTM's shoulder and elbow pitch), so that the others keep the torque
    /// the links' gravity explains.
    ///
    /// ```
    /// let mtm = dvrk_model::Model::builtin("mtm").unwrap();
    /// let frames = ["upper_arm".to_string(), "forearm".to_string()];
    /// let with = mtm.with_position_torque_on(1, &frames).unwrap();
    /// assert_eq!(with.param_names()[mtm.n_params()..], ["Pca2", "Psa2", "Pca3", "Psa3"]);
    /// // The recommendation of the MTM's description for `--preset dvrk`.
    /// assert_eq!(mtm.preset.position_torque, Some((1, frames.to_vec())));
    /// let err = mtm.with_position_torque_on(1, &["elbow".to_string()]).unwrap_err();
    /// assert!(err.to_string().contains("no frame is named elbow"), "{err}");
    /// ```
    pub fn with_position_torque_on(
        &self,
        order: usize,
        frames: &[String],
    ) -> Result<Model, ModelError> {
        PositionTorque::check_order(order).map_err(|e| ModelError::Numeric {
            model: self.name.clone(),
            message: e.to_string(),
        })?;
        self.check_position_torque_frames(frames)?;
        let mut m = self.clone();
        for (i, f) in m.frames.iter_mut().enumerate() {
            let has = f
                .elements
                .iter()
                .any(|e| matches!(e, Element::PositionTorque(_)));
            let chosen = frames.is_empty() || frames.contains(&f.name);
            if !takes_position_torque(f) || has || !chosen {
                continue;
            }
            let t = PositionTorque {
                param: m.params.len(),
                order,
                period: TAU,
            };
            m.params
                .extend(Element::PositionTorque(t.clone()).params(i + 1));
            f.elements.push(Element::PositionTorque(t));
        }
        m.element_plan = m.derive_element_plan();
        Ok(m)
    }

    /// Refuses a name of `frames` that is not one of this model's frames able to take a
    /// position torque ([`Model::with_position_torque_on`]), without building the model
    /// that would have it: for a description's `[preset]` and a fit's settings.
    pub fn check_position_torque_frames(&self, frames: &[String]) -> Result<(), ModelError> {
        for name in frames {
            let refuse =
                |why: &str| ModelError::field(&self.source, "position torque frames", name, why);
            match self.frames.iter().find(|f| &f.name == name) {
                None => return Err(refuse(&format!("no frame is named {name}"))),
                Some(f) if !takes_position_torque(f) => {
                    return Err(refuse("not a revolute frame with friction"))
                }
                Some(_) => {}
            }
        }
        Ok(())
    }
}

/// Whether `f` can take the position torque of `--position-torque`: a revolute frame
/// (a prismatic one's series needs a period in metres, which only a description gives)
/// with friction.
fn takes_position_torque(f: &Frame) -> bool {
    f.kind == JointKind::Revolute && f.friction().is_some()
}
