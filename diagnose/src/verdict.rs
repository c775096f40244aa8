//! From the two levels' findings to one verdict (DESIGN.md §5.3).
//!
//! Rule, in order:
//! 1. **Force level first.** When the held-out force gap is significant, the verdict is the
//!    best force-level candidate if it is significant and removes at least
//!    [`VerdictRules::min_excess_shrink`] of the gap's excess over noise; otherwise
//!    `unexplained`. A force-level gap that no aerodynamic candidate removes is not handed
//!    to the free-response level: structural effects cannot leave forced-motion residuals,
//!    so naming one would force a name on a gap no candidate explains.
//!    Exception: a gap that the held-out cases interpolating in K do not show and that no
//!    candidate removes is the law's extrapolation to the held-out wind speeds (the law of
//!    every case covers them), and the force level counts as clean.
//! 2. **System level.** With a clean force level, a significant free-response gap is named
//!    by the best system-level candidate under the same rule, else `unexplained`.
//!    Before any candidate is named, a gap that lies where the sim is extrapolated is
//!    `extrapolation` ([`crate::report::Coverage::explains_gap`]: the free runs outside
//!    the forced K/amplitude range carry most of it and the covered runs are clean). A gap
//!    no candidate removes while no free run is covered at all is `extrapolation` too.
//! 3. Otherwise `none`.
//!
//! Shrink is reported two ways. `shrink` = 1 − after/before (DATA_FORMAT.md), whose best
//! value is 1 − noise/before because sensor noise cannot be explained; the rule uses the
//! *excess* shrink 1 − e_after/e_before with e = sqrt(max(gap² − noise², 0)), which is 1
//! when a candidate leaves only noise.

use crate::effect::{Effect, Level, Verdict};
use crate::report::{
    CandidateScore, Channel, Diagnosis, GapReport, Harmonic, LevelResult, Split, VerdictReport,
    WhereShare, FORMAT,
};

/// Thresholds of the verdict rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerdictRules {
    /// Least excess shrink for a candidate to name the gap (default 0.3: the candidate
    /// removes at least 30 % of the excess residual amplitude above noise on held-out data,
    /// i.e. 51 % of its excess energy). Buffeting, which no candidate models, stays below
    /// 0.03; a strong stall set is named at 0.41 (force2 calibration).
    pub min_excess_shrink: f64,
}

impl Default for VerdictRules {
    fn default() -> Self {
        VerdictRules {
            min_excess_shrink: 0.3,
        }
    }
}

use crate::stats::paired_within_one_se;
pub use crate::stats::{excess, excess_shrink, plain_shrink};

/// "before is x× its noise level n" for a reason sentence; with the sim's own uncertainty
/// ([`LevelResult::model_level`]) the null level sqrt(noise² + model²) and both parts.
fn against_null(level: &LevelResult) -> String {
    match level.model_level {
        Some(m) => {
            let null = crate::system::null_level(level);
            format!(
                "{:.1}× its null level {null:.4} (noise {:.4}, the law's own uncertainty {m:.4})",
                level.before / null.max(f64::MIN_POSITIVE),
                level.noise_level
            )
        }
        None => format!(
            "{:.1}× its noise level {:.4}",
            level.before / level.noise_level.max(f64::MIN_POSITIVE),
            level.noise_level
        ),
    }
}

/// What decided the verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    /// The verdict.
    pub verdict: Verdict,
    /// Confidence in [0, 1].
    pub confidence: f64,
    /// Why, in one sentence.
    pub reason: String,
    /// Index into the levels of the level that decided (None for `none`).
    pub level: Option<usize>,
    /// Index of the winning candidate in that level's list.
    pub candidate: Option<usize>,
}

/// Whether the simpler candidate `a`'s per-run held-out energies are within one standard
/// error (paired over the held-out units) of the richer `b`'s.
fn within_one_se(a: &CandidateScore, b: &CandidateScore) -> bool {
    if a.held_out_runs.len() != b.held_out_runs.len() || a.held_out_runs.is_empty() {
        return false;
    }
    let d: Vec<f64> = a
        .held_out_runs
        .iter()
        .zip(&b.held_out_runs)
        .map(|(x, y)| x - y)
        .collect();
    paired_within_one_se(&d, 0.0)
}

