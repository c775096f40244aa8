//! The system level of the diagnosis: the sim (the law identified from every forced case,
//! coupled to the nominal structure of the free data set's manifest `[structure]`)
//! against free-response records (h, α only).
//!
//! See [`system_level`] for the steps and the documented choices.

// The crate's error enum carries identify/aeroelastic errors by value (skeleton choice).

pub mod residual;

mod analysis;
pub(crate) mod candidates;
pub mod control;
pub mod coverage;
pub(crate) mod simulate;

use std::sync::Arc;

use aeroelastic::aero::AeroModel;
use aeroelastic::identified::{IdentifiedLaw, IdentifiedOptions};
use aeroelastic::structure::{Nonlinearities, Structure, StructureSpec};
use identify::dataset::Dataset;
use identify::pipeline::{IdentifySettings, Prepared};

use crate::force::Campaign;
use identify::record::CaseKind;

use crate::effect::{Effect, Level};
use crate::report::{CandidateScore, CaseGap, LevelResult};
use crate::{Error, Result};
use candidates::{SystemTerm, Variant};

use residual::run_weights;
pub use residual::{ResidualSettings, RunResidual};

/// Options of [`system_level`].
#[derive(Debug, Clone, PartialEq)]
pub struct SystemOptions {
    /// Seed of the fold assignment (used when `folds` < number of runs).
    pub seed: u64,
    /// Number of folds over runs; 0 = leave one run out (default).
    pub folds: usize,
    /// Savitzky–Golay half window \[s\] of the derivatives (default 0.05 s: 25 samples at
    /// 512 Hz).
    pub sg_half_window_s: f64,
    /// Savitzky–Golay polynomial degree (default 4).
    pub sg_order: usize,
    /// Seconds trimmed at the start of each run: the aerodynamic start-up transient (default 0.5 s).
    pub warmup: f64,
    /// Padding \[s\] of the frequency-domain aerodynamic forces (default 4 s).
    pub pad: f64,
    /// Fewest free runs accepted (default 3).
    pub min_runs: usize,
    /// Gap test: the gap is significant when before/noise_level exceeds this (default
    /// 1.25; effect-free blind sets give 1.01–1.09, see `tests/system_level.rs`).
    pub gap_ratio: f64,
    /// Smallest held-out residual energy a candidate must remove, in units of the noise
    /// energy (default 0.05; effect-free sets: at most 0.02).
    pub min_gain: f64,
    /// Parsimony penalty: extra noise energies per fitted parameter (default 0.02).
    pub gain_per_param: f64,
    /// Identification settings (default: identify's defaults).
    pub identify: IdentifySettings,
    /// Re-simulate every run with the sim (and the best candidate) for the observables
    /// and the bifurcation diagram (default true; off saves the simulations' time).
    pub simulate: bool,
    /// Nominal structure of the sim; `None` (default): the free data set's `[structure]`.
    pub structure: Option<identify::dataset::ModalStructure>,
}

impl Default for SystemOptions {
    fn default() -> Self {
        SystemOptions {
            seed: 0,
            folds: 0,
            sg_half_window_s: 0.05,
            sg_order: 4,
            warmup: 0.5,
            pad: 4.0,
            min_runs: 3,
            gap_ratio: 1.25,
            min_gain: 0.05,
            gain_per_param: 0.02,
            identify: IdentifySettings::default(),
            simulate: true,
            structure: None,
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
            return Err(Error::setting(
                "warmup",
                self.warmup,
                "must be finite and >= 0",
            ));
        }
        if self.min_runs < 2 {
            return Err(Error::setting(
                "min_runs",
                self.min_runs as f64,
                "must be >= 2 (held-out runs need training runs)",
            ));
        }
        if self.folds == 1 {
            return Err(Error::setting(
                "folds",
                1.0,
                "must be 0 (leave one out) or >= 2",
            ));
        }
        Ok(())
    }
}

/// Identifies the sim's law from every forced case of `forced`: the force level's section
/// law ([`crate::force::section_identifications`]: identify's preprocessing, the group stage
/// with `opts.identify`, one set of nonlinear coefficients for the section), then
/// [`IdentifiedLaw::from_identification`] with the default [`IdentifiedOptions`] for the
/// data set's chord.
///
/// # Errors
/// [`Error::Data`] when `forced` has no forced case; [`Error::Identify`] /
/// [`Error::Aeroelastic`] naming the data set when preprocessing, identification or the
/// law fails.
pub fn sim_law(forced: &Dataset, opts: &SystemOptions) -> Result<IdentifiedLaw> {
    let campaign = Campaign::prepare(forced)?;
    let prepared = campaign.identification(&opts.identify)?;
    sim_identification(&campaign, &prepared, forced).map(|(_, law, _)| law)
}

/// [`sim_law`] together with the identification it was built from and its grouped
/// jackknife ([`jackknife_subsets`]; `None` when it cannot be formed).
///
/// The law is the force level's section law fitted on every forced case
/// ([`crate::force::section_identifications`]): per (configuration, wind speed) node its
/// linear derivatives, one set of nonlinear coefficients for the whole section (every
/// configuration is the same section), on the nonlinear terms the identification selected
/// in any configuration plus those the pooled nodes show. The per-case identification
/// alone folds a cubic's first harmonic into the linear derivatives at the forced
/// amplitudes (α²α̇ and α̇³ are the same at one amplitude), and the sim would carry that
/// linearisation to free runs at other amplitudes (DECISIONS, "One section law for both
/// levels").
fn sim_identification(
    campaign: &Campaign,
    prepared: &Prepared<'_>,
    forced: &Dataset,
) -> Result<(
    identify::pipeline::Identification,
    IdentifiedLaw,
    Option<Vec<identify::pipeline::Identification>>,
)> {
    let name = forced.manifest.name.clone();
    if !forced.records.iter().any(|r| r.kind == CaseKind::Forced) {
        return Err(Error::data(
            &name,
            "no forced case to identify the sim's law from",
        ));
    }
    let metas: Vec<(String, f64)> = forced
        .records
        .iter()
        .filter(|r| r.kind == CaseKind::Forced)
        .map(|r| (r.meta.config.clone().unwrap_or_default(), r.meta.wind_speed))
        .collect();
    let all: Vec<usize> = (0..metas.len()).collect();
    let jack = jackknife_subsets(&metas);
    let mut subsets = vec![all];
    if let Some(j) = &jack {
        subsets.extend(j.iter().cloned());
    }
    let mut ids = crate::force::section_identifications_of(campaign, prepared, &subsets)?;
    let id = ids.remove(0);
    let law = IdentifiedLaw::from_identification(
        &id,
        &IdentifiedOptions::new(forced.manifest.section.chord),
    )
    .map_err(|e| Error::aeroelastic(format!("data set `{name}`: identified law"), e))?;
    let jack = jack.map(|_| ids);
    Ok((id, law, jack))
}

