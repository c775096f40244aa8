//! A structure/model pair loaded from files, and the result documents of `aeroform flutter`
//! (`flutter.json`), `aeroform lco` (`lco.json`) and `aeroform branch` (`branch.json`,
//! `branch.csv`).
//!
//! Built here, not in the binary, so that the command line, the Python binding and the
//! sweeps write the same content from the same code.

use std::path::Path;

use std::fmt::Write as _;

use schemars::JsonSchema;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::branch::{
    Branch, BranchMethod, BranchOptions, BranchProgress, BranchSet, EventKind, HopfPoint,
    MeasuredDistance,
};
use crate::ensemble::{flutter_ensemble, member_laws, FlutterEnsemble, LcoEnsemble};
use crate::identified::{IdentifiedOptions, IdentifiedTables};

use crate::files::{LoadedModel, StructureFile};
use crate::flutter::{FlutterAnalysis, FlutterMethod, FlutterOptions, FlutterPoint};
use crate::lco::{Hysteresis, KIteration, LcoOptions, LcoResult, SweepPlan, SweepProgress};
use crate::section::Section;
use crate::structure::Structure;
use crate::trajectory::Trajectory;
use crate::Result;

/// Relative tolerance on the critical speed used by `aeroform flutter`.
pub const FLUTTER_TOL_REL: f64 = 1e-8;

/// The scan of `aeroform flutter` over `speeds` (≥ 2 speeds): from the lowest to the
/// highest with as many points, critical speeds to [`FLUTTER_TOL_REL`].
///
/// # Errors
/// [`crate::Error::InvalidParameter`] for fewer than 2 speeds.
pub fn flutter_options(speeds: &[f64]) -> Result<FlutterOptions> {
    if speeds.len() < 2 {
        return Err(crate::Error::param(
            "speeds",
            speeds.len() as f64,
            "a flutter scan needs at least 2 speeds",
        ));
    }
    Ok(FlutterOptions {
        u_min: speeds.iter().copied().fold(f64::INFINITY, f64::min),
        u_max: speeds.iter().copied().fold(0.0, f64::max),
        n_speeds: speeds.len(),
        tol_rel: FLUTTER_TOL_REL,
    })
}

/// Structure file, structure, model and section of a structure/model pair.
#[derive(Debug, Clone)]
pub struct LoadedPair {
    /// The structure file as read.
    pub file: StructureFile,
    /// The structure it describes.
    pub structure: Structure,
    /// The aerodynamic model.
    pub model: LoadedModel,
    /// Structure + model + air density.
    pub section: Section,
}

impl LoadedPair {
    /// Reads a structure file and a model file (model TOML or `identification.json`) and
    /// builds the section; `chord` overrides the structure file's `chord` for an
    /// identification.
    ///
    /// # Errors
    /// The errors of [`StructureFile::read`], [`StructureFile::structure`],
    /// [`LoadedModel::load`] and [`Section::new`] (each names the file and the field).
    pub fn load(structure: &Path, model: &Path, chord: Option<f64>) -> Result<Self> {
        if let Some(c) = chord {
            identify::limits::positive_at_most(c, identify::limits::MAX_CHORD, "m")
                .map_err(|m| crate::Error::param("chord", c, m))?;
        }
        let file = StructureFile::read(structure)?;
        let model = LoadedModel::load(model, chord.or(file.chord))?;
        Self::from_parts(file, model)
    }

    /// Builds the pair from a structure file already read and a model already loaded.
    ///
    /// # Errors
    /// The errors of [`StructureFile::structure`] and [`Section::new`].
    pub fn from_parts(file: StructureFile, model: LoadedModel) -> Result<Self> {
        let structure = file.structure()?;
        let section = Section::new(structure.clone(), model.model.clone(), file.air_density)?;
        Ok(LoadedPair {
            file,
            structure,
            model,
            section,
        })
    }

