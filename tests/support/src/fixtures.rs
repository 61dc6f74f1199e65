//! Fixtures that tests of several crates build alike: a scratch folder that goes away
//! with the test, the generating parameters of the bundled example log, and the check
//! that a fit recovers known parameters within what the noise allows.

use std::path::{Path, PathBuf};

use dvrk_model::Model;

/// A [`crate::temp_dir`] removed when dropped, for tests that write many or large files.
pub struct TempDir(PathBuf);

impl TempDir {
    /// A fresh, empty folder named by `tag` and the process id.
    pub fn new(tag: &str) -> TempDir {
        TempDir(crate::temp_dir(tag))
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.0
    }

    /// `file` in the folder.
    pub fn path(&self, file: impl AsRef<Path>) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The parameters that generated the bundled PSM log (`examples/psm_params.json`), in
/// `model`'s order; every parameter of `model` must be named there.
pub fn example_params(model: &Model) -> Vec<f64> {
    let doc = crate::read_json(&crate::example("psm_params.json"));
    let map = doc["parameters"]
        .as_object()
        .expect("an object of parameters");
    model
        .params_from_named(
            map.iter()
                .map(|(k, v)| (k.as_str(), v.as_f64().expect("a number"))),
            "psm_params.json",
        )
        .unwrap()
}

/// Asserts that every estimate `(name, value, standard deviation)` is within six
/// standard deviations (plus 1e-6, for estimates pinned at a bound) of `truth`: what the
/// noise alone allows. Returns the largest |error| / std, for the record.
#[track_caller]
pub fn assert_recovered<'a>(
    what: &str,
    estimates: impl IntoIterator<Item = (&'a str, f64, f64)>,
    truth: &[f64],
) -> f64 {
    let mut worst: f64 = 0.0;
    let mut count = 0;
    for ((name, value, std), t) in estimates.into_iter().zip(truth) {
        worst = worst.max((value - t).abs() / (std + 1e-12));
        assert!(
            (value - t).abs() <= 6.0 * std + 1e-6,
            "{what} {name}: {value} vs {t} (std {std})"
        );
        count += 1;
    }
    assert_eq!(count, truth.len(), "{what}: one estimate per true value");
    worst
}
