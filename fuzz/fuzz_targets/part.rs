//! Fuzz target `part`: see `aeroform::fuzz_harness::part`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    aeroform::fuzz_harness::part(data);
});
