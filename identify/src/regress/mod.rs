//! Sparse regression: STLSQ (paper Alg. 1), group STLSQ (Alg. 2) and the δ path (Alg. 3).
//!
//! Layout (what varies between optimisers is separated from what they share):
//! - [`factor`]: one QR factorisation per case; every later fit is a tiny solve.
//! - [`SparseRegressor`]: an optimiser writes only its *reduction step* (which active terms
//!   to drop given the fits on the current support). [`fit_group`] is the one shared
//!   routine doing the bookkeeping: column scaling, the support, kept terms, least-squares
//!   (or ridge) fits, the unbiasing refit and the history. Implementations: [`Stlsq`] (with
//!   its group-removal rule) and [`LeastSquares`].
//! - [`path`]: the δ path and the selection of the sparsest support under a loss limit.
//! - [`plugin`]: the [`plugin::Regressor`] trait (a regressor as a plug-in: its name, options,
//!   path parameter and fits along the path) and [`plugins`]: the registry and the
//!   registered regressors (STLSQ, pysindy, least squares). Nothing outside `plugins`
//!   names a regressor.
//! - [`adapter`]: the pysindy-compatible estimator's options and per-case paths, through
//!   [`pysindy::PysindyStlsq`].
//!
//! Coefficients come in two scales: *scaled* (coefficient of the column-normalised term,
//! ξ_s = ξ·d_j with d_j the column's 2-norm) and *raw* (coefficient of the library term in
//! the nondimensional variables). Results always report raw coefficients.

pub mod adapter;
pub mod factor;
pub mod path;
pub mod plugin;
pub mod plugins;
pub mod pysindy;

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::{Error, Result};
pub use factor::CaseFactor;

/// Bit mask of library columns (bit j = column j); libraries have at most 35 columns.
pub type Mask = u64;

/// Library indices of the set bits of `mask`, ascending.
pub fn mask_to_vec(mask: Mask) -> Vec<usize> {
    (0..64).filter(|&j| mask >> j & 1 == 1).collect()
}

/// Mask of the given library indices.
///
/// # Panics
/// When an index is ≥ 64 (a programming error).
#[track_caller]
pub fn vec_to_mask(cols: &[usize]) -> Mask {
    cols.iter().fold(0, |m, &j| {
        assert!(j < 64, "column {j} out of mask range");
        m | 1 << j
    })
}

/// Mask of the `true` entries of a boolean vector.
pub fn bools_to_mask(b: &[bool]) -> Mask {
    b.iter()
        .enumerate()
        .fold(0, |m, (j, &x)| if x { m | 1 << j } else { m })
}

/// What a threshold δ is compared with.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Measure {
    /// Scale-free contribution of a term relative to the target, ‖ξ_j θ_j‖₂ / ‖y‖₂ (the
    /// default: independent of the units and magnitude of each variable).
    #[default]
    Contribution,
    /// The paper's raw coefficient magnitude |ξ_j| (nondimensional variables).
    Coefficient,
}

/// How the measures of a term over the cases of a group decide its removal (Alg. 2).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum GroupRule {
    /// Remove when the root mean square over cases of the measure is < δ (default).
    #[default]
    Norm,
    /// Remove only when the measure is < δ in every case.
    All,
    /// Remove when the measure is < δ in any case.
    Any,
    /// Remove when the mean over cases of the measure is < δ.
    Mean,
}

impl GroupRule {
    /// Whether a term with per-case measures `m` is removed at threshold `delta`.
    pub fn removes(self, m: &[f64], delta: f64) -> bool {
        if m.is_empty() {
            return false;
        }
        let n = m.len() as f64;
        match self {
            GroupRule::Norm => (m.iter().map(|v| v * v).sum::<f64>() / n).sqrt() < delta,
            GroupRule::All => m.iter().all(|&v| v < delta),
            GroupRule::Any => m.iter().any(|&v| v < delta),
            GroupRule::Mean => m.iter().sum::<f64>() / n < delta,
        }
    }
}

/// One regression problem: one target (force coefficient) of one case, reduced to its
/// factor.
#[derive(Debug, Clone, Copy)]
pub struct CaseProblem<'a> {
    /// The case's factor.
    pub factor: &'a CaseFactor,
    /// Index of the target in the factor.
    pub target: usize,
}

impl CaseProblem<'_> {
    /// ‖y‖₂ of the target.
    pub fn y_norm(&self) -> f64 {
        self.factor.targets[self.target].norm2.sqrt()
    }
}

