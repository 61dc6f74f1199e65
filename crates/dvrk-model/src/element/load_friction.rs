//! Load-dependent Coulomb friction (issue 28): a Coulomb force proportional to the torque
//! the joint transmits. On a frame whose joint value is one coordinate's multiple,
//! `s = a·q_c + b`, with the load `L = |τ_c|` (N·m or N) and the load ratio `μ`
//! (dimensionless),
//!
//! `τ_c += μ·L·sign(q̇_c)`
//!
//! (the force along `s` is `μ·|τ_c|/|a|·sign(ṡ)`, the load carried along `s` being
//! `τ_c/a`; mapped back onto `q_c` it is the line above, whatever `a`). A capstan, a cable
//! over a pulley, a gear or a bearing that carries the joint's load rubs in proportion to
//! that load (the capstan equation, Coulomb's law on the normal force), so a joint that
//! holds a heavy arm against gravity rubs more than the same joint unloaded: the
//! parallelogram of the PSM carries its links' weight and the 105 g of the speed pair.
//!
//! **The load signal is the joint's measured torque** ([`Model::set_load`]), chosen so the
//! force stays linear in the parameters: `μ` is one regressor column
//! `|τ_c|·sign(q̇_c)`, where `τ_c` is a measured signal like `q` and `q̇`. The other
//! candidates are not: the joint's rigid-body torque under the parameters being fitted
//! multiplies `μ` by them (bilinear), and a first-pass or nominal model's gravity torque
//! needs a second fit, a parameter vector carried with the model, and a nominal model the
//! dVRK arms do not have. The measured torque is also what the friction physically sees
//! (the whole transmitted torque, inertial and gravity alike), and what a controller reads
//! every cycle. Its price is errors in variables: the measurement noise enters the
//! column, which biases `μ` toward 0 by about `σ²/E[τ²]` of the torque noise — small on
//! joints loaded well above their noise.
//!
//! **Prediction does not read the measured torque** (that would hand the model the answer
//! it predicts): [`Model::loaded_inverse_dynamics`] solves `τ = τ₀ + κ·|τ|`, `κ =
//! Σμ·sign(q̇_c)`, for the torque `τ₀` of everything else, exactly: `τ = τ₀/(1 −
//! κ·sign(τ₀))`, unique for `|κ| < 1`. The metrics, the simulation and a feedforward
//! controller use that; the fit, the momentum observer and the regressor the measured
//! load.
//!
//! The physically consistent fit keeps `0 ≤ μ ≤ 1/2`: friction dissipates (`μ ≥ 0`),
//! and a transmission that loses more than half the torque it carries is not one the
//! model describes; the bound also keeps the prediction's amplification `1/(1 − |κ|)` at
//! most 2 (a least-squares fit beyond it is predicted with the amplification capped
//! there). At rest (`q̇_c = 0`) the force is 0 and the element adds no static torque.
//!
//! Description: `load_friction = true` on a frame whose joint value is one coordinate's
//! multiple; parameter `Fl` followed by the frame's index.

use super::{
    clamp_near, sign0, BoundOrigin, BoundRow, BoundsContext, FrameContext, Law, Note, Sample,
};
use crate::error::ModelError;
use crate::param::{Nominal, ParamKind};

/// Largest load ratio `μ` of the physically consistent fit (see the module
/// documentation).
pub const MAX_LOAD_RATIO: f64 = 0.5;

/// Load-dependent Coulomb friction (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadFriction {
    /// Index of `Fl` (the load ratio `μ`, dimensionless) in the parameter vector.
    pub param: usize,
    /// The coordinate whose torque is the load: the frame's joint value is a multiple of
    /// this coordinate only.
    pub coordinate: usize,
}

impl LoadFriction {
    /// Load friction on a moving frame whose joint value is one coordinate's multiple,
    /// `Fl` at column `param`.
    pub(super) fn on(fx: &FrameContext, param: usize) -> Result<Self, ModelError> {
        fx.need_motion("load_friction")?;
        match fx.value.terms[..] {
            [(coordinate, _)] => Ok(LoadFriction { param, coordinate }),
            _ => Err(fx.error(
                "load_friction",
                "the joint value must depend on exactly one coordinate (c*q_k + const), whose torque is the load",
            )),
        }
    }

    /// The regressor factor of `Fl` on its coordinate: `L·sign(q̇_c)` (N·m or N).
    #[inline(always)]
    fn factor(&self, s: &Sample) -> f64 {
        s.load[self.coordinate] * sign0(s.dq[self.coordinate])
    }
}

impl Law for LoadFriction {
    fn labels(&self) -> &'static [&'static str] {
        &["load_friction"]
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        out.push((self.param, "Fl", ParamKind::LoadFriction));
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        out[self.coordinate * p + self.param] += self.factor(s);
    }

    #[inline(always)]
    fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
        tau[self.coordinate] += params[self.param] * self.factor(s);
    }

    // No static torque: the force is zero at rest.

    fn nominal(&self, _nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param] = 0.0;
        Some(())
    }

    /// `0 ≤ Fl ≤ 1/2`: dissipative, and at most half the load.
    fn bound_rows(&self, _b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        let lo = (0.0, BoundOrigin::Physical("load friction Fl ≥ 0"));
        let hi = (
            MAX_LOAD_RATIO,
            BoundOrigin::Physical("load friction Fl ≤ 1/2"),
        );
        BoundRow::interval(self.param, lo, Some(hi), rows);
    }

    fn clamp(&self, _b: &BoundsContext, params: &mut [f64]) {
        clamp_near(&mut params[self.param], 0.0, Some(MAX_LOAD_RATIO));
    }

    fn consistent(&self, params: &[f64], tol: f64) -> bool {
        params[self.param] >= tol && params[self.param] <= MAX_LOAD_RATIO - tol
    }

    fn note(&self, n: &Note) -> Option<String> {
        Some(format!(
            "load-dependent Coulomb friction of frame {} (on {}, proportional to the magnitude of its coordinate's torque): {} = {}",
            n.frame, n.on, n.names[self.param].name, n.params[self.param]
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>) {
        words.push("load_friction".into());
        numbers.push(self.param as f64);
        numbers.push(self.coordinate as f64);
    }

    fn description(&self, _coordinates: &[String]) -> String {
        "load_friction = true".into()
    }
}
