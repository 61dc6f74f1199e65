//! Linear filtering and zero-phase (forward-backward) filtering, as scipy.signal does it.
//!
//! Zero-phase filtering is what identification needs: a causal low-pass delays the
//! signals by a frequency-dependent lag, and delayed positions, velocities and torques no
//! longer satisfy the dynamics equation at the same instant. Running the filter forward
//! then backward cancels the phase. The edges are handled as in scipy (odd extension of
//! `padlen` samples, steady-state initial conditions scaled by the first sample), so the
//! numbers agree with scipy-based processing to rounding.

use super::butter::Section;
use super::SignalError;

fn check_coefficients(b: &[f64], a: &[f64]) -> Result<(Vec<f64>, Vec<f64>), SignalError> {
    if b.is_empty() || a.is_empty() {
        return Err(SignalError::InvalidCoefficients {
            reason: "b and a must not be empty".into(),
        });
    }
    if b.iter().chain(a.iter()).any(|v| !v.is_finite()) {
        return Err(SignalError::InvalidCoefficients {
            reason: "coefficients must be finite".into(),
        });
    }
    // scipy lfilter_zi strips leading zeros of a; lfilter requires a[0] != 0.
    let lead = a.iter().take_while(|v| **v == 0.0).count();
    if lead == a.len() {
        return Err(SignalError::InvalidCoefficients {
            reason: "a must have a non-zero coefficient".into(),
        });
    }
    let a = &a[lead..];
    let a0 = a[0];
    let (mut b, mut a) = if a0 != 1.0 {
        (
            b.iter().map(|v| v / a0).collect::<Vec<_>>(),
            a.iter().map(|v| v / a0).collect::<Vec<_>>(),
        )
    } else {
        (b.to_vec(), a.to_vec())
    };
    let n = a.len().max(b.len());
    a.resize(n, 0.0);
    b.resize(n, 0.0);
    Ok((b, a))
}

/// Direct-form II transposed IIR filter, scipy's `lfilter(b, a, x, zi=zi)`: returns the
/// output and the final state. `zi` (length `max(len(a), len(b)) - 1`) defaults to zeros
/// (filter at rest). Coefficients are normalized by `a[0]`.
///
/// ```rust
/// use dvrk_ident::signal::lfilter;
/// // y[k] = 0.5 x[k] + 0.5 y[k-1]
/// let (y, _) = lfilter(&[0.5], &[1.0, -0.5], &[1.0, 1.0, 1.0], None).unwrap();
/// assert_eq!(y, vec![0.5, 0.75, 0.875]);
/// ```
pub fn lfilter(
    b: &[f64],
    a: &[f64],
    x: &[f64],
    zi: Option<&[f64]>,
) -> Result<(Vec<f64>, Vec<f64>), SignalError> {
    let (b, a) = check_coefficients(b, a)?;
    let n = b.len();
    let mut z = vec![0.0; n - 1];
    if let Some(zi) = zi {
        if zi.len() != n - 1 {
            return Err(SignalError::InvalidCoefficients {
                reason: format!("initial state has length {}, expected {}", zi.len(), n - 1),
            });
        }
        z.copy_from_slice(zi);
    }
    let y = x.iter().map(|&xn| tf_step(&b, &a, &mut z, xn)).collect();
    Ok((y, z))
}

/// One sample through the direct-form II transposed filter with normalized, equally
/// long `b` and `a` and state `z` (`len - 1` values); the operation order of scipy's C
/// loop, shared by [`lfilter`] and the streamed filters so both round alike.
fn tf_step(b: &[f64], a: &[f64], z: &mut [f64], xn: f64) -> f64 {
    let n = b.len();
    if n == 1 {
        return xn * b[0];
    }
    let yn = z[0] + b[0] * xn;
    for i in 0..n - 2 {
        z[i] = z[i + 1] + xn * b[i + 1] - yn * a[i + 1];
    }
    z[n - 2] = xn * b[n - 1] - yn * a[n - 1];
    yn
}

/// One sample through a cascade of second-order sections with states `z` (two per
/// section); the operation order of scipy's `_sosfilt`, shared by [`sosfilt`] and the
/// streamed filters.
fn sos_step(sos: &[Section], z: &mut [[f64; 2]], xn: f64) -> f64 {
    let mut x_cur = xn;
    for (s, zs) in sos.iter().zip(z.iter_mut()) {
        let x_new = s[0] * x_cur + zs[0];
        zs[0] = s[1] * x_cur - s[4] * x_new + zs[1];
        zs[1] = s[2] * x_cur - s[5] * x_new;
        x_cur = x_new;
    }
    x_cur
}