/// What the reduction step of an optimiser sees: the current support and, per case, the
/// fitted coefficients on it.
#[derive(Debug, Clone, Copy)]
pub struct ReductionInput<'a> {
    /// Active library columns, ascending.
    pub support: &'a [usize],
    /// `kept[i]`: support entry i may not be removed.
    pub kept: &'a [bool],
    /// Per case, the scaled coefficients (one per support entry).
    pub scaled: &'a [Vec<f64>],
    /// Per case, the raw coefficients (one per support entry).
    pub raw: &'a [Vec<f64>],
    /// Per case, ‖y‖₂.
    pub y_norm: &'a [f64],
}

impl ReductionInput<'_> {
    /// Per-case measure of support entry `i` (see [`Measure`]); the contribution of a term
    /// with unit-norm column is |ξ_s|/‖y‖ (0 when y ≡ 0).
    pub fn measures(&self, measure: Measure, i: usize) -> Vec<f64> {
        (0..self.scaled.len())
            .map(|c| match measure {
                Measure::Contribution => {
                    if self.y_norm[c] > 0.0 {
                        self.scaled[c][i].abs() / self.y_norm[c]
                    } else {
                        0.0
                    }
                }
                Measure::Coefficient => self.raw[c][i].abs(),
            })
            .collect()
    }
}

/// A sparse optimiser: only its reduction step and its fitting options; [`fit_group`] does
/// the rest.
pub trait SparseRegressor: Sync {
    /// Short name for reports.
    fn name(&self) -> String;
    /// Ridge parameter λ of the fits on the column-normalised matrix (0 = least squares).
    fn ridge(&self) -> f64 {
        0.0
    }
    /// Whether the final coefficients are refitted by plain least squares on the final
    /// support (matters only with ridge > 0).
    fn unbias(&self) -> bool {
        true
    }
    /// Maximum number of fit–reduce iterations.
    fn max_iter(&self) -> usize {
        1
    }
    /// The reduction step: `true` for each support entry to remove. Entries marked kept in
    /// the input are never removed, whatever this returns.
    fn remove(&self, input: &ReductionInput<'_>) -> Vec<bool>;
}

/// Sequentially thresholded least squares (paper Alg. 1; Alg. 2 for a group of cases).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Stlsq {
    /// Threshold δ on the measure.
    pub threshold: f64,
    /// Measure compared with δ.
    pub measure: Measure,
    /// Group-removal rule (a single case: all rules agree).
    pub group_rule: GroupRule,
    /// Ridge λ on the column-normalised matrix (0 = plain least squares).
    pub ridge: f64,
    /// Maximum iterations (the support is usually stable after 2–5).
    pub max_iter: usize,
}

impl Default for Stlsq {
    fn default() -> Self {
        Stlsq {
            threshold: 0.01,
            measure: Measure::Contribution,
            group_rule: GroupRule::Norm,
            ridge: 0.0,
            max_iter: 25,
        }
    }
}

impl Stlsq {
    /// Checks the options.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `threshold`, `ridge` or `max_iter`.
    pub fn validate(&self) -> Result<()> {
        if !(self.threshold >= 0.0 && self.threshold.is_finite()) {
            return Err(Error::InvalidOption {
                name: "threshold".to_string(),
                message: format!("{} must be finite and ≥ 0", self.threshold),
            });
        }
        if !(self.ridge >= 0.0 && self.ridge.is_finite()) {
            return Err(Error::InvalidOption {
                name: "ridge".to_string(),
                message: format!("{} must be finite and ≥ 0", self.ridge),
            });
        }
        if self.max_iter == 0 {
            return Err(Error::InvalidOption {
                name: "max_iter".to_string(),
                message: "must be ≥ 1".to_string(),
            });
        }
        Ok(())
    }
}

impl SparseRegressor for Stlsq {
    fn name(&self) -> String {
        format!(
            "stlsq(δ={}, {:?}, {:?})",
            self.threshold, self.measure, self.group_rule
        )
    }
    fn ridge(&self) -> f64 {
        self.ridge
    }
    fn max_iter(&self) -> usize {
        self.max_iter
    }
    fn remove(&self, input: &ReductionInput<'_>) -> Vec<bool> {
        (0..input.support.len())
            .map(|i| {
                self.group_rule
                    .removes(&input.measures(self.measure, i), self.threshold)
            })
            .collect()
    }
}

