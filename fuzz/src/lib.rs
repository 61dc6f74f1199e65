//! The fuzz targets' bodies, one function per target (`fuzz_targets/*.rs` call them),
//! and the checks every accepted input must pass. The stable test
//! `crates/dvrk-ident/tests/fuzz_seeds.rs` includes this file and runs every committed
//! seed and crash reproducer (`fuzz/seeds/<target>/`) through the same functions.
//!
//! Uses only `dvrk_model`, `dvrk_ident`, `mcap` and `zstd`, so that it builds in both
//! places.

use std::path::PathBuf;

/// The largest single allocation an input may ask for, the fuzz runs' memory limit
/// (`-rss_limit_mb=2048`). libFuzzer refuses larger ones itself (`-malloc_limit_mb`) only
/// through a sanitizer's malloc hooks; CI's smoke run builds without a sanitizer
/// (`-s none`, 1.6× less compile time), so the harness refuses them: a corrupted length
/// field claiming gigabytes is a finding with or without AddressSanitizer. (Memory that
/// grows in smaller pieces is `-rss_limit_mb`'s, which needs no sanitizer.)
#[cfg(fuzzing)]
const MAX_ALLOCATION_BYTES: usize = 2048 << 20;

/// The system allocator, aborting (a finding, with its input saved) on an allocation
/// over [`MAX_ALLOCATION_BYTES`].
#[cfg(fuzzing)]
struct Capped;

#[cfg(fuzzing)]
impl Capped {
    fn check(layout: std::alloc::Layout) {
        if layout.size() > MAX_ALLOCATION_BYTES {
            eprintln!(
                "==dvrk-fuzz== an allocation of {} bytes, over the {MAX_ALLOCATION_BYTES}-byte limit",
                layout.size()
            );
            std::process::abort();
        }
    }
}

