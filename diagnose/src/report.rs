//! Result types of a diagnosis: what each level (force, system) returns and the
//! `diagnosis.json` document (DATA_FORMAT.md, format `aeroform-diagnosis/1`).
//!
//! Every gap is a *normalised* residual measured on held-out data only: for the force
//! level sqrt(Σ r²/Σ F²) of the predicted minus measured aerodynamic force over held-out
//! forced cases (lift and moment each normalised by their own Σ F², then combined as the
//! root mean square of the two); for the system level the analogous quantity of the free
//! response (see [`crate::system`]). `noise_level` is the value the same metric takes when
//! the model is exact and only sensor noise remains, estimated from the data.

use serde::{Deserialize, Serialize};

use crate::effect::{Effect, Level, Verdict};

/// Identifier of the `diagnosis.json` format.
pub const FORMAT: &str = "aeroform-diagnosis/1";

/// One candidate augmentation fitted on training data and scored on held-out data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CandidateScore {
    /// Catalogue effect.
    pub effect: Effect,
    /// Level of the data it was scored on (`aerodynamic` = forced records, `structural`
    /// = free response).
    pub level: Level,
    /// Held-out gap of the baseline (same metric as [`LevelResult::before`]).
    pub before: f64,
    /// Held-out gap with the augmentation fitted on the training folds.
    pub after: f64,
    /// 1 − after/before (plain; [`crate::verdict::excess_shrink`] gives the share of the
    /// excess over noise).
    pub shrink: f64,
    /// Number of fitted parameters the augmentation adds (parsimony penalty).
    pub n_params: usize,
    /// Test statistic of the held-out improvement (documented by the level).
    pub statistic: f64,
    /// Threshold the statistic must exceed to be significant.
    pub threshold: f64,
    /// Whether the held-out improvement is significant after the parsimony penalty.
    pub significant: bool,
    /// Score used for ranking (lower is better; documented by the level).
    pub score: f64,
    /// Fitted parameter values by name, in SI units (e.g. `alpha0_rad`, `tau_s`).
    #[serde(default)]
    pub parameters: Vec<(String, f64)>,
    /// Why the candidate could not be fitted, when it could not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// Sign convention and units of `parameters` (e.g. "extra restoring force added to
    /// K q: … α positive nose-up").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convention: Option<String>,
    /// What restricted or chose this candidate (its form, the runs its evidence comes
    /// from, a simpler nested candidate preferred by the one-standard-error rule).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Held-out residual energy after the candidate per held-out unit (system level: per
    /// free run, mean of the two DOFs' normalised energies; empty where not kept), for
    /// paired comparisons of nested candidates.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held_out_runs: Vec<f64>,
}

/// A share of a level's held-out gap (excess residual energy) attributed to one cell of a
/// split. The shares of one `split` sum to 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct WhereShare {
    /// Which split this cell belongs to: `level`, `channel`, `harmonic`, `region`,
    /// `state`.
    pub split: String,
    /// Level of the cell.
    pub level: Level,
    /// Channel: `lift`, `moment` (forced), `heave`, `pitch` (free), or `all`.
    pub channel: String,
    /// Harmonic or combination tone (`DC`, `1*f_alpha`, `3*f_alpha`, `2*f_alpha+f_h`,
    /// `broadband`…), or `all`.
    pub harmonic: String,
    /// Wind-speed range \[m/s\] of the cell.
    pub wind_speed: [f64; 2],
    /// Pitch-amplitude range \[deg\] of the cell (forced cases; free: amplitude of the
    /// response).
    pub amplitude: [f64; 2],
    /// Motion configuration, if the cell is one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config: Option<String>,
    /// State-space region (`|alpha| < 0.5 A`, `alpha_dot > 0`…), if the split is `state`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub state: Option<String>,
    /// Share of the split's total, in [0, 1].
    pub share: f64,
}

/// Held-out gap of one case (heat map over U × amplitude).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseGap {
    /// Case id.
    pub id: String,
    /// Level (`aerodynamic` = forced case, `structural` = free run).
    pub level: Level,
    /// Configuration label, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config: Option<String>,
    /// Wind speed \[m/s\].
    pub wind_speed: f64,
    /// Pitch amplitude \[deg\] (forced: prescribed; free: initial or mean response).
    pub amplitude: f64,
    /// Fold in which the case was held out.
    pub fold: usize,
    /// Normalised held-out residual of the baseline.
    pub before: f64,
    /// Normalised held-out residual with the level's best candidate.
    pub after: f64,
    /// Noise-level value of the same metric for this case.
    pub noise_level: f64,
}

