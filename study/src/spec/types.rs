//! The study file's schema: the serde types of every section (`[data]`, `[identify]`,
//! `[structure]`, `[aero]`, `[flutter]`, `[lco]`, `[branch]`, `[outputs]`), their defaults
//! and the model names a study accepts. Below both the parser (`spec`) and its checks
//! (`spec::validate`), which import it (docs/DECISIONS.md "No import circles, checked");
//! re-exported as `study::spec::*`.

use std::path::PathBuf;

use aeroelastic::files::{ModelFile, ModelKind};
use aeroelastic::structure::{NondimStructure, Nonlinearities, PolyTerm, StructureSpec};
use identify::pipeline::IdentifySettings;
use serde::{Deserialize, Serialize};

/// A whole study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    /// Study name (output folder `out/<name>` by default; `[A-Za-z0-9._-]+`).
    pub name: String,
    /// Free text shown at the top of the report.
    #[serde(default)]
    pub description: String,
    /// Master seed of every random draw of the study (noise of synthetic data).
    #[serde(default = "one")]
    pub seed: u64,
    /// Where the forced-motion data come from (omit for a study without identification).
    pub data: Option<DataSpec>,
    /// Identification settings (defaults when omitted and `[data]` is given).
    pub identify: Option<IdentifySpec>,
    /// Structure of the aeroelastic section (flutter / LCO stages).
    pub structure: Option<StudyStructure>,
    /// Aerodynamic model of the aeroelastic section: a model file's keys
    /// ([`ModelFile`], `model` for `kind`, `n_lag` for `rfa_lags`); the chord is the
    /// structure's 2b; `identified` without `file` is this study's identified law; keys its
    /// kind does not use are the parameters of the flutter runs of other kinds.
    pub aero: Option<ModelFile>,
    /// Flutter stage.
    pub flutter: Option<FlutterSpec>,
    /// LCO stage.
    pub lco: Option<LcoSpec>,
    /// LCO branches by continuation (stable and unstable, folds), as `aeroform branch`.
    pub branch: Option<BranchSpec>,
    /// Figures and series to save.
    #[serde(default)]
    pub outputs: OutputsSpec,
}

fn one() -> u64 {
    1
}

/// `[data]`: exactly one source.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataSpec {
    /// A data-set folder (DATA_FORMAT.md), relative to the study file.
    pub dataset: Option<PathBuf>,
    /// A synthetic campaign from a known polynomial law (`identify::synthetic`).
    pub synthetic: Option<SyntheticSpec>,
    /// The paper's numerical verification (Table IV/V, Eq. 15/16).
    pub table_iv: Option<TableIvSpec>,
    /// Virtual wind tunnel campaign (`aeroelastic::tunnel`): forced motion of a known
    /// model, then the same preprocessing and identification as a data set.
    #[serde(rename = "virtual")]
    pub virtual_tunnel: Option<VirtualSpec>,
}

/// `[data.virtual]`: a forced-motion campaign of the virtual wind tunnel on the paper's rig
/// (B = 0.25 m, span 0.75 m, ρ = 1.225 kg/m³, 512 Hz, paper sensor noise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VirtualSpec {
    /// Model TOML file (`aeroelastic::files`), relative to the study file.
    pub model: Option<PathBuf>,
    /// Inline model, keys as `[aero]` (chord 0.25 m, the rig's).
    pub aero: Option<ModelFile>,
    /// `"paper"` (Tables I–II, 448 cases) or `"config=X"` (configuration X only, 64 cases).
    #[serde(default)]
    pub campaign: aeroelastic::tunnel::CampaignName,
    /// Still-air runs (0.82 kg uniform plate) subtracted in preprocessing.
    #[serde(default)]
    pub still_air: bool,
    /// Record length \[s\].
    #[serde(default = "duration")]
    pub duration: f64,
    /// Also write the data set (manifest + CSV) under `OUT/dataset`.
    #[serde(default)]
    pub write_dataset: bool,
}

/// Section geometry of synthetic data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionSpec {
    /// Chord B \[m\].
    pub chord: f64,
    /// Span \[m\].
    pub span: f64,
    /// Air density ρ \[kg/m³\].
    pub air_density: f64,
}

