//! A position-dependent torque along a frame's joint value: a low-order Fourier series in
//! the joint value `s` (issue 28), for what a cable-driven joint feels as a function of
//! where it is — the cables' and tendons' paths over their pulleys, a counterweight, a
//! preloaded spring's varying lever arm. With the phase `θ = 2π·s/P` of the period `P`
//! (rad or m) and the order `K` (1 to [`MAX_ORDER`]),
//!
//! `F = Σₖ₌₁..K Aₖ·cos(k·θ) + Bₖ·sin(k·θ)`,
//!
//! acting as `τ += aᵀ·F`. Linear in `Aₖ`, `Bₖ` (N·m or N), so they are regressor
//! columns. The series has **no constant term**: a constant along the joint value is the
//! offset `Fo` of [`Friction`](super::Friction), which is kept as the only one so the
//! two cannot trade (a constant column twice would make neither identifiable). Nor does a
//! spring alias with it: [`Spring`](super::Spring)'s torque is affine in the deflection,
//! which no finite sum of sines and cosines is over a full period. What can alias is
//! gravity: a revolute joint whose gravity torque depends on its own angle alone (the last
//! link of a chain turning about a horizontal axis) has a gravity torque
//! `g·(lₓ·cos s − l_y·sin s)`, exactly the first order's columns. The base parameters
//! (`Model::base_parameters`) find such a dependence numerically and fold `A₁`, `B₁` into
//! the link's first moments, so the fit stays determined; they are then not separately
//! identifiable (the test `position_torque_identifiability` holds both cases).
//!
//! The series is neither dissipative nor of a known sign (a cable's elastic torque pushes
//! either way), so the physically consistent fit adds no bound on it. A
//! position-dependent torque is also there at rest, so it is part of the static torque.
//!
//! `P` defaults to `2π` (one turn) on a revolute frame; a prismatic frame must give it
//! (m), as the series in metres has no natural period. Description: `position_torque =
//! { order = 2 }` or `{ order = 1, period = 0.5 }`; parameters `Pca`, `Psa` (first order,
//! cosine and sine), `Pcb`, `Psb`, … followed by the frame's index (N·m or N).

use std::f64::consts::TAU;

use super::{FrameContext, Law, Note, Sample};
use crate::error::ModelError;
use crate::expr::Affine;
use crate::input::{self, InputError};
use crate::param::{Nominal, ParamKind};

/// Highest order of one element (the parameter names have a letter per order; a higher
/// order follows the noise of one log rather than the joint).
pub const MAX_ORDER: usize = 3;

/// Name prefixes of the cosine and sine coefficient of each order.
const PREFIXES: [[&str; 2]; MAX_ORDER] = [["Pca", "Psa"], ["Pcb", "Psb"], ["Pcc", "Psc"]];

/// A position-dependent torque (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct PositionTorque {
    /// Index of the first coefficient (`Pca`, N·m or N) in the parameter vector; the
    /// coefficients follow as cosine, sine for each order.
    pub param: usize,
    /// The series' order `K` (1 to `MAX_ORDER`, 3).
    pub order: usize,
    /// The period `P` of the series along the joint value (rad or m).
    pub period: f64,
}

impl PositionTorque {
    /// A position-dependent torque on a moving frame, its first coefficient at column
    /// `param`: order 1 to [`MAX_ORDER`], period positive and finite (required on a
    /// prismatic frame, `2π` by default on a revolute one).
    pub(super) fn on(
        fx: &FrameContext,
        order: usize,
        period: Option<f64>,
        param: usize,
    ) -> Result<Self, ModelError> {
        fx.need_motion("position_torque")?;
        Self::check_order(order).map_err(|m| fx.error("position_torque.order", m))?;
        let period = match period {
            Some(p) => Self::check_period(p).map_err(|m| fx.error("position_torque.period", m))?,
            None if fx.revolute => TAU,
            None => {
                return Err(fx.error(
                    "position_torque.period",
                    "a prismatic frame needs the series' period (m)",
                ))
            }
        };
        Ok(PositionTorque {
            param,
            order,
            period,
        })
    }

    /// `order` if it is 1 to `MAX_ORDER` (3), else the reason.
    pub fn check_order(order: usize) -> Result<usize, InputError> {
        if (1..=MAX_ORDER).contains(&order) {
            Ok(order)
        } else {
            Err(InputError::Order {
                quantity: "the position torque's order",
                max: MAX_ORDER,
                value: order,
            })
        }
    }

    /// `period` if it is positive and finite (rad or m), else the reason.
    pub fn check_period(period: f64) -> Result<f64, InputError> {
        input::check_positive(period, "the position torque's period", "rad or m")
    }

    /// The regressor factors of order `k` (1-based) at joint value `s`:
    /// `(cos(k·2π·s/P), sin(k·2π·s/P))`.
    #[inline(always)]
    pub fn factors(&self, s: f64, k: usize) -> (f64, f64) {
        let (sin, cos) = (k as f64 * TAU * s / self.period).sin_cos();
        (cos, sin)
    }

    /// The series' force at joint value `s` (N·m or N).
    #[inline(always)]
    fn force(&self, s: f64, params: &[f64]) -> f64 {
        let mut force = 0.0;
        for k in 0..self.order {
            let (c, sn) = self.factors(s, k + 1);
            force += params[self.param + 2 * k] * c + params[self.param + 2 * k + 1] * sn;
        }
        force
    }

    #[inline(always)]
    fn push(&self, value: &Affine, q: &[f64], params: &[f64], tau: &mut [f64]) {
        let force = self.force(value.eval(q), params);
        for &(c, a) in &value.terms {
            tau[c] += a * force;
        }
    }
}

impl Law for PositionTorque {
    fn labels(&self) -> &'static [&'static str] {
        &["position_torque"]
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        for (k, names) in PREFIXES.iter().take(self.order).enumerate() {
            out.push((self.param + 2 * k, names[0], ParamKind::PositionTorque));
            out.push((self.param + 2 * k + 1, names[1], ParamKind::PositionTorque));
        }
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        let v = s.value.eval(s.q);
        for k in 0..self.order {
            let (c, sn) = self.factors(v, k + 1);
            for &(coord, a) in &s.value.terms {
                let base = coord * p + self.param + 2 * k;
                out[base] += a * c;
                out[base + 1] += a * sn;
            }
        }
    }

    // A torque of the position: in motion and held at rest as well.
    position_law!();

    fn nominal(&self, _nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param..self.param + 2 * self.order].fill(0.0);
        Some(())
    }

    // No bound: the torque is neither dissipative nor of a known sign.

    fn note(&self, n: &Note) -> Option<String> {
        let coefficients: Vec<String> = (self.param..self.param + 2 * self.order)
            .map(|k| format!("{} = {}", n.names[k].name, n.params[k]))
            .collect();
        Some(format!(
            "position-dependent torque of frame {} (Fourier series of order {} and period {} in {}): {}",
            n.frame,
            self.order,
            self.period,
            n.on,
            coefficients.join(", ")
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>) {
        words.push("position_torque".into());
        numbers.push(self.param as f64);
        numbers.push(self.order as f64);
        numbers.push(self.period);
    }

    fn description(&self, _coordinates: &[String]) -> String {
        format!(
            "position_torque = {{ order = {}, period = {:?} }}",
            self.order, self.period
        )
    }
}
