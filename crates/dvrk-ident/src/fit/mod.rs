//! The identification pipeline, one stage per module: [`prepare`](prepare()) (log →
//! model coordinates → known forces removed → processed samples), the observation
//! ([`Observed`], in `observed`), the estimator ([`crate::estimate`]), the metrics
//! ([`MetricSums`](metrics::MetricSums), [`joint_metrics`]) and the result document. Three drivers run the
//! stages: logs in memory (`memory`), logs read from disk block by block for logs
//! larger than memory ([`stream`], the same result), and observation states
//! ([`crate::state`]). [`crate::FitRequest`] picks the driver: it is the one way to fit,
//! for the command line, Python and a program alike.

pub mod delay;
mod document;
mod joints;
mod memory;
mod metrics;
mod observed;
mod prepare;
pub mod select;
pub mod status;
pub mod stream;

#[cfg(feature = "report")]
pub use joints::units;
pub use joints::JointMap;
pub use metrics::{joint_metrics, predict, TorqueRange};
pub use observed::{Observed, ObservedLog};
pub use prepare::{prepare, to_model_coordinates, LogData, Prepared};

pub(crate) use memory::{fit_logs, observe_prepared, prepare_logs, test_inputs};
pub(crate) use observed::{fit_observed, no_delay_search, no_training_log, MetricPasses};
