//! The workspace's layout rules (project issue 26), checked on the tree so that a change
//! that breaks one fails here rather than in a later review: no source file under
//! `crates/*/src` over 800 lines (small files, one job each), and `unsafe` code only in
//! the two crates whose boundary needs it (`lapack-faer`, the Fortran ABI Clarabel calls,
//! and `dvrk-model-c`, the C ABI); every other crate root forbids it.

use std::path::{Path, PathBuf};

/// The longest a source file under `crates/*/src` may be, in lines.
const MAX_LINES: usize = 800;

/// The crates allowed `unsafe` code, and why (also in their crate documentation).
const UNSAFE_CRATES: [&str; 2] = ["lapack-faer", "dvrk-model-c"];

fn crates() -> Vec<PathBuf> {
    let root = dvrk_test_support::repo().join("crates");
    let mut out: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap_or_else(|e| panic!("{}: {e}", root.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    out.sort();
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn no_source_file_is_longer_than_the_limit() {
    let crates = crates();
    assert!(crates.len() >= 7, "the workspace's crates: {crates:?}");
    let mut long = Vec::new();
    let mut files = 0;
    for krate in &crates {
        let mut sources = Vec::new();
        rust_files(&krate.join("src"), &mut sources);
        for file in sources {
            files += 1;
            let lines = std::fs::read_to_string(&file).unwrap().lines().count();
            if lines > MAX_LINES {
                long.push(format!("{} ({lines} lines)", file.display()));
            }
        }
    }
    assert!(files > 100, "{files} source files found");
    assert!(long.is_empty(), "over {MAX_LINES} lines: {long:#?}");
}

#[test]
fn unsafe_code_is_forbidden_outside_the_abi_crates() {
    for krate in crates() {
        let name = krate.file_name().unwrap().to_string_lossy().into_owned();
        for root in ["src/lib.rs", "src/main.rs"] {
            let path = krate.join(root);
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            let forbids = text.lines().any(|l| l.trim() == "#![forbid(unsafe_code)]");
            assert_eq!(
                forbids,
                !UNSAFE_CRATES.contains(&name.as_str()),
                "{}: #![forbid(unsafe_code)] {}",
                path.display(),
                if forbids {
                    "in an ABI crate"
                } else {
                    "missing"
                }
            );
        }
    }
}
