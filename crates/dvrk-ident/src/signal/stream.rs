//! The processing of a log too long to hold in memory, block by block.
//!
//! A first pass over the log ([`TimingSurvey`]) validates it and finds its timing; a
//! [`BlockProcessor`] then turns the blocks, in order, into the processed samples that
//! [`super::process`] gives for the whole log (to [`SETTLE_TOLERANCE`] relative in the
//! filtered signals, exactly in everything else), holding only a window of samples: the
//! zero-phase filters' settling margin (from their slowest pole) plus a chunk.

mod difference;
mod processor;
mod timing;
mod zero_phase;

pub(crate) use super::resample::Resampler;
pub use processor::{BlockProcessor, SETTLE_TOLERANCE};
pub use timing::{LogTiming, TimingSurvey};

use super::{Processed, Processing, SignalError};
use crate::joint_log::JointLog;

/// The processing of a whole trajectory by a [`BlockProcessor`] (a timing survey, then
/// one block): what a log streamed from disk gets, to the last bit, for a log in
/// memory. It equals [`super::process`] to [`SETTLE_TOLERANCE`] relative.
pub fn process_in_blocks(traj: &JointLog, settings: &Processing) -> Result<Processed, SignalError> {
    let mut survey = TimingSurvey::new();
    let timing = loop {
        survey.observe(traj)?;
        if let Some(t) = survey.end_pass()? {
            break t;
        }
    };
    let mut p = BlockProcessor::new(
        settings,
        &traj.joint_names,
        traj.coordinates,
        traj.dq.is_some(),
        &traj.source,
        &timing,
    )?;
    let head = p.push(traj)?;
    let tail = p.finish()?;
    let join = |a: &nalgebra::DMatrix<f64>, b: &nalgebra::DMatrix<f64>| {
        let mut m = nalgebra::DMatrix::zeros(a.nrows() + b.nrows(), a.ncols());
        m.rows_mut(0, a.nrows()).copy_from(a);
        m.rows_mut(a.nrows(), b.nrows()).copy_from(b);
        m
    };
    Ok(Processed {
        time: head.time.iter().chain(&tail.time).copied().collect(),
        q: join(&head.q, &tail.q),
        dq: join(&head.dq, &tail.dq),
        ddq: join(&head.ddq, &tail.ddq),
        tau: join(&head.tau, &tail.tau),
        ..tail
    })
}
