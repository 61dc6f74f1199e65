//! Observation states: the fit of merged states equals the fit of
//! their logs; the file round trip is exact; merges are associative and commutative to
//! rounding (Gram matrices to 1e-12, fits to 1e-10); states of other robots or
//! settings, other format versions and damaged files are refused with the file named.

// The log helpers of dvrk-logs' tests (the bundled example log, a log cut into parts).
#[path = "../../../dvrk-logs/tests/support/logs.rs"]
mod logs;

use std::sync::Arc;

use crate::fit::LogData;
use crate::progress::Silent;
use crate::signal::{Cutoff, LowPass};
use crate::state::{model_hash, ObservationState, MAGIC};
use crate::{FitRequest, FitResult, FitSettings, IdentError, JointLog, Method, Training};
use dvrk_model::Model;
use logs::{example, part};

/// Three consecutive pieces of the bundled log, each long enough for the trimming.
fn pieces() -> [JointLog; 3] {
    let whole = example();
    let n = whole.len();
    [
        part(&whole, 0, n / 3),
        part(&whole, n / 3, 2 * n / 3),
        part(&whole, 2 * n / 3, n),
    ]
}

fn settings(method: Method) -> FitSettings {
    FitSettings {
        method,
        ..FitSettings::default()
    }
}

fn observe(model: &Model, log: &JointLog, s: &FitSettings) -> ObservationState {
    ObservationState::observe(model, &[LogData::new(log)], s, &Silent).unwrap()
}

/// The fit of `state` with the estimator of `s`, validated on `test`.
fn fit_state(
    state: &ObservationState,
    model: &Model,
    s: &FitSettings,
    test: &[&JointLog],
) -> Result<FitResult, IdentError> {
    let request = FitRequest {
        train: Training::Observations(vec![(Arc::new(state.clone()), None)]),
        ..FitRequest::of_samples([], test.iter().copied(), s.clone())
    };
    Ok(request.run(Some(model), &Silent)?.result)
}

/// The document without the solver's wall-clock time.
fn document(r: &FitResult) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_str(&r.to_json()).unwrap();
    v["solver"]["seconds"] = serde_json::Value::Null;
    v
}

fn merged(states: &[&ObservationState]) -> ObservationState {
    let mut total = states[0].clone();
    for s in &states[1..] {
        total.merge(s).unwrap();
    }
    total
}

#[test]
fn fit_of_merged_states_is_the_fit_of_the_logs() {
    let model = Model::builtin("psm").unwrap();
    let [a, b, c] = pieces();
    for method in [Method::Wls, Method::Irls, Method::Sdp] {
        let s = FitSettings {
            test_window: Some(150),
            ..settings(method)
        };
        let direct = FitRequest::of_samples([&a, &b], [&c], s.clone())
            .run(Some(&model), &Silent)
            .unwrap()
            .result;
        let state = merged(&[&observe(&model, &a, &s), &observe(&model, &b, &s)]);
        let from_state = fit_state(&state, &model, &s, &[&c]).unwrap();
        // The same merges in the same order: the same document to the last bit.
        assert_eq!(
            document(&from_state),
            document(&direct),
            "{}",
            method.name()
        );
        assert_eq!(direct.inputs.len(), 3);
        // Both logs observed at once give the same state as two merged.
        let both =
            ObservationState::observe(&model, &[LogData::new(&a), LogData::new(&b)], &s, &Silent)
                .unwrap();
        assert_eq!(both.to_bytes(), state.to_bytes());
    }
}

