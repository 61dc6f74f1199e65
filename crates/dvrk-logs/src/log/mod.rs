//! Reading and writing joint-space logs.
//!
//! Formats ([`LogFormat`]):
//! - [`LogFormat::Wpi`]: the 2019 dVRK identification package's CSV: no header,
//!   `q1..qn, dq1..dqn, tau1..taun` per row, no time stamps (the caller gives the rate),
//!   values in the model's coordinates. See [`read_wpi`] / [`write_wpi`].
//! - [`LogFormat::Csv`]: headered CSV with `time`, `position.<joint>`,
//!   `velocity.<joint>` (optional: all or none) and `effort.<joint>` columns in any
//!   order. See [`read_headered`] / [`write_headered`].
//! - [`LogFormat::Mcap`]: ROS 2 MCAP recordings of `sensor_msgs/msg/JointState`
//!   (dVRK `measured_js`), measured coordinates, header stamps. See [`mcap`]
//!   ([`mcap::read_mcap`] / [`mcap::write_mcap`] for topics, time source, resampling).
//! - [`LogFormat::Rosbag2`] (a `ros2 bag record` folder: `metadata.yaml` and its MCAP or
//!   sqlite3 files, split recordings included), [`LogFormat::Sqlite3`] (rosbag2's `.db3`)
//!   and [`LogFormat::Ros1`] (a ROS 1 `.bag` of `sensor_msgs/JointState`): the same
//!   messages in other containers, read by the same [`mcap`] reader. Files compressed
//!   as a whole (zstd, lz4) and messages compressed one by one are decompressed.
//!
//! Formats are recognized by content ([`detect_format`]), never by extension; a file of
//! no supported format is an error saying what it looks like.
//!
//! Every reader streams its file: [`ReadOptions::open`] gives a log of any format as a
//! [`LogReader`] of blocks of samples (for logs larger than memory), and
//! [`ReadOptions::read`] (or [`read`]) collects every block, so both go through the same
//! parsing and checks. [`ReadOptions`] holds every reading option of the command line and
//! the Python module: both map their flags and keywords onto it.
//!
//! Readers never panic on bad input: every problem is a [`LogError`] naming the file,
//! the line (1-based, as an editor shows it) and what is wrong. Writers write to a
//! temporary file in the target directory and rename it, so a crash never leaves a
//! half-written log under the final name.

mod blocks;
mod csv;
mod line_limit;
pub mod mcap;
mod options;

pub use self::line_limit::MAX_LINE_BYTES;

pub use self::blocks::{LogBlocks, LogReader};
pub use self::csv::{
    read_headered, read_wpi, write_headered, write_wpi, HeaderedBlocks, WpiBlocks,
};
pub use self::options::{ReadOptions, Resampling};

use crate::hint::Hint;
use crate::joint_log::{Coordinates, JointLog, JointLogError};
use serde::{Deserialize, Serialize};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A log file layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum LogFormat {
    /// 2019 layout: headerless `q, dq, tau` columns, model coordinates, implicit clock.
    Wpi,
    /// Headered CSV: `time`, `position.<joint>`, `velocity.<joint>`, `effort.<joint>`.
    Csv,
    /// ROS 2 MCAP with `sensor_msgs/msg/JointState` messages (see [`mcap`]).
    Mcap,
    /// A rosbag2 folder (`metadata.yaml` and its MCAP or sqlite3 files).
    Rosbag2,
    /// rosbag2's sqlite3 storage, one `.db3` file.
    Sqlite3,
    /// A ROS 1 bag (format 2.0) of `sensor_msgs/JointState`.
    Ros1,
}

impl LogFormat {
    /// Whether the format is a recording of messages on topics (every format but the
    /// CSV layouts): read by [`mcap::McapReader`], with topics and a time source.
    pub fn has_topics(self) -> bool {
        !matches!(self, LogFormat::Wpi | LogFormat::Csv)
    }

