//! Sample-wise operations: finite differences, trimming, decimation, sample selection
//! and uniform resampling. Matrices have one row per sample and one column per joint.

use super::SignalError;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Central-difference stencil for numerical derivatives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Stencil {
    /// `(x[k+1] - x[k-1]) / (2h)`: second-order accurate, exact for quadratics.
    ThreePoint,
    /// `(-x[k+2] + 8x[k+1] - 8x[k-1] + x[k-2]) / (12h)`: fourth-order accurate, exact
    /// for quartics; the stencil of the 2019 protocol for accelerations.
    #[default]
    FivePoint,
}

/// Numerical derivative of a uniformly sampled signal with step `step_s` (s).
///
/// Interior samples use the chosen central stencil. Samples too close to an edge for it
/// fall back to the 3-point central difference and, at the first and last sample, to the
/// second-order one-sided differences `(-3x[0] + 4x[1] - x[2]) / (2h)` and
/// `(3x[n-1] - 4x[n-2] + x[n-3]) / (2h)` (as `numpy.gradient(edge_order=2)`), so the
/// output has the input's length. Edge values are less accurate; the processing trims
/// them away together with the filter's edge effects. Needs at least 3 samples.
///
/// ```rust
/// use dvrk_ident::signal::{central_difference, Stencil};
/// let h = 0.1;
/// let x: Vec<f64> = (0..10).map(|k| (k as f64 * h).powi(2)).collect(); // t^2
/// let dx = central_difference(&x, h, Stencil::FivePoint).unwrap();
/// for (k, v) in dx.iter().enumerate() {
///     assert!((v - 2.0 * k as f64 * h).abs() < 1e-12); // 2t, exact for quadratics
/// }
/// ```
pub fn central_difference(
    x: &[f64],
    step_s: f64,
    stencil: Stencil,
) -> Result<Vec<f64>, SignalError> {
    if !(step_s.is_finite() && step_s > 0.0) {
        return Err(SignalError::InvalidSetting {
            name: "step_s",
            reason: format!("the time step must be positive and finite, got {step_s}"),
        });
    }
    let n = x.len();
    if n < 3 {
        return Err(SignalError::TooFewSamples { len: n, needed: 3 });
    }
    Ok((0..n)
        .map(|k| difference_at(|i| x[i], k, n, step_s, stencil))
        .collect())
}

/// The derivative at sample `k` of a signal of `n >= 3` samples (`x(i)` is sample `i`),
/// by the formulas of [`central_difference`]. Only samples within two of `k` are read,
/// and a stream that has seen sample `k + 2` may pass any `n > k + 2`: the formula
/// does not change, so a log differentiated block by block rounds like a whole one.
pub(crate) fn difference_at(
    x: impl Fn(usize) -> f64,
    k: usize,
    n: usize,
    h: f64,
    stencil: Stencil,
) -> f64 {
    if stencil == Stencil::FivePoint && k >= 2 && k + 2 < n {
        (-x(k + 2) + 8.0 * x(k + 1) - 8.0 * x(k - 1) + x(k - 2)) / (12.0 * h)
    } else if k >= 1 && k + 1 < n {
        (x(k + 1) - x(k - 1)) / (2.0 * h)
    } else if k == 0 {
        (-3.0 * x(0) + 4.0 * x(1) - x(2)) / (2.0 * h)
    } else {
        (3.0 * x(n - 1) - 4.0 * x(n - 2) + x(n - 3)) / (2.0 * h)
    }
}

/// [`central_difference`] applied to every column of `m` (samples in rows).
pub fn differentiate(
    m: &DMatrix<f64>,
    step_s: f64,
    stencil: Stencil,
) -> Result<DMatrix<f64>, SignalError> {
    map_columns(m, |col| central_difference(col, step_s, stencil))
}

