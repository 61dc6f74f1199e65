//! Inverse dynamics (recursive Newton–Euler on the open tree, mapped through Aᵀ),
//! gravity, nonlinear effects, mass matrix (composite rigid bodies) and forward
//! dynamics (Cholesky of the mass matrix in the workspace).
//!
//! By virtual work the coupled system's generalized forces are `τ = Aᵀ f_tree(s, ṡ, s̈)`
//! plus the elements (friction, springs, motor inertias): exact for closed chains, with
//! no symbolic algebra. The same holds for the mass matrix, `M = Aᵀ·M_tree·A` plus the
//! motor inertias. All of them run over the tree's bodies (moving frames, fixed links
//! merged, see `model::Body`) and allocate nothing.

use nalgebra::{DMatrix, DVector, Vector3};
use wide::f64x2;

use crate::element::{sign0, Sample};
use crate::inertia::{sym3, transform_barycentric};
use crate::model::{Axis, Body, Model};
use crate::spatial::Transform;
use crate::workspace::{BodyBuffers, Workspace};

/// The mass matrix is not positive definite at this configuration (the parameters are
/// not those of physical bodies), so forward dynamics has no solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the mass matrix is not positive definite (the parameters are not physical)")]
pub struct NotPositiveDefinite;

/// Which element terms an internal dynamics pass includes.
#[derive(Clone, Copy)]
pub(crate) struct Terms {
    /// Acceleration terms of the elements (motor inertias); forward dynamics has them
    /// in the mass matrix instead.
    pub inertial: bool,
}

pub(crate) const ALL: Terms = Terms { inertial: true };

/// Which motion a body pass includes; `false` stands for zero rates or accelerations.
#[derive(Clone, Copy)]
pub(crate) struct Motion {
    pub velocity: bool,
    pub acceleration: bool,
}

impl Motion {
    /// Rates and accelerations: the inverse dynamics.
    pub(crate) const FULL: Motion = Motion {
        velocity: true,
        acceleration: true,
    };
    /// Rates at zero acceleration: the nonlinear effects.
    pub(crate) const COASTING: Motion = Motion {
        velocity: true,
        acceleration: false,
    };
    /// At rest: gravity alone.
    pub(crate) const STILL: Motion = Motion {
        velocity: false,
        acceleration: false,
    };
}

impl Model {
    /// The bodies' inertias for `params` (fixed links merged), recomputed only when the
    /// parameters differ from the last call's.
    #[inline]
    fn body_inertias(&self, ws: &mut Workspace, params: &[f64]) {
        if !same_bits(&ws.body.inertia_of, params) {
            self.merge_inertias(ws, params);
        }
    }

    /// [`Model::body_inertias`]' computation, out of line: it runs when the parameters
    /// change, not per sample.
    #[cold]
    #[inline(never)]
    fn merge_inertias(&self, ws: &mut Workspace, params: &[f64]) {
        let b = &mut ws.body;
        b.inertia_of.clear();
        b.inertia_of.extend_from_slice(params);
        for (k, body) in self.bodies.iter().enumerate() {
            let mut sum = [0.0; 10];
            for (offset, pose) in &body.links {
                let p: &[f64; 10] = params[*offset..offset + 10].try_into().expect("10");
                let moved = match pose {
                    None => *p,
                    Some(x) => transform_barycentric(&x.rotation, &x.translation, p),
                };
                for (s, m) in sum.iter_mut().zip(moved) {
                    *s += m;
                }
            }
            b.inertia[k + 1] = sum;
        }
    }

    /// What every body pass starts from: the bodies' inertias for `params` and their
    /// transforms at `q`.
    #[inline(always)]
    fn bodies_at(&self, ws: &mut Workspace, params: &[f64], q: &[f64]) {
        self.body_inertias(ws, params);
        self.body_positions(ws, q);
    }

    /// Parent body → body transforms at `q`, into `ws.body.x`.
    #[inline]
    pub(crate) fn body_positions(&self, ws: &mut Workspace, q: &[f64]) {
        for (k, body) in self.bodies.iter().enumerate() {
            let value = &self.frames[body.frame - 1].value;
            let s = value.offset + body.rate(value, q);
            ws.body.x[k + 1] = self.joint_transform(body.frame, &body.pre, s);
        }
    }

