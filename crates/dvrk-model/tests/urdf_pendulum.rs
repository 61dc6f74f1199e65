//! Analytic check of the URDF import: a single revolute pendulum about an arbitrary axis,
//! with a point-mass-like link (mass m at perpendicular distance l from the axis, small
//! rotated inertia about the centre of mass):
//! `tau = (I_n + m l²) q̈ + m g l sin(q)` for a horizontal axis with the mass hanging below
//! it at q = 0, and the corresponding sinusoid for a tilted axis. `I_n = nᵀ I_C n` with
//! `I_C` rotated by the inertial's rpy; no velocity term (rotation about a fixed axis).

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_model::{Model, Workspace};
use nalgebra::{Matrix3, Vector3};

const G: f64 = 9.81;

fn rpy(r: [f64; 3]) -> Matrix3<f64> {
    let (sr, cr) = r[0].sin_cos();
    let (sp, cp) = r[1].sin_cos();
    let (sy, cy) = r[2].sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rz = Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    rz * ry * rx
}

struct Pendulum {
    /// joint origin rpy
    origin_rpy: [f64; 3],
    /// axis in the joint frame, not normalized
    axis: [f64; 3],
    mass: f64,
    /// centre of mass in the link frame
    com: [f64; 3],
    inertial_rpy: [f64; 3],
    /// ixx ixy ixz iyy iyz izz about the centre of mass, inertial frame
    inertia: [f64; 6],
}

impl Pendulum {
    fn urdf(&self) -> String {
        let (o, a, c, r, i) = (
            self.origin_rpy,
            self.axis,
            self.com,
            self.inertial_rpy,
            self.inertia,
        );
        format!(
            r#"<?xml version="1.0"?>
<robot name="pendulum">
  <link name="world"/>
  <link name="bob">
    <inertial>
      <origin xyz="{} {} {}" rpy="{} {} {}"/>
      <mass value="{}"/>
      <inertia ixx="{}" ixy="{}" ixz="{}" iyy="{}" iyz="{}" izz="{}"/>
    </inertial>
  </link>
  <joint name="swing" type="revolute">
    <origin xyz="0.1 -0.2 1.5" rpy="{} {} {}"/>
    <parent link="world"/>
    <child link="bob"/>
    <axis xyz="{} {} {}"/>
    <limit lower="-3.14" upper="3.14" velocity="5" effort="50"/>
  </joint>
</robot>"#,
            c[0],
            c[1],
            c[2],
            r[0],
            r[1],
            r[2],
            self.mass,
            i[0],
            i[1],
            i[2],
            i[3],
            i[4],
            i[5],
            o[0],
            o[1],
            o[2],
            a[0],
            a[1],
            a[2]
        )
    }

    /// (moment of inertia about the axis, gravity torque at q) from the closed form.
    fn analytic(&self, q: f64) -> (f64, f64) {
        let n = Vector3::from(self.axis).normalize();
        let c = Vector3::from(self.com);
        // Perpendicular part of the centre of mass: distance l, and its quarter-turn.
        let u = c - n * n.dot(&c);
        let l = u.norm();
        let i = self.inertia;
        let ic = Matrix3::new(i[0], i[1], i[2], i[1], i[3], i[4], i[2], i[4], i[5]);
        let ri = rpy(self.inertial_rpy);
        let i_n = n.dot(&(ri * ic * ri.transpose() * n));
        // Height of the centre of mass: r(q) = R_o (c_axial + u cos q + (n × u) sin q);
        // V = m g r_z, tau_g = dV/dq.
        let ro = rpy(self.origin_rpy);
        let dr = ro * (-u * q.sin() + n.cross(&u) * q.cos());
        (i_n + self.mass * l * l, self.mass * G * dr[2])
    }
}

