//! URDF export round trips: identified parameters written to a URDF and read back with
//! our importer must give the same inverse dynamics (to 1e-9) at random states.
//!
//! - replace mode on a hand-written arm with every URDF feature the importer knows
//!   (fixed, revolute, prismatic, continuous and mimic joints, skew axes, rotated
//!   inertials, links with and without inertial) and elements it does not (comments,
//!   transmission, gazebo, materials), which must survive untouched; and on the Panda of
//!   `../shared/anchors` when present;
//! - generate mode on the dVRK PSM, simplified PSM and MTM (parallelograms, tendon
//!   couplings, counterweights, virtual motor frames: coordinates as root links, every
//!   frame a mimic) and on standard-DH robots (a coordinate no frame carries alone, a
//!   post transform that does not commute with its joint, gravity not along −z; and with
//!   carriers, a −q one): the coordinates read back in order, every mimic after the
//!   joint it mimics in the depth-first, by-name order of urdfdom and Pinocchio.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_test_support as support;

use dvrk_model::Model;
use support::*;

const TOL: f64 = 1e-9;

/// A test arm: every joint type, a mimic, skew axes, rotated inertials, and elements the
/// importer does not read (materials, visuals, transmission, gazebo, comments).
const ARM: &str = include_str!("fixtures/test_arm.urdf");

/// The lines of a document outside its `<inertial>` elements, trimmed, with empty
/// `<link .../>` elements written as start and end tag (the export opens them).
fn outside_inertials(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(k) = rest.find("<inertial") {
        out.push(rest[..k].to_string());
        let after = &rest[k..];
        rest = &after[after.find("</inertial>").expect("closed inertial") + "</inertial>".len()..];
    }
    out.push(rest.to_string());
    out.concat()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .flat_map(|l| {
            if l.starts_with("<link ") && l.ends_with("/>") && !l.contains("><") {
                let open = format!("{}>", l.trim_end_matches("/>").trim_end());
                vec![open, "</link>".to_string()]
            } else if let Some(open) = l.strip_suffix("</link>").filter(|o| !o.is_empty()) {
                vec![open.to_string(), "</link>".to_string()]
            } else {
                vec![l.to_string()]
            }
        })
        .collect()
}

fn replace_round_trip(text: &str, file: &str, seed: u64) -> String {
    let model = Model::from_urdf_str(text, file).unwrap();
    let params = physical_params(&model, &mut Rng::new(seed));
    let out = model.urdf_with_inertials(&params, text, file).unwrap();
    let back = Model::from_urdf_str(&out, "exported.urdf").unwrap();
    assert_eq!(back.frame_names(), model.frame_names());
    let nominal = back.nominal_parameters().unwrap();
    let worst_param = nominal
        .iter()
        .zip(&params)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let worst = torque_difference(&model, &params, &back, &nominal, seed + 1);
    eprintln!("{file}: replace mode, max |Δπ| = {worst_param:e}, max |Δτ| = {worst:e}");
    assert!(worst_param < 1e-12, "parameters differ by {worst_param:e}");
    assert!(worst < TOL, "torques differ by {worst:e}");
    out
}

#[test]
fn replace_mode_round_trips_and_keeps_everything_else() {
    let out = replace_round_trip(ARM, "arm.urdf", 11);
    // Everything but the inertials is as it was: comments, materials, meshes,
    // transmission, gazebo, limits, dynamics, mimic, element order.
    assert_eq!(outside_inertials(&out), outside_inertials(ARM));
    for kept in [
        "<!-- A test arm: every joint type, a mimic, skew axes, rotated inertials. -->",
        "<mechanicalReduction>50</mechanicalReduction>",
        r#"<gazebo reference="wrist"><material>Gazebo/Grey</material></gazebo>"#,
        r#"<dynamics damping="0.5" friction="0.1"/>"#,
        r#"<mimic joint="j5" multiplier="-1" offset="0.1"/>"#,
    ] {
        assert!(out.contains(kept), "lost: {kept}\n{out}");
    }
    // Every link got an inertial in its own frame (rpy zero), the root kept none.
    let robot = urdf_rs::read_from_string(&out).unwrap();
    for l in &robot.links {
        if l.name == "world" {
            assert_eq!(l.inertial.mass.value, 0.0);
        } else {
            assert!(l.inertial.mass.value > 0.0, "{}", l.name);
            assert_eq!(l.inertial.origin.rpy.0, [0.0; 3], "{}", l.name);
        }
    }
    // Exporting the exported file again changes nothing but the inertials.
    let model = Model::from_urdf_str(&out, "out.urdf").unwrap();
    let again = model
        .urdf_with_inertials(&model.nominal_parameters().unwrap(), &out, "out.urdf")
        .unwrap();
    assert_eq!(outside_inertials(&again), outside_inertials(&out));
}

