//! A structure/model pair loaded from files, and the result documents of `aeroform flutter`
//! (`flutter.json`), `aeroform lco` (`lco.json`) and `aeroform branch` (`branch.json`,
//! `branch.csv`).
//!
//! Built here, not in the binary, so that the command line, the Python binding and the
//! sweeps write the same content from the same code.

use std::path::Path;

use std::fmt::Write as _;

use serde_json::{json, Value};

use crate::branch::{BranchOptions, BranchProgress, BranchSet, EventKind, MeasuredDistance};
use crate::ensemble::{flutter_ensemble, member_laws, FlutterEnsemble};
use crate::identified::IdentifiedOptions;

use crate::files::{LoadedModel, StructureFile};
use crate::flutter::{FlutterAnalysis, FlutterMethod, FlutterOptions};
use crate::lco::{Hysteresis, KIteration, LcoOptions, LcoResult, SweepPlan, SweepProgress};
use crate::section::Section;
use crate::structure::Structure;
use crate::Result;

/// Relative tolerance on the critical speed used by `aeroform flutter`.
pub const FLUTTER_TOL_REL: f64 = 1e-8;

/// The scan of `aeroform flutter` over `speeds` (≥ 2 speeds): from the lowest to the
/// highest with as many points, critical speeds to [`FLUTTER_TOL_REL`].
///
/// # Errors
/// [`crate::Error::InvalidParameter`] for fewer than 2 speeds.
pub fn flutter_options(speeds: &[f64]) -> Result<FlutterOptions> {
    if speeds.len() < 2 {
        return Err(crate::Error::param(
            "speeds",
            speeds.len() as f64,
            "a flutter scan needs at least 2 speeds",
        ));
    }
    Ok(FlutterOptions {
        u_min: speeds.iter().copied().fold(f64::INFINITY, f64::min),
        u_max: speeds.iter().copied().fold(0.0, f64::max),
        n_speeds: speeds.len(),
        tol_rel: FLUTTER_TOL_REL,
    })
}

/// Structure file, structure, model and section of a structure/model pair.
#[derive(Debug, Clone)]
pub struct LoadedPair {
    /// The structure file as read.
    pub file: StructureFile,
    /// The structure it describes.
    pub structure: Structure,
    /// The aerodynamic model.
    pub model: LoadedModel,
    /// Structure + model + air density.
    pub section: Section,
}

impl LoadedPair {
    /// Reads a structure file and a model file (model TOML or `identification.json`) and
    /// builds the section; `chord` overrides the structure file's `chord` for an
    /// identification.
    ///
    /// # Errors
    /// The errors of [`StructureFile::read`], [`StructureFile::structure`],
    /// [`LoadedModel::load`] and [`Section::new`] (each names the file and the field).
    pub fn load(structure: &Path, model: &Path, chord: Option<f64>) -> Result<Self> {
        let file = StructureFile::read(structure)?;
        let model = LoadedModel::load(model, chord.or(file.chord))?;
        Self::from_parts(file, model)
    }

    /// Builds the pair from a structure file already read and a model already loaded.
    ///
    /// # Errors
    /// The errors of [`StructureFile::structure`] and [`Section::new`].
    pub fn from_parts(file: StructureFile, model: LoadedModel) -> Result<Self> {
        let structure = file.structure()?;
        let section = Section::new(structure.clone(), model.model.clone(), file.air_density)?;
        Ok(LoadedPair {
            file,
            structure,
            model,
            section,
        })
    }

    /// Warnings of an identified model (terms dropped, extrapolated tables…).
    pub fn warnings(&self) -> &[String] {
        self.model
            .identified
            .as_ref()
            .map(|t| t.warnings.as_slice())
            .unwrap_or(&[])
    }

    /// The flutter analysis of `aeroform flutter` over `speeds` (≥ 2 speeds; the scan runs
    /// from the lowest to the highest with as many points).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for fewer than 2 speeds; the errors of
    /// [`Section::flutter`].
    pub fn flutter(&self, method: FlutterMethod, speeds: &[f64]) -> Result<FlutterAnalysis> {
        self.section.flutter(method, &flutter_options(speeds)?)
    }

    /// One LCO run at `u` [m/s] from a pitch perturbation `alpha0` \[rad\], as
    /// `aeroform lco --speed` (default options; the K iteration of a K-dependent model).
    ///
    /// # Errors
    /// The errors of [`Section::lco_run_k`].
    pub fn lco_run(&self, u: f64, alpha0: f64) -> Result<LcoResult> {
        self.section.lco_run_k(
            u,
            &self.section.perturbation(alpha0),
            &LcoOptions::default(),
            &KIteration::default(),
        )
    }