    /// Angular velocity ω (rad/s), origin velocity v (m/s), ω̇ (rad/s²) and linear
    /// acceleration a (m/s², gravity included) of body `i` in its coordinates, from its
    /// parent's in `b` and `b.x[i]`: the forward pass of Newton–Euler, shared by the
    /// dynamics and the regressor. Zero rates or accelerations (`motion`) are skipped
    /// rather than multiplied.
    #[inline(always)]
    pub(crate) fn body_velocity(
        &self,
        b: &BodyBuffers,
        body: &Body,
        i: usize,
        dq: &[f64],
        ddq: &[f64],
        motion: Motion,
    ) -> [Vector3<f64>; 4] {
        let zero = Vector3::zeros();
        let p = body.parent;
        let value = &self.frames[body.frame - 1].value;
        let x = &b.x[i];
        let rt = x.rotation.transpose();
        let (sw, sv) = &self.motion[body.frame];
        let sdd = if motion.acceleration {
            body.rate(value, ddq)
        } else {
            0.0
        };
        let revolute_z = matches!(body.axis, Axis::RevoluteZ);
        if motion.velocity && revolute_z {
            // S = (z, 0): the general branch's products with S written out.
            let sd = body.rate(value, dq);
            let mut w = rt * b.w[p];
            w.z += sd;
            let v = rt * (b.v[p] + b.w[p].cross(&x.translation));
            let mut dw = rt * b.dw[p];
            dw.x += w.y * sd;
            dw.y -= w.x * sd;
            dw.z += sdd;
            let mut a = rt * (b.a[p] + b.dw[p].cross(&x.translation));
            a.x += v.y * sd;
            a.y -= v.x * sd;
            [w, v, dw, a]
        } else if motion.velocity {
            let sd = body.rate(value, dq);
            let (wsd, vsd) = (sw * sd, sv * sd);
            let w = rt * b.w[p] + wsd;
            let v = rt * (b.v[p] + b.w[p].cross(&x.translation)) + vsd;
            let dw = rt * b.dw[p] + sw * sdd + w.cross(&wsd);
            let a = rt * (b.a[p] + b.dw[p].cross(&x.translation))
                + sv * sdd
                + w.cross(&vsd)
                + v.cross(&wsd);
            [w, v, dw, a]
        } else if motion.acceleration {
            let dw = rt * b.dw[p] + sw * sdd;
            let a = rt * (b.a[p] + b.dw[p].cross(&x.translation)) + sv * sdd;
            [zero, zero, dw, a]
        } else {
            [zero, zero, zero, rt * b.a[p]]
        }
    }

    /// Newton–Euler over the bodies from `ws.body.x`: the links' generalized forces
    /// (N·m or N) into `tau` (overwritten). Zero rates or accelerations (`motion`) are
    /// skipped rather than multiplied.
    #[inline(always)]
    fn body_rnea(
        &self,
        ws: &mut Workspace,
        dq: &[f64],
        ddq: &[f64],
        motion: Motion,
        gravity: bool,
        tau: &mut [f64],
    ) {
        let b = &mut ws.body;
        let zero = Vector3::zeros();
        b.w[0] = zero;
        b.v[0] = zero;
        b.dw[0] = zero;
        b.a[0] = if gravity { -self.gravity } else { zero };
        for (k, body) in self.bodies.iter().enumerate() {
            let i = k + 1;
            let [w, v, dw, a] = self.body_velocity(b, body, i, dq, ddq, motion);
            let pp = &b.inertia[i];
            let l = Vector3::new(pp[6], pp[7], pp[8]);
            let m = pp[9];
            let (n, f) = if motion.velocity {
                let l_in = sym3(&pp[0..6]);
                let ac = a + w.cross(&v);
                (
                    l_in * dw + w.cross(&(l_in * w)) + l.cross(&ac),
                    ac * m + dw.cross(&l) + w.cross(&w.cross(&l)),
                )
            } else if motion.acceleration {
                (sym3(&pp[0..6]) * dw + l.cross(&a), a * m + dw.cross(&l))
            } else {
                (l.cross(&a), a * m)
            };
            b.w[i] = w;
            b.v[i] = v;
            b.dw[i] = dw;
            b.a[i] = a;
            b.n[i] = n;
            b.f[i] = f;
        }
        tau.fill(0.0);
        for (k, body) in self.bodies.iter().enumerate().rev() {
            let i = k + 1;
            let (sw, sv) = &self.motion[body.frame];
            let t = sw.dot(&b.n[i]) + sv.dot(&b.f[i]);
            for &(c, a) in &self.frames[body.frame - 1].value.terms {
                tau[c] += a * t;
            }
            let p = body.parent;
            if p != 0 {
                let x = &b.x[i];
                let rf = x.rotation * b.f[i];
                let rn = x.rotation * b.n[i] + x.translation.cross(&rf);
                b.f[p] += rf;
                b.n[p] += rn;
            }
        }
    }

