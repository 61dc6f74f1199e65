//! Digital Butterworth low-pass design, following scipy.signal step by step.
//!
//! `scipy.signal.butter(N, Wn)` builds the analog prototype (`buttap`), moves its cut-off
//! to the pre-warped frequency (`lp2lp_zpk`), maps it to the z-plane (`bilinear_zpk`,
//! with `fs = 2`) and converts the zeros/poles/gain to `(b, a)` (`zpk2tf`) or to
//! second-order sections (`zpk2sos`, pairing `"nearest"`). The same steps in the same
//! order are done here so that coefficients agree with scipy to rounding
//! (checked against a scipy fixture in the tests), which matters when reproducing
//! published identification results computed with scipy.

use super::error::{SignalError, CUTOFF_RANGE_WN};
use nalgebra::Complex;
use std::f64::consts::PI;

type C64 = Complex<f64>;

/// A rational transfer function `B(z)/A(z)` in scipy's `(b, a)` form: coefficients of
/// descending powers of `z`, `a[0]` normally 1.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunction {
    /// Numerator coefficients.
    pub b: Vec<f64>,
    /// Denominator coefficients.
    pub a: Vec<f64>,
}

/// One second-order section in scipy's layout `[b0, b1, b2, a0, a1, a2]` (`a0 = 1`).
pub type Section = [f64; 6];

/// Normalized cut-off `Wn = cutoff_hz / (rate_hz / 2)` (fraction of the Nyquist
/// frequency), the argument scipy's `butter` expects, with its validity checked.
pub(crate) fn normalized_cutoff(cutoff_hz: f64, rate_hz: f64) -> Result<f64, SignalError> {
    check_rate(rate_hz)?;
    let wn = cutoff_hz / (rate_hz / 2.0);
    check_wn_for(wn, cutoff_hz, rate_hz)?;
    Ok(wn)
}

pub(crate) fn check_rate(rate_hz: f64) -> Result<(), SignalError> {
    if rate_hz.is_finite() && rate_hz > 0.0 {
        Ok(())
    } else {
        Err(SignalError::InvalidRate { rate_hz })
    }
}

pub(crate) fn check_wn_for(wn: f64, cutoff_hz: f64, rate_hz: f64) -> Result<(), SignalError> {
    if (CUTOFF_RANGE_WN[0]..=CUTOFF_RANGE_WN[1]).contains(&wn) {
        Ok(())
    } else {
        Err(SignalError::InvalidCutoff {
            cutoff_hz,
            rate_hz,
            wn,
        })
    }
}

fn check_design(order: usize, wn: f64) -> Result<(), SignalError> {
    if order == 0 {
        return Err(SignalError::InvalidOrder { order });
    }
    if !(wn > 0.0 && wn < 1.0) {
        return Err(SignalError::InvalidWn { wn });
    }
    Ok(())
}

/// Zeros, poles and gain of the digital Butterworth low-pass of order `order` and
/// normalized cut-off `wn` (scipy `butter(order, wn, output="zpk")`).
fn butter_zpk(order: usize, wn: f64) -> (Vec<C64>, Vec<C64>, f64) {
    let n = order as f64;
    // buttap: p = -exp(1j*pi*m/(2N)), m = -N+1, -N+3, ..., N-1 (m = 0 gives exactly -1).
    let analog: Vec<C64> = (0..order)
        .map(|i| {
            let m = -n + 1.0 + 2.0 * i as f64;
            // numpy evaluates 1j*pi*m/(2N) as a complex division: (pi m) * (1 / (2N)).
            let theta = (PI * m) * (1.0 / (2.0 * n));
            -C64::new(theta.cos(), theta.sin())
        })
        .collect();
    // Pre-warp (fs = 2): warped = 2*fs*tan(pi*Wn/fs).
    let fs = 2.0;
    let warped = 2.0 * fs * (PI * wn / fs).tan();
    // lp2lp_zpk: scale the poles; the gain gets wo^(relative degree) = wo^N.
    let analog: Vec<C64> = analog.iter().map(|p| p * warped).collect();
    let k = warped.powf(n);
    // bilinear_zpk with fs = 2: z = (fs2 + s)/(fs2 - s); the N zeros at infinity go to -1.
    let fs2 = 2.0 * fs;
    let poles: Vec<C64> = analog
        .iter()
        .map(|p| np_div(C64::new(fs2, 0.0) + p, C64::new(fs2, 0.0) - p))
        .collect();
    let zeros = vec![C64::new(-1.0, 0.0); order];
    let prod = analog
        .iter()
        .fold(C64::new(1.0, 0.0), |acc, p| acc * (C64::new(fs2, 0.0) - p));
    let k_z = k * np_div(C64::new(1.0, 0.0), prod).re;
    (zeros, poles, k_z)
}