#[test]
fn replace_mode_round_trips_the_panda() {
    let Some(path) = dvrk_test_support::shared("anchors/panda_arm_7dof.urdf") else {
        return;
    };
    let text = std::fs::read_to_string(&path).unwrap();
    replace_round_trip(&text, path.to_str().unwrap(), 21);
}

fn replace_error(model: &Model, params: &[f64], text: &str) -> String {
    model
        .urdf_with_inertials(params, text, "other.urdf")
        .unwrap_err()
        .to_string()
}

#[track_caller]
fn assert_mentions(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "`{p}` missing from: {message}");
    }
}

#[test]
fn replace_mode_refuses_other_robots_and_bad_parameters() {
    let model = Model::from_urdf_str(ARM, "arm.urdf").unwrap();
    let params = physical_params(&model, &mut Rng::new(5));
    // Another robot.
    let pendulum = r#"<robot name="p"><link name="world"/><link name="bob"/>
        <joint name="swing" type="continuous"><parent link="world"/><child link="bob"/></joint></robot>"#;
    let msg = replace_error(&model, &params, pendulum);
    assert_mentions(
        &msg,
        &[
            "other.urdf",
            "do not match",
            "test_arm",
            "no link named",
            "bob",
        ],
    );
    // Same links, one joint moved: the parameters would land in the wrong frame.
    let moved = ARM.replace(
        r#"<origin xyz="0.1 0 0" rpy="0 1.2 0"/>"#,
        r#"<origin xyz="0.1 0 0" rpy="0 1.3 0"/>"#,
    );
    let msg = replace_error(&model, &params, &moved);
    assert_mentions(&msg, &["other.urdf", "`wrist`", "not where"]);
    // A joint re-parented.
    let reparented = ARM.replace(
        r#"<parent link="wrist"/>
    <child link="tool"/>"#,
        r#"<parent link="slider"/>
    <child link="tool"/>"#,
    );
    let msg = replace_error(&model, &params, &reparented);
    assert_mentions(&msg, &["`tool`", "hangs from `slider`"]);
    // Not a URDF.
    let msg = replace_error(
        &model,
        &params,
        "<robot name=\"x\"><link name=\"a\"></robot>",
    );
    assert_mentions(&msg, &["other.urdf"]);
    // Parameters: not finite, negative mass, mass-less first moment, wrong length.
    let mut bad = params.clone();
    bad[model.param_index("l4y").unwrap()] = f64::NAN;
    assert_mentions(&replace_error(&model, &bad, ARM), &["l4y", "not finite"]);
    let mut bad = params.clone();
    bad[model.param_index("m1").unwrap()] = -0.5;
    assert_mentions(
        &replace_error(&model, &bad, ARM),
        &["base_link", "mass -0.5", "rigid body"],
    );
    let mut bad = params.clone();
    bad[model.param_index("m3").unwrap()] = 0.0;
    assert_mentions(
        &replace_error(&model, &bad, ARM),
        &["upper", "mass 0 with first moment"],
    );
    assert_mentions(
        &replace_error(&model, &params[1..], ARM),
        &["parameter values"],
    );
}

