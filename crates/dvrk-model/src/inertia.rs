//! Conversions between the barycentric link parameters used by the regressor and the
//! standard (centre-of-mass) form people read, and the pseudo-inertia matrix whose
//! positive definiteness is the physical-consistency condition.

use nalgebra::{Matrix3, Matrix4, Vector3};

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// `[xx, xy, xz, yy, yz, zz]` of a symmetric matrix (the inverse of [`sym3`]).
pub fn sym6(m: &Matrix3<f64>) -> [f64; 6] {
    [
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 1)],
        m[(1, 2)],
        m[(2, 2)],
    ]
}

/// Symmetric 3x3 matrix from `[xx, xy, xz, yy, yz, zz]`.
pub fn sym3(v: &[f64]) -> Matrix3<f64> {
    Matrix3::new(v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5])
}

/// Barycentric `[Lxx, Lxy, Lxz, Lyy, Lyz, Lzz, lx, ly, lz, m]` (inertia about the frame
/// origin, first moment `m·c`) from mass (kg), centre of mass `c` (m) and inertia about
/// the centre of mass `[xx, xy, xz, yy, yz, zz]` (kg·m²), all in the frame's axes.
pub fn barycentric_from_standard(mass: f64, com: [f64; 3], inertia_com: [f64; 6]) -> [f64; 10] {
    let c = Vector3::from(com);
    let s = skew(&c);
    let l = sym3(&inertia_com) + mass * s.transpose() * s;
    let s6 = sym6(&l);
    [
        s6[0],
        s6[1],
        s6[2],
        s6[3],
        s6[4],
        s6[5],
        mass * c[0],
        mass * c[1],
        mass * c[2],
        mass,
    ]
}

/// Barycentric parameters of a body (`[Lxx, Lxy, Lxz, Lyy, Lyz, Lzz, lx, ly, lz, m]`,
/// inertia about the frame origin) expressed in another frame, where
/// `x_new = rotation·x + translation`: `m' = m`, `l' = m·t + R·l`,
/// `L' = R·L·Rᵀ + (t·(m·t + 2R·l))·I − (t·l'ᵀ + R·l·tᵀ)` (the parallel-axis terms
/// `m·S(t)ᵀS(t) + S(t)ᵀS(Rl) + S(Rl)ᵀS(t)` written out). The mass matrix composes the
/// links' inertias in the base frame with it, and fixed links are merged into their
/// moving parent with it.
#[inline]
pub fn transform_barycentric(
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
    p: &[f64; 10],
) -> [f64; 10] {
    // Written out on the arrays, entries 0 and 1 of each 3-vector in the two lanes of
    // an f64x2 (every entry is the same sum of the same products as in scalar code):
    // a third of nalgebra's generic products' instructions, and this runs for every
    // body in every mass matrix.
    use wide::f64x2;
    let r = &rotation.data.0; // r[column][row]
    let xy = |c: &[f64; 3]| f64x2::new([c[0], c[1]]);
    let (c0, c1, c2) = (xy(&r[0]), xy(&r[1]), xy(&r[2]));
    let dot_z = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let row2 = [r[0][2], r[1][2], r[2][2]];
    let sp = f64x2::splat;
    // R·x: rows 0 and 1 in the lanes, row 2 apart.
    let rot = |x: &[f64; 3]| {
        (
            c0 * sp(x[0]) + c1 * sp(x[1]) + c2 * sp(x[2]),
            dot_z(&row2, x),
        )
    };
    let t = [translation[0], translation[1], translation[2]];
    let m = p[9];
    let (rl, rl2) = rot(&[p[6], p[7], p[8]]);
    let t01 = f64x2::new([t[0], t[1]]);
    let h = sp(m) * t01 + rl;
    let h2 = m * t[2] + rl2;
    let [d0, d1] = (t01 * (h + rl)).to_array();
    let d = d0 + d1 + t[2] * (h2 + rl2);
    // Rows of R·L (L symmetric: its rows are its columns): a_k = (r_0·L_k, r_1·L_k) in
    // the lanes, r_2·L_k apart.
    let (lx, ly, lz) = ([p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]);
    let (a0, a20) = rot(&lx);
    let (a1, a21) = rot(&ly);
    let (a2, a22) = rot(&lz);
    let [h0, h1] = h.to_array();
    let hs = [h0, h1, h2];
    // Entries (0, j) and (1, j): a_i·r_j − (t_i·h_j + rl_i·t_j).
    let big = |j: usize| {
        a0 * sp(r[0][j]) + a1 * sp(r[1][j]) + a2 * sp(r[2][j]) - (t01 * sp(hs[j]) + rl * sp(t[j]))
    };
    let [b00, _] = big(0).to_array();
    let [b01, b11] = big(1).to_array();
    let [b02, b12] = big(2).to_array();
    let b22 = dot_z(&[a20, a21, a22], &row2) - (t[2] * h2 + rl2 * t[2]);
    [b00 + d, b01, b02, b11 + d, b12, b22 + d, h0, h1, h2, m]
}

