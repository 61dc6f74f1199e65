//! `simulate` with a payload and an external torque: the simulated torques grow by the
//! payload's inverse dynamics (its gravity checked against its potential in
//! crates/dvrk-model/tests/payload.rs) and by the external torque file's values, in
//! model coordinates, sample by sample; a bad torque file is refused.

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::simulate::to_model_coordinates;
use dvrk_ident::simulate::ExternalTorque;
use dvrk_ident::simulate::{motion_torques, simulate, Simulation};
use dvrk_model::{Model, Payload};
use nalgebra::DMatrix;

fn trajectory(n: usize) -> FourierTrajectory {
    FourierTrajectory {
        order: 2,
        base_frequency_hz: 0.5,
        q0: (0..n).map(|j| if j == 2 { 0.12 } else { 0.1 }).collect(),
        a: (0..n).map(|j| vec![0.2, -0.1 + 0.01 * j as f64]).collect(),
        b: (0..n).map(|j| vec![0.1, -0.02 * j as f64]).collect(),
        coordinates: Vec::new(),
        robot: None,
    }
}

#[test]
fn payload_and_external_torque_add_to_the_simulated_torques() {
    let model = Model::builtin("psm").unwrap();
    let n = model.dof();
    let params: Vec<f64> = (0..model.n_params())
        .map(|k| 0.003 * (k % 7) as f64)
        .collect();
    let traj = trajectory(n);
    let payload = Payload {
        frame: "main_insertion".into(),
        mass: 0.2,
        com: [0.0, 0.02, 0.165],
        inertia: [1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0],
    };
    let names = model.coordinates.clone();
    let csv = format!(
        "time,{}\n0,0,0,0,0,0,0,0\n0.5,0,0,0,0,0,0,0\n0.5,0.1,-0.2,0.3,0.01,0,0,-0.02\n1,0.2,-0.2,0.3,0.01,0,0,-0.02\n",
        names.join(",")
    );
    let external = ExternalTorque::parse_csv(&csv, "step.csv", &names).unwrap();
    let plain = Simulation {
        rate_hz: 100.0,
        ..Simulation::default()
    };
    let loaded = Simulation {
        payload: Some(payload.clone()),
        external_torque: Some(external.clone()),
        ..plain.clone()
    };
    let a =
        to_model_coordinates(&model, &simulate(&model, &params, &traj, &plain).unwrap()).unwrap();
    let b =
        to_model_coordinates(&model, &simulate(&model, &params, &traj, &loaded).unwrap()).unwrap();
    assert_eq!(a.q, b.q);
    let (q, dq) = (&a.q, a.dq.as_ref().unwrap());
    let (_, _, ddq) = traj.sample(&a.time);
    let carried = motion_torques(
        &model,
        &payload.params(&model, "test").unwrap(),
        q,
        dq,
        &ddq,
    );
    let mut expected: DMatrix<f64> = &a.tau + carried;
    let mut at = vec![0.0; n];
    for (k, t) in a.time.iter().enumerate() {
        external.at(*t, &mut at);
        for j in 0..n {
            expected[(k, j)] += at[j];
        }
    }
    let worst = (&b.tau - &expected).abs().max();
    assert!(worst < 1e-9, "largest difference {worst}");
    // The step is there: at 0.75 s, 0.15 N·m on the first coordinate (linear from 0.1 to 0.2).
    let k = a.time.iter().position(|t| (t - 0.75).abs() < 1e-9).unwrap();
    external.at(0.75, &mut at);
    assert!((at[0] - 0.15).abs() < 1e-15);
    // The payload's torque is not negligible on the pitch and the insertion.
    let load = &b.tau - &a.tau;
    assert!(
        load[(k, 1)].abs() > 0.05 && load[(k, 2)].abs() > 0.1,
        "{}",
        load.row(k)
    );
}

#[test]
fn an_external_torque_of_the_wrong_width_is_refused() {
    let model = Model::builtin("psm").unwrap();
    let external = ExternalTorque {
        time: vec![0.0, 1.0],
        tau: DMatrix::zeros(2, 3),
    };
    let sim = Simulation {
        external_torque: Some(external),
        ..Simulation::default()
    };
    let params = vec![0.0; model.n_params()];
    let e = simulate(&model, &params, &trajectory(7), &sim)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("external_torque") && e.contains("3 columns of torques for 7"),
        "{e}"
    );
}
