//! Where one output file goes and how it is written: standard output, a device or pipe
//! in place, a regular file (symbolic links followed) atomically through a temporary
//! file beside it. Below both the log writers ([`crate::log`]) and a command's set of
//! outputs ([`crate::output`], which re-exports these), so neither depends on the other
//! for it.

use std::fs::{File, OpenOptions};
use std::io::{Seek, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
/// Symbolic links followed to find an output's file, as the kernel's own limit (40).
pub const MAX_SYMLINKS: usize = 40;

/// Where an output goes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Destination {
    /// `-`: standard output.
    Stdout,
    /// A regular file, existing or not (symbolic links followed): replaced atomically.
    File(PathBuf),
    /// A device, FIFO or socket (symbolic links followed): written in place.
    Special(PathBuf),
}

impl Destination {
    /// Where `path` goes: `-` is standard output; symbolic links are followed; a folder,
    /// a missing parent folder or a path without a file name is an error whose message
    /// says so (the caller names the path).
    pub fn of(path: &Path) -> std::io::Result<Destination> {
        if path.as_os_str() == "-" {
            return Ok(Destination::Stdout);
        }
        if path.as_os_str().is_empty() {
            return Err(invalid("empty output path"));
        }
        let resolved = resolve_links(path)?;
        match std::fs::metadata(&resolved) {
            Ok(m) if m.is_dir() => Err(std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "is a folder, not a file",
            )),
            Ok(m) if m.is_file() => Ok(Destination::File(resolved)),
            Ok(_) => Ok(Destination::Special(resolved)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                if resolved.file_name().is_none()
                    || matches!(
                        resolved.components().next_back(),
                        Some(Component::ParentDir)
                    )
                {
                    return Err(invalid("not a file path"));
                }
                let dir = parent_dir(&resolved);
                match std::fs::metadata(&dir) {
                    Ok(m) if m.is_dir() => Ok(Destination::File(resolved)),
                    Ok(_) => Err(invalid(&format!("{} is not a folder", dir.display()))),
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(std::io::Error::new(
                        std::io::ErrorKind::NotFound,
                        format!(
                            "folder {} does not exist (outputs never create folders)",
                            dir.display()
                        ),
                    )),
                    Err(e) => Err(e),
                }
            }
            Err(e) => Err(e),
        }
    }

    /// The file this destination writes, for comparing two outputs.
    pub(crate) fn key(&self) -> Option<&Path> {
        match self {
            Destination::Stdout => None,
            Destination::File(p) | Destination::Special(p) => Some(p),
        }
    }
}

pub(crate) fn invalid(message: &str) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message.to_string())
}

/// The folder a file path is in (`.` for a bare name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// `path` with its symbolic links (of the last component, repeatedly) replaced by
/// their targets; a dangling link resolves to the missing file it names.
fn resolve_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_SYMLINKS {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&current)?;
                current = if target.is_absolute() {
                    target
                } else {
                    parent_dir(&current).join(target)
                };
            }
            Ok(_) => return Ok(current),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(current),
            Err(e) => return Err(e),
        }
    }
    Err(invalid(&format!(
        "more than {MAX_SYMLINKS} symbolic links to follow"
    )))
}

/// Checks a folder output (e.g. a report folder): `dir` (symbolic links followed) is an
/// existing folder, or does not exist and its parent folder does. Returns the resolved
/// path and whether it exists.
pub fn check_dir(dir: &Path) -> std::io::Result<(PathBuf, bool)> {
    if dir.as_os_str() == "-" {
        return Err(invalid("a folder output cannot be standard output"));
    }
    let resolved = resolve_links(dir)?;
    match std::fs::metadata(&resolved) {
        Ok(m) if m.is_dir() => Ok((resolved, true)),
        Ok(_) => Err(invalid("exists and is not a folder")),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            // The parent folder is checked as for a new file.
            Destination::of(&resolved)?;
            Ok((resolved, false))
        }
        Err(e) => Err(e),
    }
}

