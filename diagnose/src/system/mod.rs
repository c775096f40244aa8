//! The system level of the diagnosis: the sim (the law identified from every forced case,
//! coupled to the nominal structure of the free data set's manifest `[structure]`)
//! against free-response records (h, α only).
//!
//! See [`system_level`] for the steps and the documented choices.

// The crate's error enum carries identify/aeroelastic errors by value (skeleton choice).

pub mod residual;

mod analysis;
mod candidates;
pub mod coverage;
pub(crate) mod simulate;

use std::sync::Arc;

use aeroelastic::aero::AeroModel;
use aeroelastic::identified::{IdentifiedLaw, IdentifiedOptions};
use aeroelastic::structure::{Nonlinearities, Structure, StructureSpec};
use identify::dataset::Dataset;
use identify::pipeline::{identify, IdentifySettings};
use identify::preprocess::PreprocessOptions;
use identify::record::CaseKind;

use crate::effect::{Effect, Level};
use crate::report::{CandidateScore, CaseGap, LevelResult};
use crate::{Error, Result};

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
    /// Preprocessing of the forced records for the identification.
    pub preprocess: PreprocessOptions,
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
            preprocess: PreprocessOptions::default(),
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

/// Identifies the sim's law from every forced case of `forced` (preprocessing and
/// identification with `opts`' settings, then [`IdentifiedLaw::from_identification`] with
/// the default [`IdentifiedOptions`] for the data set's chord).
///
/// # Errors
/// [`Error::Data`] when `forced` has no forced case; [`Error::Identify`] /
/// [`Error::Aeroelastic`] naming the data set when preprocessing, identification or the
/// law fails.
pub fn sim_law(forced: &Dataset, opts: &SystemOptions) -> Result<IdentifiedLaw> {
    sim_identification(forced, opts).map(|(_, law, _)| law)
}

/// [`sim_law`] together with the identification it was built from and the preprocessed
/// forced cases (the jackknife reuses them).
fn sim_identification(
    forced: &Dataset,
    opts: &SystemOptions,
) -> Result<(
    identify::pipeline::Identification,
    IdentifiedLaw,
    Vec<identify::record::NondimCase>,
)> {
    let name = forced.manifest.name.clone();
    if !forced.records.iter().any(|r| r.kind == CaseKind::Forced) {
        return Err(Error::data(
            &name,
            "no forced case to identify the sim's law from",
        ));
    }
    let prepared = identify::workflow::prepare_dataset(forced, &opts.preprocess)
        .map_err(|e| Error::identify(format!("data set `{name}`: preprocessing"), e))?;
    let id = identify(&prepared.cases, &opts.identify, &name, &|_| {})
        .map_err(|e| Error::identify(format!("data set `{name}`: identification"), e))?;
    let law = IdentifiedLaw::from_identification(
        &id,
        &IdentifiedOptions::new(forced.manifest.section.chord),
    )
    .map_err(|e| Error::aeroelastic(format!("data set `{name}`: identified law"), e))?;
    Ok((id, law, prepared.cases))
}

