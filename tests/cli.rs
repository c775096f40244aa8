//! End-to-end tests of the `aeroform` binary: every class of bad input ends with a clear
//! error naming the place (never a panic), and the default study recovers its known law.

use std::path::{Path, PathBuf};

use crate::common;
use common::aeroform;

const MANIFEST: &str = r#"format = "aeroform-dataset/1"
name = "bad-input test"

[section]
chord = 0.25
span = 0.75
air_density = 1.225

[units]
heave = "mm"
pitch = "deg"
lift = "N"
moment = "N*m"

[[case]]
id = "D-U6-A12"
kind = "forced"
file = "cases/D-U6-A12.csv"
wind_speed = 6.0
config = "D"
freq_pitch = 2.0
freq_heave = 1.3
"#;

/// A valid two-frequency forced case (10 s at 512 Hz) as CSV text, linear forces.
fn case_csv(duration: f64) -> String {
    let mut s = String::from("t,h,alpha,lift,moment\n");
    let n = (512.0 * duration) as usize;
    for i in 0..n {
        let t = i as f64 / 512.0;
        let a = 12.0 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
        let h = 18.0 * (2.0 * std::f64::consts::PI * 1.3 * t).sin();
        let lift = -0.9 * a - 0.02 * h;
        let moment = 0.03 * a + 0.001 * h;
        s.push_str(&format!("{t},{h},{a},{lift},{moment}\n"));
    }
    s
}

/// Writes a data set folder with the given manifest and case CSV; returns its path.
fn dataset(dir: &Path, manifest: &str, csv: &str) -> PathBuf {
    let root = dir.join("ds");
    std::fs::create_dir_all(root.join("cases")).unwrap();
    std::fs::write(root.join("manifest.toml"), manifest).unwrap();
    std::fs::write(root.join("cases/D-U6-A12.csv"), csv).unwrap();
    root
}

/// Runs `aeroform identify` on a data set and returns stderr, asserting failure without panic.
fn identify_fails(root: &Path, extra: &[&str]) -> String {
    let out = root.parent().unwrap().join("out");
    let mut args = vec![
        "identify",
        root.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (ok, _, err) = aeroform(&args);
    assert!(!ok, "expected failure, stderr: {err}");
    assert!(!err.contains("panicked"), "panic on user input: {err}");
    assert!(
        !out.join("identification.json").exists(),
        "no result may be written on failure"
    );
    err
}

fn replace_line(csv: &str, line: usize, new: &str) -> String {
    csv.lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == line { new } else { l })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn valid_data_set_identifies() {
    let tmp = tempfile::tempdir().unwrap();
    let root = dataset(tmp.path(), MANIFEST, &case_csv(10.0));
    let out = tmp.path().join("out");
    let (ok, _, err) = aeroform(&[
        "identify",
        root.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(ok, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identification.json")).unwrap())
            .unwrap();
    assert_eq!(json["format"], "aeroform-identification/1");
    assert_eq!(json["library"]["rank"], 25);
}

#[test]
fn missing_column_names_file_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = case_csv(10.0)
        .lines()
        .map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n")
        .collect::<String>();
    let root = dataset(tmp.path(), MANIFEST, &csv);
    let err = identify_fails(&root, &[]);
    assert!(
        err.contains("D-U6-A12.csv") && err.contains("moment"),
        "{err}"
    );
}

#[test]
fn nan_names_file_line_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = replace_line(&case_csv(10.0), 101, "0.1953125,1.0,NaN,0.5,0.1");
    let root = dataset(tmp.path(), MANIFEST, &csv);
    let err = identify_fails(&root, &[]);
    assert!(
        err.contains("D-U6-A12.csv:101") && err.contains("alpha"),
        "{err}"
    );
}

#[test]
fn non_uniform_time_names_the_first_bad_row() {
    let tmp = tempfile::tempdir().unwrap();
    // Row 201 (line 202) jumps ahead by ten samples.
    let csv = case_csv(10.0);
    let lines: Vec<String> = csv
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i >= 201 {
                let (t, rest) = l.split_once(',').unwrap();
                format!("{},{rest}", t.parse::<f64>().unwrap() + 10.0 / 512.0)
            } else {
                l.to_string()
            }
        })
        .collect();
    let root = dataset(tmp.path(), MANIFEST, &lines.join("\n"));
    let err = identify_fails(&root, &[]);
    assert!(
        err.contains("D-U6-A12.csv:202") && err.contains("non-uniform"),
        "{err}"
    );
}

#[test]
fn unknown_manifest_key_names_key_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let manifest = MANIFEST.replace("wind_speed = 6.0", "wind_speed = 6.0\nwindspeed = 6.0");
    let root = dataset(tmp.path(), &manifest, &case_csv(10.0));
    let err = identify_fails(&root, &[]);
    assert!(
        err.contains("manifest.toml:20") && err.contains("windspeed"),
        "{err}"
    );
}

#[test]
fn unknown_unit_names_field_and_allowed_values() {
    let tmp = tempfile::tempdir().unwrap();
    let manifest = MANIFEST.replace("heave = \"mm\"", "heave = \"inch\"");
    let root = dataset(tmp.path(), &manifest, &case_csv(10.0));
    let err = identify_fails(&root, &[]);
    assert!(
        err.contains("manifest.toml:10") && err.contains("units.heave") && err.contains("mm"),
        "{err}"
    );
}

#[test]
fn record_shorter_than_a_forcing_period_names_the_case() {
    let tmp = tempfile::tempdir().unwrap();
    // 0.5 s: shorter than one period of the 1.3 Hz heave forcing.
    let root = dataset(tmp.path(), MANIFEST, &case_csv(0.5));
    let err = identify_fails(&root, &[]);
    assert!(err.contains("D-U6-A12") && err.contains("shorter"), "{err}");
}

#[test]
fn rank_deficiency_with_the_full_basis_names_the_dependencies() {
    let tmp = tempfile::tempdir().unwrap();
    let root = dataset(tmp.path(), MANIFEST, &case_csv(10.0));
    let err = identify_fails(&root, &["--basis", "full"]);
    assert!(
        err.contains("D-U6-A12") && err.contains("rank 25") && err.contains("alpha_dot^2*h"),
        "{err}"
    );
}

#[test]
fn missing_data_set_folder_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let err = identify_fails(&tmp.path().join("nope"), &[]);
    assert!(
        err.contains("nope") && err.contains("manifest.toml"),
        "{err}"
    );
}
