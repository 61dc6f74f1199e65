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
    assert_eq!(doc["robot"], "psm");
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
    assert!(!err.contains("warning"), "{err}");
    let ev: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(ev["feasible"], true);
    let again = ev["criterion"]["value"].as_f64().unwrap();
    assert!((again - value).abs() < 1e-9 * value, "{again} vs {value}");
    let svg = std::fs::read_to_string(dir.join("again.svg")).unwrap();
    assert!(svg.contains("excitation trajectory") && svg.contains("q7"));

    // Every robot's coordinates are q1..qn: the recorded robot is what tells another
    // arm's trajectory (issue 32 class 9), in evaluate and in simulate alike.
    let t = traj.to_str().unwrap();
    let warning =
        format!("dvrk-ident: warning: {t} was designed for robot psm, not psm_simplified");
    let (ok, _, err) = run(&["excite", "--robot", "psm_simplified", "--evaluate", t]);
    assert!(ok && err.contains(&warning), "{err}");
    let log = dir.join("sim.csv");
    let (ok, _, err) = run(&[
        "simulate",
        "psm_simplified",
        "--params",
        "nominal",
        "--excitation",
        t,
        "--duration",
        "0.1",
        "--out",
        log.to_str().unwrap(),
    ]);
    assert!(err.contains(&warning), "{err}");
    let (ok2, _, err2) = run(&[
        "simulate",
        "psm",
        "--params",
        &example("psm_params.json"),
        "--excitation",
        t,
        "--duration",
        "0.1",
        "--out",
        log.to_str().unwrap(),
    ]);
    assert!(ok2 && !err2.contains("warning"), "{err2}");
    let _ = ok;
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

/// The planar 2-link arm with a `tip` frame of the excitation tests.
const ARM: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/fixtures/two_link_tip.toml"
));

#[test]
fn limits_file_with_a_cartesian_box() {
    let dir = temp_dir("box");
    let (robot, limits, traj) = (
        dir.join("arm.toml"),
        dir.join("lim.toml"),
        dir.join("t.json"),
    );
    std::fs::write(&robot, ARM).unwrap();
    let joint = "[[limits]]\nexpr = \"q1\"\nposition = [-1.0, 1.2]\nvelocity = [-1.5, 1.5]\n\n\
                 [[limits]]\nexpr = \"q2 - q1\"\nposition = [0.2, 1.6]\n\n";
    let boxed = |ymax: f64| {
        format!("{joint}[[cartesian_limits]]\nframe = \"tip\"\nmin = [-1, -1, -1]\nmax = [1, {ymax}, 1]\n")
    };
    std::fs::write(&limits, boxed(0.2)).unwrap();
    let (ok, _, err) = run(&[
        "excite",
        "--robot",
        robot.to_str().unwrap(),
        "--limits",
        limits.to_str().unwrap(),
        "--order",
        "2",
        "--f0",
        "0.25",
        "--starts",
        "2",
        "--refine",
        "1",
        "--iterations",
        "15",
        "--refine-iterations",
        "15",
        "--out",
        traj.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&traj).unwrap()).unwrap();
    assert_eq!(doc["feasibility"]["feasible"], true);
    let evaluate = |limits: &std::path::Path| {
        let (ok, out, err) = run(&[
            "excite",
            "--robot",
            robot.to_str().unwrap(),
            "--limits",
            limits.to_str().unwrap(),
            "--evaluate",
            traj.to_str().unwrap(),
            "--json",
        ]);
        assert!(ok, "{err}");
        serde_json::from_str::<serde_json::Value>(&out).unwrap()
    };
    assert_eq!(evaluate(&limits)["feasible"], true);
    // A lower box that the optimized tip path leaves: reported by name.
    let lower = dir.join("lower.toml");
    std::fs::write(&lower, boxed(-0.6)).unwrap();
    let ev = evaluate(&lower);
    assert_eq!(ev["feasible"], false);
    assert_eq!(ev["worst_violation"]["limit"], "frame tip y");
    assert_eq!(ev["worst_violation"]["bound"], -0.6);
    // A box on a frame the robot does not have: the file and the frame are named, and
    // nothing is written.
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[[cartesian_limits]]\nframe = \"hand\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n",
    )
    .unwrap();
    let out = dir.join("never.json");
    let (ok, _, err) = run(&[
        "excite",
        "--robot",
        robot.to_str().unwrap(),
        "--limits",
        bad.to_str().unwrap(),
        "--order",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("bad.toml") && err.contains("hand"), "{err}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
