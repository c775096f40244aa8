//! Issue 42 item 5: the foreign generator's structural misses, reproduced with the
//! project's own generator (`benchmark::blind`): the default blind scenario (plate rig,
//! Theodorsen truth) with a still-air decay among the free runs.
//!
//! (d) A hardening pitch cubic and the given pitch frequency 5 % too high: named
//! `freeplay` (0.400) at round 29 (a dead band wider than the runs is a linear stiffness
//! loss: the only candidate that could take the given k_α's error). Round 30: the
//! still-air decays' linear frequencies are read against the given structure with the flat
//! plate's apparent mass, and where they differ every structural candidate and its
//! baseline fit a pooled linear stiffness correction (docs/DECISIONS.md, round 30).
//!
//! (a) A sharp Coulomb friction in pitch (the generator's smoothing T_c/(10 I_α ω_α),
//! about 1e-3 rad/s) on free runs outside the forced range: named `friction`, as the
//! issue wanted (the foreign generator's `freeplay` was not reproduced).
//!
//! (b) Amplitude-dependent pitch damping c_α(1 + dα²)α̇ on free runs outside the forced
//! range: called `extrapolation` although `structural_damping` is significant there.
//! **Open**: the test is ignored and fails. Cause (round 35): the extrapolation nuisance
//! takes the law's error in phase with the motion (apparent mass) but not in quadrature
//! (aerodynamic damping), which the damping candidate then shares; an aerodynamic-damping
//! column U q̇ per outside DOF in both equations makes it pass but moves
//! `structure_first.rs`'s polynomial form choice past its one-standard-error edge, so it
//! was not kept (docs/DECISIONS.md, round 35).

use aeroelastic::effects::Form;
use benchmark::blind::{generate, BlindEffect, BlindScenario};
use diagnose::pipeline::{diagnose, DiagnoseOptions};
use diagnose::report::Diagnosis;
use diagnose::{Effect, Verdict};

/// The default blind scenario with a still-air decay first; with `uncovered` its forced
/// campaign is configurations A, B, D (1–2 Hz pitch) at 8.5–11.5 m/s only, so that the
/// free runs' reduced frequencies lie above the forced range.
fn scenario(uncovered: bool) -> BlindScenario {
    let mut sc = BlindScenario::default();
    sc.free_speed_factors.insert(0, 0.0);
    if uncovered {
        sc.campaign.configurations = aeroelastic::tunnel::reconstructed_configurations();
        sc.campaign
            .configurations
            .retain(|c| ["A", "B", "D"].contains(&c.name.as_str()));
        sc.campaign.wind_speeds = vec![8.5, 10.0, 11.5];
    }
    sc
}

/// Number of free runs outside the forced range (system level's coverage).
fn uncovered_runs(d: &Diagnosis) -> usize {
    d.levels
        .last()
        .and_then(|l| l.coverage.as_ref())
        .map_or(0, |c| c.runs.iter().filter(|r| !r.covered).count())
}

/// Prints what the system level saw (verdict, structure, the best candidates).
fn show(label: &str, d: &Diagnosis) {
    let sys = d.levels.last().unwrap();
    eprintln!(
        "{label}: verdict {:?} {:.3}; {} run(s) uncovered; system gap {:.4} (statistic \
         {:.2}); {}",
        d.verdict.effect,
        d.verdict.confidence,
        uncovered_runs(d),
        sys.before,
        sys.gap_statistic,
        d.verdict.reason
    );
    if let Some(s) = &sys.structure {
        eprintln!("  structure: {}\n  reason: {}", s.summary, s.reason);
    }
    for c in sys.candidates.iter().take(4) {
        eprintln!(
            "  {} before {:.4} after {:.4} stat {:.2} thr {:.2} sig {} {:?}",
            c.effect.name(),
            c.before,
            c.after,
            c.statistic,
            c.threshold,
            c.significant,
            c.parameters
        );
    }
}

fn diagnose_set(effect: Effect, strength: f64, seed: u64, uncovered: bool) -> Diagnosis {
    let set = generate(
        BlindEffect::Catalogue(effect),
        strength,
        Form::Primary,
        seed,
        &scenario(uncovered),
    )
    .unwrap();
    let d = diagnose(
        &set.forced,
        Some(&set.free),
        &DiagnoseOptions::new(seed),
        "test",
    )
    .unwrap();
    show(
        &format!(
            "{} {:?} (uncovered campaign: {uncovered})",
            effect.name(),
            set.truth.parameters
        ),
        &d,
    );
    d
}

