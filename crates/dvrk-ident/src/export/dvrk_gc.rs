//! The dVRK controller's MTM gravity-compensation file (version "2.0") from an identified
//! MTM model, so that a lab can hand our fit to sawIntuitiveResearchKit instead of
//! collecting an hour of data for the CUHK MATLAB/Python tool.
//!
//! What the controller does with the file (read in `robGravityCompensationMTM.cpp` of
//! jhu-dvrk/sawIntuitiveResearchKit, commit af18bd7):
//!
//! - `Create()` reads `std::stod(json["version"].asString())` (so the version is the
//!   string `"2.0"`) and, for version 2, the arrays `gc_dynamic_params_pos`,
//!   `gc_dynamic_params_neg`, `safe_upper_torque_limit`, `safe_lower_torque_limit`,
//!   `db_vel_vec`, `sat_vec_vec`, `fric_comp_ratio_vec` of `GC_controller`; an empty one
//!   is an error, other keys are ignored;
//! - `AssignRegressor(q)` fills a 7×40 matrix `Y` of the measured joint positions (rad):
//!   columns 0–9 are ten lumped gravity terms in sines and cosines of q2…q6 with
//!   `g = 9.81` (joint 1 has none), columns `10 + 5k … 14 + 5k` are `1, q, q², q³, q⁴` of
//!   joint `k + 1` in row `k` (k = 0…5), row 6 (joint 7) stays zero; [`regressor`]
//!   reproduces it, with the products of sines and cosines of q2 and q3 grouped into
//!   `cos(q2 + q3)` and `sin(q2 + q3)` as the source's sums of products are;
//! - `compute()` (version 2) blends `τ = α·(Y·pos) + (1 − α)·(Y·neg)` per joint with
//!   `α(q̇) = 0.5` for `|q̇| ≤ db_vel`, `0.5 ± 0.5·fric_comp_ratio` for `q̇ ≥ sat_vel` /
//!   `q̇ ≤ −sat_vel`, linear in between, then clamps `τ` to the safe limits.
//!
//! So `Y·pos` is the torque to feed forward while a joint moves positively and `Y·neg`
//! while it moves negatively. [`dvrk_gc`] fits both to our model's static torque
//! ([`dvrk_model::Model::static_torque`]: gravity, springs, known forces, Coulomb,
//! Stribeck and offset friction) in measured joint coordinates, over a regular grid of
//! the description's ranges of joints 1–6, in two least-squares stages:
//!
//! 1. the ten gravity parameters, shared by `pos` and `neg` as in the CUHK generator, on
//!    the links' gravity torque alone (joints 2–6). The controller does not read the
//!    wrist roll (joint 7), so the torque is averaged over a turn of it: a rigid body
//!    turning with the roll moves the gravity torque by a first harmonic `a·cos q7 +
//!    b·sin q7`, whose average is the mean of rolls 0 and π and whose amplitude (from
//!    roll π/2) is added to the residuals; a model that is not a first harmonic of the
//!    roll (checked at −π/2) is refused. The basis spans the rest of the MTM's gravity
//!    (every link rotates with the dVRK joints in the way the CUHK derivation assumes),
//!    so the average is fitted exactly to rounding, and the residual is the wrist
//!    roll's centre of mass off its axis;
//! 2. per joint and direction, the quartic in the joint's own position on what is left:
//!    springs (the wrist-pitch spring), known forces (the wrist-platform cable, a 7th
//!    degree polynomial), friction, and any gravity the basis misses. Those depend on
//!    one joint each on the MTM, so a quartic approximates them; the residual is
//!    reported per joint (max and RMS, N·m).

use dvrk_model::{Model, Workspace};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use rayon::prelude::*;

use crate::observation::Observation;
use crate::IdentError;

