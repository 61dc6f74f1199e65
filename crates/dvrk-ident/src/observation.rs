//! The weighted observation matrix `[W·H | W·τ]`, reduced on the fly to its R factor.
//!
//! The estimators only need `R` ((p+1)×(p+1)): `‖W H π − W τ‖² = ‖R₁₁ π − r₁‖² + ρ²`.
//! The rows are reduced per coordinate ([`PerCoordinate`]), unweighted, so that the
//! weights can be chosen once the data are read ([`Observation::weighted`]). Each
//! coordinate keeps a running triangular factor over the columns that have been
//! nonzero in its rows: a row of the wrist's coordinate has a few dozen nonzero
//! entries out of a hundred, and a QR update costs the square of the width, so this
//! cuts the work by about ten on the dVRK arms. Samples come in chunks of
//! [`CHUNK_SAMPLES`]; the regressor of a batch of chunks is evaluated in parallel
//! (rayon), then each factor takes its chunks' rows by a QR of the factor stacked on
//! them (faer, one thread per factor). Each coordinate has [`LANES`] factors that take
//! alternate chunks and are merged at the end, so that the work spreads over threads
//! while the result depends only on the data: not on the number of threads, and not
//! on how the log was cut into batches of whole chunks (a log streamed from disk and
//! the same log in memory give the same factors to the last bit). Memory does not grow
//! with the log length, and observations of several logs combine with
//! [`Observation::merge`].

use dvrk_model::{Model, Workspace};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor::{
    qr_in_place, qr_in_place_scratch, recommended_block_size,
};
use faer::{Mat, MatMut, Par};
use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::progress::Progress;

/// Samples per chunk: the unit of parallel regressor evaluation and of a factor's QR
/// update (1024 rows on top of the factor's at most p+1: the update costs little more
/// than the rows' own reduction).
pub const CHUNK_SAMPLES: usize = 1024;

/// Factors per coordinate, taking alternate chunks (a fixed number, so that the result
/// does not depend on the machine).
pub const LANES: usize = 2;

/// The R factor of a stacked weighted observation, plus the row count.
#[derive(Clone, Debug)]
pub struct Observation {
    /// Upper-triangular (p+1)×(p+1), non-negative diagonal; last column is the torque.
    r: DMatrix<f64>,
    /// Rows stacked so far (samples × coordinates).
    rows: usize,
}

/// Joint-space samples in model coordinates, one row per sample.
#[derive(Clone, Copy, Debug)]
pub struct Samples<'a> {
    /// rad or m
    pub q: &'a DMatrix<f64>,
    /// rad/s or m/s
    pub dq: &'a DMatrix<f64>,
    /// rad/s² or m/s²
    pub ddq: &'a DMatrix<f64>,
    /// N·m or N, known forces already subtracted
    pub tau: &'a DMatrix<f64>,
}

impl Samples<'_> {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.q.nrows()
    }

    /// Coordinates of sample `k` into the three buffers.
    pub fn read(&self, k: usize, q: &mut [f64], dq: &mut [f64], ddq: &mut [f64]) {
        for j in 0..q.len() {
            q[j] = self.q[(k, j)];
            dq[j] = self.dq[(k, j)];
            ddq[j] = self.ddq[(k, j)];
        }
    }
}

/// QR of `a` (rows × c) reduced to its c×c (or rows×c if fewer rows) R with a
/// non-negative diagonal, so factors of the same data compare entry by entry.
fn r_factor(a: &Mat<f64>) -> DMatrix<f64> {
    let c = a.ncols();
    let mut work = a.clone();
    let mut qr = Qr::default();
    qr.factor(work.as_mut());
    let k = c.min(a.nrows());
    let mut out = DMatrix::zeros(c, c);
    for i in 0..k {
        let sign = if work[(i, i)] < 0.0 { -1.0 } else { 1.0 };
        for j in i..c {
            out[(i, j)] = sign * work[(i, j)];
        }
    }
    out
}

/// A sequential in-place QR (faer's blocked Householder) with its scratch kept between
/// calls: the observation's factors are updated in parallel, one per thread, so faer's
/// own parallelism would only add synchronization.
#[derive(Default)]
struct Qr {
    coeff: Vec<f64>,
    mem: Option<MemBuffer>,
    mem_for: (usize, usize),
}

