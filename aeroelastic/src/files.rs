//! Structure and aerodynamic-model files (TOML), and `identification.json` as a model.
//!
//! **Structure file** (`*.structure.toml`, SI per unit span, same key names as a data-set
//! manifest's `[structure]`):
//!
//! ```toml
//! air_density = 1.225          # [kg/m^3], optional (1.225)
//! chord = 0.25                 # \[m\], optional: the chord for an identification.json model
//! mass = 1.0933                # [kg/m]
//! inertia = 0.005803           # [kg m^2/m] about the elastic axis
//! static_unbalance = 0.010933  # [kg m/m], + when the mass centre is aft of the axis
//! freq_heave = 2.0             # \[Hz\] uncoupled still-air natural frequencies
//! freq_pitch = 3.5
//! damping_heave = 0.005        # ratio of critical, optional (0)
//! damping_pitch = 0.005
//! # optional: heave_stiffness_terms / pitch_stiffness_terms = [{ power = 3, coefficient = 10.0 }],
//! # heave_damping_terms / pitch_damping_terms = [{ power = 2, coefficient = 0.5 }] (c q^p q̇),
//! # pitch_freeplay = 0.01 (rad), [friction] heave_force = …, pitch_moment = …
//! ```
//!
//! k_h = m (2πf_h)², k_α = I (2πf_α)², c_h = 2ζ_h m 2πf_h, c_α = 2ζ_α I 2πf_α.
//!
//! **Model file** (`*.model.toml`):
//!
//! ```toml
//! kind = "theodorsen"   # | "quasi_steady" | "steady" | "flat_plate_table" | "derivative_table" | "identified" | "dynamic_stall" | "lag"
//! chord = 0.25          # \[m\] (all kinds; for "identified" optional when given elsewhere; for "lag" default the law's)
//! elastic_axis = -0.3   # a, semi-chords aft of mid-chord (theodorsen, dynamic_stall, quasi_steady, steady; default 0;
//!                       # lag: places the thin-aerofoil apparent mass, none without it)
//! noncirculatory = true # quasi_steady (default true), steady (default false)
//! rfa_lags = 3          # flat_plate_table, derivative_table, identified (default 3)
//! k = [0.1, 0.2, …]     # flat_plate_table: the K grid (default: reference::flat_plate_k_grid)
//! # derivative_table: [[derivatives]] k = 0.5, h1 = …, h2, h3, h4, a1, a2, a3, a4
//! # identified: file = "identification.json" (relative to the model file),
//! #             groups = ["D"], missing = "error" | "skip" | "flat_plate" | "zero"
//! # lag: file = "plate.lag_law.json" (a `lag_law.json`, relative to the model file),
//! #      mean_angle = 0.2 (rad, optional: the trim angle the section is flown about)
//!
//! [[nonlinear]]         # any number; names as in DATA_FORMAT.md, total degree ≥ 2
//! term = "alpha_dot^3"
//! channel = "moment"    # "lift" | "moment"
//! coefficient = -100.0  # constant nondimensional coefficient, or an Eq. 19 table:
//! # k = [0.3, 0.6], values = [N*(0.3), N*(0.6)], k_power = 3
//! ```
//!
//! A path ending in `.json` (or a file starting with `{`) is read as a `lag_law.json`
//! ([`identify::lag::LagLawDocument`], format `aeroform-lag-law/…`: a [`LagAero`] on the
//! law's chord, no elastic axis hence no apparent mass, no trim) when its `format` field
//! says so, else as an `identification.json` ([`IdentifiedLaw`]). Unknown keys are errors naming the key and
//! the file; a key that the `kind` does not use is an error naming it too. A study's
//! `[aero]` table is the same [`ModelFile`], where `model` and `n_lag` may be written for
//! `kind` and `rfa_lags`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::aero::{
    AeroModel, Channel, Coefficient, DerivativeTable, DynamicStallAero, LagAero, NonlinearAero,
    NonlinearTerm, QuasiSteady, QuasiSteadyKind, TheodorsenAero,
};
use crate::error::positive;
use crate::identified::{IdentifiedLaw, IdentifiedOptions, IdentifiedTables, MissingDerivative};
use crate::structure::{Nonlinearities, Structure, StructureSpec};
use crate::theodorsen::Derivatives;
use crate::{Error, Result};
use identify::dataset::ModalStructure;

fn default_rho() -> f64 {
    1.225
}

/// A structure file (see the module docs): the file form of a
/// [`StructureSpec::Modal`] — air density and chord, then the keys of
/// [`ModalStructure`] and of [`Nonlinearities`] side by side in one flat table.
///
/// Unknown keys are rejected ([`StructureFile::parse`] names the key and the file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct StructureFile {
    /// Air density ρ \[kg/m³\], > 0 (default 1.225).
    #[serde(default = "default_rho")]
    pub air_density: f64,
    /// Chord B \[m\] (used when the model file does not give one), > 0.
    #[serde(default)]
    pub chord: Option<f64>,
    /// The linear structure (frequency form).
    #[serde(flatten)]
    pub linear: ModalStructure,
    /// The nonlinear terms.
    #[serde(flatten)]
    pub nonlinear: Nonlinearities,
    /// Keys that are none of the above: must be empty (serde's `deny_unknown_fields` does not
    /// combine with `flatten`, so [`StructureFile::parse`] checks it).
    #[serde(flatten, skip_serializing)]
    #[schemars(skip)]
    unknown: BTreeMap<String, toml::Value>,
}

