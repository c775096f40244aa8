//! System level on blind data sets (`benchmark::blind::generate` on the default scenario:
//! forced configurations D and G × 4 amplitudes × 5 speeds, free runs at 0.7–1.15 U_F,
//! 12 s, α₀ = 4°, paper noise). The test data come from the blind generator only; the
//! system level never sees the truth.

use aeroelastic::effects::Form;
use benchmark::blind::{generate, BlindEffect, BlindScenario, BlindSet};
use diagnose::report::LevelResult;
use diagnose::system::{system_level, SystemOptions};
use diagnose::Effect;

fn set(effect: BlindEffect, strength: f64, form: Form, seed: u64) -> BlindSet {
    generate(effect, strength, form, seed, &BlindScenario::default()).unwrap()
}

fn opts() -> SystemOptions {
    let mut o = SystemOptions::default();
    o.warmup = env_or("SYS_WARMUP", o.warmup);
    o
}

fn run(s: &BlindSet) -> LevelResult {
    system_level(&s.forced, &s.free, &opts()).unwrap()
}

/// Excess shrink of the level's best candidate (the verdict rule's measure).
fn best_excess_shrink(r: &LevelResult) -> f64 {
    diagnose::verdict::excess_shrink(r.before, r.candidates[0].after, r.noise_level)
}

/// Asserts that `effect`'s candidate ranks first, is significant, and removes at least
/// half of the gap's excess over noise (what the verdict needs to name it).
fn assert_named(effect: Effect, strength: f64, form: Form, seed: u64) {
    let b = set(BlindEffect::Catalogue(effect), strength, form, seed);
    let r = run(&b);
    let c = &r.candidates[0];
    let xs = best_excess_shrink(&r);
    let msg = format!(
        "{} s={strength} {form:?}: gap {:.4} noise {:.4} (stat {:.2}); best {} stat {:.2} sig {} \
         excess shrink {xs:.2}; second {} stat {:.2}",
        effect.name(),
        r.before,
        r.noise_level,
        r.gap_statistic,
        c.effect.name(),
        c.statistic,
        c.significant,
        r.candidates[1].effect.name(),
        r.candidates[1].statistic
    );
    assert!(r.significant_gap, "{msg}");
    assert_eq!(c.effect, effect, "{msg}");
    assert!(c.significant, "{msg}");
    assert!(xs >= 0.5, "{msg}");
}

/// Effect-free data: the held-out gap is at the noise level (statistic 1.03–1.09 over
/// 20 seeds, see `calibration_effect_free`), not significant, no candidate significant,
/// and the observables and signatures are filled in.
#[test]
fn effect_free_gap_is_at_noise_level_and_not_significant() {
    let b = set(BlindEffect::None, 0.0, Form::Primary, 3);
    let r = run(&b);
    assert!(!r.significant_gap, "stat {}", r.gap_statistic);
    // The floor is sensor noise: the gap exceeds the noise level by less than 15 %.
    assert!(
        r.gap_statistic > 0.9 && r.gap_statistic < 1.15,
        "stat {}",
        r.gap_statistic
    );
    assert!(r.candidates.iter().all(|c| !c.significant));
    assert_eq!(r.candidates.len(), 8); // six of DESIGN §5 + structural_polynomial, structural_damping
    assert_eq!(r.cases.len(), 6);
    for s in &r.signatures {
        assert!(
            !s.detected,
            "signature {} fired on effect-free data: {}",
            s.name, s.detail
        );
    }
    let bif = r.bifurcation.as_ref().expect("simulate is on by default");
    assert_eq!(bif.measured.len(), 6);
    // The sim reproduces the measured limit cycles above flutter within 10 %.
    for (m, p) in bif.measured.iter().zip(&bif.predicted_before) {
        if m.amplitude > 1.0 {
            assert!(
                (p.amplitude / m.amplitude - 1.0).abs() < 0.1,
                "{m:?} vs {p:?}"
            );
        }
    }
    let sh: f64 = r
        .where_
        .iter()
        .filter(|w| w.split == diagnose::report::Split::Channel)
        .map(|w| w.share)
        .sum();
    assert!((sh - 1.0).abs() < 1e-9);
}

