//! External torques from a log (`dvrk_ident::residual`): on a simulated PSM log with a
//! payload the model was not fitted with, the residual is the payload's torque (its
//! inverse dynamics on the same processed samples), and the momentum observer's estimate
//! is that torque through the observer's first-order lag; without any external force the
//! residual stays within the fit's noise floor.

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::residual::{
    external_torque, tip_wrench, wrench_frame, ResidualOptions, DEFAULT_WRENCH_RCOND,
};
use dvrk_ident::simulate::{simulate, Simulation};
use dvrk_ident::validate::{predict, prepare};
use dvrk_ident::FitRequest;
use dvrk_ident::Silent;
use dvrk_ident::{FitResult, FitSettings, JointLog, Joints};
use dvrk_model::{Model, Payload, Workspace};
use dvrk_test_support::{example, fixtures::example_params};
use nalgebra::{DMatrix, DVector, Vector3};

fn psm_fit() -> (Model, FitResult, FourierTrajectory, Vec<f64>) {
    let model = Model::builtin("psm").unwrap();
    let truth = example_params(&model);
    let traj = FourierTrajectory::from_json_file(example("psm_trajectory.json")).unwrap();
    let log = dvrk_ident::log::read(example("psm_excitation.mcap"), None, None).unwrap();
    let result = FitRequest::of_samples([&log], None, FitSettings::default())
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    (model, result, traj, truth)
}

/// A simulated log of `periods` periods of `traj` with 0.002 torque noise, optionally
/// carrying `payload`.
fn noisy_log(
    model: &Model,
    truth: &[f64],
    traj: &FourierTrajectory,
    periods: f64,
    seed: u64,
    payload: Option<Payload>,
) -> JointLog {
    let sim = Simulation {
        duration_s: Some(periods * traj.period_s()),
        noise_std: vec![0.002],
        seed,
        payload,
        ..Simulation::default()
    };
    simulate(model, truth, traj, &sim).unwrap()
}

/// The payload: 0.2 kg, com [0, 0.02, 0.165] m on the insertion stage.
fn insertion_payload() -> Payload {
    Payload {
        frame: "main_insertion".into(),
        mass: 0.2,
        com: [0.0, 0.02, 0.165],
        inertia: [1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0],
    }
}

fn rms(x: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0);
    for v in x {
        s += v * v;
        n += 1;
    }
    (s / n as f64).sqrt()
}

#[test]
fn residual_of_a_payload_log_is_the_payloads_torque() {
    let (model, result, traj, truth) = psm_fit();
    let params = result.params_for(&model).unwrap();
    let payload = insertion_payload();
    let log = noisy_log(&model, &truth, &traj, 2.0, 2, Some(payload.clone()));
    let options = ResidualOptions {
        joints: Some(Joints::Model),
        ..ResidualOptions::default()
    };
    let r = external_torque(&model, &params, &result, &log, &options).unwrap();
    // The payload's torque on the same processed samples.
    let data = prepare(&model, &log, &result.settings.processing).unwrap();
    let carried = predict(&model, &payload.params(&model, "test").unwrap(), &data);
    assert_eq!(r.external.shape(), carried.shape());
    let floor = r.noise_floor.clone().expect("the fit's joints");
    // The observer's lag applied to the payload's torque: what its estimate should be.
    let gain = options.observer_gain;
    let mut lagged = carried.clone();
    for k in 1..carried.nrows() {
        let a = (-gain * (r.time[k] - r.time[k - 1])).exp();
        for j in 0..7 {
            lagged[(k, j)] = a * lagged[(k - 1, j)] + (1.0 - a) * carried[(k, j)];
        }
    }
    let skip = (1.0 / gain * 10.0 / (r.time[1] - r.time[0])) as usize; // the observer's start
    for j in 0..7 {
        let size = rms(carried.column(j).iter().copied());
        let err = rms((0..carried.nrows()).map(|k| r.external[(k, j)] - carried[(k, j)]));
        let obs = rms((skip..carried.nrows()).map(|k| r.observer[(k, j)] - lagged[(k, j)]));
        let share = if size > 0.0 {
            format!("{:.2} %", 100.0 * err / size)
        } else {
            "no payload torque".into()
        };
        eprintln!(
            "{}: payload rms {size:.4}, residual error rms {err:.5} ({share}), observer error \
             rms {obs:.5}, noise floor {:.5}",
            r.joints[j], floor[j]
        );
        if size > 20.0 * floor[j] {
            assert!(err < 0.05 * size, "{}: {err} against {size}", r.joints[j]);
            assert!(
                obs < 0.05 * size,
                "{}: observer {obs} against {size}",
                r.joints[j]
            );
        } else {
            // Not carried by this joint (the wrist): the residual is noise.
            assert!(size < 1e-12, "{}: {size}", r.joints[j]);
            assert!(
                r.rms[j] < 1.5 * floor[j],
                "{}: {} against {}",
                r.joints[j],
                r.rms[j],
                floor[j]
            );
        }
    }
}

