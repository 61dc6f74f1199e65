//! Every mistake in a description file is reported with the file, the frame (or section)
//! and the field, so that the user finds the line.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use dvrk_model::{Model, ModelError};

const FILE: &str = "robots/my_arm.toml";

/// A valid two-coordinate description; the tests break one thing at a time.
const VALID: &str = r#"
name = "my arm"
convention = "modified"
coordinates = ["q1", "q2"]

[constants]
l1 = 0.3

[measured]
joints = ["shoulder", "elbow"]
coupling = [[1.0, 0.0], [-1.0, 1.0]]

[[frames]]
name = "upper"
parent = "base"
theta = "q1"
inertia = true
friction = true
bounds = { mass = [0.1, 2.0] }

[[frames]]
name = "lower"
parent = "upper"
a = "l1"
alpha = "pi/2"
theta = "q2 - q1 + pi/4"
inertia = true
motor_inertia = false

[[limits]]
expr = "q2 - q1"
position = [-1.0, 1.0]
"#;

fn load(text: &str) -> Result<Model, ModelError> {
    Model::from_toml_str(text, FILE)
}

/// Loads `text`, expects an error, and checks that its message contains every needle.
#[track_caller]
fn expect_error(text: &str, needles: &[&str]) -> ModelError {
    let err = match load(text) {
        Ok(_) => panic!("expected an error mentioning {needles:?}, but the description loaded"),
        Err(e) => e,
    };
    let msg = err.to_string();
    for needle in needles {
        assert!(
            msg.contains(needle),
            "message {msg:?} does not mention {needle:?}"
        );
    }
    assert!(msg.contains(FILE), "message {msg:?} does not name the file");
    err
}

/// `VALID` with `from` replaced by `to` (which must occur exactly once).
#[track_caller]
fn with(from: &str, to: &str) -> String {
    assert_eq!(
        VALID.matches(from).count(),
        1,
        "`{from}` must occur once in VALID"
    );
    VALID.replace(from, to)
}

#[test]
fn valid_description_loads() {
    let model = load(VALID).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.dof(), 2);
    assert_eq!(model.source, FILE);
    assert_eq!(model.measured.joints, ["shoulder", "elbow"]);
    assert_eq!(model.frame(2).value.terms, vec![(0, -1.0), (1, 1.0)]);
    assert_eq!(model.limits.len(), 1);
}

#[test]
fn malformed_toml() {
    let err = expect_error(&with("name = \"my arm\"", "name = \"my arm"), &[]);
    assert!(matches!(err, ModelError::Syntax { .. }), "{err:?}");
    // A line that is not TOML at all.
    expect_error(&with("[constants]", "[constants\n"), &[]);
    // Schema errors: an unknown key is named.
    let err = expect_error(
        &with("friction = true", "friction = true\ninertial = true"),
        &["inertial"],
    );
    assert!(matches!(err, ModelError::Syntax { .. }), "{err:?}");
    // A wrong type.
    expect_error(
        &with("inertia = true\nfriction", "inertia = \"yes\"\nfriction"),
        &["inertia"],
    );
    // A missing required key.
    expect_error(&with("convention = \"modified\"\n", ""), &["convention"]);
    // An unknown convention.
    expect_error(
        &with("convention = \"modified\"", "convention = \"craig\""),
        &["craig"],
    );
}

