//! Result documents (`fit --out`): never a panic; an accepted result has finite numbers,
//! and if it fits the PSM its parameters and 2019 params.json layout are finite.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| dvrk_fuzz::result_json(data));
