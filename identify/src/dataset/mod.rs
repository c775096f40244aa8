//! Data sets: read and write the folder format of DATA_FORMAT.md.
//!
//! A data set is a folder with `manifest.toml` and case CSV files named by the manifest
//! (paths relative to the folder). [`read_dataset`] validates everything and returns
//! [`Record`]s in SI per unit span (h \[m\], α \[rad\], L \[N/m\], M \[N·m/m\]; DESIGN.md §2
//! signs); [`write_dataset`] converts back into the manifest's units. Every violation of
//! the format is an [`crate::Error`] naming the file, the 1-based line and the field.

mod convention;
mod csv;
mod manifest;
mod units;
mod write;

use std::path::{Path, PathBuf};

pub use self::convention::{Angular, Convention, Linear};
pub use self::csv::{
    check_sampling, parse_case_csv, read_case_csv, read_case_csv_stamped, CaseTable,
};
pub use self::manifest::{
    is_valid_case_id, CaseSpec, Manifest, ModalStructure, FORMAT, PLAUSIBLE_MAX,
};
pub use self::units::{AngleUnit, ForceUnit, LengthUnit, MomentUnit, Units};
pub use self::write::write_dataset;
pub use crate::record::{CaseKind, CaseMeta, Record, SectionGeometry};

use crate::Result;

/// File name of the manifest inside a data-set folder.
pub const MANIFEST_FILE: &str = "manifest.toml";

/// File name of the JSON form of the manifest, read when there is no `manifest.toml`.
pub const MANIFEST_JSON_FILE: &str = "manifest.json";

/// The manifest file of a data-set folder: `manifest.toml`, or `manifest.json` when only
/// that exists.
pub fn manifest_path(dir: &Path) -> PathBuf {
    let toml = dir.join(MANIFEST_FILE);
    let json = dir.join(MANIFEST_JSON_FILE);
    if !toml.exists() && json.exists() {
        json
    } else {
        toml
    }
}

/// A data set read from a folder: the manifest and one [`Record`] per case, in manifest
/// order, SI per unit span.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// The data-set folder.
    pub root: PathBuf,
    /// The validated manifest.
    pub manifest: Manifest,
    /// `records[i]` is the case `manifest.cases[i]`.
    pub records: Vec<Record>,
}

impl Dataset {
    /// The record of the case with this id.
    pub fn record(&self, id: &str) -> Option<&Record> {
        self.records.iter().find(|r| r.meta.id == id)
    }
}

/// Reads a whole data set (`dir/manifest.toml`, or `dir/manifest.json` when there is no
/// TOML manifest, and every case file it names).
///
/// # Errors
/// [`crate::Error::Io`] when a file cannot be read; [`crate::Error::Manifest`],
/// [`crate::Error::Csv`] or [`crate::Error::NonUniformSampling`] naming file, line and field
/// for any violation of DATA_FORMAT.md (see [`Manifest::parse`] and [`read_case`]); a
/// case path that leaves the folder (see [`read_case`]) is refused before any case file is
/// read; an unfinished aeroform folder is refused ([`crate::io::check_complete_folder`]).
pub fn read_dataset(dir: &Path) -> Result<Dataset> {
    read_dataset_with(dir, &ReadOptions::default())
}

/// Options of [`read_dataset_with`] that change how a data set's columns are interpreted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ReadOptions {
    /// Reverse the lift direction the manifest declares (`[convention] lift`, `"down"` when
    /// absent) before reading: the `--flip-lift` flag for data exported lift-positive-up
    /// without a declaration. The returned manifest carries the convention actually used.
    pub flip_lift: bool,
}

/// [`read_dataset`] with [`ReadOptions`].
///
/// # Errors
/// As [`read_dataset`].
pub fn read_dataset_with(dir: &Path, options: &ReadOptions) -> Result<Dataset> {
    // the folder's identity before and after reading: a writer that replaces the set
    // (`tunnel … --out` swaps a new folder in) while it is read must not leave a data set
    // built from old and new files together (issue 39, row 2c)
    let before = FolderStamp::of(dir);
    let set = read_dataset_once(dir, options)?;
    before.check(dir)?;
    Ok(set)
}

