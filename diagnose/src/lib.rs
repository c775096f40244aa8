//! Sim-to-real gap: localisation, effect catalogue, attribution, verdict
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
//! * [`follow_up`]: the forced tests that would settle an `extrapolation` (a campaign plan).
//!
//! The withheld-effect generator, the benchmarks and the sharded sweeps that run many
//! diagnoses live in the `benchmark` crate above this one: the diagnosis never reads a
//! truth.

pub mod bifurcation;
mod catalogue;
pub mod effect;
pub mod error;
pub mod follow_up;
pub mod force;
mod numerics;
pub mod pipeline;
pub mod report;
mod stats;
pub mod structure;
pub mod system;
pub mod verdict;

pub use effect::{Effect, Level, Verdict};
pub use error::{Error, Result};
pub use report::{Diagnosis, FoldScheme, LevelResult};
