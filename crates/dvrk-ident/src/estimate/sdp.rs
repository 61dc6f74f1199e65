//! Physically consistent estimator: a semidefinite program solved with Clarabel.
//!
//! # Problem
//!
//! Over ALL `p = model.n_params()` parameters π (barycentric link parameters, friction,
//! motor inertia, spring; units as in [`dvrk_model::Param`]):
//!
//! ```text
//! minimize   ‖R[:, 0..p]·π − R[:, p]‖²  +  λ·Σᵢ dᵢ²·(πᵢ − priorᵢ)²
//! subject to J(π_link) ⪰ eps·I                       every link (4×4 pseudo-inertia)
//!            m_min ≤ m ≤ m_max,  m·r_min ≤ l ≤ m·r_max  frame bounds (mass, com box)
//!            tr(Q_E·J(π_link)) ≥ 0                  links with a bounding ellipsoid E
//!            Fc ≥ fc_min, Fv ≥ fv_min, Ia ≥ ia_min      global lower bounds
//!            Fc ≤ fc_max, Fv ≤ fv_max, |Fo| ≤ fo_max, Ia ≤ ia_max, K ∈ [k_min, k_max]
//! ```
//!
//! `R` is the (p+1)×(p+1) factor of the weighted observation `[W·H | W·τ] = Q·R`, so the
//! first term is `‖W·H·π − W·τ‖² = ‖R11·π − r1‖² + ρ²` without the tens of thousands of
//! rows (any square `R` with the same `RᵀR` works: all p+1 rows are used).
//!
//! # Bounding ellipsoids
//!
//! A link whose description gives a bounding ellipsoid `E` ([`dvrk_model::FrameBounds`]
//! `ellipsoid`, e.g. from a URDF's collision geometry or the dVRK's meshes) gets the row
//! `tr(Q_E·J) ≥ 0` ([`dvrk_model::inertia::Ellipsoid`]): with `J ⪰ 0` it is Wensing, Kim
//! & Slotine's condition (RA-L 2018) that the mass distribution can lie inside `E`. It
//! is linear in π, a row of the nonnegative cone like the mass bounds, and it bounds
//! what `J ⪰ 0` leaves free: the mass's spread (`tr(L)` from above) and, with the
//! mass, the first moment (the centre of mass inside `E`). Off with
//! [`SdpOptions::ellipsoids`] `false` or with `override_bounds`.
//!
//! # Regularization
//!
//! R11 is rank deficient: only the base parameters are identifiable, and the
//! pseudo-inertia constraints do not bound the inertia from above, so the optimum is
//! not unique and its non-identifiable part can run off inside an interior point method
//! (unregularized, the solver typically stops at `AlmostSolved`). The Tikhonov term pulls
//! those directions toward `prior` (zero when `None`). It is scale invariant:
//! `dᵢ = ‖R[:, i]‖` is the data's own scale of parameter i (for a column the data never
//! see, the median `d` of the parameters of the same kind and unit), so in the
//! equilibrated variables `uᵢ = dᵢ·πᵢ` the term is `λ·‖u − u_prior‖²` with
//! `λ = regularization · max diag(R̃ᵀR̃)`, `R̃ = R·diag(1/d)` (whose diagonal is all
//! ones): `regularization` is relative to the data and has no units.
//!
//! The price is a bias of about `λ/σ²` on a base direction whose equilibrated singular
//! value is σ. On noise-free synthetic PSM/MTM data (300 random samples) the base
//! parameters' torque-relative error is ≈ 700·λ, and the worst single base parameter's
//! relative error ≈ 3e8·λ; with 1% noise the noise dominates for any λ ≤ 1e-8. The
//! default 1e-12 keeps the bias below 1e-9 of the torque while every solve still ends
//! `Solved`; raise it (e.g. 1e-6) to pull the unidentifiable part toward a CAD `prior`.
//!
//! # Priors
//!
//! With [`SdpOptions::prior_weight`] `w > 0` the fit is regularized toward `prior`, in
//! one of two metrics ([`PriorMetric`]):
//!
//! - Euclidean: `w·‖u − u_prior‖²` in the equilibrated variables, i.e. the Tikhonov term
//!   above with weight `λ + w`: a parameter moved by `Δπᵢ` costs `w` times the share of
//!   `‖W·τ‖²` its column alone would move by that much.
//! - Entropic (Lee, Wensing & Park, T-RO 2020): for every link, the log-det (Bregman)
//!   divergence of its pseudo-inertia from the prior's,
//!   `d(J‖J₀) = tr(J̃) − log det J̃ − 4` with the whitened `J̃ = L₀⁻¹·J·L₀⁻ᵀ`
//!   (`J₀ = L₀·L₀ᵀ`), which is 0 at `J = J₀`, independent of the link frame and of
//!   the units, and infinite at the boundary of physical consistency; the other
//!   parameters (friction, motor inertia, spring) keep the Euclidean term. The prior's
//!   pseudo-inertias must be positive definite; nearly singular ones (an earlier
//!   semidefinite fit leaves its links at `J ⪰ eps·I`) are conditioned first (see
//!   [`PRIOR_CONDITION`](prior::PRIOR_CONDITION)).
//!
//! A **partial prior** has values for some parameters only (NaN for the others in
//! [`SdpOptions::prior`]), e.g. the link masses a robot's maker publishes and nothing
//! else. The prior term covers only the parameters with a value: the entropic metric
//! takes the links whose ten parameters all have one as above, and a link whose prior
//! gives its mass (but not all ten) by the divergence of the pseudo-inertia's mass
//! entry alone, `x − log x − 1` with `x = m/m₀` (the 1×1 case), to second order
//! `(x − 1)²/2`: scale free, so every such mass is pulled toward the same ratio to its
//! prior; the Euclidean term takes every other parameter with a value (and, with the
//! Euclidean metric, all of them); the rest keep only the regularization toward zero,
//! as without a prior. A mass whose column the data do not see (a link on a joint axis)
//! lies in the regressor's null space, so a weak weight moves it (and the parameters it
//! trades with along the null space) without moving the base parameters beyond the
//! noise: the book's identification chapter, §6.5, measures it on the dVRK.
//!
//! Both read as `‖W·H·π − W·τ‖²/ρ² + w·distance`, with `ρ` the least-squares residual
//! (at least 0.1 % of `‖W·τ‖`): the data term is about 1 at the solution whatever the
//! noise, and a weight `w` makes a divergence of 1 cost `w` times the best residual (for
//! the Euclidean metric both terms are torques, so `ρ` does not move its solution). The
//! entropic cone is scaled that way: scaled by `‖W·τ‖²` instead, a nearly exact fit
//! leaves a data term of 1e-6 beside a divergence of order `w`, and the solver stalled
//! at `AlmostSolved` (the bundled example, prior weights 1e-4 and 1e-2).
//!
//! # Formulation for Clarabel
//!
//! Variables `x = [u; t]` with `πᵢ = sᵢ·uᵢ`, `sᵢ = γ/dᵢ`, `γ = ‖R[:, p]‖ = ‖W·τ‖`, so
//! that u = O(1) and the residual norm is at most about 1. Second-order cone epigraph:
//! minimize t subject to `‖[R̃·u − R[:, p]/γ; √λ·(u − u_prior)]‖ ≤ t` (one cone of
//! dimension 2p+2; the same minimizer as the squared objective, but the solver's gap
//! tolerance then bounds the residual norm instead of its square, which matters when the
//! fit is nearly exact). Linear bounds are rows of a nonnegative cone, each normalized
//! to a unit largest coefficient. Each link's LMI is one `PSDTriangleConeT(4)` on
//! `T·(J − eps·I)·T` with `T = diag(1, 1, 1, τ)`, τ a length of the link (its largest
//! com-box bound, 0.1 m without one): a congruence, so it is the same constraint, but it
//! balances the kg·m², kg·m and kg entries of J. Clarabel's triangle convention: upper
//! triangle, column-major, off-diagonals ×√2.
//!
//! The entropic prior needs the squared residual, so the data cone is then the rotated
//! `‖v‖² ≤ t` (as `‖(v, (t−1)/2)‖ ≤ (t+1)/2`), with `v` the residual and the Euclidean
//! rows; per link, `Σᵢ τᵢ ≤ log det J̃` is the standard construction with a
//! lower-triangular `Z`: `[[J̃, Z], [Zᵀ, diag(Z)]] ⪰ 0` (one `PSDTriangleConeT(8)`) and
//! `τᵢ ≤ log Zᵢᵢ` (`(τᵢ, 1, Zᵢᵢ)` in an `ExponentialConeT`); the objective adds
//! `w·Σ_links (tr(J̃) − Σᵢ τᵢ)`. A mass-only prior link adds the row `√(w/2)·(m/m₀ − 1)`
//! to the data cone (times `ρ/γ` in the plain cone when no link has a log-det block).
//!
//! After a `Solved` status the friction, motor inertia and spring parameters (which
//! appear in no other constraint) are clamped into their bounds, and each Stribeck term
//! onto `Fc + Fs ≥ 0`, removing the solver's feasibility tolerance; link parameters are the solver's values (bounds and
//! `J ⪰ eps·I` hold to the tolerance).

