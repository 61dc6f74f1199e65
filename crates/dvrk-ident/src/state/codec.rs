//! The observation state file, version 1: writing, and reading with every check
//! before the numbers are trusted.
//!
//! Integers little-endian unsigned, numbers little-endian IEEE-754 binary64:
//!
//! | offset | bytes | content |
//! |---|---|---|
//! | 0 | 8 | magic `DVRKOBS\n` |
//! | 8 | 4 | format version (u32), 1 |
//! | 12 | 4 | zero |
//! | 16 | 8 | `H`, bytes of the header (u64, at most 16 MiB) |
//! | 24 | `H` | header: a UTF-8 JSON object (below) |
//! | 24 + `H` | 8·`n` | smallest processed torque per coordinate (N·m or N) |
//! | … | 8·`n` | largest processed torque per coordinate |
//! | … | 8·`n`·`T` | the merged factors: for each coordinate, the upper triangle of its `w`×`w` R factor row by row (`T = w(w+1)/2`) |
//! | … | 8·`n`·`T`·`L` | each log's factors, in the header's order, the same way |
//!
//! and nothing after. The header: `{"format": "dvrk-ident observation", "robot",
//! "robot_source", "robot_hash", "processing" (the `settings.processing` of a result),
//! "stribeck_velocity" (rad/s or m/s, or null), "mounting_pitch_deg" (degrees, absent for
//! the description's gravity), "coordinates": n, "width": w (the
//! model's parameters + 1, the torque column last), "logs": [{"path", "sha256", "bytes",
//! "source", "samples"}]}` (`L` logs). A log's factor reduces `samples` rows per
//! coordinate; the merged factor the sum. A PSM state (n = 7, w = 116) is 380 KB per
//! log plus 380 KB for the merged factors.
//!
//! Reading checks the magic, the version, the header and the exact size before
//! allocating the numbers, and then that every number is finite and every factor upper
//! triangular with a non-negative diagonal; anything else is an error naming the file.

use std::io::Read;
use std::path::Path;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::record::ObservationState;
use crate::error::IdentError;
use crate::fit::{Observed, ObservedLog, TorqueRange};
use crate::observation::Observation;
use crate::result::InputInfo;
use crate::signal::Processing;