/// Gravity acceleration the controller's regressor assumes (m/s²).
pub const G: f64 = 9.81;
/// Rows of the controller's regressor: the MTM's seven measured joints.
pub const JOINTS: usize = 7;
/// Columns of the controller's regressor: 10 gravity terms and 6 quartics.
pub const COLUMNS: usize = 40;
/// Gravity columns, shared by `pos` and `neg`.
const GRAVITY_COLUMNS: usize = 10;
/// The dVRK's MTM joint names in the controller's order (the measured joints of
/// `robots/mtm.toml`).
pub const MTM_JOINTS: [&str; JOINTS] = [
    "outer_yaw",
    "shoulder_pitch",
    "elbow_pitch",
    "wrist_platform",
    "wrist_pitch",
    "wrist_yaw",
    "wrist_roll",
];

/// Velocity blend of the CUHK generator's defaults (jhu-dvrk/dvrk-gravity-compensation,
/// `config/gc_controller.json`): dead band (rad/s) within which both directions count
/// half. Tuned on real MTMs for stability near rest; our identification has nothing to
/// say about it.
pub const DB_VEL: [f64; JOINTS] = [0.02, 0.02, 0.02, 0.01, 0.008, 0.008, 0.01];
/// Speed (rad/s) from which the blend is saturated (CUHK default).
pub const SAT_VEL: [f64; JOINTS] = [0.2; JOINTS];
/// Share of the friction difference `pos − neg` compensated beyond `SAT_VEL` (CUHK
/// default: less than all of it on most joints, so the handle does not drift).
pub const FRIC_COMP_RATIO: [f64; JOINTS] = [0.7, 0.01, 0.5, 0.4, 0.2, 0.2, 1.0];

/// Widening of the safe torque limits beyond the range the file's compensation spans
/// over the joint ranges, as a share of that range: the clamp stops a runaway outside
/// the workspace without cutting the model inside it.
const LIMIT_MARGIN: f64 = 0.25;
/// Least widening of the safe torque limits (N·m).
const LIMIT_MARGIN_MIN: f64 = 0.05;

/// Grid points per joint by default: 7⁶ = 117 649 configurations of joints 1–6.
pub const DEFAULT_POINTS: usize = 7;

/// The controller's regressor `Y(q)` (7×40, row-major) at measured joint positions `q`
/// (rad, the dVRK's MTM joint order; joint 7 is not used).
pub fn regressor(q: &[f64; JOINTS]) -> [[f64; COLUMNS]; JOINTS] {
    let mut y = [[0.0; COLUMNS]; JOINTS];
    let (s2, c2) = q[1].sin_cos();
    let (s3, c3) = q[2].sin_cos();
    let (s4, c4) = q[3].sin_cos();
    let (s5, c5) = q[4].sin_cos();
    let (s6, c6) = q[5].sin_cos();
    // cos(q2 + q3) and sin(q2 + q3) as the products the source sums.
    let c = c2 * c3 - s2 * s3;
    let s = s2 * c3 + c2 * s3;
    // Joints 2 and 3: columns 2–9 are the same in both rows.
    let upper = [
        c,
        -s,
        c * c4,
        -c * s4,
        -(c * c4 * s5 + s * c5),
        c * c4 * c5 - s * s5,
        c * s4 * s6 + s * c6 * s5 - c * c4 * c5 * c6,
        c * c6 * s4 - s * s5 * s6 + c * c4 * c5 * s6,
    ];
    y[1][0] = G * s2;
    y[1][1] = G * c2;
    for (k, v) in upper.iter().enumerate() {
        y[1][2 + k] = G * v;
        y[2][2 + k] = G * v;
    }
    let wrist_platform = [
        -s * s4,
        -s * c4,
        s * s4 * s5,
        -s * c5 * s4,
        s * (c4 * s6 + c5 * c6 * s4),
        s * (c4 * c6 - c5 * s4 * s6),
    ];
    for (k, v) in wrist_platform.iter().enumerate() {
        y[3][4 + k] = G * v;
    }
    let wrist_pitch = [
        -(c * s5 + s * c4 * c5),
        c * c5 - s * c4 * s5,
        s * c4 * c6 * s5 - c * c5 * c6,
        c * c5 * s6 - s * c4 * s5 * s6,
    ];
    for (k, v) in wrist_pitch.iter().enumerate() {
        y[4][6 + k] = G * v;
    }
    y[5][8] = G * (s * c6 * s4 + c * s5 * s6 + s * c4 * c5 * s6);
    y[5][9] = G * (c * c6 * s5 - s * s4 * s6 + s * c4 * c5 * c6);
    for (j, row) in y.iter_mut().enumerate().take(6) {
        let mut p = 1.0;
        for col in row[GRAVITY_COLUMNS + 5 * j..GRAVITY_COLUMNS + 5 * j + 5].iter_mut() {
            *col = p;
            p *= q[j];
        }
    }
    y
}

