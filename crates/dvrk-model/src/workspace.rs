//! Per-sample scratch buffers, reused across calls so that the real-time algorithms
//! (inverse dynamics, gravity, regressor) allocate nothing.

use nalgebra::Vector3;

use crate::model::{Model, Transform};

/// Mutable buffers for one thread. Create one per model and thread with
/// [`Workspace::new`]; every algorithm overwrites what it uses.
#[derive(Clone, Debug)]
pub struct Workspace {
    pub(crate) n_frames: usize,
    pub(crate) dof: usize,
    /// Joint values, rates and accelerations per frame (index 0 = base, unused).
    pub(crate) s: Vec<f64>,
    pub(crate) sd: Vec<f64>,
    pub(crate) sdd: Vec<f64>,
    /// Parent → frame transform.
    pub(crate) local: Vec<Transform>,
    /// Base → frame transform (pose of the frame in the base frame).
    pub(crate) world: Vec<Transform>,
    /// Body-frame angular velocity ω (rad/s), origin velocity v (m/s), ω̇ (rad/s²) and
    /// spatial linear acceleration a (m/s², gravity included as a base acceleration).
    pub(crate) w: Vec<Vector3<f64>>,
    pub(crate) v: Vec<Vector3<f64>>,
    pub(crate) dw: Vec<Vector3<f64>>,
    pub(crate) a: Vec<Vector3<f64>>,
    /// Accumulated spatial force (moment about the origin n, force f) per frame.
    pub(crate) n: Vec<Vector3<f64>>,
    pub(crate) f: Vec<Vector3<f64>>,
    /// Link regressor blocks expressed in base coordinates about the base origin,
    /// 6 rows (n; f) × 10 columns, column-major per link frame.
    pub(crate) yb: Vec<[f64; 60]>,
    /// Coordinate-sized scratch vectors.
    pub(crate) tmp_q: Vec<f64>,
    pub(crate) zeros: Vec<f64>,
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
            sd: vec![0.0; nf],
            sdd: vec![0.0; nf],
            local: vec![Transform::identity(); nf],
            world: vec![Transform::identity(); nf],
            w: vec![Vector3::zeros(); nf],
            v: vec![Vector3::zeros(); nf],
            dw: vec![Vector3::zeros(); nf],
            a: vec![Vector3::zeros(); nf],
            n: vec![Vector3::zeros(); nf],
            f: vec![Vector3::zeros(); nf],
            yb: vec![[0.0; 60]; nf],
            tmp_q: vec![0.0; n],
            zeros: vec![0.0; n],
        }
    }

    /// Pose of frame `i` in the base frame after the last kinematics call.
    pub fn pose(&self, i: usize) -> &Transform {
        &self.world[i]
    }

    pub(crate) fn check(&self, model: &Model) {
        assert!(
            self.n_frames == model.frames.len() + 1 && self.dof == model.dof(),
            "workspace was created for another model"
        );
    }
}
