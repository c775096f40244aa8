//! The system level of the diagnosis: the sim (the law identified from every forced case,
//! coupled to the nominal structure of the free data set's manifest `[structure]`)
//! against free-response records (h, α only).
//!
//! See [`system_level`] for the steps and the documented choices.

pub mod residual;

use std::sync::Arc;

use aeroelastic::aero::AeroModel;
use aeroelastic::identified::{IdentifiedLaw, IdentifiedOptions};
use identify::dataset::Dataset;
use identify::pipeline::{identify, IdentifySettings};
use identify::preprocess::PreprocessOptions;
use identify::record::CaseKind;

use crate::effect::Level;
use crate::report::LevelResult;
use crate::{Error, Result};

pub use residual::{LinearStructure, ResidualSettings, RunResidual};

/// Options of [`system_level`].
#[derive(Debug, Clone, PartialEq)]
pub struct SystemOptions {
    /// Seed of the fold assignment (used when `folds` < number of runs).
    pub seed: u64,
    /// Number of folds over runs; 0 = leave one run out (default).
    pub folds: usize,
    /// Savitzky–Golay half window [s] of the derivatives (default 0.05 s: 25 samples at
    /// 512 Hz).
    pub sg_half_window_s: f64,
    /// Savitzky–Golay polynomial degree (default 4).
    pub sg_order: usize,
    /// Seconds trimmed at the start of each run for the lag states (default 0.25 s).
    pub warmup: f64,
    /// Fewest free runs accepted (default 3).
    pub min_runs: usize,
    /// Preprocessing of the forced records for the identification.
    pub preprocess: PreprocessOptions,
    /// Identification settings (default: identify's defaults).
    pub identify: IdentifySettings,
}

impl Default for SystemOptions {
    fn default() -> Self {
        SystemOptions {
            seed: 0,
            folds: 0,
            sg_half_window_s: 0.05,
            sg_order: 4,
            warmup: 0.25,
            min_runs: 3,
            preprocess: PreprocessOptions::default(),
            identify: IdentifySettings::default(),
        }
    }
}

impl SystemOptions {
    fn check(&self) -> Result<()> {
        if !(self.sg_half_window_s.is_finite() && self.sg_half_window_s > 0.0) {
            return Err(Error::setting(
                "sg_half_window_s",
                self.sg_half_window_s,
                "must be finite and > 0",
            ));
        }
        if self.sg_order < 2 {
            return Err(Error::setting(
                "sg_order",
                self.sg_order as f64,
                "must be >= 2 (second derivatives)",
            ));
        }
        if !(self.warmup.is_finite() && self.warmup >= 0.0) {
            return Err(Error::setting("warmup", self.warmup, "must be finite and >= 0"));
        }
        if self.min_runs < 2 {
            return Err(Error::setting(
                "min_runs",
                self.min_runs as f64,
                "must be >= 2 (held-out runs need training runs)",
            ));
        }
        if self.folds == 1 {
            return Err(Error::setting("folds", 1.0, "must be 0 (leave one out) or >= 2"));
        }
        Ok(())
    }
}

/// Identifies the sim's law from every forced case of `forced` (preprocessing and
/// identification with `opts`' settings, then [`IdentifiedLaw::from_identification`] with
/// the default [`IdentifiedOptions`] for the data set's chord).
///
/// # Errors
/// [`Error::Data`] when `forced` has no forced case; [`Error::Identify`] /
/// [`Error::Aeroelastic`] naming the data set when preprocessing, identification or the
/// law fails.
pub fn sim_law(forced: &Dataset, opts: &SystemOptions) -> Result<IdentifiedLaw> {
    let name = forced.manifest.name.clone();
    if !forced.records.iter().any(|r| r.kind == CaseKind::Forced) {
        return Err(Error::data(&name, "no forced case to identify the sim's law from"));
    }
    let prepared = identify::workflow::prepare_dataset(forced, &opts.preprocess)
        .map_err(|e| Error::identify(format!("data set `{name}`: preprocessing"), e))?;
    let id = identify(&prepared.cases, &opts.identify, &name, &|_| {})
        .map_err(|e| Error::identify(format!("data set `{name}`: identification"), e))?;
    IdentifiedLaw::from_identification(&id, &IdentifiedOptions::new(forced.manifest.section.chord))
        .map_err(|e| Error::aeroelastic(format!("data set `{name}`: identified law"), e))
}