/// The first bytes of a state file.
pub const MAGIC: [u8; 8] = *b"DVRKOBS\n";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
/// Largest accepted header (a header lists the logs: about 300 bytes each).
pub const MAX_HEADER_BYTES: u64 = 16 << 20;
/// Bytes before the header.
const PREFIX: usize = 24;
/// The header's `format` value.
const FORMAT: &str = "dvrk-ident observation";
/// Most processed samples one log of a state may count: more than three years at 1 kHz.
/// The count sets the degrees of freedom of the standard errors, which a forged count
/// would shrink at will; it cannot be checked against the factors, only bounded.
pub const MAX_SAMPLES_PER_LOG: usize = 100_000_000_000;
/// Largest magnitude of a factor entry: `R` holds square roots of sums of squared
/// regressor entries, far below this for logged values within their bounds; beyond it
/// `RᵀR` would overflow.
pub const MAX_FACTOR_ENTRY: f64 = 1e100;
/// Relative tolerance of the merged factors against the logs' (`RᵀR` of the merge
/// equals the sum over the logs up to rounding: each entry within about 1e-14 of the
/// product of its two columns' norms).
const MERGE_TOLERANCE: f64 = 1e-8;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Header {
    format: String,
    robot: String,
    robot_source: String,
    robot_hash: String,
    processing: Processing,
    stribeck_velocity: Option<f64>,
    /// Degrees; absent in states written before mounting pitches (level arms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mounting_pitch_deg: Option<f64>,
    coordinates: usize,
    width: usize,
    logs: Vec<HeaderLog>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct HeaderLog {
    path: String,
    sha256: String,
    bytes: u64,
    source: String,
    samples: usize,
}

fn bad(file: &str, message: impl Into<String>) -> IdentError {
    IdentError::State {
        file: file.to_string(),
        message: message.into(),
    }
}

impl ObservationState {
    /// The state in the file layout of the module docs.
    pub fn to_bytes(&self) -> Vec<u8> {
        let o = &self.observed;
        let n = o.parts.len();
        let w = o.parts.first().map_or(0, |p| p.r().ncols());
        let header = Header {
            format: FORMAT.into(),
            robot: self.robot.clone(),
            robot_source: self.robot_source.clone(),
            robot_hash: self.robot_hash.clone(),
            processing: self.processing.clone(),
            stribeck_velocity: self.stribeck_velocity,
            mounting_pitch_deg: self.mounting_pitch_deg,
            coordinates: n,
            width: w,
            logs: o
                .logs
                .iter()
                .map(|l| HeaderLog {
                    path: l.info.path.clone(),
                    sha256: l.info.sha256.clone(),
                    bytes: l.info.bytes,
                    source: l.info.source.clone(),
                    samples: l.parts.first().map_or(0, Observation::rows),
                })
                .collect(),
        };
        let header = serde_json::to_vec(&header).expect("the header serializes");
        let t = w * (w + 1) / 2;
        let mut out =
            Vec::with_capacity(PREFIX + header.len() + 8 * (2 * n + (o.logs.len() + 1) * n * t));
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(header.len() as u64).to_le_bytes());
        out.extend_from_slice(&header);
        let (min, max) = o.range.bounds();
        for x in min.iter().chain(max) {
            out.extend_from_slice(&x.to_le_bytes());
        }
        for parts in std::iter::once(&o.parts).chain(o.logs.iter().map(|l| &l.parts)) {
            for p in parts {
                let r = p.r();
                for i in 0..w {
                    for j in i..w {
                        out.extend_from_slice(&r[(i, j)].to_le_bytes());
                    }
                }
            }
        }
        out
    }

    /// Reads a state from its bytes; `file` names it in errors.
    pub fn from_bytes(bytes: &[u8], file: &str) -> Result<ObservationState, IdentError> {
        if bytes.len() < PREFIX {
            return Err(bad(
                file,
                format!(
                    "not a dvrk-ident observation state: {} bytes, shorter than its {PREFIX}-byte prefix",
                    bytes.len()
                ),
            ));
        }
        let h = header_length(bytes[..PREFIX].try_into().expect("prefix"), file)?;
        let rest = &bytes[PREFIX..];
        if (rest.len() as u64) < h {
            return Err(bad(
                file,
                format!(
                    "truncated: the header is {h} bytes, the file has {} after the prefix",
                    rest.len()
                ),
            ));
        }
        let (header, payload) = rest.split_at(h as usize);
        let (header, size) = parse_header(header, file)?;
        check_payload_size(payload.len() as u64, size, file)?;
        decode(header, payload, file)
    }

    /// Reads a state file, its size checked against the header before the numbers are
    /// read (a pipe or device is read only as far as the header says).
    pub fn read(path: &Path) -> Result<ObservationState, IdentError> {
        let file = path.display().to_string();
        let io = |source: std::io::Error| IdentError::Io {
            file: file.clone(),
            source,
        };
        let mut f = std::fs::File::open(path).map_err(io)?;
        let mut prefix = Vec::with_capacity(PREFIX);
        (&mut f)
            .take(PREFIX as u64)
            .read_to_end(&mut prefix)
            .map_err(io)?;
        if prefix.len() < PREFIX {
            return Err(bad(
                &file,
                format!(
                    "not a dvrk-ident observation state: {} bytes, shorter than its {PREFIX}-byte prefix",
                    prefix.len()
                ),
            ));
        }
        let h = header_length(prefix[..].try_into().expect("prefix"), &file)?;
        let mut header = Vec::new();
        (&mut f).take(h).read_to_end(&mut header).map_err(io)?;
        if (header.len() as u64) < h {
            return Err(bad(
                &file,
                format!(
                    "truncated: the header is {h} bytes, the file has {} after the prefix",
                    header.len()
                ),
            ));
        }
        let (header, size) = parse_header(&header, &file)?;
        // Grows with the bytes actually read, never beyond the size the header implies
        // (plus one byte to tell a longer file).
        let mut payload = Vec::new();
        (&mut f)
            .take(size + 1)
            .read_to_end(&mut payload)
            .map_err(io)?;
        check_payload_size(payload.len() as u64, size, &file)?;
        decode(header, &payload, &file)
    }

    /// Writes the state atomically ([`crate::output`]).
    pub fn write(&self, path: &Path) -> Result<(), IdentError> {
        let bytes = self.to_bytes();
        crate::output::write_with(path, |w| w.write_all(&bytes)).map_err(|source| IdentError::Io {
            file: path.display().to_string(),
            source,
        })
    }
}

