//! The JSON documents the `aeroform` binary itself writes (the study's `flutter.json`,
//! `lco.json` and `coefficients.columns.json`, the `--timing-json` file of `identify`, the
//! `--json` documents of `run` and `tunnel`), and [`schemas`]: the JSON Schema of every
//! JSON result document aeroform writes, generated from the Rust types that write it
//! (DATA_FORMAT.md, `docs/schemas/`).
//!
//! The documents of `aeroform flutter`, `lco` and `branch` live in
//! [`aeroelastic::documents`], `identification.json` in [`identify::pipeline`] and
//! `diagnosis.json` in [`diagnose::report`]; this is the lowest crate that sees them all.

use std::collections::BTreeMap;

use aeroelastic::ensemble::{FlutterEnsemble, LcoEnsemble};
use aeroelastic::flutter::FlutterAnalysis;
use aeroelastic::lco::LcoResult;
use aeroelastic::trajectory::Trajectory;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::study_spec::FlutterReference;

/// One flutter analysis of a study (one `[[flutter.run]]`); the study's `flutter.json` is
/// an array of them, in the order of the runs. Scanlan's convention (h positive down, α
/// positive nose-up); SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FlutterRun {
    /// The run's label in tables and figures.
    pub label: String,
    /// Aerodynamic model of the run (`theodorsen`, `truth`, `identified`, …).
    pub model: crate::study_spec::StudyModel,
    /// Semi-chord b = B/2 \[m\].
    pub semi_chord: f64,
    /// Still-air pitch frequency ω_α \[rad/s\]; reduced speed = U/(b·ω_α).
    pub omega_alpha: f64,
    /// The analysis: method, one branch per structural mode (V–g, V–f), flutter point,
    /// divergence speed, failed points.
    pub analysis: FlutterAnalysis,
    /// Published values the run is compared with; `null` when the study names none.
    pub reference: Option<FlutterReference>,
    /// Intervals over the bootstrap members of the identified law (`[identify] ensemble`,
    /// runs of the `identified` model only); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<FlutterEnsemble>,
}

/// The LCO stage of a study as saved in its `lco.json`. Scanlan's convention; SI units
/// (amplitudes in rad and m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LcoStage {
    /// Aerodynamic model of the sweeps (`theodorsen`, `identified`, …).
    pub model: String,
    /// Semi-chord b = B/2 \[m\].
    pub semi_chord: f64,
    /// Still-air pitch frequency ω_α \[rad/s\].
    pub omega_alpha: f64,
    /// Linear flutter speed of the same model \[m/s\], if a flutter run of it exists;
    /// `null` otherwise.
    pub flutter_speed: Option<f64>,
    /// Upward sweep, increasing U.
    pub up: Vec<LcoResult>,
    /// Downward sweep, increasing U (empty without `up_down`).
    pub down: Vec<LcoResult>,
    /// Trajectories drawn in the phase-portrait figure.
    pub phase: Vec<Trajectory>,
    /// Linear flutter speed of the truth model \[m/s\] (`compare_truth`); absent without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth_flutter_speed: Option<f64>,
    /// Upward sweep of the truth model of `[data.virtual]` (`compare_truth`); absent
    /// when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub truth_up: Vec<LcoResult>,
    /// Downward sweep of the truth model, increasing U (`compare_truth`); absent when
    /// empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub truth_down: Vec<LcoResult>,
    /// LCO amplitude intervals over the bootstrap members of the identified law at every
    /// speed of the sweep (`[identify] ensemble` with the `identified` model), each member
    /// run from the upward sweep's perturbation; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<LcoEnsemble>,
}

/// One term column of a study's `coefficients.csv`, as listed in
/// `coefficients.columns.json` (an array of them, in column order).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct CoefficientColumn {
    /// The CSV column name (letters, digits and `_`: `alpha2_h`, `const`).
    pub column: String,
    /// The library term it holds, as named in `identification.json` (`alpha^2*h`, `1`).
    pub term: String,
    /// The term as shown in figures and the report (`α²·h/B`).
    pub display: String,
}

/// The file written by `aeroform identify --timing-json FILE`: wall time of each stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct IdentifyTiming {
    /// Reading the data set \[s\].
    pub read_s: f64,
    /// Preprocessing the cases (library, factorisation, key frequencies) \[s\].
    pub prepare_s: f64,
    /// The sparse identification itself \[s\].
    pub identify_s: f64,
    /// Whole command \[s\].
    pub total_s: f64,
    /// Number of cases identified.
    pub cases: usize,
}

