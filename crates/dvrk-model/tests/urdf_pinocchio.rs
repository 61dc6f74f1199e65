//! The URDF import and the dynamics against Pinocchio 4.1 on a 7-DoF Franka Panda
//! (`../shared/anchors/panda_arm_7dof.urdf`, `pinocchio_reference.json`): inverse
//! dynamics, mass matrix, gravity, nonlinear effects, forward dynamics (the reference
//! accelerations from its torques) and the joint-torque regressor on 20 random samples,
//! and the nominal dynamic parameters, all to 1e-9.
//!
//! Conventions (from the JSON): Pinocchio's dynamic parameters of joint i are
//! `[m, mc_x, mc_y, mc_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]` in the joint frame (= child link
//! frame), inertia about the joint-frame origin; fixed-joint child links are merged into
//! the moving parent body. Our model keeps one frame per URDF joint (fixed ones included)
//! with barycentric `[Lxx, Lxy, Lxz, Lyy, Lyz, Lzz, lx, ly, lz, m]`.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_model::inertia::{sym3, sym6};
use dvrk_model::{Model, Transform, Workspace};
use dvrk_test_support::*;
use nalgebra::{DMatrix, Matrix3, Vector3};

const TOL: f64 = 1e-9;

/// For each of our 10 barycentric parameters, its index in Pinocchio's order.
const PIN_INDEX: [usize; 10] = [4, 5, 7, 6, 8, 9, 1, 2, 3, 0];

struct Reference {
    model: Model,
    json: serde_json::Value,
}

fn load() -> Option<Reference> {
    let urdf = shared("anchors/panda_arm_7dof.urdf")?;
    let json = shared("anchors/pinocchio_reference.json")?;
    let model = Model::load(urdf.to_str().unwrap()).unwrap();
    Some(Reference {
        model,
        json: read_json(&json),
    })
}

fn matrix(v: &serde_json::Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(f64s).collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |r, c| rows[r][c])
}

/// Largest difference seen so far and where.
struct Worst {
    /// What "theirs" is, for messages.
    reference: &'static str,
    diff: f64,
    place: String,
}

impl Default for Worst {
    fn default() -> Self {
        Worst::against("Pinocchio")
    }
}

impl Worst {
    fn against(reference: &'static str) -> Self {
        Worst {
            reference,
            diff: 0.0,
            place: String::new(),
        }
    }

    fn see(&mut self, ours: f64, theirs: f64, place: impl FnOnce() -> String) {
        let d = (ours - theirs).abs();
        assert!(d.is_finite(), "non-finite value at {}", place());
        if d > self.diff {
            self.diff = d;
            self.place = format!("{}: ours {ours} {} {theirs}", place(), self.reference);
        }
    }

    fn check(&self, what: &str) {
        eprintln!(
            "{what}: max |ours - {}| = {:e} ({})",
            self.reference, self.diff, self.place
        );
        assert!(
            self.diff < TOL,
            "{what}: max difference {:e} at {}",
            self.diff,
            self.place
        );
    }
}

fn frame_index(model: &Model, name: &str) -> usize {
    model
        .frame_names()
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no frame {name}"))
}