    pub(crate) fn check_state(&self, ws: &Workspace, params: &[f64], vectors: &[&[f64]]) {
        ws.check(self);
        let n = self.dof();
        assert!(
            vectors.iter().all(|v| v.len() == n),
            "q, dq, ddq and tau must have length {n}"
        );
        assert_eq!(params.len(), self.n_params(), "parameter vector length");
    }

    /// The elements' torques (friction, springs, motor inertias...), added into `tau`.
    /// `hysteresis`, `load`: the workspace's Dahl states and coordinate loads (the
    /// workspace itself is borrowed mutably by the callers' other buffers).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn add_elements(
        &self,
        hysteresis: &[f64],
        load: &[f64],
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
        terms: Terms,
        tau: &mut [f64],
    ) {
        let plan = if terms.inertial {
            &self.element_plan.all
        } else {
            &self.element_plan.forces
        };
        for (value, e) in plan {
            let s = Sample {
                value,
                q,
                dq,
                ddq,
                hysteresis,
                load,
            };
            e.add_torque(&s, params, tau);
        }
    }

    /// Inverse dynamics `τ = H(q, q̇, q̈)·π` (N·m or N per coordinate): links, friction,
    /// springs and motor inertias; known forces (e.g. a cable) are not included, add them
    /// with [`Model::add_known_forces`] to predict a measured torque. Allocates nothing.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let model = Model::builtin("psm").unwrap();
    /// let mut ws = Workspace::new(&model);
    /// let params = vec![0.01; model.n_params()];
    /// let mut tau = [0.0; 7];
    /// model.inverse_dynamics(&mut ws, &params, &[0.1; 7], &[0.2; 7], &[0.3; 7], &mut tau);
    /// assert!(tau.iter().all(|t| t.is_finite()));
    /// ```
    pub fn inverse_dynamics(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
        tau: &mut [f64],
    ) {
        self.check_state(ws, params, &[q, dq, ddq, tau]);
        self.bodies_at(ws, params, q);
        self.body_rnea(ws, dq, ddq, Motion::FULL, true, tau);
        self.add_elements(&ws.hysteresis, &ws.load, params, q, dq, ddq, ALL, tau);
    }

    /// Gravity torque `g(q)` of the links alone (N·m or N), as Pinocchio's
    /// `computeGeneralizedGravity`: no friction, spring or known force. Allocates nothing.
    pub fn gravity_torque(&self, ws: &mut Workspace, params: &[f64], q: &[f64], tau: &mut [f64]) {
        self.check_state(ws, params, &[q, tau]);
        self.bodies_at(ws, params, q);
        self.body_rnea(ws, q, q, Motion::STILL, true, tau);
    }

    /// A bound (N·m or N) on every component of [`Model::gravity_torque`] at any
    /// position with `|q_k| ≤ q_max` (rad or m), for `params`: `+∞` if it overflows.
    ///
    /// Why: a real-time caller that must never receive a non-finite torque (the C ABI)
    /// either checks every output — about 7 ns per 7-joint call, a few percent of the
    /// call — or knows in advance that the computation cannot overflow. Below this bound
    /// it cannot: the backward pass of [`Model::gravity_torque`] only adds
    /// forces `m·a` (`|a| = |g|`, rotations keep lengths), moments `l × a` and their
    /// transports `t × f` along translations `t` whose lengths add up to at most `reach`
    /// (the fixed offsets, the merged links' poses and the prismatic joints' strokes at
    /// `q_max`), and each coordinate takes its joints' share `Σ|coefficient|·(|ω|+|v|)`
    /// of the motion axes. A factor 2 covers the rounding of these sums. No division or
    /// square root enters, and sine and cosine are finite for every finite angle.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let psm = Model::builtin("psm").unwrap();
    /// let params = vec![0.1; psm.n_params()];
    /// let bound = psm.gravity_torque_bound(&params, 1.0);
    /// let (mut ws, mut tau) = (Workspace::new(&psm), [0.0; 7]);
    /// psm.gravity_torque(&mut ws, &params, &[0.3, -0.2, 0.15, 1.0, -1.0, 0.5, 0.2], &mut tau);
    /// assert!(tau.iter().all(|t| t.abs() <= bound));
    /// ```
    pub fn gravity_torque_bound(&self, params: &[f64], q_max: f64) -> f64 {
        let m = self.magnitudes(params, q_max);
        finite_or_infinite(
            2.0 * m.share * self.gravity.norm() * (m.moment + (m.reach + 1.0) * m.mass),
        )
    }

    /// A bound (kg·m² or kg) on every entry of [`Model::mass_matrix_into`] at any
    /// position with `|q_k| ≤ q_max` (rad or m), for `params`: `+∞` if it overflows.
    ///
    /// Why: as [`Model::gravity_torque_bound`], for the mass matrix's n² outputs. Each
    /// composite inertia is the links' inertias moved along translations of total length
    /// at most `reach`: its rotational part grows by at most `4·|t|·|l| + 3·m·|t|²`, its
    /// first moment by `m·|t|`, so every composite has norm at most `4·A·(1 + reach)²`,
    /// `A` the sum over links of `‖I‖ + |l| + |m|`; its force for a unit joint rate is at
    /// most `7·A·(1 + reach)²`, and carried down to a joint below at most `(1 + reach)`
    /// times that. A factor 16 ≥ 7 covers it and the rounding. The elements' part (motor
    /// inertias) does not depend on `q` and is added as it is.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let psm = Model::builtin("psm").unwrap();
    /// let params = vec![0.1; psm.n_params()];
    /// let bound = psm.mass_matrix_bound(&params, 1.0);
    /// let (mut ws, mut m) = (Workspace::new(&psm), [0.0; 49]);
    /// psm.mass_matrix_into(&mut ws, &params, &[0.3, -0.2, 0.15, 1.0, -1.0, 0.5, 0.2], &mut m);
    /// assert!(m.iter().all(|x| x.abs() <= bound));
    /// ```
    pub fn mass_matrix_bound(&self, params: &[f64], q_max: f64) -> f64 {
        let m = self.magnitudes(params, q_max);
        let n = self.dof();
        let mut elements = vec![0.0; n * n];
        for e in &self.element_plan.inertial {
            e.add_mass(params, n, &mut elements);
        }
        let elements: f64 = elements.iter().map(|x| x.abs()).sum();
        let reach = 1.0 + m.reach;
        finite_or_infinite(16.0 * m.share * m.share * m.all * reach * reach * reach + elements)
    }

    /// What the bounds of [`Model::gravity_torque_bound`] and
    /// [`Model::mass_matrix_bound`] are made of.
    fn magnitudes(&self, params: &[f64], q_max: f64) -> Magnitudes {
        assert_eq!(params.len(), self.n_params(), "parameter vector length");
        let mut out = Magnitudes::default();
        for body in &self.bodies {
            let frame = &self.frames[body.frame - 1];
            let coefficients: f64 = frame.value.terms.iter().map(|(_, a)| a.abs()).sum();
            out.reach += body.pre.translation.norm() + frame.post.translation.norm();
            if frame.kind == crate::model::JointKind::Prismatic {
                out.reach += frame.value.offset.abs() + coefficients * q_max;
            }
            for (offset, pose) in &body.links {
                let p = &params[*offset..offset + 10];
                let mass = p[9].abs();
                let t = pose.as_ref().map_or(0.0, |x| x.translation.norm());
                let l = Vector3::new(p[6], p[7], p[8]).norm();
                // ‖I‖_F ≤ the sum of its entries' magnitudes, each of the six at most twice.
                let rotational = 2.0 * p[..6].iter().map(|x| x.abs()).sum::<f64>();
                out.mass += mass;
                out.moment += l + mass * t;
                out.all += rotational + l + mass;
                out.reach += t;
            }
            let (w, v) = &self.motion[body.frame];
            out.share += coefficients * (w.norm() + v.norm());
        }
        out
    }

    /// Static torque (N·m or N): what holds the robot still at `q` against gravity,
    /// springs and known forces (e.g. the MTM cable), plus the friction that opposes the
    /// onset of a motion in direction `motion` (model coordinates; only the sign of each
    /// frame's joint rate `s·motion` counts): Coulomb and Stribeck terms at that sign,
    /// offset friction always, no viscous friction (zero speed). A gravity-compensation
    /// controller feeds this forward, the friction part for the direction it expects to
    /// move; `motion = 0` gives the torque at rest (offset friction, no Coulomb). A
    /// frame rate below 1e-12 of the motion's scale counts as zero (rounding).
    /// Allocates nothing.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let mtm = Model::builtin("mtm").unwrap();
    /// let mut ws = Workspace::new(&mtm);
    /// let params = vec![0.01; mtm.n_params()];
    /// let (mut up, mut down) = ([0.0; 7], [0.0; 7]);
    /// let mut e1 = [0.0; 7];
    /// e1[0] = 1.0;
    /// mtm.static_torque(&mut ws, &params, &[0.1; 7], &e1, &mut up);
    /// e1[0] = -1.0;
    /// mtm.static_torque(&mut ws, &params, &[0.1; 7], &e1, &mut down);
    /// // Joint 1 only: Coulomb friction Fc1 = 0.01 one way, then the other.
    /// assert!((up[0] - down[0] - 0.02).abs() < 1e-15);
    /// ```
    pub fn static_torque(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        motion: &[f64],
        tau: &mut [f64],
    ) {
        self.check_state(ws, params, &[q, motion, tau]);
        self.gravity_torque(ws, params, q, tau);
        // A frame whose rate is rounding (a direction from the inverse of a coupling,
        // e.g. the MTM's wrist platform under elbow-pitch motion) stands still.
        let scale = motion.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (value, e) in &self.element_plan.forces {
            let rate = value.dot(motion);
            let size: f64 = value.terms.iter().map(|(_, c)| c.abs()).sum();
            let onset = if rate.abs() <= 1e-12 * scale * size {
                0.0
            } else {
                sign0(rate)
            };
            e.add_static(value, q, onset, params, tau);
        }
        self.add_known_forces(q, tau);
    }

    /// Nonlinear effects `C(q, q̇)·q̇ + g(q)` of the links alone (N·m or N): the torque
    /// that holds the links at zero acceleration, as Pinocchio's `nonLinearEffects`; no
    /// friction, spring, motor inertia or known force. Allocates nothing.
    pub fn nonlinear_effects(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        tau: &mut [f64],
    ) {
        self.check_state(ws, params, &[q, dq, tau]);
        self.bodies_at(ws, params, q);
        self.body_rnea(ws, dq, dq, Motion::COASTING, true, tau);
    }

    /// Mass matrix `M(q)` (n×n, kg·m², kg), motor inertias included, into `out`
    /// (column-major n·n; it is symmetric). Composite rigid bodies in the base frame:
    /// each subtree's inertia `I_i`, then `M_tree[i, j] = S_jᵀ·I_i·S_i` for every body
    /// `j` on the path from `i` to the base, mapped to the coordinates through `A`.
    /// Allocates nothing.
    pub fn mass_matrix_into(&self, ws: &mut Workspace, params: &[f64], q: &[f64], out: &mut [f64]) {
        let n = self.dof();
        self.check_state(ws, params, &[q]);
        assert_eq!(out.len(), n * n, "mass matrix buffer must have n*n entries");
        self.bodies_at(ws, params, q);
        self.mass_from_positions(ws, params, out);
    }

    /// [`Model::mass_matrix_into`] from `ws.body.x` and `ws.body.inertia`: composite
    /// rigid bodies in body coordinates (Featherstone's CRBA). From the tip down, each
    /// body's composite inertia `I_i` gives the force of a unit rate of its joint,
    /// `F = I_i·S_i`, carried down to the base one body at a time (`M_tree[i, j] =
    /// S_jᵀ·F` at every body `j` on the way), then `I_i` is added to its parent's.
    /// (Composites in the base frame, one dot product per entry, cost more: every
    /// body's inertia moved to the base frame outweighs the transforms of `F` saved.)
    ///
    /// A body whose parent is the body before it (every link of a serial chain) is
    /// taken with its parent: once its force is in the parent's frame, both forces go
    /// down together, the two in the lanes of one vector, so that each transform on the
    /// way serves two columns; each lane computes what the single column would.
    fn mass_from_positions(&self, ws: &mut Workspace, params: &[f64], out: &mut [f64]) {
        let n = self.dof();
        let b = &mut ws.body;
        b.composite.copy_from_slice(&b.inertia);
        out.fill(0.0);
        let mut i = self.bodies.len();
        while i > 0 {
            let body = &self.bodies[i - 1];
            let force = body.axis.inertia_times(&b.composite[i]);
            self.mass_entry(out, body, body, body.axis.dot(&force), true);
            let p = body.parent;
            if p == 0 {
                i -= 1;
                continue;
            }
            self.composite_to_parent(b, body, i);
            let mut force = force_to_parent(&b.x[i], &force);
            let parent = &self.bodies[p - 1];
            self.mass_entry(out, body, parent, parent.axis.dot(&force), false);
            if p + 1 != i {
                // Alone down to the base.
                let (mut j, mut bj) = (p, parent);
                while bj.parent != 0 {
                    force = force_to_parent(&b.x[j], &force);
                    j = bj.parent;
                    bj = &self.bodies[j - 1];
                    self.mass_entry(out, body, bj, bj.axis.dot(&force), false);
                }
                i -= 1;
                continue;
            }
            // With the parent: its composite is complete (its other children come
            // after `i`, already done).
            let own = parent.axis.inertia_times(&b.composite[p]);
            self.mass_entry(out, parent, parent, parent.axis.dot(&own), true);
            let mut pair: [f64x2; 6] = std::array::from_fn(|r| f64x2::new([force[r], own[r]]));
            let (mut j, mut bj) = (p, parent);
            while bj.parent != 0 {
                pair = forces_to_parent(&b.x[j], &pair);
                j = bj.parent;
                bj = &self.bodies[j - 1];
                let [child, own] = axis_dot_lanes(&bj.axis, &pair);
                self.mass_entry(out, body, bj, child, false);
                self.mass_entry(out, parent, bj, own, false);
            }
            if parent.parent != 0 {
                self.composite_to_parent(b, parent, p);
            }
            i -= 2;
        }
        for e in &self.element_plan.inertial {
            e.add_mass(params, n, out);
        }
    }

    /// Adds `m = S_jᵀ·I_i·S_i` of bodies `bi` and `bj` (`bj` = `bi` or below it) to the
    /// mass matrix `out` (n×n column-major): at `(ci, cj)` and `(cj, ci)` (`diagonal`:
    /// once) for every term `a_i·q_ci` of body `i`'s joint value and `a_j·q_cj` of `j`'s.
    #[inline(always)]
    fn mass_entry(&self, out: &mut [f64], bi: &Body, bj: &Body, m: f64, diagonal: bool) {
        let n = self.dof();
        let mut add = |ci: usize, ai: f64, cj: usize, aj: f64| {
            let x = ai * aj * m;
            out[ci + cj * n] += x;
            if !diagonal {
                out[cj + ci * n] += x;
            }
        };
        if let (Some((ci, ai)), Some((cj, aj))) = (bi.coordinate, bj.coordinate) {
            // The loops below without their overhead.
            add(ci, ai, cj, aj);
        } else {
            for &(ci, ai) in &self.frames[bi.frame - 1].value.terms {
                for &(cj, aj) in &self.frames[bj.frame - 1].value.terms {
                    add(ci, ai, cj, aj);
                }
            }
        }
    }

    /// Adds body `i`'s composite inertia, moved to its parent's frame, to its parent's.
    #[inline(always)]
    fn composite_to_parent(&self, b: &mut BodyBuffers, body: &Body, i: usize) {
        let x = &b.x[i];
        let moved = transform_barycentric(&x.rotation, &x.translation, &b.composite[i]);
        for (s, m) in b.composite[body.parent].iter_mut().zip(moved) {
            *s += m;
        }
    }

    /// The pose of body `i` in the base frame, from its parent's and `b.x[i]`, and its
    /// joint's unit motion there (about the base origin), into `b.world[i]` and
    /// `b.axis[i]`.
    #[inline(always)]
    pub(crate) fn body_world(&self, b: &mut BodyBuffers, body: &Body, i: usize) {
        let world = b.world[body.parent].compose(&b.x[i]);
        let (w0, v0) = match body.axis {
            Axis::RevoluteZ => {
                let z: Vector3<f64> = world.rotation.column(2).into();
                (z, world.translation.cross(&z))
            }
            _ => {
                let (sw, sv) = &self.motion[body.frame];
                let w0 = world.rotation * sw;
                (w0, world.rotation * sv + world.translation.cross(&w0))
            }
        };
        b.axis[i] = [w0[0], w0[1], w0[2], v0[0], v0[1], v0[2]];
        b.world[i] = world;
    }

    /// Mass matrix `M(q)` as a matrix (allocates).
    pub fn mass_matrix(&self, ws: &mut Workspace, params: &[f64], q: &[f64]) -> DMatrix<f64> {
        let n = self.dof();
        let mut out = vec![0.0; n * n];
        self.mass_matrix_into(ws, params, q, &mut out);
        DMatrix::from_vec(n, n, out)
    }

    /// Forward dynamics into `ddq` (rad/s², m/s²): the accelerations under torques
    /// `tau` (N·m or N, as measured: known forces are subtracted first) with friction,
    /// springs, motor inertias and gravity, `M(q)·q̈ = τ − h(q, q̇) − τ_known(q)`,
    /// solved by a Cholesky factorization in the workspace. Allocates nothing; errors
    /// (leaving `ddq` unspecified) when the mass matrix is not positive definite.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// use dvrk_model::inertia::barycentric_from_standard;
    /// let model = Model::builtin("mtm").unwrap();
    /// let mut ws = Workspace::new(&model);
    /// // Every link 0.5 kg with some inertia, no friction, spring or motor inertia.
    /// let mut params = vec![0.0; model.n_params()];
    /// for &j in model.link_frames() {
    ///     let p0 = model.frame(j).inertia.unwrap();
    ///     let link = barycentric_from_standard(0.5, [0.01, 0.02, 0.03], [0.01, 0.0, 0.0, 0.02, 0.0, 0.015]);
    ///     params[p0..p0 + 10].copy_from_slice(&link);
    /// }
    /// let (q, dq, ddq) = ([0.1; 7], [0.2; 7], [0.3; 7]);
    /// // The torque of the inverse dynamics (plus the cable) gives back q̈.
    /// let mut tau = [0.0; 7];
    /// model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
    /// model.add_known_forces(&q, &mut tau);
    /// let mut acc = [0.0; 7];
    /// model.forward_dynamics_into(&mut ws, &params, &q, &dq, &tau, &mut acc).unwrap();
    /// assert!(acc.iter().zip(ddq).all(|(a, b)| (a - b).abs() < 1e-9));
    /// ```
    pub fn forward_dynamics_into(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        tau: &[f64],
        ddq: &mut [f64],
    ) -> Result<(), NotPositiveDefinite> {
        let n = self.dof();
        self.check_state(ws, params, &[q, dq, tau, ddq]);
        let mut m = std::mem::take(&mut ws.mass);
        // h(q, q̇) into ddq, then M·q̈ = τ − h.
        self.bias_and_mass(ws, params, q, dq, ddq, &mut m);
        for (a, t) in ddq.iter_mut().zip(tau) {
            *a = t - *a;
        }
        let solved = cholesky_solve(&mut m, n, ddq);
        ws.mass = m;
        solved
    }

    /// The two halves of the equation of motion `M(q)·q̈ + h(q, q̇) = τ` (τ as measured)
    /// from one kinematics pass: `h` (N·m or N: links' Coriolis, centrifugal and gravity
    /// torques, the elements' torques at zero acceleration — friction, springs — and the
    /// known forces) into `bias`, and `M(q)` (motor inertias included, n×n column-major)
    /// into `mass`. Shared by forward dynamics and the momentum observer. Allocates
    /// nothing; the lengths are the caller's to check.
    pub(crate) fn bias_and_mass(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        bias: &mut [f64],
        mass: &mut [f64],
    ) {
        self.bodies_at(ws, params, q);
        self.body_rnea(ws, dq, dq, Motion::COASTING, true, bias);
        let terms = Terms { inertial: false };
        self.add_elements(&ws.hysteresis, &ws.load, params, q, dq, dq, terms, bias);
        self.add_known_forces(q, bias);
        self.mass_from_positions(ws, params, mass);
    }

    /// [`Model::forward_dynamics_into`] returning a vector (allocates); `None` if the
    /// mass matrix is not positive definite.
    pub fn forward_dynamics(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        tau: &[f64],
    ) -> Option<DVector<f64>> {
        let mut ddq = DVector::zeros(self.dof());
        self.forward_dynamics_into(ws, params, q, dq, tau, ddq.as_mut_slice())
            .ok()?;
        Some(ddq)
    }
}

