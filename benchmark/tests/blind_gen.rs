//! Blind data-set generator: each effect changes what it should and nothing else,
//! determinism, twins, write/read round trip, cost.

use aeroelastic::effects::Form;
use benchmark::blind::{effect_size, generate, write_blind, BlindEffect, BlindScenario, BlindSet};
use diagnose::Effect;

fn small() -> BlindScenario {
    // Same physics, shorter records (test speed); the default scenario is timed separately.
    BlindScenario {
        forced_duration: 4.0,
        free_duration: 8.0,
        ..BlindScenario::default()
    }
}

fn gen(e: BlindEffect, s: f64, form: Form, seed: u64, sc: &BlindScenario) -> BlindSet {
    generate(e, s, form, seed, sc).unwrap()
}

fn forced_equal(a: &BlindSet, b: &BlindSet) -> bool {
    a.forced.records == b.forced.records
}

fn free_equal(a: &BlindSet, b: &BlindSet) -> bool {
    a.free.records == b.free.records
}

/// Amplitude of a sinusoid of frequency f \[Hz\] in v (least squares on sin/cos).
fn line_amplitude(v: &[f64], dt: f64, f: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f;
    let (mut s, mut c) = (0.0, 0.0);
    for (i, x) in v.iter().enumerate() {
        let t = i as f64 * dt;
        s += x * (w * t).sin();
        c += x * (w * t).cos();
    }
    2.0 * (s * s + c * c).sqrt() / v.len() as f64
}

#[test]
fn same_seed_gives_identical_sets_and_strength_is_checked() {
    let sc = small();
    let a = gen(
        BlindEffect::Catalogue(Effect::DynamicStall),
        0.7,
        Form::Primary,
        11,
        &sc,
    );
    let b = gen(
        BlindEffect::Catalogue(Effect::DynamicStall),
        0.7,
        Form::Primary,
        11,
        &sc,
    );
    assert!(forced_equal(&a, &b) && free_equal(&a, &b));
    assert_eq!(a.truth, b.truth);
    let c = gen(
        BlindEffect::Catalogue(Effect::DynamicStall),
        0.7,
        Form::Primary,
        12,
        &sc,
    );
    assert!(!forced_equal(&a, &c));
    assert_eq!(a.forced.records.len(), 40);
    assert_eq!(a.free.records.len(), 6);
    assert!(generate(BlindEffect::None, 1.5, Form::Primary, 1, &sc).is_err());
}

#[test]
fn structural_effects_leave_forced_records_bit_identical_and_change_free_response() {
    let sc = small();
    let none = gen(BlindEffect::None, 0.0, Form::Primary, 5, &sc);
    for e in [Effect::StructuralCubic, Effect::Freeplay, Effect::Friction] {
        for form in [Form::Primary, Form::Alternate] {
            let s = gen(BlindEffect::Catalogue(e), 1.0, form, 5, &sc);
            assert!(
                forced_equal(&s, &none),
                "{e} {form:?} changed forced records"
            );
            let size = effect_size(&s, &none, &sc);
            assert!(
                size.free_alpha > 10.0 * size.free_noise,
                "{e} {form:?}: free change {} vs noise {}",
                size.free_alpha,
                size.free_noise
            );
        }
    }
}

#[test]
fn added_mass_leaves_free_records_identical_and_adds_acceleration_forces() {
    let sc = small();
    let none = gen(BlindEffect::None, 0.0, Form::Primary, 6, &sc);
    for form in [Form::Primary, Form::Alternate] {
        let s = gen(BlindEffect::Catalogue(Effect::AddedMass), 1.0, form, 6, &sc);
        assert!(free_equal(&s, &none));
        // The difference is ΔM q̈: at the pitch frequency only (and the heave one), ∝ q̈,
        // independent of U: same for two speeds of the same motion.
        let id = |u: &str| format!("D-U{u}-A24");
        let diff = |u: &str| -> Vec<f64> {
            let a = s.forced.record(&id(u)).unwrap().moment.as_ref().unwrap();
            let b = none.forced.record(&id(u)).unwrap().moment.as_ref().unwrap();
            a.iter().zip(b).map(|(x, y)| x - y).collect()
        };
        let (d4, d10) = (diff("4"), diff("10"));
        let (a4, a10) = (
            line_amplitude(&d4, 1.0 / 512.0, 2.0),
            line_amplitude(&d10, 1.0 / 512.0, 2.0),
        );
        assert!(a4 > 0.0 && (a4 - a10).abs() < 1e-9 * a4, "{a4} vs {a10}");
    }
}

