//! The repair and the check of a trajectory against [`Constraints`]: static poses
//! inside the limits, the largest feasible step along a segment (exact for the joint
//! limits, by bisection for the Cartesian boxes), the bounds tightened between samples,
//! and the dense feasibility check (see [`super`]).

// `!(x > 0.0)`-style tests are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

use super::constraints::*;
use crate::excite::grid::Grid;
use crate::excite::ExciteError;
use dvrk_model::{Model, Workspace};

impl Constraints {
    /// The largest excess of the position items' bounds shrunk by `margin` at a static
    /// pose `q` (≤ 0: inside), in units of each range, with the worst item.
    fn static_excess(
        &self,
        model: &Model,
        ws: &mut Workspace,
        q: &[f64],
        margin: f64,
    ) -> (f64, usize) {
        let zeros = vec![0.0; q.len()];
        let mut v = vec![0.0; self.len()];
        self.sample(model, ws, q, &zeros, &zeros, &mut v);
        let mut worst = (f64::NEG_INFINITY, 0);
        for (i, item) in self.items.iter().enumerate() {
            if item.quantity != Quantity::Position {
                continue;
            }
            let (lo, hi) = item.shrunk(margin);
            let e = ((v[i] - hi).max(lo - v[i])) / item.scale();
            if e > worst.0 {
                worst = (e, i);
            }
        }
        worst
    }

    /// Whether every item holds on `grid` (bounds shrunk by `margin`, then by
    /// `slack[i]` when given).
    fn holds(
        &self,
        model: &Model,
        ws: &mut Workspace,
        x: &[f64],
        grid: &Grid,
        margin: f64,
        slack: &[f64],
    ) -> bool {
        let mut ok = true;
        self.for_each_value(model, ws, x, grid, |_, i, v| {
            let (lo, hi) = self.items[i].within(margin, slack.get(i).copied().unwrap_or(0.0));
            ok &= lo <= v && v <= hi;
        });
        ok
    }

    /// Per item, how far the motion can exceed its bounds between two neighbouring
    /// instants of the uniform periodic `grid` while it holds them at the instants:
    /// `h²/8 · max|v̈|` (`h` the spacing; the bound of a maximum between samples). `h² v̈`
    /// is estimated by the second differences of the sampled values, and doubled: for a
    /// series of `L` harmonics the sampled maximum of `v̈` is within a relative
    /// `(L ω h)²/8` of the true one (Bernstein's inequality; ~2e-6 for the MTM at 1 kHz),
    /// and a frame origin's motion is nearly band-limited too. Pulling back onto the
    /// dense grid by this slack makes the limits hold between its samples, not only at
    /// them.
    pub fn between_samples(
        &self,
        model: &Model,
        ws: &mut Workspace,
        x: &[f64],
        grid: &Grid,
    ) -> Vec<f64> {
        let (m, t) = (self.len(), grid.len());
        let mut values = vec![0.0; m * t];
        self.for_each_value(model, ws, x, grid, |k, i, v| values[k * m + i] = v);
        (0..m)
            .map(|i| {
                let v = |k: usize| values[(k % t) * m + i];
                let curvature = (0..t)
                    .map(|k| (v(k + 1) - 2.0 * v(k) + v(k + t - 1)).abs())
                    .fold(0.0, f64::max);
                2.0 * curvature / 8.0
            })
            .collect()
    }