    /// Warnings of an identified model (terms dropped, extrapolated tables…).
    pub fn warnings(&self) -> &[String] {
        self.model
            .identified
            .as_ref()
            .map(|t| t.warnings.as_slice())
            .unwrap_or(&[])
    }

    /// The flutter analysis of `aeroform flutter` over `speeds` (≥ 2 speeds; the scan runs
    /// from the lowest to the highest with as many points).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for fewer than 2 speeds; the errors of
    /// [`Section::flutter`].
    pub fn flutter(&self, method: FlutterMethod, speeds: &[f64]) -> Result<FlutterAnalysis> {
        self.section.flutter(method, &flutter_options(speeds)?)
    }

    /// One LCO run at `u` [m/s] from a pitch perturbation `alpha0` \[rad\], as
    /// `aeroform lco --speed` (default options; the K iteration of a K-dependent model).
    ///
    /// # Errors
    /// The errors of [`Section::lco_run_k`].
    pub fn lco_run(&self, u: f64, alpha0: f64) -> Result<LcoResult> {
        self.section.lco_run_k(
            u,
            &self.section.perturbation(alpha0),
            &LcoOptions::default(),
            &KIteration::default(),
        )
    }

    /// Upward and downward LCO sweeps over `speeds` from pitch perturbations `alpha0_up`
    /// and `alpha0_down` \[rad\], as `aeroform lco --sweep` ([`Section::lco_sweeps`]).
    ///
    /// # Errors
    /// The errors of [`Section::lco_sweeps`].
    pub fn lco_sweep(
        &self,
        speeds: &[f64],
        alpha0_up: f64,
        alpha0_down: f64,
        observer: &(dyn Fn(SweepProgress) + Sync),
    ) -> Result<Hysteresis> {
        let plan = SweepPlan {
            perturbation_up: self.section.perturbation(alpha0_up),
            perturbation_down: Some(self.section.perturbation(alpha0_down)),
            k_iteration: KIteration::default(),
        };
        self.section
            .lco_sweeps(speeds, &plan, &LcoOptions::default(), observer)
    }

    /// Flutter and divergence of the first `n` members (`None`: all) of the ensemble of
    /// the identification in the file `model` (written with `identify --ensemble`), on
    /// this pair's structure and air density with the scan of [`LoadedPair::flutter`]:
    /// the `ensemble` object of `flutter.json`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] / [`crate::Error::Identify`] when `model` is not a readable
    /// identification.json; the errors of [`crate::ensemble::member_laws`] (no ensemble
    /// section, `n` out of range) and [`crate::ensemble::flutter_ensemble`].
    pub fn flutter_ensemble(
        &self,
        model: &Path,
        method: FlutterMethod,
        speeds: &[f64],
        n: Option<usize>,
    ) -> Result<FlutterEnsemble> {
        let id = identify::pipeline::Identification::read(model).map_err(|source| {
            crate::Error::Identify {
                context: format!(
                    "{}: an ensemble needs an identification.json model",
                    model.display()
                ),
                source,
            }
        })?;
        let opts = IdentifiedOptions::new(self.section.aero.chord());
        let (laws, e) = member_laws(&id, &opts, n)?;
        flutter_ensemble(
            &self.structure,
            &laws,
            e,
            self.file.air_density,
            method,
            &flutter_options(speeds)?,
        )
    }

    /// LCO branches by continuation from every Hopf point in `u_min … u_max` \[m/s\], as
    /// `aeroform branch` ([`Section::lco_branches`]).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] when the range is not 0 < `u_min` < `u_max` ≤
    /// `identify::limits::MAX_SPEED`; the errors of [`Section::lco_branches`] (no Hopf point in range,
    /// non-smooth nonlinearity, bad options).
    pub fn branches(
        &self,
        u_min: f64,
        u_max: f64,
        opts: &BranchOptions,
        observer: &dyn Fn(BranchProgress),
    ) -> Result<BranchSet> {
        use identify::limits::{positive_at_most, MAX_SPEED};
        positive_at_most(u_min, MAX_SPEED, "m/s")
            .map_err(|m| crate::Error::param("u_min", u_min, m))?;
        positive_at_most(u_max, MAX_SPEED, "m/s")
            .map_err(|m| crate::Error::param("u_max", u_max, m))?;
        if u_max <= u_min {
            return Err(crate::Error::param("u_max", u_max, "must be > u_min"));
        }
        self.section.lco_branches(u_min, u_max, opts, observer)
    }
}

