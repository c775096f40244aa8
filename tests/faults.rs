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
    // U_D (10.8 m/s, the static stiffness's root) lies beyond the scan: said so
    assert!(
        stdout.contains("divergence: U_D = 10.80")
            && stdout.contains("outside the scanned 1–5 m/s"),
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

// ---------------------------------------------------------------------------------------
// Issue 13 (part A): complete-or-absent output folders, bounded inputs, exit codes.

/// Exit code, stdout, stderr of `aeroform ARGS` (run in `cwd`).
fn code_of(args: &[&str], cwd: &Path) -> (i32, String, String) {
    let o = bin().args(args).current_dir(cwd).output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A PID that belonged to a process which has ended.
fn dead_pid() -> u32 {
    let mut c = Command::new("true").spawn().unwrap();
    let pid = c.id();
    c.wait().unwrap();
    pid
}

const MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/plate-truth.model.toml"
);
const STRUCTURE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/plate-rig.structure.toml"
);

/// The issue's list of absurd inputs (and a few more of each class): every one ends with
/// exit code 1 or 2 (never 101 = panic, 134 = allocation abort), within seconds, with a
/// message naming the flag, key or field; no output folder is left behind.
#[test]
fn absurd_inputs_exit_with_1_or_2_and_name_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let ds = one_case_dataset(dir, 1024);
    let ds_s = ds.to_str().unwrap().to_string();
    let manifest = std::fs::read_to_string(ds.join("manifest.toml")).unwrap();
    let csv = std::fs::read_to_string(ds.join("cases/D-U6-A12.csv")).unwrap();
    // data-set variants: one bad number each
    let variant = |name: &str, manifest: &str, csv: &str| -> String {
        let root = dir.join(name);
        std::fs::create_dir_all(root.join("cases")).unwrap();
        std::fs::write(root.join("manifest.toml"), manifest).unwrap();
        std::fs::write(root.join("cases/D-U6-A12.csv"), csv).unwrap();
        root.to_str().unwrap().to_string()
    };
    let wind = variant(
        "wind",
        &manifest.replace("wind_speed = 6.0", "wind_speed = 1e308"),
        &csv,
    );
    let nyq = variant(
        "nyquist",
        &manifest.replace("freq_pitch = 2.0", "freq_pitch = 1e6"),
        &csv,
    );
    // issue 27 row 16: a declared forcing frequency 10× the record's own
    let tenx = variant(
        "tenx",
        &manifest.replace("freq_pitch = 2.0", "freq_pitch = 20.0"),
        &csv,
    );
    let mut lines: Vec<String> = csv.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[10].split(',').map(String::from).collect();
    cells[3] = "1e308".into();
    lines[10] = cells.join(",");
    let huge = variant("huge", &manifest, &(lines.join("\n") + "\n"));
    // study variants
    let study = |name: &str, body: &str| -> String {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(&p, format!("name = \"{name}\"\n{body}")).unwrap();
        p.to_str().unwrap().to_string()
    };
    let synth = "[data.synthetic]\namplitudes_deg = [12.0]\nspeeds = [6.0]\n\
                 [[data.synthetic.config]]\nname = \"D\"\nfreq_pitch = 2.0\n\
                 freq_heave = 1.3\nmm_per_deg = 1.5\n";
    let hp1 = "[structure]\nmu = 20.0\nr_alpha2 = 0.24\nsigma = 0.4\nx_alpha = 0.1\n\
               [aero]\nmodel = \"theodorsen\"\nelastic_axis = nan\n\
               [flutter]\nu_min = 0.5\nu_max = 3.0\n";
    let s_duration = study(
        "dur",
        &synth.replace("speeds = [6.0]", "speeds = [6.0]\nduration = 1e300"),
    );
    let s_rate = study(
        "rate",
        &synth.replace("speeds = [6.0]", "speeds = [6.0]\nrate = 1e12"),
    );
    let s_dur9 = study(
        "dur9",
        &synth.replace("speeds = [6.0]", "speeds = [6.0]\nduration = 1e9"),
    );
    let s_speed = study(
        "speed",
        &synth.replace("speeds = [6.0]", "speeds = [6.0, 1e308]"),
    );
    let s_axis = study("axis", hp1);
    let s_nspeeds = study(
        "nspeeds",
        &hp1.replace("nan", "0.0").replace(
            "u_max = 3.0",
            "u_max = 3.0\nn_speeds = 18446744073709551615",
        ),
    );
    let s_series = study(
        "series",
        &format!("{synth}[outputs]\nseries_cases = [\"nope\"]\n"),
    );
    let s_virtual = study(
        "virt",
        "[data.virtual]\nmodel = \"m.toml\"\nduration = 1e300\n",
    );
    let s_table = study("tiv", "[data.table_iv]\nrepeats = 18446744073709551615\n");
    let s_table_rate = study("tivr", "[data.table_iv]\nrepeats = 2\nrate = 1e12\n");
    // issue 27 row 14: physical bounds of structure, model and sweep files
    let file = |name: &str, body: String| -> String {
        let p = dir.join(name);
        std::fs::write(&p, body).unwrap();
        p.to_str().unwrap().to_string()
    };
    let structure_text = std::fs::read_to_string(STRUCTURE).unwrap();
    let model_text = std::fs::read_to_string(MODEL).unwrap();
    let dense_air = file(
        "dense.structure.toml",
        format!(
            "air_density = 1e6\n{}",
            structure_text.replace("air_density", "# air_density")
        ),
    );
    let far_axis = file(
        "far.model.toml",
        model_text.replace("elastic_axis = -0.3", "elastic_axis = 100"),
    );
    let sweep = |name: &str, extra: &str| -> String {
        file(
            name,
            format!(
                "{{\"kind\":\"flutter_map\",\"structure\":\"{STRUCTURE}\",\"model\":\"{MODEL}\",\
                 \"speeds\":[1.0,2.0],\"grid\":{{\"mu\":[20.0]}}{extra}}}"
            ),
        )
    };
    let sweep_alpha = sweep("alpha.json", ",\"lco_speeds\":[5.0],\"alpha0\":1e9");
    let sweep_lco = sweep("lco.json", ",\"lco_speeds\":[1e9]");
    let out = dir.join("out");
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "flutter",
                "--structure",
                &dense_air,
                "--model",
                MODEL,
                "--out",
                o,
            ],
            "air_density",
        ),
        (
            vec![
                "flutter",
                "--structure",
                STRUCTURE,
                "--model",
                &far_axis,
                "--out",
                o,
            ],
            "elastic_axis",
        ),
        (vec!["sweep", &sweep_alpha, "--out", o], "alpha0"),
        (vec!["sweep", &sweep_lco, "--out", o], "lco_speeds"),
        (
            vec![
                "flutter",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--speeds",
                "1:20:18446744073709551615",
                "--out",
                o,
            ],
            "--speeds",
        ),
        (
            vec![
                "flutter",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--speeds",
                "1:20:1000000000",
                "--out",
                o,
            ],
            "--speeds",
        ),
        (
            vec![
                "flutter",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--speeds",
                "1:1e308:5",
                "--out",
                o,
            ],
            "--speeds",
        ),
        (
            vec![
                "tunnel",
                "forced",
                "--model",
                MODEL,
                "--duration",
                "1e300",
                "--out",
                o,
            ],
            "--duration",
        ),
        (
            vec![
                "tunnel",
                "forced",
                "--model",
                MODEL,
                "--duration",
                "1e9",
                "--out",
                o,
            ],
            "--duration",
        ),
        (
            vec![
                "tunnel",
                "forced",
                "--model",
                MODEL,
                "--duration",
                "100000",
                "--out",
                o,
            ],
            "--duration",
        ),
        (
            vec![
                "tunnel",
                "forced",
                "--model",
                MODEL,
                "--duration",
                "nan",
                "--out",
                o,
            ],
            "--duration",
        ),
        (
            vec![
                "tunnel",
                "free",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--speeds",
                "5:8:18446744073709551615",
                "--out",
                o,
            ],
            "--speeds",
        ),
        (
            vec![
                "tunnel",
                "free",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--speeds",
                "5,8",
                "--duration",
                "1e300",
                "--out",
                o,
            ],
            "--duration",
        ),
        (
            vec![
                "tunnel",
                "blind",
                "--effect",
                "none",
                "--strength",
                "1e308",
                "--out",
                o,
            ],
            "--strength",
        ),
        (
            vec!["diagnose", "--blind", "18446744073709551615", "--out", o],
            "--blind",
        ),
        (
            vec![
                "diagnose",
                "--blind",
                "340282366920938463463374607431768211456",
                "--out",
                o,
            ],
            "--blind",
        ),
        (
            vec![
                "lco",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--speed",
                "1e308",
                "--out",
                o,
            ],
            "--speed",
        ),
        (
            vec![
                "lco",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--sweep",
                "1:9:99999999999",
                "--out",
                o,
            ],
            "--sweep",
        ),
        (
            vec![
                "lco",
                "--structure",
                STRUCTURE,
                "--model",
                MODEL,
                "--speed",
                "5",
                "--alpha0",
                "1e300",
                "--out",
                o,
            ],
            "--alpha0",
        ),
        (
            vec![
                "identify",
                &ds_s,
                "--n-delta",
                "18446744073709551615",
                "--out",
                o,
            ],
            "n_delta",
        ),
        (
            vec![
                "identify",
                &ds_s,
                "--k-key",
                "18446744073709551615",
                "--out",
                o,
            ],
            "k_key",
        ),
        (vec!["identify", &wind, "--out", o], "wind_speed"),
        (vec!["identify", &nyq, "--out", o], "freq_pitch"),
        (vec!["identify", &tenx, "--out", o], "freq_pitch"),
        (vec!["identify", &huge, "--out", o], "lift"),
        (
            vec!["run", &s_duration, "--out", o],
            "data.synthetic.duration",
        ),
        (vec!["run", &s_rate, "--out", o], "data.synthetic.rate"),
        (vec!["run", &s_dur9, "--out", o], "data.synthetic.duration"),
        (vec!["run", &s_speed, "--out", o], "data.synthetic.speeds"),
        (vec!["run", &s_axis, "--out", o], "aero.elastic_axis"),
        (vec!["run", &s_nspeeds, "--out", o], "n_speeds"),
        (vec!["run", &s_series, "--out", o], "outputs.series_cases"),
        (vec!["run", &s_virtual, "--out", o], "data.virtual.duration"),
        (vec!["run", &s_table, "--out", o], "data.table_iv.repeats"),
        (vec!["run", &s_table_rate, "--out", o], "data.table_iv.rate"),
    ];
    for (args, field) in &cases {
        let t = std::time::Instant::now();
        let (code, _, err) = code_of(args, dir);
        assert!(code == 1 || code == 2, "exit {code} for {args:?}:\n{err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(
            err.contains(field),
            "{args:?}: message does not name `{field}`:\n{err}"
        );
        assert!(
            t.elapsed().as_secs() < 20,
            "{args:?} took {:?}",
            t.elapsed()
        );
        assert!(!out.exists(), "{args:?} left {}", out.display());
    }
    // the CSV error names file, line and column
    let (_, _, err) = code_of(&["identify", &huge, "--out", o], dir);
    assert!(
        err.contains("D-U6-A12.csv:11") && err.contains("`lift`"),
        "{err}"
    );
    // input errors are usage errors
    let (code, _, err) = code_of(&["run", &s_axis, "--out", o], dir);
    assert_eq!(code, 2, "{err}");
}

