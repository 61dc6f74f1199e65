//! The observation's tests: the chunked R factor against one QR of the stacked rows, each coordinate's part, batches of whole chunks to the bit, merge and select.

use super::*;
use crate::progress::Silent;
use crate::signal::stack_rows;

fn random_samples(model: &Model, count: usize, seed: u64) -> [DMatrix<f64>; 4] {
    let n = model.dof();
    let mut rng = dvrk_test_support::Rng::new(seed);
    let mut next = move || rng.uniform(-1.0, 1.0);
    let mut m = || DMatrix::from_fn(count, n, |_, _| next());
    [m(), m(), m(), m()]
}

/// The samples of the matrices `[q, q̇, q̈, τ]`.
fn samples(m: &[DMatrix<f64>; 4]) -> Samples<'_> {
    let [q, dq, ddq, tau] = m;
    Samples { q, dq, ddq, tau }
}

/// Rows `lo..hi` of each of `[q, q̇, q̈, τ]`.
fn rows(m: &[DMatrix<f64>; 4], lo: usize, hi: usize) -> [DMatrix<f64>; 4] {
    m.each_ref().map(|x| x.rows(lo, hi - lo).into_owned())
}

#[test]
fn chunked_factor_equals_one_shot_qr() {
    let model = Model::builtin("psm").unwrap();
    let (n, p) = (model.dof(), model.n_params());
    let count = 3 * CHUNK_SAMPLES + 17;
    let m = random_samples(&model, count, 7);
    let weights: Vec<f64> = (0..n).map(|j| 1.0 + 0.1 * j as f64).collect();
    let obs = Observation::assemble(&model, samples(&m), &weights);
    assert_eq!(obs.rows(), count * n);
    // One-shot: the whole weighted matrix at once.
    let full = weighted_rows(&model, samples(&m), &weights);
    // The Gram matrices agree (R is unique only up to the rank-deficient block).
    let g1 = obs.r().transpose() * obs.r();
    let g2 = full.transpose() * &full;
    let scale = g2.amax();
    assert!((g1 - g2).amax() < 1e-10 * scale);
    // Least-squares residual of any parameter vector agrees.
    let pi = nalgebra::DVector::from_fn(p, |i, _| (i as f64 * 0.37).sin());
    let mut x = pi.clone().insert_row(p, -1.0);
    let r1 = (obs.r() * &x).norm();
    let r2 = (&full * &x).norm();
    assert!((r1 - r2).abs() < 1e-9 * r2);
    x[0] += 1.0;
    assert!(((obs.r() * &x).norm() - (&full * &x).norm()).abs() < 1e-9 * r2);
}

/// The rows `[H | τ]` of coordinate `j`, one per sample, directly.
fn coordinate_rows(model: &Model, s: Samples<'_>, j: usize) -> DMatrix<f64> {
    let (n, p) = (model.dof(), model.n_params());
    let mut ws = Workspace::new(model);
    let (mut a, mut b, mut c) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut h = vec![0.0; n * p];
    let mut rows = DMatrix::zeros(s.len(), p + 1);
    for k in 0..s.len() {
        s.read(k, &mut a, &mut b, &mut c);
        model.advance_hysteresis(&mut ws, &a);
        let tau: Vec<f64> = (0..n).map(|j| s.tau[(k, j)]).collect();
        model.set_load(&mut ws, &tau);
        model.regressor_into(&mut ws, &a, &b, &c, &mut h);
        for col in 0..p {
            rows[(k, col)] = h[j * p + col];
        }
        rows[(k, p)] = s.tau[(k, j)];
    }
    rows
}

/// The rows `[H | τ]` of every coordinate, coordinate `j`'s weighted by `weights[j]`,
/// one block of rows a coordinate.
fn weighted_rows(model: &Model, s: Samples<'_>, weights: &[f64]) -> DMatrix<f64> {
    let blocks: Vec<DMatrix<f64>> = (0..model.dof())
        .map(|j| coordinate_rows(model, s, j) * weights[j])
        .collect();
    stack_rows(&blocks.iter().collect::<Vec<_>>())
}

fn assert_same_gram(what: &str, r: &DMatrix<f64>, rows: &DMatrix<f64>) {
    let g1 = r.transpose() * r;
    let g2 = rows.transpose() * rows;
    let err = (&g1 - &g2).amax();
    assert!(
        err < 1e-12 * g2.amax(),
        "{what}: Gram matrices differ by {err:e}"
    );
}

