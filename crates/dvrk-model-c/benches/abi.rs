//! What the C ABI costs over the Rust call, single thread:
//! `cargo bench -p dvrk-model-c --bench abi`. For each robot and algorithm, the same
//! computation through dvrk-model directly (`<robot> <algorithm> rust`) and through the
//! `extern "C"` entry point (`... abi`: pointer and finiteness checks, catch_unwind,
//! the copy out of the workspace's scratch buffer). Called from Rust through the rlib,
//! so a C caller's PLT jump into the shared library is not counted (one indirect jump).
//! The model is a result document of the parameters dvrk-model's benchmarks use, for the
//! PSM, the MTM and (when ../shared/anchors is there) the Panda.
//!
//! Before criterion's figures, a paired measurement prints the ABI's overhead itself:
//! blocks of calls through the two paths alternate, and each path's cost is its fastest
//! block. On a loaded machine criterion's separate means of the two paths moved by
//! ±20 % from run to run, far more than the difference to measure; a block that no other
//! process interrupted is what the two minima compare, so the load cancels out.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use dvrk_model::{Model, Workspace};
use dvrk_model_c::*;

// The parameters and the Panda of dvrk-model's own benchmarks, so the figures compare.
#[path = "../../dvrk-model/benches/common/mod.rs"]
#[allow(dead_code)]
mod common;
use common::{physical, PANDA};

/// A result document of `robot` (a built-in name or a description path) with the
/// parameters of dvrk-model's benchmarks (what the loader reads of a result).
fn result_of(label: &str, robot: &str) -> (Model, Vec<f64>, std::path::PathBuf) {
    let model = Model::load(robot).unwrap();
    let params = physical(&model);
    let named: serde_json::Map<String, serde_json::Value> = model
        .param_names()
        .into_iter()
        .zip(&params)
        .map(|(k, v)| (k, serde_json::json!(v)))
        .collect();
    let doc = serde_json::json!({
        "robot": model.name,
        "robot_source": if robot.contains('/') { robot.to_string() } else { format!("builtin:{robot}") },
        "settings": {},
        "parameters": named,
    });
    let path = std::env::temp_dir().join(format!("dvrk_model_c_bench_{label}.json"));
    std::fs::write(&path, doc.to_string()).unwrap();
    (model, params, path)
}

/// Calls in a block of the paired measurement, and blocks per path.
const BLOCK: usize = 200;
const ROUNDS: usize = 400;

/// The fastest block's time per call (ns) of `a` and of `b`, their blocks alternating
/// (and which one goes first, so neither always follows the other).
fn paired(mut a: impl FnMut(), mut b: impl FnMut()) -> (f64, f64) {
    let block = |f: &mut dyn FnMut()| {
        let start = std::time::Instant::now();
        for _ in 0..BLOCK {
            f();
        }
        start.elapsed().as_nanos() as f64 / BLOCK as f64
    };
    // Warm-up (caches, branch predictors, the clock's frequency), not counted.
    for _ in 0..ROUNDS / 8 {
        block(&mut a);
        block(&mut b);
    }
    let (mut best_a, mut best_b) = (f64::INFINITY, f64::INFINITY);
    for round in 0..ROUNDS {
        if round % 2 == 0 {
            best_a = best_a.min(block(&mut a));
            best_b = best_b.min(block(&mut b));
        } else {
            best_b = best_b.min(block(&mut b));
            best_a = best_a.min(block(&mut a));
        }
    }
    (best_a, best_b)
}

