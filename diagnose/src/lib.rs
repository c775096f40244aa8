//! Sim-to-real gap: localisation, effect catalogue, attribution, blind benchmark
//! (DESIGN.md §5).
//!
//! * [`effect`]: the catalogue names and verdicts;
//! * [`report`]: the result types and the `diagnosis.json` document;
//! * [`force`]: the force level on forced-motion records.

pub mod effect;
pub mod error;
pub mod force;
pub mod report;

pub use effect::{Effect, Level, Verdict};
pub use error::{Error, Result};
pub use report::{Diagnosis, LevelResult};
