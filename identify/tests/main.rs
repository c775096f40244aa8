//! The identify crate's end-to-end and property tests, one test binary
//! (`cargo test --release -p identify --test e2e`; one file's tests: append its module
//! path, e.g. `paper_table_v::`). A new test file is one `mod` line here
//! (docs/DECISIONS.md, "One test binary per crate").

mod identifiability;
mod paper_table_v;
mod props_common;
mod props_invariance;
mod props_recovery;
mod props_roundtrip;
mod pysindy_parity;
mod regressors;
