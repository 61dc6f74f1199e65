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

use dvrk_model::{BaseParameters, Model, Workspace};
use serde::{Deserialize, Serialize};

use super::criterion::CriterionEval;
pub use super::criterion::{Criterion, CriterionValue};
use super::error::ExciteError;
use super::grid::{from_x, to_x, Grid};
use super::limits::{Constraints, Enforced, Multipliers};
pub use super::limits::{Feasibility, Limits, Violation};
pub use super::options::{ExciteOption, ExciteOptionError, ExciteOptions};
use super::setpoints::check_dof;
use super::FourierTrajectory;
use search::{coordinate_room, explore_and_refine, hop_from_best, no_motion, Setup};

mod search;

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
    let trajectory = FourierTrajectory {
        robot: Some(model.name.clone()),
        ..from_x(&x, n, order, f0, &model.coordinates)
    };
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

#[cfg(test)]
mod tests {
    use super::super::grid::project_rest;
    use super::super::lbfgs::dot;
    use super::*;
    use dvrk_test_support::Rng;

    #[test]
    fn grid_matches_eval_and_backprop_is_adjoint() {
        let traj = FourierTrajectory {
            order: 2,
            base_frequency_hz: 0.3,
            q0: vec![0.1, -0.2],
            a: vec![vec![0.3, -0.1], vec![0.2, 0.05]],
            b: vec![vec![0.1, 0.02], vec![-0.15, 0.0]],
            coordinates: vec![],
            robot: None,
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
        let mut rng = Rng::new(3);
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
        let mut rng = Rng::new(5);
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
