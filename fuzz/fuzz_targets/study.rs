//! Fuzz target `study`: see `aeroform::fuzz_harness::study`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aeroform::fuzz_harness::study(data);
});
