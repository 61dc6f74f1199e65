//! Optimal excitation trajectories (identification reference §7): choose the Fourier
//! coefficients (per coordinate `q0`, `a_l`, `b_l`, `l = 1..L`) that minimize the
//! condition number of the column-normalized base regressor stacked over one period
//! (or maximize its log-determinant, D-optimality), subject to position, velocity and
//! acceleration limits on affine combinations of the coordinates (the description's
//! `[[limits]]`), and optionally rest (zero velocity and acceleration) at the start and
//! end of the period.
//!
//! # Method
//!
//! * Criterion: the base regressor `Y` (columns `base.independent` of
//!   `model.regressor_into`) at `samples_per_harmonic · L` equally spaced instants of one
//!   period, its columns scaled to unit norm (`Yn`), and the eigenvalues `λ` of
//!   `Yn^T Yn`. `condition` = `sqrt(λmax/λmin)` (the optimizer works on its logarithm);
//!   `log_det` = `Σ log λ` (maximized). Its gradient with respect to the coefficients is
//!   analytic in `Yn` (eigenvectors) and chains through per-sample derivatives of the
//!   regressor with respect to `q`, `q̇`, `q̈` (central differences in `q`, `q̇`; exact
//!   forward difference in `q̈`, on which the regressor is linear).
//! * Limits are linear in the coefficients. They enter as a quadratic exterior penalty on
//!   a constraint grid (40 points per harmonic), with the bounds moved inward by a small
//!   margin, and a penalty weight raised in stages; L-BFGS with Armijo backtracking
//!   minimizes each stage. Rest at the ends (`Σ_l a_jl = 0`, `Σ_l l b_jl = 0` per
//!   coordinate) is a linear subspace kept by projection.
//! * Repair and check: a static point `x_s` inside all limits is found first (cyclic
//!   projections onto the slabs); an impossible set of limits is an error. Because the
//!   limits are linear, the segment from `x_s` to an optimized point is feasible up to an
//!   exactly computable step: the result is pulled back onto it if needed, then checked on
//!   a dense grid (≥ 1 kHz over the whole period). An infeasible result is an error.
//! * Multi-start from a seed (deterministic; starts run in parallel with rayon).
//!
//! Not implemented: Cartesian box limits on frame origins.

// `!(x > 0.0)`-style tests are deliberate: they also catch NaN, which a reversed
// comparison would let through. Index loops mirror the math over several arrays.
#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    clippy::needless_range_loop,
    clippy::ptr_arg
)]

use std::f64::consts::PI;

use dvrk_model::expr::{Expr, Scope};
use dvrk_model::{BaseParameters, Limit, Model, Workspace};
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{FourierError, FourierTrajectory};

/// The optimality criterion of an excitation trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// Condition number of the column-normalized base regressor (minimized).
    Condition,
    /// `log det(Yn^T Yn)` of the column-normalized base regressor (D-optimality,
    /// maximized; at most 0).
    LogDet,
}

impl Criterion {
    pub fn name(&self) -> &'static str {
        match self {
            Criterion::Condition => "condition",
            Criterion::LogDet => "log_det",
        }
    }

    /// True when `a` is a better criterion value than `b`.
    pub fn better(&self, a: f64, b: f64) -> bool {
        match self {
            Criterion::Condition => a < b,
            Criterion::LogDet => a > b,
        }
    }

    fn report(&self, objective: f64) -> f64 {
        match self {
            Criterion::Condition => objective.exp(),
            Criterion::LogDet => -objective,
        }
    }
}

/// A criterion value with its name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CriterionValue {
    pub name: String,
    pub value: f64,
}

/// Errors of the optimizer and evaluator.
#[derive(Debug, Error)]
pub enum ExciteError {
    /// The limits admit no trajectory (not even a static pose), or are malformed.
    #[error("impossible limits: {0}")]
    ImpossibleLimits(String),
    /// No start produced a trajectory that passes the dense feasibility check.
    #[error("no feasible trajectory found: {0}")]
    Infeasible(String),
    /// Bad options or a trajectory that does not fit the model.
    #[error("{0}")]
    Invalid(String),
    #[error(transparent)]
    Fourier(#[from] FourierError),
}

/// Options of [`optimize`].
#[derive(Clone, Debug)]
pub struct ExciteOptions {
    /// Number of harmonics `L`.
    pub order: usize,
    /// Base frequency `f0`, Hz.
    pub base_frequency_hz: f64,
    pub criterion: Criterion,
    /// Regressor samples per period per harmonic (criterion grid: this × `order`).
    pub samples_per_harmonic: usize,
    /// Independent random starts.
    pub starts: usize,
    /// Seed of the starts.
    pub seed: u64,
    /// L-BFGS iterations per penalty stage (5 stages).
    pub iterations_per_stage: usize,
    /// Zero velocity and acceleration at the start (and so the end) of the period.
    pub rest: bool,
    /// Bounds moved inward by this fraction of their range while optimizing.
    pub margin: f64,
    /// Rate of the dense feasibility check, Hz (at least 1000).
    pub check_rate_hz: f64,
    /// Condition criterion: optimize a smooth surrogate (soft-max/soft-min of the
    /// eigenvalues, sharpened stage by stage) before the exact criterion.
    pub smooth: bool,
    /// Warm start: the first start refines this trajectory (same order and base
    /// frequency), first pulled inside the limits toward a static pose if needed.
    pub init: Option<FourierTrajectory>,
}

impl Default for ExciteOptions {
    fn default() -> Self {
        ExciteOptions {
            order: 6,
            base_frequency_hz: 0.18,
            criterion: Criterion::Condition,
            samples_per_harmonic: 15,
            starts: 4,
            seed: 0,
            iterations_per_stage: 150,
            rest: false,
            margin: 0.005,
            check_rate_hz: 1000.0,
            smooth: true,
            init: None,
        }
    }
}

/// The worst (largest) limit excess on a grid; positive = violated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    /// The limit's expression (e.g. `1.2177*(q7 - q6)`).
    pub limit: String,
    /// `position`, `velocity` or `acceleration`.
    pub quantity: String,
    /// Time of the worst sample, s.
    pub time_s: f64,
    /// Value of the expression there.
    pub value: f64,
    /// The bound it is compared with.
    pub bound: f64,
    /// `value - bound` beyond the bound (positive: violated; negative: the tightest
    /// margin).
    pub excess: f64,
}