use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SupportedConeT};
use dvrk_model::{BoundsContext, Model};
use nalgebra::{DMatrix, Matrix4};

mod constraints;
mod error;
mod options;
mod prior;
use constraints::{linear_rows, lmi_rows_of_links, Rows};
pub use error::SdpError;
pub use options::{PriorMetric, SdpOptions};
pub(crate) use prior::prior_weight_problem;
use prior::{
    entropic_rows, log_det_divergence, mass_divergence, mass_priors, whitenings, LOGDET_VARS,
};

/// Result of [`solve_sdp`]. Only trust `params` when `converged`.
#[derive(Clone, Debug)]
pub struct SdpSolution {
    /// All model parameters, in model order and units (the solver's last iterate, or a
    /// meaningless certificate when infeasible, if not converged).
    pub params: Vec<f64>,
    /// Clarabel's status (`Solved`, `AlmostSolved`, `PrimalInfeasible`,
    /// `MaxIterations`, ...).
    pub status: super::SolverStatus,
    /// True only for status `Solved` (not `AlmostSolved`).
    pub converged: bool,
    /// Wall time of the whole call: building the problem and solving (s).
    pub seconds: f64,
    /// Interior point iterations.
    pub iterations: u32,
    /// `‖R11·π − r1‖² + ρ² = ‖W·H·π − W·τ‖²` at `params` (the weighted residual sum of
    /// squares, without the regularization term). The unit tests check it against
    /// references; the fit reports its own metrics.
    #[cfg_attr(not(test), allow(dead_code))]
    pub objective: f64,
    /// With an entropic prior: `Σ_links d(J‖J₀)` at `params` over the links the prior
    /// gives all ten values, plus `(m/m₀ − 1)²/2` of those it gives a mass alone (no
    /// units; 0 at the prior); `None` without such links.
    pub divergence: Option<f64>,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    Some(v[v.len() / 2])
}

