//! Long (but legitimate) expressions in a description: loading must not crash.
//!
//! A stack overflow aborts the whole process, so the load runs in a child process (this
//! test binary re-run on the one test) on a thread with the default 2 MiB stack of
//! `std::thread` and of the test harness.

// Reads descriptions (TOML, URDF): needs the default `description` feature.
#![cfg(feature = "description")]

use std::process::Command;

use dvrk_model::{Model, Workspace};

const CHILD_ENV: &str = "DVRK_MODEL_LONG_EXPRESSION_CHILD";

/// `c0 + c1*q1^1 + ... + c_deg*q1^deg`, and its value at `x`.
fn polynomial(deg: usize) -> (String, impl Fn(f64) -> f64) {
    let coef = |k: usize| 0.1 * (k + 1) as f64;
    let text = (0..=deg)
        .map(|k| format!("{}*q1^{k}", coef(k)))
        .collect::<Vec<_>>()
        .join(" + ");
    (text, move |x: f64| {
        (0..=deg).map(|k| coef(k) * x.powi(k as i32)).sum()
    })
}

fn load_and_check(deg: usize) {
    let (spring, value) = polynomial(deg);
    let text = format!(
        "name = \"poly spring\"\nconvention = \"modified\"\ncoordinates = [\"q1\"]\n\
         [[frames]]\nname = \"j1\"\nparent = \"base\"\ntheta = \"q1\"\nspring = \"{spring}\"\n"
    );
    let model = Model::from_toml_str(&text, "poly.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut ws = Workspace::new(&model);
    let mut tau = [0.0];
    let x = 0.37;
    model.inverse_dynamics(&mut ws, &[2.0], &[x], &[0.0], &[0.0], &mut tau);
    // tau -= a·K·dl(q) with a = 1, K = 2.
    let expect = -2.0 * value(x);
    assert!(
        (tau[0] - expect).abs() < 1e-12 * expect.abs(),
        "{} vs {expect}",
        tau[0]
    );
}

/// Runs `test` (this binary's test of that name) in a child process; the child runs
/// `body` on a 2 MiB thread.
fn in_child(test: &str, body: fn()) {
    if std::env::var_os(CHILD_ENV).is_some() {
        std::thread::Builder::new()
            .stack_size(2 << 20)
            .spawn(body)
            .unwrap()
            .join()
            .unwrap();
        return;
    }
    let out = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", test, "--nocapture", "--test-threads=1"])
        .env(CHILD_ENV, "1")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{test}: child process failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn short_polynomial_spring_loads() {
    in_child("short_polynomial_spring_loads", || load_and_check(7));
}

/// A degree-9 polynomial spring (30 operands, the longest evaluated on the stack)
/// loads and evaluates correctly on a 2 MiB thread: nothing recursive runs on it.
#[test]
fn long_polynomial_spring_loads() {
    in_child("long_polynomial_spring_loads", || load_and_check(9));
}

/// A degree-24 polynomial (75 operands) is refused with an error naming the frame and
/// field — not a crash, and not a model whose real-time calls would allocate.
#[test]
fn too_long_polynomial_spring_is_an_error() {
    in_child("too_long_polynomial_spring_is_an_error", || {
        let (spring, _) = polynomial(24);
        let text = format!(
            "name = \"poly spring\"\nconvention = \"modified\"\ncoordinates = [\"q1\"]\n\
             [[frames]]\nname = \"j1\"\nparent = \"base\"\ntheta = \"q1\"\nspring = \"{spring}\"\n"
        );
        let err = Model::from_toml_str(&text, "poly.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("poly.toml") && err.contains("j1") && err.contains("spring"),
            "{err}"
        );
        assert!(err.contains("75 operands"), "{err}");
    });
}