impl Default for SectionSpec {
    fn default() -> Self {
        // the paper's quasi-flat plate
        SectionSpec {
            chord: 0.25,
            span: 0.75,
            air_density: 1.225,
        }
    }
}

/// One motion configuration (paper Table I).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigSpec {
    /// Label ("A".."G").
    pub name: String,
    /// Pitch frequency f_α \[Hz\].
    pub freq_pitch: f64,
    /// Heave frequency f_h \[Hz\].
    pub freq_heave: f64,
    /// Heave amplitude per pitch amplitude \[mm/deg\].
    pub mm_per_deg: f64,
}

/// One term of a synthetic law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawTermSpec {
    /// Library term name, e.g. `alpha*alpha_dot`.
    pub term: String,
    /// Nondimensional coefficient.
    pub coefficient: f64,
}

/// `[data.synthetic.law]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawSpec {
    /// `"demo"` (identify's demonstration law) or `"custom"` (the lists below).
    #[serde(default)]
    pub preset: LawPreset,
    /// Terms of C_L (custom law).
    #[serde(default)]
    pub lift: Vec<LawTermSpec>,
    /// Terms of C_M (custom law).
    #[serde(default)]
    pub moment: Vec<LawTermSpec>,
}

/// `[data.synthetic.law] preset`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LawPreset {
    /// identify's demonstration law.
    #[default]
    Demo,
    /// The law of the `lift` and `moment` lists.
    Custom,
}

impl Default for LawSpec {
    fn default() -> Self {
        LawSpec {
            preset: LawPreset::Demo,
            lift: vec![],
            moment: vec![],
        }
    }
}

/// `[data.synthetic]`: configurations × amplitudes × speeds of forced motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SyntheticSpec {
    /// Section geometry.
    #[serde(default)]
    pub section: SectionSpec,
    /// Motion configurations.
    pub config: Vec<ConfigSpec>,
    /// Pitch amplitudes \[deg\].
    pub amplitudes_deg: Vec<f64>,
    /// Wind speeds \[m/s\].
    pub speeds: Vec<f64>,
    /// Force law.
    #[serde(default)]
    pub law: LawSpec,
    /// Sampling rate \[Hz\].
    #[serde(default = "rate")]
    pub rate: f64,
    /// Record length \[s\].
    #[serde(default = "duration")]
    pub duration: f64,
    /// Force noise, fraction of each channel's peak.
    #[serde(default = "force_noise")]
    pub force_noise: f64,
    /// Heave sensor noise \[m\].
    #[serde(default = "heave_noise")]
    pub heave_noise: f64,
    /// Pitch sensor noise \[rad\].
    #[serde(default = "pitch_noise")]
    pub pitch_noise: f64,
    /// Also write the data set (manifest + CSV) under `OUT/dataset`.
    #[serde(default)]
    pub write_dataset: bool,
}

fn rate() -> f64 {
    512.0
}
fn duration() -> f64 {
    10.0
}
fn force_noise() -> f64 {
    1e-3
}
fn heave_noise() -> f64 {
    8e-6
}
fn pitch_noise() -> f64 {
    1e-4
}

/// `[data.table_iv]`: the paper's Eq. 15/16 verification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableIvSpec {
    /// Number of noise realisations (seeds `seed`, `seed+1`, …).
    pub repeats: usize,
    /// Noise standard deviation σ.
    #[serde(default = "half")]
    pub sigma: f64,
    /// Sampling rate \[Hz\].
    #[serde(default = "rate")]
    pub rate: f64,
    /// Duration \[s\].
    #[serde(default = "twenty")]
    pub duration: f64,
    /// (A1, A2, H1, H2, N1, N2) of the moment channel (paper group 1).
    #[serde(default = "group1")]
    pub moment: [f64; 6],
    /// (A1, A2, H1, H2, N1, N2) of the lift channel (paper group 2).
    #[serde(default = "group2")]
    pub lift: [f64; 6],
}

fn half() -> f64 {
    0.5
}
fn twenty() -> f64 {
    20.0
}
fn group1() -> [f64; 6] {
    identify::paper::TableIvGroup::GROUP1.coefficients
}
fn group2() -> [f64; 6] {
    identify::paper::TableIvGroup::GROUP2.coefficients
}

