//! `identify` streams its cases (issue 43 item 6): the identification read case by case is
//! the one of the whole set held in memory, a file changed before it is read again is an
//! error, and peak memory does not grow with the number of cases.

use crate::common;

use std::path::{Path, PathBuf};

use identify::dataset::{read_dataset, ReadOptions};
use identify::ensemble::{bootstrap, EnsembleSettings};
use identify::pipeline::{identify as identify_held, IdentifySettings};
use identify::preprocess::PreprocessOptions;
use identify::workflow::{prepare_dataset, prepare_streaming};

/// The configuration-D campaign of the plate truth (64 cases), `duration` s, seed 7.
fn campaign(tmp: &Path, duration: &str) -> PathBuf {
    common::forced_set(tmp, "set", "7", duration);
    tmp.join("set")
}

/// The set `src` `times` times over, as a new set `dst`: distinct case ids and file names,
/// each file a hard link to the case it copies (the campaign of issue 43 ten times over).
fn repeated(src: &Path, dst: &Path, times: usize) {
    let text = std::fs::read_to_string(src.join("manifest.toml")).unwrap();
    let mut parts = text.split("[[case]]");
    let head = parts.next().unwrap().to_string();
    let cases: Vec<&str> = parts.collect();
    std::fs::create_dir_all(dst.join("cases")).unwrap();
    let mut out = vec![head];
    for k in 0..times {
        for c in &cases {
            let field = |key: &str| {
                let at = c.find(&format!("\n{key} = \"")).unwrap() + key.len() + 5;
                c[at..at + c[at..].find('"').unwrap()].to_string()
            };
            let (id, file) = (field("id"), field("file"));
            let name = Path::new(&file).file_name().unwrap().to_string_lossy();
            let new_file = format!("cases/r{k}-{name}");
            std::fs::hard_link(src.join(&file), dst.join(&new_file)).unwrap();
            out.push(
                c.replacen(&format!("id = \"{id}\""), &format!("id = \"r{k}-{id}\""), 1)
                    .replacen(
                        &format!("file = \"{file}\""),
                        &format!("file = \"{new_file}\""),
                        1,
                    ),
            );
        }
    }
    std::fs::write(dst.join("manifest.toml"), out.join("[[case]]")).unwrap();
}

#[test]
fn the_streamed_identification_and_ensemble_are_those_of_the_whole_set() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = campaign(tmp.path(), "2");
    let settings = IdentifySettings::default();
    let pre = PreprocessOptions::default();

    let ds = read_dataset(&dir).unwrap();
    let held = prepare_dataset(&ds, &pre).unwrap();
    let mut whole = identify_held(&held.cases, &settings, &ds.manifest.name, &|_| {}).unwrap();
    let es = EnsembleSettings::new(8, 11);
    whole.ensemble = Some(bootstrap(&held.cases, &whole, &es).unwrap());

    let streamed =
        prepare_streaming(&dir, &ReadOptions::default(), &pre, &settings, &|_| {}).unwrap();
    assert_eq!(streamed.prepared.len(), held.cases.len());
    assert!(streamed.prepared.cases().is_empty(), "no samples are kept");
    let mut id = streamed
        .prepared
        .identify_all(&streamed.manifest.name, &|_| {})
        .unwrap();
    id.ensemble = Some(streamed.bootstrap(&id, &es).unwrap());
    // bit for bit: the per-case work is the same, batch or not
    assert_eq!(
        serde_json::to_string(&id).unwrap(),
        serde_json::to_string(&whole).unwrap()
    );
    assert_eq!(id.cases.len(), 64);
}

#[test]
fn a_case_file_changed_before_it_is_read_again_is_an_error_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = campaign(tmp.path(), "2");
    let settings = IdentifySettings::default();
    let streamed = prepare_streaming(
        &dir,
        &ReadOptions::default(),
        &PreprocessOptions::default(),
        &settings,
        &|_| {},
    )
    .unwrap();
    assert_eq!(
        streamed.reread(&[3]).unwrap().len(),
        1,
        "unchanged: read again"
    );
    let spec = &streamed.manifest.cases[streamed.sources[3].index];
    let path = dir.join(&spec.file);
    // the same size, one digit changed in the last row's moment
    let mut text = std::fs::read_to_string(&path).unwrap();
    let at = text
        .trim_end()
        .rfind(|c: char| c.is_ascii_digit() && c != '0')
        .unwrap();
    let d = text.as_bytes()[at];
    text.replace_range(at..at + 1, &((d - b'0') % 9 + 1).to_string());
    std::fs::write(&path, text).unwrap();
    let e = streamed.reread(&[3]).unwrap_err().to_string();
    assert!(e.contains(&spec.file.display().to_string()), "{e}");
    assert!(e.contains("changed since it was first read"), "{e}");
    let id = streamed
        .prepared
        .identify_all(&streamed.manifest.name, &|_| {})
        .unwrap();
    let e = streamed
        .bootstrap(&id, &EnsembleSettings::new(4, 1))
        .unwrap_err()
        .to_string();
    assert!(e.contains("changed since it was first read"), "{e}");
}