/// The controller's velocity blend `α(q̇)` of one joint (version 2): the weight of
/// `Y·pos`, `1 − α` that of `Y·neg`.
pub fn alpha(qd: f64, db_vel: f64, sat_vel: f64, ratio: f64) -> f64 {
    if qd >= sat_vel {
        0.5 + 0.5 * ratio
    } else if qd <= -sat_vel {
        0.5 - 0.5 * ratio
    } else if qd.abs() <= db_vel {
        0.5
    } else if qd > 0.0 {
        0.5 + 0.5 * ratio * (qd - db_vel) / (sat_vel - db_vel)
    } else {
        0.5 - 0.5 * ratio * (-qd - db_vel) / (sat_vel - db_vel)
    }
}

/// How far the file's compensation is from the model over the grid, per joint (N·m),
/// over a whole turn of the wrist roll (the error at its average plus the amplitude of
/// its first harmonic; the RMS over the turn).
#[derive(Clone, Debug, Serialize)]
pub struct Residuals {
    /// Gravity columns against the links' gravity torque.
    pub gravity_max: Vec<f64>,
    /// RMS over the grid of the same error, N·m.
    pub gravity_rms: Vec<f64>,
    /// `Y·pos` against the static torque for positive motion of the joint.
    pub pos_max: Vec<f64>,
    /// RMS over the grid of the same error, N·m.
    pub pos_rms: Vec<f64>,
    /// `Y·neg` against the static torque for negative motion of the joint.
    pub neg_max: Vec<f64>,
    /// RMS over the grid of the same error, N·m.
    pub neg_rms: Vec<f64>,
}

/// A gravity-compensation file for the dVRK's MTM controller, and how well it
/// represents the model.
#[derive(Clone, Debug)]
pub struct DvrkGc {
    /// `gc_dynamic_params_pos`, 40 values (columns 0–9 shared with `neg`).
    pub pos: Vec<f64>,
    /// `gc_dynamic_params_neg`, 40 values.
    pub neg: Vec<f64>,
    /// `safe_upper_torque_limit`, `safe_lower_torque_limit` (N·m): the range of the
    /// compensation over the grid, widened (joint 7: 0, it is not compensated).
    pub upper: Vec<f64>,
    /// `safe_lower_torque_limit` (N·m), per joint: the lower end of that range.
    pub lower: Vec<f64>,
    /// `db_vel_vec`, `sat_vec_vec` (rad/s), `fric_comp_ratio_vec`: CUHK defaults.
    pub db_vel: Vec<f64>,
    /// `sat_vec_vec` (the key as the controller spells it), rad/s: the speed beyond which
    /// the blend [`alpha`] of `pos` and `neg` stops changing.
    pub sat_vel: Vec<f64>,
    /// `fric_comp_ratio_vec` (0 to 1): the share of the friction difference `pos − neg`
    /// compensated at full speed ([`alpha`] = `0.5 ± 0.5·ratio`).
    pub fric_comp_ratio: Vec<f64>,
    /// How far the file's compensation is from the model over the grid, per joint (N·m).
    pub residuals: Residuals,
    /// Joint ranges of the grid (rad, joints 1–6) and points per joint.
    pub ranges: Vec<[f64; 2]>,
    /// Grid points per joint (6 to 10).
    pub points: usize,
    /// Configurations of the grid, `points⁶`.
    pub configurations: usize,
    /// The robot the model was loaded as.
    pub robot: String,
}