/// The physically consistent fit: minimizes `‖R11·π − r1‖² + ρ²` (plus the small
/// regularization of [`SdpOptions::regularization`]) over all model parameters subject
/// to the model's consistency constraints and bounds (see the module documentation).
///
/// `r` is the (p+1)×(p+1) R factor of `[W·H | W·τ]` over all `p = model.n_params()`
/// parameters (last column the torque). A problem the solver cannot solve (infeasible
/// bounds, iteration limit, numerical trouble) is returned with `converged = false` and
/// Clarabel's status; only malformed input is an error.
pub fn solve_sdp(
    model: &Model,
    r: &DMatrix<f64>,
    options: &SdpOptions,
) -> Result<SdpSolution, SdpError> {
    let started = Instant::now();
    #[cfg(feature = "rust-lapack")]
    lapack_faer::link();
    let prior = check_inputs(model, r, options)?;
    let p = model.n_params();
    let eps = model.bounds.pseudo_inertia_eps;
    let (s, gamma) = scaling(model, r);
    let entropic_metric =
        options.prior_weight > 0.0 && options.prior_metric == PriorMetric::Entropic;
    // Per link: the Lxx index and the whitening `L₀⁻¹` of the prior's pseudo-inertia.
    let whitening: Vec<(usize, Matrix4<f64>)> = if entropic_metric {
        whitenings(model, &prior, options.override_bounds)?
    } else {
        Vec::new()
    };
    // A partial prior's links with a mass but not all ten values: the mass's own
    // divergence (index of m, prior mass).
    let masses: Vec<(usize, f64)> = if entropic_metric {
        mass_priors(model, &prior, &whitening)
    } else {
        Vec::new()
    };
    // The log-det cones need the squared residual (the rotated cone, see the module
    // documentation); mass-only divergences are quadratic and fit the plain cone, which
    // Clarabel solves with its own equilibration (the rotated cone without log-det
    // blocks stopped at `AlmostSolved` on a planar two-link arm).
    let penalty = Penalty {
        lambda: options.regularization,
        w: options.prior_weight,
        entropic: !whitening.is_empty(),
    };
    let entropic = penalty.entropic;
    // The parameters the entropic terms cover (the others with a value: Euclidean).
    let mut covered = vec![false; p];
    for (p0, _) in &whitening {
        covered[*p0..*p0 + 10].iter_mut().for_each(|x| *x = true);
    }
    for (k, _) in &masses {
        covered[*k] = true;
    }

    // --- Variables x = [u (p); t; per entropic link: Z (10, lower triangle), τ (4)].
    // Without an entropic prior: minimize t subject to
    // ‖[R̃·u − R[:, p]/γ; √(λ + w)·(u − u_prior)]‖ ≤ t (one second-order cone). With it:
    // minimize t + w·Σ(tr J̃ − Σ τ) subject to ‖[R̃·u − R[:, p]/γ; √λ·(u − u_prior);
    // √w·(u − u_prior) on the other parameters]‖² ≤ t. ---
    let n = p + 1 + LOGDET_VARS * whitening.len();
    let pmat = CscMatrix::zeros((n, n));
    let mut q = vec![0.0; n];
    q[p] = 1.0;
    let mut rows = Rows::default();
    objective_rows(
        &mut rows,
        r,
        (&s, gamma),
        &prior,
        &penalty,
        (&covered, &masses),
    );
    linear_rows(&mut rows, model, &s, options)?;
    lmi_rows_of_links(&mut rows, model, &s, eps, options.override_bounds);
    entropic_rows(&mut rows, &mut q, &whitening, &s, penalty.w);
    let Rows {
        ai,
        aj,
        av,
        b,
        cones,
    } = rows;
    let m_rows = b.len();
    let amat = CscMatrix::new_from_triplets(m_rows, n, ai, aj, av);

    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(options.max_iter)
        .tol_gap_abs(options.tolerance)
        .tol_gap_rel(options.tolerance)
        .tol_feas(options.tolerance)
        // The entropic problem is scaled here (data in the currency of its residual,
        // whitened pseudo-inertias); Clarabel's own equilibration of it left 2 of 20
        // real-data fits (MTM, weights 1e-3 and 1e-2) at `AlmostSolved`, none without.
        .equilibrate_enable(!entropic)
        .build()
        .map_err(|e| SdpError::Solver(e.to_string()))?;
    let mut solver = DefaultSolver::new(&pmat, &q, &amat, &b, &cones, settings)
        .map_err(|e| SdpError::Solver(format!("{e:?}")))?;
    solver.solve();
    let sol = &solver.solution;
    let mut params: Vec<f64> = (0..p).map(|i| s[i] * sol.x[i]).collect();
    let status = super::SolverStatus::from(sol.status);
    let converged = status.converged();
    if converged {
        clamp_element_bounds(model, &mut params, options.override_bounds);
    }
    let objective = residual_sum_of_squares(r, &params);
    let divergence = (entropic_metric && !(whitening.is_empty() && masses.is_empty())).then(|| {
        let links: f64 = whitening
            .iter()
            .map(|(p0, wh)| log_det_divergence(wh, &params[*p0..*p0 + 10]))
            .sum();
        let alone: f64 = masses
            .iter()
            .map(|&(k, m0)| mass_divergence(params[k], m0))
            .sum();
        links + alone
    });
    Ok(SdpSolution {
        params,
        status,
        converged,
        seconds: started.elapsed().as_secs_f64(),
        iterations: sol.iterations,
        objective,
        divergence,
    })
}

