//! Per-sample scratch buffers, reused across calls so that the real-time algorithms
//! (inverse and forward dynamics, gravity, nonlinear effects, mass matrix, regressor,
//! momentum observer) allocate nothing.

use nalgebra::Vector3;

use crate::model::Model;
use crate::spatial::Transform;

/// Mutable buffers for one thread. Create one per model and thread with
/// [`Workspace::new`]; every algorithm overwrites what it uses.
#[derive(Clone, Debug)]
pub struct Workspace {
    pub(crate) n_frames: usize,
    pub(crate) dof: usize,
    /// Joint values per frame (index 0 = base, unused).
    pub(crate) s: Vec<f64>,
    /// Parent → frame transform.
    pub(crate) local: Vec<Transform>,
    /// Base → frame transform (pose of the frame in the base frame).
    pub(crate) world: Vec<Transform>,
    /// Per body (index 0 = base, as frames): the dynamics of [`Model::inverse_dynamics`],
    /// [`Model::mass_matrix_into`] and friends run over bodies (see `model::Body`).
    pub(crate) body: BodyBuffers,
    /// n×n mass matrix (column-major) and its Cholesky factor, for forward dynamics.
    pub(crate) mass: Vec<f64>,
    /// Hysteresis states by parameter column (dimensionless; a [`Dahl`](crate::Dahl)
    /// element's at its `Fd`'s index, 0 elsewhere), read by the regressor and the
    /// dynamics; [`Model::advance_hysteresis`] moves them along the positions.
    pub(crate) hysteresis: Vec<f64>,
    /// The joint value each state was last advanced to (rad or m), by parameter column;
    /// NaN before the first sample.
    pub(crate) hysteresis_at: Vec<f64>,
    /// Each coordinate's load (N·m or N, `≥ 0`), read by load friction
    /// ([`LoadFriction`](crate::LoadFriction)): set by [`Model::set_load`] or
    /// [`Model::loaded_inverse_dynamics`]; 0 in a new workspace.
    pub(crate) load: Vec<f64>,
}

/// Body-indexed buffers (index 0 = base).
#[derive(Clone, Debug)]
pub(crate) struct BodyBuffers {
    /// Parent body → body transform.
    pub x: Vec<Transform>,
    /// As the frame buffers: ω (rad/s), v (m/s), ω̇ (rad/s²), a (m/s², gravity
    /// included), moment n (N·m) and force f (N), body coordinates.
    pub w: Vec<Vector3<f64>>,
    pub v: Vec<Vector3<f64>>,
    pub dw: Vec<Vector3<f64>>,
    pub a: Vec<Vector3<f64>>,
    pub n: Vec<Vector3<f64>>,
    pub f: Vec<Vector3<f64>>,
    /// Barycentric inertia of each body with its fixed links merged, in its frame, and
    /// the link parameters it was computed from: recomputed only when they change, as
    /// Pinocchio keeps the inertias in its model.
    pub inertia: Vec<[f64; 10]>,
    pub inertia_of: Vec<f64>,
    /// Mass matrix: the composite inertia of each body's subtree (body coordinates).
    pub composite: Vec<[f64; 10]>,
    /// Regressor: base → body transform (the body's pose in the base frame), and the
    /// unit motion `(ω, v)` of its joint in the base frame about the base origin
    /// (rad/s, m/s per unit joint rate; zero for the base).
    pub world: Vec<Transform>,
    pub axis: Vec<[f64; 6]>,
}

impl Workspace {
    /// Buffers sized for `model`.
    pub fn new(model: &Model) -> Self {
        let nf = model.frames.len() + 1;
        let n = model.dof();
        Workspace {
            n_frames: nf,
            dof: n,
            s: vec![0.0; nf],
            local: vec![Transform::identity(); nf],
            world: vec![Transform::identity(); nf],
            body: BodyBuffers::new(model.bodies.len() + 1, model.n_params()),
            mass: vec![0.0; n * n],
            hysteresis: vec![0.0; model.n_params()],
            hysteresis_at: vec![f64::NAN; model.n_params()],
            load: vec![0.0; n],
        }
    }

    /// Pose of frame `i` in the base frame after the last kinematics call.
    pub fn pose(&self, i: usize) -> &Transform {
        &self.world[i]
    }

    /// The hysteresis states by parameter column (dimensionless, in `[−1, 1]`; 0 for
    /// columns that are not a [`Dahl`](crate::Dahl) element's).
    pub fn hysteresis(&self) -> &[f64] {
        &self.hysteresis
    }

    /// Sets the hysteresis state of the Dahl element whose `Fd` is column `column`, e.g.
    /// from states computed in time order before samples are evaluated out of order.
    /// Values outside `[−1, 1]` are clamped onto it; a column out of range is ignored.
    pub fn set_hysteresis(&mut self, column: usize, z: f64) {
        if let Some(h) = self.hysteresis.get_mut(column) {
            *h = z.clamp(-1.0, 1.0);
        }
    }

    /// Each coordinate's load (N·m or N) as last set ([`Model::set_load`],
    /// [`Model::loaded_inverse_dynamics`]).
    pub fn load(&self) -> &[f64] {
        &self.load
    }

    /// Forgets the path: every hysteresis state back to 0, as before the first sample.
    pub fn reset_hysteresis(&mut self) {
        self.hysteresis.fill(0.0);
        self.hysteresis_at.fill(f64::NAN);
    }

    pub(crate) fn check(&self, model: &Model) {
        assert!(
            self.n_frames == model.frames.len() + 1
                && self.dof == model.dof()
                && self.body.x.len() == model.bodies.len() + 1
                && self.hysteresis.len() == model.n_params(),
            "workspace was created for another model"
        );
    }
}

impl BodyBuffers {
    fn new(nb: usize, n_params: usize) -> Self {
        let zero = vec![Vector3::zeros(); nb];
        BodyBuffers {
            x: vec![Transform::identity(); nb],
            w: zero.clone(),
            v: zero.clone(),
            dw: zero.clone(),
            a: zero.clone(),
            n: zero.clone(),
            f: zero,
            inertia: vec![[0.0; 10]; nb],
            inertia_of: Vec::with_capacity(n_params),
            composite: vec![[0.0; 10]; nb],
            world: vec![Transform::identity(); nb],
            axis: vec![[0.0; 6]; nb],
        }
    }
}