// SAFETY: forwards every call to `System` unchanged after the size check.
#[cfg(fuzzing)]
unsafe impl std::alloc::GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        Capped::check(layout);
        unsafe { std::alloc::System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        Capped::check(layout);
        unsafe { std::alloc::System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        if let Ok(grown) = std::alloc::Layout::from_size_align(new_size, layout.align()) {
            Capped::check(grown);
        }
        unsafe { std::alloc::System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
}

#[cfg(fuzzing)]
#[global_allocator]
static CAPPED: Capped = Capped;

/// Writes `data` to this process's scratch file (in /dev/shm when there is one, so
/// every run stays in memory) named with `extension`, and returns its path.
pub fn scratch(data: &[u8], extension: &str) -> PathBuf {
    let path = scratch_path(extension);
    std::fs::write(&path, data).expect("scratch file");
    path
}

/// This process's scratch path with `extension` (see [`scratch`]), not created.
fn scratch_path(extension: &str) -> PathBuf {
    let dir = if std::path::Path::new("/dev/shm").is_dir() {
        PathBuf::from("/dev/shm")
    } else {
        std::env::temp_dir()
    };
    dir.join(format!("dvrk-fuzz-{}.{extension}", std::process::id()))
}

/// An accepted log holds only finite samples in the documented range, with increasing
/// time: what every reader promises.
pub fn check_log(t: &dvrk_ident::JointLog) {
    t.validate().expect("an accepted log is valid");
}

/// An accepted model evaluates to finite torques and regressors at a few states.
pub fn check_model(model: &dvrk_model::Model) {
    let n = model.dof();
    let mut ws = dvrk_model::Workspace::new(model);
    let params = vec![0.5; model.n_params()];
    let mut tau = vec![0.0; n];
    for scale in [0.0, 0.7, -2.0] {
        let q: Vec<f64> = (0..n).map(|k| scale * (k as f64 + 1.0).sin()).collect();
        let dq: Vec<f64> = (0..n).map(|k| scale * (k as f64).cos()).collect();
        model.inverse_dynamics(&mut ws, &params, &q, &dq, &dq, &mut tau);
        assert!(
            tau.iter().all(|t| t.is_finite()),
            "non-finite torque {tau:?}"
        );
        let h = model.regressor(&mut ws, &q, &dq, &dq);
        assert!(h.iter().all(|x| x.is_finite()), "non-finite regressor");
    }
}

/// Robot descriptions (TOML): never a panic; an accepted model evaluates to finite
/// numbers.
pub fn description(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(model) = dvrk_model::Model::from_toml_str(text, "fuzz.toml") {
        check_model(&model);
    }
}

/// URDF documents: never a panic; an accepted model evaluates to finite numbers and its
/// nominal masses are finite and non-negative.
pub fn urdf(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(model) = dvrk_model::Model::from_urdf_str(text, "fuzz.urdf") {
        check_model(&model);
        if let Some(pi) = model.nominal_parameters() {
            for f in &model.frames {
                if let Some(p0) = f.inertia {
                    let s = dvrk_model::inertia::standard_from_barycentric(&pi[p0..p0 + 10]);
                    assert!(s.mass >= 0.0 && s.mass.is_finite(), "{s:?}");
                }
            }
        }
    }
}

/// Headered CSV logs (`time, position.<joint>, velocity.<joint>, effort.<joint>`):
/// never a panic; an accepted log is valid.
pub fn csv_headered(data: &[u8]) {
    let path = scratch(data, "csv");
    if let Ok(t) = dvrk_ident::log::read(&path, Some(dvrk_ident::log::LogFormat::Csv), None) {
        check_log(&t);
    }
}

/// The 2019 headerless CSV layout (`q, dq, tau` columns at 200 Hz), and the format
/// detection that chooses between the CSV layouts: never a panic; an accepted log is
/// valid.
pub fn csv_2019(data: &[u8]) {
    let path = scratch(data, "csv");
    let wpi = Some(dvrk_ident::log::LogFormat::Wpi);
    if let Ok(t) = dvrk_ident::log::read(&path, wpi, Some(200.0)) {
        check_log(&t);
    }
    if let Ok(t) = dvrk_ident::log::read(&path, None, Some(200.0)) {
        check_log(&t);
    }
}

/// What a compressed input may expand to in the `mcap` target, MiB
/// (`--max-unpacked-mib`): small, so that a bomb reaches the bound in milliseconds (the
/// default for a small file is 64 MiB, and the bound's logic is the same).
pub const MAX_UNPACKED_MIB: u64 = 16;

/// Recordings read by content, as `fit` reads them: MCAP files (container, chunks and
/// their zstd/lz4 compression, CRCs, schemas, JointState messages), sqlite3 and ROS 1
/// bags (bz2/lz4 chunks), any of them in a whole-file zstd or lz4 frame (the seeds hold
/// each kind, and two zstd bombs), and their topic listing. The input is read as it is,
/// and again inside a zstd frame, so that every mutation also reaches the whole-file
/// decompression with a valid frame around it. Never a panic; an accepted log is valid.
pub fn mcap(data: &[u8]) {
    let options = dvrk_ident::log::mcap::McapOptions {
        max_unpacked_mib: Some(MAX_UNPACKED_MIB),
        ..Default::default()
    };
    let framed = zstd::bulk::compress(data, 1).expect("zstd compresses any input");
    for input in [data, &framed] {
        let path = scratch(input, "mcap");
        let _ = dvrk_ident::log::mcap::list_topics(&path);
        if let Ok(t) = dvrk_ident::log::mcap::read_mcap(&path, &options) {
            check_log(&t);
        }
    }
}

/// CDR payloads of sensor_msgs/msg/JointState, wrapped in a valid MCAP container so that
/// every input reaches the message decoder: the input is split at 0xFF 0x00 0xFF into up
/// to 16 messages, 5 ms apart, in chunks stored or compressed (zstd, lz4). Never a panic;
/// an accepted log is valid.
pub fn cdr(data: &[u8]) {
    let mut messages: Vec<&[u8]> = Vec::new();
    let mut rest = data;
    while messages.len() < 15 {
        match rest.windows(3).position(|w| w == [0xFF, 0x00, 0xFF]) {
            Some(k) => {
                messages.push(&rest[..k]);
                rest = &rest[k + 3..];
            }
            None => break,
        }
    }
    messages.push(rest);
    // The container's chunks are stored, zstd- or lz4-compressed by the input's length,
    // so that the messages also reach the decoder through each chunk decompression.
    let compression = match data.len() % 3 {
        0 => None,
        1 => Some(mcap::Compression::Zstd),
        _ => Some(mcap::Compression::Lz4),
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new()
            .profile("ros2")
            .compression(compression)
            .create(&mut bytes)
            .expect("writer");
        let schema = w
            .add_schema(
                dvrk_ident::log::mcap::JOINT_STATE_TYPE,
                "ros2msg",
                dvrk_ident::log::mcap::JOINT_STATE_SCHEMA.as_bytes(),
            )
            .expect("schema");
        let channel = w
            .add_channel(
                schema,
                "/arm/measured_js",
                "cdr",
                &std::collections::BTreeMap::new(),
            )
            .expect("channel");
        for (k, m) in messages.iter().enumerate() {
            let t = 1_000_000_000 + 5_000_000 * k as u64;
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: k as u32,
                log_time: t,
                publish_time: t,
            };
            w.write_to_known_channel(&header, m).expect("message");
        }
        w.finish().expect("finish");
    }
    let path = scratch(bytes.get_ref(), "mcap");
    for time_source in [
        dvrk_ident::log::mcap::TimeSource::HeaderStamp,
        dvrk_ident::log::mcap::TimeSource::LogTime,
    ] {
        let options = dvrk_ident::log::mcap::McapOptions {
            time_source,
            ..Default::default()
        };
        if let Ok(t) = dvrk_ident::log::mcap::read_mcap(&path, &options) {
            check_log(&t);
        }
    }
}

/// Result documents (`fit --out`): never a panic; an accepted result has finite numbers,
/// and if it fits the PSM its parameters and 2019 params.json layout are finite.
pub fn result_json(data: &[u8]) {
    static PSM: std::sync::OnceLock<dvrk_model::Model> = std::sync::OnceLock::new();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(result) = dvrk_ident::FitResult::from_json(text, "fuzz.json") else {
        return;
    };
    result.check_finite().expect("a read result is finite");
    let psm = PSM.get_or_init(|| dvrk_model::Model::builtin("psm").unwrap());
    if let Ok(params) = result.params_for(psm) {
        assert!(params.iter().all(|p| p.is_finite()));
        let doc = dvrk_ident::export::wpi_params::wpi_params_json(psm, &params);
        assert!(!doc.to_string().contains("null"), "{doc}");
    }
}

/// Limits files (`excite --limits`: [[limits]] and [[cartesian_limits]]) on the 2-link
/// test robot: never a panic, in reading nor in checking a trajectory against them.
pub fn limits(data: &[u8]) {
    use dvrk_ident::excite::{optimize, FourierTrajectory};
    static ROBOT: std::sync::OnceLock<dvrk_model::Model> = std::sync::OnceLock::new();
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let model = ROBOT.get_or_init(|| {
        dvrk_model::Model::from_toml_str(
            include_str!("../../tests/fixtures/two_link_tip.toml"),
            "two_link_tip.toml",
        )
        .unwrap()
    });
    let Ok(limits) = optimize::Limits::from_toml_str(model, text, "fuzz.toml") else {
        return;
    };
    let traj = FourierTrajectory {
        order: 1,
        base_frequency_hz: 1.0,
        q0: vec![0.1, 0.5],
        a: vec![vec![0.2], vec![0.1]],
        b: vec![vec![0.0], vec![0.3]],
        coordinates: Vec::new(),
        robot: None,
    };
    if let Ok(f) = optimize::check_feasibility(model, &traj, &limits, 1000.0) {
        if let Some(w) = f.worst {
            assert!(!w.excess.is_nan(), "{w:?}");
        }
    }
}

/// Observation state files (`observe --out`, the state codec): never a panic; an
/// accepted state re-encodes to bytes that read back to the same bytes, merges with
/// itself (twice the samples), and is checked against the 2-link test robot (the seed
/// was observed with it: the fuzzer keeps its hash while it changes the rest), which it
/// passes or fails with an error. (Not fitted: faer's matrix product reserves 520 MiB
/// of address space per thread on first use, which the stable seed test counts as heap,
/// and a fit per input would slow the target tenfold.)
pub fn state(data: &[u8]) {
    use dvrk_ident::ObservationState;
    static ROBOT: std::sync::OnceLock<dvrk_model::Model> = std::sync::OnceLock::new();
    let Ok(state) = ObservationState::from_bytes(data, "fuzz.obs") else {
        return;
    };
    let bytes = state.to_bytes();
    let again =
        ObservationState::from_bytes(&bytes, "again.obs").expect("a written state reads back");
    assert!(
        again.to_bytes() == bytes,
        "the state's bytes change on a round trip"
    );
    let mut merged = state.clone();
    if merged.merge(&state).is_ok() {
        assert_eq!(merged.samples(), 2 * state.samples());
    }
    let model = ROBOT.get_or_init(|| {
        dvrk_model::Model::from_toml_str(
            include_str!("../../tests/fixtures/two_link_tip.toml"),
            "two_link_tip.toml",
        )
        .unwrap()
    });
    if let Ok(fitted) = state.model(model) {
        assert_eq!(
            (fitted.dof(), fitted.n_params() + 1),
            (2, 27),
            "a state accepted for the 2-link robot has its shape"
        );
    }
}

/// rosbag2 folders: the input is a `metadata.yaml` in a folder that also holds a small
/// valid MCAP recording (`a.mcap`, the `mcap` target's seed) and a text file; the folder
/// is read as a recording, and again after the metadata is removed (the folder listing).
/// Never a panic; an accepted log is valid.
pub fn rosbag2_metadata(data: &[u8]) {
    let dir = scratch_path("rosbag2");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    std::fs::write(
        dir.join("a.mcap"),
        include_bytes!("../seeds/mcap/psm_20_samples.mcap"),
    )
    .expect("scratch file");
    std::fs::write(dir.join("notes.txt"), b"not a recording\n").expect("scratch file");
    std::fs::write(dir.join("metadata.yaml"), data).expect("scratch file");
    let options = dvrk_ident::log::mcap::McapOptions::default();
    for _ in 0..2 {
        let _ = dvrk_ident::log::mcap::list_topics(&dir);
        if let Ok(t) = dvrk_ident::log::mcap::read_mcap(&dir, &options) {
            check_log(&t);
        }
        let _ = std::fs::remove_file(dir.join("metadata.yaml"));
        let _ = std::fs::remove_file(dir.join("notes.txt"));
    }
}

/// A target's body: runs one input.
pub type Target = fn(&[u8]);

/// The targets by name (the folders of `fuzz/seeds`).
pub const TARGETS: [(&str, Target); 10] = [
    ("description", description),
    ("urdf", urdf),
    ("csv_headered", csv_headered),
    ("csv_2019", csv_2019),
    ("mcap", mcap),
    ("cdr", cdr),
    ("result_json", result_json),
    ("limits", limits),
    ("state", state),
    ("rosbag2_metadata", rosbag2_metadata),
];