/// The header length from the prefix, after the magic and the version.
fn header_length(prefix: &[u8; PREFIX], file: &str) -> Result<u64, IdentError> {
    if prefix[..8] != MAGIC {
        return Err(bad(
            file,
            format!(
                "not a dvrk-ident observation state (it starts with bytes {:02x?}, a state with \
                 `DVRKOBS`): write one with `dvrk-ident observe`",
                &prefix[..8]
            ),
        ));
    }
    let version = u32::from_le_bytes(prefix[8..12].try_into().expect("4 bytes"));
    if version != VERSION {
        return Err(bad(
            file,
            format!(
                "observation state format version {version}; this dvrk-ident reads version \
                 {VERSION} only: observe the logs again with this version"
            ),
        ));
    }
    if prefix[12..16] != [0; 4] {
        return Err(bad(file, "bytes 12..16 of the prefix must be zero"));
    }
    let h = u64::from_le_bytes(prefix[16..24].try_into().expect("8 bytes"));
    if h > MAX_HEADER_BYTES {
        return Err(bad(
            file,
            format!(
                "a header of {h} bytes, more than the {} MiB accepted",
                MAX_HEADER_BYTES >> 20
            ),
        ));
    }
    Ok(h)
}

/// The header, checked, and the payload's size in bytes.
fn parse_header(bytes: &[u8], file: &str) -> Result<(Header, u64), IdentError> {
    let header: Header = serde_json::from_slice(bytes)
        .map_err(|e| bad(file, format!("the header is not a state header: {e}")))?;
    if header.format != FORMAT {
        return Err(bad(
            file,
            format!("the header's format is {:?}, not {FORMAT:?}", header.format),
        ));
    }
    let (n, w) = (header.coordinates, header.width);
    if n == 0 || n > dvrk_model::input::MAX_COORDINATES {
        return Err(bad(
            file,
            format!(
                "{n} coordinates: 1 to {} accepted",
                dvrk_model::input::MAX_COORDINATES
            ),
        ));
    }
    if !(2..=dvrk_model::input::MAX_PARAMETERS + 1).contains(&w) {
        return Err(bad(
            file,
            format!(
                "width {w}: 2 to {} accepted (parameters + 1)",
                dvrk_model::input::MAX_PARAMETERS + 1
            ),
        ));
    }
    if header.logs.is_empty() {
        return Err(bad(file, "no log in the state"));
    }
    if let Some(l) = header.logs.iter().find(|l| l.samples == 0) {
        return Err(bad(file, format!("log {}: no sample", l.path)));
    }
    if let Some(l) = header.logs.iter().find(|l| l.samples > MAX_SAMPLES_PER_LOG) {
        return Err(bad(
            file,
            format!(
                "log {}: {} samples, more than the {MAX_SAMPLES_PER_LOG} a log can hold",
                l.path, l.samples
            ),
        ));
    }
    if let Some(v) = header.stribeck_velocity {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad(
                file,
                format!("Stribeck velocity must be positive and finite, got {v}"),
            ));
        }
    }
    header
        .processing
        .check(n)
        .map_err(|e| bad(file, format!("its processing settings: {e}")))?;
    if header
        .logs
        .iter()
        .try_fold(0usize, |total, l| total.checked_add(l.samples))
        .is_none()
    {
        return Err(bad(file, "the logs' sample counts overflow"));
    }
    if header.robot_hash.len() != 64 || !header.robot_hash.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(bad(file, "robot_hash is not a SHA-256 in hexadecimal"));
    }
    let t = (w * (w + 1) / 2) as u64;
    let size = (header.logs.len() as u64 + 1)
        .checked_mul(n as u64 * t)
        .and_then(|v| v.checked_add(2 * n as u64))
        .and_then(|v| v.checked_mul(8))
        .ok_or_else(|| bad(file, "the header lists more logs than a file can hold"))?;
    Ok((header, size))
}

fn check_payload_size(got: u64, size: u64, file: &str) -> Result<(), IdentError> {
    if got != size {
        return Err(bad(
            file,
            format!(
                "{} the header's {size} bytes of numbers (got {})",
                if got < size {
                    "truncated: fewer bytes than"
                } else {
                    "more bytes than"
                },
                if got > size {
                    "more".to_string()
                } else {
                    got.to_string()
                }
            ),
        ));
    }
    Ok(())
}