/// What a data-set folder is (device, inode and the modification time of its completion
/// marker): [`FolderStamp::of`] before and after reading its files case by case tells a set
/// swapped for another while it was read (issue 39, row 2c), as [`read_dataset_with`] does.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FolderStamp(Option<(u64, u64, Option<std::time::SystemTime>)>);

impl FolderStamp {
    /// The stamp of `dir` now.
    pub fn of(dir: &Path) -> Self {
        Self(folder_identity(dir))
    }

    /// `Ok` when `dir` is still the folder stamped `self`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] (interrupted) naming `dir`: the set was replaced or rewritten.
    pub fn check(&self, dir: &Path) -> Result<()> {
        if folder_identity(dir) == self.0 {
            return Ok(());
        }
        Err(crate::Error::io(
            dir,
            std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "the data set was replaced by another process while it was read; read it again",
            ),
        ))
    }
}

/// (device, inode, modification time) of a folder and of its completion marker: changes when
/// the folder is swapped for another, or rewritten.
fn folder_identity(dir: &Path) -> Option<(u64, u64, Option<std::time::SystemTime>)> {
    let m = std::fs::metadata(dir).ok()?;
    let marker = std::fs::metadata(dir.join(crate::io::COMPLETE_MARKER))
        .and_then(|m| m.modified())
        .ok();
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((m.dev(), m.ino(), marker))
    }
    #[cfg(not(unix))]
    {
        Some((0, 0, marker.or(m.modified().ok())))
    }
}

fn read_dataset_once(dir: &Path, options: &ReadOptions) -> Result<Dataset> {
    let manifest = open_dataset(dir, options)?;
    // the samples held, bounded as the generators' are (MAX_SAMPLES: about 1 GB of columns)
    let mut samples = SampleCount::default();
    let mut records = Vec::with_capacity(manifest.cases.len());
    for c in &manifest.cases {
        let r = read_case(dir, &manifest, c)?;
        samples.add(dir, c, &r)?;
        records.push(r);
    }
    Ok(Dataset {
        root: dir.to_path_buf(),
        manifest,
        records,
    })
}

/// The running count of the samples of a data set's records, against the limits table's
/// `MAX_SAMPLES` (the same bound whether the records are held together or read one by one).
#[derive(Debug, Clone, Copy, Default)]
pub struct SampleCount(usize);

impl SampleCount {
    /// Adds the samples of `record` (its still-air run included), the record of `case` in
    /// the data set `dir`.
    ///
    /// # Errors
    /// [`crate::Error::Manifest`] naming the manifest and the case at which the total
    /// exceeds `MAX_SAMPLES`.
    pub fn add(&mut self, dir: &Path, case: &CaseSpec, record: &Record) -> Result<()> {
        self.add_samples(dir, case, Self::of(record))
    }

    /// The samples [`SampleCount::add`] counts for `record` (its own and its still-air
    /// record's).
    pub fn of(record: &Record) -> usize {
        record.len() + record.nowind.as_ref().map_or(0, |s| s.len())
    }

    /// [`SampleCount::add`] for a record of `samples` samples ([`SampleCount::of`]), counted
    /// once the record itself is gone.
    ///
    /// # Errors
    /// As [`SampleCount::add`].
    pub fn add_samples(&mut self, dir: &Path, case: &CaseSpec, samples: usize) -> Result<()> {
        self.0 += samples;
        if self.0 as f64 > crate::limits::MAX_SAMPLES {
            return Err(crate::Error::Manifest {
                path: manifest_path(dir),
                line: 0,
                field: "case".into(),
                message: format!(
                    "the case files hold more than {} samples in all (reached at case `{}`; the limits table's MAX_SAMPLES)",
                    crate::limits::show(crate::limits::MAX_SAMPLES),
                    case.id
                ),
            });
        }
        Ok(())
    }
}

