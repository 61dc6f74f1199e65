//! Linear resampling onto a uniform clock: the one implementation is dvrk-logs'
//! [`dvrk_logs::resample`] (the readers' `resample_hz` uses it too); its errors are
//! this module's [`SignalError`]s, with the same messages.

use dvrk_logs::resample::ResampleError;
pub(crate) use dvrk_logs::resample::Resampler;

use super::SignalError;

impl From<ResampleError> for SignalError {
    fn from(e: ResampleError) -> SignalError {
        match e {
            ResampleError::InvalidRate { rate_hz } => SignalError::InvalidRate { rate_hz },
            ResampleError::TooFewSamples { len, needed } => {
                SignalError::TooFewSamples { len, needed }
            }
            ResampleError::InvalidSetting { name, reason } => {
                SignalError::InvalidSetting { name, reason }
            }
        }
    }
}
