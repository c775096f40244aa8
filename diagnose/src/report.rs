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

/// The split a where-cell belongs to (variants in the alphabetical order of their names).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    Serialize,
    Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Split {
    /// By response amplitude (system level).
    Amplitude,
    /// By channel.
    Channel,
    /// By harmonic or combination tone of the forcing ([`Harmonic`]).
    Harmonic,
    /// Between the levels.
    Level,
    /// By (configuration, wind speed, amplitude) region of the forced cases.
    Region,
    /// By state-space region (`|alpha| < 0.5 A`, `alpha_dot > 0`…).
    State,
}

impl Split {
    /// The name written in diagnosis.json (`channel`, `harmonic`, …).
    pub fn name(self) -> &'static str {
        match self {
            Split::Amplitude => "amplitude",
            Split::Channel => "channel",
            Split::Harmonic => "harmonic",
            Split::Level => "level",
            Split::Region => "region",
            Split::State => "state",
        }
    }
}

impl std::str::FromStr for Split {
    type Err = String;

    /// The split of a [`Split::name`]; an error naming the string otherwise.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        [
            Split::Amplitude,
            Split::Channel,
            Split::Harmonic,
            Split::Level,
            Split::Region,
            Split::State,
        ]
        .into_iter()
        .find(|x| x.name() == s)
        .ok_or_else(|| {
            format!("split `{s}`: expected amplitude, channel, harmonic, level, region or state")
        })
    }
}

impl std::fmt::Display for Split {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A residual channel: the forces of the forced records, the motions of the free ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    /// Lift (forced records).
    Lift,
    /// Moment (forced records).
    Moment,
    /// Heave (free records).
    Heave,
    /// Pitch (free records).
    Pitch,
    /// Every channel (a cell of another split).
    All,
}

impl Channel {
    /// The force level's channels, in column order.
    pub const FORCES: [Channel; 2] = [Channel::Lift, Channel::Moment];
    /// The system level's channels, in state order.
    pub const MOTIONS: [Channel; 2] = [Channel::Heave, Channel::Pitch];

    /// The name written in diagnosis.json (`lift`, …, `all`).
    pub fn name(self) -> &'static str {
        match self {
            Channel::Lift => "lift",
            Channel::Moment => "moment",
            Channel::Heave => "heave",
            Channel::Pitch => "pitch",
            Channel::All => "all",
        }
    }
}

impl std::str::FromStr for Channel {
    type Err = String;

    /// The channel of a [`Channel::name`]; an error naming the string otherwise.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        [
            Channel::Lift,
            Channel::Moment,
            Channel::Heave,
            Channel::Pitch,
            Channel::All,
        ]
        .into_iter()
        .find(|x| x.name() == s)
        .ok_or_else(|| format!("channel `{s}`: expected lift, moment, heave, pitch or all"))
    }
}

impl std::fmt::Display for Channel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The harmonic content of a where-cell of the `harmonic` split.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Harmonic {
    /// Every harmonic (a cell of another split): `all`.
    All,
    /// The mean: `DC`.
    Dc,
    /// The combination tone m·f_α + n·f_h (m ≥ 0, not both 0; n = 0 for pitch-only
    /// forcing): `3*f_alpha`, `2*f_alpha-f_h`, … (`identify::metrics::Tone::label`).
    Tone {
        /// Multiple of the pitch forcing frequency.
        m: i32,
        /// Multiple of the heave forcing frequency.
        n: i32,
    },
    /// A line off every forcing tone (a bin above 20 × the median): `off-harmonic line`.
    OffHarmonicLine,
    /// The broadband floor above the noise: `broadband`.
    Broadband,
}

impl Harmonic {
    /// The label written in diagnosis.json.
    pub fn label(self) -> String {
        match self {
            Harmonic::All => "all".into(),
            Harmonic::Dc => "DC".into(),
            Harmonic::Tone { m, n } => identify::metrics::Tone { freq: 0.0, m, n }.label(),
            Harmonic::OffHarmonicLine => "off-harmonic line".into(),
            Harmonic::Broadband => "broadband".into(),
        }
    }

    /// The net multiple |m + n| of a tone (`None` for the other cells): the harmonic of
    /// the pitch frequency it falls on when f_h ≈ f_α (odd ≥ 3: a cubic's tones; even: an
    /// offset's).
    pub fn net(self) -> Option<i32> {
        match self {
            Harmonic::Tone { m, n } => Some((m + n).abs()),
            _ => None,
        }
    }

