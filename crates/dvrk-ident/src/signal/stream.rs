//! The processing of a log too long to hold in memory, block by block.
//!
//! A first pass over the log ([`TimingSurvey`]) validates it and finds its timing; a
//! [`BlockProcessor`] then turns the blocks, in order, into the processed samples that
//! [`super::process`](fn@super::process) gives for the whole log (to [`SETTLE_TOLERANCE`](processor::SETTLE_TOLERANCE) relative in the
//! filtered signals, exactly in everything else), holding only a window of samples: the
//! zero-phase filters' settling margin (from their slowest pole) plus a chunk.

mod difference;
mod processor;
mod timing;
mod zero_phase;

pub(crate) use super::resample::Resampler;
pub use processor::BlockProcessor;
pub use timing::{LogTiming, TimingSurvey};

use super::{stack_rows, Processed, Processing, SignalError};
use crate::JointLog;
use nalgebra::DMatrix;

/// The processing of a trajectory held in memory as consecutive `blocks` (one or more)
/// by a `BlockProcessor` (a timing survey, then the blocks in order): what a log
/// streamed from disk gets, to the last bit, for a log in memory. It equals
/// [`super::process`](fn@super::process) of the whole to `SETTLE_TOLERANCE` relative.
pub fn process_in_blocks(
    blocks: &[JointLog],
    settings: &Processing,
) -> Result<Processed, SignalError> {
    let mut survey = TimingSurvey::new();
    let timing = loop {
        for b in blocks {
            survey.observe(b)?;
        }
        if let Some(t) = survey.end_pass()? {
            break t;
        }
    };
    // The survey refused an empty list: there is a first block.
    let first = &blocks[0];
    let mut p = BlockProcessor::new(
        settings,
        &first.joint_names,
        first.coordinates,
        first.dq.is_some(),
        &first.source,
        &timing,
    )?;
    let mut out = Vec::with_capacity(blocks.len() + 1);
    for b in blocks {
        out.push(p.push(b)?);
    }
    out.push(p.finish()?);
    let stack =
        |f: fn(&Processed) -> &DMatrix<f64>| stack_rows(&out.iter().map(f).collect::<Vec<_>>());
    let (time, q, dq, ddq, tau) = (
        out.iter().flat_map(|o| o.time.iter().copied()).collect(),
        stack(|o| &o.q),
        stack(|o| &o.dq),
        stack(|o| &o.ddq),
        stack(|o| &o.tau),
    );
    // The rest (joint names...) is the last block's, moved rather than copied.
    let last = out.pop().expect("finish() pushed a block");
    Ok(Processed {
        time,
        q,
        dq,
        ddq,
        tau,
        ..last
    })
}
