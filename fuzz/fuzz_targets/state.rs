//! Observation state files (the state codec, its checks against the robot, a fit of
//! the state): never a panic; an accepted state round-trips and fits to finite numbers.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::state(data));