#[test]
fn residual_without_external_force_stays_within_the_noise_floor() {
    let (model, result, traj, truth) = psm_fit();
    let params = result.params_for(&model).unwrap();
    // On its own training log, the residual's RMS is the fit's training error.
    let log = dvrk_ident::log::read(example("psm_excitation.mcap"), None, None).unwrap();
    let own = external_torque(&model, &params, &result, &log, &ResidualOptions::default()).unwrap();
    let floor = own.noise_floor.clone().unwrap();
    for (j, f) in floor.iter().enumerate() {
        assert!(
            (own.rms[j] - f).abs() <= 1e-9 * f,
            "{j}: {} {f}",
            own.rms[j]
        );
    }
    // On another log of the same arm (new noise), within the floor.
    let other = noisy_log(&model, &truth, &traj, 2.0, 9, None);
    let r = external_torque(
        &model,
        &params,
        &result,
        &other,
        &ResidualOptions::default(),
    )
    .unwrap();
    for (j, f) in floor.iter().enumerate() {
        let (name, rms) = (&r.joints[j], r.rms[j]);
        eprintln!("{name}: residual rms {rms:.5}, noise floor {f:.5}");
        assert!(rms <= 1.1 * f, "{name}: {rms} against {f}");
    }
    // Measured joints: the same torques through the coupling, no floor in other joints.
    let measured = ResidualOptions {
        joints: Some(Joints::Measured),
        ..ResidualOptions::default()
    };
    let m = external_torque(&model, &params, &result, &other, &measured).unwrap();
    assert_eq!(m.joints, model.measured.joints);
    assert!(m.noise_floor.is_none());
    let bad = ResidualOptions {
        observer_gain: -1.0,
        ..ResidualOptions::default()
    };
    let e = external_torque(&model, &params, &result, &other, &bad).unwrap_err();
    assert!(e.to_string().contains("observer_gain"), "{e}");
}

/// `payload`: on a simulated PSM log carrying the payload (0.2 kg, com
/// [0, 0.02, 0.165] m on the insertion stage, noise 0.002), under the model fitted on the
/// payload-free bundled example, the mass comes back within 2 % and the centre of mass
/// within 3 mm, each within a few of its standard deviations; the result with the
/// payload explains the log to the noise, and its document round-trips.
#[test]
fn payload_of_a_simulated_log_is_found() {
    use dvrk_ident::payload::identify_payload;
    let (model, result, traj, truth) = psm_fit();
    let params = result.params_for(&model).unwrap();
    let payload = insertion_payload();
    let log = noisy_log(&model, &truth, &traj, 1.0, 5, Some(payload.clone()));
    let est = identify_payload(
        &model,
        &params,
        &result,
        std::slice::from_ref(&log),
        "main_insertion",
    )
    .unwrap();
    let (p, id) = (&est.payload, &est.identification);
    eprintln!("{p:?}\n{:?}", id.std);
    assert!(
        id.determined.mass && id.determined.com(),
        "{:?}",
        id.determined
    );
    assert!((p.mass - 0.2).abs() < 0.02 * 0.2, "mass {}", p.mass);
    let std = id.std.com.unwrap();
    for (k, sd) in std.iter().enumerate() {
        let err = (p.com[k] - payload.com[k]).abs();
        assert!(
            err < 3e-3,
            "com[{k}] {} against {}",
            p.com[k],
            payload.com[k]
        );
        assert!(
            err < 5.0 * sd + 1e-4,
            "com[{k}] error {err} against std {sd}"
        );
    }
    let ms = id.std.mass.unwrap();
    assert!((p.mass - 0.2).abs() < 5.0 * ms + 1e-4 && ms > 0.0, "{ms}");
    // With the payload, what remains is the noise on the joints that carry it.
    for j in 0..3 {
        assert!(id.rms_without[j] > 0.1, "{:?}", id.rms_without);
        assert!(id.rms_with[j] < 0.0025, "{:?}", id.rms_with);
    }
    // The document: the arm's parameters unchanged, the payload added by params_for.
    let loaded = est.applied_to(&result);
    let text = loaded.to_json();
    let back = FitResult::from_json(&text, "loaded.json").unwrap();
    assert_eq!(back.parameters, result.parameters);
    let with = back.params_for(&model).unwrap();
    let mut expected = params.clone();
    p.add_to(&model, &mut expected, "test").unwrap();
    assert_eq!(with, expected);
    // A payload on top of a payload is refused.
    let err = identify_payload(&model, &with, &back, &[log], "main_insertion").unwrap_err();
    assert!(
        err.to_string().contains("already carries a payload"),
        "{err}"
    );
}

