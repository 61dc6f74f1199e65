//! Forward kinematics on the coupled tree: joint values from coordinates, frame poses,
//! and frame-origin Jacobians.

use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::model::{JointKind, Model};
use crate::spatial::Transform;
use crate::workspace::Workspace;

impl Model {
    /// Parent → frame transforms of all frames from the joint values in `ws.s`.
    #[inline]
    pub(crate) fn local_transforms(&self, ws: &mut Workspace) {
        for fi in 1..=self.frames.len() {
            self.local_transform(ws, fi);
        }
    }

    #[inline]
    fn local_transform(&self, ws: &mut Workspace, fi: usize) {
        let f = &self.frames[fi - 1];
        ws.local[fi] = match f.kind {
            JointKind::Fixed => self.fixed[fi],
            _ => self.joint_transform(fi, &f.pre, ws.s[fi]),
        };
    }

    /// `pre · joint(s) · post` of the moving frame `fi` (rotation about or translation
    /// along the joint frame's z axis by `s`, rad or m).
    #[inline(always)]
    pub(crate) fn joint_transform(&self, fi: usize, pre: &Transform, s: f64) -> Transform {
        let f = &self.frames[fi - 1];
        let r = &pre.rotation;
        if f.kind == JointKind::Prismatic {
            let shift = Vector3::new(0.0, 0.0, s) + f.post.translation;
            return Transform {
                rotation: r * f.post.rotation,
                translation: pre.translation + r * shift,
            };
        }
        let (sn, cs) = libm::sincos(s);
        // pre.rotation · Rz(s): mix the first two columns.
        let c0 = r.column(0) * cs + r.column(1) * sn;
        let c1 = r.column(1) * cs - r.column(0) * sn;
        let rz = Matrix3::from_columns(&[c0, c1, r.column(2).into_owned()]);
        let (rotation_identity, no_shift) = self.post_identity[fi];
        Transform {
            rotation: if rotation_identity {
                rz
            } else {
                rz * f.post.rotation
            },
            translation: if no_shift {
                pre.translation
            } else {
                pre.translation + rz * f.post.translation
            },
        }
    }

    /// Poses of every frame in the base frame, in `ws` (read them with
    /// [`Workspace::pose`]).
    ///
    /// ```
    /// # use dvrk_model::{Model, Workspace};
    /// let model = Model::builtin("mtm").unwrap();
    /// let mut ws = Workspace::new(&model);
    /// model.forward_kinematics(&mut ws, &[0.0; 7]);
    /// // Frame 1 (top panel) sits l_b2p = 0.2154 m below the base origin.
    /// assert!((ws.pose(1).translation.z + 0.2154).abs() < 1e-12);
    /// ```
    pub fn forward_kinematics(&self, ws: &mut Workspace, q: &[f64]) {
        ws.check(self);
        assert_eq!(q.len(), self.dof(), "q has the wrong length");
        for (i, f) in self.frames.iter().enumerate() {
            ws.s[i + 1] = f.value.eval(q);
        }
        self.local_transforms(ws);
        self.world_transforms(ws);
    }

    #[inline]
    pub(crate) fn world_transforms(&self, ws: &mut Workspace) {
        for (i, f) in self.frames.iter().enumerate() {
            let fi = i + 1;
            ws.world[fi] = ws.world[f.parent].compose(&ws.local[fi]);
        }
    }

    /// Poses of all frames (base first) as 4x4 homogeneous matrices; allocates.
    pub fn frame_poses(&self, q: &[f64]) -> Vec<Transform> {
        let mut ws = Workspace::new(self);
        self.forward_kinematics(&mut ws, q);
        ws.world.clone()
    }

    /// Jacobian of frame `frame`'s origin, 6×n: rows 0..3 the linear velocity of the
    /// origin (m/s), rows 3..6 the angular velocity (rad/s), both in the base frame, per
    /// unit coordinate rate. Call after [`Model::forward_kinematics`] at the same q.
    pub fn frame_jacobian(&self, ws: &Workspace, frame: usize) -> DMatrix<f64> {
        let mut jac = DMatrix::zeros(6, self.dof());
        let p = ws.world[frame].translation;
        let mut k = frame;
        while k != 0 {
            let f = &self.frames[k - 1];
            if f.kind != JointKind::Fixed {
                let (sw, sv) = &self.motion[k];
                let pose = &ws.world[k];
                let w0 = pose.rotation * sw;
                // Velocity of the point at `p` for a unit rate of joint k.
                let v0 = pose.rotation * sv + w0.cross(&(p - pose.translation));
                for &(c, a) in &f.value.terms {
                    for r in 0..3 {
                        jac[(r, c)] += a * v0[r];
                        jac[(r + 3, c)] += a * w0[r];
                    }
                }
            }
            k = f.parent;
        }
        jac
    }
}