/// The method description recorded in `branch.json` under `settings.method` (the
/// machine-readable choice is `settings.options.method`).
pub fn branch_method_text(method: BranchMethod) -> &'static str {
    match method {
        BranchMethod::Shooting => {
            "single shooting (fixed-step RK4) + pseudo-arclength, Floquet multipliers from the monodromy matrix"
        }
        BranchMethod::HarmonicBalance => {
            "harmonic balance (AFT) + pseudo-arclength; for linear aerodynamics independent of K condensed onto heave and pitch (lag states eliminated per harmonic) with Floquet multipliers by the exponential trapezoidal rule, otherwise every state with multipliers from RK4 on the variational equation"
        }
    }
}

/// Format tag of the `flutter.json` of `aeroform flutter` ([`FlutterDoc`]).
pub const FLUTTER_FORMAT: &str = "aeroform-flutter/1";
/// Format tag of the `lco.json` of `aeroform lco` ([`LcoDoc`]).
pub const LCO_FORMAT: &str = "aeroform-lco/1";
/// Format tag of `branch.json` ([`BranchDoc`]).
pub const BRANCH_FORMAT: &str = "aeroform-branch/1";

/// Parses `text` (from `source`, a file name) as a document of type `T` whose `format`
/// field must be `expected`; the tag is checked first, so that a document of another kind
/// is reported as such rather than as a missing field.
fn parse_document<T: DeserializeOwned>(text: &str, source: &str, expected: &str) -> Result<T> {
    #[derive(Deserialize)]
    struct Tag {
        format: String,
    }
    let doc_error = |e: serde_json::Error| crate::Error::Document {
        path: source.to_string(),
        message: e.to_string(),
    };
    let tag: Tag = serde_json::from_str(text).map_err(doc_error)?;
    if tag.format != expected {
        return Err(crate::Error::WrongFormat {
            path: source.to_string(),
            found: tag.format,
            expected: expected.to_string(),
        });
    }
    serde_json::from_str(text).map_err(doc_error)
}

/// Reads the file `path` as a document of type `T` tagged `expected`.
fn read_document<T: DeserializeOwned>(path: &Path, expected: &str) -> Result<T> {
    let text = identify::io::read_text(path).map_err(|e| {
        let (path, message) = (path.display().to_string(), e.to_string());
        // refused by the reader (missing, not a regular file, too large, not UTF-8): an
        // input error, as a document that does not parse
        if identify::io::is_input_error(&e) {
            crate::Error::Document { path, message }
        } else {
            crate::Error::Io { path, message }
        }
    })?;
    parse_document(&text, &path.display().to_string(), expected)
}

/// The JSON value of a document (objects with their keys sorted, as written to disk).
fn document_value<T: Serialize>(doc: &T) -> Value {
    // A document holds only strings, numbers (non-finite ones become `null`), booleans,
    // sequences and structs: serialising it into a `Value` cannot fail.
    serde_json::to_value(doc).expect("a result document serialises to JSON")
}

