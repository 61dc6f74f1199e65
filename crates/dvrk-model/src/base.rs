//! Base (identifiable) parameters: the largest set of parameter combinations that the
//! regressor determines, found numerically from random samples.
//!
//! Columns are scanned in parameter order and kept when they are independent of those
//! already kept (modified Gram–Schmidt with re-orthogonalization on the
//! column-normalized regressor). Every other column is a fixed linear combination of the
//! kept ones, which folds its parameter into theirs: `β = K·π`, `H_b = H[:, kept]`,
//! `H·π = H_b·β`. The samples come from a seeded generator, so the result is the same on
//! every run and machine.

use nalgebra::DMatrix;
use rand_chacha::rand_core::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::ModelError;
use crate::expr::push_term;
use crate::model::Model;
use crate::workspace::Workspace;

/// Relative residual below which a normalized column counts as dependent.
const RANK_TOL: f64 = 1e-8;
/// Coefficients below this magnitude are structural zeros (round-off of the samples).
const COEF_TOL: f64 = 1e-9;

/// The base parameters of a model.
#[derive(Clone, Debug)]
pub struct BaseParameters {
    /// Columns of the full regressor kept as the base regressor, increasing.
    pub independent: Vec<usize>,
    /// `β = K·π`, r×p.
    pub combination: DMatrix<f64>,
    /// Each base parameter as a readable combination, e.g. `L2xy + L6xy + 0.2159*l2x`.
    pub expressions: Vec<String>,
    /// The name of the leading (kept) parameter of each base parameter.
    pub names: Vec<String>,
}

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let u = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    lo + (hi - lo) * u
}

impl BaseParameters {
    /// Number of base parameters.
    pub fn rank(&self) -> usize {
        self.independent.len()
    }

    /// `β = K·π`.
    pub fn project(&self, params: &[f64]) -> Vec<f64> {
        (0..self.rank())
            .map(|r| {
                self.combination
                    .row(r)
                    .iter()
                    .zip(params)
                    .map(|(k, p)| k * p)
                    .sum()
            })
            .collect()
    }

    /// Selects the base columns of a row-major `rows × p` full regressor into a
    /// row-major `rows × r` buffer. Allocates nothing.
    pub fn select_into(&self, full: &[f64], p: usize, out: &mut [f64]) {
        let r = self.rank();
        let rows = full.len() / p;
        assert_eq!(out.len(), rows * r, "base regressor buffer size");
        for i in 0..rows {
            for (c, &k) in self.independent.iter().enumerate() {
                out[i * r + c] = full[i * p + k];
            }
        }
    }
}

impl Model {
    /// Random samples of the full regressor, stacked row-major `(samples·n) × p`, from
    /// a seeded generator (deterministic), taken in order as a path (the hysteresis
    /// states of Dahl elements follow it).
    pub fn random_regressor(&self, samples: usize, seed: u64) -> DMatrix<f64> {
        let (n, p) = (self.dof(), self.n_params());
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut ws = Workspace::new(self);
        let mut h = DMatrix::zeros(samples * n, p);
        let mut buf = vec![0.0; n * p];
        let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut load = vec![0.0; n];
        for s in 0..samples {
            for k in 0..n {
                q[k] = uniform(&mut rng, -std::f64::consts::PI, std::f64::consts::PI);
                dq[k] = uniform(&mut rng, -2.0, 2.0);
                ddq[k] = uniform(&mut rng, -2.0, 2.0);
            }
            // Load friction's load, a signal of its own (the measured torque in a fit);
            // drawn only for a model with load friction, so every other model's samples
            // stay those they always were.
            if !self.element_plan.load.is_empty() {
                for l in load.iter_mut() {
                    *l = uniform(&mut rng, 0.0, 2.0);
                }
                self.set_load(&mut ws, &load);
            }
            // The samples as a path: the hysteresis (Dahl) states move along it.
            self.advance_hysteresis(&mut ws, &q);
            self.regressor_into(&mut ws, &q, &dq, &ddq, &mut buf);
            for r in 0..n {
                for c in 0..p {
                    h[(s * n + r, c)] = buf[r * p + c];
                }
            }
        }
        h
    }