/// A designed filter with its state, one sample at a time: what a zero-phase filter
/// applied block by block needs (see `super::stream`).
#[derive(Clone, Debug)]
pub(crate) enum Stepper {
    /// Normalized `(b, a)` of equal length and the state (`len - 1` values).
    Ba {
        b: Vec<f64>,
        a: Vec<f64>,
        z: Vec<f64>,
        zi: Vec<f64>,
        /// `filtfilt`'s default padding, from the coefficients as given.
        padlen: usize,
    },
    /// Sections and their states.
    Sos {
        sos: Vec<Section>,
        z: Vec<[f64; 2]>,
        zi: Vec<[f64; 2]>,
    },
}

impl Stepper {
    /// The transfer function `(b, a)`, checked and normalized as [`lfilter`] does.
    pub(crate) fn ba(b: &[f64], a: &[f64]) -> Result<Stepper, SignalError> {
        let zi = lfilter_zi(b, a)?;
        let padlen = 3 * a.len().max(b.len());
        let (b, a) = check_coefficients(b, a)?;
        Ok(Stepper::Ba {
            z: vec![0.0; zi.len()],
            b,
            a,
            zi,
            padlen,
        })
    }

    /// Second-order sections, checked as [`sosfilt`] does.
    pub(crate) fn sos(sos: &[Section]) -> Result<Stepper, SignalError> {
        let zi = sosfilt_zi(sos)?;
        Ok(Stepper::Sos {
            sos: sos.to_vec(),
            z: vec![[0.0; 2]; zi.len()],
            zi,
        })
    }

    /// Padding of [`filtfilt`] / [`sosfiltfilt`] when `padlen` is `None`.
    pub(crate) fn default_padlen(&self) -> usize {
        match self {
            Stepper::Ba { padlen, .. } => *padlen,
            Stepper::Sos { sos, .. } => sos_default_padlen(sos),
        }
    }

    /// Sets the state to the steady state of a constant input `x0` (the initial
    /// conditions of [`filtfilt`] and [`sosfiltfilt`], computed the same way).
    pub(crate) fn settle(&mut self, x0: f64) {
        match self {
            Stepper::Ba { z, zi, .. } => {
                for (s, u) in z.iter_mut().zip(zi.iter()) {
                    *s = u * x0;
                }
            }
            Stepper::Sos { z, zi, .. } => {
                for (s, u) in z.iter_mut().zip(zi.iter()) {
                    *s = [u[0] * x0, u[1] * x0];
                }
            }
        }
    }

    /// One sample through the filter.
    pub(crate) fn step(&mut self, x: f64) -> f64 {
        match self {
            Stepper::Ba { b, a, z, .. } => tf_step(b, a, z, x),
            Stepper::Sos { sos, z, .. } => sos_step(sos, z, x),
        }
    }
}

/// Steady-state initial state of [`lfilter`] for a unit step input, scipy's
/// `lfilter_zi(b, a)`: scaled by the first sample it starts the filter as if the signal
/// had been constant forever, which removes the start-up transient.
///
/// scipy solves `(I - companion(a)ᵀ) zi = b[1:] - a[1:] b[0]` by LU. That system is
/// ill-conditioned for low-pass filters (its determinant is `sum(a)`, tiny for a low
/// cut-off and high order), so here it is solved in closed form instead: summing its
/// rows gives `zi[0] = sum(b[1:] - a[1:] b[0]) / sum(a)`, computed with exact products
/// and compensated sums, then `zi[i+1] = zi[i] + a[i+1] zi[0] - (b[i+1] - a[i+1] b[0])`.
/// The result is accurate to rounding; scipy's own rounding error then dominates any
/// difference (below 1e-10 on the fixture's 6th-order, `Wn = 0.05` case).
///
/// ```rust
/// use dvrk_ident::signal::{butter_lowpass, lfilter, lfilter_zi};
/// let tf = butter_lowpass(3, 10.0, 100.0).unwrap();
/// let zi = lfilter_zi(&tf.b, &tf.a).unwrap();
/// // Started from zi, a unit step gives a unit output from the first sample on.
/// let (y, _) = lfilter(&tf.b, &tf.a, &[1.0; 5], Some(&zi)).unwrap();
/// assert!(y.iter().all(|v| (v - 1.0).abs() < 1e-12));
/// ```
pub fn lfilter_zi(b: &[f64], a: &[f64]) -> Result<Vec<f64>, SignalError> {
    let (b, a) = check_coefficients(b, a)?;
    let n = b.len();
    if n == 1 {
        return Ok(Vec::new());
    }
    let m = n - 1;
    // rhs[i] = b[i+1] - a[i+1] b[0] as an exact sum of three doubles (FMA error term).
    let mut terms = Vec::with_capacity(3 * m);
    for i in 0..m {
        let p = a[i + 1] * b[0];
        let e = a[i + 1].mul_add(b[0], -p); // a*b0 = p + e exactly
        terms.extend([b[i + 1], -p, -e]);
    }
    let sum_rhs = neumaier_sum(&terms);
    let sum_a = neumaier_sum(&a);
    if sum_a == 0.0 {
        return Err(SignalError::SingularSteadyState);
    }
    let z0 = sum_rhs / sum_a;
    let mut zi = Vec::with_capacity(m);
    zi.push(z0);
    for i in 0..m - 1 {
        let rhs = neumaier_sum(&terms[3 * i..3 * i + 3]);
        let next = zi[i] + a[i + 1] * z0 - rhs;
        zi.push(next);
    }
    Ok(zi)
}