/// The best candidate of a level that is significant (only those scored beyond the
/// coverage, [`Effect::scored_beyond_coverage`], when `beyond_coverage_only`), with its excess shrink against its own baseline
/// ([`CandidateScore::before`]). A simpler nested candidate ([`Effect::extends`]) within one
/// standard error of the best is taken instead (the one-standard-error rule).
fn best_candidate(
    level: &LevelResult,
    beyond_coverage_only: bool,
) -> Option<(usize, &CandidateScore, f64)> {
    let ok = |c: &CandidateScore| {
        c.significant
            && c.failure.is_none()
            && c.after.is_finite()
            && (!beyond_coverage_only || c.effect.scored_beyond_coverage())
    };
    let with_shrink = |i: usize| {
        let c = &level.candidates[i];
        (i, c, excess_shrink(c.before, c.after, level.noise_level))
    };
    let best = level
        .candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| ok(c))
        .map(|(i, _)| with_shrink(i))
        .max_by(|a, b| {
            // lower score is better; ties by larger shrink
            b.1.score
                .partial_cmp(&a.1.score)
                .unwrap_or(std::cmp::Ordering::Equal)
                .then(a.2.partial_cmp(&b.2).unwrap_or(std::cmp::Ordering::Equal))
        })?;
    if let Some(simple) = best.1.effect.extends() {
        if let Some(i) = level
            .candidates
            .iter()
            .position(|c| c.effect == simple && ok(c) && within_one_se(c, best.1))
        {
            return Some(with_shrink(i));
        }
    }
    Some(best)
}