/// The key of a `#[serde(flatten)]`-composed table that serde cannot name: the first key of
/// `table` (in key order) whose value alone does not deserialize into `T`, with serde's
/// message (e.g. `invalid type: string "a", expected f64`). Serde buffers flattened tables,
/// so a wrong-typed value there reaches the caller without its key or position; this names
/// it again. `None` when every value alone is fine (the error is then about the table as
/// a whole, e.g. a missing key, which serde names itself).
pub fn flattened_bad_key<T: serde::de::DeserializeOwned>(
    table: &toml::Table,
) -> Option<(String, String)> {
    table.iter().find_map(|(k, v)| {
        let mut one = toml::Table::new();
        one.insert(k.clone(), v.clone());
        match toml::Value::Table(one).try_into::<T>() {
            Err(e) if !e.message().starts_with("missing field") => {
                Some((k.clone(), e.message().trim().to_string()))
            }
            _ => None,
        }
    })
}

/// 1-based line of the top-level `key` in a TOML text (0 when not found).
fn key_line(text: &str, key: &str) -> usize {
    identify::toml_lines::TomlLines::new(text).line_of(key)
}

/// A model or structure file's text, read by `identify::io::read_text` (regular files only,
/// at most the limits table's `MAX_TEXT_FILE_BYTES`, UTF-8 errors by line and byte). A
/// refusal of the reader is an input error ([`Error::Toml`] naming the file).
fn read_text(path: &Path) -> Result<String> {
    identify::io::read_text(path).map_err(|e| read_error(path, e))
}

/// A reader's refusal of `path` as the crate's error: an input error ([`Error::Toml`]
/// naming the file) or an I/O failure.
fn read_error(path: &Path, e: std::io::Error) -> Error {
    match identify::io::is_input_error(&e) {
        true => Error::Toml {
            source_name: path.display().to_string(),
            message: e.to_string(),
        },
        false => Error::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        },
    }
}

/// Prefixes the field of an [`Error::InvalidParameter`] with the file name.
fn in_file(path: &str, e: Error) -> Error {
    e.map_field(|field| format!("{path}: {field}"))
}

