//! The C ABI from C: tests/c/smoke.c, compiled with the system's `cc -O2` against the
//! shared library this test run built, loads the SDP result of the bundled example
//! (fitted here through dvrk-ident, with a Stribeck term so the loader's Stribeck path
//! counts) and prints gravity, inverse dynamics, mass matrix, forward dynamics and the
//! measured-joint conversions for a few states; each is compared here with dvrk-model's
//! results for the model and parameters dvrk-ident reads from the same result
//! (`FitResult::model`, `params_for`: what `dvrk-ident model psm --torque --params
//! RESULT` evaluates) to 1e-12. The program also checks the error paths (NULL, NaN and
//! infinite inputs with outputs untouched, a workspace of another model, a bad path, a
//! result of an unknown robot) and exits non-zero on any failure. Both programs run the
//! momentum observer (`dvrk_observer_update`, C++ `dvrk::Observer`) over a simulated
//! motion with an external torque step, compared with `dvrk_model::MomentumObserver`
//! bit for bit, the C program with every error path of the update tried in the middle
//! of the run (the observer must come out of them untouched).

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::fit_example;
use dvrk_ident::FitResult;
use dvrk_model::Workspace;

/// The shared library this test run built: cargo builds the crate's cdylib and
/// staticlib beside the test binary (target/<profile>/deps), from the same sources.
/// Not target/<profile>/libdvrk_model_c.so, which only `cargo build` refreshes and may
/// be stale.
fn shared_library() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let dir = exe.parent().expect("its folder").to_path_buf();
    let lib = dir.join(format!(
        "{}dvrk_model_c{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    assert!(
        lib.exists(),
        "{} is missing: cargo builds the cdylib with the tests",
        lib.display()
    );
    lib
}

/// The system's compiler `default` (or the one `$var` names) if it runs, else None.
fn compiler(var: &str, default: &str) -> Option<String> {
    let cc = std::env::var(var).unwrap_or_else(|_| default.to_string());
    let found = Command::new(&cc).arg("--version").output();
    found.is_ok_and(|o| o.status.success()).then_some(cc)
}

/// A few states inside the PSM's ranges (joint 3, the insertion, in metres), one at rest
/// (`dq = ddq = 0`: the inverse dynamics is then the whole static torque).
fn states(n: usize) -> Vec<[Vec<f64>; 3]> {
    (0..4)
        .map(|k| {
            let s = |scale: f64, phase: f64| -> Vec<f64> {
                (0..n)
                    .map(|i| {
                        let x = scale * (1.3 * i as f64 + phase + k as f64).sin();
                        if i == 2 {
                            0.12 + 0.05 * x
                        } else {
                            x
                        }
                    })
                    .collect()
            };
            if k == 0 {
                [s(0.5, 0.0), vec![0.0; n], vec![0.0; n]]
            } else {
                [s(0.5, 0.0), s(0.8, 1.0), s(2.0, 2.0)]
            }
        })
        .collect()
}

/// The numbers after `label` on the next line of `lines` that starts with it.
fn take<'a>(lines: &mut impl Iterator<Item = &'a str>, label: &str) -> Vec<f64> {
    let line = lines
        .find(|l| l.starts_with(&format!("{label} ")))
        .unwrap_or_else(|| panic!("no `{label}` line"));
    line[label.len()..]
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect()
}

/// Largest difference relative to max(1, |expected|), asserting it is at most 1e-12.
fn compare(what: &str, got: &[f64], expected: &[f64]) -> f64 {
    assert_eq!(got.len(), expected.len(), "{what}: length");
    let worst = got
        .iter()
        .zip(expected)
        .map(|(g, e)| (g - e).abs() / e.abs().max(1.0))
        .fold(0.0, f64::max);
    assert!(
        worst <= 1e-12,
        "{what}: C {got:?} vs Rust {expected:?} (worst {worst:e})"
    );
    worst
}

