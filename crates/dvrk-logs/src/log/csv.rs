//! CSV readers and writers: the 2019 (wpi) headerless layout and headered CSV.
//!
//! The readers stream the file: [`WpiBlocks`] and [`HeaderedBlocks`] parse it row by
//! row into blocks of samples, and [`read_wpi`] / [`read_headered`] collect every block,
//! so a log too long for memory and a short one go through the same parsing and checks.

use super::{fmt_f64, open_text, write_atomic, JointLogBuilder, LogError};
use crate::columns::{are_model_coordinate_names, ColumnKind, ColumnLayout};
use crate::joint_log::{Coordinates, JointLog, Signal};
use csv::{ReaderBuilder, StringRecord, Trim, WriterBuilder};
use nalgebra::DMatrix;
use std::io::BufRead;
use std::path::{Path, PathBuf};

/// The data records of a CSV file with their 1-based line numbers, read as needed.
/// Blank lines and lines starting with `#` are skipped; fields are trimmed; rows may
/// have differing lengths (checked by the callers, for precise messages).
struct Records {
    path: PathBuf,
    reader: csv::Reader<Box<dyn BufRead>>,
    done: bool,
}

impl Records {
    fn open(path: &Path) -> Result<Records, LogError> {
        let reader = ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(Trim::All)
            .comment(Some(b'#'))
            .from_reader(open_text(path)?);
        Ok(Records {
            path: path.to_path_buf(),
            reader,
            done: false,
        })
    }
}

impl Iterator for Records {
    type Item = Result<(u64, StringRecord), LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let mut record = StringRecord::new();
        loop {
            match self.reader.read_record(&mut record) {
                Ok(true) if record.iter().all(str::is_empty) => continue, // whitespace-only line
                Ok(true) => {
                    let line = record.position().map(|p| p.line()).unwrap_or(0);
                    return Some(Ok((line, record)));
                }
                Ok(false) => {
                    self.done = true;
                    return None;
                }
                Err(e) => {
                    self.done = true;
                    let (line, message) = (e.position().map(|p| p.line()), e.to_string());
                    // An I/O error is the file's, not the CSV's.
                    return Some(Err(match e.into_kind() {
                        csv::ErrorKind::Io(source) => LogError::Io {
                            path: self.path.clone(),
                            source,
                        },
                        _ => LogError::Csv {
                            path: self.path.clone(),
                            line,
                            message,
                        },
                    }));
                }
            }
        }
    }
}

/// Parses one field as a finite number; the error names the file, line and column.
fn parse_field(
    path: &Path,
    line: u64,
    column: usize,
    name: impl FnOnce() -> String,
    text: &str,
) -> Result<f64, LogError> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(LogError::NonFinite {
            path: path.to_path_buf(),
            line,
            column: column + 1,
            name: name(),
            text: text.to_string(),
        }),
        Err(_) => Err(LogError::MalformedNumber {
            path: path.to_path_buf(),
            line,
            column: column + 1,
            name: name(),
            text: text.to_string(),
        }),
    }
}

fn wpi_column_name(column: usize, dof: usize) -> String {
    let (block, j) = (column / dof, column % dof + 1);
    match block {
        0 => format!("q{j}"),
        1 => format!("dq{j}"),
        _ => format!("tau{j}"),
    }
}

/// A 2019 (wpi) layout log read block by block (see [`read_wpi`] for the layout).
pub struct WpiBlocks {
    path: PathBuf,
    records: Records,
    rate_hz: f64,
    /// Joints requested by the caller.
    dof: Option<usize>,
    /// `(columns, joints)`, from the first row.
    columns: Option<(usize, usize)>,
    rows: usize,
}