impl StructureFile {
    /// Parses and validates a structure file's text; `source` names it in errors.
    ///
    /// # Errors
    /// [`Error::Toml`] naming `source` with the parser's message (unknown key, missing
    /// field, wrong type, with line and column); [`Error::InvalidParameter`] naming
    /// `source: field` for a value out of range.
    pub fn parse(text: &str, source: &str) -> Result<Self> {
        let f: StructureFile = toml::from_str(text).map_err(|e| Error::Toml {
            source_name: source.to_string(),
            message: text
                .parse::<toml::Table>()
                .ok()
                .and_then(|t| flattened_bad_key::<StructureFile>(&t))
                .map(|(key, message)| {
                    let line = key_line(text, &key);
                    format!("line {line}: key `{key}`: {message}")
                })
                .unwrap_or_else(|| e.to_string()),
        })?;
        if let Some(key) = f.unknown.keys().next() {
            return Err(Error::Toml {
                source_name: source.to_string(),
                message: format!(
                    "line {}: unknown field `{key}`, expected one of {}",
                    key_line(text, key),
                    ["air_density", "chord"]
                        .iter()
                        .chain(&ModalStructure::KEYS)
                        .chain(&Nonlinearities::KEYS)
                        .map(|k| format!("`{k}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
        f.structure().map_err(|e| in_file(source, e))?;
        Ok(f)
    }

    /// A structure file holding `spec` (air density ρ \[kg/m³\], optional chord \[m\]);
    /// not validated ([`StructureFile::structure`] does).
    pub fn new(
        air_density: f64,
        chord: Option<f64>,
        linear: ModalStructure,
        nonlinear: Nonlinearities,
    ) -> Self {
        StructureFile {
            air_density,
            chord,
            linear,
            nonlinear,
            unknown: BTreeMap::new(),
        }
    }

    /// Reads a structure file.
    ///
    /// # Errors
    /// [`Error::Io`] when it cannot be read; otherwise as [`StructureFile::parse`].
    pub fn read(path: &Path) -> Result<Self> {
        Self::parse(&read_text(path)?, &path.display().to_string())
    }

    /// The shared structure spec of this file ([`StructureSpec::Modal`]).
    pub fn spec(&self) -> StructureSpec {
        StructureSpec::Modal {
            linear: self.linear,
            nonlinear: self.nonlinear.clone(),
        }
    }

    /// The structure (see the module docs for the conversion).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`air_density`, `freq_pitch`,
    /// `mass`, `pitch_stiffness_terms[1].power`…).
    pub fn structure(&self) -> Result<Structure> {
        use identify::limits::{positive_at_most, MAX_AIR_DENSITY, MAX_CHORD};
        positive("air_density", self.air_density)?;
        positive_at_most(self.air_density, MAX_AIR_DENSITY, "kg/m^3")
            .map_err(|m| Error::param("air_density", self.air_density, m))?;
        if let Some(c) = self.chord {
            positive("chord", c)?;
            positive_at_most(c, MAX_CHORD, "m").map_err(|m| Error::param("chord", c, m))?;
        }
        self.spec().resolve()
    }
}

/// Kind of a model file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// [`TheodorsenAero`].
    Theodorsen,
    /// [`QuasiSteady`] with [`QuasiSteadyKind::QuasiSteady`].
    QuasiSteady,
    /// [`QuasiSteady`] with [`QuasiSteadyKind::Steady`].
    Steady,
    /// [`DerivativeTable::flat_plate`] on the grid `k`.
    FlatPlateTable,
    /// [`DerivativeTable`] from `[[derivatives]]` rows.
    DerivativeTable,
    /// [`IdentifiedLaw`] from `file`.
    Identified,
    /// [`DynamicStallAero::thin_plate`] (Beddoes–Leishman-type dynamic stall).
    DynamicStall,
    /// [`LagAero`] from the `lag_law.json` `file` (the lag law of `identify --law lag`).
    Lag,
}

impl ModelKind {
    /// Every kind, in declaration order.
    pub const ALL: [ModelKind; 8] = [
        ModelKind::Theodorsen,
        ModelKind::QuasiSteady,
        ModelKind::Steady,
        ModelKind::FlatPlateTable,
        ModelKind::DerivativeTable,
        ModelKind::Identified,
        ModelKind::DynamicStall,
        ModelKind::Lag,
    ];

    /// The name as written in model files and result documents (`theodorsen`, …).
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Theodorsen => "theodorsen",
            ModelKind::QuasiSteady => "quasi_steady",
            ModelKind::Steady => "steady",
            ModelKind::FlatPlateTable => "flat_plate_table",
            ModelKind::DerivativeTable => "derivative_table",
            ModelKind::Identified => "identified",
            ModelKind::DynamicStall => "dynamic_stall",
            ModelKind::Lag => "lag",
        }
    }

    /// The optional keys of a model file this kind uses (besides `kind` and `nonlinear`).
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            ModelKind::Theodorsen | ModelKind::DynamicStall => &["chord", "elastic_axis"],
            ModelKind::QuasiSteady | ModelKind::Steady => {
                &["chord", "elastic_axis", "noncirculatory"]
            }
            ModelKind::FlatPlateTable => &["chord", "rfa_lags", "k"],
            ModelKind::DerivativeTable => &["chord", "rfa_lags", "derivatives"],
            ModelKind::Identified => &["chord", "rfa_lags", "file", "groups", "missing"],
            ModelKind::Lag => &["chord", "elastic_axis", "file", "mean_angle"],
        }
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One `[[nonlinear]]` entry of a model file or of a study's `[aero]`: an aerodynamic
/// monomial (DATA_FORMAT.md name, total degree ≥ 2) on the lift or the moment, with a
/// constant nondimensional coefficient or an Eq. 19 table over K.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NonlinearSpec {
    /// Term name (DATA_FORMAT.md), total degree ≥ 2, e.g. `alpha_dot^3`.
    pub term: String,
    /// `lift` or `moment`.
    #[serde(with = "crate::aero::channel_name")]
    #[schemars(with = "String")]
    pub channel: Channel,
    /// Constant nondimensional coefficient.
    #[serde(default)]
    pub coefficient: Option<f64>,
    /// Eq. 19 table: reduced frequencies.
    #[serde(default)]
    pub k: Option<Vec<f64>>,
    /// Eq. 19 table: N* values.
    #[serde(default)]
    pub values: Option<Vec<f64>>,
    /// Eq. 19 table: power of K.
    #[serde(default)]
    pub k_power: Option<i32>,
}

impl NonlinearSpec {
    /// The term this entry describes (the one conversion of a written nonlinear term).
    ///
    /// # Errors
    /// `(field, message)` with `field` relative to the entry: `term` when the name does not
    /// parse or its total degree is below 2; `coefficient` when neither or both of
    /// `coefficient` and the table (`k`, `values`, `k_power`) are given, or the constant is
    /// not finite or above [`identify::limits::MAX_NONLINEAR_COEFFICIENT`] in magnitude;
    /// `values` when an entry's effective coefficient K^`k_power` N* is above that bound.
    /// (The table's own checks are [`NonlinearAero::new`]'s.)
    pub fn to_term(&self) -> std::result::Result<NonlinearTerm, (&'static str, String)> {
        use identify::limits::{show, MAX_NONLINEAR_COEFFICIENT as MAX};
        let powers = NonlinearTerm::powers_of(&self.term).map_err(|e| {
            let m = match e {
                Error::InvalidParameter { message, .. } => message,
                other => other.to_string(),
            };
            ("term", m)
        })?;
        if powers.iter().sum::<u32>() < 2 {
            return Err(("term", format!("`{}`: total degree must be ≥ 2", self.term)));
        }
        let coefficient = match (self.coefficient, &self.k, &self.values, self.k_power) {
            (Some(c), None, None, None) if c.is_finite() && c.abs() <= MAX => {
                Coefficient::Constant(c)
            }
            (Some(c), None, None, None) => {
                return Err((
                    "coefficient",
                    format!(
                        "{} must be finite with |coefficient| ≤ {} (nondimensional; \
                         identify::limits::MAX_NONLINEAR_COEFFICIENT)",
                        show(c),
                        show(MAX)
                    ),
                ))
            }
            (None, Some(k), Some(v), Some(p)) => {
                // the effective coefficient K^p N* of each entry; malformed entries (K ≤ 0,
                // non-finite) are NonlinearAero::new's to name
                let big = k.iter().zip(v).enumerate().find(|(_, (&k, &n))| {
                    let xi = n * k.powi(p);
                    k.is_finite()
                        && k > 0.0
                        && n.is_finite()
                        && !(xi.is_finite() && xi.abs() <= MAX)
                });
                if let Some((i, (&k, &n))) = big {
                    return Err((
                        "values",
                        format!(
                            "entry {}: K^{p} N* = {}^{p} × {} = {} must be finite with \
                             |value| ≤ {} (nondimensional; \
                             identify::limits::MAX_NONLINEAR_COEFFICIENT)",
                            i + 1,
                            show(k),
                            show(n),
                            show(n * k.powi(p)),
                            show(MAX)
                        ),
                    ));
                }
                Coefficient::OverK {
                    k: k.clone(),
                    values: v.clone(),
                    k_power: p,
                }
            }
            _ => {
                return Err((
                    "coefficient",
                    "give either `coefficient` or all of `k`, `values`, `k_power`".into(),
                ))
            }
        };
        Ok(NonlinearTerm {
            channel: self.channel,
            powers,
            coefficient,
        })
    }
}

/// A model file (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Model kind (`model` is accepted for it, the key of a study's `[aero]`).
    #[serde(alias = "model")]
    pub kind: ModelKind,
    /// Chord B \[m\].
    #[serde(default)]
    pub chord: Option<f64>,
    /// Elastic axis a (semi-chords aft of mid-chord).
    #[serde(default)]
    pub elastic_axis: Option<f64>,
    /// Noncirculatory terms (quasi-steady kinds; default true for `quasi_steady`, false for
    /// `steady`).
    #[serde(default)]
    pub noncirculatory: Option<bool>,
    /// RFA lag roots (`n_lag` is accepted for it, the key of a study's `[aero]`).
    #[serde(default, alias = "n_lag")]
    pub rfa_lags: Option<usize>,
    /// K grid of `flat_plate_table` (default [`crate::reference::flat_plate_k_grid`]).
    #[serde(default)]
    pub k: Option<Vec<f64>>,
    /// Rows of `derivative_table`.
    #[serde(default)]
    pub derivatives: Option<Vec<Derivatives>>,
    /// `identification.json` of `identified`, `lag_law.json` of `lag` (relative to the
    /// model file).
    #[serde(default)]
    pub file: Option<PathBuf>,
    /// Groups of `identified`.
    #[serde(default)]
    pub groups: Option<Vec<String>>,
    /// Null-derivative fallback of `identified`.
    #[serde(default)]
    pub missing: Option<MissingDerivative>,
    /// Trim angle α₀ \[rad\] (nose-up) a `lag` law is flown about (|α₀| < π/2): the
    /// state and forces are taken about the static equilibrium there
    /// ([`LagAero::with_mean_angle`]).
    #[serde(default)]
    pub mean_angle: Option<f64>,
    /// Nonlinear terms added to the model.
    #[serde(default)]
    pub nonlinear: Vec<NonlinearSpec>,
}

impl ModelFile {
    /// A file of kind `kind` with no optional key and no nonlinear term.
    pub fn of_kind(kind: ModelKind) -> Self {
        ModelFile {
            kind,
            chord: None,
            elastic_axis: None,
            noncirculatory: None,
            rfa_lags: None,
            k: None,
            derivatives: None,
            file: None,
            groups: None,
            missing: None,
            mean_angle: None,
            nonlinear: Vec::new(),
        }
    }

