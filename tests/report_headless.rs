//! Headless-browser check of the HTML report: needs Chromium (`/usr/bin/chromium`, Debian
//! package `chromium`; `.ci/run` installs it). Without it the test prints why and passes
//! (a machine without the browser package cannot run it).
//!
//! Runs the quickstart into a temporary folder, then with headless Chromium:
//! (a) screenshots of `report.html` at 1400 and 420 px wide, failing on a blank page (< 1 %
//! non-white pixels); (b) at both widths, the DOM after layout from a copy of the page with
//! a probe script appended: the document must not be wider than the window
//! (`scrollWidth ≤ clientWidth`, the offending elements are listed); (c) the parsed DOM
//! keeps every figure of `figures.json` with its caption, and every link resolves (`#id`
//! to an element id of the page, a relative path to a file in the output folder).
//! Set `AEROFORM_SCREENSHOT_DIR` to keep the screenshots.
//!
//! Run: `cargo test --release --test report_headless -- --nocapture`

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
        "--disable-quic",
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

/// Appended to a copy of the report: after layout, writes the document's scroll and client
/// widths and the first elements that stick out on the right into a `<pre id="probe">`.
const PROBE: &str = r#"<script>
window.addEventListener('load', () => {
  const d = document.documentElement;
  const wide = [...document.querySelectorAll('body *')]
    .filter(e => e.getBoundingClientRect().right > d.clientWidth + 1)
    .slice(0, 8)
    .map(e => e.tagName + (e.id ? '#' + e.id : '') + ':' + Math.round(e.getBoundingClientRect().right));
  const p = document.createElement('pre');
  p.id = 'probe';
  p.textContent = 'PROBE ' + d.scrollWidth + ' ' + d.clientWidth + ' ' + wide.join(' ');
  document.body.appendChild(p);
});
</script>"#;

/// Fraction of non-white pixels of a PNG screenshot, and its size.
fn ink(shot: &Path) -> (f64, u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(shot).unwrap()));
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
    (non_white as f64 / total as f64, info.width, info.height)
}

/// Values of `attr="…"` in `html`.
fn attribute_values<'a>(html: &'a str, attr: &str) -> Vec<&'a str> {
    let key = format!(" {attr}=\"");
    html.match_indices(&key)
        .filter_map(|(i, _)| {
            let rest = &html[i + key.len()..];
            rest.find('"').map(|j| &rest[..j])
        })
        .collect()
}

#[test]
fn quickstart_report_renders_in_headless_chromium() {
    if !Path::new(CHROMIUM).exists() {
        eprintln!(
            "SKIPPED report_headless: {CHROMIUM} missing (apt-get install -y chromium; .ci/run installs it)"
        );
        return;
    }
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
    let html = std::fs::read_to_string(&report).unwrap();
    let url = format!("file://{}", report.canonicalize().unwrap().display());
    let figures: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("figures.json")).unwrap()).unwrap();
    let probe = out.join("probe.html");
    std::fs::write(&probe, html.replace("</body>", &format!("{PROBE}</body>"))).unwrap();
    let probe_url = format!("file://{}", probe.canonicalize().unwrap().display());

    for width in [1400, 420] {
        // (a) screenshot: not blank
        let shot = tmp.path().join(format!("shot-{width}.png"));
        let (ok, _, err) = chromium(
            &tmp.path().join(format!("profile-shot-{width}")),
            &[
                format!("--screenshot={}", shot.display()),
                format!("--window-size={width},4000"),
                url.clone(),
            ],
        );
        assert!(
            ok && shot.exists(),
            "screenshot at {width} px failed: {err}"
        );
        if let Ok(dir) = std::env::var("AEROFORM_SCREENSHOT_DIR") {
            std::fs::copy(&shot, Path::new(&dir).join(format!("report_{width}.png"))).unwrap();
        }
        let (frac, w, h) = ink(&shot);
        assert!(
            frac >= 0.01,
            "blank page at {width} px: {:.3} % non-white pixels of {w}×{h}",
            100.0 * frac
        );

        // (b) no horizontal overflow
        let (ok, dom, err) = chromium(
            &tmp.path().join(format!("profile-probe-{width}")),
            &[
                format!("--window-size={width},4000"),
                "--dump-dom".into(),
                probe_url.clone(),
            ],
        );
        assert!(ok, "dump-dom at {width} px failed: {err}");
        let dom = String::from_utf8_lossy(&dom);
        let line = dom
            .split("<pre id=\"probe\">PROBE ")
            .nth(1)
            .and_then(|s| s.split('<').next())
            .unwrap_or_else(|| panic!("probe did not run at {width} px"));
        let mut parts = line.split_whitespace();
        let scroll: i64 = parts.next().unwrap().parse().unwrap();
        let client: i64 = parts.next().unwrap().parse().unwrap();
        let culprits: Vec<&str> = parts.collect();
        eprintln!("window {width} px: scrollWidth {scroll}, clientWidth {client}");
        // headless Chromium lays a narrow window out at no less than ~500 px
        assert!(
            client <= width.max(500) && client > width / 2,
            "unexpected layout width {client} for a {width} px window"
        );
        assert!(
            scroll <= client,
            "horizontal overflow at {width} px: document {scroll} px wide in a {client} px \
             viewport; elements past the right edge: {culprits:?}"
        );
    }

    // (c) the DOM after parsing keeps every figure, and every link resolves
    let (ok, dom, err) = chromium(&tmp.path().join("profile-dom"), &["--dump-dom".into(), url]);
    assert!(ok, "dump-dom failed: {err}");
    let dom = String::from_utf8_lossy(&dom);
    assert_eq!(
        dom.matches("<svg").count(),
        figures.len(),
        "figures lost in parsing"
    );
    assert_eq!(dom.matches("<figcaption>").count(), figures.len());
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
    let ids = attribute_values(&dom, "id");
    let hrefs = attribute_values(&dom, "href");
    assert!(hrefs.len() > figures.len(), "{} links only", hrefs.len());
    for href in &hrefs {
        if let Some(anchor) = href.strip_prefix('#') {
            assert!(ids.contains(&anchor), "link #{anchor} has no target");
        } else {
            assert!(
                !href.contains("://") && !href.starts_with('/'),
                "external or absolute link {href}"
            );
            assert!(out.join(href).is_file(), "link {href} names no file");
        }
    }
    for f in &figures {
        let stem = f["stem"].as_str().unwrap();
        assert!(
            hrefs.contains(&format!("figures/{stem}.png").as_str()),
            "no link to figure {stem}"
        );
    }
    let study = std::fs::read_to_string(out.join("study.toml")).unwrap();
    assert!(study.contains("name = \"quickstart\""));
}
