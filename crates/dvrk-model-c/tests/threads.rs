//! The documented thread contract, exercised: one `DvrkModel` shared read-only by four
//! threads, each with its own `DvrkWorkspace`, gives every thread the results one thread
//! alone gets, bit for bit (gravity, inverse dynamics, mass matrix, forward dynamics at
//! 200 states each, the threads running at once).

mod common;

use std::ffi::CString;

use dvrk_model_c::*;

/// The shared model crosses threads as an address: `DvrkModel` is immutable after
/// loading (the header's contract), which is what this test checks holds.
#[derive(Clone, Copy)]
struct Shared(*const DvrkModel);
// SAFETY: the model is only read after loading, by every thread (the contract tested).
unsafe impl Send for Shared {}

/// Gravity, inverse dynamics, mass matrix and forward dynamics at `states` deterministic
/// states, concatenated, computed in a workspace of this thread's own.
fn evaluate(model: Shared, seed: usize, states: usize) -> Vec<f64> {
    let model = model.0;
    // SAFETY: a live model, read only.
    let (ws, n) = unsafe { (dvrk_workspace_new(model), dvrk_model_dof(model)) };
    assert!(!ws.is_null());
    let mut out = Vec::new();
    let (mut g, mut tau, mut m, mut ddq_fd) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n * n], vec![0.0; n]);
    for k in 0..states {
        let x = |i: usize, scale: f64| {
            scale * (((seed * 7919 + k * 131 + i * 17) % 997) as f64 / 498.5 - 1.0)
        };
        let q: Vec<f64> = (0..n)
            .map(|i| x(i, if i == 2 { 0.1 } else { 1.0 }))
            .collect();
        let dq: Vec<f64> = (0..n).map(|i| x(i + n, 2.0)).collect();
        let ddq: Vec<f64> = (0..n).map(|i| x(i + 2 * n, 5.0)).collect();
        // SAFETY: a live model, this thread's workspace, buffers of n and n·n doubles.
        let codes = unsafe {
            [
                dvrk_gravity(model, ws, q.as_ptr(), g.as_mut_ptr()),
                dvrk_inverse_dynamics(
                    model,
                    ws,
                    q.as_ptr(),
                    dq.as_ptr(),
                    ddq.as_ptr(),
                    tau.as_mut_ptr(),
                ),
                dvrk_mass_matrix(model, ws, q.as_ptr(), m.as_mut_ptr()),
                dvrk_forward_dynamics(
                    model,
                    ws,
                    q.as_ptr(),
                    dq.as_ptr(),
                    tau.as_ptr(),
                    ddq_fd.as_mut_ptr(),
                ),
            ]
        };
        assert_eq!(codes, [DVRK_OK; 4], "state {k} of seed {seed}");
        for v in [&g, &tau, &m, &ddq_fd] {
            out.extend_from_slice(v);
        }
    }
    // SAFETY: this thread's workspace, freed once.
    unsafe { dvrk_workspace_free(ws) };
    out
}

#[test]
fn one_model_shared_by_threads_with_a_workspace_each() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("threads");
    std::fs::create_dir_all(&dir).unwrap();
    let path = CString::new(common::fit_example(&dir).to_str().unwrap()).unwrap();
    let mut err = [0 as std::ffi::c_char; 256];
    // SAFETY: a NUL-terminated path and an error buffer of its length.
    let model = unsafe { dvrk_model_from_result(path.as_ptr(), err.as_mut_ptr(), err.len()) };
    assert!(!model.is_null());
    let shared = Shared(model);
    const THREADS: usize = 4;
    const STATES: usize = 200;
    let alone: Vec<Vec<f64>> = (0..THREADS)
        .map(|seed| evaluate(shared, seed, STATES))
        .collect();
    let together: Vec<Vec<f64>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..THREADS)
            .map(|seed| scope.spawn(move || evaluate(shared, seed, STATES)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (seed, (a, t)) in alone.iter().zip(&together).enumerate() {
        assert!(a.iter().all(|v| v.is_finite()), "seed {seed}");
        let same = a.iter().zip(t).all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(
            same && a.len() == t.len(),
            "thread {seed} differs from the same calls alone"
        );
    }
    // The seeds give different states: the comparison is not of one repeated result.
    assert_ne!(alone[0], alone[1]);
    // SAFETY: the model loaded above, freed once after every workspace.
    unsafe { dvrk_model_free(model) };
}
