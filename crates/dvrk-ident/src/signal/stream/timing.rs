//! The first pass over a streamed log: what the processing must know before the first
//! filtered sample, and what [`crate::signal::process`](fn@crate::signal::process) checks on the whole log first.

use crate::median::{ExactMedian, MedianPass};
use crate::{JointLog, JointLogError};

/// The timing of a log, from [`TimingSurvey`].
#[derive(Clone, Debug, PartialEq)]
pub struct LogTiming {
    /// Number of samples.
    pub samples: usize,
    /// Time of the first and of the last sample, s.
    pub first_s: f64,
    /// Time of the last sample, s.
    pub last_s: f64,
    /// Median time step, s (as [`JointLog::rate_hz`] computes it); `None` with
    /// fewer than two samples.
    pub median_step_s: Option<f64>,
    /// Shortest and longest time steps, s; `None` with fewer than two samples.
    pub step_range_s: Option<(f64, f64)>,
}

impl LogTiming {
    /// Whether some step is off the median by more than `relative_tolerance` (the
    /// check of [`JointLog::check_uniform`]).
    pub fn is_uniform(&self, relative_tolerance: f64) -> bool {
        match (self.median_step_s, self.step_range_s) {
            (Some(m), Some((lo, hi))) => {
                (lo - m).abs() <= relative_tolerance * m && (hi - m).abs() <= relative_tolerance * m
            }
            _ => true,
        }
    }
}

/// Validates a log given block by block and finds its timing, in one or more passes
/// (more only when the steps take very many distinct values: see `median`).
///
/// The first pass validates every block like [`JointLog::validate`] (rows numbered
/// from the start of the log, time increasing across blocks); later passes only read
/// the time steps again.
#[derive(Clone, Debug, Default)]
pub struct TimingSurvey {
    pass: usize,
    samples: usize,
    previous: Option<f64>,
    first: Option<f64>,
    /// The source and joint count of the first block (for the emptiness error).
    source: String,
    joints: Option<usize>,
    median: ExactMedian,
}

impl TimingSurvey {
    /// A survey of a log whose blocks come next.
    pub fn new() -> TimingSurvey {
        TimingSurvey::default()
    }

    /// The next block of the log (every pass must give the same blocks).
    pub fn observe(&mut self, block: &JointLog) -> Result<(), JointLogError> {
        if self.pass == 0 {
            if self.joints.is_none() {
                self.source = block.source.clone();
                self.joints = Some(block.dof());
            }
            if block.dof() > 0 {
                block.validate_rows(self.samples, self.previous)?;
            }
            self.samples += block.len();
            if self.first.is_none() {
                self.first = block.time.first().copied();
            }
        }
        for &t in &block.time {
            if let Some(p) = self.previous {
                self.median.observe((t - p).to_bits());
            }
            self.previous = Some(t);
        }
        Ok(())
    }

    /// Ends a pass: the timing once known, `None` to read the blocks again.
    pub fn end_pass(&mut self) -> Result<Option<LogTiming>, JointLogError> {
        let last = self.previous.take();
        if self.pass == 0 {
            let joints = self.joints.unwrap_or(0);
            if self.samples == 0 || joints == 0 {
                return Err(JointLogError::Empty {
                    source_name: self.source.clone(),
                    samples: self.samples,
                    joints,
                });
            }
        }
        let range = self.median.range();
        self.pass += 1;
        let median = match self.median.end_pass() {
            MedianPass::Again => return Ok(None),
            MedianPass::Done(None) => None,
            MedianPass::Done(Some((a, b))) => {
                let (a, b) = (f64::from_bits(a), f64::from_bits(b));
                Some(if self.median.count() % 2 == 1 {
                    a
                } else {
                    0.5 * (a + b)
                })
            }
        };
        Ok(Some(LogTiming {
            samples: self.samples,
            first_s: self.first.unwrap_or(f64::NAN),
            last_s: last.unwrap_or(f64::NAN),
            median_step_s: median,
            step_range_s: range.map(|(lo, hi)| (f64::from_bits(lo), f64::from_bits(hi))),
        }))
    }
}
