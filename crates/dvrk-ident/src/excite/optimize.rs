//! Optimal excitation trajectories (`docs/book/src/identification.md` §7): choose the Fourier
//! coefficients (per coordinate `q0`, `a_l`, `b_l`, `l = 1..L`) that minimize the
//! condition number of the column-normalized base regressor stacked over one period
//! (or maximize its log-determinant, D-optimality), subject to position, velocity and
//! acceleration limits on affine combinations of the coordinates (the description's
//! `[[limits]]`), boxes on frame origins (`[[cartesian_limits]]`, see [`Limits`]), and
//! optionally rest (zero velocity and acceleration) at the start and end of the period.
//!
//! # Method
//!
//! * Criterion: the base regressor `Y` (columns `base.independent` of
//!   `model.regressor_into`) at `samples_per_harmonic · L` equally spaced instants of one
//!   period, its columns scaled to unit norm (`Yn`), and the eigenvalues `λ` of
//!   `Yn^T Yn`. `condition` = `sqrt(λmax/λmin)` (the optimizer works on its logarithm);
//!   `log_det` = `Σ log λ` (maximized). Its gradient with respect to the coefficients is
//!   analytic in `Yn` (eigenvectors) and chains through per-sample derivatives of the
//!   regressor with respect to `q`, `q̇`, `q̈` (forward differences in `q`, `q̇`; exact in
//!   `q̈`, on which the regressor is linear). While optimizing, the condition number is
//!   replaced by a soft-max/soft-min surrogate sharpened stage by stage, and the Coulomb
//!   columns' `sign(ṡ)` by `tanh(ṡ/ε)` ([`ExciteOptions::coulomb_smoothing`]).
//! * Limits: a penalty on a constraint grid (80 instants per harmonic) with the bounds
//!   moved inward by a small margin, in an augmented Lagrangian: L-BFGS (Armijo
//!   backtracking) minimizes each of 7 stages, then the multipliers are updated and the
//!   penalty weight grows when the violation did not shrink enough. The variables are
//!   the coefficients scaled to position amplitudes in units of each coordinate's room.
//!   Cartesian boxes enter through the frame-origin Jacobian. Rest at the ends
//!   (`Σ_l a_jl = 0`, `Σ_l l b_jl = 0` per coordinate) is a linear subspace kept by
//!   projection.
//! * Search: `starts` starts, each the best by merit of `draws` random oscillations
//!   about a static pose (each as large as the limits allow) after the first exploring
//!   stage, run the 2 exploring stages with a weak penalty (`μ = 1`), which lets them
//!   cross infeasible regions; the `refine` best by merit run the 5 refining stages.
//!   Then `hops` rounds of basin hopping (two at a time): the best refined trajectory's
//!   harmonics moved at random by `hop_size` room units and refined again, kept when
//!   better. Deterministic for a seed; starts and hops run in parallel with rayon.
//! * Repair and check: a static pose inside all limits is found first (an impossible set
//!   of limits is an error). A refined point is pulled back along the segment from that
//!   pose if the dense grid (≥ 1 kHz over the whole period) needs it: exactly for the
//!   joint limits, which are linear in the coefficients, by bisection against the grid
//!   for the boxes, with each bound tightened by how far the motion can rise between
//!   two samples (`h²/8 · max|v̈|`, about 1e-6 rad/s on the MTM), so that the limits
//!   hold between the samples too. The result is checked on the dense grid; an
//!   infeasible one is an error.
//!
//! On the MTM (2019 limits, order 6, 0.1 Hz) the first version of this optimizer (a plain
//! penalty, 4 starts) stalled at condition 261. Where a start ends is chaotic: the last
//! bits of a re-associated sum in the regressor (gradients equal to 2e-8) send the
//! same start to condition 216.8 or 230.2, and of 8 starts refined to the end usually
//! one or none ends below the 2019 trajectory's 219.3. With one draw per start and no
//! hops (the defaults until 2026-11-24) seeds 0 to 5 ended between 213.2 and 231.5
//! depending on the build; with 4 draws per start and 4 hops they end between 209.9 and
//! 216.9 with both builds (`docs/book/src/excitation.md`).
//!
//! The L-BFGS (`excite/lbfgs.rs`) and the random numbers (`excite/rng.rs`) are our own
//! although the project prefers crates; their modules say what the crates measured.

