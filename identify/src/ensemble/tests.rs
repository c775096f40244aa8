use super::*;
use crate::pipeline::{identify, IdentifySettings};
use crate::preprocess::{prepare_with_report, PreprocessOptions};
use crate::record::CaseMeta;
use crate::synthetic::{forced_record, HarmonicMotion, PolynomialLaw, Sampling};

const CHORD: f64 = 0.25;

/// Four configuration-D-like cases (α at 2 Hz, h at 1.3 Hz, 10 s at 512 Hz) of the demo
/// law at U = 6, 8, 10, 12 m/s, paper-like noise from `seed`.
fn cases(seed: u64, duration: f64) -> Vec<NondimCase> {
    let section = crate::record::SectionGeometry {
        chord: CHORD,
        span: 0.75,
        air_density: 1.225,
    };
    let sampling = Sampling {
        duration,
        ..Sampling::default()
    };
    [6.0, 8.0, 10.0, 12.0]
        .iter()
        .enumerate()
        .map(|(i, &u)| {
            let motion = HarmonicMotion {
                freq_pitch: 2.0,
                freq_heave: 1.3,
                amp_pitch: (12.0 + 3.0 * i as f64).to_radians(),
                amp_heave: 0.02,
                mean_pitch: 0.0,
            };
            let meta = CaseMeta {
                id: format!("D-U{u}"),
                wind_speed: u,
                freq_pitch: Some(2.0),
                freq_heave: Some(1.3),
                ..Default::default()
            };
            let r = forced_record(
                meta,
                &section,
                &motion,
                &PolynomialLaw::demo(),
                &sampling,
                mix(seed ^ (i as u64) << 32),
            )
            .unwrap();
            let (p, _) = prepare_with_report(&r, &PreprocessOptions::default()).unwrap();
            p.into_nondimensional(&section).unwrap()
        })
        .collect()
}

fn identified(c: &[NondimCase]) -> Identification {
    identify(c, &IdentifySettings::default(), "synthetic", &|_| {}).unwrap()
}

/// Settings that keep every term of the demo law (either force) in the support: the
/// selection cannot drop a true term, so the estimator is unbiased and the coverage
/// measures the resampling scheme alone.
fn truth_support_settings() -> IdentifySettings {
    IdentifySettings {
        kept_terms: [
            "alpha",
            "alpha_dot",
            "h",
            "h_dot",
            "alpha*alpha_dot",
            "alpha^3",
            "alpha_dot^3",
        ]
        .map(String::from)
        .to_vec(),
        ..IdentifySettings::default()
    }
}

#[test]
fn quantiles_interpolate_between_order_statistics() {
    let v: Vec<f64> = (0..=10).map(f64::from).collect();
    assert_eq!(quantile_sorted(&v, 0.5), 5.0);
    assert!((quantile_sorted(&v, 0.05) - 0.5).abs() < 1e-12);
    assert!((quantile_sorted(&v, 0.95) - 9.5).abs() < 1e-12);
    let iv = Interval::from_samples(&[3.0, f64::NAN, 1.0, 2.0], 0.5).unwrap();
    assert_eq!((iv.lower, iv.median, iv.upper), (1.5, 2.0, 2.5));
    assert!(Interval::from_samples(&[f64::NAN], 0.9).is_none());
    assert!(iv.contains(2.5) && !iv.contains(2.6));
}

#[test]
fn normal_and_student_quantiles_match_tables() {
    assert!((normal_quantile(0.95) - 1.644_853_627).abs() < 1e-8);
    assert!((normal_quantile(0.975) - 1.959_963_985).abs() < 1e-8);
    assert!((normal_quantile(0.001) + 3.090_232_306).abs() < 1e-8);
    // t tables: t_12(0.95) = 1.782288, t_12(0.975) = 2.178813, t_5(0.95) = 2.015048
    assert!((student_quantile(0.95, 12.0) - 1.782_288).abs() < 2e-4);
    assert!((student_quantile(0.975, 12.0) - 2.178_813).abs() < 5e-4);
    assert!((student_quantile(0.95, 5.0) - 2.015_048).abs() < 2e-3);
    let c = finite_block_factor(13, 0.9);
    assert!(
        (c - (13.0f64 / 12.0).sqrt() * 1.782_288 / 1.644_854).abs() < 2e-4,
        "{c}"
    );
}

