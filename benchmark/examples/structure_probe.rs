//! The structures of generated bifurcation-level sets (a debugging aid): the truth's, the
//! given and the identified linear structure and their still-air modes.
//! `cargo run --release -p benchmark --example structure_probe -- SEED INDEX...`

use aeroelastic::section::Section;
use aeroelastic::structure::Structure;
use benchmark::branch_bench::{draw_set, BranchBenchOptions};
use diagnose::structure::rest_linearisation;
use nalgebra::{Matrix2, Matrix4};

/// Frequencies \[Hz\] and damping ratios of M q̈ + C q̇ + K q = 0 (increasing frequency).
fn modes(m: &Matrix2<f64>, k: &Matrix2<f64>, c: &Matrix2<f64>) -> Vec<(f64, f64)> {
    let Some(mi) = m.try_inverse() else {
        return vec![];
    };
    let (a, b) = (-mi * k, -mi * c);
    let mut s = Matrix4::zeros();
    s[(0, 2)] = 1.0;
    s[(1, 3)] = 1.0;
    for i in 0..2 {
        for j in 0..2 {
            s[(2 + i, j)] = a[(i, j)];
            s[(2 + i, 2 + j)] = b[(i, j)];
        }
    }
    let mut out: Vec<(f64, f64)> = s
        .complex_eigenvalues()
        .iter()
        .filter(|l| l.im > 0.0)
        .map(|l| {
            let w = l.norm();
            (w / std::f64::consts::TAU, -l.re / w)
        })
        .collect();
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    out
}

fn line(name: &str, sec: &Section, st: &Structure) {
    let (ke, ce) = rest_linearisation(st);
    let k = st.stiffness_matrix() + ke;
    let c = st.damping_matrix() + ce;
    println!(
        "  {name:10} k_h {:.5e} k_a {:.5e} c_h {:.4e} c_a {:.4e} (rest +k_a {:.3e} +c_a {:.3e}) modes {:?}",
        st.k_h,
        st.k_alpha,
        st.c_h,
        st.c_alpha,
        ke[(1, 1)],
        ce[(1, 1)],
        modes(&sec.total_mass(0.0), &k, &c)
            .iter()
            .map(|(f, z)| format!("{f:.4} Hz ζ {z:.4}"))
            .collect::<Vec<_>>()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed: u64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(2026);
    let opts = BranchBenchOptions {
        misgiven_structure: true,
        ..BranchBenchOptions::default()
    };
    let summary = args.iter().any(|a| a == "--summary");
    let mut idx = Vec::new();
    for a in args.iter().skip(1) {
        if let Some((lo, hi)) = a.split_once("..") {
            if let (Ok(lo), Ok(hi)) = (lo.parse::<usize>(), hi.parse::<usize>()) {
                idx.extend(lo..hi);
            }
        } else if let Ok(i) = a.parse::<usize>() {
            idx.push(i);
        }
    }
    for i in idx {
        match draw_set(i, seed, &opts) {
            Ok(set) if summary => {
                let t = &set.truth.structure;
                let (u, oe) = set
                    .check
                    .as_ref()
                    .map_or((set.given.structure.clone(), 0), |c| {
                        (
                            c.used_structure(&set.given.structure),
                            c.modes
                                .iter()
                                .filter(|r| r.signature.contains("output error"))
                                .count(),
                        )
                    });
                println!(
                    "{seed} {i:2} {:16} {:5} {:+.3}  k_h {:+6.2} % k_a {:+6.2} %  (given {:+6.2} {:+6.2})  oe rows {oe}",
                    format!("{:?}", set.truth_kind),
                    set.misgiven.as_ref().map_or("", |m| m.dof.as_str()),
                    set.misgiven.as_ref().map_or(0.0, |m| m.factor - 1.0),
                    100.0 * (u.k_h / t.k_h - 1.0),
                    100.0 * (u.k_alpha / t.k_alpha - 1.0),
                    100.0 * (set.given.structure.k_h / t.k_h - 1.0),
                    100.0 * (set.given.structure.k_alpha / t.k_alpha - 1.0),
                );
            }
            Ok(set) => {
                println!(
                    "set {i}: {:?} strength {:.3} misgiven {:?} truth hopf {:?}",
                    set.truth_kind, set.strength, set.misgiven, set.truth_hopf
                );
                line("truth", &set.truth, &set.truth.structure);
                line("given", &set.given, &set.given.structure);
                if let Some(c) = &set.check {
                    let used = c.used_structure(&set.given.structure);
                    line("identified", &set.given, &used);
                    println!("  used {:?}: {}", c.used, c.reason);
                    for r in &c.modes {
                        println!(
                            "    row {} {} mode {} {:.4} Hz (linear {:.4} ± {:.4}) ζ {:.4} {}",
                            r.case,
                            r.dof,
                            r.given_mode,
                            r.measured_hz,
                            r.linear_hz,
                            r.linear_hz_sd,
                            r.measured_zeta,
                            r.signature
                        );
                    }
                    for r in &c.refused {
                        println!("    refused {r}");
                    }
                }
            }
            Err(e) => eprintln!("set {i}: {e}"),
        }
    }
}
