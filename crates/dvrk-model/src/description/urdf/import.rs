//! URDF import with `urdf-rs`: joints become frames, non-mimic moving joints become
//! coordinates, mimic joints become couplings (`s = multiplier·q + offset`), child-link
//! `<inertial>` elements become nominal parameters in the joint (child link) frame.
//!
//! Every joint, fixed ones included, is one frame named after its child link and carries
//! that link's 10 barycentric parameters, so a fixed child is not merged into its moving
//! parent (as Pinocchio does): its columns are the parent's through a constant change of
//! frame, and the base-parameter reduction removes the redundancy. The root link's
//! inertial never moves and is ignored. `<limit>` elements become [`Limit`]s on the
//! joint value (`lower`/`upper` unless continuous, `velocity`, and URDF 1.2
//! `acceleration`); `<dynamics>` (damping, friction) is ignored. Gravity is −9.81 m/s²
//! along the root link's z axis.

use std::collections::HashMap;

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

use crate::error::ModelError;
use crate::expr::Affine;
use crate::input::{self, InputError};
use crate::model::*;

use crate::inertia::rotation_rpy as rpy;

/// What is wrong with a URDF document: the message of [`ModelError::Urdf`].
#[derive(Debug, thiserror::Error)]
enum ImportError {
    #[error("element <{element}> is in a namespace with no bound prefix: URDF uses no namespaces")]
    UnboundElement { element: String },
    #[error(
        "attribute `{attribute}` of <{element}> has a namespace prefix that is not bound: URDF \
         uses no namespaces"
    )]
    UnboundAttribute { attribute: String, element: String },
    #[error("cannot parse the document (malformed XML or a missing element): {0}")]
    Parse(#[source] urdf_rs::UrdfError),
    #[error("{count} joints; at most {} are accepted", input::MAX_FRAMES)]
    TooManyJoints { count: usize },
    #[error(
        "{count} moving joints; at most {} are accepted",
        input::MAX_COORDINATES
    )]
    TooManyCoordinates { count: usize },
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("link `{0}` is defined twice")]
    DuplicateLink(String),
    #[error("joint `{0}` is defined twice")]
    DuplicateJoint(String),
    #[error("expected one root link, found {}: {roots:?}", .roots.len())]
    RootCount { roots: Vec<String> },
    #[error(
        "link `{link}` has two parents (joint `{joint}` closes a loop or duplicates another \
         joint)"
    )]
    TwoParents { link: String, joint: String },
    /// Joints not below the root, each with its parent link.
    #[error("joints not connected to the root link `{root}`: {}", joint_list(.lost))]
    Disconnected {
        root: String,
        lost: Vec<(String, String)>,
    },
    #[error(
        "joint `{joint}`: type `{kind}` is not supported (revolute, continuous, prismatic, \
         fixed)"
    )]
    UnsupportedType { joint: String, kind: String },
    #[error(
        "joint `{joint}`: origin xyz {xyz:?} m, rpy {rpy:?} rad: must be finite, within ±{:e} m \
         and ±{:e} rad",
        input::MAX_LENGTH_M,
        input::MAX_ANGLE_RAD
    )]
    Origin {
        joint: String,
        xyz: [f64; 3],
        rpy: [f64; 3],
    },
    #[error("joint `{joint}`: axis {axis:?} is zero or not finite")]
    Axis { joint: String, axis: [f64; 3] },
    /// A mimic of a joint that is not a coordinate's, and why.
    #[error("joint `{joint}` mimics `{mimicked}`: {why}")]
    Mimic {
        joint: String,
        mimicked: String,
        why: &'static str,
    },
    #[error(
        "joint `{joint}`: mimic multiplier {multiplier} and offset {offset} must be finite and \
         within ±{:e}",
        input::MAX_ANGLE_RAD
    )]
    MimicRange {
        joint: String,
        multiplier: f64,
        offset: f64,
    },
    #[error("joint `{0}`: <limit> has a NaN value")]
    NanLimit(String),
    #[error("joint `{joint}`: child link `{link}` is not defined")]
    MissingChild { joint: String, link: String },
    #[error("link `{link}`: <collision> geometry: {problem}")]
    Collision { link: String, problem: InputError },
    #[error(
        "link `{link}`: inertial values must be finite (origin within ±{:e} m, ±{:e} rad)",
        input::MAX_LENGTH_M,
        input::MAX_ANGLE_RAD
    )]
    InertialNotFinite { link: String },
    #[error("link `{link}`: <inertial>: {problem}")]
    Inertial { link: String, problem: InputError },
    #[error("no moving joint")]
    NoMovingJoint,
}