#[test]
fn c_and_cpp_programs_reproduce_the_rust_model() {
    // (name, compiler, source, flags): the C API from C, the wrapper from C++.
    let programs: Vec<(&str, String, &str, &[&str])> = [
        (
            "C",
            compiler("CC", "cc"),
            "tests/c/smoke.c",
            &["-std=c99"][..],
        ),
        (
            "C++",
            compiler("CXX", "c++"),
            "tests/cpp/smoke.cpp",
            &["-std=c++11"][..],
        ),
    ]
    .into_iter()
    .filter_map(|(name, cc, source, flags)| match cc {
        Some(cc) => Some((name, cc, source, flags)),
        None => {
            // Visible in the test output (and with --nocapture) rather than a silent pass.
            println!("SKIPPED {name}: no {name} compiler on this machine");
            eprintln!("SKIPPED {name}: no {name} compiler on this machine");
            None
        }
    })
    .collect();
    if programs.is_empty() {
        return;
    }
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let result_path = fit_example("c_abi");
    let dir = result_path.parent().unwrap();

    // The Rust side: the model and parameters as dvrk-ident reads the result.
    let result = FitResult::read(&result_path).unwrap();
    let model = result.model(None).unwrap();
    let params = result.params_for(&model).unwrap();
    let n = model.dof();
    assert_eq!(
        model.n_params(),
        125,
        "115 PSM parameters and 10 Stribeck terms"
    );
    // The C library's loader reads the same model and parameters, bit for bit.
    let loaded = dvrk_model_c::DvrkModel::from_result(&result_path).unwrap();
    assert_eq!(loaded.model().param_names(), model.param_names());
    assert_eq!(
        loaded
            .params()
            .iter()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>(),
        params.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    );

    let mut ws = Workspace::new(&model);
    let cases = states(n);
    // Forward dynamics under the inverse dynamics' torque of another acceleration.
    let tau_fd: Vec<Vec<f64>> = cases
        .iter()
        .map(|[q, dq, ddq]| {
            let mut t = vec![0.0; n];
            let other: Vec<f64> = ddq.iter().map(|a| 0.5 * a - 0.7).collect();
            model.inverse_dynamics(&mut ws, &params, q, dq, &other, &mut t);
            model.add_known_forces(q, &mut t);
            t
        })
        .collect();
    let mut text = format!("{}\n", cases.len());
    for ([q, dq, ddq], t) in cases.iter().zip(&tau_fd) {
        for v in [q, dq, ddq, t] {
            let row: Vec<String> = v.iter().map(|x| format!("{x:e}")).collect();
            text += &(row.join(" ") + "\n");
        }
    }
    // The observer's run: a smooth motion whose torque is the inverse dynamics (known
    // forces included) plus a step of external torque from sample 100.
    let (samples, dt) = (400usize, 1e-3);
    let gains: Vec<f64> = (0..n).map(|i| 20.0 + 10.0 * i as f64).collect();
    let motion: Vec<[Vec<f64>; 3]> = (0..samples)
        .map(|k| {
            let t = k as f64 * dt;
            let (mut q, mut dq, mut ddq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            for i in 0..n {
                let (a, w, phase) = (
                    if i == 2 { 0.03 } else { 0.4 },
                    2.0 + 0.3 * i as f64,
                    i as f64,
                );
                let offset = if i == 2 { 0.12 } else { 0.0 };
                q[i] = offset + a * (w * t + phase).sin();
                dq[i] = a * w * (w * t + phase).cos();
                ddq[i] = -a * w * w * (w * t + phase).sin();
            }
            let mut tau = vec![0.0; n];
            model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
            model.add_known_forces(&q, &mut tau);
            if k >= 100 {
                for (i, t) in tau.iter_mut().enumerate() {
                    *t += 0.1 + 0.02 * i as f64;
                }
            }
            [q, dq, tau]
        })
        .collect();
    text += &format!("{samples} {dt:e}\n");
    text += &(gains
        .iter()
        .map(|g| format!("{g:e}"))
        .collect::<Vec<_>>()
        .join(" ")
        + "\n");
    for sample in &motion {
        let row: Vec<String> = sample.iter().flatten().map(|x| format!("{x:e}")).collect();
        text += &(row.join(" ") + "\n");
    }
    let mut observer = dvrk_model::MomentumObserver::new(&model, &gains).unwrap();
    let expected_obs: Vec<Vec<f64>> = motion
        .iter()
        .map(|[q, dq, tau]| {
            observer
                .update(&model, &mut ws, &params, q, dq, tau, dt)
                .to_vec()
        })
        .collect();
    // The step is seen: after six time constants of the slowest gain, every estimate is
    // the step to within the model's discretization (the observer's own test bounds it).
    for (i, r) in expected_obs[samples - 1].iter().enumerate() {
        let step = 0.1 + 0.02 * i as f64;
        assert!(
            (r - step).abs() < 1e-2 * step,
            "observer {i}: {r} vs {step}"
        );
    }
    let cases_path = dir.join("cases.txt");
    std::fs::write(&cases_path, text).unwrap();
    // A result of a robot nobody has: the document as fitted, another robot.
    let bad = std::fs::read_to_string(&result_path)
        .unwrap()
        .replace("\"builtin:psm\"", "\"builtin:nosuchbot\"");
    assert!(bad.contains("nosuchbot"));
    let bad_path = dir.join("unknown_robot.json");
    std::fs::write(&bad_path, bad).unwrap();

    // Compile and run the C and C++ programs against the shared library.
    let lib = shared_library();
    let minv = model.measured_to_model_matrix().unwrap();
    for (name, cc, source, flags) in programs {
        // Linked by its full path: the library has no soname, so the program records
        // that path and loads exactly this file, whatever the library search path holds
        // (cargo test puts target/<profile>, with a possibly stale build, on
        // LD_LIBRARY_PATH, which would win over an rpath).
        let exe = dir.join(format!("smoke_{}", if name == "C" { "c" } else { "cpp" }));
        let compiled = Command::new(&cc)
            .args(["-O2", "-Wall", "-Wextra", "-Werror"])
            .args(flags)
            .arg("-o")
            .arg(&exe)
            .arg(crate_dir.join(source))
            .arg("-I")
            .arg(crate_dir.join("include"))
            .arg(&lib)
            .arg("-lm")
            .output()
            .unwrap();
        assert!(
            compiled.status.success(),
            "{cc} {source} failed:\n{}",
            String::from_utf8_lossy(&compiled.stderr)
        );
        let run = Command::new(&exe)
            .env_remove("LD_LIBRARY_PATH")
            .arg(&result_path)
            .arg(&cases_path)
            .arg(&bad_path)
            .output()
            .unwrap();
        let stdout = String::from_utf8(run.stdout).unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            run.status.success(),
            "{name} program failed:\n{stderr}\nstdout:\n{stdout}"
        );
        assert!(stdout.contains("failures 0"), "{stdout}");
        assert!(
            stdout.contains(&format!("dof {n} measured {n} params 125")),
            "{stdout}"
        );
        assert!(stdout.contains("names q1 jaw Fs16"), "{stdout}");
        assert!(
            stdout.contains(&format!("version {}", env!("CARGO_PKG_VERSION"))),
            "{stdout}"
        );
        // The loading errors, each with its reason.
        if name == "C" {
            assert!(
                stdout.contains("null-path: result_path is NULL"),
                "{stdout}"
            );
        }
        assert!(
            stdout.contains("bad-path: /nonexistent/result.json: No such file"),
            "{stdout}"
        );
        let unknown = stdout
            .lines()
            .find(|l| l.starts_with("unknown-robot: "))
            .unwrap();
        assert!(unknown.contains("nosuchbot"), "{unknown}");

        // Every number of the program against dvrk-model's.
        let mut lines = stdout.lines();
        let mut worst = [0.0f64; 7];
        for ([q, dq, ddq], t) in cases.iter().zip(&tau_fd) {
            let mut g = vec![0.0; n];
            model.gravity_torque(&mut ws, &params, q, &mut g);
            worst[0] = worst[0].max(compare(
                &format!("{name}: gravity"),
                &take(&mut lines, "g"),
                &g,
            ));

            let mut tau = vec![0.0; n];
            model.inverse_dynamics(&mut ws, &params, q, dq, ddq, &mut tau);
            model.add_known_forces(q, &mut tau);
            worst[1] = worst[1].max(compare(
                &format!("{name}: inverse dynamics"),
                &take(&mut lines, "tau"),
                &tau,
            ));

            // The links alone, against dvrk-model's links-only functions: the nonlinear
            // effects at zero acceleration, the gravity at rest, and in general the
            // nonlinear effects plus the links' mass matrix (no motor inertia) times ddq,
            // that mass matrix from the links' parameters alone.
            let rigid = take(&mut lines, "rigid");
            let mut links = vec![0.0; model.n_params()];
            for &j in model.link_frames() {
                let p0 = model.frame(j).inertia.unwrap();
                links[p0..p0 + 10].copy_from_slice(&params[p0..p0 + 10]);
            }
            let mut h = vec![0.0; n];
            model.nonlinear_effects(&mut ws, &params, q, dq, &mut h);
            let m_links = model.mass_matrix(&mut ws, &links, q);
            let expected: Vec<f64> = (0..n)
                .map(|i| h[i] + (0..n).map(|k| m_links[(i, k)] * ddq[k]).sum::<f64>())
                .collect();
            worst[6] = worst[6].max(compare(
                &format!("{name}: rigid-body dynamics"),
                &rigid,
                &expected,
            ));
            if dq.iter().chain(ddq).all(|x| *x == 0.0) {
                compare(&format!("{name}: rigid-body dynamics at rest"), &rigid, &g);
            }

            let m = model.mass_matrix(&mut ws, &params, q);
            let row_major: Vec<f64> = (0..n * n).map(|k| m[(k / n, k % n)]).collect();
            // dvrk_mass_matrix hands over dvrk-model's column-major buffer as the
            // row-major matrix: right because M is symmetric to the bit.
            for i in 0..n {
                for j in 0..i {
                    assert_eq!(m[(i, j)].to_bits(), m[(j, i)].to_bits(), "M[{i},{j}]");
                }
            }
            worst[2] = worst[2].max(compare(
                &format!("{name}: mass matrix"),
                &take(&mut lines, "m"),
                &row_major,
            ));

            let acc = model.forward_dynamics(&mut ws, &params, q, dq, t).unwrap();
            let got = take(&mut lines, "ddq");
            worst[3] = worst[3].max(compare(
                &format!("{name}: forward dynamics"),
                &got,
                acc.as_slice(),
            ));
            // ... and it inverts the inverse dynamics (the acceleration the torque was for).
            for (a, d) in got.iter().zip(ddq) {
                assert!((a - (0.5 * d - 0.7)).abs() < 1e-8, "{got:?} vs {ddq:?}");
            }

            let from_measured: Vec<f64> = (0..n)
                .map(|i| (0..n).map(|k| minv[(i, k)] * q[k]).sum())
                .collect();
            worst[4] = worst[4].max(compare(
                &format!("{name}: measured to model"),
                &take(&mut lines, "from_measured"),
                &from_measured,
            ));
            // τ_measured = M⁻ᵀ τ_model: mapped back with Mᵀ it is the model torque.
            let to_measured = take(&mut lines, "to_measured");
            let back: Vec<f64> = (0..n)
                .map(|j| {
                    (0..n)
                        .map(|k| model.measured.coupling[(k, j)] * to_measured[k])
                        .sum()
                })
                .collect();
            worst[5] = worst[5].max(compare(
                &format!("{name}: model to measured torque"),
                &back,
                t,
            ));
        }
        // The observer, bit for bit, and zeros after its reset.
        for (k, expected) in expected_obs.iter().enumerate() {
            let got = take(&mut lines, "obs");
            assert_eq!(
                got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                expected.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "{name}: observer at sample {k}: {got:?} vs {expected:?}"
            );
        }
        assert_eq!(take(&mut lines, "obs-reset"), vec![0.0; n], "{name}");
        println!(
            "{name}: worst relative differences vs Rust: gravity {:e}, inverse dynamics {:e}, mass \
             matrix {:e}, forward dynamics {:e}, measured to model {:e}, torque round trip {:e}, rigid-body dynamics {:e}",
            worst[0], worst[1], worst[2], worst[3], worst[4], worst[5], worst[6]
        );
    }
}

