//! Sim-to-real gap: localisation, effect catalogue, attribution, blind benchmark
//! (DESIGN.md §5).
//!
//! * [`effect`]: the catalogue names and verdicts; `catalogue`: one file per effect (its
//!   fit at each level, its simulation term, its injection), reached through
//!   [`Effect`]'s methods;
//! * [`report`]: the result types and the `diagnosis.json` document;
//! * [`force`]: the force level (forced-motion records);
//! * [`system`]: the system level (free-response records);
//! * [`bifurcation`]: the bifurcation level (a measured bifurcation diagram: Hopf, folds,
//!   LCO branches, by continuation inside the fit);
//! * [`verdict`]: from the levels' findings to one verdict;
//! * [`blind`]: the withheld-effect data-set generator (the diagnosis never reads it);
//! * [`mod@bench`]: the withheld-effect benchmark statistics;
//! * [`physics`]: the drawn rigs and aerodynamic laws of the drawn-shapes benchmark's truths;
//! * [`sweep`]: large jobs split into independent items (shards, Dask tasks) and merged.

pub mod bench;
pub mod bench_run;
pub mod bifurcation;
pub mod blind;
mod catalogue;
pub mod effect;
pub mod error;
pub mod follow_up;
pub mod force;
mod numerics;
pub mod physics;
pub mod pipeline;
pub mod report;
mod stats;
pub mod structure;
pub mod sweep;
pub mod system;
pub mod verdict;

pub use effect::{Effect, Level, Verdict};
pub use error::{Error, Result};
pub use report::{Diagnosis, FoldScheme, LevelResult};
