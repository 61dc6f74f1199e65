//! What the tests of logs share: the bundled example log, a log cut into parts and its
//! blocks joined back, and how far a block-by-block processing is from the whole-log
//! one. Included with `#[path]` by the tests that use it (they see `JointLog` and
//! `Processed`, which the workspace's `dvrk-test-support` crate does not).
#![allow(dead_code)] // each includer uses its own part

use dvrk_ident::signal::{stack_rows, Processed};
use dvrk_ident::{log, JointLog};
use nalgebra::DMatrix;

/// The bundled simulated PSM log (`examples/psm_excitation.mcap`).
pub fn example() -> JointLog {
    log::read(
        dvrk_test_support::example("psm_excitation.mcap"),
        None,
        None,
    )
    .unwrap()
}

/// Rows `lo..hi` of a log, times kept, the source naming the range.
pub fn part(t: &JointLog, lo: usize, hi: usize) -> JointLog {
    JointLog {
        source: format!("{} [{lo}..{hi}]", t.source),
        ..t.select_rows(&(lo..hi).collect::<Vec<_>>())
    }
}

/// Consecutive blocks of one log joined back into it (joints, coordinates and source
/// the first block's).
pub fn concatenate(blocks: &[JointLog]) -> JointLog {
    let stack =
        |f: fn(&JointLog) -> &DMatrix<f64>| stack_rows(&blocks.iter().map(f).collect::<Vec<_>>());
    JointLog {
        time: blocks.iter().flat_map(|b| b.time.iter().copied()).collect(),
        q: stack(|b| &b.q),
        dq: blocks[0].dq.as_ref().map(|_| {
            stack_rows(
                &blocks
                    .iter()
                    .map(|b| b.dq.as_ref().expect("every block has velocities"))
                    .collect::<Vec<_>>(),
            )
        }),
        tau: stack(|b| &b.tau),
        ..blocks[0].clone()
    }
}

/// Largest difference relative to the signal's largest magnitude, over q, dq, ddq, tau.
pub fn worst_relative(a: &Processed, b: &Processed) -> f64 {
    let rel = |x: &DMatrix<f64>, y: &DMatrix<f64>| (x - y).amax() / y.amax().max(1e-300);
    [
        rel(&a.q, &b.q),
        rel(&a.dq, &b.dq),
        rel(&a.ddq, &b.ddq),
        rel(&a.tau, &b.tau),
    ]
    .into_iter()
    .fold(0.0, f64::max)
}