impl WpiBlocks {
    /// Opens `path`; `rate_hz` (Hz) is the implicit clock, `dof` the number of joints
    /// (`None`: columns / 3 of the first row).
    pub fn open(
        path: impl AsRef<Path>,
        rate_hz: f64,
        dof: Option<usize>,
    ) -> Result<Self, LogError> {
        let path = path.as_ref();
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(LogError::InvalidRate {
                path: path.to_path_buf(),
                what: "the sampling rate",
                setting: crate::hint::Hint::Rate,
                rate_hz,
            });
        }
        Ok(WpiBlocks {
            path: path.to_path_buf(),
            records: Records::open(path)?,
            rate_hz,
            dof,
            columns: None,
            rows: 0,
        })
    }

    /// The next block of at most `max_rows` samples (at least 1); `None` after the last.
    /// A file without rows is an error.
    pub fn next_block(&mut self, max_rows: usize) -> Result<Option<JointLog>, LogError> {
        let path = self.path.clone();
        let mut values: Vec<f64> = Vec::new();
        let mut count = 0;
        while count < max_rows.max(1) {
            let Some(rec) = self.records.next() else {
                break;
            };
            let (line, rec) = rec?;
            let (ncols, n) = match self.columns {
                Some(c) => c,
                None => {
                    let found = rec.len();
                    let ok = match self.dof {
                        Some(d) => d > 0 && found == 3 * d,
                        None => found > 0 && found % 3 == 0,
                    };
                    if !ok {
                        return Err(LogError::DofMismatch {
                            path,
                            line,
                            columns: found,
                            dof: self.dof,
                        });
                    }
                    *self.columns.insert((found, found / 3))
                }
            };
            if rec.len() != ncols {
                return Err(LogError::ColumnCount {
                    path,
                    line,
                    expected: ncols,
                    found: rec.len(),
                });
            }
            for (c, field) in rec.iter().enumerate() {
                values.push(parse_field(
                    &path,
                    line,
                    c,
                    || wpi_column_name(c, n),
                    field,
                )?);
            }
            count += 1;
        }
        let Some((ncols, n)) = self.columns else {
            return Err(LogError::Empty {
                path,
                what: "no rows",
            });
        };
        if count == 0 {
            return Ok(None);
        }
        let all = DMatrix::from_row_slice(count, ncols, &values);
        let first = self.rows;
        self.rows += count;
        Ok(Some(JointLog {
            time: (first..self.rows)
                .map(|k| k as f64 / self.rate_hz)
                .collect(),
            q: all.columns(0, n).into_owned(),
            dq: Some(all.columns(n, n).into_owned()),
            tau: all.columns(2 * n, n).into_owned(),
            joint_names: (1..=n).map(|j| format!("q{j}")).collect(),
            coordinates: Coordinates::Model,
            source: path.display().to_string(),
        }))
    }
}

/// Reads the 2019 (wpi) layout: no header, each row `q1..qn, dq1..dqn, tau1..taun`
/// (rad or m, rad/s or m/s, N·m or N), already in the model's coordinates. There are no
/// time stamps: sample `k` is at `k / rate_hz` s. `dof` fixes the number of joints
/// (the row must have `3 * dof` fields); `None` infers it as columns / 3. Joints are
/// named `q1..qn`, like the model coordinates.
///
/// ```rust
/// use dvrk_logs::log::read_wpi;
/// let path = std::env::temp_dir().join(format!("dvrk-ident-doc-wpi-{}.csv", std::process::id()));
/// std::fs::write(&path, "0.1,0.2,1.0,2.0,-3.0,4.5\n0.2,0.3,1.0,2.0,-3.0,4.5\n").unwrap();
/// let log = read_wpi(&path, 200.0, None).unwrap();
/// assert_eq!((log.len(), log.dof()), (2, 2));
/// assert_eq!(log.dq.as_ref().unwrap()[(0, 1)], 2.0);
/// assert_eq!(log.time[1], 0.005);
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn read_wpi(
    path: impl AsRef<Path>,
    rate_hz: f64,
    dof: Option<usize>,
) -> Result<JointLog, LogError> {
    let mut blocks = WpiBlocks::open(path, rate_hz, dof)?;
    let mut all = JointLogBuilder::default();
    while let Some(b) = blocks.next_block(super::BLOCK_SAMPLES)? {
        all.push(&b);
    }
    Ok(all.build())
}

/// Coordinates stated in a leading `# ... coordinates: model|measured` comment (read
/// from the file's first lines only), as the headered files of the development builds
/// before 0.1.0 have it.
fn stated_coordinates(path: &Path) -> Result<Option<Coordinates>, LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut text = open_text(path)?;
    let mut raw = Vec::new();
    loop {
        raw.clear();
        if text.read_until(b'\n', &mut raw).map_err(io)? == 0 {
            return Ok(None);
        }
        let line = String::from_utf8_lossy(&raw);
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let Some(comment) = line.strip_prefix('#') else {
            return Ok(None);
        };
        let comment = comment.to_ascii_lowercase();
        if let Some(rest) = comment.split("coordinates:").nth(1) {
            let word: String = rest
                .trim_start()
                .chars()
                .take_while(|c| c.is_ascii_alphabetic())
                .collect();
            match word.as_str() {
                "model" => return Ok(Some(Coordinates::Model)),
                "measured" => return Ok(Some(Coordinates::Measured)),
                _ => {}
            }
        }
    }
}

/// A headered CSV log read block by block (see [`read_headered`] for the layout).
pub struct HeaderedBlocks {
    path: PathBuf,
    records: Records,
    names: Vec<String>,
    kinds: Vec<ColumnKind>,
    joints: Vec<String>,
    with_velocity: bool,
    coordinates: Coordinates,
    last: Option<f64>,
    rows: usize,
}

