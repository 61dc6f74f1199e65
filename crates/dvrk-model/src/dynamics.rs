//! Inverse dynamics (recursive Newton–Euler on the open tree, mapped through Aᵀ),
//! gravity, mass matrix and forward dynamics.
//!
//! By virtual work the coupled system's generalized forces are `τ = Aᵀ f_tree(s, ṡ, s̈)`
//! plus the elements (friction, springs, motor inertias): exact for closed chains, with
//! no symbolic algebra.

use nalgebra::{DMatrix, DVector, Vector3};

use crate::inertia::sym3;
use crate::model::Model;
use crate::workspace::Workspace;

/// `sign` with `sign(0) = 0` (numpy's convention, used by the 2019 package), so that a
/// joint at rest gets no Coulomb force.
#[inline]
pub fn sign0(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Which terms an internal dynamics pass includes.
#[derive(Clone, Copy)]
pub(crate) struct Terms {
    pub gravity: bool,
    /// friction and springs
    pub dissipative: bool,
    pub motor: bool,
}

pub(crate) const ALL: Terms = Terms {
    gravity: true,
    dissipative: true,
    motor: true,
};

impl Model {
    /// Velocity and acceleration of every frame (body coordinates), from `ws.local`,
    /// `ws.sd`, `ws.sdd`.
    #[inline]
    pub(crate) fn forward_pass(&self, ws: &mut Workspace, gravity: bool) {
        ws.w[0] = Vector3::zeros();
        ws.v[0] = Vector3::zeros();
        ws.dw[0] = Vector3::zeros();
        ws.a[0] = if gravity {
            -self.gravity
        } else {
            Vector3::zeros()
        };
        for &fi in &self.active {
            let p = self.frames[fi - 1].parent;
            let x = &ws.local[fi];
            let rt = x.rotation.transpose();
            let (sw, sv) = &self.motion[fi];
            let (sd, sdd) = (ws.sd[fi], ws.sdd[fi]);
            let wsd = sw * sd;
            let vsd = sv * sd;
            let w = rt * ws.w[p] + wsd;
            let v = rt * (ws.v[p] + ws.w[p].cross(&x.translation)) + vsd;
            let dw = rt * ws.dw[p] + sw * sdd + w.cross(&wsd);
            let a = rt * (ws.a[p] + ws.dw[p].cross(&x.translation))
                + sv * sdd
                + w.cross(&vsd)
                + v.cross(&wsd);
            ws.w[fi] = w;
            ws.v[fi] = v;
            ws.dw[fi] = dw;
            ws.a[fi] = a;
        }
    }

    /// Core of the inverse dynamics; writes `tau` (length n).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn rnea(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
        terms: Terms,
        tau: &mut [f64],
    ) {
        ws.check(self);
        let n = self.dof();
        assert!(
            q.len() == n && dq.len() == n && ddq.len() == n && tau.len() == n,
            "q, dq, ddq and tau must have length {n}"
        );
        assert_eq!(params.len(), self.n_params(), "parameter vector length");
        self.joint_values(ws, q, dq, ddq);
        self.active_local_transforms(ws);
        self.forward_pass(ws, terms.gravity);
        ws.n[0] = Vector3::zeros();
        ws.f[0] = Vector3::zeros();
        for &fi in &self.active {
            ws.n[fi] = Vector3::zeros();
            ws.f[fi] = Vector3::zeros();
        }
        for &j in &self.links {
            let p0 = self.frames[j - 1].inertia.expect("link frame");
            let pp = &params[p0..p0 + 10];
            let (w, v, dw) = (ws.w[j], ws.v[j], ws.dw[j]);
            let ac = ws.a[j] + w.cross(&v);
            let l_in = sym3(&pp[0..6]);
            let l = Vector3::new(pp[6], pp[7], pp[8]);
            let m = pp[9];
            ws.f[j] = ac * m + dw.cross(&l) + w.cross(&w.cross(&l));
            ws.n[j] = l_in * dw + w.cross(&(l_in * w)) + l.cross(&ac);
        }
        tau.fill(0.0);
        for &fi in self.active.iter().rev() {
            let f = &self.frames[fi - 1];
            let (sw, sv) = &self.motion[fi];
            let t = sw.dot(&ws.n[fi]) + sv.dot(&ws.f[fi]);
            for &(k, c) in &f.value.terms {
                tau[k] += c * t;
            }
            let x = &ws.local[fi];
            let rf = x.rotation * ws.f[fi];
            let rn = x.rotation * ws.n[fi] + x.translation.cross(&rf);
            ws.f[f.parent] += rf;
            ws.n[f.parent] += rn;
        }
        self.add_elements(params, q, dq, ddq, terms, tau);
    }

    /// Friction, spring and motor-inertia torques, added into `tau`.
    #[inline]
    fn add_elements(
        &self,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
        terms: Terms,
        tau: &mut [f64],
    ) {
        for f in &self.frames {
            if terms.dissipative {
                if let Some(fr) = &f.friction {
                    let sd = f.value.dot(dq);
                    let mut force = params[fr.param] * sign0(sd)
                        + params[fr.param + 1] * sd
                        + params[fr.param + 2];
                    if let Some(st) = &fr.stribeck {
                        force += params[st.param] * st.factor(sd);
                    }
                    for &(k, c) in &f.value.terms {
                        tau[k] += c * force;
                    }
                }
                if let Some(sp) = &f.spring {
                    let force = params[sp.param] * sp.deflection.eval(q);
                    for &(k, c) in &f.value.terms {
                        tau[k] -= c * force;
                    }
                }
            }
            if terms.motor {
                if let Some(mi) = &f.motor_inertia {
                    tau[mi.coordinate] += mi.ratio * params[mi.param] * ddq[mi.coordinate];
                }
            }
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
        self.rnea(ws, params, q, dq, ddq, ALL, tau);
    }

    /// Gravity torque `g(q)` of the links alone (N·m or N), as Pinocchio's
    /// `computeGeneralizedGravity`: no friction, spring or known force. Allocates nothing.
    pub fn gravity_torque(&self, ws: &mut Workspace, params: &[f64], q: &[f64], tau: &mut [f64]) {
        let zeros = std::mem::take(&mut ws.zeros);
        let terms = Terms {
            gravity: true,
            dissipative: false,
            motor: false,
        };
        self.rnea(ws, params, q, &zeros, &zeros, terms, tau);
        ws.zeros = zeros;
    }

    /// Mass matrix `M(q)` (n×n, kg·m², kg), motor inertias included, into `out`
    /// (column-major n·n). Column k is the inverse dynamics with q̈ = e_k, q̇ = 0 and no
    /// gravity, friction or spring. Allocates nothing.
    pub fn mass_matrix_into(&self, ws: &mut Workspace, params: &[f64], q: &[f64], out: &mut [f64]) {
        let n = self.dof();
        assert_eq!(out.len(), n * n, "mass matrix buffer must have n*n entries");
        let zeros = std::mem::take(&mut ws.zeros);
        let mut e = std::mem::take(&mut ws.tmp_q);
        let terms = Terms {
            gravity: false,
            dissipative: false,
            motor: true,
        };
        for k in 0..n {
            e.fill(0.0);
            e[k] = 1.0;
            self.rnea(
                ws,
                params,
                q,
                &zeros,
                &e,
                terms,
                &mut out[k * n..(k + 1) * n],
            );
        }
        ws.zeros = zeros;
        ws.tmp_q = e;
    }

    /// Mass matrix `M(q)` as a matrix (allocates).
    pub fn mass_matrix(&self, ws: &mut Workspace, params: &[f64], q: &[f64]) -> DMatrix<f64> {
        let n = self.dof();
        let mut out = vec![0.0; n * n];
        self.mass_matrix_into(ws, params, q, &mut out);
        DMatrix::from_vec(n, n, out)
    }

    /// Forward dynamics: the accelerations (rad/s², m/s²) under torques `tau` (N·m or N,
    /// as measured: known forces are subtracted first) with friction, springs and
    /// gravity. Returns `None` if the mass matrix is not positive definite (the
    /// parameters are not physical). Allocates (Cholesky); for simulation, not control.
    pub fn forward_dynamics(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        tau: &[f64],
    ) -> Option<DVector<f64>> {
        let n = self.dof();
        let m = self.mass_matrix(ws, params, q);
        let zeros = vec![0.0; n];
        let mut h = vec![0.0; n];
        self.rnea(ws, params, q, dq, &zeros, ALL, &mut h);
        let mut rhs = DVector::from_column_slice(tau);
        let mut known = vec![0.0; n];
        self.add_known_forces(q, &mut known);
        for k in 0..n {
            rhs[k] -= h[k] + known[k];
        }
        let chol = m.cholesky()?;
        Some(chol.solve(&rhs))
    }
}
