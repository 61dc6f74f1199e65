//! The real-time entry points: gravity, inverse dynamics (whole and of the links),
//! mass matrix, forward dynamics and the measured-joint conversions. None allocates or
//! locks; each checks its pointers and inputs, computes into the workspace and copies
//! out only on success.

use std::ffi::c_int;

use dvrk_model::{Model, Workspace};

use crate::boundary::{deliver, finite, finite3, guarded, model_ref, slices, workspace_args};
use crate::codes::{DVRK_ERR_NOT_POSITIVE_DEFINITE, DVRK_ERR_NULL, DVRK_ERR_OVERFLOW};
use crate::{DvrkModel, DvrkWorkspace, BOUNDED_Q_MAX};

/// Gravity torque `g(q)` of the links alone (N·m or N per model coordinate), as
/// Pinocchio's `computeGeneralizedGravity`: no friction, spring or known force (the
/// whole static torque is `dvrk_inverse_dynamics` at `dq = ddq = 0`). A real-time call
/// (see the top of the header: codes, outputs untouched on an error).
///
/// # Safety
///
/// As every real-time call (the top of the header), with the vectors `q` and `tau`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_gravity(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    q: *const f64,
    tau: *mut f64,
) -> c_int {
    guarded(|| {
        // SAFETY: the caller's obligations, passed on.
        let (m, w, [q], tau) = unsafe { workspace_args(model, ws, [q], tau, |n| n) }?;
        // Bounded by `Model::gravity_torque_bound`.
        of_positions(m, &mut w.ws, &mut w.vector, q, tau, Model::gravity_torque)
    })
}

/// The body of `dvrk_gravity` and `dvrk_mass_matrix`, which differ only in what they
/// compute of `q` (`compute(model, ws, params, q, out)`). When the model is bounded
/// ([`DvrkModel::bounded`]) and `|q_k| ≤ BOUNDED_Q_MAX` (false for a non-finite `q`),
/// the result is finite by the bound and is computed straight into the caller's buffer
/// with no output check (benches/abi.rs: the gravity's overhead over the Rust call was
/// 5.3-5.6 % with the check and the copy of a 7-value torque, 1.0-1.5 % without);
/// otherwise `q` is checked finite and the result computed into `scratch` and delivered
/// only if finite. Inlined: as a call of its own it cost the gravity 1 ns (0.5 % on
/// the PSM, benches/abi.rs).
#[inline(always)]
fn of_positions(
    m: &DvrkModel,
    ws: &mut Workspace,
    scratch: &mut [f64],
    q: &[f64],
    out: &mut [f64],
    compute: impl Fn(&Model, &mut Workspace, &[f64], &[f64], &mut [f64]),
) -> Result<(), c_int> {
    if m.bounded && q.iter().all(|x| x.abs() <= BOUNDED_Q_MAX) {
        compute(&m.model, ws, &m.params, q, out);
        return Ok(());
    }
    finite(&[q])?;
    compute(&m.model, ws, &m.params, q, scratch);
    deliver(scratch, out)
}

/// Inverse dynamics (N·m or N per model coordinate): the torque the result's model
/// predicts at `q`, `dq`, `ddq` — links, friction (with the Stribeck term of a fit that
/// had one, its position torques, its load friction with the load predicted as
/// `Model::loaded_inverse_dynamics` does), springs, motor inertias and known forces (e.g.
/// the MTM's cable), i.e. the measured torque mapped to model coordinates. On a robot without known forces (the
/// PSM) it is `dvrk-ident model ROBOT --torque --params RESULT`. A real-time call.
///
/// # Safety
///
/// As every real-time call, with the vectors `q`, `dq`, `ddq` and `tau`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_inverse_dynamics(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    q: *const f64,
    dq: *const f64,
    ddq: *const f64,
    tau: *mut f64,
) -> c_int {
    // SAFETY: the caller's obligations, passed on.
    unsafe { dynamics(model, ws, q, dq, ddq, tau, Dynamics::Whole) }
}