/// `[identify]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IdentifySpec {
    /// Every option of `identify::pipeline::identify` (`[identify.settings]`).
    #[serde(default)]
    pub settings: IdentifySettings,
    /// Preprocessing (`[identify.preprocess]`).
    #[serde(default)]
    pub preprocess: PreprocessSpec,
    /// Block-bootstrap ensemble of this many members (≥ 2), seeded with the study's
    /// `seed`: `identification.json` gets its `ensemble` section, and the flutter and LCO
    /// stages of the identified model report percentile intervals (`ensemble` keys of
    /// `flutter.json` and `lco.json`) drawn as error bars in the figures. `None`: no
    /// ensemble.
    #[serde(default)]
    pub ensemble: Option<usize>,
    /// Level of the ensemble's intervals, in (0, 1).
    #[serde(default = "ensemble_level")]
    pub ensemble_level: f64,
}

impl Default for IdentifySpec {
    fn default() -> Self {
        IdentifySpec {
            settings: IdentifySettings::default(),
            preprocess: PreprocessSpec::default(),
            ensemble: None,
            ensemble_level: ensemble_level(),
        }
    }
}

fn ensemble_level() -> f64 {
    identify::ensemble::DEFAULT_LEVEL
}

/// `[identify.preprocess]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PreprocessSpec {
    /// How velocities are obtained: `"auto"`, `"harmonic"` or `"sg"` (Savitzky–Golay).
    #[serde(default)]
    pub velocity: VelocityChoice,
    /// Subtract still-air runs.
    #[serde(default = "yes")]
    pub subtract_nowind: bool,
    /// Savitzky–Golay half window \[samples\].
    #[serde(default = "sg_half")]
    pub sg_half_window: usize,
    /// Savitzky–Golay order.
    #[serde(default = "sg_order")]
    pub sg_order: usize,
}

/// `[identify.preprocess] velocity`: the velocity method of preprocessing
/// ([`identify::preprocess::VelocityMethod`]; `sg` takes the spec's window and order).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocityChoice {
    /// Harmonic fit for periodic records, Savitzky–Golay otherwise.
    #[default]
    Auto,
    /// Harmonic fit.
    Harmonic,
    /// Savitzky–Golay differentiation.
    Sg,
}

fn yes() -> bool {
    true
}
fn sg_half() -> usize {
    identify::preprocess::DEFAULT_SG_HALF_WINDOW
}
fn sg_order() -> usize {
    identify::preprocess::DEFAULT_SG_ORDER
}

impl Default for PreprocessSpec {
    fn default() -> Self {
        PreprocessSpec {
            velocity: VelocityChoice::Auto,
            subtract_nowind: true,
            sg_half_window: sg_half(),
            sg_order: sg_order(),
        }
    }
}

/// `[structure]`: a typical section in Hodges & Pierce's nondimensional form — the shared
/// [`NondimStructure`] (with its defaults: `semi_chord`, `omega_alpha`, `rho` = 1;
/// `x_alpha`, `zeta_h`, `zeta_alpha` = 0) plus the study's relative pitch cubic.
///
/// Unknown keys are rejected by [`Study::parse`](super::Study::parse) (naming `structure.KEY` and its line).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyStructure {
    /// The linear structure (keys `mu`, `r_alpha2`, `sigma`, …, flat in `[structure]`).
    #[serde(flatten)]
    pub linear: NondimStructure,
    /// Cubic pitch spring k_α3/k_α [1/rad²] (restoring moment k_α(α + k α³)); default 0.
    #[serde(default)]
    pub pitch_cubic: f64,
    /// Keys that are none of the above: must be empty (`deny_unknown_fields` does not
    /// combine with `flatten`; [`Study::parse`] checks it).
    #[serde(flatten, skip_serializing)]
    unknown: std::collections::BTreeMap<String, toml::Value>,
}

/// The keys of `[structure]`, in documented order (for the unknown-key message).
pub(super) const STRUCTURE_KEYS: [&str; 10] = [
    "mu",
    "r_alpha2",
    "sigma",
    "x_alpha",
    "semi_chord",
    "omega_alpha",
    "rho",
    "zeta_h",
    "zeta_alpha",
    "pitch_cubic",
];

