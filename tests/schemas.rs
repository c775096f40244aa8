//! Issue 16 (data contract): every JSON result document has a JSON Schema generated from
//! the Rust type that writes it, committed under `docs/schemas/` and linked from
//! `docs/DATA_FORMAT.md`; the committed schemas are the current ones; and the documents
//! the commands really write follow their committed schema (checked by a small validator
//! of the keywords `schemars` emits, below) and are exactly their types (parsed into the
//! type and written back, nothing is lost or changed).
//!
//! Regenerate the schemas after changing a document type:
//! `AEROFORM_BLESS=1 cargo test --release --test e2e schemas::`, then commit `docs/schemas/`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use aeroelastic::documents::{BranchDoc, FlutterDoc, LcoDoc};
use aeroform::documents::{
    CoefficientColumn, IdentifyTiming, RunSummary, TunnelBlindSummary, TunnelForcedSummary,
    TunnelFreeSummary,
};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

const REGENERATE: &str =
    "regenerate them with `AEROFORM_BLESS=1 cargo test --release --test e2e schemas::` and commit docs/schemas/";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn schema_dir() -> PathBuf {
    root().join("docs/schemas")
}

/// The text a schema is committed as: pretty JSON and a final newline.
fn schema_text(schema: &Value) -> String {
    format!("{}\n", serde_json::to_string_pretty(schema).unwrap())
}

#[test]
fn schemas_are_current() {
    let bless = std::env::var_os("AEROFORM_BLESS").is_some();
    let dir = schema_dir();
    if bless {
        std::fs::create_dir_all(&dir).unwrap();
    }
    let mut stale = Vec::new();
    let mut generated = BTreeSet::new();
    for (name, schema) in aeroform::documents::schemas() {
        let file = format!("{name}.schema.json");
        let path = dir.join(&file);
        let text = schema_text(&schema);
        if bless {
            if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
                std::fs::write(&path, &text).unwrap();
                eprintln!("wrote {}", path.display());
            }
        } else if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
            stale.push(file.clone());
        }
        generated.insert(file);
    }
    let mut extra = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".schema.json") && !generated.contains(&name) {
            if bless {
                std::fs::remove_file(dir.join(&name)).unwrap();
                eprintln!("removed {name}");
            } else {
                extra.push(name);
            }
        }
    }
    assert!(
        stale.is_empty(),
        "docs/schemas/: {stale:?} differ from the schemas generated from the document types (or are missing); {REGENERATE}"
    );
    assert!(
        extra.is_empty(),
        "docs/schemas/: {extra:?} belong to no document type; {REGENERATE}"
    );
}

#[test]
fn every_schema_is_linked_from_data_format() {
    let text = std::fs::read_to_string(root().join("docs/DATA_FORMAT.md")).unwrap();
    for (name, schema) in aeroform::documents::schemas() {
        let link = format!("schemas/{name}.schema.json");
        assert!(
            text.contains(&link),
            "docs/DATA_FORMAT.md does not link {link}"
        );
        assert!(
            schema.get("description").is_some_and(Value::is_string),
            "{name}: the document type has no doc comment (no schema description)"
        );
    }
}

fn aeroform(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroform"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run aeroform");
    assert!(
        out.status.success(),
        "aeroform {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The first place where `a` and `b` differ, as a JSON path with both values.
fn first_difference(path: &str, a: &Value, b: &Value) -> Option<String> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: BTreeSet<&String> = x.keys().chain(y.keys()).collect();
            keys.into_iter().find_map(|k| {
                let p = format!("{path}.{k}");
                match (x.get(k), y.get(k)) {
                    (Some(u), Some(v)) => first_difference(&p, u, v),
                    (u, v) => Some(format!("{p}: written {u:?}, from the type {v:?}")),
                }
            })
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (u, v))| first_difference(&format!("{path}[{i}]"), u, v)),
        _ if a == b => None,
        _ => Some(format!("{path}: written {a}, from the type {b}")),
    }
}