/// The document `aeroform run --json` prints on stdout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RunSummary {
    /// The study's name.
    pub study: String,
    /// The output folder.
    pub out: String,
    /// The study's seed, as a string (a u64 does not fit every JSON reader).
    pub seed: String,
    /// Wall time of each stage \[s\], by stage name.
    pub timings_s: BTreeMap<String, f64>,
    /// Wall time of the whole run \[s\].
    pub total_s: f64,
    /// The content of the study's `figures.json`: the figures drawn.
    pub figures: serde_json::Value,
}

/// The document `aeroform tunnel blind --json` prints on stdout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TunnelBlindSummary {
    /// The output folder.
    pub out: String,
    /// Number of forced cases written (under `forced/`).
    pub forced_cases: usize,
    /// Number of free-response runs written (under `free/`).
    pub free_runs: usize,
    /// The seed, as a string.
    pub seed: String,
}

/// The document `aeroform tunnel forced --json` prints on stdout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TunnelForcedSummary {
    /// The output folder (a data set).
    pub out: String,
    /// Number of cases written.
    pub cases: usize,
    /// Name of the aerodynamic model that generated the forces.
    pub model: String,
    /// The seed, as a string.
    pub seed: String,
    /// The data set's `manifest.toml` as JSON (DATA_FORMAT.md, `manifest.json`).
    pub manifest: serde_json::Value,
}

/// The document `aeroform tunnel free --json` prints on stdout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TunnelFreeSummary {
    /// The output folder (a data set).
    pub out: String,
    /// Number of free-response runs written.
    pub runs: usize,
    /// The seed, as a string.
    pub seed: String,
    /// The data set's `manifest.toml` as JSON (DATA_FORMAT.md, `manifest.json`).
    pub manifest: serde_json::Value,
    /// Per run, the time \[s\] at which the response left the amplitude bound (record
    /// truncated there); `null` when it did not.
    pub left_bound_at_s: Vec<Option<f64>>,
}

/// The JSON Schema of `T`, as a JSON value.
fn schema_of<T: JsonSchema>() -> serde_json::Value {
    plain_descriptions(schemars::schema_for!(T).to_value())
}

/// `schema` with the rustdoc escapes `\[` and `\]` of its `description`s (needed in doc
/// comments so that `[m/s]` is not read as a link) replaced by plain brackets.
fn plain_descriptions(schema: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match schema {
        Value::Object(o) => Value::Object(
            o.into_iter()
                .map(|(k, v)| match v {
                    Value::String(s) if k == "description" => {
                        let s = s.replace("\\[", "[").replace("\\]", "]");
                        (k, Value::String(s))
                    }
                    v => (k, plain_descriptions(v)),
                })
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.into_iter().map(plain_descriptions).collect()),
        v => v,
    }
}

/// The JSON Schema of an array of `T` (a document that is a JSON array), described as
/// `description` (the element type's doc comment describes the elements).
fn array_schema_of<T: JsonSchema>(description: &str) -> serde_json::Value {
    let mut s = schemars::schema_for!(Vec<T>);
    s.insert("description".into(), description.into());
    plain_descriptions(s.to_value())
}

/// The schema of every JSON result document aeroform writes, as `(name, schema)` pairs:
/// the schema of document `name` is committed as `docs/schemas/<name>.schema.json`
/// (DATA_FORMAT.md links each one). Generated from the Rust types that write the
/// documents, with their doc comments as `description`s; sorted by name.
pub fn schemas() -> Vec<(&'static str, serde_json::Value)> {
    let mut v = vec![
        ("flutter", schema_of::<aeroelastic::documents::FlutterDoc>()),
        ("lco", schema_of::<aeroelastic::documents::LcoDoc>()),
        ("branch", schema_of::<aeroelastic::documents::BranchDoc>()),
        (
            "identification",
            schema_of::<identify::pipeline::Identification>(),
        ),
        ("diagnosis", schema_of::<diagnose::report::Diagnosis>()),
        ("blind", schema_of::<diagnose::bench::BlindReport>()),
        (
            "study-flutter",
            array_schema_of::<FlutterRun>(
                "The `flutter.json` of a study: one flutter analysis per `[[flutter.run]]`, in \
                 the order of the runs.",
            ),
        ),
        ("study-lco", schema_of::<LcoStage>()),
        (
            "coefficients.columns",
            array_schema_of::<CoefficientColumn>(
                "The `coefficients.columns.json` of a study: one entry per term column of \
                 `coefficients.csv`, in column order.",
            ),
        ),
        ("identify-timing", schema_of::<IdentifyTiming>()),
        ("run-stdout", schema_of::<RunSummary>()),
        ("tunnel-blind-stdout", schema_of::<TunnelBlindSummary>()),
        ("tunnel-forced-stdout", schema_of::<TunnelForcedSummary>()),
        ("tunnel-free-stdout", schema_of::<TunnelFreeSummary>()),
    ];
    v.sort_by(|a, b| a.0.cmp(b.0));
    v
}
