//! What the C ABI tests share: the result document they load.

use std::path::{Path, PathBuf};

use dvrk_ident::{FitRequest, LogSource, Overrides, Training};

/// Fits the bundled example (SDP, the default method, with Stribeck terms of 0.3 rad/s
/// or m/s) and writes the result document into `dir`.
pub fn fit_example(dir: &Path) -> PathBuf {
    let log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/psm_excitation.mcap"
    );
    let psm = dvrk_model::Model::builtin("psm").unwrap();
    let request = FitRequest {
        overrides: Overrides {
            stribeck_velocity: Some(0.3),
            ..Overrides::default()
        },
        ..FitRequest::new(Training::Logs(vec![LogSource::File(log.into())]))
    };
    let outcome = request
        .run(Some(&psm), &dvrk_ident::Silent)
        .expect("the example fits");
    assert_eq!(outcome.result.method, "sdp");
    assert!(outcome.result.solver.converged);
    let path = dir.join("psm_sdp.json");
    std::fs::write(&path, outcome.result.to_json()).unwrap();
    path
}
