//! Conversions between the barycentric link parameters used by the regressor and the
//! standard (centre-of-mass) form people read, and the pseudo-inertia matrix whose
//! positive definiteness is the physical-consistency condition.

use nalgebra::{Matrix3, Matrix4, Vector3};

use crate::input::{self, InputError};

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
    // Written out on the arrays with the rows 0 and 1 of a column of R (or of a
    // 3-vector) in the two lanes of an f64x2, row 2 apart: `R·L·Rᵀ` as `v_j = L·r_j`
    // (`r_j` row j of R), then `r_i·v_j`, its diagonal and off-diagonal pairs taken
    // lane by lane (no broadcast), a third of nalgebra's generic products'
    // instructions; this runs for every body in every mass matrix.
    use wide::f64x2;
    let r = &rotation.data.0; // r[column][row]
    let sp = f64x2::splat;
    let lanes = |v: &[f64; 3]| f64x2::new([v[0], v[1]]);
    let swap = |v: f64x2| {
        let [a, b] = v.to_array();
        f64x2::new([b, a])
    };
    let c = [lanes(&r[0]), lanes(&r[1]), lanes(&r[2])];
    let row2 = [r[0][2], r[1][2], r[2][2]];
    let dot_z = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let l = [[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]];
    // (v_0k, v_1k) = Σ_l L_kl·(R_0l, R_1l), and v_2k.
    let v01 = l.map(|lk| sp(lk[0]) * c[0] + sp(lk[1]) * c[1] + sp(lk[2]) * c[2]);
    let v2 = l.map(|lk| dot_z(&lk, &row2));
    // (B_00, B_11), (B_10, B_01), (B_02, B_12) and B_22 of B = R·L·Rᵀ.
    let diag = c[0] * v01[0] + c[1] * v01[1] + c[2] * v01[2];
    let off = swap(c[0]) * v01[0] + swap(c[1]) * v01[1] + swap(c[2]) * v01[2];
    let col2 = c[0] * sp(v2[0]) + c[1] * sp(v2[1]) + c[2] * sp(v2[2]);
    let b22 = dot_z(&row2, &v2);
    // u = R·l, h' = u + m·t, d = t·(h' + u).
    let m = p[9];
    let u01 = c[0] * sp(p[6]) + c[1] * sp(p[7]) + c[2] * sp(p[8]);
    let u2 = dot_z(&row2, &[p[6], p[7], p[8]]);
    let t01 = f64x2::new([translation[0], translation[1]]);
    let t2 = translation[2];
    let h01 = u01 + sp(m) * t01;
    let h2 = u2 + m * t2;
    let [d0, d1] = (t01 * (h01 + u01)).to_array();
    let d = d0 + d1 + t2 * (h2 + u2);
    // L' = B + d·I − (t·h'ᵀ + u·tᵀ), pair by pair as B.
    let [l00, l11] = (diag - (t01 * h01 + u01 * t01) + sp(d)).to_array();
    let [l01, _] = (off - (t01 * swap(h01) + u01 * swap(t01))).to_array();
    let [l02, l12] = (col2 - (t01 * sp(h2) + u01 * sp(t2))).to_array();
    let l22 = b22 - (t2 * h2 + u2 * t2) + d;
    let [h0, h1] = h01.to_array();
    [l00, l01, l02, l11, l12, l22, h0, h1, h2, m]
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

/// Rotation matrix of URDF's fixed-axis roll, pitch, yaw (rad): `Rz(yaw)·Ry(pitch)·Rx(roll)`.
pub fn rotation_rpy(rpy: &[f64; 3]) -> Matrix3<f64> {
    *nalgebra::Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]).matrix()
}

/// A solid ellipsoid in a link's frame, `{x : (x − c)ᵀ·R·diag(1/a²)·Rᵀ·(x − c) ≤ 1}`:
/// a region the link's mass must lie in (its bounding ellipsoid). Centre `c` and semi-axes
/// `a` in m, the axes rotated by `R = rotation_rpy(rpy)` from the frame's.
///
/// A link whose mass lies inside the ellipsoid has `tr(Q·J) ≥ 0` for its pseudo-inertia
/// `J` ([`pseudo_inertia`]) and `Q = `[`Ellipsoid::q_matrix`] (Wensing, Kim & Slotine,
/// "Linear Matrix Inequalities for Physically Consistent Inertial Parameter
/// Identification: A Statistical Perspective on the Mass Distribution", RA-L 2018): for a
/// point mass `m` at `x`, `tr(Q·J) = m·(1 − (x − c)ᵀ·A·(x − c))`, and `J` is a sum (an
/// integral) of those; with `J ⪰ 0` the two are the paper's density realizability
/// condition for the ellipsoid.
///
/// ```
/// use dvrk_model::inertia::{barycentric_from_standard, pseudo_inertia, Ellipsoid};
/// let e = Ellipsoid { center: [0.1, 0.0, 0.0], semi_axes: [0.2, 0.05, 0.05], rpy: [0.0; 3] };
/// // 1 kg at x = 0.25 m (inside) and at x = 0.35 m (outside).
/// let inside = pseudo_inertia(&barycentric_from_standard(1.0, [0.25, 0.0, 0.0], [0.0; 6]));
/// let outside = pseudo_inertia(&barycentric_from_standard(1.0, [0.35, 0.0, 0.0], [0.0; 6]));
/// assert!((e.q_matrix() * inside).trace() > 0.0);
/// assert!((e.q_matrix() * outside).trace() < 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Deserialize, serde::Serialize),
    serde(deny_unknown_fields)
)]
pub struct Ellipsoid {
    /// Centre in the link frame (m).
    pub center: [f64; 3],
    /// Semi-axes along the ellipsoid's own axes (m), each positive.
    pub semi_axes: [f64; 3],
    /// Roll, pitch, yaw of the ellipsoid's axes in the link frame (rad, URDF convention,
    /// [`rotation_rpy`]); zero: the frame's axes.
    #[cfg_attr(feature = "serde", serde(default))]
    pub rpy: [f64; 3],
}