/// Compensated (Neumaier) summation: the rounding error of each addition is carried
/// along, so heavy cancellation (as in `sum(a)` of a low-pass) stays accurate.
fn neumaier_sum(x: &[f64]) -> f64 {
    let mut sum = 0.0;
    let mut c = 0.0;
    for &v in x {
        let t = sum + v;
        if sum.abs() >= v.abs() {
            c += (sum - t) + v;
        } else {
            c += (v - t) + sum;
        }
        sum = t;
    }
    sum + c
}

/// Odd extension by `n` samples at each end (scipy `odd_ext`): `2 x[0] - x[n..1]` before
/// and `2 x[-1] - x[-2..-n-1]` after. It continues the signal's value and slope, so the
/// filter's edge transient is small. Requires `n < x.len()`.
pub fn odd_ext(x: &[f64], n: usize) -> Vec<f64> {
    if n == 0 || x.is_empty() {
        return x.to_vec();
    }
    let len = x.len();
    let n = n.min(len - 1);
    let (first, last) = (x[0], x[len - 1]);
    let mut out = Vec::with_capacity(len + 2 * n);
    out.extend((1..=n).rev().map(|i| 2.0 * first - x[i]));
    out.extend_from_slice(x);
    out.extend((1..=n).map(|i| 2.0 * last - x[len - 1 - i]));
    out
}

fn check_pad(len: usize, padlen: usize) -> Result<(), SignalError> {
    if len <= padlen {
        Err(SignalError::TooShort { len, padlen })
    } else {
        Ok(())
    }
}

/// Zero-phase forward-backward filter, scipy's `filtfilt(b, a, x, padlen=padlen)` with
/// the default odd padding and steady-state initial conditions. `padlen` defaults to
/// `3 * max(len(a), len(b))` (scipy's default); the signal must be longer than it.
///
/// ```rust
/// use dvrk_ident::signal::{butter_lowpass, filtfilt};
/// let tf = butter_lowpass(2, 2.0, 100.0).unwrap();
/// // A constant is reproduced exactly up to rounding (unit DC gain, steady start).
/// let y = filtfilt(&tf.b, &tf.a, &[3.0; 50], None).unwrap();
/// assert!(y.iter().all(|v| (v - 3.0).abs() < 1e-12));
/// ```
pub fn filtfilt(
    b: &[f64],
    a: &[f64],
    x: &[f64],
    padlen: Option<usize>,
) -> Result<Vec<f64>, SignalError> {
    let ntaps = a.len().max(b.len());
    let edge = padlen.unwrap_or(3 * ntaps);
    check_pad(x.len(), edge)?;
    let ext = odd_ext(x, edge);
    let zi = lfilter_zi(b, a)?;
    let x0 = ext[0];
    let zi0: Vec<f64> = zi.iter().map(|z| z * x0).collect();
    let (mut y, _) = lfilter(b, a, &ext, Some(&zi0))?;
    y.reverse();
    let y0 = y[0];
    let zi1: Vec<f64> = zi.iter().map(|z| z * y0).collect();
    let (mut y, _) = lfilter(b, a, &y, Some(&zi1))?;
    y.reverse();
    Ok(y[edge..edge + x.len()].to_vec())
}

/// scipy's default `sosfiltfilt` padding, `3 * (2 * n_sections + 1 - k)`.
fn sos_default_padlen(sos: &[Section]) -> usize {
    let zb = sos.iter().filter(|s| s[2] == 0.0).count();
    let za = sos.iter().filter(|s| s[5] == 0.0).count();
    3 * (2 * sos.len() + 1 - zb.min(za))
}

