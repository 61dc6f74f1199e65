//! What the workspace's integration tests share, in one place (a `publish = false`
//! crate, a dev-dependency of each library crate):
//!
//! - [`shared`]: a file of the `shared/` folder beside the repository (reference data of
//!   independent tools, real dVRK logs), or `None` after a **counted skip**: [`skip`]
//!   prints `SKIPPED: ...` and appends the test and the reason to
//!   `target/skipped-tests.txt`, which `.ci/run` lists after the test run, so skips
//!   are visible in the summary instead of passing silently;
//! - [`temp_dir`]: a fresh scratch folder per test;
//! - [`repo`], [`example`]: the repository and its bundled examples;
//! - [`Rng`]: a seeded SplitMix64, the same numbers on every machine, and the one
//!   generator of the workspace's tests (uniform and normal deviates, raw `u64`s; unit
//!   tests use it too); random states and parameters, physically consistent ones
//!   included;
//! - [`PlanarTwoLink`]: the textbook closed form of a two-link arm's dynamics;
//! - [`models`]: robot descriptions the tests of several crates share (`tests/fixtures/`);
//! - [`cisst`]: the dVRK controller's DH kinematics and gravity compensation (cisst's
//!   `robManipulator::CCG_MDH` and the arms' joint maps), transcribed;
//! - [`fixtures`]: a scratch folder removed on drop, the bundled example's generating
//!   parameters, the check that a fit recovers known parameters.
#![allow(clippy::missing_panics_doc)]
// No unsafe code: the workspace's unsafe code is in crates/lapack-faer (the Fortran-ABI
// BLAS/LAPACK Clarabel calls) and crates/dvrk-model-c (the C ABI).
#![forbid(unsafe_code)]

pub mod cisst;
pub mod fixtures;
pub mod models;

use std::io::Write;
use std::path::{Path, PathBuf};

use dvrk_model::{inertia, Model, ParamKind, Workspace};
use nalgebra::{Matrix3, UnitQuaternion, Vector4};

/// The repository's root folder.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A file of the repository's `examples/`.
pub fn example(name: &str) -> PathBuf {
    repo().join("examples").join(name)
}

/// `rel` under the `shared/` folder beside the repository, or `None` after a counted
/// [`skip`] when it is absent, so that the project's own tests pass without it.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let path = repo().join("../shared").join(rel);
    if path.exists() {
        Some(path)
    } else {
        skip(format!("{} not found (../shared absent)", path.display()));
        None
    }
}

/// Records that the running test skips its checks: prints `SKIPPED: reason` and appends
/// `test: reason` to `target/skipped-tests.txt` (read by `.ci/run`).
pub fn skip(reason: impl std::fmt::Display) {
    let test = std::thread::current()
        .name()
        .unwrap_or("(unnamed)")
        .to_string();
    eprintln!("SKIPPED: {test}: {reason}");
    // The test binary is target/<profile>/deps/<name>: the target folder is three up.
    let Some(target) = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.ancestors().nth(3).map(Path::to_path_buf))
    else {
        return;
    };
    let binary = std::env::current_exe()
        .ok()
        .and_then(|e| e.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_default();
    let binary = binary.rsplit_once('-').map_or(binary.as_str(), |(b, _)| b);
    if let Ok(mut f) = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(target.join("skipped-tests.txt"))
    {
        // One write per line: lines of tests running in parallel do not interleave.
        let _ = f.write_all(format!("{binary}::{test}: {reason}\n").as_bytes());
    }
}

/// A fresh, empty folder for one test, named by `tag` and the process id.
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dvrk-test-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create a scratch folder");
    d
}

/// A JSON file's document.
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("read")).expect("JSON")
}

/// A JSON array of numbers.
pub fn f64s(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .expect("an array")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

/// SplitMix64: tiny, seeded, the same on every machine. The random inputs of every test
/// of the workspace come from it (a test that needs them takes a seed, never a generator
/// of its own); the generators that are part of the behaviour (excitation starts,
/// simulation noise, base-parameter samples) are the libraries' own.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let u = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }

    /// A standard normal deviate (Box–Muller on two uniforms in (0, 1]).
    pub fn normal(&mut self) -> f64 {
        let mut open = || ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64;
        let (u, v) = (open(), open());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    pub fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }

    /// A random rotation (normalized random quaternion).
    pub fn rotation(&mut self) -> Matrix3<f64> {
        loop {
            let v = Vector4::new(
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
                self.uniform(-1.0, 1.0),
            );
            if v.norm() > 0.1 {
                let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::from(v));
                return q.to_rotation_matrix().into_inner();
            }
        }
    }
}

