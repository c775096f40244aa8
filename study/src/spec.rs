//! The study file (TOML): what to compute and draw. Parsed once with `deny_unknown_fields`
//! everywhere; every error names the file, the line and the dotted key.

use std::path::{Path, PathBuf};

use aeroelastic::files::{ModelFile, ModelKind};
use aeroelastic::structure::{NondimStructure, Nonlinearities, PolyTerm, StructureSpec};
use identify::pipeline::IdentifySettings;
use serde::{Deserialize, Serialize};

mod validate;

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
/// Unknown keys are rejected by [`Study::parse`] (naming `structure.KEY` and its line).
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
const STRUCTURE_KEYS: [&str; 10] = [
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
    fn unknown_key(&self) -> Option<&str> {
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

/// A parsed study with its source text and location.
#[derive(Debug, Clone)]
pub struct Study {
    /// Parsed content.
    pub spec: StudySpec,
    /// The TOML text as read (copied to `OUT/study.toml`).
    pub text: String,
    /// File it came from (`<built-in quickstart>` for the embedded study).
    pub path: PathBuf,
    /// Folder relative paths are resolved against.
    pub base: PathBuf,
}

/// The built-in quickstart study.
pub const QUICKSTART: &str = include_str!("../../scenarios/quickstart.toml");

/// An error in a study file: file, line, key, message.
#[derive(Debug)]
pub struct SpecError {
    /// Study file.
    pub path: String,
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// Dotted key.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for SpecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}:{}: key `{}`: {}",
            self.path, self.line, self.key, self.message
        )
    }
}

impl std::error::Error for SpecError {}

/// The dotted key (`flutter.run[1].label`) of the first string below `t` holding a character
/// [`identify::io::disallowed_char`] refuses, with the message.
fn first_bad_string(t: &toml::Table, prefix: &str) -> Option<(String, String)> {
    fn walk(v: &toml::Value, key: &str) -> Option<(String, String)> {
        match v {
            toml::Value::String(s) => identify::io::disallowed_char(s).map(|(pos, c)| {
                (
                    key.to_string(),
                    identify::io::disallowed_char_message(pos, c),
                )
            }),
            toml::Value::Array(a) => a
                .iter()
                .enumerate()
                .find_map(|(i, x)| walk(x, &format!("{key}[{i}]"))),
            toml::Value::Table(t) => first_bad_string(t, key),
            _ => None,
        }
    }
    t.iter().find_map(|(k, v)| {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        walk(v, &key)
    })
}

