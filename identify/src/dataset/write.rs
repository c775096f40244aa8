//! Data-set writer: case CSVs in the manifest's units, then the manifest, all atomic.

use std::fmt::Write as _;
use std::path::Path;

use super::manifest::{CaseSpec, Manifest};
use crate::io::write_atomic;
use crate::record::{CaseKind, Record};
use crate::{Error, Result};

/// A float in shortest round-trip form; exponent notation for very small or large
/// magnitudes so that lines stay short.
fn num(s: &mut String, x: f64) {
    let a = x.abs();
    if a == 0.0 || (1e-5..1e16).contains(&a) {
        let _ = write!(s, "{x}");
    } else {
        let _ = write!(s, "{x:e}");
    }
}

fn bad(case: &str, field: &str, message: String) -> Error {
    Error::InvalidData {
        case: case.to_string(),
        field: field.to_string(),
        message,
    }
}

/// Checks a record before writing it: equal column lengths, finite values, forces for
/// forced cases, a valid time base.
fn check_record(id: &str, r: &Record, what: &str, need_forces: bool) -> Result<()> {
    let n = r.alpha.len();
    if !(r.dt.is_finite() && r.dt > 0.0 && r.t0.is_finite()) {
        return Err(bad(
            id,
            "t",
            format!(
                "{what}: time base t0 = {} s, dt = {} s is not valid",
                r.t0, r.dt
            ),
        ));
    }
    if n < 3 {
        return Err(bad(
            id,
            "t",
            format!("{what}: {n} samples; at least 3 are needed"),
        ));
    }
    let ctl = r.control.as_ref();
    let cols: [(&str, Option<&Vec<f64>>); 6] = [
        ("h", Some(&r.h)),
        ("alpha", Some(&r.alpha)),
        ("lift", r.lift.as_ref()),
        ("moment", r.moment.as_ref()),
        (
            if ctl.is_some_and(|c| c.calibrated) {
                "control_force"
            } else {
                "control_raw"
            },
            ctl.map(|c| &c.values),
        ),
        ("h_target", ctl.and_then(|c| c.h_target.as_ref())),
    ];
    // the control columns (the last two) are never required
    for (k, (name, col)) in cols.into_iter().enumerate() {
        match col {
            None if need_forces && k < 4 => {
                return Err(bad(
                    id,
                    name,
                    format!("{what}: `{name}` is required (forced case or still-air run)"),
                ))
            }
            None => {}
            Some(c) => {
                if c.len() != n {
                    return Err(bad(
                        id,
                        name,
                        format!("{what}: {} samples but `alpha` has {n}", c.len()),
                    ));
                }
                if let Some(i) = c.iter().position(|x| !x.is_finite()) {
                    return Err(bad(
                        id,
                        name,
                        format!("{what}: non-finite value {} at sample {i}", c[i]),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The CSV text of a record in the manifest's units (tests read it back).
#[cfg(test)]
pub(crate) fn case_csv_text(manifest: &Manifest, r: &Record) -> String {
    case_csv(manifest, r)
}

/// The CSV text of a record in the manifest's units.
fn case_csv(manifest: &Manifest, r: &Record) -> String {
    let u = &manifest.units;
    let c = &manifest.convention;
    let span = manifest.section.span;
    let ncols = 3 + r.lift.is_some() as usize + r.moment.is_some() as usize;
    let mut s = String::with_capacity(r.len() * 22 * ncols + 32);
    s.push_str("t,h,alpha");
    if r.lift.is_some() {
        s.push_str(",lift");
    }
    if r.moment.is_some() {
        s.push_str(",moment");
    }
    let ctl = r.control.as_ref();
    if let Some(c) = ctl {
        s.push_str(if c.calibrated {
            ",control_force"
        } else {
            ",control_raw"
        });
        if c.h_target.is_some() {
            s.push_str(",h_target");
        }
    }
    s.push('\n');
    for i in 0..r.len() {
        num(&mut s, r.t0 + i as f64 * r.dt);
        s.push(',');
        num(&mut s, c.heave.sign() * u.heave.from_si(r.h[i]));
        s.push(',');
        num(&mut s, c.pitch.sign() * u.pitch.from_si(r.alpha[i]));
        if let Some(l) = &r.lift {
            s.push(',');
            num(&mut s, c.lift.sign() * u.lift.from_si(l[i], span));
        }
        if let Some(m) = &r.moment {
            s.push(',');
            num(&mut s, c.moment.sign() * u.moment.from_si(m[i], span));
        }
        if let Some(k) = ctl {
            s.push(',');
            let v = k.values[i];
            num(
                &mut s,
                if k.calibrated {
                    c.lift.sign() * u.lift.from_si(v, span)
                } else {
                    v
                },
            );
            if let Some(t) = &k.h_target {
                s.push(',');
                num(&mut s, c.heave.sign() * u.heave.from_si(t[i]));
            }
        }
        s.push('\n');
    }
    s
}

fn write_file(dir: &Path, rel: &Path, text: &str) -> Result<()> {
    // the folders below `dir` only: an interrupt that took `dir` away must not see it
    // recreated here
    if let Some(sub) = rel.parent() {
        crate::io::create_dir_below(dir, sub)?;
    }
    write_atomic(&dir.join(rel), text.as_bytes())
}

/// Writes a data set: `records[i]` is the case `manifest.cases[i]` (same id), SI per unit
/// span; each is written to its `file` (and its `nowind` record to `nowind_file`) in the
/// manifest's units (totals are multiplied by `section.span`), with `t = t0 + i·dt`. The
/// case files are written first and `manifest.toml` last, every file atomically, so a
/// reader never sees a manifest naming an incomplete file. Folders are created as needed.
///
/// # Errors
/// [`Error::InvalidData`] when the records do not match the manifest's cases (count, id,
/// still-air run present exactly when `nowind_file` is named), or a record is not
/// writable (unequal column lengths, non-finite value, forced case without forces, fewer
/// than 3 samples, invalid time base), or a `file`/`nowind_file` is absolute or has a `..`
/// component; [`Error::Io`] when a file or folder cannot be
/// written.
pub fn write_dataset(dir: &Path, manifest: &Manifest, records: &[Record]) -> Result<()> {
    if records.len() != manifest.cases.len() {
        return Err(bad(
            "(all)",
            "records",
            format!(
                "{} records for {} manifest cases",
                records.len(),
                manifest.cases.len()
            ),
        ));
    }
    let pairs: Vec<(&CaseSpec, &Record)> = manifest.cases.iter().zip(records).collect();
    for (c, r) in &pairs {
        if r.meta.id != c.id {
            return Err(bad(
                &c.id,
                "id",
                format!(
                    "record has id `{}` but the manifest case is `{}`",
                    r.meta.id, c.id
                ),
            ));
        }
        for (field, path) in [
            ("file", Some(&c.file)),
            ("nowind_file", c.nowind_file.as_ref()),
        ] {
            if let Some(why) = path.and_then(|p| super::manifest::unsafe_relative_path(p)) {
                return Err(bad(
                    &c.id,
                    field,
                    format!(
                        "path {} {why}; case files must lie inside the data set folder",
                        path.map(|p| p.display().to_string()).unwrap_or_default()
                    ),
                ));
            }
        }
        check_record(&c.id, r, "record", c.kind == CaseKind::Forced)?;
        match (&c.nowind_file, &r.nowind) {
            (Some(_), Some(still)) => check_record(&c.id, still, "still-air record", true)?,
            (None, None) => {}
            (Some(f), None) => {
                return Err(bad(
                    &c.id,
                    "nowind_file",
                    format!(
                        "manifest names {} but the record has no still-air run",
                        f.display()
                    ),
                ))
            }
            (None, Some(_)) => {
                return Err(bad(
                    &c.id,
                    "nowind_file",
                    "the record has a still-air run but the manifest case names no nowind_file"
                        .into(),
                ))
            }
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for (c, r) in &pairs {
        write_file(dir, &c.file, &case_csv(manifest, r))?;
        if let (Some(f), Some(still)) = (&c.nowind_file, &r.nowind) {
            write_file(dir, f, &case_csv(manifest, still))?;
        }
    }
    write_atomic(&dir.join("manifest.toml"), manifest.to_toml().as_bytes())
}
