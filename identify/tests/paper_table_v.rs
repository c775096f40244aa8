//! Paper Table IV/V synthetic benchmark (Eq. 15/16):
//! F = H1 h + H2 ḣ + A1 α + A2 α̇ + N1 h ḣ α + N2 α² h + noise,
//! α = sin(2·2πt), h = sin(1.3·2πt), 512 Hz, 20 s, Gaussian noise std 0.5.
//! Regressed directly on the 30-term library in (α, α̇, h, ḣ) (chord = U = 1, so the
//! nondimensional variables are the physical ones), through the whole pipeline with every
//! case alone: library, identifiability (rank 25), δ path, selection.

use identify::pipeline::{identify, GroupBy, Identification, IdentifySettings};
use identify::record::{CaseMeta, Forcing, NondimCase};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const TRUE_TERMS: [&str; 6] = [
    "alpha",
    "alpha_dot",
    "h",
    "h_dot",
    "alpha*h*h_dot",
    "alpha^2*h",
];
/// (A1, A2, H1, H2, N1, N2) in the order of TRUE_TERMS: α, α̇, h, ḣ, hḣα, α²h.
const GROUP1: [f64; 6] = [0.9, 0.1, -0.4, 0.03, 0.05, 0.3];
const GROUP2: [f64; 6] = [0.1, 0.3, -0.1, 0.2, 0.5, 0.8];
const FS: f64 = 512.0;
const DURATION: f64 = 20.0;
const SIGMA: f64 = 0.5;

fn motion() -> [Vec<f64>; 4] {
    let n = (FS * DURATION) as usize;
    let (wa, wh) = (
        2.0 * std::f64::consts::PI * 2.0,
        2.0 * std::f64::consts::PI * 1.3,
    );
    let t: Vec<f64> = (0..n).map(|i| i as f64 / FS).collect();
    [
        t.iter().map(|t| (wa * t).sin()).collect(),
        t.iter().map(|t| wa * (wa * t).cos()).collect(),
        t.iter().map(|t| (wh * t).sin()).collect(),
        t.iter().map(|t| wh * (wh * t).cos()).collect(),
    ]
}

/// Columns of the true terms.
fn true_columns(x: &[Vec<f64>; 4]) -> Vec<Vec<f64>> {
    let n = x[0].len();
    vec![
        x[0].clone(),
        x[1].clone(),
        x[2].clone(),
        x[3].clone(),
        (0..n).map(|i| x[0][i] * x[2][i] * x[3][i]).collect(),
        (0..n).map(|i| x[0][i] * x[0][i] * x[2][i]).collect(),
    ]
}

fn force(cols: &[Vec<f64>], coef: &[f64; 6], rng: &mut ChaCha8Rng) -> Vec<f64> {
    let noise = Normal::new(0.0, SIGMA).unwrap();
    (0..cols[0].len())
        .map(|i| (0..6).map(|k| coef[k] * cols[k][i]).sum::<f64>() + noise.sample(rng))
        .collect()
}

/// One case per seed: moment = group 1 law, lift = group 2 law (independent noise).
fn cases(seeds: std::ops::Range<u64>) -> Vec<NondimCase> {
    let x = motion();
    let cols = true_columns(&x);
    seeds
        .map(|seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let c_moment = force(&cols, &GROUP1, &mut rng);
            let c_lift = force(&cols, &GROUP2, &mut rng);
            NondimCase {
                meta: CaseMeta {
                    id: format!("seed-{seed:03}"),
                    wind_speed: 1.0,
                    ..CaseMeta::default()
                },
                dt: 1.0 / FS,
                chord: 1.0,
                x: x.clone(),
                c_lift,
                c_moment,
                forcing: Forcing {
                    pitch: Some(2.0),
                    heave: Some(1.3),
                },
            }
        })
        .collect()
}

