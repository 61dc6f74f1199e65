//! The excitation criterion (`docs/book/src/identification.md` §7) and its gradient: the
//! condition number or log-determinant of the column-normalized base regressor over a
//! grid of one period, with the optimizer's smooth surrogates (soft-max/soft-min of the
//! eigenvalues, `tanh` for the Coulomb columns' signs). [`super::optimize`] searches
//! over it; this module only evaluates.

// `!(x > 0.0)`-style tests are deliberate: they also catch NaN, which a reversed
// comparison would let through. Index loops mirror the math over several arrays.
#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    clippy::needless_range_loop,
    clippy::ptr_arg
)]

use dvrk_model::{BaseParameters, Model, Workspace};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::grid::Grid;
use super::lbfgs::dot;

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
    /// The name the command line, Python and results use (see [`crate::names`]).
    pub fn name(&self) -> &'static str {
        crate::names::Named::name(*self)
    }

    /// True when `a` is a better criterion value than `b`.
    pub fn better(&self, a: f64, b: f64) -> bool {
        match self {
            Criterion::Condition => a < b,
            Criterion::LogDet => a > b,
        }
    }

    /// The criterion's reported value from the optimizer's objective (`log cond` or
    /// `−log det`).
    pub(super) fn report(&self, objective: f64) -> f64 {
        match self {
            Criterion::Condition => objective.exp(),
            Criterion::LogDet => -objective,
        }
    }
}

impl crate::names::Named for Criterion {
    const WHAT: &'static str = "criterion";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("condition", Criterion::Condition),
        ("log_det", Criterion::LogDet),
        ("logdet", Criterion::LogDet),
    ];
    const CANONICAL: usize = 2;
}

impl std::str::FromStr for Criterion {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}

/// A criterion value with its name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CriterionValue {
    /// The criterion's name (`condition` or `log_det`).
    pub name: String,
    /// Its value as reported: the condition number (no units, ≥ 1), or `log det` (≤ 0).
    pub value: f64,
}

/// Relative step of the forward differences of the regressor in `q` and `q̇`.
const FD_STEP: f64 = 1e-7;

/// A Coulomb friction column of the regressor: the parameter, the terms of its frame's
/// joint value (`ṡ = Σ c·q̇_j`) and the velocity scale of its smoothing (1 for a
/// revolute joint, 0.1 for a prismatic one).
pub(super) struct CoulombColumn {
    pub(super) param: usize,
    pub(super) terms: Vec<(usize, f64)>,
    pub(super) scale: f64,
}

/// Evaluates the criterion (and its gradient) of coefficient vectors on a fixed grid.
pub(super) struct CriterionEval<'a> {
    pub(super) model: &'a Model,
    pub(super) cols: &'a [usize],
    pub(super) criterion: Criterion,
    pub(super) grid: Grid,
    pub(super) ws: Workspace,
    pub(super) buf: Vec<f64>,
    /// Condition criterion only: when finite, the optimizer's smooth surrogate, half the
    /// difference of the soft-max and soft-min (temperature `1/p`) of `log λ`, which
    /// tends to `log cond` as `p → ∞` and avoids the kinks where eigenvalues cross.
    pub(super) soft_p: f64,
    pub(super) coulomb: Vec<CoulombColumn>,
    pub(super) coulomb_eps: f64,
}

impl<'a> CriterionEval<'a> {
    pub(super) fn regress(&mut self, q: &[f64], dq: &[f64], ddq: &[f64]) {
        self.model
            .regressor_into(&mut self.ws, q, dq, ddq, &mut self.buf);
        if self.coulomb_eps > 0.0 {
            let p = self.model.n_params();
            for col in &self.coulomb {
                let sd: f64 = col.terms.iter().map(|&(j, c)| c * dq[j]).sum();
                let sg = (sd / (self.coulomb_eps * col.scale)).tanh();
                for &(j, c) in &col.terms {
                    self.buf[j * p + col.param] = c * sg;
                }
            }
        }
    }

