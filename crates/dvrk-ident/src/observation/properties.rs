//! Property test (proptest, stable Rust, fixed seed): the observation (R factor) of
//! samples does not depend on how they are split into chunks nor on the order the chunks
//! are merged in.

use super::*;
use dvrk_test_support::fixed_seed_config;
use proptest::prelude::*;

/// `rows` random samples of `model` from `seed`: positions, rates and torques.
fn samples(model: &Model, rows: usize, seed: u64) -> [DMatrix<f64>; 4] {
    let mut rng = dvrk_test_support::Rng::new(seed);
    let mut next = move |scale: f64| rng.uniform(-0.5 * scale, 0.5 * scale);
    let n = model.dof();
    [2.0, 4.0, 20.0, 10.0].map(|scale| DMatrix::from_fn(rows, n, |_, _| next(scale)))
}

proptest! {
    #![proptest_config(fixed_seed_config(24))]

    #[test]
    fn merge_order_does_not_matter(
        robot in 0usize..2,
        seed: u64,
        rows in 40usize..400,
        cuts in proptest::collection::vec(0.0f64..1.0, 1..6),
        order_seed: u64,
        weights in proptest::collection::vec(0.1f64..10.0, 7),
    ) {
        let model = Model::builtin(["psm", "mtm"][robot]).unwrap();
        let n = model.dof();
        let [q, dq, ddq, tau] = samples(&model, rows, seed);
        let w = &weights[..n];
        let whole = Observation::assemble(
            &model,
            Samples { q: &q, dq: &dq, ddq: &ddq, tau: &tau },
            w,
        );
        // Chunks at the cut points, assembled separately.
        let mut bounds: Vec<usize> = cuts.iter().map(|c| (c * rows as f64) as usize).collect();
        bounds.extend([0, rows]);
        bounds.sort_unstable();
        bounds.dedup();
        let mut chunks: Vec<Observation> = bounds
            .windows(2)
            .map(|b| {
                let part = |m: &DMatrix<f64>| m.rows(b[0], b[1] - b[0]).into_owned();
                let (q, dq, ddq, tau) = (part(&q), part(&dq), part(&ddq), part(&tau));
                Observation::assemble(&model, Samples { q: &q, dq: &dq, ddq: &ddq, tau: &tau }, w)
            })
            .collect();
        // Merged in a shuffled order (Fisher–Yates from `order_seed`).
        let mut rng = dvrk_test_support::Rng::new(order_seed);
        for i in (1..chunks.len()).rev() {
            chunks.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        let mut merged = Observation::new(model.n_params());
        for c in &chunks {
            merged.merge(c);
        }
        prop_assert_eq!(merged.rows(), whole.rows());
        // The R factors are unique up to row signs: compare RᵀR, the Gram matrix of
        // [W·H | W·τ].
        let g1 = merged.r().transpose() * merged.r();
        let g2 = whole.r().transpose() * whole.r();
        let d = (&g1 - &g2).amax() / g2.amax();
        prop_assert!(d < 1e-10, "Gram matrices differ by {:e} relative", d);
    }
}