/// A re-run into an existing aeroform folder replaces it as a whole (with `--force` when a
/// file its marker does not list was added): no file of the first run survives (a stale file is gone, the manifest and every CSV come from the second
/// run), and the folder carries the completion marker.
#[test]
fn rerun_replaces_the_folder_as_a_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ds");
    let o = out.to_str().unwrap();
    let args = |seed: &'static str| {
        vec![
            "tunnel",
            "forced",
            "--model",
            MODEL,
            "--campaign",
            "config=D",
            "--duration",
            "1",
            "--seed",
            seed,
            "--out",
            o,
        ]
    };
    let (code, _, err) = code_of(&args("7"), tmp.path());
    assert_eq!(code, 0, "{err}");
    std::fs::write(out.join("stale-figure.svg"), b"<svg></svg>").unwrap();
    let first = std::fs::read(out.join("cases/D-U6-A12.csv")).ok();
    // a file its completion marker does not list is someone's: refused, kept (issue 39,
    // row 2a), unless `--force`, which replaces the folder as a whole
    let (code, _, err) = code_of(&args("1"), tmp.path());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("stale-figure.svg"), "{err}");
    assert!(out.join("stale-figure.svg").exists());
    let mut forced = args("1");
    forced.push("--force");
    let (code, _, err) = code_of(&forced, tmp.path());
    assert_eq!(code, 0, "{err}");
    assert!(
        !out.join("stale-figure.svg").exists(),
        "stale file of the first run"
    );
    assert!(out.join(".aeroform-complete").is_file());
    assert!(!out.join(".aeroform-incomplete").exists());
    let manifest = std::fs::read_to_string(out.join("manifest.toml")).unwrap();
    assert!(
        !manifest.contains("\"7\""),
        "seed of the first run in the manifest"
    );
    if let Some(first) = first {
        assert_ne!(
            std::fs::read(out.join("cases/D-U6-A12.csv")).ok(),
            Some(first)
        );
    }
    // nothing but the folder itself next to it (no staging, no lock)
    let names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["ds".to_string()], "{names:?}");
    // the data set reads
    let (code, _, err) = code_of(
        &[
            "identify",
            o,
            "--out",
            tmp.path().join("id").to_str().unwrap(),
            "--quiet",
        ],
        tmp.path(),
    );
    assert_eq!(code, 0, "{err}");
}

