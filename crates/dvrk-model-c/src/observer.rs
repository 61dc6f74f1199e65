//! The momentum observer through the C ABI: [`dvrk_model::MomentumObserver`] on a loaded
//! result, one allocation-free `dvrk_observer_update` per control cycle (the external
//! torque the model does not explain, without an acceleration). A module of its own so
//! that the observer's entry points stay apart from the model's (`dynamics.rs`); they share
//! its checks ([`pair`], [`slices`], [`finite`], [`guarded`]).

use std::ffi::c_int;
use std::panic::catch_unwind;

use dvrk_model::MomentumObserver;

use crate::boundary::{finite, guarded, input, model_ref, pair, slices};
use crate::codes::{DVRK_ERR_ARGUMENT, DVRK_ERR_NULL, DVRK_ERR_OVERFLOW};
use crate::{DvrkModel, DvrkWorkspace};

/// A generalized-momentum observer of one model (`dvrk_observer_new`): its gains and the
/// previous sample. Serves one thread at a time, like a workspace.
pub struct DvrkObserver {
    /// The model it was created for: an update with another model is refused.
    model: *const DvrkModel,
    observer: MomentumObserver,
}

/// A momentum observer for `model` with gain `gains[k]` (1/s, positive and finite;
/// `dvrk_model_dof` values) on model coordinate `k`: each estimate follows the external
/// torque with a first-order lag of time constant `1/gains[k]` s. NULL if `model` or
/// `gains` is NULL or a gain is not positive and finite. Not real-time (allocates):
/// create it before the control loop, free it with `dvrk_observer_free` before the
/// model.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`, which must outlive
/// the observer; `gains` is NULL or valid for `dvrk_model_dof` doubles.
#[no_mangle]
pub unsafe extern "C" fn dvrk_observer_new(
    model: *const DvrkModel,
    gains: *const f64,
) -> *mut DvrkObserver {
    // SAFETY: the caller's obligation, passed on.
    let Some(m) = (unsafe { model_ref(model) }) else {
        return std::ptr::null_mut();
    };
    // SAFETY: the caller's obligation, passed on.
    let Ok(gains) = (unsafe { input(gains, m.model().dof()) }) else {
        return std::ptr::null_mut();
    };
    let made = catch_unwind(|| MomentumObserver::new(m.model(), gains).ok());
    match made {
        Ok(Some(observer)) => Box::into_raw(Box::new(DvrkObserver { model, observer })),
        _ => std::ptr::null_mut(),
    }
}

/// Frees an observer from `dvrk_observer_new`; NULL does nothing.
///
/// # Safety
///
/// `observer` is NULL or a pointer from `dvrk_observer_new` not freed yet.
#[no_mangle]
pub unsafe extern "C" fn dvrk_observer_free(observer: *mut DvrkObserver) {
    if !observer.is_null() {
        // SAFETY: the pointer came from `Box::into_raw` in `dvrk_observer_new` and is
        // freed once (the caller's obligation). Dropping it cannot panic.
        drop(unsafe { Box::from_raw(observer) });
    }
}

/// Forgets the previous sample and the estimate: the next update starts the observer
/// again (returning zeros), as after a pause of the control loop or a change of tool.
/// A real-time call: 0, or `DVRK_ERR_NULL`.
///
/// # Safety
///
/// `observer` is NULL or live, not used by another thread during the call.
#[no_mangle]
pub unsafe extern "C" fn dvrk_observer_reset(observer: *mut DvrkObserver) -> c_int {
    // SAFETY: NULL or live, used by this thread alone (the caller's obligation).
    match unsafe { observer.as_mut() } {
        Some(o) => {
            o.observer.reset();
            crate::DVRK_OK
        }
        None => DVRK_ERR_NULL,
    }
}

/// One control cycle of the observer: the sample `q` (rad or m), `dq` (rad/s or m/s)
/// and applied torque `tau` (N·m or N per model coordinate, as measured: known forces
/// such as the MTM's cable are the model's), `dt` seconds after the previous update.
/// Writes into `tau_ext` the estimate of the external torque `tau − tau_model` (the
/// torque the joints apply beyond the result's model, e.g. `+g` of a payload it does not
/// know; the opposite of the torque the environment applies), N·m or N per model
/// coordinate. The first update (and the first after `dvrk_observer_reset`) only stores
/// the sample and writes zeros. A real-time call.
///
/// On an error the observer too is untouched, except on `DVRK_ERR_OVERFLOW` (an
/// estimate that is not finite), which resets it. `DVRK_ERR_NOT_FINITE` covers `dt` as
/// well; `DVRK_ERR_ARGUMENT` is `dt ≤ 0` or an observer of another model.
///
/// # Safety
///
/// As every real-time call, with the vectors `q`, `dq`, `tau` and `tau_ext`; `observer` is
/// NULL or live, made for `model` and used by this thread alone.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn dvrk_observer_update(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    observer: *mut DvrkObserver,
    q: *const f64,
    dq: *const f64,
    tau: *const f64,
    dt: f64,
    tau_ext: *mut f64,
) -> c_int {
    guarded(|| {
        // SAFETY: the caller's obligations, passed on.
        let (m, w) = unsafe { pair(model, ws) }?;
        // SAFETY: NULL or live, used by this thread alone (the caller's obligation).
        let o = unsafe { observer.as_mut() }.ok_or(DVRK_ERR_NULL)?;
        if !std::ptr::eq(o.model, model) {
            return Err(DVRK_ERR_ARGUMENT);
        }
        let n = m.model().dof();
        // SAFETY: the caller's obligations, passed on.
        let ([q, dq, tau], out) = unsafe { slices([q, dq, tau], n, tau_ext, n) }?;
        finite(&[q, dq, tau, &[dt]])?;
        if dt <= 0.0 {
            return Err(DVRK_ERR_ARGUMENT);
        }
        let estimate = o
            .observer
            .update(m.model(), &mut w.ws, m.params(), q, dq, tau, dt);
        if crate::boundary::deliver(estimate, out).is_err() {
            o.observer.reset();
            return Err(DVRK_ERR_OVERFLOW);
        }
        Ok(())
    })
}