/// The grouped-jackknife subsets of a forced campaign whose cases have the (configuration,
/// wind speed) `metas`: the interior groups (every wind speed of a configuration but its
/// lowest and highest; all groups when fewer than two are interior), sorted, are dealt
/// round-robin into k = min(groups, [`JACKKNIFE_FOLDS`]) folds, and each subset is every
/// case outside one fold. `None` with fewer than 3 groups (the sim is then scored against
/// the noise alone, as without a forced campaign).
fn jackknife_subsets(metas: &[(String, f64)]) -> Option<Vec<Vec<usize>>> {
    let key = |m: &(String, f64)| (m.0.clone(), m.1.to_bits());
    let mut groups: Vec<(String, u64)> = metas.iter().map(key).collect();
    groups.sort();
    groups.dedup();
    if groups.len() < 3 {
        return None;
    }
    // The end wind speeds of each configuration stay in every fold, so that every
    // jackknife law covers the K range the full law covers: the variance is then the
    // estimation error, not the loss of range (which the coverage rule judges). With
    // fewer than two interior groups every group is dealt (the variance then also
    // carries the range loss: an overestimate, on campaigns too small to do better).
    let interior: Vec<(String, u64)> = groups
        .iter()
        .enumerate()
        .filter(|(i, g)| {
            let first = *i == 0 || groups[i - 1].0 != g.0;
            let last = *i + 1 == groups.len() || groups[i + 1].0 != g.0;
            !(first || last)
        })
        .map(|(_, g)| g.clone())
        .collect();
    if interior.len() >= 2 {
        groups = interior;
    }
    let k = groups.len().min(JACKKNIFE_FOLDS);
    let fold: Vec<usize> = metas
        .iter()
        .map(|m| {
            groups
                .iter()
                .position(|g| *g == key(m))
                .map_or(usize::MAX, |p| p % k)
        })
        .collect();
    Some(
        (0..k)
            .map(|f| (0..metas.len()).filter(|&i| fold[i] != f).collect())
            .collect(),
    )
}

/// The sim's own uncertainty along each free run, per DOF, in the units of the gap
/// metric's energy: with the jackknife laws L_i (`ids`, built with `law_opts`) and their
/// residuals r_i along the run, the jackknife variance (k − 1)/k · Σ_i mean_t((r_i − r̄)²)
/// / norm². It is what the law's estimation error from the forced campaign puts into the
/// residual; where a run lies beyond the forced range, deleting the outer groups moves the
/// law most, and the variance is large. (A bias all the laws share, e.g. the same
/// extrapolation, is not in it: that is what the coverage rule is for.)
///
/// `None` when any jackknife law cannot be built or scored.
pub fn model_energy(
    ids: &[identify::pipeline::Identification],
    law_opts: &IdentifiedOptions,
    free: &Dataset,
    opts: &SystemOptions,
) -> Option<Vec<[f64; 2]>> {
    model_energy_with(ids, law_opts, free, opts, None)
}

/// [`model_energy`] with the runs' model-independent preparation shared through `kin`
/// (see [`prepare_free`]); the same values.
fn model_energy_with(
    ids: &[identify::pipeline::Identification],
    law_opts: &IdentifiedOptions,
    free: &Dataset,
    opts: &SystemOptions,
    kin: Option<&FreeKinematics>,
) -> Option<Vec<[f64; 2]>> {
    use rayon::prelude::*;
    if ids.len() < 2 {
        return None;
    }
    let runs: Vec<Vec<RunResidual>> = ids
        .par_iter()
        .map(|id| {
            let law = IdentifiedLaw::from_identification(id, law_opts).ok()?;
            let model: Arc<dyn AeroModel> = Arc::new(law.model().clone());
            prepare_free(free, &model, opts, kin).ok().map(|p| p.runs)
        })
        .collect::<Option<_>>()?;
    let kf = runs.len() as f64;
    let out = (0..runs[0].len())
        .map(|j| {
            [0, 1].map(|c| {
                let len = runs[0][j].r[c].len();
                let mut e = 0.0;
                for t in 0..len {
                    let mean = runs.iter().map(|r| r[j].r[c][t]).sum::<f64>() / kf;
                    e += runs
                        .iter()
                        .map(|r| (r[j].r[c][t] - mean).powi(2))
                        .sum::<f64>();
                }
                let norm = runs[0][j].norm[c];
                (kf - 1.0) / kf * e / (len.max(1) as f64 * norm * norm)
            })
        })
        .collect();
    Some(out)
}

/// Largest number of folds of the grouped jackknife ([`model_energy`]).
pub const JACKKNIFE_FOLDS: usize = 5;

/// Prepared free runs of a data set for a given aerodynamic model.
pub(crate) struct FreeRuns {
    pub runs: Vec<RunResidual>,
    pub structure: Structure,
}

/// The model-independent part of every free run's preparation ([`residual::KinematicsSlot`],
/// one per free record of one free data set), shared by [`prepare_free`] across the
/// aerodynamic models one system level prepares the runs for.
#[derive(Debug, Default)]
pub(crate) struct FreeKinematics(Vec<residual::KinematicsSlot>);

impl FreeKinematics {
    /// Empty slots for the free runs of `free`.
    fn new(free: &Dataset) -> Self {
        let n = free
            .records
            .iter()
            .filter(|r| r.kind == CaseKind::Free)
            .count();
        FreeKinematics(
            (0..n)
                .map(|_| residual::KinematicsSlot::default())
                .collect(),
        )
    }
}

