//! Issue 39, row 1: no output may be, contain or lie inside an input. Before the rule,
//! `diagnose DS --out DS` exited 0 and deleted `DS/cases` and `DS/manifest.toml` (the
//! set's completion marker let the swap replace it without `--force`); the same with
//! `diagnose B/forced --free B/free --out B`, with `run` when the study's `[data] dataset` is
//! the output, and `sweep SPEC --out SPEC` overwrote its specification.
//!
//! Every writer × every relation (is, contains, lies inside; spelled through a symbolic
//! link or `..`) is refused with exit code 2, a message that names the input's flag, and
//! every file of every input byte-identical afterwards. Outputs beside the inputs are
//! accepted (the control).

use crate::common;
use common::aeroform_code_in;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Every file below `dir` with its bytes (symbolic links not followed).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut m = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            let t = std::fs::symlink_metadata(&p).unwrap().file_type();
            if t.is_dir() {
                stack.push(p);
            } else if t.is_file() {
                m.insert(p.clone(), std::fs::read(&p).unwrap());
            } else {
                m.insert(p.clone(), b"<link>".to_vec());
            }
        }
    }
    m
}

/// A forced data set `tmp/B/forced`, a free one `tmp/B/free`, a study reading `B/forced`
/// and a sweep specification `tmp/map.json`.
fn layout() -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    let scen = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let (model, structure) = (
        scen.join("plate-truth.model.toml"),
        scen.join("plate-rig.structure.toml"),
    );
    std::fs::copy(&model, tmp.path().join("truth.model.toml")).unwrap();
    std::fs::copy(&structure, tmp.path().join("rig.structure.toml")).unwrap();
    let run = |args: &[&str]| {
        let (code, out, err) = aeroform_code_in(tmp.path(), args);
        assert_eq!(code, 0, "{args:?}\n{out}\n{err}");
    };
    run(&[
        "--quiet",
        "tunnel",
        "forced",
        "--model",
        "truth.model.toml",
        "--campaign",
        "config=D",
        "--duration",
        "2",
        "--out",
        "B/forced",
    ]);
    run(&[
        "--quiet",
        "tunnel",
        "free",
        "--structure",
        "rig.structure.toml",
        "--model",
        "truth.model.toml",
        "--speeds",
        "4,6",
        "--duration",
        "2",
        "--out",
        "B/free",
    ]);
    let study = "name = \"overlap\"\nseed = 1\n\n[data]\ndataset = \"B/forced\"\n\n\
                 [identify.settings]\ngroup_by = \"config\"\n";
    std::fs::write(tmp.path().join("study.toml"), study).unwrap();
    let spec = serde_json::json!({
        "kind": "flutter_map",
        "structure": "rig.structure.toml",
        "model": "truth.model.toml",
        "speeds": [1.0, 2.0],
        "grid": {"mu": [20.0], "sigma": [0.4]},
    });
    std::fs::write(tmp.path().join("map.json"), spec.to_string()).unwrap();
    std::os::unix::fs::symlink("B", tmp.path().join("link-to-B")).unwrap();
    tmp
}

/// Runs `args` in `dir`; asserts exit code 2, a message naming `flag` and the relation, and
/// no file of the whole folder changed (inputs included).
fn refused(dir: &Path, args: &[&str], flag: &str, relation: &str) {
    let before = snapshot(dir);
    let (code, out, err) = aeroform_code_in(dir, args);
    assert_eq!(code, 2, "{args:?} exit code\n{out}\n{err}");
    assert!(
        err.contains(flag) && err.contains(relation),
        "{args:?}: message names neither {flag} nor `{relation}`: {err}"
    );
    let after = snapshot(dir);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>(),
        "{args:?} added or removed files"
    );
    for (p, b) in &before {
        assert!(after[p] == *b, "{args:?} changed {}", p.display());
    }
}