/// Inverse dynamics of the links alone (N·m or N per model coordinate): the rigid-body
/// part of `dvrk_inverse_dynamics`, without friction, springs, motor inertias or known
/// forces, for a controller that models those itself. At `dq = ddq = 0` it is
/// `dvrk_gravity`. A real-time call.
///
/// # Safety
///
/// As `dvrk_inverse_dynamics`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_rigid_body_dynamics(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    q: *const f64,
    dq: *const f64,
    ddq: *const f64,
    tau: *mut f64,
) -> c_int {
    // SAFETY: the caller's obligations, passed on.
    unsafe { dynamics(model, ws, q, dq, ddq, tau, Dynamics::Links) }
}

/// Which torque [`dynamics`] computes.
#[derive(Clone, Copy, PartialEq)]
enum Dynamics {
    /// The result's whole model, known forces included (`dvrk_inverse_dynamics`).
    Whole,
    /// The links alone (`dvrk_rigid_body_dynamics`).
    Links,
}

/// The body of `dvrk_inverse_dynamics` and `dvrk_rigid_body_dynamics`, which differ only
/// in the parameters and the known forces.
///
/// # Safety
///
/// As `dvrk_inverse_dynamics`.
unsafe fn dynamics(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    q: *const f64,
    dq: *const f64,
    ddq: *const f64,
    tau: *mut f64,
    which: Dynamics,
) -> c_int {
    guarded(|| {
        // SAFETY: the caller's obligations, passed on.
        let (m, w, [q, dq, ddq], tau) =
            unsafe { workspace_args(model, ws, [q, dq, ddq], tau, |n| n) }?;
        finite3(q, dq, ddq)?;
        let params = match which {
            Dynamics::Whole => &m.params,
            Dynamics::Links => &m.link_params,
        };
        // Load friction (if the fit had it) with its load predicted, as in the metrics.
        m.model
            .loaded_inverse_dynamics(&mut w.ws, params, q, dq, ddq, &mut w.vector);
        if which == Dynamics::Whole {
            m.model.add_known_forces(q, &mut w.vector);
        }
        deliver(&w.vector, tau)
    })
}

/// Mass matrix `M(q)` (n×n, kg·m² or kg, motor inertias included), written row-major
/// into `m` (it is symmetric). A real-time call.
///
/// # Safety
///
/// As every real-time call, with the vector `q`; `m` is NULL or valid for n·n doubles
/// (`n = dvrk_model_dof`).
#[no_mangle]
pub unsafe extern "C" fn dvrk_mass_matrix(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    q: *const f64,
    m: *mut f64,
) -> c_int {
    guarded(|| {
        // SAFETY: the caller's obligations, passed on.
        let (dm, w, [q], out) = unsafe { workspace_args(model, ws, [q], m, |n| n * n) }?;
        // Bounded by `Model::mass_matrix_bound`. dvrk-model writes M column-major, each
        // off-diagonal product added to both of its entries at once, so M is symmetric
        // to the bit and its column-major layout is its row-major one: no transpose
        // (tests/c_abi.rs compares every entry with dvrk-model's, bit for bit).
        of_positions(
            dm,
            &mut w.ws,
            &mut w.matrix,
            q,
            out,
            Model::mass_matrix_into,
        )
    })
}

/// Forward dynamics (rad/s² or m/s² per model coordinate): the accelerations under the
/// torques `tau` (as `dvrk_inverse_dynamics` gives them: known forces included) with the
/// result's whole model, `M(q)·ddq = tau − h(q, dq) − tau_known(q)`. A real-time call;
/// `DVRK_ERR_NOT_POSITIVE_DEFINITE` when the parameters are not physical at `q`.
///
/// # Safety
///
/// As every real-time call, with the vectors `q`, `dq`, `tau` and `ddq`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_forward_dynamics(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    q: *const f64,
    dq: *const f64,
    tau: *const f64,
    ddq: *mut f64,
) -> c_int {
    guarded(|| {
        // SAFETY: the caller's obligations, passed on.
        let (m, w, [q, dq, tau], ddq) =
            unsafe { workspace_args(model, ws, [q, dq, tau], ddq, |n| n) }?;
        finite3(q, dq, tau)?;
        m.model
            .forward_dynamics_into(&mut w.ws, &m.params, q, dq, tau, &mut w.vector)
            .map_err(|_| DVRK_ERR_NOT_POSITIVE_DEFINITE)?;
        deliver(&w.vector, ddq)
    })
}

