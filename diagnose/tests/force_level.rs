//! Force level of the diagnosis on blind forced campaigns from the real generator
//! (`diagnose::blind::generate`, base scenario: configurations D and G, pitch amplitudes
//! 6–24°, U = 4–10 m/s, 512 Hz, 8 s, paper noise). Only the forced records are used; the
//! generator's forms differ from the candidates' forms in `diagnose::force`.

use diagnose::blind::{generate, BlindEffect, BlindScenario};
use diagnose::force::{force_level, ForceOptions};
use diagnose::{Effect, LevelResult};
use aeroelastic::effects::Form;
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