impl Qr {
    /// Overwrites the upper triangle of `a` with R.
    fn factor(&mut self, a: MatMut<'_, f64>) {
        let (m, n) = (a.nrows(), a.ncols());
        let size = m.min(n);
        if size == 0 {
            return;
        }
        let bs = recommended_block_size::<f64>(m, n);
        if self.mem.is_none() || self.mem_for != (bs, n) {
            let req = qr_in_place_scratch::<f64>(m, n, bs, Par::Seq, Default::default());
            self.mem = Some(MemBuffer::new(req));
            self.mem_for = (bs, n);
        }
        self.coeff.clear();
        self.coeff.resize(bs * size, 0.0);
        let coeff = MatMut::from_column_major_slice_mut(&mut self.coeff, bs, size);
        let mem = self.mem.as_mut().expect("scratch");
        qr_in_place(a, coeff, Par::Seq, MemStack::new(mem), Default::default());
    }
}

/// One coordinate's running factor over the columns (of `[H | τ]`) that have been
/// nonzero in its rows so far.
#[derive(Default)]
struct Factor {
    /// Columns seen nonzero, increasing.
    cols: Vec<usize>,
    /// Columns that can still become nonzero (the regressor's pattern, not yet seen).
    unseen: Vec<usize>,
    /// k×k upper triangular (k = `cols.len()`), column-major.
    r: Vec<f64>,
    rows: usize,
    /// Scratch: the factor stacked on the new rows (column-major), columns seen.
    stacked: Vec<f64>,
    seen: Vec<usize>,
    qr: Qr,
}

impl Factor {
    /// A factor for rows whose nonzero entries can only be in columns `pattern`.
    fn new(pattern: Vec<usize>) -> Factor {
        Factor {
            unseen: pattern,
            ..Factor::default()
        }
    }

    /// Takes the rows `rows` (full layout, p+1 wide).
    fn add<'a>(&mut self, rows: impl Iterator<Item = &'a [f64]> + Clone) {
        let count = rows.clone().count();
        if count == 0 {
            return;
        }
        // Columns newly nonzero: a zero row and column of the factor each, in order.
        self.seen.clear();
        if !self.unseen.is_empty() {
            for row in rows.clone() {
                self.unseen.retain(|&c| {
                    let new = row[c] != 0.0;
                    if new {
                        self.seen.push(c);
                    }
                    !new
                });
            }
        }
        if !self.seen.is_empty() {
            let mut cols = self.cols.clone();
            cols.extend(&self.seen);
            cols.sort_unstable();
            let (old, k) = (self.cols.len(), cols.len());
            let mut r = vec![0.0; k * k];
            let at: Vec<usize> = self
                .cols
                .iter()
                .map(|c| cols.binary_search(c).expect("kept"))
                .collect();
            for j in 0..old {
                for i in 0..=j {
                    r[at[i] + at[j] * k] = self.r[i + j * old];
                }
            }
            self.cols = cols;
            self.r = r;
        }
        let k = self.cols.len();
        let m = k + count;
        self.stacked.clear();
        self.stacked.resize(m * k, 0.0);
        for j in 0..k {
            self.stacked[j * m..j * m + j + 1].copy_from_slice(&self.r[j * k..j * k + j + 1]);
        }
        // Row by row (each row read once), into the columns.
        for (i, row) in rows.enumerate() {
            for (j, &c) in self.cols.iter().enumerate() {
                self.stacked[j * m + k + i] = row[c];
            }
        }
        let a = MatMut::from_column_major_slice_mut(&mut self.stacked, m, k);
        self.qr.factor(a);
        for j in 0..k {
            self.r[j * k..j * k + j + 1].copy_from_slice(&self.stacked[j * m..j * m + j + 1]);
        }
        self.rows += count;
    }

    /// Takes the rows of another factor of the same coordinate.
    fn merge(&mut self, other: &Factor, width: usize) {
        let k = other.cols.len();
        let rows: Vec<Vec<f64>> = (0..k)
            .map(|i| {
                let mut row = vec![0.0; width];
                for j in i..k {
                    row[other.cols[j]] = other.r[i + j * k];
                }
                row
            })
            .collect();
        let rows_before = self.rows;
        self.unseen
            .extend(other.cols.iter().filter(|c| !self.cols.contains(c)));
        self.unseen.sort_unstable();
        self.unseen.dedup();
        self.add(rows.iter().map(Vec::as_slice));
        self.rows = rows_before + other.rows;
    }

    /// The factor in the full layout, (p+1)×(p+1) with a non-negative diagonal.
    fn observation(&self, width: usize) -> Observation {
        let k = self.cols.len();
        let mut r = DMatrix::zeros(width, width);
        for i in 0..k {
            let sign = if self.r[i + i * k] < 0.0 { -1.0 } else { 1.0 };
            for j in i..k {
                r[(self.cols[i], self.cols[j])] = sign * self.r[i + j * k];
            }
        }
        Observation { r, rows: self.rows }
    }
}

