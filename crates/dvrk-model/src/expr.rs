//! Expressions of the generalized coordinates, parsed by `exmex`.
//!
//! Constants stay exmex variables whose values are filled in at evaluation, with the
//! coordinates, from a stack buffer: evaluation then allocates nothing (exmex keeps up to
//! [`MAX_EXPR_NODES`] operands on the stack, so longer expressions are refused at load
//! time), and nothing recursive runs on the expression tree (deep trees would overflow
//! the stack).

use exmex::prelude::*;
use exmex::FlatEx;

/// Largest number of distinct names (coordinates and constants) in one expression: the
/// size of the evaluation buffer.
pub const MAX_EXPR_VARS: usize = 32;
/// Largest number of operands (numbers and names) in one expression: what exmex
/// evaluates on the stack.
pub const MAX_EXPR_NODES: usize = 32;

/// What an exmex variable reads.
#[derive(Clone, Copy, Debug)]
enum Slot {
    Coordinate(usize),
    Constant(f64),
}

/// A parsed expression `f(q)`.
#[derive(Clone, Debug)]
pub struct Expr {
    text: String,
    flat: FlatEx<f64>,
    /// For each exmex variable (alphabetical order), where its value comes from.
    slots: Vec<Slot>,
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
    /// The coordinate `q_k` itself (rad or m).
    pub fn coordinate(k: usize) -> Self {
        Affine {
            terms: vec![(k, 1.0)],
            offset: 0.0,
        }
    }

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
    /// Its numbers, for fingerprints (model hashes): the term count, each `(coordinate,
    /// coefficient)` pair, the offset.
    pub fn push_numbers(&self, numbers: &mut Vec<f64>) {
        numbers.push(self.terms.len() as f64);
        for (i, c) in &self.terms {
            numbers.push(*i as f64);
            numbers.push(*c);
        }
        numbers.push(self.offset);
    }

    /// Whether no coordinate appears (the value does not depend on `q`).
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

/// A number, or an expression string evaluated at load time.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(untagged)
)]
pub enum NumOrExpr {
    /// A plain number.
    Num(f64),
    /// An expression (constants, coordinates, arithmetic) evaluated when the file is
    /// loaded.
    Expr(String),
}

impl Default for NumOrExpr {
    fn default() -> Self {
        NumOrExpr::Num(0.0)
    }
}

/// Why an expression could not be used.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprError {
    /// exmex could not parse it.
    Parse(String),
    /// It names something that is neither a coordinate nor a constant.
    Unknown(String),
    /// It uses more than [`MAX_EXPR_VARS`] names.
    TooManyVariables,
    /// It has more operands than [`MAX_EXPR_NODES`] (count given).
    TooLong(usize),
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
                write!(
                    f,
                    "expression uses more than {MAX_EXPR_VARS} distinct names"
                )
            }
            ExprError::TooLong(n) => write!(
                f,
                "expression has {n} operands; at most {MAX_EXPR_NODES} are evaluated without \
                 allocation (split it with constants, or simplify it)"
            ),
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

/// So that callers can keep an expression error as the `source` of theirs.
impl std::error::Error for ExprError {}

/// Names an expression may refer to: constants (with values) and coordinates (by index).
pub struct Scope<'a> {
    /// Named constants of the description and their values.
    pub constants: &'a [(String, f64)],
    /// Coordinate names; a name's position is the coordinate's index in `q`.
    pub coordinates: &'a [String],
}

impl Expr {
    /// Parses `text`; names must be constants of the scope or coordinates.
    pub fn parse(text: &str, scope: &Scope<'_>) -> Result<Expr, ExprError> {
        let operands = count_operands(text);
        if operands > MAX_EXPR_NODES {
            return Err(ExprError::TooLong(operands));
        }
        let flat = FlatEx::<f64>::parse(text).map_err(|e| ExprError::Parse(e.to_string()))?;
        let mut slots = Vec::with_capacity(flat.var_names().len());
        for v in flat.var_names() {
            if let Some(k) = scope.coordinates.iter().position(|c| c == v) {
                slots.push(Slot::Coordinate(k));
            } else if let Some((_, val)) = scope.constants.iter().find(|(n, _)| n == v) {
                slots.push(Slot::Constant(*val));
            } else {
                return Err(ExprError::Unknown(v.clone()));
            }
        }
        if slots.len() > MAX_EXPR_VARS {
            return Err(ExprError::TooManyVariables);
        }
        Ok(Expr {
            text: text.to_string(),
            flat,
            slots,
        })
    }

    /// The source text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// True when no coordinate appears.
    pub fn is_constant(&self) -> bool {
        !self.slots.iter().any(|s| matches!(s, Slot::Coordinate(_)))
    }

