//! Per-sample cost of the real-time algorithms, single thread:
//! `cargo bench -p dvrk-model --bench dynamics`. The book's Benchmarks
//! (docs/book/src/benchmarks.md) quotes these numbers
//! (`<robot> inverse dynamics`, `full regressor`, `mass matrix`, `forward dynamics`,
//! `gravity`, `nonlinear effects`, `momentum observer`, for psm, mtm and the Panda of
//! `../shared/anchors`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use dvrk_model::{Model, MomentumObserver, Workspace};

mod common;
use common::{physical, sample, PANDA};

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
    // One control cycle of the observer (mass matrix and h in one kinematics pass, the
    // lag's coefficients kept from the previous cycle's equal step).
    let mut observer = MomentumObserver::new(model, &vec![50.0; n]).expect("gains");
    c.bench_function(&format!("{label} momentum observer"), |b| {
        b.iter(|| {
            let r = observer.update(model, &mut ws, &params, black_box(&q), &dq, &applied, 1e-3);
            black_box(r);
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
    match Model::load(PANDA) {
        Ok(model) => bench_model(c, "panda", &model),
        Err(_) => eprintln!("SKIPPED panda benchmarks: {PANDA} not found"),
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = dvrk
}
criterion_main!(benches);