/// Generate mode on a description: exact rigid-body dynamics, the expected structure.
fn generate_round_trip(model: &Model, seed: u64) -> (String, urdf_rs::Robot) {
    let params = physical_params(model, &mut Rng::new(seed));
    let urdf = model.to_urdf(&params).unwrap();
    let robot = urdf_rs::read_from_string(&urdf).unwrap();
    let back = Model::from_urdf_str(&urdf, "generated.urdf").unwrap();
    assert_eq!(
        back.coordinates, model.coordinates,
        "the URDF's coordinates are the model's, in order"
    );
    assert_mimics_follow_their_joints(&robot);
    // Rigid body only: URDF has no motor inertia or spring, and the importer reads no
    // friction.
    let rigid = rigid_only(model, &params);
    let nominal = back.nominal_parameters().unwrap();
    let worst = torque_difference(model, &rigid, &back, &nominal, seed + 1);
    eprintln!("{}: generate mode, max |Δτ| = {worst:e}", model.name);
    assert!(worst < TOL, "{}: torques differ by {worst:e}", model.name);
    // Every identified link is in the URDF with its identified mass.
    for f in &model.frames {
        let link = robot.links.iter().find(|l| l.name == f.name).unwrap();
        let mass = f.inertia.map_or(0.0, |p0| params[p0 + 9]);
        assert_eq!(link.inertial.mass.value, mass, "{}", f.name);
    }
    // Friction of a frame driven by one coordinate is its joint's <dynamics>.
    for f in &model.frames {
        let Some(fr) = f.friction().filter(|_| f.value.terms.len() == 1) else {
            continue;
        };
        let motion = format!("{}_motion", f.name);
        let joint = robot
            .joints
            .iter()
            .find(|j| {
                j.joint_type != urdf_rs::JointType::Fixed
                    && (j.child.link == f.name || j.child.link == motion)
            })
            .unwrap();
        let d = joint.dynamics.as_ref().expect("dynamics");
        assert_eq!(
            (d.friction, d.damping),
            (params[fr.param], params[fr.param + 1]),
            "{}",
            f.name
        );
    }
    (urdf, robot)
}

/// What Pinocchio's URDF parser (`mimic=True`) needs: visiting the tree depth first with
/// each link's child joints sorted by name (urdfdom keeps joints in a map by name), the
/// joint a mimic refers to has been met before the mimic.
fn assert_mimics_follow_their_joints(robot: &urdf_rs::Robot) {
    let children = |link: &str| {
        let mut js: Vec<&urdf_rs::Joint> = robot
            .joints
            .iter()
            .filter(|j| j.parent.link == link)
            .collect();
        js.sort_by(|a, b| a.name.as_bytes().cmp(b.name.as_bytes()));
        js
    };
    let root = robot
        .links
        .iter()
        .find(|l| robot.joints.iter().all(|j| j.child.link != l.name))
        .unwrap();
    let mut seen = std::collections::HashSet::new();
    let mut stack = vec![root.name.as_str()];
    let mut order = Vec::new();
    while let Some(link) = stack.pop() {
        for j in children(link).into_iter().rev() {
            stack.push(j.child.link.as_str());
        }
        if let Some(j) = robot.joints.iter().find(|j| j.child.link == link) {
            order.push(j);
        }
    }
    for j in order {
        if let Some(m) = &j.mimic {
            assert!(
                seen.contains(m.joint.as_str()),
                "mimic joint {} is met before the joint {} it mimics",
                j.name,
                m.joint
            );
        }
        seen.insert(j.name.as_str());
    }
}

struct Counts {
    links: usize,
    joints: usize,
    mimic: usize,
    fixed: usize,
}

fn counts(robot: &urdf_rs::Robot) -> Counts {
    Counts {
        links: robot.links.len(),
        joints: robot.joints.len(),
        mimic: robot.joints.iter().filter(|j| j.mimic.is_some()).count(),
        fixed: robot
            .joints
            .iter()
            .filter(|j| j.joint_type == urdf_rs::JointType::Fixed)
            .count(),
    }
}

#[track_caller]
fn assert_counts(robot: &urdf_rs::Robot, links: usize, joints: usize, mimic: usize, fixed: usize) {
    let c = counts(robot);
    assert_eq!(
        (c.links, c.joints, c.mimic, c.fixed),
        (links, joints, mimic, fixed),
        "(links, joints, mimic joints, fixed joints)"
    );
}

fn has_link(robot: &urdf_rs::Robot, name: &str) -> bool {
    robot.links.iter().any(|l| l.name == name)
}

fn joint<'a>(robot: &'a urdf_rs::Robot, name: &str) -> &'a urdf_rs::Joint {
    robot
        .joints
        .iter()
        .find(|j| j.name == name)
        .unwrap_or_else(|| panic!("no joint {name}"))
}