/// Result of the dense feasibility check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Feasibility {
    pub feasible: bool,
    /// Samples checked (whole period).
    pub samples: usize,
    pub rate_hz: f64,
    /// The largest excess over all limits and samples (None: no limits).
    pub worst: Option<Violation>,
    /// Every violated limit (position, velocity or acceleration of one expression) with
    /// its own worst sample, largest excess first.
    pub violated: Vec<Violation>,
}

/// Criterion and feasibility of a trajectory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    pub criterion: CriterionValue,
    pub feasibility: Feasibility,
}

/// An optimized trajectory with its evaluation.
#[derive(Clone, Debug)]
pub struct Excitation {
    pub trajectory: FourierTrajectory,
    pub evaluation: Evaluation,
    /// Criterion of the best result of each start (None: the start failed).
    pub starts: Vec<Option<f64>>,
}

impl Excitation {
    /// The output document: the trajectory keys (`order`, `base_frequency_hz`, `q0`,
    /// `a`, `b`, `coordinates`) plus `criterion` {`name`, `value`} and `feasibility`.
    pub fn to_json_value(&self) -> serde_json::Value {
        let mut doc = serde_json::to_value(&self.trajectory).expect("serializable");
        let obj = doc.as_object_mut().expect("object");
        obj.insert(
            "criterion".into(),
            serde_json::to_value(&self.evaluation.criterion).expect("serializable"),
        );
        obj.insert(
            "feasibility".into(),
            serde_json::to_value(&self.evaluation.feasibility).expect("serializable"),
        );
        doc
    }
}

// ---------------------------------------------------------------------------------
// Limits as linear rows
// ---------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Quantity {
    Position,
    Velocity,
    Acceleration,
}

impl Quantity {
    fn name(&self) -> &'static str {
        match self {
            Quantity::Position => "position",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
        }
    }
}

#[derive(Clone, Debug)]
struct Row {
    label: String,
    terms: Vec<(usize, f64)>,
    /// The affine offset for positions, 0 for rates.
    offset: f64,
    quantity: Quantity,
    lo: f64,
    hi: f64,
}

impl Row {
    fn shrunk(&self, margin: f64) -> (f64, f64) {
        let m = margin * (self.hi - self.lo);
        (self.lo + m, self.hi - m)
    }
}

fn rows_of(limits: &[Limit], n: usize) -> Result<Vec<Row>, ExciteError> {
    let mut rows = Vec::new();
    for lim in limits {
        if let Some(&(k, _)) = lim.expr.terms.iter().find(|(k, _)| *k >= n) {
            return Err(ExciteError::ImpossibleLimits(format!(
                "limit {}: coordinate index {k} beyond the model's {n}",
                lim.label
            )));
        }
        for (q, range) in [
            (Quantity::Position, lim.position),
            (Quantity::Velocity, lim.velocity),
            (Quantity::Acceleration, lim.acceleration),
        ] {
            let Some([lo, hi]) = range else { continue };
            if !(lo <= hi) {
                return Err(ExciteError::ImpossibleLimits(format!(
                    "limit {}: {} range [{lo}, {hi}] is empty",
                    lim.label,
                    q.name()
                )));
            }
            rows.push(Row {
                label: lim.label.clone(),
                terms: lim.expr.terms.clone(),
                offset: if q == Quantity::Position {
                    lim.expr.offset
                } else {
                    0.0
                },
                quantity: q,
                lo,
                hi,
            });
        }
    }
    Ok(rows)
}

