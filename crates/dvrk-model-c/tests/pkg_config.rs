//! dvrk_model.pc.in works from an install prefix: install.sh puts the libraries this run
//! built, the headers and the filled-in template into a scratch prefix, then
//! `pkg-config --cflags --libs dvrk_model` (and `--static`) give the flags that compile,
//! link and run a C program calling the library. Skipped, visibly, without pkg-config
//! or cc.

use std::path::{Path, PathBuf};
use std::process::Command;

fn runs(program: &str) -> bool {
    Command::new(program)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The libraries this test run built, beside the test binary (target/<profile>/deps).
fn built(file: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let path = exe.parent().unwrap().join(file);
    assert!(path.exists(), "{} is missing", path.display());
    path
}

/// Installs into `prefix` with install.sh, from the libraries this run built; for the
/// static layout (`library` the .a) the shared library is removed, so the linker has
/// only the static one to take.
fn install(prefix: &Path, library: &str) {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let _ = std::fs::remove_dir_all(prefix);
    let libdir = built(library).parent().unwrap().to_path_buf();
    let out = Command::new("sh")
        .arg(crate_dir.join("install.sh"))
        .arg(prefix)
        .env("DVRK_MODEL_LIBDIR", &libdir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "install.sh: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pc = std::fs::read_to_string(prefix.join("lib/pkgconfig/dvrk_model.pc")).unwrap();
    assert!(!pc.contains('@'), "a placeholder is left:\n{pc}");
    assert!(
        pc.contains(&format!("Version: {}", env!("CARGO_PKG_VERSION"))),
        "{pc}"
    );
    for file in [
        "include/dvrk_model.h",
        "include/dvrk_model.hpp",
        "lib/cmake/dvrk_model/dvrk_modelConfig.cmake",
        "lib/cmake/dvrk_model/dvrk_modelConfigVersion.cmake",
    ] {
        assert!(prefix.join(file).is_file(), "install.sh left out {file}");
    }
    if library.ends_with(".a") {
        let dll = format!(
            "{}dvrk_model_c{}",
            std::env::consts::DLL_PREFIX,
            std::env::consts::DLL_SUFFIX
        );
        std::fs::remove_file(prefix.join("lib").join(dll)).unwrap();
    }
}

/// `pkg-config ARGS dvrk_model` against `prefix`: the flags, split.
fn flags(prefix: &Path, args: &[&str]) -> Vec<String> {
    let out = Command::new("pkg-config")
        .env("PKG_CONFIG_PATH", prefix.join("lib/pkgconfig"))
        .args(args)
        .arg("dvrk_model")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "pkg-config {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .split_whitespace()
        .map(String::from)
        .collect()
}

#[test]
fn pkg_config_flags_build_a_program() {
    for tool in ["pkg-config", "cc"] {
        if !runs(tool) {
            println!("SKIPPED: no {tool} on this machine");
            eprintln!("SKIPPED: no {tool} on this machine");
            return;
        }
    }
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("pkg_config");
    let source = scratch.join("version.c");
    std::fs::create_dir_all(&scratch).unwrap();
    std::fs::write(
        &source,
        "#include <dvrk_model.h>\n#include <stdio.h>\n\
         int main(void) { printf(\"%s %s\\n\", dvrk_version(), dvrk_error_string(DVRK_ERR_NULL)); \
         return dvrk_model_dof(NULL) == 0 ? 0 : 1; }\n",
    )
    .unwrap();
    let dll = format!(
        "{}dvrk_model_c{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    );
    // (prefix, library installed, pkg-config arguments): the static prefix holds only
    // the .a, so that program links the static library, with Libs.private.
    let layouts: [(&str, &str, &[&str]); 2] = [
        ("shared", &dll, &["--cflags", "--libs"]),
        (
            "static",
            "libdvrk_model_c.a",
            &["--static", "--cflags", "--libs"],
        ),
    ];
    for (name, library, args) in layouts {
        let prefix = scratch.join(name);
        install(&prefix, library);
        let flags = flags(&prefix, args);
        let include = format!("-I{}", prefix.join("include").display());
        assert!(flags.contains(&include), "{flags:?}");
        assert!(flags.contains(&"-ldvrk_model_c".to_string()), "{flags:?}");
        let exe = scratch.join(format!("version_{name}"));
        let mut cc = Command::new("cc");
        cc.args(["-O2", "-Wall", "-Werror", "-o"])
            .arg(&exe)
            .arg(&source)
            .args(&flags);
        if name == "shared" {
            cc.arg(format!("-Wl,-rpath,{}", prefix.join("lib").display()));
        }
        let compiled = cc.output().unwrap();
        assert!(
            compiled.status.success(),
            "{name}: {:?}\n{}",
            cc,
            String::from_utf8_lossy(&compiled.stderr)
        );
        let run = Command::new(&exe)
            .env_remove("LD_LIBRARY_PATH")
            .output()
            .unwrap();
        let stdout = String::from_utf8(run.stdout).unwrap();
        assert!(run.status.success(), "{name}: {stdout}");
        assert_eq!(
            stdout,
            format!("{} a pointer argument is NULL\n", env!("CARGO_PKG_VERSION")),
            "{name}"
        );
        println!("{name}: pkg-config {args:?} gives {flags:?}; the program runs");
    }
}