#[test]
fn panda_structure() {
    let Some(r) = load() else { return };
    let m = &r.model;
    let joints: Vec<String> = r.json["joint_order"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect();
    assert_eq!(m.coordinates, joints);
    assert_eq!(m.dof(), 7);
    // 7 moving + 5 fixed joints, one frame each.
    assert_eq!(m.frames.len(), 12);
    assert_eq!(m.n_params(), 120);
    let g = f64s(&r.json["gravity"]);
    assert_eq!(m.gravity.as_slice(), g.as_slice());
    // Joint limits kept: panda_joint4 in [-3.0718, -0.0698], |v| <= 2.175.
    let l4 = m.limits.iter().find(|l| l.label == "panda_joint4").unwrap();
    assert_eq!(l4.position, Some([-3.0718, -0.0698]));
    assert_eq!(l4.velocity, Some([-2.175, 2.175]));
    assert_eq!(m.limits.len(), 7);
}

#[test]
fn panda_dynamics_match_pinocchio() {
    let Some(r) = load() else { return };
    let model = &r.model;
    let pi = model
        .nominal_parameters()
        .expect("URDF gives every nominal parameter");
    let mut ws = Workspace::new(model);
    let n = model.dof();
    let (mut w_tau, mut w_m, mut w_g, mut w_nle, mut w_id0, mut w_fd) = (
        Worst::default(),
        Worst::default(),
        Worst::default(),
        Worst::default(),
        Worst::default(),
        Worst::against("the reference ddq"),
    );
    let samples = r.json["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 20);
    for (s, sample) in samples.iter().enumerate() {
        let q = f64s(&sample["q"]);
        let dq = f64s(&sample["dq"]);
        let ddq = f64s(&sample["ddq"]);
        let mut tau = vec![0.0; n];
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        for (k, t) in f64s(&sample["tau_rnea"]).iter().enumerate() {
            w_tau.see(tau[k], *t, || format!("sample {s} joint {k}"));
        }
        let mass = model.mass_matrix(&mut ws, &pi, &q);
        let mref = matrix(&sample["M"]);
        for i in 0..n {
            for j in 0..n {
                w_m.see(mass[(i, j)], mref[(i, j)], || {
                    format!("sample {s} M[{i},{j}]")
                });
            }
        }
        let mut g = vec![0.0; n];
        model.gravity_torque(&mut ws, &pi, &q, &mut g);
        for (k, t) in f64s(&sample["gravity_torque"]).iter().enumerate() {
            w_g.see(g[k], *t, || format!("sample {s} joint {k}"));
        }
        let mut nle = vec![0.0; n];
        model.nonlinear_effects(&mut ws, &pi, &q, &dq, &mut nle);
        let mut id0 = vec![0.0; n];
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &vec![0.0; n], &mut id0);
        for (k, t) in f64s(&sample["nle"]).iter().enumerate() {
            w_nle.see(nle[k], *t, || format!("sample {s} joint {k}"));
            w_id0.see(id0[k], *t, || format!("sample {s} joint {k}"));
        }
        // Pinocchio's torques of (q, q̇, q̈) accelerate the arm by q̈.
        let mut acc = vec![0.0; n];
        model
            .forward_dynamics_into(&mut ws, &pi, &q, &dq, &f64s(&sample["tau_rnea"]), &mut acc)
            .unwrap();
        for (k, a) in ddq.iter().enumerate() {
            w_fd.see(acc[k], *a, || format!("sample {s} joint {k}"));
        }
    }
    w_tau.check("inverse dynamics vs tau_rnea");
    w_m.check("mass matrix vs crba");
    w_g.check("gravity torque vs computeGeneralizedGravity");
    w_nle.check("nonlinear effects vs nonLinearEffects");
    w_id0.check("inverse dynamics with ddq = 0 vs nonLinearEffects");
    w_fd.check("forward dynamics of tau_rnea");
}

/// Barycentric parameters of a body moved from a child frame into its parent frame,
/// `x_parent = R·x_child + p`: `m' = m`, `l' = m·p + R·l`,
/// `L' = R·L·Rᵀ + m·S(p)ᵀS(p) + S(p)ᵀS(R·l) + S(R·l)ᵀS(p)` (inertia about the origin).
fn move_to_parent(x: &Transform, b: &[f64]) -> [f64; 10] {
    let skew =
        |v: &Vector3<f64>| Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0);
    let l_in = sym3(&b[..6]);
    let l = Vector3::new(b[6], b[7], b[8]);
    let m = b[9];
    let (r, p) = (&x.rotation, &x.translation);
    let rl = r * l;
    let sp = skew(p);
    let srl = skew(&rl);
    let big = r * l_in * r.transpose()
        + m * sp.transpose() * sp
        + sp.transpose() * srl
        + srl.transpose() * sp;
    let l2 = m * p + rl;
    let s = sym6(&big);
    [s[0], s[1], s[2], s[3], s[4], s[5], l2[0], l2[1], l2[2], m]
}

/// For each moving joint of the reference (1..7), our frame of its child link, and the
/// fixed frames merged into it by Pinocchio with their transform into that frame.
fn bodies(model: &Model, q: &[f64]) -> Vec<(usize, Vec<(usize, Transform)>)> {
    let poses = model.frame_poses(q);
    let link = |k: usize| frame_index(model, &format!("panda_link{k}"));
    (1..=7)
        .map(|k| {
            let body = link(k);
            let merged = (1..=model.frames.len())
                .filter(|&f| {
                    // Fixed frames whose chain of fixed ancestors ends at `body`.
                    let mut a = f;
                    while a != 0 && a != body && model.frame(a).kind == dvrk_model::JointKind::Fixed
                    {
                        a = model.frame(a).parent;
                    }
                    a == body && f != body
                })
                .map(|f| (f, poses[body].inverse().compose(&poses[f])))
                .collect();
            (body, merged)
        })
        .collect()
}