// `!(x > 0.0)`-style tests are deliberate: they also catch NaN, which a reversed
// comparison would let through. Index loops mirror the math over several arrays.
#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    clippy::needless_range_loop,
    clippy::ptr_arg
)]

use std::f64::consts::PI;

use dvrk_model::{BaseParameters, Model, Workspace};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::criterion::CriterionEval;
pub use super::criterion::{Criterion, CriterionValue};
pub use super::error::ExciteError;
use super::grid::{from_x, project_rest, to_x, Grid};
use super::lbfgs::lbfgs;
use super::limits::{Constraints, Enforced, Multipliers};
pub use super::limits::{Feasibility, Limits, Violation};
use super::rng::Rng;
use super::{check_dof, FourierTrajectory};

/// Options of [`optimize`].
#[derive(Clone, Debug)]
pub struct ExciteOptions {
    /// Number of harmonics `L`.
    pub order: usize,
    /// Base frequency `f0`, Hz.
    pub base_frequency_hz: f64,
    /// What the search optimizes (default: the condition number).
    pub criterion: Criterion,
    /// Regressor samples per period per harmonic (criterion grid: this × `order`).
    pub samples_per_harmonic: usize,
    /// Independent random starts, each explored with a weak limit penalty.
    pub starts: usize,
    /// Random oscillations drawn per start: each runs the first exploring stage and the
    /// best by merit continues as the start. Where a start ends is chaotic (the last
    /// bits of a sum change the MTM's basin), so the best of few samples is luck:
    /// more draws per start is the cheap way to more samples, since a draw's first stage
    /// costs a fifteenth of a refinement.
    pub draws: usize,
    /// How many of the explored starts (the best by their merit) are refined to a
    /// feasible trajectory.
    pub refine: usize,
    /// Seed of the starts.
    pub seed: u64,
    /// L-BFGS iterations of each of the 2 exploring stages (every start). Longer
    /// exploration is not better: the starts sink into their infeasible basins and
    /// their merits rank the basins worse (MTM: 150 gives a worse best-of-3 than 110).
    pub iterations_per_stage: usize,
    /// L-BFGS iterations of each of the 5 refining stages (the `refine` best starts).
    pub refine_iterations_per_stage: usize,
    /// Perturbations of the best refined trajectory, each refined again and kept when
    /// better (basin hopping, two at a time from the best so far). Refining the same
    /// point again barely moves it; a hop lands in a nearby basin, often a better one
    /// (MTM seed 1: 220.7 to 216.2 in four hops).
    pub hops: usize,
    /// Size of a hop: the standard deviation of each harmonic coefficient's change, in
    /// units of its coordinate's room (a unit moves the coordinate's position by its
    /// room). 0.3 scatters the MTM into worse basins; 0.1 finds better ones.
    pub hop_size: f64,
    /// Zero velocity and acceleration at the start (and so the end) of the period.
    pub rest: bool,
    /// Bounds moved inward by this fraction of their range while optimizing.
    pub margin: f64,
    /// Rate of the dense feasibility check, Hz (at least 1000).
    pub check_rate_hz: f64,
    /// Condition criterion: optimize a smooth surrogate (soft-max/soft-min of the
    /// eigenvalues, sharpened stage by stage) before the exact criterion.
    pub smooth: bool,
    /// Warm start: the first start refines this trajectory (same order and base
    /// frequency), first pulled inside the limits toward a static pose if needed.
    pub init: Option<FourierTrajectory>,
    /// While optimizing, the Coulomb friction columns use `tanh(ṡ/ε)` instead of
    /// `sign(ṡ)`, with `ε` this value in rad/s (a tenth of it in m/s for prismatic
    /// joints); 0 keeps the sign. The sign jumps when a joint's velocity crosses zero at
    /// a criterion sample, a jump the gradient cannot see: without smoothing, the
    /// optimizer parks velocities at zero on the side where the jump would cost and
    /// stalls there. Reported criteria always use the exact sign.
    pub coulomb_smoothing: f64,
}

