//! Issue 27, rows 15 and 17, end to end: flags that need `--blind` and bad `--shard` or
//! `branch --speeds` values are usage errors (exit code 2, like clap's own) naming the flag;
//! a command that fails before writing its results leaves no folder it created; `tunnel
//! forced` refuses an absurd model coefficient (naming the file and field) and a model
//! whose forces blow up (naming the case, channel and time) before writing anything.

use crate::common;

use std::path::Path;

use common::aeroform_code_in;

const MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/plate-truth.model.toml"
);
const STRUCTURE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/plate-rig.structure.toml"
);

/// A one-second configuration-D data set (64 forced cases) written to `dir/name`.
fn forced_set(dir: &Path, name: &str) {
    let (code, _, err) = aeroform_code_in(
        dir,
        &[
            "tunnel",
            "forced",
            "--model",
            MODEL,
            "--campaign",
            "config=D",
            "--duration",
            "1",
            "--out",
            name,
            "--quiet",
        ],
    );
    assert_eq!(code, 0, "{err}");
}

/// Names of the entries of `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// `diagnose DS --shard 0/2` (and `--shapes`, `--branch-level`) used to diagnose DS and
/// ignore the flag, exit 0: clap drops a `requires = "blind"` when `--blind` conflicts with
/// a present argument (the data set).
#[test]
fn benchmark_flags_without_blind_are_usage_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    forced_set(dir, "ds");
    for flags in [&["--shard", "0/2"][..], &["--shapes"], &["--branch-level"]] {
        let mut args = vec!["diagnose", "ds", "--out", "d"];
        args.extend_from_slice(flags);
        let (code, out, err) = aeroform_code_in(dir, &args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(
            err.contains(flags[0]) && err.contains("needs --blind"),
            "{args:?}: {err}"
        );
        assert_eq!(entries(dir), ["ds"], "{args:?} wrote something");
    }
}

/// Bad `--shard` values and `branch --speeds` ranges exit 2 (they exited 1), naming the
/// flag, like clap's own usage errors; nothing is written.
#[test]
fn bad_shard_and_branch_speeds_are_usage_errors_naming_the_flag() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("spec.json"), r#"{"kind":"blind","n":2,"seed":1}"#).unwrap();
    let branch = |speeds: &'static str| {
        vec![
            "branch",
            "--structure",
            STRUCTURE,
            "--model",
            MODEL,
            "--speeds",
            speeds,
            "--out",
            "b",
        ]
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["diagnose", "--blind", "2", "--shard", "3/2", "--out", "s"],
            "--shard",
        ),
        (
            vec!["diagnose", "--blind", "2", "--shard", "x", "--out", "s"],
            "--shard",
        ),
        // the drawn-shapes benchmark shards too: the shard, not the pair, is refused
        (
            vec![
                "diagnose", "--blind", "2", "--shapes", "--shard", "3/2", "--out", "s",
            ],
            "`3/2`: expected i/n",
        ),
        (vec!["sweep", "spec.json", "--shard", "2/2"], "--shard"),
        (vec!["sweep", "spec.json", "--shard", "1/0"], "--shard"),
        (branch("9:5"), "--speeds"),
        (branch("x"), "--speeds"),
        (branch("0:5"), "--speeds"),
        // clap's own usage error, for comparison
        (
            vec!["diagnose", "--blind", "2", "--no-such-flag"],
            "--no-such-flag",
        ),
    ];
    for (args, flag) in &cases {
        let (code, out, err) = aeroform_code_in(dir, args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(err.contains(flag), "{args:?} does not name {flag}: {err}");
        assert_eq!(entries(dir), ["spec.json"], "{args:?} wrote something");
    }
}