/// Reads and checks a data set's manifest and every case path it names, without reading
/// any case file: the first part of [`read_dataset_with`], for readers that then read the
/// cases one by one ([`read_case_stamped`]). The folder must be complete, the manifest
/// valid, its `[[case]]` entries at most `MAX_DATASET_CASES`, no file named by two cases,
/// no path leaving the folder. With `options.flip_lift` the returned manifest carries the
/// flipped convention.
///
/// # Errors
/// As [`read_dataset`], for everything but the case files' contents.
pub fn open_dataset(dir: &Path, options: &ReadOptions) -> Result<Manifest> {
    crate::io::check_complete_folder(dir)?;
    let mut manifest = Manifest::read(&manifest_path(dir))?;
    if options.flip_lift {
        manifest.convention = manifest.convention.with_lift_flipped();
    }
    let n_cases = manifest.cases.len();
    if n_cases > crate::limits::MAX_DATASET_CASES {
        return Err(crate::Error::Manifest {
            path: manifest_path(dir),
            line: 0,
            field: "case".into(),
            message: format!(
                "{n_cases} [[case]] entries; at most {} (the limits table's MAX_DATASET_CASES)",
                crate::limits::MAX_DATASET_CASES
            ),
        });
    }
    // One file is one record: a file named by two cases is refused before any is read (a
    // hostile manifest naming one file 10,000 times took 27 s and 3 GB, issue 39, row 5).
    let mut seen: std::collections::HashMap<&Path, &str> = std::collections::HashMap::new();
    for case in &manifest.cases {
        if let Some(first) = seen.insert(case.file.as_path(), &case.id) {
            let text = std::fs::read_to_string(manifest_path(dir)).unwrap_or_default();
            let (field, line) =
                manifest::case_key_location(&text, &manifest_path(dir), &case.id, "file");
            return Err(crate::Error::Manifest {
                path: manifest_path(dir),
                line,
                field,
                message: format!(
                    "file \"{}\" is already the record of case `{first}`; each case has its own file",
                    case.file.display()
                ),
            });
        }
    }
    // Refuse every path that leaves the folder before reading any case file.
    for case in &manifest.cases {
        resolve_case_path(dir, case, "file", &case.file)?;
        if let Some(still) = &case.nowind_file {
            resolve_case_path(dir, case, "nowind_file", still)?;
        }
    }
    Ok(manifest)
}

/// Reads one case of a data set in folder `dir` and converts it to SI per unit span and to
/// the Scanlan sign convention (each column times the sign of `manifest.convention`).
///
/// `t0` and `dt` are the least-squares intercept and slope of `t` against the row index
/// ([`check_sampling`]). When the case names a `nowind_file`, that still-air run is read the
/// same way (its `lift` and `moment` are required: they are the raw balance forces) into
/// [`Record::nowind`].
///
/// # Errors
/// [`crate::Error::Io`] when a file cannot be read; [`crate::Error::Csv`] (missing column —
/// `lift`, `moment` are required for forced cases —, wrong field count, empty, unparsable or
/// non-finite value, fewer than 3 rows, a value that overflows when converted to SI per
/// unit span) and [`crate::Error::NonUniformSampling`] (first bad row), each naming the
/// file, line and column; [`crate::Error::Manifest`] naming the manifest line and field
/// when `file` or `nowind_file` is absolute, has a `..` component or resolves outside `dir`
/// through a symbolic link, or when `freq_pitch`/`freq_heave` is not below the record's
/// Nyquist frequency; [`crate::Error::Csv`] for a value beyond [`MAX_ABS_SI`].
pub fn read_case(dir: &Path, manifest: &Manifest, case: &CaseSpec) -> Result<Record> {
    read_case_stamped(dir, manifest, case).map(|(r, _)| r)
}

/// What the files of one case were when read: the case file and its still-air run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CaseStamps {
    /// The case file `file`.
    pub file: crate::io::FileStamp,
    /// The still-air run `nowind_file`, when the case names one.
    pub nowind: Option<crate::io::FileStamp>,
}