#[test]
fn generate_mode_psm() {
    let model = Model::builtin("psm").unwrap();
    let (urdf, robot) = generate_round_trip(&model, 31);
    // No frame is driven by q5 alone (1.0186*q5) and the parallelogram mimics q2 outside
    // the subtree of the frame that turns by q2: every coordinate is a massless
    // `qk_coordinate` link at the root, every moving frame a mimic. 18 frames + base,
    // wrist_yaw_1, wrist_yaw_2 and jaw_coupling_friction depend on two coordinates (+1
    // massless link each) and wrist_yaw on three (+2), 7 coordinate links, base_frames;
    // pitch_back, tool_tip and q7_frames are fixed.
    assert_counts(&robot, 32, 31, 21, 3);
    for k in 1..=7 {
        let j = joint(&robot, &format!("q{k}"));
        assert_eq!(j.child.link, format!("q{k}_coordinate"));
        assert_eq!(j.parent.link, "base");
        assert!(j.mimic.is_none());
    }
    assert!(has_link(&robot, "wrist_yaw_1_q5"));
    assert_eq!(joint(&robot, "q7_frames").child.link, "base_frames");
    assert_eq!(joint(&robot, "yaw_joint").parent.link, "base_frames");
    let bottom = joint(&robot, "pitch_bottom_joint").mimic.as_ref().unwrap();
    assert_eq!(
        (bottom.joint.as_str(), bottom.multiplier),
        ("q2", Some(1.0))
    );
    let front = joint(&robot, "pitch_front_joint").mimic.as_ref().unwrap();
    assert_eq!((front.joint.as_str(), front.multiplier), ("q2", Some(-1.0)));
    // q3 is a length: its coordinate joint and the insertion stage are prismatic.
    assert_eq!(
        joint(&robot, "q3").joint_type,
        urdf_rs::JointType::Prismatic
    );
    assert_eq!(
        joint(&robot, "main_insertion_joint").joint_type,
        urdf_rs::JointType::Prismatic
    );
    let m = joint(&robot, "wrist_pitch_joint").mimic.as_ref().unwrap();
    assert_eq!((m.joint.as_str(), m.multiplier), ("q5", Some(1.0186)));
    for note in ["Ia10", "Ia11", "K10", "Fo1", "Fc16", "deflection -q4"] {
        assert!(urdf.contains(note), "header lacks {note}");
    }
}

#[test]
fn generate_mode_psm_simplified() {
    let model = Model::builtin("psm_simplified").unwrap();
    let (_, robot) = generate_round_trip(&model, 41);
    // 16 frames + base, the same three two-coordinate frames and three-coordinate one,
    // 7 coordinate links and base_frames.
    assert_counts(&robot, 30, 29, 19, 3);
}

#[test]
fn generate_mode_mtm() {
    let model = Model::builtin("mtm").unwrap();
    let (urdf, robot) = generate_round_trip(&model, 51);
    // 10 frames + base; forearm (q3 − q2) and front_parallel (q2 − q3) +1 link each,
    // wrist_platform (0.6697 q2 − 0.6697 q3 + q4) +2; the parallelogram turns by q3 in
    // one branch and mimics q2 in the other (and the reverse): 7 coordinate links and
    // base_frames, every frame a mimic.
    assert_counts(&robot, 23, 22, 14, 1);
    for (j, coord, multiplier) in [
        ("forearm_joint_q2", "q2", -1.0),
        ("forearm_joint_q3", "q3", 1.0),
        ("wrist_platform_joint_q2", "q2", 0.6697),
        ("wrist_platform_joint_q3", "q3", -0.6697),
        ("wrist_platform_joint_q4", "q4", 1.0),
        ("upper_arm_joint", "q2", 1.0),
        ("back_parallel_joint", "q3", 1.0),
    ] {
        let m = joint(&robot, j).mimic.as_ref().unwrap();
        assert_eq!(
            (m.joint.as_str(), m.multiplier),
            (coord, Some(multiplier)),
            "{j}"
        );
    }
    // The chain's later joints sit at the first one's origin, about the same axis.
    assert_eq!(joint(&robot, "forearm_joint_q3").origin.xyz.0, [0.0; 3]);
    assert_eq!(joint(&robot, "forearm_joint_q3").parent.link, "forearm_q2");
    for note in [
        "known force of frame wrist_platform",
        "spring K7",
        "Ia10",
        "Fc3",
    ] {
        assert!(urdf.contains(note), "header lacks {note}");
    }
    // Limits from the description (q1 in [-57, 29] degrees), on the coordinate's joint
    // and on the frame that turns by it.
    let deg = std::f64::consts::PI / 180.0;
    for j in ["q1", "top_panel_joint"] {
        let l = &joint(&robot, j).limit;
        assert!(
            (l.lower + 57.0 * deg).abs() < 1e-15 && (l.upper - 29.0 * deg).abs() < 1e-15,
            "{j}"
        );
    }
}