#[test]
fn a_bad_value_late_in_the_set_is_refused_with_its_file_line_and_column() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = campaign(tmp.path(), "2");
    let ds = read_dataset(&dir).unwrap();
    let last = ds.manifest.cases.last().unwrap();
    let path = dir.join(&last.file);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut fields: Vec<String> = lines[500].split(',').map(str::to_string).collect();
    fields[2] = "NaN".to_string();
    lines[500] = fields.join(",");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    let e = prepare_streaming(
        &dir,
        &ReadOptions::default(),
        &PreprocessOptions::default(),
        &IdentifySettings::default(),
        &|_| {},
    )
    .err()
    .expect("refused")
    .to_string();
    let held = read_dataset(&dir).unwrap_err().to_string();
    assert_eq!(e, held, "the same refusal as the whole-set reader");
    assert!(
        e.contains(&last.file.display().to_string()) && e.contains("501"),
        "{e}"
    );
}

/// Peak resident memory \[kB\] of `aeroform identify DIR`, by `/usr/bin/time -f %M`; None
/// when that tool is not there.
fn identify_peak_kb(dir: &Path, out: &Path) -> Option<u64> {
    let time = Path::new("/usr/bin/time");
    if !time.exists() {
        return None;
    }
    let report = out.with_extension("time");
    let status = std::process::Command::new(time)
        .args(["-f", "%M", "-o"])
        .arg(&report)
        .arg(env!("CARGO_BIN_EXE_aeroform"))
        .args(["--quiet", "identify"])
        .arg(dir)
        .arg("--out")
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success(), "identify {}", dir.display());
    let text = std::fs::read_to_string(&report).unwrap();
    Some(text.lines().last().unwrap().trim().parse().unwrap())
}

/// Peak memory at `n` and `10 n` copies of the 64 cases of 8 s (4,096 samples each). The
/// held identification grew by ≈ 115 B per sample, 0.47 MB per such case (0.59 MB per case
/// of 5,120 samples, docs/DECISIONS.md "Where the time goes"); streamed, what grows is the
/// per-case summary the group stage needs whatever the record length (the p × p factor and
/// Gram matrix, the key projections, a coefficient vector per δ of the path: ≈ 60 kB), so
/// the growth must stay under 0.15 MB per case.
fn peak_grows_by_the_summaries_only(n: usize) {
    let tmp = tempfile::tempdir().unwrap();
    let src = campaign(tmp.path(), "8");
    let (small, large) = (tmp.path().join("small"), tmp.path().join("large"));
    repeated(&src, &small, n);
    repeated(&src, &large, 10 * n);
    let Some(a) = identify_peak_kb(&small, &tmp.path().join("out-small")) else {
        eprintln!("no /usr/bin/time: not measured");
        return;
    };
    let b = identify_peak_kb(&large, &tmp.path().join("out-large")).unwrap();
    let per_case_mb = (b as f64 - a as f64) / 1e3 / (576 * n) as f64;
    eprintln!(
        "peak: {} cases {a} kB, {} cases {b} kB: {per_case_mb:.3} MB per case",
        64 * n,
        640 * n
    );
    assert!(
        per_case_mb < 0.15,
        "peak {a} kB at {} cases, {b} kB at {} cases: {per_case_mb:.3} MB per case",
        64 * n,
        640 * n
    );
}

#[test]
fn peak_memory_grows_by_the_summaries_only_64_to_640_cases() {
    peak_grows_by_the_summaries_only(1);
}

/// The slow form: 320 and 3,200 cases.
#[test]
#[ignore]
fn peak_memory_grows_by_the_summaries_only_320_to_3200_cases() {
    peak_grows_by_the_summaries_only(5);
}
