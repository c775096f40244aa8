//! Library part of the `aeroform` package: re-exports of the study-file parser
//! ([`study_spec`], from the `study` crate), the JSON documents the binary writes with their
//! schemas ([`documents`]), the input caps ([`limits`]) and the input-robustness harnesses
//! that the fuzz targets in `fuzz/` and the corpus test `tests/fuzz_corpus.rs` call.
//! Everything else lives in the binary and the `study` and `plots` crates.

pub use study::limits;
pub use study::spec as study_spec;

pub mod documents;
pub mod fuzz_harness;