/// An existing folder that aeroform did not write is never mixed into: refused with exit
/// 2 (files untouched) unless `--force`, which replaces it whole. `--out .` is refused.
#[test]
fn foreign_folder_is_refused_unless_forced() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep.txt"), b"mine").unwrap();
    let mut args = vec![
        "tunnel",
        "blind",
        "--effect",
        "none",
        "--out",
        out.to_str().unwrap(),
    ];
    let (code, _, err) = code_of(&args, tmp.path());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--force") && err.contains("mine"), "{err}");
    assert_eq!(std::fs::read(out.join("keep.txt")).unwrap(), b"mine");
    let (code, _, err) = code_of(&["tunnel", "blind", "--effect", "none", "--out", "."], &out);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("working directory"), "{err}");
    args.push("--force");
    let (code, _, err) = code_of(&args, tmp.path());
    assert_eq!(code, 0, "{err}");
    assert!(!out.join("keep.txt").exists());
    assert!(out.join("truth.json").is_file() && out.join(".aeroform-complete").is_file());
}

/// A run that fails late (a series case that does not exist, found once the data are
/// built) leaves no output folder and no work folder.
#[test]
fn failed_run_leaves_no_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("s.toml");
    std::fs::write(
        &p,
        "name = \"late\"\n[data.synthetic]\namplitudes_deg = [12.0]\nspeeds = [6.0]\n\
         duration = 4.0\n[[data.synthetic.config]]\nname = \"D\"\nfreq_pitch = 2.0\n\
         freq_heave = 1.3\nmm_per_deg = 1.5\n[outputs]\nseries_cases = [\"nope\"]\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (code, _, err) = code_of(
        &["run", p.to_str().unwrap(), "--out", out.to_str().unwrap()],
        tmp.path(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("series_cases") && err.contains("nope"),
        "{err}"
    );
    let names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["s.toml".to_string()], "{names:?}");
}