/// The free runs of `free` prepared for `model`. `kin`: one [`residual::KinematicsSlot`] per
/// free run of `free` (in the order of its free records), shared by the preparations of
/// the same data set for other models (see [`FreeKinematics`]); `None` computes them here.
pub(crate) fn prepare_free(
    free: &Dataset,
    model: &Arc<dyn AeroModel>,
    opts: &SystemOptions,
    kin: Option<&FreeKinematics>,
) -> Result<FreeRuns> {
    let name = free.manifest.name.as_str();
    let spec = opts.structure.or(free.manifest.structure).ok_or_else(|| {
        Error::data(
            name,
            "free-response data set has no [structure] table and no structure was given \
             (the sim needs the nominal structure)",
        )
    })?;
    let structure = StructureSpec::Modal {
        linear: spec,
        nonlinear: Nonlinearities::none(),
    }
    .resolve()
    .map_err(|e| Error::aeroelastic(format!("data set `{name}`: nominal [structure]"), e))?;
    let recs: Vec<_> = free
        .records
        .iter()
        .filter(|r| r.kind == CaseKind::Free)
        .collect();
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
        .enumerate()
        .map(|(j, r)| {
            let hw = (opts.sg_half_window_s / r.dt).round().max(2.0) as usize;
            let s = ResidualSettings {
                half_window: hw,
                order: opts.sg_order.min(2 * hw),
                warmup: opts.warmup,
                pad: opts.pad,
            };
            let slot = kin.and_then(|k| k.0.get(j));
            residual::prepare_run_with(name, r, model, rho, &structure, &s, slot)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(FreeRuns { runs, structure })
}

/// The system level (see the module docs): identifies the sim's law from `forced`
/// ([`sim_law`]) and runs [`system_level_with_model`].
///
/// Adds the level's [`crate::report::Coverage`]: each free run's response K and amplitude
/// against the forced range ([`coverage::ForcedRange`]) and, when runs leave it, the gap
/// with the tables continued by Theodorsen-shaped tails
/// ([`aeroelastic::identified::Extrapolation::Theodorsen`]) instead of straight lines; the
/// tables with the smaller gap are the sim whose gap the candidates explain.
///
/// The gap test's null adds the sim's own uncertainty to the noise: the law identified
/// again in a grouped jackknife over the forced campaign ([`model_energy`],
/// [`LevelResult::model_level`]); the coverage rule's per-run statistics use the same
/// per-run null.
///
/// # Errors
/// As [`sim_law`] and [`system_level_with_model`].
pub fn system_level(forced: &Dataset, free: &Dataset, opts: &SystemOptions) -> Result<LevelResult> {
    opts.check()?;
    let campaign = Campaign::prepare(forced)?;
    let prepared = campaign.identification(&opts.identify)?;
    system_level_of(&campaign, &prepared, forced, free, opts)
}

/// [`system_level`] of a prepared forced campaign (`campaign`, `prepared`: its
/// [`Campaign::identification`] with `opts.identify`; `forced` the data set it was
/// prepared from), so that the force level's preparation serves both levels.
///
/// # Errors
/// As [`system_level`].
pub fn system_level_of(
    campaign: &Campaign,
    prepared: &Prepared<'_>,
    forced: &Dataset,
    free: &Dataset,
    opts: &SystemOptions,
) -> Result<LevelResult> {
    opts.check()?;
    let (id, law, jack) = sim_identification(campaign, prepared, forced)?;
    let model: Arc<dyn AeroModel> = Arc::new(law.model().clone());
    let chord = forced.manifest.section.chord;
    // every model below prepares the same free runs: their derivatives once
    let kin = FreeKinematics::new(free);
    let jack_energy = |law_opts: &IdentifiedOptions| {
        jack.as_ref()
            .and_then(|ids| model_energy_with(ids, law_opts, free, opts, Some(&kin)))
    };
    let linear_energy = jack_energy(&IdentifiedOptions::new(chord));
    let range = coverage::ForcedRange::new(&id, forced, chord);
    let (mut level, _) = level_and_runs(
        &model,
        free,
        opts,
        linear_energy.as_deref(),
        Some(&range),
        true,
        Some(&kin),
    )?;
    let (linear_before, linear_statistic) = (level.before, level.gap_statistic);
    let mut tails: Option<(f64, f64)> = None;
    let mut tail_weights = Vec::new();
    if level.coverage.as_ref().is_some_and(|c| c.any_outside()) {
        let tails_opts = IdentifiedOptions {
            extrapolation: aeroelastic::identified::Extrapolation::Theodorsen,
            ..IdentifiedOptions::new(chord)
        };
        // a failure here only leaves the tails unreported
        if let Ok(tails_law) = IdentifiedLaw::from_identification(&id, &tails_opts) {
            tail_weights = tails_law.tables.tails.clone();
            let tm: Arc<dyn AeroModel> = Arc::new(tails_law.model().clone());
            let tails_energy = jack_energy(&tails_opts);
            if let Ok((tl, _)) = level_and_runs(
                &tm,
                free,
                opts,
                tails_energy.as_deref(),
                Some(&range),
                true,
                Some(&kin),
            ) {
                if tl.before.is_finite() {
                    tails = Some((
                        tl.before,
                        crate::stats::plain_shrink(level.before, tl.before),
                    ));
                    if tl.before < level.before {
                        // the physically consistent extrapolation is the better sim: its
                        // remaining gap is what the candidates are asked to explain
                        level = tl;
                        if let Some(c) = level.coverage.as_mut() {
                            c.sim_tables = "theodorsen_tails".into();
                        }
                    }
                }
            }
        }
    }
    let mut cov = level
        .coverage
        .take()
        .expect("coverage assessed with a range");
    cov.linear_before = linear_before;
    cov.linear_gap_statistic = linear_statistic;
    if let Some((t, x)) = tails {
        cov.tails_before = Some(t);
        cov.tails_shrink = Some(x);
    }
    if !tail_weights.is_empty() {
        let b = 0.5 * chord;
        let plate = std::f64::consts::PI * free.manifest.section.air_density * b * b;
        cov.tails_apparent_mass = tail_weights
            .iter()
            .find(|t| t.derivative == "H4")
            .and_then(|t| t.weights.first())
            .map(|c| c * plate);
        cov.plate_apparent_mass = Some(plate);
        cov.tail_weights = tail_weights;
    }
    let covered_candidate_significant = level
        .candidates
        .iter()
        .any(|c| c.significant && !c.effect.scored_beyond_coverage());
    cov.decide(
        level.gap_threshold,
        null_level(&level),
        covered_candidate_significant,
    );
    level.coverage = Some(cov);
    Ok(level)
}

/// Weighted mean over runs of per-DOF energies (`w`: one weight per run, see
/// [`run_weights`]).
fn wmean2(v: &[[f64; 2]], w: &[f64]) -> [f64; 2] {
    let sw: f64 = w.iter().sum();
    let mut m = [0.0; 2];
    if sw <= 0.0 {
        return m;
    }
    for (e, wj) in v.iter().zip(w) {
        m[0] += wj * e[0] / sw;
        m[1] += wj * e[1] / sw;
    }
    m
}

/// Fold of each run: leave one run out (`folds` = 0 or ≥ the number of runs), else a
/// seeded shuffle of the runs dealt round-robin into `folds` folds.
fn fold_of(n: usize, folds: usize, seed: u64) -> Vec<usize> {
    if folds == 0 || folds >= n {
        return (0..n).collect();
    }
    use rand::seq::SliceRandom;
    use rand::SeedableRng;
    let mut idx: Vec<usize> = (0..n).collect();
    idx.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    let mut f = vec![0; n];
    for (k, &i) in idx.iter().enumerate() {
        f[i] = k % folds;
    }
    f
}

/// Combined gap of per-channel mean energies: sqrt((E_heave + E_pitch)/2).
fn comb(e: [f64; 2]) -> f64 {
    (0.5 * (e[0] + e[1])).max(0.0).sqrt()
}

/// Held-out scoring of one candidate in its chosen form.
struct Scored {
    effect: Effect,
    /// Coefficient indices of the form.
    cols: Vec<usize>,
    /// Per-run energies before (with the extrapolation nuisance profiled out where it
    /// applies) and held out after; inactive runs keep their before energy.
    before_runs: Vec<[f64; 2]>,
    after_runs: Vec<[f64; 2]>,
    /// Runs the candidate is fitted and scored on.
    active: Vec<bool>,
    variant: usize,
    /// Coefficients of every column of the candidate (zero outside the form), fit sign.
    theta: Vec<f64>,
    failure: Option<String>,
    note: Option<String>,
}

/// The air's apparent mass in still air (issue 29, structure first): no identified law
/// predicts it at U = 0 (a law identified at K ≤ 1.2 extrapolates its K² terms to
/// anything; the flat-plate πρb² needs the elastic axis, which a data set does not give),
/// yet every still-air decay contains it (5 % of the plate rig's heave mass). It is fitted
/// on the still-air runs, pooled: per equation c the least-squares m_c of the normalised
/// residual on (ḧ, α̈) (the same weights as the gap), and M_a q̈ is removed from those
/// runs' residuals. Returns the 2×2 apparent mass (rows: heave, pitch equation; the
/// residual convention M q̈ + … − F, so positive is mass the nominal structure lacks), or
/// `None` without a still-air run or when the fit is singular.
fn still_air_mass(runs: &mut [RunResidual]) -> Option<[[f64; 2]; 2]> {
    let still: Vec<usize> = (0..runs.len()).filter(|&j| runs[j].u == 0.0).collect();
    if still.is_empty() {
        return None;
    }
    let mut m = [[0.0; 2]; 2];
    for (c, mc) in m.iter_mut().enumerate() {
        let mut g = [0.0; 4];
        let mut b = [0.0; 2];
        for &j in &still {
            let r = &runs[j];
            let w = 1.0 / (r.len().max(1) as f64 * r.norm[c].powi(2));
            let x = [&r.qdd[0][r.i0..r.i1], &r.qdd[1][r.i0..r.i1]];
            for a in 0..2 {
                b[a] += w * x[a].iter().zip(&r.r[c]).map(|(p, q)| p * q).sum::<f64>();
                for bb in 0..2 {
                    g[a * 2 + bb] += w * x[a].iter().zip(x[bb]).map(|(p, q)| p * q).sum::<f64>();
                }
            }
        }
        *mc = candidates::solve(&g, &b).map(|v| [v[0], v[1]])?;
    }
    for &j in &still {
        let r = &mut runs[j];
        let (i0, qdd) = (r.i0, &r.qdd);
        for (rc, mc) in r.r.iter_mut().zip(&m) {
            for (k, v) in rc.iter_mut().enumerate() {
                *v -= mc[0] * qdd[0][i0 + k] + mc[1] * qdd[1][i0 + k];
            }
        }
    }
    Some(m)
}

/// The still-air decays read against the given structure at rest (issue 42 item 5, round
/// 30) and the DOFs whose linear stiffness the structural candidates correct.
struct RestCheck {
    /// The check, with the structure identified from the decays.
    check: crate::structure::StructureCheck,
    /// Per DOF (heave, pitch): a linear stiffness nuisance Δk_d q_d is fitted with every
    /// structural candidate and its baseline.
    dofs: [bool; 2],
}

/// The flat plate's apparent mass in still air per unit span, πρb²·[[1, −ab], [−ab,
/// b²(1/8 + a²)]] (b = chord/2; rows heave, pitch; h down, α nose-up), with the elastic
/// axis a \[semi-chords, + aft of mid-chord\] read from the heave row of the fitted
/// still-air mass `fitted` ([`still_air_mass`]: its coefficients are −M_a): the heave
/// equation holds no pitch stiffness, so its α̈ coefficient is the coupling −πρb³a
/// whatever the given k_α; a is clamped to the chord, [−1, 1]. The pitch row is not read
/// from the fit: there the air's inertia is confounded with the pitch stiffness error and a
/// nonlinear spring's mean stiffness over the decay (the reason the fitted mass is no
/// test of the given structure, DECISIONS round 29).
fn plate_air_mass(fitted: [[f64; 2]; 2], rho: f64, chord: f64) -> nalgebra::Matrix2<f64> {
    let b = 0.5 * chord;
    let c = std::f64::consts::PI * rho * b * b;
    // −M_a[0][1] = fitted[0][1] = πρb³a
    let a = (fitted[0][1] / (c * b)).clamp(-1.0, 1.0);
    let a = if a.is_finite() { a } else { 0.0 };
    nalgebra::Matrix2::new(c, -c * a * b, -c * a * b, c * b * b * (0.125 + a * a))
}

/// The still-air decays of `free` against the nominal structure `st` with the flat
/// plate's apparent mass ([`plate_air_mass`] from the fitted `air_mass`), the linear
/// structure identified from them ([`crate::structure::structure_check_with_mass`]: the
/// decays' *linear* frequencies, the backbone's small-amplitude end), and the DOFs whose
/// stiffness is corrected. A DOF d is corrected when (1) some measured still-air mode's
/// linear frequency lies more than [`crate::structure::COVERAGE`] standard uncertainties
/// from the given one and the identification frees k_d (both stiffnesses with two modes
/// measured, else the one of the DOF dominating the measured mode), and (2) the
/// identified error is visible at this level: the normalised energy its force
/// (k_d,identified − k_d,given) q_d puts into DOF d's residual, mean((Δk_d q_d/norm_d)²)
/// pooled over `runs` with the level's run weights, exceeds the runs' own noise energy in
/// that DOF. (1) alone fires on errors of 0.05 % in k (window scatter of a clean decay
/// gives 0.01 % frequency uncertainties, below the plate model's own accuracy), which no
/// level can see. `None` without a still-air mode read.
fn rest_check(
    free: &Dataset,
    st: &Structure,
    runs: &[RunResidual],
    air_mass: [[f64; 2]; 2],
    rho: f64,
    chord: f64,
) -> Option<RestCheck> {
    let m = st.mass_matrix() + plate_air_mass(air_mass, rho, chord);
    let mut check = crate::structure::structure_check_with_mass(&[free], &m, st)?;
    let cov = crate::structure::COVERAGE;
    let mut dofs = [false; 2];
    let weights = run_weights(runs);
    let mut visibility = [(0.0, 0.0); 2];
    if let Some(id) = &check.identified {
        let differs = id.modes.iter().any(|md| md.frequency_z.abs() > cov);
        for (d, name) in ["k_h", "k_alpha"].iter().enumerate() {
            let Some(p) = id.parameters.iter().find(|p| p.name == *name && !p.held) else {
                continue;
            };
            let dk = p.identified - p.given;
            let per_run: Vec<[f64; 2]> = runs
                .iter()
                .map(|r| {
                    let q = &r.q[d][r.i0..r.i1];
                    let e = q.iter().map(|v| (dk * v).powi(2)).sum::<f64>()
                        / (q.len().max(1) as f64 * r.norm[d].powi(2));
                    let mut out = [0.0; 2];
                    out[d] = e;
                    out
                })
                .collect();
            let noise: Vec<[f64; 2]> = runs.iter().map(|r| r.noise_energy).collect();
            visibility[d] = (wmean2(&per_run, &weights)[d], wmean2(&noise, &weights)[d]);
            dofs[d] = differs && visibility[d].0 > visibility[d].1;
        }
    }
    // the level keeps the given structure: the correction enters as a nuisance
    check.used = crate::structure::StructureUsed::Given;
    let energies = ["heave", "pitch"]
        .iter()
        .zip(visibility)
        .filter(|(_, v)| v.1 > 0.0)
        .map(|(n, v)| {
            format!(
                "{n}: the identified stiffness error's residual energy {:.2e} against the \
                 noise's {:.2e}",
                v.0, v.1
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    check.reason = if dofs.iter().any(|&x| x) {
        format!(
            "the still-air decays' linear frequencies differ from the given structure's \
             (with the flat plate's apparent mass, elastic axis from the heave equation) \
             beyond {cov} standard uncertainties, by more than the level's noise ({energies}): \
             every structural candidate and its baseline fit a pooled linear stiffness \
             correction ({}) as a nuisance, so that what they remove is amplitude \
             dependence; the sim keeps the given structure ({})",
            [("Δk_h", dofs[0]), ("Δk_α", dofs[1])]
                .iter()
                .filter(|x| x.1)
                .map(|x| x.0)
                .collect::<Vec<_>>()
                .join(", "),
            check.reason
        )
    } else {
        format!(
            "no stiffness correction: the still-air decays' linear frequencies agree with \
             the given structure's (with the flat plate's apparent mass) within {cov} \
             standard uncertainties, or the difference lies below the level's noise \
             ({energies}), or no mode was read ({})",
            check.reason
        )
    };
    Some(RestCheck { check, dofs })
}

/// Mean of the two DOFs' energies.
fn e2(e: [f64; 2]) -> f64 {
    0.5 * (e[0] + e[1])
}

/// Held-out fit of `vars` (one form) over the `active` runs: per-run energies after, the
/// variant and coefficients fitted on every active run, a failure message.
fn held_out(
    vars: &[Variant],
    folds: &[usize],
    active: &[bool],
) -> (Vec<[f64; 2]>, usize, Vec<f64>, Option<String>) {
    let n = folds.len();
    let p = vars.first().map_or(0, |v| v.names.len());
    let mut after: Vec<[f64; 2]> = (0..n)
        .map(|j| vars.first().map_or([0.0; 2], |v| v.moments[j].e))
        .collect();
    let mut failure = None;
    let n_folds = folds.iter().max().map_or(0, |m| m + 1);
    for k in 0..n_folds {
        let held: Vec<usize> = (0..n).filter(|&j| folds[j] == k && active[j]).collect();
        if held.is_empty() {
            continue;
        }
        let train: Vec<usize> = (0..n).filter(|&j| folds[j] != k && active[j]).collect();
        match candidates::fit(vars, &train) {
            Some((v, theta, _)) if !train.is_empty() => {
                for j in held {
                    after[j] = candidates::energy_after(&vars[v].moments[j], &theta);
                }
            }
            _ => failure = Some(format!("no training run or a singular fit in fold {k}")),
        }
    }
    let all: Vec<usize> = (0..n).filter(|&j| active[j]).collect();
    let (variant, theta) = match candidates::fit(vars, &all) {
        Some((v, t, _)) if !all.is_empty() => (v, t),
        _ => {
            failure.get_or_insert_with(|| "singular least-squares fit".into());
            (0, vec![0.0; p])
        }
    };
    (after, variant, theta, failure)
}

/// Whether the simpler per-run energies `simple` are within one standard error of
/// `best` over the `active` runs (paired: the mean of the per-run differences is at most
/// their standard error), or within the parsimony allowance `allowance` (energy).
fn within_one_se(simple: &[[f64; 2]], best: &[[f64; 2]], active: &[bool], allowance: f64) -> bool {
    let d: Vec<f64> = (0..simple.len())
        .filter(|&j| active[j])
        .map(|j| e2(simple[j]) - e2(best[j]))
        .collect();
    crate::stats::paired_within_one_se(&d, allowance)
}

/// Scores one candidate: fitted on the training folds of its active runs, scored on the
/// held-out ones, in each of its forms ([`SystemTerm::forms`]); the form named is the one
/// with fewest coefficients within one standard error (or the parsimony allowance) of
/// the best form.
///
/// Coverage rule (issue 29): an aerodynamic candidate is fitted and scored on the runs
/// inside the forced range only (`uncovered[j]` false); a structural one on every run,
/// fitted jointly with the pooled apparent-mass nuisances ([`candidates::nuisance_columns`]:
/// the motion outside its forced K range, the still air) and scored against them alone, so
/// that what it removes is what the law's extrapolation and the air's mass cannot.
#[allow(clippy::too_many_arguments)]
fn score_candidate(
    effect: Effect,
    term: &dyn SystemTerm,
    runs: &[RunResidual],
    folds: &[usize],
    rho: f64,
    chord: f64,
    uncovered: &[bool],
    outside: &[[bool; 2]],
    stiffness: [bool; 2],
    allowance_per_param: f64,
) -> Scored {
    let n = runs.len();
    // gated: scored on the covered runs in the wind only
    let aero = !effect.scored_beyond_coverage();
    // the linear stiffness nuisance: structural candidates only (a static offset is
    // scored beyond coverage but is no structure)
    let structural = effect.level() == Level::Structural;
    let flags: Vec<candidates::Flags> = (0..n)
        .map(|j| {
            let still = runs[j].u == 0.0;
            if aero {
                [[false; 2]; 3]
            } else if structural {
                // in the wind only: in still air the free apparent mass and a stiffness
                // together follow any backbone (Δk − ΔM ω(t)² tracks a cubic's A(t)²)
                [outside[j], [still; 2], stiffness.map(|k| k && !still)]
            } else {
                [outside[j], [still; 2], [false; 2]]
            }
        })
        .collect();
    let vars = candidates::variants(term, runs, rho, chord, &flags);
    let p_c = term.coefficient_names().len();
    let p_all = vars.first().map_or(p_c, |v| v.names.len());
    let nuis_idx: Vec<usize> = (p_c..p_all).collect();
    // an aerodynamic candidate: runs in the wind inside the forced range only
    let in_wind = effect.level() == Level::Aerodynamic;
    let active: Vec<bool> = (0..n)
        .map(|j| !((aero && uncovered[j]) || (in_wind && runs[j].u == 0.0)))
        .collect();
    let ids = |want: bool| -> Vec<&str> {
        (0..n)
            .filter(|&j| uncovered[j] == want)
            .map(|j| runs[j].id.as_str())
            .collect()
    };
    let mut note = None;
    let profiled: Vec<&str> = (0..n)
        .filter(|&j| !aero && (outside[j][0] || outside[j][1]))
        .map(|j| runs[j].id.as_str())
        .collect();
    if (aero && uncovered.iter().any(|&u| u)) || (!aero && !profiled.is_empty()) {
        note = Some(if aero {
            let inside = ids(false);
            if inside.is_empty() {
                "not scored: no free run lies inside the forced range, and an aerodynamic \
                 candidate is named at this level only on evidence from such runs"
                    .to_string()
            } else {
                format!(
                    "fitted and scored on the run(s) inside the forced range only ({}): an \
                     aerodynamic candidate is named at this level only on their evidence",
                    inside.join(", ")
                )
            }
        } else {
            format!(
                "scored against the sim with an apparent-mass correction of the motion \
                 outside its forced K range fitted alongside (run(s) {}): what the candidate \
                 removes beyond it is what the law's extrapolation cannot produce",
                profiled.join(", ")
            )
        });
    }
    let mut before_runs: Vec<[f64; 2]> = (0..n)
        .map(|j| vars.first().map_or(runs[j].energy(), |v| v.moments[j].e))
        .collect();
    if !active.iter().any(|&a| a) {
        return Scored {
            effect,
            cols: (0..p_c).collect(),
            after_runs: before_runs.clone(),
            before_runs,
            active,
            variant: 0,
            theta: vec![0.0; p_c],
            failure: None,
            note,
        };
    }
    if !nuis_idx.is_empty() {
        // the baseline: the sim with the extrapolation nuisance alone, held out as well
        let base: Vec<Variant> = vars.iter().take(1).map(|v| v.select(&nuis_idx)).collect();
        before_runs = held_out(&base, folds, &active).0;
    }
    let noise_e = {
        let (s, m) = (0..n).filter(|&j| active[j]).fold((0.0, 0.0), |(s, m), j| {
            (s + e2(runs[j].noise_energy), m + 1.0)
        });
        s / f64::max(m, 1.0)
    };
    let forms = term.forms();
    let results: Vec<_> = forms
        .iter()
        .map(|(label, idx)| {
            let with: Vec<usize> = idx.iter().chain(&nuis_idx).copied().collect();
            let sub: Vec<Variant> = vars.iter().map(|v| v.select(&with)).collect();
            (*label, idx.clone(), held_out(&sub, folds, &active))
        })
        .collect();
    let mean = |a: &[[f64; 2]]| -> f64 {
        let v: Vec<f64> = (0..n).filter(|&j| active[j]).map(|j| e2(a[j])).collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    let best = (0..results.len())
        .min_by(|&a, &b| mean(&results[a].2 .0).total_cmp(&mean(&results[b].2 .0)))
        .unwrap_or(0);
    // the simplest form within one standard error of the best (ties: the lower mean)
    let chosen = (0..results.len())
        .filter(|&k| {
            let extra = results[best].1.len().saturating_sub(results[k].1.len());
            k == best
                || within_one_se(
                    &results[k].2 .0,
                    &results[best].2 .0,
                    &active,
                    allowance_per_param * extra as f64 * noise_e,
                )
        })
        .min_by(|&a, &b| {
            results[a]
                .1
                .len()
                .cmp(&results[b].1.len())
                .then(mean(&results[a].2 .0).total_cmp(&mean(&results[b].2 .0)))
        })
        .unwrap_or(best);
    if forms.len() > 1 {
        let form_note = if chosen == best {
            format!(
                "form `{}` (best held-out score of the forms)",
                results[chosen].0
            )
        } else {
            format!(
                "form `{}`, the simplest within one standard error of the best form `{}`",
                results[chosen].0, results[best].0
            )
        };
        note = Some(match note {
            Some(n) => format!("{form_note}; {n}"),
            None => form_note,
        });
    }
    let (_, idx, (after_runs, variant, theta_sub, failure)) =
        results.into_iter().nth(chosen).expect("chosen form exists");
    let mut theta = vec![0.0; p_c];
    for (k, &i) in idx.iter().enumerate() {
        theta[i] = theta_sub.get(k).copied().unwrap_or(0.0);
    }
    Scored {
        effect,
        cols: idx,
        before_runs,
        after_runs,
        active,
        variant,
        theta,
        failure,
        note,
    }
}

/// The system level for a given sim aerodynamic model (the identified law, or any
/// [`AeroModel`], e.g. a truth model in tests).
///
/// **Gap.** Per run and DOF the normalised energy mean((r_c/norm_c)²); the level's gap
/// is sqrt of the mean over the runs in the wind and over DOFs (the two channels weigh
/// equally); still-air runs (U = 0) are fitted and reported but pooled only when no run is
/// in the wind (they are judged by the structure check, see `LevelResult::structure`).
/// Every run is
/// held out once (the baseline has no parameter fitted on free data, so its held-out gap
/// is its gap on all runs). Noise level: the same metric for an exact model, from the
/// displacement noise σ̂ ([`identify::preprocess::noise_sigma`] of each run) through the
/// residual operator's impulse responses (differentiator, aerodynamic filter).
///
/// **Gap test.** statistic = before / null, null = noise_level here (no forced campaign,
/// no model uncertainty; [`system_level`] adds the identified law's jackknife uncertainty,
/// [`LevelResult::model_level`]); significant when it exceeds
/// [`SystemOptions::gap_ratio`] (default 1.25; on effect-free blind sets the statistic is
/// 1.01–1.09 over 20 seeds, 0 false alarms).
///
/// **Candidates.** Fitted on the training folds (least squares, grid for nonlinear
/// parameters), scored on the held-out runs. statistic = held-out residual energy
/// removed in units of the noise energy, (E_before − E_after)/E_noise; parsimony: threshold =
/// [`SystemOptions::min_gain`] + [`SystemOptions::gain_per_param`] × parameters; a candidate
/// is significant when the gap is significant and the statistic exceeds its threshold.
/// Ranking score = threshold − statistic (lower is better).
///
/// # Errors
/// [`Error::Setting`] for bad options; [`Error::Data`] naming the free data set and run
/// (no `[structure]`, fewer than `min_runs` runs, a run too short or without motion).
pub fn system_level_with_model(
    model: &Arc<dyn AeroModel>,
    free: &Dataset,
    opts: &SystemOptions,
) -> Result<LevelResult> {
    level_and_runs(model, free, opts, None, None, false, None).map(|(level, _)| level)
}

/// The gap test's null level of a level: sqrt(noise_level² + model_level²).
pub fn null_level(level: &LevelResult) -> f64 {
    level.noise_level.hypot(level.model_level.unwrap_or(0.0))
}

/// [`system_level_with_model`] and the prepared runs it scored.
/// `model_energy`: the sim's own uncertainty per run and DOF ([`model_energy`]), added to
/// the noise in the gap test's null. `rest`: the still-air decays are read against the
/// given structure with the flat plate's apparent mass ([`rest_check`]) and, where they
/// differ, every structural candidate and its baseline fit a linear stiffness nuisance
/// (with a forced campaign; the `--model` path identifies the structure instead,
/// [`crate::pipeline::diagnose_free`]). `kin`: the free runs' model-independent preparation
/// shared with other models' levels ([`prepare_free`]).
#[allow(clippy::too_many_arguments)] // one level's inputs, passed through
fn level_and_runs(
    model: &Arc<dyn AeroModel>,
    free: &Dataset,
    opts: &SystemOptions,
    model_energy: Option<&[[f64; 2]]>,
    range: Option<&coverage::ForcedRange>,
    rest: bool,
    kin: Option<&FreeKinematics>,
) -> Result<(LevelResult, FreeRuns)> {
    opts.check()?;
    let mut p = prepare_free(free, model, opts, kin)?;
    // candidates fit the still air's apparent mass jointly (a nuisance); the gap and its
    // splits are those of the residual with it removed
    let raw_runs = p.runs.clone();
    let air_mass = still_air_mass(&mut p.runs);
    let rest_structure = if rest {
        air_mass.and_then(|m| {
            rest_check(
                free,
                &p.structure,
                &p.runs,
                m,
                free.manifest.section.air_density,
                model.chord(),
            )
        })
    } else {
        None
    };
    let stiffness = rest_structure.as_ref().map_or([false; 2], |r| r.dofs);
    let n = p.runs.len();
    let folds = fold_of(n, opts.folds, opts.seed);
    // controlled records: the control force as a known input, held out like the level
    let control = control::apply_held_out(&mut p.runs, &folds);
    let runs = &p.runs;
    let rho = free.manifest.section.air_density;
    let chord = model.chord();
    let before_runs: Vec<[f64; 2]> = runs.iter().map(|r| r.energy()).collect();
    let noise_runs: Vec<[f64; 2]> = runs.iter().map(|r| r.noise_energy).collect();
    // still-air runs out of the pooled gap when runs in the wind exist
    let weights = run_weights(runs);
    let e_before = wmean2(&before_runs, &weights);
    let e_noise = wmean2(&noise_runs, &weights);
    let before = comb(e_before);
    let noise_level = comb(e_noise);
    let model_level = model_energy
        .filter(|e| e.len() == n)
        .map(|e| comb(wmean2(e, &weights)));
    let gap_statistic = before
        / noise_level
            .hypot(model_level.unwrap_or(0.0))
            .max(f64::MIN_POSITIVE);
    let significant_gap = gap_statistic > opts.gap_ratio;

    // coverage of each run against the forced range (when the range is known)
    let null_runs: Vec<f64> = (0..n)
        .map(|j| {
            let m = model_energy
                .filter(|e| e.len() == n)
                .map_or(0.0, |e| comb(e[j]));
            comb(noise_runs[j]).hypot(m)
        })
        .collect();
    let coverage = range.map(|rg| {
        let b: Vec<f64> = before_runs.iter().map(|&e| comb(e)).collect();
        coverage::assess(rg, runs, &b, &null_runs)
    });
    let uncovered: Vec<bool> = match &coverage {
        Some(c) => c.runs.iter().map(|r| !r.covered).collect(),
        None => vec![false; n],
    };
    // per mode: the DOFs whose response K leaves that DOF's forced range
    let outside: Vec<[bool; 2]> = match (&coverage, range) {
        (Some(c), Some(rg)) => c
            .runs
            .iter()
            .map(|rc| rg.k_outside(rc.k_h, rc.k_alpha))
            .collect(),
        _ => vec![[false; 2]; n],
    };
    let model_e: Vec<f64> = (0..n)
        .map(|j| {
            model_energy
                .filter(|e| e.len() == n)
                .map_or(0.0, |e| e2(e[j]))
        })
        .collect();
    let mut scored: Vec<(CandidateScore, Scored)> = Effect::ALL
        .into_iter()
        .filter_map(|e| Some((e, e.entry().system()?)))
        .map(|(effect, term)| {
            let sc = score_candidate(
                effect,
                term,
                &raw_runs,
                &folds,
                rho,
                chord,
                &uncovered,
                &outside,
                stiffness,
                opts.gain_per_param,
            );
            let act: Vec<usize> = (0..n).filter(|&j| sc.active[j]).collect();
            // weighted means over the active runs (the level's run weights)
            let m = act.iter().map(|&j| weights[j]).sum::<f64>();
            let m = if m > 0.0 { m } else { 1.0 };
            let wsum = |f: &dyn Fn(usize) -> f64| -> f64 {
                act.iter().map(|&j| weights[j] * f(j)).sum::<f64>() / m
            };
            let eb = wsum(&|j| e2(sc.before_runs[j]));
            let ea = wsum(&|j| e2(sc.after_runs[j]));
            let en = wsum(&|j| e2(noise_runs[j]));
            let em = wsum(&|j| model_e[j]);
            let (c_before, c_after) = (eb.max(0.0).sqrt(), ea.max(0.0).sqrt());
            // energy removed, summed (weighted) over the active runs and spread over every
            // run, in units of the level's noise energy: comparable across candidates
            // whatever runs they were scored on
            let en_all = noise_level * noise_level;
            let w_all: f64 = weights.iter().sum();
            let statistic = if en_all > 0.0 && !act.is_empty() && w_all > 0.0 {
                (eb - ea) * m / w_all / en_all
            } else {
                0.0
            };
            // the candidate's own baseline must show a gap: with the nuisance profiled
            // out (structural) or on the covered runs (aerodynamic)
            let own_gap = !act.is_empty()
                && c_before / (en + em).max(0.0).sqrt().max(f64::MIN_POSITIVE) > opts.gap_ratio;
            let n_params = sc.cols.len() + term.n_grid_params();
            let threshold = opts.min_gain + opts.gain_per_param * n_params as f64;
            let mut parameters: Vec<(String, f64)> = term
                .grids(runs)
                .into_iter()
                .nth(sc.variant)
                .map(|g| g.0)
                .unwrap_or_default();
            let names = term.coefficient_names();
            let sign = term.report_sign();
            parameters.extend(
                sc.cols
                    .iter()
                    .map(|&i| (names[i].to_string(), sign * sc.theta[i])),
            );
            // a dead band removes stiffness and friction opposes the motion: the other
            // sign is no such effect (it would only mimic a hardening spring or a
            // negative damping)
            let unphysical = term.sign_bound() && sc.cols.iter().any(|&i| sign * sc.theta[i] < 0.0);
            let mut note = sc.note.clone();
            if unphysical {
                let n = "not named: a fitted coefficient has the unphysical sign".to_string();
                note = Some(match note {
                    Some(x) => format!("{n}; {x}"),
                    None => n,
                });
            }
            let cs = CandidateScore {
                effect,
                level: Level::Structural,
                before: c_before,
                after: c_after,
                shrink: if c_before > 0.0 {
                    1.0 - c_after / c_before
                } else {
                    0.0
                },
                n_params,
                statistic,
                threshold,
                significant: significant_gap
                    && own_gap
                    && !unphysical
                    && statistic > threshold
                    && sc.failure.is_none(),
                score: threshold - statistic,
                parameters,
                failure: sc.failure.clone(),
                convention: Some(term.convention().to_string()),
                note,
                held_out_runs: sc.after_runs.iter().map(|&e| e2(e)).collect(),
            };
            (cs, sc)
        })
        .collect();
    scored.sort_by(|a, b| a.0.score.total_cmp(&b.0.score));
    let best = scored.first().filter(|(c, _)| c.significant);
    let cases: Vec<CaseGap> = runs
        .iter()
        .enumerate()
        .map(|(j, r)| CaseGap {
            id: r.id.clone(),
            level: Level::Structural,
            config: None,
            wind_speed: r.u,
            amplitude: r.q[1][r.i0..r.i1]
                .iter()
                .fold(0.0_f64, |m, v| m.max(v.abs()))
                .to_degrees(),
            fold: folds[j],
            before: comb(before_runs[j]),
            after: best.map_or(comb(before_runs[j]), |(_, s)| comb(s.after_runs[j])),
            noise_level: comb(noise_runs[j]),
        })
        .collect();
    let best_cols = best.and_then(|(_, s)| {
        let term = s.effect.entry().system()?;
        let grid = term
            .grids(runs)
            .into_iter()
            .nth(s.variant)
            .map(|g| g.0)
            .unwrap_or_default();
        Some((term, grid, s.theta.clone()))
    });
    let where_ = analysis::where_shares(runs, &noise_runs);
    let spectra = analysis::spectra(runs, best_cols.as_ref(), rho, chord);
    let signatures = simulate::signatures(runs, gap_statistic, opts.gap_ratio);
    let (observables, bifurcation) = if opts.simulate {
        let aug = best_cols.as_ref().map(|(term, g, t)| simulate::Augment {
            term: *term,
            grid: g.iter().map(|x| x.1).collect(),
            theta: t.clone(),
        });
        let sim = simulate::compare(model, rho, &p.structure, runs, aug.as_ref());
        (sim.observables, Some(sim.bifurcation))
    } else {
        (vec![], None)
    };
    // the still-air decays against the nominal structure with the air's mass: the flat
    // plate's with a forced campaign ([`rest_check`]), else the fitted one (which carries
    // the nominal structure's misfit too; the `--model` path replaces this check)
    let structure = match rest_structure {
        Some(r) => Some(r.check),
        None => {
            let st = &p.structure;
            let mut m = st.mass_matrix();
            if let Some(a) = air_mass {
                // the fitted coefficients remove m q̈ from the residual M q̈ + …: the air's
                // mass is −m
                for i in 0..2 {
                    for j in 0..2 {
                        m[(i, j)] -= a[i][j];
                    }
                }
            }
            crate::structure::structure_check_matrices(
                &[free],
                &m,
                &st.stiffness_matrix(),
                &st.damping_matrix(),
            )
        }
    };
    let level = LevelResult {
        interpolated_gap_statistic: None,
        model_level,
        level: Level::Structural,
        metric: "held-out normalised equation error of the free response".into(),
        before,
        noise_level,
        significant_gap,
        gap_statistic,
        gap_threshold: opts.gap_ratio,
        held_out_cases: runs.iter().map(|r| r.id.clone()).collect(),
        candidates: scored.into_iter().map(|(c, _)| c).collect(),
        where_,
        cases,
        spectra,
        signatures,
        observables,
        bifurcation,
        fold_scheme: Some(crate::report::FoldScheme {
            scheme: if folds.iter().max().map_or(0, |m| m + 1) == n {
                "leave_one_run_out".into()
            } else {
                "seeded_k_fold".into()
            },
            folds: folds.iter().max().map_or(0, |m| m + 1),
            groups: n,
            note: {
                let still = runs.iter().filter(|r| r.u == 0.0).count();
                Some(match air_mass {
                    Some(m) => format!(
                        "{still} still-air run(s) (U = 0): no circulatory force; the air's \
                         apparent mass fitted on them (least squares, 4 coefficients, \
                         removed from their residual): [[{:.4}, {:.4} kg], [{:.4} kg, {:.3e} \
                         kg m]] per unit span",
                        m[0][0], m[0][1], m[1][0], m[1][1]
                    ),
                    None if still > 0 => format!(
                        "{still} still-air run(s) (U = 0): residual without aerodynamic force"
                    ),
                    None => "no still-air decay (U = 0) among the free runs: the structure \
                             is judged on the flow runs' amplitude dependence alone"
                        .to_string(),
                })
            },
        }),
        coverage,
        structure,
        control,
    };
    Ok((level, p))
}