/// Complex division as numpy does it (Smith's algorithm), rather than num-complex's
/// textbook formula: the two differ in the last bits, and the `(b, a)` form of a
/// high-order low-pass amplifies last-bit differences in its poles.
fn np_div(x: C64, y: C64) -> C64 {
    if y.re.abs() >= y.im.abs() {
        let rat = y.im / y.re;
        let scl = 1.0 / (y.re + y.im * rat);
        C64::new((x.re + x.im * rat) * scl, (x.im - x.re * rat) * scl)
    } else {
        let rat = y.re / y.im;
        let scl = 1.0 / (y.im + y.re * rat);
        C64::new((x.re * rat + x.im) * scl, (x.im * rat - x.re) * scl)
    }
}

/// numpy's `poly`: coefficients of `prod (x - r)`, highest power first, built by
/// successive `convolve(a, [1, -r])` in the order given. The inner products are
/// accumulated like numpy's complex dot (separate sums of the four real products,
/// combined at the end), so that the coefficients agree with scipy to the last bit in
/// most cases.
fn poly(roots: &[C64]) -> Vec<C64> {
    let mut a = vec![C64::new(1.0, 0.0)];
    for r in roots {
        let w = -r;
        let n = a.len();
        let mut next = Vec::with_capacity(n + 1);
        next.push(a[0]);
        for i in 1..n {
            // dot([a[i-1], a[i]], [w, 1])
            let (x0, x1) = (a[i - 1], a[i]);
            let d0 = x0.re * w.re + x1.re;
            let d1 = x0.im * w.im;
            let d2 = x0.re * w.im;
            let d3 = x0.im * w.re + x1.im;
            next.push(C64::new(d0 - d1, d2 + d3));
        }
        next.push(a[n - 1] * w);
        a = next;
    }
    a
}

/// scipy `zpk2tf`; the imaginary parts (zero up to rounding for conjugate-closed roots)
/// are dropped.
fn zpk2tf(z: &[C64], p: &[C64], k: f64) -> TransferFunction {
    TransferFunction {
        b: poly(z).iter().map(|c| k * c.re).collect(),
        a: poly(p).iter().map(|c| c.re).collect(),
    }
}

/// Digital Butterworth low-pass in `(b, a)` form for a normalized cut-off `wn` in (0, 1)
/// (fraction of the Nyquist frequency): exactly scipy's `signal.butter(order, wn)`.
///
/// ```rust
/// let tf = dvrk_ident::signal::butter_lowpass_wn(2, 0.5).unwrap();
/// // scipy: butter(2, 0.5) -> b = [0.2929, 0.5858, 0.2929], a = [1, 0, 0.1716]
/// assert!((tf.b[0] - 0.29289321881345254).abs() < 1e-15);
/// assert!((tf.a[2] - 0.17157287525381).abs() < 1e-13);
/// ```
pub fn butter_lowpass_wn(order: usize, wn: f64) -> Result<TransferFunction, SignalError> {
    check_design(order, wn)?;
    let (z, p, k) = butter_zpk(order, wn);
    Ok(zpk2tf(&z, &p, k))
}

/// Digital Butterworth low-pass in `(b, a)` form with the cut-off in Hz:
/// `butter(order, cutoff_hz / (rate_hz / 2))`. The `(b, a)` form loses precision for
/// high orders and low cut-offs (`|Wn| << 1`); prefer [`butter_lowpass_sos`] unless
/// reproducing `(b, a)` results.
///
/// ```rust
/// use dvrk_ident::signal::{butter_lowpass, filtfilt};
/// let tf = butter_lowpass(4, 10.0, 200.0).unwrap(); // 10 Hz at 200 Hz sampling
/// let x: Vec<f64> = (0..400).map(|k| (k as f64 * 0.01).sin()).collect();
/// let y = filtfilt(&tf.b, &tf.a, &x, None).unwrap();
/// assert_eq!(y.len(), x.len());
/// ```
pub fn butter_lowpass(
    order: usize,
    cutoff_hz: f64,
    rate_hz: f64,
) -> Result<TransferFunction, SignalError> {
    butter_lowpass_wn(order, normalized_cutoff(cutoff_hz, rate_hz)?)
}

