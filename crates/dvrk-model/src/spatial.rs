//! Rigid transforms: a leaf module, so that the model, its workspace, the kinematics and
//! the dynamics all read the same type without depending on each other.

use nalgebra::{Matrix3, Vector3};

/// A rigid transform: `x_parent = rotation · x_child + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Rotation from the child frame's axes to the parent frame's.
    pub rotation: Matrix3<f64>,
    /// m
    pub translation: Vector3<f64>,
}

impl Transform {
    /// No rotation, no translation.
    pub fn identity() -> Self {
        Transform {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// A pure rotation by `angle` (rad) about the x axis.
    pub fn rot_x(angle: f64) -> Self {
        let (s, c) = angle.sin_cos();
        Transform {
            rotation: Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c),
            translation: Vector3::zeros(),
        }
    }

    /// A pure rotation by `angle` (rad) about the z axis.
    pub fn rot_z(angle: f64) -> Self {
        let (s, c) = angle.sin_cos();
        Transform {
            rotation: Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
            translation: Vector3::zeros(),
        }
    }

    /// A pure translation by `(x, y, z)` (m).
    pub fn trans(x: f64, y: f64, z: f64) -> Self {
        Transform {
            rotation: Matrix3::identity(),
            translation: Vector3::new(x, y, z),
        }
    }

    /// `self · other`.
    #[inline]
    pub fn compose(&self, other: &Transform) -> Transform {
        Transform {
            rotation: self.rotation * other.rotation,
            translation: self.translation + self.rotation * other.translation,
        }
    }

    /// The rigid inverse: `x_child = Rᵀ·x_parent − Rᵀ·t`.
    pub fn inverse(&self) -> Transform {
        let rt = self.rotation.transpose();
        Transform {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    /// 4x4 homogeneous matrix, row-major rows.
    pub fn to_homogeneous(&self) -> [[f64; 4]; 4] {
        let r = &self.rotation;
        let t = &self.translation;
        [
            [r[(0, 0)], r[(0, 1)], r[(0, 2)], t[0]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)], t[1]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)], t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }
}