impl Study {
    /// Parses a study from TOML text.
    ///
    /// # Errors
    /// [`SpecError`] naming the line and key of a syntax error, an unknown key, a value of
    /// the wrong type or a value out of range.
    pub fn parse(text: &str, path: &Path, base: &Path) -> Result<Study, SpecError> {
        let display = path.display().to_string();
        let lines = identify::toml_lines::TomlLines::new(text);
        let spec: StudySpec = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| lines.line(s.start)).unwrap_or(0);
            let msg = e.message().trim().to_string();
            // serde names the key in its message (`unknown field `x``, `missing field`);
            // a bad value (an unknown model or method name, a wrong type) is named by the
            // key of the line it stands on
            let key = msg
                .split('`')
                .nth(1)
                .filter(|_| msg.contains("field"))
                .map(str::to_string)
                .or_else(|| e.span().and_then(|s| key_at(text, s.start)));
            // `[structure]` is flattened: serde reports a wrong-typed value there without
            // its key; find the key again
            if key.is_none() {
                let culprit = text
                    .parse::<toml::Table>()
                    .ok()
                    .and_then(|t| t.get("structure").and_then(|v| v.as_table()).cloned())
                    .and_then(|t| aeroelastic::files::flattened_bad_key::<StudyStructure>(&t));
                if let Some((k, message)) = culprit {
                    let key = format!("structure.{k}");
                    return SpecError {
                        path: display.clone(),
                        line: lines.line_of(&key),
                        key,
                        message,
                    };
                }
            }
            SpecError {
                path: display.clone(),
                line,
                key: key.unwrap_or_else(|| "(syntax)".to_string()),
                message: msg,
            }
        })?;
        // every string of the study may reach a figure (SVG), the report (HTML) or the
        // terminal: a control character is refused here, by key and line, not at the figure
        // stage (issue 39, row 7)
        if let Some((key, message)) = text
            .parse::<toml::Table>()
            .ok()
            .and_then(|t| first_bad_string(&t, ""))
        {
            return Err(SpecError {
                path: display,
                line: lines.line_of(&key),
                key,
                message,
            });
        }
        let study = Study {
            spec,
            text: text.to_string(),
            path: path.to_path_buf(),
            base: base.to_path_buf(),
        };
        study.validate().map_err(|(key, message)| SpecError {
            path: display,
            line: lines.line_of(&key),
            key,
            message,
        })?;
        Ok(study)
    }

    /// Reads and parses a study file (relative data paths resolve against its folder).
    ///
    /// # Errors
    /// [`SpecError`] when the file cannot be read (line 0) or does not parse.
    pub fn read(path: &Path) -> Result<Study, SpecError> {
        let text = identify::io::read_text(path).map_err(|e| SpecError {
            path: path.display().to_string(),
            line: 0,
            key: "(file)".into(),
            message: e.to_string(),
        })?;
        let base = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        Study::parse(&text, path, &base)
    }

    /// Every file and folder the study reads, with the key that names it (`study` for the
    /// study file itself, unless embedded; `data.dataset`, `data.virtual.model`,
    /// `branch.measured`), relative paths resolved against [`Study::base`]. A run's output
    /// folder may not be, contain or lie inside any of them (issue 39, row 1).
    pub fn inputs(&self) -> Vec<(&'static str, PathBuf)> {
        let mut v = Vec::new();
        if self.path.exists() {
            v.push(("study", self.path.clone()));
        }
        let d = self.spec.data.as_ref();
        if let Some(p) = d.and_then(|d| d.dataset.as_ref()) {
            v.push(("data.dataset", self.base.join(p)));
        }
        let virtual_model = d.and_then(|d| d.virtual_tunnel.as_ref()?.model.as_ref());
        if let Some(p) = virtual_model {
            v.push(("data.virtual.model", self.base.join(p)));
        }
        if let Some(p) = self.spec.branch.as_ref().and_then(|b| b.measured.as_ref()) {
            v.push(("branch.measured", self.base.join(p)));
        }
        if let Some(p) = self.spec.aero.as_ref().and_then(|a| a.file.as_ref()) {
            v.push(("aero.file", self.base.join(p)));
        }
        v
    }

    /// The embedded quickstart study.
    ///
    /// # Errors
    /// Never for the committed file (checked by a unit test).
    pub fn quickstart() -> Result<Study, SpecError> {
        Study::parse(
            QUICKSTART,
            Path::new("<built-in quickstart.toml>"),
            Path::new("."),
        )
    }

    /// Figure kinds this study draws.
    pub fn figure_kinds(&self) -> Vec<String> {
        if let Some(f) = &self.spec.outputs.figures {
            return f.clone();
        }
        let s = &self.spec;
        let mut v: Vec<&str> = vec![];
        if s.data.is_some() {
            v.extend([
                "time_series",
                "spectrum",
                "library",
                "delta_path",
                "delta_fits",
            ]);
            v.push("histogram");
            if s.data.as_ref().is_some_and(|d| d.table_iv.is_none()) {
                v.extend([
                    "force_decomposition",
                    "heatmap",
                    "force_loops",
                    "derivatives",
                    "mean_angle",
                ]);
            }
        }
        if s.flutter.is_some() {
            v.push("vg");
        }
        if let Some(l) = &s.lco {
            v.push("bifurcation");
            if !l.phase_speeds.is_empty() {
                v.push("phase");
            }
        }
        if s.branch.is_some() {
            v.push("branch_diagram");
        }
        v.into_iter().map(String::from).collect()
    }

    /// Range and consistency checks; `Err((dotted key, message))` (the sections' checks
    /// live in `validate`).
    fn validate(&self) -> Result<(), (String, String)> {
        validate::study(&self.spec)
    }
}

