//! Where the messages of a recording are: a single file (MCAP, rosbag2's sqlite3 `.db3`,
//! a ROS 1 `.bag`, each possibly zstd- or lz4-compressed as a whole) or a rosbag2 folder
//! (its `metadata.yaml` lists the files of the recording in order, split recordings
//! included). Everything is recognized by content, never by extension: a recorder
//! names its files as it likes, and a wrong guess would read binary data as CSV.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use super::channels::mcap_error;
use super::McapProblem;
use crate::log::{LogError, LogFormat};

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

/// The text of errors about files that are no log, after what the file looks like.
pub(crate) const SUPPORTED: &str = "supported: a rosbag2 folder (metadata.yaml with MCAP or \
    sqlite3 files, split recordings, zstd or lz4 compressed files or messages), an MCAP \
    file, a rosbag2 sqlite3 .db3 file, a ROS 1 .bag (format 2.0), each possibly \
    zstd/lz4-compressed, the 2019 headerless CSV layout and the headered CSV";

/// Bytes read to recognize a file.
const SNIFF_BYTES: usize = 4096;

fn io_error(path: &Path) -> impl Fn(std::io::Error) -> LogError + '_ {
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
        let file = std::fs::File::open(path).map_err(io_error(path))?;
        let inner = zstd::stream::read::Decoder::new(file)
            .and_then(|d| head(d, 64))
            .map_err(|e| unreadable(path, "zstd", &e))?;
        (Packing::Zstd, inner)
    } else if bytes.starts_with(LZ4_MAGIC) {
        let file = std::fs::File::open(path).map_err(io_error(path))?;
        let inner = lz4::Decoder::new(file)
            .and_then(|d| head(d, 64))
            .map_err(|e| unreadable(path, "lz4", &e))?;
        (Packing::Lz4, inner)
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

fn unreadable(path: &Path, what: &str, e: &std::io::Error) -> LogError {
    mcap_error(
        path,
        None,
        McapProblem::Container {
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

/// One file of a recording.
#[derive(Debug)]
pub(crate) struct BagFile {
    /// The file as found (named in messages).
    pub path: PathBuf,
    pub storage: Storage,
    pub packing: Packing,
    /// A compressed sqlite3 or ROS 1 file decompressed into a temporary file: those
    /// formats need random access. (A compressed MCAP is decompressed as it is read.)
    unpacked: Option<TempCopy>,
}

impl BagFile {
    /// The file to read: the decompressed copy if there is one.
    pub fn readable(&self) -> &Path {
        self.unpacked.as_ref().map_or(&self.path, |t| &t.path)
    }
}

/// A recording: one file or the files of a rosbag2 folder, in order.
#[derive(Debug)]
pub(crate) struct Bag {
    /// The log as given (a file, a folder or its metadata.yaml).
    pub path: PathBuf,
    pub files: Vec<BagFile>,
    pub format: LogFormat,
}

impl Bag {
    /// Finds the files of the recording at `path` (see the module docs). A file that is
    /// no recording is a [`McapProblem::NotARecording`] error saying what it looks like.
    pub fn open(path: &Path) -> Result<Bag, LogError> {
        let located = locate(path)?;
        let (paths, format) = (located.files, located.format);
        let mut files = Vec::with_capacity(paths.len());
        for p in paths {
            let (storage, packing) = match sniff(&p)? {
                Content::Bag(s, k) => (s, k),
                // Empty: cut before its first byte (the MCAP reader says so).
                Content::Text if std::fs::metadata(&p).is_ok_and(|m| m.len() == 0) => {
                    (Storage::Mcap, Packing::None)
                }
                Content::Text => return Err(not_a_recording(&p, "a text file")),
                Content::Rosbag2Metadata => return Err(not_a_recording(&p, "a metadata.yaml")),
                Content::Other(what) => return Err(not_a_recording(&p, &what)),
            };
            let unpacked = match (storage, packing) {
                (_, Packing::None) | (Storage::Mcap, _) => None,
                _ => Some(TempCopy::unpack(&p, packing)?),
            };
            files.push(BagFile {
                path: p,
                storage,
                packing,
                unpacked,
            });
        }
        Ok(Bag {
            path: path.to_path_buf(),
            files,
            format,
        })
    }
}

/// The files of a recording, found without reading them.
pub(crate) struct Located {
    /// The rosbag2 metadata.yaml, if there is one.
    pub metadata: Option<PathBuf>,
    /// The recording files, in order.
    pub files: Vec<PathBuf>,
    pub format: LogFormat,
}

/// Finds the files of the recording at `path` (a file, a rosbag2 folder or its
/// metadata.yaml).
pub(crate) fn locate(path: &Path) -> Result<Located, LogError> {
    let meta = std::fs::metadata(path).map_err(io_error(path))?;
    if meta.is_dir() {
        let yaml = path.join("metadata.yaml");
        return Ok(if yaml.exists() {
            Located {
                files: metadata_files(&yaml, path)?,
                metadata: Some(yaml),
                format: LogFormat::Rosbag2,
            }
        } else {
            Located {
                metadata: None,
                files: folder_files(path)?,
                format: LogFormat::Rosbag2,
            }
        });
    }
    match sniff(path)? {
        Content::Rosbag2Metadata => {
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            };
            Ok(Located {
                files: metadata_files(path, &dir)?,
                metadata: Some(path.to_path_buf()),
                format: LogFormat::Rosbag2,
            })
        }
        Content::Bag(storage, _) => Ok(Located {
            metadata: None,
            files: vec![path.to_path_buf()],
            format: match storage {
                Storage::Mcap => LogFormat::Mcap,
                Storage::Sqlite3 => LogFormat::Sqlite3,
                Storage::Ros1 => LogFormat::Ros1,
            },
        }),
        // An empty file read as a recording: one that was cut before its first byte.
        Content::Text if meta.len() == 0 => Ok(Located {
            metadata: None,
            files: vec![path.to_path_buf()],
            format: LogFormat::Mcap,
        }),
        Content::Text => Err(not_a_recording(path, "a text file (a CSV log?)")),
        Content::Other(what) => Err(not_a_recording(path, &what)),
    }
}

fn not_a_recording(path: &Path, looks_like: &str) -> LogError {
    mcap_error(
        path,
        None,
        McapProblem::NotARecording {
            looks_like: looks_like.to_string(),
        },
    )
}

/// The files a rosbag2 `metadata.yaml` lists (`relative_file_paths`, relative to `dir`).
fn metadata_files(yaml: &Path, dir: &Path) -> Result<Vec<PathBuf>, LogError> {
    let bad = |reason: String| mcap_error(yaml, None, McapProblem::Metadata { reason });
    let text = std::fs::read_to_string(yaml).map_err(io_error(yaml))?;
    let docs = yaml_rust2::YamlLoader::load_from_str(&text)
        .map_err(|e| bad(format!("not valid YAML: {e}")))?;
    let info = docs
        .first()
        .map(|d| &d["rosbag2_bagfile_information"])
        .filter(|i| !i.is_badvalue())
        .ok_or_else(|| bad("no rosbag2_bagfile_information".into()))?;
    let list = info["relative_file_paths"]
        .as_vec()
        .ok_or_else(|| bad("no relative_file_paths list".into()))?;
    let mut files = Vec::with_capacity(list.len());
    for entry in list {
        let name = entry
            .as_str()
            .ok_or_else(|| bad(format!("relative_file_paths: {entry:?} is not a file name")))?;
        // Older rosbag2 versions wrote the paths with the folder's name in front.
        let direct = dir.join(name);
        let file = if direct.exists() {
            direct
        } else {
            match Path::new(name).file_name().map(|n| dir.join(n)) {
                Some(p) if p.exists() => p,
                _ => {
                    return Err(bad(format!(
                        "it lists {name}, which is not in {}",
                        dir.display()
                    )))
                }
            }
        };
        files.push(file);
    }
    if files.is_empty() {
        return Err(bad("relative_file_paths is empty".into()));
    }
    Ok(files)
}

/// A rosbag2 folder without its metadata.yaml (a recording that was interrupted before
/// writing it): its recording files, ordered by the split index rosbag2 puts at the end
/// of their names (`name_0.mcap`, `name_1.mcap`, ...).
fn folder_files(dir: &Path) -> Result<Vec<PathBuf>, LogError> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_error(dir))? {
        let p = entry.map_err(io_error(dir))?.path();
        if p.is_file() && matches!(sniff(&p)?, Content::Bag(..)) {
            found.push(p);
        }
    }
    if found.is_empty() {
        return Err(not_a_recording(
            dir,
            "a folder with neither a metadata.yaml nor a recording file",
        ));
    }
    let split_index = |p: &PathBuf| -> (u64, String) {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let stem = name.split('.').next().unwrap_or_default();
        let index = stem
            .rsplit('_')
            .next()
            .and_then(|n| n.parse::<u64>().ok())
            .unwrap_or(0);
        (index, name)
    };
    found.sort_by_key(split_index);
    Ok(found)
}

static TEMP_COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A decompressed copy of a file in the temporary folder, removed when dropped.
#[derive(Debug)]
struct TempCopy {
    path: PathBuf,
}

impl TempCopy {
    fn unpack(src: &Path, packing: Packing) -> Result<TempCopy, LogError> {
        let name = src
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let copy = TempCopy {
            path: std::env::temp_dir().join(format!(
                "dvrk-ident-{}-{}-{name}",
                std::process::id(),
                TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
            )),
        };
        let file = std::fs::File::open(src).map_err(io_error(src))?;
        let mut out = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&copy.path)
            .map_err(io_error(&copy.path))?;
        let what = if packing == Packing::Zstd {
            "zstd"
        } else {
            "lz4"
        };
        let copied = match packing {
            Packing::Zstd => zstd::stream::read::Decoder::new(file)
                .and_then(|mut d| std::io::copy(&mut d, &mut out)),
            _ => lz4::Decoder::new(file).and_then(|mut d| std::io::copy(&mut d, &mut out)),
        };
        copied.map_err(|e| {
            mcap_error(
                src,
                None,
                McapProblem::Container {
                    reason: format!("cannot decompress the {what} file: {e}"),
                },
            )
        })?;
        Ok(copy)
    }
}