/// The grouped-jackknife identifications of the forced campaign `cases` (data set
/// `name`, preprocessed as for the sim's law): the interior (configuration,
/// wind speed) groups (every wind speed of a configuration but its lowest and highest;
/// all groups when fewer than two are interior), sorted, are dealt round-robin into
/// k = min(groups, [`JACKKNIFE_FOLDS`]) folds and the law is identified again without each
/// fold (in parallel). `None` with fewer than 3 groups or when any fold fails to identify
/// (the sim is then scored against the noise alone, as without a forced campaign).
fn jackknife_identifications(
    cases: &[identify::record::NondimCase],
    name: &str,
    opts: &SystemOptions,
) -> Option<Vec<identify::pipeline::Identification>> {
    use rayon::prelude::*;
    let key = |m: &identify::record::CaseMeta| {
        (m.config.clone().unwrap_or_default(), m.wind_speed.to_bits())
    };
    let mut groups: Vec<(String, u64)> = cases.iter().map(|c| key(&c.meta)).collect();
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
    let fold: Vec<usize> = cases
        .iter()
        .map(|c| {
            groups
                .iter()
                .position(|g| *g == key(&c.meta))
                .map_or(usize::MAX, |p| p % k)
        })
        .collect();
    (0..k)
        .into_par_iter()
        .map(|f| {
            let train: Vec<_> = cases
                .iter()
                .zip(&fold)
                .filter(|(_, &g)| g != f)
                .map(|(c, _)| c.clone())
                .collect();
            identify(&train, &opts.identify, name, &|_| {}).ok()
        })
        .collect()
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
    use rayon::prelude::*;
    if ids.len() < 2 {
        return None;
    }
    let runs: Vec<Vec<RunResidual>> = ids
        .par_iter()
        .map(|id| {
            let law = IdentifiedLaw::from_identification(id, law_opts).ok()?;
            let model: Arc<dyn AeroModel> = Arc::new(law.model().clone());
            prepare_free(free, &model, opts).ok().map(|p| p.runs)
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
pub(crate) struct Prepared {
    pub runs: Vec<RunResidual>,
    pub structure: Structure,
}

pub(crate) fn prepare_free(
    free: &Dataset,
    model: &Arc<dyn AeroModel>,
    opts: &SystemOptions,
) -> Result<Prepared> {
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
        .map(|r| {
            let hw = (opts.sg_half_window_s / r.dt).round().max(2.0) as usize;
            let s = ResidualSettings {
                half_window: hw,
                order: opts.sg_order.min(2 * hw),
                warmup: opts.warmup,
                pad: opts.pad,
            };
            residual::prepare_run(name, r, model, rho, &structure, &s)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Prepared { runs, structure })
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
    let (id, law, cases) = sim_identification(forced, opts)?;
    let model: Arc<dyn AeroModel> = Arc::new(law.model().clone());
    let chord = forced.manifest.section.chord;
    let jack = jackknife_identifications(&cases, &forced.manifest.name, opts);
    let jack_energy = |law_opts: &IdentifiedOptions| {
        jack.as_ref()
            .and_then(|ids| model_energy(ids, law_opts, free, opts))
    };
    let linear_energy = jack_energy(&IdentifiedOptions::new(chord));
    let (mut level, p) = level_and_runs(&model, free, opts, linear_energy.as_deref())?;
    let range = coverage::ForcedRange::new(&id, forced, chord);
    let before: Vec<f64> = level.cases.iter().map(|c| c.before).collect();
    // each run's null level: its noise and the sim's own uncertainty along it
    let null: Vec<f64> = level
        .cases
        .iter()
        .enumerate()
        .map(|(j, c)| {
            let m = linear_energy.as_ref().map_or(0.0, |e| comb(e[j]));
            c.noise_level.hypot(m)
        })
        .collect();
    let mut cov = coverage::assess(&range, &p.runs, &before, &null);
    cov.linear_before = level.before;
    cov.linear_gap_statistic = level.gap_statistic;
    if cov.any_outside() {
        let tails_opts = IdentifiedOptions {
            extrapolation: aeroelastic::identified::Extrapolation::Theodorsen,
            ..IdentifiedOptions::new(chord)
        };
        // a failure here only leaves the tails unreported
        if let Ok(tails) = IdentifiedLaw::from_identification(&id, &tails_opts) {
            let tm: Arc<dyn AeroModel> = Arc::new(tails.model().clone());
            let tails_energy = jack_energy(&tails_opts);
            if let Ok((tl, _)) = level_and_runs(&tm, free, opts, tails_energy.as_deref()) {
                if tl.before.is_finite() {
                    cov.tails_before = Some(tl.before);
                    cov.tails_shrink = Some(crate::verdict::plain_shrink(level.before, tl.before));
                    if tl.before < level.before {
                        // the physically consistent extrapolation is the better sim: its
                        // remaining gap is what the candidates are asked to explain
                        level = tl;
                        cov.sim_tables = "theodorsen_tails".into();
                    }
                }
            }
        }
    }
    cov.decide(level.gap_threshold, null_level(&level));
    level.coverage = Some(cov);
    Ok(level)
}

/// Mean over runs of per-DOF energies.
fn mean2(v: &[[f64; 2]]) -> [f64; 2] {
    let mut m = [0.0; 2];
    for e in v {
        m[0] += e[0] / v.len() as f64;
        m[1] += e[1] / v.len() as f64;
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

/// Held-out scoring of one candidate: per-run held-out energies after, the variant and
/// coefficients fitted on all runs.
struct Scored {
    effect: Effect,
    after_runs: Vec<[f64; 2]>,
    variant: usize,
    theta: Vec<f64>,
    failure: Option<String>,
}

fn score_candidate(
    effect: Effect,
    runs: &[RunResidual],
    folds: &[usize],
    rho: f64,
    chord: f64,
) -> Scored {
    let vars = candidates::variants(effect, runs, rho, chord);
    let n = runs.len();
    let n_folds = folds.iter().max().map_or(0, |m| m + 1);
    let mut after_runs: Vec<[f64; 2]> = runs.iter().map(|r| r.energy()).collect();
    let mut failure = None;
    for k in 0..n_folds {
        let train: Vec<usize> = (0..n).filter(|&j| folds[j] != k).collect();
        match candidates::fit(&vars, &train) {
            Some((v, theta, _)) => {
                for j in (0..n).filter(|&j| folds[j] == k) {
                    after_runs[j] = candidates::energy_after(&vars[v].moments[j], &theta);
                }
            }
            None => failure = Some(format!("singular least-squares fit in fold {k}")),
        }
    }
    let all: Vec<usize> = (0..n).collect();
    let (variant, theta) = match candidates::fit(&vars, &all) {
        Some((v, t, _)) => (v, t),
        None => {
            failure.get_or_insert_with(|| "singular least-squares fit".into());
            (0, vec![0.0; vars.first().map_or(0, |v| v.names.len())])
        }
    };
    let _ = &vars[variant.min(vars.len().saturating_sub(1))];
    Scored {
        effect,
        after_runs,
        variant,
        theta,
        failure,
    }
}

/// The system level for a given sim aerodynamic model (the identified law, or any
/// [`AeroModel`], e.g. a truth model in tests).
///
/// **Gap.** Per run and DOF the normalised energy mean((r_c/norm_c)²); the level's gap
/// is sqrt of the mean over runs and DOFs (the two channels weigh equally). Every run is
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
    level_and_runs(model, free, opts, None).map(|(level, _)| level)
}

/// The gap test's null level of a level: sqrt(noise_level² + model_level²).
pub fn null_level(level: &LevelResult) -> f64 {
    level.noise_level.hypot(level.model_level.unwrap_or(0.0))
}

/// [`system_level_with_model`] and the prepared runs it scored.
/// `model_energy`: the sim's own uncertainty per run and DOF ([`model_energy`]), added to
/// the noise in the gap test's null.
fn level_and_runs(
    model: &Arc<dyn AeroModel>,
    free: &Dataset,
    opts: &SystemOptions,
    model_energy: Option<&[[f64; 2]]>,
) -> Result<(LevelResult, Prepared)> {
    opts.check()?;
    let p = prepare_free(free, model, opts)?;
    let runs = &p.runs;
    let n = runs.len();
    let rho = free.manifest.section.air_density;
    let chord = model.chord();
    let folds = fold_of(n, opts.folds, opts.seed);
    let before_runs: Vec<[f64; 2]> = runs.iter().map(|r| r.energy()).collect();
    let noise_runs: Vec<[f64; 2]> = runs.iter().map(|r| r.noise_energy).collect();
    let e_before = mean2(&before_runs);
    let e_noise = mean2(&noise_runs);
    let before = comb(e_before);
    let noise_level = comb(e_noise);
    let model_level = model_energy
        .filter(|e| e.len() == n)
        .map(|e| comb(mean2(e)));
    let gap_statistic = before
        / noise_level
            .hypot(model_level.unwrap_or(0.0))
            .max(f64::MIN_POSITIVE);
    let significant_gap = gap_statistic > opts.gap_ratio;

    let mut scored: Vec<(CandidateScore, Scored)> = candidates::CANDIDATES
        .iter()
        .map(|&effect| {
            let sc = score_candidate(effect, runs, &folds, rho, chord);
            let after = comb(mean2(&sc.after_runs));
            let eb = before * before;
            let ea = after * after;
            let en = noise_level * noise_level;
            let statistic = if en > 0.0 { (eb - ea) / en } else { 0.0 };
            let n_params = candidates::n_params(effect);
            let threshold = opts.min_gain + opts.gain_per_param * n_params as f64;
            let vars_grid = candidates::variants_grid(effect, runs);
            let mut parameters: Vec<(String, f64)> =
                vars_grid.get(sc.variant).cloned().unwrap_or_default();
            parameters.extend(
                candidates::coefficient_names(effect)
                    .into_iter()
                    .zip(sc.theta.iter().copied()),
            );
            let cs = CandidateScore {
                effect,
                level: Level::Structural,
                before,
                after,
                shrink: if before > 0.0 {
                    1.0 - after / before
                } else {
                    0.0
                },
                n_params,
                statistic,
                threshold,
                significant: significant_gap && statistic > threshold && sc.failure.is_none(),
                score: threshold - statistic,
                parameters,
                failure: sc.failure.clone(),
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
    let best_cols = best.map(|(_, s)| {
        let grid = candidates::variants_grid(s.effect, runs)
            .get(s.variant)
            .cloned()
            .unwrap_or_default();
        (s.effect, grid, s.theta.clone())
    });
    let where_ = analysis::where_shares(runs, &noise_runs);
    let spectra = analysis::spectra(runs, best_cols.as_ref(), rho, chord);
    let signatures = simulate::signatures(runs, gap_statistic, opts.gap_ratio);
    let (observables, bifurcation) = if opts.simulate {
        let aug = best_cols.as_ref().map(|(e, g, t)| simulate::Augment {
            effect: *e,
            grid: g.iter().map(|x| x.1).collect(),
            theta: t.clone(),
        });
        let sim = simulate::compare(model, rho, &p.structure, runs, aug.as_ref());
        (sim.observables, Some(sim.bifurcation))
    } else {
        (vec![], None)
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
                (still > 0).then(|| {
                    format!("{still} still-air run(s) (U = 0): residual without aerodynamic force")
                })
            },
        }),
        coverage: None,
    };
    Ok((level, p))
}