/// Mean residual amplitude spectrum of one channel over the held-out cases, before and
/// after the best candidate, on a frequency axis normalised by each case's pitch
/// frequency (forced) or in Hz (free).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ResidualSpectrum {
    /// Level.
    pub level: Level,
    /// Channel (`lift`, `moment`, `heave`, `pitch`).
    pub channel: String,
    /// Unit of `frequency` (`f/f_alpha` or `Hz`).
    pub frequency_unit: String,
    /// Frequency axis.
    pub frequency: Vec<f64>,
    /// Residual amplitude before (normalised by the rms of the measured channel).
    pub before: Vec<f64>,
    /// Residual amplitude after.
    pub after: Vec<f64>,
}

/// A residual signature test (spectral, phase, amplitude, U dependence, whiteness).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SignatureTest {
    /// Test name (`whiteness`, `dc`, `odd_harmonics`, `even_harmonics`, `off_harmonic_line`,
    /// `amplitude_threshold`, `u_dependence`, `hysteresis`, …).
    pub name: String,
    /// Level.
    pub level: Level,
    /// Statistic.
    pub statistic: f64,
    /// Threshold.
    pub threshold: f64,
    /// `statistic > threshold`.
    pub detected: bool,
    /// What the statistic is, in words, with its value where useful.
    pub detail: String,
}

/// One observable of the gap, before and after the winning augmentation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ObservableGap {
    /// Observable (`force residual`, `pitch frequency`, `LCO pitch amplitude`, `decay
    /// rate`, `flutter speed`…).
    pub name: String,
    /// Level.
    pub level: Level,
    /// Unit of `before`/`after` (`-` for normalised residuals).
    pub unit: String,
    /// Held-out gap of the baseline.
    pub before: f64,
    /// Held-out gap with the augmentation.
    pub after: f64,
    /// 1 − |after|/|before| (0 when before = 0).
    pub shrink: f64,
}

/// One point of a bifurcation diagram (free response).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BifurcationPoint {
    /// Wind speed \[m/s\].
    pub wind_speed: f64,
    /// Pitch amplitude at the end of the record \[deg\] (LCO amplitude, or the decayed
    /// amplitude below flutter).
    pub amplitude: f64,
    /// Dominant pitch frequency \[Hz\].
    pub frequency: f64,
}

/// Predicted vs measured bifurcation diagram over the free runs.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Bifurcation {
    /// From the measured free response.
    pub measured: Vec<BifurcationPoint>,
    /// From the baseline sim.
    pub predicted_before: Vec<BifurcationPoint>,
    /// From the sim with the winning augmentation (empty when none was applied).
    pub predicted_after: Vec<BifurcationPoint>,
}

