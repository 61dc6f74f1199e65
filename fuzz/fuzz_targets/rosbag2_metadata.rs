//! rosbag2 metadata.yaml and the folder listing: never a panic; an accepted log is
//! valid.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::rosbag2_metadata(data));
