//! Criterion benchmark of one whole diagnosis (`diagnose::pipeline::diagnose`: force level
//! with held-out folds, system level with candidates, coverage and re-simulation, verdict)
//! on the campaign shape of the issue-10 timing target: one configuration (D) × 7 wind speeds
//! (4 … 10 m/s) × 4 pitch amplitudes = 28 forced cases (8 s at 512 Hz) and 9 free runs
//! (0.6 … 1.2 U_F, 12 s), effect-free, from the blind generator (generation is not timed).
//!
//! Run: `cargo bench --bench diagnose`.

use criterion::{criterion_group, criterion_main, Criterion};
use diagnose::blind::{generate, BlindEffect, BlindScenario};
use diagnose::pipeline::{diagnose, DiagnoseOptions};

fn bench(c: &mut Criterion) {
    let mut scenario = BlindScenario::default();
    scenario.campaign.configurations.retain(|c| c.name == "D");
    scenario.campaign.wind_speeds = vec![4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0];
    scenario.free_speed_factors = vec![0.6, 0.7, 0.8, 0.85, 0.9, 0.95, 1.05, 1.1, 1.2];
    let set = generate(
        BlindEffect::None,
        0.0,
        aeroelastic::effects::Form::Primary,
        7,
        &scenario,
    )
    .expect("blind set");
    assert_eq!(set.forced.records.len(), 28);
    assert_eq!(set.free.records.len(), 9);
    let opts = DiagnoseOptions::new(1);
    let mut g = c.benchmark_group("diagnose");
    g.sample_size(10);
    g.bench_function("28_forced_9_free", |b| {
        b.iter(|| diagnose(&set.forced, Some(&set.free), &opts, "bench").unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
