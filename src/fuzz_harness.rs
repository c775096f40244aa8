//! Harnesses of the fuzz targets (`fuzz/fuzz_targets/*.rs`): each takes arbitrary bytes,
//! feeds them to one of the readers of untrusted files and checks the invariants a reader
//! promises. A harness returns normally for every input; a panic is a bug (the fuzzer
//! reports it as a crash). They live in this normal library so that
//! `tests/fuzz_corpus.rs` runs them on the seed corpora on stable Rust in CI.
//!
//! Input layouts:
//! - [`dataset`]: the `manifest.toml` text, then zero or more files, each introduced by a
//!   line `@@ NAME` (see [`split_dataset_input`]).
//! - [`study()`]: the study-file TOML text.
//! - [`identification`]: the `identification.json` text.
//! - [`cli`]: lines `FLAG VALUE` of the numeric command-line flags.
//! - [`aero_files`]: a structure or model file (the same bytes read as each).
//! - [`part()`]: a part document of `merge`.
//! - [`results`]: a result file `plot` reads (`flutter.json`, `lco.json`, `cases.json`, a
//!   case series).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use aeroelastic::aero::{AeroModel, Flow};
use aeroelastic::identified::{IdentifiedLaw, IdentifiedOptions, MissingDerivative};
use identify::dataset::{check_sampling, parse_case_csv, read_dataset, Manifest, MANIFEST_FILE};
use identify::pipeline::Identification;

use crate::study_spec::Study;

/// The separator that introduces a file of a [`dataset`] input: `\n@@ NAME\n`.
pub const FILE_MARKER: &[u8] = b"\n@@ ";

/// Splits a [`dataset`] input into the manifest bytes and `(file name, bytes)` pairs.
///
/// The input is `MANIFEST (\n@@ NAME\nCONTENT)*`. A NAME that is not a plain file name
/// (`[A-Za-z0-9._-]+`, not `.`/`..`/`manifest.toml`, at most 64 bytes) is replaced by
/// `fileN.csv` (N = 1-based index), so a harness never writes outside its folder.
pub fn split_dataset_input(data: &[u8]) -> (&[u8], Vec<(String, &[u8])>) {
    let mut parts = split_on(data, FILE_MARKER);
    let manifest = parts.remove(0);
    let files = parts
        .into_iter()
        .enumerate()
        .map(|(i, part)| {
            let (name, body) = match part.iter().position(|&b| b == b'\n') {
                Some(p) => (&part[..p], &part[p + 1..]),
                None => (part, &part[part.len()..]),
            };
            let name = std::str::from_utf8(name).unwrap_or("").trim();
            let ok = !name.is_empty()
                && name.len() <= 64
                && name != "."
                && name != ".."
                && name != MANIFEST_FILE
                && name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'));
            let name = if ok {
                name.to_string()
            } else {
                format!("file{}.csv", i + 1)
            };
            (name, body)
        })
        .collect();
    (manifest, files)
}

fn split_on<'a>(data: &'a [u8], sep: &[u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut i = 0;
    while i + sep.len() <= data.len() {
        if &data[i..i + sep.len()] == sep {
            out.push(&data[start..i]);
            i += sep.len();
            start = i;
        } else {
            i += 1;
        }
    }
    out.push(&data[start..]);
    out
}

/// A scratch folder unique to this process and call (under `std::env::temp_dir()`),
/// removed on drop.
struct Scratch(PathBuf);