/// Solves `m·x = b` in place (`b` becomes `x`) for a symmetric positive definite `m`
/// (n×n column-major, lower triangle read, overwritten by its Cholesky factor).
fn cholesky_solve(m: &mut [f64], n: usize, b: &mut [f64]) -> Result<(), NotPositiveDefinite> {
    for j in 0..n {
        let mut d = m[j + j * n];
        for k in 0..j {
            d -= m[j + k * n] * m[j + k * n];
        }
        if !(d > 0.0 && d.is_finite()) {
            return Err(NotPositiveDefinite);
        }
        let d = d.sqrt();
        m[j + j * n] = d;
        for i in j + 1..n {
            let mut s = m[i + j * n];
            for k in 0..j {
                s -= m[i + k * n] * m[j + k * n];
            }
            m[i + j * n] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= m[i + k * n] * b[k];
        }
        b[i] = s / m[i + i * n];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= m[k + i * n] * b[k];
        }
        b[i] = s / m[i + i * n];
    }
    Ok(())
}

/// A spatial force `[n; f]` (moment about the origin, force) in the parent's
/// coordinates, `x` being the parent → child transform: `f' = R·f`, `n' = R·n + t × f'`.
#[inline(always)]
fn force_to_parent(x: &Transform, force: &[f64; 6]) -> [f64; 6] {
    let r = &x.rotation.data.0; // r[column][row]
    let t = &x.translation;
    let rot = |v: [f64; 3], row: usize| r[0][row] * v[0] + r[1][row] * v[1] + r[2][row] * v[2];
    let (n, f) = (
        [force[0], force[1], force[2]],
        [force[3], force[4], force[5]],
    );
    let f2 = [rot(f, 0), rot(f, 1), rot(f, 2)];
    [
        rot(n, 0) + t[1] * f2[2] - t[2] * f2[1],
        rot(n, 1) + t[2] * f2[0] - t[0] * f2[2],
        rot(n, 2) + t[0] * f2[1] - t[1] * f2[0],
        f2[0],
        f2[1],
        f2[2],
    ]
}