/// `` `joint` (parent link `link`) ``, comma-separated.
fn joint_list(lost: &[(String, String)]) -> String {
    lost.iter()
        .map(|(joint, parent)| format!("`{joint}` (parent link `{parent}`)"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Rotation taking z onto `axis` (unit), the shortest one (π about x for axis = −z).
fn align_z(axis: &Vector3<f64>) -> Matrix3<f64> {
    let z = Vector3::z();
    match Rotation3::rotation_between(&z, axis) {
        Some(r) => *r.matrix(),
        None => {
            *Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::x()), std::f64::consts::PI)
                .matrix()
        }
    }
}

/// Refuses, before urdf-rs sees the document, the namespace uses that urdf-rs 0.10 cannot
/// survive: it parses the text with RustyXML 0.3 and writes it back through RustyXML's
/// `Display`, which panics on an element or attribute whose namespace has no bound prefix
/// (found by fuzzing: `<parent :ink="a"/>` and the malformed `<parent :ink9"a"/>` under a
/// default `xmlns`; reproducers `fuzz/seeds/urdf/crash-unbound-*.urdf`). The walk is the
/// one RustyXML's writer makes, on the tree RustyXML's own parser builds, so whatever
/// that parser accepts is checked; URDF uses no namespaces, so nothing valid is refused.
/// A document RustyXML cannot parse is left to urdf-rs's own error.
fn check_namespaces(text: &str) -> Result<(), ImportError> {
    let Ok(root) = text.parse::<xml::Element>() else {
        return Ok(());
    };
    // RustyXML's builder binds these two before any declaration.
    let prefixes: HashMap<&str, &str> = [(XML_NS, "xml"), (XMLNS_NS, "xmlns")].into();
    check_element_namespaces(&root, &prefixes, None)
}

const XML_NS: &str = "http://www.w3.org/XML/1998/namespace";
const XMLNS_NS: &str = "http://www.w3.org/2000/xmlns/";

/// One element of [`check_namespaces`]: `prefixes` maps each namespace bound so far to its
/// prefix, `default` is the default namespace in scope.
fn check_element_namespaces<'a>(
    e: &'a xml::Element,
    prefixes: &HashMap<&'a str, &'a str>,
    default: Option<&'a str>,
) -> Result<(), ImportError> {
    let mut prefixes = prefixes.clone();
    let mut default = default;
    for ((name, ns), value) in &e.attributes {
        match ns.as_deref() {
            None if name == "xmlns" => default = Some(value.as_str()).filter(|v| !v.is_empty()),
            Some(XMLNS_NS) => {
                prefixes.insert(value.as_str(), name.as_str());
            }
            _ => {}
        }
    }
    if e.ns.as_deref() != default && !prefixes.contains_key(e.ns.as_deref().unwrap_or("")) {
        return Err(ImportError::UnboundElement {
            element: e.name.clone(),
        });
    }
    for (name, ns) in e.attributes.keys() {
        if let Some(ns) = ns.as_deref() {
            if !prefixes.contains_key(ns) {
                return Err(ImportError::UnboundAttribute {
                    attribute: name.clone(),
                    element: e.name.clone(),
                });
            }
        }
    }
    for child in &e.children {
        if let xml::Xml::ElementNode(child) = child {
            check_element_namespaces(child, &prefixes, default)?;
        }
    }
    Ok(())
}

