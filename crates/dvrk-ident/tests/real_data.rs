//! Reads the real 2019 dVRK logs from the shared data folder (not part of the
//! repository). Skips with a message when they are not there.

use dvrk_ident::log::{read, read_wpi, LogFormat};
use dvrk_ident::signal::{process, Processing};
use dvrk_ident::Coordinates;
use std::path::PathBuf;

fn shared(rel: &str) -> Option<PathBuf> {
    dvrk_test_support::shared(&format!("data/dvrk/{rel}"))
}

#[test]
fn psm_one_results_reads() {
    let Some(path) = shared("psm/one_results.csv") else {
        return;
    };
    let t = read_wpi(&path, 200.0, None).unwrap();
    assert_eq!(t.len(), 5999);
    assert_eq!(t.dof(), 7);
    assert_eq!(t.coordinates, Coordinates::Model);
    // First row: q1 and tau7; last row: dq1 (values from the file).
    assert_eq!(t.q[(0, 0)], -0.43909142302978293);
    assert_eq!(t.tau[(0, 6)], -0.030609507592174453);
    assert_eq!(t.dq.as_ref().unwrap()[(5998, 0)], -1.0869219930273866);
    assert!((t.time[5998] - 29.99).abs() < 1e-12);
    assert!((t.rate_hz().unwrap() - 200.0).abs() < 1e-6);
    t.validate().unwrap();
    // Detected as the 2019 layout.
    assert_eq!(read(&path, None, Some(200.0)).unwrap(), t);
    assert_eq!(
        dvrk_ident::log::detect_format(&path).unwrap(),
        LogFormat::Wpi
    );
}

#[test]
fn psm_one_results_processes_with_the_2019_protocol() {
    let Some(path) = shared("psm/one_results.csv") else {
        return;
    };
    let t = read_wpi(&path, 200.0, None).unwrap();
    let p = process(&t, &Processing::wpi(5.4)).unwrap();
    assert_eq!(p.len(), 5999 - 400);
    assert!(p
        .q
        .iter()
        .chain(p.dq.iter())
        .chain(p.ddq.iter())
        .chain(p.tau.iter())
        .all(|v| v.is_finite()));
    // The 17 Hz filter barely changes the smooth positions.
    let k = 1000;
    assert!((p.q[(k, 0)] - t.q[(k + 200, 0)]).abs() < 1e-3);
}

#[test]
fn mtm_joint_test_reads_as_one_joint() {
    let Some(path) = shared("mtm/joint_test/one_results.csv") else {
        return;
    };
    let t = read_wpi(&path, 200.0, None).unwrap();
    // The file has 4885 data rows (no header); shared/data/dvrk/README.md says 4884.
    assert_eq!(t.len(), 4885);
    assert_eq!(t.dof(), 1);
}
