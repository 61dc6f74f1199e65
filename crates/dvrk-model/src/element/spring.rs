//! A spring of stiffness `K` acting as `τ −= aᵀ·K·dl(q)` along its frame's joint value
//! (the 2019 convention), its deflection `dl(q)` possibly nonlinear.

use super::{clamp_near, BoundOrigin, BoundRow, BoundsContext, FrameContext, Law, Note, Sample};
use crate::error::ModelError;
use crate::expr::{Affine, Expr};
use crate::param::{Nominal, ParamKind};

/// A spring (see the module documentation).
#[derive(Clone, Debug)]
pub struct Spring {
    /// Index of `K` (N·m or N per unit of deflection) in the parameter vector.
    pub param: usize,
    /// Deflection `dl(q)` (m or rad; may be nonlinear).
    pub deflection: Deflection,
}

/// A spring deflection: affine ones (the common case) skip the expression evaluator.
#[derive(Clone, Debug)]
pub enum Deflection {
    /// An affine deflection of the coordinates (m or rad), evaluated as a dot product.
    Affine(Affine),
    /// A nonlinear deflection, evaluated by the expression interpreter.
    Expr(Box<Expr>),
}

impl Deflection {
    /// From an expression, kept affine when it is.
    pub fn new(expr: Expr, n_coordinates: usize) -> Self {
        match expr.affine(n_coordinates) {
            Ok(a) => Deflection::Affine(a),
            Err(_) => Deflection::Expr(Box::new(expr)),
        }
    }

    #[inline(always)]
    /// The deflection `dl(q)` (m or rad) at coordinates `q`.
    pub fn eval(&self, q: &[f64]) -> f64 {
        match self {
            Deflection::Affine(a) => a.eval(q),
            Deflection::Expr(e) => e.eval(q),
        }
    }

    /// The deflection as text, coordinates by name.
    pub fn display(&self, coordinates: &[String]) -> String {
        match self {
            Deflection::Affine(a) => a.display(coordinates),
            Deflection::Expr(e) => e.text().to_string(),
        }
    }
}

impl Spring {
    /// A spring on a moving frame, its `K` at column `param`.
    pub(super) fn on(
        fx: &FrameContext,
        deflection: Deflection,
        param: usize,
    ) -> Result<Self, ModelError> {
        fx.need_motion("spring")?;
        Ok(Spring { param, deflection })
    }

    #[inline(always)]
    fn push(&self, value: &Affine, q: &[f64], params: &[f64], tau: &mut [f64]) {
        let force = params[self.param] * self.deflection.eval(q);
        for &(c, a) in &value.terms {
            tau[c] -= a * force;
        }
    }
}

impl Law for Spring {
    fn labels(&self) -> &'static [&'static str] {
        &["spring"]
    }

    fn columns(&self, out: &mut Vec<(usize, &'static str, ParamKind)>) {
        out.push((self.param, "K", ParamKind::Spring));
    }

    #[inline(always)]
    fn add_regressor(&self, s: &Sample, p: usize, out: &mut [f64]) {
        let dl = self.deflection.eval(s.q);
        for &(coord, a) in &s.value.terms {
            out[coord * p + self.param] -= a * dl;
        }
    }

    // The spring's torque, in motion and held at rest.
    position_law!();

    fn nominal(&self, nominal: &Nominal, pi: &mut [f64]) -> Option<()> {
        pi[self.param] = nominal.k?;
        Some(())
    }

    fn bound_rows(&self, b: &BoundsContext, rows: &mut Vec<BoundRow>) {
        if let Some([lo, hi]) = b.frame.spring.filter(|_| b.use_frame) {
            let origin = BoundOrigin::Frame("spring");
            BoundRow::interval(self.param, (lo, origin), Some((hi, origin)), rows);
        }
    }

    fn clamp(&self, b: &BoundsContext, params: &mut [f64]) {
        if let Some([lo, hi]) = b.frame.spring.filter(|_| b.use_frame) {
            clamp_near(&mut params[self.param], lo, Some(hi));
        }
    }

    fn note(&self, n: &Note) -> Option<String> {
        Some(format!(
            "spring {} = {} of frame {} (deflection {})",
            n.names[self.param].name,
            n.params[self.param],
            n.frame,
            self.deflection.display(n.coordinates)
        ))
    }

    fn fingerprint(&self, numbers: &mut Vec<f64>, words: &mut Vec<String>) {
        numbers.push(self.param as f64);
        match &self.deflection {
            Deflection::Affine(a) => a.push_numbers(numbers),
            Deflection::Expr(e) => words.push(e.text().to_string()),
        }
    }

    fn wpi_fields(&self, params: &[f64]) -> Vec<(&'static str, f64)> {
        vec![("K", params[self.param])]
    }

    fn description(&self, coordinates: &[String]) -> String {
        format!("spring = {:?}", self.deflection.display(coordinates))
    }
}