/// Waits until a staging folder of `name` appears in `parent` holding at least `files`
/// entries; returns it.
fn wait_for_staging(parent: &Path, name: &str, files: usize) -> std::path::PathBuf {
    let t = std::time::Instant::now();
    loop {
        if let Ok(rd) = std::fs::read_dir(parent) {
            for e in rd.flatten() {
                let n = e.file_name().to_string_lossy().into_owned();
                if n.starts_with(&format!(".{name}.aeroform-staging.")) {
                    let mut all = Vec::new();
                    walk(&e.path(), &mut all);
                    if all.len() >= files {
                        return e.path();
                    }
                }
            }
        }
        assert!(t.elapsed().as_secs() < 60, "no staging folder appeared");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// SIGKILL in the middle of writing a data set: the previous data set stays whole, the
/// leftover staging folder is refused by `identify`, `diagnose` and `plot`, and the next
/// command removes it (and takes over the dead process's lock).
#[test]
fn killed_run_leaves_a_folder_no_reader_accepts_and_the_next_run_cleans_it() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ds");
    let o = out.to_str().unwrap();
    let (code, _, err) = code_of(
        &[
            "tunnel",
            "forced",
            "--model",
            MODEL,
            "--campaign",
            "config=D",
            "--duration",
            "0.3",
            "--out",
            o,
        ],
        tmp.path(),
    );
    assert_eq!(code, 0, "{err}");
    let before = files_in(&out);
    let mut child = bin()
        .args([
            "tunnel",
            "forced",
            "--model",
            MODEL,
            "--duration",
            "4",
            "--seed",
            "9",
            "--out",
            o,
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // the campaign is generated in memory, then written: wait for the first case files
    let staging = wait_for_staging(tmp.path(), "ds", 4);
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(files_in(&out), before, "the previous data set changed");
    for args in [
        vec![
            "identify",
            staging.to_str().unwrap(),
            "--out",
            tmp.path().join("id").to_str().unwrap(),
        ],
        vec![
            "diagnose",
            staging.to_str().unwrap(),
            "--out",
            tmp.path().join("dg").to_str().unwrap(),
        ],
        vec!["plot", staging.to_str().unwrap()],
    ] {
        let (code, _, err) = code_of(&args, tmp.path());
        assert_eq!(code, 2, "{args:?} accepted an unfinished folder: {err}");
        assert!(err.contains("work folder"), "{err}");
    }
    // the same folder renamed to an ordinary name still carries the incomplete-marker
    let renamed = tmp.path().join("renamed");
    std::fs::rename(&staging, &renamed).unwrap();
    let (code, _, err) = code_of(
        &[
            "identify",
            renamed.to_str().unwrap(),
            "--out",
            tmp.path().join("id").to_str().unwrap(),
        ],
        tmp.path(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("did not finish"), "{err}");
    std::fs::rename(&renamed, &staging).unwrap();
    let (code, _, err) = code_of(
        &[
            "tunnel",
            "forced",
            "--model",
            MODEL,
            "--campaign",
            "config=D",
            "--duration",
            "0.3",
            "--seed",
            "2",
            "--out",
            o,
        ],
        tmp.path(),
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("taking over the stale lock"), "{err}");
    assert!(err.contains("no longer runs"), "{err}");
    assert!(!staging.exists(), "stale staging folder kept");
}

/// SIGINT while a folder is written: exit 130, the staging folder and the lock removed,
/// the previous results intact, and a symbolic link planted inside the staging folder
/// (to a folder outside) is removed as a link: its target is untouched.
#[test]
fn interrupted_folder_write_keeps_the_previous_results_and_follows_no_link() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ds");
    let o = out.to_str().unwrap();
    let (code, _, err) = code_of(
        &[
            "tunnel",
            "forced",
            "--model",
            MODEL,
            "--campaign",
            "config=D",
            "--duration",
            "0.3",
            "--out",
            o,
        ],
        tmp.path(),
    );
    assert_eq!(code, 0, "{err}");
    let before = files_in(&out);
    let outside = tmp.path().join("outside");
    std::fs::create_dir(&outside).unwrap();
    std::fs::write(outside.join(".x.1.tmp"), b"keep").unwrap();
    let child = bin()
        .args([
            "tunnel",
            "forced",
            "--model",
            MODEL,
            "--duration",
            "4",
            "--out",
            o,
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let staging = wait_for_staging(tmp.path(), "ds", 1);
    let _ = std::os::unix::fs::symlink(&outside, staging.join("link"));
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let o2 = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o2.stderr);
    assert_eq!(o2.status.code(), Some(130), "{err}");
    assert!(err.contains("left as it was"), "{err}");
    assert_eq!(std::fs::read(outside.join(".x.1.tmp")).unwrap(), b"keep");
    assert_eq!(files_in(&out), before);
    let names: Vec<String> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names.iter().all(|n| !n.contains("aeroform")),
        "work folder or lock left: {names:?}"
    );
}

/// Two writers of one folder: a live lock holder makes the second fail with exit 1
/// naming the PID; the holder's lock is not touched.
#[test]
fn a_live_lock_refuses_a_second_writer() {
    let tmp = tempfile::tempdir().unwrap();
    let lock = tmp.path().join(".ds.aeroform-lock");
    let me = std::process::id().to_string();
    std::fs::write(&lock, format!("{me}\n")).unwrap();
    let out = tmp.path().join("ds");
    let (code, _, err) = code_of(
        &[
            "tunnel",
            "blind",
            "--effect",
            "none",
            "--out",
            out.to_str().unwrap(),
        ],
        tmp.path(),
    );
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&me) && err.contains("another aeroform process"),
        "{err}"
    );
    assert!(lock.exists() && !out.exists());
}

/// Temporary files of dead processes in a shared output folder (`flutter`, `identify`,
/// `lco` write single files there) are removed; a link named like one is removed as a
/// link, its target kept; a live process's temporary file is kept.
#[test]
fn stale_temporary_files_of_dead_processes_are_removed() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let dead = dead_pid();
    let target = tmp.path().join("target.txt");
    std::fs::write(&target, b"keep").unwrap();
    std::fs::write(out.join(format!(".flutter.json.{dead}.tmp")), b"half").unwrap();
    std::os::unix::fs::symlink(&target, out.join(format!(".x.{dead}.tmp"))).unwrap();
    let live = format!(".other.json.{}.tmp", std::process::id());
    std::fs::write(out.join(&live), b"busy").unwrap();
    let (code, _, err) = code_of(
        &[
            "flutter",
            "--structure",
            STRUCTURE,
            "--model",
            MODEL,
            "--speeds",
            "1:5:4",
            "--out",
            out.to_str().unwrap(),
        ],
        tmp.path(),
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("removed 2 temporary file(s)"), "{err}");
    let mut names = files_in(&out);
    names.sort();
    let mut want = vec!["flutter.json".to_string(), live];
    want.sort();
    assert_eq!(names, want);
    assert_eq!(std::fs::read(&target).unwrap(), b"keep");
}

