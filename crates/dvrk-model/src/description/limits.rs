//! The limits schema: joint limits (`[[limits]]`) and Cartesian boxes
//! (`[[cartesian_limits]]`), written the same way in a robot description, in a limits
//! file (`dvrk-ident excite --limits`) and as a Python dict. One set of serde types reads
//! all three, and one compiler turns them into [`Limits`], so a field checked in one
//! place is checked in all (ranges finite and ordered, magnitudes within
//! [`crate::input`]'s bounds, frames that exist).
//!
//! ```
//! use dvrk_model::{LimitsSpec, Model};
//! let psm = Model::builtin("psm").unwrap();
//! let spec = LimitsSpec::from_toml_str(
//!     "[[limits]]\nexpr = \"jaw\"\nposition = [0, \"60*deg\"]\n",
//!     "jaw.toml",
//! )
//! .unwrap();
//! let limits = spec.compile(&psm, "jaw.toml").unwrap();
//! // The jaw is measured: its limit is an affine function of the model coordinates.
//! assert_eq!(limits.joint[0].expr.terms, vec![(5, -1.2177), (6, 1.2177)]);
//! assert!((limits.joint[0].position.unwrap()[1] - 60f64.to_radians()).abs() < 1e-15);
//! // Written back, the same limits.
//! let again = LimitsSpec::of(&psm, &limits).compile(&psm, "again").unwrap();
//! assert_eq!(again.joint[0].expr, limits.joint[0].expr);
//! ```

use serde::{Deserialize, Serialize};

use super::resolve::Ctx;
use crate::error::ModelError;
use crate::expr::NumOrExpr;
use crate::input;
use crate::limits::Limits;
use crate::model::{CartesianLimit, Limit, Measured, Model};

/// Limits as written: joint limits and Cartesian boxes (the tables of a limits file).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LimitsSpec {
    #[serde(default)]
    /// The `[[limits]]` tables (joint limits).
    pub limits: Vec<JointLimitSpec>,
    #[serde(default)]
    /// The `[[cartesian_limits]]` tables (boxes on frame origins).
    pub cartesian_limits: Vec<CartesianLimitSpec>,
}

/// One `[[limits]]` table: ranges on an affine expression of coordinates and measured
/// joints. A missing range is unlimited.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointLimitSpec {
    /// e.g. `q3`, `jaw`, `q7 - q6`.
    pub expr: String,
    /// `[low, high]`, rad or m.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "as_list::option"
    )]
    pub position: Option<[NumOrExpr; 2]>,
    /// `[low, high]`, rad/s or m/s.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "as_list::option"
    )]
    pub velocity: Option<[NumOrExpr; 2]>,
    /// `[low, high]`, rad/s² or m/s².
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "as_list::option"
    )]
    pub acceleration: Option<[NumOrExpr; 2]>,
}

/// One `[[cartesian_limits]]` table: a box, in the base frame (m), that the origin of
/// `frame` must stay in; an infinite side leaves the box open.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CartesianLimitSpec {
    /// Name of the frame whose origin is kept in the box.
    pub frame: String,
    #[serde(serialize_with = "as_list::array")]
    /// Lower corner of the box, x y z in the base frame (m); `-inf` leaves that side open.
    pub min: [NumOrExpr; 3],
    #[serde(serialize_with = "as_list::array")]
    /// Upper corner of the box, x y z in the base frame (m); `inf` leaves that side open.
    pub max: [NumOrExpr; 3],
}

/// Ranges and corners written as lists (serde writes fixed arrays as tuples, which
/// Python would get as `tuple`s where a limits file and JSON have lists).
mod as_list {
    use serde::{Serialize, Serializer};

    struct List<'a, T>(&'a [T]);

    impl<T: Serialize> Serialize for List<'_, T> {
        fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            s.collect_seq(self.0)
        }
    }

    pub fn array<S: Serializer, T: Serialize, const N: usize>(
        v: &[T; N],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        s.collect_seq(v)
    }

    pub fn option<S: Serializer, T: Serialize, const N: usize>(
        v: &Option<[T; N]>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        match v {
            Some(a) => s.serialize_some(&List(a)),
            None => s.serialize_none(),
        }
    }
}

impl Limits {
    /// The limits of a limits file's text for `model` (see [`LimitsSpec::from_toml_str`]
    /// and [`LimitsSpec::compile`]); `file` names it in messages.
    pub fn from_toml_str(model: &Model, text: &str, file: &str) -> Result<Limits, ModelError> {
        LimitsSpec::from_toml_str(text, file)?.compile(model, file)
    }
}

/// Where a spec's names and numbers are resolved: the file, its constants and the
/// coordinates (`ctx`), the measured joints and the frame names (base first).
pub(crate) struct LimitScope<'a> {
    pub ctx: &'a Ctx<'a>,
    pub measured: &'a Measured,
    pub frame_names: &'a [String],
}

/// The constants a limits file knows (a description adds its own `[constants]`).
fn file_constants() -> Vec<(String, f64)> {
    vec![
        ("pi".into(), std::f64::consts::PI),
        ("deg".into(), std::f64::consts::PI / 180.0),
    ]
}

