//! Robot descriptions (TOML): never a panic; an accepted model evaluates to finite
//! numbers.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::description(data));
