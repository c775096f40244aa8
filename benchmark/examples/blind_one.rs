//! Diagnoses one set of the drawn-shapes blind benchmark and prints its diagnosis JSON
//! (a debugging aid): `cargo run --release -p benchmark --example blind_one -- INDEX [N SEED]`
//! (`list` for INDEX: every set's truth and strength).

use benchmark::bench::{draw_specs_from, shapes_truths, CampaignShape};
use benchmark::bench_run::{run_one, BlindOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let index: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(0);
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(330);
    let seed: u64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(2026);
    let mut opts = BlindOptions::new(n, seed);
    // PLAIN=1: the default benchmark (plate scenario, no drawn shapes)
    let plain = std::env::var("PLAIN").is_ok();
    opts.shapes = !plain;
    let specs = if plain {
        benchmark::bench::draw_specs(n, seed)
    } else {
        draw_specs_from(n, seed, &shapes_truths())
    };
    if args.first().map(String::as_str) == Some("list") {
        for (i, s) in specs.iter().enumerate() {
            let shape = CampaignShape::draw_with_physics(s.seed);
            let law = shape.physics.as_ref().map(|p| match p.law {
                benchmark::physics::DrawnLaw::Eq19 { .. } => "eq19",
                benchmark::physics::DrawnLaw::EffectiveAngle { .. } => "effective_angle",
            });
            println!(
                "{i} {} {:.2} groups {} amplitudes {} law {}",
                s.truth,
                s.strength,
                shape.groups(),
                shape.amplitudes_deg.len(),
                law.unwrap_or("-")
            );
        }
        return;
    }
    let mut spec = specs[index].clone();
    if !plain {
        spec.shape = Some(CampaignShape::draw_with_physics(spec.seed));
    }
    match run_one(&spec, &opts) {
        Ok((o, d)) => {
            eprintln!(
                "{} -> {} ({:.2}) gap ratio {:.2}",
                spec.truth,
                o.verdict_name(),
                o.confidence,
                o.gap_ratio
            );
            println!("{}", serde_json::to_string_pretty(&d).unwrap_or_default());
        }
        Err(e) => eprintln!("error: {e}"),
    }
}
