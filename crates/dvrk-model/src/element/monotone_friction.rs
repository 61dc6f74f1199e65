//! Monotone friction along a frame's joint value: a velocity basis that can follow any
//! monotone, saturating friction curve, with a different curve forward and backward
//! (issue 28). With the frame's joint rate `ṡ` and velocities `v₁ < … < vₘ` (rad/s or
//! m/s, at most [`MAX_VELOCITIES`]),
//!
//! `F = Σₖ F⁺ₖ·max(tanh(ṡ/vₖ), 0) + F⁻ₖ·min(tanh(ṡ/vₖ), 0)`,
//!
//! acting as `τ += aᵀ·F`. Each term is a smooth step of width `vₖ`; between the Coulomb
//! step (`v → 0`) and the viscous line (`v → ∞`) of [`Friction`](super::Friction) the
//! steps build the curve's knee at the speeds the data show. Linear in the weights, so
//! they are regressor columns. The physically consistent fit keeps every weight `≥ 0`:
//! then `F` is non-decreasing in `ṡ` on both sides, zero at rest and dissipative
//! (`F·ṡ ≥ 0`) for any data, a sufficient linear condition that holds at every speed,
//! not only on a grid. The forward weights `F⁺` and the backward ones `F⁻` are free of
//! each other: the asymmetric part of the friction. Unconstrained, several such steps
//! over-fit (issue 28's speed pair: a test error of 7.4 on the insertion); constrained,
//! they do as well as one Stribeck term.
//!
//! Description: `monotone_friction = { velocities = [0.05, 0.2] }`; parameters `Fpa`,
//! `Fna` (first velocity, forward and backward), `Fpb`, `Fnb`, … followed by the frame's
//! index (N·m or N).

use super::{clamp_near, BoundOrigin, BoundRow, BoundsContext, FrameContext, Law, Note, Sample};
use crate::error::ModelError;
use crate::input;
use crate::param::{Nominal, ParamKind};

/// Most velocities of one element (the parameter names have a letter per velocity).
pub const MAX_VELOCITIES: usize = 4;

/// Name prefixes of the forward and backward weight of each velocity.
const PREFIXES: [[&str; 2]; MAX_VELOCITIES] = [
    ["Fpa", "Fna"],
    ["Fpb", "Fnb"],
    ["Fpc", "Fnc"],
    ["Fpd", "Fnd"],
];

/// Monotone friction (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct MonotoneFriction {
    /// Index of the first weight (`Fpa`, N·m or N) in the parameter vector; the weights
    /// follow as forward, backward for each velocity.
    pub param: usize,
    /// The steps' velocities (rad/s or m/s), positive and increasing.
    pub velocities: Vec<f64>,
}

impl MonotoneFriction {
    /// Monotone friction on a moving frame, its first weight at column `param`: 1 to
    /// [`MAX_VELOCITIES`] velocities, positive, finite and increasing.
    pub(super) fn on(
        fx: &FrameContext,
        velocities: &[f64],
        param: usize,
    ) -> Result<Self, ModelError> {
        fx.need_motion("monotone_friction")?;
        let field = "monotone_friction.velocities";
        if velocities.is_empty() || velocities.len() > MAX_VELOCITIES {
            return Err(fx.error(
                field,
                format!(
                    "give 1 to {MAX_VELOCITIES} velocities (rad/s or m/s), got {}",
                    velocities.len()
                ),
            ));
        }
        for &v in velocities {
            input::check_magnitude(v, input::MAX_VALUE, "rad/s or m/s")
                .map_err(|m| fx.error(field, m))?;
            if v <= 0.0 {
                return Err(fx.error(field, format!("must be positive (rad/s or m/s), got {v}")));
            }
        }
        if velocities.windows(2).any(|w| w[1] <= w[0]) {
            return Err(fx.error(
                field,
                format!("must increase, got {velocities:?} (rad/s or m/s)"),
            ));
        }
        Ok(MonotoneFriction {
            param,
            velocities: velocities.to_vec(),
        })
    }

    /// The regressor factors of the forward and backward weights of velocity `v` at
    /// joint rate `sd`: `(max(tanh(ṡ/v), 0), min(tanh(ṡ/v), 0))`.
    #[inline(always)]
    pub fn factors(sd: f64, v: f64) -> (f64, f64) {
        let t = (sd / v).tanh();
        (t.max(0.0), t.min(0.0))
    }
}

impl Law for MonotoneFriction {
    fn labels(&self) -> &'static [&'static str] {
        &["monotone_friction"]
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        for (k, names) in PREFIXES.iter().take(self.velocities.len()).enumerate() {
            out.push((self.param + 2 * k, names[0], ParamKind::MonotoneFriction));
            out.push((
                self.param + 2 * k + 1,
                names[1],
                ParamKind::MonotoneFriction,
            ));
        }
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        let sd = s.value.dot(s.dq);
        for (k, &v) in self.velocities.iter().enumerate() {
            let (fwd, bwd) = Self::factors(sd, v);
            for &(coord, a) in &s.value.terms {
                let base = coord * p + self.param + 2 * k;
                out[base] += a * fwd;
                out[base + 1] += a * bwd;
            }
        }
    }

    #[inline(always)]
    fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
        let sd = s.value.dot(s.dq);
        let mut force = 0.0;
        for (k, &v) in self.velocities.iter().enumerate() {
            let (fwd, bwd) = Self::factors(sd, v);
            force += params[self.param + 2 * k] * fwd + params[self.param + 2 * k + 1] * bwd;
        }
        for &(c, a) in &s.value.terms {
            tau[c] += a * force;
        }
    }

    // No static torque: every step is zero at rest (the breakaway is `Friction`'s `Fc`).

    fn nominal(&self, _nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param..self.param + 2 * self.velocities.len()].fill(0.0);
        Some(())
    }

    /// Every weight `≥ 0`: monotone and dissipative at every speed.
    fn bound_rows(&self, _b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        let origin = BoundOrigin::Physical("monotone friction weights ≥ 0");
        for k in self.param..self.param + 2 * self.velocities.len() {
            rows.push(BoundRow::at_least(k, 0.0, origin));
        }
    }

    fn clamp(&self, _b: &BoundsContext, params: &mut [f64]) {
        for v in &mut params[self.param..self.param + 2 * self.velocities.len()] {
            clamp_near(v, 0.0, None);
        }
    }

    fn consistent(&self, params: &[f64], tol: f64) -> bool {
        params[self.param..self.param + 2 * self.velocities.len()]
            .iter()
            .all(|&w| w >= tol)
    }

    fn note(&self, n: &Note) -> Option<String> {
        let weights: Vec<String> = (self.param..self.param + 2 * self.velocities.len())
            .map(|k| format!("{} = {}", n.names[k].name, n.params[k]))
            .collect();
        Some(format!(
            "monotone friction of frame {} (velocities {:?}, on {}): {}",
            n.frame,
            self.velocities,
            n.on,
            weights.join(", ")
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>) {
        words.push("monotone_friction".into());
        numbers.push(self.param as f64);
        numbers.extend(&self.velocities);
    }

    fn description(&self, _coordinates: &[String]) -> String {
        let v: Vec<String> = self.velocities.iter().map(|v| format!("{v:?}")).collect();
        format!("monotone_friction = {{ velocities = [{}] }}", v.join(", "))
    }
}