    /// Upward and downward LCO sweeps over `speeds` from pitch perturbations `alpha0_up`
    /// and `alpha0_down` \[rad\], as `aeroform lco --sweep` ([`Section::lco_sweeps`]).
    ///
    /// # Errors
    /// The errors of [`Section::lco_sweeps`].
    pub fn lco_sweep(
        &self,
        speeds: &[f64],
        alpha0_up: f64,
        alpha0_down: f64,
        observer: &(dyn Fn(SweepProgress) + Sync),
    ) -> Result<Hysteresis> {
        let plan = SweepPlan {
            perturbation_up: self.section.perturbation(alpha0_up),
            perturbation_down: Some(self.section.perturbation(alpha0_down)),
            k_iteration: KIteration::default(),
        };
        self.section
            .lco_sweeps(speeds, &plan, &LcoOptions::default(), observer)
    }

    /// Flutter and divergence of the first `n` members (`None`: all) of the ensemble of
    /// the identification in the file `model` (written with `identify --ensemble`), on
    /// this pair's structure and air density with the scan of [`LoadedPair::flutter`]:
    /// the `ensemble` object of `flutter.json`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] / [`crate::Error::Identify`] when `model` is not a readable
    /// identification.json; the errors of [`crate::ensemble::member_laws`] (no ensemble
    /// section, `n` out of range) and [`crate::ensemble::flutter_ensemble`].
    pub fn flutter_ensemble(
        &self,
        model: &Path,
        method: FlutterMethod,
        speeds: &[f64],
        n: Option<usize>,
    ) -> Result<FlutterEnsemble> {
        let id = identify::pipeline::Identification::read(model).map_err(|source| {
            crate::Error::Identify {
                context: format!(
                    "{}: an ensemble needs an identification.json model",
                    model.display()
                ),
                source,
            }
        })?;
        let opts = IdentifiedOptions::new(self.section.aero.chord());
        let (laws, e) = member_laws(&id, &opts, n)?;
        flutter_ensemble(
            &self.structure,
            &laws,
            e,
            self.file.air_density,
            method,
            &flutter_options(speeds)?,
        )
    }

    /// LCO branches by continuation from every Hopf point in `u_min … u_max` \[m/s\], as
    /// `aeroform branch` ([`Section::lco_branches`]).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] when the range is not 0 < `u_min` < `u_max`
    /// (finite); the errors of [`Section::lco_branches`] (no Hopf point in range,
    /// non-smooth nonlinearity, bad options).
    pub fn branches(
        &self,
        u_min: f64,
        u_max: f64,
        opts: &BranchOptions,
        observer: &dyn Fn(BranchProgress),
    ) -> Result<BranchSet> {
        if !(u_min.is_finite() && u_min > 0.0) {
            return Err(crate::Error::param("u_min", u_min, "finite and > 0 m/s"));
        }
        if !(u_max.is_finite() && u_max > u_min) {
            return Err(crate::Error::param("u_max", u_max, "finite and > u_min"));
        }
        self.section.lco_branches(u_min, u_max, opts, observer)
    }
}

/// The method string recorded in `branch.json` under `settings.method`.
pub const BRANCH_METHOD: &str = "single shooting (fixed-step RK4) + pseudo-arclength, Floquet multipliers from the monodromy matrix";

/// The `branch.json` document (`aeroform-branch/1`): settings, Hopf points, folds (branch,
/// U \[m/s\], pitch amplitude \[deg\], heave amplitude \[m\]), every branch with its
/// points and events, and the distances of measured points (`measured`, empty without).
pub fn branch_document(
    structure: &str,
    model: &str,
    set: &BranchSet,
    measured: &[MeasuredDistance],
) -> Value {
    let folds: Vec<Value> = set
        .branches
        .iter()
        .enumerate()
        .flat_map(|(i, b)| {
            b.events
                .iter()
                .filter(|e| e.kind == EventKind::Fold)
                .map(move |e| {
                    json!({
                        "branch": i,
                        "U_m_s": e.u,
                        "amplitude_alpha_deg": e.amplitude_alpha.to_degrees(),
                        "amplitude_h_m": e.amplitude_h,
                    })
                })
        })
        .collect();
    json!({
        "format": "aeroform-branch/1",
        "structure": structure,
        "model": model,
        "settings": {
            "method": BRANCH_METHOD,
            "options": set.options,
            "u_range_m_s": set.u_range,
        },
        "hopf_points": set.hopf_points,
        "folds": folds,
        "branches": set.branches,
        "measured": measured,
    })
}

