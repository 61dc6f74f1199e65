//! The numeric constructor (`ModelBuilder`), which a controller uses without the
//! `description` feature: this file needs none (`.ci/run` runs it with
//! `--no-default-features`). A planar two-link arm built from DH numbers, with friction
//! and a motor inertia, against the textbook closed form of its dynamics; the same arm
//! in absolute angles (a coupling `θ₂ = u₂ − u₁`, built from transforms) against the
//! chain rule; the constructor's checks.

use dvrk_model::inertia::barycentric_from_standard;
use dvrk_model::{
    Affine, Convention, ElementSpec, FrameSpec, Joint, JointKind, Model, ModelBuilder, Transform,
    Workspace,
};
use dvrk_test_support::PlanarTwoLink;

/// The links' closed form (the motor inertia and the friction are added by the tests):
/// masses, centres of mass along each link's x, moments about z at the centres of mass.
const ARM: PlanarTwoLink = PlanarTwoLink::EXAMPLE;
const FRICTION: [f64; 3] = [0.4, 0.15, -0.05]; // Fc (N·m), Fv (N·m·s/rad), Fo (N·m) of joint 1
const IA: f64 = 0.02; // kg·m², motor inertia of joint 2

fn link(name: &str, parent: &str, joint: Joint, elements: Vec<ElementSpec>) -> FrameSpec {
    let mut f = FrameSpec::new(name, parent, joint);
    f.link = true;
    f.elements = elements;
    f
}

fn dh(a: f64, theta: Affine) -> Joint {
    Joint::Dh {
        convention: Convention::Modified,
        a,
        alpha: 0.0,
        theta,
        d: Affine::constant(0.0),
    }
}

/// A two-coordinate arm in the x-y plane, gravity along −y, with its first link: joint
/// `q1` about z at the base, with friction.
fn first_link(name: &str, coordinates: &[&str]) -> ModelBuilder {
    let mut b = ModelBuilder::new(name, coordinates).unwrap();
    b.set_gravity([0.0, -ARM.gravity, 0.0]).unwrap();
    let friction = ElementSpec::Friction {
        stribeck_velocity: None,
    };
    b.add_frame(link(
        "link1",
        "base",
        dh(0.0, Affine::coordinate(0)),
        vec![friction],
    ))
    .unwrap();
    b
}

/// The arm in the x-y plane, gravity along −y, joints about z: `q1` at the base, `q2`
/// at `ARM.length` along link 1.
fn planar_arm() -> Model {
    let mut b = first_link("planar", &["q1", "q2"]);
    let motor = ElementSpec::MotorInertia;
    b.add_frame(link(
        "link2",
        "link1",
        dh(ARM.length, Affine::coordinate(1)),
        vec![motor],
    ))
    .unwrap();
    b.build().unwrap()
}

/// The parameters in the model's order: each link's barycentric block, then `Fc1 Fv1
/// Fo1` after link 1 and `Ia2` after link 2.
fn params(model: &Model) -> Vec<f64> {
    let mut p = vec![0.0; model.n_params()];
    for (i, &j) in model.link_frames().iter().enumerate() {
        let p0 = model.frame(j).inertia.unwrap();
        let izz = ARM.inertia[i];
        let inertia = [0.6 * izz, 0.0, 0.0, 0.5 * izz, 0.0, izz];
        p[p0..p0 + 10].copy_from_slice(&barycentric_from_standard(
            ARM.mass[i],
            [ARM.com[i], 0.0, 0.0],
            inertia,
        ));
    }
    for (name, v) in [
        ("Fc1", FRICTION[0]),
        ("Fv1", FRICTION[1]),
        ("Fo1", FRICTION[2]),
        ("Ia2", IA),
    ] {
        p[model.param_index(name).unwrap()] = v;
    }
    p
}

const STATES: [([f64; 2], [f64; 2], [f64; 2]); 4] = [
    ([0.4, -0.8], [1.0, -0.5], [2.0, 0.3]),
    ([-1.0, 0.6], [-2.0, 1.5], [-0.4, 4.0]),
    ([2.5, 1.9], [0.3, 0.0], [-1.0, -2.0]),
    ([0.0, 0.0], [0.0, 0.0], [0.0, 0.0]),
];

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
        "{what}: {a} against {b}"
    );
}

#[test]
fn two_link_arm_matches_the_closed_form() {
    let model = planar_arm();
    assert_eq!(model.dof(), 2);
    assert_eq!(model.n_params(), 24);
    assert_eq!(model.param_names()[10..14], ["Fc1", "Fv1", "Fo1", "L2xx"]);
    assert_eq!(model.param_names()[23], "Ia2");
    let p = params(&model);
    let mut ws = Workspace::new(&model);
    for (q, dq, ddq) in STATES {
        let mut mm = ARM.mass_matrix(q);
        mm[1][1] += IA;
        let (c, g) = (ARM.coriolis(q, dq), ARM.gravity_torque(q));

        let mut gravity = [0.0; 2];
        model.gravity_torque(&mut ws, &p, &q, &mut gravity);
        for k in 0..2 {
            close(gravity[k], g[k], "gravity");
        }

        let m = model.mass_matrix(&mut ws, &p, &q);
        for r in 0..2 {
            for s in 0..2 {
                close(m[(r, s)], mm[r][s], "mass matrix");
            }
        }
        assert_eq!(m[(0, 1)], m[(1, 0)], "mass matrix symmetric");
        assert!(
            m.clone().cholesky().is_some(),
            "mass matrix positive definite"
        );

        let mut tau = [0.0; 2];
        model.inverse_dynamics(&mut ws, &p, &q, &dq, &ddq, &mut tau);
        let sign = if dq[0] > 0.0 {
            1.0
        } else if dq[0] < 0.0 {
            -1.0
        } else {
            0.0
        };
        let friction = FRICTION[0] * sign + FRICTION[1] * dq[0] + FRICTION[2];
        for k in 0..2 {
            let expected = mm[k][0] * ddq[0]
                + mm[k][1] * ddq[1]
                + c[k]
                + g[k]
                + if k == 0 { friction } else { 0.0 };
            close(tau[k], expected, "inverse dynamics");
        }
    }
}

