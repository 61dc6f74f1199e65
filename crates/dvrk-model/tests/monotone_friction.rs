//! Monotone friction (`dvrk_model::MonotoneFriction`, issue 28): saturating steps of
//! several velocities, forward and backward weights, against its closed form in the
//! regressor and the inverse dynamics; its constraint (every weight ≥ 0) makes the force
//! non-decreasing in the joint rate and dissipative for any weights that satisfy it;
//! its description syntax, errors and round trip.

// Reads descriptions (TOML): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_test_support as support;

use dvrk_model::{
    BoundOrigin, BoundsContext, Element, FrameBounds, GlobalBounds, Model, MonotoneFriction,
    ParamKind, Workspace,
};
use support::models::one_link_with;
use support::{assert_close, id, random_params, random_state, Rng};

const LINES: &str = "friction = true\nmonotone_friction = { velocities = [0.1, 0.5] }\n";

fn pendulum() -> Model {
    Model::from_toml_str(&one_link_with(LINES), "mono.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn element(model: &Model) -> &MonotoneFriction {
    model
        .frame(1)
        .elements
        .iter()
        .find_map(|e| match e {
            Element::MonotoneFriction(x) => Some(x),
            _ => None,
        })
        .expect("monotone friction element")
}

/// Columns after the ten link parameters and `Fc1 Fv1 Fo1`.
const W: usize = 13;

/// The force of weights `w` (forward, backward per velocity) at joint rate `v`,
/// written out.
fn force(w: &[f64], velocities: &[f64], v: f64) -> f64 {
    velocities
        .iter()
        .enumerate()
        .map(|(k, vk)| {
            let t = (v / vk).tanh();
            if v > 0.0 {
                w[2 * k] * t
            } else {
                w[2 * k + 1] * t
            }
        })
        .sum()
}

#[test]
fn parameters_regressor_and_torque_follow_the_closed_form() {
    let model = pendulum();
    let names: Vec<&str> = model.params[W..].iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["Fpa1", "Fna1", "Fpb1", "Fnb1"]);
    assert!(model.params[W..]
        .iter()
        .all(|p| p.kind == ParamKind::MonotoneFriction));
    assert_eq!(element(&model).velocities, [0.1, 0.5]);
    let mut ws = Workspace::new(&model);
    let p = model.n_params();
    let w = [0.2, 0.05, 0.1, 0.3];
    let mut pi = vec![0.0; p];
    pi[W..].copy_from_slice(&w);
    let mut h = vec![0.0; p];
    for v in [0.7, -0.2, 0.03, -1.5, 0.0] {
        let tau = id(&model, &mut ws, &pi, &[0.3], &[v], &[0.0]);
        // Forward weights act only forward, backward ones only backward.
        assert_close("F", &tau, &[force(&w, &[0.1, 0.5], v)], 1e-15);
        model.regressor_into(&mut ws, &[0.3], &[v], &[0.0], &mut h);
        let (a, b) = ((v / 0.1f64).tanh(), (v / 0.5f64).tanh());
        assert_eq!(&h[W..], &[a.max(0.0), a.min(0.0), b.max(0.0), b.min(0.0)]);
    }
    // No static torque: the steps vanish at rest.
    let mut rest = vec![0.0; 1];
    model.static_torque(&mut ws, &pi, &[0.3], &[1.0], &mut rest);
    let mut without = vec![0.0; 1];
    let mut pi0 = pi.clone();
    pi0[W..].fill(0.0);
    model.static_torque(&mut ws, &pi0, &[0.3], &[1.0], &mut without);
    assert_eq!(rest, without);
    let mut rng = Rng::new(28);
    for _ in 0..20 {
        let pi = random_params(&model, &mut rng);
        let (q, dq, ddq) = random_state(&model, &mut rng);
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
        let hp: f64 = (0..p).map(|c| h[c] * pi[c]).sum();
        assert_close(
            "H·pi",
            &[hp],
            &id(&model, &mut ws, &pi, &q, &dq, &ddq),
            1e-12,
        );
    }
}