/// [`force_to_parent`] of two forces at once, one in each lane (`[n; f]` by
/// component), with the same operations per lane.
#[inline(always)]
fn forces_to_parent(x: &Transform, force: &[f64x2; 6]) -> [f64x2; 6] {
    let r = &x.rotation.data.0; // r[column][row]
    let t = &x.translation;
    let sp = f64x2::splat;
    let rot = |v: [f64x2; 3], row: usize| {
        sp(r[0][row]) * v[0] + sp(r[1][row]) * v[1] + sp(r[2][row]) * v[2]
    };
    let (n, f) = (
        [force[0], force[1], force[2]],
        [force[3], force[4], force[5]],
    );
    let f2 = [rot(f, 0), rot(f, 1), rot(f, 2)];
    let (t0, t1, t2) = (sp(t[0]), sp(t[1]), sp(t[2]));
    [
        rot(n, 0) + t1 * f2[2] - t2 * f2[1],
        rot(n, 1) + t2 * f2[0] - t0 * f2[2],
        rot(n, 2) + t0 * f2[1] - t1 * f2[0],
        f2[0],
        f2[1],
        f2[2],
    ]
}

/// [`Axis::dot`] of the two forces in the lanes of `force`, with the same operations.
#[inline(always)]
fn axis_dot_lanes(axis: &Axis, force: &[f64x2; 6]) -> [f64; 2] {
    match axis {
        Axis::RevoluteZ => force[2],
        Axis::PrismaticZ => force[5],
        Axis::General(w, v) => {
            let sp = f64x2::splat;
            sp(w[0]) * force[0]
                + sp(w[1]) * force[1]
                + sp(w[2]) * force[2]
                + sp(v[0]) * force[3]
                + sp(v[1]) * force[4]
                + sp(v[2]) * force[5]
        }
    }
    .to_array()
}