    /// The largest `s ≥ 0` such that `x0 + s (x1 − x0)` satisfies every item on `grid`
    /// (bounds shrunk by `margin`, then by `slack[i]` when given), assuming `x0` does; `inf` when unbounded. Exact for
    /// the joint limits (linear in `s`); with Cartesian boxes, the segment is bisected
    /// against the grid, which finds a feasible point (not always the farthest: a box
    /// may be left and re-entered along the segment).
    pub fn feasible_step(
        &self,
        model: &Model,
        ws: &mut Workspace,
        x0: &[f64],
        x1: &[f64],
        on: Enforced<'_>,
        slack: &[f64],
    ) -> f64 {
        let Enforced { grid, margin } = on;
        let n = model.dof();
        let (q0, dq0, ddq0) = grid.eval(x0, n);
        let (q1, dq1, ddq1) = grid.eval(x1, n);
        let mut s = f64::INFINITY;
        for (i, item) in self.items.iter().enumerate() {
            let Source::Linear { terms, offset } = &item.source else {
                continue;
            };
            let (a, b) = match item.quantity {
                Quantity::Position => (&q0, &q1),
                Quantity::Velocity => (&dq0, &dq1),
                Quantity::Acceleration => (&ddq0, &ddq1),
            };
            let (lo, hi) = item.within(margin, slack.get(i).copied().unwrap_or(0.0));
            for k in 0..grid.len() {
                let at = |src: &[f64]| {
                    offset + terms.iter().map(|&(j, c)| c * src[k * n + j]).sum::<f64>()
                };
                let (v0, v1) = (at(a), at(b));
                let d = v1 - v0;
                if d > 0.0 {
                    s = s.min(((hi - v0) / d).max(0.0));
                } else if d < 0.0 {
                    s = s.min(((lo - v0) / d).max(0.0));
                }
            }
        }
        if !self.origins {
            return s;
        }
        let mut point = vec![0.0; x0.len()];
        let mut holds_at = |s: f64, ws: &mut Workspace| {
            for (p, (a, b)) in point.iter_mut().zip(x0.iter().zip(x1)) {
                *p = a + s * (b - a);
            }
            self.holds(model, ws, &point, grid, margin, slack)
        };
        // Bracket [lo feasible, hi infeasible], then bisect.
        let (mut lo, mut hi) = if s.is_finite() {
            if holds_at(s, ws) {
                return s;
            }
            (0.0, s)
        } else {
            let mut t = 1.0;
            loop {
                if !holds_at(t, ws) {
                    break (t / 2.0, t);
                }
                if t >= 1024.0 {
                    return f64::INFINITY;
                }
                t *= 2.0;
            }
        };
        if lo > 0.0 && !holds_at(lo, ws) {
            lo = 0.0;
        }
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if holds_at(mid, ws) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The dense check: every item at every sample of `grid` (no margin).
    pub fn check(
        &self,
        model: &Model,
        ws: &mut Workspace,
        x: &[f64],
        grid: &Grid,
        rate_hz: f64,
    ) -> Feasibility {
        let mut per_item: Vec<Option<Violation>> = vec![None; self.len()];
        self.for_each_value(model, ws, x, grid, |k, i, v| {
            let item = &self.items[i];
            let (excess, bound) = if v - item.hi >= item.lo - v {
                (v - item.hi, item.hi)
            } else {
                (item.lo - v, item.lo)
            };
            let slot = &mut per_item[i];
            if slot.as_ref().is_none_or(|w| excess > w.excess) {
                *slot = Some(Violation {
                    limit: item.label.clone(),
                    quantity: item.quantity.name().into(),
                    time_s: grid.times[k],
                    value: v,
                    bound,
                    excess,
                });
            }
        });
        let mut all: Vec<Violation> = per_item.into_iter().flatten().collect();
        all.sort_by(|a, b| b.excess.total_cmp(&a.excess));
        let worst = all.first().cloned();
        Feasibility {
            feasible: worst.as_ref().is_none_or(|w| w.excess <= TOLERANCE),
            samples: grid.len(),
            rate_hz: rate_hz.max(1000.0),
            worst,
            violated: all.into_iter().filter(|v| v.excess > TOLERANCE).collect(),
        }
    }

    /// A static pose inside every position item (bounds shrunk by `margin` of each
    /// range); rate limits must allow 0, since a periodic motion's mean velocity and
    /// acceleration are 0. Joint limits alone: cyclic projections onto their slabs.
    /// With Cartesian boxes, that pose is then moved by L-BFGS on the squared excesses
    /// (through the frame Jacobians), from it and from deterministic random poses; no
    /// pose found is an error naming the closest miss.
    pub fn static_pose(&self, model: &Model, margin: f64) -> Result<Vec<f64>, ExciteError> {
        let n = model.dof();
        for r in &self.items {
            if r.quantity != Quantity::Position && !(r.lo <= 0.0 && 0.0 <= r.hi) {
                return Err(ExciteError::ImpossibleLimits(format!(
                    "limit {}: the {} range [{}, {}] excludes 0, but a periodic motion's mean {} is 0",
                    r.label,
                    r.quantity.name(),
                    r.lo,
                    r.hi,
                    r.quantity.name()
                )));
            }
        }
        let q = self.linear_static_pose(n, margin)?;
        if !self.origins {
            return Ok(q);
        }
        let mut ws = Workspace::new(model);
        if self.static_excess(model, &mut ws, &q, margin).0 <= 0.0 {
            return Ok(q);
        }
        // Aim a little inside the margin so that a converged pose is strictly inside.
        let aim = margin + 0.01;
        let mut rng = super::super::rng::Rng(0x5eed);
        let mut best = (f64::INFINITY, q.clone(), 0usize);
        for attempt in 0..24 {
            let mut p = q.clone();
            if attempt > 0 {
                p.iter_mut().for_each(|v| *v += rng.normal());
            }
            let mut f = |p: &[f64], g: &mut [f64]| -> f64 {
                self.static_penalty(model, &mut ws, p, aim, g)
            };
            super::super::lbfgs::lbfgs(&mut f, &mut p, 300);
            let (e, i) = self.static_excess(model, &mut ws, &p, margin);
            if e <= 0.0 {
                return Ok(p);
            }
            if e < best.0 {
                best = (e, p, i);
            }
        }
        let item = &self.items[best.2];
        let mut v = vec![0.0; self.len()];
        let zeros = vec![0.0; n];
        self.sample(model, &mut ws, &best.1, &zeros, &zeros, &mut v);
        Err(ExciteError::ImpossibleLimits(format!(
            "no static pose satisfies the position limits and Cartesian boxes at once; the \
             closest pose found has {} = {:.6} outside [{}, {}]",
            item.label, v[best.2], item.lo, item.hi
        )))
    }

    /// `Σ max(0, c)²` of the position items at a static pose `q` (bounds shrunk by
    /// `margin`), gradient into `g`.
    fn static_penalty(
        &self,
        model: &Model,
        ws: &mut Workspace,
        q: &[f64],
        margin: f64,
        g: &mut [f64],
    ) -> f64 {
        let n = q.len();
        let zeros = vec![0.0; n];
        let mut v = vec![0.0; self.len()];
        self.sample(model, ws, q, &zeros, &zeros, &mut v);
        g.fill(0.0);
        let (mut gdq, mut gddq) = (vec![0.0; n], vec![0.0; n]);
        let mut total = 0.0;
        for (i, item) in self.items.iter().enumerate() {
            if item.quantity != Quantity::Position {
                continue;
            }
            let (lo, hi) = item.shrunk(margin);
            let sc = item.scale();
            let e = if v[i] > hi {
                (v[i] - hi) / sc
            } else if v[i] < lo {
                (v[i] - lo) / sc
            } else {
                continue;
            };
            total += e * e;
            let gradient = SampleGradient {
                q: g,
                dq: &mut gdq,
                ddq: &mut gddq,
            };
            self.add_gradient(model, ws, i, 2.0 * e / sc, gradient);
        }
        total
    }

    /// The joint position limits' static pose: cyclic projections onto the slabs, with a
    /// large margin first so that the pose is central when the limits allow it.
    fn linear_static_pose(&self, n: usize, margin: f64) -> Result<Vec<f64>, ExciteError> {
        let pos: Vec<LinearItem> = self
            .items
            .iter()
            .filter(|r| r.quantity == Quantity::Position)
            .filter_map(|r| match &r.source {
                Source::Linear { terms, offset } => Some((r, terms, *offset)),
                Source::Origin { .. } => None,
            })
            .collect();
        let worst = |q: &[f64], margin: f64| {
            pos.iter()
                .map(|(r, terms, offset)| {
                    let (lo, hi) = r.shrunk(margin);
                    let v = offset + terms.iter().map(|&(k, c)| c * q[k]).sum::<f64>();
                    (v - hi).max(lo - v)
                })
                .fold(f64::NEG_INFINITY, f64::max)
        };
        for m in [0.2f64, 0.05, 0.0] {
            let m = m.max(margin);
            let mut q = vec![0.0; n];
            for _sweep in 0..20_000 {
                for (r, terms, offset) in &pos {
                    let (lo, hi) = r.shrunk(m);
                    let v = offset + terms.iter().map(|&(k, c)| c * q[k]).sum::<f64>();
                    let target = v.clamp(lo, hi);
                    let nn: f64 = terms.iter().map(|&(_, c)| c * c).sum();
                    if target != v && nn > 0.0 {
                        for &(k, c) in terms.iter() {
                            q[k] += c * (target - v) / nn;
                        }
                    }
                }
                if pos.is_empty() || worst(&q, m) <= 1e-12 {
                    break;
                }
            }
            if pos.is_empty() || worst(&q, margin) <= 0.0 {
                return Ok(q);
            }
        }
        let bad: Vec<String> = pos
            .iter()
            .filter(|(r, terms, offset)| terms.is_empty() && !(r.lo <= *offset && *offset <= r.hi))
            .map(|(r, _, _)| r.label.clone())
            .collect();
        Err(ExciteError::ImpossibleLimits(if bad.is_empty() {
            "no pose satisfies all position limits at once".to_string()
        } else {
            format!("constant limits out of range: {}", bad.join(", "))
        }))
    }
}
