//! A payload fixed to a frame: its parameters' gravity torque against the potential
//! energy of its mass, differentiated numerically from forward kinematics (independent
//! of the Newton–Euler pass), and its file's errors.

#![cfg(feature = "description")]

use dvrk_model::{Model, Payload, Workspace};

const FILE: &str = "frame = \"main_insertion\"\nmass = 0.2\ncom = [0.0, 0.02, 0.165]\n\
                    inertia = [1e-4, 2e-4, 1.5e-4, 0.0, 1e-5, 0.0]\n";

/// Potential energy (J) of mass `m` at `com` in frame `frame` at `q`: `−m·g·p`.
fn potential(
    model: &Model,
    ws: &mut Workspace,
    frame: usize,
    m: f64,
    com: [f64; 3],
    q: &[f64],
) -> f64 {
    model.forward_kinematics(ws, q);
    let pose = ws.pose(frame);
    let p = pose.rotation * nalgebra::Vector3::from(com) + pose.translation;
    -m * model.gravity.dot(&p)
}

#[test]
fn payload_gravity_torque_is_the_gradient_of_its_potential() {
    let psm = Model::builtin("psm").unwrap();
    let payload = Payload::from_toml_str(&psm, FILE, "payload.toml").unwrap();
    let params = payload.params(&psm, "payload.toml").unwrap();
    let frame = 1 + psm
        .frames
        .iter()
        .position(|f| f.name == "main_insertion")
        .unwrap();
    let mut ws = Workspace::new(&psm);
    let q = [0.3, -0.2, 0.12, 0.4, -0.1, 0.2, 0.3];
    let mut g = [0.0; 7];
    psm.gravity_torque(&mut ws, &params, &q, &mut g);
    let h = 1e-6;
    for k in 0..7 {
        let (mut up, mut down) = (q, q);
        up[k] += h;
        down[k] -= h;
        let dv = (potential(&psm, &mut ws, frame, 0.2, payload.com, &up)
            - potential(&psm, &mut ws, frame, 0.2, payload.com, &down))
            / (2.0 * h);
        assert!(
            (g[k] - dv).abs() < 1e-7,
            "q{}: {} against {dv}",
            k + 1,
            g[k]
        );
    }
    // The insertion carries it: a real torque and force, not zeros.
    assert!(g[1].abs() > 0.05 && g[2].abs() > 0.1, "{g:?}");
    // Added to other parameters, the link's 10 parameters grow by the payload's.
    let mut base = vec![0.5; psm.n_params()];
    payload.add_to(&psm, &mut base, "payload.toml").unwrap();
    let p0 = psm.frame(frame).inertia.unwrap();
    assert_eq!(base[p0 + 9], 0.7);
    // Lyy about the origin: the parallel-axis term m·(x² + z²).
    let lyy = 2e-4 + 0.2 * 0.165f64.powi(2);
    assert!((payload.barycentric()[3] - lyy).abs() < 1e-15);
}

#[test]
fn payload_file_errors_name_the_file_and_field() {
    let psm = Model::builtin("psm").unwrap();
    let err = |text: &str| {
        Payload::from_toml_str(&psm, text, "p.toml")
            .unwrap_err()
            .to_string()
    };
    let e = err("frame = \"nowhere\"\nmass = 1\ncom = [0, 0, 0]\n");
    assert!(
        e.contains("p.toml: payload: field `frame`: robot psm has no frame `nowhere`"),
        "{e}"
    );
    let e = err("frame = \"tool_roll\"\nmass = 1\ncom = [0, 0, 0]\n");
    assert!(
        e.contains("carries no link parameters") && e.contains("main_insertion"),
        "{e}"
    );
    let e = err("frame = \"main_insertion\"\nmass = -1\ncom = [0, 0, 0]\n");
    assert!(e.contains("field `mass`: must be positive"), "{e}");
    let e = err(
        "frame = \"main_insertion\"\nmass = 1\ncom = [0, 0, 0]\ninertia = [1, 1, 3, 0, 0, 0]\n",
    );
    assert!(
        e.contains("field `inertia`: is not that of a physical body"),
        "{e}"
    );
    let e = err("frame = \"main_insertion\"\nmass = 1\ncom = [0, 0]\n");
    assert!(e.starts_with("p.toml: "), "{e}");
    let e = err("frame = \"main_insertion\"\nmass = 1\ncom = [0, 0, 0]\nvolume = 2\n");
    assert!(e.contains("unknown field `volume`"), "{e}");
}

/// The payload model's regressor times the payload's barycentric parameters is the
/// torque the payload adds: the inverse dynamics of the whole arm with only the payload's
/// parameters (the Newton–Euler pass, not the regressor), at poses, rates and
/// accelerations away from zero; its base parameters are those of one body.
#[test]
fn payload_model_regressor_is_the_payload_torque() {
    let psm = Model::builtin("psm").unwrap();
    let payload = Payload::from_toml_str(&psm, FILE, "payload.toml").unwrap();
    let alone = payload.params(&psm, "payload.toml").unwrap();
    let body = psm.payload_model("main_insertion", "--frame").unwrap();
    assert_eq!(body.n_params(), 10);
    let frame = 1 + psm
        .frames
        .iter()
        .position(|f| f.name == "main_insertion")
        .unwrap();
    assert_eq!(body.param_names()[9], format!("m{frame}"));
    assert!(!body.has_known_forces());
    let (mut ws, mut wb) = (Workspace::new(&psm), Workspace::new(&body));
    let pi = payload.barycentric();
    for k in 0..5 {
        let t = k as f64;
        let q: Vec<f64> = (0..7).map(|i| 0.3 * (t + i as f64).sin()).collect();
        let dq: Vec<f64> = (0..7).map(|i| 0.7 * (2.0 * t + i as f64).cos()).collect();
        let ddq: Vec<f64> = (0..7).map(|i| 1.3 * (3.0 * t - i as f64).sin()).collect();
        let mut tau = vec![0.0; 7];
        psm.inverse_dynamics(&mut ws, &alone, &q, &dq, &ddq, &mut tau);
        let mut h = vec![0.0; 7 * 10];
        body.regressor_into(&mut wb, &q, &dq, &ddq, &mut h);
        for r in 0..7 {
            let hp: f64 = (0..10).map(|c| h[r * 10 + c] * pi[c]).sum();
            assert!(
                (hp - tau[r]).abs() < 1e-12,
                "q{}: {hp} against {}",
                r + 1,
                tau[r]
            );
        }
        assert!(tau[1].abs() + tau[2].abs() > 1e-2, "{tau:?}");
    }
    let err = psm
        .payload_model("tool_roll", "--frame")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("carries no link parameters") && err.contains("main_insertion"),
        "{err}"
    );
}