/// Structural cubic spring (primary form, s = 0.8: κ = 0.5·400^0.8).
#[test]
fn structural_cubic_is_named() {
    assert_named(Effect::StructuralCubic, 0.8, Form::Primary, 1);
}

/// Freeplay (primary form, half gap 0.158° = 0.001°·1000^0.733: the generator's range is
/// 0.001°–1°).
#[test]
fn freeplay_is_named_and_its_simulation_reproduces_the_lco() {
    let b = set(
        BlindEffect::Catalogue(Effect::Freeplay),
        0.733,
        Form::Primary,
        2,
    );
    let r = run(&b);
    assert_eq!(r.candidates[0].effect, Effect::Freeplay);
    assert!(r.candidates[0].significant && best_excess_shrink(&r) >= 0.5);
    // Final amplitude gap (sim − measured, rms over runs) shrinks with the augmentation.
    let o = r
        .observables
        .iter()
        .find(|o| o.name == "final pitch amplitude")
        .unwrap();
    assert!(o.before > 0.5 && o.after < 0.2 * o.before, "{o:?}");
}

/// Coulomb friction (primary form, s = 1: the gap reaches 3× the effect-free gap only
/// near s ≈ 0.95).
#[test]
fn friction_is_named() {
    assert_named(Effect::Friction, 1.0, Form::Primary, 3);
}

/// Spurious added mass in the forced records only (primary form, s = 0.8).
#[test]
fn added_mass_is_named() {
    assert_named(Effect::AddedMass, 0.8, Form::Primary, 4);
}

/// Static offset (primary form, s = 0.6); the mean-shift signature fires.
#[test]
fn static_offset_is_named() {
    assert_named(Effect::StaticOffset, 0.6, Form::Primary, 5);
}

/// Time delay (in forced and free records). Known failure at the system level: the law
/// identified from delayed forced records is itself distorted (a stiffness/mass-like
/// pitch-moment error of up to 2× the structural moment), which `added_mass` fits
/// better than a delay of the sim's force; the force level names the delay at s ≥ 0.3.
#[test]
#[ignore]
fn time_delay_is_named() {
    assert_named(Effect::TimeDelay, 0.8, Form::Primary, 6);
}

/// Alternate forms of the structural effects (quintic-plus-cubic spring, smoothed
/// freeplay, Stribeck friction) are named by the same generic candidates.
#[test]
fn alternate_structural_forms_are_named() {
    assert_named(Effect::StructuralCubic, 0.8, Form::Alternate, 7);
    assert_named(Effect::Freeplay, 0.6, Form::Alternate, 8);
    assert_named(Effect::Friction, 1.0, Form::Alternate, 9);
}

/// Calibration (release: `cargo test --release -p diagnose --test system_level
/// calibration -- --ignored --nocapture`): effect-free gap statistic over 20 seeds and the
/// false-alarm rate of the gap test.
#[test]
#[ignore]
fn calibration_effect_free() {
    let mut stats = Vec::new();
    let mut alarms = 0;
    for seed in 100..120 {
        let r = run(&set(BlindEffect::None, 0.0, Form::Primary, seed));
        stats.push(r.gap_statistic);
        alarms += r.significant_gap as usize;
        assert!(r
            .candidates
            .iter()
            .all(|c| !c.significant || r.significant_gap));
    }
    let mx = stats.iter().fold(0.0_f64, |m, v| m.max(*v));
    let mn = stats.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    eprintln!("effect-free gap/noise over 20 seeds: {mn:.3}–{mx:.3}; false alarms {alarms}/20");
    assert!(alarms <= 1, "{alarms} false alarms");
}

