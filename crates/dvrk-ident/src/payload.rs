//! Payload identification: a rigid body fixed to one frame of the arm (a tool, a weight,
//! a grasped object), estimated from logs of the arm carrying it with the rest of the
//! model held at a fit's result.
//!
//! # Method
//!
//! The payload adds `H_p(q, q̇, q̈)·π_p` to the joint torques, with `π_p` its 10
//! barycentric parameters in the frame (`[Lxx … Lzz, lx, ly, lz, m]`: inertia about the
//! frame origin, first moment `m·c`, mass) and `H_p` the regressor of the arm carrying
//! nothing but that body ([`dvrk_model::Model::payload_model`]). Each log is processed
//! with the result's own processing (filters, delays, trimming) and the result's
//! prediction — friction, springs, motor inertias and known forces included — is
//! subtracted: what remains is what [`crate::residual`] calls the external torque, here
//! fitted by `H_p·π_p`. The estimate is the semidefinite fit of any result
//! (`crate::estimate::sdp`) on that one body: weighted least squares (the result's row
//! weights per coordinate) under `J(π_p) ⪰ eps·I`, so the payload is physically
//! consistent.
//!
//! # What the logs determine
//!
//! As for a fit's parameters (`crate::fit::status`): a barycentric parameter is
//! identified when it is a base parameter of the body by itself (its motion exposes it:
//! a mass on a link that only rotates about a fixed axis shows only its first moment,
//! never its mass) and the logs measure it to `crate::fit::status::DETERMINED_FRACTION`
//! of its plausible magnitude. The mass is determined with `m`, the centre of mass with
//! `l` and `m`, the inertia about the centre of mass with `L`, `l` and `m`
//! ([`LinkDetermined`]); undetermined quantities are reported as such (their values are
//! the consistent fit's, set by its constraints and regularization, not by the data).
//! Standard deviations are those of the weighted least-squares fit of the same data
//! (white residuals assumed), carried to the centre of mass and the inertia about it to
//! first order.

use dvrk_model::inertia::standard_from_barycentric;
use dvrk_model::{Model, Payload};
use indexmap::IndexMap;
use nalgebra::DMatrix;

use crate::error::IdentError;
use crate::estimate::ols::base_least_squares;
use crate::estimate::sdp::{solve_sdp, SdpOptions};
use crate::estimate::SolverInfo;
use crate::fit::status::{link_determined, parameter_status, StatusInputs};
use crate::fit::{predict, prepare, Prepared};
use crate::observation::Observation;
use crate::progress::Silent;
use crate::JointLog;
// The identification's record is part of the result document; its public path is here.
use crate::result::{
    BaseParameterResult, FitResult, LinkDetermined, ParameterStatus, ResultPayload,
};
pub use crate::result::{PayloadIdentification, PayloadStd};

/// A payload estimated from logs ([`identify_payload`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PayloadEstimate {
    /// The physically consistent estimate (what the result document carries).
    pub payload: Payload,
    /// What the logs determined of it, with its standard deviations.
    pub identification: PayloadIdentification,
}

impl PayloadEstimate {
    /// `result` with this payload added: the same document with a `payload` section
    /// ([`FitResult::payload`]), so that validate, residual, report and every export use
    /// the arm with its load.
    pub fn applied_to(&self, result: &FitResult) -> FitResult {
        let mut out = result.clone();
        out.payload = Some(ResultPayload {
            body: self.payload.clone(),
            identification: Some(self.identification.clone()),
        });
        out
    }
}