    /// Whether [`write()`] writes the format (the CSV layouts and MCAP; the other
    /// recordings are read only).
    pub fn is_writable(self) -> bool {
        matches!(self, LogFormat::Wpi | LogFormat::Csv | LogFormat::Mcap)
    }
}

impl std::fmt::Display for LogFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(crate::names::Named::name(*self))
    }
}

/// `wpi` is the 2019 package's headerless CSV (also `wpi-csv`, `2019`); `sqlite3` also
/// `db3`, `ros1` also `bag`; case-insensitive.
impl crate::names::Named for LogFormat {
    const WHAT: &'static str = "log format";
    const NAMES: &'static [(&'static str, Self)] = &[
        ("wpi", LogFormat::Wpi),
        ("csv", LogFormat::Csv),
        ("mcap", LogFormat::Mcap),
        ("rosbag2", LogFormat::Rosbag2),
        ("sqlite3", LogFormat::Sqlite3),
        ("ros1", LogFormat::Ros1),
        ("wpi_csv", LogFormat::Wpi),
        ("2019", LogFormat::Wpi),
        ("db3", LogFormat::Sqlite3),
        ("bag", LogFormat::Ros1),
    ];
    const CANONICAL: usize = 6;
}

impl std::str::FromStr for LogFormat {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as crate::names::Named>::parse_name(s)
    }
}

