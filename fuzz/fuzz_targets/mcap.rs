//! MCAP files (container, chunks, CRCs, schemas, JointState messages): never a panic;
//! an accepted log is valid. Topic listing too.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::mcap(data));