/// `from_json`, `read` and `to_value` of a document type with a format tag.
macro_rules! document_io {
    ($ty:ident, $format:ident, $file:literal) => {
        impl $ty {
            #[doc = concat!("Parses the text of a `", $file, "` document; `source` names it in errors.")]
            ///
            /// # Errors
            /// [`crate::Error::WrongFormat`] when the `format` tag is not
            #[doc = concat!("[`", stringify!($format), "`];")]
            /// [`crate::Error::Document`] (naming `source`, line and column) when the text is
            /// not JSON of this shape. Fields the type does not know are ignored.
            pub fn from_json(text: &str, source: &str) -> Result<Self> {
                parse_document(text, source, $format)
            }

            #[doc = concat!("Reads a `", $file, "` document from the file `path`.")]
            ///
            /// # Errors
            /// [`crate::Error::Io`] naming the file when it cannot be read; the errors of
            #[doc = concat!("[`", stringify!($ty), "::from_json`]")]
            /// (naming the file).
            pub fn read(path: &Path) -> Result<Self> {
                read_document(path, $format)
            }

            /// The document as a JSON value, as it is written to disk (pretty-printed, keys
            /// sorted) and printed by `--json`.
            pub fn to_value(&self) -> Value {
                document_value(self)
            }
        }
    };
}

/// The `critical` object of `flutter.json`: the flutter point with its derived
/// frequencies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CriticalPoint {
    /// Flutter speed U_F \[m/s\].
    pub speed: f64,
    /// Flutter angular frequency ω_F \[rad/s\].
    pub omega: f64,
    /// Flutter frequency f_F = ω_F/(2π) \[Hz\].
    pub frequency_hz: f64,
    /// Reduced frequency K = B·ω_F/U_F on the full chord B (Theodorsen's k = K/2).
    pub reduced_frequency: f64,
    /// Index of the mode that goes unstable (in `analysis.branches`).
    pub mode: usize,
    /// Reduced speed U_F/(b·ω_α), b = B/2 the semi-chord.
    pub u_reduced: f64,
    /// Frequency ratio ω_F/ω_α.
    pub omega_ratio: f64,
}

impl CriticalPoint {
    /// The critical point of flutter point `f` on a section of full chord `chord` \[m\].
    pub fn new(f: &FlutterPoint, chord: f64) -> Self {
        CriticalPoint {
            speed: f.u,
            omega: f.omega,
            frequency_hz: f.omega / (2.0 * std::f64::consts::PI),
            reduced_frequency: chord * f.omega / f.u,
            mode: f.mode,
            u_reduced: f.u_reduced,
            omega_ratio: f.omega_ratio,
        }
    }
}

/// Published values a flutter analysis is compared with (a study's
/// `[[flutter.run]] reference`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FlutterReference {
    /// Published reduced flutter speed U_F/(bω_α), b the semi-chord.
    pub u_reduced: Option<f64>,
    /// Published flutter frequency ratio ω_F/ω_α.
    pub omega_ratio: Option<f64>,
    /// Published reduced divergence speed U_D/(bω_α).
    pub divergence: Option<f64>,
}

/// The `flutter.json` document (format `aeroform-flutter/1`) of `aeroform flutter`, of the
/// Python binding's `flutter` and of each run of a study's flutter stage (a study's
/// `flutter.json` is an array of them, one per `[[flutter.run]]`): the flutter analysis of
/// one structure/model pair. Scanlan's convention: h positive down, α positive nose-up; SI
/// units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FlutterDoc {
    /// Format tag, `aeroform-flutter/1`.
    pub format: String,
    /// The run's label in tables and figures (a study's `[[flutter.run]] label`); absent
    /// for `aeroform flutter`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// The structure file as named on the command line (`<study file> [structure]` in a
    /// study).
    pub structure: String,
    /// The model file (model TOML or `identification.json`) as named on the command line;
    /// in a study the run's model (`theodorsen`, `identified`, `truth`, …).
    pub model: String,
    /// Name of the aerodynamic model (`theodorsen`, `quasi_steady`, `identified`, …).
    pub model_name: String,
    /// Air density ρ \[kg/m³\].
    pub air_density: f64,
    /// Full chord B \[m\].
    pub chord: f64,
    /// Uncoupled still-air pitch frequency ω_α \[rad/s\]: reduced speed = U/(bω_α) with
    /// b = B/2.
    pub omega_alpha: f64,
    /// The flutter point with its frequencies; `null` when no mode crosses zero damping in
    /// the scanned range.
    pub critical: Option<CriticalPoint>,
    /// Static divergence speed U_D \[m/s\]; `null` when none in the scanned range.
    pub divergence_speed: Option<f64>,
    /// The whole analysis: method, one branch per structural mode (V–g, V–f), flutter
    /// point, divergence speed, failed points.
    pub analysis: FlutterAnalysis,
    /// What the identified law was built from; `null` unless the model is an
    /// `identification.json`.
    pub identified: Option<IdentifiedTables>,
    /// Published values the run is compared with (a study's `[[flutter.run]]
    /// reference`); absent without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<FlutterReference>,
    /// Flutter and divergence over the members of the identification's bootstrap ensemble
    /// (`--ensemble N`, a study's `[identify] ensemble`); absent without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<FlutterEnsemble>,
}

