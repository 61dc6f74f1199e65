//! URDF import with `urdf-rs`: joints become frames, non-mimic moving joints become
//! coordinates, mimic joints become couplings (`s = multiplier·q + offset`), child-link
//! `<inertial>` elements become nominal parameters in the joint (child link) frame.

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

use crate::error::ModelError;
use crate::expr::Affine;
use crate::model::*;

fn rpy(r: &[f64; 3]) -> Matrix3<f64> {
    *Rotation3::from_euler_angles(r[0], r[1], r[2]).matrix()
}

/// Rotation taking z onto `axis` (unit), the shortest one (π about x for axis = −z).
fn align_z(axis: &Vector3<f64>) -> Matrix3<f64> {
    let z = Vector3::z();
    match Rotation3::rotation_between(&z, axis) {
        Some(r) => *r.matrix(),
        None => *Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::x()), std::f64::consts::PI)
            .matrix(),
    }
}

impl Model {
    /// Imports a URDF document; `file` names it in error messages.
    pub fn from_urdf_str(text: &str, file: &str) -> Result<Model, ModelError> {
        let err = |message: String| ModelError::Urdf {
            file: file.to_string(),
            message,
        };
        let robot = urdf_rs::read_from_string(text).map_err(|e| err(e.to_string()))?;
        let is_child = |l: &str| robot.joints.iter().any(|j| j.child.link == l);
        let roots: Vec<&str> = robot
            .links
            .iter()
            .map(|l| l.name.as_str())
            .filter(|l| !is_child(l))
            .collect();
        if roots.len() != 1 {
            return Err(err(format!(
                "expected one root link, found {}: {:?}",
                roots.len(),
                roots
            )));
        }
        // Breadth-first order from the root so parents precede children.
        let mut order: Vec<usize> = Vec::new();
        let mut frontier = vec![roots[0].to_string()];
        let mut link_frame: std::collections::HashMap<String, usize> =
            [(roots[0].to_string(), 0usize)].into_iter().collect();
        while let Some(link) = frontier.first().cloned() {
            frontier.remove(0);
            for (ji, j) in robot.joints.iter().enumerate() {
                if j.parent.link == link {
                    if link_frame.contains_key(&j.child.link) {
                        return Err(err(format!("link `{}` has two parents", j.child.link)));
                    }
                    order.push(ji);
                    link_frame.insert(j.child.link.clone(), order.len());
                    frontier.push(j.child.link.clone());
                }
            }
        }
        if order.len() != robot.joints.len() {
            return Err(err("some joints are not connected to the root link".into()));
        }
        // Coordinates: moving joints without mimic, in tree order.
        let mut coordinates = Vec::new();
        for &ji in &order {
            let j = &robot.joints[ji];
            match j.joint_type {
                urdf_rs::JointType::Revolute
                | urdf_rs::JointType::Continuous
                | urdf_rs::JointType::Prismatic => {
                    if j.mimic.is_none() {
                        coordinates.push(j.name.clone());
                    }
                }
                urdf_rs::JointType::Fixed => {}
                ref other => {
                    return Err(err(format!(
                        "joint `{}`: type {other:?} is not supported (revolute, continuous, prismatic, fixed)",
                        j.name
                    )))
                }
            }
        }
        if coordinates.is_empty() {
            return Err(err("no moving joint".into()));
        }
        let coord_of = |name: &str| coordinates.iter().position(|c| c == name);
        let mut frames = Vec::new();
        let mut params = Vec::new();
        let mut limits = Vec::new();
        for (fi, &ji) in order.iter().enumerate() {
            let idx = fi + 1;
            let j = &robot.joints[ji];
            let origin = Transform {
                rotation: rpy(&j.origin.rpy.0),
                translation: Vector3::from(j.origin.xyz.0),
            };
            let kind = match j.joint_type {
                urdf_rs::JointType::Prismatic => JointKind::Prismatic,
                urdf_rs::JointType::Fixed => JointKind::Fixed,
                _ => JointKind::Revolute,
            };
            let (pre, post) = if kind == JointKind::Fixed {
                (origin, Transform::identity())
            } else {
                let axis = Vector3::from(j.axis.xyz.0);
                if axis.norm() < 1e-12 {
                    return Err(err(format!("joint `{}`: zero axis", j.name)));
                }
                let r = align_z(&axis.normalize());
                (
                    origin.compose(&Transform {
                        rotation: r,
                        translation: Vector3::zeros(),
                    }),
                    Transform {
                        rotation: r.transpose(),
                        translation: Vector3::zeros(),
                    },
                )
            };
            let value = if kind == JointKind::Fixed {
                Affine::constant(0.0)
            } else if let Some(m) = &j.mimic {
                let k = coord_of(&m.joint).ok_or_else(|| {
                    err(format!(
                        "joint `{}` mimics `{}`, which is not a moving non-mimic joint",
                        j.name, m.joint
                    ))
                })?;
                Affine {
                    terms: vec![(k, m.multiplier.unwrap_or(1.0))],
                    offset: m.offset.unwrap_or(0.0),
                }
            } else {
                let k = coord_of(&j.name).expect("coordinate");
                let lim = &j.limit;
                let position = (j.joint_type != urdf_rs::JointType::Continuous
                    && lim.lower.is_finite()
                    && lim.upper.is_finite()
                    && lim.lower < lim.upper)
                    .then_some([lim.lower, lim.upper]);
                let velocity = (lim.velocity.is_finite() && lim.velocity > 0.0)
                    .then_some([-lim.velocity, lim.velocity]);
                if position.is_some() || velocity.is_some() {
                    limits.push(Limit {
                        label: j.name.clone(),
                        expr: Affine {
                            terms: vec![(k, 1.0)],
                            offset: 0.0,
                        },
                        position,
                        velocity,
                        acceleration: None,
                    });
                }
                Affine {
                    terms: vec![(k, 1.0)],
                    offset: 0.0,
                }
            };
            let link = robot
                .links
                .iter()
                .find(|l| l.name == j.child.link)
                .ok_or_else(|| err(format!("joint `{}`: child link `{}` is not defined", j.name, j.child.link)))?;
            let inertial = &link.inertial;
            // Inertia about the centre of mass, rotated from the inertial frame to the link frame.
            let ri = rpy(&inertial.origin.rpy.0);
            let i = &inertial.inertia;
            let ic = ri
                * Matrix3::new(i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz)
                * ri.transpose();
            let nominal = Nominal {
                mass: Some(inertial.mass.value),
                com: Some(inertial.origin.xyz.0),
                inertia: Some([
                    ic[(0, 0)],
                    ic[(0, 1)],
                    ic[(0, 2)],
                    ic[(1, 1)],
                    ic[(1, 2)],
                    ic[(2, 2)],
                ]),
                ..Default::default()
            };
            let p0 = params.len();
            for (k, suffix) in INERTIA_SUFFIXES.iter().enumerate() {
                let name = match k {
                    0..=5 => format!("L{idx}{suffix}"),
                    6..=8 => format!("l{idx}{suffix}"),
                    _ => format!("m{idx}"),
                };
                params.push(Param {
                    name,
                    kind: ParamKind::Inertia { index: k },
                    frame: idx,
                });
            }
            frames.push(Frame {
                name: link.name.clone(),
                parent: link_frame[&j.parent.link],
                kind,
                value,
                pre,
                post,
                inertia: Some(p0),
                friction: None,
                motor_inertia: None,
                spring: None,
                known_force: None,
                nominal,
                bounds: FrameBounds::default(),
            });
        }
        let n = coordinates.len();
        let coordinate_is_length = (0..n)
            .map(|k| {
                frames.iter().any(|f: &Frame| {
                    f.kind == JointKind::Prismatic && f.value.terms.iter().any(|t| t.0 == k)
                })
            })
            .collect();
        Ok(Model {
            name: robot.name.clone(),
            source: file.to_string(),
            measured: Measured {
                joints: coordinates.clone(),
                coupling: nalgebra::DMatrix::identity(n, n),
            },
            coordinates,
            coordinate_is_length,
            frames,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            limits,
            bounds: GlobalBounds::default(),
            params,
            links: Vec::new(),
            subtree_links: Vec::new(),
            active: Vec::new(),
            motion: Vec::new(),
            fixed: Vec::new(),
        }
        .finish())
    }
}
