//! Zero-phase (forward-backward) filtering of a signal that arrives in blocks.
//!
//! The forward pass is causal: run sample by sample with its state carried over, it
//! gives exactly the numbers of the whole-log pass (same start, the odd extension of
//! the first `padlen` samples, same arithmetic). The backward pass is anti-causal:
//! the output at a sample depends on every later one. Each chunk of outputs is
//! therefore computed by a backward pass that starts [`settle_margin`] samples after
//! the chunk, from the steady state of the forward output there; the error of that
//! start decays with the filter's slowest pole below the requested tolerance before
//! it reaches the chunk. At the end of the log the backward pass starts exactly as
//! the whole-log one (odd extension of the last `padlen` samples, steady state of the
//! last forward output), so the last chunk is exact and the ends of the log are
//! treated identically.

use std::collections::VecDeque;

use crate::signal::filter::Stepper;
use crate::signal::{Section, SignalError};

/// Samples after a chunk where its backward pass starts so that the error of the
/// start is below `tolerance` (relative to the signal's scale) within the chunk.
///
/// The free response of a cascade whose `m` poles have moduli at most `r` is bounded
/// by that of `m` coincident poles at `r`, whose impulse response is
/// `C(k + m - 1, m - 1) r^k`; with the numerator's initial-state terms (at most `m`
/// taps, bounded here by `2^m`) the error after `k` samples is below
/// `2^m C(k + m - 1, m - 1) r^(k - m + 1)`. The margin is the smallest `k` where that
/// bound is below `tolerance`: a few times the slowest pole's time constant
/// `1 / ln(1/r)`.
pub(crate) fn settle_margin(sections: &[Section], tolerance: f64) -> usize {
    let mut poles = 0usize;
    let mut radius: f64 = 0.0;
    for s in sections {
        let (a1, a2) = (s[4] / s[3], s[5] / s[3]);
        let disc = a1 * a1 - 4.0 * a2;
        let r = if a2 == 0.0 {
            poles += usize::from(a1 != 0.0);
            a1.abs()
        } else if disc < 0.0 {
            poles += 2;
            a2.sqrt()
        } else {
            poles += 2;
            (a1.abs() + disc.sqrt()) / 2.0
        };
        radius = radius.max(r);
    }
    margin_for(poles, radius, tolerance)
}

/// `ln` of the bound of [`settle_margin`] after `k` samples for `poles` poles of
/// modulus `exp(log_r)`: `ln C(k + m - 1, m - 1) + (k - m + 1) ln r` (without the
/// constant `2^m`), with `ln C(k + m - 1, m - 1) = sum_{i=1}^{m-1} ln((k + i) / i)`.
fn log_bound(poles: usize, log_r: f64, k: usize) -> f64 {
    let binomial: f64 = (1..poles).map(|i| ((k + i) as f64 / i as f64).ln()).sum();
    binomial + (k as f64 - poles as f64 + 1.0) * log_r
}