    pub(super) fn new(
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
            coulomb: model
                .frames
                .iter()
                .flat_map(|f| {
                    let scale = if f.kind == dvrk_model::JointKind::Prismatic {
                        0.1
                    } else {
                        1.0
                    };
                    f.elements.iter().filter_map(move |e| {
                        Some(CoulombColumn {
                            param: e.sign_column()?,
                            terms: f.value.terms.clone(),
                            scale,
                        })
                    })
                })
                .collect(),
            coulomb_eps: 0.0,
        }
    }

    /// `φ = Σ B ⊙ H` of the regressor at one sample; `blk` is the sample's block of the
    /// criterion's gradient with respect to `Y`, laid out like the full regressor (n×p,
    /// row-major, zero in the dependent columns) so that `φ` is one contiguous dot
    /// product.
    pub(super) fn phi(&mut self, q: &[f64], dq: &[f64], ddq: &[f64], blk: &[f64]) -> f64 {
        self.regress(q, dq, ddq);
        dot(blk, &self.buf)
    }

    /// The objective (`log cond` or `−log det`) and, if `grad` is given, its gradient
    /// (overwritten). None when the regressor is rank deficient.
    pub(super) fn objective(&mut self, x: &[f64], grad: Option<&mut [f64]>) -> Option<f64> {
        let (n, r) = (self.model.dof(), self.cols.len());
        let (q, dq, ddq) = self.grid.eval(x, n);
        let (yn, norms) = self.normalized_regressor(&q, &dq, &ddq)?;
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
        let (obj, m) = self.criterion_of(&eig, imax, imin);
        if !obj.is_finite() {
            return None;
        }
        let Some(grad) = grad else { return Some(obj) };
        self.gradient((&q, &dq, &ddq), &yn, &norms, &m, grad);
        Some(obj)
    }

    /// The base regressor stacked over the grid's samples (`t·n × r`) with unit columns,
    /// and the columns' norms; None when a column is zero or not finite.
    pub(super) fn normalized_regressor(
        &mut self,
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
    ) -> Option<(DMatrix<f64>, Vec<f64>)> {
        let (n, p, r) = (self.model.dof(), self.model.n_params(), self.cols.len());
        let t = self.grid.len();
        let mut y = DMatrix::zeros(t * n, r);
        for k in 0..t {
            self.regress(&q[k * n..][..n], &dq[k * n..][..n], &ddq[k * n..][..n]);
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
        Some((yn, norms))
    }

    /// The criterion from the eigen-decomposition of the normalized Gram matrix (`imax`,
    /// `imin`: its largest and smallest eigenvalue), and the matrix `M` of its gradient
    /// (`d obj / d Yn = Yn·M`).
    pub(super) fn criterion_of(
        &self,
        eig: &nalgebra::linalg::SymmetricEigen<f64, nalgebra::Dyn>,
        imax: usize,
        imin: usize,
    ) -> (f64, DMatrix<f64>) {
        let r = self.cols.len();
        let lam = &eig.eigenvalues;
        let v = &eig.eigenvectors;
        match self.criterion {
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
        }
    }

    /// The objective's gradient with respect to `x` (overwritten into `grad`), from
    /// `M` through the column normalization, then per sample by differences of
    /// `φ_k = <G_k, Y_k(q, q̇, q̈)>`, then back through the grid.
    pub(super) fn gradient(
        &mut self,
        motion: (&[f64], &[f64], &[f64]),
        yn: &DMatrix<f64>,
        norms: &[f64],
        m: &DMatrix<f64>,
        grad: &mut [f64],
    ) {
        let (q, dq, ddq) = motion;
        let (n, p, r) = (self.model.dof(), self.model.n_params(), self.cols.len());
        let t = self.grid.len();
        // d obj / d Yn = Yn·M, then through the column normalization.
        let gn = yn * m;
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
        let mut blk = vec![0.0; n * p];
        // Row-major copies (transposes) so that each sample's block is read contiguously.
        let (gyt, ynt) = (gy.transpose(), yn.transpose());
        for k in 0..t {
            qk.copy_from_slice(&q[k * n..][..n]);
            dqk.copy_from_slice(&dq[k * n..][..n]);
            ddqk.copy_from_slice(&ddq[k * n..][..n]);
            let row0 = k * n;
            let mut phi0 = 0.0;
            for i in 0..n {
                for (c, &col) in self.cols.iter().enumerate() {
                    let g = gyt[(c, row0 + i)];
                    blk[i * p + col] = g;
                    phi0 += g * ynt[(c, row0 + i)] * norms[c];
                }
            }
            for j in 0..n {
                // Linear in q̈: exact forward difference.
                ddqk[j] += 1.0;
                gddq[k * n + j] = self.phi(&qk, &dqk, &ddqk, &blk) - phi0;
                ddqk[j] -= 1.0;
                // q̇ and q: forward differences (one regressor call each instead of
                // two: the gradient is 40 % cheaper, and its ~1e-7 relative error is
                // far below what L-BFGS notices).
                let h = FD_STEP * dqk[j].abs().max(1.0);
                let d0 = dqk[j];
                dqk[j] = d0 + h;
                gdq[k * n + j] = (self.phi(&qk, &dqk, &ddqk, &blk) - phi0) / h;
                dqk[j] = d0;
                let h = FD_STEP * qk[j].abs().max(1.0);
                let q0 = qk[j];
                qk[j] = q0 + h;
                gq[k * n + j] = (self.phi(&qk, &dqk, &ddqk, &blk) - phi0) / h;
                qk[j] = q0;
            }
        }
        grad.fill(0.0);
        self.grid.backprop(n, &gq, &gdq, &gddq, grad);
    }
}
