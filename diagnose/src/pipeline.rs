//! The whole diagnosis of one data set pair: force level, system level (when free-response
//! records are given), verdict and `diagnosis.json` (DESIGN.md §5).

use std::sync::Arc;

use aeroelastic::aero::AeroModel;
use aeroelastic::section::Section;
use aeroelastic::structure::Structure;
use identify::dataset::Dataset;

use crate::force::{force_level_of, Campaign, ForceOptions};
use crate::report::Diagnosis;
use crate::structure::{structure_check, StructureCheck, StructureGap, StructureUsed};
use crate::system::{system_level_of, system_level_with_model, SystemOptions};
use crate::verdict::{assemble, VerdictRules};
use crate::{Error, Result};

/// Settings of a diagnosis.
#[derive(Debug, Clone)]
pub struct DiagnoseOptions {
    /// Master seed (fold assignment of both levels); recorded in `diagnosis.json`.
    pub seed: u64,
    /// Force level.
    pub force: ForceOptions,
    /// System level.
    pub system: SystemOptions,
    /// Verdict rule.
    pub rules: VerdictRules,
}

impl DiagnoseOptions {
    /// Defaults of every level with `seed` as the master seed.
    pub fn new(seed: u64) -> Self {
        let mut o = DiagnoseOptions {
            seed,
            force: ForceOptions::default(),
            system: SystemOptions::default(),
            rules: VerdictRules::default(),
        };
        o.force.seed = seed;
        o.system.seed = seed;
        o
    }
}

/// Diagnoses `forced` (forced-motion records) and, when given, `free` (free-response records
/// of the same section): held-out gaps, where they lie, which candidate explains them, how
/// far it shrinks, and the verdict. `version` is written into the document.
///
/// # Errors
/// As [`crate::force::force_level`] and [`crate::system::system_level`]: [`crate::Error::Data`] naming the data set when it
/// cannot support held-out folds (too few groups or runs, no forced case, a free data set
/// without `[structure]`), [`crate::Error::Identify`] when the baseline cannot be identified.
pub fn diagnose(
    forced: &Dataset,
    free: Option<&Dataset>,
    opts: &DiagnoseOptions,
    version: &str,
) -> Result<Diagnosis> {
    // one preparation of the forced campaign for both levels (and one identification
    // preparation when both levels identify with the same settings)
    let campaign = Campaign::prepare(forced)?;
    let prepared = campaign.identification(&opts.force.identify)?;
    let system_level = |free: &Dataset| -> Result<_> {
        let other;
        let sys_prepared = if opts.system.identify == opts.force.identify {
            &prepared
        } else {
            other = campaign.identification(&opts.system.identify)?;
            &other
        };
        system_level_of(&campaign, sys_prepared, forced, free, &opts.system)
    };
    // the two levels share the preparation and nothing else: side by side (the force
    // level's longest candidate leaves a core idle otherwise); a force-level error is
    // reported first, as when they ran one after the other
    let (force, system) = rayon::join(
        || force_level_of(&campaign, &prepared, &opts.force),
        || free.map(system_level),
    );
    let mut levels = vec![force?.0];
    let mut inputs = vec![forced.root.display().to_string()];
    if let Some(free) = free {
        if let Some(level) = system {
            levels.push(level?);
        }
        inputs.push(free.root.display().to_string());
    }
    let mut d = assemble(levels, &opts.rules, opts.seed, version, inputs);
    d.follow_up = crate::follow_up::plan(&d, forced);
    Ok(d)
}

