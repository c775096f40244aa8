//! Untrusted paths: a manifest may only name case files inside its data-set folder
//! (absolute paths, `..` and symbolic links that leave the folder are refused; links that
//! stay inside are accepted).

use std::path::{Path, PathBuf};

use super::*;
use crate::Error;

const CSV: &str = "t,h,alpha,lift,moment\n0,0,0,0,0\n0.1,1,2,3,4\n0.2,2,3,4,5\n";

/// A manifest with one forced case whose `file` (and optionally `nowind_file`) are the
/// given TOML-quoted strings.
fn manifest(file: &str, nowind: Option<&str>) -> String {
    let mut s = format!(
        "format = \"aeroform-dataset/1\"\nname = \"paths\"\n\n[section]\nchord = 0.25\n\
         span = 0.75\nair_density = 1.225\n\n[units]\nheave = \"mm\"\npitch = \"deg\"\n\
         lift = \"N\"\nmoment = \"N*m\"\n\n[[case]]\nid = \"ok\"\nkind = \"forced\"\n\
         file = \"b.csv\"\nwind_speed = 5.0\n\n[[case]]\nid = \"x\"\nkind = \"forced\"\n\
         file = {}\nwind_speed = 5.0\n",
        toml_str(file)
    );
    if let Some(n) = nowind {
        s.push_str(&format!("nowind_file = {}\n", toml_str(n)));
    }
    s
}

fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// 1-based line of the last line of `text` starting with `prefix` (found independently
/// of the reader; the refused key is always in the last case).
fn last_line_starting(text: &str, prefix: &str) -> usize {
    text.lines()
        .collect::<Vec<_>>()
        .iter()
        .rposition(|l| l.starts_with(prefix))
        .unwrap()
        + 1
}

/// `tmp/ds` with `a.csv`, and `tmp/outside/secret.csv` (a valid case file, so a read
/// that escaped would succeed instead of failing).
fn layout(tmp: &Path) -> (PathBuf, PathBuf) {
    let ds = tmp.join("ds");
    let outside = tmp.join("outside");
    std::fs::create_dir_all(&ds).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::write(ds.join("a.csv"), CSV).unwrap();
    std::fs::write(ds.join("b.csv"), CSV).unwrap();
    std::fs::write(outside.join("secret.csv"), CSV).unwrap();
    (ds, outside)
}

fn write_manifest(ds: &Path, text: &str) {
    std::fs::write(ds.join(MANIFEST_FILE), text).unwrap();
}

/// Asserts a refusal naming the manifest, the line, `case[2].<key>` and the path.
fn assert_refused(e: &Error, ds: &Path, text: &str, key: &str, shown: &str, why: &str) {
    let Error::Manifest {
        path,
        line,
        field,
        message,
    } = e
    else {
        panic!("expected Error::Manifest, got {e:?}");
    };
    assert_eq!(path, &ds.join(MANIFEST_FILE));
    assert_eq!(*line, last_line_starting(text, &format!("{key} = ")));
    assert_eq!(field, &format!("case[2].{key}"));
    assert!(message.contains(shown), "{message}");
    assert!(message.contains(why), "{message}");
}

#[cfg(unix)]
fn symlink(target: &Path, link: &Path) {
    std::os::unix::fs::symlink(target, link).unwrap();
}

#[test]
fn absolute_case_file_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (ds, outside) = layout(tmp.path());
    let secret = outside.join("secret.csv");
    let text = manifest(secret.to_str().unwrap(), None);
    write_manifest(&ds, &text);
    let e = read_dataset(&ds).unwrap_err();
    assert_refused(
        &e,
        &ds,
        &text,
        "file",
        secret.to_str().unwrap(),
        "is absolute",
    );
}

#[test]
fn parent_dir_in_nowind_file_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (ds, _) = layout(tmp.path());
    let text = manifest("a.csv", Some("sub/../../outside/secret.csv"));
    write_manifest(&ds, &text);
    let e = read_dataset(&ds).unwrap_err();
    assert_refused(
        &e,
        &ds,
        &text,
        "nowind_file",
        "../outside/secret.csv",
        "`..`",
    );
}

#[cfg(unix)]
#[test]
fn symlinked_file_pointing_outside_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (ds, outside) = layout(tmp.path());
    symlink(&outside.join("secret.csv"), &ds.join("x.csv"));
    let text = manifest("x.csv", None);
    write_manifest(&ds, &text);
    let e = read_dataset(&ds).unwrap_err();
    assert_refused(&e, &ds, &text, "file", "x.csv", "symbolic link");
    assert!(
        e.to_string().contains("secret.csv"),
        "names the target: {e}"
    );
    // a relative link target escapes the same way
    std::fs::remove_file(ds.join("x.csv")).unwrap();
    symlink(Path::new("../outside/secret.csv"), &ds.join("x.csv"));
    let e = read_dataset(&ds).unwrap_err();
    assert_refused(&e, &ds, &text, "file", "x.csv", "symbolic link");
}

