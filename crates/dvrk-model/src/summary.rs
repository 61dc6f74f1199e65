//! A serializable overview of a model, shared by the CLI (`dvrk-ident model --json`) and
//! the Python module so that both print the same document.

use crate::base::BaseParameters;
use crate::model::{JointKind, Model};

/// One frame, as listed in a summary.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FrameSummary {
    /// Frame index (1-based; 0 is the base).
    pub index: usize,
    /// The frame's name in the description.
    pub name: String,
    /// Parent frame index (0 = base).
    pub parent: usize,
    /// `revolute`, `prismatic` or `fixed`
    pub joint: String,
    /// The joint value as an affine expression of the coordinates (rad or m).
    pub value: String,
    /// `inertia` for a link, then the elements' labels (`friction`, `stribeck`,
    /// `motor_inertia`, `spring`, `known_force`, `quadratic_viscous`), in parameter order.
    pub elements: Vec<String>,
}

/// One base parameter.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct BaseSummary {
    /// Name of the base parameter's leading (kept) standard parameter.
    pub name: String,
    /// The base parameter as a readable combination, e.g. `L2xy + L6xy + 0.2159*l2x`.
    pub expression: String,
}

/// The document printed by `dvrk-ident model ROBOT --json`.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ModelSummary {
    /// The robot's name, e.g. `psm`.
    pub name: String,
    /// Where the model came from (file path or `builtin:psm`).
    pub source: String,
    /// Generalized coordinate names, in order.
    pub coordinates: Vec<String>,
    /// Measured (e.g. dVRK/ROS) joint names, one per coordinate.
    pub measured_joints: Vec<String>,
    /// `q_measured = coupling · q_model`, rows.
    pub coupling: Vec<Vec<f64>>,
    /// Every frame of the tree, in index order.
    pub frames: Vec<FrameSummary>,
    /// Parameter names in regressor column order.
    pub parameters: Vec<String>,
    /// One expression string per base parameter.
    pub base_parameters: Vec<String>,
    /// Each base parameter's name and expression together.
    pub base: Vec<BaseSummary>,
    /// Gravity in the base frame (m/s²).
    pub gravity: [f64; 3],
}

impl Model {
    /// The summary document of this model with its base parameters.
    pub fn summary(&self, base: &BaseParameters) -> ModelSummary {
        let n = self.dof();
        ModelSummary {
            name: self.name.clone(),
            source: self.source.clone(),
            coordinates: self.coordinates.clone(),
            measured_joints: self.measured.joints.clone(),
            coupling: (0..n)
                .map(|r| (0..n).map(|c| self.measured.coupling[(r, c)]).collect())
                .collect(),
            frames: self
                .frames
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    let elements = f
                        .inertia
                        .map(|_| "inertia")
                        .into_iter()
                        .chain(f.elements.iter().flat_map(|e| e.labels().iter().copied()))
                        .map(String::from)
                        .collect();
                    FrameSummary {
                        index: i + 1,
                        name: f.name.clone(),
                        parent: f.parent,
                        joint: match f.kind {
                            JointKind::Revolute => "revolute",
                            JointKind::Prismatic => "prismatic",
                            JointKind::Fixed => "fixed",
                        }
                        .into(),
                        value: if f.kind == JointKind::Fixed {
                            String::new()
                        } else {
                            f.value.display(&self.coordinates)
                        },
                        elements,
                    }
                })
                .collect(),
            parameters: self.param_names(),
            base_parameters: base.expressions.clone(),
            base: base
                .names
                .iter()
                .zip(&base.expressions)
                .map(|(n, e)| BaseSummary {
                    name: n.clone(),
                    expression: e.clone(),
                })
                .collect(),
            gravity: [self.gravity[0], self.gravity[1], self.gravity[2]],
        }
    }
}
