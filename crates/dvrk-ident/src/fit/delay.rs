//! The measurement delay of each coordinate's torque, estimated by variable projection:
//! the delays `d_j ∈ [0, d_max]` that minimize the weighted residual of the linear
//! least-squares fit, the parameters solved inside for every candidate.
//!
//! Why it is cheap: only the torques move with the delays ([`crate::signal::advance`]),
//! never the regressor, and a fractional delay `(m + α)/f` gives the torque column
//! `(1 − α)·P_m + α·P_{m+1}` of two whole-sample shifts `P_m`, exactly (the processing of
//! the torques is linear: the shift, the low-pass, the trimming). So one pass over the
//! samples gathers, per coordinate `j`, the Gram matrix of `[H_j | P_0 … P_K]` (the
//! regressor's rows of `j` on the base columns, the `K + 1` shifted torques, weighted);
//! after that, the residual `f(d) = c(d) − b(d)ᵀ·N⁻¹·b(d)` (`N = Σ H_jᵀH_j`, `b`, `c`
//! assembled from the Gram blocks) costs a few dot products. On each interval
//! `[m, m + 1]` of one delay, the others fixed, `f` is a quadratic in `α`: each
//! coordinate's delay is minimized exactly over its whole range, and coordinate sweeps
//! (the delays share the parameters, so they couple weakly) repeat until no delay moves
//! by more than 1e-7 s.
//!
//! The uncertainty reported is the standard error from the curvature of the residual at
//! the optimum (the parameters re-solved, the other delays fixed):
//! `std_j = √(2σ²/f''(d_j))`, `σ² = f/(rows − base parameters − delays)`. It assumes
//! white torque noise, so it is optimistic for filtered torques.

use dvrk_model::{Model, Workspace};
use nalgebra::{DMatrix, DVector};

use super::metrics::TorqueRange;
use super::observed::no_training_log;
use super::prepare::{subtract_known_forces, to_model_coordinates, LogData};
use crate::error::IdentError;
use crate::result::DelayEstimate;
use crate::settings::{FitSettings, Method};
use crate::signal::stream::process_in_blocks;
use crate::signal::{Processed, Processing};

/// Default upper end of the delay search, s.
pub const DEFAULT_MAX_DELAY_S: f64 = 0.150;

/// Samples per chunk of the Gram accumulation.
const CHUNK: usize = 512;

/// What `--delay` (Python `delay=`) asks for: `auto` (estimated over
/// `[0, DEFAULT_MAX_DELAY_S]`), or fixed delays in seconds, one for every coordinate or
/// one per coordinate (`0`: none, today's behaviour).
#[derive(Clone, Debug, PartialEq)]
pub enum DelayOption {
    /// Estimate the delays over `[0, DEFAULT_MAX_DELAY_S]` and fit with them.
    Auto,
    /// Fixed delays, s: one value for every coordinate, or one per coordinate.
    Fixed(Vec<f64>),
}

/// As the flag reads it: `"auto"`, or the list of seconds.
impl serde::Serialize for DelayOption {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            DelayOption::Auto => s.serialize_str("auto"),
            DelayOption::Fixed(d) => d.serialize(s),
        }
    }
}

impl std::str::FromStr for DelayOption {
    type Err = crate::options::ValueError;

    /// `auto`, or seconds separated by commas.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        if text.trim().eq_ignore_ascii_case("auto") {
            return Ok(DelayOption::Auto);
        }
        text.split(',')
            .map(|t| {
                t.trim()
                    .parse::<f64>()
                    .map_err(|_| crate::options::ValueError::NotDelay(t.trim().to_string()))
            })
            .collect::<Result<Vec<f64>, _>>()
            .map(DelayOption::Fixed)
    }
}

