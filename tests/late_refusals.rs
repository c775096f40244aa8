//! Issue 39, row 7: late or unclear refusals. Each test reproduces one reported family on
//! small generated inputs and asserts what a user needs to fix the input: a control
//! character in a label refused when the file is read (by key and line, not at the figure
//! stage), invalid UTF-8 named by file, line, byte and offset in every reader, one rule for
//! the byte-order mark in every format, exit code 2, no message naming a vanished staging
//! folder, no writer writing through a symbolic link or over its own specification, and no
//! case drawn twice.

use crate::common;
use common::aeroform_code_in;

use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn scenario(name: &str) -> String {
    format!("{ROOT}/scenarios/{name}")
}

/// Runs `aeroform --quiet ARGS` in `dir`: (exit code, stderr).
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let mut v = vec!["--quiet"];
    v.extend_from_slice(args);
    let (code, _, err) = aeroform_code_in(dir, &v);
    (code, err)
}

/// The inputs of every reader, generated once into a temporary folder: a forced data set
/// `ds`, a study result folder `q` (quickstart), a sweep specification `spec.json` (one key
/// per line) and its two part documents, and copies of a structure, a model, the quickstart
/// study and the measured LCO table.
struct Inputs {
    tmp: tempfile::TempDir,
}

impl Inputs {
    fn new() -> Inputs {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        let ok = |args: &[&str]| {
            let (code, err) = run(d, args);
            assert_eq!(code, 0, "{args:?}: {err}");
        };
        ok(&[
            "tunnel",
            "forced",
            "--model",
            &scenario("plate-truth.model.toml"),
            "--campaign",
            "config=D",
            "--duration",
            "1",
            "--out",
            "ds",
        ]);
        ok(&["run", "--out", "q"]);
        for (from, to) in [
            ("plate-rig.structure.toml", "s.toml"),
            ("plate-truth.model.toml", "m.toml"),
            ("quickstart.toml", "study.toml"),
            ("bristol-spring1-lco-amplitudes.csv", "lco.csv"),
        ] {
            std::fs::copy(scenario(from), d.join(to)).unwrap();
        }
        let spec = format!(
            "{{\n  \"kind\": \"flutter_map\",\n  \"structure\": \"{}\",\n  \"model\": \"{}\",\n  \
             \"speeds\": [2.0, 12.0],\n  \"grid\": {{\"mu\": [20.0, 40.0]}}\n}}\n",
            scenario("plate-rig.structure.toml"),
            scenario("plate-truth.model.toml")
        );
        std::fs::write(d.join("spec.json"), spec).unwrap();
        for i in 0..2 {
            ok(&[
                "sweep",
                "spec.json",
                "--shard",
                &format!("{i}/2"),
                "--out",
                &format!("p{i}.json"),
            ]);
        }
        Inputs { tmp }
    }

    fn dir(&self) -> &Path {
        self.tmp.path()
    }

    fn first_case(&self) -> String {
        let mut v: Vec<PathBuf> = std::fs::read_dir(self.dir().join("ds/cases"))
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .collect();
        v.sort();
        v[0].strip_prefix(self.dir())
            .unwrap()
            .to_string_lossy()
            .into_owned()
    }

    /// Every reader of a text input: (file, command line reading it).
    fn readers(&self) -> Vec<(String, Vec<String>)> {
        let bristol_s = scenario("bristol-spring1.structure.toml");
        let bristol_m = scenario("bristol-spring1.model.toml");
        let v = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let flutter = |s: &str, m: &str| {
            v(&[
                "flutter",
                "--structure",
                s,
                "--model",
                m,
                "--speeds",
                "2:12:11",
                "--out",
                "o",
            ])
        };
        vec![
            (
                "ds/manifest.toml".into(),
                v(&["identify", "ds", "--out", "o"]),
            ),
            (self.first_case(), v(&["identify", "ds", "--out", "o"])),
            ("s.toml".into(), flutter("s.toml", "m.toml")),
            ("m.toml".into(), flutter("s.toml", "m.toml")),
            (
                "q/identification.json".into(),
                flutter("s.toml", "q/identification.json"),
            ),
            ("study.toml".into(), v(&["run", "study.toml", "--out", "o"])),
            (
                "spec.json".into(),
                v(&["sweep", "spec.json", "--out", "o.json"]),
            ),
            (
                "p0.json".into(),
                v(&["merge", "o.json", "p0.json", "p1.json"]),
            ),
            (
                "lco.csv".into(),
                v(&[
                    "branch",
                    "--structure",
                    &bristol_s,
                    "--model",
                    &bristol_m,
                    "--speeds",
                    "15:25",
                    "--measured",
                    "lco.csv",
                    "--out",
                    "o",
                ]),
            ),
            ("q/flutter.json".into(), v(&["plot", "q"])),
            ("q/series/D-U10-A6.json".into(), v(&["plot", "q"])),
        ]
    }