/// Applies `f` to each column (a contiguous slice: nalgebra is column-major) and
/// assembles the results, which must keep the column length.
pub(crate) fn map_columns(
    m: &DMatrix<f64>,
    mut f: impl FnMut(&[f64]) -> Result<Vec<f64>, SignalError>,
) -> Result<DMatrix<f64>, SignalError> {
    let (n, c) = m.shape();
    let mut out = DMatrix::zeros(n, c);
    for j in 0..c {
        let col = f(&m.as_slice()[j * n..(j + 1) * n])?;
        out.column_mut(j).copy_from_slice(&col);
    }
    Ok(out)
}

/// Removes `n` samples (rows) at each end: zero-phase filters and central differences
/// are inaccurate near the edges of a log, and the 2019 protocol drops 200 samples (1 s
/// at 200 Hz) at each end. Errors when nothing would be left.
///
/// ```rust
/// use nalgebra::DMatrix;
/// let m = DMatrix::from_fn(6, 1, |i, _| i as f64);
/// let t = dvrk_ident::signal::trim_rows(&m, 2).unwrap();
/// assert_eq!(t.as_slice(), &[2.0, 3.0]);
/// ```
pub fn trim_rows(m: &DMatrix<f64>, n: usize) -> Result<DMatrix<f64>, SignalError> {
    let len = m.nrows();
    if 2 * n >= len {
        return Err(SignalError::TrimTooLong { trim: n, len });
    }
    Ok(m.rows(n, len - 2 * n).into_owned())
}

/// Keeps every `factor`-th sample (rows `0, factor, 2 factor, ...`). Only valid after a
/// low-pass below the new Nyquist frequency (`rate / (2 factor)`), which the processing
/// applies first; it thins correlated samples and shrinks the regressor.
pub fn decimate_rows(m: &DMatrix<f64>, factor: usize) -> Result<DMatrix<f64>, SignalError> {
    if factor == 0 {
        return Err(SignalError::InvalidSetting {
            name: "decimate",
            reason: "the decimation factor must be at least 1".into(),
        });
    }
    let idx: Vec<usize> = (0..m.nrows()).step_by(factor).collect();
    Ok(select_rows(m, &idx))
}

/// The rows of `m` listed in `rows` (in that order). Indices must be in range.
pub fn select_rows(m: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), m.ncols(), |i, j| m[(rows[i], j)])
}

/// The rows of `parts` one after the other: a signal's blocks joined back. Parts without
/// rows add none (whatever their width); the others must all be as wide as the widest.
pub fn stack_rows(parts: &[&DMatrix<f64>]) -> DMatrix<f64> {
    let rows = parts.iter().map(|m| m.nrows()).sum();
    let cols = parts.iter().map(|m| m.ncols()).max().unwrap_or(0);
    let mut out = DMatrix::zeros(rows, cols);
    let mut r = 0;
    for m in parts.iter().filter(|m| m.nrows() > 0) {
        out.rows_mut(r, m.nrows()).copy_from(m);
        r += m.nrows();
    }
    out
}

/// Indices of the samples where every joint moves at least `min_speed` (|dq| >=
/// `min_speed`, rad/s or m/s). Near zero velocity the sign of Coulomb friction is
/// determined by noise, so such samples can only hurt a fit that models it.
///
/// ```rust
/// use nalgebra::DMatrix;
/// let dq = DMatrix::from_row_slice(3, 2, &[0.5, -0.5, 0.001, 0.4, -0.2, 0.3]);
/// assert_eq!(dvrk_ident::signal::moving_samples(&dq, 0.01), vec![0, 2]);
/// ```
pub fn moving_samples(dq: &DMatrix<f64>, min_speed: f64) -> Vec<usize> {
    (0..dq.nrows())
        .filter(|&i| dq.row(i).iter().all(|v| v.abs() >= min_speed))
        .collect()
}