impl HeaderedBlocks {
    /// Opens `path` and reads its header (and the coordinates comment before it).
    pub fn open(path: impl AsRef<Path>) -> Result<Self, LogError> {
        let path = path.as_ref();
        let p = || path.to_path_buf();
        let mut records = Records::open(path)?;
        let (header_line, header) = match records.next() {
            None => {
                return Err(LogError::Empty {
                    path: p(),
                    what: "no rows",
                })
            }
            Some(r) => r?,
        };
        let layout =
            ColumnLayout::parse(&header.iter().collect::<Vec<_>>(), "time").map_err(|source| {
                LogError::Columns {
                    path: p(),
                    line: header_line,
                    source,
                }
            })?;
        if layout.time().is_none() {
            return Err(LogError::MissingTime { path: p() });
        }
        let names: Vec<String> = header.iter().map(str::to_string).collect();
        let ColumnLayout {
            kinds,
            joints,
            with_velocity,
        } = layout;
        // Files of earlier versions state the coordinates in a leading comment; today's
        // carry them in the column names alone (model coordinates are `q1..qn`), so that
        // every CSV reader sees the header on the first line.
        let coordinates = match stated_coordinates(path)? {
            Some(c) => c,
            None if are_model_coordinate_names(&joints) => Coordinates::Model,
            None => Coordinates::Measured,
        };
        Ok(HeaderedBlocks {
            coordinates,
            path: p(),
            records,
            names,
            kinds,
            joints,
            with_velocity,
            last: None,
            rows: 0,
        })
    }

    /// The joints, in the order of the position columns.
    pub fn joint_names(&self) -> &[String] {
        &self.joints
    }

    /// The joint space the file states (measured unless a comment says otherwise).
    pub fn coordinates(&self) -> Coordinates {
        self.coordinates
    }

    /// Whether the file has velocity columns.
    pub fn has_velocity(&self) -> bool {
        self.with_velocity
    }

    /// The next block of at most `max_rows` samples (at least 1); `None` after the last.
    /// A header without data rows is an error.
    pub fn next_block(&mut self, max_rows: usize) -> Result<Option<JointLog>, LogError> {
        let p = || self.path.clone();
        let dof = self.joints.len();
        let mut time = Vec::new();
        let mut q = Vec::new();
        let mut dq = Vec::new();
        let mut tau = Vec::new();
        let mut row = vec![0.0; self.names.len()];
        while time.len() < max_rows.max(1) {
            let Some(rec) = self.records.next() else {
                break;
            };
            let (line, rec) = rec?;
            if rec.len() != self.names.len() {
                return Err(LogError::ColumnCount {
                    path: p(),
                    line,
                    expected: self.names.len(),
                    found: rec.len(),
                });
            }
            for (c, field) in rec.iter().enumerate() {
                row[c] = parse_field(&self.path, line, c, || self.names[c].clone(), field)?;
            }
            let base = q.len();
            q.resize(base + dof, 0.0);
            tau.resize(base + dof, 0.0);
            if self.with_velocity {
                dq.resize(base + dof, 0.0);
            }
            for (c, kind) in self.kinds.iter().enumerate() {
                match *kind {
                    ColumnKind::Time => {
                        let t = row[c];
                        if let Some(prev) = self.last {
                            if t <= prev {
                                return Err(LogError::NonMonotonicTime {
                                    path: p(),
                                    line,
                                    previous: prev,
                                    current: t,
                                });
                            }
                        }
                        self.last = Some(t);
                        time.push(t);
                    }
                    ColumnKind::Joint(Signal::Position, j) => q[base + j] = row[c],
                    ColumnKind::Joint(Signal::Velocity, j) => dq[base + j] = row[c],
                    ColumnKind::Joint(_, j) => tau[base + j] = row[c],
                }
            }
        }
        let n = time.len();
        if n == 0 {
            if self.rows == 0 {
                return Err(LogError::Empty {
                    path: p(),
                    what: "a header but no data rows",
                });
            }
            return Ok(None);
        }
        self.rows += n;
        Ok(Some(JointLog {
            time,
            q: DMatrix::from_row_slice(n, dof, &q),
            dq: self
                .with_velocity
                .then(|| DMatrix::from_row_slice(n, dof, &dq)),
            tau: DMatrix::from_row_slice(n, dof, &tau),
            joint_names: self.joints.clone(),
            coordinates: self.coordinates,
            source: self.path.display().to_string(),
        }))
    }
}

