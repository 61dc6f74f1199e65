//! The regressor `H(q, q̇, q̈)` with `τ = H·π`, linear in all parameters.
//!
//! Link columns: each link's 6×10 body regressor (spatial force as a linear function of
//! its barycentric parameters) is expressed in base coordinates; the tree joint `k`
//! collects `S_kᵀ·Y_j` over the links `j` of its subtree, and `Aᵀ` maps tree joints to
//! coordinates. Element columns follow `identification.md` §3.

use nalgebra::Vector3;

use crate::dynamics::sign0;
use crate::model::{JointKind, Model};
use crate::workspace::Workspace;

impl Model {
    /// Full regressor at one sample into `out`, row-major `n × p` (`n` coordinates,
    /// `p` = [`Model::n_params`]), so that stacked samples form an `(N·n) × p` row-major
    /// matrix. Allocates nothing.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let model = Model::builtin("mtm").unwrap();
    /// let mut ws = Workspace::new(&model);
    /// let (n, p) = (model.dof(), model.n_params());
    /// let mut h = vec![0.0; n * p];
    /// let (q, dq, ddq) = ([0.1; 7], [0.2; 7], [0.3; 7]);
    /// model.regressor_into(&mut ws, &q, &dq, &ddq, &mut h);
    /// // H·π equals the inverse dynamics.
    /// let pi: Vec<f64> = (0..p).map(|k| 0.01 * k as f64).collect();
    /// let mut tau = [0.0; 7];
    /// model.inverse_dynamics(&mut ws, &pi, &q, &dq, &ddq, &mut tau);
    /// for r in 0..n {
    ///     let hp: f64 = (0..p).map(|c| h[r * p + c] * pi[c]).sum();
    ///     assert!((hp - tau[r]).abs() < 1e-10);
    /// }
    /// ```
    pub fn regressor_into(
        &self,
        ws: &mut Workspace,
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
        out: &mut [f64],
    ) {
        ws.check(self);
        let n = self.dof();
        let p = self.n_params();
        assert!(
            q.len() == n && dq.len() == n && ddq.len() == n,
            "q, dq and ddq must have length {n}"
        );
        assert_eq!(out.len(), n * p, "regressor buffer must have n*p entries");
        out.fill(0.0);
        self.joint_values(ws, q, dq, ddq);
        self.active_local_transforms(ws);
        self.active_world_transforms(ws);
        self.forward_pass(ws, true);

        for &j in &self.links {
            link_block(ws, j);
        }
        for &k in &self.active {
            let f = &self.frames[k - 1];
            if f.kind == JointKind::Fixed {
                continue;
            }
            let (sw, sv) = &self.motion[k];
            let pose = &ws.world[k];
            let w0 = pose.rotation * sw;
            let v0 = pose.rotation * sv + pose.translation.cross(&w0);
            let s6 = [w0[0], w0[1], w0[2], v0[0], v0[1], v0[2]];
            for &j in &self.subtree_links[k] {
                let col0 = self.frames[j - 1].inertia.expect("link frame");
                let y = &ws.yb[j];
                let mut row = [0.0; 10];
                for (c, r) in row.iter_mut().enumerate() {
                    let yc = &y[6 * c..6 * c + 6];
                    *r = s6.iter().zip(yc).map(|(a, b)| a * b).sum();
                }
                for &(coord, a) in &f.value.terms {
                    let dst = &mut out[coord * p + col0..coord * p + col0 + 10];
                    for (d, r) in dst.iter_mut().zip(&row) {
                        *d += a * r;
                    }
                }
            }
        }
        for f in &self.frames {
            if let Some(fr) = &f.friction {
                let sd = f.value.dot(dq);
                let sg = sign0(sd);
                for &(coord, a) in &f.value.terms {
                    let base = coord * p + fr.param;
                    out[base] += a * sg;
                    out[base + 1] += a * sd;
                    out[base + 2] += a;
                }
                if let Some(st) = &fr.stribeck {
                    let v = st.factor(sd);
                    for &(coord, a) in &f.value.terms {
                        out[coord * p + st.param] += a * v;
                    }
                }
            }
            if let Some(mi) = &f.motor_inertia {
                out[mi.coordinate * p + mi.param] += mi.ratio * ddq[mi.coordinate];
            }
            if let Some(sp) = &f.spring {
                let dl = sp.deflection.eval(q);
                for &(coord, a) in &f.value.terms {
                    out[coord * p + sp.param] -= a * dl;
                }
            }
        }
    }

    /// Full regressor at one sample as an `n × p` matrix (allocates).
    pub fn regressor(
        &self,
        ws: &mut Workspace,
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
    ) -> nalgebra::DMatrix<f64> {
        let (n, p) = (self.dof(), self.n_params());
        let mut out = vec![0.0; n * p];
        self.regressor_into(ws, q, dq, ddq, &mut out);
        nalgebra::DMatrix::from_row_slice(n, p, &out)
    }
}

/// Link `j`'s 6×10 regressor block in base coordinates about the base origin, into
/// `ws.yb[j]` (column c = the spatial force (n; f) per unit of parameter c).
#[inline]
fn link_block(ws: &mut Workspace, j: usize) {
    let (w, v, dw) = (ws.w[j], ws.v[j], ws.dw[j]);
    let ac = ws.a[j] + w.cross(&v);
    let pose = ws.world[j];
    let mut cols = [(Vector3::zeros(), Vector3::zeros()); 10];
    // Inertia about the origin: n = K(ω̇)·L + ω × K(ω)·L, where K(x)·L = L x.
    let kcol = |x: &Vector3<f64>, c: usize| -> Vector3<f64> {
        match c {
            0 => Vector3::new(x[0], 0.0, 0.0),
            1 => Vector3::new(x[1], x[0], 0.0),
            2 => Vector3::new(x[2], 0.0, x[0]),
            3 => Vector3::new(0.0, x[1], 0.0),
            4 => Vector3::new(0.0, x[2], x[1]),
            _ => Vector3::new(0.0, 0.0, x[2]),
        }
    };
    for (c, col) in cols.iter_mut().enumerate().take(6) {
        col.0 = kcol(&dw, c) + w.cross(&kcol(&w, c));
    }
    // First moment: n = l × a_c, f = ω̇ × l + ω × (ω × l).
    for (axis, col) in cols.iter_mut().skip(6).take(3).enumerate() {
        let e = Vector3::ith(axis, 1.0);
        col.0 = e.cross(&ac);
        col.1 = dw.cross(&e) + w.cross(&w.cross(&e));
    }
    // Mass: f = m·a_c.
    cols[9].1 = ac;
    let y = &mut ws.yb[j];
    for (c, (nb, fb)) in cols.iter().enumerate() {
        let f0 = pose.rotation * fb;
        let n0 = pose.rotation * nb + pose.translation.cross(&f0);
        y[6 * c..6 * c + 3].copy_from_slice(n0.as_slice());
        y[6 * c + 3..6 * c + 6].copy_from_slice(f0.as_slice());
    }
}