static TEMP_COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A new hidden temporary file beside `target` (same folder, so the rename is atomic)
/// with `target`'s permissions when it exists.
pub(crate) fn temp_beside(target: &Path) -> std::io::Result<(PathBuf, File)> {
    let name = target
        .file_name()
        .ok_or_else(|| invalid("not a file path"))?;
    let tmp = parent_dir(target).join(format!(
        ".{}.{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    // Removed by a signal handler if the run is interrupted (its name is unique, so
    // once renamed it is gone, and removing it then does nothing).
    crate::temporary::register(&tmp);
    let file = OpenOptions::new().write(true).create_new(true).open(&tmp)?;
    if let Ok(m) = std::fs::metadata(target) {
        if let Err(e) = file.set_permissions(m.permissions()) {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
    }
    Ok((tmp, file))
}

/// An unnamed scratch file (created in the system's temporary folder and unlinked at
/// once), for writers that must seek but go to a pipe or device.
fn scratch() -> std::io::Result<File> {
    let path = std::env::temp_dir().join(format!(
        ".dvrk-ident.{}.{}.scratch",
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let file = OpenOptions::new()
        .read(true)
        .write(true)
        .create_new(true)
        .open(&path)?;
    std::fs::remove_file(&path)?;
    Ok(file)
}

/// Opens a device, FIFO or socket for writing, without truncating or creating anything.
pub(crate) fn open_special(path: &Path) -> std::io::Result<File> {
    OpenOptions::new().write(true).open(path)
}

/// Writes one output with `fill`: a regular file atomically, a device or pipe in place,
/// `-` to standard output. Errors carry the OS error only: the caller names the path.
pub fn write_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    match Destination::of(path)? {
        Destination::Stdout => {
            let mut out = std::io::stdout().lock();
            fill(&mut out)?;
            out.flush()
        }
        Destination::Special(p) => {
            let mut w = std::io::BufWriter::new(open_special(&p)?);
            fill(&mut w)?;
            w.flush()
        }
        Destination::File(p) => {
            let (tmp, file) = temp_beside(&p)?;
            let result = (|| {
                let mut w = std::io::BufWriter::new(file);
                fill(&mut w)?;
                let file = w.into_inner().map_err(|e| e.into_error())?;
                file.sync_all()?;
                std::fs::rename(&tmp, &p)
            })();
            if result.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            result
        }
    }
}

/// [`write_with`] for writers that seek back (the MCAP writer fills in lengths): `fill`
/// gets a buffered file and returns it when done. A pipe, device or standard output
/// gets the content through an unnamed scratch file, copied when complete.
pub fn write_seekable<E>(
    path: &Path,
    fill: impl FnOnce(std::io::BufWriter<File>) -> Result<std::io::BufWriter<File>, E>,
    io_error: impl Fn(std::io::Error) -> E,
) -> Result<(), E> {
    let destination = Destination::of(path).map_err(&io_error)?;
    let finish = |w: std::io::BufWriter<File>| -> std::io::Result<File> {
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        Ok(file)
    };
    match destination {
        Destination::File(p) => {
            let (tmp, file) = temp_beside(&p).map_err(&io_error)?;
            let result = fill(std::io::BufWriter::new(file)).and_then(|w| {
                finish(w)
                    .and_then(|_| std::fs::rename(&tmp, &p))
                    .map_err(&io_error)
            });
            if result.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            result
        }
        other => {
            let file = scratch().map_err(&io_error)?;
            let mut file = finish(fill(std::io::BufWriter::new(file))?).map_err(&io_error)?;
            let copy = |file: &mut File| -> std::io::Result<()> {
                file.rewind()?;
                match &other {
                    Destination::Special(p) => {
                        let mut out = open_special(p)?;
                        std::io::copy(file, &mut out)?;
                        out.flush()
                    }
                    _ => {
                        let mut out = std::io::stdout().lock();
                        std::io::copy(file, &mut out)?;
                        out.flush()
                    }
                }
            };
            copy(&mut file).map_err(&io_error)
        }
    }
}

/// The identity of an existing file or folder, symbolic links followed: two paths with
/// the same identity are the same file, whatever their spelling (links, `..`, hard
/// links). On Unix the device and inode; elsewhere the canonical path.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct FileId(#[cfg(unix)] (u64, u64), #[cfg(not(unix))] PathBuf);

impl FileId {
    /// The identity of `path`, `None` when it does not exist (nothing to protect; a
    /// dangling link included).
    pub fn of(path: &Path) -> std::io::Result<Option<FileId>> {
        match std::fs::metadata(path) {
            #[cfg(unix)]
            Ok(m) => {
                use std::os::unix::fs::MetadataExt;
                Ok(Some(FileId((m.dev(), m.ino()))))
            }
            #[cfg(not(unix))]
            Ok(_) => std::fs::canonicalize(path).map(|p| Some(FileId(p))),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e),
        }
    }
}
