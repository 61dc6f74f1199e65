//! The dVRK controller's own kinematics and gravity compensation, transcribed from
//! jhu-cisst/cisst (cisstRobot) independently of dvrk-model, so that tests compare our
//! models and exports with what the controller computes:
//!
//! - [`Link`]: one entry of a DH JSON file as `robLink::Read` / `robModifiedDH::ReadParameters`
//!   / `robJoint::Read` / `robMass::ReadMass` read it (`alpha`, `A`, `theta`, `D`, `type`,
//!   `offset`, `mass`, `cx cy cz`; an `alpha` of exactly ±1.5708 becomes ±π/2);
//! - [`forward_kinematics`]: `robModifiedDH::ForwardKinematics` chained from the base;
//! - [`ccg_mdh`]: `robManipulator::CCG_MDH(q, 0, g)`, i.e. `RNE_MDH` at zero velocity and
//!   acceleration, where `g` is the "up" vector the arm passes
//!   (`mtsIntuitiveResearchKitArm.cpp`: `(0, 9.81·sin p, 9.81·cos p)` at mounting pitch `p`);
//! - the controller's maps from the arm's joints to the physical links and back
//!   ([`psm_si_gc`], [`ecm_si_gc`], [`ecm_classic_gc`]: `GravityCompensationPSM::compute`,
//!   `GravityCompensationECM::compute`).

use nalgebra::{Matrix3, Matrix4, Vector3};

/// One link of a cisst DH file (modified convention).
#[derive(Clone, Debug)]
pub struct Link {
    /// rad (`alpha`); ±1.5708 is read as ±π/2, as cisst does
    pub alpha: f64,
    /// m (`A`)
    pub a: f64,
    /// rad (`theta`)
    pub theta: f64,
    /// m (`D`)
    pub d: f64,
    /// `revolute` or `prismatic`
    pub kind: String,
    /// rad or m, added to the joint value (`offset`, default 0)
    pub offset: f64,
    /// kg (`mass`, default 0)
    pub mass: f64,
    /// m, centre of mass in the link's frame (`cx`, default 0)
    pub cx: f64,
    /// m (`cy`)
    pub cy: f64,
    /// m (`cz`)
    pub cz: f64,
}

impl Link {
    /// A link from its DH numbers (no mass); `alpha` is rounded as cisst rounds it.
    pub fn new(alpha: f64, a: f64, theta: f64, d: f64, prismatic: bool, offset: f64) -> Link {
        Link {
            alpha,
            a,
            theta,
            d,
            kind: if prismatic { "prismatic" } else { "revolute" }.into(),
            offset,
            mass: 0.0,
            cx: 0.0,
            cy: 0.0,
            cz: 0.0,
        }
    }

    /// The same link with a point mass (kg) at `com` (m, link frame).
    pub fn with_mass(mut self, mass: f64, com: [f64; 3]) -> Link {
        self.mass = mass;
        [self.cx, self.cy, self.cz] = com;
        self
    }

    fn prismatic(&self) -> bool {
        self.kind.eq_ignore_ascii_case("prismatic") || self.kind.eq_ignore_ascii_case("slider")
    }

    /// `robModifiedDH::ReadParameters`: "just make sure we're accurate". The literal
    /// 1.5708 is what the dVRK's files write and cisst compares with, not π/2.
    #[allow(clippy::approx_constant)]
    fn alpha(&self) -> f64 {
        if self.alpha == 1.5708 {
            std::f64::consts::FRAC_PI_2
        } else if self.alpha == -1.5708 {
            -std::f64::consts::FRAC_PI_2
        } else {
            self.alpha
        }
    }

    /// `robModifiedDH::ForwardKinematics(q)`: parent → link transform.
    pub fn transform(&self, q: f64) -> Matrix4<f64> {
        let (mut theta, mut d) = (self.theta, self.d);
        if self.prismatic() {
            d += self.offset + q;
        } else {
            theta += self.offset + q;
        }
        let (ca, sa) = (self.alpha().cos(), self.alpha().sin());
        let (ct, st) = (theta.cos(), theta.sin());
        #[rustfmt::skip]
        let t = Matrix4::new(
            ct,      -st,      0.0, self.a,
            st * ca,  ct * ca, -sa, -sa * d,
            st * sa,  ct * sa,  ca,  ca * d,
            0.0,      0.0,     0.0,  1.0,
        );
        t
    }
}

/// The links of a DH JSON document (`{"DH": {"links"|"joints": [...]}}`, comments
/// removed), read field by field as `robLink::Read` does, absent numbers 0.
pub fn links_of(document: &serde_json::Value) -> Vec<Link> {
    let dh = &document["DH"];
    let list = dh
        .get("links")
        .or_else(|| dh.get("joints"))
        .expect("DH links");
    let num = |l: &serde_json::Value, k: &str| {
        l.get(k).and_then(serde_json::Value::as_f64).unwrap_or(0.0)
    };
    list.as_array()
        .expect("DH links array")
        .iter()
        .map(|l| Link {
            alpha: num(l, "alpha"),
            a: num(l, "A"),
            theta: num(l, "theta"),
            d: num(l, "D"),
            kind: l
                .get("type")
                .and_then(|t| t.as_str())
                .unwrap_or("revolute")
                .to_string(),
            offset: num(l, "offset"),
            mass: num(l, "mass"),
            cx: num(l, "cx"),
            cy: num(l, "cy"),
            cz: num(l, "cz"),
        })
        .collect()
}

