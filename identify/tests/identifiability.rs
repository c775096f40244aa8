//! Identifiability of the polynomial library under different motions (DESIGN.md §3).

use identify::identifiability::{analyse, BasisMode, RankOptions};
use identify::library::{Library, LibraryKind};
use identify::pipeline::{identify, GroupBy, IdentifySettings};
use identify::record::{CaseMeta, Forcing, NondimCase};
use identify::Error;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const N: usize = 5120;
const DT: f64 = 1.0 / 512.0;
const TAU: f64 = 2.0 * std::f64::consts::PI;

/// Nondimensional two-frequency harmonic motion: α = 0.2 sin ω_α t, h/B = 0.1 sin(ω_h t + φ),
/// B = 0.25 m, U = 8 m/s.
fn harmonic(fa: f64, fh: f64) -> [Vec<f64>; 4] {
    let (b, u) = (0.25, 8.0);
    let t: Vec<f64> = (0..N).map(|i| i as f64 * DT).collect();
    [
        t.iter().map(|t| 0.2 * (TAU * fa * t).sin()).collect(),
        t.iter()
            .map(|t| b / u * 0.2 * TAU * fa * (TAU * fa * t).cos())
            .collect(),
        t.iter().map(|t| 0.1 * (TAU * fh * t + 0.3).sin()).collect(),
        t.iter()
            .map(|t| 0.1 * TAU * fh * (TAU * fh * t + 0.3).cos())
            .collect(),
    ]
}

fn multi_sine() -> [Vec<f64>; 4] {
    let t: Vec<f64> = (0..N).map(|i| i as f64 * DT).collect();
    let comps_a = [(1.1, 0.15, 0.0), (2.3, 0.05, 0.4)];
    let comps_h = [(0.7, 0.08, 0.2), (1.9, 0.03, 1.0)];
    let pos = |c: &[(f64, f64, f64)], t: f64| {
        c.iter()
            .map(|(f, a, p)| a * (TAU * f * t + p).sin())
            .sum::<f64>()
    };
    let vel = |c: &[(f64, f64, f64)], t: f64| {
        c.iter()
            .map(|(f, a, p)| a * TAU * f * (TAU * f * t + p).cos())
            .sum::<f64>()
    };
    [
        t.iter().map(|&t| pos(&comps_a, t)).collect(),
        t.iter().map(|&t| 0.05 * vel(&comps_a, t)).collect(),
        t.iter().map(|&t| pos(&comps_h, t)).collect(),
        t.iter().map(|&t| 0.05 * vel(&comps_h, t)).collect(),
    ]
}

fn random(seed: u64) -> [Vec<f64>; 4] {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let d = Normal::new(0.0, 0.3).unwrap();
    std::array::from_fn(|_| (0..N).map(|_| d.sample(&mut rng)).collect())
}

fn rank_of(kind: LibraryKind, x: &[Vec<f64>; 4]) -> identify::identifiability::CaseIdentifiability {
    let lib = Library::new(kind, false);
    analyse(
        "test",
        &lib,
        lib.evaluate(x).as_ref(),
        &RankOptions::default(),
    )
    .unwrap()
}

#[test]
fn two_frequency_harmonic_motion_has_rank_25_with_five_named_dependencies() {
    for (fa, fh) in [(2.0, 1.3), (1.0, 0.7), (2.5, 3.1)] {
        let id = rank_of(LibraryKind::Paper30, &harmonic(fa, fh));
        assert_eq!(id.rank, 25, "f = ({fa}, {fh}): {:?}", id.singular_values);
        assert_eq!(id.basis_size(), 25);
        let mut names: Vec<&str> = id.dependencies.iter().map(|d| d.term.as_str()).collect();
        names.sort();
        // α̇²h, α̇²ḣ, αḣ², α̇ḣ² (one lower term and one kept cubic each) and one square
        assert_eq!(
            names,
            [
                "alpha*h_dot^2",
                "alpha_dot*h_dot^2",
                "alpha_dot^2*h",
                "alpha_dot^2*h_dot",
                "h_dot^2"
            ],
            "f = ({fa}, {fh})"
        );
        // the square relation names the other three squares
        let sq = id
            .dependencies
            .iter()
            .find(|d| d.term == "h_dot^2")
            .unwrap();
        let mut rhs: Vec<&str> = sq.combination.iter().map(|c| c.0.as_str()).collect();
        rhs.sort();
        assert_eq!(rhs, ["alpha^2", "alpha_dot^2", "h^2"], "{}", sq.describe());
        // (Bα̇/U)² h = K_α² A² h − K_α² α² h with K_α = Bω_α/U
        let k2 = (0.25 * TAU * fa / 8.0f64).powi(2);
        let d = id
            .dependencies
            .iter()
            .find(|d| d.term == "alpha_dot^2*h")
            .unwrap();
        let text = d.describe();
        assert!(text.starts_with("alpha_dot^2*h = "), "{text}");
        let c = |n: &str| d.combination.iter().find(|x| x.0 == n).unwrap().1;
        assert!((c("h") - k2 * 0.04).abs() < 1e-7 * k2, "{text}");
        assert!((c("alpha^2*h") + k2).abs() < 1e-7 * k2, "{text}");
        for d in &id.dependencies {
            assert!(d.residual < 1e-9, "{}: residual {}", d.term, d.residual);
        }
    }
}