impl Scratch {
    fn new() -> Option<Scratch> {
        static N: AtomicUsize = AtomicUsize::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("aeroform-fuzz-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).ok()?;
        Some(Scratch(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Dataset harness: the manifest parser, the case-CSV parser and sampling check on every
/// file, and [`read_dataset`] on the whole folder written to a scratch directory.
///
/// Checked invariants: a manifest that parses is written back by [`Manifest::to_toml`] into
/// text that parses to the same manifest (compared through its canonical text); a data set
/// that reads has one record per case, at least 3 samples per channel of equal length, a
/// finite positive `dt`, a finite `t0` and finite SI values.
///
/// # Panics
/// When an invariant fails (that is the point: the fuzzer reports it).
pub fn dataset(data: &[u8]) {
    let (manifest, files) = split_dataset_input(data);
    if let Ok(text) = std::str::from_utf8(manifest) {
        if let Ok(m) = Manifest::parse(text, Path::new(MANIFEST_FILE)) {
            let written = m.to_toml();
            let back = Manifest::parse(&written, Path::new("written.toml"))
                .unwrap_or_else(|e| panic!("written manifest does not parse: {e}\n{written}"));
            assert_eq!(back.to_toml(), written, "manifest round trip changed it");
            assert_eq!(back.cases.len(), m.cases.len());
        }
    }
    for (name, body) in &files {
        let Ok(text) = std::str::from_utf8(body) else {
            continue;
        };
        let path = Path::new(name);
        for forces in [false, true] {
            if let Ok(table) = parse_case_csv(text, path, forces) {
                let n = table.t.len();
                assert!(n >= 3, "{n} rows accepted");
                assert_eq!(table.h.len(), n);
                assert_eq!(table.alpha.len(), n);
                if forces {
                    assert_eq!(table.lift.as_ref().map(Vec::len), Some(n));
                    assert_eq!(table.moment.as_ref().map(Vec::len), Some(n));
                }
                if let Ok((t0, dt)) = check_sampling(&table.t, path, 2) {
                    assert!(t0.is_finite() && dt.is_finite() && dt > 0.0, "{t0} {dt}");
                }
            }
        }
    }
    let Some(scratch) = Scratch::new() else {
        return;
    };
    let dir = scratch.0.join("ds");
    if std::fs::create_dir(&dir).is_err()
        || std::fs::write(dir.join(MANIFEST_FILE), manifest).is_err()
    {
        return;
    }
    for (name, body) in &files {
        if std::fs::write(dir.join(name), body).is_err() {
            return;
        }
    }
    if let Ok(ds) = read_dataset(&dir) {
        assert_eq!(ds.records.len(), ds.manifest.cases.len());
        for r in &ds.records {
            for r in std::iter::once(r).chain(r.nowind.as_deref()) {
                let n = r.h.len();
                assert!(n >= 3);
                assert!(r.dt.is_finite() && r.dt > 0.0 && r.t0.is_finite());
                let chans = [
                    Some(&r.h),
                    Some(&r.alpha),
                    r.lift.as_ref(),
                    r.moment.as_ref(),
                ];
                for c in chans.into_iter().flatten() {
                    assert_eq!(c.len(), n);
                    assert!(c.iter().all(|x| x.is_finite()), "non-finite SI value");
                }
            }
        }
    }
}

/// Study harness: [`Study::parse`] on the text; when it parses, [`Study::figure_kinds`];
/// when it does not, the error's message is formatted (it names a line within the text).
///
/// # Panics
/// When an error names a line past the end of the text.
pub fn study(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Study::parse(text, Path::new("fuzz.toml"), Path::new(".")) {
        Ok(s) => {
            let _ = s.figure_kinds();
            check_study_is_bounded(&s);
        }
        Err(e) => {
            let lines = text.split('\n').count();
            assert!(e.line <= lines, "line {} of {lines}: {e}", e.line);
            let _ = e.to_string();
        }
    }
}

/// A study that parses asks for nothing beyond [`crate::limits`]: generated samples,
/// cases, speeds, periods; every number it hands to a stage is finite.
///
/// # Panics
/// When a parsed study exceeds a cap (the parser let it through).
fn check_study_is_bounded(s: &Study) {
    use crate::limits::*;
    let sp = &s.spec;
    if let Some(d) = &sp.data {
        if let Some(sy) = &d.synthetic {
            let n = sy.config.len() * sy.amplitudes_deg.len() * sy.speeds.len();
            assert!(n <= MAX_CASES, "{n} cases");
            let samples = n as f64 * (sy.duration * sy.rate).ceil();
            assert!(samples <= MAX_SAMPLES, "{samples} samples");
            assert!(sy.speeds.iter().all(|u| *u > 0.0 && *u <= MAX_SPEED));
        }
        if let Some(t) = &d.table_iv {
            let samples = t.repeats as f64 * (t.duration * t.rate).ceil();
            assert!(samples <= MAX_SAMPLES, "{samples} samples");
            assert!(t.sigma.is_finite());
        }
        if let Some(v) = &d.virtual_tunnel {
            let cases = if v.campaign == aeroelastic::tunnel::CampaignName::Paper {
                448.0
            } else {
                64.0
            };
            let records = cases * if v.still_air { 2.0 } else { 1.0 };
            let samples = records * (v.duration * 512.0).ceil();
            assert!(samples <= MAX_SAMPLES, "{samples} samples");
        }
    }
    if let Some(f) = &sp.flutter {
        assert!(f.n_speeds <= MAX_SPEEDS && f.u_max <= MAX_SPEED && f.u_min > 0.0);
    }
    if let Some(l) = &sp.lco {
        assert!(l.speeds.len() <= MAX_SPEEDS);
        assert!(l.max_periods <= MAX_PERIODS && l.phase_periods <= MAX_PHASE_PERIODS);
        assert!(l.perturbation_down_deg.is_finite());
    }
    if let Some(a) = &sp.aero {
        assert!(a.elastic_axis.is_none_or(f64::is_finite));
        assert!(a.rfa_lags.is_none_or(|n| (1..=8).contains(&n)));
    }
    if let Some(st) = &sp.structure.as_ref().map(|s| s.linear) {
        for v in [
            st.mu,
            st.r_alpha2,
            st.sigma,
            st.x_alpha,
            st.semi_chord,
            st.omega_alpha,
        ] {
            assert!(v.is_finite());
        }
    }
}

/// Command-line harness: each line `FLAG VALUE` feeds VALUE to the checker of that
/// numeric flag exactly as the binary does (`--speeds`/`--sweep`:
/// [`crate::limits::parse_speeds`]; `--duration`: [`crate::limits::samples`] with the
/// paper campaign's 448 records at 512 Hz; `--blind`: [`crate::limits::count`];
/// `--alpha0`: [`crate::limits::abs_at_most`]). Unknown flags are skipped.
///
/// # Panics
/// When an accepted value breaks a cap, or an error does not name its flag.
pub fn cli(data: &[u8]) {
    use crate::limits::*;
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for line in text.lines() {
        let Some((flag, value)) = line.trim().split_once(' ') else {
            continue;
        };
        let value = value.trim();
        let named = |e: &LimitError| {
            assert!(
                e.field.starts_with(flag),
                "error for {flag} names {}",
                e.field
            );
        };
        match flag {
            "--speeds" | "--sweep" => match parse_speeds(flag, value) {
                Ok(v) => {
                    assert!(!v.is_empty() && v.len() <= MAX_SPEEDS, "{} speeds", v.len());
                    assert!(v
                        .iter()
                        .all(|u| u.is_finite() && *u > 0.0 && *u <= MAX_SPEED));
                }
                Err(e) => named(&e),
            },
            "--duration" => {
                let Ok(d) = value.parse::<f64>() else {
                    continue;
                };
                match samples(flag, "rate", 448, d, 512.0) {
                    Ok(n) => assert!(n <= MAX_SAMPLES && d > 0.0 && d <= MAX_DURATION),
                    Err(e) => named(&e),
                }
            }
            "--blind" => {
                let Ok(n) = value.parse::<u128>() else {
                    continue;
                };
                match count(flag, n, MAX_BLIND_SETS) {
                    Ok(k) => assert!((1..=MAX_BLIND_SETS).contains(&k)),
                    Err(e) => named(&e),
                }
            }
            "--alpha0" => {
                let Ok(a) = value.parse::<f64>() else {
                    continue;
                };
                match abs_at_most(flag, a, MAX_PITCH_DEG, "deg") {
                    Ok(x) => assert!(x.abs() <= MAX_PITCH_DEG),
                    Err(e) => named(&e),
                }
            }
            _ => {}
        }
    }
}

/// Identification harness: `identification.json` parsing as [`Identification::read`]
/// does it (serde, then the `format` check), then [`IdentifiedLaw::from_identification`]
/// with every [`MissingDerivative`] policy and with the first group alone; a law that
/// builds is evaluated (derivative table at a few K, frequency response and forces).
///
/// # Panics
/// Only if a reader or the law construction panics.
pub fn identification(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(id) = serde_json::from_str::<Identification>(text) else {
        return;
    };
    if id.format != identify::pipeline::FORMAT {
        return;
    }
    let mut variants = Vec::new();
    for missing in [
        MissingDerivative::Error,
        MissingDerivative::Skip,
        MissingDerivative::FlatPlate,
        MissingDerivative::Zero,
    ] {
        let mut o = IdentifiedOptions::new(0.25);
        o.missing = missing;
        variants.push(o);
    }
    if let Some(g) = id.groups.first() {
        let mut o = IdentifiedOptions::new(0.25);
        o.groups = Some(vec![g.name.clone()]);
        o.missing = MissingDerivative::Zero;
        o.rfa_lags = 1;
        variants.push(o);
    }
    for o in &variants {
        let Ok(law) = IdentifiedLaw::from_identification(&id, o) else {
            continue;
        };
        for k in [1e-3, 0.05, 0.3, 1.0, 5.0] {
            let _ = law.table().derivatives(k);
            let _ = law.table().q(k);
        }
        let flow = Flow {
            rho: 1.225,
            u: 10.0,
        };
        let m = law.model();
        let _ = m.frequency_response(&flow, 20.0);
        let lag = vec![0.0; m.n_lag()];
        let _ = m.forces(&flow, [0.001, 0.02], [0.01, 0.1], &lag);
        let _ = law.series(aeroelastic::theodorsen::Derivative::A2);
    }
}

/// Writes `data` as `name` into a fresh [`Scratch`] folder: (folder guard, file path).
fn scratch_file(name: &str, data: &[u8]) -> Option<(Scratch, PathBuf)> {
    let s = Scratch::new()?;
    let p = s.0.join(name);
    std::fs::write(&p, data).ok()?;
    Some((s, p))
}

/// An error of a file reader names the file and is short (issue 39, row 7: every refusal
/// carries its location; a hostile file cannot make a huge message).
///
/// # Panics
/// When the message does not name `name` or is longer than 64 kB.
fn assert_names(message: &str, name: &str) {
    assert!(message.contains(name), "`{name}` not named: {message}");
    assert!(message.len() < 1 << 16, "a {}-byte message", message.len());
}

/// Structure- and model-file harness: the bytes as a file read by
/// [`aeroelastic::files::StructureFile::read`] and by
/// [`aeroelastic::files::LoadedModel::load`] (the readers of `--structure` and `--model`,
/// byte level: UTF-8, byte-order mark, TOML, values, limits).
///
/// # Panics
/// When a refusal does not name the file.
pub fn aero_files(data: &[u8]) {
    if let Some((_s, p)) = scratch_file("fuzz.structure.toml", data) {
        match aeroelastic::files::StructureFile::read(&p) {
            Ok(sf) => {
                let _ = sf.spec();
            }
            Err(e) => assert_names(&e.to_string(), "fuzz.structure.toml"),
        }
    }
    if let Some((_s, p)) = scratch_file("fuzz.model.toml", data) {
        if let Err(e) = aeroelastic::files::LoadedModel::load(&p, Some(0.25)) {
            assert_names(&e.to_string(), "fuzz.model.toml");
        }
    }
}

/// Part-document harness (`aeroform merge`): the bytes read as a part file
/// ([`identify::io::read_text`], JSON) and merged with itself as the only part
/// ([`benchmark::sweep::merge`]); a merged document is a JSON object.
///
/// # Panics
/// Only if a reader or the merge panics, or a merge accepted gives no object.
pub fn part(data: &[u8]) {
    let Some((_s, p)) = scratch_file("fuzz.part.json", data) else {
        return;
    };
    let Ok(text) = identify::io::read_text(&p) else {
        return;
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return;
    };
    if let Ok(doc) = benchmark::sweep::merge(&[("fuzz.part.json".to_string(), v)]) {
        assert!(doc.is_object(), "merged document is not an object");
    }
}

/// Result-file harness (`aeroform plot`): the bytes read by the study crate's JSON reader
/// ([`study::files::read_json`]) as each result file `plot` reads: `flutter.json`,
/// `lco.json`, `cases.json` and a case series.
///
/// # Panics
/// When a refusal does not name the file.
pub fn results(data: &[u8]) {
    use aeroelastic::documents::{FlutterDoc, LcoDoc};
    use identify::record::CaseMeta;
    use identify::series::CaseSeries;
    use study::files::read_json;
    fn one<T: serde::de::DeserializeOwned>(data: &[u8], name: &str) {
        let Some((_s, p)) = scratch_file(name, data) else {
            return;
        };
        if let Err(e) = read_json::<T>(&p) {
            // the context names the file, the cause says what is wrong
            let mut m = e.to_string();
            let mut src = std::error::Error::source(&e);
            while let Some(s) = src {
                m.push_str(&format!(": {s}"));
                src = s.source();
            }
            assert_names(&m, name);
        }
    }
    one::<Vec<FlutterDoc>>(data, "flutter.json");
    one::<LcoDoc>(data, "lco.json");
    one::<Vec<CaseMeta>>(data, "cases.json");
    one::<CaseSeries>(data, "series.json");
}