/// A static pose inside every position limit (shrunk by `margin` of each range), by
/// cyclic projections onto the slabs; rates must allow 0 (a periodic motion has zero
/// mean velocity and acceleration).
fn static_point(rows: &[Row], n: usize, margin: f64) -> Result<Vec<f64>, ExciteError> {
    for r in rows {
        if r.quantity != Quantity::Position && !(r.lo <= 0.0 && 0.0 <= r.hi) {
            return Err(ExciteError::ImpossibleLimits(format!(
                "limit {}: the {} range [{}, {}] excludes 0, but a periodic motion's mean {} is 0",
                r.label,
                r.quantity.name(),
                r.lo,
                r.hi,
                r.quantity.name()
            )));
        }
    }
    let pos: Vec<&Row> = rows
        .iter()
        .filter(|r| r.quantity == Quantity::Position)
        .collect();
    let worst = |q: &[f64], margin: f64| {
        pos.iter()
            .map(|r| {
                let (lo, hi) = r.shrunk(margin);
                let v = r.offset + r.terms.iter().map(|&(k, c)| c * q[k]).sum::<f64>();
                (v - hi).max(lo - v)
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    for m in [0.2f64, 0.05, 0.0] {
        let m = m.max(margin);
        let mut q = vec![0.0; n];
        for _sweep in 0..20_000 {
            for r in &pos {
                let (lo, hi) = r.shrunk(m);
                let v = r.offset + r.terms.iter().map(|&(k, c)| c * q[k]).sum::<f64>();
                let target = v.clamp(lo, hi);
                let nn: f64 = r.terms.iter().map(|&(_, c)| c * c).sum();
                if target != v && nn > 0.0 {
                    for &(k, c) in &r.terms {
                        q[k] += c * (target - v) / nn;
                    }
                }
            }
            if pos.is_empty() || worst(&q, m) <= 1e-12 {
                break;
            }
        }
        if pos.is_empty() || worst(&q, margin) <= 0.0 {
            return Ok(q);
        }
    }
    let bad: Vec<String> = pos
        .iter()
        .filter(|r| r.terms.is_empty() && !(r.lo <= r.offset && r.offset <= r.hi))
        .map(|r| r.label.clone())
        .collect();
    Err(ExciteError::ImpossibleLimits(if bad.is_empty() {
        "no pose satisfies all position limits at once".to_string()
    } else {
        format!("constant limits out of range: {}", bad.join(", "))
    }))
}

// ---------------------------------------------------------------------------------
// Time grids and the coefficient vector x = [q0 (n); a (n×L); b (n×L)]
// ---------------------------------------------------------------------------------

struct Grid {
    times: Vec<f64>,
    order: usize,
    w: f64,
    sin: Vec<f64>,
    cos: Vec<f64>,
}

impl Grid {
    fn new(times: Vec<f64>, order: usize, f0: f64) -> Grid {
        let w = 2.0 * PI * f0;
        let mut sin = Vec::with_capacity(times.len() * order);
        let mut cos = Vec::with_capacity(times.len() * order);
        for &t in &times {
            for l in 0..order {
                let (s, c) = (w * (l + 1) as f64 * t).sin_cos();
                sin.push(s);
                cos.push(c);
            }
        }
        Grid {
            times,
            order,
            w,
            sin,
            cos,
        }
    }

    /// `count` equally spaced instants over one period `[0, 1/f0)`.
    fn uniform(count: usize, order: usize, f0: f64) -> Grid {
        let period = 1.0 / f0;
        Grid::new(
            (0..count)
                .map(|k| k as f64 * period / count as f64)
                .collect(),
            order,
            f0,
        )
    }

    fn len(&self) -> usize {
        self.times.len()
    }

    /// Positions, velocities, accelerations, row-major `len × n`.
    fn eval(&self, x: &[f64], n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let lo = self.order;
        let (mut q, mut dq, mut ddq) = (
            vec![0.0; self.len() * n],
            vec![0.0; self.len() * n],
            vec![0.0; self.len() * n],
        );
        for k in 0..self.len() {
            let (s, c) = (&self.sin[k * lo..][..lo], &self.cos[k * lo..][..lo]);
            for j in 0..n {
                let (a, b) = (&x[n + j * lo..][..lo], &x[n + n * lo + j * lo..][..lo]);
                let (mut p, mut v, mut acc) = (x[j], 0.0, 0.0);
                for l in 0..lo {
                    let wl = self.w * (l + 1) as f64;
                    p += (a[l] * s[l] - b[l] * c[l]) / wl;
                    v += a[l] * c[l] + b[l] * s[l];
                    acc += wl * (b[l] * c[l] - a[l] * s[l]);
                }
                q[k * n + j] = p;
                dq[k * n + j] = v;
                ddq[k * n + j] = acc;
            }
        }
        (q, dq, ddq)
    }

    /// Adds the gradient with respect to `x` of a function whose gradients with respect
    /// to the grid's positions, velocities, accelerations are `gq`, `gdq`, `gddq`.
    fn backprop(&self, n: usize, gq: &[f64], gdq: &[f64], gddq: &[f64], gx: &mut [f64]) {
        let lo = self.order;
        for k in 0..self.len() {
            let (s, c) = (&self.sin[k * lo..][..lo], &self.cos[k * lo..][..lo]);
            for j in 0..n {
                let (p, v, a) = (gq[k * n + j], gdq[k * n + j], gddq[k * n + j]);
                if p == 0.0 && v == 0.0 && a == 0.0 {
                    continue;
                }
                gx[j] += p;
                for l in 0..lo {
                    let wl = self.w * (l + 1) as f64;
                    gx[n + j * lo + l] += p * s[l] / wl + v * c[l] - a * wl * s[l];
                    gx[n + n * lo + j * lo + l] += -p * c[l] / wl + v * s[l] + a * wl * c[l];
                }
            }
        }
    }
}

fn row_value(r: &Row, k: usize, n: usize, q: &[f64], dq: &[f64], ddq: &[f64]) -> f64 {
    let src = match r.quantity {
        Quantity::Position => q,
        Quantity::Velocity => dq,
        Quantity::Acceleration => ddq,
    };
    r.offset
        + r.terms
            .iter()
            .map(|&(j, c)| c * src[k * n + j])
            .sum::<f64>()
}

/// Quadratic exterior penalty `mu Σ (excess / range)²` on the grid, gradient added to
/// `gx`.
fn penalty(
    x: &[f64],
    n: usize,
    grid: &Grid,
    rows: &[Row],
    margin: f64,
    mu: f64,
    gx: &mut [f64],
) -> f64 {
    let (q, dq, ddq) = grid.eval(x, n);
    let mut g = [vec![0.0; q.len()], vec![0.0; q.len()], vec![0.0; q.len()]];
    let mut total = 0.0;
    for k in 0..grid.len() {
        for r in rows {
            let v = row_value(r, k, n, &q, &dq, &ddq);
            let (lo, hi) = r.shrunk(margin);
            let e = if v > hi {
                v - hi
            } else if v < lo {
                v - lo
            } else {
                continue;
            };
            let range = (r.hi - r.lo).max(1e-12);
            total += mu * (e / range).powi(2);
            let d = 2.0 * mu * e / (range * range);
            let gi = match r.quantity {
                Quantity::Position => 0,
                Quantity::Velocity => 1,
                Quantity::Acceleration => 2,
            };
            for &(j, c) in &r.terms {
                g[gi][k * n + j] += d * c;
            }
        }
    }
    grid.backprop(n, &g[0], &g[1], &g[2], gx);
    total
}

/// The largest `s ≥ 0` such that `x0 + s (x1 − x0)` satisfies every row on the grid
/// (bounds shrunk by `margin`), assuming `x0` does; `inf` when unbounded.
fn max_step(x0: &[f64], x1: &[f64], n: usize, grid: &Grid, rows: &[Row], margin: f64) -> f64 {
    let (q0, dq0, ddq0) = grid.eval(x0, n);
    let (q1, dq1, ddq1) = grid.eval(x1, n);
    let mut s = f64::INFINITY;
    for k in 0..grid.len() {
        for r in rows {
            let v0 = row_value(r, k, n, &q0, &dq0, &ddq0);
            let v1 = row_value(r, k, n, &q1, &dq1, &ddq1);
            let (lo, hi) = r.shrunk(margin);
            let d = v1 - v0;
            if d > 0.0 {
                s = s.min(((hi - v0) / d).max(0.0));
            } else if d < 0.0 {
                s = s.min(((lo - v0) / d).max(0.0));
            }
        }
    }
    s
}

fn to_x(traj: &FourierTrajectory) -> Vec<f64> {
    let mut x = traj.q0.clone();
    for row in &traj.a {
        x.extend_from_slice(row);
    }
    for row in &traj.b {
        x.extend_from_slice(row);
    }
    x
}

fn from_x(x: &[f64], n: usize, order: usize, f0: f64, names: &[String]) -> FourierTrajectory {
    FourierTrajectory {
        order,
        base_frequency_hz: f0,
        q0: x[..n].to_vec(),
        a: (0..n)
            .map(|j| x[n + j * order..][..order].to_vec())
            .collect(),
        b: (0..n)
            .map(|j| x[n + n * order + j * order..][..order].to_vec())
            .collect(),
        coordinates: names.to_vec(),
    }
}

/// Projects a coefficient vector (or gradient) onto the rest subspace: per coordinate
/// `Σ_l a_jl = 0` (zero velocity at t = 0) and `Σ_l l·b_jl = 0` (zero acceleration).
fn project_rest(v: &mut [f64], n: usize, order: usize) {
    let lo = order;
    let wsum: f64 = (1..=lo).map(|l| (l * l) as f64).sum();
    for j in 0..n {
        let a = &mut v[n + j * lo..][..lo];
        let mean = a.iter().sum::<f64>() / lo as f64;
        a.iter_mut().for_each(|x| *x -= mean);
        let b = &mut v[n + n * lo + j * lo..][..lo];
        let dot: f64 = b.iter().enumerate().map(|(l, x)| (l + 1) as f64 * x).sum();
        b.iter_mut()
            .enumerate()
            .for_each(|(l, x)| *x -= dot * (l + 1) as f64 / wsum);
    }
}

// ---------------------------------------------------------------------------------
// The criterion and its gradient
// ---------------------------------------------------------------------------------

/// Evaluates the criterion (and its gradient) of coefficient vectors on a fixed grid.
struct CriterionEval<'a> {
    model: &'a Model,
    cols: &'a [usize],
    criterion: Criterion,
    grid: Grid,
    ws: Workspace,
    buf: Vec<f64>,
    /// Condition criterion only: when finite, the optimizer's smooth surrogate, half the
    /// difference of the soft-max and soft-min (temperature `1/p`) of `log λ`, which
    /// tends to `log cond` as `p → ∞` and avoids the kinks where eigenvalues cross.
    soft_p: f64,
}

impl<'a> CriterionEval<'a> {
    fn new(
        model: &'a Model,
        base: &'a BaseParameters,
        criterion: Criterion,
        samples: usize,
        order: usize,
        f0: f64,
    ) -> Self {
        CriterionEval {
            model,
            cols: &base.independent,
            criterion,
            grid: Grid::uniform(samples, order, f0),
            ws: Workspace::new(model),
            buf: vec![0.0; model.dof() * model.n_params()],
            soft_p: f64::INFINITY,
        }
    }

    /// `φ = Σ B ⊙ H_base` of the regressor at one sample; `blk` is the sample's n×r block
    /// of the criterion's gradient with respect to `Y`.
    fn phi(&mut self, q: &[f64], dq: &[f64], ddq: &[f64], blk: &DMatrix<f64>, row0: usize) -> f64 {
        let (n, p) = (self.model.dof(), self.model.n_params());
        self.model
            .regressor_into(&mut self.ws, q, dq, ddq, &mut self.buf);
        let mut s = 0.0;
        for i in 0..n {
            for (c, &col) in self.cols.iter().enumerate() {
                s += blk[(row0 + i, c)] * self.buf[i * p + col];
            }
        }
        s
    }

    /// The objective (`log cond` or `−log det`) and, if `grad` is given, its gradient
    /// (overwritten). None when the regressor is rank deficient.
    fn objective(&mut self, x: &[f64], grad: Option<&mut [f64]>) -> Option<f64> {
        let (n, p, r) = (self.model.dof(), self.model.n_params(), self.cols.len());
        let t = self.grid.len();
        let (q, dq, ddq) = self.grid.eval(x, n);
        let mut y = DMatrix::zeros(t * n, r);
        for k in 0..t {
            self.model.regressor_into(
                &mut self.ws,
                &q[k * n..][..n],
                &dq[k * n..][..n],
                &ddq[k * n..][..n],
                &mut self.buf,
            );
            for i in 0..n {
                for (c, &col) in self.cols.iter().enumerate() {
                    y[(k * n + i, c)] = self.buf[i * p + col];
                }
            }
        }
        let norms: Vec<f64> = (0..r).map(|c| y.column(c).norm()).collect();
        if norms.iter().any(|&d| !(d > 0.0 && d.is_finite())) {
            return None;
        }
        let mut yn = y;
        for (c, &d) in norms.iter().enumerate() {
            yn.column_mut(c).unscale_mut(d);
        }
        let gram = yn.tr_mul(&yn);
        let eig = gram.symmetric_eigen();
        let lam = &eig.eigenvalues;
        let (mut imax, mut imin) = (0, 0);
        for i in 0..r {
            if lam[i] > lam[imax] {
                imax = i;
            }
            if lam[i] < lam[imin] {
                imin = i;
            }
        }
        if !(lam[imin] > 0.0) {
            return None;
        }
        let v = &eig.eigenvectors;
        let (obj, m) = match self.criterion {
            Criterion::Condition if self.soft_p.is_finite() => {
                let pp = self.soft_p;
                let ll: Vec<f64> = lam.iter().map(|l| l.ln()).collect();
                let softmax = |sign: f64| {
                    let top = ll
                        .iter()
                        .map(|l| sign * l)
                        .fold(f64::NEG_INFINITY, f64::max);
                    let e: Vec<f64> = ll.iter().map(|l| (pp * (sign * l - top)).exp()).collect();
                    let z: f64 = e.iter().sum();
                    (
                        (top + z.ln() / pp) * sign,
                        e.into_iter().map(|x| x / z).collect::<Vec<_>>(),
                    )
                };
                let (smax, wp) = softmax(1.0);
                let (smin, wm) = softmax(-1.0);
                let mut m = DMatrix::zeros(r, r);
                for i in 0..r {
                    let c = (wp[i] - wm[i]) / lam[i];
                    if c != 0.0 {
                        let vi = v.column(i);
                        m += c * (vi * vi.transpose());
                    }
                }
                (0.5 * (smax - smin), m)
            }
            Criterion::Condition => {
                let obj = 0.5 * (lam[imax].ln() - lam[imin].ln());
                let v1 = v.column(imax);
                let vr = v.column(imin);
                let m = v1 * v1.transpose() / lam[imax] - vr * vr.transpose() / lam[imin];
                (obj, m)
            }
            Criterion::LogDet => {
                let obj = -lam.iter().map(|l| l.ln()).sum::<f64>();
                let inv = DMatrix::from_diagonal(&lam.map(|l| 1.0 / l));
                (obj, -2.0 * v * inv * v.transpose())
            }
        };
        if !obj.is_finite() {
            return None;
        }
        let Some(grad) = grad else { return Some(obj) };
        // d obj / d Yn = Yn·M, then through the column normalization.
        let gn = &yn * &m;
        let mut gy = gn;
        for c in 0..r {
            let dot = yn.column(c).dot(&gy.column(c));
            let ync = yn.column(c).clone_owned();
            let mut col = gy.column_mut(c);
            col.axpy(-dot, &ync, 1.0);
            col.unscale_mut(norms[c]);
        }
        // Per sample: derivatives of φ_k = <G_k, Y_k(q, q̇, q̈)>.
        let mut gq = vec![0.0; t * n];
        let mut gdq = vec![0.0; t * n];
        let mut gddq = vec![0.0; t * n];
        let mut qk = vec![0.0; n];
        let mut dqk = vec![0.0; n];
        let mut ddqk = vec![0.0; n];
        for k in 0..t {
            qk.copy_from_slice(&q[k * n..][..n]);
            dqk.copy_from_slice(&dq[k * n..][..n]);
            ddqk.copy_from_slice(&ddq[k * n..][..n]);
            let row0 = k * n;
            let mut phi0 = 0.0;
            for i in 0..n {
                for c in 0..r {
                    phi0 += gy[(row0 + i, c)] * yn[(row0 + i, c)] * norms[c];
                }
            }
            for j in 0..n {
                // Linear in q̈: exact forward difference.
                ddqk[j] += 1.0;
                gddq[k * n + j] = self.phi(&qk, &dqk, &ddqk, &gy, row0) - phi0;
                ddqk[j] -= 1.0;
                // q̇: central difference.
                let h = 1e-6 * dqk[j].abs().max(1.0);
                let d0 = dqk[j];
                dqk[j] = d0 + h;
                let fp = self.phi(&qk, &dqk, &ddqk, &gy, row0);
                dqk[j] = d0 - h;
                let fm = self.phi(&qk, &dqk, &ddqk, &gy, row0);
                dqk[j] = d0;
                gdq[k * n + j] = (fp - fm) / (2.0 * h);
                // q: central difference.
                let h = 1e-6 * qk[j].abs().max(1.0);
                let q0 = qk[j];
                qk[j] = q0 + h;
                let fp = self.phi(&qk, &dqk, &ddqk, &gy, row0);
                qk[j] = q0 - h;
                let fm = self.phi(&qk, &dqk, &ddqk, &gy, row0);
                qk[j] = q0;
                gq[k * n + j] = (fp - fm) / (2.0 * h);
            }
        }
        grad.fill(0.0);
        self.grid.backprop(n, &gq, &gdq, &gddq, grad);
        Some(obj)
    }
}

// ---------------------------------------------------------------------------------
// L-BFGS with Armijo backtracking
// ---------------------------------------------------------------------------------

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Minimizes `f` (value, gradient; `inf` = invalid point) from `x` for at most `iters`
/// iterations. Returns the final value.
fn lbfgs(f: &mut dyn FnMut(&[f64], &mut [f64]) -> f64, x: &mut Vec<f64>, iters: usize) -> f64 {
    let dim = x.len();
    let mem = 10;
    let mut g = vec![0.0; dim];
    let mut fx = f(x, &mut g);
    if !fx.is_finite() {
        return fx;
    }
    let mut ss: Vec<Vec<f64>> = Vec::new();
    let mut ys: Vec<Vec<f64>> = Vec::new();
    let mut xn = vec![0.0; dim];
    let mut gn = vec![0.0; dim];
    let mut small = 0;
    for _ in 0..iters {
        // Two-loop recursion.
        let mut d: Vec<f64> = g.iter().map(|v| -v).collect();
        let mut alpha = vec![0.0; ss.len()];
        for i in (0..ss.len()).rev() {
            let rho = 1.0 / dot(&ys[i], &ss[i]);
            alpha[i] = rho * dot(&ss[i], &d);
            for (dv, yv) in d.iter_mut().zip(&ys[i]) {
                *dv -= alpha[i] * yv;
            }
        }
        if let (Some(s), Some(y)) = (ss.last(), ys.last()) {
            let gamma = dot(s, y) / dot(y, y);
            d.iter_mut().for_each(|v| *v *= gamma);
        } else {
            let gnorm = dot(&g, &g).sqrt().max(1e-300);
            d.iter_mut().for_each(|v| *v *= 0.01 / gnorm);
        }
        for i in 0..ss.len() {
            let rho = 1.0 / dot(&ys[i], &ss[i]);
            let beta = rho * dot(&ys[i], &d);
            for (dv, sv) in d.iter_mut().zip(&ss[i]) {
                *dv += (alpha[i] - beta) * sv;
            }
        }
        let mut slope = dot(&g, &d);
        if !(slope < 0.0) {
            ss.clear();
            ys.clear();
            let gnorm = dot(&g, &g).sqrt().max(1e-300);
            d = g.iter().map(|v| -v * 0.01 / gnorm).collect();
            slope = dot(&g, &d);
            if !(slope < 0.0) {
                break;
            }
        }
        let mut step = 1.0;
        let mut fnew;
        loop {
            for i in 0..dim {
                xn[i] = x[i] + step * d[i];
            }
            fnew = f(&xn, &mut gn);
            if fnew.is_finite() && fnew <= fx + 1e-4 * step * slope {
                break;
            }
            step *= 0.5;
            if step < 1e-10 {
                return fx;
            }
        }
        let s: Vec<f64> = (0..dim).map(|i| xn[i] - x[i]).collect();
        let y: Vec<f64> = (0..dim).map(|i| gn[i] - g[i]).collect();
        if dot(&s, &y) > 1e-12 * dot(&y, &y).sqrt() * dot(&s, &s).sqrt() {
            ss.push(s);
            ys.push(y);
            if ss.len() > mem {
                ss.remove(0);
                ys.remove(0);
            }
        }
        let improvement = fx - fnew;
        x.copy_from_slice(&xn);
        g.copy_from_slice(&gn);
        fx = fnew;
        if improvement < 1e-9 * (1.0 + fx.abs()) {
            small += 1;
            if small >= 5 {
                break;
            }
        } else {
            small = 0;
        }
    }
    fx
}

// ---------------------------------------------------------------------------------
// Seeded normal samples (SplitMix64 + Box–Muller; deterministic everywhere)
// ---------------------------------------------------------------------------------

struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (2.0 * PI * self.uniform()).cos()
    }
}

