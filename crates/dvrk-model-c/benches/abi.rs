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
fn paired(a: &mut dyn FnMut(), b: &mut dyn FnMut()) -> (f64, f64) {
    let block = |f: &mut dyn FnMut()| {
        let start = std::time::Instant::now();
        for _ in 0..BLOCK {
            f();
        }
        start.elapsed().as_nanos() as f64 / BLOCK as f64
    };
    // Warm-up (caches, branch predictors, the clock's frequency), not counted.
    for _ in 0..ROUNDS / 8 {
        block(a);
        block(b);
    }
    let (mut best_a, mut best_b) = (f64::INFINITY, f64::INFINITY);
    for round in 0..ROUNDS {
        if round % 2 == 0 {
            best_a = best_a.min(block(a));
            best_b = best_b.min(block(b));
        } else {
            best_b = best_b.min(block(b));
            best_a = best_a.min(block(a));
        }
    }
    (best_a, best_b)
}

/// One computation through two paths: dvrk-model directly and the `extern "C"` entry.
struct Paths<'a> {
    algorithm: &'static str,
    rust: Box<dyn FnMut() + 'a>,
    abi: Box<dyn FnMut() + 'a>,
}

fn bench_robot(c: &mut Criterion, robot: &str, source: &str) {
    let (model, params, path) = result_of(robot, source);
    let n = model.dof();
    let q: Vec<f64> = (0..n).map(|i| 0.1 + 0.05 * i as f64).collect();
    let dq: Vec<f64> = (0..n).map(|i| 0.3 - 0.1 * i as f64).collect();
    let ddq: Vec<f64> = (0..n).map(|i| 0.5 * i as f64 - 1.0).collect();
    let mut applied = vec![0.0; n];
    model.inverse_dynamics(
        &mut Workspace::new(&model),
        &params,
        &q,
        &dq,
        &ddq,
        &mut applied,
    );
    model.add_known_forces(&q, &mut applied);

    let c_path = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path, no error buffer.
    let dm = unsafe { dvrk_model_from_result(c_path.as_ptr(), std::ptr::null_mut(), 0) };
    assert!(!dm.is_null(), "{robot}: the result loads");
    // SAFETY: a live model.
    let dw = unsafe { dvrk_workspace_new(dm) };

    // Each closure owns its output (and the Rust ones a workspace), so the two paths
    // share nothing but the inputs.
    let (model, params, q, dq, ddq, applied) = (&model, &params, &q, &dq, &ddq, &applied);
    let rust_ws = || Workspace::new(model);
    let mut paths = {
        let (mut ws1, mut ws2, mut ws3, mut ws4) = (rust_ws(), rust_ws(), rust_ws(), rust_ws());
        let (mut t1, mut t2, mut t3, mut t4) =
            (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let (mut m1, mut m2) = (vec![0.0; n * n], vec![0.0; n * n]);
        let (mut a1, mut a2) = (vec![0.0; n], vec![0.0; n]);
        vec![
            Paths {
                algorithm: "inverse dynamics",
                rust: Box::new(move || {
                    model.loaded_inverse_dynamics(&mut ws1, params, black_box(q), dq, ddq, &mut t1);
                    model.add_known_forces(q, &mut t1);
                    black_box(&t1);
                }),
                abi: Box::new(move || {
                    // SAFETY: live model and workspace, buffers of n doubles.
                    let rc = unsafe {
                        dvrk_inverse_dynamics(
                            dm,
                            dw,
                            black_box(q.as_ptr()),
                            dq.as_ptr(),
                            ddq.as_ptr(),
                            t2.as_mut_ptr(),
                        )
                    };
                    black_box((rc, &t2));
                }),
            },
            Paths {
                algorithm: "gravity",
                rust: Box::new(move || {
                    model.gravity_torque(&mut ws2, params, black_box(q), &mut t3);
                    black_box(&t3);
                }),
                abi: Box::new(move || {
                    // SAFETY: live model and workspace, buffers of n doubles.
                    let rc =
                        unsafe { dvrk_gravity(dm, dw, black_box(q.as_ptr()), t4.as_mut_ptr()) };
                    black_box((rc, &t4));
                }),
            },
            Paths {
                algorithm: "mass matrix",
                rust: Box::new(move || {
                    model.mass_matrix_into(&mut ws3, params, black_box(q), &mut m1);
                    black_box(&m1);
                }),
                abi: Box::new(move || {
                    // SAFETY: live model and workspace, buffers of n and n·n doubles.
                    let rc =
                        unsafe { dvrk_mass_matrix(dm, dw, black_box(q.as_ptr()), m2.as_mut_ptr()) };
                    black_box((rc, &m2));
                }),
            },
            Paths {
                algorithm: "forward dynamics",
                rust: Box::new(move || {
                    model
                        .forward_dynamics_into(&mut ws4, params, black_box(q), dq, applied, &mut a1)
                        .expect("physical parameters");
                    black_box(&a1);
                }),
                abi: Box::new(move || {
                    // SAFETY: live model and workspace, buffers of n doubles.
                    let rc = unsafe {
                        dvrk_forward_dynamics(
                            dm,
                            dw,
                            black_box(q.as_ptr()),
                            dq.as_ptr(),
                            applied.as_ptr(),
                            a2.as_mut_ptr(),
                        )
                    };
                    assert_eq!(rc, DVRK_OK);
                    black_box(&a2);
                }),
            },
        ]
    };
    // The paired measurement (see the file's comment): one line per algorithm.
    for p in &mut paths {
        let (rust, abi) = paired(&mut *p.rust, &mut *p.abi);
        println!(
            "paired {robot} {}: rust {rust:.1} ns, abi {abi:.1} ns, overhead {:+.1} %",
            p.algorithm,
            100.0 * (abi / rust - 1.0)
        );
    }
    for p in &mut paths {
        c.bench_function(&format!("{robot} {} rust", p.algorithm), |b| {
            b.iter(&mut p.rust)
        });
        c.bench_function(&format!("{robot} {} abi", p.algorithm), |b| {
            b.iter(&mut p.abi)
        });
    }
    drop(paths);
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