/// Estimates a rigid payload fixed to frame `frame` from `logs` of the arm carrying it,
/// with the rest of the model held at `result` (`model` is the result's model, e.g. from
/// [`FitResult::model_for`], and `params` its parameters in that model's order; see the
/// module documentation).
///
/// Errors: a frame without link parameters (naming those that have them), a result
/// that already carries a payload, a log that does not fit the robot or leaves no
/// processed sample, logs that do not excite some identifiable combination of the
/// payload's parameters (naming them) or that determine none of its parameters, and a
/// semidefinite fit that does not converge.
pub fn identify_payload(
    model: &Model,
    params: &[f64],
    result: &FitResult,
    logs: &[JointLog],
    frame: &str,
) -> Result<PayloadEstimate, IdentError> {
    result.check_robot(model, "the result")?;
    if let Some(p) = &result.payload {
        return Err(IdentError::Setting {
            name: crate::error::SettingName::Argument("payload"),
            message: format!(
                "the result already carries a payload (on frame `{}`): identify a payload \
                 from the result without one",
                p.body.frame
            ),
        });
    }
    // The frame is the caller's argument (`--frame`, `frame=`): refused as it, each front
    // end naming it its own way.
    let body = model
        .payload_model(frame, "")
        .map_err(IdentError::of_setting(crate::error::SettingName::Argument(
            "frame",
        )))?;
    let n = model.dof();
    if logs.is_empty() {
        return Err(IdentError::Setting {
            name: crate::error::SettingName::Argument("logs"),
            message: "a payload needs at least one log of the arm carrying it".into(),
        });
    }
    let weights = result.weights.clone();
    if weights.len() != n || weights.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
        return Err(IdentError::Format {
            file: "the result".into(),
            message: format!(
                "its weights ({} values) are not one positive weight per coordinate of \
                 robot {} ({n})",
                weights.len(),
                model.name
            ),
        });
    }
    // Per coordinate, the factor of [H_p | τ − τ_model] over every log.
    let mut parts: Vec<Observation> = (0..n).map(|_| Observation::new(10)).collect();
    let mut samples = 0;
    for log in logs {
        let data = prepare(model, log, &result.settings.processing)?;
        if data.is_empty() {
            return Err(IdentError::NoSampleLeft {
                source_name: data.source.clone(),
            });
        }
        let unexplained = &data.tau - predict(model, params, &data);
        let residual = Prepared {
            tau: unexplained,
            ..data
        };
        samples += residual.len();
        let log_parts = Observation::assemble_per_coordinate(&body, residual.samples(), &Silent);
        for (all, part) in parts.iter_mut().zip(&log_parts) {
            all.merge(part);
        }
    }
    let source = || {
        logs.iter()
            .map(|l| l.source.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let base = body.base_parameters()?;
    let obs = Observation::weighted(&parts, &weights);
    let estimate = base_least_squares(&obs, &base).map_err(|e| IdentError::RankDeficient {
        source_name: source(),
        message: format!(
            "the logs do not excite the payload's {} on frame `{frame}` ({} rows): the arm \
             must move that frame (a still arm shows no inertia)",
            e.parameters.join(", "),
            e.rows
        ),
    })?;
    let sol = solve_sdp(&body, obs.r(), &SdpOptions::default())?;
    let solver = SolverInfo {
        name: "clarabel".into(),
        status: sol.status,
        converged: sol.converged,
        seconds: sol.seconds,
        iterations: sol.iterations,
        tolerance: Some(SdpOptions::default().tolerance),
    };
    if !sol.converged {
        return Err(IdentError::Mismatch {
            source_name: source(),
            message: format!(
                "the payload's semidefinite fit ended {} after {} iterations: no payload",
                sol.status, sol.iterations
            ),
        });
    }
    let pi = sol.params;
    let column_norms: Vec<f64> = obs.r().column_iter().map(|c| c.norm()).collect();
    let status = parameter_status(
        &body,
        &StatusInputs {
            base: &base,
            params: &pi,
            base_std: &estimate.std,
            column_norms: &column_norms,
            bounded: false,
        },
    );
    let determined = link_determined(&body, &status)[0];
    if !status.values().any(|s| s.identified()) {
        return Err(IdentError::RankDeficient {
            source_name: source(),
            message: format!(
                "the logs determine none of the payload's parameters on frame `{frame}` \
                 (each one's standard deviation exceeds {} of its plausible magnitude): a \
                 longer log, or one that moves that frame more",
                crate::fit::status::DETERMINED_FRACTION
            ),
        });
    }
    let std = standard_deviations(&base, &obs, &estimate, &status, &pi, determined);
    let beta = base.project(&pi);
    let base_parameters = BaseParameterResult::all(&base, &beta, &estimate.std);
    let rms = |p: &[f64]| -> Vec<f64> {
        parts
            .iter()
            .map(|o| (o.residual_sum_of_squares(p) / o.rows().max(1) as f64).sqrt())
            .collect()
    };
    let standard = standard_from_barycentric(&pi);
    let [xx, xy, xz, yy, yz, zz] = standard.inertia_com;
    let payload = Payload {
        frame: frame.to_string(),
        mass: standard.mass,
        com: standard.com,
        inertia: [xx, yy, zz, xy, xz, yz],
    };
    payload.check(model, "the payload's fit")?;
    let identification = PayloadIdentification {
        logs: logs.iter().map(|l| l.source.clone()).collect(),
        samples,
        determined,
        parameter_status: status,
        std,
        base_parameters,
        solver,
        weights,
        coordinates: model.coordinates.clone(),
        rms_without: rms(&[0.0; 10]),
        rms_with: rms(&pi),
    };
    let out = PayloadEstimate {
        payload,
        identification,
    };
    out.applied_to(result).check_finite()?;
    Ok(out)
}

/// The standard deviations of the determined quantities: the least-squares covariance
/// of the body's parameters `σ²·(R_bᵀR_b)⁻¹` (every determined quantity depends only on
/// identified parameters, each a base parameter by itself), carried through
/// [`standard_from_barycentric`] by its Jacobian (central differences) at `pi`.
fn standard_deviations(
    base: &dvrk_model::BaseParameters,
    obs: &Observation,
    estimate: &crate::estimate::ols::BaseEstimate,
    status: &IndexMap<String, ParameterStatus>,
    pi: &[f64],
    determined: LinkDetermined,
) -> PayloadStd {
    let r = base.rank();
    let sel = obs.select(&base.independent);
    let r11 = sel.r().view((0, 0), (r, r)).into_owned();
    let inv = r11
        .solve_upper_triangular(&DMatrix::identity(r, r))
        .expect("non-singular: base_least_squares accepted it");
    let cov_base = &inv * inv.transpose() * estimate.sigma2;
    // The 10×10 covariance over the identified parameters (zero elsewhere: unused).
    let mut cov = DMatrix::zeros(10, 10);
    let slot: Vec<Option<usize>> = (0..10)
        .map(|i| {
            let identified = status.get_index(i).is_some_and(|(_, s)| s.identified());
            base.independent
                .iter()
                .position(|&c| c == i)
                .filter(|_| identified)
        })
        .collect();
    for i in 0..10 {
        for j in 0..10 {
            if let (Some(a), Some(b)) = (slot[i], slot[j]) {
                cov[(i, j)] = cov_base[(a, b)];
            }
        }
    }
    // Standard quantities [m, c (3), I_c in the payload's order (6)] and their Jacobian.
    let standard = |p: &[f64]| -> [f64; 10] {
        let s = standard_from_barycentric(p);
        let [xx, xy, xz, yy, yz, zz] = s.inertia_com;
        [s.mass, s.com[0], s.com[1], s.com[2], xx, yy, zz, xy, xz, yz]
    };
    let mut jac = DMatrix::zeros(10, 10);
    for k in 0..10 {
        // A step relative to the parameter, or to the mass times a length of 0.1 m to
        // its power for a parameter near zero (kg·m², kg·m, kg).
        let typical = pi[9].abs() * [0.01, 0.1, 1.0][usize::from(k >= 6) + usize::from(k >= 9)];
        let h = 1e-6 * pi[k].abs().max(typical).max(1e-12);
        let (mut up, mut down) = (pi.to_vec(), pi.to_vec());
        up[k] += h;
        down[k] -= h;
        let (a, b) = (standard(&up), standard(&down));
        for q in 0..10 {
            jac[(q, k)] = (a[q] - b[q]) / (2.0 * h);
        }
    }
    let var = &jac * cov * jac.transpose();
    let sd = |q: usize| var[(q, q)].max(0.0).sqrt();
    PayloadStd {
        mass: determined.mass.then(|| sd(0)),
        com: determined.com().then(|| [sd(1), sd(2), sd(3)]),
        inertia: determined
            .inertia_com()
            .then(|| [sd(4), sd(5), sd(6), sd(7), sd(8), sd(9)]),
    }
}
