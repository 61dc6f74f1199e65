//! Where output files go, and how they are written.
//!
//! Every output of the library, the CLI and the Python module goes through here, so the
//! rules are the same everywhere:
//!
//! - a **regular file** (existing or new) is replaced atomically: the content goes to a
//!   hidden temporary file beside it, is synced, and renamed over it; its permissions are
//!   kept. An error or a crash never leaves a half-written file under the final name;
//! - a **symbolic link** is followed (up to [`MAX_SYMLINKS`] hops): the file it points to is
//!   replaced as above and the link stays a link;
//! - a **device, FIFO or socket** (`/dev/null`, `/dev/stdout`, a named pipe) is written in
//!   place, never replaced by a regular file (atomic replacement would delete the device);
//! - `-` is standard output;
//! - a missing parent folder is an error: no folder is ever created that the user did not
//!   name (a report folder itself is created, see [`Outputs::add_dir`]).
//!
//! A command with several outputs collects them in [`Outputs`]: every destination is
//! checked and every file written to its temporary name first, and only when all of them
//! succeeded are they put in place ([`Outputs::commit`]). An error before the commit
//! leaves nothing behind.
//!
//! **No output is an input.** A command names its inputs ([`Inputs`]: logs with the
//! members of a rosbag2 folder, results, parameters, states, descriptions) and every
//! output is compared with them by identity ([`FileId`]: device and inode after following
//! symbolic links), not by name: `x.csv`, `./x.csv`, a link to it and a hard link are the
//! same file. An output that is an input is an error naming both before anything is
//! written: a recording is the one thing a lab cannot make again.

use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};

pub use crate::destination::{
    check_dir, write_seekable, write_with, Destination, FileId, MAX_SYMLINKS,
};
use crate::destination::{invalid, open_special, temp_beside};

/// The files a command reads, to refuse an output that is one of them (see the module
/// documentation). Paths that do not exist are skipped: the command's read fails on them
/// before anything is written.
#[derive(Clone, Debug, Default)]
pub struct Inputs {
    /// Identity, with the path as given and, for a member of a rosbag2 folder, the path
    /// of the member.
    files: Vec<(FileId, String)>,
}

impl Inputs {
    /// No input yet.
    pub fn new() -> Inputs {
        Inputs::default()
    }

    /// Adds the file (or folder) `path`, named `what` in messages (e.g. `the log
    /// a.mcap`). Standard input (`-`) and paths without an identity are skipped.
    pub fn add(&mut self, what: impl Into<String>, path: &Path) {
        if path.as_os_str() == "-" {
            return;
        }
        if let Ok(Some(id)) = FileId::of(path) {
            let what = what.into();
            if !self.files.iter().any(|(i, _)| *i == id) {
                self.files.push((id, what));
            }
        }
    }

    /// Adds a log: the file, or a rosbag2 folder with its `metadata.yaml` and every
    /// recording file it lists ([`crate::log::files_of`]; a folder whose list cannot be
    /// read protects every file directly in it instead).
    pub fn add_log(&mut self, path: &Path) {
        let given = path.display().to_string();
        self.add(format!("the log {given}"), path);
        if !std::fs::metadata(path).is_ok_and(|m| m.is_dir()) {
            // A metadata.yaml given for its folder stands for the folder's files too.
            if let Ok(files) = crate::log::files_of(path) {
                for f in files.iter().filter(|f| f.as_path() != path) {
                    self.add(format!("{} (in the log {given})", f.display()), f);
                }
            }
            return;
        }
        let members = crate::log::files_of(path).unwrap_or_else(|_| {
            std::fs::read_dir(path)
                .into_iter()
                .flatten()
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.is_file())
                .collect()
        });
        for f in &members {
            self.add(format!("{} (in the log {given})", f.display()), f);
        }
    }

    /// An error when `output` is one of the inputs, naming the input (the caller names
    /// the output). A folder output is compared as a whole (a report folder may not be a
    /// rosbag2 recording's folder).
    pub fn check(&self, output: &Path) -> std::io::Result<()> {
        if output.as_os_str() == "-" || self.files.is_empty() {
            return Ok(());
        }
        let Some(id) = FileId::of(output)? else {
            return Ok(());
        };
        match self.files.iter().find(|(i, _)| *i == id) {
            Some((_, what)) => Err(std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                format!(
                    "the same file as {what}, an input of this command: an output never \
                     replaces an input (give another output path)"
                ),
            )),
            None => Ok(()),
        }
    }
}