/// Issue 27, row 6: `branch` writes its folder as a whole. A write failure part-way (a
/// 75 kB file limit: the CSV fits, the JSON does not) keeps the previous results intact and
/// leaves no staging folder; the next run replaces the folder with its own files only.
#[test]
fn branch_output_is_replaced_whole_or_kept_on_a_write_failure() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("br");
    let o = out.to_str().unwrap();
    let args = |speeds: &'static str| {
        vec![
            "branch",
            "--structure",
            STRUCTURE,
            "--model",
            MODEL,
            "--speeds",
            speeds,
            "--out",
            o,
            "--quiet",
        ]
    };
    let st = bin().args(args("5:9")).output().unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let first = std::fs::read(out.join("branch.json")).unwrap();
    let (ok, _, err) = sh("trap '' XFSZ; ulimit -f 150", &args("5:9.5"));
    assert!(!ok, "expected a write failure");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(std::fs::read(out.join("branch.json")).unwrap(), first);
    assert!(out.join(".aeroform-complete").exists());
    let leftovers: Vec<String> = files_in(tmp.path())
        .into_iter()
        .filter(|f| f.contains("staging") || f.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let st = bin().args(args("5:9.5")).output().unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert_ne!(std::fs::read(out.join("branch.json")).unwrap(), first);
    assert_eq!(
        files_in(&out),
        [
            ".aeroform-complete",
            "branch.csv",
            "branch.json",
            "branch_diagram.png",
            "branch_diagram.svg"
        ]
    );
}