#[test]
fn strength_zero_is_near_noise_and_strength_one_is_clearly_visible() {
    let sc = small();
    let none = gen(BlindEffect::None, 0.0, Form::Primary, 8, &sc);
    for e in Effect::generated()
        .into_iter()
        .map(BlindEffect::Catalogue)
        .chain([BlindEffect::Buffeting])
    {
        let lo = gen(e, 0.0, Form::Primary, 8, &sc);
        let hi = gen(e, 1.0, Form::Primary, 8, &sc);
        let (a, b) = (effect_size(&lo, &none, &sc), effect_size(&hi, &none, &sc));
        let structural = matches!(
            e,
            BlindEffect::Catalogue(Effect::StructuralCubic | Effect::Freeplay | Effect::Friction)
        );
        if structural {
            assert!(
                b.free_alpha_subcritical > 10.0 * b.free_noise,
                "{e:?}: {b:?}"
            );
            assert!(
                a.free_alpha_subcritical < b.free_alpha_subcritical / 10.0,
                "{e:?}: {a:?} vs {b:?}"
            );
        } else {
            let m0 = a.forced_lift.max(a.forced_moment);
            let m1 = b.forced_lift.max(b.forced_moment);
            assert!(m1 > 5.0 * b.forced_noise, "{e:?}: {b:?}");
            assert!(m0 < 2.0 * a.forced_noise, "{e:?}: {a:?}");
        }
    }
}

#[test]
fn shedding_adds_a_line_at_strouhal_frequency_moving_with_u() {
    let sc = small();
    let none = gen(BlindEffect::None, 0.0, Form::Primary, 9, &sc);
    let s = gen(
        BlindEffect::Catalogue(Effect::VortexShedding),
        1.0,
        Form::Primary,
        9,
        &sc,
    );
    for u in ["4", "7"] {
        let id = format!("D-U{u}-A12");
        let a = s.forced.record(&id).unwrap().lift.as_ref().unwrap();
        let b = none.forced.record(&id).unwrap().lift.as_ref().unwrap();
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        let uu: f64 = u.parse().unwrap();
        let fs = 0.12 * uu / sc.depth;
        // Energy within ±5 % of f_s versus far from it (periodogram by direct sums).
        let band = |f0: f64, f1: f64| -> f64 {
            let mut e = 0.0;
            let mut f = f0;
            while f < f1 {
                e += line_amplitude(&d, 1.0 / 512.0, f).powi(2);
                f += 0.25;
            }
            e
        };
        let near = band(0.95 * fs, 1.05 * fs);
        let far = band(1.5 * fs, 1.6 * fs) + band(0.5 * fs, 0.6 * fs);
        assert!(near > 50.0 * far, "U {u}: near {near} far {far}");
    }
}

#[test]
fn stall_changes_only_cases_above_the_critical_angle() {
    let sc = small();
    let none = gen(BlindEffect::None, 0.0, Form::Primary, 10, &sc);
    // s = 1: α_crit = 10°. Effective angle α + ḣ/U stays below 10° for the 6° cases at
    // U ≥ 7 m/s (ḣ/U ≤ 0.9 mm/deg·… < 1.5°), so those records are unchanged.
    let s = gen(
        BlindEffect::Catalogue(Effect::DynamicStall),
        1.0,
        Form::Primary,
        10,
        &sc,
    );
    for (rs, rn) in s.forced.records.iter().zip(&none.forced.records) {
        let a = rs.meta.amplitude.unwrap().to_degrees();
        let d = rs
            .moment
            .as_ref()
            .unwrap()
            .iter()
            .zip(rn.moment.as_ref().unwrap())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        let pk = rn
            .moment
            .as_ref()
            .unwrap()
            .iter()
            .fold(0.0_f64, |m, x| m.max(x.abs()));
        // Attached flow: only the RK4 error of a differently sub-stepped lag integration.
        if a < 7.0 && rs.meta.wind_speed >= 7.0 {
            assert!(d < 1e-7 * pk, "{}: {d} vs peak {pk}", rs.meta.id);
        }
        // Configuration D (2 Hz): the separation lag 1.5 B/U is short against the period.
        if a > 20.0 && rs.meta.config.as_deref() == Some("D") {
            assert!(d > 0.05 * pk, "{}: {d} vs peak {pk}", rs.meta.id);
        }
    }
}

#[test]
fn friction_gives_near_linear_decay() {
    // Below flutter (0.5 U_F) with strong Coulomb friction the pitch envelope falls in a
    // straight line: the peak drop per cycle is nearly constant.
    let sc = BlindScenario {
        free_speed_factors: vec![0.5],
        ..small()
    };
    let s = gen(
        BlindEffect::Catalogue(Effect::Friction),
        1.0,
        Form::Primary,
        3,
        &sc,
    );
    let alpha = &s.free.records[0].alpha;
    let n = alpha.len();
    let peaks: Vec<f64> = (1..n - 1)
        .filter(|&i| {
            alpha[i] > alpha[i - 1] && alpha[i] >= alpha[i + 1] && alpha[i] > 0.2f64.to_radians()
        })
        .map(|i| alpha[i])
        .collect();
    assert!(peaks.len() >= 4, "{} peaks", peaks.len());
    let drops: Vec<f64> = peaks.windows(2).map(|w| w[0] - w[1]).collect();
    let k = drops.len().min(4);
    let ratio = drops[k - 1] / drops[0];
    // Exponential decay would shrink each drop by the decay ratio; linear decay keeps it.
    assert!(ratio > 0.7, "drops {:?}", &drops[..k]);
}