impl DvrkGc {
    /// The file as the controller reads it, with our provenance and residuals under
    /// `dvrk_ident` (the loader reads only `version` and `GC_controller`).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "version": "2.0",
            "GC_controller": {
                "gc_dynamic_params_pos": self.pos,
                "gc_dynamic_params_neg": self.neg,
                "safe_upper_torque_limit": self.upper,
                "safe_lower_torque_limit": self.lower,
                "db_vel_vec": self.db_vel,
                "sat_vec_vec": self.sat_vel,
                "fric_comp_ratio_vec": self.fric_comp_ratio,
            },
            "dvrk_ident": {
                "robot": self.robot,
                "joints": MTM_JOINTS,
                "fit": "least squares over a regular grid of the joint ranges: the gravity \
                        columns on the links' gravity torque, then per joint and direction \
                        the quartic on the rest of the static torque (springs, cable, \
                        friction)",
                "grid": {
                    "ranges_rad": self.ranges,
                    "points_per_joint": self.points,
                    "configurations": self.configurations,
                },
                "residual_N_m": self.residuals,
                "velocity_blend": "db_vel_vec, sat_vec_vec, fric_comp_ratio_vec: defaults of \
                                   the CUHK generator (jhu-dvrk/dvrk-gravity-compensation)",
                "safe_limits": "range of the compensation over the grid, widened by 25 % \
                                (at least 0.05 N·m) on each side; joint 7 not compensated",
            }
        })
    }

    /// A per-joint table of the residuals, for the command line.
    pub fn summary(&self) -> String {
        let r = &self.residuals;
        let mut out = format!(
            "dVRK MTM gravity compensation (version 2.0): {} configurations, {} per joint\n\
             residual vs model (N·m)   gravity max/rms        pos max/rms            neg max/rms\n",
            self.configurations, self.points
        );
        for (j, name) in MTM_JOINTS.iter().enumerate() {
            out += &format!(
                "  {:<15} {:>10.2e} {:>10.2e}  {:>10.2e} {:>10.2e}  {:>10.2e} {:>10.2e}\n",
                name,
                r.gravity_max[j],
                r.gravity_rms[j],
                r.pos_max[j],
                r.pos_rms[j],
                r.neg_max[j],
                r.neg_rms[j]
            );
        }
        out += "joint 7 (wrist_roll) is not compensated by the controller (its row is zero)\n";
        out
    }
}

/// The static torques of the model at one measured configuration of joints 1–6,
/// measured coordinates (N·m), averaged over the wrist roll (joint 7), which the
/// controller does not read: the links' gravity, and per joint the static torque for
/// positive and negative motion of that joint alone; and how far the wrist roll moves
/// them about that average.
struct Static {
    gravity: [f64; JOINTS],
    pos: [f64; JOINTS],
    neg: [f64; JOINTS],
    /// Amplitude of the torque's dependence on the wrist roll (a rigid body turning
    /// about an axis: `a·cos q7 + b·sin q7` about the average).
    roll: [f64; JOINTS],
}

/// Evaluates the model in measured coordinates.
struct Evaluator<'a> {
    model: &'a Model,
    params: &'a [f64],
    ws: Workspace,
    /// `q_model = M⁻¹·q_measured`.
    to_model: DMatrix<f64>,
    /// `τ_measured = M⁻ᵀ·τ_model`.
    to_measured_torque: DMatrix<f64>,
}