/// What the logs cannot determine is told, not invented: a payload on the PSM's first
/// link (it only rotates about the fixed yaw axis) shows no mass; an arm held still
/// excites no inertia (an error naming the parameters); another robot's result and an
/// unknown frame are refused.
#[test]
fn payload_that_the_logs_cannot_show_is_reported() {
    use dvrk_ident::payload::identify_payload;
    let (model, result, traj, truth) = psm_fit();
    let params = result.params_for(&model).unwrap();
    let payload = Payload {
        frame: "yaw".into(),
        mass: 0.5,
        com: [0.05, 0.02, 0.1],
        inertia: [1e-3, 1e-3, 1e-3, 0.0, 0.0, 0.0],
    };
    let log = noisy_log(&model, &truth, &traj, 1.0, 6, Some(payload));
    let est =
        identify_payload(&model, &params, &result, std::slice::from_ref(&log), "yaw").unwrap();
    let id = &est.identification;
    eprintln!(
        "{:?}\n{:?}\n{:?}",
        id.determined, id.parameter_status, est.payload
    );
    // About the fixed axis z: the first moment across it and the inertia about it.
    let identified: Vec<&str> = id
        .parameter_status
        .iter()
        .filter(|(_, s)| s.identified())
        .map(|(k, _)| k.as_str())
        .collect();
    assert_eq!(identified, ["L1zz", "l1x", "l1y"]);
    assert!(!id.determined.mass && id.std.mass.is_none() && id.std.com.is_none());
    assert!(id.rms_with[0] < 0.0025, "{:?}", id.rms_with);
    // An arm held still at the log's first pose: no velocity, no acceleration.
    let mut still = log.clone();
    for k in 0..still.len() {
        let first = log.q.row(0).into_owned();
        still.q.set_row(k, &first);
    }
    still.dq = Some(nalgebra::DMatrix::zeros(log.len(), 7));
    let err = identify_payload(&model, &params, &result, &[still], "main_insertion")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("do not excite the payload's") && err.contains("L9xx"),
        "{err}"
    );
    let err = identify_payload(
        &model,
        &params,
        &result,
        std::slice::from_ref(&log),
        "tool_roll",
    )
    .unwrap_err();
    assert!(
        err.to_string().contains("carries no link parameters"),
        "{err}"
    );
    let mtm = Model::builtin("mtm").unwrap();
    let err = identify_payload(&mtm, &vec![0.0; mtm.n_params()], &result, &[log], "yaw")
        .unwrap_err()
        .to_string();
    assert!(err.contains("was fitted for psm, not mtm"), "{err}");
}

/// The joint torques `Jᵀ·F` of a wrench `F` at frame `frame` for the rows of `q`.
fn torques_of_wrench(model: &Model, frame: usize, q: &DMatrix<f64>, f: &[f64; 6]) -> DMatrix<f64> {
    let mut ws = Workspace::new(model);
    let mut tau = DMatrix::zeros(q.nrows(), q.ncols());
    for k in 0..q.nrows() {
        let qk: Vec<f64> = q.row(k).iter().copied().collect();
        model.forward_kinematics(&mut ws, &qk);
        let t = model.frame_jacobian(&ws, frame).transpose() * DVector::from_row_slice(f);
        tau.row_mut(k).copy_from_slice(t.as_slice());
    }
    tau
}

