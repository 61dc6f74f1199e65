//! Limits files (`excite --limits`, [[limits]] and [[cartesian_limits]]) on the 2-link
//! test robot: never a panic, in reading nor in checking a trajectory against them.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::limits(data));
