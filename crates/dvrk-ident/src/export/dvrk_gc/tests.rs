//! The MTM gravity-compensation file's tests: the gravity in the basis's span and the
//! friction per direction, the regressor's rows and the blend, other robots refused.

use super::*;

/// Rigid bodies on every link of the MTM (1 kg at a few cm, inertia about the
/// centre of mass diagonal), friction `Fc = 0.01·i`, `Fo = −0.002·i`, the spring at
/// 280 N/m.
pub(crate) fn mtm_params(model: &Model) -> Vec<f64> {
    let mut p = vec![0.0; model.n_params()];
    for (i, f) in model.frames.iter().enumerate() {
        let k = (i + 1) as f64;
        if let Some(p0) = f.inertia {
            // The wrist roll's centre of mass on its axis (z), which the
            // controller's basis assumes.
            let com = if f.name == "wrist_roll" {
                [0.0, 0.0, 0.03]
            } else {
                [0.01 * k, -0.02, 0.015 * (k - 5.0)]
            };
            let b = dvrk_model::inertia::barycentric_from_standard(
                0.2 * k,
                com,
                // Principal moments within the triangle inequality on every link.
                [0.002, 0.0, 0.0, 0.003, 0.0, 0.001 * k.min(4.0)],
            );
            p[p0..p0 + 10].copy_from_slice(&b);
        }
        if let Some(fr) = f.friction() {
            p[fr.param] = 0.01 * k;
            p[fr.param + 2] = -0.002 * k;
        }
        if let Some(sp) = f.spring() {
            p[sp.param] = 280.0;
        }
    }
    p
}

#[test]
fn mtm_gravity_is_in_the_span_and_friction_is_per_direction() {
    let model = Model::builtin("mtm").unwrap();
    let params = mtm_params(&model);
    let gc = dvrk_gc(&model, &params, 6).unwrap();
    let r = &gc.residuals;
    // Every MTM link's gravity lies in the ten columns' span.
    for j in 0..6 {
        assert!(
            r.gravity_max[j] < 1e-9,
            "joint {}: {:e}",
            j + 1,
            r.gravity_max[j]
        );
    }
    // A wrist roll whose centre of mass is off its axis (first moment 1 kg·mm: at
    // most 9.81e-3 N·m) moves the gravity of joints 4-6 by what the controller
    // cannot see.
    let roll = model
        .frames
        .iter()
        .find(|f| f.name == "wrist_roll")
        .unwrap();
    let mut off_axis = params.clone();
    off_axis[roll.inertia.unwrap() + 6] = 0.001;
    let off = dvrk_gc(&model, &off_axis, 6).unwrap().residuals;
    for j in 3..6 {
        let g = off.gravity_max[j];
        assert!(g > 1e-4 && g <= 9.81e-3 + 1e-12, "joint {}: {g:e}", j + 1);
    }
    // Joints 1, 2, 3 and 6 carry gravity and constant friction only: exact. Joint 4
    // has the cable (degree 7), joint 5 the spring: approximated, not exact.
    for j in [0, 1, 2, 5] {
        assert!(
            r.pos_max[j] < 1e-9 && r.neg_max[j] < 1e-9,
            "joint {}",
            j + 1
        );
    }
    for j in [3, 4] {
        assert!(r.pos_max[j] > 1e-5, "joint {}: {:e}", j + 1, r.pos_max[j]);
    }
    // Joint 1 (no gravity): pos − neg is twice Coulomb, the mean the offset:
    // Fc1 = 0.01, Fo1 = −0.002 as constants of its quartic (column 10).
    assert!(
        (gc.pos[10] - (0.01 - 0.002)).abs() < 1e-12,
        "{}",
        gc.pos[10]
    );
    assert!(
        (gc.neg[10] - (-0.01 - 0.002)).abs() < 1e-12,
        "{}",
        gc.neg[10]
    );
    assert_eq!(gc.pos[..10], gc.neg[..10]);
    // Safe limits enclose the compensation; joint 7 is not compensated.
    assert!(gc.upper[..6].iter().zip(&gc.lower).all(|(u, l)| u > l));
    assert_eq!((gc.upper[6], gc.lower[6]), (0.0, 0.0));
    let doc = gc.to_json();
    assert_eq!(doc["version"], "2.0");
    for (key, n) in [
        ("gc_dynamic_params_pos", 40),
        ("gc_dynamic_params_neg", 40),
        ("safe_upper_torque_limit", 7),
        ("safe_lower_torque_limit", 7),
        ("db_vel_vec", 7),
        ("sat_vec_vec", 7),
        ("fric_comp_ratio_vec", 7),
    ] {
        assert_eq!(
            doc["GC_controller"][key].as_array().unwrap().len(),
            n,
            "{key}"
        );
    }
}

#[test]
fn regressor_rows_and_blend() {
    let q = [0.3, -0.4, 0.5, 1.2, -0.7, 0.2, 2.0];
    let y = regressor(&q);
    // Joint 1 has no gravity term, joint 7 no term at all; quartics on the diagonal.
    assert!(y[0][..10].iter().all(|&v| v == 0.0));
    assert!(y[6].iter().all(|&v| v == 0.0));
    assert_eq!(
        y[3][25..30],
        [1.0, 1.2, 1.2 * 1.2, 1.2 * 1.2 * 1.2, 1.2 * 1.2 * 1.2 * 1.2]
    );
    // Column 3 of joint 2: −g·sin(q2 + q3); column 4 of joint 4: −g·sin(q2 + q3)·sin(q4).
    assert!((y[1][3] + G * (0.1f64).sin()).abs() < 1e-15);
    assert!((y[3][4] + G * (0.1f64).sin() * (1.2f64).sin()).abs() < 1e-15);
    // The blend: 0.5 in the dead band, saturated beyond sat_vel, linear between.
    assert_eq!(alpha(0.01, 0.02, 0.2, 0.7), 0.5);
    assert!((alpha(0.3, 0.02, 0.2, 0.7) - 0.85).abs() < 1e-15);
    assert!((alpha(-0.3, 0.02, 0.2, 0.7) - 0.15).abs() < 1e-15);
    assert!((alpha(0.11, 0.02, 0.2, 0.7) - (0.5 + 0.35 * 0.5)).abs() < 1e-15);
    assert!((alpha(-0.11, 0.02, 0.2, 0.7) - (0.5 - 0.35 * 0.5)).abs() < 1e-15);
}

#[test]
fn other_robots_are_refused() {
    let psm = Model::builtin("psm").unwrap();
    let p = vec![0.0; psm.n_params()];
    let e = dvrk_gc(&psm, &p, 7).unwrap_err().to_string();
    assert!(
        e.contains("for the MTM") && e.contains("outer_pitch"),
        "{e}"
    );
    let mtm = Model::builtin("mtm").unwrap();
    let e = dvrk_gc(&mtm, &vec![f64::NAN; mtm.n_params()], 7)
        .unwrap_err()
        .to_string();
    assert!(e.contains("finite"), "{e}");
}