#[test]
fn file_round_trip_is_exact() {
    let model = Model::builtin("psm").unwrap();
    let [a, b, _] = pieces();
    let s = settings(Method::Wls);
    let state = merged(&[&observe(&model, &a, &s), &observe(&model, &b, &s)]);
    let bytes = state.to_bytes();
    assert_eq!(&bytes[..8], &MAGIC);
    // n = 7, w = 116: two logs and the merged factors, each 7 triangles of 6786 numbers.
    let header = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
    assert_eq!(bytes.len(), 24 + header + 8 * (2 * 7 + 3 * 7 * 6786));
    let back = ObservationState::from_bytes(&bytes, "mem.obs").unwrap();
    assert_eq!(back.to_bytes(), bytes);
    assert_eq!(back.samples(), state.samples());
    let dir = dvrk_test_support::temp_dir("dvrk-state");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.obs");
    state.write(&path).unwrap();
    let read = ObservationState::read(&path).unwrap();
    assert_eq!(read.to_bytes(), bytes);
    assert_eq!(
        document(&fit_state(&read, &model, &s, &[]).unwrap()),
        document(&fit_state(&state, &model, &s, &[]).unwrap())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Largest difference of the merged Gram matrices `RᵀR`, relative to their largest entry.
fn gram_difference(x: &ObservationState, y: &ObservationState) -> f64 {
    let mut worst: f64 = 0.0;
    for (p, q) in x.observed.parts.iter().zip(&y.observed.parts) {
        let (g1, g2) = (p.r().transpose() * p.r(), q.r().transpose() * q.r());
        worst = worst.max((&g1 - &g2).amax() / g2.amax());
        assert_eq!(p.rows(), q.rows());
    }
    worst
}

#[test]
fn merge_is_associative_and_commutative() {
    let model = Model::builtin("psm").unwrap();
    let [a, b, c] = pieces();
    // Least squares follows the factors to rounding (1e-10 required; observed about
    // 4e-14). The semidefinite program's solution moves within the interior-point
    // solver's tolerances when its input moves by rounding (observed 3.4e-7).
    for (method, tolerance) in [(Method::Wls, 1e-10), (Method::Sdp, 1e-5)] {
        let s = settings(method);
        let (a, b, c) = (
            observe(&model, &a, &s),
            observe(&model, &b, &s),
            observe(&model, &c, &s),
        );
        let left = merged(&[&merged(&[&a, &b]), &c]);
        let orders = [
            merged(&[&a, &merged(&[&b, &c])]),
            merged(&[&merged(&[&c, &a]), &b]),
            merged(&[&b, &merged(&[&c, &a])]),
            merged(&[&c, &b, &a]),
        ];
        let fit = |st: &ObservationState| fit_state(st, &model, &s, &[]).unwrap();
        let reference = fit(&left);
        let beta =
            |r: &FitResult| -> Vec<f64> { r.base_parameters.iter().map(|b| b.value).collect() };
        for other in &orders {
            let d = gram_difference(other, &left);
            assert!(d < 1e-12, "Gram matrices differ by {d:e}");
            assert_eq!(other.observed.range.bounds(), left.observed.range.bounds());
            let r = fit(other);
            let (x, y) = (beta(&r), beta(&reference));
            let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            let diff = x
                .iter()
                .zip(&y)
                .map(|(p, q)| (p - q).powi(2))
                .sum::<f64>()
                .sqrt();
            eprintln!(
                "{}: Gram {d:e}, base parameters {:e}",
                method.name(),
                diff / norm
            );
            assert!(
                diff < tolerance * norm,
                "{}: base parameters differ by {:e} relative",
                method.name(),
                diff / norm
            );
            assert_eq!(r.metrics.train.samples, reference.metrics.train.samples);
        }
    }
}

#[test]
fn merge_refuses_other_robots_and_settings() {
    let psm = Model::builtin("psm").unwrap();
    let simplified = Model::builtin("psm_simplified").unwrap();
    let [a, b, _] = pieces();
    let s = settings(Method::Wls);
    let mut x = observe(&psm, &a, &s);
    let other_robot = observe(&simplified, &b, &s);
    let e = x.merge(&other_robot).unwrap_err().to_string();
    assert!(
        e.contains("robot psm_simplified") && e.contains("do not merge"),
        "{e}"
    );
    let cut = FitSettings {
        processing: crate::signal::Processing {
            filter: Some(LowPass {
                cutoff_hz: Cutoff::All(8.0),
                ..LowPass::default()
            }),
            ..Default::default()
        },
        ..s.clone()
    };
    let e = x.merge(&observe(&psm, &b, &cut)).unwrap_err().to_string();
    assert!(e.contains("processing settings"), "{e}");
    let stribeck = FitSettings {
        stribeck_velocity: Some(0.3),
        ..s.clone()
    };
    let e = x
        .merge(&observe(&psm, &b, &stribeck))
        .unwrap_err()
        .to_string();
    assert!(e.contains("do not merge"), "{e}");
    // Nothing was merged by the refusals.
    assert_eq!(x.observed.logs.len(), 1);
    // A state fitted with another robot.
    let e = fit_state(&x, &simplified, &s, &[]).unwrap_err().to_string();
    assert!(e.contains("reduced for robot psm"), "{e}");
}

#[test]
fn damaged_files_are_refused_with_the_file_named() {
    let model = Model::builtin("psm").unwrap();
    let [a, ..] = pieces();
    let bytes = observe(&model, &a, &settings(Method::Ols)).to_bytes();
    let err = |b: &[u8]| {
        ObservationState::from_bytes(b, "x.obs")
            .unwrap_err()
            .to_string()
    };
    let mut v = bytes.clone();
    v[8] = 2;
    let e = err(&v);
    assert!(
        e.starts_with("x.obs: ") && e.contains("format version 2"),
        "{e}"
    );
    let e = err(b"time,position.outer_yaw\n0,1\n");
    assert!(e.contains("not a dvrk-ident observation state"), "{e}");
    let e = err(&bytes[..bytes.len() - 8]);
    assert!(e.contains("truncated"), "{e}");
    let e = err(&[bytes.as_slice(), &[0u8; 8]].concat());
    assert!(e.contains("more bytes than"), "{e}");
    // A header length beyond the limit, and one beyond the file: no allocation.
    let mut v = bytes.clone();
    v[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(err(&v).contains("more than the 16 MiB"), "{}", err(&v));
    let mut v = bytes.clone();
    v[16..24].copy_from_slice(&(1u64 << 20).to_le_bytes());
    assert!(err(&v).contains("truncated"), "{}", err(&v));
    // Two logs whose sample counts sum beyond usize: refused, no overflow.
    let mut pair = ObservationState::from_bytes(&bytes, "x.obs").unwrap();
    pair.merge(&observe(&model, &a, &settings(Method::Ols)))
        .unwrap();
    let pair = pair.to_bytes();
    let header = u64::from_le_bytes(pair[16..24].try_into().unwrap()) as usize;
    let text = std::str::from_utf8(&pair[24..24 + header]).unwrap();
    let samples = format!("\"samples\":{}", a.len() - 400);
    assert!(text.contains(&samples), "{text}");
    let text = text.replacen(&samples, &format!("\"samples\":{}", usize::MAX), 1);
    let mut v = pair[..16].to_vec();
    v.extend_from_slice(&(text.len() as u64).to_le_bytes());
    v.extend_from_slice(text.as_bytes());
    v.extend_from_slice(&pair[24 + header..]);
    assert!(
        err(&v).contains("samples, more than the 100000000000 a log can hold"),
        "{}",
        err(&v)
    );
    // A NaN among the numbers (the last one: the last log's last factor entry).
    let mut v = bytes.clone();
    let end = v.len();
    v[end - 8..].copy_from_slice(&f64::NAN.to_le_bytes());
    assert!(err(&v).contains("is not finite"), "{}", err(&v));
}

/// `bytes` (a state file) with its JSON header edited by `edit`, the length field
/// rewritten: a forged state that passes the layout checks.
fn with_header(bytes: &[u8], edit: impl Fn(&str) -> String) -> Vec<u8> {
    let h = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
    let text = edit(std::str::from_utf8(&bytes[24..24 + h]).unwrap());
    let mut v = bytes[..16].to_vec();
    v.extend_from_slice(&(text.len() as u64).to_le_bytes());
    v.extend_from_slice(text.as_bytes());
    v.extend_from_slice(&bytes[24 + h..]);
    v
}

#[test]
fn forged_headers_are_refused_with_the_file_named() {
    let psm = Model::builtin("psm").unwrap();
    let simplified = Model::builtin("psm_simplified").unwrap();
    let [a, ..] = pieces();
    let s = settings(Method::Ols);
    let bytes = observe(&psm, &a, &s).to_bytes();
    let read = |b: &[u8]| ObservationState::from_bytes(b, "x.obs");
    let err = |b: &[u8]| read(b).unwrap_err().to_string();
    let expect = |e: String, words: &[&str]| {
        assert!(e.starts_with("x.obs: "), "{e}");
        for w in words {
            assert!(e.contains(w), "{w:?} not in {e}");
        }
    };
    // Every processing setting is checked as a flag would be.
    let e = err(&with_header(&bytes, |t| {
        t.replace("\"cutoff_hz\":5.4", "\"cutoff_hz\":-5.4")
    }));
    expect(e, &["cut-off -5.4 Hz", "positive"]);
    let e = err(&with_header(&bytes, |t| {
        t.replace("\"cutoff_hz\":5.4", "\"cutoff_hz\":[5.4,5.4]")
    }));
    expect(e, &["2 per-joint cut-offs given for 7 joints"]);
    let e = err(&with_header(&bytes, |t| {
        t.replace("\"stribeck_velocity\":null", "\"stribeck_velocity\":-0.3")
    }));
    expect(
        e,
        &["Stribeck velocity must be positive and finite, got -0.3"],
    );
    let e = err(&with_header(&bytes, |t| {
        t.replace("\"uniform_tolerance\":0.1", "\"uniform_tolerance\":-1.0")
    }));
    expect(e, &["uniform_tolerance"]);
    // A factor entry beyond any regressor's (its square would overflow).
    let mut v = bytes.clone();
    let end = v.len();
    v[end - 8..].copy_from_slice(&1e300f64.to_le_bytes());
    expect(err(&v), &["1e300 is beyond the accepted ±1e100"]);
    // The merged factors of other data than the logs': refused. The state of one log has
    // the log's factor as its merge, so scaling one entry of the merged R (coordinate
    // 1's first non-zero one) breaks it.
    let merged_at = 24 + u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize + 8 * 14;
    let number = |v: &[u8], k: usize| f64::from_le_bytes(v[k..k + 8].try_into().unwrap());
    let k = (0..116 * 117 / 2)
        .map(|i| merged_at + 8 * i)
        .find(|&k| number(&bytes, k) != 0.0)
        .expect("a non-zero entry of coordinate 1");
    let mut v = bytes.clone();
    v[k..k + 8].copy_from_slice(&(number(&bytes, k) * 1.001).to_le_bytes());
    expect(
        err(&v),
        &["coordinate 1", "not the merge of the logs' factors"],
    );
    // Unchanged, it reads.
    assert!(read(&bytes).is_ok());

    // A consistent file of another model's shape under psm's hash: an error naming the
    // file, from the fit and from a merge, never a panic in the factors' arithmetic.
    let forged = observe(&simplified, &a, &s).to_bytes();
    let hash = model_hash(&psm);
    let forged = with_header(&forged, |t| {
        let v: serde_json::Value = serde_json::from_str(t).unwrap();
        let old = v["robot_hash"].as_str().unwrap().to_string();
        t.replace(&old, &hash)
            .replace("builtin:psm_simplified", "builtin:psm")
            .replace("\"robot\":\"psm_simplified\"", "\"robot\":\"psm\"")
    });
    let state = read(&forged).unwrap();
    let e = fit_state(&state, &psm, &s, &[]).unwrap_err().to_string();
    expect(e, &["factors of width", "the file was altered"]);
    let mut good = read(&bytes).unwrap();
    let e = good.merge(&state).unwrap_err().to_string();
    expect(e, &["factors of width"]);
}

/// The tool tip's frames (massless, no element: kinematics only) leave the model's hash
/// as it was without them, so states observed before they were described still merge;
/// a frame that carries a parameter changes it.
#[test]
fn frames_without_parameters_leave_the_hash() {
    let text = include_str!("../../../dvrk-model/robots/psm.toml");
    let rule =
        "# ---------------------------------------------------------------------------------\n";
    let start = text.find(&format!("{rule}# The tool tip")).unwrap();
    let end = text
        .find(&format!("{rule}# 2019 excitation limits"))
        .unwrap();
    let without = format!("{}{}", &text[..start], &text[end..]);
    let psm = Model::builtin("psm").unwrap();
    let before = Model::from_toml_str(&without, "psm.toml").unwrap();
    assert_eq!(psm.frames.len(), before.frames.len() + 2);
    let hash = model_hash;
    assert_eq!(hash(&psm), hash(&before));
    let tip = text.find("name = \"tool_tip\"").unwrap();
    // Friction on the tip (turning with q4): a parameter, another hash.
    let tip_friction = format!(
        "{}{}",
        &text[..tip],
        text[tip..].replacen("theta = \"pi/2\"\n", "theta = \"q4\"\nfriction = true\n", 1)
    );
    let moved = Model::from_toml_str(&tip_friction, "psm.toml").unwrap();
    assert_ne!(hash(&moved), hash(&psm));
}
