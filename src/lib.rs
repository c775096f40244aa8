//! Library part of the `aeroform` package: the study-file parser (also used by the
//! binary), the JSON documents the binary writes with their schemas ([`documents`]) and
//! the input-robustness harnesses that the fuzz targets in `fuzz/` and the
//! corpus test `tests/fuzz_corpus.rs` call. Everything else lives in the binary.

#[path = "study/spec.rs"]
pub mod study_spec;

pub mod documents;
pub mod fuzz_harness;
pub mod limits;
