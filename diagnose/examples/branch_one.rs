//! Runs sets of the bifurcation-level benchmark and prints each outcome (a debugging aid):
//! `cargo run --release -p diagnose --example branch_one -- SEED INDEX...`.

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seed: u64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(2026);
    for a in &args[1..] {
        let Ok(i) = a.parse::<usize>() else { continue };
        match diagnose::bifurcation::bench::run_set(i, seed) {
            Ok(o) => println!("{}", serde_json::to_string(&o).unwrap_or_default()),
            Err(e) => eprintln!("set {i}: {e}"),
        }
    }
}