impl Model {
    /// Imports a URDF document; `file` names it in error messages.
    pub fn from_urdf_str(text: &str, file: &str) -> Result<Model, ModelError> {
        let err = |e: ImportError| ModelError::Urdf {
            file: file.to_string(),
            message: e.to_string(),
        };
        check_namespaces(text).map_err(err)?;
        let robot = urdf_rs::read_from_string(text).map_err(|e| err(ImportError::Parse(e)))?;
        check_sizes_and_names(&robot).map_err(err)?;
        let tree = Tree::of(&robot).map_err(err)?;
        let (coordinates, coordinate_is_length) = coordinates(&robot, &tree.order).map_err(err)?;
        let mut frames = Vec::new();
        let mut params = Vec::new();
        let mut limits = Vec::new();
        let mut ranges = vec![None; coordinates.len()];
        for (fi, &ji) in tree.order.iter().enumerate() {
            let j = &robot.joints[ji];
            let (kind, pre, post) = joint_pose(j).map_err(err)?;
            let value = joint_value(&robot, j, kind, &coordinates).map_err(err)?;
            if kind != JointKind::Fixed {
                let limit = joint_limit(j, &value).map_err(err)?;
                // A coordinate's own joint (not a mimic) gives its measured range.
                if let (Some(l), &[(k, c)]) = (&limit, value.terms.as_slice()) {
                    if c == 1.0 && value.offset == 0.0 {
                        ranges[k] = l.position;
                    }
                }
                limits.extend(limit);
            }
            let link = child_link(&robot, j).map_err(err)?;
            let nominal = link_nominal(link).map_err(err)?;
            let p0 = params.len();
            params.extend(Param::inertia_block(fi + 1));
            frames.push(Frame {
                name: link.name.clone(),
                parent: tree.link_frame[&j.parent.link],
                kind,
                value,
                pre,
                post,
                inertia: Some(p0),
                elements: Vec::new(),
                nominal,
                bounds: FrameBounds {
                    ellipsoid: collision_ellipsoid(link).map_err(err)?,
                    ..FrameBounds::default()
                },
            });
        }
        // After the frames, so that a broken mimic is reported as such.
        if coordinates.is_empty() {
            return Err(err(ImportError::NoMovingJoint));
        }
        let n = coordinates.len();
        Ok(Model {
            name: robot.name.clone(),
            source: file.to_string(),
            measured: Measured {
                joints: coordinates.clone(),
                coupling: nalgebra::DMatrix::identity(n, n),
                ranges,
            },
            coordinates,
            coordinate_is_length,
            frames,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            limits,
            params,
            ..Model::unassembled()
        }
        .finish())
    }
}