/// Reads a headered CSV log. The header has a `time` column (s), and for each joint
/// `position.<joint>` (rad or m), `effort.<joint>` (N·m or N) and optionally
/// `velocity.<joint>` (rad/s or m/s; for all joints or none), in any order. The joint
/// order is the order of the position columns; joint names may contain dots (the text
/// after the first dot). Unknown or duplicate columns are errors (a typo would
/// otherwise silently drop data). Time must strictly increase.
///
/// Columns are in model coordinates when the joints are named `q1, ..., qn` in order (as
/// [`write_headered`] writes a log in model coordinates), in measured joint space
/// otherwise; a comment line before the header saying `coordinates: model|measured` (as
/// earlier versions wrote) decides instead. Lines starting with `#` are comments.
///
/// ```rust
/// use dvrk_logs::log::read_headered;
/// let path = std::env::temp_dir().join(format!("dvrk-ident-doc-csv-{}.csv", std::process::id()));
/// std::fs::write(&path, "effort.yaw,time,position.yaw\n0.5,0.0,1.0\n0.6,0.01,1.1\n").unwrap();
/// let log = read_headered(&path).unwrap();
/// assert_eq!(log.joint_names, vec!["yaw"]);
/// assert!(log.dq.is_none());
/// assert_eq!(log.tau[(1, 0)], 0.6);
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn read_headered(path: impl AsRef<Path>) -> Result<JointLog, LogError> {
    let mut blocks = HeaderedBlocks::open(path)?;
    let mut all = JointLogBuilder::default();
    while let Some(b) = blocks.next_block(super::BLOCK_SAMPLES)? {
        all.push(&b);
    }
    Ok(all.build())
}

fn validated(path: &Path, log: &JointLog) -> Result<(), LogError> {
    log.validate().map_err(|source| LogError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes the 2019 (wpi) layout (see [`read_wpi`]) atomically. The layout holds model
/// coordinates and velocities and no time stamps: a trajectory in measured coordinates
/// or without velocities is refused, and the time stamps are dropped (the reader
/// assumes a uniform clock at the rate it is given).
pub fn write_wpi(path: impl AsRef<Path>, log: &JointLog) -> Result<(), LogError> {
    let path = path.as_ref();
    validated(path, log)?;
    if log.coordinates != Coordinates::Model {
        return Err(LogError::WrongCoordinates {
            path: path.to_path_buf(),
            found: log.coordinates,
        });
    }
    let Some(dq) = &log.dq else {
        return Err(LogError::MissingVelocity {
            path: path.to_path_buf(),
        });
    };
    write_atomic(path, |w| {
        let mut wr = WriterBuilder::new().has_headers(false).from_writer(w);
        let mut rec: Vec<String> = Vec::with_capacity(3 * log.dof());
        for i in 0..log.len() {
            rec.clear();
            for m in [&log.q, dq, &log.tau] {
                rec.extend(m.row(i).iter().map(|v| fmt_f64(*v)));
            }
            wr.write_record(&rec)?;
        }
        wr.flush()
    })
}

/// Writes a headered CSV (see [`read_headered`]) atomically: the header `time,
/// position.<joint>..., [velocity.<joint>...,] effort.<joint>...` on the first line, so
/// that pandas, numpy and spreadsheets read it with no options (units: s, rad or m, rad/s
/// or m/s, N·m or N). A log in model coordinates is written with the joints named `q1..qn`,
/// which is how the reader tells the two joint spaces apart. Values are written with the
/// shortest representation that reads back to the same `f64`, so a write-read round trip
/// is exact.
pub fn write_headered(path: impl AsRef<Path>, log: &JointLog) -> Result<(), LogError> {
    let path = path.as_ref();
    validated(path, log)?;
    let model_names: Vec<String>;
    let joint_names = match log.coordinates {
        Coordinates::Model => {
            model_names = (1..=log.dof()).map(|k| format!("q{k}")).collect();
            &model_names
        }
        Coordinates::Measured => &log.joint_names,
    };
    write_atomic(path, |w| {
        let mut wr = WriterBuilder::new().has_headers(false).from_writer(w);
        let mut header = vec!["time".to_string()];
        let mut signals: Vec<(&str, &DMatrix<f64>)> = vec![("position", &log.q)];
        if let Some(dq) = &log.dq {
            signals.push(("velocity", dq));
        }
        signals.push(("effort", &log.tau));
        for (prefix, _) in &signals {
            header.extend(joint_names.iter().map(|j| format!("{prefix}.{j}")));
        }
        wr.write_record(&header)?;
        let mut rec: Vec<String> = Vec::with_capacity(header.len());
        for i in 0..log.len() {
            rec.clear();
            rec.push(fmt_f64(log.time[i]));
            for (_, m) in &signals {
                rec.extend(m.row(i).iter().map(|v| fmt_f64(*v)));
            }
            wr.write_record(&rec)?;
        }
        wr.flush()
    })
}
