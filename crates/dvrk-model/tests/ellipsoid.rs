//! Bounding ellipsoids ([`dvrk_model::inertia::Ellipsoid`]): the density-realizability
//! inequality `tr(Q·J) ≥ 0` against brute force (clouds of point masses inside and
//! outside random ellipsoids), the least-volume ellipsoids around boxes and cylinders
//! (their corners and rims on the surface), the checks of a description's ellipsoid and
//! the ellipsoids a URDF's collision geometry gives.

use dvrk_model::inertia::{barycentric_from_standard, pseudo_inertia, Ellipsoid};
use dvrk_model::input::InputError;
use dvrk_test_support::Rng;
use nalgebra::{Matrix4, Vector3};

/// A random ellipsoid: centre within ±0.2 m, semi-axes 0.02–0.3 m, any rotation.
fn random_ellipsoid(rng: &mut Rng) -> Ellipsoid {
    Ellipsoid {
        center: [0; 3].map(|_| rng.uniform(-0.2, 0.2)),
        semi_axes: [0; 3].map(|_| rng.uniform(0.02, 0.3)),
        rpy: [0; 3].map(|_| rng.uniform(-3.2, 3.2)),
    }
}

/// A point of `e` at "radius" `r` (1: on the surface) in a random direction.
fn point_at(e: &Ellipsoid, r: f64, rng: &mut Rng) -> [f64; 3] {
    let u = Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize() * r;
    let local = Vector3::from(e.semi_axes).component_mul(&u);
    let x = dvrk_model::inertia::rotation_rpy(&e.rpy) * local + Vector3::from(e.center);
    x.into()
}

/// `(x − c)ᵀ·A·(x − c)`.
fn squared_radius(e: &Ellipsoid, x: [f64; 3]) -> f64 {
    let d = Vector3::from(x) - Vector3::from(e.center);
    (d.transpose() * e.shape() * d)[0]
}

/// The pseudo-inertia of point masses `(m, x)`.
fn cloud(points: &[(f64, [f64; 3])]) -> Matrix4<f64> {
    points
        .iter()
        .map(|&(m, x)| pseudo_inertia(&barycentric_from_standard(m, x, [0.0; 6])))
        .sum()
}

#[test]
fn ellipsoid_inequality_holds_inside_and_fails_outside() {
    let mut rng = Rng::new(0x5eed_e11f);
    for trial in 0..300 {
        let e = random_ellipsoid(&mut rng);
        let q = e.q_matrix();
        let n = 1 + (rng.next_u64() % 20) as usize;
        let cloud_at = |lo: f64, hi: f64, rng: &mut Rng| -> Vec<(f64, [f64; 3])> {
            (0..n)
                .map(|_| {
                    let r = rng.uniform(lo, hi);
                    (rng.uniform(0.01, 2.0), point_at(&e, r, rng))
                })
                .collect()
        };
        // tr(Q·J) = Σ m·(1 − d²) for point masses, whatever the ellipsoid.
        for points in [
            cloud_at(0.0, 0.999, &mut rng),
            cloud_at(1.001, 3.0, &mut rng),
        ] {
            let want: f64 = points
                .iter()
                .map(|&(m, x)| m * (1.0 - squared_radius(&e, x)))
                .sum();
            let got = (q * cloud(&points)).trace();
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "trial {trial}: tr(QJ) {got}, Σ m(1 − d²) {want}"
            );
        }
        // Every mass inside: satisfied; every mass outside: violated.
        let inside = cloud_at(0.0, 0.999, &mut rng);
        assert!(inside.iter().all(|&(_, x)| e.contains(x)));
        assert!((q * cloud(&inside)).trace() > 0.0, "trial {trial}: inside");
        let outside = cloud_at(1.001, 3.0, &mut rng);
        assert!(outside.iter().all(|&(_, x)| !e.contains(x)));
        assert!(
            (q * cloud(&outside)).trace() < 0.0,
            "trial {trial}: outside"
        );
        // The linear form the fit uses is the same number.
        let bary: Vec<f64> = inside
            .iter()
            .map(|&(m, x)| barycentric_from_standard(m, x, [0.0; 6]))
            .fold(vec![0.0; 10], |mut acc, b| {
                acc.iter_mut().zip(b).for_each(|(a, v)| *a += v);
                acc
            });
        let linear: f64 = e
            .barycentric_coefficients()
            .iter()
            .zip(&bary)
            .map(|(c, p)| c * p)
            .sum();
        let trace = (q * cloud(&inside)).trace();
        assert!((linear - trace).abs() <= 1e-12 * (1.0 + trace.abs()));
    }
}