/// Errors of `value` (at `path`) against `schema` (a node of `root`), for the subset of
/// JSON Schema 2020-12 that `schemars` generates. A keyword outside that subset fails the
/// test, so that a new kind of schema cannot pass unchecked.
fn validate(root: &Value, schema: &Value, value: &Value, path: &str, errors: &mut Vec<String>) {
    let obj = match schema {
        Value::Bool(true) => return,
        Value::Bool(false) => {
            errors.push(format!("{path}: no value is allowed here"));
            return;
        }
        Value::Object(o) => o,
        _ => panic!("{path}: schema node is not an object: {schema}"),
    };
    for (k, s) in obj {
        match k.as_str() {
            "$schema" | "title" | "description" | "$defs" | "format" | "default" | "examples"
            | "deprecated" | "readOnly" | "writeOnly" => {}
            "$ref" => {
                let r = s.as_str().unwrap();
                let target = root
                    .pointer(r.strip_prefix('#').expect("local $ref"))
                    .unwrap_or_else(|| panic!("{path}: dangling $ref {r}"));
                validate(root, target, value, path, errors);
            }
            "type" => {
                let types: Vec<&str> = match s {
                    Value::String(t) => vec![t.as_str()],
                    Value::Array(a) => a.iter().map(|t| t.as_str().unwrap()).collect(),
                    _ => panic!("bad type {s}"),
                };
                let ok = types.iter().any(|t| match *t {
                    "null" => value.is_null(),
                    "boolean" => value.is_boolean(),
                    "object" => value.is_object(),
                    "array" => value.is_array(),
                    "string" => value.is_string(),
                    "number" => value.is_number(),
                    "integer" => {
                        value.is_i64()
                            || value.is_u64()
                            || value.as_f64().is_some_and(|x| x.fract() == 0.0)
                    }
                    other => panic!("unknown type {other}"),
                });
                if !ok {
                    errors.push(format!("{path}: {value} is not of type {s}"));
                }
            }
            "properties" => {
                if let Value::Object(v) = value {
                    for (name, sub) in s.as_object().unwrap() {
                        if let Some(x) = v.get(name) {
                            validate(root, sub, x, &format!("{path}.{name}"), errors);
                        }
                    }
                }
            }
            "required" => {
                if let Value::Object(v) = value {
                    for name in s.as_array().unwrap() {
                        let name = name.as_str().unwrap();
                        if !v.contains_key(name) {
                            errors.push(format!("{path}: required field `{name}` missing"));
                        }
                    }
                }
            }
            "additionalProperties" => {
                if let Value::Object(v) = value {
                    let known = obj.get("properties").and_then(Value::as_object);
                    for (name, x) in v {
                        if !known.is_some_and(|p| p.contains_key(name)) {
                            validate(root, s, x, &format!("{path}.{name}"), errors);
                        }
                    }
                }
            }
            "items" => {
                if let Value::Array(v) = value {
                    let skip = obj
                        .get("prefixItems")
                        .and_then(Value::as_array)
                        .map_or(0, Vec::len);
                    for (i, x) in v.iter().enumerate().skip(skip) {
                        validate(root, s, x, &format!("{path}[{i}]"), errors);
                    }
                }
            }
            "prefixItems" => {
                if let Value::Array(v) = value {
                    for (i, (sub, x)) in s.as_array().unwrap().iter().zip(v).enumerate() {
                        validate(root, sub, x, &format!("{path}[{i}]"), errors);
                    }
                }
            }
            "minItems" | "maxItems" => {
                if let Value::Array(v) = value {
                    let n = s.as_u64().unwrap() as usize;
                    if (k == "minItems" && v.len() < n) || (k == "maxItems" && v.len() > n) {
                        errors.push(format!("{path}: {} items violates {k} = {n}", v.len()));
                    }
                }
            }
            "minimum" | "maximum" => {
                if let Some(x) = value.as_f64() {
                    let m = s.as_f64().unwrap();
                    if (k == "minimum" && x < m) || (k == "maximum" && x > m) {
                        errors.push(format!("{path}: {x} violates {k} = {m}"));
                    }
                }
            }
            "enum" => {
                if !s.as_array().unwrap().contains(value) {
                    errors.push(format!("{path}: {value} is not one of {s}"));
                }
            }
            "const" => {
                if s != value {
                    errors.push(format!("{path}: {value} is not {s}"));
                }
            }
            "anyOf" | "oneOf" => {
                let matching = s
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|sub| {
                        let mut e = Vec::new();
                        validate(root, sub, value, path, &mut e);
                        e.is_empty()
                    })
                    .count();
                if matching == 0 || (k == "oneOf" && matching > 1) {
                    errors.push(format!(
                        "{path}: {matching} of the {k} alternatives match {value}"
                    ));
                }
            }
            "allOf" => {
                for sub in s.as_array().unwrap() {
                    validate(root, sub, value, path, errors);
                }
            }
            other => panic!("{path}: the test's validator does not know the keyword `{other}`"),
        }
    }
}

