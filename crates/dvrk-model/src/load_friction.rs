//! The model's side of load friction ([`crate::element::LoadFriction`]): the load signal,
//! the prediction that solves for it, and adding it to the frames with friction. An
//! algorithm over the model and its workspace, like the dynamics: the element knows
//! neither, and the model does not depend on the workspace it sizes.

use crate::element::{sign0, Element, LoadFriction, MAX_LOAD_RATIO};
use crate::workspace::Workspace;

use crate::model::Model;

/// The model's side of load friction: the load signal, the prediction that solves for
/// it, and adding it to the frames with friction (`--load-friction`).
impl Model {
    /// Sets the load of every coordinate to the magnitude of its measured torque `tau`
    /// (N·m or N, model coordinates), read by the regressor and the dynamics of the
    /// following calls ([`LoadFriction`]); a non-finite torque loads nothing. Call it
    /// per sample before the regressor (a fit) or the dynamics with a measured torque
    /// (a momentum observer). A model without load friction ignores it. Allocates
    /// nothing.
    pub fn set_load(&self, ws: &mut Workspace, tau: &[f64]) {
        ws.check(self);
        assert_eq!(tau.len(), self.dof(), "tau must have length {}", self.dof());
        for (l, t) in ws.load.iter_mut().zip(tau) {
            *l = if t.is_finite() { t.abs() } else { 0.0 };
        }
    }

    /// Inverse dynamics that predicts the load rather than reading it: the torque `τ` of
    /// [`Model::inverse_dynamics`] with each coordinate's load equal to `|τ|` itself,
    /// `τ_c = τ₀_c/(1 − κ_c·sign(τ₀_c))` for `τ₀` the torque without load friction and
    /// `κ_c = Σ μ·sign(q̇_c)` of the coordinate's [`LoadFriction`] elements (the
    /// denominator held at least `1 − MAX_LOAD_RATIO` for ratios beyond the fit's
    /// bound). Leaves the workspace's load at the prediction's `|τ|`. Identical to
    /// [`Model::inverse_dynamics`] for a model without load friction. Allocates nothing.
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let psm = Model::builtin("psm").unwrap().with_load_friction();
    /// let mut ws = Workspace::new(&psm);
    /// let mut params = vec![0.0; psm.n_params()];
    /// let fo1 = psm.param_index("Fo1").unwrap();
    /// let fl1 = psm.param_index("Fl1").unwrap();
    /// (params[fo1], params[fl1]) = (0.2, 0.1);
    /// let (q, mut dq, mut tau) = ([0.0; 7], [0.0; 7], [0.0; 7]);
    /// dq[0] = 1.0;
    /// psm.loaded_inverse_dynamics(&mut ws, &params, &q, &dq, &[0.0; 7], &mut tau);
    /// // τ = 0.2 + 0.1·|τ| moving forward: τ = 0.2/0.9.
    /// assert!((tau[0] - 0.2 / 0.9).abs() < 1e-15);
    /// ```
    pub fn loaded_inverse_dynamics(
        &self,
        ws: &mut Workspace,
        params: &[f64],
        q: &[f64],
        dq: &[f64],
        ddq: &[f64],
        tau: &mut [f64],
    ) {
        ws.load.fill(0.0);
        self.inverse_dynamics(ws, params, q, dq, ddq, tau);
        if self.element_plan.load.is_empty() {
            return;
        }
        for (c, t) in tau.iter_mut().enumerate() {
            let kappa: f64 = self
                .element_plan
                .load
                .iter()
                .filter(|&&(_, coordinate)| coordinate == c)
                .map(|&(param, _)| params[param] * sign0(dq[c]))
                .sum();
            if kappa != 0.0 {
                let d = (1.0 - kappa * sign0(*t)).max(1.0 - MAX_LOAD_RATIO);
                *t /= d;
            }
            ws.load[c] = t.abs();
        }
    }

    /// This model with load friction on every frame with friction whose joint value is
    /// one coordinate's multiple, the first such frame of each coordinate (two on one
    /// coordinate would be the same column), and none there yet (e.g. `dvrk-ident fit
    /// --load-friction`); the `Fl` parameters appended in frame order.
    ///
    /// ```
    /// let psm = dvrk_model::Model::builtin("psm").unwrap();
    /// let with = psm.with_load_friction();
    /// // One per coordinate: yaw, pitch, insertion, roll, and the wrist motors q5-q7.
    /// let names = with.param_names();
    /// assert_eq!(names[psm.n_params()..], ["Fl1", "Fl2", "Fl8", "Fl10", "Fl11", "Fl14", "Fl15"]);
    /// ```
    pub fn with_load_friction(&self) -> Model {
        let mut m = self.clone();
        let mut taken = vec![false; m.dof()];
        for f in &m.frames {
            for e in &f.elements {
                if let Element::LoadFriction(l) = e {
                    taken[l.coordinate] = true;
                }
            }
        }
        for (i, f) in m.frames.iter_mut().enumerate() {
            let [(coordinate, _)] = f.value.terms[..] else {
                continue;
            };
            if f.friction().is_none() || taken[coordinate] {
                continue;
            }
            taken[coordinate] = true;
            let e = Element::LoadFriction(LoadFriction {
                param: m.params.len(),
                coordinate,
            });
            m.params.extend(e.params(i + 1));
            f.elements.push(e);
        }
        m.element_plan = m.derive_element_plan();
        m
    }
}