#[test]
fn full_library_under_harmonic_motion_also_has_rank_25() {
    // the 4 extra terms of the 34-term library are each dependent too:
    // α α̇² = K²(A² α − α³), α² α̇ via α̇³, h ḣ² = K_h²(A_h² h − h³), ḣ³ via h² ḣ
    let id = rank_of(LibraryKind::Full34, &harmonic(2.0, 1.3));
    assert_eq!(id.rank, 25);
    let names: Vec<&str> = id.dependencies.iter().map(|d| d.term.as_str()).collect();
    assert_eq!(names.len(), 9, "{names:?}");
    for t in [
        "alpha*alpha_dot^2",
        "alpha^2*alpha_dot",
        "h*h_dot^2",
        "h_dot^3",
    ] {
        assert!(names.contains(&t), "{t} not in {names:?}");
    }
    // Eq. 19 terms win over their dependent alternatives
    let lib = Library::new(LibraryKind::Full34, false);
    for t in ["alpha_dot^3", "alpha^3", "alpha*alpha_dot", "h^2*h_dot"] {
        assert!(id.in_basis[lib.index_of(t).unwrap()], "{t}");
    }
}

#[test]
fn multi_sine_and_random_motion_have_full_rank() {
    let id = rank_of(LibraryKind::Paper30, &multi_sine());
    assert_eq!(id.rank, 30, "{:?}", id.dependencies);
    assert!(id.dependencies.is_empty());
    for seed in [1, 2, 3] {
        let id = rank_of(LibraryKind::Paper30, &random(seed));
        assert_eq!(id.rank, 30);
        assert_eq!(id.basis_size(), 30);
        let id = rank_of(LibraryKind::Full34, &random(seed));
        assert_eq!(id.rank, 34);
    }
}

fn case(id: &str, x: [Vec<f64>; 4], forcing: Forcing) -> NondimCase {
    let c_moment: Vec<f64> = (0..N)
        .map(|i| 0.5 * x[0][i] - 0.2 * x[1][i] + 0.1 * x[3][i])
        .collect();
    let c_lift: Vec<f64> = (0..N).map(|i| -2.0 * x[0][i] - 1.0 * x[3][i]).collect();
    NondimCase {
        meta: CaseMeta {
            id: id.to_string(),
            wind_speed: 8.0,
            config: Some("A".to_string()),
            ..CaseMeta::default()
        },
        dt: DT,
        chord: 0.25,
        x,
        c_lift,
        c_moment,
        forcing,
    }
}

#[test]
fn full_basis_on_a_rank_deficient_library_is_an_error_naming_the_terms() {
    let c = case(
        "A-U8",
        harmonic(2.0, 1.3),
        Forcing {
            pitch: Some(2.0),
            heave: Some(1.3),
        },
    );
    let settings = IdentifySettings {
        basis: BasisMode::Full,
        ..IdentifySettings::default()
    };
    let e = identify(std::slice::from_ref(&c), &settings, "t", &|_| {}).unwrap_err();
    match &e {
        Error::RankDeficient {
            case,
            rank,
            expected,
            dependencies,
        } => {
            assert_eq!(case, "A-U8");
            assert_eq!((*rank, *expected), (25, 30));
            assert_eq!(dependencies.len(), 5);
        }
        other => panic!("expected RankDeficient, got {other:?}"),
    }
    let msg = e.to_string();
    for t in [
        "alpha_dot^2*h",
        "h_dot^2",
        "alpha*h_dot^2",
        "A-U8",
        "rank 25",
    ] {
        assert!(msg.contains(t), "`{t}` missing from: {msg}");
    }
    // the canonical basis identifies the same data without error
    let ok = identify(&[c], &IdentifySettings::default(), "t", &|_| {}).unwrap();
    assert_eq!(ok.library.rank, 25);
    assert_eq!(
        ok.cases[0]
            .moment
            .terms
            .0
            .iter()
            .filter(|t| t.1.is_none())
            .count(),
        5
    );
}

