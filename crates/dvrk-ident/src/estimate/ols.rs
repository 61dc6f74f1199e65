//! Least squares on the base parameters, through the R factor (never normal equations).

use dvrk_model::BaseParameters;
use nalgebra::{DMatrix, DVector};

use crate::observation::Observation;

/// Least-squares estimate of the base parameters.
#[derive(Clone, Debug)]
pub struct BaseEstimate {
    /// β, in the order of [`BaseParameters::independent`].
    pub beta: Vec<f64>,
    /// Standard deviation of each β (same units), from `σ²·(H_bᵀW²H_b)⁻¹`.
    pub std: Vec<f64>,
    /// Residual variance `σ² = ‖W(H_b β − τ)‖² / (rows − r)`.
    pub sigma2: f64,
    /// Condition number of the weighted base regressor `W·H_b`.
    pub condition_number: f64,
}

/// Why the data do not determine the base parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct NotExcited {
    /// Names of the base parameters the data leave (almost) undetermined.
    pub parameters: Vec<String>,
    /// Observation rows (samples × coordinates) the data had; fewer than the base
    /// parameters is one way to fail.
    pub rows: usize,
}

/// Solves `min ‖W H_b β − W τ‖` from the full observation.
pub fn base_least_squares(
    obs: &Observation,
    base: &BaseParameters,
) -> Result<BaseEstimate, NotExcited> {
    let r = base.rank();
    let sel = obs.select(&base.independent);
    let rr = sel.r();
    let r11 = rr.view((0, 0), (r, r)).into_owned();
    let rhs = DVector::from_iterator(r, (0..r).map(|i| rr[(i, r)]));
    let rho = rr[(r, r)];
    let diag_max = (0..r).map(|i| r11[(i, i)].abs()).fold(0.0, f64::max);
    let weak: Vec<String> = (0..r)
        .filter(|&i| r11[(i, i)].abs() <= 1e-10 * diag_max || r11[(i, i)].is_nan())
        .map(|i| base.names[i].clone())
        .collect();
    if obs.rows() < r || !weak.is_empty() {
        return Err(NotExcited {
            parameters: if weak.is_empty() {
                base.names.clone()
            } else {
                weak
            },
            rows: obs.rows(),
        });
    }
    let beta = r11
        .solve_upper_triangular(&rhs)
        .expect("non-singular triangular factor");
    let dof = obs.rows().saturating_sub(r).max(1) as f64;
    let sigma2 = rho * rho / dof;
    let inv = r11
        .clone()
        .solve_upper_triangular(&DMatrix::identity(r, r))
        .expect("non-singular triangular factor");
    let std = (0..r)
        .map(|i| (sigma2 * inv.row(i).norm_squared()).sqrt())
        .collect();
    let sv = r11.singular_values();
    let condition_number = sv.max() / sv.min();
    Ok(BaseEstimate {
        beta: beta.iter().copied().collect(),
        std,
        sigma2,
        condition_number,
    })
}

/// A full parameter vector reproducing base parameters β: β on the kept columns and zero
/// elsewhere (`K·π = β` since `K` is the identity on the kept columns). Least squares
/// only determines β; this representative gives the same torques.
pub fn representative(base: &BaseParameters, beta: &[f64], n_params: usize) -> Vec<f64> {
    let mut pi = vec![0.0; n_params];
    for (&c, &b) in base.independent.iter().zip(beta) {
        pi[c] = b;
    }
    pi
}
