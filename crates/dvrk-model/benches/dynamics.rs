//! Per-sample cost of the real-time algorithms, single thread:
//! `cargo bench -p dvrk-model --bench dynamics`. The README quotes these numbers
//! (`<robot> inverse dynamics`, `full regressor`, `mass matrix`, `forward dynamics`,
//! `gravity`, `nonlinear effects`, for psm, mtm and the Panda of `../shared/anchors`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use dvrk_model::inertia::barycentric_from_standard;
use dvrk_model::{Model, Workspace};

fn sample(n: usize, k: f64) -> Vec<f64> {
    (0..n).map(|i| 0.1 * k + 0.07 * i as f64).collect()
}

/// Physical parameters (forward dynamics needs a positive definite mass matrix): the
/// description's nominal values when it has them all (the Panda URDF), else every link
/// 1 kg with a box-like inertia, friction, motor inertias and springs.
fn physical(model: &Model) -> Vec<f64> {
    if let Some(p) = model.nominal_parameters() {
        return p;
    }
    let mut pi = vec![0.0; model.n_params()];
    for (i, f) in model.frames.iter().enumerate() {
        let k = i as f64;
        if let Some(p0) = f.inertia {
            let link = barycentric_from_standard(
                1.0 + 0.1 * k,
                [0.01 * k, -0.02, 0.03],
                [0.004, 0.0005, 0.0, 0.005, -0.0003, 0.003],
            );
            pi[p0..p0 + 10].copy_from_slice(&link);
        }
        if let Some(fr) = f.friction() {
            pi[fr.param..fr.param + 3].copy_from_slice(&[0.1, 0.05, 0.01]);
        }
        if let Some(mi) = f.motor_inertia() {
            pi[mi.param] = 0.01;
        }
        if let Some(sp) = f.spring() {
            pi[sp.param] = 0.2;
        }
    }
    pi
}

fn bench_model(c: &mut Criterion, label: &str, model: &Model) {
    let (n, p) = (model.dof(), model.n_params());
    let mut ws = Workspace::new(model);
    let params = physical(model);
    let (q, dq, ddq) = (sample(n, 1.0), sample(n, 2.0), sample(n, -1.0));
    let mut tau = vec![0.0; n];
    let mut h = vec![0.0; n * p];
    let mut m = vec![0.0; n * n];
    let mut acc = vec![0.0; n];
    model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
    let applied = tau.clone();
    c.bench_function(&format!("{label} inverse dynamics"), |b| {
        b.iter(|| {
            model.inverse_dynamics(&mut ws, &params, black_box(&q), &dq, &ddq, &mut tau);
            black_box(&tau);
        })
    });
    c.bench_function(&format!("{label} full regressor"), |b| {
        b.iter(|| {
            model.regressor_into(&mut ws, black_box(&q), &dq, &ddq, &mut h);
            black_box(&h);
        })
    });
    c.bench_function(&format!("{label} mass matrix"), |b| {
        b.iter(|| {
            model.mass_matrix_into(&mut ws, &params, black_box(&q), &mut m);
            black_box(&m);
        })
    });
    c.bench_function(&format!("{label} forward dynamics"), |b| {
        b.iter(|| {
            model
                .forward_dynamics_into(&mut ws, &params, black_box(&q), &dq, &applied, &mut acc)
                .expect("physical parameters");
            black_box(&acc);
        })
    });
    c.bench_function(&format!("{label} gravity"), |b| {
        b.iter(|| {
            model.gravity_torque(&mut ws, &params, black_box(&q), &mut tau);
            black_box(&tau);
        })
    });
    c.bench_function(&format!("{label} nonlinear effects"), |b| {
        b.iter(|| {
            model.nonlinear_effects(&mut ws, &params, black_box(&q), &dq, &mut tau);
            black_box(&tau);
        })
    });
}

fn dvrk(c: &mut Criterion) {
    for name in ["psm", "mtm"] {
        let model = Model::builtin(name).unwrap();
        bench_model(c, name, &model);
        c.bench_function(&format!("{name} load + base parameters"), |b| {
            b.iter(|| {
                let model = Model::builtin(black_box(name)).unwrap();
                black_box(model.base_parameters().unwrap())
            })
        });
    }
    let panda = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/anchors/panda_arm_7dof.urdf"
    );
    match Model::load(panda) {
        Ok(model) => bench_model(c, "panda", &model),
        Err(_) => eprintln!("SKIPPED panda benchmarks: {panda} not found"),
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = dvrk
}
criterion_main!(benches);
