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
mod properties;
#[cfg(test)]
mod tests;
