//! The closed loop of issue 42 item 4 on sets of the drawn-shapes blind benchmark: each set
//! is diagnosed, and when the verdict is `extrapolation` the recommended forced tests are
//! run on the truth and the set diagnosed again. One line per set:
//! `cargo run --release -p benchmark --example follow_up -- INDEX… [--n N] [--seed SEED]`.

use benchmark::bench::{draw_specs_from, shapes_truths, CampaignShape};
use benchmark::bench_run::{run_one, BlindOptions};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut take = |flag: &str, default: u64| -> u64 {
        match args.iter().position(|a| a == flag) {
            Some(i) if i + 1 < args.len() => {
                let v = args[i + 1].parse().unwrap_or(default);
                args.drain(i..=i + 1);
                v
            }
            _ => default,
        }
    };
    let n = take("--n", 330) as usize;
    let seed = take("--seed", 2026);
    let indices: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let mut opts = BlindOptions::new(n, seed);
    opts.shapes = true;
    opts.follow_up = true;
    let specs = draw_specs_from(n, seed, &shapes_truths());
    let (mut sets, mut right, mut right_before) = (0, 0, 0);
    let (mut strong, mut strong_right) = (0, 0);
    for i in indices {
        let Some(spec) = specs.get(i) else {
            eprintln!("{i}: no such set");
            continue;
        };
        let mut spec = spec.clone();
        spec.shape = Some(CampaignShape::draw_with_physics(spec.seed));
        match run_one(&spec, &opts) {
            Ok((o, _)) => {
                let after = o.follow_up.as_ref();
                println!(
                    "{i} truth {} before {} ({} uncovered) after {} ({:.2}, {} uncovered, {} cases in {} rows, gap ratio {:.2}) right {} {:.0} s",
                    spec.truth,
                    o.verdict_name(),
                    o.uncovered_runs.unwrap_or(0),
                    after.map_or("-", |f| f.verdict.name()),
                    after.map_or(f64::NAN, |f| f.confidence),
                    after.and_then(|f| f.uncovered_runs).unwrap_or(0),
                    after.map_or(0, |f| f.cases),
                    after.map_or(0, |f| f.rows),
                    after.map_or(f64::NAN, |f| f.gap_ratio),
                    o.follow_up_correct().map_or("-".into(), |c| c.to_string()),
                    o.seconds
                );
                if let Some(c) = o.follow_up_correct() {
                    sets += 1;
                    right += usize::from(c);
                    right_before += usize::from(o.correct());
                    let f = o.follow_up.as_ref().expect("followed up");
                    if f.gap_ratio >= benchmark::bench::STRONG_RATIO
                        || o.spec.truth == benchmark::blind::BlindEffect::None
                    {
                        strong += 1;
                        strong_right += usize::from(c);
                    }
                }
            }
            Err(e) => println!("{i} error: {e}"),
        }
    }
    println!(
        "followed up {sets}: right after {right}, right before {right_before}; strong after the \
         follow-up (gap ratio ≥ {}) or effect-free: {strong_right} of {strong} right",
        benchmark::bench::STRONG_RATIO
    );
}