impl Default for ExciteOptions {
    fn default() -> Self {
        ExciteOptions {
            order: 6,
            base_frequency_hz: 0.18,
            criterion: Criterion::Condition,
            samples_per_harmonic: 15,
            starts: 8,
            draws: 4,
            refine: 3,
            seed: 0,
            iterations_per_stage: 110,
            refine_iterations_per_stage: 180,
            hops: 4,
            hop_size: 0.1,
            rest: false,
            margin: 0.001,
            check_rate_hz: 1000.0,
            smooth: true,
            init: None,
            coulomb_smoothing: 0.01,
        }
    }
}

/// Criterion and feasibility of a trajectory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// The criterion of the trajectory on the criterion grid.
    pub criterion: CriterionValue,
    /// The dense check of the trajectory against the limits.
    pub feasibility: Feasibility,
}

impl Evaluation {
    /// The document of `dvrk-ident excite --evaluate --json` (and of the Python
    /// `evaluate_trajectory`): `criterion` {`name`, `value`}, `feasible`,
    /// `worst_violation` (the largest excess, negative when inside: the tightest margin),
    /// `violated` (every violated limit, worst first), `check_samples`, `check_rate_hz`.
    pub fn to_json_value(&self) -> serde_json::Value {
        serde_json::json!({
            "criterion": self.criterion,
            "feasible": self.feasibility.feasible,
            "worst_violation": self.feasibility.worst,
            "violated": self.feasibility.violated,
            "check_samples": self.feasibility.samples,
            "check_rate_hz": self.feasibility.rate_hz,
        })
    }
}

/// An optimized trajectory with its evaluation.
#[derive(Clone, Debug)]
pub struct Excitation {
    /// The best trajectory over all starts.
    pub trajectory: FourierTrajectory,
    /// Its criterion and dense feasibility check.
    pub evaluation: Evaluation,
    /// Criterion of each start's final trajectory (None: not refined, or failed).
    pub starts: Vec<Option<f64>>,
}

impl Excitation {
    /// The output document: the trajectory keys (`order`, `base_frequency_hz`, `q0`,
    /// `a`, `b`, `coordinates`) plus `criterion` {`name`, `value`} and `feasibility`.
    pub fn to_json_value(&self) -> serde_json::Value {
        let mut doc = serde_json::to_value(&self.trajectory).expect("serializable");
        let obj = doc.as_object_mut().expect("object");
        obj.insert(
            "criterion".into(),
            serde_json::to_value(&self.evaluation.criterion).expect("serializable"),
        );
        obj.insert(
            "feasibility".into(),
            serde_json::to_value(&self.evaluation.feasibility).expect("serializable"),
        );
        doc
    }
}

// ---------------------------------------------------------------------------------
// Public API
// ---------------------------------------------------------------------------------

/// Number of samples of the dense check of a trajectory of base frequency `f0`.
/// Most harmonics of a Fourier trajectory the optimizer and evaluator accept (the
/// 2019 trajectories have 6).
pub const MAX_ORDER: usize = 100;

/// Most values (samples × harmonics) of one sampling grid of a period: the dense check
/// at `check_rate` over `1 / f0` seconds, or the criterion's samples; 1e7 values are
/// 160 MB of sines and cosines (the PSM's default dense grid has 33 000).
pub const MAX_GRID_VALUES: usize = 10_000_000;

/// Most random starts (draws included: `starts · draws`) and hops, and L-BFGS
/// iterations per stage.
pub const MAX_STARTS: usize = 10_000;
/// Most L-BFGS iterations per stage (`iterations_per_stage`,
/// `refine_iterations_per_stage`).
pub const MAX_ITERATIONS: usize = 100_000;

