//! The measurement delay of the torques: column `j` of the torques read `d_j` seconds
//! later, `τ'_j(t) = τ_j(t + d_j)`, so that the torque a joint logged for the motion at
//! `t` lines up with that motion. Only the torques move: the regressor of the motion,
//! the expensive part of a fit, is the same for every delay.
//!
//! On the uniform processing clock (rate `f`), `s = d·f` samples, `m = ⌊s⌋`,
//! `α = s − m`: `τ'(k) = (1 − α)·τ(k + m) + α·τ(k + m + 1)`, indices past the end of the
//! log held at the last sample (which the trimming then drops). A fractional delay is
//! thus the same affine combination of two whole-sample shifts at every sample, which
//! the delay search ([`crate::fit::delay`]) relies on.

use std::collections::VecDeque;

use super::SignalError;

/// Largest measurement delay accepted, s.
pub const MAX_DELAY_S: f64 = 1.0;

/// Checks delays (s) for `dof` columns: none, or one per column in `[0, MAX_DELAY_S]`.
pub(crate) fn check_delays(delays_s: &[f64], dof: usize) -> Result<(), SignalError> {
    if !delays_s.is_empty() && delays_s.len() != dof {
        return Err(SignalError::InvalidSetting {
            name: "delay",
            reason: format!(
                "{} delays for {dof} coordinates (give one per coordinate)",
                delays_s.len()
            ),
        });
    }
    if let Some(d) = delays_s
        .iter()
        .find(|d| !(d.is_finite() && **d >= 0.0 && **d <= MAX_DELAY_S))
    {
        return Err(SignalError::InvalidSetting {
            name: "delay",
            reason: format!("a delay must be within [0, {MAX_DELAY_S}] s, got {d}"),
        });
    }
    Ok(())
}

/// The torque columns advanced by their delays, row by row (`push`, then `finish`).
#[derive(Clone, Debug)]
pub(crate) struct Advance {
    /// Whole samples `m_j` and fraction `α_j` per column.
    whole: Vec<usize>,
    fraction: Vec<f64>,
    /// Rows from the next one to emit on (row-major, `dof` each).
    rows: VecDeque<Vec<f64>>,
    /// Rows needed beyond the one emitted: `max m_j + 1`.
    lookahead: usize,
}

impl Advance {
    /// `None` when no column is delayed.
    pub(crate) fn new(delays_s: &[f64], rate_hz: f64) -> Option<Advance> {
        if delays_s.iter().all(|&d| d == 0.0) {
            return None;
        }
        let shifts: Vec<f64> = delays_s.iter().map(|d| d * rate_hz).collect();
        let whole: Vec<usize> = shifts.iter().map(|s| s.floor() as usize).collect();
        let fraction = shifts
            .iter()
            .zip(&whole)
            .map(|(s, &m)| s - m as f64)
            .collect();
        let lookahead = whole.iter().max().copied().unwrap_or(0) + 1;
        Some(Advance {
            whole,
            fraction,
            rows: VecDeque::new(),
            lookahead,
        })
    }

    /// One more input row; the advanced rows that are complete go to `out`.
    pub(crate) fn push(&mut self, row: &[f64], out: &mut Vec<f64>) {
        self.rows.push_back(row.to_vec());
        while self.rows.len() > self.lookahead {
            self.emit(out);
        }
    }

    /// The end of the log: the remaining rows, reading past the end as the last row.
    pub(crate) fn finish(&mut self, out: &mut Vec<f64>) {
        while !self.rows.is_empty() {
            self.emit(out);
        }
    }

    fn emit(&mut self, out: &mut Vec<f64>) {
        let last = self.rows.len() - 1;
        for (j, (&m, &a)) in self.whole.iter().zip(&self.fraction).enumerate() {
            let at = |k: usize| self.rows[k.min(last)][j];
            out.push((1.0 - a) * at(m) + a * at(m + 1));
        }
        self.rows.pop_front();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ramp advanced by 2.25 samples reads 2.25 ahead, and holds the last value past
    /// the end; pushed in one go or row by row, the same rows.
    #[test]
    fn advance_interpolates_and_holds_the_end() {
        let rate = 100.0;
        let mut a = Advance::new(&[0.0225, 0.0], rate).unwrap();
        let mut out = Vec::new();
        for k in 0..10 {
            a.push(&[k as f64, -(k as f64)], &mut out);
        }
        a.finish(&mut out);
        assert_eq!(out.len(), 20);
        for k in 0..10 {
            let want = (k as f64 + 2.25).min(9.0);
            assert!((out[2 * k] - want).abs() < 1e-12, "{k}: {}", out[2 * k]);
            assert_eq!(out[2 * k + 1], -(k as f64));
        }
        assert!(Advance::new(&[0.0, 0.0], rate).is_none());
        assert!(check_delays(&[0.1], 2).is_err());
        assert!(check_delays(&[-0.001, 0.0], 2).is_err());
        assert!(check_delays(&[f64::NAN, 0.0], 2).is_err());
        assert!(check_delays(&[0.05, 0.0], 2).is_ok());
    }
}