/// Within the size limits (joints, parameters), each link and joint defined once.
fn check_sizes_and_names(robot: &urdf_rs::Robot) -> Result<(), ImportError> {
    if robot.joints.len() > input::MAX_FRAMES {
        return Err(ImportError::TooManyJoints {
            count: robot.joints.len(),
        });
    }
    // Every joint's child link carries 10 parameters.
    input::check_parameter_count(10 * robot.joints.len())?;
    let mut seen = std::collections::HashSet::new();
    if let Some(l) = robot.links.iter().find(|l| !seen.insert(l.name.as_str())) {
        return Err(ImportError::DuplicateLink(l.name.clone()));
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(j) = robot.joints.iter().find(|j| !seen.insert(j.name.as_str())) {
        return Err(ImportError::DuplicateJoint(j.name.clone()));
    }
    Ok(())
}

/// The joints in breadth-first order from the root link, so parents precede children.
struct Tree {
    /// Joint indices, in frame order.
    order: Vec<usize>,
    /// Frame index of each link (the root link is the base, 0).
    link_frame: std::collections::HashMap<String, usize>,
}

impl Tree {
    /// The tree of `robot`: one root link, no link with two parents, every joint
    /// connected.
    fn of(robot: &urdf_rs::Robot) -> Result<Tree, ImportError> {
        let is_child = |l: &str| robot.joints.iter().any(|j| j.child.link == l);
        let roots: Vec<&str> = robot
            .links
            .iter()
            .map(|l| l.name.as_str())
            .filter(|l| !is_child(l))
            .collect();
        if roots.len() != 1 {
            return Err(ImportError::RootCount {
                roots: roots.iter().map(|r| r.to_string()).collect(),
            });
        }
        let mut order: Vec<usize> = Vec::new();
        let mut frontier = std::collections::VecDeque::from([roots[0].to_string()]);
        let mut link_frame: std::collections::HashMap<String, usize> =
            [(roots[0].to_string(), 0usize)].into_iter().collect();
        while let Some(link) = frontier.pop_front() {
            for (ji, j) in robot.joints.iter().enumerate() {
                if j.parent.link == link {
                    if link_frame.contains_key(&j.child.link) {
                        return Err(ImportError::TwoParents {
                            link: j.child.link.clone(),
                            joint: j.name.clone(),
                        });
                    }
                    order.push(ji);
                    link_frame.insert(j.child.link.clone(), order.len());
                    frontier.push_back(j.child.link.clone());
                }
            }
        }
        if order.len() != robot.joints.len() {
            let lost = robot
                .joints
                .iter()
                .enumerate()
                .filter(|(ji, _)| !order.contains(ji))
                .map(|(_, j)| (j.name.clone(), j.parent.link.clone()))
                .collect();
            return Err(ImportError::Disconnected {
                root: roots[0].to_string(),
                lost,
            });
        }
        Ok(Tree { order, link_frame })
    }
}

/// The coordinates (moving joints without mimic, in tree order) and whether each is a
/// length; unsupported joint types are refused.
fn coordinates(
    robot: &urdf_rs::Robot,
    order: &[usize],
) -> Result<(Vec<String>, Vec<bool>), ImportError> {
    let mut coordinates = Vec::new();
    let mut coordinate_is_length = Vec::new();
    for &ji in order {
        let j = &robot.joints[ji];
        match j.joint_type {
            urdf_rs::JointType::Revolute
            | urdf_rs::JointType::Continuous
            | urdf_rs::JointType::Prismatic => {
                if j.mimic.is_none() {
                    coordinates.push(j.name.clone());
                    coordinate_is_length.push(j.joint_type == urdf_rs::JointType::Prismatic);
                }
            }
            urdf_rs::JointType::Fixed => {}
            ref other => {
                return Err(ImportError::UnsupportedType {
                    joint: j.name.clone(),
                    kind: format!("{other:?}").to_lowercase(),
                });
            }
        }
    }
    if coordinates.len() > input::MAX_COORDINATES {
        return Err(ImportError::TooManyCoordinates {
            count: coordinates.len(),
        });
    }
    Ok((coordinates, coordinate_is_length))
}

/// All of `v` finite and within ±`max`.
fn finite(v: &[f64; 3], max: f64) -> bool {
    v.iter().all(|x| x.is_finite() && x.abs() <= max)
}

/// The joint's kind and its `pre`/`post` transforms: the origin, then z turned onto the
/// joint's axis (and back after the motion).
fn joint_pose(j: &urdf_rs::Joint) -> Result<(JointKind, Transform, Transform), ImportError> {
    if !finite(&j.origin.xyz.0, input::MAX_LENGTH_M)
        || !finite(&j.origin.rpy.0, input::MAX_ANGLE_RAD)
    {
        return Err(ImportError::Origin {
            joint: j.name.clone(),
            xyz: j.origin.xyz.0,
            rpy: j.origin.rpy.0,
        });
    }
    let origin = Transform {
        rotation: rpy(&j.origin.rpy.0),
        translation: Vector3::from(j.origin.xyz.0),
    };
    let kind = match j.joint_type {
        urdf_rs::JointType::Prismatic => JointKind::Prismatic,
        urdf_rs::JointType::Fixed => JointKind::Fixed,
        _ => JointKind::Revolute,
    };
    if kind == JointKind::Fixed {
        return Ok((kind, origin, Transform::identity()));
    }
    let axis = Vector3::from(j.axis.xyz.0);
    if !axis.iter().all(|x| x.is_finite()) || axis.norm() < 1e-12 {
        return Err(ImportError::Axis {
            joint: j.name.clone(),
            axis: j.axis.xyz.0,
        });
    }
    let r = align_z(&axis.normalize());
    let pre = origin.compose(&Transform {
        rotation: r,
        translation: Vector3::zeros(),
    });
    let post = Transform {
        rotation: r.transpose(),
        translation: Vector3::zeros(),
    };
    Ok((kind, pre, post))
}

/// The joint value: its own coordinate, a mimic's `multiplier·q + offset`, or a constant
/// for a fixed joint.
fn joint_value(
    robot: &urdf_rs::Robot,
    j: &urdf_rs::Joint,
    kind: JointKind,
    coordinates: &[String],
) -> Result<Affine, ImportError> {
    let coord_of = |name: &str| coordinates.iter().position(|c| c == name);
    if kind == JointKind::Fixed {
        return Ok(Affine::constant(0.0));
    }
    let Some(m) = &j.mimic else {
        return Ok(Affine {
            terms: vec![(coord_of(&j.name).expect("coordinate"), 1.0)],
            offset: 0.0,
        });
    };
    let k = coord_of(&m.joint).ok_or_else(|| {
        let why = match robot.joints.iter().find(|o| o.name == m.joint) {
            None => "no joint has that name",
            Some(o) if o.mimic.is_some() => "it is itself a mimic joint",
            Some(_) => "it is not a moving joint",
        };
        ImportError::Mimic {
            joint: j.name.clone(),
            mimicked: m.joint.clone(),
            why,
        }
    })?;
    let multiplier = m.multiplier.unwrap_or(1.0);
    let offset = m.offset.unwrap_or(0.0);
    let max = input::MAX_ANGLE_RAD;
    if !(multiplier.is_finite()
        && offset.is_finite()
        && multiplier.abs() <= max
        && offset.abs() <= max)
    {
        return Err(ImportError::MimicRange {
            joint: j.name.clone(),
            multiplier,
            offset,
        });
    }
    Ok(Affine {
        terms: vec![(k, multiplier)],
        offset,
    })
}

/// The `<limit>` of a moving joint on its value `value` (for a mimic joint,
/// multiplier·q + offset), if it limits anything.
fn joint_limit(j: &urdf_rs::Joint, value: &Affine) -> Result<Option<Limit>, ImportError> {
    let lim = &j.limit;
    if [
        lim.lower,
        lim.upper,
        lim.velocity,
        lim.acceleration,
        lim.effort,
    ]
    .iter()
    .any(|v| v.is_nan())
    {
        return Err(ImportError::NanLimit(j.name.clone()));
    }
    let position = (j.joint_type != urdf_rs::JointType::Continuous
        && lim.lower.is_finite()
        && lim.upper.is_finite()
        && lim.lower < lim.upper)
        .then_some([lim.lower, lim.upper]);
    let symmetric = |v: f64| (v.is_finite() && v > 0.0).then_some([-v, v]);
    let velocity = symmetric(lim.velocity);
    let acceleration = symmetric(lim.acceleration);
    if position.is_none() && velocity.is_none() && acceleration.is_none() {
        return Ok(None);
    }
    Ok(Some(Limit {
        label: j.name.clone(),
        expr: value.clone(),
        position,
        velocity,
        acceleration,
    }))
}

/// The joint's child link, which must be defined.
fn child_link<'a>(
    robot: &'a urdf_rs::Robot,
    j: &urdf_rs::Joint,
) -> Result<&'a urdf_rs::Link, ImportError> {
    robot
        .links
        .iter()
        .find(|l| l.name == j.child.link)
        .ok_or_else(|| ImportError::MissingChild {
            joint: j.name.clone(),
            link: j.child.link.clone(),
        })
}