/// [`read_case`], with the stamps (size, modification time, content fingerprint) of the
/// files read, taken in the same pass ([`read_case_csv_stamped`]).
///
/// # Errors
/// As [`read_case`].
pub fn read_case_stamped(
    dir: &Path,
    manifest: &Manifest,
    case: &CaseSpec,
) -> Result<(Record, CaseStamps)> {
    let meta = manifest.case_meta(case);
    let file = resolve_case_path(dir, case, "file", &case.file)?;
    let still_file = match &case.nowind_file {
        Some(p) => Some(resolve_case_path(dir, case, "nowind_file", p)?),
        None => None,
    };
    let (mut rec, file_stamp) = read_record(
        &file,
        manifest,
        case.kind,
        case.kind == CaseKind::Forced,
        meta.clone(),
    )?;
    let mut stamps = CaseStamps {
        file: file_stamp,
        nowind: None,
    };
    if let Some(still) = &still_file {
        let (still, stamp) = read_record(still, manifest, case.kind, true, meta)?;
        rec.nowind = Some(Box::new(still));
        stamps.nowind = Some(stamp);
    }
    // A forcing frequency at or above Nyquist cannot be in the record: refuse it (it would
    // otherwise silently null the derivatives of the case).
    let nyquist = 0.5 / rec.dt;
    for (key, f) in [
        ("freq_pitch", case.freq_pitch),
        ("freq_heave", case.freq_heave),
    ] {
        if let Some(f) = f.filter(|f| *f >= nyquist) {
            let manifest_path = dir.join(MANIFEST_FILE);
            let text = std::fs::read_to_string(&manifest_path).unwrap_or_default();
            let (field, line) = manifest::case_key_location(&text, &manifest_path, &case.id, key);
            return Err(crate::Error::Manifest {
                path: manifest_path,
                line,
                field,
                message: format!(
                    "{f} Hz is not below the Nyquist frequency {nyquist} Hz of {} \
                     (sample interval {} s)",
                    file.display(),
                    rec.dt
                ),
            });
        }
    }
    // A declared forcing frequency the record does not hold (a typo, a frequency in rad/s,
    // 10× the true one) would silently rescale every derivative (issue 27, row 16).
    if case.kind == CaseKind::Forced {
        for (key, f, x) in [
            ("freq_pitch", case.freq_pitch, &rec.alpha),
            ("freq_heave", case.freq_heave, &rec.h),
        ] {
            let Some(f) = f else { continue };
            if let Some((f_rec, share_rec, share_decl)) = declared_frequency_missing(x, rec.dt, f) {
                let manifest_path = dir.join(MANIFEST_FILE);
                let text = std::fs::read_to_string(&manifest_path).unwrap_or_default();
                let (field, line) =
                    manifest::case_key_location(&text, &manifest_path, &case.id, key);
                return Err(crate::Error::Manifest {
                    path: manifest_path,
                    line,
                    field,
                    message: format!(
                        "{f} Hz is not in the record {}: its motion oscillates at {f_rec:.4} Hz \
                         ({:.0} % of its variance), a sinusoid at {f} Hz explains {:.1} %",
                        file.display(),
                        100.0 * share_rec,
                        100.0 * share_decl.max(0.0)
                    ),
                });
            }
        }
    }
    Ok((rec, stamps))
}

/// Relative distance between a declared forcing frequency and the record's own beyond
/// which [`declared_frequency_missing`] looks further.
pub const DECLARED_FREQUENCY_TOL: f64 = 0.05;

/// `Some((f_record, share_record, share_declared))` when a forced record `x` (sampled every
/// `dt` s) does not hold its declared forcing frequency `f`: its dominant frequency differs
/// from `f` by more than [`DECLARED_FREQUENCY_TOL`], a sinusoid there explains at least half
/// of its variance, and one at `f` explains less than a tenth of that. A channel without
/// a dominant oscillation (a DOF not forced: noise) passes.
pub fn declared_frequency_missing(x: &[f64], dt: f64, f: f64) -> Option<(f64, f64, f64)> {
    let f0 = crate::preprocess::dominant_frequency(x, dt)?;
    let f_rec = crate::preprocess::refine_frequency(x, dt, f0);
    if (f_rec / f - 1.0).abs() <= DECLARED_FREQUENCY_TOL {
        return None;
    }
    let (share_rec, _) = crate::preprocess::harmonic_share(x, dt, f_rec)?;
    let (share_decl, _) = crate::preprocess::harmonic_share(x, dt, f)?;
    (share_rec >= 0.5 && share_decl < 0.1 * share_rec).then_some((f_rec, share_rec, share_decl))
}

