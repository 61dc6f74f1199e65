//! The regressor `H(q, q̇, q̈)` with `τ = H·π`, linear in all parameters.
//!
//! Link columns: the tree joint `k` collects `S_kᵀ·Y_j` over the links `j` of its
//! subtree, `Y_j` the link's 6×10 body regressor (its spatial force as a linear function
//! of its barycentric parameters), and `Aᵀ` maps tree joints to coordinates. The
//! kinematics run over the bodies (moving frames, fixed links merged, as the dynamics):
//! a link fixed to a body takes its motion from the body's. Each `S_kᵀ·Y_j` is written
//! out in the link's coordinates ([`LinkRows`]), so `Y_j` itself is never formed: its
//! coefficients are formed once per link, then the joints of the link's path go two at
//! a time through SIMD lanes; links of a body at the same pose share their rows. The
//! link blocks are written in place (the first one of a row) and only the rest of a
//! row is zeroed. Element columns follow `docs/book/src/identification.md` §3.2.

use nalgebra::Vector3;
use wide::f64x2;

use crate::dynamics::Motion;
use crate::model::Model;
use crate::spatial::Transform;
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
        for &(r, from, to) in &self.regressor_plan.gaps {
            out[r * p + from..r * p + to.unwrap_or(p)].fill(0.0);
        }
        self.body_positions(ws, q);
        let b = &mut ws.body;
        let zero = Vector3::zeros();
        b.w[0] = zero;
        b.v[0] = zero;
        b.dw[0] = zero;
        b.a[0] = -self.gravity;
        for (k, body) in self.bodies.iter().enumerate() {
            let i = k + 1;
            let [w, v, dw, a] = self.body_velocity(b, body, i, dq, ddq, Motion::FULL);
            b.w[i] = w;
            b.v[i] = v;
            b.dw[i] = dw;
            b.a[i] = a;
            self.body_world(b, body, i);
        }

        let plan = &self.regressor_plan;
        for pb in &plan.bodies {
            let i = pb.body;
            let (w, dw, world) = (&b.w[i], &b.dw[i], &b.world[i]);
            let ac = b.a[i] + w.cross(&b.v[i]);
            let joints = &plan.joints[pb.joints.clone()];
            for link in &plan.links[pb.links.clone()] {
                let rows = match &link.pose {
                    None => LinkRows::new(w, dw, &ac, world),
                    Some(x) => {
                        // A link fixed to the body: its frame's motion.
                        let (rt, t) = (x.rotation.transpose(), &x.translation);
                        let ac_link = rt * (ac + dw.cross(t) + w.cross(&w.cross(t)));
                        LinkRows::new(&(rt * w), &(rt * dw), &ac_link, &world.compose(x))
                    }
                };
                let columns = &plan.columns[link.columns.clone()];
                for (chunk, pair) in joints.chunks_exact(2).enumerate() {
                    let (s0, s1) = (&b.axis[pair[0]], &b.axis[pair[1]]);
                    let e = rows.rows(&std::array::from_fn(|c| f64x2::new([s0[c], s1[c]])));
                    // Entries (2i, 2i+1) of the first joint's row, then of the second's.
                    let halves: [[f64x2; 2]; 5] =
                        std::array::from_fn(|i| f64x2::transpose([e[2 * i], e[2 * i + 1]]));
                    for &(col0, targets) in columns {
                        let pair_targets =
                            &plan.targets[targets + 2 * chunk..targets + 2 * chunk + 2];
                        for (l, t) in pair_targets.iter().enumerate() {
                            let terms = &plan.terms[t.clone()];
                            if let &[(coord, 1.0, true)] = terms {
                                // The common case (one coordinate, coefficient 1):
                                // a plain copy.
                                let at = coord * p + col0;
                                let dst: &mut [f64; 10] =
                                    (&mut out[at..at + 10]).try_into().expect("10 columns");
                                for (d, h) in dst.chunks_exact_mut(2).zip(&halves) {
                                    d.copy_from_slice(&h[l].to_array());
                                }
                                continue;
                            }
                            for &(coord, a, write) in terms {
                                let at = coord * p + col0;
                                let dst: &mut [f64; 10] =
                                    (&mut out[at..at + 10]).try_into().expect("10 columns");
                                let a = f64x2::splat(a);
                                for (d, h) in dst.chunks_exact_mut(2).zip(&halves) {
                                    let x = if write {
                                        a * h[l]
                                    } else {
                                        a * h[l] + f64x2::new([d[0], d[1]])
                                    };
                                    d.copy_from_slice(&x.to_array());
                                }
                            }
                        }
                    }
                }
            }
        }
        for (value, e) in &self.element_plan.all {
            let s = crate::element::Sample {
                value,
                q,
                dq,
                ddq,
                hysteresis: &ws.hysteresis,
                load: &ws.load,
            };
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

/// Link `j`'s regressor rows as a linear map of a joint's unit motion: the power
/// `Sᵀ·Y_j` of the link's spatial force per unit parameter, in the link's coordinates
/// with `s = (sω, sv)` the joint's motion there. Inertia about the origin:
/// `n = L·ω̇ + ω × L·ω` gives `sωᵀ·L·ω̇ + (sω × ω)ᵀ·L·ω`; first moment: `n = l × a_c`,
/// `f = ω̇ × l + ω × (ω × l)` give `l·(a_c × sω + sv × ω̇ + ω (ω·sv) − sv |ω|²)`; mass:
/// `f = m·a_c` gives `sv·a_c`. Their coefficients on `sω` and `sv` depend on the link's
/// state only, so they are formed once per link; each of its joints then costs moving
/// `s` into the link's coordinates and a sparse 10×6 product, two joints at a time in
/// the two lanes of SIMD registers (every coefficient held in both lanes).
struct LinkRows {
    /// Coefficients of `sω` in the six inertia entries.
    inertia: [[f64x2; 3]; 6],
    /// Coefficients of `sv` in the first moment (its `sω` part is `a_c × sω`).
    moment: [[f64x2; 3]; 3],
    /// `a_c` (m/s²).
    ac: [f64x2; 3],
    /// The link's pose in the base frame: its columns (`rotation[c][r]`) and origin (m).
    rotation: [[f64x2; 3]; 3],
    translation: [f64x2; 3],
}

impl LinkRows {
    /// From the link's angular velocity ω (rad/s), acceleration ω̇ (rad/s²), origin
    /// acceleration `a_c` (m/s², gravity included) in its coordinates, and its pose.
    #[inline(always)]
    fn new(w: &Vector3<f64>, dw: &Vector3<f64>, ac: &Vector3<f64>, pose: &Transform) -> Self {
        let (w0, w1, w2) = (w[0], w[1], w[2]);
        let (d0, d1, d2) = (dw[0], dw[1], dw[2]);
        let (w00, w11, w22) = (w0 * w0, w1 * w1, w2 * w2);
        let (w01, w02, w12) = (w0 * w1, w0 * w2, w1 * w2);
        let splat = |x: [f64; 3]| x.map(f64x2::splat);
        let r = &pose.rotation.data.0;
        LinkRows {
            inertia: [
                splat([d0, w02, -w01]),
                splat([d1 - w02, d0 + w12, w00 - w11]),
                splat([d2 + w01, w22 - w00, d0 - w12]),
                splat([-w12, d1, w01]),
                splat([w11 - w22, d2 - w01, d1 + w02]),
                splat([w12, -w02, d2]),
            ],
            moment: [
                splat([-(w11 + w22), w01 + d2, w02 - d1]),
                splat([w01 - d2, -(w00 + w22), w12 + d0]),
                splat([w02 + d1, w12 - d0, -(w00 + w11)]),
            ],
            ac: splat([ac[0], ac[1], ac[2]]),
            rotation: [splat(r[0]), splat(r[1]), splat(r[2])],
            translation: splat([
                pose.translation[0],
                pose.translation[1],
                pose.translation[2],
            ]),
        }
    }

    /// The ten entries, each for two joints (one per lane), whose unit motions are
    /// `s = (ω0, v0)` in the base frame (rad/s, m/s, about the base origin):
    /// `sω = Rᵀ·ω0`, `sv = Rᵀ·(v0 + ω0 × t)`.
    #[inline(always)]
    fn rows(&self, s: &[f64x2; 6]) -> [f64x2; 10] {
        let (r, t) = (&self.rotation, &self.translation);
        let w0 = [s[0], s[1], s[2]];
        let v0 = [
            s[3] + w0[1] * t[2] - w0[2] * t[1],
            s[4] + w0[2] * t[0] - w0[0] * t[2],
            s[5] + w0[0] * t[1] - w0[1] * t[0],
        ];
        let dot = |k: &[f64x2; 3], x: &[f64x2; 3]| k[0] * x[0] + k[1] * x[1] + k[2] * x[2];
        let sw = [dot(&r[0], &w0), dot(&r[1], &w0), dot(&r[2], &w0)];
        let sv = [dot(&r[0], &v0), dot(&r[1], &v0), dot(&r[2], &v0)];
        let (k, m, c) = (&self.inertia, &self.moment, &self.ac);
        [
            dot(&k[0], &sw),
            dot(&k[1], &sw),
            dot(&k[2], &sw),
            dot(&k[3], &sw),
            dot(&k[4], &sw),
            dot(&k[5], &sw),
            dot(&m[0], &sv) + c[1] * sw[2] - c[2] * sw[1],
            dot(&m[1], &sv) + c[2] * sw[0] - c[0] * sw[2],
            dot(&m[2], &sv) + c[0] * sw[1] - c[1] * sw[0],
            dot(c, &sv),
        ]
    }
}
