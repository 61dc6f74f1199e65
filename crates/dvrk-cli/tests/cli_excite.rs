//! `excite` end to end: an optimized trajectory's documented keys, its setpoints in
//! measured space, its preview plot, and `--evaluate` agreeing with the optimizer.

mod support;
use std::path::PathBuf;
use support::{example, run, temp_dir};

#[test]
fn optimize_writes_trajectory_setpoints_and_plot_then_evaluate_agrees() {
    let dir = temp_dir("opt");
    let (traj, csv, plot) = (dir.join("t.json"), dir.join("s.csv"), dir.join("p.png"));
    let (ok, _, err) = run(&[
        "excite",
        "--robot",
        "psm",
        "--order",
        "2",
        "--f0",
        "0.2",
        "--starts",
        "1",
        "--iterations",
        "15",
        "--seed",
        "3",
        "--out",
        traj.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--rate",
        "50",
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&traj).unwrap()).unwrap();
    assert_eq!(doc["order"], 2);
    assert_eq!(doc["base_frequency_hz"], 0.2);
    assert_eq!(doc["q0"].as_array().unwrap().len(), 7);
    for key in ["a", "b"] {
        let rows = doc[key].as_array().unwrap();
        assert_eq!(rows.len(), 7);
        assert!(rows.iter().all(|r| r.as_array().unwrap().len() == 2));
    }
    assert_eq!(doc["coordinates"][2], "q3");
    assert_eq!(doc["criterion"]["name"], "condition");
    let value = doc["criterion"]["value"].as_f64().unwrap();
    assert!(value > 1.0 && value.is_finite());

    // Setpoints: measured joint names, 50 Hz over one 5 s period.
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    assert!(header.starts_with("time,"), "{header}");
    assert_eq!(
        header,
        "time,outer_yaw,outer_pitch,outer_insertion,outer_roll,outer_wrist_pitch,outer_wrist_yaw,jaw"
    );
    assert!(text.lines().count() >= 250);

    let png = std::fs::read(&plot).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");

    let (ok, out, err) = run(&[
        "excite",
        "--robot",
        "psm",
        "--evaluate",
        traj.to_str().unwrap(),
        "--json",
        "--plot",
        dir.join("again.svg").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let ev: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(ev["feasible"], true);
    let again = ev["criterion"]["value"].as_f64().unwrap();
    assert!((again - value).abs() < 1e-9 * value, "{again} vs {value}");
    let svg = std::fs::read_to_string(dir.join("again.svg")).unwrap();
    assert!(svg.contains("excitation trajectory") && svg.contains("q7"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_plot_path_is_an_error_naming_it() {
    let dir = temp_dir("bad");
    let example = PathBuf::from(example("psm_trajectory.json"));
    let (ok, _, err) = run(&[
        "excite",
        "--robot",
        "psm",
        "--evaluate",
        example.to_str().unwrap(),
        "--plot",
        dir.join("p.jpg").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("p.jpg"), "{err}");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}
