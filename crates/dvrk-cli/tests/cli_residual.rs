//! `residual` and `simulate --payload/--external-torque` from the command line: a push
//! simulated from a CSV file comes back out of `residual --out` in the same layout, and
//! bad payload or torque files are refused, naming the file, with nothing written; the
//! residual as MCAP (read back: the CSV's numbers) and its report page.

mod support;

use support::{fit_example_args, run, run_json, run_ok, s, simulate_example, temp_dir};

#[test]
fn a_simulated_push_comes_back_out_of_residual() {
    let dir = temp_dir("cli-residual");
    let fit = dir.join("fit.json");
    run_ok(&fit_example_args(&["--out", &s(&fit)]));
    // 0.3 N·m on the first joint from 4 to 6 s, nothing elsewhere.
    let push = dir.join("push.csv");
    std::fs::write(
        &push,
        "4,0,0,0,0,0,0,0\n4,0.3,0,0,0,0,0,0\n6,0.3,0,0,0,0,0,0\n6,0,0,0,0,0,0,0\n",
    )
    .unwrap();
    let log = dir.join("pushed.mcap");
    simulate_example(
        &log,
        &[
            "--periods",
            "2",
            "--noise",
            "0.002",
            "--seed",
            "3",
            "--external-torque",
            &s(&push),
        ],
    );
    let (out, observer) = (dir.join("residual.csv"), dir.join("observer.csv"));
    let doc = run_json(&[
        "residual",
        &s(&fit),
        &s(&log),
        "--out",
        &s(&out),
        "--observer-out",
        &s(&observer),
        "--json",
    ]);
    let r = &doc["residuals"][0];
    let floor: Vec<f64> = r["noise_floor"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let rms: Vec<f64> = r["rms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    // The push shows on the first joint only.
    assert!(rms[0] > 5.0 * floor[0], "{rms:?} {floor:?}");
    for j in 1..7 {
        assert!(
            rms[j] < 1.2 * floor[j],
            "joint {j}: {} against {}",
            rms[j],
            floor[j]
        );
    }
    // The CSV: time then the joints; the residual at 5 s is the push (the processing's
    // low-pass filter rounds its edges only).
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("time,"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let mid: Vec<&Vec<f64>> = rows.iter().filter(|r| (r[0] - 5.0).abs() < 0.5).collect();
    let mean = mid.iter().map(|r| r[1]).sum::<f64>() / mid.len() as f64;
    assert!(
        (mean - 0.3).abs() < 0.01,
        "residual of joint 1 around 5 s: {mean}"
    );
    let obs = std::fs::read_to_string(&observer).unwrap();
    assert_eq!(obs.lines().count(), text.lines().count());

    // MCAP holds measured joints: refused in the model coordinates, nothing written.
    let (mcap, obs_mcap) = (dir.join("residual.mcap"), dir.join("observer.mcap"));
    let report = dir.join("report");
    let (fit_s, log_s, report_s) = (s(&fit), s(&log), s(&report));
    let (ok, _, err) = run(&[
        "residual",
        &s(&fit),
        &s(&log),
        "--out",
        &s(&mcap),
        "--report",
        &s(&report),
    ]);
    assert!(!ok && err.contains("--joints measured"), "{err}");
    assert!(!mcap.exists() && !report.exists());
    // In the measured joints: the MCAP's efforts are the CSV's residual, bit for bit.
    let (csv_m, obs_m) = (dir.join("residual_m.csv"), dir.join("observer_m.csv"));
    for (out, observer_out) in [(&mcap, &obs_mcap), (&csv_m, &obs_m)] {
        let (out, observer_out) = (s(out), s(observer_out));
        run_ok(&[
            "residual",
            &fit_s,
            &log_s,
            "--joints",
            "measured",
            "--out",
            &out,
            "--observer-out",
            &observer_out,
        ]);
    }
    for (m, c) in [(&mcap, &csv_m), (&obs_mcap, &obs_m)] {
        let back = dvrk_ident::log::read(m, None, None).unwrap();
        let text = std::fs::read_to_string(c).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(
            header[1..],
            back.joint_names
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>()[..]
        );
        assert_eq!(back.joint_names[6], "jaw", "measured joints");
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), back.len());
        for (k, row) in rows.iter().enumerate() {
            for j in 0..7 {
                assert_eq!(
                    back.tau[(k, j)].to_bits(),
                    row[j + 1].to_bits(),
                    "{} {k} {j}",
                    m.display()
                );
            }
        }
        assert!(back.dq.is_some());
    }
    // The report (the fit's joints, where the noise floor is): the page with a row per
    // joint, joint 1's ratio flagged, the figure.
    run_ok(&["residual", &fit_s, &log_s, "--report", &report_s]);
    let page = std::fs::read_to_string(report.join("report.html")).unwrap();
    for joint in ["q1", "q7", "noise floor", "<svg"] {
        assert!(page.contains(joint), "{joint} missing from the page");
    }
    assert!(
        page.contains("<td class=bad>"),
        "joint 1's RMS well above its floor"
    );
    let svg = std::fs::read_to_string(report.join("residual_1.svg")).unwrap();
    assert!(svg.contains("momentum observer (20 /s)") && svg.contains("τ_measured − τ_model"));
    assert!(report.join("residual_1.png").exists());
    // The same fit, with a force at the tool tip (one fit per test binary's run).
    a_tip_force_comes_back_out_of_residual_wrench(&dir, &fit);
}

/// `residual --wrench tool_tip` on a log simulated with the joint torques `J(q)ᵀ·F` of a
/// constant force at the PSM's tool tip (computed here from the model along the
/// trajectory, on the simulation's own time grid): the force comes back, to the
/// processing's rounding against the same log without it (the same noise), and within
/// the wrench's noise floor (its RMS on that log) of the force; a wrong frame is
/// refused naming it and listing the robot's, with nothing written.
fn a_tip_force_comes_back_out_of_residual_wrench(dir: &std::path::Path, fit: &std::path::Path) {
    use dvrk_ident::excite::FourierTrajectory;
    use dvrk_model::{Model, Workspace};
    let model = Model::builtin("psm").unwrap();
    let tip = model
        .frame_names()
        .iter()
        .position(|f| f == "tool_tip")
        .unwrap();
    let traj = FourierTrajectory::from_json_file(support::example("psm_trajectory.json")).unwrap();
    let force = [0.5, -0.3, 0.8, 0.0, 0.0, 0.0]; // N, base frame; no moment
    let time: Vec<f64> = (0..=2400).map(|k| k as f64 / 200.0).collect();
    let (q, _, _) = traj.sample(&time);
    let mut ws = Workspace::new(&model);
    let mut csv = String::new();
    for (k, t) in time.iter().enumerate() {
        let qk: Vec<f64> = q.row(k).iter().copied().collect();
        model.forward_kinematics(&mut ws, &qk);
        let tau =
            model.frame_jacobian(&ws, tip).transpose() * nalgebra::DVector::from_row_slice(&force);
        csv.push_str(&t.to_string());
        for v in tau.iter() {
            csv.push_str(&format!(",{v}"));
        }
        csv.push('\n');
    }
    let file = dir.join("tip_force.csv");
    std::fs::write(&file, csv).unwrap();
    let (with, without) = (dir.join("tip_force.mcap"), dir.join("no_force.mcap"));
    let noise = ["--periods", "2", "--noise", "0.002", "--seed", "5"];
    let mut pushed = noise.to_vec();
    let file_s = s(&file);
    pushed.extend(["--external-torque", &file_s]);
    simulate_example(&with, &pushed);
    simulate_example(&without, &noise);
    let wrench = |log: &std::path::Path, out: &std::path::Path| {
        let doc = run_json(&[
            "residual",
            &s(fit),
            &s(log),
            "--wrench",
            "tool_tip",
            "--wrench-out",
            &s(out),
            "--json",
        ]);
        let text = std::fs::read_to_string(out).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap();
        assert!(
            header.starts_with("time,fx_base,fy_base,fz_base,mx_base,my_base,mz_base,fx_tip,")
                && header.ends_with(",mz_tip,rank"),
            "{header}"
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        (doc, rows)
    };
    let (doc, rows) = wrench(&with, &dir.join("tip_wrench.csv"));
    let (_, floor_rows) = wrench(&without, &dir.join("no_wrench.csv"));
    let w = &doc["residuals"][0]["wrench"];
    assert_eq!(w["frame"], "tool_tip");
    assert_eq!(w["min_rank"], 6, "{w}");
    assert_eq!(rows.len(), floor_rows.len());
    for c in 0..6 {
        let (mut diff, mut err, mut floor) = (0.0f64, 0.0, 0.0);
        for (r, f) in rows.iter().zip(&floor_rows) {
            assert_eq!(r[0], f[0]);
            assert_eq!(r[13], 6.0);
            diff = diff.max((r[c + 1] - f[c + 1] - force[c]).abs());
            err += (r[c + 1] - force[c]).powi(2);
            floor += f[c + 1].powi(2);
        }
        let n = rows.len() as f64;
        let (err, floor) = ((err / n).sqrt(), (floor / n).sqrt());
        eprintln!(
            "wrench {c}: largest difference {diff:.2e}, RMS error {err:.4}, floor {floor:.4}"
        );
        assert!(diff < 1e-4, "component {c}: {diff}");
        assert!(
            err < 1.2 * floor + 1e-3,
            "component {c}: {err} against {floor}"
        );
    }
    // The report: the wrench's table and figure beside the residual's.
    let report = dir.join("wrench_report");
    run_ok(&[
        "residual",
        &s(fit),
        &s(&with),
        "--wrench",
        "tool_tip",
        "--report",
        &s(&report),
    ]);
    let page = std::fs::read_to_string(report.join("report.html")).unwrap();
    assert!(page.contains("wrench at <code>tool_tip</code>") && page.contains("RMS, base axes"));
    let svg = std::fs::read_to_string(report.join("wrench_1.svg")).unwrap();
    assert!(svg.contains("force at tool_tip in its own axes"));
    // A wrong frame: named, the frames listed, nothing written.
    let never = dir.join("never.csv");
    let (ok, _, err) = run(&[
        "residual",
        &s(fit),
        &s(&with),
        "--wrench",
        "nowhere",
        "--wrench-out",
        &s(&never),
    ]);
    assert!(
        !ok && err.contains("robot psm has no frame `nowhere`") && err.contains("tool_tip"),
        "{err}"
    );
    assert!(!never.exists());
}

#[test]
fn bad_payload_and_torque_files_are_refused() {
    let dir = temp_dir("cli-residual-bad");
    let payload = dir.join("payload.toml");
    std::fs::write(
        &payload,
        "frame = \"tool_roll\"\nmass = 0.2\ncom = [0, 0, 0]\n",
    )
    .unwrap();
    let log = dir.join("never.mcap");
    let args = support::simulate_args(
        "psm",
        &support::example("psm_trajectory.json"),
        &log,
        &["--payload", &s(&payload)],
    );
    let (ok, _, err) = run(&args);
    assert!(
        !ok && err.contains("payload.toml") && err.contains("carries no link parameters"),
        "{err}"
    );
    let torque = dir.join("torque.csv");
    std::fs::write(&torque, "0,1,2\n").unwrap();
    let args = support::simulate_args(
        "psm",
        &support::example("psm_trajectory.json"),
        &log,
        &["--external-torque", &s(&torque)],
    );
    let (ok, _, err) = run(&args);
    assert!(
        !ok && err.contains("torque.csv: line 1: 3 fields; expected 8"),
        "{err}"
    );
    assert!(!log.exists());
}

/// `payload` on a simulated log carrying the payload: the mass within 2 % and
/// the centre of mass within 3 mm, and `--out` a result whose `validate` on that log is
/// at the noise; bad input (an unknown frame, an empty log, another robot's result) is
/// refused with nothing written.
#[test]
fn payload_comes_back_out_of_a_loaded_log() {
    let dir = temp_dir("cli-payload");
    let fit = dir.join("fit.json");
    run_ok(&fit_example_args(&["--out", &s(&fit)]));
    let payload = dir.join("payload.toml");
    std::fs::write(
        &payload,
        "frame = \"main_insertion\"\nmass = 0.2\ncom = [0.0, 0.02, 0.165]\n\
         inertia = [1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0]\n",
    )
    .unwrap();
    let log = dir.join("loaded.mcap");
    simulate_example(
        &log,
        &["--noise", "0.002", "--seed", "4", "--payload", &s(&payload)],
    );
    let out = dir.join("loaded.json");
    let doc = run_json(&[
        "payload",
        &s(&fit),
        &s(&log),
        "--frame",
        "main_insertion",
        "--json",
        "--out",
        &s(&out),
    ]);
    let p = &doc["payload"];
    let mass = p["mass"].as_f64().unwrap();
    assert!((mass - 0.2).abs() < 0.004, "{p}");
    for (k, c) in [0.0, 0.02, 0.165].iter().enumerate() {
        assert!((p["com"][k].as_f64().unwrap() - c).abs() < 3e-3, "{p}");
    }
    assert_eq!(doc["identification"]["determined"]["mass"], true);
    let v = run_json(&["validate", &s(&out), &s(&log), "--json"]);
    let without = run_json(&["validate", &s(&fit), &s(&log), "--json"]);
    let rms = |v: &serde_json::Value| -> Vec<f64> {
        v["validations"][0]["metrics"]["rms"]
            .as_array()
            .unwrap_or_else(|| panic!("{v}"))
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    // The payload's torque without it, the noise (0.002) with it.
    assert!(rms(&without)[..3].iter().all(|r| *r > 0.1), "{without}");
    assert!(rms(&v)[..3].iter().all(|r| *r < 0.0025), "{v}");

    // Bad input: nothing written.
    let never = dir.join("never.json");
    let bad = |extra: &[&str]| {
        let mut args = vec!["payload".to_string()];
        args.extend(extra.iter().map(|a| a.to_string()));
        args.extend(["--out".to_string(), s(&never)]);
        let (ok, _, err) = run(&args);
        assert!(!ok && !never.exists(), "{err}");
        err
    };
    let err = bad(&[&s(&fit), &s(&log), "--frame", "nowhere"]);
    assert!(
        err.contains("robot psm has no frame `nowhere`") && err.contains("main_insertion"),
        "{err}"
    );
    let empty = dir.join("empty.csv");
    std::fs::write(&empty, "").unwrap();
    let err = bad(&[&s(&fit), &s(&empty), "--frame", "main_insertion"]);
    assert!(err.contains("empty.csv: empty log"), "{err}");
    let mtm = dir.join("mtm.json");
    let mut other: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    other["robot"] = "mtm".into();
    std::fs::write(&mtm, other.to_string()).unwrap();
    let err = bad(&[&s(&mtm), &s(&log), "--frame", "main_insertion"]);
    assert!(
        err.contains("mtm.json was fitted for mtm, not psm"),
        "{err}"
    );
}
