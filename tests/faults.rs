//! Faults around study runs: an unwritable output folder and an interrupted run leave no
//! half-written result (every file is complete or absent).

use std::path::Path;
use std::process::Command;
use std::time::Duration;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroform"))
}

fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else {
                out.push(p);
            }
        }
    }
}

/// Every file is complete: JSON parses, PNG has its end chunk, SVG closes, no temporary file.
fn assert_complete(dir: &Path) {
    let mut files = Vec::new();
    walk(dir, &mut files);
    for f in files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            !name.ends_with(".tmp"),
            "temporary file left: {}",
            f.display()
        );
        let bytes = std::fs::read(&f).unwrap();
        match f.extension().and_then(|e| e.to_str()) {
            Some("json") => {
                serde_json::from_slice::<serde_json::Value>(&bytes)
                    .unwrap_or_else(|e| panic!("{}: incomplete JSON: {e}", f.display()));
            }
            Some("png") => assert!(
                bytes.len() > 12 && &bytes[bytes.len() - 8..bytes.len() - 4] == b"IEND",
                "{}: incomplete PNG",
                f.display()
            ),
            Some("svg") => assert!(
                String::from_utf8_lossy(&bytes)
                    .trim_end()
                    .ends_with("</svg>"),
                "{}: incomplete SVG",
                f.display()
            ),
            Some("html") => assert!(
                String::from_utf8_lossy(&bytes)
                    .trim_end()
                    .ends_with("</html>"),
                "{}: incomplete HTML",
                f.display()
            ),
            _ => {}
        }
    }
}

#[test]
fn unwritable_output_folder_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let out = file.join("sub");
    let o = bin()
        .args(["run", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("a-file"), "{err}");
    assert_eq!(std::fs::read(&file).unwrap(), b"x", "nothing overwritten");
}

/// SIGINT at several moments of a paper-campaign run (≈ 4 s): whatever was written is complete.
#[test]
fn interrupted_run_leaves_only_complete_files() {
    let study = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/paper-campaign.toml");
    for delay_ms in [300_u64, 1500, 3000] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let mut child = bin()
            .args(["run", study, "--out", out.to_str().unwrap(), "--quiet"])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        let _ = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status();
        let _ = child.wait();
        assert_complete(&out);
    }
}

// ---------------------------------------------------------------------------------------
// Faults of `aeroform identify`, `lco` and `flutter` (issue 6, item 4). Each test checks the
// file system afterwards: every result file is complete or absent, no temporary file.

const SCENARIOS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios");

const MANIFEST_HEAD: &str = r#"format = "aeroform-dataset/1"
name = "fault test"

[section]
chord = 0.25
span = 0.75
air_density = 1.225

[units]
heave = "mm"
pitch = "deg"
lift = "N"
moment = "N*m"
"#;

const ONE_CASE: &str = r#"
[[case]]
id = "D-U6-A12"
kind = "forced"
file = "cases/D-U6-A12.csv"
wind_speed = 6.0
config = "D"
freq_pitch = 2.0
freq_heave = 1.3
"#;

/// Writes `rows` rows of a two-frequency forced case (512 Hz, linear forces) to `w`.
fn write_case_rows(w: &mut impl std::io::Write, rows: usize) {
    writeln!(w, "t,h,alpha,lift,moment").unwrap();
    let tau = 2.0 * std::f64::consts::PI;
    for i in 0..rows {
        let t = i as f64 / 512.0;
        let a = 12.0 * (tau * 2.0 * t).sin();
        let h = 18.0 * (tau * 1.3 * t).sin();
        let lift = -0.9 * a - 0.02 * h + 1e-3 * ((i * 7919) % 1000) as f64 / 1000.0;
        let moment = 0.03 * a + 0.001 * h;
        writeln!(w, "{t},{h},{a},{lift},{moment}").unwrap();
    }
}

/// A data set folder `dir/ds` with one forced case of `rows` rows.
fn one_case_dataset(dir: &Path, rows: usize) -> std::path::PathBuf {
    let root = dir.join("ds");
    std::fs::create_dir_all(root.join("cases")).unwrap();
    std::fs::write(
        root.join("manifest.toml"),
        format!("{MANIFEST_HEAD}{ONE_CASE}"),
    )
    .unwrap();
    let f = std::fs::File::create(root.join("cases/D-U6-A12.csv")).unwrap();
    let mut w = std::io::BufWriter::new(f);
    write_case_rows(&mut w, rows);
    std::io::Write::flush(&mut w).unwrap();
    root
}

