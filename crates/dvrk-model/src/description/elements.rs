//! A frame's element fields in a description file (`robots/README.md`): `friction`,
//! `stribeck_velocity`, `motor_inertia`, `spring`, `known_force`, `quadratic_viscous`,
//! `monotone_friction`, `dahl`, `position_torque`, `load_friction`.
//! Their expressions and constants are resolved here, then each element is built by the
//! numeric constructor's [`ElementSpec`], so a description and a model built from numbers
//! are checked by the same code and their errors read the same.

use serde::Deserialize;

use super::resolve::Ctx;
use crate::element::{Deflection, ElementSpec, FrameContext, FrameElements, Stribeck};
use crate::error::ModelError;
use crate::expr::{ExprError, NumOrExpr};
use crate::input;
use crate::param::Param;

/// A frame's element fields, read by serde into the frame's table.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ElementsDesc {
    #[serde(default)]
    friction: bool,
    /// Stribeck velocity (rad/s or m/s) of a Stribeck term on this frame's friction.
    stribeck_velocity: Option<NumOrExpr>,
    #[serde(default)]
    motor_inertia: bool,
    spring: Option<String>,
    known_force: Option<KnownForceDesc>,
    quadratic_viscous: Option<QuadraticViscousDesc>,
    monotone_friction: Option<MonotoneFrictionDesc>,
    dahl: Option<DahlDesc>,
    position_torque: Option<PositionTorqueDesc>,
    #[serde(default)]
    load_friction: bool,
}

/// `position_torque = { order = 2, period = 6.283 }` (period in rad or m; optional on a
/// revolute frame).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PositionTorqueDesc {
    order: usize,
    period: Option<f64>,
}

/// `dahl = { sigma = 20 }` (1/rad or 1/m).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DahlDesc {
    sigma: f64,
}

/// `monotone_friction = { velocities = [v1, ...] }` (rad/s or m/s).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MonotoneFrictionDesc {
    velocities: Vec<f64>,
}

/// `known_force = { polynomial = [...], along = "..." }` (`along` defaults to the
/// frame's joint value).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KnownForceDesc {
    polynomial: Vec<f64>,
    along: Option<String>,
}

/// `quadratic_viscous = true | { nominal = x, max = y }` (N·m·s²/rad² or N·s²/m²).
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum QuadraticViscousDesc {
    On(bool),
    With(QuadraticViscousTable),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct QuadraticViscousTable {
    nominal: Option<f64>,
    max: Option<f64>,
}

impl ElementsDesc {
    /// Reads the elements, pushing their parameters onto `params`, in the order of the
    /// parameter vector: friction, motor inertia, spring, quadratic viscous friction,
    /// monotone friction, Dahl friction, position-dependent torque, load friction.
    pub(super) fn build(
        &self,
        ctx: &Ctx,
        fx: &FrameContext,
        params: &mut Vec<Param>,
    ) -> Result<FrameElements, ModelError> {
        let mut out = FrameElements::default();
        if self.friction {
            let spec = ElementSpec::Friction {
                stribeck_velocity: None,
            };
            spec.build(fx, params, &mut out)?;
        }
        if let Some(v) = &self.stribeck_velocity {
            out.stribeck_velocity = Some(stribeck_velocity(ctx, fx, self.friction, v)?);
        }
        if self.motor_inertia {
            ElementSpec::MotorInertia.build(fx, params, &mut out)?;
        }
        if let Some(text) = &self.spring {
            // Motion first: a spring on a fixed frame is the mistake, not its expression.
            fx.need_motion("spring")?;
            let deflection = Deflection::new(ctx.expr(fx.place, "spring", text)?, fx.n_coordinates);
            ElementSpec::Spring(deflection).build(fx, params, &mut out)?;
        }
        if let Some(kf) = &self.known_force {
            known_force(ctx, fx, kf)?.build(fx, params, &mut out)?;
        }
        let quadratic_viscous = match &self.quadratic_viscous {
            None | Some(QuadraticViscousDesc::On(false)) => None,
            Some(QuadraticViscousDesc::On(true)) => Some((None, None)),
            Some(QuadraticViscousDesc::With(t)) => Some((t.nominal, t.max)),
        };
        if let Some((nominal, max)) = quadratic_viscous {
            ElementSpec::QuadraticViscous { nominal, max }.build(fx, params, &mut out)?;
        }
        if let Some(m) = &self.monotone_friction {
            ElementSpec::MonotoneFriction {
                velocities: m.velocities.clone(),
            }
            .build(fx, params, &mut out)?;
        }
        if let Some(d) = &self.dahl {
            ElementSpec::Dahl { sigma: d.sigma }.build(fx, params, &mut out)?;
        }
        if let Some(t) = &self.position_torque {
            ElementSpec::PositionTorque {
                order: t.order,
                period: t.period,
            }
            .build(fx, params, &mut out)?;
        }
        if self.load_friction {
            ElementSpec::LoadFriction.build(fx, params, &mut out)?;
        }
        Ok(out)
    }
}

/// The `stribeck_velocity` of a description, positive and finite, on a frame with
/// friction.
fn stribeck_velocity(
    ctx: &Ctx,
    fx: &FrameContext,
    friction: bool,
    v: &NumOrExpr,
) -> Result<f64, ModelError> {
    if !friction {
        return Err(fx.error("stribeck_velocity", "needs `friction = true` on the frame"));
    }
    let v = ctx.number(
        fx.place,
        "stribeck_velocity",
        v,
        (input::MAX_VALUE, "rad/s or m/s"),
    )?;
    Stribeck::check_velocity(fx, v)
}

/// The known force of a `known_force` table, its `along` resolved.
fn known_force(
    ctx: &Ctx,
    fx: &FrameContext,
    kf: &KnownForceDesc,
) -> Result<ElementSpec, ModelError> {
    let along = match &kf.along {
        Some(text) => Some(
            ctx.expr(fx.place, "known_force.along", text)?
                .affine(fx.n_coordinates)
                .map_err(|e: ExprError| fx.error("known_force.along", e.to_string()))?,
        ),
        None => None,
    };
    Ok(ElementSpec::KnownForce {
        along,
        polynomial: kf.polynomial.clone(),
    })
}
