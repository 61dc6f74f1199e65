//! The real-time calls of the C ABI (gravity, inverse, rigid-body and forward dynamics, mass
//! matrix, measured-joint conversions, the momentum observer's update and reset) allocate nothing: a counting global allocator sees no
//! allocation across many calls of each (successful ones and the error paths), through
//! the `extern "C"` functions themselves, on the SDP+Stribeck fit of the bundled example.
//! (A controller's real-time loop must not reach `malloc`: it may take a lock or page
//! faults.) One test function, so no other test thread allocates meanwhile.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use dvrk_model_c::*;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator unchanged; counting touches no memory.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: the caller's layout, passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's pointer and layout, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: the caller's arguments, passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// `dvrk_observer_update` with the state and inverse dynamics' torque of `calls`, `dt`
/// seconds after the previous update, into `estimate`.
///
/// # Safety
///
/// `model`, `ws` and `observer` are live, made for one another, and of the `n`
/// coordinates of `calls` and `estimate`.
unsafe fn observe(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    observer: *mut DvrkObserver,
    calls: &common::Calls,
    dt: f64,
    estimate: &mut [f64],
) -> std::ffi::c_int {
    let (q, dq, tau) = (calls.q.as_ptr(), calls.dq.as_ptr(), calls.tau.as_ptr());
    // SAFETY: the caller's pointers; buffers of n doubles.
    unsafe { dvrk_observer_update(model, ws, observer, q, dq, tau, dt, estimate.as_mut_ptr()) }
}

#[test]
fn real_time_calls_allocate_nothing() {
    let (path, model) = common::load_example("no_alloc");
    // SAFETY: a live model.
    let ws = unsafe { dvrk_workspace_new(model) };
    // SAFETY: a live model.
    let n = unsafe { dvrk_model_dof(model) };
    let mut calls = common::Calls::new(n);
    for i in 0..n {
        calls.q[i] = 0.1 + 0.05 * i as f64;
        calls.dq[i] = 0.3 - 0.1 * i as f64;
        calls.ddq[i] = 0.5 * i as f64 - 1.0;
    }
    let mut nan = calls.q.clone();
    nan[1] = f64::NAN;
    let mut x = vec![0.0; n];
    let gains = vec![30.0; n];
    // SAFETY: a live model and n gains.
    let observer = unsafe { dvrk_observer_new(model, gains.as_ptr()) };
    assert!(!observer.is_null());
    let mut estimate = vec![0.0; n];

    // The counter counts: a vector allocated here is seen.
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    drop(std::hint::black_box(vec![0u8; 16]));
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst), before + 1);

    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut codes = [0; 12];
    for _ in 0..1000 {
        // SAFETY: a live model and its workspace; every buffer of n (or n·n) doubles.
        unsafe {
            codes[..4].copy_from_slice(&calls.dynamics(model, ws));
            let (q, dq, ddq) = (calls.q.as_ptr(), calls.dq.as_ptr(), calls.ddq.as_ptr());
            codes[4] = dvrk_measured_to_model(model, q, x.as_mut_ptr());
            codes[5] = dvrk_model_to_measured_torque(model, calls.tau.as_ptr(), x.as_mut_ptr());
            // The error paths too.
            codes[6] = dvrk_gravity(model, ws, nan.as_ptr(), calls.g.as_mut_ptr());
            codes[7] = dvrk_mass_matrix(model, std::ptr::null_mut(), q, calls.m.as_mut_ptr());
            codes[8] = dvrk_rigid_body_dynamics(model, ws, q, dq, ddq, x.as_mut_ptr());
            codes[9] = observe(model, ws, observer, &calls, 1e-3, &mut estimate);
            codes[10] = observe(model, ws, observer, &calls, -1.0, &mut estimate);
            std::hint::black_box(dvrk_error_string(DVRK_ERR_NULL));
        }
    }
    // SAFETY: a live observer; reset, then two updates (the second one computes).
    unsafe {
        codes[11] = dvrk_observer_reset(observer);
        for _ in 0..2 {
            observe(model, ws, observer, &calls, 1e-3, &mut estimate);
        }
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert_eq!(&codes[..6], &[DVRK_OK; 6]);
    assert_eq!(codes[6], DVRK_ERR_NOT_FINITE);
    assert_eq!(codes[7], DVRK_ERR_NULL);
    assert_eq!(codes[8], DVRK_OK);
    assert_eq!(codes[9], DVRK_OK);
    assert_eq!(codes[10], DVRK_ERR_ARGUMENT);
    assert_eq!(codes[11], DVRK_OK);
    assert_eq!(
        after - before,
        0,
        "allocations in 1000 rounds of the real-time calls"
    );
    // Forward dynamics inverted the inverse dynamics: the calls computed something.
    let (acc, ddq) = (&calls.ddq_fd, &calls.ddq);
    for (a, d) in acc.iter().zip(ddq) {
        assert!((a - d).abs() < 1e-8, "{acc:?} vs {ddq:?}");
    }
    // The observer computed: q̇ did not change between the two updates after the reset,
    // so the torque of q̈ (the inverse dynamics' tau) is unexplained and the estimate is
    // (1 − e^{−K·dt})·M(q)·q̈.
    let loaded = DvrkModel::from_result(&path).unwrap();
    let mut rust_ws = dvrk_model::Workspace::new(loaded.model());
    let mass = loaded
        .model()
        .mass_matrix(&mut rust_ws, loaded.params(), &calls.q);
    let lag = 1.0 - (-30.0f64 * 1e-3).exp();
    for i in 0..n {
        let expected = lag * (0..n).map(|k| mass[(i, k)] * ddq[k]).sum::<f64>();
        assert!(
            (estimate[i] - expected).abs() <= 1e-9 * (1.0 + expected.abs()),
            "observer {i}: {} vs {expected}",
            estimate[i]
        );
    }
    // SAFETY: live pointers from their constructors, freed once, workspace first.
    unsafe {
        dvrk_observer_free(observer);
        dvrk_workspace_free(ws);
        dvrk_model_free(model);
    }
}
