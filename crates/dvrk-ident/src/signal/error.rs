//! The errors of filter design, filtering and processing, and the range of cut-offs they
//! check against (here rather than beside the filter design so that every stage can name
//! them without depending on another).

use crate::JointLogError;
use dvrk_model::input::show_approx;
use thiserror::Error;

/// The range of normalized cut-offs (fraction of the Nyquist frequency) that processing
/// accepts. At 1e-3 (0.1 Hz at 200 Hz, the lowest base frequency of the 2019 excitations)
/// the 6th-order filter's slowest pole already has a time constant of about 2 500 samples
/// and the streamed filter's settling margin (`signal::stream::zero_phase::settle_margin`)
/// is about 120 000 samples; it grows as 1/Wn, and with it the memory and time of every
/// block, so lower cut-offs are refused. Above 0.95 the poles approach the unit circle
/// (at `Wn = 1` the filter is unstable: the margin never ends) and the filter no longer
/// filters anything.
pub const CUTOFF_RANGE_WN: [f64; 2] = [1e-3, 0.95];

/// A fraction of the Nyquist frequency for [`SignalError::InvalidCutoff`]: rounded, but
/// never to one of the range's bounds it is outside of (0.9500001 is not shown as 0.95).
fn show_fraction(wn: f64) -> String {
    let rounded = show_approx(wn);
    if CUTOFF_RANGE_WN
        .iter()
        .any(|b| rounded == show_approx(*b) && wn != *b)
    {
        dvrk_model::input::show(wn)
    } else {
        rounded
    }
}

/// Errors of filter design, filtering and processing.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SignalError {
    /// Filter order 0.
    #[error("filter order must be at least 1, got {order}")]
    InvalidOrder {
        /// The requested order.
        order: usize,
    },
    /// A normalized cut-off outside (0, 1).
    #[error("normalized cut-off Wn = {wn} must be in (0, 1) (fraction of the Nyquist frequency)")]
    InvalidWn {
        /// The requested normalized cut-off.
        wn: f64,
    },
    /// A cut-off in Hz outside 0.001 to 0.95 of the Nyquist frequency (`CUTOFF_RANGE_WN`).
    /// The rate (measured from time stamps) and the ratios are shown rounded
    /// ([`dvrk_model::input::show_approx`]), the cut-off as given.
    #[error("cut-off {cutoff_hz} Hz at a {} Hz sampling rate is {} of the Nyquist frequency: it must be between {} and {} of it ({} to {} Hz): choose a {} in that range", show_approx(*rate_hz), show_fraction(*wn), CUTOFF_RANGE_WN[0], CUTOFF_RANGE_WN[1], show_approx(CUTOFF_RANGE_WN[0] * rate_hz / 2.0), show_approx(CUTOFF_RANGE_WN[1] * rate_hz / 2.0), dvrk_logs::hint::Hint::Cutoff)]
    InvalidCutoff {
        /// Requested cut-off, Hz.
        cutoff_hz: f64,
        /// Sampling rate, Hz.
        rate_hz: f64,
        /// The normalized cut-off it gives.
        wn: f64,
    },
    /// A sampling rate that is not positive and finite.
    #[error("sampling rate must be positive and finite, got {rate_hz} Hz")]
    InvalidRate {
        /// The rate, Hz.
        rate_hz: f64,
    },
    /// Unusable filter coefficients or initial state.
    #[error("invalid filter: {reason}")]
    InvalidCoefficients {
        /// What is wrong.
        reason: String,
    },
    /// The steady-state system of `lfilter_zi` is singular (a pole at z = 1).
    #[error("the filter has no steady state (pole at z = 1): cannot compute initial conditions")]
    SingularSteadyState,
    /// The signal is not longer than the padding of the forward-backward filter.
    #[error("signal of {len} samples is too short for forward-backward filtering: it must be longer than padlen = {padlen}")]
    TooShort {
        /// Signal length, samples.
        len: usize,
        /// Padding length, samples.
        padlen: usize,
    },
    /// Too few samples for an operation.
    #[error("{len} samples given, at least {needed} needed")]
    TooFewSamples {
        /// Samples given.
        len: usize,
        /// Samples needed.
        needed: usize,
    },
    /// Per-joint cut-offs whose count differs from the number of joints.
    #[error("{found} per-joint cut-offs given for {expected} joints")]
    CutoffCount {
        /// Number of joints.
        expected: usize,
        /// Number of cut-offs given.
        found: usize,
    },
    /// Trimming would remove every sample.
    #[error("trimming {trim} samples at each end leaves nothing of {len} samples")]
    TrimTooLong {
        /// Samples trimmed at each end.
        trim: usize,
        /// Samples available.
        len: usize,
    },
    /// A processing setting out of range.
    #[error("invalid setting {name}: {reason}")]
    InvalidSetting {
        /// Setting name.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// No sample has every joint moving at least `min_speed`.
    #[error("{source_name}: no sample left after dropping samples with |dq| < {min_speed} on some joint")]
    NoSamplesLeft {
        /// The trajectory's source.
        source_name: String,
        /// The threshold, rad/s or m/s.
        min_speed: f64,
    },
    /// A failure while processing one column of a trajectory.
    #[error("{source_name}: {signal} of joint {joint:?}: {inner}")]
    InColumn {
        /// The trajectory's source.
        source_name: String,
        /// Which signal (`"position"`, `"velocity"`, `"acceleration"`, `"effort"`).
        signal: &'static str,
        /// Joint name.
        joint: String,
        /// The underlying error.
        inner: Box<SignalError>,
    },
    /// The input trajectory is invalid.
    #[error(transparent)]
    JointLog(#[from] JointLogError),
}