#[test]
fn none_twin_differs_only_by_the_effect() {
    // Vortex shedding adds forces only: forced motion channels are identical to the twin,
    // and the free runs are identical for added mass (checked above); here the noise of
    // forces is the same draw: the difference equals the noise-free effect exactly.
    let sc = small();
    let none = gen(BlindEffect::None, 0.0, Form::Primary, 4, &sc);
    let s = gen(
        BlindEffect::Catalogue(Effect::HigherOrder),
        0.5,
        Form::Primary,
        4,
        &sc,
    );
    for (a, b) in s.forced.records.iter().zip(&none.forced.records) {
        assert_eq!(a.h, b.h);
        assert_eq!(a.alpha, b.alpha);
    }
    let s2 = gen(
        BlindEffect::Catalogue(Effect::HigherOrder),
        0.0,
        Form::Primary,
        4,
        &sc,
    );
    let sz = effect_size(&s2, &none, &sc);
    assert!(sz.forced_moment < 0.01 * sz.forced_noise + 1e-3, "{sz:?}");
}

#[test]
fn alternate_forms_generate_and_differ_from_primary() {
    let sc = small();
    for e in Effect::generated()
        .into_iter()
        .map(BlindEffect::Catalogue)
        .chain([BlindEffect::Buffeting])
    {
        let p = gen(e, 0.8, Form::Primary, 2, &sc);
        let a = gen(e, 0.8, Form::Alternate, 2, &sc);
        assert!(!(forced_equal(&p, &a) && free_equal(&p, &a)), "{e:?}");
    }
}

#[test]
fn write_blind_round_trips_through_read_dataset() {
    let sc = small();
    let s = gen(
        BlindEffect::Catalogue(Effect::StaticOffset),
        0.6,
        Form::Primary,
        21,
        &sc,
    );
    let dir = tempfile::tempdir().unwrap();
    write_blind(dir.path(), &s).unwrap();
    let f = identify::dataset::read_dataset(&dir.path().join("forced")).unwrap();
    let v = identify::dataset::read_dataset(&dir.path().join("free")).unwrap();
    assert_eq!(f.records.len(), 40);
    assert_eq!(v.records.len(), 6);
    assert!(v.manifest.structure.is_some());
    // Written with printed precision: values agree to the CSV's digits.
    let (r0, w0) = (&s.forced.records[3], &f.records[3]);
    assert_eq!(r0.meta.id, w0.meta.id);
    let l0 = r0.lift.as_ref().unwrap();
    let l1 = w0.lift.as_ref().unwrap();
    let pk = l0.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for (a, b) in l0.iter().zip(l1) {
        assert!((a - b).abs() < 1e-6 * pk);
    }
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("truth.json")).unwrap())
            .unwrap();
    assert_eq!(truth["seed"], 21);
    // The data sets themselves hold no label.
    let man = std::fs::read_to_string(dir.path().join("forced/manifest.toml")).unwrap();
    assert!(!man.contains("static_offset") && !man.contains("effect"));
}

/// Calibration table (run with `--ignored --nocapture`, release): for each effect the
/// parameter at s = 0, 0.5, 1 and its size against the `None` twin.
#[test]
#[ignore]
fn calibration_table() {
    let sc = BlindScenario::default();
    let none = gen(BlindEffect::None, 0.0, Form::Primary, 1, &sc);
    println!("| effect | s | parameter | forced rel rms L | forced rel rms M | free rel rms α | free rel rms α (U < U_F) |");
    let n0 = effect_size(&none, &none, &sc);
    println!(
        "| noise | - | - | {:.2e} (balance σ / rms M) | | {:.2e} (σ_α / rms α) |",
        n0.forced_noise, n0.free_noise
    );
    for e in Effect::generated()
        .into_iter()
        .map(BlindEffect::Catalogue)
        .chain([BlindEffect::Buffeting])
    {
        for s in [0.0, 0.5, 1.0] {
            let set = gen(e, s, Form::Primary, 1, &sc);
            let z = effect_size(&set, &none, &sc);
            let (name, value) = &set.truth.parameters[0];
            println!(
                "| {} | {s} | {name} = {value:.3e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |",
                e.name(),
                z.forced_lift,
                z.forced_moment,
                z.free_alpha,
                z.free_alpha_subcritical
            );
        }
    }
}

/// Cost of one default blind set (release: well under 1 s).
#[test]
#[ignore]
fn timing_of_one_default_set() {
    let sc = BlindScenario::default();
    for e in [
        BlindEffect::None,
        BlindEffect::Catalogue(Effect::DynamicStall),
        BlindEffect::Catalogue(Effect::TimeDelay),
        BlindEffect::Buffeting,
    ] {
        let t = std::time::Instant::now();
        let _ = gen(e, 1.0, Form::Primary, 1, &sc);
        let t1 = t.elapsed();
        let t = std::time::Instant::now();
        let _ = gen(e, 0.0, Form::Primary, 1, &sc);
        println!("{}: {:?} (s = 1), {:?} (s = 0)", e.name(), t1, t.elapsed());
    }
}
