//! Compiled limits: ranges on affine functions of the coordinates and boxes on frame
//! origins, what an excitation must stay within. Written in a description, a limits file
//! or a Python dict, they are read by the `description` feature (`description/limits.rs`);
//! a model built from numbers sets them directly.

use crate::model::{CartesianLimit, Limit, Model};

/// Compiled limits of an excitation: joint limits and Cartesian boxes.
#[derive(Clone, Debug, Default)]
pub struct Limits {
    /// Ranges on affine combinations of the coordinates.
    pub joint: Vec<Limit>,
    /// Boxes (base frame, m) the origins of some frames must stay in.
    pub cartesian: Vec<CartesianLimit>,
}

impl Limits {
    /// The description's `[[limits]]` and `[[cartesian_limits]]`.
    pub fn of_model(model: &Model) -> Limits {
        Limits {
            joint: model.limits.clone(),
            cartesian: model.cartesian_limits.clone(),
        }
    }

    /// Whether there is no limit at all, so an excitation is unconstrained.
    pub fn is_empty(&self) -> bool {
        self.joint.is_empty() && self.cartesian.is_empty()
    }
}