/// Why a log could not be read or written. Messages start with `file:line:` where a
/// line is known.
#[derive(Debug, Error)]
pub enum LogError {
    /// The file could not be opened, read, written or renamed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// No data rows.
    #[error("{}: empty log: {what}", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
        /// What is missing (e.g. "no rows", "a header but no data rows").
        what: &'static str,
    },
    /// A field that is not a number.
    #[error("{}:{line}: column {column} ({name}): malformed number {text:?}", path.display())]
    MalformedNumber {
        /// The file.
        path: PathBuf,
        /// Line, 1-based.
        line: u64,
        /// Column, 1-based.
        column: usize,
        /// Column name (header, or `q3`, `dq3`, `tau3` for the 2019 layout).
        name: String,
        /// The field's text.
        text: String,
    },
    /// NaN or infinite value in the file.
    #[error("{}:{line}: column {column} ({name}): non-finite value {text:?}", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// Line, 1-based.
        line: u64,
        /// Column, 1-based.
        column: usize,
        /// Column name.
        name: String,
        /// The field's text.
        text: String,
    },
    /// A row whose number of fields differs from the header or the first row.
    #[error("{}:{line}: {found} columns, expected {expected}", path.display())]
    ColumnCount {
        /// The file.
        path: PathBuf,
        /// Line, 1-based.
        line: u64,
        /// Expected number of fields.
        expected: usize,
        /// Number of fields found.
        found: usize,
    },
    /// A 2019-layout column count that is not `3 * dof`.
    #[error("{}:{line}: {columns} columns cannot hold q, dq, tau for {}", path.display(), match dof { Some(d) => format!("{d} joints (expected {} columns)", 3 * d), None => "any number of joints (not divisible by 3)".to_string() })]
    DofMismatch {
        /// The file.
        path: PathBuf,
        /// Line, 1-based.
        line: u64,
        /// Number of columns.
        columns: usize,
        /// Number of joints requested by the caller, if any.
        dof: Option<usize>,
    },
    /// A headered CSV's header that is not a log's columns (see [`crate::columns`]).
    #[error("{}:{line}: {source}", path.display())]
    Columns {
        /// The file.
        path: PathBuf,
        /// Line of the header, 1-based.
        line: u64,
        /// What is wrong with the names.
        source: crate::columns::ColumnError,
    },
    /// A headered CSV without a `time` column.
    #[error("{}: missing column \"time\" (s)", path.display())]
    MissingTime {
        /// The file.
        path: PathBuf,
    },
    /// Time stamps that do not strictly increase.
    #[error("{}:{line}: time {current} s is not after the previous row's {previous} s", path.display())]
    NonMonotonicTime {
        /// The file.
        path: PathBuf,
        /// Line, 1-based.
        line: u64,
        /// Previous time, s.
        previous: f64,
        /// This row's time, s.
        current: f64,
    },
    /// A recording's option (topics, time source) given for a log of another format.
    #[error("{}: {option} applies to recordings (MCAP, rosbag2, sqlite3, ROS 1 bags) only, this is a {format} log", path.display())]
    NotARecording {
        /// The file.
        path: PathBuf,
        /// Its format.
        format: LogFormat,
        /// The option, as the reader calls it (`topics`, `time source`).
        option: &'static str,
    },
    /// A sampling rate given for a log that carries its own time stamps: it would change
    /// nothing, so it is refused rather than ignored.
    #[error("{}: the sampling rate ({}) applies to the 2019 layout only, which has no time stamps; this {format} log carries its own (leave {} out, or resample with {})", path.display(), Hint::Rate, Hint::Rate, Hint::ResampleHz)]
    RateNotApplicable {
        /// The file.
        path: PathBuf,
        /// Its format.
        format: LogFormat,
    },
    /// The 2019 layout has no time stamps and no rate was given.
    #[error("{}: the 2019 (wpi) layout has no time stamps: give the sampling rate with {} (the 2019 dVRK logs are 200 Hz)", path.display(), Hint::RateHz)]
    MissingRate {
        /// The file.
        path: PathBuf,
    },
    /// A rate that is not positive and finite.
    #[error("{}: {what} ({setting}) must be positive and finite, got {rate_hz} Hz", path.display())]
    InvalidRate {
        /// The file.
        path: PathBuf,
        /// What the rate is: `the sampling rate` or `the resampling rate`.
        what: &'static str,
        /// Its setting: [`Hint::Rate`] or [`Hint::Resample`].
        setting: Hint,
        /// The rate, Hz.
        rate_hz: f64,
    },
    /// A CSV-level problem (e.g. invalid UTF-8).
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Csv {
        /// The file.
        path: PathBuf,
        /// Line, 1-based, when known.
        line: Option<u64>,
        /// The parser's message.
        message: String,
    },
    /// A format this build cannot read or write yet.
    #[error("{}: {format} logs are not supported yet: {reason}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// The format.
        format: LogFormat,
        /// Why / what to do instead.
        reason: &'static str,
    },
    /// Writing the 2019 layout, which holds model coordinates, from a measured-joint
    /// trajectory.
    #[error("{}: the 2019 (wpi) layout holds model coordinates but the trajectory is in {found} coordinates: map it to model coordinates first", path.display())]
    WrongCoordinates {
        /// The file.
        path: PathBuf,
        /// The trajectory's coordinates.
        found: Coordinates,
    },
    /// Writing the 2019 layout, which requires velocities, from a trajectory without.
    #[error("{}: the 2019 (wpi) layout needs velocities but the trajectory has none", path.display())]
    MissingVelocity {
        /// The file.
        path: PathBuf,
    },
    /// A problem specific to MCAP logs: container, topic choice, message contents,
    /// timing (see [`mcap::McapProblem`]).
    #[error("{}{}: {problem}", path.display(), topic.as_ref().map(|t| format!(": topic {t}")).unwrap_or_default())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The topic concerned, if one is.
        topic: Option<String>,
        /// What is wrong.
        problem: Box<mcap::McapProblem>,
    },
    /// A recording (or a compressed file) read or written by a build of dvrk-ident
    /// without its `recordings` feature.
    #[error("{}: {what}: reading and writing recordings (MCAP, rosbag2, sqlite3, ROS 1 bags) needs the `recordings` feature of dvrk-logs (which dvrk-ident's feature of the same name enables), left out of this build", path.display())]
    RecordingsNotBuilt {
        /// The file.
        path: PathBuf,
        /// What it is (e.g. `a recording (mcap)`).
        what: String,
    },
    /// Resampling a log to a uniform rate failed.
    #[error("{}: resample to {rate_hz} Hz: {source}", path.display())]
    Resample {
        /// The file.
        path: PathBuf,
        /// The requested rate, Hz.
        rate_hz: f64,
        /// Why.
        #[source]
        source: crate::resample::ResampleError,
    },
    /// Samples the reader parsed but refuses: a value beyond its signal's range
    /// ([`crate::joint_log::Signal::max_magnitude`]) or time not increasing (the
    /// message names the file, the signal, the joint and the sample).
    #[error("{source}")]
    Samples {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        #[source]
        source: JointLogError,
    },
    /// The trajectory to write is invalid.
    #[error("{}: cannot write an invalid trajectory: {source}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong with the trajectory.
        #[source]
        source: JointLogError,
    },
}