    /// The optional keys that are given, in declaration order.
    pub fn present_keys(&self) -> impl Iterator<Item = &'static str> + '_ {
        [
            ("chord", self.chord.is_some()),
            ("elastic_axis", self.elastic_axis.is_some()),
            ("noncirculatory", self.noncirculatory.is_some()),
            ("rfa_lags", self.rfa_lags.is_some()),
            ("k", self.k.is_some()),
            ("derivatives", self.derivatives.is_some()),
            ("file", self.file.is_some()),
            ("groups", self.groups.is_some()),
            ("missing", self.missing.is_some()),
            ("mean_angle", self.mean_angle.is_some()),
        ]
        .into_iter()
        .filter_map(|(name, present)| present.then_some(name))
    }

    /// This file as kind `kind`: the keys `kind` uses are kept, the others dropped, the
    /// nonlinear terms kept (a study's flutter runs of other kinds take `[aero]`'s
    /// parameters this way).
    pub fn for_kind(&self, kind: ModelKind) -> Self {
        let keep = kind.keys();
        let k = |name: &str| keep.contains(&name);
        ModelFile {
            kind,
            chord: self.chord.filter(|_| k("chord")),
            elastic_axis: self.elastic_axis.filter(|_| k("elastic_axis")),
            noncirculatory: self.noncirculatory.filter(|_| k("noncirculatory")),
            rfa_lags: self.rfa_lags.filter(|_| k("rfa_lags")),
            k: self.k.clone().filter(|_| k("k")),
            derivatives: self.derivatives.clone().filter(|_| k("derivatives")),
            file: self.file.clone().filter(|_| k("file")),
            groups: self.groups.clone().filter(|_| k("groups")),
            missing: self.missing.filter(|_| k("missing")),
            mean_angle: self.mean_angle.filter(|_| k("mean_angle")),
            nonlinear: self.nonlinear.clone(),
        }
    }
}

/// Whether a JSON text is a lag-law document: its top-level `format` field starts with
/// `aeroform-lag-law` (any version: a wrong one is then refused by name by
/// [`read_lag_law`] rather than read as an identification).
fn is_lag_law(text: &str) -> bool {
    serde_json::from_str::<serde_json::Value>(text)
        .ok()
        .and_then(|v| v.get("format")?.as_str().map(str::to_owned))
        .is_some_and(|f| f.starts_with("aeroform-lag-law"))
}

/// An error of a file that the key `key` of the model file `model` names, with the model
/// file and the key in front: a missing or malformed law file is refused where it is named
/// (issue 39, row 7: every refusal carries its location).
fn by_key(model: &str, key: &str, e: Error) -> Error {
    let at = |what: &str| format!("{model}: key `{key}`: {what}");
    match e {
        Error::Toml {
            source_name,
            message,
        } => Error::Toml {
            source_name: at(&source_name),
            message,
        },
        Error::Io { path, message } => Error::Io {
            path: at(&path),
            message,
        },
        Error::Document { path, message } => Error::Document {
            path: at(&path),
            message,
        },
        Error::Identify { context, source } => Error::Identify {
            context: at(&context),
            source,
        },
        other => other,
    }
}

/// Names the file in a lag-law error.
fn lag_in(path: &Path, e: Error) -> Error {
    match e {
        Error::Identify { source, .. } => Error::Identify {
            context: path.display().to_string(),
            source,
        },
        other => in_file(&path.display().to_string(), other),
    }
}

/// Reads a `lag_law.json` (format [`identify::lag::LAG_LAW_FORMAT`]): the document whose
/// law [`LagAero`] flies.
///
/// # Errors
/// [`Error::Io`] when it cannot be read; [`Error::Identify`] naming the file and the field
/// (not the document, wrong `format`, bad `chord`, a law parameter out of its bounds).
pub fn read_lag_law(path: &Path) -> Result<identify::lag::LagLawDocument> {
    let text = read_text(path)?;
    identify::lag::LagLawDocument::from_json(&text, path).map_err(|source| Error::Identify {
        // a JSON error names the file itself
        context: match source {
            identify::Error::Json { .. } => "lag law".into(),
            _ => format!("lag law {}", path.display()),
        },
        source,
    })
}

/// A loaded aerodynamic model.
#[derive(Debug, Clone)]
pub struct LoadedModel {
    /// The model.
    pub model: Arc<dyn AeroModel>,
    /// The same model as a [`NonlinearAero`] when it has nonlinear terms (for K-iterated
    /// LCO runs).
    pub nonlinear: Option<NonlinearAero>,
    /// The identified tables when the model came from an identification.
    pub identified: Option<IdentifiedTables>,
}

impl LoadedModel {
    /// Loads a model file, a `lag_law.json` or an `identification.json` (by extension
    /// `.json` or a leading `{`; a lag law by its `format` field, module docs); `chord` is
    /// used when the file gives none (an identification never does; a lag law always does,
    /// and its own chord is used).
    ///
    /// # Errors
    /// [`Error::Io`] when a file cannot be read; [`Error::Toml`] naming the file and the
    /// key (unknown, missing, not used by the kind, wrong type); [`Error::InvalidParameter`]
    /// naming `file: field`; the errors of the model constructors, of
    /// [`IdentifiedLaw::read`] and of [`read_lag_law`].
    pub fn load(path: &Path, chord: Option<f64>) -> Result<Self> {
        // a `.json` file may be a large identification.json: read under the result cap
        let by_extension = path.extension().is_some_and(|e| e == "json");
        let text = if by_extension {
            identify::io::read_text_capped_io(path, identify::limits::MAX_RESULT_FILE_BYTES as u64)
                .map_err(|e| read_error(path, e))?
        } else {
            read_text(path)?
        };
        let is_json = by_extension || text.trim_start().starts_with('{');
        if is_json && is_lag_law(&text) {
            let doc = read_lag_law(path)?;
            let model = LagAero::new(doc.law, doc.chord, None).map_err(|e| lag_in(path, e))?;
            return Ok(LoadedModel {
                model: Arc::new(model),
                nonlinear: None,
                identified: None,
            });
        }
        if is_json {
            drop(text); // read again by the identification's own reader
            let chord = chord.ok_or_else(|| Error::Toml {
                source_name: path.display().to_string(),
                message: "an identification.json holds no chord: give it (--chord or `chord` in the structure file)".into(),
            })?;
            let law = IdentifiedLaw::read(path, &IdentifiedOptions::new(chord))?;
            return Ok(Self::from_law(law));
        }
        let base = path.parent().unwrap_or(Path::new("."));
        Self::parse(&text, &path.display().to_string(), base, chord)
    }