/// Prepared free runs of a data set for a given aerodynamic model.
pub(crate) struct Prepared {
    pub runs: Vec<RunResidual>,
    pub structure: LinearStructure,
}

pub(crate) fn prepare_free(
    free: &Dataset,
    model: &Arc<dyn AeroModel>,
    opts: &SystemOptions,
) -> Result<Prepared> {
    let name = free.manifest.name.as_str();
    let spec = free.manifest.structure.ok_or_else(|| {
        Error::data(
            name,
            "free-response data set has no [structure] table (the sim needs the nominal structure)",
        )
    })?;
    let structure = LinearStructure::from_spec(&spec);
    let recs: Vec<_> = free.records.iter().filter(|r| r.kind == CaseKind::Free).collect();
    if recs.len() < opts.min_runs {
        return Err(Error::data(
            name,
            format!(
                "{} free run(s); the system level needs at least {} (held-out runs)",
                recs.len(),
                opts.min_runs
            ),
        ));
    }
    let rho = free.manifest.section.air_density;
    let runs = recs
        .iter()
        .map(|r| {
            let hw = (opts.sg_half_window_s / r.dt).round().max(2.0) as usize;
            let s = ResidualSettings {
                half_window: hw,
                order: opts.sg_order.min(2 * hw),
                warmup: opts.warmup,
            };
            residual::prepare_run(name, r, model, rho, &structure, &s)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Prepared { runs, structure })
}

/// The system level (see the module docs): identifies the sim's law from `forced`
/// ([`sim_law`]) and runs [`system_level_with_model`].
///
/// # Errors
/// As [`sim_law`] and [`system_level_with_model`].
pub fn system_level(forced: &Dataset, free: &Dataset, opts: &SystemOptions) -> Result<LevelResult> {
    opts.check()?;
    let law = sim_law(forced, opts)?;
    let model: Arc<dyn AeroModel> = Arc::new(law.model().clone());
    system_level_with_model(&model, free, opts)
}

/// The system level for a given sim aerodynamic model (the identified law, or any
/// [`AeroModel`], e.g. a truth model in tests).
///
/// # Errors
/// [`Error::Setting`] for bad options; [`Error::Data`] naming the free data set and run
/// (no `[structure]`, fewer than `min_runs` runs, a run too short or without motion).
pub fn system_level_with_model(
    model: &Arc<dyn AeroModel>,
    free: &Dataset,
    opts: &SystemOptions,
) -> Result<LevelResult> {
    opts.check()?;
    let p = prepare_free(free, model, opts)?;
    let mut before = [0.0; 2];
    let mut noise = [0.0; 2];
    for r in &p.runs {
        let e = r.energy();
        for c in 0..2 {
            before[c] += e[c] / p.runs.len() as f64;
            noise[c] += r.noise_energy[c] / p.runs.len() as f64;
        }
    }
    let comb = |e: [f64; 2]| (0.5 * (e[0] + e[1])).sqrt();
    Ok(LevelResult {
        level: Level::Structural,
        metric: "held-out normalised equation error of the free response".into(),
        before: comb(before),
        noise_level: comb(noise),
        significant_gap: false,
        gap_statistic: 0.0,
        gap_threshold: 0.0,
        held_out_cases: p.runs.iter().map(|r| r.id.clone()).collect(),
        candidates: vec![],
        where_: vec![],
        cases: vec![],
        spectra: vec![],
        signatures: vec![],
        observables: vec![],
        bifurcation: None,
    })
}