/// Runs a command line through `sh -c` after `prelude` (e.g. `ulimit -f 8`), capturing
/// (success, stdout, stderr).
fn sh(prelude: &str, args: &[&str]) -> (bool, String, String) {
    let mut line = format!("{prelude}; exec '{}'", env!("CARGO_BIN_EXE_aeroform"));
    for a in args {
        line.push_str(&format!(" '{a}'"));
    }
    let o = Command::new("sh").args(["-c", &line]).output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut files = Vec::new();
    walk(dir, &mut files);
    let mut names: Vec<String> = files
        .iter()
        .map(|f| f.strip_prefix(dir).unwrap().display().to_string())
        .collect();
    names.sort();
    names
}

#[test]
fn identify_into_a_path_blocked_by_a_file_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let root = one_case_dataset(tmp.path(), 5120);
    let file = tmp.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let out = file.join("out");
    let o = bin()
        .args([
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("cannot create output folder") && err.contains("a-file"),
        "{err}"
    );
    assert_eq!(std::fs::read(&file).unwrap(), b"x", "nothing overwritten");
}

/// The final rename fails (a folder sits where `identification.json` goes) after the whole
/// identification ran: clear error naming the file, the temporary file removed, the
/// folder untouched. (Tests run as root here, so permission bits cannot make a folder
/// unwritable; this is the late-failure path of `write_atomic`.)
#[test]
fn identify_whose_result_cannot_be_renamed_into_place_leaves_no_partial_file() {
    let tmp = tempfile::tempdir().unwrap();
    let root = one_case_dataset(tmp.path(), 5120);
    let out = tmp.path().join("out");
    std::fs::create_dir_all(out.join("identification.json/keep")).unwrap();
    let o = bin()
        .args([
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("identification.json"), "{err}");
    assert_eq!(
        files_in(&out),
        Vec::<String>::new(),
        "only the blocking folder remains"
    );
    assert!(out.join("identification.json/keep").is_dir());
}

/// A full output device, simulated with RLIMIT_FSIZE (`ulimit -f`, 512-byte blocks) and
/// SIGXFSZ ignored so that a write past the limit fails with EFBIG as on a full disk:
/// `identify` writes ≈ 8 kB of JSON for this case, the limit is 4 blocks (2 kB with dash's
/// 512-byte blocks, 4 kB with 1 kB blocks). The run fails with a message
/// naming the file and the cause; no result file and no temporary file remain.
#[test]
fn identify_into_a_full_output_folder_leaves_no_partial_file() {
    let tmp = tempfile::tempdir().unwrap();
    let root = one_case_dataset(tmp.path(), 5120);
    let out = tmp.path().join("out");
    let (ok, _, err) = sh(
        "trap '' XFSZ; ulimit -f 4",
        &[
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    assert!(!ok, "expected failure");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("identification.json") && err.contains("too large"),
        "{err}"
    );
    assert_eq!(files_in(&out), Vec::<String>::new());
    // Same data set without the limit: the result is written, so the limit was the cause.
    let (ok, _, err) = sh(
        "true",
        &[
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    assert!(ok, "{err}");
    let len = std::fs::metadata(out.join("identification.json"))
        .unwrap()
        .len();
    assert!(
        len > 4 * 1024,
        "result of {len} bytes fits under the limit: test is void"
    );
}

/// A whole study (`aeroform run`, quickstart: JSON, CSV, PNG, SVG, HTML) with a 64 kB file
/// limit: small files are written, the first larger one fails; the run stops with a clear
/// message and every file present is complete.
#[test]
fn study_into_a_full_output_folder_leaves_only_complete_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (ok, _, err) = sh(
        "trap '' XFSZ; ulimit -f 128",
        &["run", "--out", out.to_str().unwrap(), "--quiet"],
    );
    assert!(!ok, "expected failure (some output exceeds 64 kB)");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("too large"), "{err}");
    assert_complete(&out);
}

#[test]
fn manifest_without_cases_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("ds");
    std::fs::create_dir_all(&root).unwrap();
    std::fs::write(root.join("manifest.toml"), MANIFEST_HEAD).unwrap();
    let out = tmp.path().join("out");
    let o = bin()
        .args([
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("manifest.toml") && err.contains("case"),
        "{err}"
    );
    assert_eq!(files_in(&out), Vec::<String>::new());
}

#[test]
fn case_with_zero_rows_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let root = one_case_dataset(tmp.path(), 0);
    let out = tmp.path().join("out");
    let o = bin()
        .args([
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("D-U6-A12.csv") && err.contains("0 data rows"),
        "{err}"
    );
    assert_eq!(files_in(&out), Vec::<String>::new());
    // An empty file (no header either).
    std::fs::write(root.join("cases/D-U6-A12.csv"), b"").unwrap();
    let o = bin()
        .args([
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("D-U6-A12.csv:1") && err.contains("header"),
        "{err}"
    );
    assert_eq!(files_in(&out), Vec::<String>::new());
}

/// A data set whose only case is free response: nothing to identify, clear error.
#[test]
fn data_set_without_forced_cases_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let root = one_case_dataset(tmp.path(), 1024);
    let manifest = format!("{MANIFEST_HEAD}{ONE_CASE}").replace("kind = \"forced\"", "kind = \"free\"")
        + "\n[structure]\nmass = 1.0\ninertia = 0.005\nstatic_unbalance = 0.0\nfreq_heave = 2.0\nfreq_pitch = 3.0\ndamping_heave = 0.005\ndamping_pitch = 0.005\n";
    // [structure] must precede [[case]] only by TOML rules for the top-level keys; tables
    // may come in any order.
    std::fs::write(root.join("manifest.toml"), manifest).unwrap();
    let out = tmp.path().join("out");
    let o = bin()
        .args([
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("no forced-motion case"), "{err}");
    assert_eq!(files_in(&out), Vec::<String>::new());
}

/// A linear model (Theodorsen, no nonlinear term) above its flutter speed (≈ 6.6 m/s on
/// the plate rig) has no limit cycle: the run ends, classified divergent, with the time it
/// left the bound; `lco.json` is complete and says so.
#[test]
fn lco_above_flutter_with_a_linear_model_ends_classified_divergent() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("linear.model.toml");
    std::fs::write(
        &model,
        "kind = \"theodorsen\"\nchord = 0.25\nelastic_axis = -0.3\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let structure = format!("{SCENARIOS}/plate-rig.structure.toml");
    let o = bin()
        .args([
            "lco",
            "--structure",
            &structure,
            "--model",
            model.to_str().unwrap(),
            "--speed",
            "8.0",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(o.status.success(), "{err}");
    assert!(
        stdout.contains("divergent (left the bound at t ="),
        "{stdout}"
    );
    assert_complete(&out);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("lco.json")).unwrap()).unwrap();
    let text = json["run"].to_string();
    assert!(text.contains("ivergent"), "{text}");
}

/// A flutter scan below the flutter speed: "none" in the message, `critical: null` in a
/// complete `flutter.json`.
#[test]
fn flutter_scan_without_flutter_in_range_says_none() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let structure = format!("{SCENARIOS}/plate-rig.structure.toml");
    let model = format!("{SCENARIOS}/plate-truth.model.toml");
    let o = bin()
        .args([
            "flutter",
            "--structure",
            &structure,
            "--model",
            &model,
            "--speeds",
            "1:5:12",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(o.status.success(), "{err}");
    assert!(
        stdout.contains("flutter: none between 1 and 5 m/s"),
        "{stdout}"
    );
    assert_complete(&out);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("flutter.json")).unwrap()).unwrap();
    assert!(json["critical"].is_null(), "{}", json["critical"]);
}

/// One very long case through the CLI with an address-space limit: identified, or a clear
/// error; either way no partial file. `rows` rows at 512 Hz.
fn long_case(rows: usize, limit_mb: usize) {
    let tmp = tempfile::tempdir().unwrap();
    let root = one_case_dataset(tmp.path(), rows);
    let out = tmp.path().join("out");
    let csv_bytes = std::fs::metadata(root.join("cases/D-U6-A12.csv"))
        .unwrap()
        .len();
    let (ok, stdout, err) = sh(
        &format!("ulimit -v {}", limit_mb * 1024),
        &[
            "identify",
            root.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    eprintln!(
        "{rows} rows ({csv_bytes} bytes of CSV), limit {limit_mb} MB: ok = {ok}\n{stdout}{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        ok,
        "{rows} rows under a {limit_mb} MB address-space limit: {err}"
    );
    assert_complete(&out);
    let id: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("identification.json")).unwrap()).unwrap();
    assert_eq!(id["cases"][0]["id"], "D-U6-A12");
}

/// 1 million rows (33 min at 512 Hz, ≈ 80 MB of CSV) identified under a 2 GB address-space
/// limit.
#[test]
fn one_million_row_case_is_identified_within_bounded_memory() {
    long_case(1_000_000, 2048);
}

/// 10 million rows (≈ 900 MB of CSV, 400 MB of raw values: 8 B × 5 columns; slow: ≈ 1 min
/// to write the file) identified under an address-space limit of 1200 MB = 3× the raw
/// values (docs/SCALE.md: peak RSS ≈ 2.3× raw once Θ and the harmonic basis are evaluated
/// in row blocks; before, 7.9 GB = 20× raw).
#[test]
#[ignore]
fn ten_million_row_case_is_identified_within_bounded_memory() {
    long_case(10_000_000, 1200);
}
