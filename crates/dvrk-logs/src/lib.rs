//! Joint-space logs of robot arms: what a lab needs to read, check and convert its
//! recordings, without the estimators.
//!
//! [`log`] reads every format (the 2019 dVRK CSV, headered CSV and, with the
//! `recordings` feature, ROS recordings: MCAP files, rosbag2 folders, sqlite3 `.db3`
//! files, ROS 1 bags) into a [`JointLog`], whole or in blocks ([`log::LogReader`]), and
//! writes the CSV layouts and MCAP; [`output`] is where every output file is written,
//! atomically. [`resample`] puts a log on a uniform clock while it is read.
//!
//! dvrk-ident builds its identification on this crate and re-exports the [`log`] module
//! as `dvrk_ident::log`, and `JointLog`, `Coordinates`, `Signal` and `Named` at its root.
//!
//! ```rust
//! use dvrk_logs::{uniform_time, Coordinates, JointLog};
//! use dvrk_logs::log::{read, write_headered};
//! use nalgebra::DMatrix;
//!
//! let path = std::env::temp_dir().join(format!("dvrk-logs-doc-{}.csv", std::process::id()));
//! let log = JointLog {
//!     time: uniform_time(3, 200.0),
//!     q: DMatrix::from_element(3, 1, 0.25),
//!     dq: None,
//!     tau: DMatrix::from_element(3, 1, 1.5),
//!     joint_names: vec!["q1".into()],
//!     coordinates: Coordinates::Measured,
//!     source: "doc".into(),
//! };
//! write_headered(&path, &log).unwrap();
//! assert_eq!(read(&path, None, None).unwrap().q, log.q);
//! std::fs::remove_file(&path).unwrap();
//! ```
//!
//! Cargo feature (default): `recordings` (the readers of ROS recordings and the MCAP
//! writer, [`log::mcap`]); without it a recording is recognized and refused with an error
//! naming the feature.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod columns;
mod destination;
pub mod hint;
mod joint_log;
pub mod log;
pub mod median;
pub mod names;
pub mod output;
pub mod resample;
pub mod temporary;

pub use joint_log::{uniform_time, Coordinates, JointLog, JointLogError, Signal};
