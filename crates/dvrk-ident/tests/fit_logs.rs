//! Several logs per fit: each processed on its own, observations merged. Checked
//! against an independent least squares on the stacked base regressor of each log's
//! processed samples (nalgebra SVD, no R factor), against each log's own metrics, and
//! the streamed fit of the same logs from files of different formats.

#[path = "support/logs.rs"]
mod logs;

use dvrk_ident::log::{self, LogFormat};
use dvrk_ident::validate::{joint_metrics, prepare, JointMap};
use dvrk_ident::Joints;
use dvrk_ident::Silent;
use dvrk_ident::Streaming;
use dvrk_ident::{FitRequest, FitSettings, JointLog, LogSource, Method, Training};
use dvrk_model::{Model, Workspace};
use logs::{example, part};
use nalgebra::{DMatrix, DVector};

fn rel(a: f64, b: f64, scale: f64) -> f64 {
    (a - b).abs() / b.abs().max(scale)
}

#[test]
fn two_logs_fit_as_their_stacked_samples_and_never_cross_the_boundary() {
    let model = Model::builtin("psm").unwrap();
    let whole = example();
    let (a, b) = (part(&whole, 0, 1000), part(&whole, 1100, whole.len()));
    let settings = FitSettings {
        method: Method::Ols,
        ..FitSettings::default()
    };
    let r = FitRequest::of_samples([&a, &b], None, settings.clone())
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    // Each log trimmed at both of its ends: 200 samples at each end of each.
    let trim = settings.processing.trim;
    let (na, nb) = (a.len() - 2 * trim, b.len() - 2 * trim);
    assert_eq!(r.metrics.train.samples, na + nb);
    assert_eq!(r.rows, (na + nb) * model.dof());

    // Independent least squares on the stacked base regressor of each log's samples.
    let base = model.base_parameters().unwrap();
    let (n, p, k) = (model.dof(), model.n_params(), base.rank());
    let prepared: Vec<_> = [&a, &b]
        .iter()
        .map(|t| prepare(&model, t, &settings.processing).unwrap())
        .collect();
    let rows: usize = prepared.iter().map(|d| d.len() * n).sum();
    let mut y = DMatrix::zeros(rows, k);
    let mut tau = DVector::zeros(rows);
    let mut ws = Workspace::new(&model);
    let (mut h, mut hb) = (vec![0.0; n * p], vec![0.0; n * k]);
    let mut row = 0;
    for d in &prepared {
        let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for i in 0..d.len() {
            for j in 0..n {
                (q[j], dq[j], ddq[j]) = (d.q[(i, j)], d.dq[(i, j)], d.ddq[(i, j)]);
            }
            model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
            base.select_into(&h, p, &mut hb);
            for j in 0..n {
                for c in 0..k {
                    y[(row, c)] = hb[j * k + c];
                }
                tau[row] = d.tau[(i, j)];
                row += 1;
            }
        }
    }
    let beta = y.svd(true, true).solve(&tau, 1e-14).unwrap();
    let scale = beta.amax() * 1e-6;
    let worst = r
        .base_parameters
        .iter()
        .zip(beta.iter())
        .map(|(got, want)| rel(got.value, *want, scale))
        .fold(0.0, f64::max);
    println!("two logs: base parameters against the stacked least squares: {worst:.1e}");
    assert!(worst < 1e-8, "{worst:e}");

    // Every input listed with its own metrics, equal to the metrics of that log alone.
    assert_eq!(r.inputs.len(), 2);
    let params = r.params_for(&model).unwrap();
    for (info, d) in r.inputs.iter().zip(&prepared) {
        assert_eq!(info.role, "train");
        assert!(info.path.is_empty());
        assert_eq!(info.sha256.len(), 64);
        // The result's training metrics come from the log's R factors, these from a
        // pass over its samples: equal up to the rounding of the factorization
        // (‖R·[π; −1]‖ against ‖H·π − τ‖, measured 1e-13 relative).
        let own = joint_metrics(
            &model,
            &params,
            d,
            None,
            &JointMap::new(&model, Joints::Model).unwrap(),
        )
        .unwrap();
        let got = info.metrics.as_ref().unwrap();
        assert_eq!((&got.joints, got.samples), (&own.joints, own.samples));
        for (a, b) in got
            .relative_error
            .iter()
            .zip(&own.relative_error)
            .chain(got.rms.iter().zip(&own.rms))
        {
            assert!(rel(*a, *b, 1e-300) < 1e-9, "{a} against {b}");
        }
    }
    assert_ne!(r.inputs[0].sha256, r.inputs[1].sha256);
    // The totals are the sums of the logs': rms² · samples adds up.
    let (ma, mb) = (
        r.inputs[0].metrics.as_ref().unwrap(),
        r.inputs[1].metrics.as_ref().unwrap(),
    );
    for j in 0..n {
        let total = r.metrics.train.rms[j].powi(2) * (na + nb) as f64;
        let sum = ma.rms[j].powi(2) * na as f64 + mb.rms[j].powi(2) * nb as f64;
        assert!(rel(total, sum, 1e-300) < 1e-12, "joint {j}");
    }

    // The two halves as one log (filtered across the cut, one trimming) differ: the
    // boundary matters, and it is respected.
    let joined = JointLog {
        time: a.time.iter().chain(&b.time).copied().collect(),
        q: DMatrix::from_fn(a.len() + b.len(), n, |i, j| {
            if i < a.len() {
                a.q[(i, j)]
            } else {
                b.q[(i - a.len(), j)]
            }
        }),
        dq: None,
        tau: DMatrix::from_fn(a.len() + b.len(), n, |i, j| {
            if i < a.len() {
                a.tau[(i, j)]
            } else {
                b.tau[(i - a.len(), j)]
            }
        }),
        ..a.clone()
    };
    // (Its 100-sample hole is a gap: refused as a single log without resampling.)
    let e = FitRequest::of_samples([&joined], None, settings.clone())
        .run(Some(&model), &Silent)
        .unwrap_err();
    assert!(
        e.to_string().contains("gap") || e.to_string().contains("uniform"),
        "{e}"
    );
}

