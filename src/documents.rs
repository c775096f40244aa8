//! The JSON documents the `aeroform` binary itself writes (the `--timing-json` file of
//! `identify`, the `--json` documents of `tunnel`; the study's `flutter.json`, `lco.json`,
//! `coefficients.columns.json` and the `--json` document of `run` live in
//! [`study::documents`] and are re-exported here), and [`schemas`]: the JSON Schema of every
//! JSON result document aeroform writes, generated from the Rust types that write it
//! (DATA_FORMAT.md, `docs/schemas/`).
//!
//! The documents of `aeroform flutter`, `lco` and `branch` live in
//! [`aeroelastic::documents`], `identification.json` in [`identify::pipeline`] and
//! `diagnosis.json` in [`diagnose::report`]; this is the lowest crate that sees them all.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

pub use study::documents::{CoefficientColumn, RunSummary};

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
        (
            "bifurcation",
            schema_of::<diagnose::bifurcation::BifurcationDiagnosis>(),
        ),
        ("blind", schema_of::<benchmark::bench::BlindReport>()),
        (
            "study-flutter",
            array_schema_of::<aeroelastic::documents::FlutterDoc>(
                "The `flutter.json` of a study: one `aeroform-flutter/1` document per \
                 `[[flutter.run]]`, in the order of the runs.",
            ),
        ),
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