// ---------------------------------------------------------------------------------
// Public API
// ---------------------------------------------------------------------------------

/// Number of samples of the dense check of a trajectory of base frequency `f0`.
fn dense_grid(order: usize, f0: f64, rate_hz: f64) -> Grid {
    let rate = rate_hz.max(1000.0);
    let count = ((rate / f0).ceil() as usize).max(2);
    Grid::uniform(count, order, f0)
}

fn check_grid(x: &[f64], n: usize, grid: &Grid, rows: &[Row], rate: f64) -> Feasibility {
    let (q, dq, ddq) = grid.eval(x, n);
    let mut per_row: Vec<Option<Violation>> = vec![None; rows.len()];
    for k in 0..grid.len() {
        for (r, slot) in rows.iter().zip(per_row.iter_mut()) {
            let v = row_value(r, k, n, &q, &dq, &ddq);
            let (excess, bound) = if v - r.hi >= r.lo - v {
                (v - r.hi, r.hi)
            } else {
                (r.lo - v, r.lo)
            };
            if slot.as_ref().is_none_or(|w| excess > w.excess) {
                *slot = Some(Violation {
                    limit: r.label.clone(),
                    quantity: r.quantity.name().into(),
                    time_s: grid.times[k],
                    value: v,
                    bound,
                    excess,
                });
            }
        }
    }
    let mut all: Vec<Violation> = per_row.into_iter().flatten().collect();
    all.sort_by(|a, b| b.excess.total_cmp(&a.excess));
    let worst = all.first().cloned();
    Feasibility {
        feasible: worst.as_ref().is_none_or(|w| w.excess <= 1e-9),
        samples: grid.len(),
        rate_hz: rate.max(1000.0),
        worst,
        violated: all.into_iter().filter(|v| v.excess > 1e-9).collect(),
    }
}

