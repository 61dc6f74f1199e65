//! The real-time calls allocate nothing once the workspace exists: a counting global
//! allocator (this test binary only) counts allocations on the current thread while a
//! flag is set.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use dvrk_test_support as support;

use dvrk_model::{Model, MomentumObserver, Workspace};

struct Counting;

thread_local! {
    static ACTIVE: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

fn note() {
    // `try_with`: the allocator may run while thread-locals are being torn down.
    let _ = ACTIVE.try_with(|a| {
        if a.get() {
            let _ = COUNT.try_with(|c| c.set(c.get() + 1));
        }
    });
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Number of allocations made by `f` on this thread.
fn allocations(f: impl FnOnce()) -> usize {
    COUNT.with(|c| c.set(0));
    ACTIVE.with(|a| a.set(true));
    f();
    ACTIVE.with(|a| a.set(false));
    COUNT.with(|c| c.get())
}

#[test]
fn the_counter_counts() {
    let n = allocations(|| {
        let v = std::hint::black_box(vec![1u8; 100]);
        drop(v);
    });
    assert_eq!(n, 1);
    assert_eq!(allocations(|| {}), 0);
}

fn check(name: &str) {
    let model = Model::builtin(name).unwrap();
    // Physical parameters: forward dynamics needs a positive definite mass matrix.
    let params = support::physical_params(&model, &mut support::Rng::new(5));
    check_model(&model, name, params);
}

/// The real-time calls of `model` with `params` allocate nothing.
fn check_model(model: &Model, name: &str, params: Vec<f64>) {
    let model = model.clone();
    let (n, p) = (model.dof(), model.n_params());
    let mut ws = Workspace::new(&model);
    let q: Vec<f64> = (0..n).map(|k| 0.1 + 0.13 * k as f64).collect();
    let dq: Vec<f64> = (0..n).map(|k| -0.3 + 0.11 * k as f64).collect();
    let ddq: Vec<f64> = (0..n).map(|k| 0.5 - 0.07 * k as f64).collect();
    // Another parameter set: the bodies' merged inertias are recomputed in place.
    let other: Vec<f64> = params.iter().map(|x| 1.5 * x).collect();
    let mut tau = vec![0.0; n];
    let mut acc = vec![0.0; n];
    let mut mass = vec![0.0; n * n];
    let mut h = vec![0.0; n * p];
    // Warm-up (first calls may initialize lazily).
    model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
    model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);

    let mut report = Vec::new();
    let a = allocations(|| model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau));
    report.push(("inverse_dynamics", a));
    let a = allocations(|| model.gravity_torque(&mut ws, &params, &q, &mut tau));
    report.push(("gravity_torque", a));
    let a = allocations(|| model.mass_matrix_into(&mut ws, &params, &q, &mut mass));
    report.push(("mass_matrix_into", a));
    let a = allocations(|| model.nonlinear_effects(&mut ws, &params, &q, &dq, &mut tau));
    report.push(("nonlinear_effects", a));
    let a = allocations(|| {
        model
            .forward_dynamics_into(&mut ws, &params, &q, &dq, &tau, &mut acc)
            .unwrap()
    });
    report.push(("forward_dynamics_into", a));
    let a = allocations(|| model.mass_matrix_into(&mut ws, &other, &q, &mut mass));
    report.push(("mass_matrix_into, new parameters", a));
    let a = allocations(|| model.inverse_dynamics(&mut ws, &other, &q, &dq, &ddq, &mut tau));
    report.push(("inverse_dynamics, new parameters", a));
    let a = allocations(|| model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h));
    report.push(("regressor_into", a));
    let a = allocations(|| model.set_load(&mut ws, &ddq));
    report.push(("set_load", a));
    let a =
        allocations(|| model.loaded_inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau));
    report.push(("loaded_inverse_dynamics", a));
    let a = allocations(|| model.add_known_forces(&q, &mut tau));
    report.push(("add_known_forces", a));
    let a = allocations(|| model.forward_kinematics(&mut ws, &q));
    report.push(("forward_kinematics", a));
    let mut observer = MomentumObserver::new(&model, &vec![50.0; n]).unwrap();
    observer.update(&model, &mut ws, &params, &q, &dq, &tau, 1e-3);
    let mut estimate = vec![0.0; n];
    let a = allocations(|| {
        let r = observer.update(&model, &mut ws, &params, &q, &dq, &tau, 1e-3);
        estimate.copy_from_slice(r);
    });
    report.push(("MomentumObserver::update", a));
    // A new step: its lag coefficients are recomputed in place.
    let a = allocations(|| {
        observer.update(&model, &mut ws, &params, &dq, &q, &tau, 2e-3);
    });
    report.push(("MomentumObserver::update, new dt", a));
    let bad: Vec<_> = report.iter().filter(|(_, a)| *a != 0).collect();
    assert!(bad.is_empty(), "{name}: allocations per call: {bad:?}");
    // The calls did something.
    assert!(h.iter().any(|x| *x != 0.0) && mass.iter().any(|x| *x != 0.0));
    assert!(acc.iter().all(|x| x.is_finite()) && acc.iter().any(|x| *x != 0.0));
    assert!(estimate.iter().all(|x| x.is_finite()) && estimate.iter().any(|x| *x != 0.0));
}

#[test]
fn psm_real_time_calls_do_not_allocate() {
    check("psm");
}

/// The PSM with every element the fit's flags add (Stribeck, Dahl, position torque of
/// order 2, load friction): their parameters appended after the built-in ones.
#[test]
fn psm_with_the_flags_elements_does_not_allocate() {
    let psm = Model::builtin("psm").unwrap();
    let mut params = support::physical_params(&psm, &mut support::Rng::new(5));
    let model = psm
        .with_stribeck(0.3)
        .and_then(|m| m.with_dahl(20.0))
        .and_then(|m| m.with_position_torque(2))
        .unwrap()
        .with_load_friction();
    params.resize(model.n_params(), 0.05);
    check_model(&model, "psm with elements", params);
}

#[test]
fn mtm_real_time_calls_do_not_allocate() {
    // The MTM has the nonlinear wrist spring (an exmex expression) and the cable force.
    check("mtm");
}

/// A long nonlinear spring expression (25 operands, near the 32 that exmex evaluates
/// on the stack; longer ones are refused at load) must not allocate either.
#[test]
fn long_spring_expression_does_not_allocate() {
    let text = r#"
name = "long spring"
convention = "modified"
coordinates = ["q1", "q2"]
[[frames]]
name = "j1"
parent = "base"
theta = "q1"
inertia = true
spring = "sin(q1) + cos(q2) + q1*q2 + q1^2 + q2^2 + 1.5*q1 - 0.5*q2 + 0.1*q1*q1*q1 + sin(q1 + q2) + cos(q1 - q2) + sqrt(1 + q1^2) + exp(0.1*q1)"
[[frames]]
name = "j2"
parent = "j1"
theta = "q2"
a = 0.3
inertia = true
"#;
    let model = Model::from_toml_str(text, "long.toml").unwrap();
    let mut ws = Workspace::new(&model);
    let params = vec![0.1; model.n_params()];
    let mut tau = [0.0; 2];
    let mut h = vec![0.0; 2 * model.n_params()];
    let (q, dq, ddq) = ([0.1, 0.2], [0.3, 0.4], [0.5, 0.6]);
    // Warm-up (first calls may initialize lazily).
    model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
    let a = allocations(|| model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau));
    let b = allocations(|| model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h));
    assert_eq!(
        (a, b),
        (0, 0),
        "allocations in inverse_dynamics, regressor_into with a long spring"
    );
}
