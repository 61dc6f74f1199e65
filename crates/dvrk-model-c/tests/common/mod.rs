//! What the C ABI tests share: the result document they load, the model loaded from it,
//! and the dynamics calls they make at a state.
// Each test binary that declares `mod common` uses part of it.
#![allow(dead_code)]

use std::ffi::{c_int, CString};
use std::path::{Path, PathBuf};

use dvrk_ident::{FitRequest, LogSource, Overrides, Training};
use dvrk_model_c::*;

/// A folder of this test run for `label`'s files, under cargo's target tmp dir.
pub fn scratch_dir(label: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(label);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Fits the bundled example (SDP, the default method, with Stribeck terms of 0.3 rad/s
/// or m/s) and writes the result document into `scratch_dir(label)`.
pub fn fit_example(label: &str) -> PathBuf {
    let log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/psm_excitation.mcap"
    );
    let psm = dvrk_model::Model::builtin("psm").unwrap();
    let request = FitRequest {
        overrides: Overrides {
            stribeck_velocity: Some(0.3),
            ..Overrides::default()
        },
        ..FitRequest::new(Training::Logs(vec![LogSource::File(log.into())]))
    };
    let outcome = request
        .run(Some(&psm), &dvrk_ident::Silent)
        .expect("the example fits");
    assert_eq!(outcome.result.method, "sdp");
    assert!(outcome.result.solver.converged);
    let path = scratch_dir(label).join("psm_sdp.json");
    std::fs::write(&path, outcome.result.to_json()).unwrap();
    path
}

/// [`fit_example`]'s result loaded through the C ABI: its path and the live model (free
/// it with `dvrk_model_free`).
pub fn load_example(label: &str) -> (PathBuf, *mut DvrkModel) {
    let path = fit_example(label);
    let c_path = CString::new(path.to_str().unwrap()).unwrap();
    let mut err = [0 as std::ffi::c_char; 256];
    // SAFETY: a NUL-terminated path and an error buffer of its length.
    let model = unsafe { dvrk_model_from_result(c_path.as_ptr(), err.as_mut_ptr(), err.len()) };
    assert!(!model.is_null(), "the example's result loads");
    (path, model)
}

/// A state (`q`, `dq`, `ddq`) and the outputs of the dynamics calls at it, allocated
/// once, before any call (so that a test counting allocations sees none of theirs).
pub struct Calls {
    pub q: Vec<f64>,
    pub dq: Vec<f64>,
    pub ddq: Vec<f64>,
    /// `dvrk_gravity`'s torque.
    pub g: Vec<f64>,
    /// `dvrk_inverse_dynamics`' torque.
    pub tau: Vec<f64>,
    /// `dvrk_mass_matrix`'s n·n matrix.
    pub m: Vec<f64>,
    /// `dvrk_forward_dynamics`' accelerations under `tau`: `ddq` again.
    pub ddq_fd: Vec<f64>,
}

impl Calls {
    /// Zeros for a model of `n` coordinates.
    pub fn new(n: usize) -> Calls {
        let zeros = || vec![0.0; n];
        Calls {
            q: zeros(),
            dq: zeros(),
            ddq: zeros(),
            g: zeros(),
            tau: zeros(),
            m: vec![0.0; n * n],
            ddq_fd: zeros(),
        }
    }

    /// Gravity, inverse dynamics, mass matrix and forward dynamics (of the inverse
    /// dynamics' torque) at the state: their return codes, in that order.
    ///
    /// # Safety
    ///
    /// `model` is live and `ws` a workspace of it used by this thread alone, both of
    /// the `n` coordinates of [`Calls::new`].
    pub unsafe fn dynamics(
        &mut self,
        model: *const DvrkModel,
        ws: *mut DvrkWorkspace,
    ) -> [c_int; 4] {
        let (q, dq) = (self.q.as_ptr(), self.dq.as_ptr());
        // SAFETY: the caller's model and workspace; every buffer of n (or n·n) doubles.
        unsafe {
            [
                dvrk_gravity(model, ws, q, self.g.as_mut_ptr()),
                dvrk_inverse_dynamics(model, ws, q, dq, self.ddq.as_ptr(), self.tau.as_mut_ptr()),
                dvrk_mass_matrix(model, ws, q, self.m.as_mut_ptr()),
                dvrk_forward_dynamics(
                    model,
                    ws,
                    q,
                    dq,
                    self.tau.as_ptr(),
                    self.ddq_fd.as_mut_ptr(),
                ),
            ]
        }
    }
}