impl StudyStructure {
    /// The shared structure spec: [`StructureSpec::Nondimensional`] whose nonlinear terms
    /// are the pitch cubic as a pitch polynomial term k_α·k·α³ (none when k = 0).
    pub fn spec(&self) -> StructureSpec {
        let mut nonlinear = Nonlinearities::none();
        if self.pitch_cubic != 0.0 {
            nonlinear.pitch_stiffness_terms.push(PolyTerm {
                power: 3,
                coefficient: self.pitch_cubic * self.linear.k_alpha(),
            });
        }
        StructureSpec::Nondimensional {
            linear: self.linear,
            nonlinear,
        }
    }

    /// The first key of the table that is not a `[structure]` key, if any.
    pub(super) fn unknown_key(&self) -> Option<&str> {
        self.unknown.keys().next().map(String::as_str)
    }
}

pub use aeroelastic::documents::FlutterReference;

/// One flutter analysis of `[flutter]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlutterRunSpec {
    /// Label in tables and figures.
    pub label: String,
    /// Aerodynamic model (as `[aero].model`, or `truth`: the model of `[data.virtual]`;
    /// default the study's).
    pub model: Option<StudyModel>,
    /// `"p"` or `"pk"`.
    pub method: aeroelastic::flutter::FlutterMethod,
    /// Published values.
    pub reference: Option<FlutterReference>,
}

/// `[flutter]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlutterSpec {
    /// Lowest speed \[m/s\].
    pub u_min: f64,
    /// Highest speed \[m/s\].
    pub u_max: f64,
    /// Speeds of the scan.
    #[serde(default = "eighty")]
    pub n_speeds: usize,
    /// Relative tolerance of the critical speed.
    #[serde(default = "tol")]
    pub tol_rel: f64,
    /// Axes of the figures: `"si"` (m/s, Hz) or `"reduced"` (U/(bω_α), ω/ω_α).
    #[serde(default)]
    pub axes: Axes,
    /// Damping axis of the V–g figures: `"zeta"` (damping ratio ζ = −Re p/|p|) or `"g"`
    /// (structural damping g = 2ζ, the NASTRAN convention).
    #[serde(default)]
    pub damping: DampingAxis,
    /// Analyses (default: one p-k analysis of `[aero]`).
    #[serde(default)]
    pub run: Vec<FlutterRunSpec>,
}

/// `[flutter] axes`: the units of the flutter figures' axes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axes {
    /// U in m/s, frequencies in Hz.
    #[default]
    Si,
    /// U/(bω_α) and ω/ω_α.
    Reduced,
}

/// `[flutter] damping`: the damping axis of the V–g figures.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DampingAxis {
    /// Damping ratio ζ = −Re p/|p|.
    #[default]
    Zeta,
    /// Structural damping g = 2ζ (the NASTRAN convention).
    G,
}

fn eighty() -> usize {
    80
}
fn tol() -> f64 {
    1e-9
}

/// `[lco]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LcoSpec {
    /// Speeds \[m/s\].
    pub speeds: Vec<f64>,
    /// Also sweep down (hysteresis).
    #[serde(default = "yes")]
    pub up_down: bool,
    /// Initial pitch perturbation of the upward sweep \[deg\].
    #[serde(default = "one_f")]
    pub perturbation_deg: f64,
    /// Initial pitch perturbation of the downward sweep \[deg\].
    #[serde(default = "ten")]
    pub perturbation_down_deg: f64,
    /// Longest run [pitch periods].
    #[serde(default = "periods")]
    pub max_periods: f64,
    /// Relative tolerance of the integrator.
    #[serde(default = "rtol")]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[serde(default = "atol")]
    pub atol: f64,
    /// Speeds \[m/s\] of the phase portraits (nearest LCO speeds of the upward sweep).
    #[serde(default)]
    pub phase_speeds: Vec<f64>,
    /// Length of the phase portraits [pitch periods].
    #[serde(default = "three")]
    pub phase_periods: f64,
    /// Also sweep the truth model of `[data.virtual]` (with the same structure) and write
    /// the truth-vs-`[aero]` comparison (`round_trip.csv`, a second bifurcation figure).
    #[serde(default)]
    pub compare_truth: bool,
}

fn one_f() -> f64 {
    1.0
}
fn ten() -> f64 {
    10.0
}
fn three() -> f64 {
    3.0
}
fn periods() -> f64 {
    600.0
}
fn rtol() -> f64 {
    1e-8
}
fn atol() -> f64 {
    1e-10
}

