//! Settings of [`super::identify`] (the `[identify]` keys, serde form of the Python
//! binding) and the format tag of `identification.json`.

use serde::{Deserialize, Serialize};

use crate::identifiability::{self, BasisMode, RankOptions};
use crate::library::{Library, LibraryKind};
use crate::metrics;
use crate::regress::path::{self, PathOptions};
use crate::regress::plugin::{FitSettings, Options, PathGrid, Regressor};
pub use crate::regress::plugin::{OptionValue, RegressorChoice};
use crate::regress::plugins;
use crate::regress::{GroupRule, Measure, Stlsq};
use crate::{Error, Result};

/// Format tag of `identification.json`.
pub const FORMAT: &str = "aeroform-identification/1";

/// How cases are grouped for group STLSQ (one support shared by a group).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum GroupBy {
    /// By motion configuration (`config` in the manifest; cases without one form the group
    /// `-`).
    #[default]
    Config,
    /// By wind speed (group name `U=<m/s>`).
    WindSpeed,
    /// By pitch amplitude (group name `amplitude=<deg>`).
    Amplitude,
    /// Every case alone (group name = case id).
    None,
}

/// Every option of the identification (`identify()`) that changes the result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct IdentifySettings {
    /// Candidate library.
    pub library: LibraryKind,
    /// Add the constant term `1`.
    pub constant: bool,
    /// Canonical identifiable basis, or the full library (rank deficiency is an error).
    pub basis: BasisMode,
    /// Relative singular-value tolerance of exact dependencies.
    pub rank_tol: f64,
    /// Relative singular-value tolerance of reported near dependencies.
    pub near_tol: f64,
    /// Terms never removed by the sparse regression (when identifiable).
    pub kept_terms: Vec<String>,
    /// Threshold measure.
    pub measure: Measure,
    /// Group-removal rule.
    pub group_rule: GroupRule,
    /// Ridge λ on the column-normalised matrix (0 = least squares).
    pub ridge: f64,
    /// Maximum STLSQ iterations per δ.
    pub max_iter: usize,
    /// Number of δ values.
    pub n_delta: usize,
    /// δ range [min, max]; `None` = the default of the measure (contribution 1e-4..1,
    /// raw coefficient and pysindy 1e-3..10).
    pub delta_range: Option<[f64; 2]>,
    /// Relative slack of the loss limit.
    pub loss_rel: f64,
    /// Absolute slack of the loss limit.
    pub loss_abs: f64,
    /// Multiple of the noise loss in the limit.
    pub loss_noise: f64,
    /// Number of key frequencies.
    pub k_key: usize,
    /// Highest order |m| + |n| of candidate tones.
    pub max_harmonic_order: u32,
    /// Optimiser: a registered regressor's name (`kind`) and its options
    /// ([`crate::regress::plugins`]).
    pub regressor: RegressorChoice,
    /// Grouping of cases.
    pub group_by: GroupBy,
    /// Regress a case with a nonzero mean pitch ᾱ (`mean_pitch` in its descriptors) about
    /// its mean: α − ᾱ replaces α and the library columns and the force are centred, which
    /// is a constant term fitted exactly (reported as `constant`, the static coefficient at
    /// ᾱ); the linear coefficients are then the local derivatives at ᾱ (Eq. 19 at a mean
    /// angle). Cases with ᾱ = 0 or no `mean_pitch` are unaffected.
    pub centre_mean_angle: bool,
}

impl Default for IdentifySettings {
    fn default() -> Self {
        let stlsq = Stlsq::default();
        IdentifySettings {
            library: LibraryKind::Paper30,
            constant: false,
            basis: BasisMode::Canonical,
            rank_tol: identifiability::DEFAULT_RANK_TOL,
            near_tol: identifiability::DEFAULT_NEAR_TOL,
            kept_terms: ["alpha", "alpha_dot", "h", "h_dot"]
                .map(String::from)
                .to_vec(),
            measure: Measure::Contribution,
            group_rule: GroupRule::Norm,
            ridge: 0.0,
            max_iter: stlsq.max_iter,
            n_delta: path::DEFAULT_N_DELTA,
            delta_range: None,
            loss_rel: path::DEFAULT_LOSS_REL,
            loss_abs: path::DEFAULT_LOSS_ABS,
            loss_noise: path::DEFAULT_LOSS_NOISE,
            k_key: metrics::DEFAULT_K_KEY,
            max_harmonic_order: metrics::DEFAULT_MAX_ORDER,
            regressor: RegressorChoice::default(),
            group_by: GroupBy::Config,
            centre_mean_angle: true,
        }
    }
}

