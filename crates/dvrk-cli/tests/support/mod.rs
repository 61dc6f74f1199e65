//! What every CLI test needs: run the binary, a scratch folder, the bundled examples.
// Each test binary compiles this module and uses only part of it.
#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

/// Runs `dvrk-ident ARGS` with stdout and stderr piped: (success, stdout, stderr).
pub fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_dvrk-ident"))
        .args(args)
        .output()
        .expect("run dvrk-ident");
    (
        out.status.success(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

// Not every test binary makes scratch folders.
#[allow(unused_imports)]
pub use dvrk_test_support::temp_dir;

/// Path of a file in the repository's `examples/`, as a command-line argument.
pub fn example(name: &str) -> String {
    dvrk_test_support::example(name).display().to_string()
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> String {
    p.display().to_string()
}

/// The file names in `dir`, sorted.
pub fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}