/// Checks the sizes of the grids a trajectory of `order` harmonics at `f0` Hz needs
/// (criterion samples, dense check at `check_rate_hz`) before any is allocated.
fn check_grids(
    order: usize,
    f0: f64,
    samples_per_harmonic: usize,
    check_rate_hz: f64,
) -> Result<(), ExciteError> {
    if order == 0 || order > MAX_ORDER {
        return Err(ExciteError::Invalid(format!(
            "order {order}: between 1 and {MAX_ORDER} harmonics are accepted"
        )));
    }
    if !(f0 > 0.0 && f0.is_finite()) {
        return Err(ExciteError::Invalid(format!(
            "the base frequency must be positive and finite, got {f0} Hz"
        )));
    }
    if samples_per_harmonic == 0 {
        return Err(ExciteError::Invalid(
            "samples per harmonic must be at least 1 (the criterion's grid has samples per \
             harmonic × order instants)"
                .into(),
        ));
    }
    if !(check_rate_hz.is_finite() && check_rate_hz > 0.0) {
        return Err(ExciteError::Invalid(format!(
            "the check rate must be positive and finite, got {check_rate_hz} Hz"
        )));
    }
    let dense = (check_rate_hz.max(1000.0) / f0).ceil() * order as f64;
    let criterion = samples_per_harmonic as f64 * (order * order) as f64;
    for (what, values) in [
        (
            "the dense feasibility check (check rate / f0 samples)",
            dense,
        ),
        (
            "the criterion (samples per harmonic × order samples)",
            criterion,
        ),
    ] {
        if values > MAX_GRID_VALUES as f64 {
            return Err(ExciteError::Invalid(format!(
                "{what} would need {values:.3e} values (samples × harmonics) for order \
                 {order} at f0 = {f0} Hz; at most {MAX_GRID_VALUES:e} are accepted"
            )));
        }
    }
    Ok(())
}

fn dense_grid(order: usize, f0: f64, rate_hz: f64) -> Grid {
    let rate = rate_hz.max(1000.0);
    let count = ((rate / f0).ceil() as usize).max(2);
    Grid::uniform(count, order, f0)
}

/// Dense feasibility check of a trajectory against limits: every sample at `rate_hz`
/// (at least 1 kHz) over one whole period.
pub fn check_feasibility(
    model: &Model,
    traj: &FourierTrajectory,
    limits: &Limits,
    rate_hz: f64,
) -> Result<Feasibility, ExciteError> {
    check_dof(model, traj)?;
    check_grids(traj.order, traj.base_frequency_hz, 1, rate_hz)?;
    let cons = Constraints::new(model, limits)?;
    let grid = dense_grid(traj.order, traj.base_frequency_hz, rate_hz);
    let mut ws = Workspace::new(model);
    Ok(cons.check(model, &mut ws, &to_x(traj), &grid, rate_hz))
}

/// The criterion of a trajectory: the column-normalized base regressor at
/// `samples_per_harmonic · order` equally spaced instants of one period.
pub fn criterion_value(
    model: &Model,
    base: &BaseParameters,
    traj: &FourierTrajectory,
    criterion: Criterion,
    samples_per_harmonic: usize,
) -> Result<CriterionValue, ExciteError> {
    check_dof(model, traj)?;
    check_grids(
        traj.order,
        traj.base_frequency_hz,
        samples_per_harmonic,
        1000.0,
    )?;
    let mut ev = trajectory_criterion(model, base, traj, criterion, samples_per_harmonic);
    let value = match ev.objective(&to_x(traj), None) {
        Some(obj) => criterion.report(obj),
        None => match criterion {
            Criterion::Condition => f64::INFINITY,
            Criterion::LogDet => f64::NEG_INFINITY,
        },
    };
    Ok(CriterionValue {
        name: criterion.name().into(),
        value,
    })
}

