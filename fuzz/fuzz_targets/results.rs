//! Fuzz target `results`: see `aeroform::fuzz_harness::results`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aeroform::fuzz_harness::results(data);
});
