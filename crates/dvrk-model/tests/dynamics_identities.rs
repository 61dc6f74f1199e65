//! Identities that must hold for every model at every sample: regressor vs inverse
//! dynamics, mass matrix, forward dynamics, energy balance, gravity, Jacobians — on the
//! built-in PSM, simplified PSM and MTM at seeded random samples.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_test_support as support;

use dvrk_model::{Model, ParamKind, Workspace};
use nalgebra::{DMatrix, DVector, Vector3};
use support::{
    assert_close, filter_params, id, is_friction_or_spring, physical_params, random_params,
    random_state, Rng,
};

const ROBOTS: [&str; 7] = [
    "psm",
    "psm_simplified",
    "mtm",
    "ecm",
    "psm_si",
    "psm_si_tool",
    "ecm_si",
];
const SAMPLES: usize = 30;

fn builtin(name: &str) -> Model {
    Model::builtin(name).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn regressor_times_params_is_inverse_dynamics() {
    for (r, name) in ROBOTS.iter().enumerate() {
        let model = builtin(name);
        let (n, p) = (model.dof(), model.n_params());
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(100 + r as u64);
        let mut h = vec![0.0; n * p];
        let pattern = model.regressor_pattern();
        let mut nonzero = vec![vec![false; p]; n];
        for _ in 0..SAMPLES {
            let (q, dq, ddq) = random_state(&model, &mut rng);
            let pi = random_params(&model, &mut rng);
            let tau = id(&model, &mut ws, &pi, &q, &dq, &ddq);
            model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
            for (row, seen) in nonzero.iter_mut().enumerate() {
                for (c, s) in seen.iter_mut().enumerate() {
                    *s |= h[row * p + c] != 0.0;
                }
            }
            // The allocating form agrees with the buffer form.
            let hm = model.regressor(&mut ws, &q, &dq, &ddq);
            for row in 0..n {
                let terms: Vec<f64> = (0..p).map(|c| h[row * p + c] * pi[c]).collect();
                let hp: f64 = terms.iter().sum();
                let scale: f64 = terms.iter().map(|t| t.abs()).sum::<f64>().max(1e-300);
                assert!(
                    (hp - tau[row]).abs() <= 1e-10 * scale,
                    "{name}: row {row}: H·pi = {hp}, inverse dynamics {}",
                    tau[row]
                );
                for c in 0..p {
                    assert_eq!(hm[(row, c)], h[row * p + c]);
                }
            }
            // Each column alone is the inverse dynamics of a unit parameter.
            let c = (rng.next_u64() % p as u64) as usize;
            let mut e = vec![0.0; p];
            e[c] = 1.0;
            let col = id(&model, &mut ws, &e, &q, &dq, &ddq);
            let hc: Vec<f64> = (0..n).map(|row| h[row * p + c]).collect();
            assert_close(&format!("{name}: column {c}"), &col, &hc, 1e-12);
        }
        // The pattern holds every entry seen nonzero, and little else.
        let mut extra = 0;
        for (row, seen) in nonzero.iter().enumerate() {
            for (c, &s) in seen.iter().enumerate() {
                let listed = pattern[row].binary_search(&c).is_ok();
                assert!(
                    !s || listed,
                    "{name}: H[{row}, {c}] nonzero outside the pattern"
                );
                extra += usize::from(listed && !s);
            }
        }
        let listed: usize = pattern.iter().map(Vec::len).sum();
        assert!(
            extra * 4 < listed,
            "{name}: {extra} of {listed} pattern entries never nonzero"
        );
    }
}

#[test]
fn mass_matrix_symmetric_positive_definite() {
    for (r, name) in ROBOTS.iter().enumerate() {
        let model = builtin(name);
        let n = model.dof();
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(200 + r as u64);
        let mut buf = vec![0.0; n * n];
        for _ in 0..SAMPLES {
            let (q, _, _) = random_state(&model, &mut rng);
            let pi = physical_params(&model, &mut rng);
            let m = model.mass_matrix(&mut ws, &pi, &q);
            model.mass_matrix_into(&mut ws, &pi, &q, &mut buf);
            assert_eq!(
                m.as_slice(),
                &buf[..],
                "{name}: mass_matrix vs mass_matrix_into"
            );
            let scale = m.abs().max();
            let asym = (&m - m.transpose()).abs().max();
            assert!(
                asym <= 1e-12 * scale,
                "{name}: asymmetry {asym:e} (scale {scale})\n{m}"
            );
            let sym = (&m + m.transpose()) * 0.5;
            let eig = sym.clone().symmetric_eigenvalues();
            assert!(eig.min() > 0.0, "{name}: eigenvalues {eig} at q = {q:?}");
            assert!(sym.cholesky().is_some(), "{name}: Cholesky failed");
            // Arbitrary parameters: still symmetric (M is linear in the parameters).
            let pa = random_params(&model, &mut rng);
            let ma = model.mass_matrix(&mut ws, &pa, &q);
            let asym = (&ma - ma.transpose()).abs().max();
            assert!(
                asym <= 1e-12 * ma.abs().max(),
                "{name}: asymmetry {asym:e} for arbitrary parameters"
            );
        }
    }
}

#[test]
fn mass_matrix_plus_bias_is_inverse_dynamics() {
    for (r, name) in ROBOTS.iter().enumerate() {
        let model = builtin(name);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(300 + r as u64);
        for _ in 0..SAMPLES {
            let (q, dq, ddq) = random_state(&model, &mut rng);
            for pi in [
                physical_params(&model, &mut rng),
                random_params(&model, &mut rng),
            ] {
                let m = model.mass_matrix(&mut ws, &pi, &q);
                let h = id(&model, &mut ws, &pi, &q, &dq, &vec![0.0; model.dof()]);
                let tau = id(&model, &mut ws, &pi, &q, &dq, &ddq);
                let pred = &m * DVector::from_column_slice(&ddq) + DVector::from_column_slice(&h);
                assert_close(&format!("{name}: M q̈ + h"), pred.as_slice(), &tau, 1e-11);
            }
        }
    }
}

#[test]
fn forward_dynamics_inverts_inverse_dynamics() {
    for (r, name) in ROBOTS.iter().enumerate() {
        let model = builtin(name);
        let n = model.dof();
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(400 + r as u64);
        for _ in 0..SAMPLES {
            let (q, dq, ddq) = random_state(&model, &mut rng);
            let pi = physical_params(&model, &mut rng);
            // The torque a sensor would see: the inverse dynamics plus the known forces.
            let mut tau = id(&model, &mut ws, &pi, &q, &dq, &ddq);
            model.add_known_forces(&q, &mut tau);
            let acc = model
                .forward_dynamics(&mut ws, &pi, &q, &dq, &tau)
                .unwrap_or_else(|| panic!("{name}: mass matrix not positive definite"));
            assert_eq!(acc.len(), n);
            assert_close(
                &format!("{name}: forward dynamics"),
                acc.as_slice(),
                &ddq,
                1e-8,
            );
        }
    }
}

#[test]
fn mtm_known_force_is_the_cable_polynomial() {
    let model = builtin("mtm");
    assert!(model.has_known_forces());
    assert!(!builtin("psm").has_known_forces());
    let coefs = [
        0.0004877, -0.0037149, 0.0067497, 0.008519, -0.0201475, -0.025265, 0.048095, 0.00255,
    ];
    let mut rng = Rng::new(42);
    for _ in 0..10 {
        let (q, _, _) = random_state(&model, &mut rng);
        let s = 0.6697 * q[1] - 0.6697 * q[2] + q[3];
        let p: f64 = coefs
            .iter()
            .enumerate()
            .map(|(k, c)| c * s.powi(7 - k as i32))
            .sum();
        let mut tau = vec![0.0; 7];
        model.add_known_forces(&q, &mut tau);
        assert_close(
            "mtm cable",
            &tau,
            &[0.0, 0.6697 * p, -0.6697 * p, p, 0.0, 0.0, 0.0],
            1e-13,
        );
    }
}

/// Potential energy of the links: V = −Σ gᵀ (m_j p_j + R_j l_j) from the poses.
fn potential(model: &Model, ws: &mut Workspace, pi: &[f64], q: &[f64]) -> f64 {
    model.forward_kinematics(ws, q);
    let mut v = 0.0;
    for &j in model.link_frames() {
        let p0 = model.frame(j).inertia.unwrap();
        let pose = ws.pose(j);
        let l = Vector3::new(pi[p0 + 6], pi[p0 + 7], pi[p0 + 8]);
        let first_moment = pose.translation * pi[p0 + 9] + pose.rotation * l;
        v -= model.gravity.dot(&first_moment);
    }
    v
}

fn energy(model: &Model, ws: &mut Workspace, pi: &[f64], q: &[f64], dq: &[f64]) -> f64 {
    let m = model.mass_matrix(ws, pi, q);
    let v = DVector::from_column_slice(dq);
    0.5 * v.dot(&(&m * &v)) + potential(model, ws, pi, q)
}

#[test]
fn power_balance() {
    for (r, name) in ROBOTS.iter().enumerate() {
        let model = builtin(name);
        let n = model.dof();
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(500 + r as u64);
        for _ in 0..SAMPLES {
            let (q0, dq0, ddq0) = random_state(&model, &mut rng);
            let pi = physical_params(&model, &mut rng);
            let tau = id(&model, &mut ws, &pi, &q0, &dq0, &ddq0);
            let fs = filter_params(&model, &pi, is_friction_or_spring);
            let tau_fs = id(&model, &mut ws, &fs, &q0, &dq0, &ddq0);
            let terms: Vec<f64> = (0..n).map(|k| dq0[k] * (tau[k] - tau_fs[k])).collect();
            let power: f64 = terms.iter().sum();
            let scale: f64 = terms.iter().map(|t| t.abs()).sum();
            // E(t) along q(t) = q0 + q̇0 t + q̈0 t²/2; five-point central difference at 0.
            let h = 1e-3;
            let mut e_at = |t: f64| {
                let q: Vec<f64> = (0..n)
                    .map(|k| q0[k] + dq0[k] * t + 0.5 * ddq0[k] * t * t)
                    .collect();
                let dq: Vec<f64> = (0..n).map(|k| dq0[k] + ddq0[k] * t).collect();
                energy(&model, &mut ws, &pi, &q, &dq)
            };
            let de =
                (-e_at(2.0 * h) + 8.0 * e_at(h) - 8.0 * e_at(-h) + e_at(-2.0 * h)) / (12.0 * h);
            assert!(
                (de - power).abs() <= 1e-6 * scale,
                "{name}: dE/dt = {de}, q̇ᵀ(τ − τ_friction − τ_spring) = {power} (scale {scale})"
            );
        }
    }
}

#[test]
fn gravity_torque_is_static_inverse_dynamics() {
    for (r, name) in ROBOTS.iter().enumerate() {
        let model = builtin(name);
        let n = model.dof();
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(600 + r as u64);
        let zeros = vec![0.0; n];
        for _ in 0..SAMPLES {
            let (q, _, _) = random_state(&model, &mut rng);
            let pi = random_params(&model, &mut rng);
            let mut g = vec![0.0; n];
            model.gravity_torque(&mut ws, &pi, &q, &mut g);
            let no_fs = filter_params(&model, &pi, |k| !is_friction_or_spring(k));
            let expect = id(&model, &mut ws, &no_fs, &q, &zeros, &zeros);
            assert_close(&format!("{name}: gravity"), &g, &expect, 1e-12);
            // Gravity is the only static torque of the links: only inertial parameters
            // matter.
            let links_only = filter_params(&model, &pi, |k| matches!(k, ParamKind::Inertia { .. }));
            let mut g2 = vec![0.0; n];
            model.gravity_torque(&mut ws, &links_only, &q, &mut g2);
            assert_close(&format!("{name}: gravity (links only)"), &g2, &g, 1e-12);
        }
    }
}

/// `gravity_torque_bound` and `mass_matrix_bound` bound the gravity torque and the mass
/// matrix at every position within their range
/// (random positions and the corners of the box, where the prismatic strokes are longest),
/// for random parameters of every sign, from a unit range to one of 1e6 (rad or m); and it
/// is +∞ when the parameters overflow it. The C ABI skips its output checks on these bounds.
#[test]
fn gravity_and_mass_matrix_stay_within_their_bounds() {
    for (r, name) in ROBOTS.iter().enumerate() {
        let model = builtin(name);
        let n = model.dof();
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(650 + r as u64);
        let (mut g, mut m) = (vec![0.0; n], vec![0.0; n * n]);
        for q_max in [1.0, 1e6] {
            for sample in 0..SAMPLES {
                let pi = random_params(&model, &mut rng);
                let bound = model.gravity_torque_bound(&pi, q_max);
                assert!(bound.is_finite() && bound > 0.0, "{name}: bound {bound}");
                let q: Vec<f64> = (0..n)
                    .map(|_| {
                        let u = rng.uniform(-1.0, 1.0);
                        q_max * if sample % 2 == 0 { u } else { u.signum() }
                    })
                    .collect();
                model.gravity_torque(&mut ws, &pi, &q, &mut g);
                let largest = g.iter().fold(0.0f64, |a, t| a.max(t.abs()));
                assert!(
                    largest <= bound,
                    "{name}: |g| = {largest} above its bound {bound} at q_max {q_max}"
                );
                let mass_bound = model.mass_matrix_bound(&pi, q_max);
                assert!(mass_bound.is_finite(), "{name}: mass bound {mass_bound}");
                model.mass_matrix_into(&mut ws, &pi, &q, &mut m);
                let largest = m.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                assert!(
                    largest <= mass_bound,
                    "{name}: |M| = {largest} above its bound {mass_bound} at q_max {q_max}"
                );
            }
        }
        let huge: Vec<f64> = random_params(&model, &mut rng)
            .iter()
            .map(|p| p * 1e306)
            .collect();
        assert_eq!(
            model.gravity_torque_bound(&huge, 1.0),
            f64::INFINITY,
            "{name}"
        );
        assert_eq!(model.mass_matrix_bound(&huge, 1.0), f64::INFINITY, "{name}");
    }
}

/// Rotation-vector of `R(q + h e_k) R(q − h e_k)ᵀ`-style finite differences: ω from the
/// skew part of Ṙ·Rᵀ.
fn angular_rate(dr: &nalgebra::Matrix3<f64>, r: &nalgebra::Matrix3<f64>) -> Vector3<f64> {
    let w = dr * r.transpose();
    Vector3::new(
        0.5 * (w[(2, 1)] - w[(1, 2)]),
        0.5 * (w[(0, 2)] - w[(2, 0)]),
        0.5 * (w[(1, 0)] - w[(0, 1)]),
    )
}

#[test]
fn frame_jacobian_matches_finite_differences() {
    for (r, name) in ["psm", "mtm", "psm_simplified"].iter().enumerate() {
        let model = builtin(name);
        let n = model.dof();
        let n_frames = model.frames.len();
        let mut ws = Workspace::new(&model);
        let mut ws2 = Workspace::new(&model);
        let mut rng = Rng::new(700 + r as u64);
        let h = 1e-6;
        for _ in 0..5 {
            let (q, _, _) = random_state(&model, &mut rng);
            model.forward_kinematics(&mut ws, &q);
            for frame in 1..=n_frames {
                let jac = model.frame_jacobian(&ws, frame);
                assert_eq!(jac.shape(), (6, n));
                let r0 = ws.pose(frame).rotation;
                for k in 0..n {
                    let mut qp = q.clone();
                    qp[k] += h;
                    model.forward_kinematics(&mut ws2, &qp);
                    let (tp, rp) = (ws2.pose(frame).translation, ws2.pose(frame).rotation);
                    let mut qm = q.clone();
                    qm[k] -= h;
                    model.forward_kinematics(&mut ws2, &qm);
                    let (tm, rm) = (ws2.pose(frame).translation, ws2.pose(frame).rotation);
                    let lin = (tp - tm) / (2.0 * h);
                    let ang = angular_rate(&((rp - rm) / (2.0 * h)), &r0);
                    for i in 0..3 {
                        assert!(
                            (jac[(i, k)] - lin[i]).abs() < 1e-7,
                            "{name}: frame {frame} linear row {i} column {k}: {} vs {}",
                            jac[(i, k)],
                            lin[i]
                        );
                        assert!(
                            (jac[(i + 3, k)] - ang[i]).abs() < 1e-7,
                            "{name}: frame {frame} angular row {i} column {k}: {} vs {}",
                            jac[(i + 3, k)],
                            ang[i]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn frame_poses_match_forward_kinematics() {
    let model = builtin("psm");
    let q = [0.1, -0.2, 0.15, 0.3, -0.4, 0.5, 0.6];
    let poses = model.frame_poses(&q);
    assert_eq!(poses.len(), model.frames.len() + 1);
    let mut ws = Workspace::new(&model);
    model.forward_kinematics(&mut ws, &q);
    for (i, p) in poses.iter().enumerate() {
        assert_eq!(p, ws.pose(i));
    }
    // The remote centre of motion: the parallelogram keeps the insertion axis (frame 8's
    // z) through a fixed point. In this model the pitch axis is at the base origin and
    // the chain 2-3-4-6-8 puts the joint-8 origin at (l_2H1 cos q2, l_2L2 + l_2H1 sin q2)
    // in the pitch plane, with the insertion axis pointing to (0, l_2L2): the centre is
    // l_2H1 behind the joint-8 origin along the axis, i.e. at frame8 − (q3 − l_RCC)·z8,
    // and it is (0, l_2L2, 0) in the base (on the yaw axis, the base's y axis).
    let rcc = |q: &[f64; 7]| {
        let p = model.frame_poses(q);
        let f = &p[8];
        f.translation - f.rotation * Vector3::new(0.0, 0.0, q[2] - 0.4318)
    };
    for q in [
        [0.0; 7],
        [0.2, -0.5, 0.1, 0.0, 0.0, 0.0, 0.0],
        [-1.2, 0.6, 0.2, 1.0, 0.3, 0.2, 0.1],
        [0.7, 0.3, -0.05, -2.0, 1.0, -1.0, 0.5],
    ] {
        let c = rcc(&q);
        assert!(
            (c - Vector3::new(0.0, 0.516, 0.0)).norm() < 1e-12,
            "remote centre at {c} for q = {q:?}"
        );
    }
}

/// The PSM's `tool_tip` frame is the dVRK's own tool tip (jhu-dvrk/sawIntuitiveResearchKit
/// at 9e535e6: share/kinematic/PSM.json for yaw, pitch and insertion, share/tool/
/// LARGE_NEEDLE_DRIVER_400006.json for roll, wrist pitch, wrist yaw and its
/// tooltip_offset), transcribed here as the controller computes it: the six modified-DH
/// frames from the measured joints, times tooltip_offset. The model's base lies l_2L2
/// along the yaw axis (base y) from the dVRK's, the remote centre of motion.
#[test]
fn psm_tool_tip_is_the_dvrks() {
    use nalgebra::Matrix4;
    let mdh = |alpha: f64, a: f64, theta: f64, d: f64| -> Matrix4<f64> {
        let (sa, ca, st, ct) = (alpha.sin(), alpha.cos(), theta.sin(), theta.cos());
        #[rustfmt::skip]
        let m = Matrix4::new(
            ct, -st, 0.0, a,
            st * ca, ct * ca, -sa, -sa * d,
            st * sa, ct * sa, ca, ca * d,
            0.0, 0.0, 0.0, 1.0,
        );
        m
    };
    #[rustfmt::skip]
    let tooltip_offset = Matrix4::<f64>::new(
        0.0, -1.0, 0.0, 0.0,
        0.0, 0.0, 1.0, 0.0,
        -1.0, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    );
    let h = std::f64::consts::FRAC_PI_2;
    for name in ["psm", "psm_simplified"] {
        let model = builtin(name);
        let tip = model
            .frame_names()
            .iter()
            .position(|f| f == "tool_tip")
            .unwrap();
        let mut rng = Rng::new(11);
        let mut ws = Workspace::new(&model);
        for _ in 0..10 {
            let (q, _, _) = random_state(&model, &mut rng);
            let qd = &model.measured.coupling * DVector::from_column_slice(&q);
            // (alpha, A, theta, D) per joint: yaw, pitch, insertion, roll, wrist pitch,
            // wrist yaw (the JSON's 1.5708 is pi/2).
            let chain = [
                (h, 0.0, qd[0] + h, 0.0),
                (-h, 0.0, qd[1] - h, 0.0),
                (h, 0.0, 0.0, qd[2] - 0.4318),
                (0.0, 0.0, qd[3], 0.4162),
                (-h, 0.0, qd[4] - h, 0.0),
                (-h, 0.0091, qd[5] - h, 0.0),
            ];
            let mut dvrk: Matrix4<f64> = chain
                .iter()
                .fold(Matrix4::<f64>::identity(), |t, &(al, a, th, d)| {
                    t * mdh(al, a, th, d)
                })
                * tooltip_offset;
            dvrk[(1, 3)] += 0.516; // l_2L2
            model.forward_kinematics(&mut ws, &q);
            let p = ws.pose(tip);
            for r in 0..3 {
                for c in 0..3 {
                    assert!(
                        (p.rotation[(r, c)] - dvrk[(r, c)]).abs() < 1e-12,
                        "{name} {q:?}"
                    );
                }
                assert!(
                    (p.translation[r] - dvrk[(r, 3)]).abs() < 1e-12,
                    "{name} {q:?}"
                );
            }
        }
    }
}

#[test]
fn psm_constraint_jacobian() {
    let model = builtin("psm");
    let a = model.constraint_jacobian();
    assert_eq!(a.shape(), (18, 7));
    #[rustfmt::skip]
    let expect = DMatrix::from_row_slice(18, 7, &[
        1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,       // 1 yaw
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0,       // 2 pitch_intermediate
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,       // 3 pitch_back (fixed)
        0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0,      // 4 pitch_front
        0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0,      // 5 pitch_front_ext
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0,       // 6 pitch_bottom
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0,       // 7 pitch_top
        0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0,       // 8 pitch_end
        0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0,       // 9 main_insertion
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,       // 10 tool_roll
        0.0, 0.0, 0.0, 0.0, 1.0186, 0.0, 0.0,    // 11 wrist_pitch
        0.0, 0.0, 0.0, 0.0, -0.8306, 1.2178, 0.0, // 12 wrist_yaw_1
        0.0, 0.0, 0.0, 0.0, -0.8306, 0.0, 1.2178, // 13 wrist_yaw_2
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,       // 14 motor_6
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,       // 15 motor_7
        0.0, 0.0, 0.0, 0.0, 0.0, -1.2178, 1.2178, // 16 jaw_coupling_friction
        0.0, 0.0, 0.0, 0.0, -0.8306, 0.6089, 0.6089, // 17 wrist_yaw (the jaws' mean)
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,       // 18 tool_tip (fixed)
    ]);
    let err = (&a - &expect).abs().max();
    assert!(err < 1e-14, "A =\n{a}\nexpected\n{expect}");
    assert_eq!(a[(10, 4)], 1.0186);
    // Offsets: the insertion stage's d = q3 − l_RCC + l_2H1.
    assert!((model.frame(8).value.offset - (-0.4318 + 0.14454)).abs() < 1e-15);
    assert!((model.frame(11).value.offset - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert_eq!(
        model.coordinate_is_length,
        [false, false, true, false, false, false, false]
    );

    let mtm = builtin("mtm");
    let a = mtm.constraint_jacobian();
    assert_eq!(a.shape(), (10, 7));
    assert_eq!(
        a.row(2).iter().copied().collect::<Vec<_>>(),
        [0.0, -1.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    );
    assert_eq!(
        a.row(4).iter().copied().collect::<Vec<_>>(),
        [0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0]
    );
    let row5: Vec<f64> = a.row(5).iter().copied().collect();
    assert_close(
        "mtm frame 6 row",
        &row5,
        &[0.0, 0.6697, -0.6697, 1.0, 0.0, 0.0, 0.0],
        1e-15,
    );
    assert_eq!(
        a.row(9).iter().copied().collect::<Vec<_>>(),
        [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    );
}

#[test]
fn parameter_counts_and_base_ranks() {
    let psm = builtin("psm");
    assert_eq!(psm.n_params(), 115);
    assert_eq!(psm.base_parameters().unwrap().rank(), 49);
    let mtm = builtin("mtm");
    assert_eq!(mtm.n_params(), 122);
    assert_eq!(mtm.base_parameters().unwrap().rank(), 73);
    assert_eq!(builtin("psm_simplified").n_params(), 95);
}
