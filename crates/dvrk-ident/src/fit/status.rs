//! What the data determined of each parameter: the result's `parameter_status`
//! ([`ParameterStatus`]) and, per link, [`LinkDetermined`].
//!
//! # Criterion
//!
//! The torques are `τ = H·π`, and the weighted data determine exactly the projections
//! of `π` on the row space of `W·H`. Since `H = H_b·K` with `H_b` of full column rank
//! (the base parameters, [`dvrk_model::BaseParameters`]; a fit refuses data that leave
//! one undetermined), that row space is the row space of `K`. A single parameter `πᵢ`
//! is a function of the data when the unit vector `eᵢ` lies in it: `eᵢ = Kᵀ·c`. `K` is
//! the identity on the kept columns, so `c` can only be the unit vector of the base
//! parameter whose leading column is `i`, and the condition reads: **`i` leads a base
//! parameter whose combination is `πᵢ` alone** (nothing folded into it). Every other
//! parameter moves along the regressor's null space without changing any torque, so
//! its value comes from whatever else the estimator minimizes or imposes (the
//! regularization, a prior, the pseudo-inertia constraints, the bounds, or for least
//! squares the representative's zeros). This is exact and needs no tolerance: the
//! base-parameter machinery already decides which coefficients are structural zeros.
//!
//! Beyond the null space, a direction can be excited too weakly for the noise. A
//! structurally identifiable `πᵢ` has the data-only standard deviation of its base
//! parameter, `σ·‖R_b⁻ᵀ·e_k‖` (the least-squares fit of the same weighted data). It is
//! compared with the parameter's plausible magnitude `sᵢ = ‖W·τ‖ / ‖W·H·eᵢ‖`, the value
//! at which `πᵢ` alone would produce the whole measured weighted torque (the semidefinite
//! fit's own equilibration scale, [`crate::estimate::sdp`]): `πᵢ` is `identified` when
//! `std(πᵢ) ≤ DETERMINED_FRACTION·sᵢ`, i.e. when one standard deviation of it, acting
//! alone, moves the weighted torques by at most 10 % of their norm. The standard
//! deviation assumes white residuals; real residuals are correlated in time, so it is
//! optimistic, which is why the fraction is not smaller.
//!
//! Bounds come first: a parameter of a semidefinite fit sitting on one of the fit's
//! linear bounds ([`dvrk_model::Model::bound_rows`]: mass range, centre-of-mass box,
//! friction and motor-inertia bounds, `Fc + Fs ≥ 0`) to
//! `BOUND_TOLERANCE·max(1, |bound|)` ([`BOUND_TOLERANCE`] = 1e-4) is
//! `at_lower_bound` / `at_upper_bound`, whether or not the data would determine it: the
//! bound, not the data, set its value. Least-squares fits have no bounds.

use dvrk_model::{BaseParameters, Model, ParamKind, Side};
use indexmap::IndexMap;

use crate::result::{LinkDetermined, ParameterStatus};

/// The largest standard deviation, as a fraction of a parameter's plausible magnitude
/// `‖W·τ‖ / ‖W·H·eᵢ‖`, at which the data still determine it (see the module
/// documentation).
pub const DETERMINED_FRACTION: f64 = 0.1;

/// A parameter within `BOUND_TOLERANCE·max(1, |bound|)` of a bound sits on it (in the
/// bound's unit; a hundred times the tolerance the fit clamps element parameters onto
/// their bounds with, [`dvrk_model::Element::clamp`]). The semidefinite fit meets its
/// link bounds only to Clarabel's tolerance (1e-8) in variables scaled by each
/// parameter's plausible magnitude, so a link parameter on its bound misses it by more:
/// on the real 2019 logs with the dVRK preset, the MTM's `back_parallel` mass ends
/// 4e-4 kg below its 10 kg bound and the PSM's `pitch_top` 1.4e-5 kg below its 0.5 kg
/// one, both held there by the bound alone (1e-5 missed them; 1e-6 missed the MTM's
/// `m4 = 9.99998968` kg of an earlier preset).
pub const BOUND_TOLERANCE: f64 = 1e-4;

/// What the fit had to decide each parameter's status from.
pub(crate) struct StatusInputs<'a> {
    /// The model's base parameters.
    pub base: &'a BaseParameters,
    /// The fitted parameters, model order.
    pub params: &'a [f64],
    /// Standard deviation of each base parameter (order of `base.independent`).
    pub base_std: &'a [f64],
    /// Column norms of the weighted observation `[W·H | W·τ]` (p + 1 entries).
    pub column_norms: &'a [f64],
    /// The fit applied the model's linear bounds (the semidefinite fit).
    pub bounded: bool,
}

/// Every parameter's status, by name in the model's order (see the module
/// documentation).
pub(crate) fn parameter_status(
    model: &Model,
    inputs: &StatusInputs<'_>,
) -> IndexMap<String, ParameterStatus> {
    let p = model.n_params();
    let gamma = inputs.column_norms[p];
    let mut status = vec![ParameterStatus::Unidentified; p];
    for (k, &i) in inputs.base.independent.iter().enumerate() {
        let alone = inputs
            .base
            .combination
            .row(k)
            .iter()
            .enumerate()
            .all(|(j, &c)| j == i || c == 0.0);
        let relative = inputs.base_std[k] * inputs.column_norms[i] / gamma;
        if alone && relative <= DETERMINED_FRACTION {
            status[i] = ParameterStatus::Identified;
        }
    }
    if inputs.bounded {
        for (_, row) in model.bound_rows(true) {
            let Some((k, bound, side)) = row.bound_on_first(inputs.params) else {
                continue;
            };
            if (inputs.params[k] - bound).abs() <= BOUND_TOLERANCE * bound.abs().max(1.0) {
                status[k] = match side {
                    Side::Lower => ParameterStatus::AtLowerBound,
                    Side::Upper => ParameterStatus::AtUpperBound,
                };
            }
        }
    }
    model.param_names().into_iter().zip(status).collect()
}

/// Per link (in `model.link_frames()` order): whether its mass, first moment and
/// rotational inertia are each identified.
pub(crate) fn link_determined(
    model: &Model,
    status: &IndexMap<String, ParameterStatus>,
) -> Vec<LinkDetermined> {
    let identified = |i: usize| status[i].identified();
    model
        .link_frames()
        .iter()
        .map(|&j| {
            let p0 = model.frame(j).inertia.expect("link");
            debug_assert!(matches!(
                model.params[p0].kind,
                ParamKind::Inertia { index: 0 }
            ));
            LinkDetermined {
                mass: identified(p0 + 9),
                first_moment: (p0 + 6..p0 + 9).all(identified),
                inertia: (p0..p0 + 6).all(identified),
            }
        })
        .collect()
}