/// Measured joint positions or velocities (the dVRK's/ROS joint space,
/// `dvrk_model_n_measured` values) to model coordinates: `q_model = M⁻¹ q_measured`
/// where `q_measured = M q_model` is the description's coupling (linear, so velocities
/// map the same way). A real-time call, with no workspace.
///
/// # Safety
///
/// As every real-time call, with the vectors `measured` and `model_out`
/// (`dvrk_model_dof` = `dvrk_model_n_measured` doubles).
#[no_mangle]
pub unsafe extern "C" fn dvrk_measured_to_model(
    model: *const DvrkModel,
    measured: *const f64,
    model_out: *mut f64,
) -> c_int {
    // SAFETY: the caller's obligations, passed on.
    unsafe { map_linear(model, measured, model_out, Coupling::Inverse) }
}

/// Model-coordinate torques (as `dvrk_inverse_dynamics` gives them) to the measured
/// joints' efforts, by virtual work: `tau_measured = M⁻ᵀ tau_model` (dvrk-ident maps
/// measured efforts to the model as `tau_model = Mᵀ tau_measured`). A real-time call,
/// with no workspace.
///
/// # Safety
///
/// As every real-time call, with the vectors `tau_model` and `measured_out`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_to_measured_torque(
    model: *const DvrkModel,
    tau_model: *const f64,
    measured_out: *mut f64,
) -> c_int {
    // SAFETY: the caller's obligations, passed on.
    unsafe { map_linear(model, tau_model, measured_out, Coupling::InverseTransposed) }
}

/// Which matrix of the coupling `M` a joint conversion applies.
#[derive(Clone, Copy, PartialEq)]
enum Coupling {
    /// `M⁻¹`: measured positions or velocities to model coordinates.
    Inverse,
    /// `M⁻ᵀ`: model torques to measured efforts.
    InverseTransposed,
}

/// The body of the joint conversions, which differ only in the matrix: `out = A·x` with
/// `A` = `M⁻¹` or `M⁻ᵀ` (`which`, read from the model's row-major `M⁻¹`) after the
/// checks (model, then `x` and `out` NULL, then `x` finite). They have no workspace to
/// compute into: every entry is checked finite before any is written (each computed
/// twice, 2n² flops), so `out` is untouched on `DVRK_ERR_OVERFLOW` as with `deliver`.
///
/// # Safety
///
/// `model` is NULL or live; `x` and `out` are NULL or valid for `dvrk_model_dof` doubles
/// and do not overlap.
unsafe fn map_linear(
    model: *const DvrkModel,
    x: *const f64,
    out: *mut f64,
    which: Coupling,
) -> c_int {
    guarded(|| {
        // SAFETY: the caller's obligation, passed on.
        let m = unsafe { model_ref(model) }.ok_or(DVRK_ERR_NULL)?;
        let n = m.model.dof();
        // SAFETY: the caller's obligations, passed on.
        let ([x], out) = unsafe { slices([x], n, out, n) }?;
        finite(&[x])?;
        let m_inv = &m.measured_to_model;
        let a = |i: usize, k: usize| match which {
            Coupling::Inverse => m_inv[i * n + k],
            Coupling::InverseTransposed => m_inv[k * n + i],
        };
        let row = |i: usize| (0..n).fold(0.0, |acc, k| acc + a(i, k) * x[k]);
        if !(0..n).all(|i| row(i).is_finite()) {
            return Err(DVRK_ERR_OVERFLOW);
        }
        for (i, o) in out.iter_mut().enumerate() {
            *o = row(i);
        }
        Ok(())
    })
}
