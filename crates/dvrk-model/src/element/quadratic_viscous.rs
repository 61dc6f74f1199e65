//! Quadratic viscous friction `F = Fq·ṡ·|ṡ|` along a frame's joint value: a drag that
//! grows with the square of the speed (seals, lubricant shear at high speed), which
//! the linear `Fv·ṡ` of [`Friction`](super::Friction) cannot follow. Linear in `Fq`, so
//! it is one more regressor column; it dissipates (`F·ṡ ≥ 0`) exactly when `Fq ≥ 0`.
//!
//! Description: `quadratic_viscous = true`, or with a nominal value and an upper bound
//! for the physically consistent fit, `quadratic_viscous = { nominal = 0.01, max = 0.5 }`
//! (N·m·s²/rad² or N·s²/m²).
//!
//! This element is the example of issue 13: everything about it is in this module, plus
//! its variant in [`Element`](super::Element), its field in the description
//! (`description/elements.rs`) and its [`ParamKind`].

use super::{clamp_near, BoundOrigin, BoundRow, BoundsContext, FrameContext, Law, Note, Sample};
use crate::error::ModelError;
use crate::input;
use crate::param::{Nominal, ParamKind};

/// Quadratic viscous friction (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct QuadraticViscous {
    /// Index of `Fq` (N·m·s²/rad² or N·s²/m²) in the parameter vector.
    pub param: usize,
    /// Nominal `Fq` (same unit), 0 unless the description gives one.
    pub nominal: f64,
    /// Upper bound of `Fq` for the physically consistent fit, if any.
    pub max: Option<f64>,
}

impl QuadraticViscous {
    /// Quadratic viscous friction on a moving frame, its `Fq` at column `param`.
    pub(super) fn on(
        fx: &FrameContext,
        nominal: Option<f64>,
        max: Option<f64>,
        param: usize,
    ) -> Result<Self, ModelError> {
        fx.need_motion("quadratic_viscous")?;
        let unit = "N·m·s²/rad² or N·s²/m²";
        for (field, v) in [
            ("quadratic_viscous.nominal", nominal),
            ("quadratic_viscous.max", max),
        ] {
            if let Some(v) = v {
                input::check_magnitude(v, input::MAX_VALUE, unit)
                    .map_err(|m| fx.error(field, m))?;
            }
        }
        if let Some(m) = max.filter(|&m| m < 0.0) {
            return Err(fx.error(
                "quadratic_viscous.max",
                format!("{m}: below the physical lower bound 0"),
            ));
        }
        Ok(QuadraticViscous {
            param,
            nominal: nominal.unwrap_or(0.0),
            max,
        })
    }

    /// The regressor factor of `Fq` at joint rate `sd`: `ṡ·|ṡ|`.
    #[inline(always)]
    pub fn factor(sd: f64) -> f64 {
        sd * sd.abs()
    }
}

impl Law for QuadraticViscous {
    fn labels(&self) -> &'static [&'static str] {
        &["quadratic_viscous"]
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        out.push((self.param, "Fq", ParamKind::QuadraticViscous));
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        let v = Self::factor(s.value.dot(s.dq));
        for &(coord, a) in &s.value.terms {
            out[coord * p + self.param] += a * v;
        }
    }

    #[inline(always)]
    fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
        let force = params[self.param] * Self::factor(s.value.dot(s.dq));
        for &(c, a) in &s.value.terms {
            tau[c] += a * force;
        }
    }

    // No static torque: the force vanishes at rest.

    fn nominal(&self, _nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param] = self.nominal;
        Some(())
    }

    /// `Fq ≥ 0` (dissipation), `Fq ≤ max` with the frame's bounds.
    fn bound_rows(&self, b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        let lo = (0.0, BoundOrigin::Physical("Fq ≥ 0"));
        let hi = self.max.filter(|_| b.use_frame);
        let hi = hi.map(|v| (v, BoundOrigin::Frame("quadratic_viscous.max")));
        BoundRow::interval(self.param, lo, hi, rows);
    }

    fn clamp(&self, b: &BoundsContext, params: &mut [f64]) {
        clamp_near(
            &mut params[self.param],
            0.0,
            self.max.filter(|_| b.use_frame),
        );
    }

    fn consistent(&self, params: &[f64], tol: f64) -> bool {
        params[self.param] >= tol
    }

    fn note(&self, n: &Note) -> Option<String> {
        Some(format!(
            "quadratic viscous friction {} = {} of frame {} (on {})",
            n.names[self.param].name, n.params[self.param], n.frame, n.on
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>) {
        words.push("quadratic_viscous".into());
        numbers.push(self.param as f64);
    }

    fn description(&self, _coordinates: &[String]) -> String {
        let mut fields = vec![format!("nominal = {:?}", self.nominal)];
        if let Some(m) = self.max {
            fields.push(format!("max = {m:?}"));
        }
        format!("quadratic_viscous = {{ {} }}", fields.join(", "))
    }
}