fn check_dof(model: &Model, traj: &FourierTrajectory) -> Result<(), ExciteError> {
    traj.validate("trajectory")?;
    if traj.dof() != model.dof() {
        return Err(ExciteError::Invalid(format!(
            "the trajectory has {} coordinates, model {} has {}",
            traj.dof(),
            model.name,
            model.dof()
        )));
    }
    Ok(())
}

/// Dense feasibility check of a trajectory against limits: every sample at `rate_hz`
/// (at least 1 kHz) over one whole period.
pub fn check_feasibility(
    model: &Model,
    traj: &FourierTrajectory,
    limits: &[Limit],
    rate_hz: f64,
) -> Result<Feasibility, ExciteError> {
    check_dof(model, traj)?;
    let rows = rows_of(limits, model.dof())?;
    let grid = dense_grid(traj.order, traj.base_frequency_hz, rate_hz);
    Ok(check_grid(&to_x(traj), model.dof(), &grid, &rows, rate_hz))
}

/// The criterion of a trajectory: the column-normalized base regressor at
/// `samples_per_harmonic · order` equally spaced instants of one period.
pub fn criterion_value(
    model: &Model,
    base: &BaseParameters,
    traj: &FourierTrajectory,
    criterion: Criterion,
    samples_per_harmonic: usize,
) -> Result<CriterionValue, ExciteError> {
    check_dof(model, traj)?;
    let samples = samples_per_harmonic.max(1) * traj.order;
    let mut ev = CriterionEval::new(
        model,
        base,
        criterion,
        samples,
        traj.order,
        traj.base_frequency_hz,
    );
    let value = match ev.objective(&to_x(traj), None) {
        Some(obj) => criterion.report(obj),
        None => match criterion {
            Criterion::Condition => f64::INFINITY,
            Criterion::LogDet => f64::NEG_INFINITY,
        },
    };
    Ok(CriterionValue {
        name: criterion.name().into(),
        value,
    })
}