/// (d), about 30 s: seed 5, strength 0.8 (k₃ ≈ 169 N m/rad³). Round 30: right structure
/// `structural_cubic` (0.674), f_α given 5 % high `structural_cubic` (0.703, was
/// `freeplay` 0.400).
#[test]
fn a_hardening_pitch_cubic_is_named_when_the_given_pitch_frequency_is_5_percent_high() {
    let seed = 5;
    let set = generate(
        BlindEffect::Catalogue(Effect::StructuralCubic),
        0.8,
        Form::Primary,
        seed,
        &scenario(false),
    )
    .unwrap();
    let mut verdicts = Vec::new();
    for f in [1.0, 1.05] {
        let mut free = set.free.clone();
        if let Some(s) = free.manifest.structure.as_mut() {
            s.freq_pitch *= f;
        }
        let d = diagnose(
            &set.forced,
            Some(&free),
            &DiagnoseOptions::new(seed),
            "test",
        )
        .unwrap();
        show(&format!("f_alpha × {f}"), &d);
        let sys = d.levels.last().unwrap();
        let s = sys.structure.as_ref().expect("a still-air decay is read");
        let id = s
            .identified
            .as_ref()
            .expect("the linear structure identified");
        let pitch = id
            .modes
            .iter()
            .max_by(|a, b| a.given_hz.total_cmp(&b.given_hz))
            .unwrap();
        if f > 1.0 {
            // the decays tell the wrong pitch frequency apart: far beyond 2 σ
            assert!(pitch.frequency_z < -10.0, "{}", s.reason);
        }
        verdicts.push(d.verdict.effect);
    }
    let cubic = Verdict::Effect(Effect::StructuralCubic);
    assert_eq!(verdicts[0], cubic, "right structure");
    assert_eq!(verdicts[1], cubic, "pitch frequency given 5 % high");
}

/// (a), about 20 s: T_c ≈ 1.3e-3 N m/m (strength 0.85; the generator's smoothing about
/// 1e-3 rad/s), seed 5, every free run in the wind outside the forced range: `friction`.
#[test]
fn a_sharp_pitch_friction_on_uncovered_free_runs_is_named_friction() {
    let d = diagnose_set(Effect::Friction, 0.85, 5, true);
    assert!(
        uncovered_runs(&d) >= 5,
        "the free runs leave the forced range"
    );
    assert_eq!(d.verdict.effect, Verdict::Effect(Effect::Friction));
}

/// (b), open, about 20 s: d ≈ 2690 rad⁻² (strength 0.9, truth c₂ = c_α d = 3.43 N m
/// s/rad³), seed 5. With the default campaign `structural_damping` (0.924, c₂ 3.47); with
/// every free run in the wind outside the forced range `extrapolation` (0.998):
/// `structural_damping` is significant (c₂ 2.82, statistic 0.56 against 0.07) but its
/// excess shrink is 0.12 < 0.3 against a baseline that keeps the law's extrapolation error
/// in quadrature. With an aerodynamic-damping nuisance (round 35, not kept)
/// `structural_damping` 0.587, c₂ 3.20. Asserts both verdicts and c₂ within 15 % of the
/// truth's.
#[test]
#[ignore = "open (issue 42 item 5 b): fails; cause found, the fix moves structure_first (docs/DECISIONS.md round 35)"]
fn amplitude_dependent_pitch_damping_on_uncovered_free_runs_is_named() {
    let mut verdicts = Vec::new();
    for uncovered in [false, true] {
        let set = generate(
            BlindEffect::Catalogue(Effect::StructuralDamping),
            0.9,
            Form::Primary,
            5,
            &scenario(uncovered),
        )
        .unwrap();
        let d = diagnose(
            &set.forced,
            Some(&set.free),
            &DiagnoseOptions::new(5),
            "test",
        )
        .unwrap();
        show(
            &format!("structural_damping (uncovered campaign: {uncovered})"),
            &d,
        );
        if uncovered {
            assert!(
                uncovered_runs(&d) >= 5,
                "the free runs leave the forced range"
            );
        }
        // the truth's c₂ = c_α·d, the generator's pitch damping c_α times its d
        let c_alpha = set
            .free
            .manifest
            .structure
            .as_ref()
            .map(|s| {
                aeroelastic::structure::Structure::from_modal(s)
                    .unwrap()
                    .c_alpha
            })
            .unwrap();
        let truth = c_alpha * set.truth.parameters[0].1;
        let c2 = d
            .levels
            .last()
            .unwrap()
            .candidates
            .iter()
            .find(|c| c.effect == Effect::StructuralDamping)
            .and_then(|c| c.parameters.iter().find(|p| p.0 == "c2_pitch_Nms_per_rad3"))
            .map(|p| p.1)
            .unwrap();
        eprintln!("  c2 {c2:.3} against the truth's {truth:.3}");
        assert!((c2 / truth - 1.0).abs() < 0.15, "c2 {c2} truth {truth}");
        verdicts.push(d.verdict.effect);
    }
    let damping = Verdict::Effect(Effect::StructuralDamping);
    assert_eq!(verdicts[0], damping, "default campaign");
    assert_eq!(verdicts[1], damping, "free runs outside the forced range");
}