impl FlutterDoc {
    /// The document of the analysis `fa` of `section`; `structure` and `model` name the
    /// inputs, `identified` what an identified law was built from. Without label,
    /// reference or ensemble (set the fields to add them).
    pub fn new(
        structure: &str,
        model: &str,
        section: &Section,
        fa: &FlutterAnalysis,
        identified: Option<IdentifiedTables>,
    ) -> Self {
        let b = section.aero.chord();
        FlutterDoc {
            format: FLUTTER_FORMAT.to_string(),
            label: None,
            structure: structure.to_string(),
            model: model.to_string(),
            model_name: fa.model.clone(),
            air_density: section.rho,
            chord: b,
            omega_alpha: section.structure.omega_alpha(),
            critical: fa.flutter.as_ref().map(|f| CriticalPoint::new(f, b)),
            divergence_speed: fa.divergence_speed,
            analysis: fa.clone(),
            identified,
            reference: None,
            ensemble: None,
        }
    }
}

document_io!(FlutterDoc, FLUTTER_FORMAT, "flutter.json");

/// The `lco.json` document (format `aeroform-lco/1`) of `aeroform lco`, of the Python
/// binding's `lco` and of a study's LCO stage: either one run (`run`) or an upward and a
/// downward sweep (`sweep`, `hysteresis_speeds`), with a study's phase portraits and truth
/// sweeps when it has them. Scanlan's convention; SI units (amplitudes in rad and m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LcoDoc {
    /// Format tag, `aeroform-lco/1`.
    pub format: String,
    /// The structure file as named on the command line (`<study file> [structure]` in a
    /// study).
    pub structure: String,
    /// The model file as named on the command line; in a study its `[aero]` model
    /// (`theodorsen`, `identified`, …).
    pub model: String,
    /// Name of the aerodynamic model with its nonlinear terms (`theodorsen+nonlinear`, …).
    pub model_name: String,
    /// Full chord B \[m\].
    pub chord: f64,
    /// Uncoupled still-air pitch frequency ω_α \[rad/s\] (reduced speed U/(bω_α), b = B/2).
    pub omega_alpha: f64,
    /// The run at one speed (`--speed`); absent for a sweep.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run: Option<LcoResult>,
    /// The upward and downward sweeps (`--sweep`, a study's `[lco]`; the downward one empty
    /// without `up_down`); absent for one run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<Hysteresis>,
    /// Speeds \[m/s\] at which the two sweeps disagree (one settles on an LCO, the other
    /// not): the hysteresis band on the sweep's grid; present (possibly empty) with
    /// `sweep`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hysteresis_speeds: Option<Vec<f64>>,
    /// Linear flutter speed of the same model \[m/s\] (a study with a flutter run of it);
    /// absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_speed: Option<f64>,
    /// Trajectories of a study's phase-portrait figure; absent when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub phase: Vec<Trajectory>,
    /// The same sweeps of the truth model of a study's `[data.virtual]` (`compare_truth`);
    /// absent without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<TruthSweeps>,
    /// LCO amplitudes over the members of the identification's bootstrap ensemble
    /// (`--ensemble N`, a study's `[identify] ensemble`), one point per speed; absent
    /// without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<LcoEnsemble>,
}

