//! What the tests of logs share: the log helpers of dvrk-logs' tests (the bundled example
//! log, a log cut into parts and its blocks joined back), and how far a block-by-block
//! processing is from the whole-log one. Included with `#[path]` by the tests that use it
//! (they see `Processed`, which the workspace's `dvrk-test-support` crate does not).
#![allow(dead_code, unused_imports)] // each includer uses its own part

#[path = "../../../dvrk-logs/tests/support/logs.rs"]
mod log_parts;
pub use log_parts::{example, part};

use dvrk_ident::signal::Processed;
use nalgebra::DMatrix;

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