/// A random state `(q, q̇, q̈)`.
pub fn random_state(model: &Model, rng: &mut Rng) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = model.dof();
    (
        rng.vec(n, -1.2, 1.2),
        rng.vec(n, -2.0, 2.0),
        rng.vec(n, -3.0, 3.0),
    )
}

/// Arbitrary (not necessarily physical) parameters in [-1, 1].
pub fn random_params(model: &Model, rng: &mut Rng) -> Vec<f64> {
    rng.vec(model.n_params(), -1.0, 1.0)
}

pub use dvrk_model::inertia::sym6;

/// The configuration of every property test: `cases` cases from one fixed seed, and no
/// failure files, so a run is the same on every machine and writes nothing.
#[cfg(feature = "proptest")]
pub fn fixed_seed_config(cases: u32) -> proptest::test_runner::Config {
    use proptest::test_runner::{Config, RngSeed};
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x005e_ed19),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A random positive-definite inertia about the centre of mass that a real mass
/// distribution realizes (principal moments from positive second moments, so the
/// triangle inequalities hold), in random principal axes.
pub fn random_inertia_com(mass: f64, rng: &mut Rng) -> [f64; 6] {
    let (a, b, c) = (
        mass * rng.uniform(1e-4, 1e-2),
        mass * rng.uniform(1e-4, 1e-2),
        mass * rng.uniform(1e-4, 1e-2),
    );
    let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(b + c, a + c, a + b));
    let r = rng.rotation();
    sym6(&(r * d * r.transpose()))
}

/// Physically consistent random parameters: every link a positive mass, a centre of mass
/// and a positive-definite inertia about it; positive friction, motor inertias, springs.
pub fn physical_params(model: &Model, rng: &mut Rng) -> Vec<f64> {
    let mut pi = vec![f64::NAN; model.n_params()];
    for f in &model.frames {
        if let Some(p0) = f.inertia {
            let m = rng.uniform(0.2, 2.0);
            let com = [
                rng.uniform(-0.15, 0.15),
                rng.uniform(-0.15, 0.15),
                rng.uniform(-0.15, 0.15),
            ];
            let ic = random_inertia_com(m, rng);
            let bary = inertia::barycentric_from_standard(m, com, ic);
            assert!(inertia::pseudo_inertia_min_eigenvalue(&bary) > 0.0);
            pi[p0..p0 + 10].copy_from_slice(&bary);
        }
        if let Some(fr) = f.friction() {
            pi[fr.param] = rng.uniform(0.01, 0.3);
            pi[fr.param + 1] = rng.uniform(0.01, 0.3);
            pi[fr.param + 2] = rng.uniform(-0.2, 0.2);
        }
        if let Some(mi) = f.motor_inertia() {
            pi[mi.param] = rng.uniform(0.01, 0.1);
        }
        if let Some(sp) = f.spring() {
            pi[sp.param] = rng.uniform(0.1, 2.0);
        }
    }
    assert!(pi.iter().all(|x| x.is_finite()), "every parameter was set");
    pi
}

/// Coulomb (N·m), viscous (N·m·s/rad) and offset (N·m) friction from a frame's bounds.
pub type FrictionRule = Box<dyn Fn(&dvrk_model::FrameBounds) -> [f64; 3]>;

/// How [`ParamRule::params`] picks each link's and element's value from the description's
/// bounds: deterministic parameters inside them, the same every run (the examples, the
/// synthetic fits and the command-line tests each keep their own rule).
pub struct ParamRule {
    /// A link's mass (kg) from its bounds (`None`: the link has none).
    pub mass: Box<dyn Fn(Option<[f64; 2]>) -> f64>,
    /// A link's inertia about its centre of mass (kg·m², xx xy xz yy yz zz) from its mass.
    pub inertia_com: Box<dyn Fn(f64) -> [f64; 6]>,
    /// Coulomb (N·m), viscous (N·m·s/rad) and offset (N·m) friction from the frame's
    /// bounds.
    pub friction: FrictionRule,
    /// Every motor inertia, kg·m².
    pub motor_inertia: f64,
    /// A spring's stiffness from its bounds.
    pub spring: Box<dyn Fn(Option<[f64; 2]>) -> f64>,
}

/// The inertia of a 6 x 5 x 4 cm box of mass `m` about its centre, kg·m².
pub fn box_inertia(m: f64) -> [f64; 6] {
    let (x, y, z) = (0.06, 0.05, 0.04);
    [
        m * (y * y + z * z) / 12.0,
        0.0,
        0.0,
        m * (x * x + z * z) / 12.0,
        0.0,
        m * (x * x + y * y) / 12.0,
    ]
}