/// Digital Butterworth low-pass as second-order sections for a normalized cut-off `wn`:
/// exactly scipy's `signal.butter(order, wn, output="sos")` (same pole/zero pairing and
/// section order, gain in the first section). Odd orders get a first-order section
/// padded with a zero and a pole at the origin, as scipy does.
pub fn butter_lowpass_sos_wn(order: usize, wn: f64) -> Result<Vec<Section>, SignalError> {
    check_design(order, wn)?;
    let (z, p, k) = butter_zpk(order, wn);
    Ok(zpk2sos_nearest(z, p, k))
}

/// Digital Butterworth low-pass as second-order sections with the cut-off in Hz:
/// `butter(order, cutoff_hz / (rate_hz / 2), output="sos")`. Numerically robust at any
/// order; use with [`sosfiltfilt`](super::sosfiltfilt).
///
/// ```rust
/// use dvrk_ident::signal::{butter_lowpass_sos, sosfiltfilt};
/// let sos = butter_lowpass_sos(6, 5.4, 200.0).unwrap();
/// assert_eq!(sos.len(), 3);
/// let x = vec![1.0; 100];
/// let y = sosfiltfilt(&sos, &x, None).unwrap();
/// assert!(y.iter().all(|v| (v - 1.0).abs() < 1e-12)); // unit DC gain
/// ```
pub fn butter_lowpass_sos(
    order: usize,
    cutoff_hz: f64,
    rate_hz: f64,
) -> Result<Vec<Section>, SignalError> {
    butter_lowpass_sos_wn(order, normalized_cutoff(cutoff_hz, rate_hz)?)
}

fn is_real(c: &C64) -> bool {
    c.im == 0.0
}

/// scipy `_cplxreal`: complex roots with positive imaginary part (one per conjugate
/// pair, averaged with its partner) followed by the real roots, both sorted by real part.
fn cplxreal(z: &[C64]) -> Vec<C64> {
    let tol = 100.0 * f64::EPSILON;
    let mut z = z.to_vec();
    z.sort_by(|a, b| {
        a.re.total_cmp(&b.re)
            .then_with(|| a.im.abs().total_cmp(&b.im.abs()))
    });
    let (real, cplx): (Vec<C64>, Vec<C64>) =
        z.into_iter().partition(|c| c.im.abs() <= tol * c.norm());
    let mut zp: Vec<C64> = cplx.iter().copied().filter(|c| c.im > 0.0).collect();
    let mut zn: Vec<C64> = cplx.iter().copied().filter(|c| c.im < 0.0).collect();
    // Within runs of equal real part, sort by |imag| (as scipy does) so that partners
    // line up.
    let mut start = 0;
    while start < zp.len() {
        let mut stop = start + 1;
        while stop < zp.len() && zp[stop].re - zp[stop - 1].re <= tol * zp[stop - 1].norm() {
            stop += 1;
        }
        let by_imag = |a: &C64, b: &C64| a.im.abs().total_cmp(&b.im.abs());
        zp[start..stop].sort_by(by_imag);
        let zn_len = zn.len();
        zn[start.min(zn_len)..stop.min(zn_len)].sort_by(by_imag);
        start = stop;
    }
    let mut out: Vec<C64> = zp
        .iter()
        .zip(zn.iter())
        .map(|(p, n)| (p + n.conj()) / 2.0)
        .collect();
    out.extend(real.iter().map(|c| C64::new(c.re, 0.0)));
    out
}

#[derive(Clone, Copy, PartialEq)]
enum Which {
    Real,
    Complex,
    Any,
}

/// scipy `_nearest_real_complex_idx`: index in `fro` of the element nearest `to` among
/// the real, complex or all elements.
fn nearest_idx(fro: &[C64], to: C64, which: Which) -> Option<usize> {
    let mut order: Vec<usize> = (0..fro.len()).collect();
    order.sort_by(|&i, &j| (fro[i] - to).norm().total_cmp(&(fro[j] - to).norm()));
    order.into_iter().find(|&i| match which {
        Which::Any => true,
        Which::Real => is_real(&fro[i]),
        Which::Complex => !is_real(&fro[i]),
    })
}

/// Index of the pole closest to the unit circle (scipy's digital `idx_worst`).
fn idx_worst(p: &[C64]) -> usize {
    let mut best = 0;
    for i in 1..p.len() {
        if (1.0 - p[i].norm()).abs() < (1.0 - p[best].norm()).abs() {
            best = i;
        }
    }
    best
}

