//! The weighted observation matrix `[W·H | W·τ]`, reduced on the fly to its R factor.
//!
//! The estimators only need `R` ((p+1)×(p+1)): `‖W H π − W τ‖² = ‖R₁₁ π − r₁‖² + ρ²`.
//! Samples are assembled in chunks in parallel (rayon), each chunk is reduced by a QR
//! (faer), and the chunk factors are merged in order by a QR of the stacked factors —
//! exact, so memory does not grow with the log length, long logs stream, and
//! observations of several logs combine with [`Observation::merge`].

use dvrk_model::{Model, Workspace};
use faer::Mat;
use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::progress::{Progress, Silent};

/// Samples per parallel chunk: 256 samples of a 7-DoF arm with 116 columns are 1.7 MB.
pub const CHUNK_SAMPLES: usize = 256;

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
    pub fn len(&self) -> usize {
        self.q.nrows()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
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
    let qr = a.qr();
    let r = qr.thin_R();
    let k = r.nrows();
    let mut out = DMatrix::zeros(c, c);
    for i in 0..k {
        let sign = if r[(i, i)] < 0.0 { -1.0 } else { 1.0 };
        for j in i..c {
            out[(i, j)] = sign * r[(i, j)];
        }
    }
    out
}

impl Observation {
    /// An empty observation for `p` parameters.
    pub fn new(p: usize) -> Self {
        Observation {
            r: DMatrix::zeros(p + 1, p + 1),
            rows: 0,
        }
    }

    /// Number of parameters (columns without the torque).
    pub fn n_params(&self) -> usize {
        self.r.ncols() - 1
    }

