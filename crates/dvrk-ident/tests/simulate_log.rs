//! `dvrk_ident::simulate`: the measured log maps back to the model's inverse dynamics
//! (plus known forces), the noise has the requested level and is reproducible, and bad
//! inputs are refused with messages naming them.

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::simulate::to_model_coordinates;
use dvrk_ident::simulate::{simulate, to_measured_coordinates, Simulation};
use dvrk_ident::Coordinates;
use dvrk_model::{Model, Workspace};

fn params(model: &Model) -> Vec<f64> {
    // Any values: the check is an identity, not physics.
    (0..model.n_params())
        .map(|k| 0.01 * ((k * 7) % 11) as f64 + 0.002)
        .collect()
}

fn trajectory(n: usize) -> FourierTrajectory {
    FourierTrajectory {
        order: 3,
        base_frequency_hz: 0.25,
        q0: (0..n).map(|j| 0.1 + 0.02 * j as f64).collect(),
        a: (0..n)
            .map(|j| vec![0.2, -0.1 + 0.01 * j as f64, 0.05])
            .collect(),
        b: (0..n).map(|j| vec![0.1, 0.03, -0.02 * j as f64]).collect(),
        coordinates: Vec::new(),
        robot: None,
    }
}

fn check_identity(robot: &str) {
    let model = Model::builtin(robot).unwrap();
    let n = model.dof();
    let pi = params(&model);
    let traj = trajectory(n);
    let sim = Simulation {
        rate_hz: 100.0,
        ..Simulation::default()
    };
    let log = simulate(&model, &pi, &traj, &sim).unwrap();
    assert_eq!(log.coordinates, Coordinates::Measured);
    assert_eq!(log.joint_names, model.measured.joints);
    assert_eq!(log.len(), 400, "one period of 4 s at 100 Hz");
    assert_eq!(log.time[1], 0.01);
    let back = to_model_coordinates(&model, &log).unwrap();
    let mut ws = Workspace::new(&model);
    let (mut q, mut dq, mut ddq, mut tau) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in (0..log.len()).step_by(7) {
        traj.eval(log.time[k], &mut q, &mut dq, &mut ddq);
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        model.add_known_forces(&q, &mut tau);
        for j in 0..n {
            assert!((back.q[(k, j)] - q[j]).abs() < 1e-12, "{robot} q");
            assert!((back.dq.as_ref().unwrap()[(k, j)] - dq[j]).abs() < 1e-12);
            assert!(
                (back.tau[(k, j)] - tau[j]).abs() < 1e-11 * (1.0 + tau[j].abs()),
                "{robot} sample {k} joint {j}: {} vs {}",
                back.tau[(k, j)],
                tau[j]
            );
        }
        // Measured = M q, and the power is the same in both spaces.
        let m = &model.measured.coupling;
        let (mut p_meas, mut p_model) = (0.0, 0.0);
        for i in 0..n {
            let qm: f64 = (0..n).map(|j| m[(i, j)] * q[j]).sum();
            assert!((log.q[(k, i)] - qm).abs() < 1e-12);
            p_meas += log.tau[(k, i)] * log.dq.as_ref().unwrap()[(k, i)];
            p_model += tau[i] * dq[i];
        }
        assert!((p_meas - p_model).abs() < 1e-10 * (1.0 + p_model.abs()));
    }
}

#[test]
fn psm_log_maps_back_to_inverse_dynamics() {
    check_identity("psm");
}

#[test]
fn mtm_log_includes_the_known_cable_force() {
    let model = Model::builtin("mtm").unwrap();
    assert!(model.has_known_forces());
    check_identity("mtm");
}