/// Least-squares standard errors σ·sqrt(diag((ΘᵀΘ)⁻¹)) of the true terms.
fn standard_errors() -> [f64; 6] {
    let cols = true_columns(&motion());
    let mut g = [[0.0; 6]; 6];
    for a in 0..6 {
        for b in 0..6 {
            g[a][b] = cols[a].iter().zip(&cols[b]).map(|(u, v)| u * v).sum();
        }
    }
    // Gauss–Jordan inverse
    let mut inv = [[0.0; 6]; 6];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for k in 0..6 {
        let p = (k..6)
            .max_by(|&a, &b| g[a][k].abs().total_cmp(&g[b][k].abs()))
            .unwrap();
        g.swap(k, p);
        inv.swap(k, p);
        let d = g[k][k];
        for c in 0..6 {
            g[k][c] /= d;
            inv[k][c] /= d;
        }
        for r in 0..6 {
            if r != k {
                let f = g[r][k];
                for c in 0..6 {
                    g[r][c] -= f * g[k][c];
                    inv[r][c] -= f * inv[k][c];
                }
            }
        }
    }
    std::array::from_fn(|k| SIGMA * inv[k][k].sqrt())
}

struct Stats {
    hits: [usize; 2],
    /// Cases whose δ path visits the exact support at some δ.
    true_on_path: [usize; 2],
    mean: [[f64; 6]; 2],
    std: [[f64; 6]; 2],
    n: usize,
    misses: Vec<String>,
}

fn run(seeds: std::ops::Range<u64>) -> Stats {
    run_with(
        seeds,
        &IdentifySettings {
            group_by: GroupBy::None,
            ..IdentifySettings::default()
        },
    )
}

fn run_with(seeds: std::ops::Range<u64>, settings: &IdentifySettings) -> Stats {
    let cs = cases(seeds);
    let id: Identification = identify(&cs, settings, "paper Table V", &|_| {}).unwrap();
    assert_eq!(id.library.rank, 25, "{:?}", id.library.dependencies);
    let n = id.cases.len();
    let mut hits = [0; 2];
    let mut sum = [[0.0; 6]; 2];
    let mut sum2 = [[0.0; 6]; 2];
    let mut misses = Vec::new();
    let mut true_on_path = [0; 2];
    for (g, name) in [(0usize, "moment"), (1, "lift")] {
        for (c, grp) in id.cases.iter().zip(&id.groups) {
            assert_eq!(grp.name, c.id);
            let support = if g == 0 {
                &grp.moment.support
            } else {
                &grp.lift.support
            };
            let mut s: Vec<&str> = support.iter().map(String::as_str).collect();
            s.sort();
            let mut t = TRUE_TERMS.to_vec();
            t.sort();
            let force = if g == 0 { &grp.moment } else { &grp.lift };
            let on_path = force.path.iter().any(|p| {
                let mut q: Vec<&str> = p.support.iter().map(String::as_str).collect();
                q.sort();
                q == t
            });
            if on_path {
                true_on_path[g] += 1;
            }
            if s == t {
                hits[g] += 1;
            } else {
                misses.push(format!(
                    "{} {name}: {support:?} (true support on the δ path: {on_path})",
                    c.id
                ));
            }
            let terms = if g == 0 {
                &c.moment.terms
            } else {
                &c.lift.terms
            };
            for (k, term) in TRUE_TERMS.iter().enumerate() {
                let v = terms.get(term).unwrap_or(0.0);
                sum[g][k] += v;
                sum2[g][k] += v * v;
            }
        }
    }
    let mut mean = [[0.0; 6]; 2];
    let mut std = [[0.0; 6]; 2];
    for g in 0..2 {
        for k in 0..6 {
            mean[g][k] = sum[g][k] / n as f64;
            std[g][k] = ((sum2[g][k] - n as f64 * mean[g][k] * mean[g][k]) / (n as f64 - 1.0))
                .max(0.0)
                .sqrt();
        }
    }
    Stats {
        hits,
        true_on_path,
        mean,
        std,
        n,
        misses,
    }
}

