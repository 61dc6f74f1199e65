//! Fourier excitation trajectories: the 2019 coefficient files (from
//! `shared/anchors/wpi2019_excitation_trajectories.json`, skipped when absent) and the
//! analytic derivatives against finite differences.

use std::path::PathBuf;

use dvrk_ident::excite::{FourierError, FourierTrajectory};
use dvrk_model::Model;

fn anchor(name: &str) -> Option<PathBuf> {
    dvrk_test_support::shared(&format!("anchors/{name}"))
}

#[test]
fn every_2019_trajectory_loads_in_the_documented_layout() {
    let Some(path) = anchor("wpi2019_excitation_trajectories.json") else {
        return;
    };
    let raw: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let names = FourierTrajectory::wpi_names(&path).unwrap();
    assert_eq!(names.len(), 9, "{names:?}");
    for name in &names {
        let f = FourierTrajectory::from_wpi_file(&path, name).unwrap();
        let e = &raw["trajectories"][name];
        let c: Vec<f64> = e["coefficients"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(f.dof(), 7);
        assert_eq!(f.order, 6);
        assert_eq!(f.base_frequency_hz, e["base_freq_hz"].as_f64().unwrap());
        for d in 0..7 {
            // [q0, a1..a6, b1..b6] per coordinate.
            assert_eq!(f.q0[d], c[13 * d]);
            for l in 0..6 {
                assert_eq!(f.a[d][l], c[13 * d + 1 + l]);
                assert_eq!(f.b[d][l], c[13 * d + 7 + l]);
            }
        }
        assert_eq!(f.coordinates[6], "q7");
        // The file's own formula, written out: q = q0 + Σ a sin(w t)/w − b cos(w t)/w,
        // w = 2π l f0.
        let (mut q, mut dq, mut ddq) = ([0.0; 7], [0.0; 7], [0.0; 7]);
        for t in [0.0, 0.7, 3.3] {
            f.eval(t, &mut q, &mut dq, &mut ddq);
            for d in 0..7 {
                let mut expected = c[13 * d];
                for l in 1..=6 {
                    let w = 2.0 * std::f64::consts::PI * l as f64 * f.base_frequency_hz;
                    expected +=
                        c[13 * d + l] * (w * t).sin() / w - c[13 * d + 6 + l] * (w * t).cos() / w;
                }
                assert!((q[d] - expected).abs() < 1e-13, "{name} q{d} t {t}");
            }
        }
    }
    let e = FourierTrajectory::from_wpi_file(&path, "psm_five").unwrap_err();
    assert!(matches!(e, FourierError::UnknownName { .. }));
    assert!(e.to_string().contains("psm_one"), "{e}");
}

#[test]
fn psm_one_stays_inside_the_psm_position_limits() {
    let Some(path) = anchor("wpi2019_excitation_trajectories.json") else {
        return;
    };
    let model = Model::builtin("psm").unwrap();
    let f = FourierTrajectory::from_wpi_file(&path, "psm_one").unwrap();
    let n = 2000;
    let (mut q, mut dq, mut ddq) = ([0.0; 7], [0.0; 7], [0.0; 7]);
    let mut worst = vec![(f64::INFINITY, f64::NEG_INFINITY); model.limits.len()];
    for k in 0..n {
        f.eval(
            k as f64 * f.period_s() / n as f64,
            &mut q,
            &mut dq,
            &mut ddq,
        );
        for (w, l) in worst.iter_mut().zip(&model.limits) {
            let v = l.expr.eval(&q);
            *w = (w.0.min(v), w.1.max(v));
        }
    }
    for (w, l) in worst.iter().zip(&model.limits) {
        println!(
            "{}: [{:.4}, {:.4}] limit {:?}",
            l.label, w.0, w.1, l.position
        );
        if let Some([lo, hi]) = l.position {
            // Within 1% of each range: q2 reaches -0.7565, 6.5 mrad below its -0.75.
            let tol = 0.01 * (hi - lo);
            assert!(lo - tol <= w.0 && w.1 <= hi + tol, "{}", l.label);
        }
    }
}

#[test]
fn derivatives_and_period_of_a_2019_trajectory() {
    let Some(path) = anchor("wpi2019_excitation_trajectories.json") else {
        return;
    };
    let f = FourierTrajectory::from_wpi_file(&path, "mtm_two").unwrap();
    let h = 1e-5;
    let n = f.dof();
    let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut qp, mut dqp, mut ddqp) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut qm, mut dqm, mut ddqm) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in 0..40 {
        let t = 0.2537 * k as f64;
        f.eval(t, &mut q, &mut dq, &mut ddq);
        f.eval(t + h, &mut qp, &mut dqp, &mut ddqp);
        f.eval(t - h, &mut qm, &mut dqm, &mut ddqm);
        for j in 0..n {
            assert!(((qp[j] - qm[j]) / (2.0 * h) - dq[j]).abs() < 1e-7);
            assert!(((dqp[j] - dqm[j]) / (2.0 * h) - ddq[j]).abs() < 1e-7);
        }
        f.eval(t + f.period_s(), &mut qp, &mut dqp, &mut ddqp);
        for j in 0..n {
            assert!((qp[j] - q[j]).abs() < 1e-11);
            assert!((dqp[j] - dq[j]).abs() < 1e-11);
            assert!((ddqp[j] - ddq[j]).abs() < 1e-10);
        }
    }
    assert!((f.period_s() - 10.0).abs() < 1e-12);
}

#[test]
fn json_file_errors_name_the_file() {
    let dir = dvrk_test_support::temp_dir("dvrk-fourier");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("bad.json");
    std::fs::write(
        &p,
        r#"{"order": 2, "base_frequency_hz": 0.1, "q0": [0.0], "a": [[1.0]], "b": [[1.0, 2.0]]}"#,
    )
    .unwrap();
    let e = FourierTrajectory::from_json_file(&p)
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.json") && e.contains("a[0]"), "{e}");
    let e = FourierTrajectory::from_json_file(dir.join("absent.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("absent.json"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
