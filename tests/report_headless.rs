//! Headless-browser check of the HTML report (ignored by default: needs
//! `/usr/bin/chromium`, `apt-get install -y chromium`).
//!
//! Runs the quickstart into a temporary folder, then with headless Chromium (a) takes a
//! 1400 × 4000 screenshot of `report.html` and fails on a blank page (< 1 % non-white
//! pixels), (b) dumps the parsed DOM and fails when the number of `<svg` elements differs
//! from the figures listed in `figures.json` or a figure kind of the study is missing.
//! Set `AEROFORM_SCREENSHOT_DIR` to keep the screenshot.
//!
//! Run: `cargo test -p aeroform --test report_headless -- --ignored`

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const CHROMIUM: &str = "/usr/bin/chromium";

/// Runs Chromium headless with the given extra arguments; kills it after 120 s. Output goes
/// to files next to the profile (a piped stream that nobody drains would block Chromium).
fn chromium(profile: &Path, extra: &[String]) -> (bool, Vec<u8>, String) {
    let (out_path, err_path) = (
        profile.with_extension("stdout"),
        profile.with_extension("stderr"),
    );
    let mut cmd = Command::new(CHROMIUM);
    cmd.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
    ])
    .arg(format!("--user-data-dir={}", profile.display()))
    .args(extra)
    .stdout(Stdio::from(std::fs::File::create(&out_path).unwrap()))
    .stderr(Stdio::from(std::fs::File::create(&err_path).unwrap()));
    let mut child = cmd.spawn().expect("start chromium");
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait chromium") {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("chromium did not finish within 120 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    (
        status.success(),
        std::fs::read(&out_path).unwrap_or_default(),
        std::fs::read_to_string(&err_path).unwrap_or_default(),
    )
}

#[test]
#[ignore = "needs /usr/bin/chromium; run with --ignored"]
fn quickstart_report_renders_in_headless_chromium() {
    assert!(
        Path::new(CHROMIUM).exists(),
        "{CHROMIUM} missing: apt-get install -y chromium"
    );
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_aeroform"))
        .args(["run", "--out", out.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report = out.join("report.html");
    let url = format!("file://{}", report.canonicalize().unwrap().display());
    let figures: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("figures.json")).unwrap()).unwrap();

    // (a) screenshot: not blank
    let shot = tmp.path().join("shot.png");
    let (ok, _, err) = chromium(
        &tmp.path().join("profile-a"),
        &[
            format!("--screenshot={}", shot.display()),
            "--window-size=1400,4000".into(),
            url.clone(),
        ],
    );
    assert!(ok && shot.exists(), "screenshot failed: {err}");
    if let Ok(dir) = std::env::var("AEROFORM_SCREENSHOT_DIR") {
        std::fs::copy(&shot, Path::new(&dir).join("report_screenshot.png")).unwrap();
    }
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let px = &buf[..info.buffer_size()];
    let total = px.len() / channels;
    let non_white = px
        .chunks(channels)
        .filter(|p| p.iter().take(3).any(|&c| c < 245))
        .count();
    let frac = non_white as f64 / total as f64;
    assert!(
        frac >= 0.01,
        "blank page: {:.3} % non-white pixels of {}×{}",
        100.0 * frac,
        info.width,
        info.height
    );

    // (b) the DOM after parsing keeps every figure
    let (ok, dom, err) = chromium(&tmp.path().join("profile-b"), &["--dump-dom".into(), url]);
    assert!(ok, "dump-dom failed: {err}");
    let dom = String::from_utf8_lossy(&dom);
    assert_eq!(
        dom.matches("<svg").count(),
        figures.len(),
        "figures lost in parsing"
    );
    let study = std::fs::read_to_string(out.join("study.toml")).unwrap();
    assert!(study.contains("name = \"quickstart\""));
    for kind in [
        "time_series",
        "spectrum",
        "delta_path",
        "heatmap",
        "histogram",
        "derivatives",
        "vg",
        "bifurcation",
        "phase",
    ] {
        assert!(
            figures.iter().any(|f| f["kind"] == kind),
            "no {kind} figure in the quickstart report"
        );
    }
    assert_eq!(dom.matches("<figcaption>").count(), figures.len());
}