/// Calibration: per effect and strength, gap/effect-free gap, rank of the true
/// candidate, its significance and excess shrink (the weak end of the benchmark).
#[test]
#[ignore]
fn calibration_weak_end() {
    let floor = run(&set(BlindEffect::None, 0.0, Form::Primary, 0)).before;
    for e in [
        Effect::StructuralCubic,
        Effect::Freeplay,
        Effect::Friction,
        Effect::AddedMass,
        Effect::TimeDelay,
        Effect::StaticOffset,
    ] {
        for s in [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0] {
            let r = run(&set(BlindEffect::Catalogue(e), s, Form::Primary, 0));
            let rank = r.candidates.iter().position(|c| c.effect == e).unwrap() + 1;
            let c = &r.candidates[rank - 1];
            eprintln!(
                "{:>16} s={s:.1}: gap/floor {:6.2} significant {} | true candidate rank {rank} sig {} \
                 excess shrink {:.2} | best {}",
                e.name(),
                r.before / floor,
                r.significant_gap,
                c.significant,
                diagnose::verdict::excess_shrink(r.before, c.after, r.noise_level),
                r.candidates[0].effect.name()
            );
        }
    }
}

/// Timing of the whole system level per set, with and without the simulations
/// (release build).
#[test]
#[ignore]
fn timing_per_set() {
    let b = set(BlindEffect::None, 0.0, Form::Primary, 0);
    for simulate in [false, true] {
        let mut o = opts();
        o.simulate = simulate;
        let t = std::time::Instant::now();
        for _ in 0..5 {
            system_level(&b.forced, &b.free, &o).unwrap();
        }
        eprintln!(
            "simulate {simulate}: {:.3} s per set",
            t.elapsed().as_secs_f64() / 5.0
        );
    }
}

fn env_or<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

fn parse_effect(s: &str) -> BlindEffect {
    match s {
        "none" => BlindEffect::None,
        "buffeting" => BlindEffect::Buffeting,
        n => BlindEffect::Catalogue(Effect::ALL.into_iter().find(|e| e.name() == n).unwrap()),
    }
}

/// Exploration: `SYS_EFFECTS=none,freeplay SYS_STRENGTHS=0.6 SYS_SEEDS=3 SYS_FORM=alt
/// SYS_VERBOSE=1 cargo test --release -p diagnose --test system_level explore -- --ignored
/// --nocapture`.
#[test]
#[ignore]
fn explore() {
    let effects: String = env_or("SYS_EFFECTS", "none".to_string());
    let strengths: String = env_or("SYS_STRENGTHS", "0.6".to_string());
    let seeds: u64 = env_or("SYS_SEEDS", 3);
    let seed0: u64 = env_or("SYS_SEED0", 0);
    let verbose: u32 = env_or("SYS_VERBOSE", 0);
    let form = if env_or("SYS_FORM", "primary".to_string()) == "alt" {
        Form::Alternate
    } else {
        Form::Primary
    };
    for e in effects.split(',') {
        let effect = parse_effect(e);
        for s in strengths.split(',') {
            let s: f64 = s.parse().unwrap();
            for seed in seed0..seed0 + seeds {
                let t = std::time::Instant::now();
                let b = set(effect, s, form, seed);
                let tg = t.elapsed().as_secs_f64();
                let t = std::time::Instant::now();
                let r = run(&b);
                let td = t.elapsed().as_secs_f64();
                let c = &r.candidates[0];
                let xs = diagnose::verdict::excess_shrink(r.before, c.after, r.noise_level);
                eprintln!(
                    "{e} s={s} seed={seed}: gen {tg:.2}s sys {td:.2}s before {:.4} noise {:.4} \
                     stat {:.2} sig {} | best {} stat {:.3} thr {:.3} sig {} xshrink {:.2} | 2nd {} {:.3}",
                    r.before,
                    r.noise_level,
                    r.gap_statistic,
                    r.significant_gap,
                    c.effect.name(),
                    c.statistic,
                    c.threshold,
                    c.significant,
                    xs,
                    r.candidates[1].effect.name(),
                    r.candidates[1].statistic,
                );
                if verbose > 1 {
                    for o in &r.observables {
                        eprintln!(
                            "   obs {} [{}] before {:.4} after {:.4}",
                            o.name, o.unit, o.before, o.after
                        );
                    }
                    for g in &r.signatures {
                        eprintln!(
                            "   sig {} {:.3} > {:.3}: {}",
                            g.name, g.statistic, g.threshold, g.detected
                        );
                    }
                    if let Some(b) = &r.bifurcation {
                        for (k, m) in b.measured.iter().enumerate() {
                            eprintln!(
                                "   bif U {:.2} meas {:.3}° {:.3} Hz | before {:?} | after {:?}",
                                m.wind_speed,
                                m.amplitude,
                                m.frequency,
                                b.predicted_before
                                    .get(k)
                                    .map(|p| (p.amplitude, p.frequency)),
                                b.predicted_after.get(k).map(|p| (p.amplitude, p.frequency))
                            );
                        }
                    }
                }
                if verbose > 0 {
                    for c in &r.candidates {
                        eprintln!(
                            "   {:>16} after {:.4} stat {:.3} thr {:.3} sig {} {:?}",
                            c.effect.name(),
                            c.after,
                            c.statistic,
                            c.threshold,
                            c.significant,
                            c.parameters
                        );
                    }
                    for c in &r.cases {
                        eprintln!(
                            "   case {} U {:.2} amp {:.2} before {:.4} after {:.4} noise {:.4}",
                            c.id, c.wind_speed, c.amplitude, c.before, c.after, c.noise_level
                        );
                    }
                }
            }
        }
    }
}

