//! What a program that only fits gets without the default feature `recordings` (what
//! `.ci/run` tests with `--no-default-features --features rust-lapack --lib`): a test
//! module beside the crate's root, so that the module graph keeps its one direction.

use crate::excite::FourierTrajectory;
use crate::log::{detect_format, write, write_headered, LogError, LogFormat, ReadOptions};
use crate::progress::Silent;
use crate::simulate::{simulate, Simulation};
use crate::{FitRequest, FitSettings, Method};
use dvrk_model::Model;

/// A CSV log is read and fitted as usual, and the
/// bundled MCAP example is recognized and refused with the error naming the feature.
#[test]
fn without_recordings_csv_fits_and_a_recording_is_refused() {
    let model = Model::builtin("psm").unwrap();
    let examples = dvrk_test_support::repo().join("examples");
    let truth = dvrk_test_support::fixtures::example_params(&model);
    let excitation =
        FourierTrajectory::from_json_file(examples.join("psm_trajectory.json")).unwrap();
    let noise = 0.005; // N·m
    let simulation = Simulation {
        duration_s: Some(60.0),
        noise_std: vec![noise],
        seed: 1,
        ..Simulation::default()
    };
    let log = simulate(&model, &truth, &excitation, &simulation).unwrap();
    let dir = dvrk_test_support::temp_dir("without-recordings");
    let csv = dir.join("psm.csv");
    write_headered(&csv, &log).unwrap();
    let read = ReadOptions::default().for_model(&model).read(&csv).unwrap();
    assert_eq!(read.q, log.q);
    assert_eq!(read.tau, log.tau);

    let mut settings = FitSettings {
        method: Method::Ols,
        ..FitSettings::default()
    };
    // Exact signals: no filter; derivatives of the analytic velocity are accurate.
    settings.processing.filter = None;
    settings.processing.trim = 10;
    let result = FitRequest::of_samples([&read], None, settings)
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    let beta_true = model.base_parameters().unwrap().project(&truth);
    dvrk_test_support::fixtures::assert_recovered(
        "psm OLS",
        result
            .base_parameters
            .iter()
            .map(|b| (b.expression.as_str(), b.value, b.std)),
        &beta_true,
    );

    let mcap = examples.join("psm_excitation.mcap");
    assert_eq!(detect_format(&mcap).unwrap(), LogFormat::Mcap);
    let err = ReadOptions::default().read(&mcap).unwrap_err();
    assert!(matches!(err, LogError::RecordingsNotBuilt { .. }), "{err}");
    let text = err.to_string();
    assert!(
        text.starts_with(&format!("{}: a recording (mcap): ", mcap.display()))
            && text.contains("`recordings` feature"),
        "{text}"
    );
    let out = dir.join("out.mcap");
    let err = write(&out, &log, LogFormat::Mcap).unwrap_err();
    assert!(matches!(err, LogError::RecordingsNotBuilt { .. }), "{err}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