/// `dir.join(rel)` when the file `rel` named by `case.<key>` stays inside the data-set
/// folder `dir`.
///
/// Refused: an absolute path or one with a `..` component (as [`Manifest::parse`] does, for
/// manifests built in code), and a path that resolves outside the folder through a
/// symbolic link (a link as the file itself or as a folder on the way): both the folder and
/// the file are canonicalised and the file must lie under the folder. Links that stay
/// inside are accepted. A file that does not exist is refused naming the manifest line and
/// key.
///
/// # Errors
/// [`crate::Error::Manifest`] naming `dir/manifest.toml`, the line of the key, the field
/// (`case[i].file` / `case[i].nowind_file`), the path and where it resolves, or that it does
/// not exist;
/// [`crate::Error::Io`] when the folder itself cannot be resolved.
fn resolve_case_path(dir: &Path, case: &CaseSpec, key: &str, rel: &Path) -> Result<PathBuf> {
    let manifest_path = self::manifest_path(dir);
    let refuse = |why: String| {
        let text = std::fs::read_to_string(&manifest_path).unwrap_or_default();
        let (field, line) = manifest::case_key_location(&text, &manifest_path, &case.id, key);
        crate::Error::Manifest {
            path: manifest_path.clone(),
            line,
            field,
            message: format!(
                "path \"{}\" {why}; case files must be inside the data set folder",
                rel.display()
            ),
        }
    };
    if let Some(why) = manifest::unsafe_relative_path(rel) {
        return Err(refuse(why.to_string()));
    }
    let joined = dir.join(rel);
    let real = match std::fs::canonicalize(&joined) {
        Ok(r) => r,
        // a missing case file is refused where it is named: manifest line and key (issue
        // 39, row 7), not as a bare path
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let text = std::fs::read_to_string(&manifest_path).unwrap_or_default();
            let (field, line) = manifest::case_key_location(&text, &manifest_path, &case.id, key);
            return Err(crate::Error::Manifest {
                path: manifest_path.clone(),
                line,
                field,
                message: format!(
                    "path \"{}\": no such file (or a symbolic link to none) in the data set \
                     folder {}",
                    rel.display(),
                    dir.display()
                ),
            });
        }
        Err(_) => return Ok(joined),
    };
    let root = std::fs::canonicalize(dir).map_err(|e| crate::Error::io(dir, e))?;
    if real.starts_with(&root) {
        Ok(joined)
    } else {
        Err(refuse(format!(
            "resolves through a symbolic link to {}, outside the data set folder {}",
            real.display(),
            root.display()
        )))
    }
}

/// Largest magnitude of a case-CSV value after conversion to SI per unit span, per column
/// (name, bound, unit): 1 km of heave (and heave target), 1000 rad of pitch, 1e12 N/m or
/// N·m/m of force (a calibrated control force included), 1e12 raw controller units.
/// Values beyond are refused as physically implausible (docs/DATA_FORMAT.md); they are
/// far outside any wind-tunnel record and keep every cubic library term and its sum of
/// squares finite.
pub const MAX_ABS_SI: [(&str, f64, &str); 7] = [
    ("h", 1e3, "m"),
    ("alpha", 1e3, "rad"),
    ("lift", 1e12, "N/m"),
    ("moment", 1e12, "N*m/m"),
    ("h_target", 1e3, "m"),
    ("control_raw", 1e12, "(raw units)"),
    ("control_force", 1e12, "N/m"),
];

fn read_record(
    path: &Path,
    manifest: &Manifest,
    kind: CaseKind,
    forces_required: bool,
    meta: CaseMeta,
) -> Result<(Record, crate::io::FileStamp)> {
    let (table, stamp) = read_case_csv_stamped(path, forces_required)?;
    Ok((record_from_table(table, path, manifest, kind, meta)?, stamp))
}