/// The per-coordinate reduction of samples given in order (see the module docs):
/// [`PerCoordinate::add`] batches of whole chunks (any number of samples in the last
/// one), then [`PerCoordinate::finish`].
pub struct PerCoordinate {
    n: usize,
    width: usize,
    /// `LANES` factors per coordinate: coordinate j, lane l at `j * LANES + l`.
    factors: Vec<Factor>,
    /// Chunks added so far, and whether the last one was partial (the end).
    chunks: usize,
    ended: bool,
    /// The rows of the chunks in flight, reused.
    blocks: Vec<Vec<f64>>,
    /// The hysteresis (Dahl) states carried from batch to batch in time order (`None`
    /// for a model without Dahl elements), and their columns.
    hysteresis: Option<(Workspace, Vec<usize>)>,
    /// Each sample's hysteresis states of the batch in flight, `columns` per sample.
    states: Vec<f64>,
}

impl PerCoordinate {
    /// An empty reduction for `model`'s coordinates and parameters.
    pub fn new(model: &Model) -> Self {
        let n = model.dof();
        let p = model.n_params();
        let pattern = model.regressor_pattern();
        PerCoordinate {
            n,
            width: p + 1,
            factors: (0..n * LANES)
                .map(|f| {
                    let mut columns = pattern[f / LANES].clone();
                    columns.push(p);
                    Factor::new(columns)
                })
                .collect(),
            chunks: 0,
            ended: false,
            blocks: Vec::new(),
            hysteresis: {
                let columns = model.hysteresis_columns();
                (!columns.is_empty()).then(|| (Workspace::new(model), columns))
            },
            states: Vec::new(),
        }
    }

