//! `aeroform._core`: the Python binding of aeroform. It converts Python values, calls the
//! library crates and returns their documents as JSON text (the same content the command
//! line writes); the Python package `aeroform` (python/aeroform) turns them into dicts and
//! numpy arrays. Every library error becomes `aeroform.AeroformError` (a `ValueError`)
//! carrying the library's message; long computations release the GIL.

use std::fmt::Display;
use std::path::{Path, PathBuf};

use aeroelastic::branch::{measured_distances, read_measured_amplitudes, BranchOptions};
use aeroelastic::documents::{
    branch_csv, branch_document, flutter_document, lco_run_document, lco_sweep_document, LoadedPair,
};
use aeroelastic::flutter::FlutterMethod;
use benchmark::sweep::SweepSpec;
use diagnose::pipeline::DiagnoseOptions;
use identify::dataset::{record_from_table, CaseKind, CaseTable, Dataset, Manifest};
use identify::pipeline::IdentifySettings;
use identify::preprocess::{PreprocessOptions, VelocityMethod};
use identify::workflow::prepare_dataset;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

create_exception!(
    _core,
    AeroformError,
    PyValueError,
    "An aeroform error: bad input (the message names the file, line, field or term) or a \
     computation that cannot proceed."
);

fn err(e: impl Display) -> PyErr {
    AeroformError::new_err(e.to_string())
}

fn to_json<T: serde::Serialize>(v: &T) -> PyResult<String> {
    serde_json::to_string(v).map_err(err)
}

/// A data set (DATA_FORMAT.md) held in memory: manifest and records in SI per unit span.
#[pyclass(module = "aeroform._core", name = "Dataset", frozen)]
pub struct PyDataset {
    inner: Dataset,
}

#[pymethods]
impl PyDataset {
    /// The manifest's `name`.
    #[getter]
    fn name(&self) -> String {
        self.inner.manifest.name.clone()
    }

    /// The folder the data set was read from (`<arrays>` when built from arrays).
    #[getter]
    fn root(&self) -> String {
        self.inner.root.display().to_string()
    }

    /// Case ids in manifest order.
    fn case_ids(&self) -> Vec<String> {
        self.inner
            .manifest
            .cases
            .iter()
            .map(|c| c.id.clone())
            .collect()
    }

    /// The manifest as TOML text (DATA_FORMAT.md layout).
    fn manifest_toml(&self) -> String {
        self.inner.manifest.to_toml()
    }

    /// Per-case metadata (id, kind, wind speed, config, amplitude…) as JSON text.
    fn cases_json(&self) -> PyResult<String> {
        let v: Vec<serde_json::Value> = self
            .inner
            .records
            .iter()
            .map(|r| {
                let mut m = serde_json::to_value(&r.meta).unwrap_or_default();
                m["kind"] = serde_json::to_value(r.kind).unwrap_or_default();
                m["samples"] = r.len().into();
                m["dt"] = r.dt.into();
                m["t0"] = r.t0.into();
                m["has_nowind"] = r.nowind.is_some().into();
                m
            })
            .collect();
        to_json(&v)
    }

    /// The columns of case `id` in SI per unit span: t \[s\], h \[m\], alpha \[rad\], lift
    /// [N/m], moment [N·m/m] (lift and moment absent for a free case without them).
    fn columns<'py>(&self, py: Python<'py>, id: &str) -> PyResult<Bound<'py, PyDict>> {
        let r = self.inner.record(id).ok_or_else(|| {
            err(format!(
                "data set `{}`: no case `{id}`",
                self.inner.manifest.name
            ))
        })?;
        let d = PyDict::new(py);
        let t: Vec<f64> = (0..r.len()).map(|i| r.t0 + r.dt * i as f64).collect();
        d.set_item("t", PyArray1::from_vec(py, t))?;
        d.set_item("h", PyArray1::from_slice(py, &r.h))?;
        d.set_item("alpha", PyArray1::from_slice(py, &r.alpha))?;
        if let Some(l) = &r.lift {
            d.set_item("lift", PyArray1::from_slice(py, l))?;
        }
        if let Some(m) = &r.moment {
            d.set_item("moment", PyArray1::from_slice(py, m))?;
        }
        Ok(d)
    }

    /// Writes the data set as a folder (manifest.toml + one CSV per case, in the
    /// manifest's units).
    fn write(&self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        let ds = &self.inner;
        py.detach(|| identify::dataset::write_dataset(&dir, &ds.manifest, &ds.records))
            .map_err(err)
    }
}

