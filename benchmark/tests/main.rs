//! The benchmark crate's end-to-end tests, one test binary (`cargo test --release -p
//! benchmark --test e2e`; one file's tests: append its module path, e.g.
//! `structural_misses::`). A new test file is one `mod` line here (docs/DECISIONS.md,
//! "One test binary per crate").

mod blind_benchmark;
mod blind_gen;
mod coverage;
mod force_level;
mod shapes;
mod structural_misses;
mod structure_first;
mod structure_used;
mod system_level;
