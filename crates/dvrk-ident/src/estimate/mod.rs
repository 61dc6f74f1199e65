//! Estimators, each a function of the observation's R factor: ordinary/weighted least
//! squares on the base parameters ([`ols`]) and the physically consistent semidefinite
//! fit over all parameters ([`sdp`]), and their dispatch by [`Method`] (`estimate`),
//! shared by every fit driver so that all of them give the same document.

pub mod ols;
pub mod sdp;
mod status;

pub use status::{SolverInfo, SolverStatus};

use dvrk_model::{BaseParameters, Model};
use serde::{Deserialize, Serialize};

use crate::observation::Observation;
use crate::progress::Progress;
use ols::{base_least_squares, representative, BaseEstimate};
use sdp::{solve_sdp, SdpOptions};

/// Which estimator to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Ordinary least squares on the base parameters.
    Ols,
    /// Weighted least squares, joint weights 1 / (torque range on the training set).
    Wls,
    /// Iteratively re-weighted least squares: weights 1 / (residual std per joint).
    Irls,
    /// Physically consistent semidefinite fit over all parameters (WLS weights).
    #[default]
    Sdp,
}

impl Method {
    /// The name the command line, Python and results use (see [`crate::names`]).
    pub fn name(self) -> &'static str {
        crate::names::Named::name(self)
    }
}

impl crate::names::Named for Method {
    const WHAT: &'static str = "method";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("ols", Method::Ols),
        ("wls", Method::Wls),
        ("irls", Method::Irls),
        ("sdp", Method::Sdp),
    ];
    const CANONICAL: usize = 4;
}

impl std::str::FromStr for Method {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}

/// What the estimator made of an observation.
pub struct Estimated {
    /// Every parameter (the SDP's, or the least-squares representative).
    pub params: Vec<f64>,
    /// The (last) weighted least-squares estimate of the base parameters.
    pub estimate: BaseEstimate,
    /// The per-coordinate weights of that estimate.
    pub weights: Vec<f64>,
    /// How the solver ended.
    pub solver: SolverInfo,
    /// Rows of the weighted observation.
    pub rows: usize,
    /// The column norms of the weighted observation `[W·H | W·τ]` (p + 1 entries, the
    /// last `‖W·τ‖`; units of the weighted torque per unit of each parameter): the
    /// scales [`crate::fit::status`] measures each parameter's precision against.
    pub column_norms: Vec<f64>,
    /// With an entropic prior, `Σ_links d(J‖J₀)` at `params`.
    pub prior_divergence: Option<f64>,
}

/// What an [`estimate`] reports to: when the fit started (the solver time counts from
/// it) and where its progress goes.
#[derive(Clone, Copy)]
pub(crate) struct Run<'a> {
    pub started: std::time::Instant,
    pub progress: &'a dyn Progress,
}

/// How to estimate: the method, IRLS's re-weighting passes and the semidefinite
/// program's options (its prior already in the model's parameter order).
pub(crate) struct Estimator<'a> {
    pub method: Method,
    pub irls_iterations: usize,
    pub sdp: &'a SdpOptions,
}

/// The estimator on the per-coordinate observation parts: weighted least squares from
/// `weights`; for IRLS, passes re-weighted by the inverse residual RMS of each
/// coordinate (from the parts, [`Observation::residual_sum_of_squares`]: no pass over
/// the data); then the semidefinite program or the least-squares representative.
pub(crate) fn estimate(
    model: &Model,
    base: &BaseParameters,
    parts: &[Observation],
    mut weights: Vec<f64>,
    how: &Estimator<'_>,
    run: &Run<'_>,
) -> Result<Estimated, EstimateError> {
    let Run { started, progress } = *run;
    let p = model.n_params();
    let mut obs = Observation::weighted(parts, &weights);
    let mut estimate: BaseEstimate =
        base_least_squares(&obs, base).map_err(EstimateError::NotExcited)?;
    let mut solver = SolverInfo {
        name: "qr".into(),
        status: SolverStatus::Solved,
        converged: true,
        seconds: 0.0,
        iterations: 1,
        tolerance: None,
    };
    if how.method == Method::Irls {
        for it in 0..how.irls_iterations {
            let pi = representative(base, &estimate.beta, p);
            weights = inverse_rms(parts, &pi);
            obs = Observation::weighted(parts, &weights);
            estimate = base_least_squares(&obs, base).map_err(EstimateError::NotExcited)?;
            solver.iterations = it as u32 + 2;
        }
    }
    let mut prior_divergence = None;
    let params = if how.method == Method::Sdp {
        progress.stage("solving the semidefinite program", None);
        let sol = solve_sdp(model, obs.r(), how.sdp)?;
        progress.finish();
        solver = SolverInfo {
            name: "clarabel".into(),
            status: sol.status,
            converged: sol.converged,
            seconds: sol.seconds,
            iterations: sol.iterations,
            tolerance: Some(how.sdp.tolerance),
        };
        prior_divergence = sol.divergence;
        sol.params
    } else {
        solver.seconds = started.elapsed().as_secs_f64();
        representative(base, &estimate.beta, p)
    };
    Ok(Estimated {
        params,
        estimate,
        weights,
        solver,
        rows: obs.rows(),
        column_norms: obs.r().column_iter().map(|c| c.norm()).collect(),
        prior_divergence,
    })
}

/// IRLS weights: `1 / rms` of each coordinate's residual (1 where it is zero).
fn inverse_rms(parts: &[Observation], params: &[f64]) -> Vec<f64> {
    parts
        .iter()
        .map(|o| {
            let rms = (o.residual_sum_of_squares(params) / o.rows().max(1) as f64).sqrt();
            if rms > 0.0 {
                1.0 / rms
            } else {
                1.0
            }
        })
        .collect()
}

/// Why an estimate gave no parameters.
#[derive(Debug)]
pub enum EstimateError {
    /// The data do not determine the base parameters.
    NotExcited(ols::NotExcited),
    /// The semidefinite program could not be set up or solved.
    Sdp(sdp::SdpError),
}

impl From<sdp::SdpError> for EstimateError {
    fn from(e: sdp::SdpError) -> Self {
        EstimateError::Sdp(e)
    }
}
