//! The end-to-end tests of the `aeroform` binary and the workspace, one test binary
//! (`cargo test --release --test e2e`; one file's tests: `cargo test --release --test e2e
//! branch_cli::`). One binary instead of one per file: each file linked on its own cost
//! most of a fresh clone's test build (docs/DECISIONS.md, "One test binary per crate").
//! A new test file is one `mod` line here.

mod branch_cli;
mod campaign;
mod cli;
mod common;
mod diagnose_cli;
mod ensemble;
mod faults;
mod fuzz_corpus;
mod identify_round_trip;
mod identify_streaming;
mod input_output_overlap;
mod json_output;
mod lag_flight;
mod lag_identify;
mod late_refusals;
mod limits;
mod merge_cli;
mod races;
mod report_headless;
mod round_trip;
mod schemas;
mod study;
mod untrusted_paths;
mod untrusted_sets;
mod usage_errors;