/// Issue 27, rows 7 and 8: SIGINT at eight moments of a `plot` redraw and of a `tunnel`
/// campaign with still-air runs (both write from several threads): exit 0 or 130, never a
/// staging folder, trash folder or lock left behind (the handler used to remove the
/// staging folder in place while the writers went on, and lost the race), and the study
/// folder `plot` redraws keeps its complete set of files.
#[test]
fn interrupts_at_any_moment_leave_no_work_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let q = tmp.path().join("q");
    let t = tmp.path().join("t");
    let (code, _, err) = code_of(
        &["run", "--out", q.to_str().unwrap(), "--quiet"],
        tmp.path(),
    );
    assert_eq!(code, 0, "{err}");
    let before = files_in(&q);
    let plot = ["plot", q.to_str().unwrap(), "--quiet"];
    let tunnel = [
        "tunnel",
        "forced",
        "--model",
        MODEL,
        "--campaign",
        "config=A",
        "--still-air",
        "--out",
        t.to_str().unwrap(),
        "--quiet",
    ];
    for delay_ms in [20, 50, 80, 120, 160, 220, 300, 400] {
        for args in [&plot[..], &tunnel[..]] {
            let child = bin()
                .args(args)
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap();
            std::thread::sleep(std::time::Duration::from_millis(delay_ms));
            let _ = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .stderr(std::process::Stdio::null())
                .status();
            let o = child.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            let code = o.status.code();
            assert!(
                code == Some(0) || code == Some(130),
                "{args:?} at {delay_ms} ms: {code:?} {err}"
            );
            let names: Vec<String> = std::fs::read_dir(tmp.path())
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            assert!(
                names.iter().all(|n| !n.contains("aeroform")),
                "{args:?} interrupted at {delay_ms} ms left {names:?}"
            );
            assert_eq!(files_in(&q), before, "{args:?} at {delay_ms} ms");
        }
    }
}