/// The README's C++ example is tests/cpp/readme.cpp, word for word, and it compiles and
/// runs on the example's fit: the static torque at rest it prints is the inverse
/// dynamics at `dq = ddq = 0` of dvrk-model (printed to 6 decimals).
#[test]
fn readme_cpp_example_runs() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(crate_dir.join("README.md")).unwrap();
    let source = std::fs::read_to_string(crate_dir.join("tests/cpp/readme.cpp")).unwrap();
    let start = readme.find("```cpp\n").expect("a C++ block in the README") + 7;
    let end = start + readme[start..].find("```").unwrap();
    assert_eq!(
        &readme[start..end],
        source,
        "README.md's C++ block is not tests/cpp/readme.cpp"
    );
    let Some(cxx) = compiler("CXX", "c++") else {
        println!("SKIPPED: no C++ compiler on this machine");
        eprintln!("SKIPPED: no C++ compiler on this machine");
        return;
    };
    let result_path = fit_example("c_abi_readme");
    let exe = result_path.with_file_name("readme");
    let compiled = Command::new(&cxx)
        .args(["-O2", "-std=c++11", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(crate_dir.join("tests/cpp/readme.cpp"))
        .arg("-I")
        .arg(crate_dir.join("include"))
        .arg(shared_library())
        .output()
        .unwrap();
    assert!(
        compiled.status.success(),
        "{}",
        String::from_utf8_lossy(&compiled.stderr)
    );
    let run = Command::new(&exe)
        .env_remove("LD_LIBRARY_PATH")
        .arg(&result_path)
        .output()
        .unwrap();
    let stdout = String::from_utf8(run.stdout).unwrap();
    assert!(run.status.success(), "{stdout}");
    let result = FitResult::read(&result_path).unwrap();
    let model = result.model(None).unwrap();
    let params = result.params_for(&model).unwrap();
    let n = model.dof();
    let mut q = vec![0.1; n];
    q[2] = 0.12;
    let mut tau = vec![0.0; n];
    let mut ws = Workspace::new(&model);
    model.inverse_dynamics(&mut ws, &params, &q, &vec![0.0; n], &vec![0.0; n], &mut tau);
    model.add_known_forces(&q, &mut tau);
    let expected: Vec<String> = tau.iter().map(|t| format!("{t:.6}")).collect();
    let line = format!("static torque {}", expected.join(" "));
    assert!(stdout.contains(&line), "{stdout}\nexpected: {line}");
    println!("{stdout}");
}

/// A result document of the built-in PSM with these parameters (by name) and fit
/// settings, written into a folder `label` of the test's scratch space (what the loader
/// reads of a result).
fn psm_result(
    label: &str,
    names: &[String],
    params: &[f64],
    settings: serde_json::Value,
) -> PathBuf {
    let named: serde_json::Map<String, serde_json::Value> = names
        .iter()
        .zip(params)
        .map(|(n, v)| (n.to_string(), (*v).into()))
        .collect();
    let doc = serde_json::json!({
        "robot": "psm",
        "robot_source": "builtin:psm",
        "settings": settings,
        "parameters": named,
    });
    let path = common::scratch_dir(label).join("result.json");
    std::fs::write(&path, doc.to_string()).unwrap();
    path
}

/// A result fitted with `--position-torque 1 --load-friction` loads (its `Pca`, `Psa`
/// and `Fl` parameters are part of the model, in dvrk-ident's order), and the ABI's
/// inverse dynamics is the prediction with the load solved for
/// (`Model::loaded_inverse_dynamics`), to the bit. No compiler needed.
#[test]
fn a_result_with_position_torque_and_load_friction_loads() {
    let psm = dvrk_model::Model::builtin("psm").unwrap();
    let model = psm.with_position_torque(1).unwrap().with_load_friction();
    let names = model.param_names();
    let params: Vec<f64> = (0..model.n_params())
        .map(|k| 0.01 * ((k % 7) as f64 + 1.0))
        .collect();
    let settings = serde_json::json!({ "position_torque_order": 1, "load_friction": true });
    let path = psm_result("c_abi_elements", &names, &params, settings);
    let loaded = dvrk_model_c::DvrkModel::from_result(&path).unwrap();
    assert_eq!(loaded.model().param_names(), names);
    let (q, dq, ddq) = ([0.1, -0.2, 0.12, 0.3, -0.1, 0.2, 0.4], [0.5; 7], [-0.3; 7]);
    let mut want = [0.0; 7];
    let mut ws = Workspace::new(&model);
    model.loaded_inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut want);
    let mut got = [0.0; 7];
    // SAFETY: live model and workspace of this thread, arrays of the model's dof.
    unsafe {
        let w = dvrk_model_c::dvrk_workspace_new(&loaded);
        let rc = dvrk_model_c::dvrk_inverse_dynamics(
            &loaded,
            w,
            q.as_ptr(),
            dq.as_ptr(),
            ddq.as_ptr(),
            got.as_mut_ptr(),
        );
        dvrk_model_c::dvrk_workspace_free(w);
        assert_eq!(rc, 0);
    }
    assert_eq!(got, want, "the PSM has no known forces");
    // The load friction did something: with every `Fl` at 0 the torques differ by more
    // than rounding.
    let without: Vec<f64> = names
        .iter()
        .zip(&params)
        .map(|(n, &v)| if n.starts_with("Fl") { 0.0 } else { v })
        .collect();
    let mut plain = [0.0; 7];
    model.loaded_inverse_dynamics(&mut ws, &without, &q, &dq, &ddq, &mut plain);
    assert!(got.iter().zip(&plain).any(|(a, b)| (a - b).abs() > 1e-4));
}

