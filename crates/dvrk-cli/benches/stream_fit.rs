//! The streamed fit of long logs, end to end through the command line: simulates PSM logs
//! of 10 min and 1 h at 1 kHz into a temporary folder (the bundled example's parameters
//! and trajectory), fits each with `fit --stream` and prints the wall time and the peak
//! resident memory of the fit (what `/usr/bin/time -v` and `top` report), then checks
//! that the 10-minute log's streamed fit equals its in-memory fit.
//!
//! `cargo bench -p dvrk-cli --bench stream_fit` (about 2 minutes; 800 MB of temporary
//! files). `STREAM_FIT_MINUTES=10,60` chooses the lengths.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Runs `args` with the `dvrk-ident` binary as a child of a fresh copy of this process,
/// so that the child's peak RSS is the only one `getrusage(RUSAGE_CHILDREN)` sees.
fn measured(args: &[String]) -> (f64, f64) {
    let me = std::env::current_exe().expect("own path");
    let started = Instant::now();
    let out = Command::new(me)
        .arg("--measure")
        .args(args)
        .output()
        .expect("run the measuring copy");
    let seconds = started.elapsed().as_secs_f64();
    assert!(
        out.status.success(),
        "dvrk-ident {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let kb: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("peak-rss-kb "))
        .and_then(|v| v.trim().parse().ok())
        .expect("the measuring copy prints the peak RSS");
    (seconds, kb / 1024.0)
}

/// The measuring copy: runs the binary and prints its peak resident set (KiB).
fn measure(args: &[String]) -> ! {
    let status = Command::new(env!("CARGO_BIN_EXE_dvrk-ident"))
        .args(args)
        .status()
        .expect("run dvrk-ident");
    // SAFETY: getrusage writes the struct it is given; zeroed is a valid rusage.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) };
    assert_eq!(rc, 0, "getrusage");
    println!("peak-rss-kb {}", usage.ru_maxrss);
    std::process::exit(status.code().unwrap_or(1));
}

fn base_parameters(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).expect("result");
    let doc: serde_json::Value = serde_json::from_str(&text).expect("result JSON");
    doc["base_parameters"]
        .as_array()
        .expect("base_parameters")
        .iter()
        .map(|b| b["value"].as_f64().expect("value"))
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--measure") {
        measure(&args[1..]);
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let examples = root.join("examples");
    let dir = std::env::temp_dir().join(format!("dvrk-stream-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary folder");
    let minutes: Vec<u64> = std::env::var("STREAM_FIT_MINUTES")
        .unwrap_or_else(|_| "10,60".into())
        .split(',')
        .map(|m| {
            m.trim()
                .parse()
                .expect("STREAM_FIT_MINUTES: minutes, comma-separated")
        })
        .collect();
    let s = |p: &Path| p.display().to_string();
    println!("| log | samples | fit --stream (WLS) | peak RSS |");
    println!("|---|---|---|---|");
    for &m in &minutes {
        let log = dir.join(format!("psm_{m}min.mcap"));
        let simulate = [
            "simulate".into(),
            "psm".into(),
            "--params".into(),
            s(&examples.join("psm_params.json")),
            "--excitation".into(),
            s(&examples.join("psm_trajectory.json")),
            "--rate".into(),
            "1000".into(),
            "--duration".into(),
            (m * 60).to_string(),
            "--noise".into(),
            "0.01".into(),
            "--quiet".into(),
            "--out".into(),
            s(&log),
        ];
        measured(&simulate);
        let fit = |out: &Path, stream: bool| {
            let mut a = vec![
                "fit".to_string(),
                s(&log),
                "--robot".into(),
                "psm".into(),
                "--method".into(),
                "wls".into(),
                "--quiet".into(),
                "--out".into(),
                s(out),
            ];
            if stream {
                a.push("--stream".into());
            }
            measured(&a)
        };
        let streamed = dir.join(format!("streamed_{m}.json"));
        let (seconds, mb) = fit(&streamed, true);
        println!(
            "| {m} min | {} | {seconds:.1} s | {mb:.0} MB |",
            m * 60 * 1000
        );
        if m <= 10 {
            let in_memory = dir.join(format!("in_memory_{m}.json"));
            let (s_mem, mb_mem) = fit(&in_memory, false);
            let (a, b) = (base_parameters(&streamed), base_parameters(&in_memory));
            let scale = b.iter().fold(0.0f64, |x, v| x.max(v.abs())) * 1e-6;
            let worst = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs() / y.abs().max(scale))
                .fold(0.0f64, f64::max);
            println!(
                "| {m} min in memory | {} | {s_mem:.1} s | {mb_mem:.0} MB |  (base parameters: \
                 streamed against in memory {worst:.1e} relative)",
                m * 60 * 1000
            );
            assert!(
                worst <= 1e-9,
                "streamed and in-memory fits differ by {worst:e}"
            );
        }
        std::fs::remove_file(&log).ok();
    }
    std::fs::remove_dir_all(&dir).ok();
}