/// Coulomb 0.5, viscous 0.3 and offset 0.2 of their maxima (0.1 without).
pub fn friction_within_bounds(b: &dvrk_model::FrameBounds) -> [f64; 3] {
    [
        0.5 * b.fc_max.unwrap_or(0.1),
        0.3 * b.fv_max.unwrap_or(0.1),
        0.2 * b.fo_max.unwrap_or(0.1),
    ]
}

/// A spring at mid-range of its bounds (0.1 without).
pub fn mid_spring(b: Option<[f64; 2]>) -> f64 {
    b.map_or(0.1, |[a, b]| 0.5 * (a + b))
}

impl ParamRule {
    /// The parameters of `model` by this rule, each link's centre of mass at the middle
    /// of its box.
    pub fn params(&self, model: &Model) -> Vec<f64> {
        let mut pi = vec![0.0; model.n_params()];
        for f in &model.frames {
            if let Some(p0) = f.inertia {
                let m = (self.mass)(f.bounds.mass);
                let c = f.bounds.com.map_or([0.0; 3], |b| {
                    [
                        0.5 * (b[0][0] + b[0][1]),
                        0.5 * (b[1][0] + b[1][1]),
                        0.5 * (b[2][0] + b[2][1]),
                    ]
                });
                let ic = (self.inertia_com)(m);
                pi[p0..p0 + 10].copy_from_slice(&inertia::barycentric_from_standard(m, c, ic));
            }
            if let Some(fr) = f.friction() {
                pi[fr.param..fr.param + 3].copy_from_slice(&(self.friction)(&f.bounds));
            }
            if let Some(mi) = f.motor_inertia() {
                pi[mi.param] = self.motor_inertia;
            }
            if let Some(sp) = f.spring() {
                pi[sp.param] = (self.spring)(f.bounds.spring);
            }
        }
        pi
    }
}

/// The command-line and streaming tests' MTM rule: 1.5 times each lower mass bound, a
/// small diagonal inertia, Coulomb `coulomb` (N·m), viscous 0.02, offset 0.01, motor
/// inertias 0.005, springs 270.
pub fn mtm_rule(coulomb: f64) -> ParamRule {
    ParamRule {
        mass: Box::new(|b| b.map_or(1.0, |[a, _]| 1.5 * a)),
        inertia_com: Box::new(|m| {
            let d = 0.05 * m;
            [d * 0.01, 0.0, 0.0, d * 0.012, 0.0, d * 0.008]
        }),
        friction: Box::new(move |_| [coulomb, 0.02, 0.01]),
        motor_inertia: 0.005,
        spring: Box::new(|_| 270.0),
    }
}

/// Copy of `params` keeping only the parameters for which `keep` is true (others 0).
pub fn filter_params(model: &Model, params: &[f64], keep: impl Fn(ParamKind) -> bool) -> Vec<f64> {
    model
        .params
        .iter()
        .zip(params)
        .map(|(p, &v)| if keep(p.kind) { v } else { 0.0 })
        .collect()
}

/// True for friction and spring parameters.
pub fn is_friction_or_spring(kind: ParamKind) -> bool {
    matches!(
        kind,
        ParamKind::Coulomb | ParamKind::Viscous | ParamKind::Offset | ParamKind::Spring
    )
}

/// Inverse dynamics into a new vector.
pub fn id(
    model: &Model,
    ws: &mut Workspace,
    params: &[f64],
    q: &[f64],
    dq: &[f64],
    ddq: &[f64],
) -> Vec<f64> {
    let mut tau = vec![0.0; model.dof()];
    model.inverse_dynamics(ws, params, q, dq, ddq, &mut tau);
    tau
}

/// `H(q, q̇, q̈)·π` from the regressor, its arguments in the formula's order: the torque
/// the identity `H·π = inverse dynamics` compares with.
pub fn regressor_times(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    dq: &[f64],
    ddq: &[f64],
    params: &[f64],
) -> Vec<f64> {
    let h = model.regressor(ws, q, dq, ddq);
    (h * nalgebra::DVector::from_column_slice(params))
        .iter()
        .copied()
        .collect()
}

/// Asserts `|a - b| <= tol * scale` element-wise, scale = max(1, max |b|).
#[track_caller]
pub fn assert_close(what: &str, a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tol * scale,
            "{what}[{k}]: {x} vs {y} (diff {:e}, tol {:e})\n  got {a:?}\n  expected {b:?}",
            (x - y).abs(),
            tol * scale
        );
    }
}