/// Resamples `m` (rows at the strictly increasing times `time`, s) onto the uniform grid
/// `time[0] + k / rate_hz` up to `time[last]`, by linear interpolation between the
/// neighbouring samples. Filtering and differentiation need a uniform clock; logs with
/// jitter or gaps (e.g. ROS time stamps) are made uniform this way first.
///
/// ```rust
/// use nalgebra::DMatrix;
/// use dvrk_ident::signal::resample_linear;
/// let time = [0.0, 0.1, 0.3];
/// let m = DMatrix::from_column_slice(3, 1, &[0.0, 1.0, 3.0]);
/// let (t, r) = resample_linear(&time, &m, 10.0).unwrap();
/// assert_eq!(t.len(), 4);
/// assert!((r[(2, 0)] - 2.0).abs() < 1e-12);
/// ```
pub fn resample_linear(
    time: &[f64],
    m: &DMatrix<f64>,
    rate_hz: f64,
) -> Result<(Vec<f64>, DMatrix<f64>), SignalError> {
    let mut resampler = super::resample::Resampler::new(m.ncols(), rate_hz)?;
    let n = time.len();
    if n != m.nrows() {
        return Err(SignalError::InvalidSetting {
            name: "time",
            reason: format!("{} time stamps for {} samples", n, m.nrows()),
        });
    }
    let (mut grid, mut values) = (Vec::new(), Vec::new());
    let mut row = vec![0.0; m.ncols()];
    for (i, &t) in time.iter().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = m[(i, j)];
        }
        resampler.push(t, &row, &mut grid, &mut values)?;
    }
    resampler.finish(&mut grid, &mut values)?;
    let out = DMatrix::from_row_slice(grid.len(), m.ncols(), &values);
    Ok((grid, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn five_point_exact_for_quartic_interior() {
        let h = 0.01;
        let f = |t: f64| 1.0 - 2.0 * t + 3.0 * t * t - 0.5 * t.powi(3) + 0.25 * t.powi(4);
        let df = |t: f64| -2.0 + 6.0 * t - 1.5 * t * t + t.powi(3);
        let x: Vec<f64> = (0..50).map(|k| f(k as f64 * h)).collect();
        let d = central_difference(&x, h, Stencil::FivePoint).unwrap();
        for (k, dk) in d.iter().enumerate().take(48).skip(2) {
            assert!((dk - df(k as f64 * h)).abs() < 1e-9, "k={k}");
        }
        // Three-point is not exact for a quartic: O(h^2) error.
        let d3 = central_difference(&x, h, Stencil::ThreePoint).unwrap();
        let err3 = (d3[25] - df(0.25)).abs();
        assert!(err3 > 1e-7 && err3 < 1e-3, "{err3}");
    }

    #[test]
    fn both_stencils_exact_for_quadratic_everywhere() {
        let h = 0.05;
        let x: Vec<f64> = (0..12)
            .map(|k| 2.0 + 3.0 * (k as f64 * h) - 4.0 * (k as f64 * h).powi(2))
            .collect();
        for s in [Stencil::ThreePoint, Stencil::FivePoint] {
            let d = central_difference(&x, h, s).unwrap();
            for (k, v) in d.iter().enumerate() {
                assert!(
                    (v - (3.0 - 8.0 * k as f64 * h)).abs() < 1e-11,
                    "{s:?} k={k}"
                );
            }
        }
        // Minimal length works too.
        let d = central_difference(&x[..3], h, Stencil::FivePoint).unwrap();
        assert_eq!(d.len(), 3);
    }

    #[test]
    fn sine_error_orders() {
        // Derivative of sin(w t): error ~ h^2 w^3 / 6 (3-point) and h^4 w^5 / 30 (5-point).
        let w = 2.0 * std::f64::consts::PI * 1.5;
        let h = 1.0 / 200.0;
        let x: Vec<f64> = (0..400).map(|k| (w * k as f64 * h).sin()).collect();
        let d3 = central_difference(&x, h, Stencil::ThreePoint).unwrap();
        let d5 = central_difference(&x, h, Stencil::FivePoint).unwrap();
        let mut e3: f64 = 0.0;
        let mut e5: f64 = 0.0;
        for k in 2..398 {
            let exact = w * (w * k as f64 * h).cos();
            e3 = e3.max((d3[k] - exact).abs());
            e5 = e5.max((d5[k] - exact).abs());
        }
        let b3 = h * h * w.powi(3) / 6.0;
        let b5 = h.powi(4) * w.powi(5) / 30.0;
        assert!(e3 <= 1.01 * b3 && e3 > 0.9 * b3, "{e3} vs {b3}");
        assert!(e5 <= 1.01 * b5 && e5 > 0.9 * b5, "{e5} vs {b5}");
    }

    #[test]
    fn derivative_errors() {
        assert!(matches!(
            central_difference(&[1.0, 2.0], 0.1, Stencil::ThreePoint),
            Err(SignalError::TooFewSamples { len: 2, needed: 3 })
        ));
        assert!(central_difference(&[1.0; 5], 0.0, Stencil::ThreePoint).is_err());
        assert!(central_difference(&[1.0; 5], f64::NAN, Stencil::ThreePoint).is_err());
    }

    #[test]
    fn matrix_ops() {
        let m = DMatrix::from_fn(10, 2, |i, j| (i * 10 + j) as f64);
        let d = differentiate(&m, 1.0, Stencil::FivePoint).unwrap();
        assert!(d.iter().all(|v| (v - 10.0).abs() < 1e-12));
        let t = trim_rows(&m, 3).unwrap();
        assert_eq!(t.nrows(), 4);
        assert_eq!(t[(0, 1)], 31.0);
        assert!(matches!(
            trim_rows(&m, 5),
            Err(SignalError::TrimTooLong { trim: 5, len: 10 })
        ));
        let dec = decimate_rows(&m, 3).unwrap();
        assert_eq!(dec.nrows(), 4);
        assert_eq!(dec[(3, 0)], 90.0);
        assert_eq!(decimate_rows(&m, 1).unwrap(), m);
        assert!(decimate_rows(&m, 0).is_err());
        let s = select_rows(&m, &[9, 0]);
        assert_eq!(s[(0, 1)], 91.0);
        // Cut and joined back, an empty block between: the same matrix.
        let (head, tail) = (
            select_rows(&m, &[0, 1, 2, 3]),
            select_rows(&m, &[4, 5, 6, 7, 8, 9]),
        );
        assert_eq!(stack_rows(&[&head, &DMatrix::zeros(0, 0), &tail]), m);
        assert_eq!(stack_rows(&[]).shape(), (0, 0));
        assert_eq!(s[(1, 0)], 0.0);
    }

    #[test]
    fn resampling_linear_signals_is_exact() {
        // Jittered clock, linear signal: interpolation reproduces it exactly.
        let time: Vec<f64> = (0..50)
            .map(|k| k as f64 * 0.01 + if k % 3 == 1 { 0.002 } else { 0.0 })
            .collect();
        let m = DMatrix::from_fn(50, 2, |i, j| (j as f64 + 1.0) * time[i] - 0.3);
        let (t, r) = resample_linear(&time, &m, 100.0).unwrap();
        assert_eq!(t.len(), 50);
        for (i, ti) in t.iter().enumerate() {
            assert!((ti - i as f64 * 0.01).abs() < 1e-12);
            for j in 0..2 {
                assert!((r[(i, j)] - ((j as f64 + 1.0) * ti - 0.3)).abs() < 1e-12);
            }
        }
        // Upsampling by 2 over [0, 0.49]: 99 points.
        let (t2, _) = resample_linear(&time, &m, 200.0).unwrap();
        assert_eq!(t2.len(), 99);
        assert!(resample_linear(&time, &m, 0.0).is_err());
        assert!(resample_linear(&time[..10], &m, 100.0).is_err());
        let bad = [0.0, 0.0, 1.0];
        assert!(resample_linear(&bad, &DMatrix::zeros(3, 1), 10.0).is_err());
    }
}