impl Ellipsoid {
    /// The ellipsoid of least volume enclosing the box of centre `center` and half sides
    /// `half` (m) along the axes rotated by `rpy`: semi-axes `√3·half` (by symmetry
    /// its axes are the box's, and among those the volume `∏ aᵢ` under the corner
    /// constraint `Σ hᵢ²/aᵢ² = 1` is least at equal terms).
    pub fn around_box(center: [f64; 3], half: [f64; 3], rpy: [f64; 3]) -> Ellipsoid {
        Ellipsoid {
            center,
            semi_axes: half.map(|h| 3f64.sqrt() * h),
            rpy,
        }
    }

    /// The ellipsoid of least volume enclosing a solid cylinder of radius `radius` and
    /// length `length` (m) along the z axis rotated by `rpy`, centred at `center`: semi-axes
    /// `√(3/2)·radius` across and `√3·length/2` along (the rim circles on the surface,
    /// `r²/a² + h²/b² = 1`, and `a²·b` least at `r²/a² = 2/3`).
    pub fn around_cylinder(center: [f64; 3], radius: f64, length: f64, rpy: [f64; 3]) -> Ellipsoid {
        let across = 1.5f64.sqrt() * radius;
        Ellipsoid {
            center,
            semi_axes: [across, across, 3f64.sqrt() * 0.5 * length],
            rpy,
        }
    }

    /// Finite centre and angles within the accepted magnitudes, positive finite semi-axes;
    /// the error names the field.
    pub fn check(&self) -> Result<(), InputError> {
        for (field, values, max) in [
            ("center", self.center, input::MAX_LENGTH_M),
            ("rpy", self.rpy, input::MAX_ANGLE_RAD),
        ] {
            for v in values {
                input::check_magnitude(v, max, "").map_err(|e| e.of(field))?;
            }
        }
        for a in self.semi_axes {
            if !(a.is_finite() && a > 0.0 && a <= input::MAX_LENGTH_M) {
                return Err(InputError::SemiAxis { value: a });
            }
        }
        Ok(())
    }

    /// `A = R·diag(1/a²)·Rᵀ` (1/m²): the ellipsoid is `(x − c)ᵀ·A·(x − c) ≤ 1`.
    pub fn shape(&self) -> Matrix3<f64> {
        let r = rotation_rpy(&self.rpy);
        let d = Matrix3::from_diagonal(&Vector3::from(self.semi_axes.map(|a| 1.0 / (a * a))));
        r * d * r.transpose()
    }

    /// Whether the point `x` (m, link frame) lies in the closed ellipsoid.
    pub fn contains(&self, x: [f64; 3]) -> bool {
        let d = Vector3::from(x) - Vector3::from(self.center);
        (d.transpose() * self.shape() * d)[0] <= 1.0
    }

    /// `Q = [[−A, A·c], [cᵀ·A, 1 − cᵀ·A·c]]`, so that `[x; 1]ᵀ·Q·[x; 1] =
    /// 1 − (x − c)ᵀ·A·(x − c)` and the mass lies inside only if `tr(Q·J) ≥ 0` (see
    /// [`Ellipsoid`]).
    pub fn q_matrix(&self) -> Matrix4<f64> {
        let a = self.shape();
        let c = Vector3::from(self.center);
        let ac = a * c;
        let mut q = Matrix4::zeros();
        q.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-a));
        for k in 0..3 {
            q[(k, 3)] = ac[k];
            q[(3, k)] = ac[k];
        }
        q[(3, 3)] = 1.0 - c.dot(&ac);
        q
    }

    /// `tr(Q·J(π))` as coefficients of the 10 barycentric parameters
    /// `[Lxx, Lxy, Lxz, Lyy, Lyz, Lzz, lx, ly, lz, m]` (the constraint is linear in them).
    pub fn barycentric_coefficients(&self) -> [f64; 10] {
        let q = self.q_matrix();
        std::array::from_fn(|k| {
            let mut e = [0.0; 10];
            e[k] = 1.0;
            (q * pseudo_inertia(&e)).trace()
        })
    }
}

