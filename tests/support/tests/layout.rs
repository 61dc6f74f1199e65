//! The workspace's layout rules (project issue 26), checked on the tree so that a change
//! that breaks one fails here rather than in a later review: no source file under
//! `crates/*/src` over 800 lines (small files, one job each), and `unsafe` code only in
//! the two crates whose boundary needs it (`lapack-faer`, the Fortran ABI Clarabel calls,
//! and `dvrk-model-c`, the C ABI); every other crate root forbids it; no crate's module
//! graph has a cycle, and no module of dvrk-ident names an item its parent defines (a
//! parent declares its children and re-exports theirs: `tools/module_cycles.py
//! --parents`).

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

/// `tools/module_cycles.py` with `args`: its exit status and what it printed.
fn module_cycles(args: &[&str]) -> (i32, String) {
    let script = dvrk_test_support::repo().join("tools/module_cycles.py");
    let out = std::process::Command::new("python3")
        .arg(&script)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("python3 {}: {e}", script.display()));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    (out.status.code().unwrap_or(-1), text)
}

/// A crate of `files` (path under `src/`, text) in a scratch folder.
fn scratch_crate(tag: &str, files: &[(&str, &str)]) -> PathBuf {
    let root = dvrk_test_support::temp_dir(tag);
    for (path, text) in files {
        let file = root.join("src").join(path);
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(file, text).unwrap();
    }
    root
}

#[test]
fn no_module_cycle_and_no_module_of_dvrk_ident_calls_back_into_its_parent() {
    let repo = dvrk_test_support::repo();
    let (status, text) = module_cycles(&[]);
    assert_eq!(status, 0, "{text}");
    assert!(text.matches(", 0 cycles").count() >= 7, "{text}");
    let ident = repo.join("crates/dvrk-ident");
    let (status, text) = module_cycles(&["--parents", ident.to_str().unwrap()]);
    assert_eq!(status, 0, "{text}");
    assert!(
        text.contains("dvrk-ident: 0 call-backs into a parent"),
        "{text}"
    );
}

#[test]
fn the_module_check_finds_a_cycle_and_a_call_back() {
    let cycle = scratch_crate(
        "layout-cycle",
        &[
            ("lib.rs", "mod a;\nmod b;\n"),
            ("a.rs", "use crate::b::Y;\npub struct X(Y);\n"),
            ("b.rs", "use crate::a::X;\npub struct Y(Box<X>);\n"),
        ],
    );
    let (status, text) = module_cycles(&[cycle.to_str().unwrap()]);
    assert_eq!(status, 1, "{text}");
    assert!(text.contains("cycle: a <-> b"), "{text}");
    // A child naming its parent's own item is a call-back; one re-exported from a
    // sibling, or a test module's, is not.
    let back = scratch_crate(
        "layout-call-back",
        &[
            ("lib.rs", "mod a;\n"),
            (
                "a.rs",
                "mod b;\nmod c;\n#[cfg(test)]\nmod tests;\npub use c::Z;\npub struct X;\n",
            ),
            ("a/b.rs", "use super::{X, Z};\n"),
            ("a/c.rs", "pub struct Z;\n"),
            ("a/tests.rs", "use super::*;\n"),
        ],
    );
    let (status, text) = module_cycles(&["--parents", back.to_str().unwrap()]);
    assert_eq!(status, 1, "{text}");
    assert!(text.contains("1 call-back into a parent"), "{text}");
    assert!(text.contains("a::b -> a::X"), "{text}");
    for dir in [cycle, back] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}
