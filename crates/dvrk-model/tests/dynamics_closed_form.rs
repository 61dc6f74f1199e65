//! Closed-form checks of the dynamics on small hand-written descriptions: a pendulum,
//! the textbook planar two-link arm, a prismatic joint along gravity, springs, friction,
//! motor inertias on coupled frames, standard vs modified DH, known forces.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_test_support as support;

use dvrk_model::{inertia, sign0, Model, Workspace};
use dvrk_test_support::{regressor_times, PlanarTwoLink};
use support::models::one_link_with;
use support::{assert_close, id, Rng};

const G: f64 = 9.81;

fn load(text: &str) -> Model {
    Model::from_toml_str(text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

// ------------------------------------------------------------------------------------
// Single pendulum
// ------------------------------------------------------------------------------------

/// Revolute joint about the base's -y axis (alpha = pi/2, modified DH): the link's x axis
/// is (cos q, 0, sin q) and its y axis (-sin q, 0, cos q) in the base, so a centre of mass
/// at (cx, cy, cz) is at height cx·sin q + cy·cos q and
/// `tau = Lzz·q̈ + m g (cx cos q − cy sin q) + Fc sign(q̇) + Fv q̇ + Fo`, where
/// `Lzz = Izz_c + m (cx² + cy²)` is the inertia about the joint axis.
fn pendulum() -> Model {
    load(&one_link_with("friction = true\n"))
}

#[test]
fn pendulum_closed_form() {
    let model = pendulum();
    assert_eq!(model.n_params(), 13);
    assert_eq!(
        model.param_names(),
        [
            "L1xx", "L1xy", "L1xz", "L1yy", "L1yz", "L1zz", "l1x", "l1y", "l1z", "m1", "Fc1",
            "Fv1", "Fo1"
        ]
    );
    let mut ws = Workspace::new(&model);
    let (m, c) = (1.3, [0.4, -0.07, 0.12]);
    // Products of inertia and an off-axis com component must not leak into the torque.
    let ic = [0.03, 0.004, -0.006, 0.025, 0.005, 0.02];
    let (fc, fv, fo) = (0.15, 0.08, -0.03);
    let mut pi = inertia::barycentric_from_standard(m, c, ic).to_vec();
    pi.extend([fc, fv, fo]);
    let lzz = ic[5] + m * (c[0] * c[0] + c[1] * c[1]);
    assert!((pi[5] - lzz).abs() < 1e-15);

    let samples: [(f64, f64, f64); 5] = [
        (0.0, 0.0, 0.0),
        (0.3, 0.0, 0.0),
        (0.7, 1.1, -2.0),
        (-1.9, -0.4, 0.6),
        (2.8, 3.0, 1.5),
    ];
    for (q, dq, ddq) in samples {
        let expect =
            lzz * ddq + m * G * (c[0] * q.cos() - c[1] * q.sin()) + fc * sign0(dq) + fv * dq + fo;
        let tau = id(&model, &mut ws, &pi, &[q], &[dq], &[ddq]);
        assert_close("pendulum tau", &tau, &[expect], 1e-12);
        let hp = regressor_times(&model, &mut ws, &[q], &[dq], &[ddq], &pi);
        assert_close("pendulum H·pi", &hp, &[expect], 1e-12);

        let mut g = [0.0];
        model.gravity_torque(&mut ws, &pi, &[q], &mut g);
        assert_close(
            "pendulum gravity",
            &g,
            &[m * G * (c[0] * q.cos() - c[1] * q.sin())],
            1e-12,
        );
        let mm = model.mass_matrix(&mut ws, &pi, &[q]);
        assert!((mm[(0, 0)] - lzz).abs() < 1e-14, "M = {mm}");
    }

    // Horizontal arm at rest, no centre-of-mass offset along y: pure m g cx, no Coulomb.
    let tau = id(&model, &mut ws, &pi, &[0.0], &[0.0], &[0.0]);
    assert!((tau[0] - (m * G * c[0] + fo)).abs() < 1e-12);
}

// ------------------------------------------------------------------------------------
// Planar two-link arm (Spong, Hutchinson, Vidyasagar, "Robot Modeling and Control", §7.4)
// ------------------------------------------------------------------------------------

const TWO_LINK: &str = r#"
name = "two link"
convention = "modified"
coordinates = ["q1", "q2"]
gravity = [0.0, -9.81, 0.0]

[constants]
l1 = 0.7 # PlanarTwoLink::EXAMPLE's

[[frames]]
name = "link1"
parent = "base"
theta = "q1"
inertia = true

[[frames]]
name = "link2"
parent = "link1"
a = "l1"
theta = "q2"
inertia = true
"#;

#[test]
fn two_link_arm_matches_spong() {
    let model = load(TWO_LINK);
    let mut ws = Workspace::new(&model);
    let arm = PlanarTwoLink::EXAMPLE;
    // The centre of mass may sit off the plane (z) and the inertia may have products and
    // other moments: with parallel joint axes along z only Izz about the com matters.
    let p1 = inertia::barycentric_from_standard(
        arm.mass[0],
        [arm.com[0], 0.0, 0.05],
        [0.02, 0.001, 0.003, 0.03, -0.002, arm.inertia[0]],
    );
    let p2 = inertia::barycentric_from_standard(
        arm.mass[1],
        [arm.com[1], 0.0, -0.04],
        [0.01, -0.002, 0.001, 0.015, 0.004, arm.inertia[1]],
    );
    let pi: Vec<f64> = p1.iter().chain(&p2).copied().collect();

    let mut rng = Rng::new(7);
    for _ in 0..20 {
        let q = rng.vec(2, -3.0, 3.0);
        let dq = rng.vec(2, -2.0, 2.0);
        let ddq = rng.vec(2, -4.0, 4.0);
        let (q2, dq2) = ([q[0], q[1]], [dq[0], dq[1]]);
        let mm = arm.mass_matrix(q2);
        let c = arm.coriolis(q2, dq2);
        let g = arm.gravity_torque(q2);
        let expect = arm.torque(q2, dq2, [ddq[0], ddq[1]]);
        let tau = id(&model, &mut ws, &pi, &q, &dq, &ddq);
        assert_close("two-link tau", &tau, &expect, 1e-12);
        let hp = regressor_times(&model, &mut ws, &q, &dq, &ddq, &pi);
        assert_close("two-link H·pi", &hp, &expect, 1e-12);

        let m = model.mass_matrix(&mut ws, &pi, &q);
        for r in 0..2 {
            for k in 0..2 {
                assert!(
                    (m[(r, k)] - mm[r][k]).abs() < 1e-13,
                    "M({r},{k}) = {} vs {}",
                    m[(r, k)],
                    mm[r][k]
                );
            }
        }
        let mut gt = [0.0; 2];
        model.gravity_torque(&mut ws, &pi, &q, &mut gt);
        assert_close("two-link gravity", &gt, &g, 1e-12);
        // Coriolis alone: no gravity term is isolated by the difference.
        let no_acc = id(&model, &mut ws, &pi, &q, &dq, &[0.0, 0.0]);
        let cg: Vec<f64> = (0..2).map(|r| c[r] + g[r]).collect();
        assert_close("two-link C+g", &no_acc, &cg, 1e-12);
        // Forward dynamics gives back the accelerations.
        let acc = model
            .forward_dynamics(&mut ws, &pi, &q, &dq, &expect)
            .unwrap();
        assert_close("two-link forward dynamics", acc.as_slice(), &ddq, 1e-10);
    }
}

// ------------------------------------------------------------------------------------
// Prismatic joint along gravity
// ------------------------------------------------------------------------------------

/// A vertical revolute joint (q1) carrying a prismatic joint along the vertical (q2),
/// 0.2 m off the axis. The slider's vertical force is `m (q̈2 + g)` whatever the rotation,
/// and the rotation sees a constant inertia `Izz_c + m ρ²` (ρ = horizontal distance of the
/// com from the axis) and no Coriolis term (the slide does not change ρ).
const VERTICAL_SLIDER: &str = include_str!("fixtures/vertical_slider.toml");

#[test]
fn prismatic_along_gravity() {
    let model = load(VERTICAL_SLIDER);
    assert_eq!(model.coordinate_is_length, [false, true]);
    let mut ws = Workspace::new(&model);
    let (m, c) = (0.9, [0.1, 0.05, 0.02]);
    let ic = [0.003, 0.0002, -0.0004, 0.004, 0.0001, 0.005];
    let pi = inertia::barycentric_from_standard(m, c, ic);
    // Frame 2 is rotated by theta = 0.3 about z from the turntable, 0.2 m along its x:
    // the com's horizontal position in the turntable frame is (0.2, 0) + Rz(0.3)(cx, cy).
    let (s, co) = 0.3f64.sin_cos();
    let rx = 0.2 + co * c[0] - s * c[1];
    let ry = s * c[0] + co * c[1];
    let j = ic[5] + m * (rx * rx + ry * ry);
    let mut rng = Rng::new(11);
    for _ in 0..10 {
        let q = rng.vec(2, -2.0, 2.0);
        let dq = rng.vec(2, -2.0, 2.0);
        let ddq = rng.vec(2, -5.0, 5.0);
        let tau = id(&model, &mut ws, &pi, &q, &dq, &ddq);
        assert_close("slider tau", &tau, &[j * ddq[0], m * (ddq[1] + G)], 1e-12);
    }

    // Upside down (alpha = pi): the joint axis points down, tau = m (q̈ − g).
    let flipped = load(
        r#"
name = "hanging slider"
convention = "modified"
coordinates = ["q1"]
[[frames]]
name = "slider"
parent = "base"
alpha = "pi"
d = "q1"
inertia = true
"#,
    );
    let mut ws = Workspace::new(&flipped);
    let pi = inertia::barycentric_from_standard(
        2.5,
        [0.3, -0.2, 0.1],
        [0.01, 0.0, 0.0, 0.01, 0.0, 0.01],
    );
    for (q, dq, ddq) in [(0.0, 0.0, 0.0), (0.4, -1.0, 2.0), (-0.3, 0.5, -7.0)] {
        let tau = id(&flipped, &mut ws, &pi, &[q], &[dq], &[ddq]);
        assert_close("hanging slider", &tau, &[2.5 * (ddq - G)], 1e-12);
        let mut g = [0.0];
        flipped.gravity_torque(&mut ws, &pi, &[q], &mut g);
        assert_close("hanging slider gravity", &g, &[-2.5 * G], 1e-12);
    }
}

// ------------------------------------------------------------------------------------
// Springs, friction, motor inertias
// ------------------------------------------------------------------------------------

const ELEMENTS: &str = r#"
name = "elements"
convention = "modified"
coordinates = ["q1", "q2"]

# tau -= a·K1·dl with a = [1, 0], dl = -q1: tau1 += K1·q1
[[frames]]
name = "spring1"
parent = "base"
theta = "q1"
spring = "-q1"

# coupled frame s = 2 q1 - q2 + 0.1, nonlinear deflection
[[frames]]
name = "spring2"
parent = "base"
theta = "2*q1 - q2 + 0.1"
spring = "q2^2 + sin(q1)"

# friction on a coupled revolute value s = 2 q1 - q2
[[frames]]
name = "friction_coupled"
parent = "base"
theta = "2*q1 - q2"
friction = true

# friction on a prismatic value s = q2
[[frames]]
name = "friction_slide"
parent = "base"
d = "q2"
friction = true

# motor inertias: s = 1.5 q1 + 0.3 and s = -2 q2
[[frames]]
name = "motor1"
parent = "base"
theta = "1.5*q1 + 0.3"
motor_inertia = true

[[frames]]
name = "motor2"
parent = "base"
theta = "-2*q2"
motor_inertia = true
"#;

/// Parameters in model order: K1, K2, Fc3, Fv3, Fo3, Fc4, Fv4, Fo4, Ia5, Ia6.
const ELEMENT_PARAMS: [f64; 10] = [3.0, 0.7, 0.2, 0.5, 0.05, 0.4, 1.5, -0.1, 0.02, 0.03];

fn elements_expected(q: &[f64], dq: &[f64], ddq: &[f64]) -> [f64; 2] {
    let [k1, k2, fc3, fv3, fo3, fc4, fv4, fo4, ia5, ia6] = ELEMENT_PARAMS;
    let mut tau = [0.0; 2];
    // springs
    tau[0] += k1 * q[0];
    let dl2 = q[1] * q[1] + q[0].sin();
    tau[0] -= 2.0 * k2 * dl2;
    tau[1] -= -k2 * dl2;
    // friction on s = 2 q1 - q2
    let sd = 2.0 * dq[0] - dq[1];
    let f3 = fc3 * sign0(sd) + fv3 * sd + fo3;
    tau[0] += 2.0 * f3;
    tau[1] -= f3;
    // friction on s = q2
    tau[1] += fc4 * sign0(dq[1]) + fv4 * dq[1] + fo4;
    // motor inertias, 2019 convention c·Ia·q̈
    tau[0] += 1.5 * ia5 * ddq[0];
    tau[1] += -2.0 * ia6 * ddq[1];
    tau
}

#[test]
fn springs_friction_motor_inertia() {
    let model = load(ELEMENTS);
    assert_eq!(
        model.param_names(),
        ["K1", "K2", "Fc3", "Fv3", "Fo3", "Fc4", "Fv4", "Fo4", "Ia5", "Ia6"]
    );
    let mi = model.frame(5).motor_inertia().unwrap();
    assert_eq!((mi.coordinate, mi.ratio), (0, 1.5));
    let mi = model.frame(6).motor_inertia().unwrap();
    assert_eq!((mi.coordinate, mi.ratio), (1, -2.0));
    let pi = ELEMENT_PARAMS.to_vec();
    let mut ws = Workspace::new(&model);
    let samples: [([f64; 2], [f64; 2], [f64; 2]); 5] = [
        ([0.4, -0.3], [0.7, -0.2], [1.0, 2.0]),
        ([-1.1, 0.8], [-0.3, 0.9], [-0.5, 0.25]),
        // 2·0.5 − 1.0 = 0 exactly: the coupled value is at rest, no Coulomb term there.
        ([0.2, 0.1], [0.5, 1.0], [0.0, 0.0]),
        // everything at rest: only springs and offsets
        ([0.3, -0.6], [0.0, 0.0], [0.0, 0.0]),
        ([0.0, 0.0], [0.0, 0.0], [3.0, -1.0]),
    ];
    for (q, dq, ddq) in samples {
        let expect = elements_expected(&q, &dq, &ddq);
        let tau = id(&model, &mut ws, &pi, &q, &dq, &ddq);
        assert_close("elements tau", &tau, &expect, 1e-13);
        let hp = regressor_times(&model, &mut ws, &q, &dq, &ddq, &pi);
        assert_close("elements H·pi", &hp, &expect, 1e-13);
    }

    // Spring alone, the brief's example: dl = -q1 gives +K q1.
    let only_k1: Vec<f64> = (0..10).map(|k| if k == 0 { 2.5 } else { 0.0 }).collect();
    let tau = id(&model, &mut ws, &only_k1, &[0.8, 0.0], &[0.0; 2], &[0.0; 2]);
    assert_close("spring +K q1", &tau, &[2.5 * 0.8, 0.0], 1e-15);

    // sign(0) = 0: at rest the Coulomb column of the regressor is exactly zero.
    let p = model.n_params();
    let mut h = vec![0.0; 2 * p];
    model.regressor_into(&mut ws, &[0.2, 0.1], &[0.5, 1.0], &[0.0; 2], &mut h);
    assert_eq!((h[2], h[p + 2]), (0.0, 0.0), "Fc3 columns with s' = 0");
    assert_eq!((h[3], h[p + 3]), (0.0, 0.0), "Fv3 columns with s' = 0");
    assert_eq!((h[4], h[p + 4]), (2.0, -1.0), "Fo3 columns");
    assert_eq!((h[5], h[p + 5]), (0.0, 1.0), "Fc4 columns with s' = 1");

    // Mass matrix: the motor inertias only, c·Ia on the diagonal.
    let m = model.mass_matrix(&mut ws, &pi, &[0.3, 0.4]);
    assert!((m[(0, 0)] - 1.5 * 0.02).abs() < 1e-15);
    assert!((m[(1, 1)] + 2.0 * 0.03).abs() < 1e-15);
    assert_eq!((m[(0, 1)], m[(1, 0)]), (0.0, 0.0));
    // gravity_torque has no spring nor friction term.
    let mut g = [1.0; 2];
    model.gravity_torque(&mut ws, &pi, &[0.3, 0.4], &mut g);
    assert_eq!(g, [0.0, 0.0]);
}

/// A motor inertia on a frame that also carries a link: the link's inertia about the
/// axis enters as c²·Lzz (through Aᵀ), the motor inertia as c·Ia.
#[test]
fn motor_inertia_on_coupled_link_frame() {
    let model = load(
        r#"
name = "geared"
convention = "modified"
coordinates = ["q1"]
gravity = [0.0, 0.0, 0.0]
[[frames]]
name = "rotor"
parent = "base"
theta = "0.25*q1 - 1.0"
inertia = true
motor_inertia = true
"#,
    );
    let mut ws = Workspace::new(&model);
    let mut pi = inertia::barycentric_from_standard(
        0.5,
        [0.1, 0.0, 0.0],
        [0.001, 0.0, 0.0, 0.002, 0.0, 0.003],
    )
    .to_vec();
    let lzz = pi[5];
    pi.push(0.04);
    for ddq in [1.0, -2.5] {
        let tau = id(&model, &mut ws, &pi, &[0.7], &[0.0], &[ddq]);
        let expect = 0.25 * 0.25 * lzz * ddq + 0.25 * 0.04 * ddq;
        assert_close("geared", &tau, &[expect], 1e-14);
    }
}

// ------------------------------------------------------------------------------------
// Standard DH equals its modified-DH equivalent
// ------------------------------------------------------------------------------------

/// Standard DH: frame i = RotZ(θi)·TransZ(di)·TransX(ai)·RotX(αi) from frame i−1.
const STANDARD_RPR: &str = include_str!("fixtures/rpr_standard.toml");

/// The same chain in modified DH (RotX(α)·TransX(a)·RotZ(θ)·TransZ(d)): each standard
/// frame is a moving frame (θ, d) followed by a fixed frame (α, a) that carries the link,
/// since TransX(a)·RotX(α) = RotX(α)·TransX(a).
const MODIFIED_RPR: &str = include_str!("fixtures/rpr_modified.toml");

/// Hand-written standard DH transform, for the poses.
fn dh_standard(theta: f64, d: f64, a: f64, alpha: f64) -> nalgebra::Matrix4<f64> {
    let (st, ct) = theta.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    nalgebra::Matrix4::new(
        ct,
        -st * ca,
        st * sa,
        a * ct,
        st,
        ct * ca,
        -ct * sa,
        a * st,
        0.0,
        sa,
        ca,
        d,
        0.0,
        0.0,
        0.0,
        1.0,
    )
}

#[test]
fn standard_dh_equals_modified_equivalent() {
    let std_model = load(STANDARD_RPR);
    let mod_model = load(MODIFIED_RPR);
    assert_eq!(std_model.n_params(), 30);
    assert_eq!(mod_model.n_params(), 30);
    assert_eq!(std_model.coordinate_is_length, [false, true, false]);
    let mut ws_s = Workspace::new(&std_model);
    let mut ws_m = Workspace::new(&mod_model);
    let mut rng = Rng::new(3);
    let pi = support::physical_params(&std_model, &mut rng);
    let pi_arbitrary = support::random_params(&std_model, &mut rng);
    for _ in 0..10 {
        let q = rng.vec(3, -1.5, 1.5);
        let dq = rng.vec(3, -2.0, 2.0);
        let ddq = rng.vec(3, -3.0, 3.0);
        for params in [&pi, &pi_arbitrary] {
            let ts = id(&std_model, &mut ws_s, params, &q, &dq, &ddq);
            let tm = id(&mod_model, &mut ws_m, params, &q, &dq, &ddq);
            assert_close("standard vs modified tau", &ts, &tm, 1e-12);
            let ms = std_model.mass_matrix(&mut ws_s, params, &q);
            let mm = mod_model.mass_matrix(&mut ws_m, params, &q);
            assert!((ms - mm).abs().max() < 1e-12);
        }
        // Poses: standard frame i = modified frame 2i; and the hand-written DH product.
        std_model.forward_kinematics(&mut ws_s, &q);
        mod_model.forward_kinematics(&mut ws_m, &q);
        let dh = [
            (q[0] + 0.1, 0.3, 0.2, std::f64::consts::FRAC_PI_2),
            (0.4, q[1] + 0.05, 0.1, -std::f64::consts::FRAC_PI_2),
            (q[2] - 0.2, 0.07, 0.15, std::f64::consts::FRAC_PI_3),
        ];
        let mut t = nalgebra::Matrix4::<f64>::identity();
        for (i, &(th, d, a, al)) in dh.iter().enumerate() {
            t *= dh_standard(th, d, a, al);
            let ps = ws_s.pose(i + 1).to_homogeneous();
            let pm = ws_m.pose(2 * i + 2).to_homogeneous();
            for r in 0..4 {
                for c in 0..4 {
                    assert!((ps[r][c] - pm[r][c]).abs() < 1e-13, "frame {} pose", i + 1);
                    assert!(
                        (ps[r][c] - t[(r, c)]).abs() < 1e-13,
                        "frame {} vs DH product",
                        i + 1
                    );
                }
            }
        }
    }
}

// ------------------------------------------------------------------------------------
// Known forces
// ------------------------------------------------------------------------------------

/// Friction on q1; known polynomial forces along q2 (`p = 0.5 s³ − s² + 2 s + 0.25`) and,
/// on a fixed frame, along `s = q1 − 3 q2 + 0.2` (`p = 3 s + 1`).
const KNOWN: &str = include_str!("fixtures/known_forces.toml");

#[test]
fn known_force_polynomial() {
    let model = load(KNOWN);
    assert!(model.has_known_forces());
    assert!(!pendulum().has_known_forces());
    let mut rng = Rng::new(5);
    for _ in 0..10 {
        let q = rng.vec(2, -2.0, 2.0);
        let s = q[1];
        let p1 = 0.5 * s * s * s - s * s + 2.0 * s + 0.25;
        let s2 = q[0] - 3.0 * q[1] + 0.2;
        let p2 = 3.0 * s2 + 1.0;
        let mut tau = [10.0, 20.0];
        model.add_known_forces(&q, &mut tau);
        assert_close(
            "known forces (added)",
            &tau,
            &[10.0 + p2, 20.0 + p1 - 3.0 * p2],
            1e-13,
        );
        // Not part of the inverse dynamics.
        let pi = [0.0f64; 3];
        let t = id(
            &model,
            &mut Workspace::new(&model),
            &pi,
            &q,
            &[0.0; 2],
            &[0.0; 2],
        );
        assert_eq!(t, [0.0, 0.0]);
    }
}

// ------------------------------------------------------------------------------------
// The built-in robots' springs
// ------------------------------------------------------------------------------------

#[test]
fn builtin_springs_closed_form() {
    // PSM tool roll: deflection -q4 on s = q4, tau4 = K·q4.
    let psm = Model::builtin("psm").unwrap();
    let mut pi = vec![0.0; psm.n_params()];
    pi[psm.param_index("K10").unwrap()] = 0.3;
    let q = [0.1, 0.2, 0.12, 0.8, 0.3, -0.2, 0.4];
    let tau = id(
        &psm,
        &mut Workspace::new(&psm),
        &pi,
        &q,
        &[0.5; 7],
        &[0.7; 7],
    );
    assert_close(
        "psm spring",
        &tau,
        &[0.0, 0.0, 0.0, 0.3 * 0.8, 0.0, 0.0, 0.0],
        1e-15,
    );

    // MTM wrist pitch gravity-compensation spring on s = q5:
    // l = sqrt(r_s² + h_s² − 2 r_s h_s cos φ), φ = π + q_o − q5, dl = r_s h_s sin φ / l · (l − l_r)
    let mtm = Model::builtin("mtm").unwrap();
    let mut pi = vec![0.0; mtm.n_params()];
    let k = 270.0;
    pi[mtm.param_index("K7").unwrap()] = k;
    let (r_s, h_s, l_r, q_o) = (0.0075, 0.1035, 0.0613, 23f64.to_radians());
    let mut ws = Workspace::new(&mtm);
    for q5 in [-1.2, 0.0, 0.4, 1.9, 3.0] {
        let q = [0.2, 0.3, 0.1, -0.5, q5, 0.2, 1.0];
        let phi = std::f64::consts::PI + q_o - q5;
        let l = (r_s * r_s + h_s * h_s - 2.0 * r_s * h_s * phi.cos()).sqrt();
        let dl = r_s * h_s * phi.sin() / l * (l - l_r);
        let tau = id(&mtm, &mut ws, &pi, &q, &[0.0; 7], &[0.0; 7]);
        assert_close(
            "mtm spring",
            &tau,
            &[0.0, 0.0, 0.0, 0.0, -k * dl, 0.0, 0.0],
            1e-13,
        );
    }
}

// ------------------------------------------------------------------------------------
// Stribeck friction
// ------------------------------------------------------------------------------------

/// `Fs·sign(ṡ)·exp(−(ṡ/vs)²)` on a coupled value, from the description and from
/// `with_stribeck`, equal to the closed form in inverse dynamics and in `H·π`.
#[test]
fn stribeck_friction_closed_form() {
    let described = load(&ELEMENTS.replace(
        "theta = \"2*q1 - q2\"\nfriction = true",
        "theta = \"2*q1 - q2\"\nfriction = true\nstribeck_velocity = 0.2",
    ));
    assert_eq!(described.param_names().last().unwrap(), "Fs3");
    assert_eq!(described.n_params(), 11);
    let all = load(ELEMENTS).with_stribeck(0.2).unwrap();
    assert_eq!(&all.param_names()[10..], ["Fs3", "Fs4"]);
    assert!(load(ELEMENTS).with_stribeck(0.0).is_err());
    assert!(all.clone().add_stribeck(3, 0.1).is_err(), "already has one");
    assert!(
        all.clone().add_stribeck(1, 0.1).is_err(),
        "frame 1 has no friction"
    );

    let (fs3, fs4, vs) = (0.3, -0.15, 0.2);
    let mut pi = ELEMENT_PARAMS.to_vec();
    pi.extend([fs3, fs4]);
    let mut ws = Workspace::new(&all);
    for (q, dq, ddq) in [
        ([0.4, -0.3], [0.07, -0.02], [1.0, 2.0]),
        ([-1.1, 0.8], [-0.3, 0.9], [-0.5, 0.25]),
        ([0.2, 0.1], [0.5, 1.0], [0.0, 0.0]),
    ] {
        let mut expect = elements_expected(&q, &dq, &ddq);
        let sd3 = 2.0 * dq[0] - dq[1];
        let f3 = fs3 * sign0(sd3) * (-(sd3 / vs).powi(2)).exp();
        expect[0] += 2.0 * f3;
        expect[1] -= f3;
        expect[1] += fs4 * sign0(dq[1]) * (-(dq[1] / vs).powi(2)).exp();
        let tau = id(&all, &mut ws, &pi, &q, &dq, &ddq);
        assert_close("stribeck tau", &tau, &expect, 1e-13);
        let hp = regressor_times(&all, &mut ws, &q, &dq, &ddq, &pi);
        assert_close("stribeck H·pi", &hp, &expect, 1e-13);
    }

    let err = Model::from_toml_str(
        &ELEMENTS.replace(
            "name = \"motor1\"",
            "name = \"motor1\"\nstribeck_velocity = 0.1",
        ),
        "stribeck.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("stribeck.toml") && err.contains("stribeck_velocity"),
        "{err}"
    );
    let err = Model::from_toml_str(
        &ELEMENTS.replace(
            "d = \"q2\"\nfriction = true",
            "d = \"q2\"\nfriction = true\nstribeck_velocity = -1",
        ),
        "neg.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("must be positive"), "{err}");
}
