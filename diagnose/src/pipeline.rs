//! The whole diagnosis of one data set pair: force level, system level (when free-response
//! records are given), verdict and `diagnosis.json` (DESIGN.md §5).

use identify::dataset::Dataset;

use crate::force::{force_level, ForceOptions};
use crate::report::Diagnosis;
use crate::system::{system_level, SystemOptions};
use crate::verdict::{assemble, VerdictRules};
use crate::Result;

/// Settings of a diagnosis.
#[derive(Debug, Clone)]
pub struct DiagnoseOptions {
    /// Master seed (fold assignment of both levels); recorded in `diagnosis.json`.
    pub seed: u64,
    /// Force level.
    pub force: ForceOptions,
    /// System level.
    pub system: SystemOptions,
    /// Verdict rule.
    pub rules: VerdictRules,
}

impl DiagnoseOptions {
    /// Defaults of every level with `seed` as the master seed.
    pub fn new(seed: u64) -> Self {
        let mut o = DiagnoseOptions {
            seed,
            force: ForceOptions::default(),
            system: SystemOptions::default(),
            rules: VerdictRules::default(),
        };
        o.force.seed = seed;
        o.system.seed = seed;
        o
    }
}

/// Diagnoses `forced` (forced-motion records) and, when given, `free` (free-response records
/// of the same section): held-out gaps, where they lie, which candidate explains them, how
/// far it shrinks, and the verdict. `version` is written into the document.
///
/// # Errors
/// As [`force_level`] and [`system_level`]: [`crate::Error::Data`] naming the data set when it
/// cannot support held-out folds (too few groups or runs, no forced case, a free data set
/// without `[structure]`), [`crate::Error::Identify`] when the baseline cannot be identified.
pub fn diagnose(
    forced: &Dataset,
    free: Option<&Dataset>,
    opts: &DiagnoseOptions,
    version: &str,
) -> Result<Diagnosis> {
    let mut levels = vec![force_level(forced, &opts.force)?];
    let mut inputs = vec![forced.root.display().to_string()];
    if let Some(free) = free {
        levels.push(system_level(forced, free, &opts.system)?);
        inputs.push(free.root.display().to_string());
    }
    Ok(assemble(levels, &opts.rules, opts.seed, version, inputs))
}
