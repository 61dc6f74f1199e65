//! A loaded model's sizes, parameters and names, and the workspaces for its calls.

use std::ffi::{c_char, c_int};
use std::panic::catch_unwind;

use dvrk_model::Workspace;

use crate::boundary::model_ref;
use crate::codes::{DVRK_ERR_NULL, DVRK_OK};
use crate::{DvrkModel, DvrkWorkspace};

/// Number of model coordinates `n` (the length of `q`, `dq`, `ddq`, `tau`; the mass
/// matrix is n×n); 0 for NULL.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_dof(model: *const DvrkModel) -> usize {
    // SAFETY: the caller's obligation, passed on.
    unsafe { model_ref(model) }.map_or(0, |m| m.model.dof())
}

/// Number of measured joints (the dVRK's/ROS joint space; equal to the number of model
/// coordinates, which the coupling maps one-to-one); 0 for NULL.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_n_measured(model: *const DvrkModel) -> usize {
    // SAFETY: the caller's obligation, passed on.
    unsafe { model_ref(model) }.map_or(0, |m| m.model.measured.joints.len())
}

/// Number of parameters of the model (with the fit's Stribeck terms); 0 for NULL.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_n_params(model: *const DvrkModel) -> usize {
    // SAFETY: the caller's obligation, passed on.
    unsafe { model_ref(model) }.map_or(0, |m| m.params.len())
}

/// The fitted parameters (`dvrk_model_n_params` doubles, in the order of
/// `dvrk_model_param_name`) copied into `out`.
///
/// # Safety
///
/// `model` is NULL or a live model; `out` is NULL or valid for `dvrk_model_n_params`
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_params(model: *const DvrkModel, out: *mut f64) -> c_int {
    // SAFETY: the caller's obligation, passed on.
    let Some(m) = (unsafe { model_ref(model) }) else {
        return DVRK_ERR_NULL;
    };
    if out.is_null() {
        return DVRK_ERR_NULL;
    }
    // SAFETY: non-NULL and valid for n_params doubles (the caller's obligation).
    let out = unsafe { std::slice::from_raw_parts_mut(out, m.params.len()) };
    out.copy_from_slice(&m.params);
    DVRK_OK
}

/// A NUL-terminated name from `names[index]`, or NULL.
fn name_at(names: &[std::ffi::CString], index: usize) -> *const c_char {
    names.get(index).map_or(std::ptr::null(), |s| s.as_ptr())
}

/// Name of parameter `index` (0-based, e.g. `L1xx`, `Fc1`, `Fs1`), valid as long as the
/// model; NULL for a NULL model or an index out of range.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_param_name(
    model: *const DvrkModel,
    index: usize,
) -> *const c_char {
    // SAFETY: the caller's obligation, passed on.
    unsafe { model_ref(model) }.map_or(std::ptr::null(), |m| name_at(&m.param_names, index))
}

/// Name of model coordinate `index` (0-based), valid as long as the model; NULL for a
/// NULL model or an index out of range.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_coordinate_name(
    model: *const DvrkModel,
    index: usize,
) -> *const c_char {
    // SAFETY: the caller's obligation, passed on.
    unsafe { model_ref(model) }.map_or(std::ptr::null(), |m| name_at(&m.coordinate_names, index))
}

/// Name of measured joint `index` (0-based, the dVRK's/ROS names, e.g. `jaw`), valid as
/// long as the model; NULL for a NULL model or an index out of range.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`.
#[no_mangle]
pub unsafe extern "C" fn dvrk_model_joint_name(
    model: *const DvrkModel,
    index: usize,
) -> *const c_char {
    // SAFETY: the caller's obligation, passed on.
    unsafe { model_ref(model) }.map_or(std::ptr::null(), |m| name_at(&m.joint_names, index))
}

/// A workspace (scratch buffers) for calls on `model`, from one thread at a time; NULL
/// if `model` is NULL. Not real-time (allocates): create it before the control loop.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`, which must outlive
/// the workspace.
#[no_mangle]
pub unsafe extern "C" fn dvrk_workspace_new(model: *const DvrkModel) -> *mut DvrkWorkspace {
    // SAFETY: the caller's obligation, passed on.
    let Some(m) = (unsafe { model_ref(model) }) else {
        return std::ptr::null_mut();
    };
    let made = catch_unwind(|| {
        let n = m.model.dof();
        DvrkWorkspace {
            model,
            ws: Workspace::new(&m.model),
            vector: vec![0.0; n],
            matrix: vec![0.0; n * n],
        }
    });
    made.map_or(std::ptr::null_mut(), |ws| Box::into_raw(Box::new(ws)))
}

/// Frees a workspace from `dvrk_workspace_new`; NULL does nothing.
///
/// # Safety
///
/// `ws` is NULL or a pointer from `dvrk_workspace_new` not freed yet.
#[no_mangle]
pub unsafe extern "C" fn dvrk_workspace_free(ws: *mut DvrkWorkspace) {
    if !ws.is_null() {
        // SAFETY: the pointer came from `Box::into_raw` in `dvrk_workspace_new` and is
        // freed once (the caller's obligation).
        drop(unsafe { Box::from_raw(ws) });
    }
}
