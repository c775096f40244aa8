//! Shared helpers of the property tests (`props_*.rs`): a small synthetic forced-motion
//! campaign in SI, a manifest for it in any units, and the whole chain records →
//! preprocessing → identification.

#![allow(dead_code)]

use std::path::Path;

use identify::dataset::{
    read_dataset, write_dataset, AngleUnit, CaseSpec, Dataset, ForceUnit, LengthUnit, Manifest,
    MomentUnit, Units,
};
use identify::pipeline::{identify, Identification, IdentifySettings};
use identify::preprocess::PreprocessOptions;
use identify::record::{CaseMeta, Record, SectionGeometry};
use identify::synthetic::{forced_record, HarmonicMotion, PolynomialLaw, Sampling};
use identify::workflow::prepare_dataset;

/// Section geometry of every synthetic campaign (B = 0.25 m as the paper's plate).
pub fn section(span: f64) -> SectionGeometry {
    SectionGeometry {
        chord: 0.25,
        span,
        air_density: 1.225,
    }
}

/// One synthetic case: configuration label, forcing, amplitudes, wind speed.
#[derive(Debug, Clone)]
pub struct CaseDef {
    pub id: String,
    pub config: String,
    pub motion: HarmonicMotion,
    pub wind_speed: f64,
}

/// `n_configs` configurations × `per_config` (amplitude, wind speed) cases; configuration c
/// forces pitch at 1.5 + 0.25c Hz and heave at 0.7·f_α + 0.13 Hz (two incommensurate tones,
/// as in the paper's Table I).
pub fn case_defs(n_configs: usize, per_config: usize) -> Vec<CaseDef> {
    let mut out = Vec::new();
    for c in 0..n_configs {
        let fa = 1.5 + 0.25 * c as f64;
        let label = ((b'A' + c as u8) as char).to_string();
        for k in 0..per_config {
            let amp_deg = 8.0 + 6.0 * k as f64;
            let wind = 6.0 + 1.5 * k as f64;
            out.push(CaseDef {
                id: format!("{label}-U{wind}-A{amp_deg}"),
                config: label.clone(),
                motion: HarmonicMotion {
                    freq_pitch: fa,
                    freq_heave: 0.7 * fa + 0.13,
                    amp_pitch: amp_deg.to_radians(),
                    amp_heave: 0.002 * (1.0 + k as f64),
                    mean_pitch: 0.0,
                },
                wind_speed: wind,
            });
        }
    }
    out
}

/// SI records of `defs` with forces from `law` (`Record`s per unit span) and the matching
/// manifest in `units`.
pub fn campaign(
    defs: &[CaseDef],
    law: &PolynomialLaw,
    sampling: &Sampling,
    span: f64,
    units: Units,
    seed: u64,
) -> (Manifest, Vec<Record>) {
    let sec = section(span);
    let mut records = Vec::new();
    let mut cases = Vec::new();
    for (i, d) in defs.iter().enumerate() {
        let meta = CaseMeta {
            id: d.id.clone(),
            wind_speed: d.wind_speed,
            config: Some(d.config.clone()),
            amplitude: Some(d.motion.amp_pitch),
            freq_pitch: Some(d.motion.freq_pitch),
            freq_heave: Some(d.motion.freq_heave),
            ..CaseMeta::default()
        };
        let r = forced_record(meta, &sec, &d.motion, law, sampling, seed + i as u64)
            .expect("valid synthetic record");
        records.push(r);
        cases.push(CaseSpec {
            config: Some(d.config.clone()),
            amplitude: Some(units.pitch.from_si(d.motion.amp_pitch)),
            freq_pitch: Some(d.motion.freq_pitch),
            freq_heave: Some(d.motion.freq_heave),
            ..CaseSpec::forced(d.id.clone(), format!("cases/{}.csv", d.id), d.wind_speed)
        });
    }
    let manifest = Manifest {
        name: "props".into(),
        description: None,
        section: sec,
        structure: None,
        units,
        convention: Default::default(),
        cases,
        extra: None,
    };
    (manifest, records)
}

/// The manifest with other units (values of `amplitude`/`mean_pitch` converted).
pub fn with_units(m: &Manifest, units: Units) -> Manifest {
    let mut out = m.clone();
    let from = m.units.pitch;
    out.units = units;
    for c in &mut out.cases {
        c.amplitude = c.amplitude.map(|a| units.pitch.from_si(from.to_si(a)));
        c.mean_pitch = c.mean_pitch.map(|a| units.pitch.from_si(from.to_si(a)));
    }
    out
}