/// The margin of [`settle_margin`] for `poles` poles of modulus at most `radius`.
///
/// The bound rises, then falls (it is concave in `k`); the first `k` where it is below
/// the target is found by doubling then bisection, so the cost is logarithmic in the
/// margin (a linear search took 21.7 s for a 0.0001 Hz cut-off at 200 Hz). A radius
/// that rounds to 1, which the cut-off range of processing excludes, would never settle:
/// the search stops at [`MAX_MARGIN`], longer than any log.
fn margin_for(poles: usize, radius: f64, tolerance: f64) -> usize {
    if poles == 0 || radius == 0.0 {
        return 0;
    }
    let log_r = radius.ln();
    if log_r.is_nan() || log_r >= 0.0 {
        return MAX_MARGIN;
    }
    let target = tolerance.ln() - poles as f64 * std::f64::consts::LN_2;
    let above = |k: usize| log_bound(poles, log_r, k) > target;
    if !above(poles) {
        return poles;
    }
    // Invariant: above(lo), !above(hi).
    let mut lo = poles;
    let mut hi = 2 * poles;
    while above(hi) {
        if hi >= MAX_MARGIN {
            return MAX_MARGIN;
        }
        lo = hi;
        hi = (2 * hi).min(MAX_MARGIN);
    }
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if above(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The largest margin [`settle_margin`] returns (samples): more than any log holds.
const MAX_MARGIN: usize = 1 << 40;

/// One column's filter, forward state and pending samples.
#[derive(Clone, Debug)]
struct Column {
    forward: Stepper,
    backward: Stepper,
    /// The first `padlen + 1` samples, until the forward pass can start.
    head: Vec<f64>,
    /// Forward outputs of the samples not yet emitted (front: the next to emit).
    pending: VecDeque<f64>,
    /// The last `padlen + 1` samples: the end's odd extension.
    tail: VecDeque<f64>,
}

impl Column {
    fn push(&mut self, x: f64, padlen: usize) {
        if self.tail.len() == padlen + 1 {
            self.tail.pop_front();
        }
        self.tail.push_back(x);
        if self.head.len() <= padlen {
            self.head.push(x);
            if self.head.len() == padlen + 1 {
                self.start(padlen);
            }
            return;
        }
        let y = self.forward.step(x);
        self.pending.push_back(y);
    }

    /// The forward pass over the start's odd extension and the first samples.
    fn start(&mut self, padlen: usize) {
        let x0 = self.head[0];
        let first = 2.0 * x0 - self.head[padlen];
        self.forward.settle(first);
        for i in (1..=padlen).rev() {
            self.forward.step(2.0 * x0 - self.head[i]);
        }
        for i in 0..self.head.len() {
            let y = self.forward.step(self.head[i]);
            self.pending.push_back(y);
        }
    }

    /// Backward pass from pending sample `from` down to 0, starting in the steady
    /// state of `pending[from]`; the outputs of samples `0..count` in order.
    fn backward_chunk(&mut self, from: usize, count: usize, out: &mut Vec<f64>) {
        self.backward.settle(self.pending[from]);
        let start = out.len();
        out.resize(start + count, 0.0);
        for i in (0..=from).rev() {
            let y = self.backward.step(self.pending[i]);
            if i < count {
                out[start + i] = y;
            }
        }
        self.pending.drain(..count);
    }

    /// The end: forward pass over the end's odd extension, then the exact backward
    /// pass over everything pending.
    fn finish(&mut self, padlen: usize, out: &mut Vec<f64>) {
        let last = *self.tail.back().expect("started");
        let n = self.tail.len();
        let mut ext = Vec::with_capacity(padlen);
        for i in 1..=padlen {
            ext.push(self.forward.step(2.0 * last - self.tail[n - 1 - i]));
        }
        let y_end = ext
            .last()
            .copied()
            .unwrap_or_else(|| *self.pending.back().expect("started"));
        self.backward.settle(y_end);
        for &y in ext.iter().rev() {
            self.backward.step(y);
        }
        let count = self.pending.len();
        let start = out.len();
        out.resize(start + count, 0.0);
        for i in (0..count).rev() {
            out[start + i] = self.backward.step(self.pending[i]);
        }
        self.pending.clear();
    }
}

/// Forward-backward filtering of several columns (one filter each, the same padding),
/// fed one row at a time; outputs come in rows, in order, `margin` to `2 margin` rows
/// behind the input and all at the end.
#[derive(Clone, Debug)]
pub(crate) struct ZeroPhase {
    columns: Vec<Column>,
    padlen: usize,
    margin: usize,
    /// Outputs computed per backward pass (besides the margin).
    chunk: usize,
    count: usize,
    scratch: Vec<Vec<f64>>,
}

impl ZeroPhase {
    /// One filter per column; `padlen` as in [`crate::signal::filtfilt`] (`None`: the
    /// filters' default, which must agree); `margin` from [`settle_margin`].
    pub(crate) fn new(
        filters: Vec<Stepper>,
        padlen: Option<usize>,
        margin: usize,
    ) -> Result<ZeroPhase, SignalError> {
        let defaults: Vec<usize> = filters.iter().map(Stepper::default_padlen).collect();
        let padlen = match padlen {
            Some(p) => p,
            None => {
                let p = defaults.first().copied().unwrap_or(0);
                if defaults.iter().any(|&d| d != p) {
                    return Err(SignalError::InvalidCoefficients {
                        reason: "per-joint filters of different orders".into(),
                    });
                }
                p
            }
        };
        let columns = filters
            .into_iter()
            .map(|f| Column {
                backward: f.clone(),
                forward: f,
                head: Vec::with_capacity(padlen + 1),
                pending: VecDeque::new(),
                tail: VecDeque::with_capacity(padlen + 1),
            })
            .collect::<Vec<_>>();
        Ok(ZeroPhase {
            scratch: vec![Vec::new(); columns.len()],
            columns,
            padlen,
            margin,
            chunk: margin.max(256),
            count: 0,
        })
    }

    /// Adds a row; appends the rows that are done to `out` (row-major).
    pub(crate) fn push(&mut self, row: &[f64], out: &mut Vec<f64>) {
        self.count += 1;
        for (c, &x) in self.columns.iter_mut().zip(row) {
            c.push(x, self.padlen);
        }
        let pending = self.columns.first().map_or(0, |c| c.pending.len());
        if pending >= self.chunk + self.margin {
            let (from, count) = (self.chunk + self.margin - 1, self.chunk);
            for (c, s) in self.columns.iter_mut().zip(&mut self.scratch) {
                s.clear();
                c.backward_chunk(from, count, s);
            }
            self.interleave(count, out);
        }
    }

    /// The end of the signal: appends every remaining row. The signal must be longer
    /// than the padding.
    pub(crate) fn finish(&mut self, out: &mut Vec<f64>) -> Result<(), SignalError> {
        if self.count <= self.padlen {
            return Err(SignalError::TooShort {
                len: self.count,
                padlen: self.padlen,
            });
        }
        let count = self.columns.first().map_or(0, |c| c.pending.len());
        for (c, s) in self.columns.iter_mut().zip(&mut self.scratch) {
            s.clear();
            c.finish(self.padlen, s);
        }
        self.interleave(count, out);
        Ok(())
    }

    fn interleave(&self, count: usize, out: &mut Vec<f64>) {
        for k in 0..count {
            out.extend(self.scratch.iter().map(|s| s[k]));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::{butter_lowpass_sos_wn, butter_lowpass_wn, filtfilt, sosfiltfilt, Section};

    fn signal(n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 / 200.0;
                (0.7 * t).sin() + 0.3 * (5.3 * t + 1.0).cos() + if k % 97 < 40 { 0.2 } else { -0.1 }
            })
            .collect()
    }

    fn streamed(filter: Stepper, margin: usize, padlen: Option<usize>, x: &[f64]) -> Vec<f64> {
        let mut z = ZeroPhase::new(vec![filter], padlen, margin).unwrap();
        let mut out = Vec::new();
        for &v in x {
            z.push(&[v], &mut out);
        }
        z.finish(&mut out).unwrap();
        out
    }

    #[test]
    fn margin_grows_with_the_slowest_pole() {
        let fast = settle_margin(&butter_lowpass_sos_wn(6, 0.2).unwrap(), 1e-12);
        let slow = settle_margin(&butter_lowpass_sos_wn(6, 0.02).unwrap(), 1e-12);
        assert!(fast > 50 && slow > 8 * fast, "{fast} {slow}");
        let loose = settle_margin(&butter_lowpass_sos_wn(6, 0.02).unwrap(), 1e-6);
        assert!(loose < slow);
        let pure_gain: [Section; 1] = [[2.0, 0.0, 0.0, 1.0, 0.0, 0.0]];
        assert_eq!(settle_margin(&pure_gain, 1e-12), 0);
    }

    #[test]
    fn margin_search_is_the_first_crossing_and_always_ends() {
        // The linear search it replaced, on the accepted cut-off range and beyond.
        for poles in [1, 2, 6, 12] {
            for radius in [1e-20, 0.1, 0.5, 0.9, 0.99, 0.999, 0.9999] {
                for tolerance in [1e-12, 1e-6] {
                    let log_r = f64::ln(radius);
                    let target = f64::ln(tolerance) - poles as f64 * std::f64::consts::LN_2;
                    let mut k = poles;
                    while log_bound(poles, log_r, k) > target {
                        k += 1;
                    }
                    assert_eq!(
                        margin_for(poles, radius, tolerance),
                        k,
                        "{poles} poles at {radius}, {tolerance}"
                    );
                }
            }
        }
        // A pole on the unit circle (a cut-off at the Nyquist frequency) never settles.
        assert_eq!(margin_for(6, 1.0, 1e-12), MAX_MARGIN);
        assert_eq!(margin_for(6, 1.0 - 1e-16, 1e-12), MAX_MARGIN);
        // The slowest accepted filter (Wn = 1e-3) settles in about 120 000 samples; the
        // margin scales as 1/Wn (1 192 474 at 1e-4).
        let slowest = settle_margin(&butter_lowpass_sos_wn(6, 1e-3).unwrap(), 1e-12);
        assert!((100_000..140_000).contains(&slowest), "{slowest}");
    }

    #[test]
    fn streamed_equals_whole_for_both_forms() {
        let x = signal(5000);
        let sos = butter_lowpass_sos_wn(6, 0.054).unwrap();
        let margin = settle_margin(&sos, 1e-12);
        let whole = sosfiltfilt(&sos, &x, None).unwrap();
        let got = streamed(Stepper::sos(&sos).unwrap(), margin, None, &x);
        let err = whole
            .iter()
            .zip(&got)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert_eq!(got.len(), x.len());
        assert!(err < 1e-12, "sos {err:e}");
        // The last chunk (and a log shorter than the margin) is exact.
        assert_eq!(got[x.len() - 10..], whole[x.len() - 10..]);
        let short = &x[..300];
        assert_eq!(
            streamed(Stepper::sos(&sos).unwrap(), margin, None, short),
            sosfiltfilt(&sos, short, None).unwrap()
        );
        let tf = butter_lowpass_wn(6, 0.17).unwrap();
        let whole = filtfilt(&tf.b, &tf.a, &x, Some(20)).unwrap();
        let margin = settle_margin(&butter_lowpass_sos_wn(6, 0.17).unwrap(), 1e-12);
        let got = streamed(Stepper::ba(&tf.b, &tf.a).unwrap(), margin, Some(20), &x);
        let err = whole
            .iter()
            .zip(&got)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-11, "ba {err:e}");
        // Without enough margin the streamed result is visibly off: the margin matters.
        let got = streamed(Stepper::sos(&sos).unwrap(), 5, None, &x);
        let whole = sosfiltfilt(&sos, &x, None).unwrap();
        let err = whole
            .iter()
            .zip(&got)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err > 1e-6, "{err:e}");
    }

    #[test]
    fn too_short_is_an_error() {
        let sos = butter_lowpass_sos_wn(4, 0.1).unwrap();
        let mut z = ZeroPhase::new(vec![Stepper::sos(&sos).unwrap()], None, 100).unwrap();
        let mut out = Vec::new();
        // scipy's default padding of 2 sections: 3 * (2 * 2 + 1) = 15 samples.
        for _ in 0..15 {
            z.push(&[1.0], &mut out);
        }
        assert!(matches!(
            z.finish(&mut out),
            Err(SignalError::TooShort {
                len: 15,
                padlen: 15
            })
        ));
        assert!(out.is_empty());
    }
}