/// Reads a log, choosing the layout from `format` or, when `None`, from its content
/// ([`detect_format`]).
///
/// `rate_hz` (Hz) is required for the 2019 layout, which has no time stamps (the dVRK
/// logs are 200 Hz), and ignored for formats with time stamps. Recordings are read with
/// the default options (automatic topic, header stamps, no resampling; use
/// [`ReadOptions::read`] for more). The 2019 layout's number of joints is inferred as
/// columns / 3 ([`ReadOptions::dof`] checks it).
///
/// ```rust
/// use dvrk_logs::log::{read, write_wpi};
/// use dvrk_logs::{Coordinates, JointLog, uniform_time};
/// use nalgebra::DMatrix;
/// let path = std::env::temp_dir().join(format!("dvrk-ident-doc-read-{}.csv", std::process::id()));
/// let log = JointLog {
///     time: uniform_time(4, 200.0),
///     q: DMatrix::from_element(4, 2, 0.5),
///     dq: Some(DMatrix::zeros(4, 2)),
///     tau: DMatrix::from_element(4, 2, -1.25),
///     joint_names: vec!["q1".into(), "q2".into()],
///     coordinates: Coordinates::Model,
///     source: "doc".into(),
/// };
/// write_wpi(&path, &log).unwrap();
/// let back = read(&path, None, Some(200.0)).unwrap(); // detected as the 2019 layout
/// assert_eq!(back.dof(), 2);
/// assert_eq!(back.tau[(3, 1)], -1.25);
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn read(
    path: impl AsRef<Path>,
    format: Option<LogFormat>,
    rate_hz: Option<f64>,
) -> Result<JointLog, LogError> {
    ReadOptions {
        format,
        rate_hz,
        ..ReadOptions::default()
    }
    .read(path)
}

/// Every signal of `log` (read from `path`) resampled to a uniform `hz` (Hz) by linear
/// interpolation: what `--resample` does for logs read without MCAP's own resampling.
pub fn resample(path: &Path, log: JointLog, hz: f64) -> Result<JointLog, LogError> {
    log.validate().map_err(|source| LogError::Samples {
        path: path.to_path_buf(),
        source,
    })?;
    let mut r = blocks::BlockResampler::new(path, hz, log.dof(), log.dq.is_some())?;
    let mut all = JointLogBuilder::default();
    all.push(&r.push(&log)?);
    all.push(&r.finish(&log)?);
    Ok(all.build())
}

/// Writes a trajectory in the given layout (atomically). See [`write_wpi`],
/// [`write_headered`] and [`mcap::write_mcap`] (here on topic
/// [`mcap::DEFAULT_TOPIC`] with [`mcap::McapWriteOptions::default`]) for what each layout
/// requires.
pub fn write(path: impl AsRef<Path>, log: &JointLog, format: LogFormat) -> Result<(), LogError> {
    let path = path.as_ref();
    match format {
        LogFormat::Wpi => write_wpi(path, log),
        LogFormat::Csv => write_headered(path, log),
        #[cfg(feature = "recordings")]
        LogFormat::Mcap => mcap::write_mcap(
            path,
            log,
            mcap::DEFAULT_TOPIC,
            &mcap::McapWriteOptions::default(),
        ),
        #[cfg(not(feature = "recordings"))]
        LogFormat::Mcap => Err(recordings_not_built(path, LogFormat::Mcap)),
        other => Err(LogError::Unsupported {
            path: path.to_path_buf(),
            format: other,
            reason: "only read: write MCAP (a rosbag2 folder can hold MCAP files)",
        }),
    }
}

