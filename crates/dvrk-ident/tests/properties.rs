//! Property tests (proptest, stable Rust) of invariants that hold for any accepted input:
//!
//! - the streamed (block) processing of a log equals the whole-log processing, for any
//!   signal, length, cut-off, trimming and choice of measured velocities and torque
//!   filtering;
//! - the observation (R factor) of samples does not depend on how they are split into
//!   chunks nor on the order the chunks are merged in.
//!
//! The seeds are fixed, so a run is reproducible. (That a streamed fit equals the
//! in-memory fit for any block size is in `stream_fit.rs`.)

#[path = "support/logs.rs"]
mod logs;

use dvrk_ident::joint_log::{uniform_time, Coordinates, JointLog};
use dvrk_ident::observation::{Observation, Samples};
use dvrk_ident::signal::stream::process_in_blocks;
use dvrk_ident::signal::{process, Cutoff, LowPass, Processing};
use dvrk_model::Model;
use logs::worst_relative;
use nalgebra::DMatrix;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn config(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x005e_ed19),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A signal of `n` samples at 200 Hz per joint: a sum of sines given by
/// `(amplitude, frequency Hz, phase)` triples, plus a square wave of the given height
/// (the friction steps of a torque).
fn signal(n: usize, waves: &[(f64, f64, f64)], step: f64, joint: usize) -> Vec<f64> {
    let time = uniform_time(n, 200.0);
    time.iter()
        .map(|&t| {
            let mut v: f64 = waves
                .iter()
                .map(|&(a, f, p)| a * (2.0 * std::f64::consts::PI * f * t + p + joint as f64).sin())
                .sum();
            v += if (0.7 * t + joint as f64).sin() > 0.0 {
                step
            } else {
                -step
            };
            v
        })
        .collect()
}

fn trajectory(n: usize, waves: &[(f64, f64, f64)], step: f64, with_dq: bool) -> JointLog {
    let dof = 3;
    let column = |scale: f64, offset: usize| {
        let cols: Vec<Vec<f64>> = (0..dof)
            .map(|j| signal(n, waves, step * scale, j + offset))
            .collect();
        DMatrix::from_fn(n, dof, |i, j| scale * cols[j][i])
    };
    JointLog {
        time: uniform_time(n, 200.0),
        q: column(1.0, 0),
        dq: with_dq.then(|| column(3.0, 5)),
        tau: column(2.0, 11),
        joint_names: vec!["a".into(), "b".into(), "c".into()],
        coordinates: Coordinates::Model,
        source: "property".into(),
    }
}

proptest! {
    #![proptest_config(config(48))]

    #[test]
    fn block_processing_equals_whole_log_processing(
        n in 300usize..4000,
        waves in proptest::collection::vec((0.01f64..2.0, 0.05f64..30.0, 0.0f64..6.3), 1..5),
        step in 0.0f64..0.5,
        with_dq: bool,
        filter_torque: bool,
        cutoff in 0.5f64..60.0,
        trim in 0usize..150,
    ) {
        let log = trajectory(n, &waves, step, with_dq);
        let settings = Processing {
            filter: Some(LowPass { cutoff_hz: Cutoff::All(cutoff), ..LowPass::default() }),
            filter_torque,
            trim,
            ..Processing::default()
        };
        // Both refuse, or both give the same samples.
        match (process(&log, &settings), process_in_blocks(std::slice::from_ref(&log), &settings)) {
            (Ok(whole), Ok(blocks)) => {
                prop_assert_eq!(whole.len(), blocks.len());
                prop_assert_eq!(&whole.time, &blocks.time);
                let w = worst_relative(&blocks, &whole);
                prop_assert!(w < 1e-9, "differs by {:e}", w);
            }
            (Err(a), Err(b)) => prop_assert_eq!(a.to_string(), b.to_string()),
            (a, b) => prop_assert!(false, "whole {:?}, blocks {:?}", a.err(), b.err()),
        }
    }
}

/// `rows` random samples of `model` from `seed`: positions, rates and torques.
fn samples(model: &Model, rows: usize, seed: u64) -> [DMatrix<f64>; 4] {
    let mut rng = dvrk_test_support::Rng::new(seed);
    let mut next = move |scale: f64| rng.uniform(-0.5 * scale, 0.5 * scale);
    let n = model.dof();
    [2.0, 4.0, 20.0, 10.0].map(|scale| DMatrix::from_fn(rows, n, |_, _| next(scale)))
}

proptest! {
    #![proptest_config(config(24))]

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
