//! Debug aid: the system level of one drawn-shapes blind set with the generator's truth
//! law as the sim (no identification): `cargo run --release -p benchmark --example truth_sim -- INDEX [DIR [N SEED]]`
//! (DIR: also write the set there, `-` for none; N, SEED: the benchmark, default 330 2026).

use std::sync::Arc;

use benchmark::bench::{draw_specs_from, shapes_truths, CampaignShape};
use benchmark::bench_run::BlindOptions;
use benchmark::blind::generate;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let index: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(0);
    let n: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(330);
    let seed: u64 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(2026);
    let opts = BlindOptions::new(n, seed);
    let mut spec = draw_specs_from(n, seed, &shapes_truths())[index].clone();
    let shape = CampaignShape::draw_with_physics(spec.seed);
    spec.shape = Some(shape.clone());
    let scenario = shape.scenario(&opts.scenario).expect("scenario");
    let effect = spec.truth;
    let set = generate(effect, spec.strength, shape.form(), spec.seed, &scenario).expect("set");
    if let Some(dir) = args.get(1).filter(|d| d.as_str() != "-") {
        benchmark::blind::write_blind(std::path::Path::new(dir), &set).expect("write");
        std::fs::write(
            std::path::Path::new(dir).join("truth.model.toml"),
            &scenario.truth_model,
        )
        .expect("write truth model");
    }
    let loaded = aeroelastic::files::LoadedModel::parse(
        &scenario.truth_model,
        "truth",
        std::path::Path::new("."),
        None,
    )
    .expect("truth");
    let model: Arc<dyn aeroelastic::aero::AeroModel> = loaded.model;
    let mut sopts = opts.diagnose.system.clone();
    sopts.seed = spec.seed;
    let level =
        diagnose::system::system_level_with_model(&model, &set.free, &sopts).expect("level");
    println!(
        "before {:.4} noise {:.4} stat {:.2}",
        level.before, level.noise_level, level.gap_statistic
    );
    for c in &level.cases {
        println!(
            "  {} U {:.3} before {:.4} noise {:.4}",
            c.id, c.wind_speed, c.before, c.noise_level
        );
    }
}