/// `truth` of `lco.json`: the sweeps of a study's truth model beside those of its model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TruthSweeps {
    /// Linear flutter speed of the truth model \[m/s\]; `null` when none was computed.
    pub flutter_speed: Option<f64>,
    /// Upward and downward sweeps of the truth model, increasing U.
    pub sweep: Hysteresis,
}

impl LcoDoc {
    /// A document of `section` with neither run nor sweep (set them, or use
    /// [`lco_run_document`] / [`lco_sweep_document`]); `structure` and `model` name the
    /// inputs.
    pub fn new(structure: &str, model: &str, section: &Section) -> Self {
        LcoDoc {
            format: LCO_FORMAT.to_string(),
            structure: structure.to_string(),
            model: model.to_string(),
            model_name: section.aero.name(),
            chord: section.aero.chord(),
            omega_alpha: section.structure.omega_alpha(),
            run: None,
            sweep: None,
            hysteresis_speeds: None,
            flutter_speed: None,
            phase: Vec::new(),
            truth: None,
            ensemble: None,
        }
    }

    /// Sets the sweeps and their hysteresis band.
    pub fn with_sweep(mut self, sweep: Hysteresis) -> Self {
        self.hysteresis_speeds = Some(sweep.band());
        self.sweep = Some(sweep);
        self
    }
}

document_io!(LcoDoc, LCO_FORMAT, "lco.json");

/// `settings` of `branch.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BranchSettings {
    /// The numerical method ([`branch_method_text`]).
    pub method: String,
    /// The continuation options.
    pub options: BranchOptions,
    /// Speed range searched for Hopf points and continued over, `[u_min, u_max]` \[m/s\].
    pub u_range_m_s: [f64; 2],
}

/// A fold (saddle-node of limit cycles) of `branch.json`'s `folds`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BranchFold {
    /// Index of the branch (in `branches`) it lies on.
    pub branch: usize,
    /// Wind speed U \[m/s\].
    #[serde(rename = "U_m_s")]
    pub u_m_s: f64,
    /// Pitch amplitude (half peak-to-peak) \[deg\].
    pub amplitude_alpha_deg: f64,
    /// Heave amplitude (half peak-to-peak) \[m\], heave positive down.
    pub amplitude_h_m: f64,
}

/// The `branch.json` document of `aeroform branch`, of a study's `[branch]` stage and of
/// the Python binding's `branch` (format `aeroform-branch/1`): LCO branches continued from
/// every Hopf point in the speed range. Scanlan's convention; SI units unless a name says
/// otherwise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct BranchDoc {
    /// Format tag, `aeroform-branch/1`.
    pub format: String,
    /// The structure file as named on the command line (`study.toml [structure]` in a
    /// study).
    pub structure: String,
    /// The model file as named on the command line (the study's `aero.model` in a study).
    pub model: String,
    /// Method, options and speed range.
    pub settings: BranchSettings,
    /// Hopf points in the range, increasing U.
    pub hopf_points: Vec<HopfPoint>,
    /// Every fold event of every branch, in branch order.
    pub folds: Vec<BranchFold>,
    /// One branch per Hopf point, with its points, events and stop reason.
    pub branches: Vec<Branch>,
    /// Distances of measured amplitudes (`--measured`) to the predicted branches; empty
    /// without.
    pub measured: Vec<MeasuredDistance>,
    /// The orbit at one speed continued in a parameter of the section (`--parameter`,
    /// [`Section::continue_in`](crate::section::Section::continue_in)); absent without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parameter: Option<crate::branch::LensBranch>,
}

