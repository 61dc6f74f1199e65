//! The hostile corpus (`tests/hostile/cases.toml`, described in `tests/hostile/README.md`)
//! run through the command line: every case gives its expected exit code and message,
//! and no case may panic, hang, leave an output behind or print a non-finite number.
//!
//! The per-case time limit only guards against a hang (a case that exceeds it fails);
//! whether a case passes is decided by its exit code and output, never by its time.

mod support;

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde::Deserialize;

/// A case that runs longer than this has hung (the slowest case takes a few seconds).
const HANG_LIMIT: Duration = Duration::from_secs(300);

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    #[serde(rename = "case")]
    cases: Vec<Case>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Case {
    name: String,
    /// What kind of input it attacks (descriptions, urdf, csv, ...): the README's table.
    kind: String,
    args: Vec<String>,
    /// Expected exit code.
    exit: i32,
    /// A fragment of stderr (error cases) or stdout (exit 0).
    message: String,
    /// Text files written into the case's folder first (name → content).
    #[serde(default)]
    files: BTreeMap<String, String>,
    /// Files made from others: a copy truncated, with bytes flipped, or repeated text.
    #[serde(default)]
    derive: Vec<Derive>,
    /// Symbolic links made in the case's folder (link → target).
    #[serde(default)]
    links: BTreeMap<String, String>,
    /// A copy of /dev/null (`mknod c 1 3`) with this name, when this user may make
    /// one (else the case is skipped, visibly).
    #[serde(default)]
    null_device: Option<String>,
    /// Files an exit-0 case must have written (folder-relative).
    #[serde(default)]
    outputs: Vec<String>,
    /// Files (folder-relative) whose content must be the same after the case (inputs
    /// given as outputs too).
    #[serde(default)]
    unchanged: Vec<String>,
    /// Needs `../shared` (skipped, visibly, when it is absent).
    #[serde(default)]
    shared: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Derive {
    /// File written into the case's folder.
    name: String,
    /// Source file (placeholders allowed), or none with `text`.
    #[serde(default)]
    from: Option<String>,
    /// Keep only the first N bytes.
    #[serde(default)]
    truncate: Option<usize>,
    /// XOR these byte offsets with 0xFF.
    #[serde(default)]
    flip: Vec<usize>,
    /// XOR these byte offsets counted from the end (1: the last byte) with 0xFF.
    #[serde(default)]
    flip_end: Vec<usize>,
    /// Text replacements in the JSON header of an observation state (`from` a state
    /// file), its length field rewritten to match: a state forged consistently.
    #[serde(default)]
    state_header: BTreeMap<String, String>,
    /// Text written `repeat` times (after `from`'s content and `prefix`, before
    /// `suffix`), `{n}` replaced by the repetition's index (0-based).
    #[serde(default)]
    text: Option<String>,
    #[serde(default = "one")]
    repeat: usize,
    #[serde(default)]
    prefix: String,
    #[serde(default)]
    suffix: String,
    /// JSON edits of `from` (a JSON document): pointer → new value.
    #[serde(default)]
    json_set: BTreeMap<String, toml::Value>,
}

fn one() -> usize {
    1
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn shared_data() -> PathBuf {
    repo().join("../shared/data/dvrk")
}

/// Replaces `{tmp}`, `{examples}`, `{fixtures}`, `{shared}` and `{work}`.
fn expand(text: &str, tmp: &Path, work: &Path) -> String {
    text.replace("{tmp}", &tmp.display().to_string())
        .replace("{examples}", &repo().join("examples").display().to_string())
        .replace(
            "{fixtures}",
            &repo().join("tests/fixtures").display().to_string(),
        )
        .replace("{shared}", &shared_data().display().to_string())
        .replace("{work}", &work.display().to_string())
}

fn toml_to_json(v: &toml::Value) -> serde_json::Value {
    match v {
        toml::Value::String(s) => serde_json::Value::String(s.clone()),
        toml::Value::Integer(i) => serde_json::json!(i),
        toml::Value::Float(f) => serde_json::json!(f),
        toml::Value::Boolean(b) => serde_json::json!(b),
        toml::Value::Array(a) => a.iter().map(toml_to_json).collect(),
        toml::Value::Table(t) => t
            .iter()
            .map(|(k, v)| (k.clone(), toml_to_json(v)))
            .collect::<serde_json::Map<_, _>>()
            .into(),
        toml::Value::Datetime(d) => serde_json::Value::String(d.to_string()),
    }
}

fn make(d: &Derive, tmp: &Path, work: &Path) -> Vec<u8> {
    let mut bytes = match &d.from {
        Some(from) => std::fs::read(expand(from, tmp, work)).expect("derive source"),
        None => Vec::new(),
    };
    if !d.json_set.is_empty() {
        let mut doc: serde_json::Value = serde_json::from_slice(&bytes).expect("JSON source");
        for (pointer, value) in &d.json_set {
            let mut value = toml_to_json(value);
            if let serde_json::Value::String(text) = &value {
                value = serde_json::Value::String(expand(text, tmp, work));
            }
            *doc.pointer_mut(pointer)
                .unwrap_or_else(|| panic!("{}: no {pointer}", d.name)) = value;
        }
        // Numbers JSON cannot hold (1e400) are written as text by the case itself.
        bytes = serde_json::to_vec_pretty(&doc).unwrap();
    }
    if !d.state_header.is_empty() {
        // The state layout: 24-byte prefix (header length at 16..24), header, numbers.
        let h = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
        let mut header = String::from_utf8(bytes[24..24 + h].to_vec()).unwrap();
        for (old, new) in &d.state_header {
            assert!(
                header.contains(old.as_str()),
                "{}: no {old} in the header",
                d.name
            );
            header = header.replace(old.as_str(), &expand(new, tmp, work));
        }
        let mut out = bytes[..16].to_vec();
        out.extend_from_slice(&(header.len() as u64).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(&bytes[24 + h..]);
        bytes = out;
    }
    if let Some(n) = d.truncate {
        bytes.truncate(n);
    }
    for &k in &d.flip {
        bytes[k] ^= 0xFF;
    }
    let len = bytes.len();
    for &k in &d.flip_end {
        bytes[len - k] ^= 0xFF;
    }
    bytes.extend_from_slice(expand(&d.prefix, tmp, work).as_bytes());
    if let Some(text) = &d.text {
        let text = expand(text, tmp, work);
        for k in 0..d.repeat {
            bytes.extend_from_slice(text.replace("{n}", &k.to_string()).as_bytes());
        }
    }
    bytes.extend_from_slice(expand(&d.suffix, tmp, work).as_bytes());
    bytes
}

/// The names in `dir` (not following links), sorted.
fn listing(dir: &Path) -> Vec<String> {
    support::files(dir)
}

/// Runs the binary with a time limit and `temp` as its temporary folder; `None` when it
/// had to be killed.
fn run_limited(args: &[String], temp: &Path) -> Option<(i32, String, String)> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_dvrk-ident"))
        .args(args)
        .env("TMPDIR", temp)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run dvrk-ident");
    // Read both pipes on threads so that a chatty child never blocks on a full pipe.
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let out_thread = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = out.read_to_end(&mut b);
        b
    });
    let err_thread = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = err.read_to_end(&mut b);
        b
    });
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break Some(status);
        }
        if started.elapsed() > HANG_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = String::from_utf8_lossy(&out_thread.join().unwrap()).into_owned();
    let stderr = String::from_utf8_lossy(&err_thread.join().unwrap()).into_owned();
    let status = status?;
    // A signal (abort, segfault) has no code: -1, which no case expects.
    Some((status.code().unwrap_or(-1), stdout, stderr))
}