/// Reads a data-set folder (manifest.toml + case CSV files).
#[pyfunction]
fn read_dataset(py: Python<'_>, path: PathBuf) -> PyResult<PyDataset> {
    let ds = py
        .detach(|| identify::dataset::read_dataset(&path))
        .map_err(err)?;
    Ok(PyDataset { inner: ds })
}

/// Builds a data set from a manifest (TOML text; every case's `file` is a placeholder) and
/// per-case columns in the manifest's units, validated as the file reader validates a
/// data set.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn dataset_from_columns(
    manifest_toml: &str,
    ids: Vec<String>,
    t: Vec<PyReadonlyArray1<'_, f64>>,
    h: Vec<PyReadonlyArray1<'_, f64>>,
    alpha: Vec<PyReadonlyArray1<'_, f64>>,
    lift: Vec<Option<PyReadonlyArray1<'_, f64>>>,
    moment: Vec<Option<PyReadonlyArray1<'_, f64>>>,
) -> PyResult<PyDataset> {
    let source = Path::new("<arrays>/manifest.toml");
    let manifest = Manifest::parse(manifest_toml, source).map_err(err)?;
    let n = ids.len();
    if [t.len(), h.len(), alpha.len(), lift.len(), moment.len()]
        .iter()
        .any(|&k| k != n)
    {
        return Err(err(
            "dataset_from_columns: one column list per case id is needed",
        ));
    }
    let mut records = Vec::with_capacity(manifest.cases.len());
    for case in &manifest.cases {
        let k = ids
            .iter()
            .position(|i| *i == case.id)
            .ok_or_else(|| err(format!("case `{}`: no columns given", case.id)))?;
        if case.nowind_file.is_some() {
            return Err(err(format!(
                "case `{}`: `nowind_file` is not supported from arrays (give the aerodynamic forces, or write the data set as a folder)",
                case.id
            )));
        }
        let label = PathBuf::from(format!("<arrays>/{}", case.id));
        let n_t = t[k].as_array().len();
        let col = |a: &PyReadonlyArray1<'_, f64>, name: &str| -> PyResult<Vec<f64>> {
            let v = a.as_array().to_vec();
            if v.len() != n_t {
                return Err(err(format!(
                    "case `{}`: column `{name}` has {} values, `t` has {}",
                    case.id,
                    v.len(),
                    n_t
                )));
            }
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(err(format!(
                    "case `{}`: column `{name}` row {i}: {} is not finite",
                    case.id, v[i]
                )));
            }
            Ok(v)
        };
        let forced = case.kind == CaseKind::Forced;
        let opt =
            |a: &Option<PyReadonlyArray1<'_, f64>>, name: &str| -> PyResult<Option<Vec<f64>>> {
                match a {
                    Some(a) => col(a, name).map(Some),
                    None if forced => Err(err(format!(
                        "case `{}`: column `{name}` is required for a forced case",
                        case.id
                    ))),
                    None => Ok(None),
                }
            };
        let table = CaseTable {
            t: col(&t[k], "t")?,
            h: col(&h[k], "h")?,
            alpha: col(&alpha[k], "alpha")?,
            lift: opt(&lift[k], "lift")?,
            moment: opt(&moment[k], "moment")?,
            ..CaseTable::default()
        };
        // Rows counted from 0 in the message (no header line in arrays).
        identify::dataset::check_sampling(&table.t, &label, 0).map_err(err)?;
        let rec = record_from_table(
            table,
            &label,
            &manifest,
            case.kind,
            manifest.case_meta(case),
        )
        .map_err(err)?;
        records.push(rec);
    }
    if let Some(extra) = ids.iter().find(|i| manifest.case(i).is_none()) {
        return Err(err(format!(
            "columns given for `{extra}`, which the manifest does not list"
        )));
    }
    Ok(PyDataset {
        inner: Dataset {
            root: PathBuf::from("<arrays>"),
            manifest,
            records,
        },
    })
}

