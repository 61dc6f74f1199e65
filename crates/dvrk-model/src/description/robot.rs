//! The robot description file (TOML, documented in `robots/README.md`) and its
//! translation into a [`Model`]. Everything a user can get wrong is checked here, and
//! each error names the file, the frame and the field.

use std::collections::BTreeMap;

use serde::Deserialize;

use super::elements::ElementsDesc;
use super::limits::{CartesianLimitSpec, JointLimitSpec, LimitScope, LimitsSpec};
use super::resolve::Ctx;
use crate::builder::{dh_geometry, Convention, FrameInput, Geometry, ModelBuilder};
use crate::element::FrameContext;
use crate::error::ModelError;
use crate::expr::{Expr, ExprError, NumOrExpr, Scope};
use crate::input;
use crate::model::*;

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
    #[serde(default)]
    preset: PresetDesc,
}

/// `[preset]`: what the identification preset adds to the model (see
/// [`PresetElements`]).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PresetDesc {
    /// `position_torque = { order = 1, frames = ["upper_arm", "forearm"] }`.
    position_torque: Option<PresetTorqueDesc>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PresetTorqueDesc {
    order: usize,
    frames: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeasuredDesc {
    joints: Vec<String>,
    coupling: Option<Vec<Vec<f64>>>,
    /// `[min, max]` per joint (rad or m).
    ranges: Option<Vec<[f64; 2]>>,
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

/// The model of a parsed description: its constants resolved, then its frames, measured
/// joints and limits built through [`ModelBuilder`] (whose checks name the file).
fn build(desc: FileDesc, file: &str) -> Result<Model, ModelError> {
    let mut b = ModelBuilder::start(
        desc.name.clone(),
        file,
        desc.coordinates.clone(),
        desc.frames.len(),
    )?;
    let constants = resolve_constants(file, &desc.constants, &desc.coordinates)?;
    let ctx = Ctx {
        file,
        constants,
        coordinates: &desc.coordinates,
    };
    if let Some(g) = &desc.gravity {
        let mut v = [0.0; 3];
        for k in 0..3 {
            v[k] = ctx.number("top level", "gravity", &g[k], (input::MAX_GRAVITY, "m/s²"))?;
        }
        b.set_gravity(v)?;
    }
    for fd in &desc.frames {
        add_frame(&mut b, &ctx, desc.convention, fd)?;
    }
    b.check_parameters()?;
    if let Some(m) = &desc.measured {
        b.set_measured(m.joints.clone(), m.coupling.clone(), m.ranges.clone())?;
    }
    let spec = LimitsSpec {
        limits: desc.limits,
        cartesian_limits: desc.cartesian_limits,
    };
    let limits = spec.compile_in(&LimitScope {
        ctx: &ctx,
        measured: &b.measured(),
        frame_names: b.frame_names(),
    })?;
    b.set_limits(limits)?;
    b.set_bounds(desc.bounds);
    let mut model = b.build()?;
    if let Some(t) = desc.preset.position_torque {
        // Checked as the preset will use it: the order and each frame.
        crate::element::PositionTorque::check_order(t.order)
            .map_err(|e| ModelError::field(file, "preset", "position_torque.order", e))?;
        model.check_position_torque_frames(&t.frames)?;
        model.preset.position_torque = Some((t.order, t.frames));
    }
    Ok(model)
}

/// One `[[frames]]` table: its DH numbers and elements resolved against the file's
/// constants and coordinates.
fn add_frame(
    b: &mut ModelBuilder,
    ctx: &Ctx,
    convention: Convention,
    fd: &FrameDesc,
) -> Result<usize, ModelError> {
    b.frame_with(FrameInput {
        name: &fd.name,
        parent: &fd.parent,
        geometry: |place: &str| dh_frame(ctx, convention, place, fd),
        link: fd.inertia,
        elements: |fx: &FrameContext, params: &mut Vec<Param>| fd.elements.build(ctx, fx, params),
        nominal: fd.nominal.clone().unwrap_or_default(),
        bounds: fd.bounds.clone().unwrap_or_default(),
    })
}

/// The frame's `a`, `alpha`, `theta`, `d` and what they make.
fn dh_frame(
    ctx: &Ctx,
    convention: Convention,
    place: &str,
    fd: &FrameDesc,
) -> Result<Geometry, ModelError> {
    let (length, angle) = ((input::MAX_LENGTH_M, "m"), (input::MAX_ANGLE_RAD, "rad"));
    let a = ctx.number(place, "a", &fd.a, length)?;
    let alpha = ctx.number(place, "alpha", &fd.alpha, angle)?;
    let theta = ctx.affine(place, "theta", &fd.theta, angle)?;
    let d = ctx.affine(place, "d", &fd.d, length)?;
    dh_geometry(convention, a, alpha, &theta, &d)
        .map_err(|m| ModelError::field(ctx.file, place, "theta/d", m))
}