    /// The harmonic of a label ([`Harmonic::label`]; a tone may also spell a unit
    /// multiple, `1*f_alpha`).
    ///
    /// # Errors
    /// A message naming the label when it is none of the forms above.
    pub fn from_label(s: &str) -> std::result::Result<Self, String> {
        match s {
            "all" => return Ok(Harmonic::All),
            "DC" => return Ok(Harmonic::Dc),
            "off-harmonic line" => return Ok(Harmonic::OffHarmonicLine),
            "broadband" => return Ok(Harmonic::Broadband),
            _ => {}
        }
        let bad = || {
            format!(
                "harmonic `{s}`: expected `all`, `DC`, `off-harmonic line`, `broadband` or a \
                 tone such as `3*f_alpha`, `2*f_alpha-f_h`"
            )
        };
        let (mut m, mut n) = (None, None);
        let spaced = s.replace('-', "+-");
        for part in spaced.split('+').filter(|p| !p.is_empty()) {
            let (coef, var) = match part.split_once('*') {
                Some((c, v)) => (c.parse::<i32>().map_err(|_| bad())?, v),
                None => match part.strip_prefix('-') {
                    Some(v) => (-1, v),
                    None => (1, part),
                },
            };
            let slot = match var {
                "f_alpha" => &mut m,
                "f_h" => &mut n,
                _ => return Err(bad()),
            };
            if slot.replace(coef).is_some() {
                return Err(bad());
            }
        }
        let (m, n) = (m.unwrap_or(0), n.unwrap_or(0));
        if (m, n) == (0, 0) {
            return Err(bad());
        }
        // `1*f_alpha` reads as `f_alpha` (written back in the canonical spelling)
        Ok(Harmonic::Tone { m, n })
    }
}

impl std::str::FromStr for Harmonic {
    type Err = String;

    /// [`Harmonic::from_label`].
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        Harmonic::from_label(s)
    }
}

impl std::fmt::Display for Harmonic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.label())
    }
}

/// Written as its [`Harmonic::label`].
impl Serialize for Harmonic {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.label())
    }
}

/// Read from its [`Harmonic::label`]; any other string is an error naming it.
impl<'de> Deserialize<'de> for Harmonic {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        Harmonic::from_label(&s).map_err(serde::de::Error::custom)
    }
}

/// A string: `all`, `DC`, `off-harmonic line`, `broadband` or a tone label.
impl schemars::JsonSchema for Harmonic {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Harmonic".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "`all`, `DC` (the mean), `off-harmonic line`, `broadband` or a \
                combination tone m*f_alpha+n*f_h written as `f_alpha`, `3*f_alpha`, \
                `2*f_alpha-f_h`, `f_h`.",
            "type": "string",
        })
    }
}

/// A share of a level's held-out gap (excess residual energy) attributed to one cell of a
/// split. The shares of one `split` sum to 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct WhereShare {
    /// Which split this cell belongs to.
    pub split: Split,
    /// Level of the cell.
    pub level: Level,
    /// Channel: `lift`, `moment` (forced), `heave`, `pitch` (free), or `all`.
    pub channel: Channel,
    /// Harmonic or combination tone (`DC`, `f_alpha`, `3*f_alpha`, `2*f_alpha+f_h`,
    /// `broadband`…), or `all`.
    pub harmonic: Harmonic,
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
    pub channel: Channel,
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
    /// With a given model (`diagnose --free … --model M`, structure first): against the
    /// nominal structure with the model's apparent mass at U = 0, with the linear
    /// structure identified from the decays, the structure `used` and the `gap` before
    /// and after the correction alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub structure: Option<crate::structure::StructureCheck>,
    /// Free-response level with controlled records (control-based continuation): the
    /// controller's force as a measured input — its fitted gain and offset (raw signal),
    /// the gap without and with it, per run, the DOF the data points at, and why the
    /// controlled runs are not simulated ([`crate::system::control`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control: Option<crate::system::control::ControlReport>,
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
    /// The forced tests that would cover the free runs outside the forced range, ranked
    /// (issue 42 item 4; [`crate::follow_up::plan`]); absent when every run is covered.
    /// Also written as `follow_up.campaign.toml` for `aeroform tunnel forced
    /// --campaign-file`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub follow_up: Option<aeroelastic::tunnel::CampaignPlan>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_labels_round_trip_and_bad_ones_are_named() {
        let mut cells = vec![
            Harmonic::All,
            Harmonic::Dc,
            Harmonic::OffHarmonicLine,
            Harmonic::Broadband,
        ];
        for m in 0..=9 {
            for n in -9..=9 {
                if (m, n) != (0, 0) && !(m == 0 && n < 0) {
                    cells.push(Harmonic::Tone { m, n });
                }
            }
        }
        for h in cells {
            let json = serde_json::to_string(&h).unwrap();
            assert_eq!(
                serde_json::from_str::<Harmonic>(&json).unwrap(),
                h,
                "{json}"
            );
        }
        assert_eq!(
            Harmonic::from_label("3*f_alpha"),
            Ok(Harmonic::Tone { m: 3, n: 0 })
        );
        assert_eq!(
            Harmonic::from_label("2*f_alpha-f_h"),
            Ok(Harmonic::Tone { m: 2, n: -1 })
        );
        assert_eq!(Harmonic::Tone { m: 2, n: -1 }.net(), Some(1));
        assert_eq!(
            Harmonic::from_label("1*f_alpha"),
            Ok(Harmonic::Tone { m: 1, n: 0 })
        );
        for bad in ["", "f_alpha+f_alpha", "3*f_beta", "dc", "0*f_h"] {
            let e = Harmonic::from_label(bad).unwrap_err();
            assert!(e.contains(&format!("`{bad}`")), "{e}");
        }
        for (s, c) in [("lift", Channel::Lift), ("all", Channel::All)] {
            assert_eq!(s.parse::<Channel>(), Ok(c));
        }
        assert!("torque".parse::<Channel>().unwrap_err().contains("torque"));
        assert_eq!("state".parse::<Split>(), Ok(Split::State));
    }
}