document_io!(BranchDoc, BRANCH_FORMAT, "branch.json");

/// The `branch.json` document (`aeroform-branch/1`) of the branches `set`: settings, Hopf
/// points, folds (branch, U \[m/s\], pitch amplitude \[deg\], heave amplitude \[m\]), every
/// branch with its points and events, and the distances of measured points (`measured`,
/// empty without); `structure` and `model` name the inputs.
pub fn branch_document(
    structure: &str,
    model: &str,
    set: &BranchSet,
    measured: &[MeasuredDistance],
) -> BranchDoc {
    let folds = set
        .branches
        .iter()
        .enumerate()
        .flat_map(|(i, b)| {
            b.events
                .iter()
                .filter(|e| e.kind == EventKind::Fold)
                .map(move |e| BranchFold {
                    branch: i,
                    u_m_s: e.u,
                    amplitude_alpha_deg: e.amplitude_alpha.to_degrees(),
                    amplitude_h_m: e.amplitude_h,
                })
        })
        .collect();
    BranchDoc {
        format: BRANCH_FORMAT.to_string(),
        structure: structure.to_string(),
        model: model.to_string(),
        settings: BranchSettings {
            method: branch_method_text(set.options.method).to_string(),
            options: set.options,
            u_range_m_s: set.u_range,
        },
        hopf_points: set.hopf_points.clone(),
        folds,
        branches: set.branches.clone(),
        measured: measured.to_vec(),
        parameter: None,
    }
}

/// The `branch_parameter.csv` table of a branch continued in a parameter: one row per
/// point, from the lower end, with columns `value` (the parameter, its own unit), `U_m_s`,
/// `stable`, `amplitude_alpha_deg`, `amplitude_h_m` (half peak-to-peak), `omega_rad_s` and
/// `max_floquet`.
pub fn lens_csv(b: &crate::branch::LensBranch) -> String {
    let mut s = String::from(
        "value,U_m_s,stable,amplitude_alpha_deg,amplitude_h_m,omega_rad_s,max_floquet\n",
    );
    for p in &b.points {
        let o = &p.orbit;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{}",
            p.value,
            o.u,
            o.stable,
            o.amplitude_alpha.to_degrees(),
            o.amplitude_h,
            o.omega,
            o.max_floquet
        );
    }
    s
}

/// The `branch.csv` table: one row per branch point with columns `U_m_s`, `stable`,
/// `amplitude_alpha_deg` and `amplitude_h_m` (half peak-to-peak), `omega_rad_s`,
/// `max_floquet` (largest Floquet multiplier modulus, the trivial one excluded),
/// `branch` (index), `amplitude1_alpha_deg` and `amplitude1_h_m` (first harmonic).
pub fn branch_csv(set: &BranchSet) -> String {
    let mut s = String::from(
        "U_m_s,stable,amplitude_alpha_deg,amplitude_h_m,omega_rad_s,max_floquet,branch,amplitude1_alpha_deg,amplitude1_h_m\n",
    );
    for (i, b) in set.branches.iter().enumerate() {
        for p in &b.points {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{}",
                p.u,
                p.stable,
                p.amplitude_alpha.to_degrees(),
                p.amplitude_h,
                p.omega,
                p.max_floquet,
                i,
                p.amplitude1_alpha.to_degrees(),
                p.amplitude1_h
            );
        }
    }
    s
}

/// The `critical` object of `flutter.json` as a JSON value ([`CriticalPoint`]); `null`
/// when the scan found no flutter. `chord` is the full chord B \[m\].
pub fn flutter_point_json(fa: &FlutterAnalysis, chord: f64) -> Value {
    match &fa.flutter {
        Some(f) => document_value(&CriticalPoint::new(f, chord)),
        None => Value::Null,
    }
}