    /// Removes what an accepted run wrote.
    fn clean(&self) {
        let _ = std::fs::remove_dir_all(self.dir().join("o"));
        let _ = std::fs::remove_file(self.dir().join("o.json"));
    }
}

/// Invalid UTF-8 at the start of line 3 of every text input: refused with exit code 2, the
/// message naming the file, the line, the byte and its offset in the file, and never the
/// staging folder of `plot` (which is gone when the message is read).
#[test]
fn invalid_utf8_is_named_by_file_line_byte_and_offset_in_every_reader() {
    let inp = Inputs::new();
    let d = inp.dir();
    let mut readers = inp.readers();
    readers.push((
        "lco.csv".into(),
        [
            "diagnose",
            "--measured-branch",
            "lco.csv",
            "--model",
            &scenario("bristol-spring1.model.toml"),
            "--structure",
            &scenario("bristol-spring1.structure.toml"),
            "--out",
            "o",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
    ));
    for (file, args) in readers {
        let p = d.join(&file);
        let clean = std::fs::read(&p).unwrap();
        let mut nl = clean.iter().enumerate().filter(|(_, b)| **b == b'\n');
        let at = nl.nth(1).unwrap().0 + 1;
        let mut bad = clean[..at].to_vec();
        bad.push(0xff);
        bad.extend_from_slice(&clean[at..]);
        std::fs::write(&p, &bad).unwrap();
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = run(d, &a);
        std::fs::write(&p, &clean).unwrap();
        let what = format!("{file} ({})", args[0]);
        assert_eq!(code, 2, "{what}: {err}");
        assert!(
            err.contains(&file)
                && err.contains(&format!("line 3, byte 1 (offset {at} in the file)")),
            "{what}: file, line, byte and offset not named: {err}"
        );
        assert!(!err.contains("aeroform-staging"), "{what}: {err}");
        assert!(
            !d.join("o").exists() && !d.join("o.json").exists(),
            "{what}"
        );
    }
}

/// One rule for the byte-order mark: a leading UTF-8 BOM is accepted in every format (TOML,
/// CSV, JSON, the measured table, the result files `plot` reads). Before, JSON documents and
/// the measured table refused it ("expected value at line 1 column 1").
#[test]
fn a_leading_bom_is_accepted_in_every_format() {
    let inp = Inputs::new();
    let d = inp.dir();
    for (file, args) in inp.readers() {
        let p = d.join(&file);
        let clean = std::fs::read(&p).unwrap();
        let mut with = b"\xef\xbb\xbf".to_vec();
        with.extend_from_slice(&clean);
        std::fs::write(&p, &with).unwrap();
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = run(d, &a);
        std::fs::write(&p, &clean).unwrap();
        assert_eq!(code, 0, "{file} with a BOM ({}): {err}", args[0]);
        inp.clean();
    }
}

/// Every refusal of a reader is an input error (exit code 2) naming the file: a missing
/// file, a folder or a device in its place, an empty or cut file, a JSON document that does
/// not parse (a part of `merge`, a result file of `plot`: these exited 1). A file `plot`
/// rewrites that is a folder is named in the user's folder, not in the staging copy.
#[test]
fn reader_refusals_exit_2_and_name_the_file() {
    let inp = Inputs::new();
    let d = inp.dir();
    let mut readers = inp.readers();
    readers.push(("q/figures.json".into(), vec!["plot".into(), "q".into()]));
    for (file, args) in readers {
        let p = d.join(&file);
        let clean = std::fs::read(&p).unwrap();
        let json = file.ends_with(".json");
        for family in ["missing", "folder", "device", "empty", "cut"] {
            if file.ends_with("figures.json") && family != "folder" {
                continue; // not read, only rewritten
            }
            std::fs::remove_file(&p).unwrap();
            match family {
                "missing" => {}
                "folder" => std::fs::create_dir(&p).unwrap(),
                "device" => std::os::unix::fs::symlink("/dev/zero", &p).unwrap(),
                "empty" => std::fs::write(&p, b"").unwrap(),
                _ => std::fs::write(&p, &clean[..clean.len() / 2]).unwrap(),
            }
            let a: Vec<&str> = args.iter().map(String::as_str).collect();
            let (code, err) = run(d, &a);
            let _ = std::fs::remove_dir(&p);
            let _ = std::fs::remove_file(&p);
            std::fs::write(&p, &clean).unwrap();
            let what = format!("{file} {family} ({})", args[0]);
            if code == 0 && !json && family == "cut" {
                // half a CSV or TOML file can still be a valid one
                inp.clean();
                continue;
            }
            assert_eq!(code, 2, "{what}: {err}");
            let name = file.rsplit('/').next().unwrap();
            assert!(err.contains(name), "{what}: the file is not named: {err}");
            assert!(!err.contains("aeroform-staging"), "{what}: {err}");
            assert!(
                !d.join("o").exists() && !d.join("o.json").exists(),
                "{what}"
            );
        }
    }
}

/// Control characters in strings of a study (valid TOML escapes) are refused when the
/// study is read, naming the key and line, instead of failing at the figure stage ("SVG not
/// parsed: non-XML character", no key); the same for every string of a data-set manifest.
#[test]
fn control_characters_in_labels_are_refused_when_read_by_key_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let study = std::fs::read_to_string(scenario("quickstart.toml")).unwrap();
    let line_of =
        |text: &str, needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
    for (from, to, key) in [
        (
            "label = \"Theodorsen exact (p-k)\"",
            "label = \"Theodorsen\\u0001 exact (p-k)\"",
            "flutter.run[0].label",
        ),
        (
            "label = \"Theodorsen–Jones state space (p)\"",
            "label = \"\\u001b[2J(p)\"",
            "flutter.run[1].label",
        ),
        ("description = \"", "description = \"\\u007f", "description"),
    ] {
        assert!(study.contains(from), "{from}");
        let text = study.replacen(from, to, 1);
        std::fs::write(d.join("s.toml"), &text).unwrap();
        let t = std::time::Instant::now();
        let (code, err) = run(d, &["run", "s.toml", "--out", "o"]);
        assert_eq!(code, 2, "{key}: {err}");
        let want = format!("s.toml:{}: key `{key}`", line_of(&text, to));
        assert!(err.contains(&want), "{key}: `{want}` not in {err}");
        assert!(
            err.contains("control character") && !err.contains("SVG"),
            "{err}"
        );
        assert!(t.elapsed().as_secs_f64() < 5.0, "refused late");
        assert!(!d.join("o").exists());
    }
    // a data set: the manifest's `name`, a case's `config` and `description`
    let (code, err) = run(
        d,
        &[
            "tunnel",
            "forced",
            "--model",
            &scenario("plate-truth.model.toml"),
            "--campaign",
            "config=D",
            "--duration",
            "1",
            "--out",
            "ds",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let m = d.join("ds/manifest.toml");
    let manifest = std::fs::read_to_string(&m).unwrap();
    for (from, to, key) in [
        ("config = \"D\"", "config = \"D\\u0008\"", "case[1].config"),
        ("name = \"", "name = \"\\u0000", "name"),
        ("description = \"", "description = \"\\u009b", "description"),
    ] {
        let text = manifest.replacen(from, to, 1);
        std::fs::write(&m, &text).unwrap();
        let (code, err) = run(d, &["identify", "ds", "--out", "o"]);
        assert_eq!(code, 2, "{key}: {err}");
        let want = format!("manifest.toml:{}: field `{key}`", line_of(&text, to));
        assert!(err.contains(&want), "{key}: `{want}` not in {err}");
        assert!(!d.join("o").exists());
    }
}

/// The single-file writers refuse a symbolic link as `--out` (as the folder writers do):
/// `identify`, `flutter` and `lco` wrote through it; `sweep` refuses a link as its output
/// file and never writes over its own specification (also when the default output name is
/// the specification's).
#[test]
fn single_file_writers_refuse_a_symlinked_out_and_sweep_keeps_its_spec() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir(d.join("elsewhere")).unwrap();
    std::os::unix::fs::symlink(d.join("elsewhere"), d.join("link")).unwrap();
    let (s, m) = (
        scenario("plate-rig.structure.toml"),
        scenario("plate-truth.model.toml"),
    );
    let (code, err) = run(
        d,
        &[
            "tunnel",
            "forced",
            "--model",
            &m,
            "--campaign",
            "config=D",
            "--duration",
            "1",
            "--out",
            "ds",
        ],
    );
    assert_eq!(code, 0, "{err}");
    for args in [
        vec!["identify", "ds", "--out", "link"],
        vec![
            "flutter",
            "--structure",
            &s,
            "--model",
            &m,
            "--speeds",
            "2:12:11",
            "--out",
            "link",
        ],
        vec![
            "lco",
            "--structure",
            &s,
            "--model",
            &m,
            "--speed",
            "7",
            "--out",
            "link",
        ],
    ] {
        let (code, err) = run(d, &args);
        assert_eq!(code, 2, "{}: {err}", args[0]);
        assert!(err.contains("--out link: is a symbolic link"), "{err}");
        assert_eq!(std::fs::read_dir(d.join("elsewhere")).unwrap().count(), 0);
    }
    let spec = format!(
        "{{\"kind\":\"flutter_map\",\"structure\":\"{s}\",\"model\":\"{m}\",\
         \"speeds\":[2.0,12.0],\"grid\":{{\"mu\":[20.0,40.0]}}}}"
    );
    std::fs::write(d.join("sweep.json"), &spec).unwrap();
    std::fs::write(d.join("elsewhere/keep.json"), "keep").unwrap();
    std::os::unix::fs::symlink(d.join("elsewhere/keep.json"), d.join("out.json")).unwrap();
    let (code, err) = run(d, &["sweep", "sweep.json", "--out", "out.json"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("is a symbolic link"), "{err}");
    assert_eq!(
        std::fs::read_to_string(d.join("elsewhere/keep.json")).unwrap(),
        "keep"
    );
    // the default output `sweep.json` is the specification itself; so is `--out SPEC`
    for args in [
        vec!["sweep", "sweep.json"],
        vec!["sweep", "sweep.json", "--out", "sweep.json"],
    ] {
        let (code, err) = run(d, &args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("is the input SPEC"), "{err}");
        assert_eq!(std::fs::read_to_string(d.join("sweep.json")).unwrap(), spec);
    }
}

/// A case named twice in `outputs.series_cases` is refused naming the key (it drew the
/// case's figures again: 10× the time).
#[test]
fn repeated_series_cases_are_refused_naming_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let study = std::fs::read_to_string(scenario("quickstart.toml")).unwrap();
    let from = "series_cases = [\"D-U4-A24\", \"D-U10-A6\"]";
    assert!(study.contains(from));
    let text = study.replacen(
        from,
        "series_cases = [\"D-U4-A24\", \"D-U10-A6\", \"D-U4-A24\"]",
        1,
    );
    std::fs::write(d.join("s.toml"), &text).unwrap();
    let (code, err) = run(d, &["run", "s.toml", "--out", "o"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("key `outputs.series_cases[2]`") && err.contains("already entry 0"),
        "{err}"
    );
    assert!(!d.join("o").exists());
}
