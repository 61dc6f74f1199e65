//! The fuzz corpus as a regression test on stable Rust: every committed seed and crash
//! reproducer (`fuzz/seeds/<target>/`) goes through its fuzz target's body (the same
//! function `cargo fuzz` runs, from `fuzz/src/lib.rs`), which panics on any broken
//! promise: a reader that panics, a log accepted with a value out of range, a result
//! with a non-finite number; and none may make the heap grow past [`HEAP_LIMIT`]
//! (counted by this test's allocator: a corrupted length field must not be allocated).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Heap allowed to one seed (all are under 20 kB; the fuzz runs' limit is 2 GB).
const HEAP_LIMIT: usize = 16 << 20;

/// The system allocator, counting the bytes in use and their peak.
struct Counting;

static IN_USE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = IN_USE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        IN_USE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[path = "../../../fuzz/src/lib.rs"]
#[allow(dead_code)]
mod fuzz;

#[test]
fn every_seed_and_reproducer_passes_its_target() {
    let seeds = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds");
    let mut total = 0;
    for (target, run) in fuzz::TARGETS {
        let dir = seeds.join(target);
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        assert!(!files.is_empty(), "no seed for {target}");
        for f in files {
            let name = f.file_name().unwrap().to_string_lossy().into_owned();
            if name.starts_with("upstream-") && cfg!(debug_assertions) {
                // A dependency's own overflow check (see fuzz/Cargo.toml): release only.
                dvrk_test_support::skip(format!(
                    "{name}: an upstream overflow, checked in release builds"
                ));
                continue;
            }
            let data = std::fs::read(&f).unwrap();
            // Once unmeasured: what is reserved once per process or thread on first use
            // (the targets' robots, faer's matrix-product buffer of 520 MiB of address
            // space per thread) is not the input's doing; what an input allocates, it
            // allocates again.
            run(&data);
            let before = IN_USE.load(Ordering::Relaxed);
            PEAK.store(before, Ordering::Relaxed);
            run(&data);
            let grown = PEAK.load(Ordering::Relaxed) - before;
            eprintln!("{target}: {}: heap peak +{grown} bytes", f.display());
            assert!(
                grown < HEAP_LIMIT,
                "{target}: {}: the heap grew by {grown} bytes",
                f.display()
            );
            total += 1;
        }
    }
    eprintln!("{total} seeds");
}

/// The compressed seeds of the `mcap` target (`fuzz/seeds/gen_compressed.py`) start the
/// fuzzer where they are meant to: each recording is read through its decompression
/// (the four samples it holds), and each zstd bomb is refused at the target's bound.
/// The target ignores errors, so without this a seed refused for an unrelated reason
/// would pass and leave its decompressor unfuzzed.
#[test]
fn compressed_seeds_are_read_and_bombs_refused() {
    use dvrk_ident::log::mcap::{read_mcap, McapOptions};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/mcap");
    let options = McapOptions {
        max_unpacked_mib: Some(fuzz::MAX_UNPACKED_MIB),
        ..Default::default()
    };
    for name in [
        "compressed-lz4-chunks.mcap",
        "compressed-file.mcap.zst",
        "compressed-file.mcap.lz4",
        "compressed-file.db3.zst",
        "compressed-bz2-chunks.bag",
        "compressed-lz4-chunks.bag",
    ] {
        let log = read_mcap(dir.join(name), &options).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((log.time.len(), log.dof()), (4, 7), "{name}");
        // position of joint j at sample k: ((k (j + 1)) mod 17 − 8) / 32 (exact); k = 3,
        // j = 1: (6 − 8) / 32
        assert_eq!(log.q[(3, 1)], -2.0 / 32.0, "{name}");
    }
    for name in ["bomb-declared.db3.zst", "bomb-streamed.bag.zst"] {
        let error = read_mcap(dir.join(name), &options).unwrap_err().to_string();
        let bound = format!("more than {} MiB", fuzz::MAX_UNPACKED_MIB);
        assert!(error.contains(&bound), "{name}: {error}");
    }
}
