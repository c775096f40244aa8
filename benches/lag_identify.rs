//! Criterion benchmark of the lag-law identification (`identify::lag::fit`, issue 41) on a
//! 50-case campaign, beside the memoryless identification (`identify::pipeline::identify`,
//! default settings) of the same cases: the default law (fixed rate share 0, no pressure
//! lag) and the optioned law of the stall-flutter round trip (rate share c and pressure lag
//! τ_p fitted, `LagFitOptions::fit_rate_share` + `fit_pressure_lag`).
//!
//! Campaign: the project's stall truth (`aeroelastic::aero::DynamicStallAero::thin_plate`,
//! B = 0.25 m, a = −0.3, U = 10 m/s) pitching about a 15° mean: 10 reduced frequencies
//! K = 0.04 … 0.3 × 5 amplitudes 4° … 12°, 8 periods of 256 samples each (2048 samples per
//! case, 102 400 in all), 0.5 % noise on the forces.
//!
//! Run: `cargo bench --bench lag_identify`.

use std::time::Instant;

use aeroelastic::aero::{DynamicStallAero, Flow};
use aeroelastic::tunnel::{forced_forces, Motion, Sine};
use criterion::{criterion_group, criterion_main, Criterion};
use identify::lag::{fit, LagFitOptions};
use identify::pipeline::{identify, IdentifySettings};
use identify::record::{CaseMeta, Forcing, NondimCase};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const U: f64 = 10.0;
const CHORD: f64 = 0.25;
const RHO: f64 = 1.225;
const PER_CYCLE: usize = 256;
const CYCLES: usize = 8;

fn campaign() -> Vec<NondimCase> {
    let model = DynamicStallAero::thin_plate(CHORD, -0.3).unwrap();
    let flow = Flow { rho: RHO, u: U };
    let qd = 0.5 * RHO * U * U;
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let mut out = Vec::with_capacity(50);
    for i in 0..10 {
        let k = 0.04 + (0.3 - 0.04) * i as f64 / 9.0;
        for j in 0..5 {
            let amp = (4.0 + 2.0 * j as f64).to_radians();
            let f = k * U / (2.0 * std::f64::consts::PI * CHORD);
            let motion = Motion {
                pitch: vec![Sine {
                    freq: f,
                    amplitude: amp,
                    phase: 0.0,
                }],
                heave: vec![],
                mean_pitch: 15f64.to_radians(),
            };
            let dt = 1.0 / (f * PER_CYCLE as f64);
            let n = PER_CYCLE * CYCLES;
            let pre = 2.0 / f + 30.0 * CHORD / U;
            let (l, m) = forced_forces(&model, &flow, &motion, 0.0, dt, n, pre, "bench").unwrap();
            let (mut a, mut ad) = (Vec::with_capacity(n), Vec::with_capacity(n));
            for s in 0..n {
                let (q, v, _) = motion.eval(s as f64 * dt);
                a.push(q[1]);
                ad.push(CHORD * v[1] / U);
            }
            let mut cl: Vec<f64> = l.iter().map(|v| v / (qd * CHORD)).collect();
            let mut cm: Vec<f64> = m.iter().map(|v| v / (qd * CHORD * CHORD)).collect();
            for y in [&mut cl, &mut cm] {
                let sd = 0.005 * y.iter().map(|v| v * v).sum::<f64>().sqrt() / (n as f64).sqrt();
                let noise = Normal::new(0.0, sd).unwrap();
                for v in y.iter_mut() {
                    *v += noise.sample(&mut rng);
                }
            }
            out.push(NondimCase {
                meta: CaseMeta {
                    id: format!("k{i}a{j}"),
                    wind_speed: U,
                    mean_pitch: Some(15f64.to_radians()),
                    amplitude: Some(amp),
                    freq_pitch: Some(f),
                    ..CaseMeta::default()
                },
                dt,
                chord: CHORD,
                x: [a, ad, vec![0.0; n], vec![0.0; n]],
                c_lift: cl,
                c_moment: cm,
                forcing: Forcing {
                    pitch: Some(f),
                    heave: None,
                },
            });
        }
    }
    out
}

fn bench(c: &mut Criterion) {
    let cases = campaign();
    let opts = LagFitOptions::default();
    let settings = IdentifySettings::default();
    let t = Instant::now();
    let f = fit(&cases, &opts).unwrap();
    let lag_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    identify(&cases, &settings, "bench", &|_| {}).unwrap();
    let mem_s = t.elapsed().as_secs_f64();
    let optioned = LagFitOptions {
        fit_rate_share: true,
        fit_pressure_lag: true,
        ..LagFitOptions::default()
    };
    let t = Instant::now();
    let fo = fit(&cases, &optioned).unwrap();
    let opt_s = t.elapsed().as_secs_f64();
    let line = |name: &str, s: f64, f: &identify::lag::LagFit| {
        let n = f.report.cases.len() as f64;
        eprintln!(
            "one pass: {name} {s:.3} s ({} LM iterations; τ₁ {:.3} τ₂ {:.3} α* {:.2}° m {:.2} c {:.3} τ_p {:.3}; mean R² lift {:.4} moment {:.4}; objective {:.5})",
            f.report.iterations,
            f.law.tau1,
            f.law.tau2,
            f.law.alpha_star.to_degrees(),
            f.law.sharpness,
            f.law.rate_share,
            f.law.pressure_lag,
            f.report.cases.iter().map(|c| c.r2_lift).sum::<f64>() / n,
            f.report.cases.iter().map(|c| c.r2_moment).sum::<f64>() / n,
            f.report.objective,
        );
    };
    line("lag law", lag_s, &f);
    line("lag law with fitted c and τ_p", opt_s, &fo);
    eprintln!("one pass: memoryless {mem_s:.3} s");
    let mut g = c.benchmark_group("lag_identify");
    g.sample_size(10);
    g.bench_function("lag law, 50 cases x 2048 samples", |b| {
        b.iter(|| fit(&cases, &opts).unwrap())
    });
    g.bench_function("lag law fitted c and tau_p, 50 cases x 2048 samples", |b| {
        b.iter(|| fit(&cases, &optioned).unwrap())
    });
    g.bench_function("memoryless, 50 cases x 2048 samples", |b| {
        b.iter(|| identify(&cases, &settings, "bench", &|_| {}).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
