//! Property tests (proptest, stable Rust) of an invariant that holds for any accepted
//! input: the streamed (block) processing of a log equals the whole-log processing, for
//! any signal, length, cut-off, trimming and choice of measured velocities and torque
//! filtering.
//!
//! The seeds are fixed, so a run is reproducible. (That a streamed fit equals the
//! in-memory fit for any block size is in `stream_fit.rs`; that the observation of
//! samples does not depend on their chunks, in the crate's `observation::properties`.)

#[path = "support/logs.rs"]
mod logs;

use dvrk_ident::signal::process_in_blocks;
use dvrk_ident::signal::{process, Cutoff, LowPass, Processing};
use dvrk_ident::{Coordinates, JointLog};
use dvrk_logs::uniform_time;
use dvrk_test_support::fixed_seed_config;
use logs::worst_relative;
use nalgebra::DMatrix;
use proptest::prelude::*;

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
    #![proptest_config(fixed_seed_config(48))]

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
