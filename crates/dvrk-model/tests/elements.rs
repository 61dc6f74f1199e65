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