fn check(p: &Pendulum, closed_form: impl Fn(f64, f64) -> f64) {
    let model = Model::from_urdf_str(&p.urdf(), "pendulum.urdf").unwrap();
    assert_eq!(model.dof(), 1);
    let pi = model.nominal_parameters().unwrap();
    let mut ws = Workspace::new(&model);
    let mut worst = 0.0f64;
    for (q, dq, ddq) in [
        (0.0, 0.0, 0.0),
        (0.3, 0.0, 0.0),
        (-1.2, 2.5, 0.0),
        (2.0, -1.0, 3.0),
        (0.7, 4.0, -6.0),
    ] {
        let (inertia, gravity) = p.analytic(q);
        let expected = inertia * ddq + gravity;
        // The closed form as the caller writes it (e.g. m g l sin q) agrees with the
        // vector form above.
        let written = closed_form(q, ddq);
        assert!(
            (written - expected).abs() < 1e-12,
            "closed forms disagree: {written} vs {expected}"
        );
        let mut tau = [0.0];
        model.inverse_dynamics(&mut ws, &pi, &[q], &[dq], &[ddq], &mut tau);
        worst = worst.max((tau[0] - expected).abs());
        assert!(
            (tau[0] - expected).abs() < 1e-12,
            "q={q} dq={dq} ddq={ddq}: ours {} analytic {expected}",
            tau[0]
        );
        let mut g = [0.0];
        model.gravity_torque(&mut ws, &pi, &[q], &mut g);
        assert!(
            (g[0] - gravity).abs() < 1e-12,
            "gravity at q={q}: ours {} analytic {gravity}",
            g[0]
        );
        let m = model.mass_matrix(&mut ws, &pi, &[q]);
        assert!(
            (m[(0, 0)] - inertia).abs() < 1e-13,
            "mass matrix: ours {} analytic {inertia}",
            m[(0, 0)]
        );
    }
    eprintln!(
        "pendulum about {:?}: max |tau - analytic| = {worst:e}",
        p.axis
    );
}

/// Horizontal skew axis, mass hanging l below it: tau = (I_n + m l²) q̈ + m g l sin q.
#[test]
fn horizontal_pendulum() {
    let (m, l) = (1.7, 0.45);
    let n = Vector3::new(1.0, 2.0, 0.0).normalize();
    let p = Pendulum {
        origin_rpy: [0.0; 3],
        axis: [1.0, 2.0, 0.0],
        mass: m,
        com: [0.0, 0.0, -l],
        inertial_rpy: [0.2, 0.5, -0.3],
        inertia: [2e-4, 1e-5, -2e-5, 3e-4, 3e-5, 2.5e-4],
    };
    let ri = rpy(p.inertial_rpy);
    let i = p.inertia;
    let ic = Matrix3::new(i[0], i[1], i[2], i[1], i[3], i[4], i[2], i[4], i[5]);
    let i_n = n.dot(&(ri * ic * ri.transpose() * n));
    check(&p, |q, ddq| (i_n + m * l * l) * ddq + m * G * l * q.sin());
}

/// Axis (0 1 0), the mass 0.3 m along x: the classic pendulum released horizontally,
/// tau = (I + m l²) q̈ + m g l cos q (about +y, +q lowers the mass).
#[test]
fn pendulum_about_y() {
    let (m, l, iyy) = (0.8, 0.3, 1e-3);
    let p = Pendulum {
        origin_rpy: [0.0; 3],
        axis: [0.0, 1.0, 0.0],
        mass: m,
        com: [l, 0.0, 0.0],
        inertial_rpy: [0.0; 3],
        inertia: [5e-4, 0.0, 0.0, iyy, 0.0, 7e-4],
    };
    // Rotating x about y by q gives (cos q, 0, −sin q): the height is −l sin q,
    // V = −m g l sin q and tau_g = −m g l cos q.
    check(&p, |q, ddq| (iyy + m * l * l) * ddq - m * G * l * q.cos());
}

/// A tilted skew axis after a rotated joint origin, the centre of mass with an axial
/// component (which changes nothing): the vector closed form.
#[test]
fn tilted_pendulum() {
    let n = Vector3::new(1.0, -2.0, 3.0).normalize();
    let u = n.cross(&Vector3::new(0.3, -1.0, 0.5)).normalize();
    let com = u * 0.35 + n * 0.12;
    let p = Pendulum {
        origin_rpy: [0.4, -0.2, 0.9],
        axis: [1.0, -2.0, 3.0],
        mass: 2.2,
        com: [com[0], com[1], com[2]],
        inertial_rpy: [-0.6, 0.1, 1.3],
        inertia: [3e-3, 2e-4, -1e-4, 4e-3, 3e-4, 5e-3],
    };
    // The height of the centre of mass is const + l·(R_o(n × u))_z·sin q + l·(R_o u)_z·cos q,
    // so the gravity torque is m g (a cos q + b sin q), i.e. m g l sin(tilt) sin(q + φ).
    let ro = rpy(p.origin_rpy);
    let (a, b) = ((ro * n.cross(&(u * 0.35)))[2], (ro * (-u * 0.35))[2]);
    let (inertia, _) = p.analytic(0.0);
    check(&p, |q, ddq| {
        inertia * ddq + 2.2 * G * (a * q.cos() + b * q.sin())
    });
}