/// The criterion on the grid of `traj`'s shape (order, base frequency) with
/// `samples_per_harmonic · order` equally spaced instants of one period.
fn trajectory_criterion<'a>(
    model: &'a Model,
    base: &'a BaseParameters,
    traj: &FourierTrajectory,
    criterion: Criterion,
    samples_per_harmonic: usize,
) -> CriterionEval<'a> {
    CriterionEval::new(
        model,
        base,
        criterion,
        samples_per_harmonic.max(1) * traj.order,
        traj.order,
        traj.base_frequency_hz,
    )
}

/// Criterion and dense feasibility of any trajectory.
pub fn evaluate(
    model: &Model,
    base: &BaseParameters,
    traj: &FourierTrajectory,
    limits: &Limits,
    criterion: Criterion,
    samples_per_harmonic: usize,
    check_rate_hz: f64,
) -> Result<Evaluation, ExciteError> {
    Ok(Evaluation {
        criterion: criterion_value(model, base, traj, criterion, samples_per_harmonic)?,
        feasibility: check_feasibility(model, traj, limits, check_rate_hz)?,
    })
}

/// The objective the optimizer minimizes (`log cond` or `−log det`) and its gradient with
/// respect to the coefficient vector `[q0; a (row per coordinate); b]` (exposed for
/// tests). None when the regressor is rank deficient. `soft_p`: the smooth surrogate's
/// sharpness for the condition criterion (`f64::INFINITY`: the exact `log cond`);
/// `coulomb_smoothing`: see [`ExciteOptions::coulomb_smoothing`] (0: the exact sign).
pub fn objective_and_gradient(
    model: &Model,
    base: &BaseParameters,
    traj: &FourierTrajectory,
    criterion: Criterion,
    samples_per_harmonic: usize,
    soft_p: f64,
    coulomb_smoothing: f64,
) -> Option<(f64, Vec<f64>)> {
    let mut ev = trajectory_criterion(model, base, traj, criterion, samples_per_harmonic);
    ev.soft_p = soft_p;
    ev.coulomb_eps = coulomb_smoothing;
    let x = to_x(traj);
    let mut g = vec![0.0; x.len()];
    let v = ev.objective(&x, Some(&mut g))?;
    Some((v, g))
}

/// The optimizer's limit term on its constraint grid and its gradient with respect to
/// the coefficient vector (exposed for tests): the quadratic exterior penalty
/// `μ/2 Σ max(0, c)²` of the normalized excesses `c` beyond the bounds shrunk by
/// `margin`, Cartesian boxes included.
pub fn penalty_and_gradient(
    model: &Model,
    traj: &FourierTrajectory,
    limits: &Limits,
    margin: f64,
    mu: f64,
) -> Result<(f64, Vec<f64>), ExciteError> {
    check_dof(model, traj)?;
    let cons = Constraints::new(model, limits)?;
    let grid = constraint_grid(traj.order, traj.base_frequency_hz);
    let x = to_x(traj);
    let mut g = vec![0.0; x.len()];
    let mut ws = Workspace::new(model);
    let on = Enforced {
        grid: &grid,
        margin,
    };
    let exterior = Multipliers { lambda: &[], mu };
    let v = cons.lagrangian(model, &mut ws, &x, on, exterior, Some(&mut g));
    Ok((v, g))
}

/// The grid on which the optimizer enforces the limits: 80 instants per harmonic
/// (at least 400), so that a peak between two instants exceeds them by at most ~0.1 %
/// of the highest harmonic's amplitude; the final pull-back covers the rest exactly.
fn constraint_grid(order: usize, f0: f64) -> Grid {
    Grid::uniform((80 * order).max(400), order, f0)
}

