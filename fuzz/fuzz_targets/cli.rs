//! Fuzz target `cli`: see `aeroform::fuzz_harness::cli`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aeroform::fuzz_harness::cli(data);
});