impl Drop for TempCopy {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Decompresses payloads of messages compressed on their own (rosbag2's
/// `compression_mode: message`), reusing one zstd context: creating one per message
/// would cost more than the message.
#[derive(Default)]
pub(crate) struct Unpacker {
    zstd: Option<zstd::bulk::Decompressor<'static>>,
    /// The last payload decompressed.
    pub out: Vec<u8>,
}

impl Unpacker {
    /// Largest decompressed message, bytes: bounds what a corrupted frame can allocate.
    const LIMIT: u64 = 1 << 28;

    /// Decompresses `data` into [`Unpacker::out`]; `None` if it is not compressed. Only
    /// for CDR and JSON payloads, which cannot start with a zstd or lz4 frame magic.
    pub(crate) fn unpack(&mut self, data: &[u8]) -> Option<Result<(), String>> {
        let limit = Self::LIMIT;
        let fail = |e: std::io::Error| format!("a compressed message does not decompress: {e}");
        self.out.clear();
        if data.starts_with(ZSTD_MAGIC) {
            if let Ok(Some(size)) = zstd::zstd_safe::get_frame_content_size(data) {
                if size > limit {
                    return Some(Err(format!(
                        "a compressed message of {size} bytes is larger than {limit}"
                    )));
                }
                let decompressor = match &mut self.zstd {
                    Some(d) => d,
                    None => match zstd::bulk::Decompressor::new() {
                        Ok(d) => self.zstd.insert(d),
                        Err(e) => return Some(Err(fail(e))),
                    },
                };
                self.out.reserve(size as usize);
                return Some(
                    decompressor
                        .decompress_to_buffer(data, &mut self.out)
                        .map(|_| ())
                        .map_err(fail),
                );
            }
        }
        let decoded: std::io::Result<Box<dyn Read + '_>> = if data.starts_with(ZSTD_MAGIC) {
            zstd::stream::read::Decoder::new(data).map(|d| Box::new(d) as Box<dyn Read>)
        } else if data.starts_with(LZ4_MAGIC) {
            lz4::Decoder::new(data).map(|d| Box::new(d) as Box<dyn Read>)
        } else {
            return None;
        };
        Some(
            decoded
                .and_then(|d| d.take(limit + 1).read_to_end(&mut self.out))
                .map_err(fail)
                .and_then(|n| {
                    if n as u64 > limit {
                        Err(format!("a compressed message is larger than {limit} bytes"))
                    } else {
                        Ok(())
                    }
                }),
        )
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

    #[test]
    fn message_unpacking() {
        let payload = b"\x00\x01\x00\x00some CDR bytes".repeat(20);
        let z = zstd::bulk::compress(&payload, 3).unwrap();
        let mut u = Unpacker::default();
        u.unpack(&z).unwrap().unwrap();
        assert_eq!(u.out, payload);
        // A frame without its content size (streamed): the streaming decoder.
        let mut streamed = Vec::new();
        let mut enc = zstd::stream::write::Encoder::new(&mut streamed, 3).unwrap();
        std::io::Write::write_all(&mut enc, &payload).unwrap();
        enc.finish().unwrap();
        u.unpack(&streamed).unwrap().unwrap();
        assert_eq!(u.out, payload);
        let mut enc = lz4::EncoderBuilder::new().build(Vec::new()).unwrap();
        std::io::Write::write_all(&mut enc, &payload).unwrap();
        let (l, r) = enc.finish();
        r.unwrap();
        u.unpack(&l).unwrap().unwrap();
        assert_eq!(u.out, payload);
        assert!(u.unpack(&payload).is_none());
        let mut bad = z.clone();
        bad.truncate(z.len() / 2);
        assert!(u.unpack(&bad).unwrap().is_err());
        // Twice the same context: the second message is right too.
        u.unpack(&z).unwrap().unwrap();
        assert_eq!(u.out, payload);
    }
}
