//! A serializable overview of a model, shared by the CLI (`dvrk-ident model --json`) and
//! the Python module so that both print the same document.

use serde::Serialize;

use crate::base::BaseParameters;
use crate::model::{JointKind, Model};

/// One frame, as listed in a summary.
#[derive(Clone, Debug, Serialize)]
pub struct FrameSummary {
    pub index: usize,
    pub name: String,
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
#[derive(Clone, Debug, Serialize)]
pub struct BaseSummary {
    pub name: String,
    pub expression: String,
}

/// The document printed by `dvrk-ident model ROBOT --json`.
#[derive(Clone, Debug, Serialize)]
pub struct ModelSummary {
    pub name: String,
    pub source: String,
    pub coordinates: Vec<String>,
    pub measured_joints: Vec<String>,
    /// `q_measured = coupling · q_model`, rows.
    pub coupling: Vec<Vec<f64>>,
    pub frames: Vec<FrameSummary>,
    /// Parameter names in regressor column order.
    pub parameters: Vec<String>,
    /// One expression string per base parameter.
    pub base_parameters: Vec<String>,
    pub base: Vec<BaseSummary>,
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
