//! What every CLI test needs: run the binary, a scratch folder, the bundled examples.
// Each test binary compiles this module and uses only part of it.
#![allow(dead_code)]

use std::path::Path;
use std::process::Command;

use dvrk_ident::joint_log::{uniform_time, Coordinates, JointLog};
use dvrk_model::{Model, Workspace};
use nalgebra::DMatrix;

/// Runs `dvrk-ident ARGS` with stdout and stderr piped: (success, stdout, stderr).
pub fn run(args: &[&str]) -> (bool, String, String) {
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

pub const ARM: &str = r#"<?xml version="1.0"?>
<!-- a three-joint arm for the export test -->
<robot name="arm">
  <link name="world"/>
  <link name="l1">
    <inertial>
      <origin xyz="0 0 0.1" rpy="0 0 0"/>
      <mass value="2"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/>
    </inertial>
    <visual><geometry><cylinder radius="0.05" length="0.2"/></geometry></visual>
  </link>
  <joint name="j1" type="revolute">
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <parent link="world"/>
    <child link="l1"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="20" velocity="2"/>
  </joint>
  <link name="l2">
    <inertial>
      <origin xyz="0.15 0 0" rpy="0 0 0"/>
      <mass value="1.5"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.012" iyz="0" izz="0.012"/>
    </inertial>
  </link>
  <joint name="j2" type="revolute">
    <origin xyz="0 0 0.2" rpy="1.5707963267948966 0 0"/>
    <parent link="l1"/>
    <child link="l2"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="20" velocity="2"/>
  </joint>
  <link name="l3">
    <inertial>
      <origin xyz="0.1 0.01 0" rpy="0.2 0 0"/>
      <mass value="0.8"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.004"/>
    </inertial>
  </link>
  <joint name="j3" type="revolute">
    <origin xyz="0.3 0 0" rpy="0 0 0"/>
    <parent link="l2"/>
    <child link="l3"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="20" velocity="2"/>
  </joint>
</robot>
"#;

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
    let traj = JointLog {
        time,
        q,
        dq: Some(dq),
        tau,
        joint_names: model.coordinates.clone(),
        coordinates: Coordinates::Model,
        source: "test".into(),
    };
    dvrk_ident::log::write(path, &traj, dvrk_ident::log::LogFormat::Wpi).unwrap();
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
