//! The compiled limits (`Item`s, `Constraints`) and their values and gradients on a
//! grid (see [`super`]); the repair and the dense check are `repair`'s.

// `!(x > 0.0)`-style tests are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub use dvrk_model::Limits;
use dvrk_model::{Model, Workspace};
use serde::{Deserialize, Serialize};

use crate::excite::grid::Grid;
use crate::excite::ExciteError;

/// The worst (largest) limit excess on a grid; positive = violated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    /// The limit: a joint limit's expression (e.g. `1.2177*(q7 - q6)`), or `frame NAME
    /// AXIS` for a Cartesian box (e.g. `frame wrist_pitch x`).
    pub limit: String,
    /// `position`, `velocity` or `acceleration` (a box limits a position).
    pub quantity: String,
    /// Time of the worst sample, s.
    pub time_s: f64,
    /// Value there (rad, m, or their rates; a box: the origin's coordinate, m).
    pub value: f64,
    /// The bound it is compared with.
    pub bound: f64,
    /// `value - bound` beyond the bound (positive: violated; negative: the tightest
    /// margin).
    pub excess: f64,
}

/// Result of the dense feasibility check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Feasibility {
    /// No limit exceeded by more than 1e-9 at any sample.
    pub feasible: bool,
    /// Samples checked (whole period).
    pub samples: usize,
    /// The sampling rate of the check, Hz (the rate asked for, at least 1 kHz).
    pub rate_hz: f64,
    /// The largest excess over all limits and samples (None: no limits).
    pub worst: Option<Violation>,
    /// Every violated limit (position, velocity or acceleration of one expression, or
    /// one axis of a box) with its own worst sample, largest excess first.
    pub violated: Vec<Violation>,
}

/// An excess up to this is rounding, not a violation (values are rad, m and rates of
/// order 1).
pub(crate) const TOLERANCE: f64 = 1e-9;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Quantity {
    Position,
    Velocity,
    Acceleration,
}

impl Quantity {
    pub fn name(&self) -> &'static str {
        match self {
            Quantity::Position => "position",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
        }
    }
}

#[derive(Clone, Debug)]
pub(crate) enum Source {
    /// `offset + Σ c·(q, q̇ or q̈)[j]` (the offset only for positions).
    Linear {
        terms: Vec<(usize, f64)>,
        offset: f64,
    },
    /// Coordinate `axis` of frame `frame`'s origin in the base frame.
    Origin { frame: usize, axis: usize },
}

/// One bounded scalar of the motion.
#[derive(Clone, Debug)]
pub(crate) struct Item {
    pub label: String,
    pub quantity: Quantity,
    pub source: Source,
    pub lo: f64,
    pub hi: f64,
}

impl Item {
    /// The unit of the normalized constraint values: the range, or 1 (m) for a box axis
    /// bounded on one side only.
    pub(super) fn scale(&self) -> f64 {
        let r = self.hi - self.lo;
        if r.is_finite() {
            r.max(1e-12)
        } else {
            1.0
        }
    }

    /// The bounds moved inward by `margin` of the range ([`Item::scale`] for a half-open
    /// one).
    pub fn shrunk(&self, margin: f64) -> (f64, f64) {
        let m = margin * self.scale();
        Item::ordered(self.lo + m, self.hi - m)
    }

    /// [`Item::shrunk`], then moved inward by `slack` (absolute units).
    pub fn within(&self, margin: f64, slack: f64) -> (f64, f64) {
        let (lo, hi) = self.shrunk(margin);
        Item::ordered(lo + slack, hi - slack)
    }

    /// A range moved inward past its own width collapses to its midpoint instead of
    /// turning inside out (a narrow limit shrunk by a margin; `f64::clamp` panics on an
    /// inverted range).
    fn ordered(lo: f64, hi: f64) -> (f64, f64) {
        if lo <= hi {
            (lo, hi)
        } else {
            let mid = 0.5 * (lo + hi);
            (mid, mid)
        }
    }
}

/// A joint position limit: the item, its terms and its offset.
pub(super) type LinearItem<'a> = (&'a Item, &'a Vec<(usize, f64)>, f64);

/// Where the limits are enforced: at the instants of `grid`, with every bound shrunk
/// by `margin` (a fraction of its range).
#[derive(Clone, Copy)]
pub(crate) struct Enforced<'a> {
    pub grid: &'a Grid,
    pub margin: f64,
}

/// The augmented Lagrangian's multipliers `λ` (one per bound side and instant, as
/// [`Constraints::multipliers`] counts them; empty: all zero, the exterior penalty) and
/// its penalty weight `μ`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Multipliers<'a> {
    pub lambda: &'a [f64],
    pub mu: f64,
}

