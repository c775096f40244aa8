//! Criterion benchmark of a 100-speed LCO sweep (≥ 200 response cycles per speed, fixed
//! duration, rtol 1e-8 / atol 1e-10) of the HP-1 section with Theodorsen–Jones
//! aerodynamics and a cubic pitch spring — the same work as
//! `benches/peers/lco_scipy.py` does with scipy's DOP853.

use criterion::{criterion_group, criterion_main, Criterion};

use aeroelastic::flutter::{FlutterMethod, FlutterOptions};
use aeroelastic::lco::LcoOptions;
use aeroelastic::reference::hp1_cubic_pitch;

fn lco_sweep(c: &mut Criterion) {
    let s = hp1_cubic_pitch();
    let fo = FlutterOptions {
        u_min: 0.05,
        u_max: 4.0,
        n_speeds: 80,
        tol_rel: 1e-10,
    };
    let uf = s
        .flutter(FlutterMethod::P, &fo)
        .expect("flutter")
        .flutter
        .expect("flutter point")
        .u;
    let speeds: Vec<f64> = (0..100)
        .map(|i| uf * (0.8 + 0.5 * i as f64 / 99.0))
        .collect();
    let opts = LcoOptions {
        rtol: 1e-8,
        atol: 1e-10,
        max_periods: 200.0 / 0.64,
        stop_when_classified: false,
        ..LcoOptions::default()
    };
    let y0 = s.perturbation(0.05);
    let mut g = c.benchmark_group("lco");
    g.sample_size(10);
    g.bench_function("sweep_100_speeds_200_cycles_sequential", |b| {
        b.iter(|| {
            speeds
                .iter()
                .map(|&u| s.lco_run(u, &y0, &opts).expect("run").rhs_evals)
                .sum::<u64>()
        })
    });
    g.bench_function("sweep_100_speeds_200_cycles_parallel", |b| {
        b.iter(|| {
            s.lco_scan_parallel(&speeds, &y0, &opts, &|_| {})
                .expect("scan")
                .len()
        })
    });
    g.finish();
}

criterion_group!(benches, lco_sweep);
criterion_main!(benches);
