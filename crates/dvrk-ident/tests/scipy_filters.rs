//! Filter design and zero-phase filtering against scipy reference values
//! (fixtures/scipy_filters.json, produced by fixtures/gen_scipy_reference.py).

use dvrk_ident::signal::{
    butter_lowpass_sos_wn, butter_lowpass_wn, filtfilt, sosfiltfilt, CutoffConvention, LowPass,
};
use serde::Deserialize;

#[derive(Deserialize)]
struct Fixture {
    scipy: String,
    x: Vec<f64>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    order: usize,
    wn: f64,
    padlen: Option<usize>,
    stated_cutoff_hz: Option<f64>,
    rate_hz: Option<f64>,
    b: Vec<f64>,
    a: Vec<f64>,
    sos: Vec<[f64; 6]>,
    y_ba: Vec<f64>,
    y_sos: Vec<f64>,
}

fn fixture() -> Fixture {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/scipy_filters.json"
    );
    let text = std::fs::read_to_string(path).expect("fixture present");
    serde_json::from_str(&text).expect("fixture parses")
}

/// Largest |x - r| / (|r| + floor) over the pairs.
fn max_rel(x: &[f64], r: &[f64], floor: f64) -> f64 {
    assert_eq!(x.len(), r.len());
    x.iter()
        .zip(r)
        .map(|(x, r)| (x - r).abs() / (r.abs() + floor))
        .fold(0.0, f64::max)
}

fn max_abs(x: &[f64], r: &[f64]) -> f64 {
    assert_eq!(x.len(), r.len());
    x.iter()
        .zip(r)
        .map(|(x, r)| (x - r).abs())
        .fold(0.0, f64::max)
}

#[test]
fn fixture_covers_orders_2_4_6_and_2019() {
    let f = fixture();
    assert!(!f.scipy.is_empty());
    for order in [2, 4, 6] {
        assert!(f.cases.iter().filter(|c| c.order == order).count() >= 3);
    }
    assert_eq!(
        f.cases
            .iter()
            .filter(|c| c.stated_cutoff_hz.is_some())
            .count(),
        2
    );
}

#[test]
fn butter_ba_coefficients_match_scipy() {
    for c in fixture().cases {
        let tf = butter_lowpass_wn(c.order, c.wn).unwrap();
        let eb = max_rel(&tf.b, &c.b, 1e-300);
        let ea = max_rel(&tf.a, &c.a, 1e-300);
        assert!(eb < 1e-10 && ea < 1e-10, "{}: b {eb:e}, a {ea:e}", c.name);
    }
}

#[test]
fn butter_sos_coefficients_match_scipy() {
    for c in fixture().cases {
        let sos = butter_lowpass_sos_wn(c.order, c.wn).unwrap();
        assert_eq!(sos.len(), c.sos.len(), "{}", c.name);
        for (i, (s, r)) in sos.iter().zip(&c.sos).enumerate() {
            // Scale-aware: the gain sits in the first section's b (tiny at low Wn).
            let scale = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let e = max_abs(s, r) / scale;
            assert!(e < 1e-10, "{} section {i}: {e:e}\n{s:?}\n{r:?}", c.name);
        }
    }
}

#[test]
fn filtfilt_matches_scipy() {
    let f = fixture();
    for c in &f.cases {
        let y = filtfilt(&c.b, &c.a, &f.x, c.padlen).unwrap();
        let e = max_abs(&y, &c.y_ba);
        assert!(e < 1e-10, "{} (scipy coefficients): {e:e}", c.name);
        // And with our own design.
        let tf = butter_lowpass_wn(c.order, c.wn).unwrap();
        let y = filtfilt(&tf.b, &tf.a, &f.x, c.padlen).unwrap();
        let e = max_abs(&y, &c.y_ba);
        assert!(e < 1e-10, "{} (own design): {e:e}", c.name);
    }
}

#[test]
fn sosfiltfilt_matches_scipy() {
    let f = fixture();
    for c in &f.cases {
        let y = sosfiltfilt(&c.sos, &f.x, c.padlen).unwrap();
        let e = max_abs(&y, &c.y_sos);
        assert!(e < 1e-10, "{} (scipy sections): {e:e}", c.name);
        let sos = butter_lowpass_sos_wn(c.order, c.wn).unwrap();
        let y = sosfiltfilt(&sos, &f.x, c.padlen).unwrap();
        let e = max_abs(&y, &c.y_sos);
        assert!(e < 1e-10, "{} (own design): {e:e}", c.name);
    }
}

#[test]
fn wpi_lowpass_reproduces_the_2019_filter() {
    let f = fixture();
    for c in f.cases.iter().filter(|c| c.stated_cutoff_hz.is_some()) {
        let (fc, rate) = (c.stated_cutoff_hz.unwrap(), c.rate_hz.unwrap());
        assert!((CutoffConvention::Wpi.wn(fc, rate) - c.wn).abs() < 1e-15);
        let y = LowPass::wpi(fc).apply_slice(&f.x, fc, rate).unwrap();
        let e = max_abs(&y, &c.y_ba);
        assert!(e < 1e-10, "{}: {e:e}", c.name);
    }
}
