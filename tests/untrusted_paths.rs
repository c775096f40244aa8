//! Untrusted paths through the CLI: `aeroform identify` refuses a manifest whose `file` or
//! `nowind_file` is absolute, climbs out with `..`, or leaves the data-set folder through
//! a symbolic link (file or folder), with an error naming the manifest line, the field and
//! the path, and writes no output file. Links that stay inside the folder are accepted.

use std::path::{Path, PathBuf};
use std::process::Command;

fn aeroform(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroform"))
        .args(args)
        .output()
        .expect("run aeroform");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A valid two-frequency forced case (4 s at 256 Hz) as CSV text, linear forces.
fn case_csv() -> String {
    let mut s = String::from("t,h,alpha,lift,moment\n");
    for i in 0..1024 {
        let t = i as f64 / 256.0;
        let a = 12.0 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
        let h = 18.0 * (2.0 * std::f64::consts::PI * 1.3 * t).sin();
        s.push_str(&format!(
            "{t},{h},{a},{},{}\n",
            -0.9 * a - 0.02 * h,
            0.03 * a + 0.001 * h
        ));
    }
    s
}

/// Manifest of one forced case with the given `file` and optional `nowind_file`.
fn manifest(file: &str, nowind: Option<&str>) -> String {
    let q = |s: &str| toml::Value::String(s.to_string()).to_string();
    let mut m = format!(
        "format = \"aeroform-dataset/1\"\nname = \"untrusted\"\n\n[section]\nchord = 0.25\n\
         span = 0.75\nair_density = 1.225\n\n[units]\nheave = \"mm\"\npitch = \"deg\"\n\
         lift = \"N\"\nmoment = \"N*m\"\n\n[[case]]\nid = \"D-U6-A12\"\nkind = \"forced\"\n\
         file = {}\nwind_speed = 6.0\nconfig = \"D\"\nfreq_pitch = 2.0\nfreq_heave = 1.3\n",
        q(file)
    );
    if let Some(n) = nowind {
        m.push_str(&format!("nowind_file = {}\n", q(n)));
    }
    m
}

/// `tmp/ds/` (manifest written by the test, `cases/ok.csv`) and `tmp/outside/secret.csv`
/// (a valid case file: if it were read, identification would succeed).
struct Layout {
    _tmp: tempfile::TempDir,
    ds: PathBuf,
    outside: PathBuf,
    out: PathBuf,
}

fn layout() -> Layout {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let outside = tmp.path().join("outside");
    std::fs::create_dir_all(ds.join("cases")).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    let csv = case_csv();
    std::fs::write(ds.join("cases/ok.csv"), &csv).unwrap();
    std::fs::write(outside.join("secret.csv"), &csv).unwrap();
    let out = tmp.path().join("out");
    Layout {
        ds,
        outside,
        out,
        _tmp: tmp,
    }
}

/// Runs identify with this manifest; asserts failure naming `manifest.toml:LINE`, the field
/// and the path, no panic, and no file at all in the output folder.
fn refused(l: &Layout, manifest: &str, key: &str, shown: &str) -> String {
    std::fs::write(l.ds.join("manifest.toml"), manifest).unwrap();
    let (ok, err) = aeroform(&[
        "identify",
        l.ds.to_str().unwrap(),
        "--out",
        l.out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!ok, "expected a refusal, stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let line = manifest
        .lines()
        .position(|x| x.starts_with(&format!("{key} = ")))
        .unwrap()
        + 1;
    assert!(
        err.contains(&format!("manifest.toml:{line}: field `case[1].{key}`")),
        "names manifest line {line} and case[1].{key}: {err}"
    );
    assert!(err.contains(shown), "names the path {shown}: {err}");
    let written: Vec<_> = std::fs::read_dir(&l.out)
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    assert!(written.is_empty(), "no output may be written: {written:?}");
    err
}

#[test]
fn absolute_file_is_refused() {
    let l = layout();
    let secret = l.outside.join("secret.csv");
    let s = secret.to_str().unwrap();
    let err = refused(&l, &manifest(s, None), "file", s);
    assert!(err.contains("is absolute"), "{err}");
}

#[test]
fn absolute_nowind_file_is_refused() {
    let l = layout();
    let secret = l.outside.join("secret.csv");
    let s = secret.to_str().unwrap();
    let err = refused(&l, &manifest("cases/ok.csv", Some(s)), "nowind_file", s);
    assert!(err.contains("is absolute"), "{err}");
}

#[test]
fn parent_dir_escape_is_refused() {
    let l = layout();
    let p = "cases/../../outside/secret.csv";
    let err = refused(&l, &manifest(p, None), "file", p);
    assert!(err.contains("`..`"), "{err}");
    let err = refused(&l, &manifest("cases/ok.csv", Some(p)), "nowind_file", p);
    assert!(err.contains("`..`"), "{err}");
}

#[cfg(unix)]
fn symlink(target: &Path, link: &Path) {
    std::os::unix::fs::symlink(target, link).unwrap();
}

#[cfg(unix)]
#[test]
fn symlinked_file_leaving_the_folder_is_refused() {
    let l = layout();
    symlink(&l.outside.join("secret.csv"), &l.ds.join("cases/link.csv"));
    let err = refused(
        &l,
        &manifest("cases/link.csv", None),
        "file",
        "cases/link.csv",
    );
    assert!(err.contains("symbolic link"), "{err}");
    let err = refused(
        &l,
        &manifest("cases/ok.csv", Some("cases/link.csv")),
        "nowind_file",
        "cases/link.csv",
    );
    assert!(err.contains("secret.csv"), "names where it resolves: {err}");
}

#[cfg(unix)]
#[test]
fn symlinked_folder_leaving_the_folder_is_refused() {
    let l = layout();
    symlink(Path::new("../outside"), &l.ds.join("more"));
    let err = refused(
        &l,
        &manifest("more/secret.csv", None),
        "file",
        "more/secret.csv",
    );
    assert!(err.contains("outside the data set folder"), "{err}");
}

#[cfg(unix)]
#[test]
fn symlinks_inside_the_folder_are_accepted() {
    let l = layout();
    symlink(Path::new("cases"), &l.ds.join("alias"));
    symlink(Path::new("ok.csv"), &l.ds.join("cases/link.csv"));
    std::fs::write(l.ds.join("manifest.toml"), manifest("alias/link.csv", None)).unwrap();
    let (ok, err) = aeroform(&[
        "identify",
        l.ds.to_str().unwrap(),
        "--out",
        l.out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(ok, "{err}");
    assert!(l.out.join("identification.json").is_file());
}
