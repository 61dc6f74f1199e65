//! Coulomb, viscous and offset friction along a frame's joint value:
//! `F = Fc·sign(ṡ) + Fv·ṡ + Fo` (the 2019 model), acting as `τ += aᵀ·F`, optionally
//! with a [`Stribeck`] term `Fs·sign(ṡ)·exp(−(ṡ/vs)²)` in the same force.

use super::{
    clamp_near, sign0, BoundOrigin, BoundRow, BoundsContext, FrameContext, Law, Note, Sample,
    Stribeck,
};
use crate::error::ModelError;
use crate::expr::Affine;
use crate::param::{Nominal, ParamKind};

/// Coulomb, viscous and offset friction on a frame's joint value.
#[derive(Clone, Debug)]
pub struct Friction {
    /// Index of `Fc` (N·m or N) in the parameter vector; `Fv` (N·m·s/rad or N·s/m) and
    /// `Fo` (N·m or N) follow.
    pub param: usize,
    /// The low-speed term, whose `Fs` is added after every other parameter (see
    /// `Model::add_stribeck`).
    pub stribeck: Option<Stribeck>,
}

impl Friction {
    /// Friction on a moving frame, its `Fc` at column `param` (no Stribeck term yet).
    pub(super) fn on(fx: &FrameContext, param: usize) -> Result<Self, ModelError> {
        fx.need_motion("friction")?;
        Ok(Friction {
            param,
            stribeck: None,
        })
    }
}

impl Law for Friction {
    fn labels(&self) -> &'static [&'static str] {
        match self.stribeck {
            None => &["friction"],
            Some(_) => &["friction", "stribeck"],
        }
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        let k = self.param;
        out.push((k, "Fc", ParamKind::Coulomb));
        out.push((k + 1, "Fv", ParamKind::Viscous));
        out.push((k + 2, "Fo", ParamKind::Offset));
        if let Some(st) = &self.stribeck {
            out.push((st.param, "Fs", ParamKind::Stribeck));
        }
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        let sd = s.value.dot(s.dq);
        let sg = sign0(sd);
        for &(coord, a) in &s.value.terms {
            let base = coord * p + self.param;
            out[base] += a * sg;
            out[base + 1] += a * sd;
            out[base + 2] += a;
        }
        if let Some(st) = &self.stribeck {
            let v = st.factor(sd);
            for &(coord, a) in &s.value.terms {
                out[coord * p + st.param] += a * v;
            }
        }
    }

    #[inline(always)]
    fn add_torque(&self, s: &Sample, params: &[f64], tau: &mut [f64]) {
        let sd = s.value.dot(s.dq);
        let k = self.param;
        let mut force = params[k] * sign0(sd) + params[k + 1] * sd + params[k + 2];
        if let Some(st) = &self.stribeck {
            force += params[st.param] * st.factor(sd);
        }
        for &(c, a) in &s.value.terms {
            tau[c] += a * force;
        }
    }

    /// Coulomb friction at the onset's sign, offset friction always, no viscous term;
    /// the Stribeck term at the onset's sign (`exp(−(ṡ/vs)²) → 1`).
    #[inline(always)]
    fn add_static(&self, value: &Affine, _q: &[f64], onset: f64, params: &[f64], tau: &mut [f64]) {
        let mut force = params[self.param] * onset + params[self.param + 2];
        if let Some(st) = &self.stribeck {
            force += params[st.param] * onset;
        }
        for &(c, a) in &value.terms {
            tau[c] += a * force;
        }
    }

    fn nominal(&self, nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param] = nominal.fc.unwrap_or(0.0);
        pi[self.param + 1] = nominal.fv.unwrap_or(0.0);
        pi[self.param + 2] = nominal.fo.unwrap_or(0.0);
        if let Some(st) = &self.stribeck {
            pi[st.param] = nominal.fs.unwrap_or(0.0);
        }
        Some(())
    }

    fn bound_rows(&self, b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        let (fc, fv, fo) = (self.param, self.param + 1, self.param + 2);
        let g = b.global;
        rows.push(BoundRow::at_least(
            fc,
            g.fc_min,
            BoundOrigin::Global("fc_min"),
        ));
        rows.push(BoundRow::at_least(
            fv,
            g.fv_min,
            BoundOrigin::Global("fv_min"),
        ));
        if let Some(st) = &self.stribeck {
            rows.push(st.bound_row(fc));
        }
        if b.use_frame {
            let f = b.frame;
            if let Some(v) = f.fc_max {
                rows.push(BoundRow::at_most(fc, v, BoundOrigin::Frame("fc_max")));
            }
            if let Some(v) = f.fv_max {
                rows.push(BoundRow::at_most(fv, v, BoundOrigin::Frame("fv_max")));
            }
            if let Some(v) = f.fo_max {
                rows.push(BoundRow::at_most(fo, v, BoundOrigin::Frame("fo_max")));
                rows.push(BoundRow {
                    coefficients: vec![(fo, -1.0)],
                    limit: v,
                    origin: BoundOrigin::Frame("fo_max"),
                });
            }
        }
    }

    fn clamp(&self, b: &BoundsContext, params: &mut [f64]) {
        let upper = |v: Option<f64>| v.filter(|_| b.use_frame);
        clamp_near(
            &mut params[self.param],
            b.global.fc_min,
            upper(b.frame.fc_max),
        );
        clamp_near(
            &mut params[self.param + 1],
            b.global.fv_min,
            upper(b.frame.fv_max),
        );
        if let Some(fo) = upper(b.frame.fo_max) {
            clamp_near(&mut params[self.param + 2], -fo, Some(fo));
        }
        if let Some(st) = &self.stribeck {
            st.clamp(self.param, params);
        }
    }

    /// Friction dissipates: `Fc, Fv ≥ 0`, and `Fc + Fs ≥ 0`.
    fn consistent(&self, params: &[f64], tol: f64) -> bool {
        params[self.param] >= tol
            && params[self.param + 1] >= tol
            && self
                .stribeck
                .is_none_or(|st| params[self.param] + params[st.param] >= tol)
    }

    /// Friction itself is written as URDF `<dynamics>` by the export, where it can be.
    fn note(&self, n: &Note) -> Option<String> {
        self.stribeck.map(|st| st.note(n))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, _words: &mut Vec<String>) {
        numbers.push(self.param as f64);
        if let Some(st) = &self.stribeck {
            numbers.extend([st.param as f64, st.velocity]);
        }
    }

    fn wpi_fields(&self, params: &[f64]) -> Vec<(&'static str, f64)> {
        let k = self.param;
        vec![
            ("Fc", params[k]),
            ("Fv", params[k + 1]),
            ("Fo", params[k + 2]),
        ]
    }

    fn sign_column(&self) -> Option<usize> {
        Some(self.param)
    }

    fn description(&self, _coordinates: &[String]) -> String {
        match &self.stribeck {
            None => "friction = true".into(),
            Some(st) => format!("friction = true\nstribeck_velocity = {:?}", st.velocity),
        }
    }
}