/// `written` is valid against the committed schema `docs/schemas/<name>.schema.json`.
fn follows_schema(name: &str, what: &str, written: &Value) {
    let schema = read_value(&schema_dir().join(format!("{name}.schema.json")));
    let mut errors = Vec::new();
    validate(&schema, &schema, written, "$", &mut errors);
    assert!(
        errors.is_empty(),
        "{what} does not follow docs/schemas/{name}.schema.json: {errors:#?}"
    );
}

/// `written` follows the schema `schema` and parses into `T` (unknown fields are tolerated by the readers, so this alone
/// would not catch a field the type lacks) and serialises back to exactly `written`.
fn round_trips<T: Serialize + DeserializeOwned>(schema: &str, what: &str, written: &Value) -> T {
    follows_schema(schema, what, written);
    let typed: T = serde_json::from_value(written.clone())
        .unwrap_or_else(|e| panic!("{what}: not a document of its type: {e}"));
    let back = serde_json::to_value(&typed).unwrap();
    if let Some(d) = first_difference("$", written, &back) {
        panic!("{what}: the written document is not exactly its type: {d}");
    }
    typed
}

fn read_value(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn stdout_value(what: &str, stdout: &str) -> Value {
    serde_json::from_str(stdout)
        .unwrap_or_else(|e| panic!("{what} --json: not one JSON document ({e}):\n{stdout}"))
}

/// Runs the commands of the other end-to-end tests on `scenarios/` (virtual campaign →
/// identification with an ensemble → flutter, LCO run and sweep, branches with measured
/// points; the quickstart study; a blind set → diagnosis) and checks every JSON document
/// they write, on disk and on stdout, against its committed schema and its type.
#[test]
fn written_documents_follow_their_schemas_and_types() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let s = root().join("scenarios");
    let sc = |f: &str| s.join(f).to_str().unwrap().to_string();
    let (truth, rig) = (sc("plate-truth.model.toml"), sc("plate-rig.structure.toml"));

    let stdout = aeroform(
        d,
        &[
            "tunnel",
            "forced",
            "--model",
            &truth,
            "--campaign",
            "config=D",
            "--duration",
            "3",
            "--out",
            "forced",
            "--json",
        ],
    );
    round_trips::<TunnelForcedSummary>(
        "tunnel-forced-stdout",
        "tunnel forced",
        &stdout_value("tunnel forced", &stdout),
    );
    let stdout = aeroform(
        d,
        &[
            "tunnel",
            "free",
            "--structure",
            &rig,
            "--model",
            &truth,
            "--speeds",
            "5,7",
            "--duration",
            "3",
            "--out",
            "free",
            "--json",
        ],
    );
    round_trips::<TunnelFreeSummary>(
        "tunnel-free-stdout",
        "tunnel free",
        &stdout_value("tunnel free", &stdout),
    );

    let stdout = aeroform(
        d,
        &[
            "identify",
            "forced",
            "--out",
            "id",
            "--ensemble",
            "4",
            "--timing-json",
            "timing.json",
            "--json",
        ],
    );
    let id_path = d.join("id/identification.json");
    let id = identify::pipeline::Identification::read(&id_path).unwrap();
    assert!(id.ensemble.is_some());
    round_trips::<identify::pipeline::Identification>(
        "identification",
        "identification.json",
        &read_value(&id_path),
    );
    round_trips::<identify::pipeline::Identification>(
        "identification",
        "identify --json",
        &stdout_value("identify", &stdout),
    );
    round_trips::<IdentifyTiming>(
        "identify-timing",
        "timing.json",
        &read_value(&d.join("timing.json")),
    );

    let model = "id/identification.json";
    let stdout = aeroform(
        d,
        &[
            "flutter",
            "--structure",
            &rig,
            "--model",
            model,
            "--ensemble",
            "4",
            "--out",
            "fl",
            "--json",
        ],
    );
    let path = d.join("fl/flutter.json");
    let doc = FlutterDoc::read(&path).unwrap();
    assert!(doc.identified.is_some() && doc.ensemble.is_some());
    assert!(doc.critical.is_some());
    round_trips::<FlutterDoc>("flutter", "flutter.json", &read_value(&path));
    round_trips::<FlutterDoc>(
        "flutter",
        "flutter --json",
        &stdout_value("flutter", &stdout),
    );

    aeroform(
        d,
        &[
            "lco",
            "--structure",
            &rig,
            "--model",
            &truth,
            "--speed",
            "7",
            "--out",
            "lco-run",
            "--quiet",
        ],
    );
    let path = d.join("lco-run/lco.json");
    assert!(LcoDoc::read(&path).unwrap().run.is_some());
    round_trips::<LcoDoc>("lco", "lco.json (run)", &read_value(&path));
    let stdout = aeroform(
        d,
        &[
            "lco",
            "--structure",
            &rig,
            "--model",
            &truth,
            "--sweep",
            "6,7.5",
            "--out",
            "lco-sweep",
            "--json",
        ],
    );
    let path = d.join("lco-sweep/lco.json");
    let doc = LcoDoc::read(&path).unwrap();
    assert!(doc.sweep.is_some() && doc.hysteresis_speeds.is_some());
    round_trips::<LcoDoc>("lco", "lco.json (sweep)", &read_value(&path));
    round_trips::<LcoDoc>("lco", "lco --json", &stdout_value("lco", &stdout));

    aeroform(
        d,
        &[
            "branch",
            "--structure",
            &sc("bristol-spring1.structure.toml"),
            "--model",
            &sc("bristol-spring1.model.toml"),
            "--speeds",
            "10:20",
            "--max-points",
            "30",
            "--measured",
            &sc("bristol-spring1-lco-amplitudes.csv"),
            "--out",
            "br",
            "--quiet",
        ],
    );
    let path = d.join("br/branch.json");
    let doc = BranchDoc::read(&path).unwrap();
    assert!(!doc.branches.is_empty() && !doc.measured.is_empty());
    round_trips::<BranchDoc>("branch", "branch.json", &read_value(&path));

    let stdout = aeroform(d, &["run", "--out", "qs", "--json"]);
    round_trips::<RunSummary>("run-stdout", "run --json", &stdout_value("run", &stdout));
    let qs = d.join("qs");
    round_trips::<Vec<FlutterDoc>>(
        "study-flutter",
        "study flutter.json",
        &read_value(&qs.join("flutter.json")),
    );
    round_trips::<LcoDoc>("lco", "study lco.json", &read_value(&qs.join("lco.json")));
    round_trips::<identify::pipeline::Identification>(
        "identification",
        "study identification.json",
        &read_value(&qs.join("identification.json")),
    );
    round_trips::<Vec<CoefficientColumn>>(
        "coefficients.columns",
        "coefficients.columns.json",
        &read_value(&qs.join("coefficients.columns.json")),
    );

    let stdout = aeroform(
        d,
        &[
            "tunnel",
            "blind",
            "--effect",
            "none",
            "--strength",
            "0.5",
            "--out",
            "bl",
            "--json",
        ],
    );
    round_trips::<TunnelBlindSummary>(
        "tunnel-blind-stdout",
        "tunnel blind",
        &stdout_value("tunnel blind", &stdout),
    );
    aeroform(
        d,
        &[
            "diagnose",
            "bl/forced",
            "--free",
            "bl/free",
            "--out",
            "dg",
            "--quiet",
        ],
    );
    round_trips::<diagnose::report::Diagnosis>(
        "diagnosis",
        "diagnosis.json",
        &read_value(&d.join("dg/diagnosis.json")),
    );
}