#[test]
fn streamed_logs_of_mixed_formats_equal_the_in_memory_fit() {
    let model = Model::builtin("psm").unwrap();
    let whole = example();
    let dir = dvrk_test_support::temp_dir("dvrk-fit-logs");
    std::fs::create_dir_all(&dir).unwrap();
    let logs = [
        (part(&whole, 0, 900), "a.mcap", LogFormat::Mcap),
        (part(&whole, 900, 1700), "b.csv", LogFormat::Csv),
        (part(&whole, 1700, whole.len()), "c.mcap", LogFormat::Mcap),
    ];
    let mut paths = Vec::new();
    for (t, name, format) in &logs {
        let path = dir.join(name);
        log::write(&path, t, *format).unwrap();
        paths.push(path);
    }
    let files = |range: std::ops::Range<usize>| -> Vec<LogSource> {
        paths[range]
            .iter()
            .map(|p| LogSource::File(p.clone()))
            .collect()
    };
    for method in [Method::Wls, Method::Irls, Method::Sdp] {
        let settings = FitSettings {
            method,
            test_window: Some(100),
            ..FitSettings::default()
        };
        let request = FitRequest {
            test: files(2..3),
            settings,
            streaming: Streaming::Never,
            block_samples: 700,
            ..FitRequest::new(Training::Logs(files(0..2)))
        };
        let memory = request.run(Some(&model), &Silent).unwrap().result;
        let streamed = FitRequest {
            streaming: Streaming::Always,
            ..request
        };
        let streamed = streamed.run(Some(&model), &Silent).unwrap().result;
        // To the last bit: the same per-log processing and chunk factors.
        assert_eq!(memory.parameters, streamed.parameters, "{method:?}");
        assert_eq!(memory.metrics, streamed.metrics, "{method:?}");
        assert_eq!(memory.inputs, streamed.inputs, "{method:?}");
        assert_eq!(memory.weights, streamed.weights, "{method:?}");
        let roles: Vec<&str> = memory.inputs.iter().map(|i| i.role.as_str()).collect();
        assert_eq!(roles, ["train", "train", "test"]);
        assert_eq!(memory.metrics.test.as_ref().unwrap().samples, 100);
        for (info, p) in memory.inputs.iter().zip(&paths) {
            assert_eq!(info.path, p.display().to_string());
            assert_eq!(info.bytes, std::fs::metadata(p).unwrap().len());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The pendulum of the element tests with Coulomb, viscous and offset friction
/// (`Fc1 Fv1 Fo1` after its ten inertial parameters).
fn pendulum() -> Model {
    let text = dvrk_test_support::models::one_link_with("friction = true\n");
    Model::from_toml_str(&text, "pendulum.toml").unwrap()
}

/// The pendulum's parameters: a 1.2 kg link, `Fc1 = 0.08` N·m, `Fv1 = 0.05` N·m·s/rad,
/// `Fo1 = fo`, and `extra` (e.g. `Fd1`) after them.
fn pendulum_truth(fo: f64, extra: &[f64]) -> Vec<f64> {
    let mut pi = dvrk_model::inertia::barycentric_from_standard(
        1.2,
        [0.1, 0.02, 0.0],
        [0.01, 0.0, 0.0, 0.012, 0.0, 0.008],
    )
    .to_vec();
    pi.extend([0.08, 0.05, fo]);
    pi.extend(extra);
    pi
}

/// A simulated pendulum log: three harmonics of 0.1 Hz (velocity reversals of a few
/// hundredths to half a radian), `seconds` at 100 Hz, torque noise `noise` N·m.
fn pendulum_log(model: &Model, params: &[f64], seconds: f64, noise: f64, seed: u64) -> JointLog {
    use dvrk_ident::excite::FourierTrajectory;
    use dvrk_ident::simulate::{simulate, Simulation};
    let traj = FourierTrajectory {
        order: 3,
        base_frequency_hz: 0.1,
        q0: vec![0.2],
        a: vec![vec![0.25, 0.1, 0.3]],
        b: vec![vec![0.1, -0.2, 0.05]],
        coordinates: Vec::new(),
        robot: None,
    };
    let sim = Simulation {
        duration_s: Some(seconds),
        rate_hz: 100.0,
        noise_std: vec![noise],
        seed,
        ..Simulation::default()
    };
    simulate(model, params, &traj, &sim).unwrap()
}

/// The held-out mean of candidate `name` in a result's selection.
fn held_out(r: &dvrk_ident::FitResult, name: &str) -> f64 {
    let s = r.selection.as_ref().unwrap();
    s.candidates
        .iter()
        .find(|c| c.candidate == name)
        .unwrap()
        .mean
}

/// `select` on one simulated log (4 blocks in time): with Dahl friction in the
/// torques (Fd = 0.06 N·m, noise 5 mN·m), the candidate without it has the higher
/// held-out error and loses, and the winner refitted on all the data recovers Fd;
/// without Dahl friction in the torques, the richer candidate (Stribeck + Dahl) does
/// not beat Coulomb + viscous by more than the noise's share of the error.
#[test]
fn select_chooses_the_friction_law_of_the_torques_by_held_out_error() {
    use dvrk_ident::{Candidates, Folds};
    let plain = pendulum();
    let settings = |cands: &str| FitSettings {
        method: Method::Ols,
        select: Some(cands.parse::<Candidates>().unwrap()),
        ..FitSettings::default()
    };
    let dahl = plain.with_dahl(20.0).unwrap();
    assert_eq!(dahl.param_names()[13], "Fd1");
    let log = pendulum_log(&dahl, &pendulum_truth(0.02, &[0.06]), 40.0, 0.005, 3);
    let r = FitRequest::of_samples([&log], None, settings("coulomb,dahl"))
        .run(Some(&plain), &Silent)
        .unwrap()
        .result;
    let s = r.selection.as_ref().unwrap();
    print!("{}", s.table());
    assert!(
        matches!(s.folds, Folds::Blocked { folds: 4, .. }),
        "{:?}",
        s.folds
    );
    let (coulomb, with_dahl) = (held_out(&r, "coulomb"), held_out(&r, "dahl"));
    assert_eq!(s.chosen, "dahl");
    assert!(coulomb > 1.5 * with_dahl, "{coulomb} vs {with_dahl}");
    assert_eq!(r.settings.dahl_sigma, Some(20.0));
    assert_eq!(
        r.settings.select.as_ref().unwrap().to_string(),
        "coulomb,dahl"
    );
    let fd = r.parameters["Fd1"];
    assert!((fd - 0.06).abs() < 0.006, "Fd1 {fd}");

    let log = pendulum_log(&plain, &pendulum_truth(0.02, &[]), 40.0, 0.005, 4);
    let r = FitRequest::of_samples([&log], None, settings("coulomb,stribeck+dahl"))
        .run(Some(&plain), &Silent)
        .unwrap()
        .result;
    print!("{}", r.selection.as_ref().unwrap().table());
    let (simple, rich) = (held_out(&r, "coulomb"), held_out(&r, "stribeck+dahl"));
    // Noise of 5 mN·m on torques of about 1 N·m: both errors are the noise's; the two
    // terms too many may fit a little of it, never a tenth of it.
    assert!(rich > 0.9 * simple, "{rich} vs {simple}");
    assert!(simple < 0.02, "{simple}");

    // The candidates give the friction terms: one given beside them is refused.
    let mut request = FitRequest::of_samples([&log], None, settings("coulomb,dahl"));
    request.overrides.stribeck_velocity = Some(0.3);
    let e = request.run(Some(&plain), &Silent).unwrap_err().to_string();
    assert!(
        e.contains("the candidates give the friction terms, and stribeck"),
        "{e}"
    );
}

/// `log_offsets`: two simulated logs of the pendulum re-homed between them (Fo 0.02
/// then 0.17 N·m, noise 5 mN·m). With the option, the second log's own offset is
/// recovered within noise and the model's Fo is the first log's; without it the common
/// Fo sits between them and the training error is several times larger.
#[test]
fn log_offsets_recover_each_logs_offset() {
    let model = pendulum();
    let a = pendulum_log(&model, &pendulum_truth(0.02, &[]), 20.0, 0.005, 5);
    let b = pendulum_log(&model, &pendulum_truth(0.17, &[]), 20.0, 0.005, 6);
    let fit = |offsets: bool| {
        let s = FitSettings {
            method: Method::Ols,
            log_offsets: offsets,
            ..FitSettings::default()
        };
        FitRequest::of_samples([&a, &b], None, s)
            .run(Some(&model), &Silent)
            .unwrap()
            .result
    };
    let (with, without) = (fit(true), fit(false));
    let offsets: Vec<_> = with
        .inputs
        .iter()
        .map(|i| i.offset.clone().unwrap())
        .collect();
    println!("offsets {offsets:?}, Fo1 {}", with.parameters["Fo1"]);
    assert_eq!(offsets[0], [0.0]);
    assert!((offsets[1][0] - 0.15).abs() < 0.002, "{offsets:?}");
    assert!((with.parameters["Fo1"] - 0.02).abs() < 0.002);
    assert!(without.inputs.iter().all(|i| i.offset.is_none()));
    let mean = |r: &dvrk_ident::FitResult| r.metrics.train.relative_error[0];
    println!(
        "train error with {} without {}",
        mean(&with),
        mean(&without)
    );
    assert!(mean(&without) > 3.0 * mean(&with));
}
