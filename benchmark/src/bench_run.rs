//! Running the withheld-effect benchmark: generate, diagnose without the label, compare.

use std::time::Instant;

use aeroelastic::effects::Form;
use rayon::prelude::*;

use crate::bench::FollowUpOutcome;
use crate::bench::{draw_specs, summarize, BlindOutcome, BlindReport, BlindSpec};
use crate::blind::{follow_up_forced, generate, BlindEffect, BlindScenario};
use crate::{Error, Result};
use diagnose::effect::Verdict;
use diagnose::pipeline::{diagnose, DiagnoseOptions};
use diagnose::report::Diagnosis;

/// Settings of a benchmark run.
#[derive(Debug, Clone)]
pub struct BlindOptions {
    /// Number of data sets.
    pub n: usize,
    /// Master seed (labels, strengths, each set's seed); recorded in the report.
    pub seed: u64,
    /// Functional form of the injected effects.
    pub form: Form,
    /// Scenario of every set.
    pub scenario: BlindScenario,
    /// Diagnosis settings (their seed is replaced by each set's seed).
    pub diagnose: DiagnoseOptions,
    /// Draw each set's campaign shape ([`crate::bench::CampaignShape`]); `form` and the
    /// scenario's campaign and noise then come from the shape.
    pub shapes: bool,
    /// Close the loop of every `extrapolation`: run the recommended forced tests
    /// ([`diagnose::follow_up::plan`]) on the truth and diagnose the set again
    /// ([`BlindOutcome::follow_up`]).
    pub follow_up: bool,
}

impl BlindOptions {
    /// `n` sets from `seed`, primary forms, default scenario and diagnosis, without the
    /// free-response re-simulation (its observables and bifurcation diagram are not used
    /// by the verdict; it costs about as much as the rest of the system level).
    pub fn new(n: usize, seed: u64) -> Self {
        let mut diagnose = DiagnoseOptions::new(seed);
        diagnose.system.simulate = false;
        BlindOptions {
            n,
            seed,
            form: Form::Primary,
            scenario: BlindScenario::default(),
            diagnose,
            shapes: false,
            follow_up: false,
        }
    }
}

/// Ratio of each level's held-out gap in `diag` to the same level's gap in `twin`; the
/// larger one.
pub fn gap_ratio(diag: &Diagnosis, twin: &Diagnosis) -> f64 {
    diag.levels
        .iter()
        .filter_map(|l| {
            let t = twin.levels.iter().find(|t| t.level == l.level)?;
            (t.before > 0.0).then(|| l.before / t.before)
        })
        .fold(f64::NAN, f64::max)
}

/// Generates and diagnoses one set (and its effect-free twin for the gap ratio).
///
/// # Errors
/// Generation or diagnosis errors of the set or its twin.
pub fn run_one(spec: &BlindSpec, opts: &BlindOptions) -> Result<(BlindOutcome, Diagnosis)> {
    let t = Instant::now();
    let effect = spec.truth;
    let true_effect = match effect {
        BlindEffect::Catalogue(e) => Some(e),
        _ => None,
    };
    let mut dopts = opts.diagnose.clone();
    dopts.seed = spec.seed;
    dopts.force.seed = spec.seed;
    dopts.system.seed = spec.seed;
    let (form, scenario) = match &spec.shape {
        Some(shape) => (shape.form(), shape.scenario(&opts.scenario)?),
        None => (opts.form, opts.scenario.clone()),
    };
    let set = generate(effect, spec.strength, form, spec.seed, &scenario)?;
    let diag = diagnose(&set.forced, Some(&set.free), &dopts, "blind")?;
    // Baseline gaps only: no candidates are needed for the twin.
    let mut topts = dopts.clone();
    topts.force.candidates.clear();
    let (ratio, twin) = if effect == BlindEffect::None {
        (1.0, None)
    } else {
        let twin = generate(BlindEffect::None, 0.0, form, spec.seed, &scenario)?;
        let twin_diag = diagnose(&twin.forced, Some(&twin.free), &topts, "blind twin")?;
        (gap_ratio(&diag, &twin_diag), Some(twin))
    };
    let true_candidate_shrink = diag
        .candidates
        .iter()
        .filter(|c| Some(c.effect) == true_effect && c.failure.is_none())
        .map(|c| diagnose::verdict::plain_shrink(c.before, c.after))
        .fold(None, |a: Option<f64>, s| Some(a.map_or(s, |a| a.max(s))));
    let outcome = BlindOutcome {
        spec: spec.clone(),
        verdict: Some(diag.verdict.effect),
        confidence: diag.verdict.confidence,
        gap_ratio: ratio,
        shrink: diag.gap.shrink,
        excess_shrink: diag.gap.excess_shrink,
        true_candidate_shrink,
        parameters: set.truth.parameters.clone(),
        error: None,
        seconds: t.elapsed().as_secs_f64(),
        uncovered_runs: diag
            .levels
            .iter()
            .find_map(|l| l.coverage.as_ref())
            .map(|c| c.runs.iter().filter(|r| !r.covered).count()),
        follow_up: None,
    };
    let mut outcome = outcome;
    if opts.follow_up && diag.verdict.effect == Verdict::Extrapolation {
        if let Some(plan) = &diag.follow_up {
            let cases = plan.cases();
            let forced = follow_up_forced(
                effect,
                spec.strength,
                form,
                spec.seed,
                &scenario,
                &set.forced,
                &cases,
            )?;
            let again = diagnose(&forced, Some(&set.free), &dopts, "blind follow-up")?;
            // the twin gets the same tests: the effect's own gap once the runs are covered
            let gap_ratio = match &twin {
                None => 1.0,
                Some(twin) => {
                    let tf = follow_up_forced(
                        BlindEffect::None,
                        0.0,
                        form,
                        spec.seed,
                        &scenario,
                        &twin.forced,
                        &cases,
                    )?;
                    let td = diagnose(&tf, Some(&twin.free), &topts, "blind twin follow-up")?;
                    self::gap_ratio(&again, &td)
                }
            };
            outcome.follow_up = Some(FollowUpOutcome {
                cases: cases.len(),
                rows: plan.rows.len(),
                verdict: again.verdict.effect,
                confidence: again.verdict.confidence,
                gap_ratio,
                uncovered_runs: uncovered(&again),
            });
        }
        outcome.seconds = t.elapsed().as_secs_f64();
    }
    Ok((outcome, diag))
}