#[test]
fn unknown_constant_names_file_frame_and_field() {
    let err = expect_error(
        &with("a = \"l1\"", "a = \"l_foo\""),
        &["frame 2", "lower", "`a`", "l_foo"],
    );
    match err {
        ModelError::Field {
            file,
            place,
            field,
            message,
        } => {
            assert_eq!(file, FILE);
            assert!(place.contains("lower"), "{place}");
            assert_eq!(field, "a");
            assert!(message.contains("unknown name"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    // In a joint value.
    expect_error(
        &with("theta = \"q1\"", "theta = \"q1 + offset1\""),
        &["upper", "`theta`", "offset1"],
    );
    // A coordinate that does not exist is an unknown name too.
    expect_error(
        &with("theta = \"q1\"", "theta = \"q3\""),
        &["upper", "`theta`", "q3"],
    );
    // In a constant.
    let text = with("l1 = 0.3", "l1 = \"0.3 + l_missing\"");
    expect_error(&text, &["constants", "l1", "l_missing"]);
}

#[test]
fn constant_problems() {
    // Cycles cannot be resolved.
    let text = with("l1 = 0.3", "l1 = \"l2\"\nl2 = \"l1\"");
    expect_error(&text, &["constants"]);
    // Reserved names.
    expect_error(
        &with("l1 = 0.3", "l1 = 0.3\npi = 3.0"),
        &["constants", "pi", "reserved"],
    );
    expect_error(
        &with("l1 = 0.3", "l1 = 0.3\nq2 = 3.0"),
        &["constants", "q2", "reserved"],
    );
    // A constant field that depends on a coordinate.
    expect_error(
        &with("a = \"l1\"", "a = \"l1*q1\""),
        &["lower", "`a`", "q1"],
    );
    // Constants may refer to later ones (resolved in dependency order).
    let ok = with("l1 = 0.3", "l1 = \"2*l0\"\nl0 = 0.15");
    let model = load(&ok).unwrap_or_else(|e| panic!("{e}"));
    assert!((model.frame(2).pre.translation.x - 0.3).abs() < 1e-15);
}

#[test]
fn nonlinear_joint_value_is_rejected() {
    expect_error(
        &with("theta = \"q1\"", "theta = \"sin(q1)\""),
        &["upper", "`theta`", "affine"],
    );
    expect_error(
        &with("theta = \"q1\"", "theta = \"q1*q2\""),
        &["upper", "`theta`", "affine"],
    );
    expect_error(
        &with("theta = \"q1\"", "d = \"q1^2\""),
        &["upper", "`d`", "affine"],
    );
}

#[test]
fn theta_and_d_both_moving() {
    expect_error(
        &with("theta = \"q1\"", "theta = \"q1\"\nd = \"q2\""),
        &["upper", "theta", "d", "only one"],
    );
}

#[test]
fn unknown_parent() {
    expect_error(
        &with("parent = \"upper\"", "parent = \"uper\""),
        &["lower", "`parent`", "uper"],
    );
    // A later frame is not a valid parent either (the tree is given in order).
    let text = with("parent = \"base\"", "parent = \"lower\"");
    expect_error(&text, &["upper", "`parent`", "lower"]);
}

#[test]
fn duplicate_frame_name() {
    expect_error(
        &with("name = \"lower\"", "name = \"upper\""),
        &["frame 2", "upper", "`name`", "duplicate"],
    );
    // `base` is reserved for frame 0.
    expect_error(
        &with("name = \"upper\"", "name = \"base\""),
        &["frame 1", "base", "`name`"],
    );
}

#[test]
fn motor_inertia_needs_one_coordinate() {
    let text = with("motor_inertia = false", "motor_inertia = true");
    expect_error(&text, &["lower", "`motor_inertia`", "one coordinate"]);
    // On a fixed frame.
    let text = with("motor_inertia = false", "motor_inertia = true")
        .replace("theta = \"q2 - q1 + pi/4\"", "theta = 0.2");
    expect_error(&text, &["lower", "`motor_inertia`", "moving"]);
}

#[test]
fn elements_on_fixed_frames() {
    let text = with("theta = \"q2 - q1 + pi/4\"", "theta = 0.1\nspring = \"q1\"");
    expect_error(&text, &["lower", "`spring`", "moving"]);
    expect_error(
        &with("theta = \"q1\"", "theta = 0.1"),
        &["upper", "`friction`", "moving"],
    );
    // A spring deflection may be nonlinear but must use known names.
    expect_error(
        &with(
            "theta = \"q1\"",
            "theta = \"q1\"\nspring = \"k_unknown*q1\"",
        ),
        &["upper", "`spring`", "k_unknown"],
    );
    assert!(load(&with(
        "theta = \"q1\"",
        "theta = \"q1\"\nspring = \"sin(q1)^2\""
    ))
    .is_ok());
}

#[test]
fn known_force_errors() {
    let text = with(
        "motor_inertia = false",
        "known_force = { polynomial = [1.0, 2.0], along = \"q1^2\" }",
    );
    expect_error(&text, &["lower", "known_force.along", "affine"]);
    let text = with("motor_inertia = false", "known_force = { polynomial = [] }");
    expect_error(&text, &["lower", "known_force.polynomial"]);
}

#[test]
fn coupling_matrix_errors() {
    let text = with(
        "coupling = [[1.0, 0.0], [-1.0, 1.0]]",
        "coupling = [[1.0, 1.0], [1.0, 1.0]]",
    );
    expect_error(&text, &["measured", "`coupling`", "singular"]);
    let text = with(
        "coupling = [[1.0, 0.0], [-1.0, 1.0]]",
        "coupling = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]",
    );
    expect_error(&text, &["measured", "`coupling`", "2 rows of 2"]);
    let text = with(
        "coupling = [[1.0, 0.0], [-1.0, 1.0]]",
        "coupling = [[1.0, 0.0]]",
    );
    expect_error(&text, &["measured", "`coupling`", "2 rows of 2"]);
}

#[test]
fn wrong_number_of_measured_joints() {
    let text = with(
        "joints = [\"shoulder\", \"elbow\"]",
        "joints = [\"shoulder\"]",
    );
    expect_error(
        &text,
        &["measured", "`joints`", "1 names for 2 coordinates"],
    );
    let text = with(
        "joints = [\"shoulder\", \"elbow\"]",
        "joints = [\"a\", \"b\", \"c\"]",
    );
    expect_error(&text, &["measured", "`joints`", "3 names"]);
}

#[test]
fn bounds_lower_above_upper() {
    // Excitation limit.
    let text = with("position = [-1.0, 1.0]", "position = [1.0, -1.0]");
    expect_error(
        &text,
        &[
            "limits[0]",
            "q2 - q1",
            "`position`",
            "lower bound 1 is above upper bound -1",
        ],
    );
    let text = with(
        "position = [-1.0, 1.0]",
        "position = [-1.0, 1.0]\nvelocity = [\"2*pi\", \"pi\"]",
    );
    expect_error(&text, &["limits[0]", "`velocity`"]);
    // Frame bounds.
    let text = with(
        "bounds = { mass = [0.1, 2.0] }",
        "bounds = { mass = [2.0, 0.1] }",
    );
    expect_error(&text, &["upper", "bounds.mass", "[2, 0.1]"]);
    let text = with(
        "bounds = { mass = [0.1, 2.0] }",
        "bounds = { com = [[0.0, 0.1], [0.2, -0.2], [0.0, 0.1]] }",
    );
    expect_error(&text, &["upper", "bounds.com"]);
    // Mass bounds on a frame without a link.
    let text = with(
        "[[limits]]",
        "[[frames]]\nname = \"massless\"\nparent = \"lower\"\ntheta = \"q2\"\nbounds = { mass = [0.1, 1.0] }\n\n[[limits]]",
    );
    expect_error(&text, &["massless", "bounds", "without link inertia"]);
}

#[test]
fn cartesian_limits_load_and_name_their_mistakes() {
    let boxed = |frame: &str, min: &str, max: &str| {
        format!("{VALID}\n[[cartesian_limits]]\nframe = \"{frame}\"\nmin = {min}\nmax = {max}\n")
    };
    let model = load(&boxed("lower", "[-1, \"-l1\", -inf]", "[1, 0.25, inf]"))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.cartesian_limits.len(), 1);
    let c = &model.cartesian_limits[0];
    assert_eq!((c.frame, c.frame_name.as_str()), (2, "lower"));
    assert_eq!(c.min, [-1.0, -0.3, f64::NEG_INFINITY]);
    assert_eq!(c.max, [1.0, 0.25, f64::INFINITY]);
    expect_error(
        &boxed("hand", "[0, 0, 0]", "[1, 1, 1]"),
        &[
            "cartesian_limits[0] (hand)",
            "`frame`",
            "no frame named `hand`",
            "upper, lower",
        ],
    );
    expect_error(
        &boxed("base", "[0, 0, 0]", "[1, 1, 1]"),
        &["cartesian_limits[0] (base)", "`frame`", "does not move"],
    );
    expect_error(
        &boxed("lower", "[0, 2, 0]", "[1, 1, 1]"),
        &[
            "cartesian_limits[0] (lower)",
            "`min`",
            "y: lower bound 2 is above upper bound 1",
        ],
    );
    expect_error(
        &boxed("lower", "[0, 0, inf]", "[1, 1, inf]"),
        &[
            "cartesian_limits[0] (lower)",
            "`min`",
            "z: inf is not a lower bound",
        ],
    );
    expect_error(
        &boxed("lower", "[0, 0, 0]", "[1, \"q1\", 1]"),
        &["cartesian_limits[0] (lower)", "`max`"],
    );
    expect_error(
        &format!("{VALID}\n[[cartesian_limits]]\nframe = \"lower\"\nmin = [0, 0, 0]\n"),
        &["missing field `max`"],
    );
}

#[test]
fn limit_expression_must_be_affine() {
    let text = with("expr = \"q2 - q1\"", "expr = \"cos(q2)\"");
    expect_error(&text, &["limits[0]", "`expr`", "affine"]);
}

#[test]
fn coordinate_list_errors() {
    expect_error(
        &with(
            "coordinates = [\"q1\", \"q2\"]",
            "coordinates = [\"q1\", \"q1\"]",
        ),
        &["coordinates", "twice"],
    );
    expect_error(
        &with("coordinates = [\"q1\", \"q2\"]", "coordinates = []"),
        &["coordinates"],
    );
}

#[test]
fn no_parameter() {
    let text = r#"
name = "empty"
convention = "standard"
coordinates = ["q1"]
[[frames]]
name = "j1"
parent = "base"
theta = "q1"
"#;
    expect_error(text, &["no parameter"]);
}

#[test]
fn unknown_builtin_robot() {
    let err = Model::builtin("suj").unwrap_err();
    assert!(matches!(err, ModelError::UnknownRobot(ref n) if n == "suj"));
    // The message lists every built-in arm, the ECM and Si arms too.
    for name in Model::builtin_names() {
        assert!(err.to_string().contains(name), "{name}: {err}");
    }
    let err = Model::load("/nonexistent/robot.toml").unwrap_err();
    assert!(err.to_string().contains("/nonexistent/robot.toml"));
}

#[test]
fn ellipsoid_loads_and_names_its_mistakes() {
    let ellipsoid = |fields: &str| {
        with(
            "bounds = { mass = [0.1, 2.0] }",
            &format!("bounds = {{ mass = [0.1, 2.0], ellipsoid = {{ {fields} }} }}"),
        )
    };
    let model = load(&ellipsoid(
        "center = [0.1, 0.0, 0.0], semi_axes = [0.2, 0.05, 0.04], rpy = [0.0, 0.0, 0.5]",
    ))
    .unwrap();
    let e = model.frames[0].bounds.ellipsoid.as_ref().unwrap();
    assert_eq!(e.center, [0.1, 0.0, 0.0]);
    assert_eq!(e.semi_axes, [0.2, 0.05, 0.04]);
    assert_eq!(e.rpy, [0.0, 0.0, 0.5]);
    // rpy defaults to the frame's axes.
    let model = load(&ellipsoid(
        "center = [0.0, 0.0, 0.0], semi_axes = [0.1, 0.1, 0.1]",
    ))
    .unwrap();
    assert_eq!(
        model.frames[0].bounds.ellipsoid.as_ref().unwrap().rpy,
        [0.0; 3]
    );
    expect_error(
        &ellipsoid("center = [0.0, 0.0, 0.0], semi_axes = [0.1, -0.1, 0.1]"),
        &["upper", "bounds.ellipsoid", "semi_axes", "positive", "-0.1"],
    );
    expect_error(
        &ellipsoid("center = [0.0, 0.0, 0.0], semi_axes = [0.1, 0.0, 0.1]"),
        &["upper", "bounds.ellipsoid", "semi_axes"],
    );
    expect_error(
        &ellipsoid("center = [0.0, nan, 0.0], semi_axes = [0.1, 0.1, 0.1]"),
        &["upper", "bounds.ellipsoid", "center", "finite"],
    );
    expect_error(
        &ellipsoid("center = [0.0, 0.0, 0.0], semi_axes = [0.1, nan, 0.1]"),
        &["upper", "bounds.ellipsoid", "semi_axes"],
    );
    expect_error(
        &ellipsoid("center = [0.0, 0.0, 0.0], semi_axes = [0.1, 0.1, 0.1], rpy = [0.0, inf, 0.0]"),
        &["upper", "bounds.ellipsoid", "rpy"],
    );
    // Missing semi-axes, an unknown field: the parser names them.
    expect_error(&ellipsoid("center = [0.0, 0.0, 0.0]"), &["semi_axes"]);
    expect_error(
        &ellipsoid("center = [0.0, 0.0, 0.0], semi_axes = [0.1, 0.1, 0.1], radius = 1"),
        &["radius"],
    );
    // On a frame without a link.
    let text = with(
        "[[limits]]",
        "[[frames]]\nname = \"massless\"\nparent = \"lower\"\ntheta = \"q2\"\nbounds = { ellipsoid = { center = [0.0, 0.0, 0.0], semi_axes = [0.1, 0.1, 0.1] } }\n\n[[limits]]",
    );
    expect_error(&text, &["massless", "bounds", "without link inertia"]);
}

/// `[preset]`'s position torque is checked when the description loads, as the preset
/// will use it: an order out of 1-3, a frame that does not exist or has no friction.
#[test]
fn preset_position_torque_errors() {
    let ok =
        format!("{VALID}\n[preset]\nposition_torque = {{ order = 1, frames = [\"upper\"] }}\n");
    let m = load(&ok).unwrap();
    assert_eq!(
        m.preset.position_torque,
        Some((1, vec!["upper".to_string()]))
    );
    // The model as described does not have it.
    assert!(!m.param_names().iter().any(|p| p.starts_with("Pc")));
    assert_eq!(load(VALID).unwrap().preset.position_torque, None);
    expect_error(
        &ok.replace("order = 1", "order = 0"),
        &[FILE, "preset", "position_torque.order"],
    );
    expect_error(
        &ok.replace("[\"upper\"]", "[\"elbow\"]"),
        &[FILE, "elbow", "no frame is named elbow"],
    );
    // `lower` has no friction.
    expect_error(
        &ok.replace("[\"upper\"]", "[\"lower\"]"),
        &[FILE, "lower", "not a revolute frame with friction"],
    );
    expect_error(
        &ok.replace("order = 1,", "order = 1, period = 2.0,"),
        &[FILE, "period"],
    );
}
