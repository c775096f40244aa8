//! Coverage as a cause (issue 10): free runs whose response leaves the K range of the forced
//! cases. The blind generator's default scenario with the forced wind speeds cut to
//! 7–10 m/s: the forced K_α then stops at ≈ 0.67 while the free runs at 4.6–7.6 m/s respond
//! at K ≈ 0.56–1.1, so the sim's tables are extrapolated for most runs.

use aeroelastic::effects::Form;
use benchmark::blind::{generate, BlindEffect, BlindScenario, BlindSet};
use diagnose::pipeline::{diagnose, DiagnoseOptions};
use diagnose::report::Diagnosis;
use diagnose::{Effect, Verdict};

fn high_speed_campaign() -> BlindScenario {
    let mut s = BlindScenario::default();
    s.campaign.wind_speeds = vec![7.0, 8.5, 10.0];
    s
}

fn run(set: &BlindSet) -> Diagnosis {
    diagnose(
        &set.forced,
        Some(&set.free),
        &DiagnoseOptions::new(1),
        "test",
    )
    .unwrap()
}

fn describe(d: &Diagnosis) -> String {
    let sys = d.levels.last().unwrap();
    let cov = sys.coverage.as_ref().unwrap();
    let runs: Vec<String> = cov
        .runs
        .iter()
        .map(|r| {
            format!(
                "{} U={:.2} K_h={:?} K_α={:?} A={:.1}° gap={:.4} {}",
                r.id,
                r.wind_speed,
                r.k_h.map(|k| (k * 1000.0).round() / 1000.0),
                r.k_alpha.map(|k| (k * 1000.0).round() / 1000.0),
                r.amplitude_alpha_deg,
                r.before,
                r.outside.join("; ")
            )
        })
        .collect();
    format!(
        "verdict {} ({}); force stat {:.2}; system gap {:.4} noise {:.4} stat {:.2}; K_h {:?} \
         K_α {:?}; share {:.2}, covered stat {:?}, tails {:?} shrink {:?}\n{}",
        d.verdict.effect,
        d.verdict.reason,
        d.levels[0].gap_statistic,
        sys.before,
        sys.noise_level,
        sys.gap_statistic,
        cov.k_h_range,
        cov.k_alpha_range,
        cov.extrapolated_share,
        cov.covered_gap_statistic,
        cov.tails_before,
        cov.tails_shrink,
        runs.join("\n")
    )
}

/// The default campaign: every free run's K_α inside the forced range; runs flagged
/// outside are exactly those beyond a range (K_h of the forced heave stops at 0.67 while a
/// coupled response carries heave at its pitch frequency); the verdict stays `none`.
#[test]
fn the_default_campaign_flags_exactly_the_runs_beyond_a_range() {
    let set = generate(
        BlindEffect::None,
        0.0,
        Form::Primary,
        3,
        &BlindScenario::default(),
    )
    .unwrap();
    let d = run(&set);
    let msg = describe(&d);
    let cov = d.levels.last().unwrap().coverage.as_ref().unwrap();
    let widen = 1.0 + cov.margin;
    for r in &cov.runs {
        let beyond = r.k_h.is_some_and(|k| k > cov.k_h_range[1] * widen)
            || r.k_alpha.is_some_and(|k| k > cov.k_alpha_range[1] * widen)
            || r.k_alpha.is_some_and(|k| k < cov.k_alpha_range[0] / widen);
        assert_eq!(r.covered, !beyond, "{}: {msg}", r.id);
        assert!(
            r.k_alpha.is_some_and(|k| k <= cov.k_alpha_range[1] * widen),
            "{msg}"
        );
    }
    assert_eq!(d.verdict.effect, Verdict::None, "{msg}");
}

/// Effect-free data from a campaign that stops short of the free runs' K: the runs outside
/// are reported with their K, the forced cases that would cover them are suggested, and the
/// verdict is `none` or `extrapolation`, never an effect or `unexplained`.
#[test]
fn an_effect_free_set_beyond_the_forced_range_is_never_an_effect() {
    let scenario = high_speed_campaign();
    for seed in [3, 4] {
        let set = generate(BlindEffect::None, 0.0, Form::Primary, seed, &scenario).unwrap();
        let d = run(&set);
        let msg = describe(&d);
        eprintln!("seed {seed}: {msg}");
        let cov = d.levels.last().unwrap().coverage.as_ref().unwrap();
        let outside: Vec<_> = cov.runs.iter().filter(|r| !r.covered).collect();
        assert!(outside.len() >= 2, "{msg}");
        for r in &outside {
            assert!(
                r.k_alpha.is_some_and(|k| k > cov.k_alpha_range[1])
                    || r.k_h.is_some_and(|k| k > cov.k_h_range[1])
                    || r.amplitude_alpha_deg > cov.amplitude_alpha_deg_range[1],
                "{msg}"
            );
            // each is covered by a suggested forced case at a lower wind speed
            let s: Vec<_> = cov.suggestions.iter().filter(|s| s.run == r.id).collect();
            assert!(!s.is_empty() || r.k_alpha.is_none(), "{msg}");
            for s in s {
                assert!(s.wind_speed < 7.0 && s.wind_speed > 0.0, "{msg}");
            }
        }
        assert!(
            matches!(d.verdict.effect, Verdict::None | Verdict::Extrapolation),
            "{msg}"
        );
    }
}

