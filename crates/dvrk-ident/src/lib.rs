//! Identification pipeline for coupled robot arms (dVRK PSM/MTM and others).
//!
//! [`FitRequest`] is the one way to fit: the training logs ([`LogSource`]: files, or
//! samples already in memory; or observation states), the test logs, how the files are
//! read ([`ReadOptions`]), the base settings ([`FitSettings`]) and the settings changed
//! from them ([`Overrides`], the command line's flags and Python's keyword arguments),
//! the decision to read the logs block by block ([`Streaming`]). [`FitRequest::run`]
//! gives a [`FitOutcome`]: the model and settings used, and the [`FitResult`] document
//! that [`Export`] writes as the files other tools read (URDF, the 2019 params.json, the
//! dVRK controller's gravity compensation). The command line and the Python module only
//! map their flags and keyword arguments onto it: a difference between them is a bug of
//! one of the mappings.
//!
//! ```
//! use dvrk_ident::{FitRequest, LogSource, Method, Overrides, Training};
//!
//! let psm = dvrk_model::Model::builtin("psm").unwrap();
//! let log = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/psm_excitation.mcap");
//! let request = FitRequest {
//!     overrides: Overrides { method: Some(Method::Ols), ..Overrides::default() },
//!     ..FitRequest::new(Training::Logs(vec![LogSource::File(log.into())]))
//! };
//! let outcome = request.run(Some(&psm), &dvrk_ident::progress::Silent).unwrap();
//! let result = outcome.result; // a FitResult: result.to_json() is the CLI's document
//! assert_eq!(result.robot, "psm");
//! assert!(result.metrics.train.relative_error.iter().all(|e| *e < 0.05));
//! ```
//!
//! Inside, data flow one way: [`log`] reads joint-space logs into a [`JointLog`],
//! [`signal`] filters and differentiates them into `q, dq, ddq, tau`, [`observation`]
//! reduces the weighted regressor to an R factor in parallel chunks, [`estimate`] fits
//! the parameters (least squares or the physically consistent semidefinite program), and
//! [`fit`] holds the stages and the drivers [`FitRequest`] picks: logs in memory, logs
//! larger than memory read block by block ([`log::LogReader`], [`signal::stream`]; the
//! same result), and observation states ([`ObservationState`]: the training logs
//! reduced in a versioned file, merged across processes or machines, the fit of a
//! merged state being the fit of its logs).
//!
//! Around the fit: [`excite`] designs excitation trajectories ([`FourierTrajectory`]),
//! [`simulate`] makes logs from a model, [`residual`] estimates external torques from a
//! log and a result, [`compare`] sets two results side by side, [`report`] draws them.
//!
//! Cargo features (all default): `rust-lapack` (Clarabel's BLAS/LAPACK in Rust over
//! faer, from the workspace's `lapack-faer` crate, so no system library is linked),
//! `recordings` (the readers of ROS recordings and the MCAP writer, [`log::mcap`]) and
//! `report` (figures and the HTML report, [`report`]); a program that only fits CSV logs
//! can leave out the last two.

#![warn(missing_docs)]
// The Fortran-ABI routines Clarabel calls are unsafe code of their own crate,
// crates/lapack-faer (the C ABI of crates/dvrk-model-c is the other one).
#![forbid(unsafe_code)]

// The modules. A program uses the types re-exported below, at the root; the modules
// stay public for the parts the command line, Python and the tests reach inside them
// (the processing stages, the readers, the report's figures).
use dvrk_logs::median;
pub use dvrk_logs::{columns, joint_log, log, names, output, temporary};
pub mod cable;
pub mod compare;
pub mod error;
pub mod estimate;
pub mod excite;
pub mod export;
pub mod external;
pub mod fit;
pub mod observation;
mod options;
pub mod payload;
pub mod progress;
#[cfg(feature = "report")]
pub mod report;
pub mod reproduce;
pub mod request;
pub mod residual;
pub mod result;
pub mod settings;
pub mod signal;
pub mod simulate;
pub mod state;
#[cfg(all(test, not(feature = "recordings")))]
mod without_recordings;

// The request, its logs and its outcome.
pub use request::{
    FitOutcome, FitRequest, LogSource, ObserveRequest, Overrides, Preset, Streaming, Training,
};
// Logs and how they are read.
pub use joint_log::{Coordinates, JointLog, JointLogError};
pub use log::{LogFormat, ReadOptions};
// Settings.
pub use settings::{BoundsSet, FitSettings, Joints, Method};
// The result, the observation states, the exports.
pub use export::Export;
pub use result::FitResult;
pub use state::ObservationState;
// Errors.
pub use error::IdentError;
// Excitation trajectories.
pub use excite::FourierTrajectory;

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