/// Converts the columns of one case, in the manifest's units, to a [`Record`] in SI per
/// unit span, as [`read_dataset`] does after reading a case file: the sampling check of
/// DATA_FORMAT.md on `t`, then the unit conversion. `path` names the case in errors (a file
/// or, for columns built in memory, any label); row i is reported as line i + 2.
///
/// # Errors
/// [`crate::Error::NonUniformSampling`] and [`crate::Error::Csv`] as [`check_sampling`];
/// [`crate::Error::Csv`] naming the column and line of a value that is not finite in SI.
pub fn record_from_table(
    table: CaseTable,
    path: &Path,
    manifest: &Manifest,
    kind: CaseKind,
    meta: CaseMeta,
) -> Result<Record> {
    let (t0, dt) = check_sampling(&table.t, path, 2)?;
    let u = &manifest.units;
    let c = &manifest.convention;
    let (sh, sa, sl, sm) = (
        c.heave.sign(),
        c.pitch.sign(),
        c.lift.sign(),
        c.moment.sign(),
    );
    let span = manifest.section.span;
    // Finite in the file's units can overflow in SI (a total force divided by a tiny span):
    // name the first such value. Row i of the table is line i + 2 (header on line 1; blank
    // lines are only allowed at the end).
    // A finite but absurd value (1e308 mm) would overflow later, in the library's cubic
    // terms and their sums of squares: it is refused here, with file, line and column
    // ([`MAX_ABS_SI`]).
    let conv = |v: Vec<f64>, column: &str, f: &dyn Fn(f64) -> f64| -> Result<Vec<f64>> {
        let (max, unit) = MAX_ABS_SI
            .iter()
            .find(|(c, _, _)| *c == column)
            .map(|(_, m, u)| (*m, *u))
            .unwrap_or((f64::MAX, ""));
        let mut v = v;
        for (i, x) in v.iter_mut().enumerate() {
            let y = f(*x);
            if !y.is_finite() {
                return Err(crate::Error::Csv {
                    path: path.to_path_buf(),
                    line: i + 2,
                    field: column.to_string(),
                    message: format!(
                        "{x} is {y} in SI per unit span (span = {span} m): out of range"
                    ),
                });
            }
            if y.abs() > max {
                return Err(crate::Error::Csv {
                    path: path.to_path_buf(),
                    line: i + 2,
                    field: column.to_string(),
                    message: format!(
                        "{x} is {y} {unit} in SI: physically implausible (|{column}| must be \
                         ≤ {max:e} {unit})"
                    ),
                });
            }
            *x = y;
        }
        Ok(v)
    };
    Ok(Record {
        kind,
        meta,
        t0,
        dt,
        h: conv(table.h, "h", &|x| sh * u.heave.to_si(x))?,
        alpha: conv(table.alpha, "alpha", &|x| sa * u.pitch.to_si(x))?,
        lift: table
            .lift
            .map(|v| conv(v, "lift", &|x| sl * u.lift.to_si(x, span)))
            .transpose()?,
        moment: table
            .moment
            .map(|v| conv(v, "moment", &|x| sm * u.moment.to_si(x, span)))
            .transpose()?,
        nowind: None,
        control: control_signal(
            table.h_target,
            table.control_raw,
            table.control_force,
            &conv,
            &|x| sh * u.heave.to_si(x),
            &|x| sl * u.lift.to_si(x, span),
        )?,
    })
}

/// A column converter of [`record_from_table`]: (values, column name, unit map) → SI values.
type Convert<'a> = &'a dyn Fn(Vec<f64>, &str, &dyn Fn(f64) -> f64) -> Result<Vec<f64>>;

/// The control signal of a controlled record (DATA_FORMAT.md, "Controlled records") from
/// its columns: `control_force` converted like lift (`force`), `control_raw` kept in its
/// units, `h_target` converted like heave (`heave`) and kept only with a control column;
/// `None` without a control column.
fn control_signal(
    h_target: Option<Vec<f64>>,
    raw: Option<Vec<f64>>,
    force: Option<Vec<f64>>,
    conv: Convert<'_>,
    heave: &dyn Fn(f64) -> f64,
    lift: &dyn Fn(f64) -> f64,
) -> Result<Option<crate::record::ControlSignal>> {
    let (calibrated, values) = match (raw, force) {
        (Some(v), None) => (false, conv(v, "control_raw", &|x| x)?),
        (None, Some(v)) => (true, conv(v, "control_force", lift)?),
        // both: refused by the reader; a table built in code keeps the calibrated one
        (Some(_), Some(v)) => (true, conv(v, "control_force", lift)?),
        (None, None) => return Ok(None),
    };
    let h_target = h_target.map(|v| conv(v, "h_target", heave)).transpose()?;
    Ok(Some(crate::record::ControlSignal {
        calibrated,
        values,
        h_target,
    }))
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod path_tests;
