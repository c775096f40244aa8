//! Fuzz target `dataset`: see `aeroform::fuzz_harness::dataset`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aeroform::fuzz_harness::dataset(data);
});