/// Exploration with the truth aerodynamics as the sim (separates residual-method error
/// from identification error).
#[test]
#[ignore]
fn explore_truth_model() {
    use aeroelastic::files::LoadedModel;
    let sc = BlindScenario::default();
    let m = LoadedModel::parse(&sc.truth_model, "truth", std::path::Path::new("."), None)
        .unwrap()
        .model;
    let seeds: u64 = env_or("SYS_SEEDS", 1);
    for seed in 0..seeds {
        let b = set(BlindEffect::None, 0.0, Form::Primary, seed);
        let r = diagnose::system::system_level_with_model(&m, &b.free, &opts()).unwrap();
        eprintln!(
            "truth model seed {seed}: before {:.4} noise {:.4}",
            r.before, r.noise_level
        );
        for c in &r.cases {
            eprintln!(
                "   case {} U {:.2} amp {:.2} before {:.4} noise {:.4}",
                c.id, c.wind_speed, c.amplitude, c.before, c.noise_level
            );
        }
        for c in &r.candidates {
            eprintln!(
                "   {:>16} after {:.4} {:?}",
                c.effect.name(),
                c.after,
                c.parameters
            );
        }
    }
}

/// Exploration: residual rms per 1 s segment of each run, identified law vs truth.
#[test]
#[ignore]
fn explore_segments() {
    use aeroelastic::files::LoadedModel;
    use aeroelastic::structure::{Nonlinearities, StructureSpec};
    use diagnose::system::residual::{prepare_run, ResidualSettings};
    use diagnose::system::sim_law;
    use std::sync::Arc;
    let sc = BlindScenario::default();
    let truth = LoadedModel::parse(&sc.truth_model, "truth", std::path::Path::new("."), None)
        .unwrap()
        .model;
    let b = set(
        parse_effect(&env_or("SYS_EFFECTS", "none".to_string())),
        env_or("SYS_STRENGTHS", 0.6),
        Form::Primary,
        0,
    );
    let o = opts();
    let law = sim_law(&b.forced, &o).unwrap();
    let ident: Arc<dyn aeroelastic::aero::AeroModel> = Arc::new(law.model().clone());
    let st = StructureSpec::Modal {
        linear: b.free.manifest.structure.unwrap(),
        nonlinear: Nonlinearities::none(),
    }
    .resolve()
    .unwrap();
    let s = ResidualSettings {
        half_window: 26,
        order: 4,
        warmup: o.warmup,
        pad: o.pad,
    };
    for rec in &b.free.records {
        for (name, m) in [("truth", &truth), ("ident", &ident)] {
            let r = prepare_run("x", rec, m, b.free.manifest.section.air_density, &st, &s).unwrap();
            let seg = 512;
            let mut line = format!("{} {name} K {:.2} f {:.2}:", r.id, r.k, r.freq);
            for k in (0..r.len()).step_by(seg) {
                let e = (k + seg).min(r.len());
                let rr = |c: usize| {
                    (r.r[c][k..e].iter().map(|v| v * v).sum::<f64>() / (e - k) as f64).sqrt()
                        / r.norm[c]
                };
                let amp = r.q[1][r.i0 + k..r.i0 + e]
                    .iter()
                    .fold(0.0_f64, |m, v| m.max(v.abs()))
                    .to_degrees();
                line += &format!(" [{amp:.2}° h{:.3} a{:.3}]", rr(0), rr(1));
            }
            eprintln!("{line}");
        }
    }
}

