//! The prior of the semidefinite fit (`--prior`): the entropic (log-det) divergence of
//! each link's pseudo-inertia from the prior's, as cones for Clarabel, the quadratic
//! pull of a link that only has a prior mass, and the limits on the prior's weight.

use clarabel::solver::SupportedConeT;
use dvrk_model::Model;
use nalgebra::Matrix4;

use super::constraints::link_length;
use super::constraints::Rows;
use super::error::SdpError;
use dvrk_model::inertia::pseudo_inertia;

/// The entropic prior's cones and objective terms (nothing without it).
pub(super) fn entropic_rows(
    rows: &mut Rows,
    q: &mut [f64],
    whitening: &[(usize, Matrix4<f64>)],
    s: &[f64],
    w: f64,
) {
    let p = s.len();
    // Entropic prior: per link, [[J̃, Z], [Zᵀ, diag(Z)]] ⪰ 0 and τᵢ ≤ log Zᵢᵢ, and
    // w·(tr J̃ − Σ τᵢ) in the objective.
    for (l, (p0, wh)) in whitening.iter().enumerate() {
        let first = p + 1 + LOGDET_VARS * l;
        let z = |i: usize, c: usize| first + lower_index(i, c);
        let tau = |i: usize| first + 10 + i;
        // J̃(π) = Σₖ πₖ·(L₀⁻¹·Pₖ·L₀⁻ᵀ), πₖ = sₖ·uₖ.
        let basis: Vec<Matrix4<f64>> = (0..10)
            .map(|k| {
                let mut e = [0.0; 10];
                e[k] = 1.0;
                wh * pseudo_inertia(&e) * wh.transpose()
            })
            .collect();
        for (k, bk) in basis.iter().enumerate() {
            q[p0 + k] += w * s[p0 + k] * bk.trace();
        }
        for i in 0..4 {
            q[tau(i)] = -w;
        }
        for col in 0..8 {
            for row in 0..=col {
                let at = rows.b.len();
                let scale = if row == col {
                    1.0
                } else {
                    std::f64::consts::SQRT_2
                };
                if col < 4 {
                    for (k, bk) in basis.iter().enumerate() {
                        let c = bk[(row, col)];
                        if c != 0.0 {
                            rows.ai.push(at);
                            rows.aj.push(p0 + k);
                            rows.av.push(-scale * c * s[p0 + k]);
                        }
                    }
                } else {
                    let c = col - 4;
                    // Top right: Z (lower triangular); bottom right: diag(Z).
                    let var = if row < 4 {
                        (row >= c).then(|| z(row, c))
                    } else {
                        (row - 4 == c).then(|| z(c, c))
                    };
                    if let Some(v) = var {
                        rows.ai.push(at);
                        rows.aj.push(v);
                        rows.av.push(-scale);
                    }
                }
                rows.b.push(0.0);
            }
        }
        rows.cones.push(SupportedConeT::PSDTriangleConeT(8));
        for i in 0..4 {
            // (τᵢ, 1, Zᵢᵢ) ∈ K_exp: e^τᵢ ≤ Zᵢᵢ.
            let at = rows.b.len();
            rows.ai.extend([at, at + 2]);
            rows.aj.extend([tau(i), z(i, i)]);
            rows.av.extend([-1.0, -1.0]);
            rows.b.extend([0.0, 1.0, 0.0]);
            rows.cones.push(SupportedConeT::ExponentialConeT());
        }
    }
}

/// A partial prior's links that have a positive prior mass but not all ten values
/// (they have no prior pseudo-inertia to whiten by): `(index of m, prior mass)`.
pub(super) fn mass_priors(
    model: &Model,
    prior: &[f64],
    whitening: &[(usize, Matrix4<f64>)],
) -> Vec<(usize, f64)> {
    model
        .frames
        .iter()
        .filter_map(|f| f.inertia)
        .filter(|p0| !whitening.iter().any(|(w0, _)| w0 == p0))
        .map(|p0| (p0 + 9, prior[p0 + 9]))
        .filter(|&(_, m0)| m0 > 0.0)
        .collect()
}

/// The entropic metric of a link whose prior gives its mass alone: the log-det
/// divergence of the pseudo-inertia's mass entry, `x − log x − 1` with `x = m/m₀` (the
/// 1×1 case of `d(J‖J₀)`), to second order: `(x − 1)²/2`. Zero at the prior mass,
/// independent of the units, so every such mass is pulled toward the same ratio to its
/// prior. (The exact form, an exponential cone per link, left 4 of 7 real PSM fits at
/// `AlmostSolved`, weights 1e-3 to 1e-1; the quadratic is a row of the objective's
/// second-order cone.)
pub(super) fn mass_divergence(m: f64, m0: f64) -> f64 {
    (m / m0 - 1.0).powi(2) / 2.0
}

/// Variables of one link's log-det block: `Z` (lower triangle) and `τ`.
pub(super) const LOGDET_VARS: usize = 14;

/// Index of `Z[i][c]`, `i ≥ c`, among the 10 lower-triangle entries (column by column).
pub(super) fn lower_index(i: usize, c: usize) -> usize {
    debug_assert!(i >= c && i < 4);
    // Columns 0..c hold 4 + 3 + ... entries.
    (0..c).map(|k| 4 - k).sum::<usize>() + (i - c)
}

