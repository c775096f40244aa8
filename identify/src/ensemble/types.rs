//! The data of an identification's ensemble ([`Ensemble`], its settings and intervals):
//! below both `crate::ensemble` (the bootstrap that fills it) and `crate::pipeline`
//! (whose `Identification` carries it), so neither imports the other's module for it
//! (issue 40, docs/DECISIONS.md "No import circles, checked").

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// Default confidence level of the intervals (90 %).
pub const DEFAULT_LEVEL: f64 = 0.9;

/// Settings of [`bootstrap`](crate::ensemble::bootstrap).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EnsembleSettings {
    /// Number of members N (≥ 2).
    pub members: usize,
    /// Master seed of every draw (written as a string: a u64 does not fit every JSON or
    /// TOML reader).
    #[serde(with = "seed_string")]
    #[schemars(with = "String")]
    pub seed: u64,
    /// Confidence level of the intervals, in (0, 1).
    pub level: f64,
    /// Block length in periods of the case's slowest forcing frequency (> 0).
    pub block_periods: f64,
    /// Apply the finite-block correction √(n_b/(n_b − 1))·t_{n_b−1}/z (`crate::ensemble` module docs).
    pub variance_correction: bool,
}

impl EnsembleSettings {
    /// N members from `seed`: 90 % intervals, blocks of one slowest forcing period, with the
    /// finite-block correction.
    pub fn new(members: usize, seed: u64) -> Self {
        EnsembleSettings {
            members,
            seed,
            level: DEFAULT_LEVEL,
            block_periods: 1.0,
            variance_correction: true,
        }
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `ensemble.members` (< 2 or above
    /// [`crate::limits::MAX_ENSEMBLE`]), `ensemble.level` (outside
    /// (0, 1)) or `ensemble.block_periods` (not finite and > 0).
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, message: String| Error::InvalidOption {
            name: format!("ensemble.{name}"),
            message,
        };
        if !(2..=crate::limits::MAX_ENSEMBLE).contains(&self.members) {
            return Err(bad(
                "members",
                format!(
                    "{} must be in 2..={}",
                    self.members,
                    crate::limits::MAX_ENSEMBLE
                ),
            ));
        }
        if !(self.level > 0.0 && self.level < 1.0) {
            return Err(bad("level", format!("{} must be in (0, 1)", self.level)));
        }
        if !(self.block_periods.is_finite() && self.block_periods > 0.0) {
            return Err(bad(
                "block_periods",
                format!("{} must be finite and > 0", self.block_periods),
            ));
        }
        Ok(())
    }
}

mod seed_string {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&v.to_string())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let s = String::deserialize(d)?;
        s.parse()
            .map_err(|_| serde::de::Error::custom(format!("seed `{s}` is not an unsigned integer")))
    }
}

/// A percentile interval of an ensemble of values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Interval {
    /// Median of the members.
    pub median: f64,
    /// Lower bound: quantile (1 − level)/2.
    pub lower: f64,
    /// Upper bound: quantile (1 + level)/2.
    pub upper: f64,
}

impl Interval {
    /// Median and central `level` interval of the finite values of `values` (non-finite
    /// ones are ignored); `None` when no value is finite.
    pub fn from_samples(values: &[f64], level: f64) -> Option<Interval> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        Some(Interval {
            median: quantile_sorted(&v, 0.5),
            lower: quantile_sorted(&v, (1.0 - level) / 2.0),
            upper: quantile_sorted(&v, (1.0 + level) / 2.0),
        })
    }

    /// Whether `x` lies in [lower, upper].
    pub fn contains(&self, x: f64) -> bool {
        self.lower <= x && x <= self.upper
    }
}

/// Quantile `p` ∈ [0, 1] of sorted values by linear interpolation between order statistics
/// (Hyndman–Fan type 7: position p·(n − 1)).
///
/// # Panics
/// When `sorted` is empty (programming error).
#[track_caller]
pub fn quantile_sorted(sorted: &[f64], p: f64) -> f64 {
    assert!(!sorted.is_empty(), "quantile of no value");
    let pos = p.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let i = pos.floor() as usize;
    let f = pos - i as f64;
    if i + 1 < sorted.len() {
        sorted[i] + f * (sorted[i + 1] - sorted[i])
    } else {
        sorted[i]
    }
}

/// Ensemble of one force of one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ForceEnsemble {
    /// The re-fitted support (term names, library order).
    pub support: Vec<String>,
    /// Interval of every support term's raw nondimensional coefficient.
    pub terms: BTreeMap<String, Interval>,
    /// Interval of every Eq. 19 value (A1..A4 or H1..H4, N1..N3) whose term is in the
    /// support (a term outside it is 0 in every member and has no entry).
    pub eq19: BTreeMap<String, Interval>,
    /// Member × support-term raw coefficients (`samples[m][k]` is term `support[k]` of
    /// member m).
    pub samples: Vec<Vec<f64>>,
}

/// Ensemble of one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseEnsemble {
    /// Case id.
    pub id: String,
    /// Number of blocks n_b the record was cut into.
    pub blocks: usize,
    /// Samples in the first block (blocks differ by at most one sample).
    pub block_samples: usize,
    /// Moment.
    pub moment: ForceEnsemble,
    /// Lift.
    pub lift: ForceEnsemble,
}

/// The optional `ensemble` section of `identification.json` (DATA_FORMAT.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Ensemble {
    /// Always `block_bootstrap` (the resampling scheme of `crate::ensemble`).
    pub method: String,
    /// Settings (members, seed, level, block length, correction).
    pub settings: EnsembleSettings,
    /// One entry per case, in the order of the identification's cases.
    pub cases: Vec<CaseEnsemble>,
}
