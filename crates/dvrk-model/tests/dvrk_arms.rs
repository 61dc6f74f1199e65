//! The ECM, PSM Si and ECM Si descriptions against the dVRK controller's own files and
//! code (jhu-dvrk/sawIntuitiveResearchKit share/kinematic/*.json, read by jhu-cisst/cisst
//! cisstRobot), transcribed in `dvrk_test_support::cisst` independently of dvrk-model:
//! forward kinematics against the virtual DH the controller uses for the arm's pose,
//! every physical-DH frame against the gravity-compensation chain, and the nominal
//! masses' gravity torque against the controller's gravity compensation at several
//! mounting pitches.
// The dVRK's files write π/2 as 1.5708 or 1.570796327 (and π as 3.14159625): those
// literals are transcribed as they are, which is what the controller reads.
#![allow(clippy::approx_constant)]
#![cfg(feature = "description")]

use std::f64::consts::FRAC_PI_2;

use dvrk_model::{Model, Workspace};
use dvrk_test_support::cisst::{self, Link};
use dvrk_test_support::Rng;
use nalgebra::{Matrix4, Vector3};

const POSES: usize = 200;

/// The virtual DH of an arm as its JSON writes it. The files write the joint offsets ±π/2
/// as ±1.5708 (cisst rounds only `alpha` = ±1.5708 to ±π/2): the transcription uses π/2,
/// the 3.7e-6 rad difference being the file's rounding, not geometry.
fn virtual_dh(insertion_offset: f64, roll: bool) -> Vec<Link> {
    let mut links = vec![
        Link::new(1.5708, 0.0, 0.0, 0.0, false, FRAC_PI_2),
        Link::new(-1.5708, 0.0, 0.0, 0.0, false, -FRAC_PI_2),
        Link::new(1.5708, 0.0, 0.0, 0.0, true, insertion_offset),
    ];
    if roll {
        links.push(Link::new(0.0, 0.0, 0.0, 0.3829, false, 0.0));
    }
    links
}

/// PSM_Si_physical.json, as written (masses and centres of mass included).
fn psm_si_physical() -> Vec<Link> {
    vec![
        Link::new(1.570796327, 0.0, 1.570796327, 0.0, false, 0.0)
            .with_mass(0.994, [-0.094, 0.082, 0.0]),
        Link::new(-1.570796327, -0.0712, 1.570796327, 0.0, false, 0.0),
        Link::new(0.0, 0.2913, -2.04193, 0.0, false, 0.0).with_mass(1.005, [0.011, -0.056, 0.0]),
        Link::new(0.0, 0.203130, 1.83474, 0.0, false, 0.0).with_mass(2.060, [0.004, -0.020, 0.0]),
        Link::new(0.0, 0.346122, 0.207187, 0.0, false, 0.0).with_mass(2.041, [0.019, 0.013, 0.0]),
        Link::new(-1.570796327, 0.0602, 3.14159625, -0.1800, true, 0.0),
        Link::new(0.0, -0.0320, 0.0, -0.1215, true, 0.0).with_mass(0.637, [0.018, 0.0, 0.060]),
    ]
}

/// ECM_Si_physical.json, as written, with the endoscope mass the controller sets on
/// link 6 for `endoscope_kg`.
fn ecm_si_physical(endoscope_kg: f64) -> Vec<Link> {
    vec![
        Link::new(1.570796327, 0.0, 1.570796327, 0.0, false, 0.0)
            .with_mass(1.003, [-0.117, 0.068, 0.0]),
        Link::new(-1.570796327, -0.0712, 1.570796327, 0.0, false, 0.0),
        Link::new(0.0, 0.2913, -2.04193, 0.0, false, 0.0).with_mass(1.391, [0.200, -0.100, 0.0]),
        Link::new(0.0, 0.203130, 1.83474, 0.0, false, 0.0).with_mass(1.792, [0.0, 0.0, 0.0]),
        Link::new(0.0, 0.346122, 0.207187, 0.0, false, 0.0).with_mass(1.845, [0.0, -0.080, 0.0]),
        Link::new(-1.570796327, 0.0922, 3.14159625, -0.2012, true, 0.0)
            .with_mass(endoscope_kg, [0.0, 0.0, -0.144]),
    ]
}

/// ECM.json (virtual DH used as physical) with the endoscope mass on link 3.
fn ecm_classic_physical(endoscope_kg: f64) -> Vec<Link> {
    let mut links = virtual_dh(-0.3822, true);
    links[2] = links[2].clone().with_mass(endoscope_kg, [0.0, 0.0, -0.1]);
    links
}

fn builtin(name: &str) -> Model {
    Model::builtin(name).unwrap_or_else(|e| panic!("{e}"))
}

fn frame_index(model: &Model, name: &str) -> usize {
    model
        .frame_names()
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("{}: no frame {name}", model.name))
}

/// A random pose within the description's measured joint ranges.
fn random_pose(model: &Model, rng: &mut Rng) -> Vec<f64> {
    model
        .measured
        .ranges
        .iter()
        .map(|r| {
            let [lo, hi] = r.expect("measured range");
            rng.uniform(lo, hi)
        })
        .collect()
}

fn pose_of(ws: &Workspace, frame: usize) -> Matrix4<f64> {
    let p = ws.pose(frame);
    let mut t = Matrix4::identity();
    t.fixed_view_mut::<3, 3>(0, 0).copy_from(&p.rotation);
    t.fixed_view_mut::<3, 1>(0, 3).copy_from(&p.translation);
    t
}

fn max_abs_diff(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
    (a - b).abs().max()
}

