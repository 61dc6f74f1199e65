//! A motor (rotor) inertia on a frame whose joint value is `ratio·q[coordinate] +
//! const`: `τ[coordinate] += ratio·Ia·q̈[coordinate]` (the 2019 convention), an
//! acceleration term, so forward dynamics puts it on the mass matrix's diagonal.

use super::{clamp_near, BoundOrigin, BoundRow, BoundsContext, FrameContext, Law, Note, Sample};
use crate::error::ModelError;
use crate::param::{Nominal, ParamKind};

/// A motor inertia (see the module documentation).
#[derive(Clone, Debug)]
pub struct MotorInertia {
    /// Index of `Ia` (kg·m²) in the parameter vector.
    pub param: usize,
    /// The coordinate whose motor it is: the frame's joint value is a multiple of this
    /// coordinate only.
    pub coordinate: usize,
    /// The frame's joint value per unit of `q[coordinate]` (`a` in `s = a·q + b`); the
    /// torque is `ratio·Ia·q̈`.
    pub ratio: f64,
}

impl MotorInertia {
    /// `motor_inertia = true` on a moving frame whose joint value is one coordinate's
    /// multiple (plus a constant).
    pub(super) fn on(fx: &FrameContext, param: usize) -> Result<Self, ModelError> {
        fx.need_motion("motor_inertia")?;
        if fx.value.terms.len() != 1 {
            return Err(fx.error(
                "motor_inertia",
                "the joint value must depend on exactly one coordinate (c*q_k + const)",
            ));
        }
        let (coordinate, ratio) = fx.value.terms[0];
        Ok(MotorInertia {
            param,
            coordinate,
            ratio,
        })
    }
}

impl Law for MotorInertia {
    fn labels(&self) -> &'static [&'static str] {
        &["motor_inertia"]
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        out.push((self.param, "Ia", ParamKind::MotorInertia));
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        out[self.coordinate * p + self.param] += self.ratio * s.ddq[self.coordinate];
    }

    #[inline(always)]
    fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
        tau[self.coordinate] += self.ratio * params[self.param] * s.ddq[self.coordinate];
    }

    #[inline(always)]
    fn inertial(&self) -> bool {
        true
    }

    #[inline(always)]
    fn add_mass(&self, params: &[f64], n: usize, out: &mut [f64]) {
        out[self.coordinate * (n + 1)] += self.ratio * params[self.param];
    }

    fn nominal(&self, nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param] = nominal.ia?;
        Some(())
    }

    fn bound_rows(&self, b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        let lo = (b.global.ia_min, BoundOrigin::Global("ia_min"));
        let hi = b.frame.ia_max.filter(|_| b.use_frame);
        let hi = hi.map(|v| (v, BoundOrigin::Frame("ia_max")));
        BoundRow::interval(self.param, lo, hi, rows);
    }

    fn clamp(&self, b: &BoundsContext, params: &mut [f64]) {
        let hi = b.frame.ia_max.filter(|_| b.use_frame);
        clamp_near(&mut params[self.param], b.global.ia_min, hi);
    }

    /// A motor has inertia: `Ia ≥ 0`.
    fn consistent(&self, params: &[f64], tol: f64) -> bool {
        params[self.param] >= tol
    }

    fn note(&self, n: &Note) -> Option<String> {
        Some(format!(
            "motor inertia {} = {} of frame {} (on {})",
            n.names[self.param].name, n.params[self.param], n.frame, n.on
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, _words: &mut Vec<String>) {
        numbers.extend([self.param as f64, self.coordinate as f64, self.ratio]);
    }

    fn wpi_fields(&self, params: &[f64]) -> Vec<(&'static str, f64)> {
        vec![("Im", params[self.param])]
    }

    fn description(&self, _coordinates: &[String]) -> String {
        "motor_inertia = true".into()
    }
}
