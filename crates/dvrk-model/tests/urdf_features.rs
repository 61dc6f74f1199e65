//! URDF features on small hand-written documents: prismatic, continuous, fixed and mimic
//! joints, axes not along z, rotated inertials, the rpy convention, limits, and the
//! error messages (which must name the file and the problem).

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_model::inertia::{sym3, sym6};
use dvrk_model::{JointKind, Model, Transform, Workspace};
use dvrk_test_support::PlanarTwoLink;
use nalgebra::{Matrix3, Vector3};

const G: f64 = 9.81;

/// URDF `rpy`: fixed axes x, y, z, i.e. `Rz(yaw)·Ry(pitch)·Rx(roll)`, written out.
fn rpy(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    let (sr, cr) = r.sin_cos();
    let (sp, cp) = p.sin_cos();
    let (sy, cy) = y.sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rz = Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    rz * ry * rx
}

/// Rotation by `angle` about `axis` (normalized here), Rodrigues' formula.
fn rot(axis: [f64; 3], angle: f64) -> Matrix3<f64> {
    let n = Vector3::from(axis).normalize();
    let k = Matrix3::new(0.0, -n[2], n[1], n[2], 0.0, -n[0], -n[1], n[0], 0.0);
    Matrix3::identity() + angle.sin() * k + (1.0 - angle.cos()) * k * k
}

fn close_m(a: &Matrix3<f64>, b: &Matrix3<f64>, tol: f64, what: &str) {
    let d = (a - b).abs().max();
    assert!(d < tol, "{what}: difference {d:e}\nours {a}\nexpected {b}");
}

fn close_v(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64, what: &str) {
    let d = (a - b).abs().max();
    assert!(
        d < tol,
        "{what}: difference {d:e}: ours {a:?} expected {b:?}"
    );
}

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() < tol * (1.0 + b.abs()),
        "{what}: ours {a} expected {b}"
    );
}

fn link(name: &str, mass: f64, xyz: [f64; 3], rpy: [f64; 3], i: [f64; 6]) -> String {
    format!(
        r#"<link name="{name}"><inertial>
             <origin xyz="{} {} {}" rpy="{} {} {}"/>
             <mass value="{mass}"/>
             <inertia ixx="{}" ixy="{}" ixz="{}" iyy="{}" iyz="{}" izz="{}"/>
           </inertial></link>"#,
        xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2], i[0], i[1], i[2], i[3], i[4], i[5]
    )
}

