//! The Stribeck term `Fs·sign(ṡ)·exp(−(ṡ/vs)²)` of a [`Friction`](super::Friction)
//! element, in the same force (one sum per sample, as the 2019-compatible results were
//! computed): the extra
//! friction at low speed that the Coulomb + viscous model misses at every velocity
//! reversal. Linear in `Fs` for a fixed Stribeck velocity `vs`, so it stays a regressor
//! column.

use super::{near, sign0, BoundOrigin, BoundRow, FrameContext, Note};
use crate::error::ModelError;

/// A Stribeck term on a frame's friction (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stribeck {
    /// Index of `Fs` (N·m or N) in the parameter vector.
    pub param: usize,
    /// Stribeck velocity `vs` (rad/s or m/s), positive.
    pub velocity: f64,
}

impl Stribeck {
    /// The regressor factor of `Fs` at joint rate `sd`.
    #[inline(always)]
    pub fn factor(&self, sd: f64) -> f64 {
        let x = sd / self.velocity;
        sign0(sd) * (-x * x).exp()
    }

    /// A Stribeck velocity (rad/s or m/s): positive and finite.
    pub(crate) fn check_velocity(fx: &FrameContext, v: f64) -> Result<f64, ModelError> {
        if !(v > 0.0 && v.is_finite()) {
            return Err(fx.error(
                "stribeck_velocity",
                format!("must be positive (rad/s or m/s), got {v}"),
            ));
        }
        Ok(v)
    }
}

impl Stribeck {
    /// `Fc + Fs ≥ 0` (`fc`: the friction's `Fc`). `Fs` itself may be negative (a
    /// friction that builds up with speed, or the smoothing the low-pass filter gives
    /// the measured Coulomb steps).
    pub(super) fn bound_row(&self, fc: usize) -> BoundRow {
        BoundRow {
            coefficients: vec![(self.param, -1.0), (fc, -1.0)],
            limit: 0.0,
            origin: BoundOrigin::Physical("Fc + Fs ≥ 0"),
        }
    }

    /// `Fc + Fs ≥ 0` once `Fc` (parameter `fc`) is in place: `Fs` is in no other
    /// constraint, and `Fc + (−Fc)` is exactly zero.
    pub(super) fn clamp(&self, fc: usize, params: &mut [f64]) {
        let sum = params[fc] + params[self.param];
        if sum < 0.0 && near(sum, 0.0) {
            params[self.param] = -params[fc];
        }
    }

    pub(super) fn note(&self, n: &Note) -> String {
        format!(
            "Stribeck friction {} = {} of frame {} (velocity {}, on {})",
            n.names[self.param].name, n.params[self.param], n.frame, self.velocity, n.on
        )
    }
}