/// Identification of a data set: `settings_json` holds `IdentifySettings` fields (those
/// absent take their defaults), `velocity` is `auto`, `harmonic` or `sg`. Returns the
/// `identification.json` document as JSON text.
#[pyfunction]
#[pyo3(name = "identify", signature = (dataset, settings_json, velocity, subtract_nowind, ensemble = None, seed = 2024, level = identify::ensemble::DEFAULT_LEVEL))]
#[allow(clippy::too_many_arguments)]
fn py_identify(
    py: Python<'_>,
    dataset: &PyDataset,
    settings_json: &str,
    velocity: &str,
    subtract_nowind: bool,
    ensemble: Option<usize>,
    seed: u64,
    level: f64,
) -> PyResult<String> {
    let settings: IdentifySettings = serde_json::from_str(settings_json)
        .map_err(|e| err(format!("invalid identification option: {e}")))?;
    settings
        .validate()
        .map_err(|e| err(format!("invalid identification option: {e}")))?;
    let velocity = match velocity {
        "auto" => VelocityMethod::Auto,
        "harmonic" => VelocityMethod::Harmonic,
        "sg" => VelocityMethod::SavitzkyGolay {
            half_window: identify::preprocess::DEFAULT_SG_HALF_WINDOW,
            order: identify::preprocess::DEFAULT_SG_ORDER,
        },
        other => {
            return Err(err(format!(
                "velocity = `{other}`: expected `auto`, `harmonic` or `sg`"
            )))
        }
    };
    let pre = PreprocessOptions {
        velocity,
        subtract_nowind,
        ..PreprocessOptions::default()
    };
    pre.check()
        .map_err(|e| err(format!("invalid preprocessing option: {e}")))?;
    let ds = &dataset.inner;
    if let Some(n) = ensemble {
        // as `aeroform identify --ensemble N` (tests/limits.rs): refused before any work
        identify::limits::ensemble_fits(n, ds.manifest.cases.len() as u128)
            .map_err(|m| err(format!("ensemble = {n}: {m}")))?;
    }
    py.detach(|| {
        let prepared = prepare_dataset(ds, &pre).map_err(|e| format!("preprocessing: {e}"))?;
        if prepared.cases.is_empty() {
            return Err(format!(
                "{}: the data set has no forced-motion case to identify",
                ds.root.display()
            ));
        }
        let mut id =
            identify::pipeline::identify(&prepared.cases, &settings, &ds.manifest.name, &|_| {})
                .map_err(|e| format!("identification: {e}"))?;
        if let Some(n) = ensemble {
            // As `aeroform identify --ensemble N --seed S --level L`.
            let mut es = identify::ensemble::EnsembleSettings::new(n, seed);
            es.level = level;
            let e = identify::ensemble::bootstrap(&prepared.cases, &id, &es)
                .map_err(|e| format!("ensemble (block bootstrap): {e}"))?;
            id.ensemble = Some(e);
        }
        serde_json::to_string(&id).map_err(|e| e.to_string())
    })
    .map_err(err)
}

fn flutter_method(name: &str) -> PyResult<FlutterMethod> {
    name.parse().map_err(|m| err(format!("method = {m}")))
}

/// A speed list against the limits table: at most `MAX_SPEEDS` speeds, each finite, > 0 and
/// ≤ `MAX_SPEED` m/s; the error names the argument.
fn check_speeds(speeds: &[f64], what: &str) -> PyResult<()> {
    use identify::limits::{positive_at_most, MAX_SPEED, MAX_SPEEDS};
    if speeds.len() > MAX_SPEEDS {
        return Err(err(format!(
            "{what}: {} speeds, at most {MAX_SPEEDS}",
            speeds.len()
        )));
    }
    for u in speeds {
        positive_at_most(*u, MAX_SPEED, "m/s").map_err(|m| err(format!("{what}: {m}")))?;
    }
    Ok(())
}

