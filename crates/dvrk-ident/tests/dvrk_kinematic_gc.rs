//! The dVRK kinematic gravity-compensation export against the controller's own
//! computation: the exported file read as cisst's `LoadRobot` reads it, the arm's joints
//! mapped onto its links, `CCG_MDH` for the up vector of the mounting pitch and the
//! efforts mapped back, all transcribed independently in `dvrk_test_support::cisst`,
//! equal the model's gravity torque at 200 random poses within the joint ranges.

use dvrk_ident::export::dvrk_kinematic_gc::{dvrk_kinematic_gc, KinematicGc};
use dvrk_ident::export::Export;
use dvrk_model::{Model, Workspace};
use dvrk_test_support::cisst;
use dvrk_test_support::{physical_params, Rng};

const POSES: usize = 200;

/// The controller's efforts from the exported file at the arm's joints `j`. With an
/// instrument (psm_si_tool), the controller's effort vector has one entry per joint and
/// `GravityCompensationPSM::compute` leaves the instrument's at 0.
fn controller(robot: &str, file: &serde_json::Value, j: &[f64], up: [f64; 3]) -> Vec<f64> {
    let links = cisst::links_of(file);
    match robot {
        "psm_si" | "psm_si_tool" => {
            let mut e = cisst::psm_si_gc(&links, &[j[0], j[1], j[2]], up).to_vec();
            e.resize(j.len(), 0.0);
            e
        }
        "ecm_si" => cisst::ecm_si_gc(&links, &[j[0], j[1], j[2], j[3]], up).to_vec(),
        "ecm" => cisst::ecm_classic_gc(&links, &[j[0], j[1], j[2], j[3]], up).to_vec(),
        _ => unreachable!(),
    }
}

/// The file as the controller loads it: the ECM's insertion link gets its endoscope
/// type's mass whatever the file says (`set_endoscope_mass`).
fn as_loaded(robot: &str, gc: &KinematicGc) -> serde_json::Value {
    let mut file = gc.to_json();
    let link = match robot {
        "ecm_si" => Some(5),
        "ecm" => Some(2),
        _ => None,
    };
    if let (Some(l), Some((_, mass))) = (link, &gc.endoscope) {
        file["DH"]["joints"][l]["mass"] = serde_json::json!(mass);
    }
    file
}

/// Largest difference per joint between the controller's efforts and the model's
/// gravity torque at random poses within the joint ranges.
fn worst_difference(model: &Model, params: &[f64], gc: &KinematicGc, seed: u64) -> Vec<f64> {
    let file = as_loaded(&model.name, gc);
    // What the controller is configured with: the file's recorded mounting pitch.
    let up = cisst::up_vector(file["dvrk_ident"]["mounting_pitch_rad"].as_f64().unwrap());
    let mut rng = Rng::new(seed);
    let mut ws = Workspace::new(model);
    let mut tau = vec![0.0; model.dof()];
    let mut worst = vec![0.0f64; model.dof()];
    for _ in 0..POSES {
        let q: Vec<f64> = model
            .measured
            .ranges
            .iter()
            .map(|r| {
                let [lo, hi] = r.unwrap();
                rng.uniform(lo, hi)
            })
            .collect();
        model.gravity_torque(&mut ws, params, &q, &mut tau);
        let theirs = controller(&model.name, &file, &q, up);
        for (w, (a, b)) in worst.iter_mut().zip(tau.iter().zip(&theirs)) {
            *w = w.max((a - b).abs());
        }
    }
    worst
}

fn endoscope(robot: &str) -> Option<&'static str> {
    match robot {
        "ecm_si" => Some("Si_HD_STRAIGHT"),
        "ecm" => Some("Classic_HD_UP"),
        _ => None,
    }
}

/// Random physically consistent links (every centre of mass off every axis): the PSM Si
/// and the Classic ECM files represent them exactly (the PSM Si's first insertion stage,
/// which the controller leaves out of the insertion effort, moved onto the others; the
/// Classic ECM's extra insertion mass onto the roll link), the ECM Si's cannot (its
/// insertion mass is the endoscope's, its roll is not compensated), and says so. The PSM
/// Si with its instrument gives the file of its arm (the instrument moves no link) and no
/// gravity on the instrument's joints, as the controller.
#[test]
fn export_is_the_model_in_the_controllers_computation() {
    for (k, robot) in ["psm_si", "ecm", "ecm_si", "psm_si_tool"]
        .into_iter()
        .enumerate()
    {
        for (i, pitch_deg) in [0.0f64, -45.0, 70.0].into_iter().enumerate() {
            let mut model = Model::builtin(robot).unwrap();
            model.set_mounting_pitch(pitch_deg).unwrap();
            let mut rng = Rng::new(7000 + 10 * k as u64 + i as u64);
            let params = physical_params(&model, &mut rng);
            let gc = dvrk_kinematic_gc(&model, &params, endoscope(robot)).unwrap();
            if robot == "psm_si_tool" {
                // The same arm parameters (the arm's frames and parameters come first).
                let mut arm = Model::builtin("psm_si").unwrap();
                arm.set_mounting_pitch(pitch_deg).unwrap();
                let alone = dvrk_kinematic_gc(&arm, &params[..arm.n_params()], None).unwrap();
                assert_eq!(gc.links, alone.links, "{robot} at {pitch_deg}°");
                assert_eq!(gc.joints, ["yaw", "pitch", "insertion"]);
            }
            assert!(
                (gc.mounting_pitch_rad() - pitch_deg.to_radians()).abs() < 1e-12,
                "{robot}: mounting pitch {} rad",
                gc.mounting_pitch_rad()
            );
            let worst = worst_difference(&model, &params, &gc, 8000 + i as u64);
            println!(
                "{robot} at {pitch_deg}°: largest difference {worst:.3?}, reported residual {:.3?}",
                gc.residual_max
            );
            if robot == "ecm_si" {
                // Not representable: the roll's gravity and the insertion mass differ.
                assert!(
                    gc.residual_max[3] > 1e-3 && gc.residual_max[2] > 1e-3,
                    "{robot}: {:?}",
                    gc.residual_max
                );
                for (j, w) in worst.iter().enumerate() {
                    assert!(
                        *w <= gc.residual_max[j] + 1e-6,
                        "{robot} at {pitch_deg}° joint {j}: {w:e} beyond the reported residual {:e}",
                        gc.residual_max[j]
                    );
                }
            } else {
                assert!(
                    gc.residual_max.iter().all(|r| *r < 1e-9),
                    "{robot}: {:?}",
                    gc.residual_max
                );
                assert!(
                    worst.iter().all(|w| *w < 1e-6),
                    "{robot} at {pitch_deg}°: {worst:?}"
                );
            }
        }
    }
}