    /// Adds `samples`, which continue the samples added so far; every call but the last
    /// must give whole chunks of [`CHUNK_SAMPLES`]. `progress` counts the samples done
    /// (from the worker threads, one call per chunk).
    pub fn add(&mut self, model: &Model, samples: Samples<'_>, progress: &dyn Progress) {
        assert!(
            !self.ended,
            "samples after a partial chunk: all but the last batch must be whole chunks"
        );
        let (n, p, width) = (self.n, model.n_params(), self.width);
        assert_eq!(model.dof(), n, "the model of the reduction");
        let count = samples.len();
        let chunks: Vec<(usize, usize)> = (0..count)
            .step_by(CHUNK_SAMPLES)
            .map(|s| (s, (s + CHUNK_SAMPLES).min(count)))
            .collect();
        self.ended = count % CHUNK_SAMPLES != 0;
        // The hysteresis states depend on the path: integrated here in time order (from
        // the state the previous batch ended in), then read by the chunks in parallel.
        let m = self.hysteresis.as_ref().map_or(0, |(_, c)| c.len());
        if let Some((carry, columns)) = &mut self.hysteresis {
            self.states.clear();
            self.states.reserve(count * m);
            let mut q = vec![0.0; n];
            for k in 0..count {
                for (j, x) in q.iter_mut().enumerate() {
                    *x = samples.q[(k, j)];
                }
                model.advance_hysteresis(carry, &q);
                let z = carry.hysteresis();
                self.states.extend(columns.iter().map(|&c| z[c]));
            }
        }
        let (states, columns) = (
            &self.states,
            self.hysteresis.as_ref().map(|(_, c)| c.as_slice()),
        );
        let in_flight = (2 * rayon::current_num_threads()).clamp(2 * LANES, 16);
        for group in chunks.chunks(in_flight) {
            // The rows [H | τ] of each chunk, row k·n + j for coordinate j of sample k.
            if self.blocks.len() < group.len() {
                self.blocks.resize_with(group.len(), Vec::new);
            }
            let blocks = &mut self.blocks[..group.len()];
            group.par_iter().zip(blocks.par_iter_mut()).for_each_init(
                || {
                    (
                        Workspace::new(model),
                        vec![0.0; n * p],
                        vec![0.0; n],
                        vec![0.0; n],
                        vec![0.0; n],
                        vec![0.0; n],
                    )
                },
                |(ws, h, q, dq, ddq, tau), (&(start, end), block)| {
                    // Every entry is written below.
                    block.resize((end - start) * n * width, 0.0);
                    for k in start..end {
                        samples.read(k, q, dq, ddq);
                        if let Some(columns) = columns {
                            for (i, &c) in columns.iter().enumerate() {
                                ws.set_hysteresis(c, states[k * m + i]);
                            }
                        }
                        // Load friction's load: the measured torque of the sample.
                        for (j, t) in tau.iter_mut().enumerate() {
                            *t = samples.tau[(k, j)];
                        }
                        model.set_load(ws, tau);
                        model.regressor_into(ws, q, dq, ddq, h);
                        for j in 0..n {
                            let row = &mut block[((k - start) * n + j) * width..][..width];
                            row[..p].copy_from_slice(&h[j * p..(j + 1) * p]);
                            row[p] = samples.tau[(k, j)];
                        }
                    }
                    progress.advance((end - start) as u64);
                },
            );
            let blocks = &self.blocks[..group.len()];
            let first = self.chunks;
            self.factors
                .par_iter_mut()
                .enumerate()
                .for_each(|(f, factor)| {
                    let (j, lane) = (f / LANES, f % LANES);
                    for (c, block) in blocks.iter().enumerate() {
                        if (first + c) % LANES == lane {
                            factor.add(block.chunks_exact(width).skip(j).step_by(n));
                        }
                    }
                });
            self.chunks += group.len();
        }
    }

    /// One observation per coordinate (the lanes merged in order).
    pub fn finish(mut self) -> Vec<Observation> {
        let width = self.width;
        self.factors
            .chunks_mut(LANES)
            .map(|lanes| {
                let (first, rest) = lanes.split_at_mut(1);
                for other in rest.iter() {
                    first[0].merge(other, width);
                }
                first[0].observation(width)
            })
            .collect()
    }
}

impl Observation {
    /// An empty observation for `p` parameters.
    pub fn new(p: usize) -> Self {
        Observation {
            r: DMatrix::zeros(p + 1, p + 1),
            rows: 0,
        }
    }

    /// An observation from its factor (read back from an observation state): `r` is
    /// (p+1)×(p+1) upper triangular, `rows` the rows it reduces.
    pub(crate) fn from_factor(r: DMatrix<f64>, rows: usize) -> Observation {
        debug_assert!(r.is_square());
        Observation { r, rows }
    }

    /// Number of parameters (columns without the torque).
    pub fn n_params(&self) -> usize {
        self.r.ncols() - 1
    }

    /// Rows stacked so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// `‖R·[π; −1]‖²`: the sum over the rows of `(τ − H·π)²` (exact up to rounding),
    /// the residual of `params` without a pass over the data (the training metrics and
    /// IRLS's weights).
    pub fn residual_sum_of_squares(&self, params: &[f64]) -> f64 {
        let mut x = params.to_vec();
        x.push(-1.0);
        (&self.r * nalgebra::DVector::from_column_slice(&x)).norm_squared()
    }

    /// The R factor, (p+1)×(p+1).
    pub fn r(&self) -> &DMatrix<f64> {
        &self.r
    }