/// Flutter and divergence (`aeroform flutter`): returns the `flutter.json` document.
#[pyfunction]
#[pyo3(signature = (structure, model, speeds, method = "pk", chord = None, ensemble = None))]
fn flutter(
    py: Python<'_>,
    structure: PathBuf,
    model: PathBuf,
    speeds: Vec<f64>,
    method: &str,
    chord: Option<f64>,
    ensemble: Option<usize>,
) -> PyResult<String> {
    let method = flutter_method(method)?;
    check_speeds(&speeds, "speeds")?;
    py.detach(|| {
        let pair = LoadedPair::load(&structure, &model, chord).map_err(|e| e.to_string())?;
        let fa = pair
            .flutter(method, &speeds)
            .map_err(|e| format!("flutter analysis: {e}"))?;
        let mut doc = flutter_document(
            &structure.display().to_string(),
            &model.display().to_string(),
            &pair,
            &fa,
        );
        if let Some(n) = ensemble {
            let e = pair
                .flutter_ensemble(&model, method, &speeds, Some(n))
                .map_err(|e| format!("ensemble flutter analysis: {e}"))?;
            doc.ensemble = Some(e);
        }
        Ok::<_, String>(doc.to_value().to_string())
    })
    .map_err(err)
}

/// Limit cycles (`aeroform lco`): one run at `speed`, or upward and downward sweeps over
/// `sweep`; initial pitch perturbations in degrees. Returns the `lco.json` document.
#[pyfunction]
#[pyo3(signature = (structure, model, speed = None, sweep = None, alpha0 = 2.0, alpha0_down = 20.0, chord = None))]
#[allow(clippy::too_many_arguments)]
fn lco(
    py: Python<'_>,
    structure: PathBuf,
    model: PathBuf,
    speed: Option<f64>,
    sweep: Option<Vec<f64>>,
    alpha0: f64,
    alpha0_down: f64,
    chord: Option<f64>,
) -> PyResult<String> {
    match (&speed, &sweep) {
        (Some(u), None) => check_speeds(&[*u], "speed")?,
        (None, Some(s)) if !s.is_empty() => check_speeds(s, "sweep")?,
        _ => {
            return Err(err(
                "lco: give exactly one of `speed` or a non-empty `sweep`",
            ))
        }
    }
    for (name, x) in [("alpha0", alpha0), ("alpha0_down", alpha0_down)] {
        identify::limits::abs_at_most(x, identify::limits::MAX_PITCH_DEG, "deg")
            .map_err(|m| err(format!("{name}: {m}")))?;
    }
    py.detach(|| {
        let pair = LoadedPair::load(&structure, &model, chord).map_err(|e| e.to_string())?;
        let (s, m) = (structure.display().to_string(), model.display().to_string());
        let doc = match (speed, &sweep) {
            (Some(u), _) => {
                let r = pair
                    .lco_run(u, alpha0.to_radians())
                    .map_err(|e| format!("LCO run at U = {u} m/s: {e}"))?;
                lco_run_document(&s, &m, &pair.section, &r)
            }
            (None, Some(speeds)) => {
                let h = pair
                    .lco_sweep(
                        speeds,
                        alpha0.to_radians(),
                        alpha0_down.to_radians(),
                        &|_| {},
                    )
                    .map_err(|e| format!("LCO sweep: {e}"))?;
                lco_sweep_document(&s, &m, &pair.section, &h)
            }
            (None, None) => unreachable!("checked above"),
        };
        Ok::<_, String>(doc.to_value().to_string())
    })
    .map_err(err)
}