/// Standard parameters of one link.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StandardInertia {
    /// kg
    pub mass: f64,
    /// centre of mass in the link frame (m); zero when the mass is not positive
    pub com: [f64; 3],
    /// inertia about the centre of mass, link-frame axes `[xx, xy, xz, yy, yz, zz]` (kg·m²)
    pub inertia_com: [f64; 6],
}

/// Inverse of [`barycentric_from_standard`].
pub fn standard_from_barycentric(p: &[f64]) -> StandardInertia {
    let m = p[9];
    let c = if m > 0.0 {
        Vector3::new(p[6], p[7], p[8]) / m
    } else {
        Vector3::zeros()
    };
    let s = skew(&c);
    let ic = sym3(&p[0..6]) - m * s.transpose() * s;
    StandardInertia {
        mass: m,
        com: [c[0], c[1], c[2]],
        inertia_com: sym6(&ic),
    }
}

/// The 4x4 pseudo-inertia `J = [[tr(L)/2·I − L, l], [lᵀ, m]]` of barycentric parameters.
/// `J ≻ 0` iff the parameters are those of a rigid body with positive mass density.
pub fn pseudo_inertia(p: &[f64]) -> Matrix4<f64> {
    let l = sym3(&p[0..6]);
    let sigma = 0.5 * l.trace() * Matrix3::identity() - l;
    let mut j = Matrix4::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&sigma);
    for k in 0..3 {
        j[(k, 3)] = p[6 + k];
        j[(3, k)] = p[6 + k];
    }
    j[(3, 3)] = p[9];
    j
}

/// Smallest eigenvalue of the pseudo-inertia (kg·m²); positive means consistent.
pub fn pseudo_inertia_min_eigenvalue(p: &[f64]) -> f64 {
    pseudo_inertia(p).symmetric_eigenvalues().min()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_parallel_axis() {
        let b = barycentric_from_standard(2.0, [0.1, -0.2, 0.3], [1.0, 0.4, 0.5, 2.0, 0.6, 3.0]);
        // Pinocchio's Inertia(m=2, c=[.1,-.2,.3], I_C).toDynamicParameters() gives
        // Ixx = 1 + 2*(0.04+0.09) = 1.26, Ixy = 0.4 - 2*(0.1*-0.2) = 0.44.
        assert!((b[0] - 1.26).abs() < 1e-15);
        assert!((b[1] - 0.44).abs() < 1e-15);
        assert!((b[2] - (0.5 - 2.0 * 0.1 * 0.3)).abs() < 1e-15);
        let s = standard_from_barycentric(&b);
        assert!((s.mass - 2.0).abs() < 1e-15);
        for (x, y) in s.com.iter().zip([0.1, -0.2, 0.3]) {
            assert!((x - y).abs() < 1e-15);
        }
        for (x, y) in s.inertia_com.iter().zip([1.0, 0.4, 0.5, 2.0, 0.6, 3.0]) {
            assert!((x - y).abs() < 1e-14);
        }
    }

    #[test]
    fn transform_equals_the_standard_parallel_axis_theorem() {
        // A body of mass 2, centre of mass c, inertia I_C about it; moved by (R, t) its
        // centre of mass is R·c + t and its inertia about it R·I_C·Rᵀ.
        let (m, c, ic) = (2.0, [0.1, -0.2, 0.3], [1.0, 0.4, 0.5, 2.0, 0.6, 3.0]);
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
        let t = Vector3::new(0.5, 0.7, -0.4);
        let moved = transform_barycentric(&r, &t, &barycentric_from_standard(m, c, ic));
        let c2 = r * Vector3::from(c) + t;
        let ic2 = sym6(&(r * sym3(&ic) * r.transpose()));
        let expect = barycentric_from_standard(m, [c2[0], c2[1], c2[2]], ic2);
        for (a, b) in moved.iter().zip(expect) {
            assert!((a - b).abs() < 1e-14, "{moved:?} {expect:?}");
        }
    }

    #[test]
    fn pseudo_inertia_detects_triangle_violation() {
        // A solid box is consistent.
        let (m, a, b, c) = (1.0, 0.1, 0.2, 0.3);
        let ixx = m * (b * b + c * c) / 12.0;
        let iyy = m * (a * a + c * c) / 12.0;
        let izz = m * (a * a + b * b) / 12.0;
        let p = barycentric_from_standard(m, [0.0; 3], [ixx, 0.0, 0.0, iyy, 0.0, izz]);
        assert!(pseudo_inertia_min_eigenvalue(&p) > 0.0);
        // Izz > Ixx + Iyy violates the triangle inequality: no density realizes it.
        let p = barycentric_from_standard(m, [0.0; 3], [ixx, 0.0, 0.0, iyy, 0.0, ixx + iyy + 0.01]);
        assert!(pseudo_inertia_min_eigenvalue(&p) < 0.0);
    }
}