/// Refuses a malformed problem (R's size, non-finite values, options out of range, a
/// prior of the wrong length); returns the prior values (zeros without a prior).
fn check_inputs(
    model: &Model,
    r: &DMatrix<f64>,
    options: &SdpOptions,
) -> Result<Vec<f64>, SdpError> {
    let p = model.n_params();
    let np1 = p + 1;
    if r.nrows() != np1 || r.ncols() != np1 {
        return Err(SdpError::Dimension {
            model: model.name.clone(),
            rows: r.nrows(),
            cols: r.ncols(),
            expected: np1,
            params: p,
        });
    }
    if r.iter().any(|x| !x.is_finite()) {
        return Err(SdpError::NonFinite {
            what: "the R factor".into(),
        });
    }
    if !(options.regularization.is_finite() && options.regularization >= 0.0) {
        return Err(SdpError::Option {
            name: "regularization",
            message: format!("must be finite and >= 0, got {}", options.regularization),
        });
    }
    if let Some(message) = prior_weight_problem(options.prior_weight) {
        return Err(SdpError::Option {
            name: "prior_weight",
            message,
        });
    }
    if options.prior_weight > 0.0 && options.prior.is_none() {
        return Err(SdpError::Option {
            name: "prior_weight",
            message: "a prior weight needs prior values".into(),
        });
    }
    if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
        return Err(SdpError::Option {
            name: "tolerance",
            message: format!("must be finite and > 0, got {}", options.tolerance),
        });
    }
    if options.max_iter == 0 {
        return Err(SdpError::Option {
            name: "max_iter",
            message: "must be at least 1".into(),
        });
    }
    let prior = match &options.prior {
        Some(v) if v.len() != p => {
            return Err(SdpError::PriorLength {
                model: model.name.clone(),
                found: v.len(),
                expected: p,
            })
        }
        Some(v) if v.iter().any(|x| x.is_infinite()) => {
            return Err(SdpError::NonFinite {
                what: "the prior".into(),
            })
        }
        Some(v) if options.prior_weight > 0.0 && v.iter().all(|x| x.is_nan()) => {
            return Err(SdpError::Option {
                name: "prior",
                message: "the prior has no value for any parameter".into(),
            })
        }
        Some(v) => v.clone(),
        None => vec![0.0; p],
    };
    let eps = model.bounds.pseudo_inertia_eps;
    if !eps.is_finite() {
        return Err(SdpError::NonFinite {
            what: "bounds.pseudo_inertia_eps".into(),
        });
    }
    Ok(prior)
}

