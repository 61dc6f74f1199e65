//! Expressions of the generalized coordinates, parsed by `exmex`.
//!
//! Constants are substituted as numbers at load time so that the evaluated expression only
//! has coordinates as variables; evaluation then fills a stack buffer, which keeps the
//! real-time path free of allocation.

use exmex::prelude::*;
use exmex::{Differentiate, FlatEx};

/// Largest number of distinct coordinates one expression may use (the stack buffer size).
pub const MAX_EXPR_VARS: usize = 16;

/// A parsed expression `f(q)` with constants already substituted.
#[derive(Clone, Debug)]
pub struct Expr {
    text: String,
    flat: FlatEx<f64>,
    /// For each exmex variable (alphabetical order), the coordinate index it reads.
    vars: Vec<usize>,
}

/// An affine function `s = a·q + b`, stored sparsely (only non-zero coefficients).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Affine {
    /// `(coordinate index, coefficient)` pairs, sorted by index, coefficients non-zero.
    pub terms: Vec<(usize, f64)>,
    /// Constant offset `b`.
    pub offset: f64,
}

impl Affine {
    /// A constant.
    pub fn constant(b: f64) -> Self {
        Affine {
            terms: Vec::new(),
            offset: b,
        }
    }

    /// `a·q + b`.
    #[inline]
    pub fn eval(&self, q: &[f64]) -> f64 {
        self.offset + self.dot(q)
    }

    /// `a·x` (no offset): the rate of the value for a coordinate rate `x`.
    #[inline]
    pub fn dot(&self, x: &[f64]) -> f64 {
        self.terms.iter().map(|&(k, c)| c * x[k]).sum()
    }

    /// True when the value does not depend on any coordinate.
    pub fn is_constant(&self) -> bool {
        self.terms.is_empty()
    }

    /// Dense coefficient row of length `n`.
    pub fn dense(&self, n: usize) -> Vec<f64> {
        let mut row = vec![0.0; n];
        for &(k, c) in &self.terms {
            row[k] = c;
        }
        row
    }

    /// A readable form such as `0.6697*q2 - 0.6697*q3 + q4`.
    pub fn display(&self, names: &[String]) -> String {
        let mut s = String::new();
        for &(k, c) in &self.terms {
            push_term(&mut s, c, &names[k]);
        }
        if self.offset != 0.0 || s.is_empty() {
            push_term(&mut s, self.offset, "");
        }
        s
    }
}

/// Appends `± c*name` to a linear-combination string (`name` empty for a constant).
pub(crate) fn push_term(s: &mut String, c: f64, name: &str) {
    let mag = c.abs();
    let mag_txt = format_coefficient(mag);
    if s.is_empty() {
        if c < 0.0 {
            s.push('-');
        }
    } else if c < 0.0 {
        s.push_str(" - ");
    } else {
        s.push_str(" + ");
    }
    if name.is_empty() {
        s.push_str(&mag_txt);
    } else if mag_txt == "1" {
        s.push_str(name);
    } else {
        s.push_str(&mag_txt);
        s.push('*');
        s.push_str(name);
    }
}

/// Formats a coefficient with 10 significant digits, trailing zeros removed, so that
/// expressions are stable across platforms and readable (`0.2159`, not `0.21590000000000004`).
pub(crate) fn format_coefficient(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let digits = 10 - 1 - x.abs().log10().floor() as i32;
    let txt = if (0..=17).contains(&digits) {
        format!("{:.*}", digits as usize, x)
    } else {
        format!("{:.9e}", x)
    };
    if txt.contains('.') && !txt.contains('e') {
        txt.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        txt
    }
}

/// Why an expression could not be used.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprError {
    /// exmex could not parse it.
    Parse(String),
    /// It names something that is neither a coordinate nor a constant.
    Unknown(String),
    /// It uses more than [`MAX_EXPR_VARS`] coordinates.
    TooManyVariables,
    /// It must be affine in the coordinates but is not.
    NotAffine,
    /// It must be constant but depends on coordinates.
    NotConstant(Vec<String>),
    /// Evaluation failed or gave a non-finite number.
    Eval(String),
}

