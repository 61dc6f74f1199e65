//! The temporary files of this process: decompressed copies of recordings (in the
//! system's temporary folder) and outputs being written (hidden files beside them, see
//! [`crate::output`]). Each is registered when it is created, so that an interrupted run
//! (Ctrl-C, `kill`) can remove them: the command line's signal handler calls
//! [`remove_all`] before it exits. On every other exit path their owners remove them
//! (errors, drop); a path left registered after its file was renamed or removed is
//! harmless, its name being unique to this process.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

static PATHS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn paths() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while holding the lock leaves a list that is still right.
    PATHS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Registers `path` (a file or a folder about to be created).
pub(crate) fn register(path: &Path) {
    paths().push(path.to_path_buf());
}

/// Forgets `path` (removed or renamed by its owner: the rosbag2 writer of `recordings`).
#[cfg(feature = "recordings")]
pub(crate) fn forget(path: &Path) {
    let mut paths = paths();
    if let Some(k) = paths.iter().rposition(|p| p == path) {
        paths.swap_remove(k);
    }
}

/// Removes every registered temporary file and folder that still exists: for a signal
/// handler (the command line's runs on a thread of its own), which then exits.
pub fn remove_all() {
    for p in paths().drain(..) {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.is_dir() => {
                let _ = std::fs::remove_dir_all(&p);
            }
            Ok(_) => {
                let _ = std::fs::remove_file(&p);
            }
            Err(_) => {}
        }
    }
}