/// Recognizes a log by its content: a folder (or its `metadata.yaml`) is a rosbag2
/// recording, a file starting with the MCAP, SQLite or ROS 1 bag magic (possibly inside
/// a zstd or lz4 frame) is that recording; a text file is a CSV, whose first row that is
/// not blank or a `#` comment decides: all fields numbers means the headerless 2019
/// layout, else a headered CSV. Anything else is an error saying what the file looks
/// like and what is supported.
pub fn detect_format(path: impl AsRef<Path>) -> Result<LogFormat, LogError> {
    use self::mcap::sniff::{sniff, Content, Storage};
    let path = path.as_ref();
    let meta = std::fs::metadata(path).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if meta.is_dir() {
        return Ok(LogFormat::Rosbag2);
    }
    match sniff(path)? {
        Content::Bag(Storage::Mcap, _) => return Ok(LogFormat::Mcap),
        Content::Bag(Storage::Sqlite3, _) => return Ok(LogFormat::Sqlite3),
        Content::Bag(Storage::Ros1, _) => return Ok(LogFormat::Ros1),
        Content::Rosbag2Metadata => return Ok(LogFormat::Rosbag2),
        Content::Other(looks_like) => {
            return Err(LogError::Mcap {
                path: path.to_path_buf(),
                topic: None,
                problem: Box::new(mcap::McapProblem::NotARecording { looks_like }),
            })
        }
        Content::Text => {}
    }
    let mut text = open_text(path)?;
    let mut raw = Vec::new();
    loop {
        raw.clear();
        let read = text
            .read_until(b'\n', &mut raw)
            .map_err(|source| LogError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        if read == 0 {
            return Err(LogError::Empty {
                path: path.to_path_buf(),
                what: "no rows",
            });
        }
        let line = String::from_utf8_lossy(&raw);
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let numeric = line
            .split(',')
            .all(|f| f.trim().trim_matches('"').parse::<f64>().is_ok());
        return Ok(if numeric {
            LogFormat::Wpi
        } else {
            LogFormat::Csv
        });
    }
}

/// The files that hold the log at `path`: the file itself, or a rosbag2 folder's
/// `metadata.yaml` and recording files in order (what the result's provenance hashes).
pub fn files_of(path: impl AsRef<Path>) -> Result<Vec<PathBuf>, LogError> {
    use self::mcap::sniff::{sniff, Content};
    let path = path.as_ref();
    // Only a folder or its metadata.yaml stand for other files: any other file is
    // itself, whatever its content (it is hashed, not read, here).
    let is_bag = std::fs::metadata(path)
        .map_err(|source| LogError::Io {
            path: path.to_path_buf(),
            source,
        })?
        .is_dir()
        || matches!(sniff(path)?, Content::Rosbag2Metadata);
    if !is_bag {
        return Ok(vec![path.to_path_buf()]);
    }
    #[cfg(feature = "recordings")]
    {
        let located = mcap::bag::locate(path)?;
        Ok(located.metadata.into_iter().chain(located.files).collect())
    }
    #[cfg(not(feature = "recordings"))]
    Err(recordings_not_built(path, LogFormat::Rosbag2))
}

/// The error of a build without the `recordings` feature for a log of `format`.
#[cfg(not(feature = "recordings"))]
pub(crate) fn recordings_not_built(path: &Path, format: LogFormat) -> LogError {
    LogError::RecordingsNotBuilt {
        path: path.to_path_buf(),
        what: format!("a recording ({format})"),
    }
}

/// Samples per block when a reader's blocks are collected into a whole log.
pub(crate) const BLOCK_SAMPLES: usize = 4096;

/// A text file, buffered, past its UTF-8 byte-order mark if it has one, with lines of
/// at most [`MAX_LINE_BYTES`].
pub(crate) fn open_text(path: &Path) -> Result<Box<dyn BufRead>, LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut reader = line_limit::LineLimit::new(
        std::io::BufReader::with_capacity(1 << 16, file),
        MAX_LINE_BYTES,
    );
    if reader.fill_buf().map_err(io)?.starts_with(b"\xEF\xBB\xBF") {
        reader.consume(3);
    }
    Ok(Box::new(reader))
}

