//! What every CLI test needs: run the binary, a scratch folder, the bundled examples.
// Each test binary compiles this module and uses only part of it.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::fmt::Debug;
use std::path::Path;
use std::process::Command;

use dvrk_ident::{Coordinates, JointLog};
use dvrk_logs::uniform_time;
use dvrk_model::{Model, Workspace};
use nalgebra::DMatrix;

/// Runs `dvrk-ident ARGS` with stdout and stderr piped: (success, stdout, stderr).
pub fn run<A: AsRef<OsStr>>(args: &[A]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_dvrk-ident"))
        .args(args)
        .output()
        .expect("run dvrk-ident");
    (
        out.status.success(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// Runs `dvrk-ident ARGS`, which must succeed (the failure shows the arguments and
/// stderr): its stdout.
#[track_caller]
pub fn run_ok<A: AsRef<OsStr> + Debug>(args: &[A]) -> String {
    let (ok, out, err) = run(args);
    assert!(ok, "{args:?}: {err}");
    out
}

/// [`run_ok`] of a command that prints a JSON document (`--json`): the document.
#[track_caller]
pub fn run_json<A: AsRef<OsStr> + Debug>(args: &[A]) -> serde_json::Value {
    let out = run_ok(args);
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{args:?}: stdout is not JSON: {e}"))
}

/// The arguments of the README's main command, `fit examples/psm_excitation.mcap --robot
/// psm` (the bundled simulated PSM log), then `extra`.
pub fn fit_example_args(extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = ["fit", &example("psm_excitation.mcap"), "--robot", "psm"]
        .map(String::from)
        .into();
    args.extend(extra.iter().map(|x| x.to_string()));
    args
}

/// The arguments of `fit LOG --robot ROBOT` for a log in the 2019 layout (`--format
/// wpi-csv --rate 200`, the dVRK's rate), then `extra`.
pub fn fit_wpi_args(log: &Path, robot: &str, extra: &[&str]) -> Vec<String> {
    let log = s(log);
    let mut args: Vec<String> = [
        "fit", &log, "--robot", robot, "--format", "wpi-csv", "--rate", "200",
    ]
    .map(String::from)
    .into();
    args.extend(extra.iter().map(|x| x.to_string()));
    args
}

/// The arguments of `simulate ROBOT` with the bundled example's parameters
/// (`examples/psm_params.json`) along the trajectory file `trajectory`, into `out`, then
/// `extra`: the simulations the tests make their logs with.
pub fn simulate_args(robot: &str, trajectory: &str, out: &Path, extra: &[&str]) -> Vec<String> {
    let params = example("psm_params.json");
    let mut args: Vec<String> = [
        "simulate",
        robot,
        "--params",
        &params,
        "--excitation",
        trajectory,
        "--out",
        &s(out),
    ]
    .map(String::from)
    .into();
    args.extend(extra.iter().map(|x| x.to_string()));
    args
}

/// Runs `simulate psm` of the bundled example (its parameters along its trajectory,
/// `examples/psm_trajectory.json`) into `out` with the flags `extra`, which must
/// succeed: its stdout.
#[track_caller]
pub fn simulate_example(out: &Path, extra: &[&str]) -> String {
    run_ok(&simulate_args(
        "psm",
        &example("psm_trajectory.json"),
        out,
        extra,
    ))
}

// Not every test binary makes scratch folders.
#[allow(unused_imports)]
pub use dvrk_test_support::temp_dir;

/// Path of a file in the repository's `examples/`, as a command-line argument.
pub fn example(name: &str) -> String {
    dvrk_test_support::example(name).display().to_string()
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> String {
    p.display().to_string()
}

/// The file names in `dir`, sorted.
pub fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The three-joint arm of the export and prior tests (a URDF with nominal inertials).
pub const ARM: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/fixtures/three_joint_arm.urdf"
));

/// A noise-free 200 Hz log of `count` samples in the 2019 CSV layout (model
/// coordinates): `motion(j, t)` is coordinate `j`'s `(q, q̇, q̈)` at `t` (s), the torques
/// are `model`'s inverse dynamics with `pi` plus its known forces.
pub fn write_model_log(
    model: &Model,
    pi: &[f64],
    count: usize,
    path: &Path,
    motion: impl Fn(usize, f64) -> (f64, f64, f64),
) {
    let n = model.dof();
    let time = uniform_time(count, 200.0);
    let (mut q, mut dq, mut tau) = (
        DMatrix::zeros(count, n),
        DMatrix::zeros(count, n),
        DMatrix::zeros(count, n),
    );
    let mut ws = Workspace::new(model);
    let (mut a, mut b, mut c, mut t) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for (k, &tk) in time.iter().enumerate() {
        for j in 0..n {
            (a[j], b[j], c[j]) = motion(j, tk);
        }
        model.inverse_dynamics(&mut ws, pi, &a, &b, &c, &mut t);
        model.add_known_forces(&a, &mut t);
        for j in 0..n {
            q[(k, j)] = a[j];
            dq[(k, j)] = b[j];
            tau[(k, j)] = t[j];
        }
    }
    let log = JointLog {
        time,
        q,
        dq: Some(dq),
        tau,
        joint_names: model.coordinates.clone(),
        coordinates: Coordinates::Model,
        source: "test".into(),
    };
    dvrk_ident::log::write(path, &log, dvrk_ident::log::LogFormat::Wpi).unwrap();
}

/// A noise-free log of the arm (2019 CSV layout, model coordinates) with its URDF's
/// nominal parameters.
pub fn write_arm_log(urdf: &Path, log: &Path) {
    let model = Model::load(&s(urdf)).unwrap();
    let pi = model.nominal_parameters().unwrap();
    write_model_log(&model, &pi, 2000, log, |j, tk| {
        let (w1, w2, p) = (0.7 + 0.17 * j as f64, 1.9 + 0.23 * j as f64, j as f64);
        (
            0.8 * (w1 * tk + p).sin() + 0.3 * (w2 * tk + 2.0 * p).sin(),
            0.8 * w1 * (w1 * tk + p).cos() + 0.3 * w2 * (w2 * tk + 2.0 * p).cos(),
            -0.8 * w1 * w1 * (w1 * tk + p).sin() - 0.3 * w2 * w2 * (w2 * tk + 2.0 * p).sin(),
        )
    });
}