impl Evaluator<'_> {
    /// The links' gravity torque, measured joints.
    fn gravity(&mut self, qm: &[f64; JOINTS]) -> DVector<f64> {
        let q = &self.to_model * DVector::from_column_slice(qm);
        let mut tau = DVector::zeros(JOINTS);
        self.model
            .gravity_torque(&mut self.ws, self.params, q.as_slice(), tau.as_mut_slice());
        &self.to_measured_torque * tau
    }

    /// `None` when the gravity torque is not a first harmonic of the wrist roll.
    fn eval(&mut self, qm: &[f64; JOINTS]) -> Option<Static> {
        let n = JOINTS;
        // Wrist roll at 0, π, ±π/2: the average and the amplitude of a first harmonic.
        let at = |roll: f64| {
            let mut q = *qm;
            q[6] = roll;
            q
        };
        let half = std::f64::consts::FRAC_PI_2;
        let g0 = self.gravity(&at(0.0));
        let g_pi = self.gravity(&at(std::f64::consts::PI));
        let g_up = self.gravity(&at(half));
        let g_down = self.gravity(&at(-half));
        let mean = (&g0 + &g_pi) * 0.5;
        let harmonic = (&g_up + &g_down) * 0.5 - &mean;
        let size = 1.0 + mean.amax() + g_up.amax();
        if harmonic.amax() > 1e-9 * size {
            return None;
        }
        let mut out = Static {
            gravity: [0.0; JOINTS],
            pos: [0.0; JOINTS],
            neg: [0.0; JOINTS],
            roll: [0.0; JOINTS],
        };
        for j in 0..n {
            out.gravity[j] = mean[j];
            out.roll[j] = (0.5 * (g0[j] - g_pi[j])).hypot(g_up[j] - mean[j]);
        }
        // Springs, known forces and friction at roll 0, gravity averaged.
        let q = &self.to_model * DVector::from_column_slice(&at(0.0));
        let mut tau = DVector::zeros(n);
        for j in 0..n {
            for sign in [1.0, -1.0] {
                // Motion of measured joint j alone, in model coordinates.
                let motion = self.to_model.column(j) * sign;
                self.model.static_torque(
                    &mut self.ws,
                    self.params,
                    q.as_slice(),
                    motion.as_slice(),
                    tau.as_mut_slice(),
                );
                let t = self.to_measured_torque.row(j).dot(&tau.transpose()) + mean[j] - g0[j];
                if sign > 0.0 {
                    out.pos[j] = t;
                } else {
                    out.neg[j] = t;
                }
            }
        }
        Some(out)
    }
}

/// The position range (rad) of each measured joint 1–6 from the description's limits: a
/// `[[limits]]` entry whose expression is the joint (its row of the coupling).
fn joint_ranges(model: &Model) -> Result<Vec<[f64; 2]>, IdentError> {
    let m = &model.measured.coupling;
    (0..6)
        .map(|j| {
            model
                .limits
                .iter()
                .filter(|lim| {
                    let mut row = vec![0.0; model.dof()];
                    for &(k, c) in &lim.expr.terms {
                        row[k] = c;
                    }
                    lim.expr.offset == 0.0
                        && row
                            .iter()
                            .enumerate()
                            .all(|(k, c)| (c - m[(j, k)]).abs() <= 1e-12)
                })
                .find_map(|lim| lim.position)
                .filter(|[lo, hi]| lo.is_finite() && hi.is_finite() && lo < hi)
                .ok_or_else(|| IdentError::Mismatch {
                    source_name: format!("robot `{}`", model.name),
                    message: format!(
                        "no finite position range of measured joint `{}` (a [[limits]] entry \
                         with expr = \"{}\" and position = [lower, upper]): the \
                         gravity-compensation fit needs the joint ranges",
                        model.measured.joints[j], model.measured.joints[j]
                    ),
                })
        })
        .collect()
}

/// The grid configuration of index `index` (measured joints; joint 7 at 0).
fn grid_point(ranges: &[[f64; 2]], points: usize, mut index: usize) -> [f64; JOINTS] {
    let mut q = [0.0; JOINTS];
    for (j, [lo, hi]) in ranges.iter().enumerate() {
        let i = index % points;
        index /= points;
        q[j] = lo + (hi - lo) * i as f64 / (points - 1) as f64;
    }
    q
}

/// Rows of configurations handed to the QR factor at a time.
const BLOCK: usize = 2048;