/// Whether `a` and `b` hold the same numbers bit for bit (a NaN or a `-0.0` counts as a
/// change): the check, on every call, that the cached body inertias are still those of
/// the parameters. No early exit and four lanes at a time, so that the compiler makes it
/// a few vector instructions per four parameters rather than a compare and branch each.
#[inline]
fn same_bits(a: &[f64], b: &[f64]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut acc = [0u64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .fold(0u64, |d, (x, y)| d | (x.to_bits() ^ y.to_bits()));
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] |= x[k].to_bits() ^ y[k].to_bits();
        }
    }
    (acc[0] | acc[1] | acc[2] | acc[3] | tail) == 0
}

/// Sums over a model's links and joints that bound its dynamics (see
/// [`Model::gravity_torque_bound`]).
#[derive(Default)]
struct Magnitudes {
    /// Σ|m| (kg).
    mass: f64,
    /// Σ(|l| + |m|·|pose translation|) (kg·m): first moments in their bodies' frames.
    moment: f64,
    /// Σ(‖I‖ + |l| + |m|) over the links.
    all: f64,
    /// Total length (m) of every translation in the tree at `|q| ≤ q_max`.
    reach: f64,
    /// Σ over joints of Σ|coefficient|·(|ω| + |v|): the coordinates' share of the axes.
    share: f64,
}

/// `x`, or `+∞` for NaN (a non-finite parameter).
fn finite_or_infinite(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        f64::INFINITY
    }
}
