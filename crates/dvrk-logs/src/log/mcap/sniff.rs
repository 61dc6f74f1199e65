//! What a file is, from its first bytes: a recording (MCAP, rosbag2's sqlite3 `.db3`, a
//! ROS 1 `.bag`, each possibly zstd- or lz4-compressed as a whole), a rosbag2
//! `metadata.yaml`, text (a CSV log) or something else, described for the error.
//! Everything is recognized by content, never by extension: a recorder names its files
//! as it likes, and a wrong guess would read binary data as CSV.

use std::io::Read;
use std::path::Path;

#[cfg(feature = "recordings")]
use super::problem::{mcap_error, McapProblem};
use crate::log::LogError;

const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";
const ROS1_MAGIC: &[u8] = b"#ROSBAG V2.0\n";
pub(crate) const ZSTD_MAGIC: &[u8] = &[0x28, 0xB5, 0x2F, 0xFD];
pub(crate) const LZ4_MAGIC: &[u8] = &[0x04, 0x22, 0x4D, 0x18];

/// How a recording stores its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Storage {
    Mcap,
    Sqlite3,
    Ros1,
}

/// How a whole file is compressed (rosbag2's `compression_mode: file`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Packing {
    None,
    Zstd,
    Lz4,
}

/// What the first bytes of a file say it is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Content {
    /// A recording of messages.
    Bag(Storage, Packing),
    /// rosbag2's `metadata.yaml`.
    Rosbag2Metadata,
    /// Text (UTF-8, no NUL byte at its start): a CSV log, or nothing we read.
    Text,
    /// Anything else, described for an error message.
    Other(String),
}

/// Bytes read to recognize a file.
const SNIFF_BYTES: usize = 4096;

pub(super) fn io_error(path: &Path) -> impl Fn(std::io::Error) -> LogError + '_ {
    move |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Up to `n` bytes from the start of `r` (fewer only at its end).
fn head(mut r: impl Read, n: usize) -> std::io::Result<Vec<u8>> {
    let mut buf = Vec::with_capacity(n);
    r.by_ref().take(n as u64).read_to_end(&mut buf)?;
    Ok(buf)
}

/// Recognizes a file by its first bytes (see [`Content`]).
pub(crate) fn sniff(path: &Path) -> Result<Content, LogError> {
    let file = std::fs::File::open(path).map_err(io_error(path))?;
    let bytes = head(file, SNIFF_BYTES).map_err(io_error(path))?;
    let (packing, inner) = if bytes.starts_with(ZSTD_MAGIC) {
        (Packing::Zstd, unpacked_head(path, Packing::Zstd)?)
    } else if bytes.starts_with(LZ4_MAGIC) {
        (Packing::Lz4, unpacked_head(path, Packing::Lz4)?)
    } else {
        (Packing::None, bytes)
    };
    // A file cut inside the MCAP magic is a truncated MCAP (its reader says so).
    let cut_magic =
        !inner.is_empty() && inner.len() < MCAP_MAGIC.len() && MCAP_MAGIC.starts_with(&inner);
    let storage = if inner.starts_with(MCAP_MAGIC) || cut_magic {
        Some(Storage::Mcap)
    } else if inner.starts_with(SQLITE_MAGIC) {
        Some(Storage::Sqlite3)
    } else if inner.starts_with(ROS1_MAGIC) {
        Some(Storage::Ros1)
    } else {
        None
    };
    Ok(match (storage, packing) {
        (Some(s), p) => Content::Bag(s, p),
        (None, Packing::None) => describe(&inner),
        (None, p) => Content::Other(format!(
            "{}-compressed data that is not a recording (it does not start with the MCAP, \
             SQLite or ROS 1 bag magic once decompressed)",
            if p == Packing::Zstd { "zstd" } else { "lz4" }
        )),
    })
}

/// The first bytes of a file compressed as a whole (`packing` zstd or lz4), decompressed.
#[cfg(feature = "recordings")]
fn unpacked_head(path: &Path, packing: Packing) -> Result<Vec<u8>, LogError> {
    let file = std::fs::File::open(path).map_err(io_error(path))?;
    if packing == Packing::Zstd {
        zstd::stream::read::Decoder::new(file)
            .and_then(|d| head(d, 64))
            .map_err(|e| unreadable(path, "zstd", &e))
    } else {
        lz4::Decoder::new(file)
            .and_then(|d| head(d, 64))
            .map_err(|e| unreadable(path, "lz4", &e))
    }
}