/// Solves the least-squares problem of an observation (R factor of `[A | b]`).
fn solve(obs: &Observation, what: &str) -> Result<Vec<f64>, IdentError> {
    let p = obs.n_params();
    let r = obs.r();
    let r11 = r.view((0, 0), (p, p)).into_owned();
    let diag_max = (0..p).map(|i| r11[(i, i)].abs()).fold(0.0, f64::max);
    // NaN on the diagonal fails the comparison too.
    let determined = |i: usize| r11[(i, i)].abs() > 1e-12 * diag_max;
    if !(0..p).all(determined) {
        return Err(IdentError::RankDeficient {
            source_name: "dVRK gravity compensation".into(),
            message: format!("the grid does not determine the {what}"),
        });
    }
    let rhs = DVector::from_iterator(p, (0..p).map(|i| r[(i, p)]));
    let x = r11
        .solve_upper_triangular(&rhs)
        .expect("non-singular triangular factor");
    Ok(x.iter().copied().collect())
}

/// The MTM gravity-compensation file of `params` for `model` (the MTM, or a
/// description with its measured joints), fitted over `points` grid points per joint
/// (6 to 10: the quartics need five distinct positions, one more to see a residual;
/// 10⁶ configurations take about 20 s and 250 MB).
pub fn dvrk_gc(model: &Model, params: &[f64], points: usize) -> Result<DvrkGc, IdentError> {
    let to_model = check_inputs(model, params, points)?;
    // The controller's file holds the links' gravity: only rigid bodies, as a URDF
    // (whose exports check the same inside dvrk-model).
    model.check_rigid_bodies(params)?;
    let grid = Grid {
        ranges: joint_ranges(model)?,
        points,
        configurations: points.pow(6),
    };
    let statics = evaluate(model, params, &to_model, &grid)?;
    let gravity = fit_gravity(&statics, &grid)?;
    let (pos, neg) = fit_quartics(&statics, &grid, &gravity)?;
    let (residuals, upper, lower) = residuals_and_limits(&statics, &grid, &gravity, &pos, &neg);
    let out = DvrkGc {
        pos,
        neg,
        upper,
        lower,
        db_vel: DB_VEL.to_vec(),
        sat_vel: SAT_VEL.to_vec(),
        fric_comp_ratio: FRIC_COMP_RATIO.to_vec(),
        residuals,
        ranges: grid.ranges,
        points: grid.points,
        configurations: grid.configurations,
        robot: model.name.clone(),
    };
    let finite = out
        .pos
        .iter()
        .chain(&out.neg)
        .chain(&out.upper)
        .chain(&out.lower)
        .all(|v| v.is_finite());
    if !finite {
        return Err(IdentError::RankDeficient {
            source_name: "dVRK gravity compensation".into(),
            message: "the fit gave non-finite values".into(),
        });
    }
    Ok(out)
}

/// The grid the file is fitted over: `points` positions per joint in `ranges`,
/// `configurations = points⁶` in all.
struct Grid {
    ranges: Vec<[f64; 2]>,
    points: usize,
    configurations: usize,
}

/// A robot that is not the MTM, or parameters that do not fit it.
fn mismatch(model: &Model, message: String) -> IdentError {
    IdentError::Mismatch {
        source_name: format!("robot `{}`", model.name),
        message,
    }
}

/// Refuses a grid size, a robot or parameters the file cannot be made from; returns
/// the measured-to-model joint matrix.
fn check_inputs(model: &Model, params: &[f64], points: usize) -> Result<DMatrix<f64>, IdentError> {
    if !(6..=10).contains(&points) {
        return Err(IdentError::Setting {
            name: crate::error::SettingName::Argument("points"),
            message: format!(
                "grid points per joint must be 6 to 10 (10⁶ configurations), got {points}"
            ),
        });
    }
    let mismatch = |message: String| mismatch(model, message);
    if model
        .measured
        .joints
        .iter()
        .map(String::as_str)
        .ne(MTM_JOINTS)
    {
        return Err(mismatch(format!(
            "the dVRK gravity-compensation file is for the MTM, whose measured joints are \
             {}; this robot's are {}",
            MTM_JOINTS.join(", "),
            model.measured.joints.join(", ")
        )));
    }
    if params.len() != model.n_params() || params.iter().any(|p| !p.is_finite()) {
        return Err(mismatch(format!(
            "expected {} finite parameters, got {}",
            model.n_params(),
            params.len()
        )));
    }
    model
        .measured_to_model_matrix()
        .ok_or_else(|| mismatch("the coupling matrix is singular".into()))
}