fn uncovered(d: &Diagnosis) -> Option<usize> {
    d.levels
        .iter()
        .find_map(|l| l.coverage.as_ref())
        .map(|c| c.runs.iter().filter(|r| !r.covered).count())
}

/// [`run_one`] with a failure recorded in the outcome (verdict `error`, the message in
/// `error`) instead of returned: what the benchmark keeps for each set.
pub fn run_outcome(spec: &BlindSpec, opts: &BlindOptions) -> BlindOutcome {
    let t = Instant::now();
    match run_one(spec, opts) {
        Ok((o, _)) => o,
        Err(e) => failed(spec, &e, t.elapsed().as_secs_f64()),
    }
}

/// The `n` sets of the withheld-effect benchmark with master seed `seed` (set i's seed and
/// strength depend on the seed and i alone; the truths are dealt over the n sets): the
/// default benchmark's ([`draw_specs`]) or, with `shapes`, the drawn-shapes benchmark's
/// truths, each set with its drawn campaign shape and physics
/// ([`crate::bench::CampaignShape::draw_with_physics`]).
pub fn blind_specs(n: usize, seed: u64, shapes: bool) -> Vec<BlindSpec> {
    if !shapes {
        return draw_specs(n, seed);
    }
    let mut specs = crate::bench::draw_specs_from(n, seed, &crate::bench::shapes_truths());
    for s in &mut specs {
        s.shape = Some(crate::bench::CampaignShape::draw_with_physics(s.seed));
    }
    specs
}

/// Runs the benchmark: `opts.n` sets drawn by [`blind_specs`], in parallel; a set that fails
/// to generate or diagnose is recorded with its error (and counted as failed), never
/// dropped. `observer` is called after each set.
pub fn run_blind(opts: &BlindOptions, observer: &(dyn Fn(&BlindOutcome) + Sync)) -> BlindReport {
    let specs = blind_specs(opts.n, opts.seed, opts.shapes);
    let outcomes: Vec<BlindOutcome> = specs
        .par_iter()
        .map(|s| {
            let o = run_outcome(s, opts);
            observer(&o);
            o
        })
        .collect();
    summarize(opts.seed, outcomes)
}

/// The outcome of a set that failed to generate or diagnose: no verdict, `error` set, its
/// gap ratio and shrinks NaN (written `null`).
pub(crate) fn failed(spec: &BlindSpec, e: &Error, seconds: f64) -> BlindOutcome {
    BlindOutcome {
        spec: spec.clone(),
        verdict: None,
        confidence: 0.0,
        gap_ratio: f64::NAN,
        shrink: f64::NAN,
        excess_shrink: f64::NAN,
        true_candidate_shrink: None,
        parameters: vec![],
        error: Some(e.to_string()),
        seconds,
        uncovered_runs: None,
        follow_up: None,
    }
}
