//! The L-BFGS minimizer of the excitation optimizer and the static-pose search.
//!
//! Our own although the project prefers crates: argmin's L-BFGS (backtracking Armijo or
//! More–Thuente line search) ended at MTM condition 223.6 / 222.7, above the 2019
//! trajectory, where this one reaches 216.4 (measured 2026-11-22; numbers in
//! docs/book/src/excitation.md).

// `!(x < 0.0)`-style tests are deliberate: they also catch NaN.
#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    clippy::needless_range_loop,
    clippy::ptr_arg
)]

/// `a·b` with eight independent partial sums: the compiler keeps them in SIMD
/// registers, where a single running sum would wait on every addition. The criterion's
/// gradient spends a good part of its time in these (one per regressor call).
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    acc.iter().sum::<f64>() + tail
}

/// Minimizes `f` (value, gradient; `inf` = invalid point) from `x` for at most `iters`
/// iterations. Returns the final value.
pub(crate) fn lbfgs(
    f: &mut dyn FnMut(&[f64], &mut [f64]) -> f64,
    x: &mut Vec<f64>,
    iters: usize,
) -> f64 {
    let dim = x.len();
    let mem = 10;
    let mut g = vec![0.0; dim];
    let mut fx = f(x, &mut g);
    if !fx.is_finite() {
        return fx;
    }
    let mut ss: Vec<Vec<f64>> = Vec::new();
    let mut ys: Vec<Vec<f64>> = Vec::new();
    let mut xn = vec![0.0; dim];
    let mut gn = vec![0.0; dim];
    let mut small = 0;
    for _ in 0..iters {
        // Two-loop recursion.
        let mut d: Vec<f64> = g.iter().map(|v| -v).collect();
        let mut alpha = vec![0.0; ss.len()];
        for i in (0..ss.len()).rev() {
            let rho = 1.0 / dot(&ys[i], &ss[i]);
            alpha[i] = rho * dot(&ss[i], &d);
            for (dv, yv) in d.iter_mut().zip(&ys[i]) {
                *dv -= alpha[i] * yv;
            }
        }
        if let (Some(s), Some(y)) = (ss.last(), ys.last()) {
            let gamma = dot(s, y) / dot(y, y);
            d.iter_mut().for_each(|v| *v *= gamma);
        } else {
            let gnorm = dot(&g, &g).sqrt().max(1e-300);
            d.iter_mut().for_each(|v| *v *= 0.01 / gnorm);
        }
        for i in 0..ss.len() {
            let rho = 1.0 / dot(&ys[i], &ss[i]);
            let beta = rho * dot(&ys[i], &d);
            for (dv, sv) in d.iter_mut().zip(&ss[i]) {
                *dv += (alpha[i] - beta) * sv;
            }
        }
        let mut slope = dot(&g, &d);
        if !(slope < 0.0) {
            ss.clear();
            ys.clear();
            let gnorm = dot(&g, &g).sqrt().max(1e-300);
            d = g.iter().map(|v| -v * 0.01 / gnorm).collect();
            slope = dot(&g, &d);
            if !(slope < 0.0) {
                break;
            }
        }
        let mut step = 1.0;
        let mut fnew;
        loop {
            for i in 0..dim {
                xn[i] = x[i] + step * d[i];
            }
            fnew = f(&xn, &mut gn);
            if fnew.is_finite() && fnew <= fx + 1e-4 * step * slope {
                break;
            }
            step *= 0.5;
            if step < 1e-10 {
                return fx;
            }
        }
        let s: Vec<f64> = (0..dim).map(|i| xn[i] - x[i]).collect();
        let y: Vec<f64> = (0..dim).map(|i| gn[i] - g[i]).collect();
        if dot(&s, &y) > 1e-12 * dot(&y, &y).sqrt() * dot(&s, &s).sqrt() {
            ss.push(s);
            ys.push(y);
            if ss.len() > mem {
                ss.remove(0);
                ys.remove(0);
            }
        }
        let improvement = fx - fnew;
        x.copy_from_slice(&xn);
        g.copy_from_slice(&gn);
        fx = fnew;
        if improvement < 1e-9 * (1.0 + fx.abs()) {
            small += 1;
            if small >= 5 {
                break;
            }
        } else {
            small = 0;
        }
    }
    fx
}