#[test]
fn forward_kinematics_matches_the_controllers_virtual_dh() {
    // (robot, frame that is the virtual DH's last frame, the virtual DH)
    let cases = [
        ("psm_si", "insertion", virtual_dh(-0.4826, false)),
        ("ecm_si", "roll", virtual_dh(-0.3822, true)),
        ("ecm", "roll", virtual_dh(-0.3822, true)),
    ];
    for (k, (robot, tip, links)) in cases.iter().enumerate() {
        let model = builtin(robot);
        let frame = frame_index(&model, tip);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(290 + k as u64);
        let mut worst = 0.0f64;
        for _ in 0..POSES {
            let q = random_pose(&model, &mut rng);
            model.forward_kinematics(&mut ws, &q);
            let ours = pose_of(&ws, frame);
            let theirs = *cisst::forward_kinematics(links, &q).last().unwrap();
            worst = worst.max(max_abs_diff(&ours, &theirs));
        }
        println!("{robot}: virtual DH, largest difference {worst:e}");
        assert!(
            worst < 1e-9,
            "{robot}: frame {tip} differs from the virtual DH by {worst:e}"
        );
    }
}

/// Every frame of the Si descriptions that carries mass is the physical DH's frame of the
/// same link (so a centre of mass means the same in both), up to the file's rounding: its
/// parallelogram angles have 6 digits and its insertion `theta` is written 3.14159625
/// (π is 3.14159265), a few µrad, a few µm over the arm's 0.6 m.
#[test]
fn si_frames_are_the_controllers_physical_dh_frames() {
    let cases = [
        (
            "psm_si",
            psm_si_physical(),
            [
                "yaw",
                "intermediate_yaw",
                "pitch1",
                "pitch2",
                "pitch3",
                "insertion1",
                "insertion2",
            ]
            .as_slice(),
        ),
        (
            "ecm_si",
            ecm_si_physical(0.0),
            [
                "yaw",
                "intermediate_yaw",
                "pitch1",
                "pitch2",
                "pitch3",
                "insertion",
            ]
            .as_slice(),
        ),
    ];
    for (k, (robot, links, names)) in cases.iter().enumerate() {
        let model = builtin(robot);
        let frames: Vec<usize> = names.iter().map(|n| frame_index(&model, n)).collect();
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(390 + k as u64);
        // The physical DH's base is on the yaw axis (base −y), l_rcm = 0.2913 + 0.33872 m
        // from the RCM, the virtual DH's (and the description's) base; same axes.
        let mut base = Matrix4::identity();
        base[(1, 3)] = -(0.2913 + 0.33872);
        let mut worst = 0.0f64;
        for _ in 0..POSES {
            let q = random_pose(&model, &mut rng);
            let physical_q: Vec<f64> = match *robot {
                "psm_si" => vec![q[0], 0.0, q[1], -q[1], q[1], q[2] / 2.0, q[2] / 2.0],
                _ => vec![q[0], 0.0, q[1], -q[1], q[1], q[2]],
            };
            model.forward_kinematics(&mut ws, &q);
            let theirs = cisst::forward_kinematics(links, &physical_q);
            for (f, t) in frames.iter().zip(&theirs) {
                worst = worst.max(max_abs_diff(&pose_of(&ws, *f), &(base * t)));
            }
        }
        println!("{robot}: physical DH frames, largest difference {worst:e}");
        assert!(
            worst < 2e-5,
            "{robot}: physical DH frames differ by {worst:e}"
        );
        assert!(
            worst > 1e-7,
            "{robot}: the file's rounding should show ({worst:e})"
        );
    }
}

/// The description's nominal masses give the controller's gravity compensation, at the
/// mounting pitches 0, −45° and 70°: gravity (0, −9.81·sin p, −9.81·cos p) in the model,
/// the up vector (0, 9.81·sin p, 9.81·cos p) in CCG_MDH.
#[test]
fn nominal_gravity_is_the_controllers_gravity_compensation() {
    for (k, robot) in ["psm_si", "ecm_si", "ecm"].into_iter().enumerate() {
        let mut model = builtin(robot);
        let params = model.nominal_parameters().expect("nominal parameters");
        let mut rng = Rng::new(490 + k as u64);
        for pitch_deg in [0.0f64, -45.0, 70.0] {
            let p = pitch_deg.to_radians();
            model.gravity = Vector3::new(0.0, -9.81 * p.sin(), -9.81 * p.cos());
            let up = cisst::up_vector(p);
            let mut ws = Workspace::new(&model);
            let mut tau = vec![0.0; model.dof()];
            let mut worst = 0.0f64;
            let mut largest = 0.0f64;
            for _ in 0..POSES {
                let q = random_pose(&model, &mut rng);
                model.gravity_torque(&mut ws, &params, &q, &mut tau);
                let theirs: Vec<f64> = match robot {
                    "psm_si" => {
                        cisst::psm_si_gc(&psm_si_physical(), &[q[0], q[1], q[2]], up).to_vec()
                    }
                    "ecm_si" => {
                        cisst::ecm_si_gc(&ecm_si_physical(1.8), &[q[0], q[1], q[2], q[3]], up)
                            .to_vec()
                    }
                    _ => cisst::ecm_classic_gc(
                        &ecm_classic_physical(2.5),
                        &[q[0], q[1], q[2], q[3]],
                        up,
                    )
                    .to_vec(),
                };
                for (a, b) in tau.iter().zip(&theirs) {
                    worst = worst.max((a - b).abs());
                    largest = largest.max(b.abs());
                }
            }
            println!("{robot} at {pitch_deg}°: largest gravity torque {largest:.3}, difference {worst:e} N·m");
            assert!(
                largest > 1.0,
                "{robot} at {pitch_deg}°: no gravity torque ({largest})"
            );
            assert!(
                worst < 1e-4,
                "{robot} at {pitch_deg}°: nominal gravity torque differs from the controller's by {worst:e} N·m"
            );
        }
    }
}
