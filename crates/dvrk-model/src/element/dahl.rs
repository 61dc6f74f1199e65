//! Dahl friction along a frame's joint value: rate-independent hysteresis (issue 28).
//! Dahl's model (P. R. Dahl, "A solid friction model", Aerospace Corp. TOR-0158, 1968;
//! "Solid friction damping of mechanical vibrations", AIAA J. 14, 1976), in the
//! normalized form of Åström & Canudas de Wit ("Revisiting the LuGre friction model",
//! IEEE Control Systems 28(6), 2008, eq. 2 with exponent 1), has an internal state
//! `z ∈ [−1, 1]` (dimensionless) driven by the displacement `ds` of the joint value only,
//!
//! `dz/ds = σ·(1 − z·sign(ṡ))`,
//!
//! and a friction force `F = Fd·z`, acting as `τ += aᵀ·F`. After a reversal `z` moves from
//! one sign to the other over a travel of a few `1/σ` (rad or m), whatever the speed: the
//! friction of a cable-driven joint (presliding, cable stretch) that builds up over a
//! displacement rather than a time, which a delay fitted at one speed gets wrong at
//! another (docs/book/src/generalization.md). For a monotone step `Δs` the equation
//! integrates exactly to `z' = sign(Δs) − (sign(Δs) − z)·exp(−σ·|Δs|)` ([`Dahl::step`]), so
//! the state between samples does not depend on the sampling rate, only on the path of
//! `s`; it stays in `[−1, 1]` for any step.
//!
//! `σ` (1/rad or 1/m) is fixed per element, like the Stribeck velocity, so the force is
//! linear in `Fd` (N·m or N) and `z` is a signal computed from the positions in time order
//! ([`Model::advance_hysteresis`](crate::Model::advance_hysteresis)) and read from the
//! [`Workspace`](crate::Workspace) by the regressor and the dynamics. The physically
//! consistent fit keeps `Fd ≥ 0`: the force then opposes the last motion (dissipative
//! once `z` has settled). Before the first sample `z = 0`.
//!
//! Description: `dahl = { sigma = 20 }`; parameter `Fd` followed by the frame's index.

use super::{clamp_near, BoundOrigin, BoundRow, BoundsContext, FrameContext, Law, Note, Sample};
use crate::error::ModelError;
use crate::input::{self, InputError};
use crate::param::{Nominal, ParamKind};

/// Dahl friction (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Dahl {
    /// Index of `Fd` (N·m or N) in the parameter vector; the element's state in the
    /// workspace is kept at the same index.
    pub param: usize,
    /// Stiffness of the hysteresis `σ` (1/rad or 1/m): `z` settles after a travel of a
    /// few `1/σ`.
    pub sigma: f64,
}

impl Dahl {
    /// Dahl friction on a moving frame, `Fd` at column `param`, `σ` positive and finite.
    pub(super) fn on(fx: &FrameContext, sigma: f64, param: usize) -> Result<Self, ModelError> {
        fx.need_motion("dahl")?;
        let sigma = Dahl::check_sigma(sigma).map_err(|m| fx.error("dahl.sigma", m))?;
        Ok(Dahl { param, sigma })
    }

    /// `σ` if it is positive and finite (1/rad or 1/m), else the reason.
    pub fn check_sigma(sigma: f64) -> Result<f64, InputError> {
        input::check_positive(sigma, "the Dahl stiffness sigma", "1/rad or 1/m")
    }

    /// The state after a monotone displacement `ds` (rad or m) from state `z`: the exact
    /// solution of `dz/ds = σ·(1 − z·sign(ds))`, in `[−1, 1]` when `z` is.
    #[inline(always)]
    pub fn step(z: f64, ds: f64, sigma: f64) -> f64 {
        if ds > 0.0 {
            1.0 - (1.0 - z) * (-sigma * ds).exp()
        } else if ds < 0.0 {
            -1.0 + (1.0 + z) * (sigma * ds).exp()
        } else {
            z
        }
    }
}

impl Law for Dahl {
    fn labels(&self) -> &'static [&'static str] {
        &["dahl"]
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        out.push((self.param, "Fd", ParamKind::Dahl));
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        let z = s.hysteresis[self.param];
        for &(coord, a) in &s.value.terms {
            out[coord * p + self.param] += a * z;
        }
    }

    #[inline(always)]
    fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
        let force = params[self.param] * s.hysteresis[self.param];
        for &(c, a) in &s.value.terms {
            tau[c] += a * force;
        }
    }

    // No static torque: at rest the force depends on the path that led there (`z`), not
    // on the direction of the next motion.

    fn nominal(&self, _nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param] = 0.0;
        Some(())
    }

    /// `Fd ≥ 0`: the force opposes the last motion.
    fn bound_rows(&self, _b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        let origin = BoundOrigin::Physical("Dahl friction Fd ≥ 0");
        rows.push(BoundRow::at_least(self.param, 0.0, origin));
    }

    fn clamp(&self, _b: &BoundsContext, params: &mut [f64]) {
        clamp_near(&mut params[self.param], 0.0, None);
    }

    fn consistent(&self, params: &[f64], tol: f64) -> bool {
        params[self.param] >= tol
    }

    fn note(&self, n: &Note) -> Option<String> {
        Some(format!(
            "Dahl friction of frame {} (sigma {} per unit of {}, a state carried from sample to sample): {} = {}",
            n.frame, self.sigma, n.on, n.names[self.param].name, n.params[self.param]
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>) {
        words.push("dahl".into());
        numbers.push(self.param as f64);
        numbers.push(self.sigma);
    }

    fn description(&self, _coordinates: &[String]) -> String {
        format!("dahl = {{ sigma = {:?} }}", self.sigma)
    }
}