/// Criterion and dense feasibility of any trajectory.
pub fn evaluate(
    model: &Model,
    base: &BaseParameters,
    traj: &FourierTrajectory,
    limits: &[Limit],
    criterion: Criterion,
    samples_per_harmonic: usize,
    check_rate_hz: f64,
) -> Result<Evaluation, ExciteError> {
    Ok(Evaluation {
        criterion: criterion_value(model, base, traj, criterion, samples_per_harmonic)?,
        feasibility: check_feasibility(model, traj, limits, check_rate_hz)?,
    })
}

/// The objective the optimizer minimizes (`log cond` or `−log det`) and its gradient with
/// respect to the coefficient vector `[q0; a (row per coordinate); b]` (exposed for
/// tests). None when the regressor is rank deficient. `soft_p`: the smooth surrogate's
/// sharpness for the condition criterion (`f64::INFINITY`: the exact `log cond`).
pub fn objective_and_gradient(
    model: &Model,
    base: &BaseParameters,
    traj: &FourierTrajectory,
    criterion: Criterion,
    samples_per_harmonic: usize,
    soft_p: f64,
) -> Option<(f64, Vec<f64>)> {
    let samples = samples_per_harmonic.max(1) * traj.order;
    let mut ev = CriterionEval::new(
        model,
        base,
        criterion,
        samples,
        traj.order,
        traj.base_frequency_hz,
    );
    ev.soft_p = soft_p;
    let x = to_x(traj);
    let mut g = vec![0.0; x.len()];
    let v = ev.objective(&x, Some(&mut g))?;
    Some((v, g))
}