fn bench_robot(c: &mut Criterion, robot: &str, source: &str) {
    let (model, params, path) = result_of(robot, source);
    let n = model.dof();
    let mut ws = Workspace::new(&model);
    let q: Vec<f64> = (0..n).map(|i| 0.1 + 0.05 * i as f64).collect();
    let dq: Vec<f64> = (0..n).map(|i| 0.3 - 0.1 * i as f64).collect();
    let ddq: Vec<f64> = (0..n).map(|i| 0.5 * i as f64 - 1.0).collect();
    let mut tau = vec![0.0; n];
    let mut m = vec![0.0; n * n];
    let mut acc = vec![0.0; n];
    model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
    model.add_known_forces(&q, &mut tau);
    let applied = tau.clone();

    let c_path = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path, no error buffer.
    let dm = unsafe { dvrk_model_from_result(c_path.as_ptr(), std::ptr::null_mut(), 0) };
    assert!(!dm.is_null(), "{robot}: the result loads");
    // SAFETY: a live model.
    let dw = unsafe { dvrk_workspace_new(dm) };

    // The paired measurement (see the file's comment): one line per algorithm.
    {
        let cell = std::cell::RefCell::new((&mut ws, &mut tau, &mut m, &mut acc));
        let rows: [(&str, (f64, f64)); 4] = [
            (
                "inverse dynamics",
                paired(
                    || {
                        let (ws, tau, ..) = &mut *cell.borrow_mut();
                        model.inverse_dynamics(ws, &params, black_box(&q), &dq, &ddq, tau);
                        model.add_known_forces(&q, tau);
                        black_box(&tau);
                    },
                    || {
                        let (_, tau, ..) = &mut *cell.borrow_mut();
                        // SAFETY: live model and workspace, buffers of n doubles.
                        let rc = unsafe {
                            dvrk_inverse_dynamics(
                                dm,
                                dw,
                                black_box(q.as_ptr()),
                                dq.as_ptr(),
                                ddq.as_ptr(),
                                tau.as_mut_ptr(),
                            )
                        };
                        black_box((rc, &tau));
                    },
                ),
            ),
            (
                "gravity",
                paired(
                    || {
                        let (ws, tau, ..) = &mut *cell.borrow_mut();
                        model.gravity_torque(ws, &params, black_box(&q), tau);
                        black_box(&tau);
                    },
                    || {
                        let (_, tau, ..) = &mut *cell.borrow_mut();
                        // SAFETY: live model and workspace, buffers of n doubles.
                        let rc = unsafe {
                            dvrk_gravity(dm, dw, black_box(q.as_ptr()), tau.as_mut_ptr())
                        };
                        black_box((rc, &tau));
                    },
                ),
            ),
            (
                "mass matrix",
                paired(
                    || {
                        let (ws, _, m, _) = &mut *cell.borrow_mut();
                        model.mass_matrix_into(ws, &params, black_box(&q), m);
                        black_box(&m);
                    },
                    || {
                        let (_, _, m, _) = &mut *cell.borrow_mut();
                        // SAFETY: live model and workspace, buffers of n and n·n doubles.
                        let rc = unsafe {
                            dvrk_mass_matrix(dm, dw, black_box(q.as_ptr()), m.as_mut_ptr())
                        };
                        black_box((rc, &m));
                    },
                ),
            ),
            (
                "forward dynamics",
                paired(
                    || {
                        let (ws, _, _, acc) = &mut *cell.borrow_mut();
                        model
                            .forward_dynamics_into(ws, &params, black_box(&q), &dq, &applied, acc)
                            .expect("physical parameters");
                        black_box(&acc);
                    },
                    || {
                        let (.., acc) = &mut *cell.borrow_mut();
                        // SAFETY: live model and workspace, buffers of n doubles.
                        let rc = unsafe {
                            dvrk_forward_dynamics(
                                dm,
                                dw,
                                black_box(q.as_ptr()),
                                dq.as_ptr(),
                                applied.as_ptr(),
                                acc.as_mut_ptr(),
                            )
                        };
                        assert_eq!(rc, DVRK_OK);
                        black_box(&acc);
                    },
                ),
            ),
        ];
        for (algorithm, (rust, abi)) in rows {
            println!(
                "paired {robot} {algorithm}: rust {rust:.1} ns, abi {abi:.1} ns, overhead {:+.1} %",
                100.0 * (abi / rust - 1.0)
            );
        }
    }

    c.bench_function(&format!("{robot} inverse dynamics rust"), |b| {
        b.iter(|| {
            model.inverse_dynamics(&mut ws, &params, black_box(&q), &dq, &ddq, &mut tau);
            model.add_known_forces(&q, &mut tau);
            black_box(&tau);
        })
    });
    c.bench_function(&format!("{robot} inverse dynamics abi"), |b| {
        b.iter(|| {
            // SAFETY: live model and workspace, buffers of n doubles.
            let rc = unsafe {
                dvrk_inverse_dynamics(
                    dm,
                    dw,
                    black_box(q.as_ptr()),
                    dq.as_ptr(),
                    ddq.as_ptr(),
                    tau.as_mut_ptr(),
                )
            };
            black_box((rc, &tau));
        })
    });
    c.bench_function(&format!("{robot} gravity rust"), |b| {
        b.iter(|| {
            model.gravity_torque(&mut ws, &params, black_box(&q), &mut tau);
            black_box(&tau);
        })
    });
    c.bench_function(&format!("{robot} gravity abi"), |b| {
        b.iter(|| {
            // SAFETY: live model and workspace, buffers of n doubles.
            let rc = unsafe { dvrk_gravity(dm, dw, black_box(q.as_ptr()), tau.as_mut_ptr()) };
            black_box((rc, &tau));
        })
    });
    c.bench_function(&format!("{robot} mass matrix rust"), |b| {
        b.iter(|| {
            model.mass_matrix_into(&mut ws, &params, black_box(&q), &mut m);
            black_box(&m);
        })
    });
    c.bench_function(&format!("{robot} mass matrix abi"), |b| {
        b.iter(|| {
            // SAFETY: live model and workspace, buffers of n and n·n doubles.
            let rc = unsafe { dvrk_mass_matrix(dm, dw, black_box(q.as_ptr()), m.as_mut_ptr()) };
            black_box((rc, &m));
        })
    });
    c.bench_function(&format!("{robot} forward dynamics rust"), |b| {
        b.iter(|| {
            model
                .forward_dynamics_into(&mut ws, &params, black_box(&q), &dq, &applied, &mut acc)
                .expect("physical parameters");
            black_box(&acc);
        })
    });
    c.bench_function(&format!("{robot} forward dynamics abi"), |b| {
        b.iter(|| {
            // SAFETY: live model and workspace, buffers of n doubles.
            let rc = unsafe {
                dvrk_forward_dynamics(
                    dm,
                    dw,
                    black_box(q.as_ptr()),
                    dq.as_ptr(),
                    applied.as_ptr(),
                    acc.as_mut_ptr(),
                )
            };
            assert_eq!(rc, DVRK_OK);
            black_box(&acc);
        })
    });
    // SAFETY: live pointers, freed once, workspace first.
    unsafe {
        dvrk_workspace_free(dw);
        dvrk_model_free(dm);
    }
}

fn benches(c: &mut Criterion) {
    bench_robot(c, "psm", "psm");
    bench_robot(c, "mtm", "mtm");
    if std::path::Path::new(PANDA).exists() {
        bench_robot(c, "panda", PANDA);
    } else {
        eprintln!("SKIPPED panda: {PANDA} is missing");
    }
}

criterion_group!(abi, benches);
criterion_main!(abi);