#[test]
fn solid_ellipsoid_sits_at_two_fifths() {
    // A uniform solid filling E: E[(x − c)ᵀA(x − c)] = 3/5, so tr(Q·J) = 0.4·m; the
    // same solid grown by s has 1 − 3s²/5, negative beyond s = √(5/3).
    let e = Ellipsoid {
        center: [0.1, -0.05, 0.2],
        semi_axes: [0.3, 0.1, 0.05],
        rpy: [0.3, -0.7, 1.1],
    };
    let m = 2.0;
    for s in [0.5, 1.0, 1.2, 1.4] {
        let r = dvrk_model::inertia::rotation_rpy(&e.rpy);
        let a = Vector3::from(e.semi_axes) * s;
        let local = nalgebra::Matrix3::from_diagonal(&Vector3::new(
            m * (a[1] * a[1] + a[2] * a[2]) / 5.0,
            m * (a[0] * a[0] + a[2] * a[2]) / 5.0,
            m * (a[0] * a[0] + a[1] * a[1]) / 5.0,
        ));
        let ic = r * local * r.transpose();
        let j = pseudo_inertia(&barycentric_from_standard(
            m,
            e.center,
            dvrk_model::inertia::sym6(&ic),
        ));
        let got = (e.q_matrix() * j).trace();
        let want = m * (1.0 - 0.6 * s * s);
        assert!((got - want).abs() < 1e-12, "s {s}: {got} vs {want}");
    }
}

#[test]
fn box_and_cylinder_ellipsoids_touch_their_corners() {
    let mut rng = Rng::new(7);
    for _ in 0..50 {
        let center = [0; 3].map(|_| rng.uniform(-0.5, 0.5));
        let half = [0; 3].map(|_| rng.uniform(0.01, 0.3));
        let rpy = [0; 3].map(|_| rng.uniform(-3.0, 3.0));
        let e = Ellipsoid::around_box(center, half, rpy);
        let r = dvrk_model::inertia::rotation_rpy(&rpy);
        for corner in 0..8 {
            let s = |k: usize| if corner >> k & 1 == 1 { 1.0 } else { -1.0 };
            let local = Vector3::new(s(0) * half[0], s(1) * half[1], s(2) * half[2]);
            let x: [f64; 3] = (r * local + Vector3::from(center)).into();
            assert!((squared_radius(&e, x) - 1.0).abs() < 1e-12);
        }
        // Least volume: semi-axes √3·h (equal shares of the corner's 1).
        for (a, h) in e.semi_axes.iter().zip(half) {
            assert!((a - 3f64.sqrt() * h).abs() < 1e-15);
        }
        let (radius, length) = (rng.uniform(0.01, 0.2), rng.uniform(0.01, 0.8));
        let c = Ellipsoid::around_cylinder(center, radius, length, rpy);
        for k in 0..16 {
            let phi = k as f64 * std::f64::consts::PI / 8.0;
            for z in [-0.5 * length, 0.5 * length] {
                let local = Vector3::new(radius * phi.cos(), radius * phi.sin(), z);
                let x: [f64; 3] = (r * local + Vector3::from(center)).into();
                assert!((squared_radius(&c, x) - 1.0).abs() < 1e-12);
            }
        }
        // Any other split of the rim's 1 between the axes gives a larger volume.
        let volume = |e: &Ellipsoid| e.semi_axes.iter().product::<f64>();
        for u in [0.5f64, 0.6, 0.7, 0.8] {
            let other = Ellipsoid {
                center,
                semi_axes: [
                    radius / u.sqrt(),
                    radius / u.sqrt(),
                    0.5 * length / (1.0 - u).sqrt(),
                ],
                rpy,
            };
            assert!(volume(&other) >= volume(&c) * (1.0 - 1e-12));
        }
    }
}

#[test]
fn ellipsoid_check_names_the_field() {
    let good = Ellipsoid {
        center: [0.0, 0.1, 0.0],
        semi_axes: [0.1, 0.2, 0.3],
        rpy: [0.0; 3],
    };
    assert!(good.check().is_ok());
    for (semi, needle) in [
        ([-0.1, 0.2, 0.3], "semi_axes"),
        ([0.0, 0.2, 0.3], "semi_axes"),
        ([0.1, f64::NAN, 0.3], "semi_axes"),
        ([0.1, f64::INFINITY, 0.3], "semi_axes"),
    ] {
        let e = Ellipsoid {
            semi_axes: semi,
            ..good.clone()
        };
        let error = e.check().unwrap_err();
        assert!(matches!(error, InputError::SemiAxis { .. }), "{error:?}");
        assert!(error.to_string().contains(needle), "{error}");
    }
    let e = Ellipsoid {
        center: [f64::NAN, 0.0, 0.0],
        ..good.clone()
    };
    let error = e.check().unwrap_err();
    assert!(
        matches!(&error, InputError::Named { name, problem } if name == "center"
            && matches!(**problem, InputError::NotFinite { .. })),
        "{error:?}"
    );
    assert_eq!(
        error.to_string(),
        "center: must be a finite number, got NaN"
    );
    let e = Ellipsoid {
        rpy: [0.0, f64::INFINITY, 0.0],
        ..good
    };
    let error = e.check().unwrap_err();
    assert!(
        matches!(&error, InputError::Named { name, .. } if name == "rpy"),
        "{error:?}"
    );
}