const ODD: &str = models::DH_ODD;

#[test]
fn generate_mode_fallbacks_are_exact() {
    let model = Model::from_toml_str(ODD, "odd.toml").unwrap();
    let (urdf, robot) = generate_round_trip(&model, 61);
    // No frame turns by w alone (2*w, u + w): the coordinates are root links. base_world
    // (gravity along −y in the model), base, 4 frames; one_motion and four_motion
    // (standard DH revolute with a ≠ 0: the post transform moves off the joint axis, so
    // it is a fixed joint after the motion); four_u (chain u, w); u, v, w_coordinate;
    // base_frames under the fixed joint w_frames (sorts after u, v, w).
    assert_counts(&robot, 13, 12, 5, 4);
    for l in [
        "base_world",
        "one_motion",
        "four_motion",
        "four_u",
        "u_coordinate",
        "w_coordinate",
        "base_frames",
    ] {
        assert!(has_link(&robot, l), "no link {l}");
    }
    assert_eq!(joint(&robot, "w_frames").child.link, "base_frames");
    assert_eq!(joint(&robot, "one_joint").parent.link, "base_frames");
    assert_eq!(joint(&robot, "three_joint").parent.link, "two");
    assert_eq!(joint(&robot, "four_joint_w").child.link, "four_motion");
    let one = joint(&robot, "one_joint").mimic.as_ref().unwrap();
    assert_eq!(
        (one.joint.as_str(), one.multiplier, one.offset),
        ("u", Some(-1.0), Some(0.3))
    );
    assert_eq!(joint(&robot, "w").child.link, "w_coordinate");
    assert_eq!(joint(&robot, "w").joint_type, urdf_rs::JointType::Revolute);
    let l = &joint(&robot, "w").limit;
    assert_eq!((l.lower, l.upper), (-0.5, 0.75));
    // three's joint value is 2w: its mimic limits are the coordinate's, doubled.
    let l = &joint(&robot, "three_joint").limit;
    assert_eq!((l.lower, l.upper), (-1.0, 1.5));
    assert!(
        urdf.contains("friction Fc4"),
        "two-coordinate friction noted"
    );
}

#[test]
fn generate_mode_carriers_when_they_lead_their_mimics() {
    // The same robot with frame three turning by w: every coordinate has a frame of its
    // own above every frame that depends on it, so the coordinates are those frames'
    // joints (−u + 0.3 with the axis reversed, v + 0.05 with the offset in the origin).
    let text = ODD.replace("theta = \"2*w\"", "theta = \"w\"");
    let model = Model::from_toml_str(&text, "odd.toml").unwrap();
    let (_, robot) = generate_round_trip(&model, 71);
    assert_counts(&robot, 9, 8, 2, 3);
    assert_eq!(joint(&robot, "u").axis.xyz.0, [0.0, 0.0, -1.0]);
    assert_eq!(joint(&robot, "u").child.link, "one_motion");
    assert_eq!(joint(&robot, "v").child.link, "two");
    assert_eq!(joint(&robot, "w").child.link, "three");
    let l = &joint(&robot, "w").limit;
    assert_eq!((l.lower, l.upper), (-0.5, 0.75));
    assert!(!has_link(&robot, "base_frames"));
}

#[test]
fn generate_mode_refuses_what_urdf_cannot_hold() {
    let model = Model::builtin("psm").unwrap();
    let mut params = physical_params(&model, &mut Rng::new(3));
    let m = model.param_index("m4").unwrap();
    params[m] = 0.0;
    let msg = model.to_urdf(&params).unwrap_err().to_string();
    assert_mentions(&msg, &["psm", "pitch_front", "mass 0 with first moment"]);
    params[m] = f64::INFINITY;
    let msg = model.to_urdf(&params).unwrap_err().to_string();
    assert_mentions(&msg, &["m4", "not finite"]);
}
