//! Numerical derivatives of a signal that arrives in rows: the formulas of
//! [`crate::signal::central_difference`] (the same function computes both), two rows
//! behind the input, the last two at the end.

use std::collections::VecDeque;

use crate::signal::ops::difference_at;
use crate::signal::{SignalError, Stencil};

/// Derivative of every column, fed one row at a time.
#[derive(Clone, Debug)]
pub(crate) struct Difference {
    columns: usize,
    step_s: f64,
    stencil: Stencil,
    /// The last five rows (row-major); `window[0]` is row `count - window.len() / columns`.
    window: VecDeque<f64>,
    count: usize,
    /// Derivatives emitted so far.
    done: usize,
}

impl Difference {
    pub(crate) fn new(columns: usize, step_s: f64, stencil: Stencil) -> Difference {
        Difference {
            columns,
            step_s,
            stencil,
            window: VecDeque::with_capacity(5 * columns),
            count: 0,
            done: 0,
        }
    }

    /// Derivative row `k` of a signal whose length is (at least) `n`.
    fn emit(&mut self, n: usize, out: &mut Vec<f64>) {
        let k = self.done;
        let first = self.count - self.window.len() / self.columns;
        for c in 0..self.columns {
            let x = |i: usize| self.window[(i - first) * self.columns + c];
            out.push(difference_at(x, k, n, self.step_s, self.stencil));
        }
        self.done += 1;
    }

    /// Adds a row; appends the derivative row that became known to `out`.
    pub(crate) fn push(&mut self, row: &[f64], out: &mut Vec<f64>) {
        if self.window.len() == 5 * self.columns {
            self.window.drain(..self.columns);
        }
        self.window.extend(row);
        self.count += 1;
        if self.count >= 3 {
            // Row `count - 1` exists, so row `count - 3` has its formula.
            self.emit(self.count, out);
        }
    }

    /// The end: appends the last derivative rows. Needs at least 3 rows.
    pub(crate) fn finish(&mut self, out: &mut Vec<f64>) -> Result<(), SignalError> {
        if self.count < 3 {
            return Err(SignalError::TooFewSamples {
                len: self.count,
                needed: 3,
            });
        }
        while self.done < self.count {
            self.emit(self.count, out);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::central_difference;

    #[test]
    fn streamed_equals_whole_bit_for_bit() {
        for stencil in [Stencil::FivePoint, Stencil::ThreePoint] {
            for n in [3, 4, 5, 6, 40] {
                let x: Vec<f64> = (0..n).map(|k| (0.3 * k as f64).sin() * 7.0).collect();
                let y: Vec<f64> = x.iter().map(|v| v * v - 1.0).collect();
                let mut d = Difference::new(2, 0.005, stencil);
                let mut out = Vec::new();
                for k in 0..n {
                    d.push(&[x[k], y[k]], &mut out);
                }
                d.finish(&mut out).unwrap();
                let wx = central_difference(&x, 0.005, stencil).unwrap();
                let wy = central_difference(&y, 0.005, stencil).unwrap();
                let got_x: Vec<f64> = out.iter().step_by(2).copied().collect();
                let got_y: Vec<f64> = out.iter().skip(1).step_by(2).copied().collect();
                assert_eq!((got_x, got_y), (wx, wy), "{stencil:?} n = {n}");
            }
        }
        let mut d = Difference::new(1, 0.005, Stencil::FivePoint);
        let mut out = Vec::new();
        d.push(&[1.0], &mut out);
        d.push(&[2.0], &mut out);
        assert!(matches!(
            d.finish(&mut out),
            Err(SignalError::TooFewSamples { len: 2, needed: 3 })
        ));
    }
}