/// Exploration: the first seconds of run 1 of a set against its effect-free twin.
#[test]
#[ignore]
fn explore_twin_start() {
    let e = parse_effect(&env_or("SYS_EFFECTS", "time_delay".to_string()));
    let b = set(e, env_or("SYS_STRENGTHS", 0.6), Form::Primary, 0);
    let t = set(BlindEffect::None, 0.0, Form::Primary, 0);
    let (r, r0) = (&b.free.records[0], &t.free.records[0]);
    for i in (0..1024).step_by(16) {
        eprintln!(
            "t {:.3} alpha {:+.5} twin {:+.5} diff {:+.6} h {:+.6} twin {:+.6}",
            i as f64 * r.dt,
            r.alpha[i].to_degrees(),
            r0.alpha[i].to_degrees(),
            (r.alpha[i] - r0.alpha[i]).to_degrees(),
            r.h[i],
            r0.h[i]
        );
    }
}

/// Exploration: the whole pipeline's force level on a set (which level decides).
#[test]
#[ignore]
fn explore_force_level() {
    let e = parse_effect(&env_or("SYS_EFFECTS", "time_delay".to_string()));
    for s in env_or("SYS_STRENGTHS", "0.6".to_string()).split(',') {
        let b = set(e, s.parse().unwrap(), Form::Primary, 0);
        let f = diagnose::force::force_level(&b.forced, &Default::default()).unwrap();
        eprintln!(
            "{} s={s}: force before {:.4} noise {:.4} stat {:.2} sig {} best {} sig {}",
            e.name(),
            f.before,
            f.noise_level,
            f.gap_statistic,
            f.significant_gap,
            f.candidates[0].effect.name(),
            f.candidates[0].significant
        );
    }
}

/// Exploration: cost of the parts (identification vs the rest).
#[test]
#[ignore]
fn explore_timing() {
    let b = set(BlindEffect::None, 0.0, Form::Primary, 0);
    let o = opts();
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let law = diagnose::system::sim_law(&b.forced, &o).unwrap();
        let ti = t.elapsed().as_secs_f64();
        let m: std::sync::Arc<dyn aeroelastic::aero::AeroModel> =
            std::sync::Arc::new(law.model().clone());
        let t = std::time::Instant::now();
        let _ = diagnose::system::system_level_with_model(&m, &b.free, &o).unwrap();
        eprintln!("identify {ti:.3}s rest {:.3}s", t.elapsed().as_secs_f64());
    }
}

/// Exploration: the whole pipeline's verdict on a set.
#[test]
#[ignore]
fn explore_pipeline() {
    let e = parse_effect(&env_or("SYS_EFFECTS", "freeplay".to_string()));
    for s in env_or("SYS_STRENGTHS", "0.6".to_string()).split(',') {
        let b = set(e, s.parse().unwrap(), Form::Primary, 0);
        let d = diagnose::pipeline::diagnose(
            &b.forced,
            Some(&b.free),
            &diagnose::pipeline::DiagnoseOptions::new(0),
            "test",
        )
        .unwrap();
        eprintln!("{} s={s}: verdict {:?}", e.name(), d.verdict);
        for l in &d.levels {
            eprintln!(
                "   level {:?} stat {:.2} thr {:.2} sig {}",
                l.level, l.gap_statistic, l.gap_threshold, l.significant_gap
            );
        }
    }
}
