//! Identification pipeline for coupled robot arms (dVRK PSM/MTM and others).
//!
//! [`FitRequest`] is the one way to fit: the training logs ([`LogSource`]: files, or
//! samples already in memory; or observation states), the test logs, how the files are
//! read ([`log::ReadOptions`]), the base settings ([`FitSettings`]) and the settings
//! changed from them ([`Overrides`], the command line's flags and Python's keyword
//! arguments), the decision to read the logs block by block ([`Streaming`]).
//! [`FitRequest::run`] gives a [`FitOutcome`]: the model and settings used, and the
//! [`FitResult`] document that [`export::Export`] writes as the files other tools read
//! (URDF, the 2019 params.json, the dVRK controller's gravity compensation). The command
//! line and the Python module only map their flags and keyword arguments onto it: a
//! difference between them is a bug of one of the mappings.
//!
//! ```
//! use dvrk_ident::{FitRequest, LogSource, Method, Overrides, Silent, Training};
//!
//! let psm = dvrk_model::Model::builtin("psm").unwrap();
//! let log = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/psm_excitation.mcap");
//! let request = FitRequest {
//!     overrides: Overrides { method: Some(Method::Ols), ..Overrides::default() },
//!     ..FitRequest::new(Training::Logs(vec![LogSource::File(log.into())]))
//! };
//! let outcome = request.run(Some(&psm), &Silent).unwrap();
//! let result = outcome.result; // a FitResult: result.to_json() is the CLI's document
//! assert_eq!(result.robot, "psm");
//! assert!(result.metrics.train.relative_error.iter().all(|e| *e < 0.05));
//! ```
//!
//! # The public surface
//!
//! Every public item has one path. At the root, what a fit takes and gives:
//!
//! - the request: [`FitRequest`], [`FitOutcome`], [`LogSource`], [`Training`],
//!   [`Streaming`] (and [`STREAM_ABOVE_BYTES`]), [`Overrides`] with its [`Setting`]s and
//!   [`Preset`]s, [`PriorSource`]; [`ObserveRequest`] for an [`ObservationState`] (the
//!   training logs reduced in a versioned file, merged across processes or machines; the
//!   fit of a merged state is the fit of its logs; [`model_hash`] names its model);
//! - logs in memory: [`JointLog`], its [`Coordinates`] and [`Signal`]s; [`Named`], the
//!   names every option enum reads and writes;
//! - settings: [`FitSettings`], [`Method`], [`BoundsSet`], [`Joints`], [`Prior`] and
//!   [`PriorMetric`], [`DelayOption`], the friction models a fit selects among
//!   ([`Candidates`], [`Folds`]), [`Difference`] between two settings;
//! - the result document and its parts: [`FitResult`], [`LinkResult`],
//!   [`ParameterStatus`], [`BaseParameterResult`], [`Metrics`], [`InputInfo`],
//!   [`SolverInfo`], [`Selection`], ...;
//! - progress reports ([`Progress`], [`Silent`]) and errors ([`IdentError`], which
//!   carries the others);
//! - the cable model of a coupled joint ([`fit_cable`]).
//!
//! The public modules are the features a program calls on its own: [`log`] reads and
//! writes logs (every format, block by block, ROS recordings); [`signal`] is the
//! processing a fit applies (its settings, [`Processing`](signal::Processing), are a
//! field of [`FitSettings`]) and the SciPy-compatible filters it is made of; [`validate`]
//! puts a result to other logs; [`excite`] designs excitation trajectories; [`simulate`]
//! makes logs from a model; [`residual`] estimates external torques from a log and a
//! result; [`payload`] identifies a payload; [`compare`] sets two results side by side;
//! [`export`] writes a result for other tools; [`reproduce`] renders the command line
//! and Python call that repeat a fit; [`report`] draws figures and the HTML report.
//!
//! The stages of the pipeline are the crate's own: logs are read, processed into
//! `q, dq, ddq, tau`, reduced to an R factor of the weighted regressor in parallel
//! chunks, and fitted (least squares or the physically consistent semidefinite program),
//! in memory or block by block for logs larger than memory (the same result).
//!
//! Cargo features (all default): `rust-lapack` (Clarabel's BLAS/LAPACK in Rust over
//! faer, from the workspace's `lapack-faer` crate, so no system library is linked),
//! `recordings` (the readers of ROS recordings and the MCAP writer, [`log::mcap`]) and
//! `report` (figures and the HTML report, [`report`]); a program that only fits CSV logs
//! can leave out the last two.

