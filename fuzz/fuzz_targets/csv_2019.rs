//! The 2019 headerless CSV layout (`q, dq, tau` columns at 200 Hz), and the format
//! detection that chooses between the CSV layouts: never a panic; an accepted log is
//! valid.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::csv_2019(data));