/// `tip_wrench` inverts `τ = J(q)ᵀ·F` at the PSM's tool tip: a known wrench comes back
/// to 1e-9 in the base frame's axes at every configuration, and in the tip's axes as
/// `R_tipᵀ` times it; the frame's name is checked against the robot's.
#[test]
fn tip_wrench_inverts_the_jacobian_transpose() {
    let model = Model::builtin("psm").unwrap();
    let tip = wrench_frame(&model, "tool_tip").unwrap();
    // Configurations over the arm's range (model coordinates, insertion 5 to 23 cm).
    let mut q = DMatrix::zeros(6, 7);
    for k in 0..6 {
        let s = k as f64 / 5.0;
        let row = [
            -1.2 + 2.4 * s,
            0.7 - 1.3 * s,
            0.05 + 0.18 * s,
            2.0 - 3.5 * s,
            -0.9 + 1.6 * s,
            0.4 - 0.9 * s,
            0.6 - 0.5 * s,
        ];
        q.row_mut(k).copy_from_slice(&row);
    }
    let f = [1.5, -0.7, 2.2, 0.03, -0.05, 0.011];
    let tau = torques_of_wrench(&model, tip, &q, &f);
    let w = tip_wrench(&model, "tool_tip", &q, &tau, DEFAULT_WRENCH_RCOND).unwrap();
    assert_eq!(w.rank, vec![6; 6]);
    assert!(w.unsensed_in_base.iter().all(Vec::is_empty));
    let mut ws = Workspace::new(&model);
    for k in 0..6 {
        for (c, fc) in f.iter().enumerate() {
            assert!(
                (w.in_base[(k, c)] - fc).abs() < 1e-9,
                "{k} {c}: {}",
                w.in_base
            );
        }
        let qk: Vec<f64> = q.row(k).iter().copied().collect();
        model.forward_kinematics(&mut ws, &qk);
        let r = ws.pose(tip).rotation;
        let force = r.transpose() * Vector3::new(f[0], f[1], f[2]);
        let moment = r.transpose() * Vector3::new(f[3], f[4], f[5]);
        for c in 0..3 {
            assert!((w.in_tip[(k, c)] - force[c]).abs() < 1e-9);
            assert!((w.in_tip[(k, c + 3)] - moment[c]).abs() < 1e-9);
        }
    }
    // Bad frames and thresholds: errors that name them (and list the frames).
    let e = tip_wrench(&model, "nowhere", &q, &tau, 1e-6)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("robot psm has no frame `nowhere`") && e.contains("tool_tip"),
        "{e}"
    );
    let e = tip_wrench(&model, "base", &q, &tau, 1e-6)
        .unwrap_err()
        .to_string();
    assert!(e.contains("the base frame does not move"), "{e}");
    let e = tip_wrench(&model, "tool_tip", &q, &tau, f64::NAN)
        .unwrap_err()
        .to_string();
    assert!(e.contains("wrench_rcond"), "{e}");
    let e = tip_wrench(
        &model,
        "tool_tip",
        &q,
        &tau.columns(0, 6).into_owned(),
        1e-6,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("q is 6×7 and the external torque 6×6"), "{e}");
}