/// The dotted key (`table.array[i].key`) of the `key = value` line holding byte `offset`
/// of `text`, from the nearest table header above it; `None` off a `key = value` line.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let start = text[..offset.min(text.len())]
        .rfind('\n')
        .map_or(0, |i| i + 1);
    let line = text[start..].lines().next()?;
    let leaf = line.split_once('=')?.0.trim();
    if leaf.is_empty() || leaf.starts_with('[') {
        return None;
    }
    let above = &text[..start];
    let header = above
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['));
    let table = match header {
        Some(h) if h.starts_with("[[") => {
            let name = h.trim_start_matches('[').trim_end_matches(']').trim();
            let count = above
                .lines()
                .map(str::trim)
                .filter(|l| {
                    l.starts_with("[[")
                        && l.trim_start_matches('[').trim_end_matches(']').trim() == name
                })
                .count();
            format!("{name}[{}].", count.saturating_sub(1))
        }
        Some(h) => format!(
            "{}.",
            h.trim_start_matches('[').trim_end_matches(']').trim()
        ),
        None => String::new(),
    };
    Some(format!("{table}{leaf}"))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Study, SpecError> {
        Study::parse(text, Path::new("s.toml"), Path::new("."))
    }

    /// `lag` takes its law from `aero.file` (relative to the study file, an input of the
    /// study); every other kind refuses a `file`, by key and line.
    #[test]
    fn lag_needs_its_file_and_other_kinds_refuse_one() {
        let base = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n[aero]\n";
        // a missing key is located at its table
        let e = parse(&format!("{base}model = \"lag\"\n")).unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.file", 6), "{e}");
        assert!(e.message.contains("identify DATASET --law lag"), "{e}");
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\nfile = \"l.json\"\n"
        ))
        .unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.file", 8), "{e}");
        assert!(e.message.contains("only `lag`"), "{e}");
        let s = parse(&format!("{base}model = \"lag\"\nfile = \"l.json\"\n")).unwrap();
        assert!(s
            .inputs()
            .iter()
            .any(|(k, p)| *k == "aero.file" && p.ends_with("l.json")));
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[flutter]\nu_min = 1.0\nu_max = 2.0\n\
             [[flutter.run]]\nlabel = \"l\"\nmethod = \"pk\"\nmodel = \"lag\"\n"
        ))
        .unwrap_err();
        assert_eq!(e.key, "flutter.run[0].model", "{e}");
    }

    #[test]
    fn quickstart_parses() {
        let s = Study::quickstart().unwrap();
        assert_eq!(s.spec.name, "quickstart");
        assert!(s.figure_kinds().contains(&"bifurcation".to_string()));
    }

    #[test]
    fn unknown_key_names_key_and_line() {
        let e = parse("name = \"x\"\n\n[flutter]\nu_min = 1.0\nu_maxx = 2.0\n").unwrap_err();
        assert_eq!(e.line, 5, "{e}");
        assert_eq!(e.key, "u_maxx", "{e}");
    }

    #[test]
    fn range_error_names_nested_key_and_line() {
        let text = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n\
                    [aero]\nmodel = \"theodorsen\"\n[flutter]\nu_min = 1.0\nu_max = 3.0\n\
                    [[flutter.run]]\nlabel = \"a\"\nmethod = \"pk\"\n[[flutter.run]]\n\
                    label = \"b\"\nmethod = \"q\"\n";
        let e = parse(text).unwrap_err();
        assert_eq!(e.key, "flutter.run[1].method", "{e}");
        assert_eq!(e.line, 16, "{e}");
    }

    /// Model names are an enum: a misspelt one is refused at parsing, by key and line, with
    /// the names that exist; `truth` is a flutter-run model only.
    #[test]
    fn unknown_or_misplaced_model_names_the_key() {
        let base = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n[aero]\n";
        let e = parse(&format!("{base}model = \"theodorsn\"\n")).unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.model", 7), "{e}");
        assert!(e.message.contains("theodorsen"), "{e}");
        // [aero] is a model file: `truth` is no kind of it (a flutter-run model only)
        let e = parse(&format!("{base}model = \"truth\"\n")).unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.model", 7), "{e}");
        assert!(e.message.contains("unknown variant `truth`"), "{e}");
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[flutter]\nu_min = 0.1\nu_max = 3.0\n[[flutter.run]]\nlabel = \"t\"\nmodel = \"truth\"\nmethod = \"pk\"\n"
        ))
        .unwrap_err();
        assert_eq!(e.key, "flutter.run[0].model", "{e}");
        assert!(e.message.contains("[data.virtual]"), "{e}");
        // the chord of a study's model is the structure's; a study cannot run dynamic stall
        let e = parse(&format!("{base}model = \"theodorsen\"\nchord = 0.3\n")).unwrap_err();
        assert_eq!(e.key, "aero.chord", "{e}");
        let e = parse(&format!("{base}model = \"dynamic_stall\"\n")).unwrap_err();
        assert_eq!(e.key, "aero.model", "{e}");
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[[aero.nonlinear]]\nchannel = \"lift\"\nterm = \"h\"\ncoefficient = 1.0\n"
        ))
        .unwrap_err();
        assert_eq!(e.key, "aero.nonlinear[0].term", "{e}");
        assert!(e.message.contains("total degree must be ≥ 2"), "{e}");
        // a nonlinear term's channel is typed: a bad name is refused at parse, by key
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[[aero.nonlinear]]\nchannel = \"pitch\"\n\
             term = \"alpha^3\"\ncoefficient = 1.0\n"
        ))
        .unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.line),
            ("aero.nonlinear[0].channel", 9),
            "{e}"
        );
        assert!(e.message.contains("expected \"lift\" or \"moment\""), "{e}");
    }

    /// Option names are enums: a misspelt one is refused at parsing with its key and line.
    #[test]
    fn option_names_are_refused_by_key_and_line() {
        let base = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n[aero]\nmodel = \"theodorsen\"\n[flutter]\nu_min = 0.1\nu_max = 3.0\n";
        for (line, key) in [
            ("axes = \"reducd\"", "flutter.axes"),
            ("damping = \"h\"", "flutter.damping"),
        ] {
            let e = parse(&format!("{base}{line}\n")).unwrap_err();
            assert_eq!((e.key.as_str(), e.line), (key, 11), "{e}");
            assert!(e.message.contains("unknown variant"), "{e}");
        }
        let ok = parse(&format!("{base}axes = \"reduced\"\ndamping = \"g\"\n")).unwrap();
        let f = ok.spec.flutter.unwrap();
        assert_eq!((f.axes, f.damping), (Axes::Reduced, DampingAxis::G));
    }

    #[test]
    fn ensemble_size_and_level_are_checked_with_their_key() {
        for (v, key) in [
            ("ensemble = 1", "identify.ensemble"),
            ("ensemble = 100000", "identify.ensemble"),
            (
                "ensemble = 5\nensemble_level = 1.0",
                "identify.ensemble_level",
            ),
            (
                "ensemble = 5\nensemble_level = nan",
                "identify.ensemble_level",
            ),
        ] {
            let e = parse(&format!("name = \"x\"\n[identify]\n{v}\n")).unwrap_err();
            assert_eq!(e.key, key, "{v}: {e}");
        }
        let s = parse("name = \"x\"\n[identify]\nensemble = 8\n").unwrap();
        let id = s.spec.identify.unwrap();
        assert_eq!((id.ensemble, id.ensemble_level), (Some(8), 0.9));
    }

    #[test]
    fn data_needs_exactly_one_source_and_virtual_is_checked() {
        let e = parse("name = \"x\"\n[data]\n").unwrap_err();
        assert_eq!(e.key, "data");
        // neither a model file nor an inline model
        let e = parse("name = \"x\"\n[data.virtual]\nstill_air = true\n").unwrap_err();
        assert_eq!(e.key, "data.virtual");
        assert_eq!(e.line, 2, "{e}");
        let e =
            parse("name = \"x\"\n[data.virtual]\nmodel = \"m.toml\"\ncampaign = \"config=Q\"\n")
                .unwrap_err();
        assert_eq!(e.key, "data.virtual.campaign", "{e}");
        assert_eq!(e.line, 4, "{e}");
        let e = parse(
            "name = \"x\"\n[data.virtual]\n[data.virtual.aero]\nmodel = \"theodorsen\"\n\
             [[data.virtual.aero.nonlinear]]\nchannel = \"moment\"\nterm = \"alpha\"\ncoefficient = 1.0\n",
        )
        .unwrap_err();
        assert_eq!(e.key, "data.virtual.aero.nonlinear[0].term", "{e}");
        assert!(parse(
            "name = \"x\"\n[data.virtual]\nmodel = \"m.toml\"\ncampaign = \"config=D\"\n"
        )
        .is_ok());
    }
}
