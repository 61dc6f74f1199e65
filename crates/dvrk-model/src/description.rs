//! The robot description file (TOML, documented in `robots/README.md`) and its
//! translation into a [`Model`]. Everything a user can get wrong is checked here, and
//! each error names the file, the frame and the field.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, Vector3};
use serde::Deserialize;

use crate::element::{ElementsDesc, FrameContext, FrameElements};
use crate::error::ModelError;
use crate::expr::{Affine, Expr, ExprError, NumOrExpr, Scope};
use crate::input;
use crate::limits::{CartesianLimitSpec, JointLimitSpec, LimitScope, Limits, LimitsSpec};
use crate::model::*;
use crate::resolve::Ctx;

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
/// How a DH frame's `a`, `alpha`, `d`, `theta` compose into the transform from the
/// parent frame (the description's `convention` field).
pub enum Convention {
    /// Craig: `RotX(alpha)·TransX(a)·RotZ(theta)·TransZ(d)`
    Modified,
    /// `RotZ(theta)·TransZ(d)·TransX(a)·RotX(alpha)`
    Standard,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDesc {
    name: String,
    convention: Convention,
    coordinates: Vec<String>,
    gravity: Option<[NumOrExpr; 3]>,
    #[serde(default)]
    constants: BTreeMap<String, NumOrExpr>,
    measured: Option<MeasuredDesc>,
    frames: Vec<FrameDesc>,
    #[serde(default)]
    limits: Vec<JointLimitSpec>,
    #[serde(default)]
    cartesian_limits: Vec<CartesianLimitSpec>,
    #[serde(default)]
    bounds: GlobalBounds,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeasuredDesc {
    joints: Vec<String>,
    coupling: Option<Vec<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameDesc {
    name: String,
    parent: String,
    #[serde(default)]
    a: NumOrExpr,
    #[serde(default)]
    alpha: NumOrExpr,
    #[serde(default)]
    d: NumOrExpr,
    #[serde(default)]
    theta: NumOrExpr,
    #[serde(default)]
    inertia: bool,
    /// Friction, springs... (see [`ElementsDesc`]).
    #[serde(flatten)]
    elements: ElementsDesc,
    nominal: Option<Nominal>,
    bounds: Option<FrameBounds>,
}

/// Resolves constants that may refer to each other, in dependency order.
fn resolve_constants(
    file: &str,
    raw: &BTreeMap<String, NumOrExpr>,
    coordinates: &[String],
) -> Result<Vec<(String, f64)>, ModelError> {
    let mut known: Vec<(String, f64)> = vec![
        ("pi".into(), std::f64::consts::PI),
        ("deg".into(), std::f64::consts::PI / 180.0),
    ];
    for name in raw.keys() {
        if name == "pi" || name == "deg" || coordinates.contains(name) {
            return Err(ModelError::field(
                file,
                "constants",
                name,
                "this name is reserved (pi, deg or a coordinate name)",
            ));
        }
    }
    let mut pending: Vec<(&String, &NumOrExpr)> = raw.iter().collect();
    while !pending.is_empty() {
        let before = pending.len();
        let mut last_err = None;
        pending.retain(|(name, val)| {
            let v = match val {
                NumOrExpr::Num(x) if !x.is_finite() => Err(ExprError::Eval(format!(
                    "value is {x}, not a finite number"
                ))),
                NumOrExpr::Num(x) => Ok(*x),
                NumOrExpr::Expr(s) => {
                    let scope = Scope {
                        constants: &known,
                        coordinates: &[],
                    };
                    Expr::parse(s, &scope).and_then(|e| e.constant_value(&[]))
                }
            };
            match v {
                Ok(x) => {
                    known.push(((*name).clone(), x));
                    false
                }
                Err(e) => {
                    last_err = Some(((*name).clone(), e));
                    true
                }
            }
        });
        if pending.len() == before {
            let (name, e) = last_err.expect("a constant failed");
            // Constants that only wait for each other form a cycle: say so rather than
            // "unknown name" of the first of them.
            let waiting: Vec<&str> = pending.iter().map(|(n, _)| n.as_str()).collect();
            if pending.iter().all(|(_, v)| match v {
                NumOrExpr::Expr(text) => waiting.iter().any(|w| mentions(text, w)),
                NumOrExpr::Num(_) => false,
            }) {
                return Err(ModelError::field(
                    file,
                    "constants",
                    &waiting.join(", "),
                    format!(
                        "these constants are defined in terms of each other (a cycle): {}",
                        pending
                            .iter()
                            .map(|(n, v)| match v {
                                NumOrExpr::Expr(t) => format!("{n} = \"{t}\""),
                                NumOrExpr::Num(x) => format!("{n} = {x}"),
                            })
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
            }
            return Err(ModelError::field(file, "constants", &name, e.to_string()));
        }
    }
    Ok(known)
}

/// Whether the expression `text` uses the name `name` (as a whole identifier).
fn mentions(text: &str, name: &str) -> bool {
    text.split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .any(|token| token == name)
}

/// A frame's nominal values: a rigid body where they give one (mass, centre of mass and
/// inertia), every other value finite and within range.
fn check_nominal(n: &Nominal) -> Result<(), String> {
    if let Some(m) = n.mass.filter(|&m| m < 0.0) {
        return Err(format!("mass {m} kg: must be non-negative"));
    }
    if let (Some(mass), Some(com), Some(inertia)) = (n.mass, n.com, n.inertia) {
        input::check_rigid_body(mass, com, inertia)?;
    }
    let scalars = [
        ("mass", n.mass),
        ("fc", n.fc),
        ("fv", n.fv),
        ("fo", n.fo),
        ("fs", n.fs),
        ("ia", n.ia),
        ("k", n.k),
    ];
    for (name, v) in scalars {
        if let Some(v) = v {
            input::check_magnitude(v, input::MAX_VALUE, "").map_err(|m| format!("{name}: {m}"))?;
        }
    }
    for (name, values) in [
        ("com", n.com.as_ref().map(|c| &c[..])),
        ("inertia", n.inertia.as_ref().map(|i| &i[..])),
    ] {
        for &v in values.unwrap_or(&[]) {
            input::check_magnitude(v, input::MAX_VALUE, "").map_err(|m| format!("{name}: {m}"))?;
        }
    }
    Ok(())
}

fn check_range(
    file: &str,
    place: &str,
    field: &str,
    r: Option<[f64; 2]>,
) -> Result<(), ModelError> {
    if let Some([lo, hi]) = r {
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(ModelError::field(
                file,
                place,
                field,
                format!("invalid range [{lo}, {hi}]"),
            ));
        }
    }
    Ok(())
}

impl Model {
    /// Builds a model from description text; `file` names it in error messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Model, ModelError> {
        let desc: FileDesc = toml::from_str(text).map_err(|e| ModelError::Syntax {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        build(desc, file)
    }
}

fn build(desc: FileDesc, file: &str) -> Result<Model, ModelError> {
    let n = desc.coordinates.len();
    if n > input::MAX_COORDINATES {
        return Err(ModelError::field(
            file,
            "top level",
            "coordinates",
            format!(
                "{n} coordinates; at most {} are accepted",
                input::MAX_COORDINATES
            ),
        ));
    }
    if desc.frames.len() > input::MAX_FRAMES {
        return Err(ModelError::field(
            file,
            "frames",
            "",
            format!(
                "{} frames; at most {} are accepted",
                desc.frames.len(),
                input::MAX_FRAMES
            ),
        ));
    }
    if n == 0 {
        return Err(ModelError::field(
            file,
            "top level",
            "coordinates",
            "no coordinate",
        ));
    }
    for (i, c) in desc.coordinates.iter().enumerate() {
        if desc.coordinates[..i].contains(c) {
            return Err(ModelError::field(
                file,
                "top level",
                "coordinates",
                format!("`{c}` appears twice"),
            ));
        }
    }
    let constants = resolve_constants(file, &desc.constants, &desc.coordinates)?;
    let ctx = Ctx {
        file,
        constants,
        coordinates: &desc.coordinates,
    };
    let gravity = match &desc.gravity {
        Some(g) => {
            let mut v = Vector3::zeros();
            for k in 0..3 {
                v[k] = ctx.number("top level", "gravity", &g[k], (input::MAX_GRAVITY, "m/s²"))?;
            }
            v
        }
        None => Vector3::new(0.0, 0.0, -9.81),
    };

    let mut names: Vec<String> = vec!["base".into()];
    let mut frames = Vec::with_capacity(desc.frames.len());
    let mut params: Vec<Param> = Vec::new();
    let mut stribeck: Vec<(usize, f64)> = Vec::new();
    for (i, fd) in desc.frames.iter().enumerate() {
        let idx = i + 1;
        let place = format!("frame {idx} ({})", fd.name);
        if names.contains(&fd.name) {
            return Err(ModelError::field(
                file,
                &place,
                "name",
                "duplicate frame name",
            ));
        }
        let parent = names.iter().position(|n| *n == fd.parent).ok_or_else(|| {
            ModelError::field(
                file,
                &place,
                "parent",
                format!("`{}` is not the base nor an earlier frame", fd.parent),
            )
        })?;
        let (length, angle) = ((input::MAX_LENGTH_M, "m"), (input::MAX_ANGLE_RAD, "rad"));
        let a = ctx.number(&place, "a", &fd.a, length)?;
        let alpha = ctx.number(&place, "alpha", &fd.alpha, angle)?;
        let theta = ctx.affine(&place, "theta", &fd.theta, angle)?;
        let d = ctx.affine(&place, "d", &fd.d, length)?;
        if !theta.is_constant() && !d.is_constant() {
            return Err(ModelError::field(
                file,
                &place,
                "theta/d",
                "only one of theta and d may depend on the coordinates",
            ));
        }
        let kind = if !theta.is_constant() {
            JointKind::Revolute
        } else if !d.is_constant() {
            JointKind::Prismatic
        } else {
            JointKind::Fixed
        };
        let (th0, d0) = (theta.offset, d.offset);
        let (pre, post, value) = match (desc.convention, kind) {
            (Convention::Modified, JointKind::Revolute) => (
                Transform::rot_x(alpha).compose(&Transform::trans(a, 0.0, 0.0)),
                Transform::trans(0.0, 0.0, d0),
                theta,
            ),
            (Convention::Modified, JointKind::Prismatic) => (
                Transform::rot_x(alpha)
                    .compose(&Transform::trans(a, 0.0, 0.0))
                    .compose(&Transform::rot_z(th0)),
                Transform::identity(),
                d,
            ),
            (Convention::Modified, JointKind::Fixed) => (
                Transform::rot_x(alpha)
                    .compose(&Transform::trans(a, 0.0, 0.0))
                    .compose(&Transform::rot_z(th0))
                    .compose(&Transform::trans(0.0, 0.0, d0)),
                Transform::identity(),
                Affine::constant(0.0),
            ),
            (Convention::Standard, JointKind::Revolute) => (
                Transform::identity(),
                Transform::trans(0.0, 0.0, d0)
                    .compose(&Transform::trans(a, 0.0, 0.0))
                    .compose(&Transform::rot_x(alpha)),
                theta,
            ),
            (Convention::Standard, JointKind::Prismatic) => (
                Transform::rot_z(th0),
                Transform::trans(a, 0.0, 0.0).compose(&Transform::rot_x(alpha)),
                d,
            ),
            (Convention::Standard, JointKind::Fixed) => (
                Transform::rot_z(th0)
                    .compose(&Transform::trans(0.0, 0.0, d0))
                    .compose(&Transform::trans(a, 0.0, 0.0))
                    .compose(&Transform::rot_x(alpha)),
                Transform::identity(),
                Affine::constant(0.0),
            ),
        };
        let moving = kind != JointKind::Fixed;

        let inertia = if fd.inertia {
            let p0 = params.len();
            params.extend(Param::inertia_block(idx));
            Some(p0)
        } else {
            None
        };
        let FrameElements {
            elements,
            stribeck_velocity,
        } = fd.elements.build(
            &FrameContext {
                ctx: &ctx,
                place: &place,
                index: idx,
                value: &value,
                moving,
            },
            &mut params,
        )?;
        if let Some(v) = stribeck_velocity {
            stribeck.push((idx, v));
        }
        let nominal = fd.nominal.clone().unwrap_or_default();
        check_nominal(&nominal).map_err(|m| ModelError::field(file, &place, "nominal", m))?;
        let bounds = fd.bounds.clone().unwrap_or_default();
        for (field, v) in [
            ("bounds.fc_max", bounds.fc_max),
            ("bounds.fv_max", bounds.fv_max),
            ("bounds.fo_max", bounds.fo_max),
            ("bounds.ia_max", bounds.ia_max),
        ] {
            if let Some(v) = v {
                input::check_magnitude(v, input::MAX_VALUE, "")
                    .map_err(|m| ModelError::field(file, &place, field, m))?;
            }
        }
        if (bounds.mass.is_some() || bounds.com.is_some()) && inertia.is_none() {
            return Err(ModelError::field(
                file,
                &place,
                "bounds",
                "mass/com bounds on a frame without link inertia",
            ));
        }
        check_range(file, &place, "bounds.mass", bounds.mass)?;
        check_range(file, &place, "bounds.spring", bounds.spring)?;
        if let Some(com) = bounds.com {
            for r in com {
                check_range(file, &place, "bounds.com", Some(r))?;
            }
        }
        frames.push(Frame {
            name: fd.name.clone(),
            parent,
            kind,
            value,
            pre,
            post,
            inertia,
            elements,
            nominal,
            bounds,
        });
        names.push(fd.name.clone());
    }
    if params.is_empty() {
        return Err(ModelError::field(
            file,
            "frames",
            "",
            "the model has no parameter",
        ));
    }
    input::check_parameter_count(params.len() + stribeck.len())
        .map_err(|m| ModelError::field(file, "frames", "", m))?;

    let measured = match &desc.measured {
        Some(m) => {
            if m.joints.len() != n {
                return Err(ModelError::field(
                    file,
                    "measured",
                    "joints",
                    format!("{} names for {n} coordinates", m.joints.len()),
                ));
            }
            let coupling = match &m.coupling {
                Some(rows) => {
                    if rows.len() != n || rows.iter().any(|r| r.len() != n) {
                        return Err(ModelError::field(
                            file,
                            "measured",
                            "coupling",
                            format!("must be {n} rows of {n} numbers"),
                        ));
                    }
                    for (r, row) in rows.iter().enumerate() {
                        for (c, &x) in row.iter().enumerate() {
                            input::check_magnitude(x, input::MAX_ANGLE_RAD, "").map_err(|m| {
                                ModelError::field(
                                    file,
                                    "measured",
                                    "coupling",
                                    format!("row {}, column {}: {m}", r + 1, c + 1),
                                )
                            })?;
                        }
                    }
                    DMatrix::from_fn(n, n, |r, c| rows[r][c])
                }
                None => DMatrix::identity(n, n),
            };
            if coupling.clone().try_inverse().is_none() {
                return Err(ModelError::field(
                    file,
                    "measured",
                    "coupling",
                    "the matrix is singular",
                ));
            }
            Measured {
                joints: m.joints.clone(),
                coupling,
            }
        }
        None => Measured {
            joints: desc.coordinates.clone(),
            coupling: DMatrix::identity(n, n),
        },
    };

    let spec = LimitsSpec {
        limits: desc.limits,
        cartesian_limits: desc.cartesian_limits,
    };
    let Limits {
        joint: limits,
        cartesian: cartesian_limits,
    } = spec.compile_in(&LimitScope {
        ctx: &ctx,
        measured: &measured,
        frame_names: &names,
    })?;

    let coordinate_is_length = (0..n)
        .map(|k| {
            frames
                .iter()
                .any(|f| f.kind == JointKind::Prismatic && f.value.terms.iter().any(|t| t.0 == k))
        })
        .collect();
    let mut model = Model {
        name: desc.name,
        source: file.to_string(),
        coordinates: desc.coordinates,
        coordinate_is_length,
        frames,
        gravity,
        measured,
        limits,
        cartesian_limits,
        bounds: desc.bounds,
        params,
        links: Vec::new(),
        active: Vec::new(),
        motion: Vec::new(),
        fixed: Vec::new(),
        post_identity: Vec::new(),
        bodies: Vec::new(),
        regressor_plan: Default::default(),
        element_plan: Default::default(),
    }
    .finish();
    // Stribeck parameters come after all the others, as `Model::with_stribeck` adds them.
    for (frame, v) in stribeck {
        model.add_stribeck(frame, v)?;
    }
    Ok(model)
}