/// `[branch]`: LCO branches by continuation from every Hopf point in `speeds`, on the
/// section of `[structure]` and `[aero]` (as `aeroform branch`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BranchSpec {
    /// Speed range `[a, b]` \[m/s\], 0 < a < b: Hopf points are searched and branches
    /// continued in it.
    pub speeds: [f64; 2],
    /// Largest number of orbits per branch.
    #[serde(default = "branch_points")]
    pub max_points: usize,
    /// Fixed RK4 steps per period of the shooting integration (or of harmonic balance's
    /// variational equation).
    #[serde(default = "steps_per_period")]
    pub steps_per_period: usize,
    /// Orbit discretisation, `shooting` (default) or `harmonic_balance`.
    #[serde(default)]
    pub method: aeroelastic::branch::BranchMethod,
    /// Harmonics of the harmonic-balance series.
    #[serde(default = "harmonics")]
    pub harmonics: usize,
    /// Measured amplitudes to overlay (CSV: `branch, wind_speed_m_s, heave_amp_m,
    /// pitch_amp_rad`), relative to the study file.
    pub measured: Option<PathBuf>,
}

fn harmonics() -> usize {
    aeroelastic::branch::BranchOptions::default().harmonics
}

fn branch_points() -> usize {
    200
}
fn steps_per_period() -> usize {
    128
}

/// Figure kinds a study can draw.
pub const FIGURE_KINDS: [&str; 15] = [
    "time_series",
    "spectrum",
    "force_decomposition",
    "library",
    "delta_path",
    "delta_fits",
    "heatmap",
    "force_loops",
    "histogram",
    "derivatives",
    "mean_angle",
    "vg",
    "bifurcation",
    "phase",
    "branch_diagram",
];

/// `[outputs]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct OutputsSpec {
    /// Figure kinds to draw (default: every kind the stages support).
    pub figures: Option<Vec<String>>,
    /// Case ids shown in time-series and spectrum figures (default: the first and the last
    /// case).
    #[serde(default)]
    pub series_cases: Vec<String>,
    /// Groups whose δ path is drawn (default: every group, at most 4).
    #[serde(default)]
    pub delta_groups: Vec<String>,
}

/// An aerodynamic model of a study by name (`[aero].model`, `[[flutter.run]].model`): a
/// model kind built with `[aero]`'s parameters (`identified`: this study's identified law),
/// or the truth model of `[data.virtual]` (flutter runs only). Written as the kind's name
/// ([`ModelKind::name`]) or `truth`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StudyModel {
    /// A model kind with `[aero]`'s parameters.
    Kind(ModelKind),
    /// The truth model of `[data.virtual]` (flutter runs only).
    Truth,
}

impl StudyModel {
    /// This study's identified law.
    pub const IDENTIFIED: StudyModel = StudyModel::Kind(ModelKind::Identified);

    /// The name as written in the study file and the result documents.
    pub fn name(self) -> &'static str {
        match self {
            StudyModel::Kind(k) => k.name(),
            StudyModel::Truth => "truth",
        }
    }
}

impl Serialize for StudyModel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for StudyModel {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{value::StrDeserializer, Error as _};
        let name = String::deserialize(d)?;
        if name == "truth" {
            return Ok(StudyModel::Truth);
        }
        ModelKind::deserialize(StrDeserializer::<D::Error>::new(&name))
            .map(StudyModel::Kind)
            .map_err(|_| {
                let known: Vec<&str> = ModelKind::ALL.iter().map(|k| k.name()).collect();
                D::Error::custom(format!(
                    "unknown model `{name}`: expected one of {}, truth",
                    known.join(", ")
                ))
            })
    }
}

impl schemars::JsonSchema for StudyModel {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "StudyModel".into()
    }

    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "An aerodynamic model of a study: a model kind built with [aero]'s parameters (`identified`: the study's identified law), or `truth`, the model of [data.virtual].",
            "anyOf": [
                g.subschema_for::<ModelKind>(),
                { "const": "truth", "description": "The truth model of [data.virtual] (flutter runs only)." }
            ]
        })
    }
}

impl std::fmt::Display for StudyModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
