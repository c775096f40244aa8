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
