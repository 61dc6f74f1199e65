//! The element abstraction (`dvrk_model::Element`): the quadratic viscous friction
//! `Fq·ṡ·|ṡ|`, added in one module, against its closed form in every algorithm that
//! visits elements (inverse dynamics, regressor, forward dynamics, static torque, nominal
//! values, bounds, clamping, consistency, description syntax); and, for every element of
//! the built-in robots, the invariants each element must keep (its columns partition the
//! non-link parameters, its description line reads back as itself).

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_test_support as support;

use dvrk_model::{
    BoundOrigin, BoundRow, BoundsContext, Deflection, Element, FrameBounds, GlobalBounds, Model,
    ParamKind, QuadraticViscous, UnitClass, Workspace,
};
use support::{assert_close, id, random_params, random_state, Rng};

fn load(text: &str) -> Model {
    Model::from_toml_str(text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// A link on q1 with friction and quadratic viscous friction (nominal 0.02, at most
/// 0.5), quadratic viscous friction alone on the coupled value `s = 2·q1 − q2`, and a
/// sliding link on q2 so that the mass matrix is positive definite.
const DRAG: &str = include_str!("fixtures/drag.toml");

/// Columns of `Fq1`, `Fq2`.
const FQ1: usize = 13;
const FQ2: usize = 14;

fn quadratic(model: &Model, frame: usize) -> &QuadraticViscous {
    model
        .frame(frame)
        .elements
        .iter()
        .find_map(|e| match e {
            Element::QuadraticViscous(x) => Some(x),
            _ => None,
        })
        .expect("quadratic viscous element")
}

#[test]
fn quadratic_viscous_parameters_follow_the_frame_order() {
    let model = load(DRAG);
    let names = model.param_names();
    assert_eq!(model.n_params(), 25);
    assert_eq!(&names[10..15], ["Fc1", "Fv1", "Fo1", "Fq1", "Fq2"]);
    for k in [FQ1, FQ2] {
        assert_eq!(model.params[k].kind, ParamKind::QuadraticViscous);
        assert_eq!(
            model.params[k].kind.unit_class(),
            UnitClass::QuadraticViscous
        );
    }
    assert_eq!(quadratic(&model, 1).param, FQ1);
    assert_eq!(quadratic(&model, 2).param, FQ2);
    assert_eq!(quadratic(&model, 1).max, Some(0.5));
    // Rows of the coupled value: both coordinates see Fq2, only q1 sees Fq1.
    let pattern = model.regressor_pattern();
    assert!(pattern[0].contains(&FQ1) && pattern[0].contains(&FQ2));
    assert!(!pattern[1].contains(&FQ1) && pattern[1].contains(&FQ2));
    let labels: Vec<&str> = model
        .frame(1)
        .elements
        .iter()
        .flat_map(|e| e.labels().iter().copied())
        .collect();
    assert_eq!(labels, ["friction", "quadratic_viscous"]);
}

/// `τ = aᵀ·Fq·ṡ·|ṡ|`: with every other parameter zero, `τ1 = Fq1·q̇1|q̇1| + 2·Fq2·ṡ|ṡ|`,
/// `τ2 = −Fq2·ṡ|ṡ|` with `ṡ = 2·q̇1 − q̇2`; in inverse dynamics and in `H·π`, and `H·π`
/// equals inverse dynamics for random parameters.
#[test]
fn quadratic_viscous_closed_form() {
    let model = load(DRAG);
    let mut ws = Workspace::new(&model);
    let (n, p) = (model.dof(), model.n_params());
    let (fq1, fq2): (f64, f64) = (0.3, 0.07);
    let mut pi = vec![0.0; p];
    pi[FQ1] = fq1;
    pi[FQ2] = fq2;
    let mut h = vec![0.0; n * p];
    for (q, dq, ddq) in [
        ([0.4, -0.3], [0.7, -0.2], [1.0, 2.0]),
        ([-1.1, 0.8], [-0.3, 0.9], [-0.5, 0.25]),
        ([0.2, 0.1], [0.0, 0.0], [0.3, 0.0]),
    ] {
        let (q, dq, ddq): ([f64; 2], [f64; 2], [f64; 2]) = (q, dq, ddq);
        let sd = 2.0 * dq[0] - dq[1];
        let expect = [
            fq1 * dq[0] * dq[0].abs() + 2.0 * fq2 * sd * sd.abs(),
            -fq2 * sd * sd.abs(),
        ];
        assert_close(
            "Fq tau",
            &id(&model, &mut ws, &pi, &q, &dq, &ddq),
            &expect,
            1e-15,
        );
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
        assert_eq!(h[FQ1], dq[0] * dq[0].abs());
        assert_eq!(h[FQ2], 2.0 * sd * sd.abs());
        assert_eq!(h[p + FQ1], 0.0);
        assert_eq!(h[p + FQ2], -(sd * sd.abs()));
    }
    let mut rng = Rng::new(13);
    for _ in 0..20 {
        let pi = random_params(&model, &mut rng);
        let (q, dq, ddq) = random_state(&model, &mut rng);
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
        let hp: Vec<f64> = (0..n)
            .map(|r| (0..p).map(|c| h[r * p + c] * pi[c]).sum())
            .collect();
        assert_close("H·pi", &hp, &id(&model, &mut ws, &pi, &q, &dq, &ddq), 1e-12);
    }
}

/// Forward dynamics inverts the inverse dynamics with the drag in it, and the static
/// torque has none of it (the force vanishes at rest).
#[test]
fn quadratic_viscous_forward_and_static() {
    let model = load(DRAG);
    let mut ws = Workspace::new(&model);
    let mut pi = model.nominal_parameters().expect("every nominal value");
    pi[FQ2] = 0.4;
    let (q, dq, ddq) = ([0.3, -0.2], [1.5, -0.7], [0.4, -1.2]);
    let tau = id(&model, &mut ws, &pi, &q, &dq, &ddq);
    let mut acc = [0.0; 2];
    model
        .forward_dynamics_into(&mut ws, &pi, &q, &dq, &tau, &mut acc)
        .unwrap();
    assert_close("forward dynamics", &acc, &ddq, 1e-10);

    let mut without = pi.clone();
    without[FQ1] = 0.0;
    without[FQ2] = 0.0;
    let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
    model.static_torque(&mut ws, &pi, &q, &[1.0, -1.0], &mut a);
    model.static_torque(&mut ws, &without, &q, &[1.0, -1.0], &mut b);
    assert_eq!(a, b);
}

/// The nominal value comes from the element's own syntax (0 when not given).
#[test]
fn quadratic_viscous_nominal() {
    let model = load(DRAG);
    let pi = model.nominal_parameters().expect("every nominal value");
    assert_eq!(pi[FQ1], 0.02);
    assert_eq!(pi[FQ2], 0.0);
}

/// `Fq ≥ 0` always, `Fq ≤ max` with the frame's bounds; clamping moves a solver's
/// rounding onto them and leaves a real miss visible; consistency is `Fq ≥ tol`.
#[test]
fn quadratic_viscous_bounds_and_clamping() {
    let model = load(DRAG);
    let e = &model.frame(1).elements[1];
    let (global, frame) = (GlobalBounds::PHYSICAL, FrameBounds::default());
    let with = BoundsContext {
        global: &global,
        frame: &frame,
        use_frame: true,
    };
    let without = BoundsContext {
        use_frame: false,
        ..with
    };
    let mut rows = Vec::new();
    e.bound_rows(&with, &mut rows);
    assert_eq!(
        rows,
        [
            BoundRow::at_least(FQ1, 0.0, BoundOrigin::Physical("Fq ≥ 0")),
            BoundRow::at_most(FQ1, 0.5, BoundOrigin::Frame("quadratic_viscous.max")),
        ]
    );
    rows.clear();
    e.bound_rows(&without, &mut rows);
    assert_eq!(rows.len(), 1);

    let mut pi = vec![0.0; model.n_params()];
    for (v, ctx, want) in [
        (-1e-9, &with, 0.0),
        (0.5 + 1e-9, &with, 0.5),
        (0.5 + 1e-9, &without, 0.5 + 1e-9),
        (-1e-3, &with, -1e-3),
    ] {
        pi[FQ1] = v;
        e.clamp(ctx, &mut pi);
        assert_eq!(pi[FQ1], want, "clamp of {v}");
    }
    pi[FQ1] = -1e-10;
    assert!(e.consistent(&pi, -1e-9));
    assert!(!e.consistent(&pi, 0.0));
}

/// Errors name the file, the frame and the field.
#[test]
fn quadratic_viscous_description_errors() {
    let cases = [
        // A fixed frame has no joint value to act on.
        (
            DRAG.replace("theta = \"2*q1 - q2\"\n", ""),
            &["frame 2 (coupled)", "quadratic_viscous", "moving frame"][..],
        ),
        (
            DRAG.replace("max = 0.5", "max = -0.5"),
            &["frame 1 (link)", "quadratic_viscous.max", "below"][..],
        ),
        (
            DRAG.replace("max = 0.5", "max = 1e300"),
            &["quadratic_viscous.max"][..],
        ),
        (
            DRAG.replace("quadratic_viscous = true", "quadratic_viscous = \"yes\""),
            &["bad.toml"][..],
        ),
        (DRAG.replace("max = 0.5", "min = 0.5"), &["bad.toml"][..]),
        (
            DRAG.replace("quadratic_viscous = true", "quadratic_viscosity = true"),
            &["bad.toml", "unknown field `quadratic_viscosity`"][..],
        ),
    ];
    for (text, needles) in cases {
        let err = Model::from_toml_str(&text, "bad.toml")
            .unwrap_err()
            .to_string();
        for needle in needles {
            assert!(err.contains(needle), "`{needle}` not in: {err}");
        }
    }
    // `false` is no element.
    let off = load(&DRAG.replace("quadratic_viscous = true", "quadratic_viscous = false"));
    assert_eq!(off.n_params(), 24);
    assert!(off.frame(2).elements.is_empty());
}

/// Every element's description line, put back on a frame with the same joint value,
/// reads back as the same element (same line, same labels; nonlinear spring deflections
/// excepted, their text names the file's constants); and the elements' columns
/// and the link blocks partition the parameter vector. For the built-in robots (with
/// Stribeck terms) and the quadratic viscous example.
#[test]
fn element_description_round_trip_and_columns() {
    let mut models: Vec<Model> = Model::builtin_names()
        .iter()
        .map(|name| Model::builtin(name).unwrap().with_stribeck(0.3).unwrap())
        .collect();
    models.push(load(DRAG).with_stribeck(0.3).unwrap());
    let mut checked = 0;
    for model in &models {
        let mut owner = vec![0usize; model.n_params()];
        for (i, f) in model.frames.iter().enumerate() {
            if let Some(p0) = f.inertia {
                owner[p0..p0 + 10].iter_mut().for_each(|o| *o += 1);
            }
            for e in &f.elements {
                for c in e.columns() {
                    owner[c] += 1;
                }
                for (c, param) in e.columns().into_iter().zip(e.params(i + 1)) {
                    assert_eq!(model.params[c].name, param.name);
                    assert_eq!(model.params[c].kind, param.kind);
                }
                // A nonlinear deflection is written as its source text, which names
                // the description's constants: it reads back only in its own file.
                if let Element::Spring(s) = e {
                    if matches!(s.deflection, Deflection::Expr(_)) {
                        continue;
                    }
                }
                let line = e.description(&model.coordinates);
                let joint = match f.kind {
                    dvrk_model::JointKind::Prismatic => "d",
                    _ => "theta",
                };
                let text = format!(
                    "name = \"one\"\nconvention = \"modified\"\ncoordinates = {:?}\n\n\
                     [[frames]]\nname = \"f\"\nparent = \"base\"\ninertia = true\n{joint} = \"{}\"\n{line}\n",
                    model.coordinates,
                    f.value.display(&model.coordinates)
                );
                let back = Model::from_toml_str(&text, "round-trip.toml")
                    .unwrap_or_else(|e| panic!("{}: {line}: {e}", model.name))
                    .with_stribeck(0.3)
                    .unwrap();
                let e2 = &back.frame(1).elements[0];
                assert_eq!(e2.description(&model.coordinates), line, "{}", model.name);
                assert_eq!(e2.labels(), e.labels());
                checked += 1;
            }
        }
        assert!(
            owner.iter().all(|&o| o == 1),
            "{}: every parameter in exactly one link or element",
            model.name
        );
    }
    assert!(checked > 30, "{checked} elements checked");
}

/// `|a − b| ≤ tol`.
fn near(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

/// `Σ aₖ·bₖ`: a regressor row times the parameters (`H·π`), or columns times coefficients.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `pi` with the parameters `cols` (an element's) set to zero: the model without it.
fn zeroed(pi: &[f64], cols: std::ops::Range<usize>) -> Vec<f64> {
    let mut without = pi.to_vec();
    without[cols].fill(0.0);
    without
}

/// A pendulum ([`support::models::ONE_LINK`]) with friction and `element` (its
/// description line), whose parameters follow `Fc1 Fv1 Fo1` from column 13.
fn pendulum_with(element: &str) -> Model {
    load(&support::models::one_link_with(&format!(
        "friction = true\n{element}\n"
    )))
}

/// The pendulum's last element (the one [`pendulum_with`] adds) and its bound rows
/// under the default bounds, the frame's included.
fn element_rows(model: &Model) -> (Element, Vec<BoundRow>) {
    let e = model.frame(1).elements.last().unwrap().clone();
    let (global, frame) = (GlobalBounds::default(), FrameBounds::default());
    let ctx = BoundsContext {
        global: &global,
        frame: &frame,
        use_frame: true,
    };
    let mut rows = Vec::new();
    e.bound_rows(&ctx, &mut rows);
    (e, rows)
}

/// A pendulum with friction and Dahl friction of stiffness 20 /rad (`Fd1` after
/// `Fc1 Fv1 Fo1`).
fn dahl_pendulum() -> Model {
    pendulum_with("dahl = { sigma = 20 }")
}

/// The state follows the closed form of `dz/ds = σ·(1 − z·sign(ṡ))`: from rest (`z = 0`)
/// down by `d`, `z = −1 + e^(−σd)`; then up by `Δ` after the reversal,
/// `z = 1 − (1 − z_r)·e^(−σΔ)`, whatever the number of samples the path is cut into.
#[test]
fn dahl_state_follows_the_closed_form_along_a_path() {
    let model = dahl_pendulum();
    assert_eq!(model.param_names()[13], "Fd1");
    assert_eq!(model.params[13].kind, ParamKind::Dahl);
    let sigma = 20.0;
    for steps in [1usize, 7, 100] {
        let mut ws = Workspace::new(&model);
        model.advance_hysteresis(&mut ws, &[0.3]);
        assert_eq!(
            ws.hysteresis()[13],
            0.0,
            "the first sample only starts the path"
        );
        for k in 1..=steps {
            model.advance_hysteresis(&mut ws, &[0.3 - 0.1 * k as f64 / steps as f64]);
        }
        let zr = -1.0 + (-sigma * 0.1f64).exp();
        near(ws.hysteresis()[13], zr, 1e-12, "after 0.1 rad down");
        for k in 1..=steps {
            model.advance_hysteresis(&mut ws, &[0.2 + 0.05 * k as f64 / steps as f64]);
        }
        let z = 1.0 - (1.0 - zr) * (-sigma * 0.05f64).exp();
        near(ws.hysteresis()[13], z, 1e-12, "0.05 rad after the reversal");
        ws.reset_hysteresis();
        assert_eq!(ws.hysteresis()[13], 0.0);
    }
    // Any step keeps z within [−1, 1].
    let mut ws = Workspace::new(&model);
    for q in [0.0, 1e6, -1e6, 3.0, 3.0 + 1e-12] {
        model.advance_hysteresis(&mut ws, &[q]);
        assert!(ws.hysteresis()[13].abs() <= 1.0);
    }
}

/// `H·π` equals the inverse dynamics along a path (the state read by both), the force is
/// `Fd·z`, and `Fd ≥ 0` is the element's bound and consistency condition.
#[test]
fn dahl_regressor_torque_and_bound() {
    let model = dahl_pendulum();
    let p = model.n_params();
    let mut rng = Rng::new(3);
    let pi = random_params(&model, &mut rng);
    let mut ws = Workspace::new(&model);
    let (mut h, mut tau) = (vec![0.0; p], [0.0]);
    for k in 0..50 {
        let q = [(0.2 * k as f64).sin()];
        let (dq, ddq) = ([(0.2 * k as f64).cos()], [rng.uniform(-1.0, 1.0)]);
        model.advance_hysteresis(&mut ws, &q);
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
        let z = ws.hysteresis()[13];
        assert_eq!(h[13], z, "the Fd1 column is z");
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        near(dot(&h, &pi), tau[0], 1e-10, "H·π = τ");
        let without = zeroed(&pi, 13..14);
        let mut tau0 = [0.0];
        model.inverse_dynamics(&mut ws, &without, &q, &dq, &ddq, &mut tau0);
        near(tau[0] - tau0[0], pi[13] * z, 1e-12, "force Fd·z");
    }
    let (e, rows) = element_rows(&model);
    assert_eq!(
        rows,
        [BoundRow::at_least(
            13,
            0.0,
            BoundOrigin::Physical("Dahl friction Fd ≥ 0")
        )]
    );
    let mut x = vec![0.0; p];
    x[13] = -1e-3;
    assert!(!e.consistent(&x, 0.0));
    x[13] = 0.5;
    assert!(e.consistent(&x, 0.0));
    assert_eq!(e.description(&model.coordinates), "dahl = { sigma = 20.0 }");
}

/// Bad stiffnesses are refused with the file and the field named; `with_dahl` likewise.
#[test]
fn dahl_refuses_bad_sigma() {
    for (sigma, says) in [
        ("0", "must be positive"),
        ("-3", "must be positive"),
        ("nan", "must be a finite number"),
        ("inf", "must be a finite number"),
        ("1e300", "beyond the accepted"),
    ] {
        let text = support::models::one_link_with(&format!(
            "friction = true\ndahl = {{ sigma = {sigma} }}\n"
        ));
        let err = Model::from_toml_str(&text, "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains("dahl.sigma") && err.contains(says),
            "{sigma}: {err}"
        );
    }
    let psm = Model::builtin("psm").unwrap();
    for sigma in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e300] {
        let err = psm.with_dahl(sigma).unwrap_err().to_string();
        assert!(err.contains("Dahl stiffness sigma"), "{sigma}: {err}");
    }
    // Twice: the second adds nothing.
    let once = psm.with_dahl(20.0).unwrap();
    assert_eq!(once.with_dahl(5.0).unwrap().n_params(), once.n_params());
}

/// A pendulum (horizontal axis) with friction and a position torque of order 2
/// (`Pca1 Psa1 Pcb1 Psb1` after `Fc1 Fv1 Fo1`).
fn position_pendulum() -> Model {
    pendulum_with("position_torque = { order = 2 }")
}

/// The torque is `Σ Aₖ·cos(k·q) + Bₖ·sin(k·q)` against its closed form, in `H·π`, the
/// inverse dynamics (`H·π = τ`) and the static torque (a torque of the position, held at
/// rest); no bound (neither dissipative nor signed); the description line reads back.
#[test]
fn position_torque_closed_form() {
    let model = position_pendulum();
    let names = model.param_names();
    assert_eq!(
        &names[10..17],
        ["Fc1", "Fv1", "Fo1", "Pca1", "Psa1", "Pcb1", "Psb1"]
    );
    assert!(model.params[13..17]
        .iter()
        .all(|p| p.kind == ParamKind::PositionTorque && p.kind.unit_class() == UnitClass::Force));
    let p = model.n_params();
    let mut rng = Rng::new(8);
    let pi = random_params(&model, &mut rng);
    let mut ws = Workspace::new(&model);
    let (mut h, mut tau, mut tau0, mut rest) = (vec![0.0; p], [0.0], [0.0], [0.0]);
    for k in 0..20 {
        let q = [rng.uniform(-3.0, 3.0)];
        let (dq, ddq) = ([rng.uniform(-2.0, 2.0)], [rng.uniform(-2.0, 2.0)]);
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
        let expected = [
            q[0].cos(),
            q[0].sin(),
            (2.0 * q[0]).cos(),
            (2.0 * q[0]).sin(),
        ];
        assert_close(
            "columns cos q, sin q, cos 2q, sin 2q",
            &h[13..17],
            &expected,
            1e-14,
        );
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        near(dot(&h, &pi), tau[0], 1e-10, "H·π = τ");
        let without = zeroed(&pi, 13..17);
        model.inverse_dynamics(&mut ws, &without, &q, &dq, &ddq, &mut tau0);
        let force = dot(&expected, &pi[13..17]);
        near(tau[0] - tau0[0], force, 1e-12, "force Σ A·cos + B·sin");
        // At rest the static torque holds the series too (no friction at onset 0).
        let mut with_static = [0.0];
        model.static_torque(&mut ws, &pi, &q, &[0.0], &mut with_static);
        model.static_torque(&mut ws, &without, &q, &[0.0], &mut rest);
        near(
            with_static[0] - rest[0],
            force,
            1e-12,
            &format!("static torque {k}"),
        );
    }
    let (e, rows) = element_rows(&model);
    assert!(rows.is_empty(), "no bound on a position torque: {rows:?}");
    assert!(e.consistent(&vec![-5.0; p], 0.0));
    assert_eq!(
        e.description(&model.coordinates),
        format!(
            "position_torque = {{ order = 2, period = {:?} }}",
            std::f64::consts::TAU
        )
    );
    // A prismatic frame's series in its period (m): cos(2π·s/P).
    let slide = load(
        "name = \"s\"\nconvention = \"modified\"\ncoordinates = [\"q1\"]\n[[frames]]\n\
         name = \"slide\"\nparent = \"base\"\nd = \"q1\"\ninertia = true\nfriction = true\n\
         position_torque = { order = 1, period = 0.5 }\n",
    );
    let mut ws = Workspace::new(&slide);
    let mut h = vec![0.0; slide.n_params()];
    slide.regressor_into(&mut ws, &[0.1], &[0.0], &[0.0], &mut h);
    let phase = std::f64::consts::TAU * 0.1 / 0.5;
    assert_close("prismatic", &h[13..15], &[phase.cos(), phase.sin()], 1e-14);
}

/// No column of the series aliases the offset `Fo` (no constant term) or a spring (affine
/// in the joint value): on a link turning about a vertical axis (no gravity torque) with a
/// spring, every coefficient is a base parameter. On the pendulum, whose gravity torque
/// `g·(lₓ·cos q − l_y·sin q)` is the first order's columns, the base parameters fold
/// `Pca1`, `Psa1` into the link's first moments and keep the second order and `Fo1`.
#[test]
fn position_torque_identifiability() {
    let vertical = |extra: &str| {
        load(&format!(
            "name = \"v\"\nconvention = \"modified\"\ncoordinates = [\"q1\"]\n[[frames]]\n\
             name = \"link\"\nparent = \"base\"\ntheta = \"q1\"\ninertia = true\n\
             friction = true\nspring = \"q1\"\n{extra}"
        ))
    };
    let kept = |m: &Model| -> Vec<String> {
        let base = m.base_parameters().unwrap();
        base.independent
            .iter()
            .map(|&c| m.param_names()[c].to_string())
            .collect()
    };
    let without = kept(&vertical(""));
    let with = kept(&vertical("position_torque = { order = 2 }\n"));
    assert_eq!(with.len(), without.len() + 4, "{with:?}");
    for name in ["Fo1", "K1", "Pca1", "Psa1", "Pcb1", "Psb1"] {
        assert!(with.iter().any(|n| n == name), "{name} in {with:?}");
    }
    let plain = kept(&load(&support::models::one_link_with("friction = true\n")));
    let pendulum = kept(&position_pendulum());
    assert_eq!(pendulum.len(), plain.len() + 2, "{pendulum:?}");
    for name in ["Fo1", "Pcb1", "Psb1"] {
        assert!(pendulum.iter().any(|n| n == name), "{name} in {pendulum:?}");
    }
    for name in ["Pca1", "Psa1"] {
        assert!(
            !pendulum.iter().any(|n| n == name),
            "{name} folded: {pendulum:?}"
        );
    }
}

/// Bad orders and periods are refused with the file and the field named; a prismatic
/// frame needs a period; `with_position_torque` refuses a bad order, adds the series to
/// the revolute friction frames only, and once.
#[test]
fn position_torque_refuses_bad_input() {
    for (fields, field, says) in [
        ("order = 0", "position_torque.order", "must be 1 to 3"),
        ("order = 4", "position_torque.order", "must be 1 to 3"),
        (
            "order = 1, period = 0",
            "position_torque.period",
            "must be positive",
        ),
        (
            "order = 1, period = -1",
            "position_torque.period",
            "must be positive",
        ),
        (
            "order = 1, period = nan",
            "position_torque.period",
            "must be a finite number",
        ),
        (
            "order = 1, period = 1e300",
            "position_torque.period",
            "beyond the accepted",
        ),
    ] {
        let text = support::models::one_link_with(&format!(
            "friction = true\nposition_torque = {{ {fields} }}\n"
        ));
        let err = Model::from_toml_str(&text, "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains(field) && err.contains(says),
            "{fields}: {err}"
        );
    }
    let slide = "name = \"s\"\nconvention = \"modified\"\ncoordinates = [\"q1\"]\n[[frames]]\n\
                 name = \"slide\"\nparent = \"base\"\nd = \"q1\"\ninertia = true\n\
                 position_torque = { order = 1 }\n";
    let err = Model::from_toml_str(slide, "slide.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("slide.toml") && err.contains("needs the series' period"),
        "{err}"
    );
    let psm = Model::builtin("psm").unwrap();
    for order in [0, 4] {
        let err = psm.with_position_torque(order).unwrap_err().to_string();
        assert!(err.contains("must be 1 to 3"), "{order}: {err}");
    }
    let once = psm.with_position_torque(1).unwrap();
    let frames: Vec<usize> = once.params[psm.n_params()..]
        .iter()
        .map(|p| p.frame)
        .collect();
    // Every revolute friction frame (not the insertion, frame 8), two columns each.
    assert_eq!(
        frames,
        [1, 1, 2, 2, 10, 10, 11, 11, 12, 12, 13, 13, 14, 14, 15, 15, 16, 16]
    );
    assert_eq!(
        once.with_position_torque(2).unwrap().n_params(),
        once.n_params()
    );
}

/// A pendulum with friction and load friction (`Fl1` after `Fc1 Fv1 Fo1`).
fn load_pendulum() -> Model {
    pendulum_with("load_friction = true")
}

/// The column is `|τ_measured|·sign(q̇)` with the load given (`Model::set_load`), and
/// `H·π` equals the inverse dynamics with that load; the prediction
/// (`Model::loaded_inverse_dynamics`) solves `τ = τ₀ + μ·|τ|·sign(q̇)` exactly and leaves
/// its `|τ|` as the load, so the inverse dynamics then gives the same torque; the bounds
/// are `0 ≤ Fl ≤ 1/2`; the description line reads back.
#[test]
fn load_friction_closed_form() {
    let model = load_pendulum();
    assert_eq!(model.param_names()[13], "Fl1");
    assert_eq!(model.params[13].kind, ParamKind::LoadFriction);
    assert_eq!(model.params[13].kind.unit_class(), UnitClass::Ratio);
    let p = model.n_params();
    let mut rng = Rng::new(4);
    let mut pi = random_params(&model, &mut rng);
    pi[13] = 0.2;
    let mut ws = Workspace::new(&model);
    let (mut h, mut tau, mut tau0) = (vec![0.0; p], [0.0], [0.0]);
    for _ in 0..20 {
        let q = [rng.uniform(-3.0, 3.0)];
        let (dq, ddq) = ([rng.uniform(-2.0, 2.0)], [rng.uniform(-2.0, 2.0)]);
        let measured = [rng.uniform(-2.0, 2.0)];
        model.set_load(&mut ws, &measured);
        assert_eq!(ws.load(), [measured[0].abs()]);
        model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
        near(
            h[13],
            measured[0].abs() * dq[0].signum(),
            1e-15,
            "column |τ|·sign(q̇)",
        );
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        near(
            dot(&h, &pi),
            tau[0],
            1e-10,
            "H·π = τ with the measured load",
        );
        // The prediction: a fixed point of τ = τ₀ + μ·|τ|·sign(q̇).
        model.loaded_inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        let without = zeroed(&pi, 13..14);
        model.inverse_dynamics(&mut ws, &without, &q, &dq, &ddq, &mut tau0);
        let fixed = tau0[0] + 0.2 * tau[0].abs() * dq[0].signum();
        near(tau[0], fixed, 1e-12, "τ = τ₀ + μ|τ|sign(q̇)");
        let predicted = tau[0];
        model.loaded_inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        assert_eq!(ws.load(), [predicted.abs()]);
        model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
        near(
            tau[0],
            predicted,
            1e-12,
            "the predicted load reproduces the prediction",
        );
    }
    let (e, rows) = element_rows(&model);
    assert_eq!(
        rows,
        [
            BoundRow::at_least(13, 0.0, BoundOrigin::Physical("load friction Fl ≥ 0")),
            BoundRow::at_most(13, 0.5, BoundOrigin::Physical("load friction Fl ≤ 1/2")),
        ]
    );
    let mut x = vec![0.0; p];
    for (fl, ok) in [(-1e-3, false), (0.1, true), (0.6, false)] {
        x[13] = fl;
        assert_eq!(e.consistent(&x, 0.0), ok, "Fl {fl}");
    }
    assert_eq!(e.description(&model.coordinates), "load_friction = true");
    // A coupled joint value has no one coordinate whose torque is the load.
    let coupled = "name = \"c\"\nconvention = \"modified\"\ncoordinates = [\"q1\", \"q2\"]\n\
                   [[frames]]\nname = \"j\"\nparent = \"base\"\ntheta = \"q1 - q2\"\n\
                   inertia = true\nload_friction = true\n";
    let err = Model::from_toml_str(coupled, "coupled.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("coupled.toml")
            && err.contains("load_friction")
            && err.contains("exactly one coordinate"),
        "{err}"
    );
    // Added once per coordinate.
    let psm = Model::builtin("psm").unwrap().with_load_friction();
    assert_eq!(psm.with_load_friction().n_params(), psm.n_params());
}