/// A `<joint>` of `kind` from `parent` to `child` at the origin `xyz` (m) and `rpy`
/// (rad), about `axis` (`None`: URDF's default, x), with the `inner` elements (`<limit>`,
/// `<mimic>`).
fn joint(
    name: &str,
    kind: &str,
    (parent, child): (&str, &str),
    (xyz, rpy): ([f64; 3], [f64; 3]),
    axis: Option<[f64; 3]>,
    inner: &str,
) -> String {
    let axis = axis.map_or(String::new(), |a| {
        format!(r#"<axis xyz="{} {} {}"/>"#, a[0], a[1], a[2])
    });
    format!(
        r#"<joint name="{name}" type="{kind}">
             <origin xyz="{} {} {}" rpy="{} {} {}"/>
             <parent link="{parent}"/><child link="{child}"/>{axis}{inner}
           </joint>"#,
        xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
    )
}

/// A `<robot>` document: a root link `base`, then `parts` (links and joints).
fn robot(name: &str, parts: &[String]) -> String {
    format!(
        r#"<robot name="{name}"><link name="base"/>{}</robot>"#,
        parts.concat()
    )
}

/// The `<limit>` of position [-1, 1] and velocity and effort 1 of the chains' joints.
const UNIT_LIMIT: &str = r#"<limit lower="-1" upper="1" velocity="1" effort="1"/>"#;

/// Asserts a pose's rotation and translation (m), each to `tol`.
fn close_pose(
    pose: &Transform,
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
    tol: f64,
    what: &str,
) {
    close_m(&pose.rotation, rotation, tol, &format!("{what} rotation"));
    close_v(
        &pose.translation,
        translation,
        tol,
        &format!("{what} translation"),
    );
}

fn frame(model: &Model, name: &str) -> usize {
    model
        .frame_names()
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no frame {name}"))
}

fn torque(model: &Model, q: &[f64], dq: &[f64], ddq: &[f64]) -> Vec<f64> {
    let pi = model.nominal_parameters().unwrap();
    let mut ws = Workspace::new(model);
    let mut tau = vec![0.0; model.dof()];
    model.inverse_dynamics(&mut ws, &pi, q, dq, ddq, &mut tau);
    // The regressor agrees with the inverse dynamics.
    let h = model.regressor(&mut ws, q, dq, ddq);
    for (r, t) in tau.iter().enumerate() {
        let hp: f64 = (0..model.n_params()).map(|c| h[(r, c)] * pi[c]).sum();
        close(hp, *t, 1e-12, "H·π vs inverse dynamics");
    }
    tau
}

#[test]
fn prismatic_joint() {
    let text = robot(
        "slider",
        &[
            link(
                "carriage",
                2.5,
                [0.1, -0.2, 0.05],
                [0.3, 0.2, 0.1],
                [0.1, 0.01, 0.02, 0.2, 0.03, 0.25],
            ),
            joint(
                "slide",
                "prismatic",
                ("base", "carriage"),
                ([0.5, 0.0, 0.2], [0.0, 0.0, 0.3]),
                Some([0.0, 3.0, 4.0]),
                r#"<limit lower="-0.1" upper="0.25" velocity="0.5" effort="100"/>"#,
            ),
        ],
    );
    let model = Model::from_urdf_str(&text, "slider.urdf").unwrap();
    assert_eq!(model.coordinates, ["slide"]);
    assert_eq!(model.coordinate_is_length, [true]);
    assert_eq!(model.frame(1).kind, JointKind::Prismatic);
    // The axis is normalized: (0, 0.6, 0.8) in the joint-origin frame.
    let axis = rpy(0.0, 0.0, 0.3) * Vector3::new(0.0, 0.6, 0.8);
    for q in [-0.1, 0.0, 0.17] {
        let poses = model.frame_poses(&[q]);
        close_pose(
            &poses[1],
            &rpy(0.0, 0.0, 0.3),
            &(Vector3::new(0.5, 0.0, 0.2) + q * axis),
            1e-15,
            "slide",
        );
    }
    // Pure translation: tau = m (ddq − g·axis), g = −9.81 z; nothing else matters.
    for (q, dq, ddq) in [(0.1, 0.0, 0.0), (-0.05, 0.7, -1.3), (0.2, -2.0, 3.0)] {
        let tau = torque(&model, &[q], &[dq], &[ddq]);
        close(tau[0], 2.5 * (ddq + G * 0.8), 1e-14, "prismatic torque");
    }
    let mut ws = Workspace::new(&model);
    let m = model.mass_matrix(&mut ws, &model.nominal_parameters().unwrap(), &[0.0]);
    close(m[(0, 0)], 2.5, 1e-14, "prismatic mass");
    assert_eq!(model.limits.len(), 1);
    assert_eq!(model.limits[0].position, Some([-0.1, 0.25]));
    assert_eq!(model.limits[0].velocity, Some([-0.5, 0.5]));
    assert_eq!(model.limits[0].acceleration, None);
}

#[test]
fn continuous_joint() {
    let text = robot(
        "wheel",
        &[
            link(
                "wheel",
                1.0,
                [0.0, 0.0, -0.5],
                [0.0; 3],
                [0.01, 0.0, 0.0, 0.01, 0.0, 0.01],
            ),
            link("wheel2", 0.0, [0.0; 3], [0.0; 3], [0.0; 6]),
            joint(
                "spin",
                "continuous",
                ("base", "wheel"),
                ([0.0, 0.0, 1.0], [0.0; 3]),
                Some([1.0, 0.0, 0.0]),
                r#"<limit velocity="6" effort="1"/>"#,
            ),
            joint(
                "free",
                "continuous",
                ("wheel", "wheel2"),
                ([0.0; 3], [0.0; 3]),
                Some([0.0, 0.0, 1.0]),
                "",
            ),
        ],
    );
    let model = Model::from_urdf_str(&text, "wheel.urdf").unwrap();
    assert_eq!(model.coordinates, ["spin", "free"]);
    assert_eq!(model.coordinate_is_length, [false, false]);
    assert_eq!(model.frame(1).kind, JointKind::Revolute);
    // No position limit; the velocity limit is kept; no <limit> at all gives no limit.
    assert_eq!(model.limits.len(), 1);
    assert_eq!(model.limits[0].label, "spin");
    assert_eq!(model.limits[0].position, None);
    assert_eq!(model.limits[0].velocity, Some([-6.0, 6.0]));
    // Any angle, several turns.
    let a = model.frame_poses(&[0.4, 0.0]);
    let b = model.frame_poses(&[0.4 + 6.0 * std::f64::consts::PI, 0.0]);
    close_m(&a[1].rotation, &b[1].rotation, 1e-14, "periodic");
    close_m(
        &a[1].rotation,
        &rot([1.0, 0.0, 0.0], 0.4),
        1e-15,
        "rotation about x",
    );
    // A pendulum hanging 0.5 m below the axis x: tau = (I + m l²) ddq + m g l sin q.
    for (q, dq, ddq) in [(0.3, 1.0, -2.0), (10.0, -3.0, 0.5)] {
        let tau = torque(&model, &[q, 0.0], &[dq, 0.0], &[ddq, 0.0]);
        close(
            tau[0],
            (0.01 + 0.25) * ddq + G * 0.5 * q.sin(),
            1e-13,
            "continuous pendulum",
        );
    }
}

/// A fixed joint in the middle of a chain: its child link moves with the parent and
/// gives the same torques as the two links merged into one in the parent's frame.
#[test]
fn fixed_joint() {
    let (ma, ca, ia) = (
        1.2,
        [0.1, 0.02, -0.03],
        [0.02, 0.001, -0.002, 0.03, 0.003, 0.025],
    );
    let (mb, cb, ib) = (
        0.7,
        [0.05, -0.04, 0.06],
        [0.01, -0.001, 0.0015, 0.012, 0.002, 0.009],
    );
    let (mc, cc, ic) = (0.4, [0.0, 0.1, 0.02], [0.004, 0.0, 0.0, 0.003, 0.0, 0.005]);
    let (p, r) = ([0.3, 0.05, -0.1], [0.3, -0.5, 0.7]);
    let j2 = [0.02, 0.1, 0.0];
    // j1 about y at 0.4 m above the base, j2 about x: the chain with and without b.
    let j1 = joint(
        "j1",
        "revolute",
        ("base", "a"),
        ([0.0, 0.0, 0.4], [0.0; 3]),
        Some([0.0, 1.0, 0.0]),
        UNIT_LIMIT,
    );
    let j2_from = |parent: &str, origin: ([f64; 3], [f64; 3])| {
        joint(
            "j2",
            "revolute",
            (parent, "c"),
            origin,
            Some([1.0, 0.0, 0.0]),
            UNIT_LIMIT,
        )
    };
    let link_c = link("c", mc, cc, [0.0; 3], ic);
    let with_fixed = robot(
        "chain",
        &[
            link("a", ma, ca, [0.0; 3], ia),
            link("b", mb, cb, [0.0; 3], ib),
            link_c.clone(),
            j1.clone(),
            joint("bolt", "fixed", ("a", "b"), (p, r), None, ""),
            j2_from("b", (j2, [0.0; 3])),
        ],
    );
    let model = Model::from_urdf_str(&with_fixed, "chain.urdf").unwrap();
    assert_eq!(model.coordinates, ["j1", "j2"]);
    assert_eq!(model.frames.len(), 3);
    assert_eq!(model.n_params(), 30);
    let b = frame(&model, "b");
    assert_eq!(model.frame(b).kind, JointKind::Fixed);
    assert!(model.frame(b).value.is_constant());
    let a = model.constraint_jacobian();
    assert_eq!(a.row(b - 1).iter().copied().collect::<Vec<_>>(), [0.0, 0.0]);
    assert_eq!(a[(0, 0)], 1.0);
    assert_eq!(a[(2, 1)], 1.0);
    // The fixed frame's pose is the parent's times the joint origin.
    let q = [0.4, -0.8];
    let poses = model.frame_poses(&q);
    let origin = Transform {
        rotation: rpy(r[0], r[1], r[2]),
        translation: Vector3::from(p),
    };
    let expected = poses[frame(&model, "a")].compose(&origin);
    close_pose(
        &poses[b],
        &expected.rotation,
        &expected.translation,
        1e-15,
        "fixed",
    );

    // The same robot with b merged into a: mass, centre of mass, inertia about it.
    let skew =
        |v: &Vector3<f64>| Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0);
    let rb = rpy(r[0], r[1], r[2]);
    let cb_a = Vector3::from(p) + rb * Vector3::from(cb);
    let m = ma + mb;
    let c = (ma * Vector3::from(ca) + mb * cb_a) / m;
    let da = skew(&(Vector3::from(ca) - c));
    let db = skew(&(cb_a - c));
    let i = sym3(&ia)
        + ma * da.transpose() * da
        + rb * sym3(&ib) * rb.transpose()
        + mb * db.transpose() * db;
    let j2_a = Vector3::from(p) + rb * Vector3::from(j2);
    let merged = robot(
        "merged",
        &[
            link("a", m, [c[0], c[1], c[2]], [0.0; 3], sym6(&i)),
            link_c,
            j1,
            j2_from("a", ([j2_a[0], j2_a[1], j2_a[2]], r)),
        ],
    );
    let merged = Model::from_urdf_str(&merged, "merged.urdf").unwrap();
    for (q, dq, ddq) in [
        ([0.4, -0.8], [1.0, -0.5], [2.0, 0.3]),
        ([-1.0, 0.6], [-2.0, 1.5], [-0.4, 4.0]),
        ([0.0, 0.0], [0.0, 0.0], [0.0, 0.0]),
    ] {
        let t1 = torque(&model, &q, &dq, &ddq);
        let t2 = torque(&merged, &q, &dq, &ddq);
        for k in 0..2 {
            close(t1[k], t2[k], 1e-13, "fixed child vs merged link");
        }
    }
}