#[test]
fn settings_are_checked() {
    assert!(EnsembleSettings::new(1, 0).validate().is_err());
    let mut s = EnsembleSettings::new(10, 0);
    s.level = 1.0;
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("ensemble.level"), "{e}");
    s.level = 0.9;
    s.block_periods = 0.0;
    assert!(s
        .validate()
        .unwrap_err()
        .to_string()
        .contains("block_periods"));
}

/// With every block drawn once the block re-fit is the full-data least-squares fit on the
/// selected support, i.e. the identification's own coefficients.
#[test]
fn all_blocks_once_reproduce_the_identification() {
    let c = cases(1, 10.0);
    let id = identified(&c);
    let lib = Library::new(id.settings.library, id.settings.constant);
    for (i, case) in c.iter().enumerate() {
        let g = id
            .groups
            .iter()
            .find(|g| g.name == id.cases[i].group)
            .unwrap();
        let cols: Vec<usize> = g
            .moment
            .support
            .iter()
            .map(|t| lib.index_of(t).unwrap())
            .collect();
        let blocks = blocks_of(case, 1.0, 2 * cols.len() + 2);
        assert_eq!(blocks.len(), 13, "10 s of 1.3 Hz periods");
        let theta = lib.evaluate(&case.x);
        let fb = ForceBlocks::new(theta.as_ref(), cols, &case.c_moment, &blocks);
        let x = fb.fit(&vec![1; blocks.len()]);
        for (t, v) in g.moment.support.iter().zip(&x) {
            let want = id.cases[i].moment.terms.get(t).unwrap();
            assert!(
                (v - want).abs() <= 1e-9 * want.abs().max(1e-3),
                "{t}: {v} vs {want}"
            );
        }
    }
}

