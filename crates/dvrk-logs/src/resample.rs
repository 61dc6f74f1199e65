//! Linear resampling onto a uniform clock of a signal that arrives in rows: the one
//! implementation behind the readers' `resample_hz` ([`crate::log::ReadOptions`]) and,
//! in dvrk-ident, `signal::resample_linear` (which feeds it a whole matrix) and the
//! processing's resampling.

use thiserror::Error;

/// Why a signal cannot be resampled. dvrk-ident's `SignalError` converts from it variant
/// by variant, with the same messages.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ResampleError {
    /// A sampling rate that is not positive and finite.
    #[error("sampling rate must be positive and finite, got {rate_hz} Hz")]
    InvalidRate {
        /// The rate, Hz.
        rate_hz: f64,
    },
    /// Too few samples to interpolate between.
    #[error("{len} samples given, at least {needed} needed")]
    TooFewSamples {
        /// Samples given.
        len: usize,
        /// Samples needed.
        needed: usize,
    },
    /// A setting out of range (`resample`: a rate far above the log's own) or time
    /// stamps that are not finite and strictly increasing (`time`).
    #[error("invalid setting {name}: {reason}")]
    InvalidSetting {
        /// Setting name.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
}

fn check_rate(rate_hz: f64) -> Result<(), ResampleError> {
    if rate_hz.is_finite() && rate_hz > 0.0 {
        Ok(())
    } else {
        Err(ResampleError::InvalidRate { rate_hz })
    }
}

/// Resampler of every column onto `t0 + k / rate` (`t0`: the first time) up to the last
/// time. A grid time is interpolated as soon as a sample at or after it arrives,
/// between that sample and the one before; grid times past the last sample (within
/// the rounding allowance of the count) take the last sample.
#[derive(Clone, Debug)]
pub struct Resampler {
    rate_hz: f64,
    step: f64,
    origin: f64,
    /// The two latest samples: `[previous, latest]` times and rows.
    times: [f64; 2],
    rows: [Vec<f64>; 2],
    count: usize,
    /// Grid points emitted.
    emitted: usize,
    /// A non-finite first time, reported once a second sample shows the log is long
    /// enough to resample (a one-sample log is "too few samples" first).
    bad_first: bool,
}

/// Most resampled samples per logged sample, beyond a first [`RESAMPLE_ALLOWANCE`]:
/// linear interpolation adds no information, so a rate far above the log's own only
/// multiplies memory and time (`--resample 1e9` on a 200 Hz log asked for 5 million
/// samples per logged one and aborted at 13.8 GB).
pub const MAX_UPSAMPLING: usize = 4;

/// Resampled samples always allowed (gaps at the start of a log), whatever the ratio.
pub const RESAMPLE_ALLOWANCE: usize = 1 << 20;

fn bad_time() -> ResampleError {
    ResampleError::InvalidSetting {
        name: "time",
        reason: "time stamps must be finite and strictly increasing".into(),
    }
}

impl Resampler {
    /// A resampler of rows of `columns` values onto a `rate_hz` grid.
    pub fn new(columns: usize, rate_hz: f64) -> Result<Resampler, ResampleError> {
        check_rate(rate_hz)?;
        Ok(Resampler {
            rate_hz,
            step: 1.0 / rate_hz,
            origin: 0.0,
            times: [0.0; 2],
            rows: [vec![0.0; columns], vec![0.0; columns]],
            count: 0,
            emitted: 0,
            bad_first: false,
        })
    }

    /// Number of grid points of a log from `first` to `last` (s).
    pub fn grid_len(&self, first: f64, last: f64) -> usize {
        // Include the end point despite rounding in k * step.
        ((last - first) / self.step + 1e-9).floor() as usize + 1
    }

    /// Appends grid point `emitted` (time, then the row) interpolated between the two
    /// latest samples, unless that would make more than [`MAX_UPSAMPLING`] grid points
    /// per logged sample (beyond [`RESAMPLE_ALLOWANCE`]).
    fn emit(&mut self, times: &mut Vec<f64>, out: &mut Vec<f64>) -> Result<(), ResampleError> {
        if self.emitted >= MAX_UPSAMPLING * self.count + RESAMPLE_ALLOWANCE {
            return Err(ResampleError::InvalidSetting {
                name: "resample",
                reason: format!(
                    "{} Hz makes more than {MAX_UPSAMPLING} samples per logged sample \
                     ({} grid points after {} logged samples): interpolation adds no \
                     information, resample near the log's own rate",
                    self.rate_hz, self.emitted, self.count
                ),
            });
        }
        let t = self.origin + self.emitted as f64 * self.step;
        let [ta, tb] = self.times;
        let w = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
        let [a, b] = &self.rows;
        out.extend(a.iter().zip(b).map(|(a, b)| (1.0 - w) * a + w * b));
        times.push(t);
        self.emitted += 1;
        Ok(())
    }

    /// Adds the sample at `time` (s); appends the grid points that became known.
    pub fn push(
        &mut self,
        time: f64,
        row: &[f64],
        times: &mut Vec<f64>,
        out: &mut Vec<f64>,
    ) -> Result<(), ResampleError> {
        if self.count == 0 {
            self.bad_first = !time.is_finite();
            self.origin = time;
        } else if self.bad_first || !(time.is_finite() && time > self.times[1]) {
            return Err(bad_time());
        }
        self.times = [self.times[1], time];
        self.rows.swap(0, 1);
        self.rows[1].copy_from_slice(row);
        self.count += 1;
        if self.count >= 2 {
            while self.origin + self.emitted as f64 * self.step <= time {
                self.emit(times, out)?;
            }
        }
        Ok(())
    }

    /// The end: appends the grid points left. Needs at least 2 samples.
    pub fn finish(
        &mut self,
        times: &mut Vec<f64>,
        out: &mut Vec<f64>,
    ) -> Result<(), ResampleError> {
        if self.count < 2 {
            return Err(ResampleError::TooFewSamples {
                len: self.count,
                needed: 2,
            });
        }
        let total = self.grid_len(self.origin, self.times[1]);
        while self.emitted < total {
            self.emit(times, out)?;
        }
        Ok(())
    }
}
