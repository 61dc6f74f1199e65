//! The mass matrix (composite rigid bodies, Featherstone's CRBA) and the forward
//! dynamics solved with it (Cholesky of the mass matrix in the workspace).

use nalgebra::{DMatrix, DVector};
use wide::f64x2;

use super::{Motion, NotPositiveDefinite, Terms};
use crate::inertia::transform_barycentric;
use crate::model::{Axis, Body, Model};
use crate::spatial::Transform;
use crate::workspace::{BodyBuffers, Workspace};

impl Model {
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
