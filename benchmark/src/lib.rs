//! Benchmarks and large jobs above the diagnosis (DESIGN.md §5): what generates data sets
//! with a known, withheld effect, runs the diagnosis on many of them and scores it, and
//! splits large jobs into independent items. The diagnosis itself (`diagnose`) never reads
//! this crate.
//!
//! * [`blind`]: the withheld-effect data-set generator (forced and free records of a truth
//!   with one effect withheld from the diagnosis);
//! * [`physics`]: the drawn rigs and aerodynamic laws of the drawn-shapes benchmark's truths;
//! * [`mod@bench`]: the withheld-effect benchmark's draws and statistics (confusion matrix,
//!   acceptance lines, the follow-up loop's outcomes);
//! * [`bench_run`]: runs the withheld-effect benchmark (generation, diagnosis, scoring);
//! * [`branch_bench`]: the branch-level benchmark (generated rigs with a measured
//!   bifurcation diagram, diagnosed at the bifurcation level);
//! * [`sweep`]: large jobs split into independent items (shards, Dask tasks) and merged.
//!
//! Errors are the diagnosis's ([`diagnose::Error`]): every failure here is one of a
//! diagnosis, a generation through `aeroelastic`/`identify`, or a sweep specification
//! (`diagnose::Error::Sweep`).

pub mod bench;
pub mod bench_run;
pub mod blind;
pub mod branch_bench;
pub mod physics;
pub mod sweep;

pub use diagnose::{Error, Result};