/// Largest |τ_a − τ_b| (inverse dynamics) over 40 random states, coordinates matched by
/// name; `a` uses `pa` and `b` uses `pb` (e.g. a model and the same robot read back
/// from an exported URDF).
pub fn torque_difference(a: &Model, pa: &[f64], b: &Model, pb: &[f64], seed: u64) -> f64 {
    assert_eq!(a.dof(), b.dof(), "number of coordinates");
    let perm: Vec<usize> = b
        .coordinates
        .iter()
        .map(|c| {
            a.coordinates
                .iter()
                .position(|d| d == c)
                .unwrap_or_else(|| panic!("coordinate {c} of the URDF is not the model's"))
        })
        .collect();
    let mut rng = Rng::new(seed);
    let (mut wa, mut wb) = (Workspace::new(a), Workspace::new(b));
    let mut worst = 0.0f64;
    for _ in 0..40 {
        let (q, dq, ddq) = random_state(a, &mut rng);
        let pick = |v: &[f64]| perm.iter().map(|&k| v[k]).collect::<Vec<f64>>();
        let ta = id(a, &mut wa, pa, &q, &dq, &ddq);
        let tb = id(b, &mut wb, pb, &pick(&q), &pick(&dq), &pick(&ddq));
        assert!(
            ta.iter().any(|t| t.abs() > 1e-3),
            "the test moves something"
        );
        for (j, &k) in perm.iter().enumerate() {
            worst = worst.max((ta[k] - tb[j]).abs());
        }
    }
    worst
}

/// The rigid-body parameters of `params` (friction, motor inertias, springs zeroed).
pub fn rigid_only(model: &Model, params: &[f64]) -> Vec<f64> {
    filter_params(model, params, |k| matches!(k, ParamKind::Inertia { .. }))
}

/// A planar arm of two revolute joints, the textbook closed form of its dynamics (Spong,
/// Hutchinson & Vidyasagar, Robot Modeling and Control, §7.4): angles `q` (rad) from the
/// horizontal, gravity `gravity` (m/s²) pulling down in the plane of motion.
#[derive(Clone, Copy, Debug)]
pub struct PlanarTwoLink {
    /// Link masses (kg).
    pub mass: [f64; 2],
    /// Distance of each link's centre of mass from its joint, along the link (m).
    pub com: [f64; 2],
    /// Each link's moment of inertia about its centre of mass, about the joint axes (kg·m²).
    pub inertia: [f64; 2],
    /// Length of the first link: the second joint's distance from the first (m).
    pub length: f64,
    /// Gravity's magnitude (m/s²).
    pub gravity: f64,
}

impl PlanarTwoLink {
    /// The arm the closed-form tests of several files share: links of unequal mass, each
    /// centre of mass off its link's middle, so no term of the closed form vanishes.
    pub const EXAMPLE: PlanarTwoLink = PlanarTwoLink {
        mass: [2.5, 1.5],
        com: [0.3, 0.25],
        inertia: [0.08, 0.05],
        length: 0.7,
        gravity: 9.81,
    };

    /// The mass matrix (kg·m²).
    pub fn mass_matrix(&self, q: [f64; 2]) -> [[f64; 2]; 2] {
        let (m, lc, i, l1) = (self.mass, self.com, self.inertia, self.length);
        let c2 = q[1].cos();
        let m11 = i[0]
            + i[1]
            + m[0] * lc[0] * lc[0]
            + m[1] * (l1 * l1 + lc[1] * lc[1] + 2.0 * l1 * lc[1] * c2);
        let m12 = i[1] + m[1] * (lc[1] * lc[1] + l1 * lc[1] * c2);
        let m22 = i[1] + m[1] * lc[1] * lc[1];
        [[m11, m12], [m12, m22]]
    }

    /// Coriolis and centrifugal torques `C(q, q̇)·q̇` (N·m).
    pub fn coriolis(&self, q: [f64; 2], dq: [f64; 2]) -> [f64; 2] {
        let h = self.mass[1] * self.length * self.com[1] * q[1].sin();
        [
            -h * (2.0 * dq[0] * dq[1] + dq[1] * dq[1]),
            h * dq[0] * dq[0],
        ]
    }

    /// Gravity torques `g(q)` (N·m).
    pub fn gravity_torque(&self, q: [f64; 2]) -> [f64; 2] {
        let (m, lc, g) = (self.mass, self.com, self.gravity);
        let g2 = m[1] * lc[1] * g * (q[0] + q[1]).cos();
        [
            (m[0] * lc[0] + m[1] * self.length) * g * q[0].cos() + g2,
            g2,
        ]
    }

    /// Inverse dynamics `M(q)·q̈ + C(q, q̇)·q̇ + g(q)` (N·m).
    pub fn torque(&self, q: [f64; 2], dq: [f64; 2], ddq: [f64; 2]) -> [f64; 2] {
        let (mm, c, g) = (
            self.mass_matrix(q),
            self.coriolis(q, dq),
            self.gravity_torque(q),
        );
        [0, 1].map(|k| mm[k][0] * ddq[0] + mm[k][1] * ddq[1] + c[k] + g[k])
    }
}