impl LimitsSpec {
    /// Reads a limits file's text; `file` names it in messages. A file without any
    /// table is refused (an empty `--limits` file is almost certainly a mistake: it
    /// would lift every limit).
    pub fn from_toml_str(text: &str, file: &str) -> Result<LimitsSpec, ModelError> {
        let spec: LimitsSpec = toml::from_str(text).map_err(|e| ModelError::Syntax {
            file: file.into(),
            message: e.to_string(),
        })?;
        if spec.limits.is_empty() && spec.cartesian_limits.is_empty() {
            return Err(ModelError::Syntax {
                file: file.into(),
                message: "expected [[limits]] or [[cartesian_limits]] tables".into(),
            });
        }
        Ok(spec)
    }

    /// The limits of `model`'s coordinates, measured joints and frames, with the
    /// constants `pi` and `deg`; `file` names the spec's origin in messages.
    pub fn compile(&self, model: &Model, file: &str) -> Result<Limits, ModelError> {
        let ctx = Ctx {
            file,
            constants: file_constants(),
            coordinates: &model.coordinates,
        };
        let frame_names = model.frame_names();
        self.compile_in(&LimitScope {
            ctx: &ctx,
            measured: &model.measured,
            frame_names: &frame_names,
        })
    }

    pub(crate) fn compile_in(&self, scope: &LimitScope<'_>) -> Result<Limits, ModelError> {
        let ctx = scope.ctx;
        let mut out = Limits::default();
        for (i, ld) in self.limits.iter().enumerate() {
            let place = format!("limits[{i}] ({})", ld.expr);
            let expr = scope
                .measured
                .affine(&ld.expr, &ctx.constants, ctx.coordinates)
                .map_err(|e| ModelError::field(ctx.file, &place, "expr", e.to_string()))?;
            out.joint.push(Limit {
                label: ld.expr.clone(),
                expr,
                position: ctx.range(
                    &place,
                    "position",
                    &ld.position,
                    (input::MAX_ANGLE_RAD, "rad or m"),
                )?,
                velocity: ctx.range(
                    &place,
                    "velocity",
                    &ld.velocity,
                    (input::MAX_VALUE, "rad/s or m/s"),
                )?,
                acceleration: ctx.range(
                    &place,
                    "acceleration",
                    &ld.acceleration,
                    (input::MAX_VALUE, "rad/s² or m/s²"),
                )?,
            });
        }
        for (i, cd) in self.cartesian_limits.iter().enumerate() {
            let place = format!("cartesian_limits[{i}] ({})", cd.frame);
            let mut corners = [[0.0; 3]; 2];
            for (corner, (field, values)) in
                corners.iter_mut().zip([("min", &cd.min), ("max", &cd.max)])
            {
                for (v, raw) in corner.iter_mut().zip(values) {
                    // An infinite side leaves the box open (documented); NaN is refused.
                    *v = match raw {
                        NumOrExpr::Num(x) if x.is_infinite() => *x,
                        raw => ctx.number(&place, field, raw, (input::MAX_LENGTH_M, "m"))?,
                    };
                }
            }
            let limit = CartesianLimit::new(scope.frame_names, &cd.frame, corners[0], corners[1])
                .map_err(|(field, message)| {
                ModelError::field(ctx.file, &place, field, message)
            })?;
            out.cartesian.push(limit);
        }
        Ok(out)
    }

    /// `limits` written as a spec that [`LimitsSpec::compile`] reads back to the same
    /// limits: a starting point for one's own file (e.g. a robot's limits plus a box).
    /// Each `expr` is the limit's label when that compiles to the same affine function
    /// with the file constants (`deg`, `pi`), else the affine function written out.
    pub fn of(model: &Model, limits: &Limits) -> LimitsSpec {
        let constants = file_constants();
        let pair = |r: Option<[f64; 2]>| r.map(|[a, b]| [NumOrExpr::Num(a), NumOrExpr::Num(b)]);
        let limits_out = limits
            .joint
            .iter()
            .map(|lim| {
                let same = model
                    .measured
                    .affine(&lim.label, &constants, &model.coordinates)
                    .is_ok_and(|a| a == lim.expr);
                let expr = if same {
                    lim.label.clone()
                } else {
                    let mut text: Vec<String> = lim
                        .expr
                        .terms
                        .iter()
                        .map(|&(k, c)| format!("({c:?})*{}", model.coordinates[k]))
                        .collect();
                    if lim.expr.offset != 0.0 || text.is_empty() {
                        text.push(format!("({:?})", lim.expr.offset));
                    }
                    text.join(" + ")
                };
                JointLimitSpec {
                    expr,
                    position: pair(lim.position),
                    velocity: pair(lim.velocity),
                    acceleration: pair(lim.acceleration),
                }
            })
            .collect();
        let corner = |v: [f64; 3]| v.map(NumOrExpr::Num);
        LimitsSpec {
            limits: limits_out,
            cartesian_limits: limits
                .cartesian
                .iter()
                .map(|c| CartesianLimitSpec {
                    frame: c.frame_name.clone(),
                    min: corner(c.min),
                    max: corner(c.max),
                })
                .collect(),
        }
    }
}