/// Diagnoses free-response records alone against a given sim: `model` (a model file or an
/// identification, loaded by the caller) coupled to the nominal structure (`opts.system.
/// structure`, else the data set's `[structure]`). This is the real-rig case: no forced
/// campaign, only free runs (still-air runs at U = 0 included: they test the structure
/// without aerodynamics). Every run is held out once.
///
/// Structure first (DESIGN §5): the still-air runs are checked against the nominal
/// structure with the model's apparent mass at U = 0 ([`crate::structure::structure_check`]);
/// when they differ beyond their uncertainty the level runs on the linear structure
/// identified from them, and its `structure` says so with the gap on the given structure
/// (`structure.gap.given`) and on the identified one (`structure.gap.identified`).
///
/// # Errors
/// As [`system_level_with_model`]: [`Error::Data`] naming the data set (no structure,
/// fewer than `min_runs` runs, a run too short or without motion); [`Error::Aeroelastic`]
/// when the nominal structure and the model make no section.
pub fn diagnose_free(
    free: &Dataset,
    model: &Arc<dyn AeroModel>,
    opts: &DiagnoseOptions,
    version: &str,
) -> Result<Diagnosis> {
    let check = structure_first(free, model, &opts.system)?;
    let mut level = system_level_with_model(model, free, &opts.system)?;
    let mut sentence = String::new();
    if let Some(mut c) = check {
        if let (StructureUsed::Identified, Some(id)) = (c.used, &c.identified) {
            let mut o = opts.system.clone();
            o.structure = Some(id.modal);
            let on_id = system_level_with_model(model, free, &o)?;
            c.gap = Some(StructureGap {
                metric: on_id.metric.clone(),
                given: level.before,
                identified: on_id.before,
                hopf_given: None,
                hopf_identified: None,
            });
            sentence = format!(
                "; on the structure identified from the still-air decays (the correction \
                 alone moves the held-out gap {:.4} → {:.4})",
                level.before, on_id.before
            );
            level = on_id;
        } else {
            sentence = "; on the given structure".into();
        }
        level.structure = Some(c);
    }
    let mut d = assemble(
        vec![level],
        &opts.rules,
        opts.seed,
        version,
        vec![free.root.display().to_string()],
    );
    d.verdict.reason.push_str(&sentence);
    Ok(d)
}

/// The still-air decays of `free` against the nominal structure (`opts.structure`, else
/// the manifest's) with `model`'s apparent mass at U = 0, and the linear structure
/// identified from them; `None` without a still-air run or a structure.
///
/// # Errors
/// [`Error::Aeroelastic`] when the nominal structure and the model make no section.
fn structure_first(
    free: &Dataset,
    model: &Arc<dyn AeroModel>,
    opts: &SystemOptions,
) -> Result<Option<StructureCheck>> {
    let Some(spec) = opts.structure.or(free.manifest.structure) else {
        return Ok(None);
    };
    if !free.records.iter().any(|r| r.meta.wind_speed <= 0.0) {
        return Ok(None);
    }
    let name = free.manifest.name.as_str();
    let st = Structure::from_modal(&spec)
        .map_err(|e| Error::aeroelastic(format!("data set `{name}`: nominal [structure]"), e))?;
    let section = Section::new(st, model.clone(), free.manifest.section.air_density)
        .map_err(|e| Error::aeroelastic(format!("data set `{name}`: nominal section"), e))?;
    Ok(structure_check(&[free], &section))
}

/// One free-response data set from several (e.g. LCO records in the flow and a still-air
/// decay of the same rig): the first set's manifest with every set's free records
/// appended; a repeated case id gets the folder name as a prefix.
///
/// # Errors
/// [`Error::Data`] when `sets` is empty or the sections (chord, air density) differ.
pub fn merge_free(sets: &[Dataset]) -> Result<Dataset> {
    let Some(first) = sets.first() else {
        return Err(Error::data("(none)", "no free-response data set given"));
    };
    let mut out = first.clone();
    for s in &sets[1..] {
        let (a, b) = (&first.manifest.section, &s.manifest.section);
        if (a.chord - b.chord).abs() > 1e-12 * a.chord.abs() {
            return Err(Error::data(
                &s.manifest.name,
                format!(
                    "chord {} m differs from `{}`'s {} m",
                    b.chord, first.manifest.name, a.chord
                ),
            ));
        }
        if out.manifest.structure.is_none() {
            out.manifest.structure = s.manifest.structure;
        }
        for (case, rec) in s.manifest.cases.iter().zip(&s.records) {
            let mut case = case.clone();
            let mut rec = rec.clone();
            if out.records.iter().any(|r| r.meta.id == rec.meta.id) {
                let tag = s
                    .root
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "set".into());
                rec.meta.id = format!("{tag}.{}", rec.meta.id);
                case.id = rec.meta.id.clone();
            }
            out.manifest.cases.push(case);
            out.records.push(rec);
        }
    }
    Ok(out)
}
