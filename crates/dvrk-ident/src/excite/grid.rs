//! The coefficient vector `x = [q0 (n); a (n×L, row per coordinate); b (n×L)]` and its
//! evaluation on fixed time grids. Everything the optimizer computes on the motion
//! (criterion samples, limit checks) is linear in `x` through these grids, so caching the
//! sines and cosines once and back-propagating gradients with the transpose
//! ([`Grid::backprop`]) makes every chain rule exact and cheap.

// Index loops mirror the math over several arrays.
#![allow(clippy::needless_range_loop)]

use std::f64::consts::PI;

use super::FourierTrajectory;

pub(crate) struct Grid {
    pub times: Vec<f64>,
    order: usize,
    w: f64,
    sin: Vec<f64>,
    cos: Vec<f64>,
}

impl Grid {
    pub fn new(times: Vec<f64>, order: usize, f0: f64) -> Grid {
        let w = 2.0 * PI * f0;
        let mut sin = Vec::with_capacity(times.len() * order);
        let mut cos = Vec::with_capacity(times.len() * order);
        for &t in &times {
            for l in 0..order {
                let (s, c) = (w * (l + 1) as f64 * t).sin_cos();
                sin.push(s);
                cos.push(c);
            }
        }
        Grid {
            times,
            order,
            w,
            sin,
            cos,
        }
    }

    /// `count` equally spaced instants over one period `[0, 1/f0)`.
    pub fn uniform(count: usize, order: usize, f0: f64) -> Grid {
        let period = 1.0 / f0;
        Grid::new(
            (0..count)
                .map(|k| k as f64 * period / count as f64)
                .collect(),
            order,
            f0,
        )
    }

    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Positions, velocities, accelerations, row-major `len × n`.
    pub fn eval(&self, x: &[f64], n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let lo = self.order;
        let (mut q, mut dq, mut ddq) = (
            vec![0.0; self.len() * n],
            vec![0.0; self.len() * n],
            vec![0.0; self.len() * n],
        );
        for k in 0..self.len() {
            let (s, c) = (&self.sin[k * lo..][..lo], &self.cos[k * lo..][..lo]);
            for j in 0..n {
                let (a, b) = (&x[n + j * lo..][..lo], &x[n + n * lo + j * lo..][..lo]);
                let (mut p, mut v, mut acc) = (x[j], 0.0, 0.0);
                for l in 0..lo {
                    let wl = self.w * (l + 1) as f64;
                    p += (a[l] * s[l] - b[l] * c[l]) / wl;
                    v += a[l] * c[l] + b[l] * s[l];
                    acc += wl * (b[l] * c[l] - a[l] * s[l]);
                }
                q[k * n + j] = p;
                dq[k * n + j] = v;
                ddq[k * n + j] = acc;
            }
        }
        (q, dq, ddq)
    }

    /// Adds the gradient with respect to `x` of a function whose gradients with respect
    /// to the grid's positions, velocities, accelerations are `gq`, `gdq`, `gddq`.
    pub fn backprop(&self, n: usize, gq: &[f64], gdq: &[f64], gddq: &[f64], gx: &mut [f64]) {
        let lo = self.order;
        for k in 0..self.len() {
            let (s, c) = (&self.sin[k * lo..][..lo], &self.cos[k * lo..][..lo]);
            for j in 0..n {
                let (p, v, a) = (gq[k * n + j], gdq[k * n + j], gddq[k * n + j]);
                if p == 0.0 && v == 0.0 && a == 0.0 {
                    continue;
                }
                gx[j] += p;
                for l in 0..lo {
                    let wl = self.w * (l + 1) as f64;
                    gx[n + j * lo + l] += p * s[l] / wl + v * c[l] - a * wl * s[l];
                    gx[n + n * lo + j * lo + l] += -p * c[l] / wl + v * s[l] + a * wl * c[l];
                }
            }
        }
    }
}

pub(crate) fn to_x(traj: &FourierTrajectory) -> Vec<f64> {
    let mut x = traj.q0.clone();
    for row in &traj.a {
        x.extend_from_slice(row);
    }
    for row in &traj.b {
        x.extend_from_slice(row);
    }
    x
}

pub(crate) fn from_x(
    x: &[f64],
    n: usize,
    order: usize,
    f0: f64,
    names: &[String],
) -> FourierTrajectory {
    FourierTrajectory {
        order,
        base_frequency_hz: f0,
        q0: x[..n].to_vec(),
        a: (0..n)
            .map(|j| x[n + j * order..][..order].to_vec())
            .collect(),
        b: (0..n)
            .map(|j| x[n + n * order + j * order..][..order].to_vec())
            .collect(),
        coordinates: names.to_vec(),
        robot: None,
    }
}

/// Projects a coefficient vector (or gradient) onto the rest subspace: per coordinate
/// `Σ_l a_jl = 0` (zero velocity at t = 0) and `Σ_l l·b_jl = 0` (zero acceleration).
pub(crate) fn project_rest(v: &mut [f64], n: usize, order: usize) {
    let lo = order;
    let wsum: f64 = (1..=lo).map(|l| (l * l) as f64).sum();
    for j in 0..n {
        let a = &mut v[n + j * lo..][..lo];
        let mean = a.iter().sum::<f64>() / lo as f64;
        a.iter_mut().for_each(|x| *x -= mean);
        let b = &mut v[n + n * lo + j * lo..][..lo];
        let dot: f64 = b.iter().enumerate().map(|(l, x)| (l + 1) as f64 * x).sum();
        b.iter_mut()
            .enumerate()
            .for_each(|(l, x)| *x -= dot * (l + 1) as f64 / wsum);
    }
}