    /// The base parameters (rank, kept columns, combinations and their expressions).
    ///
    /// ```
    /// let model = dvrk_model::Model::builtin("mtm").unwrap();
    /// let base = model.base_parameters().unwrap();
    /// assert_eq!(base.rank(), 73);
    /// ```
    pub fn base_parameters(&self) -> Result<BaseParameters, ModelError> {
        let p = self.n_params();
        let samples = (4 * p / self.dof()).max(100);
        let h = self.random_regressor(samples, 0x5eed_d7e4);
        let rows = h.nrows();
        let norms: Vec<f64> = (0..p).map(|c| h.column(c).norm()).collect();
        let max_norm = norms.iter().cloned().fold(0.0, f64::max);
        // Modified Gram–Schmidt in column order on normalized columns.
        let mut basis: Vec<Vec<f64>> = Vec::new();
        let mut rmat: Vec<Vec<f64>> = Vec::new(); // rmat[c] = coefficients of column c on the basis
        let mut kept = Vec::new();
        let mut coords_of: Vec<Option<Vec<f64>>> = vec![None; p];
        for c in 0..p {
            if norms[c] <= 1e-12 * max_norm {
                coords_of[c] = Some(Vec::new()); // structurally zero column
                continue;
            }
            let mut v: Vec<f64> = h.column(c).iter().map(|x| x / norms[c]).collect();
            let mut coef = vec![0.0; basis.len()];
            for _pass in 0..2 {
                for (b, qb) in basis.iter().enumerate() {
                    let d: f64 = qb.iter().zip(&v).map(|(x, y)| x * y).sum();
                    coef[b] += d;
                    for (vi, qi) in v.iter_mut().zip(qb) {
                        *vi -= d * qi;
                    }
                }
            }
            let res: f64 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if res > RANK_TOL {
                for vi in v.iter_mut() {
                    *vi /= res;
                }
                basis.push(v);
                coef.push(res);
                rmat.push(coef);
                kept.push(c);
            } else {
                coords_of[c] = Some(coef);
            }
        }
        let r = kept.len();
        if r == 0 {
            return Err(ModelError::Numeric {
                model: self.name.clone(),
                message: "no parameter affects the torques".into(),
            });
        }
        // Upper-triangular R (r×r) with column j = rmat[j] padded.
        let mut rr = DMatrix::zeros(r, r);
        for (j, col) in rmat.iter().enumerate() {
            for (i, v) in col.iter().enumerate() {
                rr[(i, j)] = *v;
            }
        }
        let mut k = DMatrix::zeros(r, p);
        for (j, &c) in kept.iter().enumerate() {
            k[(j, c)] = 1.0;
        }
        for c in 0..p {
            let Some(coef) = &coords_of[c] else { continue };
            if coef.is_empty() {
                continue;
            }
            let mut b = nalgebra::DVector::zeros(r);
            for (i, v) in coef.iter().enumerate() {
                b[i] = *v;
            }
            let x = rr
                .solve_upper_triangular(&b)
                .ok_or_else(|| ModelError::Numeric {
                    model: self.name.clone(),
                    message: "singular triangular factor in base parameters".into(),
                })?;
            for (j, &kc) in kept.iter().enumerate() {
                let val = x[j] * norms[c] / norms[kc];
                if val.abs() > COEF_TOL {
                    k[(j, c)] = val;
                }
            }
        }
        // Check: H = H_b·K to round-off.
        let hb = h.select_columns(&kept);
        let err = (&hb * &k - &h).abs().max();
        if err > 1e-8 * max_norm * (rows as f64).sqrt() {
            return Err(ModelError::Numeric {
                model: self.name.clone(),
                message: format!("base parameter reconstruction error {err:e}"),
            });
        }
        let names = self.param_names();
        let expressions = (0..r)
            .map(|j| {
                let mut s = String::new();
                for c in 0..p {
                    let v = k[(j, c)];
                    if v != 0.0 {
                        push_term(&mut s, v, &names[c]);
                    }
                }
                s
            })
            .collect();
        Ok(BaseParameters {
            names: kept.iter().map(|&c| names[c].clone()).collect(),
            independent: kept,
            combination: k,
            expressions,
        })
    }
}