/// `dvrk_gravity` and `dvrk_mass_matrix` write straight into the caller's buffer when
/// the model's bounds prove the result finite (`|q| ≤ 1e6`), and check their result
/// otherwise: both paths give dvrk-model's numbers to the bit (within the bound, and at
/// an insertion of 1e7 m, beyond it but finite), and an insertion of 1e300 m, whose
/// mass matrix overflows, is `DVRK_ERR_OVERFLOW` with the output untouched. No compiler
/// needed.
#[test]
fn gravity_and_mass_matrix_are_bit_exact_on_both_paths_and_refuse_overflow() {
    use dvrk_model_c::*;
    let model = dvrk_model::Model::builtin("psm").unwrap();
    let names = model.param_names();
    let params: Vec<f64> = (0..model.n_params())
        .map(|k| 0.02 * ((k % 5) as f64 + 1.0))
        .collect();
    let path = psm_result("c_abi_bounded", &names, &params, serde_json::json!({}));
    let loaded = DvrkModel::from_result(&path).unwrap();
    let mut ws = Workspace::new(&model);
    for insertion in [0.12, -3e5, 1e7, 1e300] {
        let q = [0.1, -0.2, insertion, 0.3, -0.1, 0.2, 0.4];
        let (mut g, mut m) = ([0.0; 7], [0.0; 49]);
        model.gravity_torque(&mut ws, &params, &q, &mut g);
        model.mass_matrix_into(&mut ws, &params, &q, &mut m);
        let (mut got_g, mut got_m) = ([-1.5; 7], [-1.5; 49]);
        // SAFETY: a live model and a workspace of this thread, arrays of 7 and 49.
        let (rc_g, rc_m) = unsafe {
            let w = dvrk_workspace_new(&loaded);
            let rc = (
                dvrk_gravity(&loaded, w, q.as_ptr(), got_g.as_mut_ptr()),
                dvrk_mass_matrix(&loaded, w, q.as_ptr(), got_m.as_mut_ptr()),
            );
            dvrk_workspace_free(w);
            rc
        };
        // At 1e300 m the mass matrix (m·t²) overflows; the gravity torque (m·g·t) may.
        assert_eq!(
            m.iter().all(|x| x.is_finite()),
            insertion != 1e300,
            "insertion {insertion}"
        );
        for (what, rc, got, want, sentinel) in [
            ("gravity", rc_g, &got_g[..], &g[..], [-1.5; 7].as_slice()),
            (
                "mass matrix",
                rc_m,
                &got_m[..],
                &m[..],
                [-1.5; 49].as_slice(),
            ),
        ] {
            if want.iter().all(|x| x.is_finite()) {
                assert_eq!(rc, DVRK_OK, "{what} at insertion {insertion}");
                assert_eq!(got, want, "{what} at insertion {insertion}");
            } else {
                assert_eq!(rc, DVRK_ERR_OVERFLOW, "{what} at insertion {insertion}");
                assert_eq!(got, sentinel, "{what}: untouched");
            }
        }
    }
}
