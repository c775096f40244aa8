//! Fuzz target `identification`: see `aeroform::fuzz_harness::identification`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aeroform::fuzz_harness::identification(data);
});