/// The link's bounding ellipsoid in the link frame from its `<collision>` geometry, for
/// the fit's density-realizability constraint ([`crate::inertia::Ellipsoid`]): one box,
/// cylinder, capsule (as its enclosing cylinder) or sphere gives the least-volume
/// ellipsoid enclosing it; several give the one enclosing the axis-aligned box around
/// their ellipsoids. `None` without collision geometry or with a mesh (its vertices are
/// in another file, which the import does not read): that link is only kept physically
/// consistent.
fn collision_ellipsoid(
    link: &urdf_rs::Link,
) -> Result<Option<crate::inertia::Ellipsoid>, ImportError> {
    use crate::inertia::Ellipsoid;
    use urdf_rs::Geometry;
    let invalid = |problem| ImportError::Collision {
        link: link.name.clone(),
        problem,
    };
    let mut parts = Vec::new();
    for c in &link.collision {
        let (center, rpy) = (c.origin.xyz.0, c.origin.rpy.0);
        let e = match &c.geometry {
            Geometry::Box { size } => Ellipsoid::around_box(center, size.0.map(|s| 0.5 * s), rpy),
            Geometry::Cylinder { radius, length } => {
                Ellipsoid::around_cylinder(center, *radius, *length, rpy)
            }
            Geometry::Capsule { radius, length } => {
                Ellipsoid::around_cylinder(center, *radius, length + 2.0 * radius, rpy)
            }
            Geometry::Sphere { radius } => Ellipsoid {
                center,
                semi_axes: [*radius; 3],
                rpy,
            },
            Geometry::Mesh { .. } => return Ok(None),
        };
        e.check().map_err(invalid)?;
        parts.push(e);
    }
    Ok(match parts.len() {
        0 => None,
        1 => parts.pop(),
        _ => {
            // Half widths of an ellipsoid along the frame axes: sqrt of diag(A⁻¹).
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for e in &parts {
                let r = rpy(&e.rpy);
                let a2 = Matrix3::from_diagonal(&Vector3::from(e.semi_axes.map(|a| a * a)));
                let cov = r * a2 * r.transpose();
                for k in 0..3 {
                    let w = cov[(k, k)].sqrt();
                    lo[k] = lo[k].min(e.center[k] - w);
                    hi[k] = hi[k].max(e.center[k] + w);
                }
            }
            let e = Ellipsoid::around_box(
                std::array::from_fn(|k| 0.5 * (lo[k] + hi[k])),
                std::array::from_fn(|k| 0.5 * (hi[k] - lo[k])),
                [0.0; 3],
            );
            e.check().map_err(invalid)?;
            Some(e)
        }
    })
}