/// A strong catalogue effect in the same campaign is still named: the covered runs carry it.
#[test]
fn a_strong_effect_beyond_the_forced_range_is_still_named() {
    let scenario = high_speed_campaign();
    let set = generate(
        BlindEffect::Catalogue(Effect::Friction),
        0.9,
        Form::Primary,
        3,
        &scenario,
    )
    .unwrap();
    let d = run(&set);
    assert_eq!(
        d.verdict.effect,
        Verdict::Effect(Effect::Friction),
        "{}",
        describe(&d)
    );
}

/// Issue 42 item 4, the closed loop on the same campaign: an effect-free set whose free runs
/// lie beyond the forced range is `extrapolation`; the diagnosis recommends forced tests
/// (`Diagnosis::follow_up`, a plan `tunnel forced --campaign-file` reads), each uncovered
/// run named in a row; run on the truth and appended to the forced set, they cover every
/// run that was outside, and the set is diagnosed again as effect-free (`none`).
#[test]
fn the_recommended_forced_tests_cover_the_runs_and_settle_an_effect_free_set() {
    let scenario = high_speed_campaign();
    let seed = 3;
    let set = generate(BlindEffect::None, 0.0, Form::Primary, seed, &scenario).unwrap();
    let d = run(&set);
    let msg = describe(&d);
    assert_eq!(d.verdict.effect, Verdict::Extrapolation, "{msg}");
    let plan = d.follow_up.clone().expect("a follow-up plan");
    let text = plan.to_toml().unwrap();
    let back = aeroelastic::tunnel::CampaignPlan::parse(&text, "follow_up.campaign.toml").unwrap();
    assert_eq!(back, plan);
    let cov = d.levels.last().unwrap().coverage.clone().unwrap();
    for r in cov
        .runs
        .iter()
        .filter(|r| !r.covered && r.k_alpha.is_some())
    {
        assert!(
            plan.rows.iter().any(|row| row.covers.contains(&r.id)),
            "run {} not in the plan:\n{text}",
            r.id
        );
    }
    // ranks are 1..n; the coverage rows carry two amplitudes at least; every row says the
    // record length it assumes (the campaign's own)
    for (i, r) in plan.rows.iter().enumerate() {
        assert_eq!(r.rank, i + 1);
        if !r.covers.is_empty() {
            assert!(r.amplitudes_deg.len() >= 2, "{text}");
        }
        assert_eq!(
            r.record_duration_s,
            Some(scenario.forced_duration),
            "{text}"
        );
    }
    // with no effect, no force-level candidate to settle: no repeated row
    assert!(plan.rows.iter().all(|r| r.repeats.is_none()), "{text}");
    let cases = plan.cases();
    let forced = benchmark::blind::follow_up_forced(
        BlindEffect::None,
        0.0,
        Form::Primary,
        seed,
        &scenario,
        &set.forced,
        &cases,
    )
    .unwrap();
    assert_eq!(forced.records.len(), set.forced.records.len() + cases.len());
    // the set's own records are kept as they were
    assert_eq!(forced.records[0], set.forced.records[0]);
    let again = diagnose(&forced, Some(&set.free), &DiagnoseOptions::new(1), "test").unwrap();
    let msg2 = describe(&again);
    let cov2 = again.levels.last().unwrap().coverage.as_ref().unwrap();
    for r in cov
        .runs
        .iter()
        .filter(|r| !r.covered && r.k_alpha.is_some())
    {
        let r2 = cov2.runs.iter().find(|x| x.id == r.id).unwrap();
        assert!(
            r2.outside.iter().all(|o| !o.starts_with("K_α")),
            "{} still outside in K_α after the follow-up:\n{msg2}",
            r.id
        );
    }
    assert_eq!(again.verdict.effect, Verdict::None, "{msg}\n---\n{msg2}");
}
