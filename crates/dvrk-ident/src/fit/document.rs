//! The last stage of a fit: the result document ([`FitResult`]) of an estimate.

use dvrk_model::{inertia, BaseParameters, Model};

use super::status::{link_determined, parameter_status, StatusInputs};
use crate::error::IdentError;
use crate::estimate::Estimated;
use crate::result::*;
use crate::settings::FitSettings;

/// Friction and motor inertia count as non-negative down to `-ELEMENT_TOLERANCE`
/// (N·m, N·m·s/rad, kg·m²): zero up to rounding. A converged semidefinite fit meets its
/// sign bounds exactly (projected after the solve, `estimate::sdp`), so its verdict
/// never hangs on Clarabel's feasibility tolerance (1e-8 relative).
pub const ELEMENT_TOLERANCE: f64 = 1e-9;

/// The result document of an estimate: every parameter by name with what the data
/// determined of it ([`super::status`]), each link's standard parameters and
/// pseudo-inertia verdict, the base parameters with their standard
/// deviations, the solver's end state, and `metrics`.
pub(crate) fn build_result(
    model: &Model,
    base: &BaseParameters,
    settings: &FitSettings,
    estimated: Estimated,
    metrics: Metrics,
) -> Result<FitResult, IdentError> {
    let Estimated {
        params,
        estimate,
        weights,
        solver,
        rows,
        column_norms,
        prior_divergence,
    } = estimated;
    let beta = base.project(&params);
    let names = model.param_names();
    let parameter_status = parameter_status(
        model,
        &StatusInputs {
            base,
            params: &params,
            base_std: &estimate.std,
            column_norms: &column_norms,
            bounded: settings.method == crate::Method::Sdp,
        },
    );
    let determined = link_determined(model, &parameter_status);
    let mut links = Vec::new();
    let mut consistency = Vec::new();
    for (&j, determined) in model.link_frames().iter().zip(determined) {
        let f = model.frame(j);
        let p0 = f.inertia.expect("link");
        let bary = &params[p0..p0 + 10];
        let std = inertia::standard_from_barycentric(bary);
        let min_eig = inertia::pseudo_inertia_min_eigenvalue(bary);
        links.push(LinkResult {
            frame: j,
            link: f.name.clone(),
            mass: std.mass,
            com: std.com,
            inertia_com: std.inertia_com,
            determined: Some(determined),
        });
        consistency.push(Consistency {
            frame: j,
            link: f.name.clone(),
            min_eigenvalue: min_eig,
            consistent: min_eig > 0.0,
        });
    }
    let base_parameters = BaseParameterResult::all(base, &beta, &estimate.std);
    // Sign conditions hold up to rounding (see `ELEMENT_TOLERANCE`).
    let tol = -ELEMENT_TOLERANCE;
    let elements_ok = params.iter().all(|v| v.is_finite())
        && model
            .frames
            .iter()
            .flat_map(|f| &f.elements)
            .all(|e| e.consistent(&params, tol));
    let result = FitResult {
        tool: format!("dvrk-ident {}", env!("CARGO_PKG_VERSION")),
        robot: model.name.clone(),
        robot_source: model.source.clone(),
        method: settings.method.name().into(),
        settings: settings.clone(),
        inputs: Vec::new(),
        parameters: names.iter().cloned().zip(params.iter().copied()).collect(),
        parameter_order: names,
        parameter_status,
        links,
        base_parameters,
        consistency,
        physically_consistent: elements_ok
            && model.link_frames().iter().all(|&j| {
                let p0 = model.frame(j).inertia.expect("link");
                inertia::pseudo_inertia_min_eigenvalue(&params[p0..p0 + 10]) > 0.0
            }),
        solver,
        weights,
        rows,
        condition_number: estimate.condition_number,
        sigma2: estimate.sigma2,
        metrics,
        delay: None,
        selection: None,
        prior_divergence,
        payload: None,
    };
    result.check_finite()?;
    Ok(result)
}
