//! Fuzz target `aero_files`: see `aeroform::fuzz_harness::aero_files`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aeroform::fuzz_harness::aero_files(data);
});
