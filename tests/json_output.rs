//! Issue 16: `--json` on every command prints the command's result document on stdout and
//! nothing else there; `--quiet` prints nothing on stdout. Checked command by command on
//! one small chain (virtual campaign → identify → flutter / LCO / branch; study run → plot;
//! blind set → diagnose).

use std::path::Path;

use crate::common;
use common::aeroform_in as aeroform;

/// Runs `args` with `--json` (stdout must be exactly one JSON document, returned) and with
/// `--quiet` into a second folder (stdout must be empty).
fn json_and_quiet(dir: &Path, args: &[&str], out: &str) -> serde_json::Value {
    let mut a: Vec<&str> = args.to_vec();
    a.extend(["--out", out, "--json"]);
    let (ok, stdout, err) = aeroform(dir, &a);
    assert!(ok, "{args:?}: {err}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
        panic!("{args:?} --json: stdout is not one JSON document ({e}):\n{stdout}")
    });
    let quiet_out = format!("{out}-quiet");
    let mut q: Vec<&str> = args.to_vec();
    q.extend(["--out", &quiet_out, "--quiet"]);
    let (ok, stdout, err) = aeroform(dir, &q);
    assert!(ok, "{args:?} --quiet: {err}");
    assert_eq!(stdout, "", "{args:?} --quiet printed on stdout");
    v
}

#[test]
fn every_command_prints_its_document_with_json_and_nothing_with_quiet() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let s = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios");
    let truth = format!("{s}/plate-truth.model.toml");
    let rig = format!("{s}/plate-rig.structure.toml");
    let v = json_and_quiet(
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
        ],
        "forced",
    );
    assert_eq!(v["cases"], 64);
    assert_eq!(v["manifest"]["case"].as_array().unwrap().len(), 64);

    let v = json_and_quiet(d, &["identify", "forced"], "id");
    assert_eq!(v["format"], "aeroform-identification/1");
    // the document on stdout is the file's content
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("id/identification.json")).unwrap())
            .unwrap();
    assert_eq!(v, file);

    let model = "id/identification.json";
    let v = json_and_quiet(d, &["flutter", "--structure", &rig, "--model", model], "fl");
    assert!(v["analysis"]["flutter"]["u"].as_f64().unwrap() > 0.0, "{v}");
    let v = json_and_quiet(
        d,
        &[
            "lco",
            "--structure",
            &rig,
            "--model",
            &truth,
            "--speed",
            "7",
        ],
        "lco",
    );
    assert!(v.get("run").is_some(), "{v}");
    let v = json_and_quiet(
        d,
        &[
            "branch",
            "--structure",
            &format!("{s}/bristol-spring1.structure.toml"),
            "--model",
            &format!("{s}/bristol-spring1.model.toml"),
            "--speeds",
            "10:20",
            "--max-points",
            "30",
        ],
        "br",
    );
    assert_eq!(v["format"], "aeroform-branch/1");

    let v = json_and_quiet(d, &["run"], "qs");
    assert_eq!(v["study"], "quickstart");
    assert!(!v["figures"].as_array().unwrap().is_empty());
    let (ok, stdout, err) = aeroform(d, &["plot", "qs", "--json"]);
    assert!(ok, "{err}");
    let figs: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(figs, v["figures"]);
    let (ok, stdout, _) = aeroform(d, &["plot", "qs", "--quiet"]);
    assert!(ok && stdout.is_empty());

    let v = json_and_quiet(
        d,
        &["tunnel", "blind", "--effect", "none", "--strength", "0.5"],
        "bl",
    );
    assert_eq!(v["forced_cases"], 40);
    let v = json_and_quiet(d, &["diagnose", "bl/forced", "--free", "bl/free"], "dg");
    assert!(v["verdict"]["effect"].is_string(), "{v}");
}