    /// Appends rows `[W·H | W·τ]` (each row: p regressor entries then the torque).
    pub fn add_rows(&mut self, block: &DMatrix<f64>) {
        assert_eq!(block.ncols(), self.r.ncols(), "block width");
        if block.nrows() == 0 {
            return;
        }
        let c = self.r.ncols();
        let stacked = Mat::from_fn(c + block.nrows(), c, |i, j| {
            if i < c {
                self.r[(i, j)]
            } else {
                block[(i - c, j)]
            }
        });
        self.r = r_factor(&stacked);
        self.rows += block.nrows();
    }

    /// Combines with the observation of other data: the result is the factor of both
    /// stacked (exact up to round-off).
    pub fn merge(&mut self, other: &Observation) {
        assert_eq!(
            other.r.ncols(),
            self.r.ncols(),
            "observations of different models"
        );
        let c = self.r.ncols();
        let stacked = Mat::from_fn(2 * c, c, |i, j| {
            if i < c {
                self.r[(i, j)]
            } else {
                other.r[(i - c, j)]
            }
        });
        self.r = r_factor(&stacked);
        self.rows += other.rows;
    }

    /// The factor of the columns `cols` (and the torque), e.g. the base regressor's:
    /// `‖A x‖ = ‖R x‖` for every `x`, so selecting columns of `R` and re-factorizing
    /// gives the factor of the selected columns of the full observation.
    pub fn select(&self, cols: &[usize]) -> Observation {
        let p = self.n_params();
        let mut all: Vec<usize> = cols.to_vec();
        all.push(p);
        let sel = Mat::from_fn(self.r.nrows(), all.len(), |i, j| self.r[(i, all[j])]);
        Observation {
            r: r_factor(&sel),
            rows: self.rows,
        }
    }

    /// The factor of the rows with column `col`'s direction projected out:
    /// `A (I − e e ᵀAᵀA / ‖A e‖²)` for `e` the unit vector of `col`, so column `col`
    /// becomes zero and every other column (and the torque) loses its least-squares
    /// component along it (exact up to rounding, from the factor alone since
    /// `A e = Q·R e`). For a column that is constant over the rows (a coordinate's
    /// torque offset `Fo`), this removes each column's mean: a fit of the result is the
    /// fit with one free offset for these rows, eliminated (Frisch–Waugh–Lovell). A
    /// column that is zero over the rows leaves the factor as it is.
    pub fn project_out(&self, col: usize) -> Observation {
        let u = self.r.column(col).into_owned();
        let uu = u.norm_squared();
        if uu == 0.0 {
            return self.clone();
        }
        let proj = &self.r - &u * (u.transpose() * &self.r) / uu;
        let m = Mat::from_fn(proj.nrows(), proj.ncols(), |i, j| proj[(i, j)]);
        Observation {
            r: r_factor(&m),
            rows: self.rows,
        }
    }

    /// Observation of `samples` with per-coordinate row weights `weights` (1/N·m or
    /// 1/N): the per-coordinate reduction, weighted (the tests' reference).
    #[cfg(test)]
    pub fn assemble(model: &Model, samples: Samples<'_>, weights: &[f64]) -> Observation {
        let parts = Observation::assemble_per_coordinate(model, samples, &crate::progress::Silent);
        Observation::weighted(&parts, weights)
    }

    /// One observation per coordinate, unweighted: the rows of the observation split by
    /// the coordinate they belong to ([`PerCoordinate`]). Weights can then be chosen
    /// after the data are read, with [`Observation::weighted`]: what a fit streamed
    /// over a long log needs, where the weights come from the whole log.
    ///
    /// `progress` counts the samples done (from the worker threads, one call per chunk).
    pub fn assemble_per_coordinate(
        model: &Model,
        samples: Samples<'_>,
        progress: &dyn Progress,
    ) -> Vec<Observation> {
        let mut reduction = PerCoordinate::new(model);
        reduction.add(model, samples, progress);
        reduction.finish()
    }