    /// Rows stacked so far.
    pub fn rows(&self) -> usize {
        self.rows
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

    /// Observation of `samples` with per-coordinate row weights `weights` (1/N·m or
    /// 1/N), assembled in parallel chunks and merged in order (the result does not
    /// depend on the number of threads).
    pub fn assemble(model: &Model, samples: Samples<'_>, weights: &[f64]) -> Observation {
        let n = model.dof();
        assert_eq!(weights.len(), n, "one weight per coordinate");
        let mut obs = Observation::new(model.n_params());
        chunk_factors(
            model,
            samples,
            &Silent,
            |block| {
                let rows = block.nrows();
                let mut block = block;
                for i in 0..rows {
                    let w = weights[i % n];
                    for c in 0..block.ncols() {
                        block[(i, c)] *= w;
                    }
                }
                vec![Observation {
                    r: r_factor(&block),
                    rows,
                }]
            },
            |f| obs.merge(&f[0]),
        );
        obs
    }

    /// One observation per coordinate, unweighted: the rows of [`Observation::assemble`]
    /// split by the coordinate they belong to. Weights can then be chosen after the
    /// data are read, with [`Observation::weighted`]: what a fit streamed over a long
    /// log needs, where the weights come from the whole log.
    ///
    /// `progress` counts the samples done (from the worker threads, one call per chunk).
    pub fn assemble_per_coordinate(
        model: &Model,
        samples: Samples<'_>,
        progress: &dyn Progress,
    ) -> Vec<Observation> {
        let mut parts = vec![Observation::new(model.n_params()); model.dof()];
        add_per_coordinate(&mut parts, model, samples, progress);
        parts
    }

    /// Adds `samples` to the per-coordinate observations `parts`: each chunk of
    /// [`CHUNK_SAMPLES`] samples is factored (in parallel) and merged into `parts` in
    /// order. Samples added in batches of whole chunks therefore give the same factors,
    /// to the last bit, as all at once: a log streamed in blocks and the same log in
    /// memory are fitted alike.
    pub fn add_per_coordinate(parts: &mut [Observation], model: &Model, samples: Samples<'_>) {
        add_per_coordinate(parts, model, samples, &Silent);
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

/// [`Observation::add_per_coordinate`] reporting the samples done to `progress`.
fn add_per_coordinate(
    parts: &mut [Observation],
    model: &Model,
    samples: Samples<'_>,
    progress: &dyn Progress,
) {
    let n = model.dof();
    assert_eq!(parts.len(), n, "one observation per coordinate");
    chunk_factors(
        model,
        samples,
        progress,
        |block| {
            let count = block.nrows() / n;
            (0..n)
                .map(|j| {
                    let rows = Mat::from_fn(count, block.ncols(), |k, c| block[(k * n + j, c)]);
                    Observation {
                        r: r_factor(&rows),
                        rows: count,
                    }
                })
                .collect()
        },
        |f| {
            for (o, part) in parts.iter_mut().zip(&f) {
                o.merge(part);
            }
        },
    );
}

/// Chunks factored in parallel before their factors are merged: bounds the factors
/// held at once (a long log in memory has thousands of chunks).
const CHUNKS_IN_FLIGHT: usize = 32;

/// The rows `[H | τ]` of `samples` in parallel chunks of [`CHUNK_SAMPLES`] (row
/// `k·n + j`: coordinate `j` of the chunk's sample `k`), each reduced by `reduce`;
/// `merge` gets the chunks' results in order.
fn chunk_factors(
    model: &Model,
    samples: Samples<'_>,
    progress: &dyn Progress,
    reduce: impl Fn(Mat<f64>) -> Vec<Observation> + Sync,
    mut merge: impl FnMut(Vec<Observation>),
) {
    let n = model.dof();
    let p = model.n_params();
    let count = samples.len();
    let chunks: Vec<(usize, usize)> = (0..count)
        .step_by(CHUNK_SAMPLES)
        .map(|s| (s, (s + CHUNK_SAMPLES).min(count)))
        .collect();
    for group in chunks.chunks(CHUNKS_IN_FLIGHT) {
        let factors: Vec<Vec<Observation>> = group
            .par_iter()
            .map_init(
                || {
                    (
                        Workspace::new(model),
                        vec![0.0; n * p],
                        vec![0.0; n],
                        vec![0.0; n],
                        vec![0.0; n],
                    )
                },
                |(ws, h, q, dq, ddq), &(start, end)| {
                    let rows = (end - start) * n;
                    let mut block = Mat::<f64>::zeros(rows, p + 1);
                    for k in start..end {
                        samples.read(k, q, dq, ddq);
                        model.regressor_into(ws, q, dq, ddq, h);
                        for j in 0..n {
                            let row = (k - start) * n + j;
                            for c in 0..p {
                                block[(row, c)] = h[j * p + c];
                            }
                            block[(row, p)] = samples.tau[(k, j)];
                        }
                    }
                    let factor = reduce(block);
                    progress.advance((end - start) as u64);
                    factor
                },
            )
            .collect();
        factors.into_iter().for_each(&mut merge);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_samples(model: &Model, count: usize, seed: u64) -> [DMatrix<f64>; 4] {
        let n = model.dof();
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut m = || DMatrix::from_fn(count, n, |_, _| next());
        [m(), m(), m(), m()]
    }

    #[test]
    fn chunked_factor_equals_one_shot_qr() {
        let model = Model::builtin("psm").unwrap();
        let (n, p) = (model.dof(), model.n_params());
        let count = 3 * CHUNK_SAMPLES + 17;
        let [q, dq, ddq, tau] = random_samples(&model, count, 7);
        let weights: Vec<f64> = (0..n).map(|j| 1.0 + 0.1 * j as f64).collect();
        let s = Samples {
            q: &q,
            dq: &dq,
            ddq: &ddq,
            tau: &tau,
        };
        let obs = Observation::assemble(&model, s, &weights);
        assert_eq!(obs.rows(), count * n);
        // One-shot: the whole weighted matrix at once.
        let mut ws = Workspace::new(&model);
        let mut full = DMatrix::zeros(count * n, p + 1);
        let (mut a, mut b, mut c) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut h = vec![0.0; n * p];
        for k in 0..count {
            s.read(k, &mut a, &mut b, &mut c);
            model.regressor_into(&mut ws, &a, &b, &c, &mut h);
            for j in 0..n {
                for col in 0..p {
                    full[(k * n + j, col)] = weights[j] * h[j * p + col];
                }
                full[(k * n + j, p)] = weights[j] * tau[(k, j)];
            }
        }
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

    #[test]
    fn per_coordinate_parts_weighted_equal_the_weighted_assembly() {
        let model = Model::builtin("psm").unwrap();
        let n = model.dof();
        let [q, dq, ddq, tau] = random_samples(&model, 2 * CHUNK_SAMPLES + 5, 11);
        let s = Samples {
            q: &q,
            dq: &dq,
            ddq: &ddq,
            tau: &tau,
        };
        let weights: Vec<f64> = (0..n).map(|j| 0.5 + 0.3 * j as f64).collect();
        let direct = Observation::assemble(&model, s, &weights);
        let parts = Observation::assemble_per_coordinate(&model, s, &Silent);
        assert!(parts.iter().all(|o| o.rows() == q.nrows()));
        let combined = Observation::weighted(&parts, &weights);
        assert_eq!(combined.rows(), direct.rows());
        let g1 = combined.r().transpose() * combined.r();
        let g2 = direct.r().transpose() * direct.r();
        assert!(
            (&g1 - &g2).amax() < 1e-12 * g2.amax(),
            "{}",
            (&g1 - &g2).amax()
        );
        // One coordinate's factor holds that coordinate's residual: zero weight elsewhere.
        let mut only = vec![0.0; n];
        only[2] = 1.0;
        let third = Observation::weighted(&parts, &only);
        let g3 = third.r().transpose() * third.r();
        let g = parts[2].r().transpose() * parts[2].r();
        assert!((&g3 - &g).amax() < 1e-12 * g.amax());
    }

    #[test]
    fn merge_and_select_are_exact() {
        let model = Model::builtin("mtm").unwrap();
        let n = model.dof();
        let [q, dq, ddq, tau] = random_samples(&model, 300, 3);
        let w = vec![1.0; n];
        let half = |a: &DMatrix<f64>, lo: usize, hi: usize| a.rows(lo, hi - lo).into_owned();
        let all = Observation::assemble(
            &model,
            Samples {
                q: &q,
                dq: &dq,
                ddq: &ddq,
                tau: &tau,
            },
            &w,
        );
        let (q1, dq1, ddq1, t1) = (
            half(&q, 0, 100),
            half(&dq, 0, 100),
            half(&ddq, 0, 100),
            half(&tau, 0, 100),
        );
        let (q2, dq2, ddq2, t2) = (
            half(&q, 100, 300),
            half(&dq, 100, 300),
            half(&ddq, 100, 300),
            half(&tau, 100, 300),
        );
        let mut a = Observation::assemble(
            &model,
            Samples {
                q: &q1,
                dq: &dq1,
                ddq: &ddq1,
                tau: &t1,
            },
            &w,
        );
        let b = Observation::assemble(
            &model,
            Samples {
                q: &q2,
                dq: &dq2,
                ddq: &ddq2,
                tau: &t2,
            },
            &w,
        );
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