/// Scaling: `πᵢ = sᵢ·uᵢ` with `sᵢ = γ/dᵢ`, `dᵢ` the norm of R's column `i` (the median
/// of the seen columns of its unit class for a column the data do not see) and `γ` the
/// norm of the torque column; returns `(s, γ)`.
fn scaling(model: &Model, r: &DMatrix<f64>) -> (Vec<f64>, f64) {
    let p = model.n_params();
    let norms: Vec<f64> = (0..p).map(|c| r.column(c).norm()).collect();
    let max_norm = norms.iter().cloned().fold(0.0, f64::max);
    let seen = |c: usize| max_norm > 0.0 && norms[c] > 1e-9 * max_norm;
    let mut d = norms.clone();
    let all_seen: Vec<f64> = (0..p).filter(|&c| seen(c)).map(|c| norms[c]).collect();
    let global = median(all_seen).unwrap_or(1.0);
    for (c, dc) in d.iter_mut().enumerate() {
        if !seen(c) {
            let class = model.params[c].kind.unit_class();
            let same: Vec<f64> = (0..p)
                .filter(|&k| seen(k) && model.params[k].kind.unit_class() == class)
                .map(|k| norms[k])
                .collect();
            *dc = median(same).unwrap_or(global);
        }
    }
    let tau_norm = r.column(p).norm();
    let gamma = if tau_norm > 0.0 { tau_norm } else { 1.0 };
    let s: Vec<f64> = d.iter().map(|di| gamma / di).collect();
    (s, gamma)
}

/// The Tikhonov and prior weights of the objective: `λ` (regularization), `w` (prior
/// weight) and whether the prior is the entropic one.
struct Penalty {
    lambda: f64,
    w: f64,
    entropic: bool,
}

