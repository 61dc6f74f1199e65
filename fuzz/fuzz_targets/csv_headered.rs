//! Headered CSV logs (`time, position.<joint>, velocity.<joint>, effort.<joint>`):
//! never a panic; an accepted log is valid.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::csv_headered(data));