impl IdentifySettings {
    /// The settings every regressor shares ([`FitSettings`]).
    pub fn fit_settings(&self) -> FitSettings {
        FitSettings {
            measure: self.measure,
            group_rule: self.group_rule,
            ridge: self.ridge,
            max_iter: self.max_iter,
        }
    }

    /// The regressor of [`plugins::registry`] these settings choose, its resolved options and
    /// the canonical choice ([`RegressorChoice::resolve`]).
    ///
    /// # Errors
    /// As [`RegressorChoice::resolve`].
    pub fn regressor_in<'r>(
        &self,
        registry: &[&'r dyn Regressor],
    ) -> Result<(&'r dyn Regressor, Options, RegressorChoice)> {
        self.regressor.resolve(registry, &self.fit_settings())
    }

    /// The measure the δ grid applies to: that of the regressor's path parameter (raw
    /// coefficients in pysindy mode), the settings' `measure` for a regressor without a
    /// path or not registered.
    pub fn effective_measure(&self) -> Measure {
        self.effective_measure_in(plugins::registry())
    }

    /// [`IdentifySettings::effective_measure`] among the regressors of `registry`.
    pub fn effective_measure_in(&self, registry: &[&dyn Regressor]) -> Measure {
        match crate::regress::plugin::find(registry, &self.regressor.kind)
            .map(|r| r.path_parameter(&self.fit_settings()).grid)
        {
            Ok(PathGrid::Log { measure }) => measure,
            _ => self.measure,
        }
    }

    /// The δ path options these settings imply.
    pub fn path_options(&self) -> PathOptions {
        self.path_options_in(plugins::registry())
    }

    /// [`IdentifySettings::path_options`] among the regressors of `registry`.
    pub fn path_options_in(&self, registry: &[&dyn Regressor]) -> PathOptions {
        let (lo, hi) = match self.delta_range {
            Some([a, b]) => (a, b),
            None => path::default_range(self.effective_measure_in(registry)),
        };
        PathOptions {
            n_delta: self.n_delta,
            delta_min: lo,
            delta_max: hi,
            loss_rel: self.loss_rel,
            loss_abs: self.loss_abs,
            loss_noise: self.loss_noise,
        }
    }

    /// Checks every option once, at the boundary, against the registered regressors.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming the option (e.g. `k_key`, `delta_range`,
    /// `kept_terms`, `regressor`, `pysindy.alpha`) and its value.
    pub fn validate(&self) -> Result<()> {
        self.validate_in(plugins::registry())
    }

    /// [`IdentifySettings::validate`] against the regressors of `registry`.
    ///
    /// # Errors
    /// As [`IdentifySettings::validate`].
    pub fn validate_in(&self, registry: &[&dyn Regressor]) -> Result<()> {
        RankOptions {
            tol: self.rank_tol,
            near_tol: self.near_tol,
        }
        .validate()?;
        self.path_options_in(registry).validate()?;
        Stlsq {
            threshold: 0.0,
            measure: self.measure,
            group_rule: self.group_rule,
            ridge: self.ridge,
            max_iter: self.max_iter,
        }
        .validate()?;
        self.regressor_in(registry)?;
        // k_key key frequencies are picked among the tones of harmonic order ≤ 20 (at most
        // a few hundred): a larger count is a typo, refused before any allocation.
        if self.k_key == 0 || self.k_key > 1000 {
            return Err(Error::InvalidOption {
                name: "k_key".to_string(),
                message: format!("{} must be in 1..=1000", self.k_key),
            });
        }
        if self.max_iter > 1_000_000 {
            return Err(Error::InvalidOption {
                name: "max_iter".to_string(),
                message: format!("{} must be ≤ 1000000", self.max_iter),
            });
        }
        if self.max_harmonic_order == 0 || self.max_harmonic_order > 20 {
            return Err(Error::InvalidOption {
                name: "max_harmonic_order".to_string(),
                message: format!("{} must be in 1..=20", self.max_harmonic_order),
            });
        }
        let lib = Library::new(self.library, self.constant);
        for t in &self.kept_terms {
            lib.index_of(t).map_err(|e| Error::InvalidOption {
                name: "kept_terms".to_string(),
                message: e.to_string(),
            })?;
        }
        Ok(())
    }
}