/// With the endoscope's identified mass equal to its type's and the roll's centre of
/// mass on its axis (the nominal ECM Si: the SCOPE_Si_HD mass, the roll without mass),
/// the ECM Si's file is exact too; the nominal PSM Si's file is the dVRK's own masses.
#[test]
fn nominal_si_arms_export_exactly_and_the_psm_si_gives_back_the_shipped_masses() {
    for robot in ["ecm_si", "psm_si"] {
        let mut model = Model::builtin(robot).unwrap();
        model.set_mounting_pitch(-45.0).unwrap();
        let params = model.nominal_parameters().unwrap();
        let gc = dvrk_kinematic_gc(&model, &params, endoscope(robot)).unwrap();
        let worst = worst_difference(&model, &params, &gc, 9);
        assert!(worst.iter().all(|w| *w < 1e-6), "{robot}: {worst:?}");
        if robot == "psm_si" {
            // PSM_Si_physical.json: yaw 0.994 kg at (−0.094, 0.082, 0), insertion2 0.637
            // kg at (0.018, 0, 0.060); insertion1 has no mass, so nothing moves.
            let yaw = &gc.links[0];
            assert!((yaw.mass - 0.994).abs() < 1e-9 && (yaw.com[0] + 0.094).abs() < 1e-9);
            let ins2 = &gc.links[6];
            assert!((ins2.mass - 0.637).abs() < 1e-9 && (ins2.com[2] - 0.060).abs() < 1e-9);
            assert!((gc.links[2].alpha).abs() < 1e-12 && (gc.links[2].a - 0.2913).abs() < 1e-12);
        }
    }
}

#[test]
fn other_arms_and_bad_endoscopes_are_refused() {
    let message = |robot: &str, endoscope: Option<&str>| {
        let model = Model::builtin(robot).unwrap();
        let params = vec![0.1; model.n_params()];
        Export::DvrkKinematicGc { endoscope }
            .build(&model, &params)
            .unwrap_err()
            .to_string()
    };
    let mtm = message("mtm", None);
    // The command line's spelling of the export that serves the MTM (Python's:
    // tests/python/test_export.py).
    assert!(
        mtm.ends_with(
            "the MTM's gravity compensation is its own file: export --dvrk-gc (Python \
             FitResult.dvrk_gc())"
        ),
        "{mtm}"
    );
    let psm = message("psm", None);
    assert!(
        psm.ends_with(
            "the Classic PSM (its controller loads none; only the PSM Si's): export --urdf \
             or --wpi-json for other controllers"
        ),
        "{psm}"
    );
    let ecm = message("ecm", None);
    assert!(
        ecm.contains("endoscope") && ecm.contains("Classic_HD_STRAIGHT"),
        "{ecm}"
    );
    let unknown = message("ecm_si", Some("Classic_XL"));
    assert!(
        unknown.contains("unknown endoscope type \"Classic_XL\""),
        "{unknown}"
    );
    let psm_si = message("psm_si", Some("Si_HD_UP"));
    assert!(psm_si.contains("carries no endoscope"), "{psm_si}");
    // An instrument link with mass: the controller's file has no link for it.
    let text = include_str!("../../dvrk-model/robots/psm_si_tool.toml").replace(
        "theta = \"c_roll*q4\"\nfriction = true",
        "theta = \"c_roll*q4\"\ninertia = true\nfriction = true",
    );
    let heavy = Model::from_toml_str(&text, "psm_si_tool with a heavy roll").unwrap();
    let mut rng = Rng::new(11);
    let params = physical_params(&heavy, &mut rng);
    let err = dvrk_kinematic_gc(&heavy, &params, None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("frame roll carries a link moved by coordinate(s) beyond the arm's 3"),
        "{err}"
    );
    // The settings right, parameters of no rigid body (0.1 everywhere: principal
    // moments of −0.3 kg·m²) are refused, as the MTM's file and a URDF refuse them.
    let not_rigid = message("ecm", Some("Classic_HD_STRAIGHT"));
    assert!(not_rigid.contains("are not rigid bodies"), "{not_rigid}");
}