/// Blocks of one log appended into a whole trajectory (the first block gives the
/// names, coordinates and source).
#[derive(Default)]
pub(crate) struct JointLogBuilder {
    first: Option<JointLog>,
    time: Vec<f64>,
    /// Row-major `q`, `dq` and `tau`.
    values: [Vec<f64>; 3],
}

impl JointLogBuilder {
    pub(crate) fn push(&mut self, block: &JointLog) {
        if self.first.is_none() {
            let dof = block.dof();
            self.first = Some(JointLog {
                time: Vec::new(),
                q: nalgebra::DMatrix::zeros(0, dof),
                dq: block.dq.as_ref().map(|_| nalgebra::DMatrix::zeros(0, dof)),
                tau: nalgebra::DMatrix::zeros(0, dof),
                joint_names: block.joint_names.clone(),
                coordinates: block.coordinates,
                source: block.source.clone(),
            });
        }
        self.time.extend_from_slice(&block.time);
        let signals = [Some(&block.q), block.dq.as_ref(), Some(&block.tau)];
        for (out, m) in self.values.iter_mut().zip(signals) {
            if let Some(m) = m {
                for i in 0..m.nrows() {
                    out.extend(m.row(i).iter());
                }
            }
        }
    }

    pub(crate) fn build(self) -> JointLog {
        let Some(first) = self.first else {
            return JointLog {
                time: Vec::new(),
                q: nalgebra::DMatrix::zeros(0, 0),
                dq: None,
                tau: nalgebra::DMatrix::zeros(0, 0),
                joint_names: Vec::new(),
                coordinates: Coordinates::Measured,
                source: String::new(),
            };
        };
        let (n, dof) = (self.time.len(), first.dof());
        let [q, dq, tau] = self.values;
        let matrix = |v: &[f64]| nalgebra::DMatrix::from_row_slice(n, dof, v);
        JointLog {
            q: matrix(&q),
            dq: first.dq.as_ref().map(|_| matrix(&dq)),
            tau: matrix(&tau),
            time: self.time,
            ..first
        }
    }
}

/// Formats a value so that parsing it gives back the same `f64` (shortest round-trip
/// representation), in plain notation for ordinary magnitudes and exponent notation for
/// very small or large ones (Rust's plain `{}` would print 1e-300 with 300 zeros).
pub(crate) fn fmt_f64(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || (1e-5..1e16).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Writes `path` with `fill` through [`crate::output::write_with`]: a regular file
/// atomically (temporary file in the same directory, synced, renamed; on failure `path`
/// is left untouched), a symbolic link through to its target, a device or pipe in place,
/// `-` to standard output.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), LogError> {
    crate::destination::write_with(path, fill).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn float_format_round_trips() {
        for v in [
            0.0,
            -0.0,
            1.0,
            -0.1,
            1e-300,
            -2.5e-7,
            1e20,
            f64::MAX,
            f64::MIN_POSITIVE,
            0.1 + 0.2,
            -0.43909142302978293,
        ] {
            let s = fmt_f64(v);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
            assert!(s.len() < 30, "{s}");
        }
    }
}