/// The objective's second-order cone: the epigraph row(s) of `t`, the residual and the
/// Tikhonov rows; `scaled` = `(s, γ)`.
fn objective_rows(
    rows: &mut Rows,
    r: &DMatrix<f64>,
    scaled: (&[f64], f64),
    prior: &[f64],
    penalty: &Penalty,
    entropic_terms: (&[bool], &[(usize, f64)]),
) {
    let (covered, masses) = entropic_terms;
    let (s, gamma) = scaled;
    let (p, np1) = (r.ncols() - 1, r.ncols());
    let Penalty {
        lambda,
        w,
        entropic,
    } = *penalty;
    // Cone rows s = b − A·x: the epigraph row(s) of t, then the residual R̃·u − r̃, then
    // the Tikhonov rows.
    if entropic {
        // s₀ = (t + 1)/2, s₁ = (t − 1)/2.
        rows.ai.extend([0, 1]);
        rows.aj.extend([p, p]);
        rows.av.extend([-0.5, -0.5]);
        rows.b.extend([0.5, -0.5]);
    } else {
        rows.ai.push(0);
        rows.aj.push(p);
        rows.av.push(-1.0);
        rows.b.push(0.0);
    }
    // The entropic objective adds a divergence to the squared residual, so the residual's
    // currency matters: it is measured against the least-squares residual (the rows of
    // the cone × γ/ρ), so that it is about 1 at the solution whatever the noise.
    let ratio = if entropic || !masses.is_empty() {
        gamma / least_squares_residual(r, gamma)
    } else {
        1.0
    };
    let currency = if entropic { ratio } else { 1.0 };
    for row in 0..np1 {
        let at = rows.b.len();
        for c in 0..p {
            let v = r[(row, c)];
            if v != 0.0 {
                rows.ai.push(at);
                rows.aj.push(c);
                rows.av.push(-v * s[c] / gamma * currency);
            }
        }
        rows.b.push(-r[(row, p)] / gamma * currency);
    }
    // A parameter without a prior value (NaN: a partial prior) keeps only the
    // regularization, toward zero.
    let tikhonov = |i: usize| {
        let euclidean = !covered[i];
        let has_value = !prior[i].is_nan();
        lambda + if euclidean && has_value { w } else { 0.0 }
    };
    for i in 0..p {
        let weight = tikhonov(i);
        if weight > 0.0 {
            let sl = weight.sqrt() * currency;
            let target = if prior[i].is_nan() { 0.0 } else { prior[i] };
            rows.ai.push(rows.b.len());
            rows.aj.push(i);
            rows.av.push(-sl);
            rows.b.push(-sl * target / s[i]);
        }
    }
    // Mass-only prior links: √(w/2)·(m/m₀ − 1) in the currency of the divergences (the
    // data term ‖·‖²/ρ²); in the plain cone, whose data rows are scaled by γ, × ρ/γ.
    for &(k, m0) in masses {
        let c = (w / 2.0).sqrt() * currency / ratio;
        rows.ai.push(rows.b.len());
        rows.aj.push(k);
        rows.av.push(-c * s[k] / m0);
        rows.b.push(-c);
    }
    rows.cones
        .push(SupportedConeT::SecondOrderConeT(rows.b.len()));
}

/// `ρ = min ‖R[:, 0..p]·π − R[:, p]‖` over all π (by SVD: `R11` is rank deficient),
/// at least `1e-3·γ`: data fitted more closely than 0.1 % are weighed as if they were
/// not, so a noise-free fit does not make the residual term unbounded.
fn least_squares_residual(r: &DMatrix<f64>, gamma: f64) -> f64 {
    let p = r.ncols() - 1;
    let a = r.columns(0, p).into_owned();
    let rhs = r.column(p).into_owned();
    let svd = a.clone().svd(true, true);
    let rho = svd
        .solve(&rhs, 1e-12 * svd.singular_values.max())
        .map(|x| (&a * x - &rhs).norm())
        .unwrap_or(gamma);
    if rho.is_finite() {
        rho.max(1e-3 * gamma)
    } else {
        gamma
    }
}

/// Clamps the elements' parameters (friction, motor inertia, spring...) into their
/// bounds (and Stribeck terms onto `Fc + Fs ≥ 0`) when they miss them by at most
/// `1e-6·max(1, |bound|)`. Each appears in no other constraint,
/// and a solved problem satisfies its bounds to the solver's tolerance (relative to the
/// variable's scale, e.g. ~1e-5 N·m/rad on the MTM's 300 N·m/rad spring), so this only
/// makes the bounds hold exactly; a larger miss is left visible.
fn clamp_element_bounds(model: &Model, params: &mut [f64], override_bounds: bool) {
    for f in &model.frames {
        let bounds = BoundsContext {
            global: &model.bounds,
            frame: &f.bounds,
            use_frame: !override_bounds,
        };
        for e in &f.elements {
            e.clamp(&bounds, params);
        }
    }
}

/// `‖R[:, 0..p]·π − R[:, p]‖²` (= `‖R11·π − r1‖² + ρ²` for a triangular R).
fn residual_sum_of_squares(r: &DMatrix<f64>, params: &[f64]) -> f64 {
    let p = params.len();
    (0..r.nrows())
        .map(|row| {
            let v: f64 = (0..p).map(|c| r[(row, c)] * params[c]).sum::<f64>() - r[(row, p)];
            v * v
        })
        .sum()
}

#[cfg(test)]
mod tests;
