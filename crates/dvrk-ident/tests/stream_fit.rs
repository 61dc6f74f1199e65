//! The streamed fit (logs read from disk block by block) gives the in-memory fit: the
//! bundled MCAP example and simulated CSV logs (headered without velocities, the 2019
//! layout as the test log), every estimator, several block sizes; parameters, base
//! parameters and metrics to 1e-9 relative.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::log::{self, LogFormat, ReadOptions};
use dvrk_ident::simulate::to_model_coordinates;
use dvrk_ident::simulate::{simulate, Simulation};
use dvrk_ident::Streaming;
use dvrk_ident::{FitRequest, FitResult, FitSettings, JointLog, LogSource, Method, Training};
use dvrk_ident::{Progress, Silent};
use dvrk_model::Model;

fn example() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/psm_excitation.mcap")
}

/// The in-memory fit of the samples `train` (and `test`).
fn fit(
    model: &Model,
    train: &JointLog,
    test: Option<&JointLog>,
    settings: &FitSettings,
) -> Result<FitResult, dvrk_ident::IdentError> {
    let request = FitRequest::of_samples([train], test, settings.clone());
    Ok(request.run(Some(model), &Silent)?.result)
}

/// The fit of the files `train` (and `test`) read with `read`, block by block
/// (`block` samples each).
fn fit_stream(
    model: &Model,
    (train, test): (&PathBuf, Option<&PathBuf>),
    read: &ReadOptions,
    settings: &FitSettings,
    block: usize,
    progress: &dyn Progress,
) -> Result<FitResult, dvrk_ident::IdentError> {
    let request = FitRequest {
        test: test
            .map(|p| LogSource::File(p.clone()))
            .into_iter()
            .collect(),
        read: read.clone(),
        settings: settings.clone(),
        streaming: Streaming::Always,
        block_samples: block,
        ..FitRequest::new(Training::Logs(vec![LogSource::File(train.clone())]))
    };
    Ok(request.run(Some(model), progress)?.result)
}

/// Largest relative difference, each entry against `max(|b|, 1e-3 max|b|)` (entries
/// near zero are compared at the vector's scale).
fn worst(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(1e-3 * scale).max(1e-300))
        .fold(0.0, f64::max)
}

/// Compares two results; returns the worst relative difference of the parameters and
/// of the metrics.
fn compare(streamed: &FitResult, whole: &FitResult, what: &str) -> (f64, f64) {
    assert_eq!(streamed.rows, whole.rows, "{what}: rows");
    assert_eq!(streamed.solver.converged, whole.solver.converged, "{what}");
    let values = |r: &FitResult| r.parameters.values().copied().collect::<Vec<_>>();
    let base = |r: &FitResult| {
        r.base_parameters
            .iter()
            .map(|b| b.value)
            .collect::<Vec<_>>()
    };
    let p = worst(&values(streamed), &values(whole)).max(worst(&base(streamed), &base(whole)));
    let mut m = worst(&streamed.weights, &whole.weights);
    let mut metrics = vec![(&streamed.metrics.train, &whole.metrics.train)];
    if let (Some(a), Some(b)) = (&streamed.metrics.test, &whole.metrics.test) {
        metrics.push((a, b));
    }
    assert_eq!(
        streamed.metrics.test.is_some(),
        whole.metrics.test.is_some(),
        "{what}"
    );
    for (a, b) in metrics {
        assert_eq!(a.samples, b.samples, "{what}: metric samples");
        m = m
            .max(worst(&a.relative_error, &b.relative_error))
            .max(worst(&a.rms, &b.rms));
    }
    assert!(p < 1e-9, "{what}: parameters differ by {p:e}");
    assert!(m < 1e-9, "{what}: weights or metrics differ by {m:e}");
    (p, m)
}

/// Counts the stages and samples a streamed fit reports.
#[derive(Default)]
struct Counter {
    stages: Mutex<Vec<String>>,
    units: AtomicU64,
}

impl Progress for Counter {
    fn stage(&self, name: &str, _total: Option<u64>) {
        self.stages.lock().unwrap().push(name.to_string());
    }
    fn advance(&self, units: u64) {
        self.units.fetch_add(units, Ordering::Relaxed);
    }
}