    fn from_law(law: IdentifiedLaw) -> Self {
        let nl = law.model().clone();
        LoadedModel {
            model: Arc::new(nl.clone()),
            nonlinear: Some(nl),
            identified: Some(law.tables.clone()),
        }
    }

    /// Parses a model file's text; `source` names it in errors, `base` is the folder
    /// relative paths are resolved against, `chord` the fallback chord.
    ///
    /// # Errors
    /// As [`LoadedModel::load`].
    pub fn parse(text: &str, source: &str, base: &Path, chord: Option<f64>) -> Result<Self> {
        let toml_err = |m: String| Error::Toml {
            source_name: source.to_string(),
            message: m,
        };
        let f: ModelFile = toml::from_str(text).map_err(|e| toml_err(e.to_string()))?;
        Self::from_spec(&f, source, base, chord)
    }

    /// Builds the model a parsed model file describes (the one constructor of every model
    /// kind, used by model files and by a study's `[aero]`); `source` names it in errors,
    /// `base` is the folder relative paths are resolved against, `chord` the fallback chord.
    ///
    /// # Errors
    /// [`Error::Toml`] naming `source` and the key (not used by the kind, missing for it,
    /// a bad nonlinear term); [`Error::InvalidParameter`] naming `source: field`; the errors
    /// of the model constructors and of [`IdentifiedLaw::read`].
    pub fn from_spec(f: &ModelFile, source: &str, base: &Path, chord: Option<f64>) -> Result<Self> {
        let toml_err = |m: String| Error::Toml {
            source_name: source.to_string(),
            message: m,
        };
        let kind_name = format!("\"{}\"", f.kind);
        if let Some(name) = f.present_keys().find(|k| !f.kind.keys().contains(k)) {
            return Err(toml_err(format!(
                "key `{name}` is not used by kind = {kind_name}"
            )));
        }
        let need = |name: &str| toml_err(format!("missing key `{name}` for kind = {kind_name}"));
        let chord = f.chord.or(chord);
        let wrap = |e: Error| in_file(source, e);
        let a = f.elastic_axis.unwrap_or(0.0);
        identify::limits::abs_at_most(a, identify::limits::MAX_ELASTIC_AXIS, "semi-chords")
            .map_err(|m| wrap(Error::param("elastic_axis", a, m)))?;
        if let Some(c) = chord {
            identify::limits::positive_at_most(c, identify::limits::MAX_CHORD, "m")
                .map_err(|m| wrap(Error::param("chord", c, m)))?;
        }
        let lags = f.rfa_lags.unwrap_or(3);
        let (linear, identified): (Arc<dyn AeroModel>, Option<IdentifiedLaw>) = match f.kind {
            ModelKind::Theodorsen => (
                Arc::new(
                    TheodorsenAero::new(chord.ok_or_else(|| need("chord"))?, a).map_err(wrap)?,
                ),
                None,
            ),
            ModelKind::DynamicStall => (
                Arc::new(
                    DynamicStallAero::thin_plate(chord.ok_or_else(|| need("chord"))?, a)
                        .map_err(wrap)?,
                ),
                None,
            ),
            ModelKind::QuasiSteady | ModelKind::Steady => {
                let k = if f.kind == ModelKind::Steady {
                    QuasiSteadyKind::Steady
                } else {
                    QuasiSteadyKind::QuasiSteady
                };
                (
                    Arc::new(
                        QuasiSteady::new(
                            chord.ok_or_else(|| need("chord"))?,
                            a,
                            k,
                            f.noncirculatory.unwrap_or(f.kind == ModelKind::QuasiSteady),
                        )
                        .map_err(wrap)?,
                    ),
                    None,
                )
            }
            ModelKind::FlatPlateTable => (
                Arc::new(
                    DerivativeTable::flat_plate(
                        chord.ok_or_else(|| need("chord"))?,
                        &f.k.clone()
                            .unwrap_or_else(crate::reference::flat_plate_k_grid),
                        lags,
                    )
                    .map_err(wrap)?,
                ),
                None,
            ),
            ModelKind::DerivativeTable => (
                Arc::new(
                    DerivativeTable::new(
                        chord.ok_or_else(|| need("chord"))?,
                        f.derivatives.clone().ok_or_else(|| need("derivatives"))?,
                        lags,
                    )
                    .map_err(wrap)?,
                ),
                None,
            ),
            ModelKind::Lag => {
                let file = base.join(f.file.as_ref().ok_or_else(|| need("file"))?);
                let doc = read_lag_law(&file).map_err(|e| by_key(source, "file", e))?;
                let mut m = LagAero::new(doc.law, f.chord.unwrap_or(doc.chord), f.elastic_axis)
                    .map_err(wrap)?;
                if let Some(a0) = f.mean_angle {
                    m = m.with_mean_angle(a0).map_err(wrap)?;
                }
                (Arc::new(m) as Arc<dyn AeroModel>, None)
            }
            ModelKind::Identified => {
                let file = base.join(f.file.as_ref().ok_or_else(|| need("file"))?);
                let mut o = IdentifiedOptions::new(chord.ok_or_else(|| need("chord"))?);
                o.groups = f.groups.clone();
                o.missing = f.missing.unwrap_or_default();
                o.rfa_lags = lags;
                let law = IdentifiedLaw::read(&file, &o).map_err(|e| by_key(source, "file", e))?;
                (law.table().clone() as Arc<dyn AeroModel>, Some(law))
            }
        };
        let terms = f
            .nonlinear
            .iter()
            .enumerate()
            .map(|(i, n)| {
                n.to_term()
                    .map_err(|(field, m)| toml_err(format!("nonlinear[{}].{field}: {m}", i + 1)))
            })
            .collect::<Result<Vec<_>>>()?;
        let tables = identified.as_ref().map(|l| l.tables.clone());
        if let Some(law) = identified {
            if terms.is_empty() {
                return Ok(Self::from_law(law));
            }
            // Identified terms plus the file's extra terms.
            let mut all: Vec<NonlinearTerm> = law.model().terms().to_vec();
            all.extend(terms);
            let nl = NonlinearAero::new(linear, all, law.model().k_eval()).map_err(wrap)?;
            return Ok(LoadedModel {
                model: Arc::new(nl.clone()),
                nonlinear: Some(nl),
                identified: tables,
            });
        }
        if terms.is_empty() {
            return Ok(LoadedModel {
                model: linear,
                nonlinear: None,
                identified: None,
            });
        }
        let k_eval = terms
            .iter()
            .filter_map(|t| match &t.coefficient {
                Coefficient::OverK { k, .. } => k.first().map(|k0| (k0 * k[k.len() - 1]).sqrt()),
                _ => None,
            })
            .next()
            .unwrap_or(1.0);
        let nl = NonlinearAero::new(linear, terms, k_eval).map_err(|e| {
            in_file(
                source,
                match e {
                    Error::InvalidParameter {
                        field,
                        value,
                        message,
                    } => Error::InvalidParameter {
                        // terms[i] → nonlinear[i+1]
                        field: field
                            .strip_prefix("terms[")
                            .and_then(|r| r.split_once(']'))
                            .and_then(|(i, rest)| {
                                i.parse::<usize>()
                                    .ok()
                                    .map(|i| format!("nonlinear[{}]{rest}", i + 1))
                            })
                            .unwrap_or(field),
                        value,
                        message,
                    },
                    other => other,
                },
            )
        })?;
        Ok(LoadedModel {
            model: Arc::new(nl.clone()),
            nonlinear: Some(nl),
            identified: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::{QuasiSteady, QuasiSteadyKind};

    const RIG: &str = r#"
mass = 1.0933
inertia = 0.0058
static_unbalance = 0.0109
freq_heave = 2.0
freq_pitch = 3.5
damping_heave = 0.005
damping_pitch = 0.005
"#;

    #[test]
    fn structure_file_converts_frequencies_and_names_bad_fields() {
        let f = StructureFile::parse(RIG, "rig.toml").unwrap();
        let s = f.structure().unwrap();
        assert!((s.omega_alpha() - 2.0 * std::f64::consts::PI * 3.5).abs() < 1e-12);
        assert!((s.c_h - 2.0 * 0.005 * 1.0933 * 4.0 * std::f64::consts::PI).abs() < 1e-12);
        assert_eq!(f.air_density, 1.225);
        let e = StructureFile::parse(&format!("{RIG}masss = 1.0\n"), "rig.toml").unwrap_err();
        let m = e.to_string();
        assert!(m.contains("rig.toml") && m.contains("masss"), "{m}");
        let e = StructureFile::parse(
            &RIG.replace("freq_pitch = 3.5", "freq_pitch = -1"),
            "rig.toml",
        )
        .unwrap_err();
        let m = e.to_string();
        assert!(m.contains("rig.toml: freq_pitch"), "{m}");
        let e = StructureFile::parse(
            &RIG.replace("static_unbalance = 0.0109", "static_unbalance = 0.1"),
            "r",
        )
        .unwrap_err();
        assert!(e.to_string().contains("static_unbalance"), "{e}");
        // a wrong-typed value inside the flattened table still names its key and line
        let e = StructureFile::parse(
            &RIG.replace("freq_pitch = 3.5", "freq_pitch = \"a\""),
            "rig.toml",
        )
        .unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("rig.toml") && m.contains("line 6: key `freq_pitch`"),
            "{m}"
        );
        let e = StructureFile::parse(&format!("{RIG}[friction]\npitch_momentt = 1.0\n"), "r")
            .unwrap_err();
        assert!(e.to_string().contains("pitch_momentt"), "{e}");
        // the file is the modal form of the shared spec
        assert_eq!(f.spec().resolve().unwrap(), s);
    }

    #[test]
    fn model_files_build_models_and_reject_unused_or_unknown_keys() {
        let base = Path::new(".");
        let m = LoadedModel::parse(
            "kind = \"theodorsen\"\nchord = 0.25\nelastic_axis = -0.3\n\n[[nonlinear]]\nterm = \"alpha_dot^3\"\nchannel = \"moment\"\ncoefficient = -100.0\n",
            "m.toml",
            base,
            None,
        )
        .unwrap();
        assert_eq!(m.model.chord(), 0.25);
        assert_eq!(m.nonlinear.unwrap().terms()[0].powers, [0, 3, 0, 0]);
        let e = LoadedModel::parse(
            "kind = \"theodorsen\"\nchord = 0.25\nk = [0.1]\n",
            "m.toml",
            base,
            None,
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("m.toml") && e.to_string().contains("`k`"),
            "{e}"
        );
        let e = LoadedModel::parse(
            "kind = \"theodorsen\"\nchrod = 0.25\n",
            "m.toml",
            base,
            None,
        )
        .unwrap_err();
        assert!(e.to_string().contains("chrod"), "{e}");
        let e = LoadedModel::parse("kind = \"theodorsen\"\n", "m.toml", base, None).unwrap_err();
        assert!(e.to_string().contains("missing key `chord`"), "{e}");
        let e = LoadedModel::parse(
            "kind = \"theodorsen\"\nchord = 0.25\n[[nonlinear]]\nterm = \"alpha\"\nchannel = \"moment\"\ncoefficient = 1.0\n",
            "m.toml",
            base,
            None,
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .contains("m.toml: nonlinear[1].term: `alpha`: total degree must be ≥ 2"),
            "{e}"
        );
        let e = LoadedModel::parse(
            "kind = \"theodorsen\"\nchord = 0.25\n[[nonlinear]]\nterm = \"alpha^3\"\nchannel = \"pitch\"\ncoefficient = 1.0\n",
            "m.toml",
            base,
            None,
        )
        .unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("line 5") && m.contains("`pitch`: expected \"lift\" or \"moment\""),
            "{m}"
        );
        let ft = LoadedModel::parse(
            "kind = \"flat_plate_table\"\nchord = 0.25\nk = [0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.5]\n",
            "m.toml",
            base,
            None,
        )
        .unwrap();
        assert_eq!(ft.model.n_lag(), 6);
    }

    /// Issue 27 row 15: a nonlinear coefficient beyond the limits table is refused at
    /// parsing, naming the file and the entry's field; the limit itself reads.
    #[test]
    fn nonlinear_coefficients_beyond_the_limit_are_refused_naming_the_field() {
        use identify::limits::MAX_NONLINEAR_COEFFICIENT as MAX;
        let base = Path::new(".");
        let model = |c: &str| {
            format!(
                "kind = \"theodorsen\"\nchord = 0.25\n[[nonlinear]]\nterm = \"alpha^3\"\n\
                 channel = \"moment\"\ncoefficient = -2.0\n[[nonlinear]]\n\
                 term = \"alpha_dot^3\"\nchannel = \"lift\"\ncoefficient = {c}\n"
            )
        };
        for c in [MAX, -MAX] {
            LoadedModel::parse(&model(&format!("{c:e}")), "m.toml", base, None).unwrap();
        }
        for (c, shown) in [
            ("1e300", "1e300"),
            ("-1.000001e9", "-1000001000"),
            ("inf", "inf"),
        ] {
            let e = LoadedModel::parse(&model(c), "m.toml", base, None).unwrap_err();
            let m = e.to_string();
            assert!(
                m.contains("m.toml: nonlinear[2].coefficient: ")
                    && m.contains(shown)
                    && m.contains("≤ 1000000000"),
                "{m}"
            );
        }
        // an Eq. 19 table: the bound is on the effective coefficient K^p N*
        let table = |v: &str| {
            format!(
                "kind = \"theodorsen\"\nchord = 0.25\n[[nonlinear]]\nterm = \"alpha^3\"\n\
                 channel = \"moment\"\nk = [0.5, 1.0]\nvalues = [1.0, {v}]\nk_power = 6\n"
            )
        };
        LoadedModel::parse(&table("1e9"), "m.toml", base, None).unwrap();
        let e = LoadedModel::parse(&table("1e300"), "m.toml", base, None).unwrap_err();
        assert!(
            e.to_string()
                .contains("m.toml: nonlinear[1].values: entry 2"),
            "{e}"
        );
    }

    #[test]
    fn a_model_file_takes_the_study_key_names_and_documented_defaults() {
        let base = Path::new(".");
        // `model` and `n_lag` (a study's [aero] keys) are the same keys as `kind` and
        // `rfa_lags`; a flat-plate table without `k` is on the reference grid
        let a = LoadedModel::parse(
            "model = \"flat_plate_table\"\nn_lag = 2\n",
            "m.toml",
            base,
            Some(0.3),
        )
        .unwrap();
        let b = LoadedModel::from_spec(
            &ModelFile {
                chord: Some(0.3),
                rfa_lags: Some(2),
                k: Some(crate::reference::flat_plate_k_grid()),
                ..ModelFile::of_kind(ModelKind::FlatPlateTable)
            },
            "m",
            base,
            None,
        )
        .unwrap();
        let flow = crate::aero::Flow { rho: 1.2, u: 7.0 };
        assert_eq!(a.model.n_lag(), 4, "2 lag roots, 2 states each");
        assert_eq!(
            a.model.frequency_response(&flow, 9.0),
            b.model.frequency_response(&flow, 9.0)
        );
        // `steady` leaves the noncirculatory terms out unless asked, `quasi_steady` keeps them
        let name = |t: &str| {
            LoadedModel::parse(t, "m.toml", base, Some(0.3))
                .unwrap()
                .model
                .name()
        };
        assert_eq!(name("kind = \"steady\"\n"), "steady");
        assert_ne!(name("kind = \"steady\"\nnoncirculatory = true\n"), "steady");
        assert_eq!(
            name("kind = \"quasi_steady\"\n"),
            name("kind = \"quasi_steady\"\nnoncirculatory = true\n")
        );
        // another kind keeps only the keys it uses
        let f: ModelFile = toml::from_str(
            "model = \"theodorsen\"\nelastic_axis = -0.3\nn_lag = 4\n[[nonlinear]]\nterm = \"alpha^3\"\nchannel = \"lift\"\ncoefficient = 2.0\n",
        )
        .unwrap();
        let t = f.for_kind(ModelKind::FlatPlateTable);
        assert_eq!(t.present_keys().collect::<Vec<_>>(), ["rfa_lags"]);
        assert_eq!(t.nonlinear, f.nonlinear);
        assert_eq!(
            f.for_kind(ModelKind::Steady)
                .present_keys()
                .collect::<Vec<_>>(),
            ["elastic_axis"]
        );
    }

    /// Issue 41: a `lag_law.json` is a model by its `format` field (directly, on the law's
    /// chord, no apparent mass) and through a model file (`kind = "lag"`: elastic axis,
    /// chord, trim); bad documents and keys are refused naming the file and the field.
    #[test]
    fn lag_laws_load_directly_and_from_model_files_and_bad_ones_are_named() {
        let scen = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
        let law = scen.join("plate-lag.lag_law.json");
        let direct = LoadedModel::load(&law, Some(0.3)).unwrap();
        assert_eq!(direct.model.name(), "lag_law");
        assert_eq!(direct.model.chord(), 0.25, "the law's own chord");
        assert_eq!(direct.model.n_lag(), 1);
        let flow = crate::aero::Flow { rho: 1.2, u: 5.0 };
        assert_eq!(
            direct.model.apparent_mass(&flow),
            nalgebra::Matrix2::zeros()
        );
        let file = LoadedModel::load(&scen.join("plate-lag.model.toml"), None).unwrap();
        assert_eq!(file.model.elastic_axis(), Some(-0.3));
        // attached: the quasi-steady thin aerofoil about the same axis
        let qs = QuasiSteady::new(0.25, -0.3, QuasiSteadyKind::QuasiSteady, true).unwrap();
        let (a, b) = (
            file.model.frequency_response(&flow, 17.0),
            qs.frequency_response(&flow, 17.0),
        );
        assert!((a - b).norm() < 1e-12 * b.norm(), "{a} vs {b}");
        let dir = tempfile::tempdir().unwrap();
        let text = std::fs::read_to_string(&law).unwrap();
        let write = |name: &str, t: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, t).unwrap();
            p
        };
        let model = |extra: &str| {
            write(
                "m.model.toml",
                &format!(
                    "kind = \"lag\"\nfile = \"{}\"\n{extra}",
                    law.display().to_string().replace('\\', "/")
                ),
            )
        };
        let m = LoadedModel::load(&model("chord = 0.5\nmean_angle = 0.2\n"), None).unwrap();
        assert_eq!(m.model.chord(), 0.5);
        let show = |p: &Path| LoadedModel::load(p, None).unwrap_err().to_string();
        let e = show(&model("mean_angle = 3.0\n"));
        assert!(e.contains("m.model.toml: mean_angle"), "{e}");
        let e = show(&model("rfa_lags = 2\n"));
        assert!(
            e.contains("`rfa_lags` is not used by kind = \"lag\""),
            "{e}"
        );
        let e = show(&write("n.model.toml", "kind = \"lag\"\n"));
        assert!(e.contains("missing key `file`"), "{e}");
        let e = show(&write(
            "v2.json",
            &text.replace("aeroform-lag-law/1", "aeroform-lag-law/2"),
        ));
        assert!(e.contains("v2.json") && e.contains("field `format`"), "{e}");
        let e = show(&write(
            "t.json",
            &text.replace("\"tau1\": 3.0", "\"tau1\": -3.0"),
        ));
        assert!(e.contains("t.json") && e.contains("tau1"), "{e}");
        let e = show(&write(
            "c.json",
            &text.replace("\"chord\": 0.25", "\"chord\": 0.0"),
        ));
        assert!(e.contains("c.json") && e.contains("field `chord`"), "{e}");
        let e = show(&write(
            "x.json",
            &text.replace("\"sharpness\"", "\"sharp\""),
        ));
        assert!(e.contains("x.json") && e.contains("sharpness"), "{e}");
    }
}