/// The model at every grid configuration, once (21 numbers each), in parallel.
fn evaluate(
    model: &Model,
    params: &[f64],
    to_model: &DMatrix<f64>,
    grid: &Grid,
) -> Result<Vec<Static>, IdentError> {
    let to_measured_torque = to_model.transpose();
    let statics: Option<Vec<Static>> = (0..grid.configurations)
        .into_par_iter()
        .chunks(BLOCK)
        .flat_map_iter(|chunk| {
            let mut ev = Evaluator {
                model,
                params,
                ws: Workspace::new(model),
                to_model: to_model.clone(),
                to_measured_torque: to_measured_torque.clone(),
            };
            chunk
                .into_iter()
                .map(|c| ev.eval(&grid_point(&grid.ranges, grid.points, c)))
                .collect::<Vec<_>>()
        })
        .collect();
    statics.ok_or_else(|| {
        mismatch(
            model,
            "its gravity torque depends on the wrist roll (joint 7) otherwise than a rigid \
             body turning about the roll axis; the controller cannot represent it"
                .into(),
        )
    })
}

/// Stage 1: gravity columns on the gravity torque of joints 2–6.
fn fit_gravity(statics: &[Static], grid: &Grid) -> Result<Vec<f64>, IdentError> {
    let mut gravity_obs = Observation::new(GRAVITY_COLUMNS);
    let mut block = DMatrix::zeros(0, GRAVITY_COLUMNS + 1);
    let mut start = 0;
    while start < grid.configurations {
        let end = (start + BLOCK).min(grid.configurations);
        block = block.resize((end - start) * 5, GRAVITY_COLUMNS + 1, 0.0);
        for (c, st) in statics.iter().enumerate().take(end).skip(start) {
            let y = regressor(&grid_point(&grid.ranges, grid.points, c));
            for (j, row) in y.iter().enumerate().take(6).skip(1) {
                let r = (c - start) * 5 + j - 1;
                for (k, v) in row[..GRAVITY_COLUMNS].iter().enumerate() {
                    block[(r, k)] = *v;
                }
                block[(r, GRAVITY_COLUMNS)] = st.gravity[j];
            }
        }
        gravity_obs.add_rows(&block);
        start = end;
    }
    solve(&gravity_obs, "gravity parameters")
}

/// The gravity columns' share of joint `j`'s torque.
fn gravity_part(y: &[[f64; COLUMNS]; JOINTS], j: usize, gravity: &[f64]) -> f64 {
    (0..GRAVITY_COLUMNS).map(|k| y[j][k] * gravity[k]).sum()
}

