//! The URDF document being generated: its links and joints with unique names
//! ([`Builder`]), a joint to write ([`JointSpec`]) with its range ([`Range`]), and
//! why a model cannot be written ([`GenerateError`]).

use std::collections::HashSet;

use nalgebra::Vector3;

use super::super::inertials::urdf_inertial;
use super::rpy_from_rotation;
use crate::inertia::StandardInertia;
use crate::model::*;

/// A transform as a URDF origin: translation and roll, pitch, yaw.
fn pose(t: &Transform) -> urdf_rs::Pose {
    urdf_rs::Pose {
        xyz: urdf_rs::Vec3(t.translation.map(|x| x + 0.0).into()),
        rpy: urdf_rs::Vec3(rpy_from_rotation(&t.rotation)),
    }
}

/// Position range and speed bound of a coordinate from the description's limits.
#[derive(Clone, Copy, Default)]
pub(super) struct Range {
    pub(super) position: Option<[f64; 2]>,
    pub(super) velocity: Option<f64>,
}

impl Range {
    /// The range of `a·q + c` for `q` in this range.
    pub(super) fn map(&self, a: f64, c: f64) -> Range {
        Range {
            position: self.position.map(|[lo, hi]| {
                let (x, y) = (a * lo + c, a * hi + c);
                [x.min(y), x.max(y)]
            }),
            velocity: self.velocity.map(|v| a.abs() * v),
        }
    }

    pub(super) fn limit(&self) -> urdf_rs::JointLimit {
        let [lower, upper] = self.position.unwrap_or([f64::NEG_INFINITY, f64::INFINITY]);
        urdf_rs::JointLimit {
            lower,
            upper,
            effort: 0.0,
            velocity: self.velocity.unwrap_or(0.0),
            ..Default::default()
        }
    }
}

/// A joint being written; `None` limit means the joint type has none.
pub(super) struct JointSpec {
    pub(super) name: String,
    pub(super) kind: JointKind,
    pub(super) origin: Transform,
    pub(super) parent: String,
    pub(super) child: String,
    pub(super) axis: Vector3<f64>,
    pub(super) range: Range,
    pub(super) mimic: Option<(String, f64, f64)>,
    pub(super) dynamics: Option<urdf_rs::Dynamics>,
}

impl JointSpec {
    /// A fixed joint placing `child` at `origin` in `parent`.
    pub(super) fn fixed(
        name: String,
        origin: Transform,
        parent: String,
        child: String,
    ) -> JointSpec {
        JointSpec {
            name,
            kind: JointKind::Fixed,
            origin,
            parent,
            child,
            axis: Vector3::z(),
            range: Range::default(),
            mimic: None,
            dynamics: None,
        }
    }
}

/// Why a model cannot be written as URDF: the message of
/// [`ModelError::Urdf`](crate::error::ModelError::Urdf).
#[derive(Debug, thiserror::Error)]
pub(super) enum GenerateError {
    /// Two frames (or a frame and a link the generator adds) give one link name.
    #[error("two links would be named `{0}`")]
    DuplicateLink(String),
    /// Two joints the generator writes get one name.
    #[error("two joints would be named `{0}`")]
    DuplicateJoint(String),
    /// urdf-rs cannot write the document.
    #[error(transparent)]
    Write(#[from] urdf_rs::UrdfError),
}

/// The URDF being generated, with unique names.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) links: Vec<urdf_rs::Link>,
    pub(super) joints: Vec<urdf_rs::Joint>,
    pub(super) link_names: HashSet<String>,
    pub(super) joint_names: HashSet<String>,
}

impl Builder {
    pub(super) fn link(
        &mut self,
        name: &str,
        inertial: Option<&StandardInertia>,
    ) -> Result<(), GenerateError> {
        if !self.link_names.insert(name.to_string()) {
            return Err(GenerateError::DuplicateLink(name.to_string()));
        }
        self.links.push(urdf_rs::Link {
            name: name.to_string(),
            inertial: urdf_inertial(inertial),
            visual: Vec::new(),
            collision: Vec::new(),
        });
        Ok(())
    }

    pub(super) fn joint(&mut self, j: JointSpec) -> Result<(), GenerateError> {
        if !self.joint_names.insert(j.name.clone()) {
            return Err(GenerateError::DuplicateJoint(j.name));
        }
        let joint_type = match j.kind {
            JointKind::Fixed => urdf_rs::JointType::Fixed,
            JointKind::Prismatic => urdf_rs::JointType::Prismatic,
            JointKind::Revolute if j.range.position.is_some() => urdf_rs::JointType::Revolute,
            JointKind::Revolute => urdf_rs::JointType::Continuous,
        };
        self.joints.push(urdf_rs::Joint {
            name: j.name,
            joint_type,
            origin: pose(&j.origin),
            parent: urdf_rs::LinkName { link: j.parent },
            child: urdf_rs::LinkName { link: j.child },
            axis: urdf_rs::Axis {
                xyz: urdf_rs::Vec3(j.axis.map(|x| x + 0.0).into()),
            },
            limit: j.range.limit(),
            calibration: None,
            dynamics: j.dynamics,
            mimic: j.mimic.map(|(joint, multiplier, offset)| urdf_rs::Mimic {
                joint,
                multiplier: Some(multiplier),
                offset: (offset != 0.0).then_some(offset),
            }),
            safety_controller: None,
        });
        Ok(())
    }
}