#[test]
fn per_coordinate_parts_hold_their_coordinates_rows() {
    let mtm = Model::builtin("mtm").unwrap();
    // With Dahl friction the states integrated in time order before the parallel
    // chunks equal those of the sample-by-sample rows.
    for model in [mtm.clone(), mtm.with_dahl(20.0).unwrap()] {
        per_coordinate_parts_of(&model);
    }
}

fn per_coordinate_parts_of(model: &Model) {
    let model = model.clone();
    let n = model.dof();
    let mut m = random_samples(&model, 2 * CHUNK_SAMPLES + 700, 11);
    // At rest for a chunk and a half: the Coulomb, viscous and motor-inertia columns
    // are zero until the arm moves, then join the factors.
    for k in 0..CHUNK_SAMPLES * 3 / 2 {
        for j in 0..n {
            m[1][(k, j)] = 0.0;
            m[2][(k, j)] = 0.0;
        }
    }
    let s = samples(&m);
    let parts = Observation::assemble_per_coordinate(&model, s, &Silent);
    assert_eq!(parts.len(), n);
    for (j, part) in parts.iter().enumerate() {
        assert_eq!(part.rows(), s.len());
        let r = part.r();
        for i in 0..r.nrows() {
            assert!(r[(i, i)] >= 0.0, "non-negative diagonal");
            for c in 0..i {
                assert_eq!(r[(i, c)], 0.0, "upper triangular");
            }
        }
        assert_same_gram(
            &format!("coordinate {j}"),
            r,
            &coordinate_rows(&model, s, j),
        );
    }
    // Weighted: the factor of the weighted rows of all coordinates.
    let weights: Vec<f64> = (0..n).map(|j| 0.5 + 0.3 * j as f64).collect();
    let combined = Observation::weighted(&parts, &weights);
    assert_same_gram(
        "weighted",
        combined.r(),
        &weighted_rows(&model, s, &weights),
    );
}

#[test]
fn batches_of_whole_chunks_give_the_same_factors_to_the_bit() {
    let psm = Model::builtin("psm").unwrap();
    // The Dahl states carried from batch to batch: streamed == in memory, to the bit.
    for model in [psm.clone(), psm.with_dahl(20.0).unwrap()] {
        batches_of(&model);
    }
}

fn batches_of(model: &Model) {
    let model = model.clone();
    let m = random_samples(&model, 4 * CHUNK_SAMPLES + 123, 5);
    let once = Observation::assemble_per_coordinate(&model, samples(&m), &Silent);
    let mut reduction = PerCoordinate::new(&model);
    let cuts = [0, CHUNK_SAMPLES, 3 * CHUNK_SAMPLES, m[0].nrows()];
    for w in cuts.windows(2) {
        reduction.add(&model, samples(&rows(&m, w[0], w[1])), &Silent);
    }
    let batched = reduction.finish();
    for (x, y) in once.iter().zip(&batched) {
        assert_eq!(x.r(), y.r());
        assert_eq!(x.rows(), y.rows());
    }
}

#[test]
fn merge_and_select_are_exact() {
    let model = Model::builtin("mtm").unwrap();
    let n = model.dof();
    let m = random_samples(&model, 300, 3);
    let w = vec![1.0; n];
    let all = Observation::assemble(&model, samples(&m), &w);
    let mut a = Observation::assemble(&model, samples(&rows(&m, 0, 100)), &w);
    let b = Observation::assemble(&model, samples(&rows(&m, 100, 300)), &w);
    a.merge(&b);
    assert_eq!(a.rows(), all.rows());
    let g1 = a.r().transpose() * a.r();
    let g2 = all.r().transpose() * all.r();
    assert!((g1 - &g2).amax() < 1e-10 * g2.amax());
    // Selecting columns equals the Gram sub-matrix.
    let cols = [0usize, 5, 9, 40];
    let s = all.select(&cols);
    let gs = s.r().transpose() * s.r();
    let p = model.n_params();
    let idx = [0usize, 5, 9, 40, p];
    for (i, &a) in idx.iter().enumerate() {
        for (j, &b) in idx.iter().enumerate() {
            assert!((gs[(i, j)] - g2[(a, b)]).abs() < 1e-10 * g2.amax());
        }
    }
}
