//! Criterion benchmark of one whole diagnosis (`diagnose::pipeline::diagnose`: force level
//! with held-out folds, system level with candidates, coverage and re-simulation, verdict)
//! on the campaign shape of the issue-10 timing target: one configuration (D) × 7 wind speeds
//! (4 … 10 m/s) × 4 pitch amplitudes = 28 forced cases (8 s at 512 Hz) and 9 free runs
//! (0.6 … 1.2 U_F, 12 s), effect-free, from the blind generator (generation is not timed).
//!
//! The second group times the bifurcation-level diagnosis of the Bristol rig
//! (`diagnose::bifurcation::diagnose_branches`: the linear model against the nine measured
//! LCO points, every catalogue candidate fitted with its held-out folds), which
//! `diagnose/tests/bifurcation.rs` checks for correctness only; `bristol_9_points` with the
//! default difference Jacobians, `bristol_9_points_sensitivities` with the smooth objective
//! fitted by the orbits' sensitivities (`FitJacobian::Sensitivities`, DECISIONS "The smooth
//! bifurcation-level objective, round 33").
//!
//! Run: `cargo bench --bench diagnose` (`-- bifurcation` for the second group only).

use benchmark::blind::{generate, BlindEffect, BlindScenario};
use criterion::{criterion_group, criterion_main, Criterion};
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

fn bench_bifurcation(c: &mut Criterion) {
    use aeroelastic::files::{LoadedModel, StructureFile};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let sf = StructureFile::read(&root.join("../scenarios/bristol-spring1.structure.toml"))
        .expect("structure");
    let model = LoadedModel::load(
        &root.join("../scenarios/bristol-spring1.model.toml"),
        sf.chord,
    )
    .expect("model");
    let st = aeroelastic::structure::Structure::from_modal(&sf.linear).expect("modal");
    let section =
        aeroelastic::section::Section::new(st, model.model, sf.air_density).expect("section");
    let points = aeroelastic::branch::read_measured_amplitudes(
        &root.join("../diagnose/tests/data/bristol-spring1-record-points.csv"),
    )
    .expect("points");
    let opts = diagnose::bifurcation::BifurcationOptions::default();
    let mut g = c.benchmark_group("bifurcation");
    g.sample_size(10);
    g.bench_function("bristol_9_points", |b| {
        b.iter(|| {
            diagnose::bifurcation::diagnose_branches(
                &points,
                &section,
                None,
                vec![],
                &opts,
                vec![],
                "bench",
            )
            .unwrap()
        })
    });
    let sens = diagnose::bifurcation::BifurcationOptions {
        jacobian: diagnose::bifurcation::FitJacobian::Sensitivities,
        ..diagnose::bifurcation::BifurcationOptions::default()
    };
    g.bench_function("bristol_9_points_sensitivities", |b| {
        b.iter(|| {
            diagnose::bifurcation::diagnose_branches(
                &points,
                &section,
                None,
                vec![],
                &sens,
                vec![],
                "bench",
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench, bench_bifurcation);
criterion_main!(benches);
