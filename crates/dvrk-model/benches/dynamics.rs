//! Per-sample cost of the real-time algorithms, single thread:
//! `cargo bench -p dvrk-model --bench dynamics`. The README quotes these numbers.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use dvrk_model::{Model, Workspace};

fn sample(n: usize, k: f64) -> Vec<f64> {
    (0..n).map(|i| 0.1 * k + 0.07 * i as f64).collect()
}

fn bench_model(c: &mut Criterion, label: &str, model: &Model) {
    let (n, p) = (model.dof(), model.n_params());
    let mut ws = Workspace::new(model);
    let params: Vec<f64> = (0..p).map(|k| 0.01 + 0.001 * k as f64).collect();
    let (q, dq, ddq) = (sample(n, 1.0), sample(n, 2.0), sample(n, -1.0));
    let mut tau = vec![0.0; n];
    let mut h = vec![0.0; n * p];
    let mut m = vec![0.0; n * n];
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
