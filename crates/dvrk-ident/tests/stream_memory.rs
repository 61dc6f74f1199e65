//! A streamed fit holds a bounded amount of memory, whatever the log's length: a counting
//! global allocator (this test binary only) measures the peak heap while fitting
//! simulated MCAP logs of N and 10·N samples from their files, streamed and in memory.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::log::{self, LogFormat};
use dvrk_ident::simulate::{simulate, Simulation};
use dvrk_ident::Silent;
use dvrk_ident::Streaming;
use dvrk_ident::{FitRequest, FitResult, FitSettings, LogSource, Method, Training};
use dvrk_model::Model;

/// Bytes allocated now, and the most since the last reset (all threads).
static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

struct Counting;

fn grew(bytes: usize) {
    let now = CURRENT.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
            grew(new_size);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Peak heap above the current level while `f` runs, bytes.
fn peak_during<T>(f: impl FnOnce() -> T) -> (usize, T) {
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let out = f();
    (PEAK.load(Ordering::Relaxed) - base, out)
}

/// The bundled example's robot, parameters and trajectory, `samples` long, with noise.
fn write_log(model: &Model, samples: usize, path: &Path) {
    let pi = dvrk_test_support::fixtures::example_params(model);
    let traj = FourierTrajectory::from_json_file(dvrk_test_support::example("psm_trajectory.json"))
        .unwrap();
    let sim = Simulation {
        duration_s: Some(samples as f64 / 200.0),
        noise_std: vec![0.002],
        seed: 7,
        ..Simulation::default()
    };
    let log = simulate(model, &pi, &traj, &sim).unwrap();
    assert_eq!(log.len(), samples);
    log::write(path, &log, LogFormat::Mcap).unwrap();
}

/// The fit of the file `path`, read block by block (default block size) or whole.
fn fit_file(model: &Model, path: &Path, settings: &FitSettings, streaming: Streaming) -> FitResult {
    let request = FitRequest {
        settings: settings.clone(),
        streaming,
        ..FitRequest::new(Training::Logs(vec![LogSource::File(path.into())]))
    };
    request.run(Some(model), &Silent).unwrap().result
}

#[test]
fn streamed_fit_memory_does_not_grow_with_the_log() {
    let model = Model::builtin("psm").unwrap();
    let dir = dvrk_test_support::temp_dir("dvrk-ident-memory");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let settings = FitSettings {
        method: Method::Wls,
        ..FitSettings::default()
    };
    let n = 20_000;
    let mut streamed = Vec::new();
    let mut whole = Vec::new();
    for samples in [n, 10 * n] {
        let path = dir.join(format!("log-{samples}.mcap"));
        write_log(&model, samples, &path);
        if samples == n {
            // What a process allocates once, not per log: the thread pool, the base
            // parameters, and faer's global buffers on its first QR (about 660 MB of
            // address space on this machine, kept for the process's lifetime).
            fit_file(&model, &path, &settings, Streaming::Always);
        }
        let (peak, result) = peak_during(|| fit_file(&model, &path, &settings, Streaming::Always));
        assert_eq!(result.metrics.train.samples, samples - 400);
        streamed.push(peak);
        let (peak, in_memory) =
            peak_during(|| fit_file(&model, &path, &settings, Streaming::Never));
        assert_eq!(in_memory.parameters, result.parameters);
        whole.push(peak);
        std::fs::remove_file(&path).unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
    let mb = |b: usize| b as f64 / 1e6;
    println!(
        "peak heap, N = {n} and 10 N samples: streamed {:.1} MB and {:.1} MB, in memory {:.1} MB and {:.1} MB",
        mb(streamed[0]),
        mb(streamed[1]),
        mb(whole[0]),
        mb(whole[1])
    );
    assert!(
        (streamed[1] as f64) < 1.3 * streamed[0] as f64,
        "the streamed fit's memory grows with the log: {streamed:?}"
    );
    assert!(
        (whole[1] as f64) > 3.0 * whole[0] as f64,
        "the in-memory fit should grow with the log (is the measure working?): {whole:?}"
    );
    assert!(streamed[1] < whole[1]);
}
