//! Bounds on the dynamics' outputs over a box of positions, from the parameters alone:
//! what lets a real-time caller (the C ABI) skip checking every output for overflow.

use nalgebra::Vector3;

use crate::model::Model;

impl Model {
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