#[test]
fn noise_has_the_requested_level_and_is_reproducible() {
    let model = Model::builtin("psm").unwrap();
    let n = model.dof();
    let pi = params(&model);
    let traj = trajectory(n);
    let std: Vec<f64> = (0..n).map(|j| 0.01 * (j + 1) as f64).collect();
    let sim = Simulation {
        duration_s: Some(20.0),
        noise_std: std.clone(),
        seed: 3,
        ..Simulation::default()
    };
    let noisy = simulate(&model, &pi, &traj, &sim).unwrap();
    assert_eq!(noisy.len(), 4000);
    let clean = simulate(
        &model,
        &pi,
        &traj,
        &Simulation {
            noise_std: vec![],
            ..sim.clone()
        },
    )
    .unwrap()
    .tau;
    let (a, b) = (
        to_model_coordinates(&model, &noisy).unwrap(),
        to_model_coordinates(
            &model,
            &dvrk_ident::JointLog {
                tau: clean.clone(),
                ..noisy.clone()
            },
        )
        .unwrap(),
    );
    for (j, &sd) in std.iter().enumerate() {
        let e = a.tau.column(j) - b.tau.column(j);
        let s = (e.norm_squared() / e.len() as f64).sqrt();
        assert!((s / sd - 1.0).abs() < 0.05, "joint {j}: {s} vs {sd}");
        assert!(e.mean().abs() < 4.0 * sd / (e.len() as f64).sqrt());
    }
    // Positions and velocities are exact; the same seed gives the same log, another seed
    // another one.
    assert_eq!(noisy.q, simulate(&model, &pi, &traj, &sim).unwrap().q);
    assert_eq!(noisy.tau, simulate(&model, &pi, &traj, &sim).unwrap().tau);
    let other = simulate(&model, &pi, &traj, &Simulation { seed: 4, ..sim }).unwrap();
    assert_ne!(noisy.tau, other.tau);
}

#[test]
fn measured_conversion_is_the_inverse_of_the_model_mapping() {
    let model = Model::builtin("psm").unwrap();
    let log = simulate(
        &model,
        &params(&model),
        &trajectory(7),
        &Simulation::default(),
    )
    .unwrap();
    let there = to_model_coordinates(&model, &log).unwrap();
    let back = to_measured_coordinates(&model, &there).unwrap();
    assert_eq!(back.joint_names, log.joint_names);
    assert!((&back.q - &log.q).abs().max() < 1e-13);
    assert!((&back.tau - &log.tau).abs().max() < 1e-12);
    // Already measured: unchanged.
    assert_eq!(to_measured_coordinates(&model, &log).unwrap(), log);
}

#[test]
fn bad_inputs_are_refused_with_their_names() {
    let model = Model::builtin("psm").unwrap();
    let pi = params(&model);
    let err = |traj: &FourierTrajectory, pi: &[f64], sim: &Simulation| {
        simulate(&model, pi, traj, sim).unwrap_err().to_string()
    };
    let ok = Simulation::default();
    let e = err(&trajectory(6), &pi, &ok);
    assert!(e.contains("6 coordinates") && e.contains("7"), "{e}");
    let mut named = trajectory(7);
    named.coordinates = (1..=7).map(|j| format!("joint{j}")).collect();
    assert!(err(&named, &pi, &ok).contains("joint1"));
    assert!(err(&trajectory(7), &pi[1..], &ok).contains("parameter"));
    let mut nan = pi.clone();
    nan[3] = f64::NAN;
    let e = err(&trajectory(7), &nan, &ok);
    assert!(e.contains(&model.params[3].name), "{e}");
    for (sim, word) in [
        (
            Simulation {
                rate_hz: 0.0,
                ..ok.clone()
            },
            "rate",
        ),
        (
            Simulation {
                duration_s: Some(-1.0),
                ..ok.clone()
            },
            "duration",
        ),
        (
            Simulation {
                duration_s: Some(0.001),
                ..ok.clone()
            },
            "duration",
        ),
        (
            Simulation {
                noise_std: vec![0.1, 0.2],
                ..ok.clone()
            },
            "noise",
        ),
        (
            Simulation {
                noise_std: vec![f64::NAN],
                ..ok.clone()
            },
            "noise",
        ),
        (
            Simulation {
                noise_std: vec![-0.1],
                ..ok.clone()
            },
            "noise",
        ),
    ] {
        let e = err(&trajectory(7), &pi, &sim);
        assert!(e.contains(word), "{word}: {e}");
    }
}
