//! Where the messages of a recording are: a single file (MCAP, rosbag2's sqlite3 `.db3`,
//! a ROS 1 `.bag`, each possibly zstd- or lz4-compressed as a whole) or a rosbag2 folder
//! (its `metadata.yaml` lists the files of the recording in order, split recordings
//! included). Everything is recognized by content (`sniff`), never by extension: a
//! recorder names its files as it likes, and a wrong guess would read binary data as CSV.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use super::problem::{mcap_error, McapProblem, UnpackBound};
use super::sniff::{io_error, LZ4_MAGIC, ZSTD_MAGIC};
pub(crate) use super::sniff::{sniff, Content, Packing, Storage};
use crate::log::{LogError, LogFormat};

/// One file of a recording.
#[derive(Debug)]
pub(crate) struct BagFile {
    /// The file as found (named in messages).
    pub path: PathBuf,
    pub storage: Storage,
    pub packing: Packing,
    /// Most bytes the file may decompress to ([`unpack_limit`] of its size): as a
    /// whole, and separately what its compressed chunks or messages decompress to.
    pub unpack_limit: u64,
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
    /// `max_unpacked_mib` bounds what a compressed sqlite3 or ROS 1 file may decompress
    /// to ([`unpack_limit`]).
    pub fn open(path: &Path, max_unpacked_mib: Option<u64>) -> Result<Bag, LogError> {
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
            let size = std::fs::metadata(&p).map_err(io_error(&p))?.len();
            let limit = unpack_limit(size, max_unpacked_mib);
            let unpacked = match (storage, packing) {
                (_, Packing::None) | (Storage::Mcap, _) => None,
                _ => Some(TempCopy::unpack(&p, packing, limit)?),
            };
            files.push(BagFile {
                path: p,
                storage,
                packing,
                unpack_limit: limit,
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

/// Most recording files a rosbag2 `metadata.yaml` may list: a split recording of 10 000
/// files is terabytes at rosbag2's usual split sizes.
pub(crate) const MAX_BAG_FILES: usize = 10_000;

/// Deepest nesting of a `metadata.yaml` (rosbag2 writes 4 levels).
const MAX_YAML_DEPTH: usize = 32;

/// Checks a `metadata.yaml` before it is loaded: no anchors or aliases (rosbag2 never
/// writes them, and an alias expanded by the loader can turn a kilobyte into gigabytes)
/// and a nesting of at most [`MAX_YAML_DEPTH`] (a deeper one is no rosbag2 metadata).
fn check_yaml_events(text: &str) -> Result<(), YamlProblem> {
    use yaml_rust2::parser::{Event, Parser};
    let mut parser = Parser::new_from_str(text);
    let mut depth = 0usize;
    loop {
        let (event, mark) = parser.next_token().map_err(YamlProblem::Invalid)?;
        let line = mark.line();
        let anchored = match &event {
            Event::StreamEnd => return Ok(()),
            Event::Alias(_) => return Err(YamlProblem::Alias { line }),
            Event::SequenceStart(anchor, _) | Event::MappingStart(anchor, _) => {
                depth += 1;
                if depth > MAX_YAML_DEPTH {
                    return Err(YamlProblem::TooDeep { line });
                }
                *anchor
            }
            Event::SequenceEnd | Event::MappingEnd => {
                depth = depth.saturating_sub(1);
                0
            }
            Event::Scalar(_, _, anchor, _) => *anchor,
            _ => 0,
        };
        if anchored > 0 {
            return Err(YamlProblem::Anchor { line });
        }
    }
}

/// Why a `metadata.yaml` is not loaded ([`check_yaml_events`]).
#[derive(Debug, thiserror::Error)]
enum YamlProblem {
    #[error("not valid YAML: {0}")]
    Invalid(yaml_rust2::ScanError),
    #[error("line {line}: a YAML alias (`*name`); rosbag2 never writes anchors or aliases")]
    Alias { line: usize },
    #[error("line {line}: nested more than {MAX_YAML_DEPTH} levels deep; rosbag2 metadata has 4")]
    TooDeep { line: usize },
    #[error("line {line}: a YAML anchor (`&name`); rosbag2 never writes anchors or aliases")]
    Anchor { line: usize },
}

/// The files a rosbag2 `metadata.yaml` lists (`relative_file_paths`, relative to `dir`):
/// each a file inside `dir` (no absolute path, no `..`, no symbolic link leading out of
/// it), each once, at most [`MAX_BAG_FILES`].
fn metadata_files(yaml: &Path, dir: &Path) -> Result<Vec<PathBuf>, LogError> {
    let bad = |reason: String| mcap_error(yaml, None, McapProblem::Metadata { reason });
    let text = dvrk_model::input::read_text(yaml).map_err(io_error(yaml))?;
    check_yaml_events(&text).map_err(|e| bad(e.to_string()))?;
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
    if list.len() > MAX_BAG_FILES {
        return Err(bad(format!(
            "relative_file_paths lists {} files, more than the {MAX_BAG_FILES} accepted",
            list.len()
        )));
    }
    // The folder as the links inside it are compared with.
    let root = std::fs::canonicalize(dir).map_err(io_error(dir))?;
    let mut files = Vec::with_capacity(list.len());
    let mut seen = std::collections::HashMap::with_capacity(list.len());
    for entry in list {
        let name = entry
            .as_str()
            .ok_or_else(|| bad(format!("relative_file_paths: {entry:?} is not a file name")))?;
        let file = member(dir, &root, name)
            .map_err(|reason| bad(format!("relative_file_paths entry `{name}`: {reason}")))?;
        let id = crate::destination::FileId::of(&file)
            .ok()
            .flatten()
            .ok_or_else(|| {
                bad(format!(
                    "relative_file_paths entry `{name}`: cannot be read"
                ))
            })?;
        if let Some(first) = seen.insert(id, name) {
            return Err(bad(format!(
                "relative_file_paths entries `{first}` and `{name}` are the same file: a \
                 recording lists each of its files once"
            )));
        }
        files.push(file);
    }
    if files.is_empty() {
        return Err(bad("relative_file_paths is empty".into()));
    }
    Ok(files)
}

/// The file `name` of a rosbag2 folder `dir` (canonically `root`): a relative path of
/// normal components only, which exists and, symbolic links followed, is a file inside
/// the folder. Older rosbag2 versions wrote the paths with the folder's name in front:
/// the file name alone is tried next.
fn member(dir: &Path, root: &Path, name: &str) -> Result<PathBuf, MemberProblem> {
    use std::path::Component;
    let relative = Path::new(name);
    if name.is_empty() {
        return Err(MemberProblem::Empty);
    }
    if relative.is_absolute() || relative.has_root() {
        return Err(MemberProblem::Absolute);
    }
    if relative
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err(MemberProblem::LeadsOut);
    }
    let direct = dir.join(relative);
    let file = if std::fs::symlink_metadata(&direct).is_ok() {
        direct
    } else {
        match relative.file_name().map(|n| dir.join(n)) {
            Some(p) if std::fs::symlink_metadata(&p).is_ok() => p,
            _ => return Err(MemberProblem::Missing(dir.to_path_buf())),
        }
    };
    let resolved = std::fs::canonicalize(&file).map_err(|e| {
        if e.raw_os_error() == Some(40) || e.to_string().contains("symbolic links") {
            MemberProblem::LinkLoop
        } else {
            MemberProblem::Unfollowable(e)
        }
    })?;
    if !resolved.starts_with(root) {
        return Err(MemberProblem::LinkOut(resolved));
    }
    if !resolved.is_file() {
        return Err(MemberProblem::NotAFile);
    }
    Ok(file)
}

/// Why a name is not a file of a rosbag2 folder ([`member`]).
#[derive(Debug, thiserror::Error)]
enum MemberProblem {
    #[error("an empty file name")]
    Empty,
    #[error("an absolute path; a recording names files inside its folder")]
    Absolute,
    #[error("a path leading out of the folder (`..`); a recording names files inside its folder")]
    LeadsOut,
    /// Not in the folder (the folder).
    #[error("not in {}", .0.display())]
    Missing(PathBuf),
    #[error("a loop of symbolic links")]
    LinkLoop,
    #[error("cannot be followed: {0}")]
    Unfollowable(std::io::Error),
    /// A symbolic link out of the folder (where it leads).
    #[error("a symbolic link to {}, outside the folder; a recording names files inside its folder", .0.display())]
    LinkOut(PathBuf),
    #[error("not a file")]
    NotAFile,
}

/// A rosbag2 folder without its metadata.yaml (a recording that was interrupted before
/// writing it): its recording files, ordered by the split index rosbag2 puts at the end
/// of their names (`name_0.mcap`, `name_1.mcap`, ...).
fn folder_files(dir: &Path) -> Result<Vec<PathBuf>, LogError> {
    let mut found = Vec::new();
    let root = std::fs::canonicalize(dir).map_err(io_error(dir))?;
    for entry in std::fs::read_dir(dir).map_err(io_error(dir))? {
        let entry = entry.map_err(io_error(dir))?;
        let p = entry.path();
        // A symbolic link is a member only if it stays in the folder, as for a listed file.
        if entry.file_type().is_ok_and(|t| t.is_symlink()) {
            let name = entry.file_name().to_string_lossy().into_owned();
            member(dir, &root, &name).map_err(|reason| {
                mcap_error(
                    dir,
                    None,
                    McapProblem::Damaged {
                        kind: "rosbag2 folder",
                        reason: format!("entry `{name}`: {reason}"),
                    },
                )
            })?;
        }
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

/// Default bound of a decompressed copy, as a multiple of the compressed file: JointState
/// recordings compress 5 to 20 times; a decompression bomb, thousands of times.
pub const UNPACK_RATIO: u64 = 100;
/// The default bound is at least this, bytes (64 MiB: small files may compress better).
pub const UNPACK_FLOOR: u64 = 64 << 20;
/// The default bound is at most this, bytes (16 GiB).
pub const UNPACK_CEILING: u64 = 16 << 30;

/// The most bytes a compressed sqlite3 or ROS 1 file of `compressed` bytes may
/// decompress to: `max_unpacked_mib` MiB when given (`--max-unpacked-mib`), else
/// [`UNPACK_RATIO`] times its size within [`UNPACK_FLOOR`] and [`UNPACK_CEILING`].
pub fn unpack_limit(compressed: u64, max_unpacked_mib: Option<u64>) -> u64 {
    match max_unpacked_mib {
        Some(mib) => mib.saturating_mul(1 << 20),
        None => compressed
            .saturating_mul(UNPACK_RATIO)
            .clamp(UNPACK_FLOOR, UNPACK_CEILING),
    }
}

/// A decompressed copy of a file in the temporary folder, removed when dropped.
#[derive(Debug)]
struct TempCopy {
    path: PathBuf,
}

impl TempCopy {
    /// Decompresses `src` into the temporary folder, refusing more than `limit` bytes.
    fn unpack(src: &Path, packing: Packing, limit: u64) -> Result<TempCopy, LogError> {
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
        crate::temporary::register(&copy.path);
        let file = std::fs::File::open(src).map_err(io_error(src))?;
        let compressed = file.metadata().map_err(io_error(src))?.len();
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
        // One byte more than the bound tells a larger content, which is never written.
        let copied = match packing {
            Packing::Zstd => zstd::stream::read::Decoder::new(file)
                .and_then(|d| std::io::copy(&mut d.take(limit + 1), &mut out)),
            _ => lz4::Decoder::new(file)
                .and_then(|d| std::io::copy(&mut d.take(limit + 1), &mut out)),
        };
        if matches!(copied, Ok(n) if n > limit) {
            return Err(mcap_error(
                src,
                None,
                McapProblem::Unpacked {
                    kind: "compressed file",
                    bound: UnpackBound::File {
                        what: "it",
                        limit,
                        compressed,
                    },
                },
            ));
        }
        copied.map_err(|e| {
            mcap_error(
                src,
                None,
                McapProblem::Damaged {
                    kind: "compressed file",
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
        crate::temporary::forget(&self.path);
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
    /// More than `budget` bytes (or [`Unpacker::LIMIT`]) is an error, found before
    /// decompressing when the frame states its size.
    pub(crate) fn unpack(&mut self, data: &[u8], budget: u64) -> Option<Result<(), McapProblem>> {
        let limit = Self::LIMIT.min(budget);
        let fail = |e: std::io::Error| McapProblem::Container {
            reason: format!("a compressed message does not decompress: {e}"),
        };
        let bound = |bound| McapProblem::Unpacked {
            kind: "MCAP file",
            bound,
        };
        self.out.clear();
        if data.starts_with(ZSTD_MAGIC) {
            if let Ok(Some(size)) = zstd::zstd_safe::get_frame_content_size(data) {
                if size > limit {
                    return Some(Err(bound(UnpackBound::MessageStated { size, limit })));
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
                        Err(bound(UnpackBound::Message { limit }))
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

    /// A compressed sqlite3 file that expands beyond its bound is refused before the
    /// bound is exceeded on disk, and its temporary copy is removed; a given bound
    /// replaces the default.
    #[test]
    fn decompression_is_bounded() {
        assert_eq!(unpack_limit(1000, None), UNPACK_FLOOR);
        assert_eq!(unpack_limit(1 << 30, None), UNPACK_CEILING);
        assert_eq!(unpack_limit(1 << 22, None), 100 << 22);
        assert_eq!(unpack_limit(1000, Some(3)), 3 << 20);
        assert_eq!(unpack_limit(1000, Some(u64::MAX)), u64::MAX);
        let dir = std::env::temp_dir().join(format!("dvrk-ident-bomb-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // An SQLite header and 80 MiB of zeros: a few kB compressed.
        let mut content = b"SQLite format 3\0".to_vec();
        content.resize(80 << 20, 0);
        let packed = zstd::bulk::compress(&content, 3).unwrap();
        assert!(packed.len() < 100_000, "{}", packed.len());
        let bomb = dir.join("bomb.db3.zst");
        std::fs::write(&bomb, &packed).unwrap();
        let left = || {
            std::fs::read_dir(std::env::temp_dir())
                .unwrap()
                .flatten()
                .filter(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    name.starts_with(&format!("dvrk-ident-{}-", std::process::id()))
                        && name.ends_with("bomb.db3.zst")
                })
                .count()
        };
        let e = Bag::open(&bomb, None).unwrap_err().to_string();
        assert!(
            e.contains(
                "bomb.db3.zst: invalid compressed file: it decompresses to more than 64 MiB"
            ) && e.contains("--max-unpacked-mib"),
            "{e}"
        );
        assert_eq!(left(), 0);
        let e = Bag::open(&bomb, Some(1)).unwrap_err().to_string();
        assert!(e.contains("more than 1 MiB"), "{e}");
        assert_eq!(left(), 0);
        // Raised above its size, it is decompressed (and removed when dropped).
        let bag = Bag::open(&bomb, Some(81)).unwrap();
        assert_eq!(
            std::fs::metadata(bag.files[0].readable()).unwrap().len(),
            80 << 20
        );
        drop(bag);
        assert_eq!(left(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn message_unpacking() {
        let payload = b"\x00\x01\x00\x00some CDR bytes".repeat(20);
        let z = zstd::bulk::compress(&payload, 3).unwrap();
        let mut u = Unpacker::default();
        u.unpack(&z, u64::MAX).unwrap().unwrap();
        assert_eq!(u.out, payload);
        // A frame without its content size (streamed): the streaming decoder.
        let mut streamed = Vec::new();
        let mut enc = zstd::stream::write::Encoder::new(&mut streamed, 3).unwrap();
        std::io::Write::write_all(&mut enc, &payload).unwrap();
        enc.finish().unwrap();
        u.unpack(&streamed, u64::MAX).unwrap().unwrap();
        assert_eq!(u.out, payload);
        let mut enc = lz4::EncoderBuilder::new().build(Vec::new()).unwrap();
        std::io::Write::write_all(&mut enc, &payload).unwrap();
        let (l, r) = enc.finish();
        r.unwrap();
        u.unpack(&l, u64::MAX).unwrap().unwrap();
        assert_eq!(u.out, payload);
        assert!(u.unpack(&payload, u64::MAX).is_none());
        let mut bad = z.clone();
        bad.truncate(z.len() / 2);
        assert!(u.unpack(&bad, u64::MAX).unwrap().is_err());
        // Twice the same context: the second message is right too.
        u.unpack(&z, u64::MAX).unwrap().unwrap();
        assert_eq!(u.out, payload);
    }
}