#[test]
fn streamed_fit_of_the_example_equals_the_in_memory_fit() {
    let model = Model::builtin("psm").unwrap();
    let whole_log = log::read(example(), None, None).unwrap();
    let (file, read) = (example(), ReadOptions::default());
    for method in [Method::Ols, Method::Wls, Method::Irls, Method::Sdp] {
        let settings = FitSettings {
            method,
            ..FitSettings::default()
        };
        let whole = fit(&model, &whole_log, None, &settings).unwrap();
        for block in [1000, 333] {
            let counter = Counter::default();
            let streamed =
                fit_stream(&model, (&file, None), &read, &settings, block, &counter).unwrap();
            let (p, m) = compare(&streamed, &whole, &format!("{method:?}, blocks of {block}"));
            println!("example {method:?}, blocks of {block}: parameters {p:.1e}, metrics {m:.1e}");
            let stages = counter.stages.lock().unwrap();
            assert!(stages[0].starts_with("reading"), "{stages:?}");
            assert!(stages.iter().any(|s| s == "assembling the observation"));
            assert_eq!(
                stages
                    .iter()
                    .any(|s| s == "solving the semidefinite program"),
                method == Method::Sdp
            );
            // Every pass reads the whole log: the survey and the observation. The
            // training metrics and the IRLS re-weightings come from the R factors.
            assert!(!stages.iter().any(|s| s.starts_with("re-weighting")));
            let passes = 2;
            assert_eq!(counter.units.load(Ordering::Relaxed), passes * 2222);
        }
    }
}

/// Consistent MTM parameters (the cable is a known force: it is subtracted too).
fn mtm_params(model: &Model) -> Vec<f64> {
    dvrk_test_support::mtm_rule(0.05).params(model)
}

fn excitation(n: usize, phase: f64) -> FourierTrajectory {
    FourierTrajectory {
        order: 3,
        base_frequency_hz: 0.2,
        q0: (0..n).map(|j| 0.1 + 0.05 * j as f64).collect(),
        a: (0..n)
            .map(|j| vec![0.5 + phase, -0.3 + 0.05 * j as f64, 0.2])
            .collect(),
        b: (0..n)
            .map(|j| vec![0.2, 0.1 - phase, -0.1 * j as f64])
            .collect(),
        coordinates: Vec::new(),
        robot: None,
    }
}

fn simulated(model: &Model, phase: f64, seconds: f64, seed: u64) -> JointLog {
    let sim = Simulation {
        duration_s: Some(seconds),
        noise_std: vec![0.01],
        seed,
        ..Simulation::default()
    };
    simulate(
        model,
        &mtm_params(model),
        &excitation(model.dof(), phase),
        &sim,
    )
    .unwrap()
}