/// A command that fails after it has prepared its output folder removes the folders it
/// created (they are empty); a folder that existed before is kept.
#[test]
fn failed_commands_leave_no_out_folder_they_created() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // identify: a data set that reads but cannot be identified (no heave at all: the
    // library is rank-deficient with --basis full)
    forced_set(dir, "flat");
    for f in std::fs::read_dir(dir.join("flat/cases")).unwrap() {
        let p = f.unwrap().path();
        let text = std::fs::read_to_string(&p).unwrap();
        let mut lines = text.lines();
        let mut out = format!("{}\n", lines.next().unwrap());
        for l in lines {
            let mut c: Vec<&str> = l.split(',').collect();
            c[1] = "0";
            out.push_str(&c.join(","));
            out.push('\n');
        }
        std::fs::write(&p, out).unwrap();
    }
    // diagnose: a free-response data set given as the forced one
    let (code, _, err) = aeroform_code_in(
        dir,
        &[
            "tunnel",
            "free",
            "--structure",
            STRUCTURE,
            "--model",
            MODEL,
            "--speeds",
            "3,4",
            "--duration",
            "2",
            "--out",
            "free",
            "--quiet",
        ],
    );
    assert_eq!(code, 0, "{err}");
    // tunnel forced: a model whose forces blow up along the motion
    std::fs::write(
        dir.join("big.model.toml"),
        "kind = \"theodorsen\"\nchord = 0.25\n[[nonlinear]]\nterm = \"alpha^2\"\n\
         channel = \"lift\"\ncoefficient = 1e9\n",
    )
    .unwrap();
    let before = entries(dir);
    let ensemble = |cmd: &'static str, out: &'static str| {
        let mut v = vec![cmd, "--structure", STRUCTURE, "--model", MODEL];
        if cmd == "lco" {
            v.extend(["--speed", "5"]);
        }
        v.extend(["--ensemble", "3", "--out", out]);
        v
    };
    let failing: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["identify", "flat", "--basis", "full", "--out", "new/id"],
            "rank",
        ),
        (
            vec!["diagnose", "free", "--out", "new/diag"],
            "no forced case",
        ),
        (
            vec![
                "tunnel",
                "forced",
                "--model",
                "big.model.toml",
                "--campaign",
                "config=D",
                "--duration",
                "1",
                "--out",
                "new/forced",
            ],
            "|C_L|",
        ),
        // --ensemble needs an identification.json: refused after the flutter scan
        (ensemble("flutter", "new/flutter"), "identification.json"),
        (ensemble("lco", "new/lco"), "identification.json"),
    ];
    for (args, what) in &failing {
        let (code, out, err) = aeroform_code_in(dir, args);
        assert_ne!(code, 0, "{args:?}: {out}{err}");
        assert!(err.contains(what), "{args:?}: {err}");
        assert_eq!(entries(dir), before, "{args:?} left a folder");
    }
    // a folder that existed before stays (empty), a sub-folder created in it goes
    std::fs::create_dir(dir.join("keep")).unwrap();
    for out in ["keep", "keep/sub/deeper"] {
        let (code, _, err) = aeroform_code_in(dir, &ensemble("flutter", out));
        assert_eq!(code, 2, "{err}");
        assert!(dir.join("keep").is_dir());
        assert!(entries(&dir.join("keep")).is_empty(), "--out {out}");
    }
}

/// Row 15: `tunnel forced` with an α̇³ lift coefficient of 1e300 wrote lift 4.7e295 N with
/// exit 0; now the model file is refused naming its field. A coefficient within the cap
/// whose forces still blow up is refused naming the case, the channel and the time.
#[test]
fn tunnel_forced_refuses_absurd_coefficients_and_blowing_up_forces() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let truth = std::fs::read_to_string(MODEL).unwrap();
    let with = |term: &str, c: &str| {
        format!(
            "{truth}\n[[nonlinear]]\nterm = \"{term}\"\nchannel = \"lift\"\ncoefficient = {c}\n"
        )
    };
    std::fs::write(dir.join("huge.model.toml"), with("alpha_dot^3", "1e300")).unwrap();
    std::fs::write(dir.join("big.model.toml"), with("alpha^2", "1e9")).unwrap();
    let tunnel = |model: &'static str| {
        vec![
            "tunnel",
            "forced",
            "--model",
            model,
            "--campaign",
            "config=D",
            "--duration",
            "1",
            "--out",
            "t",
        ]
    };
    let (code, out, err) = aeroform_code_in(dir, &tunnel("huge.model.toml"));
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("huge.model.toml: nonlinear[4].coefficient: 1e300 must be finite")
            && err.contains("≤ 1000000000"),
        "{err}"
    );
    let (code, out, err) = aeroform_code_in(dir, &tunnel("big.model.toml"));
    assert_eq!(code, 2, "{out}{err}");
    assert!(
        err.contains("case `D-U3-A3`, lift at t = ")
            && err.contains("|C_L| must be finite and ≤ 10000"),
        "{err}"
    );
    assert_eq!(entries(dir), ["big.model.toml", "huge.model.toml"]);
}