/// Optimizes an excitation trajectory. `progress` counts the starts explored, then
/// those refined (reported from the worker threads).
pub fn optimize(
    model: &Model,
    base: &BaseParameters,
    limits: &Limits,
    opts: &ExciteOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<Excitation, ExciteError> {
    let n = model.dof();
    let order = opts.order;
    let f0 = opts.base_frequency_hz;
    check_grids(order, f0, opts.samples_per_harmonic, opts.check_rate_hz)?;
    check_options(opts)?;
    let cons = Constraints::new(model, limits)?;
    check_init(model, opts)?;
    let xs = {
        let q = cons.static_pose(model, opts.margin)?;
        let mut x = vec![0.0; n * (2 * order + 1)];
        x[..n].copy_from_slice(&q);
        x
    };
    let samples = (opts.samples_per_harmonic.max(1) * order).max(base.rank().div_ceil(n) + 1);
    let cgrid = constraint_grid(order, f0);
    let dense = dense_grid(order, f0, opts.check_rate_hz);
    let room = coordinate_room(model, &cons, &xs, &cgrid, opts.margin);
    let setup = Setup {
        model,
        base,
        opts,
        cons: &cons,
        xs: &xs,
        cgrid: &cgrid,
        dense: &dense,
        samples,
        room,
    };

    let (starts, mut best) = explore_and_refine(&setup, progress);
    hop_from_best(&setup, progress, &mut best);
    let Some((obj, x)) = best else {
        return Err(no_motion(&setup));
    };
    let trajectory = from_x(&x, n, order, f0, &model.coordinates);
    let mut ws = Workspace::new(model);
    let feasibility = cons.check(model, &mut ws, &x, &dense, opts.check_rate_hz);
    if !feasibility.feasible {
        let w = feasibility.worst.as_ref().expect("violation");
        return Err(ExciteError::Infeasible(format!(
            "dense check: {} {} = {} beyond {} by {} at t = {} s",
            w.limit, w.quantity, w.value, w.bound, w.excess, w.time_s
        )));
    }
    Ok(Excitation {
        trajectory,
        evaluation: Evaluation {
            criterion: CriterionValue {
                name: opts.criterion.name().into(),
                value: opts.criterion.report(obj),
            },
            feasibility,
        },
        starts,
    })
}

/// Refuses option values the search cannot run with (before the limits are compiled,
/// so that a too large `--starts` is named as such).
fn check_options(opts: &ExciteOptions) -> Result<(), ExciteError> {
    if opts.starts == 0 || opts.refine == 0 || opts.draws == 0 {
        return Err(ExciteError::Invalid(
            "at least one start, one draw per start and one refined start are needed".into(),
        ));
    }
    if !(opts.hop_size >= 0.0 && opts.hop_size.is_finite()) {
        return Err(ExciteError::Invalid(format!(
            "hop_size must be finite and ≥ 0 (got {})",
            opts.hop_size
        )));
    }
    if opts.starts > MAX_STARTS
        || opts.iterations_per_stage > MAX_ITERATIONS
        || opts.refine_iterations_per_stage > MAX_ITERATIONS
    {
        return Err(ExciteError::Invalid(format!(
            "at most {MAX_STARTS} starts and {MAX_ITERATIONS} iterations per stage are \
             accepted (got {} starts, {} and {} iterations)",
            opts.starts, opts.iterations_per_stage, opts.refine_iterations_per_stage
        )));
    }
    // After the starts alone, so `--starts` too large is named as such.
    if opts.starts.saturating_mul(opts.draws) > MAX_STARTS || opts.hops > MAX_STARTS {
        return Err(ExciteError::Invalid(format!(
            "at most {MAX_STARTS} draws (starts × draws) and {MAX_STARTS} hops are accepted \
             (got {} × {} draws, {} hops)",
            opts.starts, opts.draws, opts.hops
        )));
    }
    if !(opts.margin >= 0.0 && opts.margin < 0.5 && opts.coulomb_smoothing >= 0.0) {
        return Err(ExciteError::Invalid(format!(
            "margin must be in [0, 0.5) and coulomb_smoothing ≥ 0 (got {}, {})",
            opts.margin, opts.coulomb_smoothing
        )));
    }
    Ok(())
}

/// Refuses an initial trajectory that does not fit the robot or the options.
fn check_init(model: &Model, opts: &ExciteOptions) -> Result<(), ExciteError> {
    let (order, f0) = (opts.order, opts.base_frequency_hz);
    if let Some(t) = &opts.init {
        check_dof(model, t)?;
        if t.order != order || (t.base_frequency_hz - f0).abs() > 1e-12 * f0 {
            return Err(ExciteError::Invalid(format!(
                "the initial trajectory has order {} and f0 {} Hz, the options {order} and {f0} Hz",
                t.order, t.base_frequency_hz
            )));
        }
    }
    Ok(())
}

/// The best point of the search, if any: its objective and coefficient vector.
type Best = Option<(f64, Vec<f64>)>;

/// Explores every start, then refines the warm start and the best merits; returns the
/// criterion reached from each start and the best `(objective, x)`.
fn explore_and_refine(
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
fn no_motion(setup: &Setup<'_>) -> ExciteError {
    let (model, xs) = (setup.model, setup.xs);
    let n = model.dof();
    let mut rng = super::rng::Rng(0x5eed);
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
fn hop_from_best(setup: &Setup<'_>, progress: &dyn crate::progress::Progress, best: &mut Best) {
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
fn coordinate_room(
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
struct Setup<'a> {
    model: &'a Model,
    base: &'a BaseParameters,
    opts: &'a ExciteOptions,
    cons: &'a Constraints,
    /// The static pose as a coefficient vector (feasible with the margin).
    xs: &'a [f64],
    cgrid: &'a Grid,
    dense: &'a Grid,
    samples: usize,
    /// See [`coordinate_room`].
    room: Vec<f64>,
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

#[cfg(test)]
mod tests {
    use super::super::lbfgs::dot;
    use super::*;

    #[test]
    fn grid_matches_eval_and_backprop_is_adjoint() {
        let traj = FourierTrajectory {
            order: 2,
            base_frequency_hz: 0.3,
            q0: vec![0.1, -0.2],
            a: vec![vec![0.3, -0.1], vec![0.2, 0.05]],
            b: vec![vec![0.1, 0.02], vec![-0.15, 0.0]],
            coordinates: vec![],
        };
        let grid = Grid::uniform(17, 2, 0.3);
        let x = to_x(&traj);
        let (q, dq, ddq) = grid.eval(&x, 2);
        let (mut a, mut b, mut c) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        for k in 0..17 {
            traj.eval(grid.times[k], &mut a, &mut b, &mut c);
            for j in 0..2 {
                assert!((a[j] - q[k * 2 + j]).abs() < 1e-12);
                assert!((b[j] - dq[k * 2 + j]).abs() < 1e-12);
                assert!((c[j] - ddq[k * 2 + j]).abs() < 1e-12);
            }
        }
        // <g, J x> = <J^T g, x> (the map x -> (q - q0 part, dq, ddq) is linear).
        let mut rng = Rng(3);
        let g: Vec<f64> = (0..3 * 34).map(|_| rng.normal()).collect();
        let mut gx = vec![0.0; x.len()];
        grid.backprop(2, &g[..34], &g[34..68], &g[68..], &mut gx);
        let lhs: f64 = (0..34)
            .map(|i| g[i] * q[i] + g[34 + i] * dq[i] + g[68 + i] * ddq[i])
            .sum();
        assert!((lhs - dot(&gx, &x)).abs() < 1e-9 * lhs.abs().max(1.0));
    }

    #[test]
    fn rest_projection_zeroes_start_rates() {
        let mut rng = Rng(5);
        let (n, order) = (3, 4);
        let mut x: Vec<f64> = (0..n * (2 * order + 1)).map(|_| rng.normal()).collect();
        project_rest(&mut x, n, order);
        let t = from_x(&x, n, order, 0.2, &[]);
        let (mut q, mut dq, mut ddq) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        t.eval(0.0, &mut q, &mut dq, &mut ddq);
        assert!(
            dq.iter().chain(&ddq).all(|v| v.abs() < 1e-12),
            "{dq:?} {ddq:?}"
        );
    }
}