impl std::fmt::Display for ExprError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ExprError::Parse(m) => write!(f, "cannot parse expression: {m}"),
            ExprError::Unknown(v) => write!(
                f,
                "unknown name `{v}` (not a coordinate nor a constant; predefined: pi, deg)"
            ),
            ExprError::TooManyVariables => {
                write!(f, "expression uses more than {MAX_EXPR_VARS} coordinates")
            }
            ExprError::NotAffine => write!(
                f,
                "must be affine in the coordinates (a·q + b), but it is not"
            ),
            ExprError::NotConstant(v) => {
                write!(f, "must be a constant but depends on {}", v.join(", "))
            }
            ExprError::Eval(m) => write!(f, "cannot evaluate: {m}"),
        }
    }
}

/// Names an expression may refer to: constants (with values) and coordinates (by index).
pub struct Scope<'a> {
    pub constants: &'a [(String, f64)],
    pub coordinates: &'a [String],
}

impl Expr {
    /// Parses `text`, substituting constants from the scope.
    pub fn parse(text: &str, scope: &Scope<'_>) -> Result<Expr, ExprError> {
        let raw = FlatEx::<f64>::parse(text).map_err(|e| ExprError::Parse(e.to_string()))?;
        for v in raw.var_names() {
            let known = scope.constants.iter().any(|(n, _)| n == v)
                || scope.coordinates.iter().any(|c| c == v);
            if !known {
                return Err(ExprError::Unknown(v.clone()));
            }
        }
        let mut sub = |var: &str| {
            scope
                .constants
                .iter()
                .find(|(n, _)| n == var)
                .map(|(_, val)| FlatEx::<f64>::from_num(*val))
        };
        let flat = raw
            .subs(&mut sub)
            .map_err(|e| ExprError::Parse(e.to_string()))?;
        let vars: Vec<usize> = flat
            .var_names()
            .iter()
            .map(|v| {
                scope
                    .coordinates
                    .iter()
                    .position(|c| c == v)
                    .expect("remaining variables are coordinates")
            })
            .collect();
        if vars.len() > MAX_EXPR_VARS {
            return Err(ExprError::TooManyVariables);
        }
        Ok(Expr {
            text: text.to_string(),
            flat,
            vars,
        })
    }

    /// The source text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// True when no coordinate appears.
    pub fn is_constant(&self) -> bool {
        self.vars.is_empty()
    }

    /// Evaluates at coordinates `q` without allocating. A failed evaluation gives NaN,
    /// which the callers' finiteness checks then report.
    #[inline]
    pub fn eval(&self, q: &[f64]) -> f64 {
        let mut buf = [0.0; MAX_EXPR_VARS];
        for (slot, &k) in buf.iter_mut().zip(&self.vars) {
            *slot = q[k];
        }
        self.flat.eval(&buf[..self.vars.len()]).unwrap_or(f64::NAN)
    }