/// LCO branches by continuation (`aeroform branch`) from every Hopf point in
/// `u_min … u_max` [m/s]: returns `(branch.json document, branch.csv text)`. `measured`
/// is a CSV of measured amplitudes (columns `branch`, `wind_speed_m_s`, `heave_amp_m`,
/// `pitch_amp_rad`) whose distances to the predicted branches are reported. With
/// `parameter` (a name of `aeroform branch --parameter`, e.g. `"pitch_stiffness[3]"`),
/// `parameter_range = (a, b)` and `at_speed` [m/s], the orbit at that speed is also
/// continued in the parameter (`branch.json`'s `parameter`, as the CLI).
#[pyfunction]
#[pyo3(signature = (structure, model, u_min, u_max, measured = None, max_points = 200, steps_per_period = 128, chord = None, method = "shooting", harmonics = 5, parameter = None, parameter_range = None, at_speed = None))]
#[allow(clippy::too_many_arguments)]
fn branch(
    py: Python<'_>,
    structure: PathBuf,
    model: PathBuf,
    u_min: f64,
    u_max: f64,
    measured: Option<PathBuf>,
    max_points: usize,
    steps_per_period: usize,
    chord: Option<f64>,
    method: &str,
    harmonics: usize,
    parameter: Option<String>,
    parameter_range: Option<(f64, f64)>,
    at_speed: Option<f64>,
) -> PyResult<(String, String)> {
    let method: aeroelastic::branch::BranchMethod = method.parse().map_err(err)?;
    let lens = match (&parameter, parameter_range, at_speed) {
        (None, None, None) => None,
        (Some(name), Some((a, b)), Some(u)) => Some((
            aeroelastic::branch::SectionParameter::parse(name).map_err(err)?,
            [a, b],
            u,
        )),
        _ => {
            return Err(err(
                "parameter, parameter_range and at_speed go together: give all three or none",
            ))
        }
    };
    py.detach(|| {
        let pair = LoadedPair::load(&structure, &model, chord).map_err(|e| e.to_string())?;
        let measured = match &measured {
            Some(p) => {
                Some(read_measured_amplitudes(p).map_err(|e| format!("measured amplitudes: {e}"))?)
            }
            None => None,
        };
        let opts = BranchOptions {
            max_points,
            steps_per_period,
            method,
            harmonics,
            ..BranchOptions::default()
        };
        let set = pair
            .branches(u_min, u_max, &opts, &|_| {})
            .map_err(|e| format!("LCO branches in U = {u_min}…{u_max} m/s: {e}"))?;
        let dist = measured
            .as_deref()
            .map(|m| measured_distances(&set, m))
            .unwrap_or_default();
        let mut doc = branch_document(
            &structure.display().to_string(),
            &model.display().to_string(),
            &set,
            &dist,
        );
        if let Some((lens, range, u)) = &lens {
            doc.parameter = Some(
                pair.section
                    .continue_set_in(&set, lens, *range, *u, &opts)
                    .map_err(|e| format!("continuation in a parameter at U = {u} m/s: {e}"))?,
            );
        }
        Ok::<_, String>((doc.to_value().to_string(), branch_csv(&set)))
    })
    .map_err(err)
}

/// The limits table (`identify::limits::TABLE`, docs/DATA_FORMAT.md "Limits"): one
/// `(name, max, unit, set_by)` per entry; `max` is the largest allowed value (of |x| for
/// signed quantities) in `unit`.
#[pyfunction]
fn limits() -> Vec<(&'static str, f64, &'static str, &'static str)> {
    identify::limits::TABLE
        .iter()
        .map(|l| (l.name, l.max, l.unit, l.set_by))
        .collect()
}

/// The registered regressors (`identify::regress::plugins`) as JSON text: per regressor its
/// name, aliases, doc, path parameter and options (name, type, default, range, doc).
#[pyfunction]
fn regressors() -> String {
    let r = identify::regress::plugins::registry();
    identify::regress::plugins::describe(r).to_string()
}

/// Sim-to-real diagnosis (`aeroform diagnose`): returns the `diagnosis.json` document.
#[pyfunction]
#[pyo3(name = "diagnose", signature = (forced, free = None, seed = 1))]
fn py_diagnose(
    py: Python<'_>,
    forced: &PyDataset,
    free: Option<&PyDataset>,
    seed: u64,
) -> PyResult<String> {
    let opts = DiagnoseOptions::new(seed);
    let version = format!("aeroform {} (python)", env!("CARGO_PKG_VERSION"));
    let (f, fr) = (&forced.inner, free.map(|d| &d.inner));
    py.detach(|| {
        let d = diagnose::pipeline::diagnose(f, fr, &opts, &version).map_err(|e| e.to_string())?;
        serde_json::to_string(&d).map_err(|e| e.to_string())
    })
    .map_err(err)
}