/// The link's `<inertial>` as nominal values in the link frame: a rigid body of finite
/// numbers, its inertia about the centre of mass rotated from the inertial frame.
fn link_nominal(link: &urdf_rs::Link) -> Result<Nominal, ImportError> {
    let inertial = &link.inertial;
    let i = &inertial.inertia;
    let values = [
        inertial.mass.value,
        i.ixx,
        i.ixy,
        i.ixz,
        i.iyy,
        i.iyz,
        i.izz,
    ];
    if !values.iter().all(|x| x.is_finite())
        || !finite(&inertial.origin.xyz.0, input::MAX_LENGTH_M)
        || !finite(&inertial.origin.rpy.0, input::MAX_ANGLE_RAD)
    {
        return Err(ImportError::InertialNotFinite {
            link: link.name.clone(),
        });
    }
    // Inertia about the centre of mass, rotated from the inertial frame to the link frame.
    let ri = rpy(&inertial.origin.rpy.0);
    let ic =
        ri * Matrix3::new(
            i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
        ) * ri.transpose();
    crate::inertia::check_rigid_body(
        inertial.mass.value,
        inertial.origin.xyz.0,
        [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz],
    )
    .map_err(|problem| ImportError::Inertial {
        link: link.name.clone(),
        problem,
    })?;
    Ok(Nominal {
        mass: Some(inertial.mass.value),
        com: Some(inertial.origin.xyz.0),
        inertia: Some(crate::inertia::sym6(&ic)),
        ..Default::default()
    })
}
