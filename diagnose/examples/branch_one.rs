//! Runs sets of the bifurcation-level benchmark and prints each outcome (a debugging aid):
//! `cargo run --release -p diagnose --example branch_one -- SEED INDEX... [--misgiven]`
//! (`--misgiven`: the structure handed to the diagnosis has one DOF's frequency 3–8 % off,
//! with still-air decays of the truth; `--hold-given`: the same, fitted on the given
//! structure anyway; `A..B` runs indices A to B − 1).

use diagnose::bifurcation::bench::{run_set_with, BranchBenchOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed: u64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(2026);
    let opts = BranchBenchOptions {
        misgiven_structure: args
            .iter()
            .any(|a| a == "--misgiven" || a == "--hold-given"),
        hold_given: args.iter().any(|a| a == "--hold-given"),
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
    for i in idx {
        match run_set_with(i, seed, &opts) {
            Ok(o) => println!("{}", serde_json::to_string(&o).unwrap_or_default()),
            Err(e) => eprintln!("set {i}: {e}"),
        }
    }
}