/// Confidence of naming `best`: its excess shrink, reduced by how much of the same
/// improvement the runner-up achieves (1 − Δ₂/Δ₁ with Δ = before − after; a candidate
/// nested with `best` is not its runner-up).
fn effect_confidence(level: &LevelResult, best_idx: usize, shrink: f64) -> f64 {
    let b = &level.candidates[best_idx];
    let nested = |e: Effect| e.extends() == Some(b.effect) || b.effect.extends() == Some(e);
    let d1 = b.before - b.after;
    let d2 = level
        .candidates
        .iter()
        .enumerate()
        .filter(|(i, c)| {
            *i != best_idx && c.failure.is_none() && c.after.is_finite() && !nested(c.effect)
        })
        .map(|(_, c)| c.before - c.after)
        .fold(0.0_f64, f64::max);
    let margin = if d1 > 0.0 {
        (1.0 - d2.max(0.0) / d1).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (shrink.clamp(0.0, 1.0) * (0.5 + 0.5 * margin)).clamp(0.0, 1.0)
}

/// The decision naming candidate `ci` of level `li`.
fn named(level: &LevelResult, li: usize, ci: usize, c: &CandidateScore, shrink: f64) -> Decision {
    let own = if (c.before - level.before).abs() > 5e-3 * level.before.abs() {
        format!(" ({:.4} on the candidate's own baseline)", c.before)
    } else {
        String::new()
    };
    Decision {
        verdict: Verdict::Effect(c.effect),
        confidence: effect_confidence(level, ci, shrink),
        reason: format!(
            "{} held-out gap {:.4} is {}; adding `{}` brings it to {:.4}{own} (excess \
             shrink {:.0} %)",
            level.level.name(),
            level.before,
            against_null(level),
            c.effect,
            c.after,
            100.0 * shrink
        ),
        level: Some(li),
        candidate: Some(ci),
    }
}

/// Decides one level with a significant gap.
fn decide_level(levels: &[LevelResult], li: usize, rules: &VerdictRules) -> Decision {
    let level = &levels[li];
    if let Some(cov) = &level.coverage {
        let tails = cov
            .tails_before
            .map(|t| excess_shrink(cov.linear_before, t, level.noise_level));
        // a candidate scored on every run (structural, static offset) significant beyond
        // the runs' extrapolation nuisance is evidence the extrapolation cannot produce:
        // it is named even so
        let structural =
            best_candidate(level, true).filter(|(_, _, shrink)| *shrink >= rules.min_excess_shrink);
        if let (true, Some((ci, c, shrink))) = (cov.explains_gap, structural) {
            return named(level, li, ci, c, shrink);
        }
        if cov.explains_gap {
            let outside: Vec<&str> = cov
                .runs
                .iter()
                .filter(|r| !r.covered)
                .map(|r| r.id.as_str())
                .collect();
            let covered = match cov.covered_gap_statistic {
                Some(s) if s > level.gap_threshold => format!(
                    "the covered runs alone are at {s:.2}× their null level (threshold {:.2}) \
                     but carry only {:.1} % of the excess, and no candidate scored on them \
                     removes it",
                    level.gap_threshold,
                    100.0 * (1.0 - cov.extrapolated_share)
                ),
                Some(s) => format!(
                    "the covered runs alone are at {s:.2}× their null level (threshold {:.2})",
                    level.gap_threshold
                ),
                None => "no run is covered".to_string(),
            };
            let mass = match (cov.tails_apparent_mass, cov.plate_apparent_mass) {
                (Some(m), Some(p)) => {
                    format!("; their apparent heave mass {m:.4} kg/m against πρb² {p:.4}")
                }
                _ => String::new(),
            };
            let tail = match (cov.tails_before, tails) {
                (Some(t), Some(x)) => format!(
                    "; Theodorsen-shaped tails instead of straight lines give {t:.4} (excess \
                     shrink {:.0} %){mass}",
                    100.0 * x
                ),
                _ => String::new(),
            };
            return Decision {
                verdict: Verdict::Extrapolation,
                confidence: cov.extrapolated_share.clamp(0.0, 1.0),
                reason: format!(
                    "{} held-out gap {:.4} is {:.1}× its {} {:.4}, {:.0} % of its \
                     excess in {} run(s) outside the forced K/amplitude range ({}); {covered}{tail}",
                    level.level.name(),
                    cov.linear_before,
                    cov.linear_gap_statistic,
                    if level.model_level.is_some() { "null level" } else { "noise level" },
                    crate::system::null_level(level),
                    100.0 * cov.extrapolated_share,
                    outside.len(),
                    outside.join(", "),
                ),
                level: Some(li),
                candidate: None,
            };
        }
    }
    match best_candidate(level, false) {
        Some((ci, c, shrink)) if shrink >= rules.min_excess_shrink => {
            named(level, li, ci, c, shrink)
        }
        best => {
            let (what, shrink) = match best {
                Some((_, c, s)) => (format!("the best candidate `{}`", c.effect), s),
                None => ("no candidate significantly".to_string(), 0.0),
            };
            // No run inside the forced range: the gap cannot be told from the model's
            // extrapolation, so it is not claimed as an unmodelled effect.
            let uncovered = level.coverage.as_ref().filter(|c| {
                c.covered_gap_statistic.is_none()
                    && c.any_outside()
                    && c.extrapolated_share >= crate::system::coverage::MIN_SHARE
            });
            let (verdict, confidence, tail) = match uncovered {
                Some(cov) => (
                    Verdict::Extrapolation,
                    cov.extrapolated_share.clamp(0.0, 1.0),
                    ", all of it in runs outside the forced K/amplitude range (no run is \
                     covered): extrapolation, not a named effect",
                ),
                None => (
                    Verdict::Unexplained,
                    (1.0 - shrink.max(0.0)).clamp(0.0, 1.0),
                    "",
                ),
            };
            Decision {
                verdict,
                confidence,
                reason: format!(
                    "{} held-out gap {:.4} is {}, and {what} removes only {:.0} % of its \
                     excess{tail}",
                    level.level.name(),
                    level.before,
                    against_null(level),
                    100.0 * shrink.max(0.0)
                ),
                level: Some(li),
                candidate: None,
            }
        }
    }
}

/// Whether a significant force-level gap is only the law's extrapolation to held-out wind
/// speeds: the held-out cases that interpolate in K show no significant gap
/// ([`LevelResult::interpolated_gap_statistic`]) and no candidate removes
/// [`VerdictRules::min_excess_shrink`] of it. Such a level counts as clean: every case is
/// covered by the law identified on all of them.
fn cross_validation_extrapolation(level: &LevelResult, rules: &VerdictRules) -> bool {
    level
        .interpolated_gap_statistic
        .is_some_and(|x| x <= level.gap_threshold)
        && best_candidate(level, false)
            .is_none_or(|(_, _, shrink)| shrink < rules.min_excess_shrink)
}

/// Decides the verdict from the levels (force level first, then system level; see the
/// module docs).
pub fn decide(levels: &[LevelResult], rules: &VerdictRules) -> Decision {
    let order = [Level::Aerodynamic, Level::Structural];
    for want in order {
        if let Some(li) = levels.iter().position(|l| {
            l.level == want
                && (l.significant_gap || l.coverage.as_ref().is_some_and(|c| c.explains_gap))
                && !cross_validation_extrapolation(l, rules)
        }) {
            return decide_level(levels, li, rules);
        }
    }
    // Confidence of `none`: how far below its threshold the most critical gap test is.
    let worst = levels
        .iter()
        .map(|l| {
            if l.gap_threshold > 0.0 {
                l.gap_statistic / l.gap_threshold
            } else {
                0.0
            }
        })
        .fold(0.0_f64, f64::max);
    Decision {
        verdict: Verdict::None,
        confidence: (1.0 - worst).clamp(0.0, 1.0),
        reason: format!(
            "no level has a held-out gap significantly above its noise level (largest \
             statistic/threshold {worst:.2})"
        ),
        level: None,
        candidate: None,
    }
}

/// The `level` split of the where-table: each level's share of the total excess, the
/// excess measured in units of its own noise level (e² / noise²), so that levels with
/// different metrics are comparable.
pub fn level_shares(levels: &[LevelResult]) -> Vec<WhereShare> {
    let e: Vec<f64> = levels
        .iter()
        .map(|l| {
            let n = l.noise_level.max(f64::MIN_POSITIVE);
            (excess(l.before, l.noise_level) / n).powi(2)
        })
        .collect();
    let total: f64 = e.iter().sum();
    levels
        .iter()
        .zip(&e)
        .map(|(l, &ei)| WhereShare {
            split: Split::Level,
            level: l.level,
            channel: Channel::All,
            harmonic: Harmonic::All,
            wind_speed: speed_range(l),
            amplitude: amplitude_range(l),
            config: None,
            state: None,
            share: if total > 0.0 {
                ei / total
            } else {
                1.0 / levels.len() as f64
            },
        })
        .collect()
}

fn speed_range(l: &LevelResult) -> [f64; 2] {
    range(l.cases.iter().map(|c| c.wind_speed))
}

fn amplitude_range(l: &LevelResult) -> [f64; 2] {
    range(l.cases.iter().map(|c| c.amplitude))
}

fn range(v: impl Iterator<Item = f64>) -> [f64; 2] {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if lo <= hi {
        [lo, hi]
    } else {
        [0.0, 0.0]
    }
}

/// Assembles the `diagnosis.json` document from the levels (force level first), the seed,
/// the version string and the input names.
pub fn assemble(
    mut levels: Vec<LevelResult>,
    rules: &VerdictRules,
    seed: u64,
    version: &str,
    inputs: Vec<String>,
) -> Diagnosis {
    // Normalise every candidate's plain shrink so that all levels report the same quantity.
    for l in &mut levels {
        for c in &mut l.candidates {
            c.shrink = plain_shrink(c.before, c.after);
        }
    }
    let d = decide(&levels, rules);
    let gap = match d.level {
        Some(li) if d.verdict == Verdict::Extrapolation && levels[li].coverage.is_some() => {
            // before: the sim with straight-line tables; after: with Theodorsen-shaped tails
            let l = &levels[li];
            let cov = l.coverage.as_ref().expect("checked");
            let after = cov.tails_before.unwrap_or(cov.linear_before);
            GapReport {
                metric: l.metric.clone(),
                before: cov.linear_before,
                after,
                shrink: plain_shrink(cov.linear_before, after),
                excess_shrink: excess_shrink(cov.linear_before, after, l.noise_level),
                noise_level: l.noise_level,
                held_out_cases: l.held_out_cases.clone(),
            }
        }
        Some(li) => {
            let l = &levels[li];
            let after = d
                .candidate
                .map(|ci| l.candidates[ci].after)
                .unwrap_or(l.before);
            GapReport {
                metric: l.metric.clone(),
                before: l.before,
                after,
                shrink: plain_shrink(l.before, after),
                excess_shrink: excess_shrink(l.before, after, l.noise_level),
                noise_level: l.noise_level,
                held_out_cases: l.held_out_cases.clone(),
            }
        }
        None => {
            let l = &levels[0];
            GapReport {
                metric: l.metric.clone(),
                before: l.before,
                after: l.before,
                shrink: 0.0,
                excess_shrink: 0.0,
                noise_level: l.noise_level,
                held_out_cases: l.held_out_cases.clone(),
            }
        }
    };
    let mut where_ = level_shares(&levels);
    where_.extend(levels.iter().flat_map(|l| l.where_.iter().cloned()));
    let mut candidates: Vec<CandidateScore> = levels
        .iter()
        .flat_map(|l| l.candidates.iter().cloned())
        .collect();
    // Best first overall: the deciding level's order first, then the others.
    if let Some(li) = d.level {
        let lvl = levels[li].level;
        candidates.sort_by_key(|c| c.level != lvl);
    }
    Diagnosis {
        format: FORMAT.into(),
        verdict: VerdictReport {
            effect: d.verdict,
            level: d.verdict.level(),
            confidence: d.confidence,
            reason: d.reason,
        },
        gap,
        where_,
        candidates,
        levels,
        seed,
        version: version.into(),
        inputs,
        follow_up: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effect::Effect;

    fn cand(
        effect: Effect,
        before: f64,
        after: f64,
        significant: bool,
        score: f64,
    ) -> CandidateScore {
        CandidateScore {
            effect,
            level: effect.level(),
            before,
            after,
            shrink: 0.0,
            n_params: 1,
            statistic: 0.0,
            threshold: 0.0,
            significant,
            score,
            parameters: vec![],
            failure: None,
            convention: None,
            note: None,
            held_out_runs: vec![],
        }
    }

    fn level(
        level: Level,
        before: f64,
        noise: f64,
        significant: bool,
        c: Vec<CandidateScore>,
    ) -> LevelResult {
        LevelResult {
            level,
            metric: "m".into(),
            before,
            noise_level: noise,
            significant_gap: significant,
            gap_statistic: if significant { 10.0 } else { 0.2 },
            gap_threshold: 1.0,
            held_out_cases: vec!["a".into()],
            candidates: c,
            where_: vec![],
            cases: vec![],
            spectra: vec![],
            signatures: vec![],
            observables: vec![],
            bifurcation: None,
            fold_scheme: None,
            coverage: None,
            structure: None,
            control: None,
            interpolated_gap_statistic: None,
            model_level: None,
        }
    }

    #[test]
    fn force_gap_named_by_its_best_candidate() {
        let f = level(
            Level::Aerodynamic,
            0.3,
            0.1,
            true,
            vec![
                cand(Effect::HigherOrder, 0.3, 0.2, true, 5.0),
                cand(Effect::DynamicStall, 0.3, 0.101, true, 1.0),
            ],
        );
        let d = decide(&[f], &VerdictRules::default());
        assert_eq!(d.verdict, Verdict::Effect(Effect::DynamicStall));
        assert!(
            d.confidence > 0.5 && d.confidence <= 1.0,
            "{}",
            d.confidence
        );
    }

    #[test]
    fn a_gap_no_candidate_removes_is_unexplained_not_structural() {
        let f = level(
            Level::Aerodynamic,
            0.3,
            0.1,
            true,
            vec![cand(Effect::VortexShedding, 0.3, 0.28, true, 1.0)],
        );
        let s = level(
            Level::Structural,
            0.5,
            0.1,
            true,
            vec![cand(Effect::Friction, 0.5, 0.1, true, 1.0)],
        );
        let d = decide(&[f, s], &VerdictRules::default());
        assert_eq!(d.verdict, Verdict::Unexplained);
    }

    /// A force-level gap that the held-out cases interpolating in K do not show, and that
    /// no candidate removes, is cross-validation extrapolation: the verdict comes from the
    /// free response. A candidate that removes it is still named at the force level.
    #[test]
    fn a_force_gap_only_at_extrapolated_wind_speeds_defers_to_the_free_response() {
        let f = |c: Vec<CandidateScore>, interpolated: Option<f64>| LevelResult {
            interpolated_gap_statistic: interpolated,
            model_level: None,
            ..level(Level::Aerodynamic, 0.2, 0.1, true, c)
        };
        let s = level(Level::Structural, 0.1, 0.1, false, vec![]);
        let weak = || vec![cand(Effect::HigherOrder, 0.2, 0.19, true, 1.0)];
        let d = decide(&[f(weak(), Some(0.5)), s.clone()], &VerdictRules::default());
        assert_eq!(d.verdict, Verdict::None, "{}", d.reason);
        // the interpolating cases show the gap too: unexplained as before
        let d = decide(&[f(weak(), Some(5.0)), s.clone()], &VerdictRules::default());
        assert_eq!(d.verdict, Verdict::Unexplained, "{}", d.reason);
        // no interpolating case at all: unexplained as before
        let d = decide(&[f(weak(), None), s.clone()], &VerdictRules::default());
        assert_eq!(d.verdict, Verdict::Unexplained, "{}", d.reason);
        // a candidate that removes the gap is named even so
        let strong = vec![cand(Effect::TimeDelay, 0.2, 0.11, true, 1.0)];
        let d = decide(&[f(strong, Some(0.5)), s], &VerdictRules::default());
        assert_eq!(
            d.verdict,
            Verdict::Effect(Effect::TimeDelay),
            "{}",
            d.reason
        );
    }

    /// With no free run inside the forced range, a free-response gap no candidate removes is
    /// the model's extrapolation, not an unmodelled effect; one covered run is enough to
    /// keep `unexplained`, and a candidate that removes the gap is still named.
    #[test]
    fn an_uncovered_gap_no_candidate_removes_is_extrapolation() {
        let f = level(Level::Aerodynamic, 0.1, 0.1, false, vec![]);
        let run = |id: &str, covered: bool| crate::report::RunCoverage {
            id: id.into(),
            wind_speed: 2.0,
            k_h: Some(0.9),
            k_alpha: Some(0.5),
            amplitude_alpha_deg: 2.0,
            amplitude_h_m: 0.001,
            covered,
            outside: if covered {
                vec![]
            } else {
                vec!["k_alpha".into()]
            },
            before: 0.5,
        };
        let coverage = |covered: Option<f64>, runs| crate::report::Coverage {
            k_h_range: [0.3, 0.8],
            k_alpha_range: [0.1, 0.3],
            amplitude_alpha_deg_range: [6.0, 24.0],
            margin: 0.1,
            runs,
            extrapolated_share: 1.0,
            covered_gap_statistic: covered,
            linear_before: 0.5,
            linear_gap_statistic: 5.0,
            tails_before: Some(0.9),
            tails_shrink: Some(-0.3),
            tail_weights: vec![],
            tails_apparent_mass: None,
            plate_apparent_mass: None,
            sim_tables: "linear".into(),
            explains_gap: false,
            suggestions: vec![],
        };
        let s = |cov, c: Vec<CandidateScore>| LevelResult {
            coverage: Some(cov),
            ..level(Level::Structural, 0.5, 0.1, true, c)
        };
        let weak = || vec![cand(Effect::Friction, 0.5, 0.45, true, 1.0)];
        let d = decide(
            &[
                f.clone(),
                s(coverage(None, vec![run("free-1", false)]), weak()),
            ],
            &VerdictRules::default(),
        );
        assert_eq!(d.verdict, Verdict::Extrapolation, "{}", d.reason);
        assert!(d.reason.contains("no run is covered"), "{}", d.reason);
        let d = decide(
            &[
                f.clone(),
                s(
                    coverage(Some(4.0), vec![run("free-1", false), run("free-2", true)]),
                    weak(),
                ),
            ],
            &VerdictRules::default(),
        );
        assert_eq!(d.verdict, Verdict::Unexplained, "{}", d.reason);
        let d = decide(
            &[
                f,
                s(
                    coverage(None, vec![run("free-1", false)]),
                    vec![cand(Effect::Freeplay, 0.5, 0.12, true, 1.0)],
                ),
            ],
            &VerdictRules::default(),
        );
        assert_eq!(d.verdict, Verdict::Effect(Effect::Freeplay), "{}", d.reason);
    }

    #[test]
    fn clean_force_level_defers_to_free_response() {
        let f = level(Level::Aerodynamic, 0.1, 0.1, false, vec![]);
        let s = level(
            Level::Structural,
            0.5,
            0.1,
            true,
            vec![
                cand(Effect::Freeplay, 0.5, 0.12, true, 2.0),
                cand(Effect::StructuralCubic, 0.5, 0.3, true, 3.0),
            ],
        );
        let diag = assemble(vec![f, s], &VerdictRules::default(), 7, "v", vec![]);
        assert_eq!(diag.verdict.effect, Verdict::Effect(Effect::Freeplay));
        assert_eq!(diag.verdict.level, Level::Structural);
        assert!((diag.gap.shrink - (1.0 - 0.12 / 0.5)).abs() < 1e-12);
        let shares: f64 = diag
            .where_
            .iter()
            .filter(|w| w.split == Split::Level)
            .map(|w| w.share)
            .sum();
        assert!((shares - 1.0).abs() < 1e-12);
    }

    #[test]
    fn quiet_levels_give_none() {
        let f = level(
            Level::Aerodynamic,
            0.1,
            0.1,
            false,
            vec![cand(Effect::HigherOrder, 0.1, 0.09, true, 1.0)],
        );
        let d = decide(&[f], &VerdictRules::default());
        assert_eq!(d.verdict, Verdict::None);
        assert!((d.confidence - 0.8).abs() < 1e-12);
    }

    #[test]
    fn excess_shrink_is_one_when_only_noise_remains() {
        assert!((excess_shrink(0.3, 0.1, 0.1) - 1.0).abs() < 1e-12);
        assert!((plain_shrink(0.3, 0.1) - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(excess_shrink(0.1, 0.05, 0.1), 0.0);
    }
}