#[test]
fn pitch_only_forcing_leaves_heave_derivatives_unidentified() {
    let mut x = harmonic(2.0, 1.3);
    x[2] = vec![0.0; N];
    x[3] = vec![0.0; N];
    let c = case(
        "P",
        x,
        Forcing {
            pitch: Some(2.0),
            heave: None,
        },
    );
    let settings = IdentifySettings {
        group_by: GroupBy::None,
        ..IdentifySettings::default()
    };
    let id = identify(&[c], &settings, "t", &|_| {}).unwrap();
    let m = &id.cases[0].moment;
    assert_eq!(m.terms.0.iter().find(|t| t.0 == "h").unwrap().1, None);
    assert_eq!(m.eq19.A1, None);
    assert_eq!(m.eq19.A4, None);
    assert!(m.eq19.A2.is_some() && m.eq19.A3.is_some());
    let json = serde_json::to_string(&id).unwrap();
    assert!(
        json.contains("\"A1\":null"),
        "unidentifiable must be null, never a number"
    );
    // the law 0.5 α − 0.2 Bα̇/U is recovered: A3 = 0.5/K², A2 = −0.2/K
    let k = id.cases[0].k_alpha.unwrap();
    assert!(
        (m.eq19.A3.unwrap() - 0.5 / (k * k)).abs() < 1e-8,
        "{:?}",
        m.eq19
    );
    assert!((m.eq19.A2.unwrap() + 0.2 / k).abs() < 1e-8, "{:?}", m.eq19);
}

/// Configuration G of the paper (3° mean angle): a force law in the total angle with a
/// static offset, C = c₀ + k α + n α³ (+ damping). Regressed about ᾱ (the default) the fit
/// is exact: α-coefficient k + 3nᾱ² (the local slope), `alpha^2` 3nᾱ, `alpha^3` n and the
/// constant c₀ + kᾱ + nᾱ³. Regressed on α itself (no constant) the offset has no term and
/// the δ path must buy it with spurious terms.
#[test]
fn mean_angle_is_regressed_about_its_mean_with_a_constant() {
    let abar = 3f64.to_radians();
    let mut x = harmonic(1.3, 2.0);
    x[0].iter_mut().for_each(|a| *a += abar);
    let (c0, k, n3, d) = (0.05, 2.0 * std::f64::consts::PI, -4.0, -1.5);
    let law = |x: &[Vec<f64>; 4], i: usize| c0 + k * x[0][i] + n3 * x[0][i].powi(3) + d * x[1][i];
    let mut c = case(
        "G-U8-A11",
        x.clone(),
        Forcing {
            pitch: Some(1.3),
            heave: Some(2.0),
        },
    );
    c.c_lift = (0..N).map(|i| law(&x, i)).collect();
    c.c_moment = (0..N).map(|i| 0.25 * law(&x, i)).collect();
    c.meta.mean_pitch = Some(abar);
    let r = identify(
        std::slice::from_ref(&c),
        &IdentifySettings::default(),
        "t",
        &|_| {},
    )
    .unwrap();
    let cr = &r.cases[0];
    assert_eq!(cr.mean_pitch, Some(abar));
    let t = &cr.lift.terms;
    let want = [
        ("alpha", k + 3.0 * n3 * abar * abar),
        ("alpha^2", 3.0 * n3 * abar),
        ("alpha^3", n3),
        ("alpha_dot", d),
    ];
    for (name, v) in want {
        let got = t.get(name).unwrap();
        assert!(
            (got - v).abs() < 1e-6 * v.abs().max(1.0),
            "{name}: {got} vs {v}"
        );
    }
    let support: Vec<&str> = r.groups[0]
        .lift
        .support
        .iter()
        .map(|s| s.as_str())
        .collect();
    assert_eq!(
        support,
        ["alpha", "alpha_dot", "h", "h_dot", "alpha^2", "alpha^3"],
        "{support:?}"
    );
    let c_want = c0 + k * abar + n3 * abar.powi(3);
    let got = cr.lift.constant.unwrap();
    assert!((got - c_want).abs() < 1e-9, "constant {got} vs {c_want}");
    assert!(cr.lift.r2.unwrap() > 1.0 - 1e-12);
    // not centred: the offset c₀ needs terms the law does not have
    let off = IdentifySettings {
        centre_mean_angle: false,
        ..IdentifySettings::default()
    };
    let r2 = identify(std::slice::from_ref(&c), &off, "t", &|_| {}).unwrap();
    assert!(r2.cases[0].mean_pitch.is_none() && r2.cases[0].lift.constant.is_none());
    let s2 = &r2.groups[0].lift.support;
    assert!(
        s2.len() > 6,
        "an uncentred fit of an offset law should need extra terms: {s2:?}"
    );
}