fn check_sos(sos: &[Section]) -> Result<(), SignalError> {
    if sos.is_empty() {
        return Err(SignalError::InvalidCoefficients {
            reason: "at least one second-order section is needed".into(),
        });
    }
    for (i, s) in sos.iter().enumerate() {
        if s.iter().any(|v| !v.is_finite()) {
            return Err(SignalError::InvalidCoefficients {
                reason: format!("section {i} has non-finite coefficients"),
            });
        }
        if s[3] != 1.0 {
            return Err(SignalError::InvalidCoefficients {
                reason: format!("section {i}: a0 = {} must be 1", s[3]),
            });
        }
    }
    Ok(())
}

/// Cascade of second-order sections, scipy's `sosfilt(sos, x, zi=zi)`: returns the
/// output and the final state (two values per section). Every section must have
/// `a0 = 1`.
pub fn sosfilt(
    sos: &[Section],
    x: &[f64],
    zi: Option<&[[f64; 2]]>,
) -> Result<(Vec<f64>, Vec<[f64; 2]>), SignalError> {
    check_sos(sos)?;
    let mut z = vec![[0.0; 2]; sos.len()];
    if let Some(zi) = zi {
        if zi.len() != sos.len() {
            return Err(SignalError::InvalidCoefficients {
                reason: format!(
                    "initial state has {} sections, expected {}",
                    zi.len(),
                    sos.len()
                ),
            });
        }
        z.copy_from_slice(zi);
    }
    let y = x.iter().map(|&xn| sos_step(sos, &mut z, xn)).collect();
    Ok((y, z))
}

/// Steady-state initial state of [`sosfilt`] for a unit step, scipy's `sosfilt_zi`:
/// each section's `lfilter_zi` scaled by the DC gain of the sections before it.
pub fn sosfilt_zi(sos: &[Section]) -> Result<Vec<[f64; 2]>, SignalError> {
    check_sos(sos)?;
    let mut scale = 1.0;
    let mut out = Vec::with_capacity(sos.len());
    for s in sos {
        let (b, a) = (&s[..3], &s[3..]);
        let zi = lfilter_zi(b, a)?;
        out.push([scale * zi[0], scale * zi[1]]);
        scale *= (b[0] + b[1] + b[2]) / (a[0] + a[1] + a[2]);
    }
    Ok(out)
}

