//! URDF documents: never a panic; an accepted model evaluates to finite numbers and its
//! nominal inertials are rigid bodies.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::urdf(data));