#[test]
fn every_writer_refuses_an_output_that_is_contains_or_lies_inside_an_input() {
    let tmp = layout();
    let d = tmp.path();
    let m = "truth.model.toml";
    let s = "rig.structure.toml";
    // the reported reproductions
    refused(
        d,
        &["diagnose", "B/forced", "--out", "B/forced"],
        "FORCED",
        "is the input",
    );
    refused(
        d,
        &["diagnose", "B/forced", "--free", "B/free", "--out", "B"],
        "FORCED",
        "contains the input",
    );
    refused(
        d,
        &["run", "study.toml", "--out", "B/forced"],
        "data.dataset",
        "is the input",
    );
    refused(
        d,
        &["sweep", "map.json", "--out", "map.json"],
        "SPEC",
        "is the input",
    );
    // other spellings of the same folder
    refused(
        d,
        &["diagnose", "link-to-B/forced", "--out", "B/forced"],
        "FORCED",
        "is the input",
    );
    refused(
        d,
        &["diagnose", "B/forced", "--out", "B/free/../forced"],
        "FORCED",
        "is the input",
    );
    // lies inside an input
    refused(
        d,
        &["diagnose", "B/forced", "--out", "B/forced/diagnosis"],
        "FORCED",
        "lies inside the input",
    );
    refused(
        d,
        &["identify", "B/forced", "--out", "B/forced"],
        "DATASET",
        "lies inside the input",
    );
    refused(
        d,
        &[
            "identify",
            "B/forced",
            "--out",
            "id",
            "--timing-json",
            "B/forced/manifest.toml",
        ],
        "DATASET",
        "lies inside the input",
    );
    // the other writers, each with an input inside its output folder
    refused(
        d,
        &[
            "diagnose", "--free", "B/free", "--model", m, "--out", "B/free",
        ],
        "--free",
        "is the input",
    );
    std::fs::create_dir(d.join("W")).unwrap();
    std::fs::copy(d.join(m), d.join("W/m.toml")).unwrap();
    std::fs::write(
        d.join("W/m.csv"),
        "branch,wind_speed_m_s,heave_amp_m,pitch_amp_rad\n",
    )
    .unwrap();
    refused(
        d,
        &["tunnel", "forced", "--model", "W/m.toml", "--out", "W"],
        "--model",
        "contains the input",
    );
    refused(
        d,
        &[
            "tunnel",
            "free",
            "--structure",
            s,
            "--model",
            "W/m.toml",
            "--speeds",
            "4",
            "--out",
            "W",
        ],
        "--model",
        "contains the input",
    );
    refused(
        d,
        &[
            "branch",
            "--structure",
            s,
            "--model",
            m,
            "--speeds",
            "1:2",
            "--measured",
            "W/m.csv",
            "--out",
            "W",
        ],
        "--measured",
        "contains the input",
    );
    refused(
        d,
        &[
            "diagnose",
            "--measured-branch",
            "W/m.csv",
            "--model",
            m,
            "--structure",
            s,
            "--out",
            "W",
        ],
        "--measured-branch",
        "contains the input",
    );
}

/// The control: the same commands with outputs beside their inputs succeed, and the
/// inputs are unchanged.
#[test]
fn outputs_beside_the_inputs_are_accepted() {
    let tmp = layout();
    let d = tmp.path();
    let before = snapshot(&d.join("B"));
    for args in [
        vec!["--quiet", "identify", "B/forced", "--out", "id"],
        vec!["--quiet", "diagnose", "B/forced", "--out", "diag"],
        vec!["--quiet", "sweep", "map.json", "--out", "map.out.json"],
        // a shared output folder may hold inputs: only its own file is replaced
        vec![
            "--quiet",
            "flutter",
            "--structure",
            "rig.structure.toml",
            "--model",
            "truth.model.toml",
            "--out",
            ".",
        ],
    ] {
        let (code, out, err) = aeroform_code_in(d, &args);
        assert_eq!(code, 0, "{args:?}\n{out}\n{err}");
    }
    assert_eq!(snapshot(&d.join("B")), before);
}