/// Without the decompressors a compressed file is taken for a compressed recording, the
/// only compressed logs there are: refused for the missing feature.
#[cfg(not(feature = "recordings"))]
fn unpacked_head(path: &Path, packing: Packing) -> Result<Vec<u8>, LogError> {
    Err(LogError::RecordingsNotBuilt {
        path: path.to_path_buf(),
        what: format!(
            "{}-compressed data",
            if packing == Packing::Zstd {
                "zstd"
            } else {
                "lz4"
            }
        ),
    })
}

#[cfg(feature = "recordings")]
fn unreadable(path: &Path, what: &str, e: &std::io::Error) -> LogError {
    mcap_error(
        path,
        None,
        McapProblem::Damaged {
            kind: "compressed file",
            reason: format!(
                "the file starts like {what}-compressed data but does not decompress: {e}"
            ),
        },
    )
}

/// What uncompressed bytes look like.
fn describe(bytes: &[u8]) -> Content {
    const KNOWN: [(&[u8], &str); 13] = [
        (
            b"#ROSRECORD V1.2",
            "a ROS 1 bag in the old 1.2 format (convert it with `rosbag fix` to 2.0)",
        ),
        (b"#ROSBAG V", "a ROS 1 bag of an unknown format version"),
        (
            b"\x1f\x8b",
            "gzip-compressed data (decompress it, or compress with zstd or lz4)",
        ),
        (
            b"BZh",
            "bzip2-compressed data (decompress it, or compress with zstd or lz4)",
        ),
        (
            b"\xfd7zXZ\x00",
            "xz-compressed data (decompress it, or compress with zstd or lz4)",
        ),
        (b"PK\x03\x04", "a zip archive (extract it first)"),
        (b"\x89HDF\r\n\x1a\n", "an HDF5 file"),
        (
            b"\x93NUMPY",
            "a numpy .npy array (load it in Python and use dvrk_ident.Data)",
        ),
        (
            b"PAR1",
            "a Parquet file (load it with pandas and use dvrk_ident.Data.from_dataframe)",
        ),
        (b"\x89PNG", "a PNG image"),
        (b"%PDF", "a PDF document"),
        (b"\x7fELF", "an executable"),
        (b"\x89MCAP", "an MCAP file of an unknown format version"),
    ];
    if let Some((_, what)) = KNOWN.iter().find(|(m, _)| bytes.starts_with(m)) {
        return Content::Other((*what).to_string());
    }
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => Some(t),
        // A multi-byte character cut by the end of the sniffed bytes.
        Err(e) if e.error_len().is_none() => std::str::from_utf8(&bytes[..e.valid_up_to()]).ok(),
        Err(_) => None,
    };
    match text {
        Some(t) if !t.contains('\0') => {
            let t = t.trim_start_matches('\u{feff}');
            let first = t
                .lines()
                .map(str::trim)
                .find(|l| !l.is_empty() && !l.starts_with('#'));
            if first.is_some_and(|l| l.starts_with("rosbag2_bagfile_information:")) {
                Content::Rosbag2Metadata
            } else {
                Content::Text
            }
        }
        _ => {
            let shown: Vec<String> = bytes.iter().take(8).map(|b| format!("{b:02x}")).collect();
            Content::Other(format!(
                "binary data of no known log format (it starts with bytes {})",
                shown.join(" ")
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptions() {
        assert_eq!(describe(b"time,position.a\n0,1\n"), Content::Text);
        assert_eq!(describe(b""), Content::Text);
        assert_eq!(
            describe(b"# comment\nrosbag2_bagfile_information:\n  version: 5\n"),
            Content::Rosbag2Metadata
        );
        assert!(matches!(describe(b"\x1f\x8b\x08\x00"), Content::Other(w) if w.contains("gzip")));
        assert!(matches!(describe(b"a\0b"), Content::Other(w) if w.contains("61 00 62")));
        // A multi-byte character cut at the end of the sniffed bytes is still text.
        let mut cut = "é".repeat(10).into_bytes();
        cut.pop();
        assert_eq!(describe(&cut), Content::Text);
        assert!(matches!(describe(&[0xff, 0xfe, 0x41]), Content::Other(_)));
    }
}