/// The `flutter.json` document (`aeroform-flutter/1`) of the analysis `fa` of `pair`;
/// `structure` and `model` name the inputs ([`FlutterDoc::new`]).
pub fn flutter_document(
    structure: &str,
    model: &str,
    pair: &LoadedPair,
    fa: &FlutterAnalysis,
) -> FlutterDoc {
    FlutterDoc::new(
        structure,
        model,
        &pair.section,
        fa,
        pair.model.identified.clone(),
    )
}

/// The `lco.json` document (`aeroform-lco/1`) of one run of `section`; `structure` and
/// `model` name the inputs. Without an ensemble (set [`LcoDoc::ensemble`] to add one).
pub fn lco_run_document(
    structure: &str,
    model: &str,
    section: &Section,
    run: &LcoResult,
) -> LcoDoc {
    LcoDoc {
        run: Some(run.clone()),
        ..LcoDoc::new(structure, model, section)
    }
}

/// The `lco.json` document (`aeroform-lco/1`) of an upward/downward sweep of `section`;
/// `structure` and `model` name the inputs. Without an ensemble (set [`LcoDoc::ensemble`]
/// to add one).
pub fn lco_sweep_document(
    structure: &str,
    model: &str,
    section: &Section,
    sweep: &Hysteresis,
) -> LcoDoc {
    LcoDoc::new(structure, model, section).with_sweep(sweep.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flutter_scan_of_one_speed_is_refused_with_the_field_named() {
        let dir = tempfile::tempdir().unwrap();
        let s = dir.path().join("s.toml");
        let m = dir.path().join("m.toml");
        std::fs::write(
            &s,
            "mass = 1.0\ninertia = 0.01\nfreq_heave = 2.0\nfreq_pitch = 3.0\n",
        )
        .unwrap();
        std::fs::write(&m, "kind = \"theodorsen\"\nchord = 0.25\n").unwrap();
        let pair = LoadedPair::load(&s, &m, None).unwrap();
        let e = pair.flutter(FlutterMethod::Pk, &[5.0]).unwrap_err();
        assert!(e.to_string().contains("speeds"), "{e}");
        let fa = pair.flutter(FlutterMethod::Pk, &[1.0, 30.0]).unwrap();
        let doc = flutter_document("s.toml", "m.toml", &pair, &fa).to_value();
        assert_eq!(doc["format"], "aeroform-flutter/1");
        assert_eq!(doc["chord"], 0.25);
    }

    #[test]
    fn a_document_round_trips_and_another_format_is_refused_with_the_file_named() {
        let dir = tempfile::tempdir().unwrap();
        let s = dir.path().join("s.toml");
        let m = dir.path().join("m.toml");
        std::fs::write(
            &s,
            "mass = 1.0\ninertia = 0.01\nfreq_heave = 2.0\nfreq_pitch = 3.0\n",
        )
        .unwrap();
        std::fs::write(&m, "kind = \"theodorsen\"\nchord = 0.25\n").unwrap();
        let pair = LoadedPair::load(&s, &m, None).unwrap();
        let fa = pair.flutter(FlutterMethod::Pk, &[1.0, 30.0]).unwrap();
        let doc = flutter_document("s.toml", "m.toml", &pair, &fa);
        let path = dir.path().join("flutter.json");
        std::fs::write(&path, format!("{:#}\n", doc.to_value())).unwrap();
        assert_eq!(FlutterDoc::read(&path).unwrap(), doc);
        let e = LcoDoc::read(&path).unwrap_err();
        assert!(
            matches!(&e, crate::Error::WrongFormat { found, .. } if found == FLUTTER_FORMAT),
            "{e}"
        );
        assert!(e.to_string().contains("flutter.json"), "{e}");
        let e =
            FlutterDoc::from_json("{\"format\": \"aeroform-flutter/1\"}", "x.json").unwrap_err();
        assert!(
            matches!(&e, crate::Error::Document { path, .. } if path == "x.json"),
            "{e}"
        );
    }
}