/// Bifurcation-level diagnosis (`aeroform diagnose --measured-branch`): the same request
/// and the same input choices as the command (`diagnose::bifurcation::inputs`): `measured`
/// a CSV table or a data-set folder of records, `structure` a structure file or `None`
/// (the data sets' `[structure]`), `free` further data sets (still-air decays), `onsets`
/// and `no_lco` rows as the command's `--onset` / `--no-lco` values. Returns the
/// `bifurcation.json` document.
#[pyfunction]
#[pyo3(signature = (measured, model, structure = None, free = Vec::new(), onsets = Vec::new(), no_lco = Vec::new()))]
fn diagnose_branch(
    py: Python<'_>,
    measured: PathBuf,
    model: PathBuf,
    structure: Option<PathBuf>,
    free: Vec<PathBuf>,
    onsets: Vec<String>,
    no_lco: Vec<String>,
) -> PyResult<String> {
    let version = format!("aeroform {} (python)", env!("CARGO_PKG_VERSION"));
    py.detach(|| {
        let prepared = diagnose::bifurcation::inputs::MeasuredBranchRequest {
            measured: &measured,
            model: &model,
            structure: structure.as_deref(),
            free: &free,
            onsets: &onsets,
            no_lco: &no_lco,
        }
        .prepare()
        .map_err(|e| e.to_string())?;
        let d = prepared
            .diagnose(
                &diagnose::bifurcation::BifurcationOptions::default(),
                &version,
            )
            .map_err(|e| e.to_string())?;
        serde_json::to_string(&d).map_err(|e| e.to_string())
    })
    .map_err(err)
}

fn spec(spec_json: &str) -> PyResult<SweepSpec> {
    SweepSpec::from_json(spec_json, "sweep spec").map_err(err)
}

/// Number of items of a sweep specification (JSON text).
#[pyfunction]
fn sweep_n_items(spec_json: &str) -> PyResult<usize> {
    Ok(spec(spec_json)?.n_items())
}

/// Runs the items `indices` of a sweep; returns a JSON array of items.
#[pyfunction]
fn sweep_run_items(py: Python<'_>, spec_json: &str, indices: Vec<usize>) -> PyResult<String> {
    let s = spec(spec_json)?;
    py.detach(|| {
        s.run_items(&indices)
            .map(|v| serde_json::Value::Array(v).to_string())
    })
    .map_err(err)
}

/// Gathers items (JSON arrays, any order) into the document of the whole sweep.
#[pyfunction]
fn sweep_assemble(py: Python<'_>, spec_json: &str, items_json: Vec<String>) -> PyResult<String> {
    let s = spec(spec_json)?;
    py.detach(|| {
        let mut items = Vec::new();
        for (k, text) in items_json.iter().enumerate() {
            match serde_json::from_str::<serde_json::Value>(text) {
                Ok(serde_json::Value::Array(v)) => items.extend(v),
                Ok(_) => return Err(format!("items chunk {k}: not a JSON array")),
                Err(e) => return Err(format!("items chunk {k}: {e}")),
            }
        }
        s.assemble(items)
            .map(|v| v.to_string())
            .map_err(|e| e.to_string())
    })
    .map_err(err)
}

/// The whole sweep in this process (rayon): the reference the distributed run must equal.
#[pyfunction]
fn sweep_local(py: Python<'_>, spec_json: &str) -> PyResult<String> {
    let s = spec(spec_json)?;
    py.detach(|| s.run_local(&|_| {}).map(|v| v.to_string()))
        .map_err(err)
}

/// The Python extension module `aeroform._core`.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("AeroformError", m.py().get_type::<AeroformError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyDataset>()?;
    m.add_function(wrap_pyfunction!(read_dataset, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_from_columns, m)?)?;
    m.add_function(wrap_pyfunction!(py_identify, m)?)?;
    m.add_function(wrap_pyfunction!(flutter, m)?)?;
    m.add_function(wrap_pyfunction!(lco, m)?)?;
    m.add_function(wrap_pyfunction!(branch, m)?)?;
    m.add_function(wrap_pyfunction!(py_diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose_branch, m)?)?;
    m.add_function(wrap_pyfunction!(limits, m)?)?;
    m.add_function(wrap_pyfunction!(regressors, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_n_items, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_run_items, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_assemble, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_local, m)?)?;
    Ok(())
}
