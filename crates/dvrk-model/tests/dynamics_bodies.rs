//! The body algorithms (mass matrix by composite rigid bodies, gravity, nonlinear
//! effects, forward dynamics by Cholesky in the workspace) against the regressor, which
//! walks the tree frame by frame and shares none of their code: the mass matrix's
//! columns are `H(q, 0, e_k)·π − H(q, 0, 0)·π` (the inverse dynamics of a unit
//! acceleration, as the mass matrix was computed before), gravity is `H(q, 0, 0)·π` and
//! the nonlinear effects `H(q, q̇, 0)·π` with the links' parameters alone. On the
//! built-in robots and on a chain with fixed links between and after moving frames
//! (merged into their moving parent).

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_test_support as support;

use dvrk_model::{Model, Workspace};
use dvrk_test_support::regressor_times;
use support::{assert_close, physical_params, random_params, random_state, rigid_only, Rng};

const SAMPLES: usize = 20;

/// A planar-ish chain where fixed frames carry links: one between two moving frames,
/// one at the tip, one on a branch, and one fixed to the base (no dynamic effect), plus
/// a coupled coordinate, friction, a spring and a motor inertia.
const FIXED_LINKS: &str = r#"
name = "fixed links"
convention = "modified"
coordinates = ["q1", "q2", "q3"]

[[frames]]
name = "shoulder"
parent = "base"
theta = "q1"
inertia = true
friction = true
motor_inertia = true

[[frames]]
name = "bracket"
parent = "shoulder"
alpha = "pi/2"
a = 0.1
theta = "0.3"
d = 0.05
inertia = true

[[frames]]
name = "elbow"
parent = "bracket"
a = 0.3
theta = "q2 - 0.5*q1"
inertia = true
spring = "q2"

[[frames]]
name = "slider"
parent = "elbow"
alpha = "-pi/2"
a = 0.2
d = "q3"
inertia = true

[[frames]]
name = "tip"
parent = "slider"
a = 0.05
d = 0.1
theta = "-0.4"
inertia = true

[[frames]]
name = "side"
parent = "elbow"
alpha = 0.7
a = -0.1
inertia = true

[[frames]]
name = "pedestal"
parent = "base"
d = 0.2
inertia = true
"#;

fn models() -> Vec<Model> {
    let mut models: Vec<Model> = Model::builtin_names()
        .iter()
        .map(|name| Model::builtin(name).unwrap())
        .collect();
    models.push(Model::from_toml_str(FIXED_LINKS, "fixed_links.toml").unwrap());
    models
}

#[test]
fn fixed_links_model_has_fixed_frames_with_links() {
    let model = Model::from_toml_str(FIXED_LINKS, "fixed_links.toml").unwrap();
    let fixed: Vec<&str> = model
        .frames
        .iter()
        .filter(|f| f.kind == dvrk_model::JointKind::Fixed && f.inertia.is_some())
        .map(|f| f.name.as_str())
        .collect();
    assert_eq!(fixed, ["bracket", "tip", "side", "pedestal"]);
}

#[test]
fn mass_matrix_columns_are_unit_acceleration_torques() {
    for (r, model) in models().iter().enumerate() {
        let n = model.dof();
        let mut ws = Workspace::new(model);
        let mut rng = Rng::new(700 + r as u64);
        let zeros = vec![0.0; n];
        let mut m = vec![0.0; n * n];
        for s in 0..SAMPLES {
            let (q, _, _) = random_state(model, &mut rng);
            // Alternate between two parameter sets: the merged inertias follow.
            let pi = if s % 2 == 0 {
                physical_params(model, &mut rng)
            } else {
                random_params(model, &mut rng)
            };
            model.mass_matrix_into(&mut ws, &pi, &q, &mut m);
            let rest = regressor_times(model, &mut ws, &q, &zeros, &zeros, &pi);
            for k in 0..n {
                let mut e = zeros.clone();
                e[k] = 1.0;
                let col: Vec<f64> = regressor_times(model, &mut ws, &q, &zeros, &e, &pi)
                    .iter()
                    .zip(&rest)
                    .map(|(a, b)| a - b)
                    .collect();
                assert_close(
                    &format!("{}: mass matrix column {k}", model.name),
                    &m[k * n..(k + 1) * n],
                    &col,
                    1e-12,
                );
            }
        }
    }
}