    /// The value of a constant expression.
    pub fn constant_value(&self, coordinate_names: &[String]) -> Result<f64, ExprError> {
        if !self.is_constant() {
            let names = self
                .vars
                .iter()
                .map(|&k| coordinate_names[k].clone())
                .collect();
            return Err(ExprError::NotConstant(names));
        }
        let v = self
            .flat
            .eval(&[])
            .map_err(|e| ExprError::Eval(e.to_string()))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ExprError::Eval(format!("value is {v}")))
        }
    }

    /// Extracts `a` and `b` of an affine expression, checking affinity.
    ///
    /// The coefficients come from exmex's symbolic partial derivatives (exact for
    /// literals such as `1.0186`); affinity is then checked numerically: each derivative
    /// must be the same at several points and the expression must equal `a·q + b` there.
    pub fn affine(&self, n_coordinates: usize) -> Result<Affine, ExprError> {
        let n_vars = self.vars.len();
        let probes: [f64; 4] = [0.0, 0.731, -1.913, 2.417];
        let point =
            |p: usize, i: usize| probes[(p + 3 * i) % probes.len()] * (1.0 + 0.1 * i as f64);
        let mut terms = Vec::new();
        for (i, &k) in self.vars.iter().enumerate() {
            let d = self
                .flat
                .clone()
                .partial(i)
                .map_err(|e| ExprError::Parse(e.to_string()))?;
            let vals: Vec<f64> = (0..probes.len())
                .map(|p| {
                    let x: Vec<f64> = (0..n_vars).map(|j| point(p, j)).collect();
                    d.eval(&x).unwrap_or(f64::NAN)
                })
                .collect();
            let c = vals[0];
            if !c.is_finite() || vals.iter().any(|v| (v - c).abs() > 1e-12 * (1.0 + c.abs())) {
                return Err(ExprError::NotAffine);
            }
            if c != 0.0 {
                terms.push((k, c));
            }
        }
        terms.sort_by_key(|t| t.0);
        let zero = vec![0.0; n_vars];
        let b = self
            .flat
            .eval(&zero)
            .map_err(|e| ExprError::Eval(e.to_string()))?;
        if !b.is_finite() {
            return Err(ExprError::Eval(format!("value at q = 0 is {b}")));
        }
        let aff = Affine { terms, offset: b };
        // Value check at the probe points, in full coordinate space.
        for p in 1..probes.len() {
            let x: Vec<f64> = (0..n_vars).map(|j| point(p, j)).collect();
            let mut q = vec![0.0; n_coordinates];
            for (j, &k) in self.vars.iter().enumerate() {
                q[k] = x[j];
            }
            let exact = self.flat.eval(&x).unwrap_or(f64::NAN);
            let lin = aff.eval(&q);
            if !exact.is_finite() || (exact - lin).abs() > 1e-10 * (1.0 + exact.abs()) {
                return Err(ExprError::NotAffine);
            }
        }
        Ok(aff)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scope_names() -> (Vec<(String, f64)>, Vec<String>) {
        (
            vec![
                ("pi".into(), std::f64::consts::PI),
                ("l_RCC".into(), 0.4318),
                ("l_2H1".into(), 0.14454),
            ],
            vec!["q1".into(), "q2".into(), "q3".into()],
        )
    }

    #[test]
    fn affine_extraction_with_constants() {
        let (c, q) = scope_names();
        let scope = Scope {
            constants: &c,
            coordinates: &q,
        };
        let e = Expr::parse("q3 - l_RCC + l_2H1", &scope).unwrap();
        let a = e.affine(3).unwrap();
        assert_eq!(a.terms, vec![(2, 1.0)]);
        assert!((a.offset - (0.14454 - 0.4318)).abs() < 1e-15);
        let e = Expr::parse("-0.8306*q1 + 1.2178*q2 + pi/2", &scope).unwrap();
        let a = e.affine(3).unwrap();
        assert_eq!(a.terms, vec![(0, -0.8306), (1, 1.2178)]);
        assert!((a.offset - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    }

    #[test]
    fn nonlinear_is_rejected_and_unknown_named() {
        let (c, q) = scope_names();
        let scope = Scope {
            constants: &c,
            coordinates: &q,
        };
        let e = Expr::parse("sin(q1)", &scope).unwrap();
        assert_eq!(e.affine(3), Err(ExprError::NotAffine));
        let e = Expr::parse("q1*q2", &scope).unwrap();
        assert_eq!(e.affine(3), Err(ExprError::NotAffine));
        match Expr::parse("q1 + l_foo", &scope) {
            Err(ExprError::Unknown(v)) => assert_eq!(v, "l_foo"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn eval_nonlinear() {
        let (c, q) = scope_names();
        let scope = Scope {
            constants: &c,
            coordinates: &q,
        };
        let e = Expr::parse("sqrt(l_RCC^2 + q2^2)*cos(q2)", &scope).unwrap();
        let x: f64 = 0.3;
        let expect = (0.4318f64.powi(2) + x * x).sqrt() * x.cos();
        assert!((e.eval(&[9.0, x, -4.0]) - expect).abs() < 1e-15);
    }

    #[test]
    fn coefficient_format() {
        assert_eq!(format_coefficient(0.21590000000000004), "0.2159");
        assert_eq!(format_coefficient(1.0), "1");
        assert_eq!(format_coefficient(1234.5), "1234.5");
        let mut s = String::new();
        push_term(&mut s, 1.0, "L2xy");
        push_term(&mut s, -1.0, "L6xy");
        push_term(&mut s, 0.2159, "l2x");
        assert_eq!(s, "L2xy - L6xy + 0.2159*l2x");
    }
}