/// The gradient slices of one sample, with respect to its `q`, `q̇` and `q̈`.
pub(super) struct SampleGradient<'a> {
    pub(super) q: &'a mut [f64],
    pub(super) dq: &'a mut [f64],
    pub(super) ddq: &'a mut [f64],
}

/// The limits of one model as items, with what evaluating them needs.
pub(crate) struct Constraints {
    pub items: Vec<Item>,
    /// Whether any item is a frame origin (then every sample needs forward kinematics).
    pub(super) origins: bool,
}

impl Constraints {
    pub fn new(model: &Model, limits: &Limits) -> Result<Constraints, ExciteError> {
        let n = model.dof();
        let mut items = Vec::new();
        for lim in &limits.joint {
            if let Some(&(k, _)) = lim.expr.terms.iter().find(|(k, _)| *k >= n) {
                return Err(ExciteError::ImpossibleLimits(format!(
                    "limit {}: coordinate index {k} beyond the model's {n}",
                    lim.label
                )));
            }
            for (q, range) in [
                (Quantity::Position, lim.position),
                (Quantity::Velocity, lim.velocity),
                (Quantity::Acceleration, lim.acceleration),
            ] {
                let Some([lo, hi]) = range else { continue };
                if !(lo <= hi) {
                    return Err(ExciteError::ImpossibleLimits(format!(
                        "limit {}: {} range [{lo}, {hi}] is empty",
                        lim.label,
                        q.name()
                    )));
                }
                if lo == hi {
                    return Err(ExciteError::ImpossibleLimits(format!(
                        "limit {}: {} range [{lo}, {hi}] has zero width: nothing that it \
                         limits could move, so the motion could not excite it",
                        lim.label,
                        q.name()
                    )));
                }
                items.push(Item {
                    label: lim.label.clone(),
                    quantity: q,
                    source: Source::Linear {
                        terms: lim.expr.terms.clone(),
                        offset: if q == Quantity::Position {
                            lim.expr.offset
                        } else {
                            0.0
                        },
                    },
                    lo,
                    hi,
                });
            }
        }
        for c in &limits.cartesian {
            if c.frame == 0 || c.frame > model.frames.len() {
                return Err(ExciteError::ImpossibleLimits(format!(
                    "Cartesian limit on frame {}: index {} is not a moving frame of {}",
                    c.frame_name, c.frame, model.name
                )));
            }
            for (axis, name) in ["x", "y", "z"].iter().enumerate() {
                let (lo, hi) = (c.min[axis], c.max[axis]);
                if !(lo <= hi) {
                    return Err(ExciteError::ImpossibleLimits(format!(
                        "frame {} {name}: range [{lo}, {hi}] is empty",
                        c.frame_name
                    )));
                }
                if lo == f64::NEG_INFINITY && hi == f64::INFINITY {
                    continue;
                }
                items.push(Item {
                    label: format!("frame {} {name}", c.frame_name),
                    quantity: Quantity::Position,
                    source: Source::Origin {
                        frame: c.frame,
                        axis,
                    },
                    lo,
                    hi,
                });
            }
        }
        let origins = items
            .iter()
            .any(|i| matches!(i.source, Source::Origin { .. }));
        Ok(Constraints { items, origins })
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Every item's value at one sample, into `v`; leaves `ws` at this sample's
    /// kinematics (for [`Constraints::add_gradient`]).
    pub fn sample(
        &self,
        model: &Model,
        ws: &mut Workspace,
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
        v: &mut [f64],
    ) {
        if self.origins {
            model.forward_kinematics(ws, q);
        }
        for (out, item) in v.iter_mut().zip(&self.items) {
            *out = match &item.source {
                Source::Linear { terms, offset } => {
                    let src = match item.quantity {
                        Quantity::Position => q,
                        Quantity::Velocity => dq,
                        Quantity::Acceleration => ddq,
                    };
                    offset + terms.iter().map(|&(j, c)| c * src[j]).sum::<f64>()
                }
                Source::Origin { frame, axis } => ws.pose(*frame).translation[*axis],
            };
        }
    }

    /// Adds `weight · ∂v_item/∂(q, q̇, q̈)` of one sample to its gradient slices; `ws`
    /// must hold that sample's kinematics ([`Constraints::sample`]).
    pub(super) fn add_gradient(
        &self,
        model: &Model,
        ws: &Workspace,
        item: usize,
        weight: f64,
        gradient: SampleGradient<'_>,
    ) {
        let SampleGradient {
            q: gq,
            dq: gdq,
            ddq: gddq,
        } = gradient;
        let it = &self.items[item];
        match &it.source {
            Source::Linear { terms, .. } => {
                let dst = match it.quantity {
                    Quantity::Position => gq,
                    Quantity::Velocity => gdq,
                    Quantity::Acceleration => gddq,
                };
                for &(j, c) in terms {
                    dst[j] += weight * c;
                }
            }
            Source::Origin { frame, axis } => {
                let jac = model.frame_jacobian(ws, *frame);
                for (j, g) in gq.iter_mut().enumerate() {
                    *g += weight * jac[(*axis, j)];
                }
            }
        }
    }

    /// The augmented-Lagrangian term of the limits on `grid` (bounds shrunk by
    /// `margin`): `Σ (max(0, λ + μ c)² − λ²) / (2μ)` over the normalized constraint
    /// values `c ≤ 0`; with `λ = 0` it is the quadratic exterior penalty `μ/2 Σ max(0,
    /// c)²`. The gradient with respect to `x` is added to `gx` when given.
    pub fn lagrangian(
        &self,
        model: &Model,
        ws: &mut Workspace,
        x: &[f64],
        on: Enforced<'_>,
        multipliers: Multipliers<'_>,
        gx: Option<&mut [f64]>,
    ) -> f64 {
        let Enforced { grid, margin } = on;
        let Multipliers { lambda, mu } = multipliers;
        let n = model.dof();
        let m = self.len();
        if m == 0 {
            return 0.0;
        }
        let (q, dq, ddq) = grid.eval(x, n);
        let want = gx.is_some();
        let (mut gq, mut gdq, mut gddq) = if want {
            (vec![0.0; q.len()], vec![0.0; q.len()], vec![0.0; q.len()])
        } else {
            (Vec::new(), Vec::new(), Vec::new())
        };
        let mut v = vec![0.0; m];
        let mut total = 0.0;
        for k in 0..grid.len() {
            let s = k * n..(k + 1) * n;
            self.sample(
                model,
                ws,
                &q[s.clone()],
                &dq[s.clone()],
                &ddq[s.clone()],
                &mut v,
            );
            for (i, item) in self.items.iter().enumerate() {
                let (lo, hi) = item.shrunk(margin);
                let sc = item.scale();
                let idx = 2 * (k * m + i);
                let mut dv = 0.0;
                for (side, c) in [(0, (lo - v[i]) / sc), (1, (v[i] - hi) / sc)] {
                    if !c.is_finite() {
                        continue;
                    }
                    let l = lambda.get(idx + side).copied().unwrap_or(0.0);
                    let t = (l + mu * c).max(0.0);
                    if t == 0.0 && l == 0.0 {
                        continue;
                    }
                    total += (t * t - l * l) / (2.0 * mu);
                    dv += if side == 0 { -t / sc } else { t / sc };
                }
                if want && dv != 0.0 {
                    let (a, b, c) = (
                        &mut gq[s.clone()],
                        &mut gdq[s.clone()],
                        &mut gddq[s.clone()],
                    );
                    let gradient = SampleGradient {
                        q: a,
                        dq: b,
                        ddq: c,
                    };
                    self.add_gradient(model, ws, i, dv, gradient);
                }
            }
        }
        if let Some(gx) = gx {
            grid.backprop(n, &gq, &gdq, &gddq, gx);
        }
        total
    }

    /// Updates the multipliers after an inner minimization, `λ ← max(0, λ + μ c)`, and
    /// returns the largest normalized violation `max(0, c)`.
    pub fn update_multipliers(
        &self,
        model: &Model,
        ws: &mut Workspace,
        x: &[f64],
        on: Enforced<'_>,
        lambda: &mut [f64],
        mu: f64,
    ) -> f64 {
        let Enforced { grid, margin } = on;
        let mut worst = 0.0f64;
        self.for_each_value(model, ws, x, grid, |k, i, v| {
            let item = &self.items[i];
            let (lo, hi) = item.shrunk(margin);
            let sc = item.scale();
            let idx = 2 * (k * self.len() + i);
            for (side, c) in [(0, (lo - v) / sc), (1, (v - hi) / sc)] {
                if c.is_finite() {
                    lambda[idx + side] = (lambda[idx + side] + mu * c).max(0.0);
                    worst = worst.max(c);
                }
            }
        });
        worst
    }

    /// Number of multipliers on a grid of `samples` instants.
    pub fn multipliers(&self, samples: usize) -> usize {
        2 * samples * self.len()
    }

    /// Calls `f(sample, item, value)` for every item at every sample of `grid`.
    pub(super) fn for_each_value(
        &self,
        model: &Model,
        ws: &mut Workspace,
        x: &[f64],
        grid: &Grid,
        mut f: impl FnMut(usize, usize, f64),
    ) {
        let n = model.dof();
        let m = self.len();
        if m == 0 {
            return;
        }
        let (q, dq, ddq) = grid.eval(x, n);
        let mut v = vec![0.0; m];
        for k in 0..grid.len() {
            let s = k * n..(k + 1) * n;
            self.sample(model, ws, &q[s.clone()], &dq[s.clone()], &ddq[s], &mut v);
            for (i, &vi) in v.iter().enumerate() {
                f(k, i, vi);
            }
        }
    }
}