#[test]
fn deterministic_seeded_and_members_rebuild() {
    let c = cases(2, 6.0);
    let id = identified(&c);
    let s = EnsembleSettings::new(20, 7);
    let a = bootstrap(&c, &id, &s).unwrap();
    let b = bootstrap(&c, &id, &s).unwrap();
    assert_eq!(a, b);
    let other = bootstrap(&c, &id, &EnsembleSettings::new(20, 8)).unwrap();
    assert_ne!(a.cases[0].moment.samples, other.cases[0].moment.samples);
    // the interval brackets the median and the members differ
    let iv = a.cases[0].moment.eq19["A2"];
    assert!(iv.lower < iv.median && iv.median < iv.upper, "{iv:?}");
    // member identification: coefficients and Eq. 19 of member 3
    let m = a.member(&id, 3).unwrap();
    let e = &a.cases[1].moment;
    let k = e.support.iter().position(|t| t == "alpha_dot").unwrap();
    let xi = e.samples[3][k];
    assert_eq!(m.cases[1].moment.terms.get("alpha_dot"), Some(xi));
    let a2 = m.cases[1].moment.eq19.A2.unwrap();
    assert!((a2 - xi / m.cases[1].k_alpha.unwrap()).abs() < 1e-12);
    assert!(a.member(&id, 20).is_err());
    // JSON round trip, seed as a string
    let mut with = id.clone();
    with.ensemble = Some(a.clone());
    let text = serde_json::to_string(&with).unwrap();
    assert!(text.contains(r#""seed":"7""#));
    let back: Identification = serde_json::from_str(&text).unwrap();
    // serde_json's default float parser may differ in the last bit
    let b = back.ensemble.unwrap();
    assert_eq!(b.settings, a.settings);
    for (x, y) in b.cases.iter().zip(&a.cases) {
        assert_eq!(x.moment.support, y.moment.support);
        for (r, s) in x.moment.samples.iter().zip(&y.moment.samples) {
            for (u, v) in r.iter().zip(s) {
                assert!((u - v).abs() <= 1e-15 * v.abs(), "{u} vs {v}");
            }
        }
    }
    assert!(
        !a.cases[0].moment.eq19.contains_key("N3"),
        "N3 is not in the support"
    );
    // a truncated section is refused with the case and field named
    let mut bad = a.clone();
    bad.cases[2].lift.samples.pop();
    let err = bad.member(&id, 0).unwrap_err().to_string();
    assert!(
        err.contains("ensemble.lift.samples") && err.contains("D-U10"),
        "{err}"
    );
}

#[test]
fn refuses_ridge_and_missing_cases() {
    let c = cases(3, 4.0);
    let mut id = identified(&c);
    let s = EnsembleSettings::new(5, 0);
    let err = bootstrap(&c[..2], &id, &s).unwrap_err().to_string();
    assert!(err.contains("D-U10"), "{err}");
    id.settings.ridge = 1e-3;
    assert!(bootstrap(&c, &id, &s).is_err());
}

/// Coverage of the nominal intervals of every true coefficient of the demo law over
/// independent noise seeds: (hits, trials) per (force, term).
fn coverage(
    settings: &IdentifySettings,
    seeds: std::ops::Range<u64>,
    members: usize,
    level: f64,
) -> Vec<(String, usize, usize)> {
    let law = PolynomialLaw::demo();
    let name = |powers: [u8; 4]| crate::library::Term { powers }.name();
    // the law's terms, and the moment's nonlinear terms in the lift with true value 0
    let mut truth: Vec<(bool, String, f64)> = law
        .moment
        .iter()
        .map(|t| (true, name(t.powers), t.coefficient))
        .chain(
            law.lift
                .iter()
                .map(|t| (false, name(t.powers), t.coefficient)),
        )
        .collect();
    for t in ["alpha*alpha_dot", "alpha_dot^3"] {
        if settings.kept_terms.iter().any(|k| k == t) {
            truth.push((false, t.to_string(), 0.0));
        }
    }
    let mut tally: Vec<(String, usize, usize)> = truth
        .iter()
        .map(|(m, n, _)| (format!("{} {n}", if *m { "C_M" } else { "C_L" }), 0, 0))
        .collect();
    for seed in seeds {
        let c = cases(1000 + seed, 10.0);
        let id = identify(&c, settings, "synthetic", &|_| {}).unwrap();
        let mut s = EnsembleSettings::new(members, seed);
        s.level = level;
        let e = bootstrap(&c, &id, &s).unwrap();
        for ce in &e.cases {
            for (k, (moment, term, value)) in truth.iter().enumerate() {
                let f = if *moment { &ce.moment } else { &ce.lift };
                // a true term that selection dropped has no interval: a miss
                let hit = f.terms.get(term).is_some_and(|iv| iv.contains(*value));
                tally[k].1 += usize::from(hit);
                tally[k].2 += 1;
            }
        }
    }
    tally
}

fn report(tally: &[(String, usize, usize)], level: f64) -> f64 {
    let (h, n) = tally.iter().fold((0, 0), |a, t| (a.0 + t.1, a.1 + t.2));
    for (name, h, n) in tally {
        eprintln!("{name:>20}: {h}/{n} = {:.3}", *h as f64 / *n as f64);
    }
    let p = h as f64 / n as f64;
    eprintln!(
        "all terms: {h}/{n} = {p:.3} ± {:.3} (binomial s.e.), nominal {level}",
        (p * (1.0 - p) / n as f64).sqrt()
    );
    p
}

/// Fast variant (CI): 6 noise seeds × 4 cases × 14 true terms (the selection held at a
/// superset of the true support), 100 members. Asserts that the coverage is not absurd (a
/// scheme that ignored the noise would cover ~0, one that covered everything is useless).
#[test]
fn coverage_of_true_coefficients_is_not_absurd() {
    let t = coverage(&truth_support_settings(), 0..6, 100, 0.9);
    let p = report(&t, 0.9);
    assert!((0.75..=0.99).contains(&p), "coverage {p}");
}

/// Full check (ignored: ~1 min): 100 noise seeds × 4 cases, 200 members, nominal 90 %, the
/// true support kept: coverage of every true coefficient within 3 points + 2 s.e. of 90 %.
/// Numbers in docs/DECISIONS.md.
#[test]
#[ignore]
fn coverage_of_true_coefficients_full() {
    let t = coverage(&truth_support_settings(), 0..100, 200, 0.9);
    let p = report(&t, 0.9);
    let n: usize = t.iter().map(|x| x.2).sum();
    let se = (0.9 * 0.1 / n as f64).sqrt();
    assert!((p - 0.9).abs() < 0.03 + 2.0 * se, "coverage {p}");
}

/// The same with default selection (ignored; reported, not asserted): selection drops the
/// small true C_M term (Bα̇/U)³, whose harmonic at ω_α is absorbed by Bα̇/U, so these two
/// under-cover; the intervals are conditional on the selected support.
#[test]
#[ignore]
fn coverage_with_default_selection_full() {
    let t = coverage(&IdentifySettings::default(), 0..100, 200, 0.9);
    report(&t, 0.9);
}
