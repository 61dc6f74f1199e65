//! What the tests of logs share: the bundled example log, a log cut into parts and its
//! blocks joined back. Included with `#[path]` by the tests that use it, here and in
//! dvrk-ident (whose `tests/support/logs.rs` adds what compares processed samples).
#![allow(dead_code)] // each includer uses its own part

use dvrk_logs::{log, JointLog};
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

/// The rows of `parts` one after the other.
fn stack_rows(parts: &[&DMatrix<f64>]) -> DMatrix<f64> {
    let cols = parts.first().map_or(0, |p| p.ncols());
    let rows: usize = parts.iter().map(|p| p.nrows()).sum();
    let mut out = DMatrix::zeros(rows, cols);
    let mut at = 0;
    for p in parts {
        out.rows_mut(at, p.nrows()).copy_from(*p);
        at += p.nrows();
    }
    out
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
