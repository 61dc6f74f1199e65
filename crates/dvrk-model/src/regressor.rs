//! The regressor `H(q, q̇, q̈)` with `τ = H·π`, linear in all parameters.
//!
//! Link columns: the tree joint `k` collects `S_kᵀ·Y_j` over the links `j` of its
//! subtree, `Y_j` the link's 6×10 body regressor (its spatial force as a linear function
//! of its barycentric parameters), and `Aᵀ` maps tree joints to coordinates. Each
//! `S_kᵀ·Y_j` is written out in the link's coordinates from its velocity and
//! acceleration (`link_row`), so `Y_j` itself is never formed; the link blocks are
//! written in place (the first one of a row) and only the rest of a row is zeroed.
//! Element columns follow `docs/identification.md` §3.2.

use nalgebra::Vector3;

use crate::model::Model;
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
        // Zero what no link block writes.
        for (r, row) in out.chunks_exact_mut(p).enumerate() {
            let mut from = 0;
            for &c in &self.regressor_plan.blocks[r] {
                row[from..c].fill(0.0);
                from = c + 10;
            }
            row[from..].fill(0.0);
        }
        self.joint_values(ws, q, dq, ddq);
        self.active_local_transforms(ws);
        self.active_world_transforms(ws);
        self.forward_pass(ws, true);

        for &j in &self.links {
            let (w, v) = (ws.w[j], ws.v[j]);
            ws.ac[j] = ws.a[j] + w.cross(&v);
        }
        for plan in &self.regressor_plan.frames {
            let (sw, sv) = &self.motion[plan.frame];
            let pose = &ws.world[plan.frame];
            let w0 = pose.rotation * sw;
            let v0 = pose.rotation * sv + pose.translation.cross(&w0);
            for link in &plan.links {
                let (row, col0) = (link_row(ws, link.link, &w0, &v0), link.col0);
                for &(coord, a, write) in &link.targets {
                    let dst: &mut [f64; 10] = (&mut out[coord * p + col0..coord * p + col0 + 10])
                        .try_into()
                        .expect("10 columns");
                    if write {
                        for (d, r) in dst.iter_mut().zip(&row) {
                            *d = a * r;
                        }
                    } else {
                        for (d, r) in dst.iter_mut().zip(&row) {
                            *d += a * r;
                        }
                    }
                }
            }
        }
        for (value, e) in &self.element_plan.all {
            let s = crate::element::Sample { value, q, dq, ddq };
            e.add_regressor(&s, p, out);
        }
    }

    /// For each row (coordinate), the columns that [`Model::regressor_into`] can make
    /// nonzero, increasing: every other entry of the row is exactly zero at every
    /// sample (links outside the subtrees the coordinate moves, elements of other
    /// coordinates). Reductions of many rows use it to skip those columns.
    pub fn regressor_pattern(&self) -> Vec<Vec<usize>> {
        let mut rows: Vec<std::collections::BTreeSet<usize>> = vec![Default::default(); self.dof()];
        for (r, blocks) in self.regressor_plan.blocks.iter().enumerate() {
            rows[r].extend(blocks.iter().flat_map(|&c| c..c + 10));
        }
        // An element writes its columns on the rows of its frame's joint value (a motor
        // inertia: its coordinate, which is that joint value's one coordinate).
        for f in &self.frames {
            for e in &f.elements {
                for &(c, _) in &f.value.terms {
                    rows[c].extend(e.columns());
                }
            }
        }
        rows.into_iter().map(|r| r.into_iter().collect()).collect()
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

/// The regressor row of link `j`'s ten parameters for a joint whose unit motion is
/// `(w0, v0)` in the base frame (rad/s, m/s, about the base origin): the power
/// `Sᵀ·Y_j` of the link's spatial force per unit parameter, written out in the link's
/// coordinates with `s = (sω, sv)` the joint's motion there. Inertia about the origin:
/// `n = L·ω̇ + ω × L·ω` gives `sωᵀ·L·ω̇ + (sω × ω)ᵀ·L·ω`; first moment: `n = l × a_c`,
/// `f = ω̇ × l + ω × (ω × l)` give `l·(a_c × sω + sv × ω̇ + ω (ω·sv) − sv |ω|²)`; mass:
/// `f = m·a_c` gives `sv·a_c`.
#[inline(always)]
fn link_row(ws: &Workspace, j: usize, w0: &Vector3<f64>, v0: &Vector3<f64>) -> [f64; 10] {
    let pose = &ws.world[j];
    let rt = pose.rotation.transpose();
    let s_w = rt * w0;
    let s_v = rt * (v0 + w0.cross(&pose.translation));
    let (w, dw, ac) = (&ws.w[j], &ws.dw[j], &ws.ac[j]);
    let u = s_w.cross(w);
    let lin = ac.cross(&s_w) + s_v.cross(dw) + w * w.dot(&s_v) - s_v * w.dot(w);
    [
        s_w[0] * dw[0] + u[0] * w[0],
        s_w[0] * dw[1] + s_w[1] * dw[0] + u[0] * w[1] + u[1] * w[0],
        s_w[0] * dw[2] + s_w[2] * dw[0] + u[0] * w[2] + u[2] * w[0],
        s_w[1] * dw[1] + u[1] * w[1],
        s_w[1] * dw[2] + s_w[2] * dw[1] + u[1] * w[2] + u[2] * w[1],
        s_w[2] * dw[2] + u[2] * w[2],
        lin[0],
        lin[1],
        lin[2],
        s_v.dot(ac),
    ]
}
