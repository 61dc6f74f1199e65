//! The documented thread contract, exercised: one `DvrkModel` shared read-only by four
//! threads, each with its own `DvrkWorkspace`, gives every thread the results one thread
//! alone gets, bit for bit (gravity, inverse dynamics, mass matrix, forward dynamics at
//! 200 states each, the threads running at once).

mod common;

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
    let mut calls = common::Calls::new(n);
    for k in 0..states {
        let x = |i: usize, scale: f64| {
            scale * (((seed * 7919 + k * 131 + i * 17) % 997) as f64 / 498.5 - 1.0)
        };
        for i in 0..n {
            calls.q[i] = x(i, if i == 2 { 0.1 } else { 1.0 });
            calls.dq[i] = x(i + n, 2.0);
            calls.ddq[i] = x(i + 2 * n, 5.0);
        }
        // SAFETY: a live model and this thread's workspace.
        let codes = unsafe { calls.dynamics(model, ws) };
        assert_eq!(codes, [DVRK_OK; 4], "state {k} of seed {seed}");
        for v in [&calls.g, &calls.tau, &calls.m, &calls.ddq_fd] {
            out.extend_from_slice(v);
        }
    }
    // SAFETY: this thread's workspace, freed once.
    unsafe { dvrk_workspace_free(ws) };
    out
}

#[test]
fn one_model_shared_by_threads_with_a_workspace_each() {
    let (_, model) = common::load_example("threads");
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