fn check(stats: &Stats, min_hits: usize, se_of_mean_factor: f64, ratio: (f64, f64), print: bool) {
    let se = standard_errors();
    let names = [
        ["A1", "A2", "H1", "H2", "N1", "N2"],
        ["A1", "A2", "H1", "H2", "N1", "N2"],
    ];
    if print {
        println!(
            "Table V reproduction over {} seeds (σ = {SIGMA}, 512 Hz, 20 s)",
            stats.n
        );
        println!(
            "{:<6} {:<4} {:>9} {:>11} {:>10} {:>10} {:>8}",
            "group", "coef", "truth", "mean", "std", "LS s.e.", "std/se"
        );
    }
    for (g, truth) in [GROUP1, GROUP2].iter().enumerate() {
        for k in 0..6 {
            let (m, s) = (stats.mean[g][k], stats.std[g][k]);
            if print {
                println!(
                    "{:<6} {:<4} {:>9.4} {:>11.5} {:>10.5} {:>10.5} {:>8.3}",
                    g + 1,
                    names[g][k],
                    truth[k],
                    m,
                    s,
                    se[k],
                    s / se[k]
                );
            }
            let tol = (0.01 * truth[k].abs()).max(se_of_mean_factor * s / (stats.n as f64).sqrt());
            assert!(
                (m - truth[k]).abs() <= tol,
                "group {} {}: mean {m} vs {} (tol {tol})",
                g + 1,
                names[g][k],
                truth[k]
            );
            let r = s / se[k];
            assert!(
                r >= ratio.0 && r <= ratio.1,
                "group {} {}: std {s} vs LS s.e. {} (ratio {r})",
                g + 1,
                names[g][k],
                se[k]
            );
        }
    }
    if print {
        println!(
            "exact support: group 1 (moment) {}/{}, group 2 (lift) {}/{}",
            stats.hits[0], stats.n, stats.hits[1], stats.n
        );
        for m in &stats.misses {
            println!("  miss: {m}");
        }
    }
    for g in 0..2 {
        assert!(
            stats.hits[g] >= min_hits,
            "group {}: exact support in {}/{} seeds; misses {:?}",
            g + 1,
            stats.hits[g],
            stats.n,
            stats.misses
        );
    }
}

/// The acceptance check (run with `--nocapture` to print the table; about 1 s in release):
/// 100 seeds per group, exact support in ≥ 99, means within max(1 %, 1 s.e.m.),
/// std/LS-s.e. in [0.75, 1.3].
#[test]
fn table_v_hundred_seeds() {
    let stats = run(0..100);
    check(&stats, 99, 1.0, (0.75, 1.3), true);
}

/// The paper's raw-coefficient threshold (`measure = coefficient`, δ over 1e-3..10) on the
/// same 100 seeds: the rate of exact supports is recorded here and in DECISIONS.md
/// ("Table V with the raw threshold"); the test fails if it moves, so a change of the
/// regression that alters it has to update the documented number.
#[test]
fn table_v_raw_threshold_rate() {
    let stats = run_with(
        0..100,
        &IdentifySettings {
            group_by: GroupBy::None,
            measure: identify::regress::Measure::Coefficient,
            ..IdentifySettings::default()
        },
    );
    println!(
        "raw threshold: exact support moment {}/{}, lift {}/{}; exact support on the δ path \
         moment {}/{}, lift {}/{}",
        stats.hits[0],
        stats.n,
        stats.hits[1],
        stats.n,
        stats.true_on_path[0],
        stats.n,
        stats.true_on_path[1],
        stats.n
    );
    for m in &stats.misses {
        println!("  miss: {m}");
    }
    assert_eq!(
        stats.hits,
        [RAW_HITS_MOMENT, RAW_HITS_LIFT],
        "{:?}",
        stats.misses
    );
}

/// Documented exact-support counts of [`table_v_raw_threshold_rate`] (seeds 0..100).
const RAW_HITS_MOMENT: usize = 70;
const RAW_HITS_LIFT: usize = 100;
