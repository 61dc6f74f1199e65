//! Inverse dynamics (recursive Newton–Euler on the open tree, mapped through Aᵀ),
//! gravity, nonlinear effects, mass matrix (composite rigid bodies) and forward
//! dynamics (Cholesky of the mass matrix in the workspace).
//!
//! By virtual work the coupled system's generalized forces are `τ = Aᵀ f_tree(s, ṡ, s̈)`
//! plus the elements (friction, springs, motor inertias): exact for closed chains, with
//! no symbolic algebra. The same holds for the mass matrix, `M = Aᵀ·M_tree·A` plus the
//! motor inertias. All of them run over the tree's bodies (moving frames, fixed links
//! merged, see `model::Body`) and allocate nothing.
//!
//! This file holds the recursive Newton–Euler passes and their entry points; `mass`
//! the mass matrix and forward dynamics, `bounds` the bounds on gravity and the mass
//! matrix that spare a real-time caller its output checks.

use nalgebra::Vector3;

use crate::element::{sign0, Sample};
use crate::inertia::{sym3, transform_barycentric};
use crate::model::{Axis, Body, Model};
use crate::workspace::{BodyBuffers, Workspace};

mod bounds;
mod mass;

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
