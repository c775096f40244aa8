//! Runs sets of the bifurcation-level benchmark and prints each outcome (a debugging aid):
//! `cargo run --release -p benchmark --example branch_one -- SEED INDEX... [--misgiven]`
//! (`--misgiven`: the structure handed to the diagnosis has one DOF's frequency 3–8 % off,
//! with still-air decays of the truth; `--hold-given`: the same, fitted on the given
//! structure anyway; `A..B` runs indices A to B − 1; `--detail`: also the structure's
//! reason and every candidate's held-out score, shrink and first Hopf point, on stderr;
//! `--sensitivities`: the fits' smooth objective and its derivatives).

use benchmark::branch_bench::{run_set_diagnosis, BranchBenchOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed: u64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(2026);
    let opts = BranchBenchOptions {
        misgiven_structure: args
            .iter()
            .any(|a| a == "--misgiven" || a == "--hold-given"),
        hold_given: args.iter().any(|a| a == "--hold-given"),
        jacobian: if args.iter().any(|a| a == "--sensitivities") {
            diagnose::bifurcation::FitJacobian::Sensitivities
        } else {
            diagnose::bifurcation::FitJacobian::Differences
        },
    };
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
    let detail = args.iter().any(|a| a == "--detail");
    for i in idx {
        match run_set_diagnosis(i, seed, &opts) {
            Ok((o, d)) => {
                println!("{}", serde_json::to_string(&o).unwrap_or_default());
                if detail {
                    if let Some(c) = &d.structure {
                        eprintln!("set {i} structure: {}", c.reason);
                        eprintln!("  decays: {}", c.summary);
                        if let Some(id) = &c.identified {
                            for p in &id.parameters {
                                eprintln!(
                                    "  {} given {:.5e} identified {:.5e} held {}",
                                    p.name, p.given, p.identified, p.held
                                );
                            }
                        }
                    }
                    eprintln!(
                        "  nominal score {:.4} decays {:?} (noise {:?}, cycles {:?}) hopf {:?}",
                        d.nominal.errors.score,
                        d.nominal_decay_misfit,
                        d.decay_noise,
                        d.decay_cycles,
                        d.nominal.hopf.first().map(|h| (h.u, h.criticality.clone()))
                    );
                    for c in &d.candidates {
                        eprintln!(
                            "  {:40} held-out {:.4} ± {:.4} shrink {:+.3} decays {:?} hopf {:?} values {:?}",
                            c.label(),
                            c.held_out.score,
                            c.score_se,
                            c.shrink,
                            c.decay_misfit,
                            c.fit.hopf.first().map(|h| (h.u, h.criticality.clone())),
                            c.parameters.iter().map(|p| p.value).collect::<Vec<_>>()
                        );
                    }
                    eprintln!("  verdict: {}", d.verdict.explanation);
                }
            }
            Err(e) => eprintln!("set {i}: {e}"),
        }
    }
}
