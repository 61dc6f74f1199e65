//! Identification pipeline for coupled robot arms (dVRK PSM/MTM and others).
//!
//! Data flows one way: [`log`] reads joint-space logs into a [`JointLog`],
//! [`signal`] filters and differentiates them into `q, dq, ddq, tau`, [`observation`]
//! reduces the weighted regressor to an R factor in parallel chunks, [`estimate`] fits
//! the parameters (least squares or the physically consistent semidefinite program),
//! and [`fit()`] runs the whole pipeline and builds the [`result`] document, which
//! [`export`] writes as the files other tools read (URDF, the 2019 params.json, the dVRK
//! controller's gravity compensation).
//!
//! Logs larger than memory go through the same steps block by block:
//! [`log::LogReader`] reads any format in blocks, [`signal::stream`] processes them,
//! and [`fit::stream::fit_stream`] reduces them into the observation in several passes
//! over the files, with the same result as [`fit()`].
//!
//! Fits spread over processes or machines: [`state::ObservationState`] holds the
//! training logs reduced (each log's factors, all of them merged, the torque range) in a
//! versioned file; states merge, and the fit of a merged state is the fit of its logs.
//!
//! The command line and the Python module only map their flags and keyword arguments
//! onto [`log::ReadOptions`] and [`request::FitRequest`]: a difference between them is a
//! bug of one of the mappings. A program fits the same way, with the types re-exported
//! here:
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
//! Cargo features (all default): `rust-lapack` (Clarabel's BLAS/LAPACK in Rust over
//! faer, from the workspace's `lapack-faer` crate, so no system library is linked),
//! `recordings` (the readers of ROS recordings and the MCAP writer, [`log::mcap`]) and
//! `report` (figures and the HTML report, [`report`]); a program that only fits CSV logs
//! can leave out the last two.

#![warn(missing_docs)]
// The Fortran-ABI routines Clarabel calls are unsafe code of their own crate,
// crates/lapack-faer (the C ABI of crates/dvrk-model-c is the other one).
#![forbid(unsafe_code)]

pub mod compare;
pub mod error;
pub mod estimate;
pub mod excite;
pub mod external;
// The logs live in their own crate (crates/dvrk-logs), under the same paths here.
use dvrk_logs::median;
pub use dvrk_logs::{columns, joint_log, log, names, output, temporary};
pub mod observation;
pub mod progress;
#[cfg(feature = "report")]
pub mod report;
pub mod reproduce;
pub mod request;
pub mod residual;
pub mod settings;
pub mod signal;
pub mod simulate;
pub mod state;
#[cfg(all(test, not(feature = "recordings")))]
mod without_recordings;

pub use error::IdentError;
pub use joint_log::{Coordinates, JointLog, JointLogError};
pub mod fit;
pub mod result;

pub use fit::{fit, BoundsSet, FitSettings, Method};
pub use log::{LogFormat, ReadOptions};
pub use request::{FitOutcome, FitRequest, LogSource, Overrides, Preset, Training};
pub use result::FitResult;
pub use settings::Joints;
pub mod cable;
pub mod export;

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