/// Stage 2 (after stage 1): per joint and direction, the quartic `[1, q, q², q³, q⁴]`
/// of what gravity leaves; returns the `pos` and `neg` coefficient vectors.
fn fit_quartics(
    statics: &[Static],
    grid: &Grid,
    gravity: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), IdentError> {
    let mut quartic_obs: Vec<[Observation; 2]> = (0..6)
        .map(|_| [Observation::new(5), Observation::new(5)])
        .collect();
    let mut blocks: Vec<[DMatrix<f64>; 2]> = (0..6)
        .map(|_| [DMatrix::zeros(0, 6), DMatrix::zeros(0, 6)])
        .collect();
    let mut start = 0;
    while start < grid.configurations {
        let end = (start + BLOCK).min(grid.configurations);
        for pair in blocks.iter_mut() {
            for b in pair.iter_mut() {
                *b = std::mem::replace(b, DMatrix::zeros(0, 0)).resize(end - start, 6, 0.0);
            }
        }
        for (c, st) in statics.iter().enumerate().take(end).skip(start) {
            let y = regressor(&grid_point(&grid.ranges, grid.points, c));
            for (j, pair) in blocks.iter_mut().enumerate() {
                let g = gravity_part(&y, j, gravity);
                for (b, target) in pair.iter_mut().zip([st.pos[j], st.neg[j]]) {
                    for k in 0..5 {
                        b[(c - start, k)] = y[j][GRAVITY_COLUMNS + 5 * j + k];
                    }
                    b[(c - start, 5)] = target - g;
                }
            }
        }
        for (obs, b) in quartic_obs.iter_mut().zip(&blocks) {
            obs[0].add_rows(&b[0]);
            obs[1].add_rows(&b[1]);
        }
        start = end;
    }
    let mut pos = vec![0.0; COLUMNS];
    pos[..GRAVITY_COLUMNS].copy_from_slice(gravity);
    let mut neg = pos.clone();
    for (j, obs) in quartic_obs.iter().enumerate() {
        let cols = GRAVITY_COLUMNS + 5 * j..GRAVITY_COLUMNS + 5 * j + 5;
        pos[cols.clone()].copy_from_slice(&solve(&obs[0], &format!("quartic of joint {}", j + 1))?);
        neg[cols].copy_from_slice(&solve(&obs[1], &format!("quartic of joint {}", j + 1))?);
    }
    Ok((pos, neg))
}

/// Residuals and the range of the compensation, on the same grid; returns the
/// residuals and the upper and lower torque limits.
fn residuals_and_limits(
    statics: &[Static],
    grid: &Grid,
    gravity: &[f64],
    pos: &[f64],
    neg: &[f64],
) -> (Residuals, Vec<f64>, Vec<f64>) {
    let mut max = [[0.0f64; JOINTS]; 3];
    let mut sum2 = [[0.0f64; JOINTS]; 3];
    let mut low = [f64::INFINITY; JOINTS];
    let mut high = [f64::NEG_INFINITY; JOINTS];
    for (c, st) in statics.iter().enumerate() {
        let y = regressor(&grid_point(&grid.ranges, grid.points, c));
        for j in 0..JOINTS {
            let tp: f64 = (0..COLUMNS).map(|k| y[j][k] * pos[k]).sum();
            let tn: f64 = (0..COLUMNS).map(|k| y[j][k] * neg[k]).sum();
            let errors = [
                gravity_part(&y, j, gravity) - st.gravity[j],
                tp - st.pos[j],
                tn - st.neg[j],
            ];
            // Over a turn of the wrist roll: the error at its average plus (or, squared
            // and averaged, half) the amplitude of the roll's first harmonic.
            let a = st.roll[j];
            for (i, e) in errors.iter().enumerate() {
                max[i][j] = max[i][j].max(e.abs() + a);
                sum2[i][j] += e * e + 0.5 * a * a;
            }
            low[j] = low[j].min(tp.min(tn));
            high[j] = high[j].max(tp.max(tn));
        }
    }
    let rms = |i: usize| -> Vec<f64> {
        sum2[i]
            .iter()
            .map(|s| (s / grid.configurations as f64).sqrt())
            .collect()
    };
    let mut upper = vec![0.0; JOINTS];
    let mut lower = vec![0.0; JOINTS];
    for j in 0..6 {
        let margin = (LIMIT_MARGIN * (high[j] - low[j])).max(LIMIT_MARGIN_MIN);
        upper[j] = high[j] + margin;
        lower[j] = low[j] - margin;
    }
    let residuals = Residuals {
        gravity_max: max[0].to_vec(),
        gravity_rms: rms(0),
        pos_max: max[1].to_vec(),
        pos_rms: rms(1),
        neg_max: max[2].to_vec(),
        neg_rms: rms(2),
    };
    (residuals, upper, lower)
}

#[cfg(test)]
pub(crate) mod tests;