#[test]
fn streamed_fit_of_csv_logs_equals_the_in_memory_fit() {
    let model = Model::builtin("mtm").unwrap();
    let dir = dvrk_test_support::temp_dir("dvrk-ident-stream-fit");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // Training: headered CSV in measured joints, without velocities (differentiated).
    let mut train = simulated(&model, 0.0, 14.0, 3);
    train.dq = None;
    let train_path = dir.join("train.csv");
    log::write(&train_path, &train, LogFormat::Csv).unwrap();
    // Test: the 2019 layout (model coordinates, velocities).
    let test = to_model_coordinates(&model, &simulated(&model, 0.1, 9.0, 4)).unwrap();
    let test_path = dir.join("test.csv");
    log::write(&test_path, &test, LogFormat::Wpi).unwrap();
    let opts = ReadOptions::default();
    let train_whole = log::read(&train_path, None, None).unwrap();
    let test_whole = log::read(&test_path, None, Some(200.0)).unwrap();
    // The rate is the 2019-layout test log's (the training log has time stamps).
    let read = ReadOptions {
        rate_hz: Some(200.0),
        ..opts
    };
    for (method, filter_torque) in [
        (Method::Ols, false),
        (Method::Wls, true),
        (Method::Sdp, false),
    ] {
        let mut settings = FitSettings {
            method,
            test_window: Some(700),
            ..FitSettings::default()
        };
        settings.processing.filter_torque = filter_torque;
        settings.processing.decimate = 3;
        if method == Method::Wls {
            // Measurement delays (whole and fractional samples, up to 20 at 200 Hz):
            // the torques read ahead across block boundaries.
            settings.processing.delay_s = vec![0.0, 0.0125, 0.05, 0.0, 0.007, 0.0, 0.1];
        }
        let whole = fit(&model, &train_whole, Some(&test_whole), &settings).unwrap();
        for block in [4096, 250] {
            let streamed = fit_stream(
                &model,
                (&train_path, Some(&test_path)),
                &read,
                &settings,
                block,
                &Silent,
            )
            .unwrap();
            let (p, m) = compare(&streamed, &whole, &format!("{method:?}, blocks of {block}"));
            println!("csv {method:?}, blocks of {block}: parameters {p:.1e}, metrics {m:.1e}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn streamed_fit_errors_name_the_file() {
    let model = Model::builtin("psm").unwrap();
    let dir = dvrk_test_support::temp_dir("dvrk-ident-stream-err");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let opts = ReadOptions::default();
    // Too short for the trimming: the same error as in memory, before any long pass.
    let short = dir.join("short.mcap");
    let whole = log::read(example(), None, None).unwrap();
    let first: JointLog = JointLog {
        time: whole.time[..300].to_vec(),
        q: whole.q.rows(0, 300).into_owned(),
        dq: whole.dq.as_ref().map(|d| d.rows(0, 300).into_owned()),
        tau: whole.tau.rows(0, 300).into_owned(),
        ..whole.clone()
    };
    log::write(&short, &first, LogFormat::Mcap).unwrap();
    let settings = FitSettings::default();
    let e = fit_stream(&model, (&short, None), &opts, &settings, 100, &Silent).unwrap_err();
    let in_memory = fit(
        &model,
        &log::read(&short, None, None).unwrap(),
        None,
        &settings,
    )
    .unwrap_err();
    assert_eq!(e.to_string(), in_memory.to_string());
    assert!(e.to_string().contains("short.mcap"), "{e}");
    // A truncated file: named, never a panic.
    let bytes = std::fs::read(example()).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = opts.open(&cut).unwrap_err();
    assert!(
        e.to_string().contains("cut.mcap") && e.to_string().contains("truncated"),
        "{e}"
    );
    // A NaN in a CSV log: the file and line.
    let nan = dir.join("nan.csv");
    log::write(&nan, &first, LogFormat::Csv).unwrap();
    let text = std::fs::read_to_string(&nan).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut fields: Vec<&str> = lines[100].split(',').collect();
    fields[3] = "NaN";
    let bad = fields.join(",");
    let mut out: Vec<&str> = lines.clone();
    out[100] = &bad;
    std::fs::write(&nan, out.join("\n")).unwrap();
    let e = fit_stream(&model, (&nan, None), &opts, &settings, 64, &Silent).unwrap_err();
    assert!(e.to_string().contains("nan.csv:101"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

mod properties {
    //! Property (proptest): for any block size, trajectory, noise seed, decimation and
    //! least-squares estimator, the streamed fit of a log file equals the in-memory fit.

    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngSeed};

    proptest! {
        #![proptest_config(Config {
            cases: 12,
            rng_seed: RngSeed::Fixed(0x005e_ed19),
            failure_persistence: None,
            ..Config::default()
        })]

        #[test]
        fn streamed_fit_equals_in_memory_fit_for_any_block_size(
            block in 1usize..6000,
            phase in -0.2f64..0.2,
            seed: u64,
            decimate in 1usize..4,
            method in prop_oneof![Just(Method::Ols), Just(Method::Wls), Just(Method::Irls)],
            with_dq: bool,
        ) {
            let model = Model::builtin("mtm").unwrap();
            let dir = dvrk_test_support::temp_dir("dvrk-ident-stream-prop");
            std::fs::create_dir_all(&dir).unwrap();
            let mut train = simulated(&model, phase, 8.0, seed);
            if !with_dq {
                train.dq = None;
            }
            let path = dir.join("train.csv");
            log::write(&path, &train, LogFormat::Csv).unwrap();
            let mut settings = FitSettings { method, ..FitSettings::default() };
            settings.processing.decimate = decimate;
            let whole = fit(&model, &log::read(&path, None, None).unwrap(), None, &settings)
                .unwrap();
            let read = ReadOptions::default();
            let streamed =
                fit_stream(&model, (&path, None), &read, &settings, block, &Silent).unwrap();
            compare(&streamed, &whole, &format!("{method:?}, blocks of {block}"));
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