    /// Evaluates at coordinates `q` without allocating. A failed evaluation gives NaN,
    /// which the callers' finiteness checks then report.
    #[inline]
    pub fn eval(&self, q: &[f64]) -> f64 {
        let mut buf = [0.0; MAX_EXPR_VARS];
        for (slot, s) in buf.iter_mut().zip(&self.slots) {
            *slot = match *s {
                Slot::Coordinate(k) => q[k],
                Slot::Constant(v) => v,
            };
        }
        self.flat.eval(&buf[..self.slots.len()]).unwrap_or(f64::NAN)
    }

    /// Coordinates the expression reads.
    fn coordinates(&self) -> impl Iterator<Item = usize> + '_ {
        self.slots.iter().filter_map(|s| match s {
            Slot::Coordinate(k) => Some(*k),
            Slot::Constant(_) => None,
        })
    }

    /// The value of a constant expression.
    pub fn constant_value(&self, coordinate_names: &[String]) -> Result<f64, ExprError> {
        if !self.is_constant() {
            let names = self
                .coordinates()
                .map(|k| coordinate_names[k].clone())
                .collect();
            return Err(ExprError::NotConstant(names));
        }
        let v = self.eval(&[]);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ExprError::Eval(format!("value is {v}")))
        }
    }

    /// Extracts `a` and `b` of an affine expression, checking affinity.
    ///
    /// `b = f(0)`; `a_k` from a symmetric difference over a wide step (the offset
    /// cancels), snapped to the shortest decimal within a few ulps, so that `1.0186*q5`
    /// gives exactly 1.0186. The expression must then equal `a·q + b` at several other
    /// points (a nonlinear term cannot pass).
    pub fn affine(&self, n_coordinates: usize) -> Result<Affine, ExprError> {
        let mut x = vec![0.0; n_coordinates];
        let b = self.eval(&x);
        if !b.is_finite() {
            return Err(ExprError::Eval(format!("value at q = 0 is {b}")));
        }
        let mut used: Vec<usize> = self.coordinates().collect();
        used.sort_unstable();
        used.dedup();
        let mut terms = Vec::new();
        for &k in &used {
            const STEP: f64 = 1048576.0; // 2^20: scaling by it is exact
            x[k] = STEP;
            let up = self.eval(&x);
            x[k] = -STEP;
            let down = self.eval(&x);
            x[k] = 0.0;
            let c = shortest_decimal((up - down) / (2.0 * STEP));
            if !c.is_finite() {
                return Err(ExprError::NotAffine);
            }
            // Round-off of `(c + b) − b` is far below any meaningful coefficient.
            if c.abs() > 1e-14 * (1.0 + b.abs()) {
                terms.push((k, c));
            }
        }
        let aff = Affine { terms, offset: b };
        let probes: [f64; 4] = [0.731, -1.913, 2.417, -0.377];
        for p in 0..probes.len() {
            for (i, &k) in used.iter().enumerate() {
                x[k] = probes[(p + i) % probes.len()] * (1.0 + 0.1 * i as f64);
            }
            let exact = self.eval(&x);
            let lin = aff.eval(&x);
            if !exact.is_finite() || (exact - lin).abs() > 1e-10 * (1.0 + exact.abs()) {
                return Err(ExprError::NotAffine);
            }
        }
        Ok(aff)
    }
}

/// The decimal with the fewest significant digits within 8 ulps of `x` (`x` itself if
/// none): undoes the round-off of a difference quotient for literal coefficients.
fn shortest_decimal(x: f64) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    let ulp = f64::EPSILON * x.abs();
    for digits in 1..=16 {
        if let Ok(c) = format!("{:.*e}", digits - 1, x).parse::<f64>() {
            if (c - x).abs() <= 8.0 * ulp {
                return c;
            }
        }
    }
    x
}

/// Numbers and names in `text` that are operands (not function names): an upper bound
/// of exmex's operand nodes.
fn count_operands(text: &str) -> usize {
    let chars: Vec<char> = text.chars().collect();
    let mut count = 0;
    let mut i = 0;
    while i < chars.len() {
        if chars[i].is_alphanumeric() || chars[i] == '_' || chars[i] == '.' {
            let start = i;
            while i < chars.len()
                && (chars[i].is_alphanumeric() || chars[i] == '_' || chars[i] == '.')
            {
                i += 1;
            }
            let mut j = i;
            while j < chars.len() && chars[j].is_whitespace() {
                j += 1;
            }
            let is_function = j < chars.len() && chars[j] == '(' && chars[start].is_alphabetic();
            if !is_function {
                count += 1;
            }
        } else {
            i += 1;
        }
    }
    count
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