/// Units from four choices (false = SI per unit span).
pub fn units(mm: bool, deg: bool, lift_total: bool, moment_total: bool) -> Units {
    Units {
        heave: if mm { LengthUnit::Mm } else { LengthUnit::M },
        pitch: if deg { AngleUnit::Deg } else { AngleUnit::Rad },
        lift: if lift_total {
            ForceUnit::N
        } else {
            ForceUnit::NPerM
        },
        moment: if moment_total {
            MomentUnit::Nm
        } else {
            MomentUnit::NmPerM
        },
    }
}

/// Preprocesses and identifies a data set with `settings` (default preprocessing).
pub fn identify_dataset(ds: &Dataset, settings: &IdentifySettings) -> Identification {
    let prepared = prepare_dataset(ds, &PreprocessOptions::default()).expect("preprocessing");
    identify(&prepared.cases, settings, &ds.manifest.name, &|_| {}).expect("identification")
}

/// Identifies records in memory (no file).
pub fn identify_records(
    manifest: &Manifest,
    records: Vec<Record>,
    settings: &IdentifySettings,
) -> Identification {
    let ds = Dataset {
        root: ".".into(),
        manifest: manifest.clone(),
        records,
    };
    identify_dataset(&ds, settings)
}

/// Writes the data set to `dir` and reads it back.
pub fn write_read(dir: &Path, manifest: &Manifest, records: &[Record]) -> Dataset {
    write_dataset(dir, manifest, records).expect("write data set");
    read_dataset(dir).expect("read data set")
}

/// `|a − b| ≤ tol·max(|a|, |b|)` (both exactly zero passes).
pub fn rel_close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs())
}

/// Every Eq. 19 derivative, R², MFWA, key-frequency loss and raw term coefficient of two
/// identifications, matched by case id: supports identical, numbers within `tol` relative.
/// Returns the first mismatch as text.
pub fn compare_identifications(
    a: &Identification,
    b: &Identification,
    tol: f64,
) -> Result<(), String> {
    if a.cases.len() != b.cases.len() {
        return Err(format!("{} vs {} cases", a.cases.len(), b.cases.len()));
    }
    let ga: Vec<_> = a
        .groups
        .iter()
        .map(|g| (&g.name, &g.moment.support, &g.lift.support))
        .collect();
    let gb: Vec<_> = b
        .groups
        .iter()
        .map(|g| (&g.name, &g.moment.support, &g.lift.support))
        .collect();
    if ga != gb {
        return Err(format!("supports differ:\n{ga:?}\n{gb:?}"));
    }
    for ca in &a.cases {
        let cb = b
            .cases
            .iter()
            .find(|c| c.id == ca.id)
            .ok_or_else(|| format!("case {} missing", ca.id))?;
        let pairs = [
            (
                "moment",
                serde_json::to_value(&ca.moment).unwrap(),
                serde_json::to_value(&cb.moment).unwrap(),
            ),
            (
                "lift",
                serde_json::to_value(&ca.lift).unwrap(),
                serde_json::to_value(&cb.lift).unwrap(),
            ),
        ];
        for (force, va, vb) in pairs {
            compare_json(&va, &vb, tol, &format!("{}.{force}", ca.id))?;
        }
    }
    Ok(())
}

/// Numbers within `tol` relative, everything else equal.
fn compare_json(
    a: &serde_json::Value,
    b: &serde_json::Value,
    tol: f64,
    at: &str,
) -> Result<(), String> {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if rel_close(x, y, tol) {
                Ok(())
            } else {
                Err(format!(
                    "{at}: {x} vs {y} (rel {:.3e})",
                    (x - y).abs() / x.abs().max(y.abs())
                ))
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                compare_json(p, q, tol, &format!("{at}[{i}]"))?;
            }
            Ok(())
        }
        (Value::Object(x), Value::Object(y)) if x.len() == y.len() => {
            for (k, p) in x {
                let q = y.get(k).ok_or_else(|| format!("{at}.{k} missing"))?;
                compare_json(p, q, tol, &format!("{at}.{k}"))?;
            }
            Ok(())
        }
        _ if a == b => Ok(()),
        _ => Err(format!("{at}: {a} vs {b}")),
    }
}
