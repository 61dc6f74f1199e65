//! Helpers shared by the integration tests: locating `../shared` (skipping cleanly when
//! it is absent) and reading its JSON files.
#![allow(dead_code)]

use std::path::PathBuf;

/// Path of a file under the workspace's sibling `shared/` folder, or `None` (with the
/// reason printed) when it is absent, so that the project's own tests pass without it.
pub fn shared_file(rel: &str) -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    let path = root.join(rel);
    if path.exists() {
        Some(path)
    } else {
        eprintln!(
            "SKIPPED: {} not found (the ../shared folder is absent)",
            path.display()
        );
        None
    }
}

pub fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

pub fn f64s(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}