impl DelayOption {
    /// Sets the delay of `settings` for a model of `dof` coordinates; an error names
    /// the option (`delay`).
    pub fn apply(&self, settings: &mut FitSettings, dof: usize) -> Result<(), IdentError> {
        let refuse = |message: String| IdentError::Setting {
            name: crate::options::Setting::Delay.into(),
            message,
        };
        match self {
            DelayOption::Auto => {
                settings.delay_search_s = Some(DEFAULT_MAX_DELAY_S);
                settings.processing.delay_s.clear();
            }
            DelayOption::Fixed(d) => {
                let all = crate::signal::per_coordinate(d, dof).ok_or_else(|| {
                    refuse(format!(
                        "{} delays for {dof} coordinates: give one for all or one per \
                         coordinate",
                        d.len()
                    ))
                })?;
                crate::signal::advance::check_delays(&all, dof).map_err(|e| {
                    refuse(match e {
                        crate::signal::SignalError::InvalidSetting { reason, .. } => reason,
                        e => e.to_string(),
                    })
                })?;
                settings.delay_search_s = None;
                settings.processing.delay_s = if all.iter().all(|&v| v == 0.0) {
                    Vec::new()
                } else {
                    all
                };
            }
        }
        Ok(())
    }
}

/// The delays of `logs` (training logs) minimizing the least-squares residual of
/// `model` (the settings' model) with `settings`' processing and the weights of its
/// method, over `[0, max_s]` for every coordinate.
pub fn estimate_delays(
    model: &Model,
    logs: &[LogData<'_>],
    settings: &FitSettings,
    max_s: f64,
) -> Result<DelayEstimate, IdentError> {
    if !(max_s.is_finite() && max_s > 0.0 && max_s <= crate::signal::advance::MAX_DELAY_S) {
        return Err(IdentError::Setting {
            name: crate::options::Setting::Delay.into(),
            message: format!(
                "the delay search range must be within (0, {}] s, got {max_s}",
                crate::signal::advance::MAX_DELAY_S
            ),
        });
    }
    let n = model.dof();
    let base = model.base_parameters()?;
    let kept = &base.independent;
    let r = kept.len();
    let Shifted {
        logs: shifted,
        rate_hz: rate,
        shifts,
    } = shifted_logs(model, logs, settings, max_s)?;
    let rate = rate.ok_or_else(no_training_log)?;
    let columns = shifts + 1;
    let weights = match settings.method {
        Method::Ols | Method::Irls => vec![1.0; n],
        Method::Wls | Method::Sdp => {
            let mut range = TorqueRange::new(n);
            for all in &shifted {
                range.add(&all[0].tau);
            }
            range.weights()
        }
    };
    let (gram, rows) = gram_matrices(model, kept, &shifted, &weights, columns);
    let search = Search::new(&gram, r, columns, rate, max_s)?;
    let (delay_s, sweeps) = search.minimize();
    let residual = search.residual(&delay_s);
    let dof = rows.saturating_sub(r + n).max(1);
    let sigma2 = residual.max(0.0) / dof as f64;
    let std_s = (0..n)
        .map(|j| {
            let curvature = search.curvature(j, &delay_s);
            if curvature > 0.0 {
                (2.0 * sigma2 / curvature).sqrt().min(max_s)
            } else {
                max_s
            }
        })
        .collect();
    Ok(DelayEstimate {
        delay_s,
        std_s,
        max_s,
        residual,
        sweeps,
    })
}

/// Each log processed at every whole-sample shift `0..=K` (`K` from the first log's
/// rate).
fn shifted_logs(
    model: &Model,
    logs: &[LogData<'_>],
    settings: &FitSettings,
    max_s: f64,
) -> Result<Shifted, IdentError> {
    let n = model.dof();
    let mut shifted: Vec<Vec<Processed>> = Vec::with_capacity(logs.len());
    let mut rate: Option<f64> = None;
    let mut shifts = 0usize;
    for log in logs {
        let mut t = to_model_coordinates(model, log.samples)?;
        subtract_known_forces(model, &mut t);
        let process = |delay: f64| -> Result<Processed, IdentError> {
            let processing = Processing {
                delay_s: vec![delay; n],
                ..settings.processing.clone()
            };
            process_in_blocks(std::slice::from_ref(&t), &processing).map_err(|error| {
                IdentError::Signal {
                    source_name: t.source.clone(),
                    error,
                }
            })
        };
        let first = process(0.0)?;
        match rate {
            None => {
                rate = Some(first.rate_hz);
                shifts = (max_s * first.rate_hz).ceil() as usize;
            }
            Some(f) if (f - first.rate_hz).abs() > 1e-9 * f => {
                return Err(IdentError::Setting {
                    name: crate::options::Setting::Delay.into(),
                    message: format!(
                        "the delay search needs the training logs at one rate: {} is at {} Hz, \
                         the first log at {f} Hz (resample them to one rate)",
                        t.source, first.rate_hz
                    ),
                });
            }
            Some(_) => {}
        }
        let f = rate.expect("set");
        let mut all = vec![first];
        for k in 1..=shifts {
            all.push(process(k as f64 / f)?);
        }
        shifted.push(all);
    }
    Ok(Shifted {
        logs: shifted,
        rate_hz: rate,
        shifts,
    })
}

/// The training logs processed at every shift.
struct Shifted {
    /// Per log, processed at `0..=shifts` samples of delay.
    logs: Vec<Vec<Processed>>,
    /// The logs' rate, Hz; `None` without logs.
    rate_hz: Option<f64>,
    shifts: usize,
}

/// Gram matrices of `[w·H_j | w·P_0 … w·P_K]` per coordinate `j` (`H_j` the regressor
/// row of the `kept` columns, `P_k` the torque shifted by `k` samples, `w` the
/// coordinate's weight), and the number of rows.
fn gram_matrices(
    model: &Model,
    kept: &[usize],
    shifted: &[Vec<Processed>],
    weights: &[f64],
    columns: usize,
) -> (Vec<DMatrix<f64>>, usize) {
    let n = model.dof();
    let r = kept.len();
    let width = r + columns;
    let mut gram = vec![DMatrix::<f64>::zeros(width, width); n];
    let mut rows = 0usize;
    let p = model.n_params();
    let mut ws = Workspace::new(model);
    let mut h = vec![0.0; n * p];
    let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut load = vec![0.0; n];
    for all in shifted {
        let motion = &all[0];
        let len = motion.time.len();
        rows += len;
        // Each log's hysteresis states start from rest.
        ws.reset_hysteresis();
        let mut start = 0;
        while start < len {
            let end = (start + CHUNK).min(len);
            let mut x: Vec<DMatrix<f64>> = vec![DMatrix::zeros(end - start, width); n];
            for i in start..end {
                for j in 0..n {
                    q[j] = motion.q[(i, j)];
                    dq[j] = motion.dq[(i, j)];
                    ddq[j] = motion.ddq[(i, j)];
                    // Load friction's load: the first candidate's torques (the regressor
                    // is shared by every candidate delay).
                    load[j] = motion.tau[(i, j)];
                }
                model.advance_hysteresis(&mut ws, &q);
                model.set_load(&mut ws, &load);
                model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
                for (j, xj) in x.iter_mut().enumerate() {
                    let w = weights[j];
                    for (c, &col) in kept.iter().enumerate() {
                        xj[(i - start, c)] = w * h[j * p + col];
                    }
                    for (k, pk) in all.iter().enumerate() {
                        xj[(i - start, r + k)] = w * pk.tau[(i, j)];
                    }
                }
            }
            for (g, xj) in gram.iter_mut().zip(&x) {
                *g += xj.tr_mul(xj);
            }
            start = end;
        }
    }
    (gram, rows)
}

/// The residual as a function of the delays, from the Gram blocks.
struct Search {
    /// `N⁻¹·G_j` and `G_j` (`r × (K+1)`), `A_j` (`(K+1)²`) per coordinate.
    y: Vec<DMatrix<f64>>,
    g: Vec<DMatrix<f64>>,
    a: Vec<DMatrix<f64>>,
    rate: f64,
    max_s: f64,
}

impl Search {
    fn new(
        gram: &[DMatrix<f64>],
        r: usize,
        columns: usize,
        rate: f64,
        max_s: f64,
    ) -> Result<Search, IdentError> {
        let mut normal = DMatrix::<f64>::zeros(r, r);
        for g in gram {
            normal += g.view((0, 0), (r, r));
        }
        // Equilibrated Cholesky: N = D⁻¹·(D·N·D)·D⁻¹ with D = diag(1/√N_ii).
        let d = DVector::from_iterator(
            r,
            (0..r).map(|i| {
                let v = normal[(i, i)];
                if v > 0.0 {
                    1.0 / v.sqrt()
                } else {
                    1.0
                }
            }),
        );
        let scaled = DMatrix::from_fn(r, r, |i, k| d[i] * normal[(i, k)] * d[k]);
        let chol = scaled.cholesky().ok_or_else(|| IdentError::RankDeficient {
            source_name: "delay search".into(),
            message: "the data do not determine the base parameters: no delay can be \
                      estimated. Use a longer or more exciting trajectory."
                .into(),
        })?;
        let mut y = Vec::new();
        let mut g_all = Vec::new();
        let mut a_all = Vec::new();
        for g in gram {
            let gj = g.view((0, r), (r, columns)).into_owned();
            let mut rhs = gj.clone();
            for i in 0..r {
                rhs.row_mut(i).scale_mut(d[i]);
            }
            let mut yj = chol.solve(&rhs);
            for i in 0..r {
                yj.row_mut(i).scale_mut(d[i]);
            }
            y.push(yj);
            g_all.push(gj);
            a_all.push(g.view((r, r), (columns, columns)).into_owned());
        }
        Ok(Search {
            y,
            g: g_all,
            a: a_all,
            rate,
            max_s,
        })
    }

    /// Whole samples and fraction of a delay.
    fn split(&self, d: f64) -> (usize, f64) {
        let s = d * self.rate;
        let m = (s.floor() as usize).min(self.a[0].ncols() - 1);
        (m, s - m as f64)
    }

    /// `g_j(d)`, `y_j(d) = N⁻¹·g_j(d)` and `a_j(d)`.
    fn column(&self, j: usize, d: f64) -> (DVector<f64>, DVector<f64>, f64) {
        let (m, al) = self.split(d);
        let last = self.a[j].ncols() - 1;
        let m1 = (m + 1).min(last);
        let g = self.g[j].column(m) * (1.0 - al) + self.g[j].column(m1) * al;
        let y = self.y[j].column(m) * (1.0 - al) + self.y[j].column(m1) * al;
        let a = &self.a[j];
        let c = (1.0 - al).powi(2) * a[(m, m)]
            + 2.0 * al * (1.0 - al) * a[(m, m1)]
            + al * al * a[(m1, m1)];
        (g, y, c)
    }

    /// The weighted residual sum of squares at delays `d` (s).
    fn residual(&self, d: &[f64]) -> f64 {
        let (mut b, mut y, mut c) = (None::<DVector<f64>>, None::<DVector<f64>>, 0.0);
        for (j, &dj) in d.iter().enumerate() {
            let (gj, yj, cj) = self.column(j, dj);
            b = Some(b.map_or(gj.clone(), |b| b + gj));
            y = Some(y.map_or(yj.clone(), |y| y + yj));
            c += cj;
        }
        match (b, y) {
            (Some(b), Some(y)) => c - b.dot(&y),
            _ => 0.0,
        }
    }

    /// The residual on interval `m` of delay `j` (others in `rest`: `b`, `y`, `c` of
    /// the other coordinates) as `f0 + 2α·f1 + α²·f2`.
    fn quadratic(
        &self,
        j: usize,
        m: usize,
        rest: &(DVector<f64>, DVector<f64>, f64),
    ) -> (f64, f64, f64) {
        let (b, y, c) = rest;
        let (g, yj, a) = (&self.g[j], &self.y[j], &self.a[j]);
        let m1 = m + 1;
        let b0 = b + g.column(m);
        let y0 = y + yj.column(m);
        let dg = g.column(m1) - g.column(m);
        let dy = yj.column(m1) - yj.column(m);
        let f0 = c + a[(m, m)] - b0.dot(&y0);
        // b(α)ᵀN⁻¹b(α) = b0ᵀy0 + α(dgᵀy0 + b0ᵀdy) + α²·dgᵀdy; N symmetric, so the two
        // cross terms are equal up to rounding: their mean keeps f symmetric.
        let f1 = (a[(m, m1)] - a[(m, m)]) - 0.5 * (dg.dot(&y0) + b0.dot(&dy));
        let f2 = (a[(m, m)] - 2.0 * a[(m, m1)] + a[(m1, m1)]) - dg.dot(&dy);
        (f0, f1, f2)
    }

    /// The other coordinates' sums at `d`, without coordinate `j`.
    fn rest(&self, j: usize, d: &[f64]) -> (DVector<f64>, DVector<f64>, f64) {
        let r = self.g[0].nrows();
        let (mut b, mut y, mut c) = (DVector::zeros(r), DVector::zeros(r), 0.0);
        for (i, &di) in d.iter().enumerate() {
            if i != j {
                let (gi, yi, ci) = self.column(i, di);
                b += gi;
                y += yi;
                c += ci;
            }
        }
        (b, y, c)
    }

    /// The best delay of coordinate `j` over its whole range, the others at `d`.
    fn best(&self, j: usize, d: &[f64]) -> f64 {
        let rest = self.rest(j, d);
        let intervals = self.a[j].ncols() - 1;
        let mut best = (f64::INFINITY, 0.0);
        for m in 0..intervals {
            let top = (self.max_s * self.rate - m as f64).min(1.0);
            if top < 0.0 {
                break;
            }
            let (f0, f1, f2) = self.quadratic(j, m, &rest);
            let value = |al: f64| f0 + 2.0 * al * f1 + al * al * f2;
            let mut candidates = vec![0.0, top];
            if f2 > 0.0 {
                candidates.push((-f1 / f2).clamp(0.0, top));
            }
            for al in candidates {
                let v = value(al);
                if v < best.0 {
                    best = (v, (m as f64 + al) / self.rate);
                }
            }
        }
        best.1.clamp(0.0, self.max_s)
    }

    /// Coordinate sweeps from zero delays; the delays and the sweeps made.
    fn minimize(&self) -> (Vec<f64>, usize) {
        let n = self.g.len();
        let mut d = vec![0.0; n];
        for sweep in 1..=50 {
            let mut moved = 0.0f64;
            for j in 0..n {
                let new = self.best(j, &d);
                moved = moved.max((new - d[j]).abs());
                d[j] = new;
            }
            if moved <= 1e-7 {
                return (d, sweep);
            }
        }
        (d, 50)
    }

    /// `f''(d_j)` (per s²) on the interval holding `d_j` (at a whole sample: the mean
    /// of the two intervals around it).
    fn curvature(&self, j: usize, d: &[f64]) -> f64 {
        let rest = self.rest(j, d);
        let intervals = self.a[j].ncols() - 1;
        let s = d[j] * self.rate;
        let m = (s.floor() as usize).min(intervals - 1);
        let at = |m: usize| 2.0 * self.quadratic(j, m, &rest).2 * self.rate * self.rate;
        if s == m as f64 && m > 0 {
            0.5 * (at(m) + at(m - 1))
        } else {
            at(m)
        }
    }
}