/// The `branch.csv` table: one row per branch point with columns `U_m_s`, `stable`,
/// `amplitude_alpha_deg` and `amplitude_h_m` (half peak-to-peak), `omega_rad_s`,
/// `max_floquet` (largest Floquet multiplier modulus, the trivial one excluded),
/// `branch` (index), `amplitude1_alpha_deg` and `amplitude1_h_m` (first harmonic).
pub fn branch_csv(set: &BranchSet) -> String {
    let mut s = String::from(
        "U_m_s,stable,amplitude_alpha_deg,amplitude_h_m,omega_rad_s,max_floquet,branch,amplitude1_alpha_deg,amplitude1_h_m\n",
    );
    for (i, b) in set.branches.iter().enumerate() {
        for p in &b.points {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{}",
                p.u,
                p.stable,
                p.amplitude_alpha.to_degrees(),
                p.amplitude_h,
                p.omega,
                p.max_floquet,
                i,
                p.amplitude1_alpha.to_degrees(),
                p.amplitude1_h
            );
        }
    }
    s
}

/// The `critical` object of `flutter.json`: speed, angular and cyclic frequency, reduced
/// frequency K = Bω/U, mode, U/(bω_α), ω/ω_α; `null` when the scan found no flutter.
pub fn flutter_point_json(fa: &FlutterAnalysis, chord: f64) -> Value {
    match fa.flutter {
        Some(f) => json!({
            "speed": f.u,
            "omega": f.omega,
            "frequency_hz": f.omega / (2.0 * std::f64::consts::PI),
            "reduced_frequency": chord * f.omega / f.u,
            "mode": f.mode,
            "u_reduced": f.u_reduced,
            "omega_ratio": f.omega_ratio,
        }),
        None => Value::Null,
    }
}

/// The `flutter.json` document (`aeroform-flutter/1`); `structure` and `model` name the
/// inputs.
pub fn flutter_document(
    structure: &str,
    model: &str,
    pair: &LoadedPair,
    fa: &FlutterAnalysis,
) -> Value {
    let b = pair.section.aero.chord();
    json!({
        "format": "aeroform-flutter/1",
        "structure": structure,
        "model": model,
        "model_name": fa.model,
        "air_density": pair.file.air_density,
        "chord": b,
        "critical": flutter_point_json(fa, b),
        "divergence_speed": fa.divergence_speed,
        "analysis": fa,
        "identified": pair.model.identified,
    })
}

/// The `lco.json` document (`aeroform-lco/1`) of one run.
pub fn lco_run_document(structure: &str, model: &str, run: &LcoResult) -> Value {
    json!({
        "format": "aeroform-lco/1",
        "structure": structure,
        "model": model,
        "run": run,
    })
}

/// The `lco.json` document (`aeroform-lco/1`) of an upward/downward sweep.
pub fn lco_sweep_document(structure: &str, model: &str, sweep: &Hysteresis) -> Value {
    json!({
        "format": "aeroform-lco/1",
        "structure": structure,
        "model": model,
        "sweep": sweep,
        "hysteresis_speeds": sweep.band(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flutter_scan_of_one_speed_is_refused_with_the_field_named() {
        let dir = tempfile::tempdir().unwrap();
        let s = dir.path().join("s.toml");
        let m = dir.path().join("m.toml");
        std::fs::write(
            &s,
            "mass = 1.0\ninertia = 0.01\nfreq_heave = 2.0\nfreq_pitch = 3.0\n",
        )
        .unwrap();
        std::fs::write(&m, "kind = \"theodorsen\"\nchord = 0.25\n").unwrap();
        let pair = LoadedPair::load(&s, &m, None).unwrap();
        let e = pair.flutter(FlutterMethod::Pk, &[5.0]).unwrap_err();
        assert!(e.to_string().contains("speeds"), "{e}");
        let fa = pair.flutter(FlutterMethod::Pk, &[1.0, 30.0]).unwrap();
        let doc = flutter_document("s.toml", "m.toml", &pair, &fa);
        assert_eq!(doc["format"], "aeroform-flutter/1");
        assert_eq!(doc["chord"], 0.25);
    }
}