/// The merged factors must be the merge of the logs' factors: for each coordinate `RᵀR`
/// of the merge equals the sum over the logs of their `RᵀR`, up to rounding (a state
/// edited by hand, or merged factors of other logs, would fit other data than the logs
/// it lists).
fn check_merged(
    merged: &[Observation],
    logs: &[ObservedLog],
    file: &str,
) -> Result<(), IdentError> {
    for (j, m) in merged.iter().enumerate() {
        let gram = |r: &DMatrix<f64>| r.tr_mul(r);
        let mut sum = DMatrix::zeros(m.r().ncols(), m.r().ncols());
        for l in logs {
            sum += gram(l.parts[j].r());
        }
        // Each entry against its columns' norms (rounding errs by about eps·‖a‖·‖b‖),
        // with a floor for columns that are (nearly) zero.
        let d = sum.diagonal();
        let floor = 1e-12 * d.max().max(f64::MIN_POSITIVE);
        let merged = gram(m.r());
        let mut difference = 0.0f64;
        for a in 0..d.len() {
            for b in a..d.len() {
                let norm = (d[a] * d[b]).sqrt().max(floor);
                let x = (merged[(a, b)] - sum[(a, b)]).abs() / norm;
                // NaN (never: the entries are finite and bounded) counts as a mismatch.
                difference = if x.is_nan() {
                    f64::INFINITY
                } else {
                    difference.max(x)
                };
            }
        }
        if difference > MERGE_TOLERANCE {
            return Err(bad(
                file,
                format!(
                    "coordinate {}: the merged factors are not the merge of the logs' \
                     factors (relative difference {difference:.1e}, more than \
                     {MERGE_TOLERANCE:e}): the file was altered; observe the logs again",
                    j + 1
                ),
            ));
        }
    }
    Ok(())
}

/// The state from a checked header and a payload of its exact size.
fn decode(header: Header, payload: &[u8], file: &str) -> Result<ObservationState, IdentError> {
    let (n, w) = (header.coordinates, header.width);
    let mut numbers = payload
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")));
    let mut next = |what: &dyn Fn() -> String| -> Result<f64, IdentError> {
        let x = numbers.next().expect("the size was checked");
        if !x.is_finite() {
            Err(bad(file, format!("{}: {x} is not finite", what())))
        } else if x.abs() > MAX_FACTOR_ENTRY {
            Err(bad(
                file,
                format!(
                    "{}: {x:e} is beyond the accepted ±{MAX_FACTOR_ENTRY:e}",
                    what()
                ),
            ))
        } else {
            Ok(x)
        }
    };
    let mut bound = |name: &str| -> Result<Vec<f64>, IdentError> {
        (0..n)
            .map(|j| next(&|| format!("torque {name}imum of coordinate {}", j + 1)))
            .collect()
    };
    let min = bound("min")?;
    let max = bound("max")?;
    let max_torque = crate::Signal::Effort.max_magnitude();
    if let Some(x) = min.iter().chain(&max).find(|x| x.abs() > max_torque) {
        return Err(bad(
            file,
            format!("torque range: {x:e} is beyond the accepted ±{max_torque:e} N·m or N"),
        ));
    }
    if let Some(j) = (0..n).find(|&j| min[j] > max[j]) {
        return Err(bad(
            file,
            format!(
                "coordinate {}: torque minimum {} above its maximum {}",
                j + 1,
                min[j],
                max[j]
            ),
        ));
    }
    let total: usize = header.logs.iter().map(|l| l.samples).sum();
    let mut factors = |what: &str, rows: usize| -> Result<Vec<Observation>, IdentError> {
        (0..n)
            .map(|j| {
                let mut r = DMatrix::zeros(w, w);
                for i in 0..w {
                    for c in i..w {
                        r[(i, c)] = next(&|| format!("{what}, coordinate {}", j + 1))?;
                    }
                    if r[(i, i)] < 0.0 {
                        return Err(bad(
                            file,
                            format!(
                                "{what}, coordinate {}: negative diagonal entry {} of the R factor",
                                j + 1,
                                r[(i, i)]
                            ),
                        ));
                    }
                }
                Ok(Observation::from_factor(r, rows))
            })
            .collect()
    };
    let parts = factors("merged factors", total)?;
    let mut logs = Vec::with_capacity(header.logs.len());
    for l in &header.logs {
        let parts = factors(&format!("log {}", l.path), l.samples)?;
        logs.push(ObservedLog {
            info: InputInfo {
                role: "train".into(),
                path: l.path.clone(),
                sha256: l.sha256.clone(),
                bytes: l.bytes,
                source: l.source.clone(),
                metrics: None,
                offset: None,
            },
            parts,
        });
    }
    check_merged(&parts, &logs, file)?;
    Ok(ObservationState {
        file: Some(file.to_string()),
        robot: header.robot,
        robot_source: header.robot_source,
        robot_hash: header.robot_hash,
        processing: header.processing,
        stribeck_velocity: header.stribeck_velocity,
        mounting_pitch_deg: header.mounting_pitch_deg,
        observed: Observed {
            logs,
            parts,
            range: TorqueRange::from_bounds(min, max),
        },
    })
}