/// The same arm in absolute link angles `u₁ = q₁`, `u₂ = q₁ + q₂`: link 2's joint value
/// is the coupling `u₂ − u₁`, given as a transform. By virtual work its torques are
/// `τ_u = (∂q/∂u)ᵀ·τ_q = [τ₁ − τ₂, τ₂]`.
#[test]
fn a_coupled_joint_follows_the_chain_rule() {
    let relative = planar_arm();
    let mut b = first_link("absolute", &["u1", "u2"]);
    let coupled = Joint::Transform {
        kind: JointKind::Revolute,
        value: Affine {
            terms: vec![(0, -1.0), (1, 1.0)],
            offset: 0.0,
        },
        pre: Transform::trans(ARM.length, 0.0, 0.0),
        post: Transform::identity(),
    };
    b.add_frame(link("link2", "link1", coupled, vec![]))
        .unwrap();
    let absolute = b.build().unwrap();
    let mut p = params(&relative);
    p.pop(); // no motor inertia on the coupled joint (it needs one coordinate)
    let pr = {
        let mut x = p.clone();
        x.push(0.0);
        x
    };
    let (mut wr, mut wa) = (Workspace::new(&relative), Workspace::new(&absolute));
    for (q, dq, ddq) in STATES {
        let u = [q[0], q[0] + q[1]];
        let du = [dq[0], dq[0] + dq[1]];
        let ddu = [ddq[0], ddq[0] + ddq[1]];
        let (mut tq, mut tu) = ([0.0; 2], [0.0; 2]);
        relative.inverse_dynamics(&mut wr, &pr, &q, &dq, &ddq, &mut tq);
        absolute.inverse_dynamics(&mut wa, &p, &u, &du, &ddu, &mut tu);
        close(tu[0], tq[0] - tq[1], "coupled τ₁");
        close(tu[1], tq[1], "coupled τ₂");
    }
}

#[test]
fn the_numeric_constructor_checks_its_input() {
    let err = |b: Result<usize, dvrk_model::ModelError>| b.unwrap_err().to_string();
    let mut b = ModelBuilder::new("planar", &["q1", "q2"]).unwrap();
    assert_eq!(
        err(b.add_frame(link("l", "nope", dh(0.0, Affine::coordinate(0)), vec![]))),
        "numeric:planar: frame 1 (l): field `parent`: `nope` is not the base nor an earlier frame"
    );
    assert_eq!(
        err(b.add_frame(link("l", "base", dh(0.0, Affine::coordinate(5)), vec![]))),
        "numeric:planar: frame 1 (l): field `theta`: coordinate 5 does not exist (2 coordinates)"
    );
    let coupled = Affine {
        terms: vec![(0, 1.0), (1, 1.0)],
        offset: 0.0,
    };
    assert_eq!(
        err(b.add_frame(link(
            "l",
            "base",
            dh(0.0, coupled),
            vec![ElementSpec::MotorInertia]
        ))),
        "numeric:planar: frame 1 (l): field `motor_inertia`: the joint value must depend on \
         exactly one coordinate (c*q_k + const)"
    );
    let fixed = Joint::Transform {
        kind: JointKind::Fixed,
        value: Affine::coordinate(0),
        pre: Transform::identity(),
        post: Transform::identity(),
    };
    assert_eq!(
        err(b.add_frame(link("l", "base", fixed, vec![]))),
        "numeric:planar: frame 1 (l): field `value`: a fixed frame's value must be constant"
    );
    let friction = ElementSpec::Friction {
        stribeck_velocity: Some(-1.0),
    };
    assert_eq!(
        err(b.add_frame(link(
            "l",
            "base",
            dh(0.0, Affine::coordinate(0)),
            vec![friction]
        ))),
        "numeric:planar: frame 1 (l): field `stribeck_velocity`: must be positive (rad/s or \
         m/s), got -1"
    );
    assert_eq!(
        ModelBuilder::new("planar", &["q1", "q1"])
            .unwrap_err()
            .to_string(),
        "numeric:planar: top level: field `coordinates`: `q1` appears twice"
    );
    // The frames refused added nothing.
    assert_eq!(
        b.clone().build().unwrap_err().to_string(),
        "numeric:planar: frames: field ``: the model has no parameter"
    );
    let singular = Some(vec![vec![1.0, 1.0], vec![2.0, 2.0]]);
    assert_eq!(
        b.set_measured(vec!["a".into(), "b".into()], singular, None)
            .unwrap_err()
            .to_string(),
        "numeric:planar: measured: field `coupling`: the matrix is singular"
    );
}