/// [`PlanarTwoLink::EXAMPLE`] with both joint axes along −y (the moments that count are
/// `iyy`); `mimic` goes inside the elbow joint.
fn two_link(mimic: &str) -> String {
    let arm = PlanarTwoLink::EXAMPLE;
    let inertia = |k: usize| {
        let i = arm.inertia[k];
        [0.4 * i, 0.0, 0.0, i, 0.0, 0.8 * i]
    };
    let com = |k: usize| [arm.com[k], 0.0, 0.0];
    robot(
        "two_link",
        &[
            link("upper", arm.mass[0], com(0), [0.0; 3], inertia(0)),
            link("fore", arm.mass[1], com(1), [0.0; 3], inertia(1)),
            joint(
                "shoulder",
                "revolute",
                ("base", "upper"),
                ([0.0; 3], [0.0; 3]),
                Some([0.0, -1.0, 0.0]),
                r#"<limit lower="-2" upper="2" velocity="3" effort="10"/>"#,
            ),
            joint(
                "elbow",
                "revolute",
                ("upper", "fore"),
                ([arm.length, 0.0, 0.0], [0.0; 3]),
                Some([0.0, -1.0, 0.0]),
                &format!(r#"<limit lower="-1" upper="1.5" velocity="2" effort="10"/>{mimic}"#),
            ),
        ],
    )
}

#[test]
fn mimic_joint() {
    let (k, b) = (-0.7, 0.3);
    let open = Model::from_urdf_str(&two_link(""), "open.urdf").unwrap();
    let model = Model::from_urdf_str(
        &two_link(&format!(
            r#"<mimic joint="shoulder" multiplier="{k}" offset="{b}"/>"#
        )),
        "mimic.urdf",
    )
    .unwrap();
    assert_eq!(open.coordinates, ["shoulder", "elbow"]);
    assert_eq!(model.coordinates, ["shoulder"]);
    assert_eq!(model.dof(), 1);
    // The mimic frame's joint value is multiplier·q + offset; A shows it.
    let fore = frame(&model, "fore");
    assert_eq!(model.frame(fore).value.terms, [(0, k)]);
    assert_eq!(model.frame(fore).value.offset, b);
    let a = model.constraint_jacobian();
    assert_eq!((a.nrows(), a.ncols()), (2, 1));
    assert_eq!((a[(0, 0)], a[(1, 0)]), (1.0, k));
    let q = 0.9;
    let poses = model.frame_poses(&[q]);
    close_m(
        &poses[fore].rotation,
        &rot([0.0, -1.0, 0.0], q + k * q + b),
        1e-15,
        "mimic pose",
    );
    // The mimic joint's limits apply to its joint value.
    let lim = model.limits.iter().find(|l| l.label == "elbow").unwrap();
    assert_eq!(lim.expr.terms, [(0, k)]);
    assert_eq!(lim.expr.offset, b);
    assert_eq!(lim.position, Some([-1.0, 1.5]));
    assert_eq!(lim.velocity, Some([-2.0, 2.0]));

    // Both axes along −y, so the angles lift the links from +x towards +z.
    let arm = PlanarTwoLink::EXAMPLE;
    for (q, dq, ddq) in [
        (0.9, 1.3, -2.1),
        (-0.5, -2.0, 0.7),
        (0.0, 0.0, 0.0),
        (1.7, 0.4, 5.0),
    ] {
        // The open chain against the closed form.
        let th = [q, k * q + b];
        let (dth, ddth) = ([dq, k * dq], [ddq, k * ddq]);
        let t_open = torque(&open, &th, &dth, &ddth);
        let t_ref = arm.torque(th, dth, ddth);
        close(t_open[0], t_ref[0], 1e-13, "open chain tau1");
        close(t_open[1], t_ref[1], 1e-13, "open chain tau2");
        // Virtual work: the mimic coordinate's torque is tau1 + multiplier·tau2.
        let t = torque(&model, &[q], &[dq], &[ddq]);
        close(t[0], t_ref[0] + k * t_ref[1], 1e-13, "mimic torque");
    }
    // Defaults: multiplier 1, offset 0.
    let model =
        Model::from_urdf_str(&two_link(r#"<mimic joint="shoulder"/>"#), "mimic.urdf").unwrap();
    let fore = frame(&model, "fore");
    assert_eq!(model.frame(fore).value.terms, [(0, 1.0)]);
    assert_eq!(model.frame(fore).value.offset, 0.0);
}

/// Joint axes (0 1 0), (−1 0 0), (0 0 −1) and a skew one, after joint origins with rpy:
/// poses and Jacobians against Rodrigues' formula.
#[test]
fn axes_not_along_z() {
    let axes = [
        [0.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
        [1.0, -2.0, 2.0],
    ];
    let origins = [
        ([0.1, 0.0, 0.3], [0.0, 0.0, 0.0]),
        ([0.0, 0.2, 0.1], [0.5, -0.3, 1.2]),
        ([0.3, -0.1, 0.0], [std::f64::consts::FRAC_PI_2, 0.0, 0.0]),
        ([0.0, 0.0, 0.25], [-0.2, 0.9, 0.4]),
    ];
    let mut body = String::from(r#"<robot name="axes"><link name="l0"/>"#);
    for (k, (axis, (xyz, r))) in axes.iter().zip(&origins).enumerate() {
        body += &link(
            &format!("l{}", k + 1),
            0.5,
            [0.05, 0.02, 0.1],
            [0.0; 3],
            [0.01, 0.0, 0.0, 0.01, 0.0, 0.01],
        );
        body += &format!(
            r#"<joint name="j{}" type="revolute">
                 <origin xyz="{} {} {}" rpy="{} {} {}"/>
                 <parent link="l{k}"/><child link="l{}"/>
                 <axis xyz="{} {} {}"/>
                 <limit lower="-3" upper="3" velocity="1" effort="1"/>
               </joint>"#,
            k + 1,
            xyz[0],
            xyz[1],
            xyz[2],
            r[0],
            r[1],
            r[2],
            k + 1,
            axis[0],
            axis[1],
            axis[2]
        );
    }
    body += "</robot>";
    let model = Model::from_urdf_str(&body, "axes.urdf").unwrap();
    assert_eq!(model.dof(), 4);
    let q = [0.7, -1.1, 0.4, 2.2];
    let mut ws = Workspace::new(&model);
    model.forward_kinematics(&mut ws, &q);
    let poses = model.frame_poses(&q);
    let mut pose = Transform::identity();
    let mut axes_world = Vec::new();
    for k in 0..4 {
        let (xyz, r) = origins[k];
        let origin = Transform {
            rotation: rpy(r[0], r[1], r[2]),
            translation: Vector3::from(xyz),
        };
        pose = pose.compose(&origin);
        axes_world.push((
            pose.rotation * Vector3::from(axes[k]).normalize(),
            pose.translation,
        ));
        pose = pose.compose(&Transform {
            rotation: rot(axes[k], q[k]),
            translation: Vector3::zeros(),
        });
        close_pose(
            &poses[k + 1],
            &pose.rotation,
            &pose.translation,
            1e-14,
            &format!("frame {}", k + 1),
        );
    }
    // Jacobian of the last frame: angular columns are the world axes, linear ones
    // axis × (p − joint origin).
    let jac = model.frame_jacobian(&ws, 4);
    for (k, (w, o)) in axes_world.iter().enumerate() {
        let v = w.cross(&(pose.translation - o));
        for r in 0..3 {
            close(jac[(r, k)], v[r], 1e-14, "linear Jacobian");
            close(jac[(r + 3, k)], w[r], 1e-14, "angular Jacobian");
        }
    }
    // A prismatic joint along −x.
    let text = format!(
        r#"<robot name="p"><link name="a"/>{}
             <joint name="s" type="prismatic"><parent link="a"/><child link="b"/>
               <origin rpy="0 0 0.5"/><axis xyz="-1 0 0"/>
               <limit lower="0" upper="1" velocity="1" effort="1"/></joint></robot>"#,
        link("b", 1.0, [0.0; 3], [0.0; 3], [0.0; 6])
    );
    let model = Model::from_urdf_str(&text, "p.urdf").unwrap();
    let poses = model.frame_poses(&[0.3]);
    close_pose(
        &poses[1],
        &rpy(0.0, 0.0, 0.5),
        &(rpy(0.0, 0.0, 0.5) * Vector3::new(-0.3, 0.0, 0.0)),
        1e-15,
        "prismatic along -x",
    );
}

#[test]
fn rpy_convention_of_joint_origins() {
    let (r, p, y) = (0.3, -0.7, 1.9);
    let text = format!(
        r#"<robot name="r"><link name="a"/>{}{}
             <joint name="f" type="fixed"><parent link="a"/><child link="b"/>
               <origin xyz="1 2 3" rpy="{r} {p} {y}"/></joint>
             <joint name="j" type="revolute"><parent link="b"/><child link="c"/>
               <limit lower="-1" upper="1" velocity="1" effort="1"/></joint></robot>"#,
        link("b", 0.0, [0.0; 3], [0.0; 3], [0.0; 6]),
        link("c", 1.0, [0.0; 3], [0.0; 3], [0.0; 6]),
    );
    let model = Model::from_urdf_str(&text, "r.urdf").unwrap();
    let poses = model.frame_poses(&[0.5]);
    close_pose(
        &poses[1],
        &rpy(r, p, y),
        &Vector3::new(1.0, 2.0, 3.0),
        1e-15,
        "rpy is Rz(yaw)·Ry(pitch)·Rx(roll), origin",
    );
    // The default axis is x (URDF).
    close_m(
        &poses[2].rotation,
        &(rpy(r, p, y) * rot([1.0, 0.0, 0.0], 0.5)),
        1e-15,
        "default axis",
    );
}

#[test]
fn inertial_with_rpy() {
    // Rotated a quarter turn about z: the inertial x axis is the link's y axis.
    let i = [1.0, 0.1, 0.0, 2.0, 0.0, 3.0];
    let text = format!(
        r#"<robot name="i"><link name="a"/>{}{}
             <joint name="j1" type="continuous"><parent link="a"/><child link="b"/></joint>
             <joint name="j2" type="continuous"><parent link="b"/><child link="c"/></joint>
           </robot>"#,
        link(
            "b",
            2.0,
            [0.1, 0.2, 0.3],
            [0.0, 0.0, std::f64::consts::FRAC_PI_2],
            i
        ),
        link(
            "c",
            1.0,
            [0.0, 0.0, 0.0],
            [0.3, -0.4, 1.1],
            [0.5, 0.01, -0.02, 0.6, 0.03, 0.7]
        ),
    );
    let model = Model::from_urdf_str(&text, "i.urdf").unwrap();
    let nb = &model.frame(frame(&model, "b")).nominal;
    assert_eq!(nb.mass, Some(2.0));
    assert_eq!(nb.com, Some([0.1, 0.2, 0.3]));
    let expected = [2.0, -0.1, 0.0, 1.0, 0.0, 3.0];
    for (a, b) in nb.inertia.unwrap().iter().zip(expected) {
        close(*a, b, 1e-15, "quarter-turn inertia");
    }
    // General rpy: R·I·Rᵀ with R = Rz·Ry·Rx.
    let r = rpy(0.3, -0.4, 1.1);
    let ic = Matrix3::new(0.5, 0.01, -0.02, 0.01, 0.6, 0.03, -0.02, 0.03, 0.7);
    let rot_i = r * ic * r.transpose();
    let nc = model.frame(frame(&model, "c")).nominal.inertia.unwrap();
    let ours = Matrix3::new(
        nc[0], nc[1], nc[2], nc[1], nc[3], nc[4], nc[2], nc[4], nc[5],
    );
    close_m(&ours, &rot_i, 1e-15, "rotated inertia");
    // The inertia about the joint (default axis x) of link c alone: tau2 = Ixx·ddq2.
    let tau = torque(&model, &[0.0, 0.0], &[0.0, 0.0], &[0.0, 1.0]);
    close(
        tau[1],
        rot_i[(0, 0)],
        1e-14,
        "rotated inertia in the dynamics",
    );
    // And it differs from the unrotated value, so the rotation is not a no-op here.
    assert!((rot_i[(0, 0)] - 0.5).abs() > 1e-3);
}

#[test]
fn limits_are_kept() {
    let text = format!(
        r#"<robot name="lim" version="1.2"><link name="a"/>{}{}{}
             <joint name="r" type="revolute"><parent link="a"/><child link="b"/>
               <limit lower="-1.5" upper="0.5" velocity="2" acceleration="10" effort="1"/></joint>
             <joint name="p" type="prismatic"><parent link="b"/><child link="c"/>
               <limit lower="0" upper="0.2" effort="1"/></joint>
             <joint name="c" type="continuous"><parent link="c"/><child link="d"/></joint>
           </robot>"#,
        link("b", 1.0, [0.0; 3], [0.0; 3], [0.1, 0.0, 0.0, 0.1, 0.0, 0.1]),
        link("c", 1.0, [0.0; 3], [0.0; 3], [0.1, 0.0, 0.0, 0.1, 0.0, 0.1]),
        link("d", 1.0, [0.0; 3], [0.0; 3], [0.1, 0.0, 0.0, 0.1, 0.0, 0.1]),
    );
    let model = Model::from_urdf_str(&text, "lim.urdf").unwrap();
    assert_eq!(model.coordinate_is_length, [false, true, false]);
    // URDF 1.2: an omitted velocity means no limit; the continuous joint has none.
    let labels: Vec<&str> = model.limits.iter().map(|l| l.label.as_str()).collect();
    assert_eq!(labels, ["r", "p"]);
    let r = &model.limits[0];
    assert_eq!(r.expr.terms, [(0, 1.0)]);
    assert_eq!(r.position, Some([-1.5, 0.5]));
    assert_eq!(r.velocity, Some([-2.0, 2.0]));
    assert_eq!(r.acceleration, Some([-10.0, 10.0]));
    let p = &model.limits[1];
    assert_eq!(p.expr.terms, [(1, 1.0)]);
    assert_eq!(p.position, Some([0.0, 0.2]));
    assert_eq!(p.velocity, None);
    assert_eq!(p.acceleration, None);
}

/// The error message of a document that must be rejected.
fn error(text: &str, file: &str) -> String {
    match Model::from_urdf_str(text, file) {
        Ok(_) => panic!("{file} was accepted"),
        Err(e) => {
            eprintln!("{e}");
            e.to_string()
        }
    }
}

fn assert_names(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(
            message.contains(p),
            "message `{message}` does not contain `{p}`"
        );
    }
}

const TWO_LINKS: &str = r#"<link name="a"/><link name="b"><inertial><mass value="1"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>"#;

#[test]
fn error_floating_and_planar_joints() {
    for kind in ["floating", "planar"] {
        let text = format!(
            r#"<robot name="x">{TWO_LINKS}<joint name="free" type="{kind}">
                 <parent link="a"/><child link="b"/></joint></robot>"#
        );
        let msg = error(&text, "robots/free.urdf");
        assert_names(
            &msg,
            &[
                "robots/free.urdf",
                "`free`",
                &format!("`{kind}` is not supported"),
            ],
        );
    }
}

#[test]
fn error_two_root_links() {
    let text = format!(
        r#"<robot name="x">{TWO_LINKS}<link name="stray"/>
             <joint name="j" type="continuous"><parent link="a"/><child link="b"/></joint></robot>"#
    );
    let msg = error(&text, "two_roots.urdf");
    assert_names(
        &msg,
        &[
            "two_roots.urdf",
            "expected one root link, found 2",
            "\"a\"",
            "\"stray\"",
        ],
    );
}

#[test]
fn error_mimic_of_unknown_joint() {
    let text = format!(
        r#"<robot name="x">{TWO_LINKS}<joint name="j" type="continuous"><parent link="a"/>
             <child link="b"/><mimic joint="nope" multiplier="2"/></joint></robot>"#
    );
    let msg = error(&text, "mimic.urdf");
    assert_names(
        &msg,
        &[
            "mimic.urdf",
            "joint `j` mimics `nope`",
            "no joint has that name",
        ],
    );
    // A mimic of a mimic is refused too, with the reason.
    let text = r#"<robot name="x"><link name="a"/><link name="b"/><link name="c"/><link name="d"/>
        <joint name="j1" type="continuous"><parent link="a"/><child link="b"/></joint>
        <joint name="j2" type="continuous"><parent link="b"/><child link="c"/><mimic joint="j1"/></joint>
        <joint name="j3" type="continuous"><parent link="c"/><child link="d"/><mimic joint="j2"/></joint>
        </robot>"#;
    let msg = error(text, "mimic2.urdf");
    assert_names(
        &msg,
        &[
            "mimic2.urdf",
            "joint `j3` mimics `j2`",
            "itself a mimic joint",
        ],
    );
}

#[test]
fn error_malformed_xml() {
    let msg = error(r#"<robot name="x"><link name="a"></robot>"#, "broken.urdf");
    assert_names(
        &msg,
        &["broken.urdf", "URDF", "cannot parse", "not properly nested"],
    );
    let msg = error("not xml at all", "garbage.urdf");
    assert_names(&msg, &["garbage.urdf", "URDF", "cannot parse"]);
    // A required element missing.
    let msg = error(
        r#"<robot name="x"><link name="a"/><link name="b"><inertial><mass value="1"/></inertial></link>
           <joint name="j" type="continuous"><parent link="a"/><child link="b"/></joint></robot>"#,
        "missing.urdf",
    );
    assert_names(&msg, &["missing.urdf", "cannot parse", "inertia"]);
    // Through Model::load, the path names the file.
    let dir = dvrk_test_support::temp_dir("dvrk_model_urdf");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.urdf");
    std::fs::write(&path, r#"<robot name="x"><link name="a"></robot>"#).unwrap();
    let msg = Model::load(path.to_str().unwrap()).unwrap_err().to_string();
    eprintln!("{msg}");
    std::fs::remove_dir_all(&dir).unwrap();
    assert_names(&msg, &[path.to_str().unwrap(), "URDF", "cannot parse"]);
}

/// urdf-rs 0.10 writes the document back through RustyXML, which panics on a namespace
/// with no bound prefix: both fuzzing reproducers are refused with the file named, and the
/// `xmlns:xacro` declaration that xacro leaves on real URDFs still loads.
#[test]
fn namespaces() {
    let seeds = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fuzz/seeds/urdf/");
    for (seed, attribute) in [
        ("crash-unbound-attribute-prefix.urdf", "`ink`"),
        ("crash-unbound-malformed-attribute.urdf", "`ink9"),
    ] {
        let text = std::fs::read_to_string(format!("{seeds}{seed}")).unwrap();
        assert_names(
            &error(&text, seed),
            &[
                seed,
                "URDF",
                attribute,
                "<parent>",
                "not bound",
                "no namespaces",
            ],
        );
    }
    let xacro = format!(
        r#"<robot name="x" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="a"/>{}
           <joint name="j" type="continuous"><parent link="a"/><child link="b"/></joint></robot>"#,
        link(
            "b",
            1.0,
            [0.0, 0.0, 0.5],
            [0.0; 3],
            [0.1, 0.0, 0.0, 0.1, 0.0, 0.1]
        )
    );
    let model = Model::from_urdf_str(&xacro, "xacro.urdf").unwrap();
    assert_eq!(model.dof(), 1);
}

#[test]
fn error_structure() {
    // Continuous joints (name, parent link, child link) after TWO_LINKS and `more` links,
    // and what the error names.
    type Joints<'a> = &'a [(&'a str, &'a str, &'a str)];
    let cases: [(&str, Joints, &[&str]); 4] = [
        // A child link that is not defined.
        (
            "",
            &[("j", "a", "b"), ("k", "b", "ghost")],
            &["joint `k`", "child link `ghost` is not defined"],
        ),
        // A link with two parents (a closed loop).
        (
            r#"<link name="c"/>"#,
            &[("j", "a", "b"), ("k", "a", "c"), ("l", "c", "b")],
            &["link `b` has two parents", "`l`"],
        ),
        // A joint hanging from an undefined link.
        (
            r#"<link name="c"/>"#,
            &[("j", "a", "b"), ("k", "nowhere", "c")],
            &[
                "not connected to the root link `a`",
                "`k` (parent link `nowhere`)",
            ],
        ),
        // Duplicate names.
        (
            r#"<link name="b"/>"#,
            &[("j", "a", "b")],
            &["link `b` is defined twice"],
        ),
    ];
    for (more, joints, names) in cases {
        let joints: String = joints
            .iter()
            .map(|(name, parent, child)| {
                format!(
                    r#"<joint name="{name}" type="continuous"><parent link="{parent}"/><child link="{child}"/></joint>"#
                )
            })
            .collect();
        let text = format!(r#"<robot name="x">{TWO_LINKS}{more}{joints}</robot>"#);
        let msg = error(&text, "s.urdf");
        assert_names(&msg, &["s.urdf"]);
        assert_names(&msg, names);
    }
    // A zero axis.
    let text = format!(
        r#"<robot name="x">{TWO_LINKS}<joint name="j" type="continuous"><parent link="a"/>
             <child link="b"/><axis xyz="0 0 0"/></joint></robot>"#
    );
    assert_names(&error(&text, "s.urdf"), &["s.urdf", "joint `j`", "zero"]);
    // No moving joint.
    let text = format!(
        r#"<robot name="x">{TWO_LINKS}<joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint></robot>"#
    );
    assert_names(&error(&text, "s.urdf"), &["s.urdf", "no moving joint"]);
    // A negative mass.
    let text = r#"<robot name="x"><link name="a"/><link name="b"><inertial><mass value="-1"/>
        <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
        <joint name="j" type="continuous"><parent link="a"/><child link="b"/></joint></robot>"#;
    assert_names(
        &error(text, "s.urdf"),
        &["s.urdf", "link `b`", "non-negative"],
    );
}

/// A link with `<collision>` elements `geometries` (each `(origin xyz, rpy, geometry)`).
fn collision_link(name: &str, geometries: &[([f64; 3], [f64; 3], &str)]) -> String {
    let inertial = link(
        name,
        1.0,
        [0.0; 3],
        [0.0; 3],
        [0.01, 0.0, 0.0, 0.01, 0.0, 0.01],
    );
    let collisions: String = geometries
        .iter()
        .map(|(xyz, rpy, g)| {
            format!(
                r#"<collision><origin xyz="{} {} {}" rpy="{} {} {}"/><geometry>{g}</geometry></collision>"#,
                xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
            )
        })
        .collect();
    inertial.replace("</link>", &format!("{collisions}</link>"))
}

/// The bounding ellipsoid of the one link of a revolute chain whose link has
/// `geometries`.
fn collision_ellipsoid(
    geometries: &[([f64; 3], [f64; 3], &str)],
) -> Result<Option<dvrk_model::inertia::Ellipsoid>, dvrk_model::ModelError> {
    let doc = robot(
        "collide",
        &[
            collision_link("arm", geometries),
            joint(
                "j1",
                "revolute",
                ("base", "arm"),
                ([0.0; 3], [0.0; 3]),
                Some([0.0, 0.0, 1.0]),
                UNIT_LIMIT,
            ),
        ],
    );
    let model = Model::from_urdf_str(&doc, "collide.urdf")?;
    Ok(model.frame(frame(&model, "arm")).bounds.ellipsoid.clone())
}

#[test]
fn collision_geometry_gives_bounding_ellipsoids() {
    let s3 = 3f64.sqrt();
    // A box: the least-volume ellipsoid through its corners, placed by the origin.
    let e = collision_ellipsoid(&[(
        [0.1, 0.0, 0.2],
        [0.0, 0.0, 0.3],
        r#"<box size="0.2 0.1 0.4"/>"#,
    )])
    .unwrap()
    .unwrap();
    assert_eq!(e.center, [0.1, 0.0, 0.2]);
    assert_eq!(e.rpy, [0.0, 0.0, 0.3]);
    for (a, h) in e.semi_axes.iter().zip([0.1, 0.05, 0.2]) {
        close(*a, s3 * h, 1e-15, "box semi-axis");
    }
    // A cylinder along its z: √(3/2)·r across, √3·l/2 along.
    let e = collision_ellipsoid(&[(
        [0.0; 3],
        [0.0; 3],
        r#"<cylinder radius="0.05" length="0.3"/>"#,
    )])
    .unwrap()
    .unwrap();
    close(
        e.semi_axes[0],
        1.5f64.sqrt() * 0.05,
        1e-15,
        "cylinder across",
    );
    close(e.semi_axes[2], s3 * 0.15, 1e-15, "cylinder along");
    // A sphere is its own ellipsoid.
    let e = collision_ellipsoid(&[([0.0, 0.1, 0.0], [0.0; 3], r#"<sphere radius="0.07"/>"#)])
        .unwrap()
        .unwrap();
    assert_eq!(e.semi_axes, [0.07; 3]);
    // Two spheres: the box around both, then its ellipsoid.
    let e = collision_ellipsoid(&[
        ([0.0; 3], [0.0; 3], r#"<sphere radius="0.1"/>"#),
        ([0.4, 0.0, 0.0], [0.0; 3], r#"<sphere radius="0.1"/>"#),
    ])
    .unwrap()
    .unwrap();
    for (got, want) in e.center.iter().zip([0.2, 0.0, 0.0]) {
        close(*got, want, 1e-15, "union centre");
    }
    for (got, want) in e.semi_axes.iter().zip([0.3, 0.1, 0.1]) {
        close(*got, s3 * want, 1e-15, "union semi-axis");
    }
    // A mesh (vertices in another file) or no collision at all: no ellipsoid.
    assert!(
        collision_ellipsoid(&[([0.0; 3], [0.0; 3], r#"<mesh filename="arm.stl"/>"#)])
            .unwrap()
            .is_none()
    );
    assert!(collision_ellipsoid(&[]).unwrap().is_none());
    // A degenerate box is refused, naming the link.
    let err =
        collision_ellipsoid(&[([0.0; 3], [0.0; 3], r#"<box size="0.1 0 0.1"/>"#)]).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("collide.urdf") && msg.contains("arm") && msg.contains("semi_axes"),
        "{msg}"
    );
}
