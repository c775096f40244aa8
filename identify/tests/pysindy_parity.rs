//! Parity with pysindy 2.1 STLSQ on a stored fixture.
//!
//! `tests/fixtures/pysindy_parity.csv` holds the signals x0..x3 (α, Bα̇/U, h/B, ḣ/U) and the
//! target y; `tests/fixtures/pysindy_parity.json` holds pysindy's feature names of
//! `PolynomialLibrary(degree=3, include_bias=False)` and, for several option sets, the
//! coefficients pysindy fitted (both written by `benches/peers/make_parity_fixture.py`).
//! This test builds Θ in pysindy's column order from the feature names (self-contained: it
//! does not use aeroform's library module), runs `PysindyStlsq`, and requires identical
//! supports, the same number of iterations, and every coefficient within 1e-6 relative
//! (zeros exactly zero, i.e. within 1e-12 absolute).

use std::path::PathBuf;

use identify::numerics::mat::Mat;
use identify::regress::pysindy::PysindyStlsq;
use serde_json::Value;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("fixtures")
        .join(name)
}

/// Columns x0..x3 and y of a fixture CSV.
fn read_csv(name: &str) -> (Vec<[f64; 4]>, Vec<f64>) {
    let text = std::fs::read_to_string(fixture(name)).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap().trim(), "x0,x1,x2,x3,y");
    let mut x = Vec::new();
    let mut y = Vec::new();
    for (k, line) in lines.enumerate() {
        let v: Vec<f64> = line
            .split(',')
            .map(|s| {
                s.trim()
                    .parse()
                    .unwrap_or_else(|e| panic!("line {}: {s}: {e}", k + 2))
            })
            .collect();
        assert_eq!(v.len(), 5, "line {}", k + 2);
        x.push([v[0], v[1], v[2], v[3]]);
        y.push(v[4]);
    }
    (x, y)
}

/// Parses a pysindy feature name such as `x0 x1^2` into the list of variable indices of its
/// factors in order (`[0, 1, 1]`).
fn parse_feature(name: &str) -> Vec<usize> {
    let mut factors = Vec::new();
    for tok in name.split_whitespace() {
        let (var, pow) = match tok.split_once('^') {
            Some((v, p)) => (v, p.parse::<usize>().unwrap()),
            None => (tok, 1),
        };
        let idx: usize = var.strip_prefix('x').unwrap().parse().unwrap();
        factors.extend(std::iter::repeat_n(idx, pow));
    }
    factors
}

/// Θ with one column per feature name, each the product of its factors multiplied left to
/// right (the order numpy's `prod` uses in pysindy's PolynomialLibrary).
fn build_theta(x: &[[f64; 4]], names: &[String]) -> Mat<f64> {
    let factors: Vec<Vec<usize>> = names.iter().map(|n| parse_feature(n)).collect();
    Mat::from_fn(x.len(), names.len(), |i, j| {
        let f = &factors[j];
        let mut v = x[i][f[0]];
        for &k in &f[1..] {
            v *= x[i][k];
        }
        v
    })
}

#[test]
fn feature_names_parse() {
    assert_eq!(parse_feature("x0"), vec![0]);
    assert_eq!(parse_feature("x0 x1^2"), vec![0, 1, 1]);
    assert_eq!(parse_feature("x3^3"), vec![3, 3, 3]);
    assert_eq!(parse_feature("x0^2 x2"), vec![0, 0, 2]);
}

#[test]
fn stlsq_matches_pysindy_2_1() {
    let worst = check_fixture("pysindy_parity", 11);
    eprintln!("pysindy_parity: max relative difference {worst:.2e}");
}

/// Campaign-like single-frequency motion: the library is rank deficient (numerical rank
/// recorded in the JSON), so only ridge runs (α > 0) are in the fixture.
#[test]
fn stlsq_matches_pysindy_2_1_on_rank_deficient_harmonic_library() {
    let worst = check_fixture("pysindy_parity_harmonic", 5);
    eprintln!("pysindy_parity_harmonic: max relative difference {worst:.2e}");
}

/// Runs every option set of fixture `stem` and returns the largest relative coefficient
/// difference; panics on any support, iteration-count or 1e-6 mismatch.
fn check_fixture(stem: &str, min_runs: usize) -> f64 {
    let meta: Value =
        serde_json::from_str(&std::fs::read_to_string(fixture(&format!("{stem}.json"))).unwrap())
            .unwrap();
    assert!(meta["pysindy_version"].as_str().unwrap().starts_with("2.1"));
    let names: Vec<String> = meta["feature_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    assert_eq!(names.len(), 34);
    let (x, y) = read_csv(&format!("{stem}.csv"));
    assert_eq!(x.len(), meta["n_samples"].as_u64().unwrap() as usize);
    let theta = build_theta(&x, &names);

    let runs = meta["runs"].as_array().unwrap();
    assert!(runs.len() >= min_runs);
    let mut worst = 0.0f64;
    for run in runs {
        let o = &run["options"];
        let opts = PysindyStlsq {
            threshold: o["threshold"].as_f64().unwrap(),
            alpha: o["alpha"].as_f64().unwrap(),
            max_iter: o["max_iter"].as_u64().unwrap() as usize,
            unbias: o["unbias"].as_bool().unwrap(),
        };
        let normalize = o["normalize_columns"].as_bool().unwrap();
        let fit = opts.fit_report(theta.as_ref(), &y, normalize);
        let expected: Vec<f64> = run["coefficients"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let got = if normalize {
            opts.fit_normalized_columns(theta.as_ref(), &y)
        } else {
            opts.fit(theta.as_ref(), &y)
        };
        assert_eq!(got, fit.coefficients, "fit and fit_report agree");
        assert_eq!(
            fit.iterations as u64,
            run["iterations"].as_u64().unwrap(),
            "iterations, run {o}"
        );
        let mut run_worst = 0.0f64;
        for (j, (g, e)) in got.iter().zip(&expected).enumerate() {
            if *e == 0.0 {
                assert!(g.abs() <= 1e-12, "run {o}: {} = {g}, pysindy 0", names[j]);
                assert_eq!(*g, 0.0, "run {o}: support differs at {}", names[j]);
            } else {
                assert!(*g != 0.0, "run {o}: support differs at {}", names[j]);
                let rel = (g - e).abs() / e.abs();
                run_worst = run_worst.max(rel);
                assert!(
                    rel <= 1e-6,
                    "run {o}: {}: aeroform {g}, pysindy {e}, rel {rel:e}",
                    names[j]
                );
            }
        }
        eprintln!(
            "run {o}: {} terms, {} iterations, max rel diff {run_worst:.2e}",
            expected.iter().filter(|c| **c != 0.0).count(),
            fit.iterations
        );
        worst = worst.max(run_worst);
    }
    worst
}