/// Optimizes an excitation trajectory. `progress` counts the starts done (reported
/// from the worker threads).
pub fn optimize(
    model: &Model,
    base: &BaseParameters,
    limits: &[Limit],
    opts: &ExciteOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<Excitation, ExciteError> {
    let n = model.dof();
    let order = opts.order;
    let f0 = opts.base_frequency_hz;
    if order == 0 || !(f0 > 0.0 && f0.is_finite()) {
        return Err(ExciteError::Invalid(format!(
            "order must be ≥ 1 and the base frequency positive (got {order}, {f0})"
        )));
    }
    if opts.starts == 0 {
        return Err(ExciteError::Invalid("at least one start is needed".into()));
    }
    let rows = rows_of(limits, n)?;
    if let Some(t) = &opts.init {
        check_dof(model, t)?;
        if t.order != order || (t.base_frequency_hz - f0).abs() > 1e-12 * f0 {
            return Err(ExciteError::Invalid(format!(
                "the initial trajectory has order {} and f0 {} Hz, the options {order} and {f0} Hz",
                t.order, t.base_frequency_hz
            )));
        }
    }
    let xs = {
        let q = static_point(&rows, n, opts.margin)?;
        let mut x = vec![0.0; n * (2 * order + 1)];
        x[..n].copy_from_slice(&q);
        x
    };
    let samples = (opts.samples_per_harmonic.max(1) * order).max(base.rank().div_ceil(n) + 1);
    let cgrid = Grid::uniform((40 * order).max(200), order, f0);
    let dense = dense_grid(order, f0, opts.check_rate_hz);
    progress.stage("optimizing (starts)", Some(opts.starts as u64));
    let results: Vec<Option<(f64, Vec<f64>)>> = (0..opts.starts)
        .into_par_iter()
        .map(|start| {
            let out = run_start(
                model, base, opts, &rows, &xs, &cgrid, &dense, samples, start,
            );
            progress.advance(1);
            out
        })
        .collect();
    progress.finish();
    let mut best: Option<(f64, Vec<f64>)> = None;
    for (obj, x) in results.iter().flatten() {
        if best.as_ref().is_none_or(|(b, _)| obj < b) {
            best = Some((*obj, x.clone()));
        }
    }
    let Some((obj, x)) = best else {
        return Err(ExciteError::Infeasible(
            "every start failed (rank-deficient regressor or no feasible motion)".into(),
        ));
    };
    let trajectory = from_x(&x, n, order, f0, &model.coordinates);
    let feasibility = check_grid(&x, n, &dense, &rows, opts.check_rate_hz);
    if !feasibility.feasible {
        let w = feasibility.worst.as_ref().expect("violation");
        return Err(ExciteError::Infeasible(format!(
            "dense check: {} {} = {} beyond {} by {} at t = {} s",
            w.limit, w.quantity, w.value, w.bound, w.excess, w.time_s
        )));
    }
    Ok(Excitation {
        trajectory,
        evaluation: Evaluation {
            criterion: CriterionValue {
                name: opts.criterion.name().into(),
                value: opts.criterion.report(obj),
            },
            feasibility,
        },
        starts: results
            .iter()
            .map(|r| r.as_ref().map(|(o, _)| opts.criterion.report(*o)))
            .collect(),
    })
}

#[allow(clippy::too_many_arguments)]
fn run_start(
    model: &Model,
    base: &BaseParameters,
    opts: &ExciteOptions,
    rows: &[Row],
    xs: &[f64],
    cgrid: &Grid,
    dense: &Grid,
    samples: usize,
    start: usize,
) -> Option<(f64, Vec<f64>)> {
    let n = model.dof();
    let order = opts.order;
    let f0 = opts.base_frequency_hz;
    let dim = xs.len();
    let mut rng = Rng(opts
        .seed
        .wrapping_mul(0x2545_f491_4f6c_dd1d)
        .wrapping_add(start as u64 + 1));
    // Random oscillation, scaled per coordinate to half its room, then jointly.
    let mut d = vec![0.0; dim];
    for v in d.iter_mut().skip(n) {
        *v = rng.normal();
    }
    if opts.rest {
        project_rest(&mut d, n, order);
    }
    for j in 0..n {
        let mut dj = vec![0.0; dim];
        for l in 0..order {
            dj[n + j * order + l] = d[n + j * order + l];
            dj[n + n * order + j * order + l] = d[n + n * order + j * order + l];
        }
        let x1: Vec<f64> = xs.iter().zip(&dj).map(|(a, b)| a + b).collect();
        let s = max_step(xs, &x1, n, cgrid, rows, opts.margin);
        let scale = 0.5 * if s.is_finite() { s } else { 1.0 };
        for l in 0..order {
            d[n + j * order + l] *= scale;
            d[n + n * order + j * order + l] *= scale;
        }
    }
    let x1: Vec<f64> = match (&opts.init, start) {
        (Some(t), 0) => {
            let mut x = to_x(t);
            if opts.rest {
                project_rest(&mut x, n, order);
            }
            d = x.iter().zip(xs).map(|(a, b)| a - b).collect();
            x
        }
        _ => xs.iter().zip(&d).map(|(a, b)| a + b).collect(),
    };
    let s = max_step(xs, &x1, n, cgrid, rows, opts.margin);
    let scale = if s < 1.0 { 0.999 * s } else { 1.0 };
    let mut x: Vec<f64> = xs.iter().zip(&d).map(|(a, b)| a + scale * b).collect();

    let mut ev = CriterionEval::new(model, base, opts.criterion, samples, order, f0);
    ev.objective(&x, None)?;
    let mut pg = vec![0.0; dim];
    for (mu, p) in [
        (1.0, 4.0),
        (10.0, 10.0),
        (100.0, 30.0),
        (1e3, 100.0),
        (1e4, f64::INFINITY),
    ] {
        ev.soft_p = if opts.smooth { p } else { f64::INFINITY };
        let mut f = |x: &[f64], g: &mut [f64]| -> f64 {
            let Some(obj) = ev.objective(x, Some(g)) else {
                return f64::INFINITY;
            };
            pg.fill(0.0);
            let pen = penalty(x, n, cgrid, rows, opts.margin, mu, &mut pg);
            for (gi, pi) in g.iter_mut().zip(&pg) {
                *gi += pi;
            }
            if opts.rest {
                project_rest(g, n, order);
            }
            obj + pen
        };
        lbfgs(&mut f, &mut x, opts.iterations_per_stage);
    }
    ev.soft_p = f64::INFINITY;
    if opts.rest {
        // Remove the round-off drift out of the rest subspace.
        project_rest(&mut x, n, order);
    }
    // Pull back onto the segment from the static point if the dense grid needs it.
    let s = max_step(xs, &x, n, dense, rows, 0.0);
    if s < 1.0 {
        let s = s * (1.0 - 1e-9);
        for (xi, x0) in x.iter_mut().zip(xs) {
            *xi = x0 + s * (*xi - x0);
        }
    }
    let obj = ev.objective(&x, None)?;
    Some((obj, x))
}

/// Setpoints of one period at `rate_hz` in the MEASURED joint space (`q_meas = M q`):
/// a CSV with header `time,<measured joint names>` (s; rad or m), one row per sample.
pub fn setpoints_csv(
    model: &Model,
    traj: &FourierTrajectory,
    rate_hz: f64,
) -> Result<String, ExciteError> {
    check_dof(model, traj)?;
    if !(rate_hz > 0.0 && rate_hz.is_finite()) {
        return Err(ExciteError::Invalid(format!(
            "rate must be positive, got {rate_hz}"
        )));
    }
    let n = model.dof();
    let m = &model.measured.coupling;
    let count = (traj.period_s() * rate_hz).round().max(1.0) as usize;
    let mut out = String::from("time");
    for name in &model.measured.joints {
        out.push(',');
        out.push_str(name);
    }
    out.push('\n');
    let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in 0..count {
        let t = k as f64 / rate_hz;
        traj.eval(t, &mut q, &mut dq, &mut ddq);
        out.push_str(&format!("{t:.6}"));
        for i in 0..n {
            let v: f64 = (0..n).map(|j| m[(i, j)] * q[j]).sum();
            out.push_str(&format!(",{v:.9}"));
        }
        out.push('\n');
    }
    Ok(out)
}

/// Reads limits from a TOML file of `[[limits]]` tables (`expr`, and optional
/// `position`, `velocity`, `acceleration` ranges of numbers or constant expressions such
/// as `"-57*deg"`), like a description's. Expressions use the model's coordinate names;
/// `deg` and `pi` are known constants.
pub fn limits_from_toml_str(
    model: &Model,
    text: &str,
    source: &str,
) -> Result<Vec<Limit>, ExciteError> {
    let bad = |m: String| ExciteError::ImpossibleLimits(format!("{source}: {m}"));
    let doc: toml::Table = text
        .parse()
        .map_err(|e| bad(format!("not valid TOML: {e}")))?;
    let constants = vec![("deg".to_string(), PI / 180.0), ("pi".to_string(), PI)];
    let scope = Scope {
        constants: &constants,
        coordinates: &model.coordinates,
    };
    let Some(list) = doc.get("limits").and_then(|v| v.as_array()) else {
        return Err(bad("expected [[limits]] tables".into()));
    };
    let num = |v: &toml::Value, place: &str| -> Result<f64, ExciteError> {
        match v {
            toml::Value::Float(x) => Ok(*x),
            toml::Value::Integer(i) => Ok(*i as f64),
            toml::Value::String(s) => {
                let e = Expr::parse(s, &scope).map_err(|e| bad(format!("{place}: {e}")))?;
                if !e.is_constant() {
                    return Err(bad(format!("{place}: `{s}` is not a constant")));
                }
                Ok(e.eval(&vec![0.0; model.dof()]))
            }
            _ => Err(bad(format!(
                "{place}: expected a number or a constant expression"
            ))),
        }
    };
    let mut out = Vec::new();
    for (i, item) in list.iter().enumerate() {
        let t = item
            .as_table()
            .ok_or_else(|| bad(format!("limits[{i}] is not a table")))?;
        for k in t.keys() {
            if !["expr", "position", "velocity", "acceleration"].contains(&k.as_str()) {
                return Err(bad(format!("limits[{i}]: unknown key {k}")));
            }
        }
        let text = t
            .get("expr")
            .and_then(|v| v.as_str())
            .ok_or_else(|| bad(format!("limits[{i}]: missing expr")))?;
        let e = Expr::parse(text, &scope).map_err(|e| bad(format!("limits[{i}] ({text}): {e}")))?;
        let expr = e
            .affine(model.dof())
            .map_err(|e| bad(format!("limits[{i}] ({text}): not affine: {e}")))?;
        let mut ranges = [None; 3];
        for (r, key) in ["position", "velocity", "acceleration"].iter().enumerate() {
            if let Some(v) = t.get(*key) {
                let place = format!("limits[{i}].{key}");
                let arr = v
                    .as_array()
                    .filter(|a| a.len() == 2)
                    .ok_or_else(|| bad(format!("{place}: expected [low, high]")))?;
                ranges[r] = Some([num(&arr[0], &place)?, num(&arr[1], &place)?]);
            }
        }
        out.push(Limit {
            label: text.to_string(),
            expr,
            position: ranges[0],
            velocity: ranges[1],
            acceleration: ranges[2],
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_matches_eval_and_backprop_is_adjoint() {
        let traj = FourierTrajectory {
            order: 2,
            base_frequency_hz: 0.3,
            q0: vec![0.1, -0.2],
            a: vec![vec![0.3, -0.1], vec![0.2, 0.05]],
            b: vec![vec![0.1, 0.02], vec![-0.15, 0.0]],
            coordinates: vec![],
        };
        let grid = Grid::uniform(17, 2, 0.3);
        let x = to_x(&traj);
        let (q, dq, ddq) = grid.eval(&x, 2);
        let (mut a, mut b, mut c) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        for k in 0..17 {
            traj.eval(grid.times[k], &mut a, &mut b, &mut c);
            for j in 0..2 {
                assert!((a[j] - q[k * 2 + j]).abs() < 1e-12);
                assert!((b[j] - dq[k * 2 + j]).abs() < 1e-12);
                assert!((c[j] - ddq[k * 2 + j]).abs() < 1e-12);
            }
        }
        // <g, J x> = <J^T g, x> (the map x -> (q - q0 part, dq, ddq) is linear).
        let mut rng = Rng(3);
        let g: Vec<f64> = (0..3 * 34).map(|_| rng.normal()).collect();
        let mut gx = vec![0.0; x.len()];
        grid.backprop(2, &g[..34], &g[34..68], &g[68..], &mut gx);
        let lhs: f64 = (0..34)
            .map(|i| g[i] * q[i] + g[34 + i] * dq[i] + g[68 + i] * ddq[i])
            .sum();
        assert!((lhs - dot(&gx, &x)).abs() < 1e-9 * lhs.abs().max(1.0));
    }

    #[test]
    fn rest_projection_zeroes_start_rates() {
        let mut rng = Rng(5);
        let (n, order) = (3, 4);
        let mut x: Vec<f64> = (0..n * (2 * order + 1)).map(|_| rng.normal()).collect();
        project_rest(&mut x, n, order);
        let t = from_x(&x, n, order, 0.2, &[]);
        let (mut q, mut dq, mut ddq) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        t.eval(0.0, &mut q, &mut dq, &mut ddq);
        assert!(
            dq.iter().chain(&ddq).all(|v| v.abs() < 1e-12),
            "{dq:?} {ddq:?}"
        );
    }
}
