//! The processing of a log too long to hold in memory, block by block.
//!
//! A first pass over the log ([`TimingSurvey`]) validates it and finds its timing; a
//! [`BlockProcessor`] then turns the blocks, in order, into the processed samples that
//! [`super::process`] gives for the whole log (to [`SETTLE_TOLERANCE`] relative in the
//! filtered signals, exactly in everything else), holding only a window of samples: the
//! zero-phase filters' settling margin (from their slowest pole) plus a chunk.

mod difference;
mod processor;
mod resample;
mod timing;
mod zero_phase;

pub use processor::{BlockProcessor, SETTLE_TOLERANCE};
pub(crate) use resample::Resampler;
pub use timing::{LogTiming, TimingSurvey};