#![warn(missing_docs)]
// Every type the public API hands out has a public path (a re-export at the root or an
// item of a public module): the public surface is the one written below, not an accident.
#![warn(unnameable_types)]
// The Fortran-ABI routines Clarabel calls are unsafe code of their own crate,
// crates/lapack-faer (the C ABI of crates/dvrk-model-c is the other one).
#![forbid(unsafe_code)]

// The public surface, one path per item (docs/book/src/architecture.md, "The library's
// public surface"): the root re-exports below, and the public modules, each a feature a
// program calls on its own. The stages of the pipeline are the crate's own.
pub mod compare;
pub mod excite;
pub mod export;
/// The log readers and writers (the `dvrk-logs` crate's `log` module): every format, the
/// block reader behind `--stream`, ROS recordings, how a file is read ([`log::ReadOptions`]).
pub use dvrk_logs::log;
pub mod payload;
#[cfg(feature = "report")]
pub mod report;
pub mod reproduce;
pub mod residual;
pub mod signal;
pub mod simulate;
pub mod validate;

// The stages and their plumbing.
pub(crate) mod cable;
pub(crate) mod error;
pub(crate) mod estimate;
pub(crate) mod external;
pub(crate) mod fit;
pub(crate) mod observation;
mod options;
pub(crate) mod progress;
pub(crate) mod request;
pub(crate) mod result;
pub(crate) mod settings;
pub(crate) mod state;
#[cfg(test)]
mod tests;
#[cfg(all(test, not(feature = "recordings")))]
mod without_recordings;
// The logs' crate, under the paths the stages use.
use dvrk_logs::{median, names, output};

// The request, its logs and its outcome.
pub use request::{
    FitOutcome, FitRequest, LogSource, ObserveRequest, Overrides, Preset, PriorSource, Setting,
    SettingError, Streaming, Training, STREAM_ABOVE_BYTES,
};
// Logs in memory (the readers are the `log` module).
pub use dvrk_logs::{Coordinates, JointLog, JointLogError, Signal};
pub use names::{Named, UnknownName};
pub use options::ValueError;
// Settings: the estimator's, the delays', the friction models a fit selects among
// (`FitSettings::select`); the processing's are the `signal` module's.
pub use fit::delay::{DelayOption, DEFAULT_MAX_DELAY_S};
pub use result::Folds;
pub use settings::{
    BoundsSet, Candidate, Candidates, Difference, FitSettings, FrameNames, Joints, Method, Prior,
    PriorMetric,
};
// The result document and its parts.
pub use estimate::{SolverInfo, SolverStatus};
pub use result::{
    BaseParameterResult, CandidateScore, Consistency, DelayEstimate, FitResult, InputInfo,
    JointMetrics, LinkDetermined, LinkResult, Metrics, ParameterStatus, ResultPayload, Selection,
};
pub use state::{model_hash, ObservationState};
// The cable model of a coupled joint (the command line's `cable-fit`).
pub use cable::{fit_cable, CableFit, CableSettings};
// Progress reports.
pub use progress::{Progress, Silent};
// Errors (and those of the public modules: `log::LogError`, `signal::SignalError`,
// `excite::ExciteError`, which `IdentError` carries too).
pub use error::{IdentError, NotFiniteCause, SettingName};
pub use estimate::sdp::SdpError;
pub use output::OutputError;
pub use result::MetricsError;

// The book's Rust chapter (docs/book/src/rust.md): its Rust blocks are this crate's doc
// tests, so the chapter's examples compile and pass with the API they show.
#[cfg(doctest)]
#[doc = include_str!("../../../docs/book/src/rust.md")]
pub struct BookRustChapter;

// The book's page on external torques (docs/book/src/residual.md): its Rust block (the
// momentum observer) is a doc test too.
#[cfg(doctest)]
#[doc = include_str!("../../../docs/book/src/residual.md")]
pub struct BookResidualChapter;