/// scipy `_single_zpksos`: one section from up to two zeros and poles, coefficients
/// right-aligned.
fn single_section(z: &[C64], p: &[C64]) -> Section {
    let tf = zpk2tf(z, p, 1.0);
    let mut s = [0.0; 6];
    let nb = tf.b.len();
    let na = tf.a.len();
    s[3 - nb..3].copy_from_slice(&tf.b);
    s[6 - na..6].copy_from_slice(&tf.a);
    s
}

/// scipy `zpk2sos(z, p, k, pairing="nearest")` for a digital filter with at least as
/// many zeros as poles after padding (always the case for Butterworth designs here).
fn zpk2sos_nearest(z: Vec<C64>, p: Vec<C64>, k: f64) -> Vec<Section> {
    let zero = C64::new(0.0, 0.0);
    let mut z = z;
    let mut p = p;
    // Same number of poles and zeros.
    while p.len() < z.len() {
        p.push(zero);
    }
    while z.len() < p.len() {
        z.push(zero);
    }
    let n_sections = p.len().max(z.len()).div_ceil(2);
    if p.len() % 2 == 1 {
        p.push(zero);
        z.push(zero);
    }
    let mut z = cplxreal(&z);
    let mut p = cplxreal(&p);
    let mut sos = vec![[0.0; 6]; n_sections];
    // Build from the last section: the pole nearest the unit circle goes last.
    for si in (0..n_sections).rev() {
        let p1 = p.remove(idx_worst(&p));
        let n_real_p = p.iter().filter(|c| is_real(c)).count();
        let n_real_z = z.iter().filter(|c| is_real(c)).count();
        if is_real(&p1) && n_real_p == 0 {
            // Special case (1): last remaining real pole, paired with the nearest real
            // zero and padded with a pole and a zero at the origin.
            let z1 = match nearest_idx(&z, p1, Which::Real) {
                Some(i) => z.remove(i),
                None => zero,
            };
            sos[si] = single_section(&[z1, zero], &[p1, zero]);
        } else if p.len() + 1 == z.len() && !is_real(&p1) && n_real_p == 1 && n_real_z == 1 {
            // Special case (2): must pair with a complex zero.
            let z1 = match nearest_idx(&z, p1, Which::Complex) {
                Some(i) => z.remove(i),
                None => zero,
            };
            sos[si] = single_section(&[z1, z1.conj()], &[p1, p1.conj()]);
        } else {
            let p2 = if is_real(&p1) {
                let real_idx: Vec<usize> = (0..p.len()).filter(|&i| is_real(&p[i])).collect();
                let reals: Vec<C64> = real_idx.iter().map(|&i| p[i]).collect();
                let i = real_idx[idx_worst(&reals)];
                p.remove(i)
            } else {
                p1.conj()
            };
            if let Some(i) = nearest_idx(&z, p1, Which::Any) {
                let z1 = z.remove(i);
                if !is_real(&z1) {
                    sos[si] = single_section(&[z1, z1.conj()], &[p1, p2]);
                } else if let Some(j) = nearest_idx(&z, p1, Which::Real) {
                    let z2 = z.remove(j);
                    sos[si] = single_section(&[z1, z2], &[p1, p2]);
                } else {
                    sos[si] = single_section(&[z1], &[p1, p2]);
                }
            } else {
                sos[si] = single_section(&[], &[p1, p2]);
            }
        }
    }
    for c in sos[0].iter_mut().take(3) {
        *c *= k;
    }
    sos
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn second_order_half_band_matches_closed_form() {
        // butter(2, 0.5): K = tan(pi/4) = 1, b = [1,2,1]/(2+sqrt2), a = [1, 0, (2-sqrt2)/(2+sqrt2)]
        let tf = butter_lowpass_wn(2, 0.5).unwrap();
        let s2 = 2f64.sqrt();
        let g = 1.0 / (2.0 + s2);
        for (x, y) in tf.b.iter().zip([g, 2.0 * g, g]) {
            assert!((x - y).abs() < 1e-15, "{x} {y}");
        }
        assert!((tf.a[0] - 1.0).abs() < 1e-15);
        assert!(tf.a[1].abs() < 1e-15);
        assert!((tf.a[2] - (2.0 - s2) / (2.0 + s2)).abs() < 1e-15);
    }

    #[test]
    fn unit_dc_gain_and_stable_poles() {
        for order in 1..=8 {
            for wn in [0.01, 0.1, 0.5, 0.9] {
                let tf = butter_lowpass_wn(order, wn).unwrap();
                let dc = tf.b.iter().sum::<f64>() / tf.a.iter().sum::<f64>();
                // The (b, a) form's DC gain is a ratio of two tiny sums at low Wn and
                // high order (sum(a) ~ 1e-13 at order 8, Wn 0.01): only loosely 1 there.
                let tol = if order <= 4 || wn >= 0.1 { 1e-9 } else { 1e-2 };
                assert!((dc - 1.0).abs() < tol, "order {order} wn {wn}: {dc}");
                let sos = butter_lowpass_sos_wn(order, wn).unwrap();
                assert_eq!(sos.len(), order.div_ceil(2));
                let dc: f64 = sos
                    .iter()
                    .map(|s| (s[0] + s[1] + s[2]) / (s[3] + s[4] + s[5]))
                    .product();
                assert!((dc - 1.0).abs() < 1e-10, "order {order} wn {wn}: {dc}");
                for s in &sos {
                    assert_eq!(s[3], 1.0);
                    // |poles| < 1 for a stable section: |a2| < 1 and |a1| < 1 + a2.
                    assert!(s[5].abs() < 1.0 && s[4].abs() < 1.0 + s[5]);
                }
            }
        }
    }

    #[test]
    fn rejects_bad_designs() {
        assert!(matches!(
            butter_lowpass_wn(0, 0.5),
            Err(SignalError::InvalidOrder { .. })
        ));
        assert!(matches!(
            butter_lowpass_wn(2, 1.0),
            Err(SignalError::InvalidWn { .. })
        ));
        assert!(matches!(
            butter_lowpass_sos_wn(2, 0.0),
            Err(SignalError::InvalidWn { .. })
        ));
        assert!(matches!(
            butter_lowpass(2, 150.0, 200.0),
            Err(SignalError::InvalidCutoff { .. })
        ));
        assert!(matches!(
            butter_lowpass(2, f64::NAN, 200.0),
            Err(SignalError::InvalidCutoff { .. })
        ));
        // At and just below the Nyquist frequency (rate read as 200.00000000000426 Hz
        // from a 2019 log: the check used to pass and the filter never settled), and far
        // below any motion.
        for (fc, rate) in [
            (100.0, 200.00000000000426),
            (99.999999, 200.0),
            (96.0, 200.0),
            (0.000001, 200.0),
            (0.0001, 200.0),
            (0.09, 200.0),
        ] {
            assert!(
                matches!(
                    butter_lowpass_sos(6, fc, rate),
                    Err(SignalError::InvalidCutoff { .. })
                ),
                "{fc} Hz at {rate} Hz"
            );
        }
        assert!(butter_lowpass_sos(6, 95.0, 200.0).is_ok());
        assert!(butter_lowpass_sos(6, 0.1, 200.0).is_ok());
        // The message rounds the measured rate and the ratios, not the cut-off given,
        // and never rounds a ratio onto the bound it is outside of.
        let message = |fc: f64, rate: f64| butter_lowpass_sos(6, fc, rate).unwrap_err().to_string();
        assert_eq!(
            message(150.0, 200.00000000000426),
            "cut-off 150 Hz at a 200 Hz sampling rate is 1.5 of the Nyquist frequency: it \
             must be between 0.001 and 0.95 of it (0.1 to 95 Hz): choose a --cutoff in that \
             range"
        );
        let above = message(95.0000001, 200.0);
        assert!(
            above.contains("is 0.9500000") && !above.contains("is 0.95 of"),
            "{above}"
        );
        assert!(message(0.09, 200.0).contains("is 0.0009 of the Nyquist"));
        assert!(matches!(
            butter_lowpass_sos(2, 5.0, -1.0),
            Err(SignalError::InvalidRate { .. })
        ));
    }

    #[test]
    fn cplxreal_orders_pairs_then_reals() {
        let z = [
            C64::new(0.5, 0.0),
            C64::new(-0.2, -0.3),
            C64::new(-0.2, 0.3),
            C64::new(-0.9, 0.0),
        ];
        let out = cplxreal(&z);
        assert_eq!(out.len(), 3);
        assert_eq!(out[0], C64::new(-0.2, 0.3));
        assert_eq!(out[1], C64::new(-0.9, 0.0));
        assert_eq!(out[2], C64::new(0.5, 0.0));
    }
}