/// Base → link `i` transforms, `i = 0..links.len()` (link 1 first).
pub fn forward_kinematics(links: &[Link], q: &[f64]) -> Vec<Matrix4<f64>> {
    assert_eq!(links.len(), q.len());
    let mut t = Matrix4::identity();
    links
        .iter()
        .zip(q)
        .map(|(l, &qi)| {
            t *= l.transform(qi);
            t
        })
        .collect()
}

/// `robManipulator::CCG_MDH(q, qd = 0, g)`: `RNE_MDH` with zero velocities and
/// accelerations, the base's linear acceleration `g` (the "up" vector, m/s²), no external
/// force, the base rotation identity. Returns one effort per link (N·m or N): the effort
/// that holds the arm against gravity.
pub fn ccg_mdh(links: &[Link], q: &[f64], g: [f64; 3]) -> Vec<f64> {
    let n = links.len();
    assert_eq!(n, q.len());
    let z0 = Vector3::z();
    let rot =
        |i: usize| -> Matrix3<f64> { links[i].transform(q[i]).fixed_view::<3, 3>(0, 0).into() };
    let pos =
        |i: usize| -> Vector3<f64> { links[i].transform(q[i]).fixed_view::<3, 1>(0, 3).into() };
    // Forward recursion: with w = wd = 0, vd_i = A_i·vd_{i-1} (A = rotation⁻¹) for both
    // joint types, and F_i = m_i·vd_i; N_i = 0.
    let mut vd = Vector3::from(g);
    let mut f_link = Vec::with_capacity(n);
    for (i, link) in links.iter().enumerate() {
        vd = rot(i).transpose() * vd;
        f_link.push(link.mass * vd);
    }
    // Backward recursion.
    let mut f = Vector3::zeros();
    let mut nm = Vector3::zeros();
    let mut tau = vec![0.0; n];
    for i in (0..n).rev() {
        let s = Vector3::new(links[i].cx, links[i].cy, links[i].cz);
        let (a, ps) = if i + 1 < n {
            (rot(i + 1), pos(i + 1))
        } else {
            (Matrix3::identity(), Vector3::zeros())
        };
        nm = a * nm + s.cross(&f_link[i]) + ps.cross(&(a * f));
        f = a * f + f_link[i];
        tau[i] = if links[i].prismatic() {
            f.dot(&z0)
        } else {
            nm.dot(&z0)
        };
    }
    tau
}

/// The "up" vector the dVRK passes to its gravity compensation at mounting pitch `p`
/// (rad): `(0, 9.81·sin p, 9.81·cos p)` (mtsIntuitiveResearchKitArm.cpp).
pub fn up_vector(pitch_rad: f64) -> [f64; 3] {
    [0.0, pitch_rad.sin() * 9.81, pitch_rad.cos() * 9.81]
}

/// `GravityCompensationPSM::compute`: the PSM Si's 7 physical links at joints
/// `[q1, 0, q2, −q2, q2, q3/2, q3/2]`, efforts back as `[e0, e2 − e3 + e4, e6]`.
pub fn psm_si_gc(links: &[Link], j: &[f64; 3], g: [f64; 3]) -> [f64; 3] {
    assert_eq!(links.len(), 7);
    let q = [j[0], 0.0, j[1], -j[1], j[1], 0.5 * j[2], 0.5 * j[2]];
    let e = ccg_mdh(links, &q, g);
    [e[0], e[2] - e[3] + e[4], e[6]]
}

/// `GravityCompensationECM::compute`, 6 links (Si): joints `[q1, 0, q2, −q2, q2, q3]`,
/// efforts `[e0, e2 − e3 + e4, e5]` and 0 for the roll.
pub fn ecm_si_gc(links: &[Link], j: &[f64; 4], g: [f64; 3]) -> [f64; 4] {
    assert_eq!(links.len(), 6);
    let q = [j[0], 0.0, j[1], -j[1], j[1], j[2]];
    let e = ccg_mdh(links, &q, g);
    [e[0], e[2] - e[3] + e[4], e[5], 0.0]
}

/// `GravityCompensationECM::compute`, 4 links (Classic): the virtual DH used as physical,
/// joints unchanged.
pub fn ecm_classic_gc(links: &[Link], j: &[f64; 4], g: [f64; 3]) -> [f64; 4] {
    assert_eq!(links.len(), 4);
    let e = ccg_mdh(links, j, g);
    [e[0], e[1], e[2], e[3]]
}
