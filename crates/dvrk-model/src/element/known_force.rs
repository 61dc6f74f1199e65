//! A known generalized force `τ += ∇s·p(s)`, `s` affine in q (the MTM's cable
//! polynomial): no parameter, not part of `H·π`; measured torques have it subtracted
//! before a fit, and predictions (and the static torque) add it back with
//! `Model::add_known_forces`.

use super::{FrameContext, Law, Note, Sample};
use crate::error::ModelError;
use crate::expr::Affine;
use crate::param::{Nominal, ParamKind};

/// A known force (see the module documentation).
#[derive(Clone, Debug)]
pub struct KnownForce {
    /// The affine function `s(q)` the force acts along (rad or m): its gradient `∇s` maps
    /// the force into the coordinates. Defaults to the frame's joint value.
    pub along: Affine,
    /// Coefficients of `p`, highest degree first (N·m or N).
    pub polynomial: Vec<f64>,
}

impl KnownForce {
    /// The polynomial at the current coordinates (N·m or N along `s`).
    #[inline(always)]
    pub fn value(&self, q: &[f64]) -> f64 {
        let s = self.along.eval(q);
        self.polynomial.iter().fold(0.0, |acc, &c| acc * s + c)
    }

    /// A known force along `along` (`None`: the frame's joint value, which must move).
    pub(super) fn on(
        fx: &FrameContext,
        along: Option<Affine>,
        polynomial: &[f64],
    ) -> Result<Self, ModelError> {
        let along = match along {
            Some(a) => a,
            None => {
                fx.need_motion("known_force")?;
                fx.value.clone()
            }
        };
        if polynomial.is_empty() || polynomial.iter().any(|c| !c.is_finite()) {
            return Err(fx.error(
                "known_force.polynomial",
                "needs at least one finite coefficient",
            ));
        }
        if let Some(&(k, _)) = along.terms.iter().find(|t| t.0 >= fx.n_coordinates) {
            return Err(fx.error(
                "known_force.along",
                format!(
                    "coordinate {k} does not exist ({} coordinates)",
                    fx.n_coordinates
                ),
            ));
        }
        Ok(KnownForce {
            along,
            polynomial: polynomial.to_vec(),
        })
    }
}

impl Law for KnownForce {
    fn labels(&self) -> &'static [&'static str] {
        &["known_force"]
    }

    fn columns(&self, _out: &mut Vec<(usize, &'static str, ParamKind)>) {}

    fn add_regressor(&self, _s: &Sample, _p: usize, _out: &mut [f64]) {}

    fn add_torque(&self, _s: &Sample, _params: &[f64], _tau: &mut [f64]) {}

    #[inline(always)]
    fn add_known(&self, q: &[f64], tau: &mut [f64]) {
        let v = self.value(q);
        for &(k, c) in &self.along.terms {
            tau[k] += c * v;
        }
    }

    fn nominal(&self, _nominal: &Nominal, _pi: &mut [f64]) -> Option<()> {
        Some(())
    }

    fn note(&self, n: &Note) -> Option<String> {
        Some(format!(
            "known force of frame {}: polynomial {:?} (highest degree first) along {}",
            n.frame,
            self.polynomial,
            self.along.display(n.coordinates)
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, _words: &mut Vec<String>) {
        self.along.push_numbers(numbers);
        numbers.extend(self.polynomial.iter());
    }

    fn description(&self, coordinates: &[String]) -> String {
        let poly: Vec<String> = self.polynomial.iter().map(|c| format!("{c:?}")).collect();
        format!(
            "known_force = {{ polynomial = [{}], along = {:?} }}",
            poly.join(", "),
            self.along.display(coordinates)
        )
    }
}