/// Plain least squares on the whole basis (no sparsification).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub struct LeastSquares;

impl SparseRegressor for LeastSquares {
    fn name(&self) -> String {
        "least_squares".to_string()
    }
    fn remove(&self, input: &ReductionInput<'_>) -> Vec<bool> {
        vec![false; input.support.len()]
    }
}

/// Fits of every case of a group on one support.
#[derive(Debug, Clone, PartialEq)]
pub struct SupportFits {
    /// The support (library columns, ascending).
    pub support: Vec<usize>,
    /// Per case, scaled coefficients (one per support entry).
    pub scaled: Vec<Vec<f64>>,
    /// Per case, raw coefficients (one per support entry).
    pub raw: Vec<Vec<f64>>,
}

/// Bytes of support fits a [`FitCache`] holds before it forgets the least recently used
/// ones (64 MiB: every support of a path for groups of up to a few thousand cases; for a
/// 50,000-case group, the last few).
pub const FIT_CACHE_BUDGET: usize = 64 << 20;

/// Memo of support fits of one group and target, keyed by (support, ridge used, exact).
///
/// Bounded: it holds at most [`FIT_CACHE_BUDGET`] bytes of fits (estimated from the
/// number of cases and support sizes; the most recent fit is always held) and forgets the
/// least recently used beyond. A forgotten fit is computed again when asked for, to the
/// same numbers (a fit is a function of the case, the support and the ridge alone), so
/// the bound changes time, never results.
#[derive(Debug)]
pub struct FitCache {
    map: HashMap<(Mask, u64), (std::rc::Rc<SupportFits>, u64, usize)>,
    /// Estimated bytes held.
    held: usize,
    /// Use counter (recency of the entries).
    tick: u64,
    budget: usize,
    /// Number of support fits computed (a forgotten one computed again counts again).
    pub n_fits: usize,
}

impl Default for FitCache {
    fn default() -> Self {
        FitCache::with_budget(FIT_CACHE_BUDGET)
    }
}

impl FitCache {
    /// An empty memo holding at most `budget` bytes of fits (at least the most recent).
    pub fn with_budget(budget: usize) -> Self {
        FitCache {
            map: HashMap::new(),
            held: 0,
            tick: 0,
            budget,
            n_fits: 0,
        }
    }