/// Largest prior weight: the data term is about 1 at the solution, so beyond this the
/// data have no say, and on the bundled example a weight of 1e9 left the solver a
/// point outside the cone of its own divergence (1e6 solves).
pub const MAX_PRIOR_WEIGHT: f64 = 1e6;

/// Smallest positive prior weight: the pull of a smaller one is below what the solver
/// resolves (its gap tolerance is 1e-8 of a data term about 1), and on the bundled example
/// a weight of 1e-12 left it at AlmostSolved where 1e-9 solves.
pub const MIN_PRIOR_WEIGHT: f64 = 1e-9;

/// Why `weight` is not a prior weight, if it is not: 0 (no pull) or within
/// [[`MIN_PRIOR_WEIGHT`], [`MAX_PRIOR_WEIGHT`]] (tests/prior.rs:
/// `prior_weights_are_zero_or_in_range`).
pub fn prior_weight_problem(weight: f64) -> Option<String> {
    if weight == 0.0 || (MIN_PRIOR_WEIGHT..=MAX_PRIOR_WEIGHT).contains(&weight) {
        None
    } else {
        Some(format!(
            "must be 0 or in [{MIN_PRIOR_WEIGHT:e}, {MAX_PRIOR_WEIGHT:e}], got {}",
            dvrk_model::input::show(weight)
        ))
    }
}

/// Smallest eigenvalue of a prior's balanced pseudo-inertia `T·J₀·T` kept by the
/// entropic metric, relative to its largest.
pub const PRIOR_CONDITION: f64 = 1e-4;

/// Per link of `model` whose ten parameters all have a prior value: its Lxx index and
/// `L₀⁻¹` for the Cholesky factor of the prior's pseudo-inertia `J₀ = L₀·L₀ᵀ`,
/// conditioned; an error names a link whose `J₀` is not positive definite.
///
/// Conditioned: the eigenvalues of `T·J₀·T` (`T = diag(1, 1, 1, τ)` as in the LMI, so
/// the kg·m² and kg entries compare) are raised to at least [`PRIOR_CONDITION`] times
/// the largest. A prior from an earlier semidefinite fit of real data has every link at
/// the boundary `J ⪰ eps·I` (condition numbers about 1e7 on the dVRK): whitened by it,
/// the problem is so badly scaled that the solver stopped at `AlmostSolved` in 4 of 20
/// real-data fits (PSM and MTM, short logs, priors from the other trajectory, weights
/// 1e-3 to 10), none with it.
/// The change only touches directions in which the prior is a nearly flat mass
/// distribution; physical links (a solid rod 0.3 m × 1 cm: about 3e-3) are left alone.
pub(super) fn whitenings(
    model: &Model,
    prior: &[f64],
    override_bounds: bool,
) -> Result<Vec<(usize, Matrix4<f64>)>, SdpError> {
    let mut out = Vec::new();
    for (fi, f) in model.frames.iter().enumerate() {
        let Some(p0) = f.inertia else { continue };
        if prior[p0..p0 + 10].iter().any(|x| x.is_nan()) {
            // A partial prior's link: the Euclidean term on the values it has.
            continue;
        }
        let j0 = pseudo_inertia(&prior[p0..p0 + 10]);
        let eig = j0.symmetric_eigen();
        let inconsistent = || SdpError::PriorInconsistent {
            link: f.name.clone(),
            frame: fi + 1,
            min_eigenvalue: eig.eigenvalues.min(),
        };
        let min = eig.eigenvalues.min();
        if min.is_nan() || min <= 0.0 {
            return Err(inconsistent());
        }
        let tau = link_length(model, fi, override_bounds);
        let t = Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, 1.0, 1.0, tau));
        let t_inv = Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0, 1.0, 1.0, 1.0 / tau));
        let balanced = (t * j0 * t).symmetric_eigen();
        let floor = PRIOR_CONDITION * balanced.eigenvalues.max();
        let raised = balanced.eigenvalues.map(|l| l.max(floor));
        let conditioned = t_inv
            * balanced.eigenvectors
            * Matrix4::from_diagonal(&raised)
            * balanced.eigenvectors.transpose()
            * t_inv;
        let l0 = conditioned.cholesky().ok_or_else(inconsistent)?.l();
        let inv = l0.try_inverse().ok_or_else(inconsistent)?;
        if !inv.iter().all(|x| x.is_finite()) {
            return Err(inconsistent());
        }
        out.push((p0, inv));
    }
    Ok(out)
}

/// `d(J‖J₀) = tr(J̃) − log det J̃ − 4`, `J̃ = L₀⁻¹·J·L₀⁻ᵀ` (`whitening` = `L₀⁻¹`);
/// infinite when `J` is not positive definite.
pub(super) fn log_det_divergence(whitening: &Matrix4<f64>, bary: &[f64]) -> f64 {
    let jt = whitening * pseudo_inertia(bary) * whitening.transpose();
    match jt.cholesky() {
        Some(c) => {
            let log_det: f64 = (0..4).map(|i| 2.0 * c.l()[(i, i)].ln()).sum();
            jt.trace() - log_det - 4.0
        }
        None => f64::INFINITY,
    }
}
