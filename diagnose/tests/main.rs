//! The diagnose crate's end-to-end tests, one test binary (`cargo test --release -p
//! diagnose --test e2e`; one file's tests: append its module path, e.g. `bifurcation::`).
//! A new test file is one `mod` line here (docs/DECISIONS.md, "One test binary per crate").

mod bifurcation;
mod controlled;
mod onset_rows;
mod real_data;