    /// The observation of the coordinates' rows (`parts`, one per coordinate, from
    /// [`Observation::assemble_per_coordinate`]) each scaled by its weight: the factor
    /// of `[w₁ R₁; …; wₙ Rₙ]`, which has the Gram matrix of the weighted rows (exact up
    /// to rounding).
    pub fn weighted(parts: &[Observation], weights: &[f64]) -> Observation {
        assert_eq!(parts.len(), weights.len(), "one weight per coordinate");
        let c = parts.first().map_or(1, |o| o.r.ncols());
        let stacked = Mat::from_fn(c * parts.len(), c, |i, j| {
            weights[i / c] * parts[i / c].r[(i % c, j)]
        });
        Observation {
            r: r_factor(&stacked),
            rows: parts.iter().map(|o| o.rows).sum(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;
    use crate::signal::stack_rows;

    fn random_samples(model: &Model, count: usize, seed: u64) -> [DMatrix<f64>; 4] {
        let n = model.dof();
        let mut rng = dvrk_test_support::Rng::new(seed);
        let mut next = move || rng.uniform(-1.0, 1.0);
        let mut m = || DMatrix::from_fn(count, n, |_, _| next());
        [m(), m(), m(), m()]
    }

    /// The samples of the matrices `[q, q̇, q̈, τ]`.
    fn samples(m: &[DMatrix<f64>; 4]) -> Samples<'_> {
        let [q, dq, ddq, tau] = m;
        Samples { q, dq, ddq, tau }
    }

    /// Rows `lo..hi` of each of `[q, q̇, q̈, τ]`.
    fn rows(m: &[DMatrix<f64>; 4], lo: usize, hi: usize) -> [DMatrix<f64>; 4] {
        m.each_ref().map(|x| x.rows(lo, hi - lo).into_owned())
    }

    #[test]
    fn chunked_factor_equals_one_shot_qr() {
        let model = Model::builtin("psm").unwrap();
        let (n, p) = (model.dof(), model.n_params());
        let count = 3 * CHUNK_SAMPLES + 17;
        let m = random_samples(&model, count, 7);
        let weights: Vec<f64> = (0..n).map(|j| 1.0 + 0.1 * j as f64).collect();
        let obs = Observation::assemble(&model, samples(&m), &weights);
        assert_eq!(obs.rows(), count * n);
        // One-shot: the whole weighted matrix at once.
        let full = weighted_rows(&model, samples(&m), &weights);
        // The Gram matrices agree (R is unique only up to the rank-deficient block).
        let g1 = obs.r().transpose() * obs.r();
        let g2 = full.transpose() * &full;
        let scale = g2.amax();
        assert!((g1 - g2).amax() < 1e-10 * scale);
        // Least-squares residual of any parameter vector agrees.
        let pi = nalgebra::DVector::from_fn(p, |i, _| (i as f64 * 0.37).sin());
        let mut x = pi.clone().insert_row(p, -1.0);
        let r1 = (obs.r() * &x).norm();
        let r2 = (&full * &x).norm();
        assert!((r1 - r2).abs() < 1e-9 * r2);
        x[0] += 1.0;
        assert!(((obs.r() * &x).norm() - (&full * &x).norm()).abs() < 1e-9 * r2);
    }

    /// The rows `[H | τ]` of coordinate `j`, one per sample, directly.
    fn coordinate_rows(model: &Model, s: Samples<'_>, j: usize) -> DMatrix<f64> {
        let (n, p) = (model.dof(), model.n_params());
        let mut ws = Workspace::new(model);
        let (mut a, mut b, mut c) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut h = vec![0.0; n * p];
        let mut rows = DMatrix::zeros(s.len(), p + 1);
        for k in 0..s.len() {
            s.read(k, &mut a, &mut b, &mut c);
            model.advance_hysteresis(&mut ws, &a);
            let tau: Vec<f64> = (0..n).map(|j| s.tau[(k, j)]).collect();
            model.set_load(&mut ws, &tau);
            model.regressor_into(&mut ws, &a, &b, &c, &mut h);
            for col in 0..p {
                rows[(k, col)] = h[j * p + col];
            }
            rows[(k, p)] = s.tau[(k, j)];
        }
        rows
    }

    /// The rows `[H | τ]` of every coordinate, coordinate `j`'s weighted by `weights[j]`,
    /// one block of rows a coordinate.
    fn weighted_rows(model: &Model, s: Samples<'_>, weights: &[f64]) -> DMatrix<f64> {
        let blocks: Vec<DMatrix<f64>> = (0..model.dof())
            .map(|j| coordinate_rows(model, s, j) * weights[j])
            .collect();
        stack_rows(&blocks.iter().collect::<Vec<_>>())
    }

    fn assert_same_gram(what: &str, r: &DMatrix<f64>, rows: &DMatrix<f64>) {
        let g1 = r.transpose() * r;
        let g2 = rows.transpose() * rows;
        let err = (&g1 - &g2).amax();
        assert!(
            err < 1e-12 * g2.amax(),
            "{what}: Gram matrices differ by {err:e}"
        );
    }

    #[test]
    fn per_coordinate_parts_hold_their_coordinates_rows() {
        let mtm = Model::builtin("mtm").unwrap();
        // With Dahl friction the states integrated in time order before the parallel
        // chunks equal those of the sample-by-sample rows.
        for model in [mtm.clone(), mtm.with_dahl(20.0).unwrap()] {
            per_coordinate_parts_of(&model);
        }
    }

    fn per_coordinate_parts_of(model: &Model) {
        let model = model.clone();
        let n = model.dof();
        let mut m = random_samples(&model, 2 * CHUNK_SAMPLES + 700, 11);
        // At rest for a chunk and a half: the Coulomb, viscous and motor-inertia columns
        // are zero until the arm moves, then join the factors.
        for k in 0..CHUNK_SAMPLES * 3 / 2 {
            for j in 0..n {
                m[1][(k, j)] = 0.0;
                m[2][(k, j)] = 0.0;
            }
        }
        let s = samples(&m);
        let parts = Observation::assemble_per_coordinate(&model, s, &Silent);
        assert_eq!(parts.len(), n);
        for (j, part) in parts.iter().enumerate() {
            assert_eq!(part.rows(), s.len());
            let r = part.r();
            for i in 0..r.nrows() {
                assert!(r[(i, i)] >= 0.0, "non-negative diagonal");
                for c in 0..i {
                    assert_eq!(r[(i, c)], 0.0, "upper triangular");
                }
            }
            assert_same_gram(
                &format!("coordinate {j}"),
                r,
                &coordinate_rows(&model, s, j),
            );
        }
        // Weighted: the factor of the weighted rows of all coordinates.
        let weights: Vec<f64> = (0..n).map(|j| 0.5 + 0.3 * j as f64).collect();
        let combined = Observation::weighted(&parts, &weights);
        assert_same_gram(
            "weighted",
            combined.r(),
            &weighted_rows(&model, s, &weights),
        );
    }

    #[test]
    fn batches_of_whole_chunks_give_the_same_factors_to_the_bit() {
        let psm = Model::builtin("psm").unwrap();
        // The Dahl states carried from batch to batch: streamed == in memory, to the bit.
        for model in [psm.clone(), psm.with_dahl(20.0).unwrap()] {
            batches_of(&model);
        }
    }

    fn batches_of(model: &Model) {
        let model = model.clone();
        let m = random_samples(&model, 4 * CHUNK_SAMPLES + 123, 5);
        let once = Observation::assemble_per_coordinate(&model, samples(&m), &Silent);
        let mut reduction = PerCoordinate::new(&model);
        let cuts = [0, CHUNK_SAMPLES, 3 * CHUNK_SAMPLES, m[0].nrows()];
        for w in cuts.windows(2) {
            reduction.add(&model, samples(&rows(&m, w[0], w[1])), &Silent);
        }
        let batched = reduction.finish();
        for (x, y) in once.iter().zip(&batched) {
            assert_eq!(x.r(), y.r());
            assert_eq!(x.rows(), y.rows());
        }
    }

    #[test]
    fn merge_and_select_are_exact() {
        let model = Model::builtin("mtm").unwrap();
        let n = model.dof();
        let m = random_samples(&model, 300, 3);
        let w = vec![1.0; n];
        let all = Observation::assemble(&model, samples(&m), &w);
        let mut a = Observation::assemble(&model, samples(&rows(&m, 0, 100)), &w);
        let b = Observation::assemble(&model, samples(&rows(&m, 100, 300)), &w);
        a.merge(&b);
        assert_eq!(a.rows(), all.rows());
        let g1 = a.r().transpose() * a.r();
        let g2 = all.r().transpose() * all.r();
        assert!((g1 - &g2).amax() < 1e-10 * g2.amax());
        // Selecting columns equals the Gram sub-matrix.
        let cols = [0usize, 5, 9, 40];
        let s = all.select(&cols);
        let gs = s.r().transpose() * s.r();
        let p = model.n_params();
        let idx = [0usize, 5, 9, 40, p];
        for (i, &a) in idx.iter().enumerate() {
            for (j, &b) in idx.iter().enumerate() {
                assert!((gs[(i, j)] - g2[(a, b)]).abs() < 1e-10 * g2.amax());
            }
        }
    }
}

/// Property test (proptest, stable Rust, fixed seed): the observation (R factor) of
/// samples does not depend on how they are split into chunks nor on the order the chunks
/// are merged in.
#[cfg(test)]
mod properties {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngSeed};

    fn config(cases: u32) -> Config {
        Config {
            cases,
            rng_seed: RngSeed::Fixed(0x005e_ed19),
            failure_persistence: None,
            ..Config::default()
        }
    }

    /// `rows` random samples of `model` from `seed`: positions, rates and torques.
    fn samples(model: &Model, rows: usize, seed: u64) -> [DMatrix<f64>; 4] {
        let mut rng = dvrk_test_support::Rng::new(seed);
        let mut next = move |scale: f64| rng.uniform(-0.5 * scale, 0.5 * scale);
        let n = model.dof();
        [2.0, 4.0, 20.0, 10.0].map(|scale| DMatrix::from_fn(rows, n, |_, _| next(scale)))
    }

    proptest! {
        #![proptest_config(config(24))]

        #[test]
        fn merge_order_does_not_matter(
            robot in 0usize..2,
            seed: u64,
            rows in 40usize..400,
            cuts in proptest::collection::vec(0.0f64..1.0, 1..6),
            order_seed: u64,
            weights in proptest::collection::vec(0.1f64..10.0, 7),
        ) {
            let model = Model::builtin(["psm", "mtm"][robot]).unwrap();
            let n = model.dof();
            let [q, dq, ddq, tau] = samples(&model, rows, seed);
            let w = &weights[..n];
            let whole = Observation::assemble(
                &model,
                Samples { q: &q, dq: &dq, ddq: &ddq, tau: &tau },
                w,
            );
            // Chunks at the cut points, assembled separately.
            let mut bounds: Vec<usize> = cuts.iter().map(|c| (c * rows as f64) as usize).collect();
            bounds.extend([0, rows]);
            bounds.sort_unstable();
            bounds.dedup();
            let mut chunks: Vec<Observation> = bounds
                .windows(2)
                .map(|b| {
                    let part = |m: &DMatrix<f64>| m.rows(b[0], b[1] - b[0]).into_owned();
                    let (q, dq, ddq, tau) = (part(&q), part(&dq), part(&ddq), part(&tau));
                    Observation::assemble(&model, Samples { q: &q, dq: &dq, ddq: &ddq, tau: &tau }, w)
                })
                .collect();
            // Merged in a shuffled order (Fisher–Yates from `order_seed`).
            let mut rng = dvrk_test_support::Rng::new(order_seed);
            for i in (1..chunks.len()).rev() {
                chunks.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
            }
            let mut merged = Observation::new(model.n_params());
            for c in &chunks {
                merged.merge(c);
            }
            prop_assert_eq!(merged.rows(), whole.rows());
            // The R factors are unique up to row signs: compare RᵀR, the Gram matrix of
            // [W·H | W·τ].
            let g1 = merged.r().transpose() * merged.r();
            let g2 = whole.r().transpose() * whole.r();
            let d = (&g1 - &g2).amax() / g2.amax();
            prop_assert!(d < 1e-10, "Gram matrices differ by {:e} relative", d);
        }
    }
}