/// How a level's held-out folds were formed (`levels[].fold_scheme` of `diagnosis.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FoldScheme {
    /// `leave_one_group_out` (each (configuration, wind speed) group is a fold: fewer
    /// groups than the requested folds), `stratified` (groups dealt to folds per
    /// configuration) or `leave_one_run_out` (free runs).
    pub scheme: String,
    /// Number of folds.
    pub folds: usize,
    /// Number of groups (forced: (configuration, wind speed) nodes; free: runs).
    pub groups: usize,
    /// Anything else that changed the folds (e.g. configurations pooled), one sentence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// What one level (force or system) of the diagnosis found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LevelResult {
    /// `aerodynamic` (forced records) or `structural` (free response).
    pub level: Level,
    /// Name of the gap metric.
    pub metric: String,
    /// Held-out gap of the baseline.
    pub before: f64,
    /// Noise-level value of the same metric.
    pub noise_level: f64,
    /// Whether `before` is significantly above `noise_level` (statistic and threshold in
    /// `gap_statistic`/`gap_threshold`).
    pub significant_gap: bool,
    /// Statistic of the gap test.
    pub gap_statistic: f64,
    /// Threshold of the gap test.
    pub gap_threshold: f64,
    /// Force level: the same statistic over the held-out cases whose reduced frequency
    /// lies inside the K range their fold was trained on (same configuration), i.e. whose
    /// prediction interpolates; absent when no held-out case does (and at the system
    /// level). A gap above threshold that these cases do not show, and that no candidate
    /// removes, comes from extrapolating the law to held-out wind speeds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interpolated_gap_statistic: Option<f64>,
    /// System level with a forced campaign: the sim's own uncertainty in the same metric,
    /// from a grouped jackknife over the forced campaign (the law identified again without
    /// each fold of (configuration, wind speed) groups; see
    /// [`crate::system::model_energy`]). The gap test's null level is then
    /// sqrt(noise_level² + model_level²): a gap the law's estimation error can produce is
    /// not an unmodelled effect. Absent at the force level (its held-out gap already
    /// carries that error), without a forced campaign, or below 3 groups.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_level: Option<f64>,
    /// Ids of the held-out cases (every case is held out once).
    pub held_out_cases: Vec<String>,
    /// Every candidate of this level, best first.
    pub candidates: Vec<CandidateScore>,
    /// Where the gap lies.
    #[serde(rename = "where")]
    pub where_: Vec<WhereShare>,
    /// Per-case gaps.
    pub cases: Vec<CaseGap>,
    /// Residual spectra before/after the best candidate.
    pub spectra: Vec<ResidualSpectrum>,
    /// Residual signature tests.
    pub signatures: Vec<SignatureTest>,
    /// Observables before/after the best candidate.
    pub observables: Vec<ObservableGap>,
    /// Bifurcation diagram (system level only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bifurcation: Option<Bifurcation>,
    /// How the held-out folds were formed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fold_scheme: Option<FoldScheme>,
    /// System level with a forced campaign: each free run's response against the K and
    /// amplitude range the forced cases identified (verdict `extrapolation` when the gap
    /// lies outside it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<Coverage>,
    /// System level: the still-air decays among the free runs against the nominal
    /// structure with the air's fitted apparent mass ([`crate::structure`]: frequency and
    /// damping against amplitude, envelope shape); `None` without a still-air run (the
    /// structural candidates then rest on the flow runs' amplitude dependence alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub structure: Option<crate::structure::StructureCheck>,
}

/// Free runs against the range the forced campaign identified (`levels[].coverage`).
///
/// A run's response reduced frequency per DOF is K = B·2πf/U with f its dominant
/// frequency of that DOF (B the full chord); it is *covered* when K lies within the K range
/// of the forced cases that identified that DOF's derivatives (K_h for H1, H4, A1, A4;
/// K_α for H2, H3, A2, A3), widened by [`Coverage::margin`], and its pitch amplitude does
/// not exceed the largest forced pitch amplitude by more than that margin. Still-air runs
/// (U = 0) have no aerodynamic force and are always covered.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Coverage {
    /// K_h range [min, max] of the forced cases.
    pub k_h_range: [f64; 2],
    /// K_α range [min, max] of the forced cases.
    pub k_alpha_range: [f64; 2],
    /// Pitch amplitude range [min, max] of the forced cases \[deg\].
    pub amplitude_alpha_deg_range: [f64; 2],
    /// Relative widening of the ranges before a run counts as outside (0.1).
    pub margin: f64,
    /// Every free run.
    pub runs: Vec<RunCoverage>,
    /// Share of the level's excess residual energy (gap² − null², summed over runs; null:
    /// the noise and, with a jackknife, the sim's own uncertainty) in the runs that leave
    /// the range.
    pub extrapolated_share: f64,
    /// Gap statistic (gap / null level, as the level's test) over the covered runs alone;
    /// `None` when no run is covered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covered_gap_statistic: Option<f64>,
    /// The level's gap with the derivative tables continued by straight lines beyond the
    /// forced range (the default sim), and its statistic (gap / noise level).
    pub linear_before: f64,
    /// Gap statistic of `linear_before`.
    pub linear_gap_statistic: f64,
    /// The level's gap with the derivative tables continued by Theodorsen-shaped tails
    /// instead of straight lines (`None` when no run leaves the range).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tails_before: Option<f64>,
    /// 1 − tails_before / linear_before: how far the physically consistent extrapolation
    /// shrinks the gap.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tails_shrink: Option<f64>,
    /// The tails' fitted weights on the flat plate's derivatives, per derivative (empty
    /// when no run leaves the range).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tail_weights: Vec<aeroelastic::identified::TailWeights>,
    /// The apparent heave mass the tails imply \[kg/m\]: the H4 tail's weight on the
    /// plate's own H4 × πρb² (the plate's K² growth of H4 is its apparent mass).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tails_apparent_mass: Option<f64>,
    /// πρb² of the section \[kg/m\] (ρ the free data set's air density, b the half chord):
    /// a flat plate's apparent heave mass, against which `tails_apparent_mass` reads.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plate_apparent_mass: Option<f64>,
    /// Which tables the level's gap and candidates use: `linear` or `theodorsen_tails` (the
    /// tails when runs leave the range and the tails give the smaller gap).
    pub sim_tables: String,
    /// Whether the gap is put down to extrapolation (verdict `extrapolation`): the linear
    /// sim's gap is significant, the runs outside the range carry at least half of its
    /// excess, and either the covered runs alone are clean or, with no run covered, the
    /// tails leave no significant gap.
    pub explains_gap: bool,
    /// Forced cases that would cover the runs outside the range.
    pub suggestions: Vec<SuggestedCase>,
}