/// Zero-phase forward-backward filter with second-order sections, scipy's
/// `sosfiltfilt(sos, x, padlen=padlen)`: odd padding, steady-state initial conditions.
/// `padlen` defaults to scipy's `3 * (2 * n_sections + 1 - k)`, where `k` is the number
/// of sections whose `b2` and `a2` are both zero (first-order sections), counted as
/// scipy does.
///
/// ```rust
/// use dvrk_ident::signal::{butter_lowpass_sos, sosfiltfilt};
/// let sos = butter_lowpass_sos(4, 5.0, 200.0).unwrap();
/// let x: Vec<f64> = (0..300).map(|k| (0.05 * k as f64).sin()).collect();
/// let y = sosfiltfilt(&sos, &x, None).unwrap();
/// // A 1.6 Hz sine passes a 5 Hz low-pass nearly unchanged and without delay.
/// assert!((y[150] - x[150]).abs() < 1e-3);
/// ```
pub fn sosfiltfilt(
    sos: &[Section],
    x: &[f64],
    padlen: Option<usize>,
) -> Result<Vec<f64>, SignalError> {
    check_sos(sos)?;
    let edge = padlen.unwrap_or_else(|| sos_default_padlen(sos));
    check_pad(x.len(), edge)?;
    let ext = odd_ext(x, edge);
    let zi = sosfilt_zi(sos)?;
    let scaled = |v: f64| -> Vec<[f64; 2]> { zi.iter().map(|z| [z[0] * v, z[1] * v]).collect() };
    let (mut y, _) = sosfilt(sos, &ext, Some(&scaled(ext[0])))?;
    y.reverse();
    let (mut y, _) = sosfilt(sos, &y, Some(&scaled(y[0])))?;
    y.reverse();
    Ok(y[edge..edge + x.len()].to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::{butter_lowpass_sos_wn, butter_lowpass_wn};

    #[test]
    fn lfilter_fir_and_state() {
        // Moving sum of two samples.
        let (y, zf) = lfilter(&[1.0, 1.0], &[1.0], &[1.0, 2.0, 3.0], None).unwrap();
        assert_eq!(y, vec![1.0, 3.0, 5.0]);
        assert_eq!(zf, vec![3.0]);
        // Continuing from the final state equals filtering the concatenation.
        let (y2, _) = lfilter(&[1.0, 1.0], &[1.0], &[4.0], Some(&zf)).unwrap();
        assert_eq!(y2, vec![7.0]);
    }

    #[test]
    fn lfilter_normalizes_a0() {
        let (y1, _) = lfilter(&[1.0], &[2.0, -1.0], &[2.0, 2.0], None).unwrap();
        let (y2, _) = lfilter(&[0.5], &[1.0, -0.5], &[2.0, 2.0], None).unwrap();
        assert_eq!(y1, y2);
    }

    #[test]
    fn lfilter_zi_is_steady_state() {
        let tf = butter_lowpass_wn(4, 0.2).unwrap();
        let zi = lfilter_zi(&tf.b, &tf.a).unwrap();
        let (y, zf) = lfilter(&tf.b, &tf.a, &[1.0; 20], Some(&zi)).unwrap();
        for v in y {
            assert!((v - 1.0).abs() < 1e-12);
        }
        for (a, b) in zf.iter().zip(&zi) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn sosfilt_matches_lfilter() {
        let tf = butter_lowpass_wn(4, 0.3).unwrap();
        let sos = butter_lowpass_sos_wn(4, 0.3).unwrap();
        let x: Vec<f64> = (0..100)
            .map(|k| ((k * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let (y1, _) = lfilter(&tf.b, &tf.a, &x, None).unwrap();
        let (y2, _) = sosfilt(&sos, &x, None).unwrap();
        for (a, b) in y1.iter().zip(&y2) {
            assert!((a - b).abs() < 1e-12);
        }
        let y1 = filtfilt(&tf.b, &tf.a, &x, None).unwrap();
        let y2 = sosfiltfilt(&sos, &x, None).unwrap();
        for (a, b) in y1.iter().zip(&y2) {
            assert!((a - b).abs() < 1e-10);
        }
    }

    #[test]
    fn odd_extension() {
        let x = [1.0, 2.0, 4.0, 7.0];
        assert_eq!(
            odd_ext(&x, 2),
            vec![-2.0, 0.0, 1.0, 2.0, 4.0, 7.0, 10.0, 12.0]
        );
        assert_eq!(odd_ext(&x, 0), x.to_vec());
    }

    #[test]
    fn too_short_and_bad_coefficients() {
        let tf = butter_lowpass_wn(2, 0.3).unwrap();
        assert!(matches!(
            filtfilt(&tf.b, &tf.a, &[1.0; 9], None),
            Err(SignalError::TooShort { len: 9, padlen: 9 })
        ));
        assert!(filtfilt(&tf.b, &tf.a, &[1.0; 10], None).is_ok());
        assert!(filtfilt(&tf.b, &tf.a, &[1.0; 3], Some(2)).is_ok());
        assert!(filtfilt(&tf.b, &tf.a, &[], Some(0)).is_err());
        assert!(lfilter(&[], &[1.0], &[1.0], None).is_err());
        assert!(lfilter(&[1.0], &[0.0, 0.0], &[1.0], None).is_err());
        assert!(lfilter(&[1.0], &[1.0, f64::NAN], &[1.0], None).is_err());
        assert!(lfilter(&[1.0, 1.0], &[1.0], &[1.0], Some(&[1.0, 2.0])).is_err());
        // A pole at z = 1 (integrator) has no steady state.
        assert!(matches!(
            lfilter_zi(&[1.0], &[1.0, -1.0]),
            Err(SignalError::SingularSteadyState)
        ));
        let sos = butter_lowpass_sos_wn(4, 0.3).unwrap();
        assert!(sosfiltfilt(&sos, &[1.0; 15], None).is_err());
        assert!(sosfiltfilt(&[], &[1.0; 50], None).is_err());
        let mut bad = sos.clone();
        bad[0][3] = 2.0;
        assert!(sosfilt(&bad, &[1.0], None).is_err());
        assert!(sosfilt(&sos, &[1.0], Some(&[[0.0; 2]])).is_err());
    }

    #[test]
    fn zero_phase_no_delay() {
        // A slow sine through a zero-phase low-pass keeps its phase: the peak stays put.
        let sos = butter_lowpass_sos_wn(6, 0.1).unwrap();
        let n = 1000;
        let x: Vec<f64> = (0..n)
            .map(|k| (2.0 * std::f64::consts::PI * k as f64 / 200.0).sin())
            .collect();
        let y = sosfiltfilt(&sos, &x, None).unwrap();
        // Away from the edges (odd-extension transients), the output equals the input.
        for k in 300..700 {
            assert!((y[k] - x[k]).abs() < 1e-6, "{k}: {} {}", y[k], x[k]);
        }
    }
}