#[test]
fn panda_nominal_parameters_match_pinocchio() {
    let Some(r) = load() else { return };
    let model = &r.model;
    let pi = model.nominal_parameters().unwrap();
    let phi = f64s(&r.json["phi_nominal"]);
    let mut worst = Worst::default();
    let bodies = bodies(model, &[0.0; 7]);
    assert!(bodies[..6].iter().all(|(_, merged)| merged.is_empty()));
    assert_eq!(
        bodies[6].1.len(),
        5,
        "panda_link8, panda_hand, panda_hand_tcp, two fingers"
    );
    for (j, (body, merged)) in bodies.iter().enumerate() {
        let p0 = model.frame(*body).inertia.unwrap();
        let mut sum: [f64; 10] = pi[p0..p0 + 10].try_into().unwrap();
        for (f, x) in merged {
            let c0 = model.frame(*f).inertia.unwrap();
            let moved = move_to_parent(x, &pi[c0..c0 + 10]);
            for (s, m) in sum.iter_mut().zip(moved) {
                *s += m;
            }
        }
        for (c, &pin) in PIN_INDEX.iter().enumerate() {
            worst.see(sum[c], phi[10 * j + pin], || {
                format!("joint {} parameter {}", j + 1, model.params[p0 + c].name)
            });
        }
    }
    worst.check("nominal parameters (merged) vs phi_nominal");
}

#[test]
fn panda_regressor_matches_pinocchio() {
    let Some(r) = load() else { return };
    let model = &r.model;
    let pi = model.nominal_parameters().unwrap();
    let (n, p) = (model.dof(), model.n_params());
    let mut ws = Workspace::new(model);
    let mut w_cols = Worst::default();
    let mut w_merged = Worst::against("H_body·move(e_c)");
    let mut w_hpi = Worst::default();
    for (s, sample) in r.json["samples"].as_array().unwrap().iter().enumerate() {
        let q = f64s(&sample["q"]);
        let dq = f64s(&sample["dq"]);
        let ddq = f64s(&sample["ddq"]);
        let h = model.regressor(&mut ws, &q, &dq, &ddq);
        let y = matrix(&sample["regressor"]);
        assert_eq!((y.nrows(), y.ncols()), (7, 70));
        // The columns of the body of every moving joint, by position.
        let bodies = bodies(model, &q);
        for (j, (body, merged)) in bodies.iter().enumerate() {
            let p0 = model.frame(*body).inertia.unwrap();
            for (c, &pin) in PIN_INDEX.iter().enumerate() {
                for row in 0..n {
                    w_cols.see(h[(row, p0 + c)], y[(row, 10 * j + pin)], || {
                        format!(
                            "sample {s} row {row} {} vs Pinocchio column {}",
                            model.params[p0 + c].name,
                            10 * j + pin
                        )
                    });
                }
            }
            // A merged fixed child's columns are the body's columns through the change of
            // frame: H_child·e_c = H_body·move(e_c).
            for (f, x) in merged {
                let c0 = model.frame(*f).inertia.unwrap();
                for c in 0..10 {
                    let mut e = [0.0; 10];
                    e[c] = 1.0;
                    let moved = move_to_parent(x, &e);
                    for row in 0..n {
                        let via_body: f64 = (0..10).map(|k| h[(row, p0 + k)] * moved[k]).sum();
                        w_merged.see(h[(row, c0 + c)], via_body, || {
                            format!("sample {s} row {row} {}", model.params[c0 + c].name)
                        });
                    }
                }
            }
        }
        // H·π with our full nominal parameters is Pinocchio's torque.
        let tau = f64s(&sample["tau_rnea"]);
        for row in 0..n {
            let hp: f64 = (0..p).map(|c| h[(row, c)] * pi[c]).sum();
            w_hpi.see(hp, tau[row], || format!("sample {s} joint {row}"));
        }
    }
    w_cols.check("regressor columns of the moving bodies vs computeJointTorqueRegressor");
    w_merged.check("fixed-child columns vs the moving parent's columns through the frame change");
    w_hpi.check("H·π_nominal vs tau_rnea");
}