/// Words that spell a non-finite number in the program's output (JSON `null` is also
/// what serde writes for NaN, but results are checked finite before they are written,
/// and `null` is a legitimate value of optional fields).
fn non_finite_token(text: &str) -> Option<&str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .find(|w| matches!(*w, "NaN" | "nan" | "inf" | "Infinity" | "infinity"))
}

fn make_null_device(path: &Path) -> bool {
    Command::new("mknod")
        .arg(path)
        .args(["c", "1", "3"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

#[test]
fn hostile_corpus() {
    let manifest_path = repo().join("tests/hostile/cases.toml");
    let text = std::fs::read_to_string(&manifest_path).unwrap();
    let manifest: Manifest = toml::from_str(&text).unwrap();
    let only = std::env::var("HOSTILE_CASE").ok();
    // HOSTILE_SHOW=1 prints every case's message, to re-read them all.
    let show = std::env::var_os("HOSTILE_SHOW").is_some();
    let root = support::temp_dir("hostile");
    // A result file the result cases edit: an OLS fit of the bundled example.
    let work = root.join("work");
    std::fs::create_dir_all(&work).unwrap();
    let (ok, _, err) = support::run(&[
        "fit",
        &support::example("psm_excitation.mcap"),
        "--robot",
        "psm",
        "--method",
        "ols",
        "--quiet",
        "--out",
        &work.join("psm_ols.json").display().to_string(),
    ]);
    assert!(ok, "{err}");
    // An observation state the state cases damage: the bundled example observed.
    let (ok, _, err) = support::run(&[
        "observe",
        &support::example("psm_excitation.mcap"),
        "--robot",
        "psm",
        "--quiet",
        "--out",
        &work.join("psm.obs").display().to_string(),
    ]);
    assert!(ok, "{err}");
    let mut names = std::collections::HashSet::new();
    let mut failures = Vec::new();
    let (mut ran, mut skipped) = (0, 0);
    for case in &manifest.cases {
        assert!(
            names.insert(case.name.clone()),
            "duplicate case {}",
            case.name
        );
        if only
            .as_ref()
            .is_some_and(|o| !case.name.contains(o.as_str()))
        {
            continue;
        }
        if case.shared && !shared_data().exists() {
            dvrk_test_support::skip(format!("{}: ../shared absent", case.name));
            skipped += 1;
            continue;
        }
        let tmp = root.join(&case.name);
        std::fs::create_dir_all(&tmp).unwrap();
        // Names may be in subfolders (a rosbag2 folder's files), made first.
        let in_folder = |name: &str| {
            let path = tmp.join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            path
        };
        for (name, content) in &case.files {
            std::fs::write(in_folder(name), expand(content, &tmp, &work)).unwrap();
        }
        for d in &case.derive {
            std::fs::write(in_folder(&d.name), make(d, &tmp, &work)).unwrap();
        }
        for (link, target) in &case.links {
            std::os::unix::fs::symlink(expand(target, &tmp, &work), in_folder(link)).unwrap();
        }
        if let Some(dev) = &case.null_device {
            if !make_null_device(&tmp.join(dev)) {
                dvrk_test_support::skip(format!(
                    "{}: cannot make a device node (not root)",
                    case.name
                ));
                skipped += 1;
                continue;
            }
        }
        let before = listing(&tmp);
        let contents: Vec<Vec<u8>> = case
            .unchanged
            .iter()
            .map(|f| std::fs::read(tmp.join(f)).expect("an unchanged file"))
            .collect();
        // The case's own temporary folder (TMPDIR): whatever the command leaves in it
        // (a decompressed copy, a scratch file) is a failure.
        let temp = root.join(format!("{}.tmpdir", case.name));
        std::fs::create_dir_all(&temp).unwrap();
        let args: Vec<String> = case.args.iter().map(|a| expand(a, &tmp, &work)).collect();
        let mut problems = Vec::new();
        match run_limited(&args, &temp) {
            None => problems.push(format!("did not finish in {HANG_LIMIT:?} (hang)")),
            Some((code, stdout, stderr)) => {
                if code != case.exit {
                    problems.push(format!("exit {code}, expected {}", case.exit));
                }
                let where_ = if case.exit == 0 { &stdout } else { &stderr };
                if show {
                    eprintln!("--- {}: {}", case.name, where_.trim_end());
                }
                if !where_.contains(&expand(&case.message, &tmp, &work)) {
                    problems.push(format!("message {:?} not in the output", case.message));
                }
                if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
                    problems.push("panicked".into());
                }
                if let Some(w) = non_finite_token(&stdout) {
                    problems.push(format!("stdout has a non-finite number ({w})"));
                }
                let after = listing(&tmp);
                let mut expected = before.clone();
                if case.exit == 0 {
                    for o in &case.outputs {
                        if !tmp.join(o).exists() {
                            problems.push(format!("output {o} missing"));
                        }
                        let top = o.split('/').next().unwrap().to_string();
                        if !expected.contains(&top) {
                            expected.push(top);
                        }
                    }
                    expected.sort();
                }
                if after != expected {
                    problems.push(format!("folder has {after:?}, expected {expected:?}"));
                }
                for (f, before) in case.unchanged.iter().zip(&contents) {
                    if std::fs::read(tmp.join(f)).ok().as_ref() != Some(before) {
                        problems.push(format!("{f} was changed"));
                    }
                }
                let left = listing(&temp);
                if !left.is_empty() {
                    problems.push(format!("temporary files left behind: {left:?}"));
                }
                for link in case.links.keys() {
                    let is_link = std::fs::symlink_metadata(tmp.join(link))
                        .is_ok_and(|m| m.file_type().is_symlink());
                    if !is_link {
                        problems.push(format!("{link} is no longer a symbolic link"));
                    }
                }
                if let Some(dev) = &case.null_device {
                    use std::os::unix::fs::FileTypeExt;
                    let is_dev = std::fs::symlink_metadata(tmp.join(dev))
                        .is_ok_and(|m| m.file_type().is_char_device());
                    if !is_dev {
                        problems.push(format!("{dev} is no longer a device"));
                    }
                }
                if !problems.is_empty() {
                    problems.push(format!(
                        "stderr: {}",
                        stderr.chars().take(600).collect::<String>()
                    ));
                }
            }
        }
        ran += 1;
        let _ = std::fs::remove_dir_all(&temp);
        if problems.is_empty() {
            let _ = std::fs::remove_dir_all(&tmp);
        } else {
            failures.push(format!(
                "{} ({}): {}",
                case.name,
                case.kind,
                problems.join("; ")
            ));
        }
    }
    eprintln!(
        "hostile corpus: {ran} cases run, {skipped} skipped, {} failed",
        failures.len()
    );
    assert!(
        only.is_some() || manifest.cases.len() >= 60,
        "{} cases",
        manifest.cases.len()
    );
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
    let _ = std::fs::remove_dir_all(&root);
}