/// Checks that mass (kg), centre of mass (m) and inertia about the centre of mass
/// `[xx, xy, xz, yy, yz, zz]` (kg·m²) describe a rigid body: finite and within range,
/// mass ≥ 0, principal moments ≥ 0 and each at most the sum of the other two (the
/// triangle inequality: no mass distribution has others). Moments are compared with a
/// relative tolerance of 1e-6 so that inertias rounded to a few digits (CAD exports)
/// pass. The error names the broken condition.
pub fn check_rigid_body(mass: f64, com: [f64; 3], inertia_com: [f64; 6]) -> Result<(), InputError> {
    input::check_magnitude(mass, input::MAX_MASS_KG, "kg").map_err(|e| e.of("mass"))?;
    if mass < 0.0 {
        return Err(InputError::NegativeMass { mass });
    }
    for c in com {
        input::check_magnitude(c, input::MAX_LENGTH_M, "m").map_err(|e| e.of("centre of mass"))?;
    }
    for i in inertia_com {
        input::check_magnitude(i, input::MAX_VALUE, "kg·m²").map_err(|e| e.of("inertia"))?;
    }
    let mut moments: Vec<f64> = sym3(&inertia_com)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    moments.sort_by(f64::total_cmp);
    let moments = [moments[0], moments[1], moments[2]];
    let tol = 1e-6 * moments[2].abs().max(f64::MIN_POSITIVE);
    if moments[0] < -tol {
        return Err(InputError::NegativeMoment { moments });
    }
    if moments[2] > moments[0] + moments[1] + tol {
        return Err(InputError::TriangleInequality { moments });
    }
    Ok(())
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

    #[test]
    fn rigid_bodies() {
        // A uniform box 0.1 × 0.2 × 0.3 m of 2 kg: I = m/12 (b² + c², ...).
        let m = 2.0;
        let (a, b, c): (f64, f64, f64) = (0.1, 0.2, 0.3);
        let i = [
            m / 12.0 * (b * b + c * c),
            0.0,
            0.0,
            m / 12.0 * (a * a + c * c),
            0.0,
            m / 12.0 * (a * a + b * b),
        ];
        check_rigid_body(m, [0.0, 0.1, 0.0], i).unwrap();
        // A thin rod (one moment zero, the other two equal) and a massless link.
        check_rigid_body(1.0, [0.0; 3], [0.1, 0.0, 0.0, 0.1, 0.0, 0.0]).unwrap();
        check_rigid_body(0.0, [0.0; 3], [0.0; 6]).unwrap();
        // ixx < 0, and a triangle inequality broken (3 > 1 + 1).
        let e = check_rigid_body(1.0, [0.0; 3], [-0.1, 0.0, 0.0, 0.1, 0.0, 0.1]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "inertia about the centre of mass has a negative principal moment (-0.1, 0.1, \
             0.1 kg·m²): no rigid body has it"
        );
        let e = check_rigid_body(1.0, [0.0; 3], [1.0, 0.0, 0.0, 1.0, 0.0, 3.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "principal moments 1, 1, 3 kg·m² break the triangle inequality (the largest \
             exceeds the sum of the other two): no rigid body has them"
        );
        // Rotated: the products of inertia count (eigenvalues 3, 1, -1).
        let e = check_rigid_body(1.0, [0.0; 3], [1.0, 2.0, 0.0, 1.0, 0.0, 1.0]).unwrap_err();
        let InputError::NegativeMoment { moments } = e else {
            panic!("{e:?}")
        };
        for (m, want) in moments.iter().zip([-1.0, 1.0, 3.0]) {
            assert!((m - want).abs() < 1e-12, "{moments:?}");
        }
        let e = check_rigid_body(-1.0, [0.0; 3], [0.0; 6]).unwrap_err();
        assert_eq!(e, InputError::NegativeMass { mass: -1.0 });
        assert_eq!(e.to_string(), "mass -1 kg: must be non-negative");
        let e = check_rigid_body(f64::NAN, [0.0; 3], [0.0; 6]).unwrap_err();
        assert_eq!(e.to_string(), "mass: must be a finite number, got NaN");
        let e = check_rigid_body(1e299, [0.0; 3], [0.0; 6]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "mass: 1e299 kg is beyond the accepted ±1e6 kg"
        );
        let e = check_rigid_body(1.0, [0.0, 2e3, 0.0], [0.0; 6]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "centre of mass: 2000 m is beyond the accepted ±1e3 m"
        );
    }
}