/// One free run against the forced range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RunCoverage {
    /// Run id.
    pub id: String,
    /// Wind speed U \[m/s\].
    pub wind_speed: f64,
    /// Response K of heave, B·2πf_h/U (`None` at U = 0 or without heave motion).
    pub k_h: Option<f64>,
    /// Response K of pitch, B·2πf_α/U (`None` at U = 0 or without pitch motion).
    pub k_alpha: Option<f64>,
    /// Largest |α| over the scored part of the run \[deg\].
    pub amplitude_alpha_deg: f64,
    /// Largest |h| over the scored part of the run \[m\].
    pub amplitude_h_m: f64,
    /// Whether the run lies inside the forced range (K of both DOFs and amplitude).
    pub covered: bool,
    /// What leaves the range, e.g. `K_h 1.21 above 0.79`; empty when covered.
    pub outside: Vec<String>,
    /// The run's held-out gap (as `cases[].before`).
    pub before: f64,
}

/// A forced case that would bring a run's response inside the identified range: same
/// configuration and forcing frequency, the wind speed that gives the run's K.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SuggestedCase {
    /// The free run it covers.
    pub run: String,
    /// `heave` or `pitch`: which derivatives it identifies.
    pub dof: String,
    /// Configuration (group) of the forced cases whose forcing frequency is used.
    pub configuration: String,
    /// Forcing frequency of that configuration \[Hz\].
    pub frequency_hz: f64,
    /// Wind speed U = B·2πf/K \[m/s\].
    pub wind_speed: f64,
    /// Pitch amplitude to force \[deg\] (the run's).
    pub amplitude_alpha_deg: f64,
    /// The K it reaches.
    pub k: f64,
}

/// `verdict` of `diagnosis.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct VerdictReport {
    /// The verdict: a catalogue effect, `none`, `unexplained` or `extrapolation` (written
    /// as its name).
    pub effect: Verdict,
    /// `aerodynamic`, `structural` or `none`.
    pub level: Level,
    /// Confidence in [0, 1] (documented in [`crate::verdict`]).
    pub confidence: f64,
    /// One sentence saying why.
    pub reason: String,
}

/// `gap` of `diagnosis.json`: the headline gap of the level that decided the verdict.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct GapReport {
    /// Metric name.
    pub metric: String,
    /// Held-out gap before.
    pub before: f64,
    /// Held-out gap after the winning augmentation (= before when none).
    pub after: f64,
    /// 1 − after/before.
    pub shrink: f64,
    /// 1 − e_after/e_before with e = sqrt(max(gap² − noise², 0)): the share of the gap's
    /// excess over noise that the winning augmentation removes.
    #[serde(default)]
    pub excess_shrink: f64,
    /// Noise-level value of the metric.
    pub noise_level: f64,
    /// Held-out cases.
    pub held_out_cases: Vec<String>,
}

/// The `diagnosis.json` document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Diagnosis {
    /// Always [`FORMAT`].
    pub format: String,
    /// Verdict.
    pub verdict: VerdictReport,
    /// Headline gap.
    pub gap: GapReport,
    /// Where the gap lies (all levels).
    #[serde(rename = "where")]
    pub where_: Vec<WhereShare>,
    /// Every candidate scored, best first, all levels.
    pub candidates: Vec<CandidateScore>,
    /// Per level details.
    pub levels: Vec<LevelResult>,
    /// Seed of every random draw (fold assignment).
    pub seed: u64,
    /// aeroform version (`git describe` when known).
    pub version: String,
    /// Input data sets (folders or names).
    pub inputs: Vec<String>,
}