    /// Number of fits held.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// True when no fit is held.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// Fits (or recalls) every case on `mask` with ridge λ. Uses the Gram/Cholesky solve
    /// and falls back to the QR solve per case when it is ill-conditioned; `exact = true`
    /// always uses the QR solve (final coefficients).
    pub fn fits(
        &mut self,
        cases: &[CaseProblem<'_>],
        mask: Mask,
        ridge: f64,
        exact: bool,
    ) -> std::rc::Rc<SupportFits> {
        let key = (mask, ridge.to_bits() ^ (exact as u64) << 63);
        self.tick += 1;
        if let Some((f, used, _)) = self.map.get_mut(&key) {
            *used = self.tick;
            return f.clone();
        }
        let support = mask_to_vec(mask);
        let mut scaled = Vec::with_capacity(cases.len());
        let mut raw = Vec::with_capacity(cases.len());
        for c in cases {
            let x = if exact {
                None
            } else {
                c.factor.fit_gram(c.target, &support, ridge)
            };
            let x = x.unwrap_or_else(|| c.factor.fit(c.target, &support, ridge).0);
            raw.push(
                support
                    .iter()
                    .zip(&x)
                    .map(|(&j, v)| v / c.factor.scales[j])
                    .collect(),
            );
            scaled.push(x);
        }
        // two vectors per case: header, data, allocator overhead
        let bytes = cases.len() * 2 * (3 * 8 + 8 * support.len().max(1) + 16);
        let f = std::rc::Rc::new(SupportFits {
            support,
            scaled,
            raw,
        });
        while self.held + bytes > self.budget && !self.map.is_empty() {
            let oldest = self
                .map
                .iter()
                .min_by_key(|(_, (_, used, _))| *used)
                .map(|(k, _)| *k);
            if let Some((_, _, b)) = oldest.and_then(|k| self.map.remove(&k)) {
                self.held -= b;
            }
        }
        self.map.insert(key, (f.clone(), self.tick, bytes));
        self.held += bytes;
        self.n_fits += 1;
        f
    }
}

/// Per case, the raw coefficients over the whole library (0 outside `mask`) of the plain
/// least-squares fit on `mask` by the QR solve: the final coefficients [`fit_group`] gives
/// for that support when unbiasing (or without ridge), the same numbers.
pub fn exact_fit_over_library(cases: &[CaseProblem<'_>], mask: Mask) -> Vec<Vec<f64>> {
    let support = mask_to_vec(mask);
    cases
        .iter()
        .map(|c| {
            let x = c.factor.fit(c.target, &support, 0.0).0;
            let mut full = vec![0.0; c.factor.n_columns()];
            for (&j, v) in support.iter().zip(&x) {
                full[j] = v / c.factor.scales[j];
            }
            full
        })
        .collect()
}

/// Result of [`fit_group`]: one support shared by the cases, coefficients per case.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupFit {
    /// Final support (library columns, ascending).
    pub support: Vec<usize>,
    /// Per case, raw coefficients over the whole library (0 outside the support).
    pub coefficients: Vec<Vec<f64>>,
    /// Per case, scaled coefficients over the whole library.
    pub scaled: Vec<Vec<f64>>,
    /// Supports visited, starting with the initial one.
    pub history: Vec<Vec<usize>>,
    /// Whether the support stopped changing before `max_iter`.
    pub converged: bool,
}

/// The shared fitting routine: starting from the columns `start`, alternates fits of every
/// case on the support with the regressor's reduction step until the support no longer
/// changes (or `max_iter`), never removing the columns in `kept`; then refits by plain least
/// squares on the final support when the regressor uses ridge and asks for unbiasing.
/// Returns a new value; nothing is mutated but the memo `cache`.
///
/// # Panics
/// When `cases` is empty or the factors have different column counts (programming errors).
#[track_caller]
pub fn fit_group(
    cases: &[CaseProblem<'_>],
    regressor: &dyn SparseRegressor,
    start: Mask,
    kept: Mask,
    cache: &mut FitCache,
) -> GroupFit {
    assert!(!cases.is_empty(), "a group needs at least one case");
    let p = cases[0].factor.n_columns();
    assert!(
        cases.iter().all(|c| c.factor.n_columns() == p),
        "library sizes differ"
    );
    let y_norm: Vec<f64> = cases.iter().map(CaseProblem::y_norm).collect();
    let ridge = regressor.ridge();
    let mut support = start;
    let mut history = vec![mask_to_vec(support)];
    let mut converged = false;
    for _ in 0..regressor.max_iter() {
        let fits = cache.fits(cases, support, ridge, false);
        let kept_v: Vec<bool> = fits.support.iter().map(|&j| kept >> j & 1 == 1).collect();
        let input = ReductionInput {
            support: &fits.support,
            kept: &kept_v,
            scaled: &fits.scaled,
            raw: &fits.raw,
            y_norm: &y_norm,
        };
        let remove = regressor.remove(&input);
        let mut next = support;
        for (i, &j) in fits.support.iter().enumerate() {
            if remove[i] && !kept_v[i] {
                next &= !(1 << j);
            }
        }
        if next == support {
            converged = true;
            break;
        }
        support = next;
        history.push(mask_to_vec(support));
    }
    let final_ridge = if regressor.unbias() { 0.0 } else { ridge };
    let fits = cache.fits(cases, support, final_ridge, true);
    let expand = |v: &Vec<f64>| {
        let mut full = vec![0.0; p];
        for (&j, &x) in fits.support.iter().zip(v) {
            full[j] = x;
        }
        full
    };
    GroupFit {
        support: fits.support.clone(),
        coefficients: fits.raw.iter().map(expand).collect(),
        scaled: fits.scaled.iter().map(expand).collect(),
        history,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn group_rules_differ_as_documented() {
        let m = [0.05, 0.2, 0.01];
        assert!(!GroupRule::Norm.removes(&m, 0.1)); // rms 0.12
        assert!(GroupRule::Mean.removes(&m, 0.1)); // mean 0.087
        assert!(GroupRule::Any.removes(&m, 0.1));
        assert!(!GroupRule::All.removes(&m, 0.1));
        assert!(GroupRule::All.removes(&m, 0.3));
    }

    #[test]
    fn masks_round_trip() {
        let v = vec![0, 3, 17, 33];
        assert_eq!(mask_to_vec(vec_to_mask(&v)), v);
        assert_eq!(bools_to_mask(&[true, false, true]), 0b101);
    }
}