/// Why an output could not be prepared or written: the path as the user gave it and the
/// reason.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct OutputError {
    /// The output as given.
    pub path: PathBuf,
    /// What went wrong.
    #[source]
    pub source: std::io::Error,
}

impl OutputError {
    fn new(path: &Path, source: std::io::Error) -> OutputError {
        OutputError {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// One staged output.
enum Staged {
    /// A complete temporary file, renamed over `target` at the commit.
    File { tmp: PathBuf, target: PathBuf },
    /// A complete temporary folder, renamed to `target` (which did not exist) at the
    /// commit.
    Dir { tmp: PathBuf, target: PathBuf },
    /// Content for standard output or a device, written at the commit.
    Direct {
        destination: Destination,
        given: PathBuf,
        bytes: Vec<u8>,
    },
}

/// The outputs of one command, checked and written to temporary names before any is put
/// in place (see the module documentation). Dropping it without [`Outputs::commit`]
/// removes every temporary file.
#[derive(Default)]
pub struct Outputs {
    staged: Vec<Staged>,
    /// Destinations taken so far (resolved paths; `None` for standard output), with the
    /// path as given.
    taken: Vec<(Option<PathBuf>, PathBuf)>,
    /// The command's inputs, which no output may replace.
    inputs: Inputs,
}

impl Outputs {
    /// No output yet.
    pub fn new() -> Outputs {
        Outputs::default()
    }

    /// No output yet, none of which may replace one of `inputs`.
    pub fn protecting(inputs: Inputs) -> Outputs {
        Outputs {
            staged: Vec::new(),
            taken: Vec::new(),
            inputs,
        }
    }

    /// Checks that `path` can be an output of this command (see [`Destination::of`]) and
    /// that no earlier output of it goes to the same place.
    fn claim(&mut self, path: &Path) -> Result<Destination, OutputError> {
        let destination = Destination::of(path).map_err(|e| OutputError::new(path, e))?;
        self.inputs
            .check(path)
            .map_err(|e| OutputError::new(path, e))?;
        let key = destination.key().map(Path::to_path_buf);
        if let Some((_, other)) = self.taken.iter().find(|(k, _)| *k == key) {
            return Err(OutputError::new(
                path,
                invalid(&format!(
                    "the same destination as the output {} of this command",
                    other.display()
                )),
            ));
        }
        self.taken.push((key, path.to_path_buf()));
        Ok(destination)
    }

    /// Stages `bytes` for `path`.
    pub fn add(&mut self, path: &Path, bytes: impl AsRef<[u8]>) -> Result<(), OutputError> {
        self.add_with(path, |w| w.write_all(bytes.as_ref()))
    }

    /// Stages the output of `fill` for `path`: a regular file is written to its
    /// temporary name now, standard output and devices are kept in memory until the
    /// commit.
    pub fn add_with(
        &mut self,
        path: &Path,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), OutputError> {
        let err = |e| OutputError::new(path, e);
        match self.claim(path)? {
            Destination::File(target) => {
                let (tmp, file) = temp_beside(&target).map_err(err)?;
                // Registered before writing, so that a failure removes it.
                self.staged.push(Staged::File {
                    tmp: tmp.clone(),
                    target,
                });
                let mut w = std::io::BufWriter::new(file);
                fill(&mut w).map_err(err)?;
                let file = w.into_inner().map_err(|e| err(e.into_error()))?;
                file.sync_all().map_err(err)
            }
            destination => {
                let mut bytes = Vec::new();
                fill(&mut bytes).map_err(err)?;
                self.staged.push(Staged::Direct {
                    destination,
                    given: path.to_path_buf(),
                    bytes,
                });
                Ok(())
            }
        }
    }

    /// Stages a folder of files (`name`, content), e.g. a report: into `dir` if it is an
    /// existing folder (each file replaced atomically), else into a new folder `dir`
    /// whose parent must exist, built under a temporary name and renamed at the commit.
    /// Returns the final paths of the files.
    pub fn add_dir(
        &mut self,
        dir: &Path,
        files: &[(String, &[u8])],
    ) -> Result<Vec<PathBuf>, OutputError> {
        let err = |e| OutputError::new(dir, e);
        self.inputs.check(dir).map_err(err)?;
        match check_dir(dir).map_err(err)? {
            (_, true) => {
                for (name, bytes) in files {
                    self.add(&dir.join(name), bytes)?;
                }
            }
            (resolved, false) => {
                if self
                    .taken
                    .iter()
                    .any(|(k, _)| k.as_deref() == Some(&resolved))
                {
                    return Err(err(invalid(
                        "the same destination as another output of this command",
                    )));
                }
                self.taken.push((Some(resolved.clone()), dir.to_path_buf()));
                let (tmp, file) = temp_beside(&resolved).map_err(err)?;
                drop(file);
                std::fs::remove_file(&tmp).map_err(err)?;
                std::fs::create_dir(&tmp).map_err(err)?;
                self.staged.push(Staged::Dir {
                    tmp: tmp.clone(),
                    target: resolved,
                });
                for (name, bytes) in files {
                    let path = tmp.join(name);
                    let mut file = OpenOptions::new()
                        .write(true)
                        .create_new(true)
                        .open(&path)
                        .map_err(err)?;
                    file.write_all(bytes).map_err(err)?;
                    file.sync_all().map_err(err)?;
                }
            }
        }
        Ok(files.iter().map(|(name, _)| dir.join(name)).collect())
    }

    /// Puts every staged output in place: standard output and devices first (the
    /// writes that can still fail), then the renames.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let staged = std::mem::take(&mut self.staged);
        let (direct, renames): (Vec<_>, Vec<_>) = staged
            .into_iter()
            .partition(|s| matches!(s, Staged::Direct { .. }));
        // From here on the temporary files are ours to clean up on failure.
        let cleanup = |rest: &[Staged]| rest.iter().for_each(remove_staged);
        for s in &direct {
            if let Staged::Direct {
                destination,
                given,
                bytes,
            } = s
            {
                let write = || -> std::io::Result<()> {
                    match destination {
                        Destination::Special(p) => {
                            let mut f = open_special(p)?;
                            f.write_all(bytes)?;
                            f.flush()
                        }
                        _ => {
                            let mut out = std::io::stdout().lock();
                            out.write_all(bytes)?;
                            out.flush()
                        }
                    }
                };
                if let Err(e) = write() {
                    cleanup(&renames);
                    return Err(OutputError::new(given, e));
                }
            }
        }
        for (k, s) in renames.iter().enumerate() {
            let (Staged::File { tmp, target } | Staged::Dir { tmp, target }) = s else {
                continue;
            };
            if let Err(e) = std::fs::rename(tmp, target) {
                cleanup(&renames[k..]);
                return Err(OutputError::new(target, e));
            }
        }
        Ok(())
    }
}

fn remove_staged(s: &Staged) {
    match s {
        Staged::File { tmp, .. } => {
            let _ = std::fs::remove_file(tmp);
        }
        Staged::Dir { tmp, .. } => {
            let _ = std::fs::remove_dir_all(tmp);
        }
        Staged::Direct { .. } => {}
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        self.staged.iter().for_each(remove_staged);
    }
}

#[cfg(test)]
mod tests;
