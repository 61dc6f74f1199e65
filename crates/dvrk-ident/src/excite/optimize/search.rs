//! The search of [`super::optimize`]: random starts explored with a weak penalty, the
//! best refined stage by stage in the augmented Lagrangian, then basin hopping from the
//! best (the module docs of [`super`], "Search" and "Repair and check").

use std::f64::consts::PI;

use dvrk_model::{BaseParameters, Model, Workspace};
use rayon::prelude::*;

use super::super::criterion::CriterionEval;
use super::super::grid::{project_rest, to_x, Grid};
use super::super::lbfgs::lbfgs;
use super::super::limits::{Constraints, Enforced, Multipliers};
use super::super::rng::Rng;
use super::{ExciteError, ExciteOptions};

/// The best point of the search, if any: its objective and coefficient vector.
pub(super) type Best = Option<(f64, Vec<f64>)>;

/// Explores every start, then refines the warm start and the best merits; returns the
/// criterion reached from each start and the best `(objective, x)`.
pub(super) fn explore_and_refine(
    setup: &Setup<'_>,
    progress: &dyn crate::progress::Progress,
) -> (Vec<Option<f64>>, Best) {
    let opts = setup.opts;
    progress.stage("exploring starts", Some(opts.starts as u64));
    let mut explored: Vec<Option<Run>> = (0..opts.starts)
        .into_par_iter()
        .map(|start| {
            let out = setup.explore(start);
            progress.advance(1);
            out
        })
        .collect();
    progress.finish();
    // The warm start is always refined; then the best merits.
    let mut ranked: Vec<usize> = (0..opts.starts)
        .filter(|&i| explored[i].is_some())
        .collect();
    ranked.sort_by(|&a, &b| {
        let key = |i: usize| {
            let warm = opts.init.is_some() && i == 0;
            (
                !warm,
                explored[i].as_ref().map_or(f64::INFINITY, |r| r.merit),
            )
        };
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    let chosen: Vec<(usize, Run)> = ranked
        .into_iter()
        .take(opts.refine)
        .filter_map(|i| explored[i].take().map(|r| (i, r)))
        .collect();
    progress.stage("refining the best starts", Some(chosen.len() as u64));
    let refined: Vec<(usize, Option<Refined>)> = chosen
        .into_par_iter()
        .map(|(i, run)| {
            let out = setup.refine(run);
            progress.advance(1);
            (i, out)
        })
        .collect();
    progress.finish();
    let mut starts = vec![None; opts.starts];
    let mut best: Option<(f64, Vec<f64>)> = None;
    for (i, r) in refined {
        if let Some((obj, x)) = r {
            starts[i] = Some(opts.criterion.report(obj));
            if best.as_ref().is_none_or(|(b, _)| obj < *b) {
                best = Some((obj, x));
            }
        }
    }
    (starts, best)
}

/// Why every start failed: when a motion of a micro-radian (or micrometre) about the
/// static pose already breaks a limit, that limit leaves no room to move (e.g. a
/// Cartesian box of zero width, a velocity range of one value) and is named; else the
/// regressor was rank deficient everywhere the limits allow.
pub(super) fn no_motion(setup: &Setup<'_>) -> ExciteError {
    let (model, xs) = (setup.model, setup.xs);
    let n = model.dof();
    let mut rng = super::super::rng::Rng(0x5eed);
    let x: Vec<f64> = xs
        .iter()
        .enumerate()
        .map(|(k, v)| if k < n { *v } else { v + 1e-6 * rng.normal() })
        .collect();
    let mut ws = Workspace::new(model);
    let check = setup
        .cons
        .check(model, &mut ws, &x, setup.dense, setup.opts.check_rate_hz);
    match check.violated.first() {
        Some(w) => ExciteError::ImpossibleLimits(format!(
            "every start failed: no motion fits limit {}, which leaves no room to move (a \
             motion of 1e-6 about the static pose gives {} = {} beyond {}); widen it",
            w.limit, w.quantity, w.value, w.bound
        )),
        None => ExciteError::Infeasible(
            "every start failed (rank-deficient regressor or no feasible motion)".into(),
        ),
    }
}

/// Basin hopping from `best`, which it replaces by a better point.
pub(super) fn hop_from_best(
    setup: &Setup<'_>,
    progress: &dyn crate::progress::Progress,
    best: &mut Best,
) {
    let opts = setup.opts;
    // Basin hopping from the best, two hops at a time (a fixed number, so that the
    // result does not depend on the thread count). No refinement, no hops: a warm start
    // with 0 iterations is only pulled inside the limits.
    if let Some((best_obj, best_x)) = best
        .as_mut()
        .filter(|_| opts.refine_iterations_per_stage > 0)
    {
        progress.stage("hopping from the best", Some(opts.hops as u64));
        for round in (0..opts.hops).collect::<Vec<_>>().chunks(HOPS_PER_ROUND) {
            let from: &[f64] = best_x;
            let hopped: Vec<Option<Refined>> = round
                .par_iter()
                .map(|&k| {
                    let out = setup.hop(from, k);
                    progress.advance(1);
                    out
                })
                .collect();
            for (obj, x) in hopped.into_iter().flatten() {
                if obj < *best_obj {
                    *best_obj = obj;
                    *best_x = x;
                }
            }
        }
        progress.finish();
    }
}

/// Per coordinate, half the width of the positions it can take alone from the static
/// pose (1 when unbounded or stuck): the unit of that coordinate's variables.
pub(super) fn coordinate_room(
    model: &Model,
    cons: &Constraints,
    xs: &[f64],
    grid: &Grid,
    margin: f64,
) -> Vec<f64> {
    let mut ws = Workspace::new(model);
    (0..model.dof())
        .map(|j| {
            let mut step = [0.0; 2];
            for (s, sign) in step.iter_mut().zip([1.0, -1.0]) {
                let mut x1 = xs.to_vec();
                x1[j] += sign;
                *s = cons.feasible_step(model, &mut ws, xs, &x1, Enforced { grid, margin }, &[]);
            }
            let half = 0.5 * (step[0] + step[1]);
            if half.is_finite() && half > 0.0 {
                half
            } else {
                1.0
            }
        })
        .collect()
}

/// Stages of the minimization: the soft-max sharpness of each (∞: the exact criterion).
/// The first [`EXPLORE_STAGES`] run on every start with a weak limit penalty, which
/// lets the motion cross infeasible regions toward better basins; the best starts then
/// continue.
const SHARPNESS: [f64; 7] = [
    4.0,
    10.0,
    30.0,
    100.0,
    f64::INFINITY,
    f64::INFINITY,
    f64::INFINITY,
];
const EXPLORE_STAGES: usize = 2;

/// Hops refined side by side, each round from the best so far.
const HOPS_PER_ROUND: usize = 2;

/// A refined start: its objective value and coefficients.
type Refined = (f64, Vec<f64>);

/// The state of one start between stages.
struct Run {
    x: Vec<f64>,
    /// Multipliers of the limits on the constraint grid, and the penalty weight.
    lambda: Vec<f64>,
    mu: f64,
    last_violation: f64,
    /// The minimized function (criterion surrogate plus limit terms) after the last
    /// stage: how the starts are ranked.
    merit: f64,
}

/// What every start shares.
pub(super) struct Setup<'a> {
    pub(super) model: &'a Model,
    pub(super) base: &'a BaseParameters,
    pub(super) opts: &'a ExciteOptions,
    pub(super) cons: &'a Constraints,
    /// The static pose as a coefficient vector (feasible with the margin).
    pub(super) xs: &'a [f64],
    pub(super) cgrid: &'a Grid,
    pub(super) dense: &'a Grid,
    pub(super) samples: usize,
    /// See [`coordinate_room`].
    pub(super) room: Vec<f64>,
}

/// The coordinate of entry `i` of a coefficient vector.
fn coordinate_of(i: usize, n: usize, order: usize) -> usize {
    if i < n {
        i
    } else {
        ((i - n) / order) % n
    }
}

impl<'a> Setup<'a> {
    /// The limits on the constraint grid, with the options' margin.
    fn enforced(&self) -> Enforced<'a> {
        Enforced {
            grid: self.cgrid,
            margin: self.opts.margin,
        }
    }

    fn criterion_eval(&self) -> CriterionEval<'_> {
        let mut ev = CriterionEval::new(
            self.model,
            self.base,
            self.opts.criterion,
            self.samples,
            self.opts.order,
            self.opts.base_frequency_hz,
        );
        ev.coulomb_eps = self.opts.coulomb_smoothing;
        ev
    }

    /// The variable scale of each coefficient: the coordinate's room times, for `a_jl`
    /// and `b_jl`, `w_f·l`. In these units a unit step moves any coordinate's position by
    /// its room, whatever the harmonic: the plain coefficients are velocity amplitudes,
    /// whose position effect shrinks as `1/l` and whose natural size differs by the
    /// coordinates' ranges (the MTM's roll has 20 times the room of its elbow), which
    /// leaves L-BFGS badly conditioned.
    fn variable_scale(&self) -> Vec<f64> {
        let (n, order) = (self.model.dof(), self.opts.order);
        let wf = 2.0 * PI * self.opts.base_frequency_hz;
        (0..n * (2 * order + 1))
            .map(|i| {
                let r = self.room[coordinate_of(i, n, order)];
                if i < n {
                    r
                } else {
                    r * wf * ((i - n) % order + 1) as f64
                }
            })
            .collect()
    }

    /// One start: `draws` first points (random oscillations about the static pose, or
    /// the warm start alone), each through the first exploring stage, and the best by
    /// merit through the others, all with a weak penalty (`μ = 1`) that lets the motion
    /// cross infeasible regions. None when the regressor is rank deficient at every draw.
    fn explore(&self, start: usize) -> Option<Run> {
        let draws = if self.opts.init.is_some() && start == 0 {
            1
        } else {
            self.opts.draws
        };
        let mut ws = Workspace::new(self.model);
        let mut ev = self.criterion_eval();
        let mut best: Option<Run> = None;
        for draw in 0..draws {
            let Some(run) = self.draw(&mut ev, &mut ws, start, draw) else {
                continue;
            };
            if best.as_ref().is_none_or(|b| run.merit < b.merit) {
                best = Some(run);
            }
        }
        let mut run = best?;
        self.stages(&mut ev, &mut ws, &mut run, 1..EXPLORE_STAGES);
        run.merit.is_finite().then_some(run)
    }

    /// One draw of a start: its first point (a random oscillation about the static
    /// pose, or the warm start), inside the limits, through the first exploring stage.
    /// Draw 0 of a start is the start as it was before draws existed (same random
    /// numbers).
    fn draw(
        &self,
        ev: &mut CriterionEval,
        ws: &mut Workspace,
        start: usize,
        draw: usize,
    ) -> Option<Run> {
        let (model, opts, cons, xs) = (self.model, self.opts, self.cons, self.xs);
        let n = model.dof();
        let order = opts.order;
        let dim = xs.len();
        let mut rng = Rng(opts
            .seed
            .wrapping_mul(0x2545_f491_4f6c_dd1d)
            .wrapping_add(start as u64 + 1)
            .wrapping_add((draw as u64) << 32));
        // A random oscillation, each coordinate's part scaled to the largest the limits
        // allow alone, then all together pulled inside. (Half of that room, as first
        // written, starts from small motions: the starts then settle in worse basins,
        // e.g. a best of 8 MTM starts at 222-228 instead of 216-218.)
        let mut d = vec![0.0; dim];
        for v in d.iter_mut().skip(n) {
            *v = rng.normal();
        }
        if opts.rest {
            project_rest(&mut d, n, order);
        }
        let room = |ws: &mut Workspace, d: &[f64]| {
            let x1: Vec<f64> = xs.iter().zip(d).map(|(a, b)| a + b).collect();
            cons.feasible_step(model, ws, xs, &x1, self.enforced(), &[])
        };
        for j in 0..n {
            let mut dj = vec![0.0; dim];
            for l in 0..order {
                dj[n + j * order + l] = d[n + j * order + l];
                dj[n + n * order + j * order + l] = d[n + n * order + j * order + l];
            }
            let s = room(ws, &dj);
            let scale = if s.is_finite() { s } else { 1.0 };
            for l in 0..order {
                d[n + j * order + l] *= scale;
                d[n + n * order + j * order + l] *= scale;
            }
        }
        if let (Some(t), 0) = (&opts.init, start) {
            let mut x = to_x(t);
            if opts.rest {
                project_rest(&mut x, n, order);
            }
            d = x.iter().zip(xs).map(|(a, b)| a - b).collect();
        }
        let s = room(ws, &d);
        let scale = if s < 1.0 { 0.999 * s } else { 1.0 };
        let x: Vec<f64> = xs.iter().zip(&d).map(|(a, b)| a + scale * b).collect();
        ev.objective(&x, None)?;
        let mut run = Run {
            x,
            lambda: vec![0.0; cons.multipliers(self.cgrid.len())],
            mu: 1.0,
            last_violation: f64::INFINITY,
            merit: f64::INFINITY,
        };
        self.stages(ev, ws, &mut run, 0..1);
        run.merit.is_finite().then_some(run)
    }

    /// The remaining stages of an explored start, then the pull-back onto the dense
    /// grid's feasible set: the objective value and the coefficients, None when the
    /// regressor is rank deficient.
    fn refine(&self, mut run: Run) -> Option<Refined> {
        let (model, opts, cons, xs) = (self.model, self.opts, self.cons, self.xs);
        let (n, order) = (model.dof(), opts.order);
        let mut ws = Workspace::new(model);
        let mut ev = self.criterion_eval();
        self.stages(&mut ev, &mut ws, &mut run, EXPLORE_STAGES..SHARPNESS.len());
        let mut x = run.x;
        ev.soft_p = f64::INFINITY;
        ev.coulomb_eps = 0.0;
        if opts.rest {
            // Remove the round-off drift out of the rest subspace.
            project_rest(&mut x, n, order);
        }
        // Pull back onto the segment from the static pose if the dense grid needs it,
        // with the slack that keeps the limits between its samples too.
        let slack = cons.between_samples(model, &mut ws, &x, self.dense);
        let dense = Enforced {
            grid: self.dense,
            margin: 0.0,
        };
        let s = cons.feasible_step(model, &mut ws, xs, &x, dense, &slack);
        if s < 1.0 {
            let s = s * (1.0 - 1e-9);
            for (xi, x0) in x.iter_mut().zip(xs) {
                *xi = x0 + s * (*xi - x0);
            }
        }
        let obj = ev.objective(&x, None)?;
        Some((obj, x))
    }

    /// Hop `hop` of the basin hopping: the harmonic coefficients of `x` (a refined
    /// trajectory) moved by `hop_size` room units at random, then refined.
    fn hop(&self, x: &[f64], hop: usize) -> Option<Refined> {
        let (n, order) = (self.model.dof(), self.opts.order);
        let mut rng = Rng(self
            .opts
            .seed
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .wrapping_add(hop as u64 + 1));
        let dscale = self.variable_scale();
        let mut d: Vec<f64> = (0..x.len())
            .map(|i| {
                if i < n {
                    0.0
                } else {
                    self.opts.hop_size * dscale[i] * rng.normal()
                }
            })
            .collect();
        if self.opts.rest {
            project_rest(&mut d, n, order);
        }
        let run = Run {
            x: x.iter().zip(&d).map(|(a, b)| a + b).collect(),
            lambda: vec![0.0; self.cons.multipliers(self.cgrid.len())],
            mu: 1.0,
            last_violation: f64::INFINITY,
            merit: f64::INFINITY,
        };
        self.refine(run)
    }

    /// Augmented-Lagrangian stages `stages` of [`SHARPNESS`] on `run` (L-BFGS on the
    /// scaled variables, then a multiplier update; the penalty weight grows tenfold when
    /// the violation did not shrink fourfold).
    fn stages(
        &self,
        ev: &mut CriterionEval,
        ws: &mut Workspace,
        run: &mut Run,
        stages: std::ops::Range<usize>,
    ) {
        let (model, opts, cons) = (self.model, self.opts, self.cons);
        let n = model.dof();
        let order = opts.order;
        let dim = run.x.len();
        let dscale = self.variable_scale();
        let mut z: Vec<f64> = run.x.iter().zip(&dscale).map(|(a, d)| a / d).collect();
        let mut xb = vec![0.0; dim];
        let mut pg = vec![0.0; dim];
        for stage in stages {
            ev.soft_p = if opts.smooth {
                SHARPNESS[stage]
            } else {
                f64::INFINITY
            };
            let (lambda, mu) = (&run.lambda, run.mu);
            let mut f = |z: &[f64], g: &mut [f64]| -> f64 {
                for i in 0..dim {
                    xb[i] = z[i] * dscale[i];
                }
                let Some(obj) = ev.objective(&xb, Some(g)) else {
                    return f64::INFINITY;
                };
                pg.fill(0.0);
                let pen = cons.lagrangian(
                    model,
                    ws,
                    &xb,
                    self.enforced(),
                    Multipliers { lambda, mu },
                    Some(&mut pg),
                );
                for (gi, pi) in g.iter_mut().zip(&pg) {
                    *gi += pi;
                }
                if opts.rest {
                    project_rest(g, n, order);
                }
                for i in 0..dim {
                    g[i] *= dscale[i];
                }
                obj + pen
            };
            let iters = if stage < EXPLORE_STAGES {
                opts.iterations_per_stage
            } else {
                opts.refine_iterations_per_stage
            };
            run.merit = lbfgs(&mut f, &mut z, iters);
            for i in 0..dim {
                run.x[i] = z[i] * dscale[i];
            }
            let violation = cons.update_multipliers(
                model,
                ws,
                &run.x,
                self.enforced(),
                &mut run.lambda,
                run.mu,
            );
            if violation > 0.25 * run.last_violation {
                run.mu = (run.mu * 10.0).min(1e6);
            }
            run.last_violation = violation;
        }
    }
}