#[cfg(unix)]
#[test]
fn symlinked_folder_pointing_outside_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (ds, outside) = layout(tmp.path());
    symlink(&outside, &ds.join("cases"));
    let text = manifest("a.csv", Some("cases/secret.csv"));
    write_manifest(&ds, &text);
    let e = read_dataset(&ds).unwrap_err();
    assert_refused(
        &e,
        &ds,
        &text,
        "nowind_file",
        "cases/secret.csv",
        "outside the data set folder",
    );
}

#[cfg(unix)]
#[test]
fn symlinks_inside_the_folder_are_accepted() {
    let tmp = tempfile::tempdir().unwrap();
    let (ds, _) = layout(tmp.path());
    std::fs::create_dir_all(ds.join("real")).unwrap();
    std::fs::write(ds.join("real/b.csv"), CSV).unwrap();
    symlink(&ds.join("real"), &ds.join("cases")); // absolute link to a folder inside
    symlink(Path::new("a.csv"), &ds.join("link.csv")); // relative link to a file inside
    let text = manifest("cases/b.csv", Some("link.csv"));
    write_manifest(&ds, &text);
    let d = read_dataset(&ds).unwrap();
    assert_eq!(d.records.len(), 2);
    assert!(d.records[1].nowind.is_some());
    assert_eq!(d.records[1].h, d.records[0].h);
}

#[cfg(unix)]
#[test]
fn data_set_folder_reached_through_a_symlink_is_accepted() {
    // the folder itself may be a link: both sides are canonicalised before comparing
    let tmp = tempfile::tempdir().unwrap();
    let (ds, _) = layout(tmp.path());
    write_manifest(&ds, &manifest("a.csv", None));
    let alias = tmp.path().join("alias");
    symlink(&ds, &alias);
    assert_eq!(read_dataset(&alias).unwrap().records.len(), 2);
}

#[cfg(unix)]
#[test]
fn dangling_symlink_is_refused_by_manifest_line_and_key() {
    let tmp = tempfile::tempdir().unwrap();
    let (ds, outside) = layout(tmp.path());
    symlink(&outside.join("missing.csv"), &ds.join("x.csv"));
    write_manifest(&ds, &manifest("x.csv", None));
    // issue 39, row 7: a case file that does not exist is refused where it is named (it was
    // a bare I/O error naming the path)
    let e = read_dataset(&ds).unwrap_err();
    assert!(
        matches!(&e, Error::Manifest { field, line, .. } if field.ends_with(".file") && *line > 0),
        "{e:?}"
    );
    assert!(e.to_string().contains("no such file"), "{e}");
}

#[cfg(unix)]
#[test]
fn read_case_checks_paths_of_manifests_built_in_code() {
    let tmp = tempfile::tempdir().unwrap();
    let (ds, outside) = layout(tmp.path());
    let text = manifest("a.csv", None);
    write_manifest(&ds, &text);
    let m = Manifest::parse(&text, &ds.join(MANIFEST_FILE)).unwrap();
    let mut case = m.cases[1].clone();
    case.file = outside.join("secret.csv");
    let e = read_case(&ds, &m, &case).unwrap_err();
    // the manifest on disk names case `x` with `file` on its last `file =` line
    assert_refused(&e, &ds, &text, "file", "secret.csv", "is absolute");
    symlink(&outside.join("secret.csv"), &ds.join("x.csv"));
    case.file = PathBuf::from("x.csv");
    let e = read_case(&ds, &m, &case).unwrap_err();
    assert_refused(&e, &ds, &text, "file", "x.csv", "symbolic link");
    case.file = PathBuf::from("a.csv");
    assert!(read_case(&ds, &m, &case).is_ok());
}

/// Found with the `dataset` fuzz harness's "finite SI values" invariant: a total force that
/// is finite in the file became +inf N/m after division by a subnormal span, and the
/// record was accepted (input: fuzz/regressions/dataset/span-overflow-to-infinite-force).
#[test]
fn fuzz_regression_dataset_span_overflow_to_infinite_force() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path();
    let text = manifest("a.csv", None).replace("span = 0.75", "span = 1e-310");
    write_manifest(ds, &text);
    // the first case's own file (zero forces stay finite whatever the span)
    std::fs::write(
        ds.join("b.csv"),
        "t,h,alpha,lift,moment\n0,0,0,0,0\n0.1,0,0,0,0\n0.2,0,0,0,0\n",
    )
    .unwrap();
    std::fs::write(
        ds.join("a.csv"),
        "t,h,alpha,lift,moment\n0,0,0,0,0\n0.1,0,0,0,0\n0.2,1,2,3,4\n",
    )
    .unwrap();
    let e = read_dataset(ds).unwrap_err();
    assert!(
        matches!(&e, Error::Csv { line: 4, field, .. } if field == "lift"),
        "{e:?}"
    );
    assert!(e.to_string().contains("a.csv:4"), "{e}");
    // zero stays zero whatever the span: the first two rows were accepted
    std::fs::write(
        ds.join("a.csv"),
        "t,h,alpha,lift,moment\n0,0,0,0,0\n0.1,0,0,0,0\n0.2,0,0,0,0\n",
    )
    .unwrap();
    let d = read_dataset(ds).unwrap();
    assert!(d.records[0]
        .lift
        .as_ref()
        .unwrap()
        .iter()
        .all(|x| *x == 0.0));
}