/// The constraint: one lower bound 0 per weight, physical; weights that keep it give a
/// non-decreasing, dissipative force at every rate (checked on a fine grid), and a
/// negative weight is inconsistent (and its curve may fall).
#[test]
fn nonnegative_weights_keep_the_force_monotone_and_dissipative() {
    let model = pendulum();
    let e = element(&model);
    let ctx = BoundsContext {
        global: &GlobalBounds::default(),
        frame: &FrameBounds::default(),
        use_frame: true,
    };
    let mut rows = Vec::new();
    Element::MonotoneFriction(e.clone()).bound_rows(&ctx, &mut rows);
    assert_eq!(rows.len(), 4);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.coefficients, vec![(W + k, -1.0)]);
        assert_eq!(row.limit, 0.0);
        assert!(matches!(row.origin, BoundOrigin::Physical(_)));
    }
    let grid: Vec<f64> = (-3000..=3000).map(|i| i as f64 * 1e-3).collect();
    let mut rng = Rng::new(5);
    let p = model.n_params();
    for _ in 0..50 {
        let w = rng.vec(4, 0.0, 1.0);
        let mut pi = vec![0.0; p];
        pi[W..].copy_from_slice(&w);
        assert!(Element::MonotoneFriction(e.clone()).consistent(&pi, 0.0));
        let f: Vec<f64> = grid.iter().map(|&v| force(&w, &e.velocities, v)).collect();
        assert!(f.windows(2).all(|x| x[1] >= x[0]), "monotone for {w:?}");
        assert!(
            grid.iter().zip(&f).all(|(v, f)| v * f >= 0.0),
            "dissipative"
        );
    }
    // A negative weight: inconsistent, and here the curve falls (0.3·tanh(v/0.5) −
    // 0.2·tanh(v/0.1) decreases near 0).
    let mut pi = vec![0.0; p];
    pi[W..].copy_from_slice(&[-0.2, 0.0, 0.3, 0.0]);
    assert!(!Element::MonotoneFriction(e.clone()).consistent(&pi, 0.0));
    let w = &pi[W..];
    assert!(force(w, &e.velocities, 0.05) < force(w, &e.velocities, 0.0));
    // Clamping moves a solver's miss onto the bound, not a real violation.
    pi[W] = -1e-9;
    pi[W + 1] = -1e-3;
    Element::MonotoneFriction(e.clone()).clamp(&ctx, &mut pi);
    assert_eq!(pi[W], 0.0);
    assert_eq!(pi[W + 1], -1e-3);
}

#[test]
fn description_errors_name_the_field_and_the_line_round_trips() {
    let cases = [
        ("velocities = []", "give 1 to 4 velocities"),
        (
            "velocities = [0.1, 0.2, 0.3, 0.4, 0.5]",
            "give 1 to 4 velocities",
        ),
        ("velocities = [-0.1]", "must be positive"),
        ("velocities = [0.5, 0.1]", "must increase"),
        ("velocities = [0.1, 0.1]", "must increase"),
        ("velocities = [1e300]", "monotone_friction.velocities"),
        ("speeds = [0.1]", "unknown field `speeds`"),
    ];
    for (fields, needle) in cases {
        let text = one_link_with(&format!("monotone_friction = {{ {fields} }}\n"));
        let err = Model::from_toml_str(&text, "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains(needle),
            "{fields}: {err}"
        );
    }
    let model = pendulum();
    let line = Element::MonotoneFriction(element(&model).clone()).description(&model.coordinates);
    assert_eq!(line, "monotone_friction = { velocities = [0.1, 0.5] }");
    let back = Model::from_toml_str(&one_link_with(&format!("{line}\n")), "back.toml").unwrap();
    assert_eq!(element(&back).velocities, [0.1, 0.5]);
    assert_eq!(back.n_params(), 14);
}