#[test]
fn gravity_and_nonlinear_effects_are_the_links_regressor() {
    for (r, model) in models().iter().enumerate() {
        let n = model.dof();
        let mut ws = Workspace::new(model);
        let mut rng = Rng::new(800 + r as u64);
        let zeros = vec![0.0; n];
        let (mut g, mut nle) = (vec![0.0; n], vec![0.0; n]);
        for _ in 0..SAMPLES {
            let (q, dq, _) = random_state(model, &mut rng);
            let pi = random_params(model, &mut rng);
            let links = rigid_only(model, &pi);
            model.gravity_torque(&mut ws, &pi, &q, &mut g);
            let expect = regressor_times(model, &mut ws, &q, &zeros, &zeros, &links);
            assert_close(&format!("{}: gravity", model.name), &g, &expect, 1e-12);
            model.nonlinear_effects(&mut ws, &pi, &q, &dq, &mut nle);
            let expect = regressor_times(model, &mut ws, &q, &dq, &zeros, &links);
            assert_close(
                &format!("{}: nonlinear effects", model.name),
                &nle,
                &expect,
                1e-12,
            );
        }
    }
}

#[test]
fn inverse_dynamics_is_the_regressor_on_fixed_links() {
    // The built-in robots are covered by dynamics_identities; here the merged links.
    let model = Model::from_toml_str(FIXED_LINKS, "fixed_links.toml").unwrap();
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(900);
    let mut tau = vec![0.0; model.dof()];
    for _ in 0..SAMPLES {
        let (q, dq, ddq) = random_state(&model, &mut rng);
        let pi = random_params(&model, &mut rng);
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        let expect = regressor_times(&model, &mut ws, &q, &dq, &ddq, &pi);
        assert_close("fixed links: inverse dynamics", &tau, &expect, 1e-12);
    }
}

#[test]
fn forward_dynamics_into_inverts_the_regressor() {
    for (r, model) in models().iter().enumerate() {
        let n = model.dof();
        let mut ws = Workspace::new(model);
        let mut rng = Rng::new(1000 + r as u64);
        let mut acc = vec![0.0; n];
        for _ in 0..SAMPLES {
            let (q, dq, ddq) = random_state(model, &mut rng);
            let pi = physical_params(model, &mut rng);
            let mut tau = regressor_times(model, &mut ws, &q, &dq, &ddq, &pi);
            model.add_known_forces(&q, &mut tau);
            model
                .forward_dynamics_into(&mut ws, &pi, &q, &dq, &tau, &mut acc)
                .unwrap_or_else(|e| panic!("{}: {e}", model.name));
            assert_close(
                &format!("{}: forward dynamics", model.name),
                &acc,
                &ddq,
                1e-9,
            );
            let allocating = model.forward_dynamics(&mut ws, &pi, &q, &dq, &tau).unwrap();
            assert_eq!(allocating.as_slice(), &acc[..]);
        }
    }
}

#[test]
fn forward_dynamics_refuses_a_singular_mass_matrix() {
    let model = Model::builtin("mtm").unwrap();
    let n = model.dof();
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(1100);
    let (q, dq, _) = random_state(&model, &mut rng);
    let mut pi = physical_params(&model, &mut rng);
    // No inertia at all on the wrist roll q7 (its link, any motor): M loses rank.
    let roll = model
        .frames
        .iter()
        .position(|f| f.name == "wrist_roll")
        .unwrap();
    let p0 = model.frames[roll].inertia.unwrap();
    pi[p0..p0 + 10].fill(0.0);
    for mi in model.frames.iter().filter_map(|f| f.motor_inertia()) {
        if mi.coordinate == 6 {
            pi[mi.param] = 0.0;
        }
    }
    let mut acc = vec![0.0; n];
    assert_eq!(
        model.forward_dynamics_into(&mut ws, &pi, &q, &dq, &vec![0.0; n], &mut acc),
        Err(dvrk_model::NotPositiveDefinite)
    );
    assert!(model
        .forward_dynamics(&mut ws, &pi, &q, &dq, &vec![0.0; n])
        .is_none());
}