/// Where the joints sense fewer than six wrench directions the unsensed ones are
/// reported and the wrench is the minimum-norm one: the ECM (four coordinates: two
/// directions at its roll frame) against the closed form `J·(JᵀJ)⁻¹·τ`, the PSM Si
/// without its instrument (three coordinates: three directions), and the PSM
/// with its tool tip at the remote centre of motion (insertion l_RCC − l_tool = 1.56
/// cm), where the yaw and pitch do not move the tip and one force across the shaft is
/// lost.
#[test]
fn unsensed_directions_are_reported_not_estimated() {
    let f = [1.5, -0.7, 2.2, 0.03, -0.05, 0.011];
    // ECM.
    let ecm = Model::builtin("ecm").unwrap();
    let roll = wrench_frame(&ecm, "roll").unwrap();
    let q = DMatrix::from_row_slice(2, 4, &[0.3, -0.2, 0.1, 0.5, -0.6, 0.4, 0.2, -1.0]);
    let tau = torques_of_wrench(&ecm, roll, &q, &f);
    let w = tip_wrench(&ecm, "roll", &q, &tau, DEFAULT_WRENCH_RCOND).unwrap();
    let mut ws = Workspace::new(&ecm);
    for k in 0..2 {
        assert_eq!(w.rank[k], 4);
        assert_eq!(w.unsensed_in_base[k].len(), 2);
        let qk: Vec<f64> = q.row(k).iter().copied().collect();
        ecm.forward_kinematics(&mut ws, &qk);
        let j = ecm.frame_jacobian(&ws, roll);
        let t = DVector::from_iterator(4, tau.row(k).iter().copied());
        let closed = &j * (j.transpose() * &j).try_inverse().unwrap() * t;
        for c in 0..6 {
            assert!(
                (w.in_base[(k, c)] - closed[c]).abs() < 1e-9,
                "{k}: {}",
                w.in_base
            );
        }
        for v in &w.unsensed_in_base[k] {
            let v = DVector::from_row_slice(v);
            assert!((v.norm() - 1.0).abs() < 1e-12);
            assert!((j.transpose() * &v).norm() < 1e-12, "sensed: {v}");
        }
    }
    // The PSM Si without its instrument: three coordinates, three directions at the end
    // of its insertion stage.
    let si = Model::builtin("psm_si").unwrap();
    let end = wrench_frame(&si, "insertion").unwrap();
    let q = DMatrix::from_row_slice(1, 3, &[0.3, -0.4, 0.12]);
    let tau = torques_of_wrench(&si, end, &q, &f);
    let w = tip_wrench(&si, "insertion", &q, &tau, DEFAULT_WRENCH_RCOND).unwrap();
    assert_eq!((w.rank[0], w.unsensed_in_tip[0].len()), (3, 3));
    // The PSM at its singular pose: rank 5; the wrench has no component along the lost
    // direction and explains τ.
    let psm = Model::builtin("psm").unwrap();
    let tip = wrench_frame(&psm, "tool_tip").unwrap();
    let q = DMatrix::from_row_slice(1, 7, &[0.4, -0.3, 0.4318 - 0.4162, 0.7, 0.2, -0.1, 0.3]);
    let tau = torques_of_wrench(&psm, tip, &q, &f);
    let w = tip_wrench(&psm, "tool_tip", &q, &tau, DEFAULT_WRENCH_RCOND).unwrap();
    assert_eq!(w.rank, [5]);
    let v = DVector::from_row_slice(&w.unsensed_in_base[0][0]);
    let mut ws = Workspace::new(&psm);
    let qk: Vec<f64> = q.row(0).iter().copied().collect();
    psm.forward_kinematics(&mut ws, &qk);
    let j = psm.frame_jacobian(&ws, tip);
    assert!((j.transpose() * &v).norm() < 1e-9, "sensed: {v}");
    // A force with at most the moment of the wrist's lever l_p2y = 9.1 mm (which the
    // wrist pitch would feel otherwise), across the shaft (the insertion feels along
    // it): tool_roll's z.
    let force = Vector3::new(v[0], v[1], v[2]);
    assert!(v.rows(3, 3).norm() <= 0.0091 * force.norm() + 1e-12, "{v}");
    let roll = wrench_frame(&psm, "tool_roll").unwrap();
    let shaft = ws.pose(roll).rotation.column(2).into_owned();
    assert!(
        force.dot(&shaft).abs() < 1e-9,
        "across the shaft: {force} {shaft}"
    );
    let got = DVector::from_iterator(6, w.in_base.row(0).iter().copied());
    assert!(got.dot(&v).abs() < 1e-9);
    let t = DVector::from_iterator(7, tau.row(0).iter().copied());
    assert!((j.transpose() * &got - t).norm() < 1e-9);
    // In the tip's axes, the same direction rotated.
    let r = ws.pose(tip).rotation;
    let in_tip = r.transpose() * force;
    for c in 0..3 {
        assert!((w.unsensed_in_tip[0][0][c] - in_tip[c]).abs() < 1e-12);
    }
}
