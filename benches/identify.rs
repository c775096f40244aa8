//! Criterion benchmark of the whole identification (`identify::pipeline::identify`).
//!
//! 448 synthetic cases on the paper's Tables I/II: the 7 configurations of
//! `aeroelastic::tunnel::paper_configurations` (frequencies, r_A, G at a 3° mean angle, which
//! takes the mean-angle centring path) × 8 pitch amplitudes (3° … 24°) × 8 wind speeds
//! (3 … 10 m/s), B = 0.25 m, 10 s at 512 Hz, an Eq. 19-like law plus 1 % noise.
//! Full `identify()`: 30-term library, identifiability, group STLSQ by configuration, 50-value
//! δ path and metrics. Before the criterion run, one timed pass of each stage (library,
//! QR factor, harmonic projection) is printed to show where the time goes.
//!
//! A second group compares, side by side, the two ways a 5-fold cross-validation (the
//! diagnosis's force level) can identify its training sets on 28 of those cases: a full
//! `identify()` per fold, and the staged API (`prepare` once, `Prepared::identify` per fold).
//!
//! A third group, `stream`, times the hot path of `aeroform identify` on files: parsing one
//! case CSV of 10 s (`read_case_csv_stamped`: one buffered pass, fingerprint included) and
//! the streaming pass over the 64 cases of configuration D (`stream_pass`) of the plate truth written to a
//! temporary folder (`workflow::prepare_streaming`: read, preprocess, prepare case by case).
//!
//! Run: `cargo bench --bench identify` (`-- stream` for the third group alone).

use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use identify::identifiability::priority_order;
use identify::library::{Library, LibraryKind};
use identify::metrics::{candidate_tones, HarmonicProjector};
use identify::pipeline::{identify, prepare, IdentifySettings};
use identify::record::{CaseMeta, Forcing, NondimCase};
use identify::regress::CaseFactor;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const FS: f64 = 512.0;
const DURATION: f64 = 10.0;
const CHORD: f64 = 0.25;

fn synthetic_cases() -> Vec<NondimCase> {
    let n = (FS * DURATION) as usize;
    let tau = 2.0 * std::f64::consts::PI;
    let mut out = Vec::with_capacity(448);
    for (c, cfg) in aeroelastic::tunnel::paper_configurations()
        .iter()
        .enumerate()
    {
        let (fa, fh) = (cfg.freq_pitch, cfg.freq_heave);
        let mean = cfg.mean_pitch_deg.to_radians();
        for a in 0..8 {
            let amp_deg = 3.0 + 3.0 * a as f64;
            let amp = amp_deg.to_radians();
            let h_amp = cfg.amplitude_ratio * amp_deg * 1e-3; // m
            for u in 0..8 {
                let wind = 3.0 + u as f64;
                let mut rng = ChaCha8Rng::seed_from_u64((c * 64 + a * 8 + u) as u64);
                let t: Vec<f64> = (0..n).map(|i| i as f64 / FS).collect();
                let x: [Vec<f64>; 4] = [
                    t.iter()
                        .map(|t| mean + amp * (tau * fa * t).sin())
                        .collect(),
                    t.iter()
                        .map(|t| CHORD / wind * amp * tau * fa * (tau * fa * t).cos())
                        .collect(),
                    t.iter()
                        .map(|t| h_amp / CHORD * (tau * fh * t + 0.5).sin())
                        .collect(),
                    t.iter()
                        .map(|t| h_amp / wind * tau * fh * (tau * fh * t + 0.5).cos())
                        .collect(),
                ];
                let (ka, kh) = (CHORD * tau * fa / wind, CHORD * tau * fh / wind);
                // moment: Eq. 19 form with A1..A4, N1, N2; lift: H1..H4 and N1
                let m: Vec<f64> = (0..n)
                    .map(|i| {
                        kh * 0.4 * x[3][i] - ka * 0.3 * x[1][i]
                            + ka * ka * 1.2 * x[0][i]
                            + kh * kh * 0.2 * x[2][i]
                            + ka.powi(3) * 0.8 * x[0][i] * x[1][i]
                            - ka.powi(6) * 3.0 * x[0][i].powi(3)
                    })
                    .collect();
                let l: Vec<f64> = (0..n)
                    .map(|i| {
                        -kh * 2.5 * x[3][i] - ka * 1.5 * x[1][i] - ka * ka * 4.0 * x[0][i]
                            + kh * kh * 0.5 * x[2][i]
                            + ka.powi(3) * 1.5 * x[0][i] * x[1][i]
                    })
                    .collect();
                let rms =
                    |v: &[f64]| (v.iter().map(|a| a * a).sum::<f64>() / v.len() as f64).sqrt();
                let (nm, nl) = (
                    Normal::new(0.0, 0.01 * rms(&m)).unwrap(),
                    Normal::new(0.0, 0.01 * rms(&l)).unwrap(),
                );
                let c_moment = m.iter().map(|v| v + nm.sample(&mut rng)).collect();
                let c_lift = l.iter().map(|v| v + nl.sample(&mut rng)).collect();
                out.push(NondimCase {
                    meta: CaseMeta {
                        id: format!(
                            "{}-A{:02}-U{:02}",
                            (b'A' + c as u8) as char,
                            3 + 3 * a,
                            3 + u
                        ),
                        wind_speed: wind,
                        config: Some(((b'A' + c as u8) as char).to_string()),
                        amplitude: Some(amp),
                        freq_pitch: Some(fa),
                        freq_heave: Some(fh),
                        mean_pitch: (mean != 0.0).then_some(mean),
                        ..CaseMeta::default()
                    },
                    dt: 1.0 / FS,
                    chord: CHORD,
                    x,
                    c_lift,
                    c_moment,
                    forcing: Forcing {
                        pitch: Some(fa),
                        heave: Some(fh),
                    },
                });
            }
        }
    }
    out
}

/// One sequential pass of the per-case stages, to show where the time goes.
fn stage_breakdown(cases: &[NondimCase]) {
    let lib = Library::new(LibraryKind::Paper30, false);
    let order = priority_order(&lib);
    let (mut t_lib, mut t_qr, mut t_harm) = (0.0, 0.0, 0.0);
    for c in cases {
        let t0 = Instant::now();
        let theta = lib.evaluate(&c.x);
        let t1 = Instant::now();
        let f = CaseFactor::new(
            &c.meta.id,
            theta.as_ref(),
            &order,
            &[&c.c_moment, &c.c_lift],
        )
        .unwrap();
        let t2 = Instant::now();
        let tones = candidate_tones(&c.forcing, 5, c.len() as f64 * c.dt, c.dt);
        let freqs: Vec<f64> = tones.iter().map(|t| t.freq).collect();
        let h = HarmonicProjector::new(&freqs, c.len(), c.dt).unwrap();
        let cols = h.column_amplitudes(theta.as_ref());
        let t3 = Instant::now();
        std::hint::black_box((&f, &cols));
        t_lib += (t1 - t0).as_secs_f64();
        t_qr += (t2 - t1).as_secs_f64();
        t_harm += (t3 - t2).as_secs_f64();
    }
    println!(
        "sequential per-case stages over {} cases: library {:.3} s, QR factor {:.3} s, harmonic projection {:.3} s",
        cases.len(),
        t_lib,
        t_qr,
        t_harm
    );
    let t = Instant::now();
    let id = identify(cases, &IdentifySettings::default(), "bench", &|_| {}).unwrap();
    println!(
        "one identify() run ({} cores available): {:.3} s; group A moment support {:?}",
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
        t.elapsed().as_secs_f64(),
        id.groups[0].moment.support
    );
}

fn bench(c: &mut Criterion) {
    let cases = synthetic_cases();
    stage_breakdown(&cases);
    let settings = IdentifySettings::default();
    let mut g = c.benchmark_group("identify");
    g.sample_size(10);
    g.bench_function(
        "448 cases x 10 s x 512 Hz, Paper30, group STLSQ, 50 deltas",
        |b| b.iter(|| identify(&cases, &settings, "bench", &|_| {}).unwrap()),
    );
    g.finish();

    // 5 folds over the first configuration's first 28 cases; fold k holds out i % 5 == k
    let first = cases[0].meta.config.clone();
    let cv: Vec<NondimCase> = cases
        .iter()
        .filter(|c| c.meta.config == first)
        .take(28)
        .cloned()
        .collect();
    let train = |k: usize| -> Vec<usize> { (0..cv.len()).filter(|i| i % 5 != k).collect() };
    let mut g = c.benchmark_group("five_folds");
    g.sample_size(10);
    g.bench_function("identify per fold", |b| {
        b.iter(|| {
            for k in 0..5 {
                let fold: Vec<NondimCase> = train(k).iter().map(|&i| cv[i].clone()).collect();
                identify(&fold, &settings, "bench", &|_| {}).unwrap();
            }
        })
    });
    g.bench_function("prepare once, identify subsets", |b| {
        b.iter(|| {
            let p = prepare(&cv, &settings, &|_| {}).unwrap();
            for k in 0..5 {
                p.identify(&train(k), "bench", &|_| {}).unwrap();
            }
        })
    });
    g.finish();
}

/// The configuration-D campaign of the plate truth (64 cases × 10 s), written to `dir`.
fn written_campaign(dir: &std::path::Path) {
    use aeroelastic::files::LoadedModel;
    use aeroelastic::tunnel::{self, Campaign, ForcedOptions};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let truth = LoadedModel::load(&root.join("../scenarios/plate-truth.model.toml"), None)
        .unwrap()
        .nonlinear
        .unwrap();
    let campaign = Campaign::paper_config("D").unwrap();
    let opts = ForcedOptions::paper(1);
    let (manifest, records) =
        tunnel::forced_dataset(&truth, &campaign.cases(), &opts, &|_| {}).unwrap();
    tunnel::write(dir, &manifest, &records).unwrap();
}

fn bench_stream(c: &mut Criterion) {
    use identify::dataset::{read_case_csv_stamped, ReadOptions};
    use identify::preprocess::PreprocessOptions;
    use identify::workflow::prepare_streaming;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    written_campaign(&dir);
    let m = identify::dataset::read_dataset(&dir).unwrap().manifest;
    let file = dir.join(&m.cases[0].file);
    let bytes = std::fs::metadata(&file).unwrap().len();
    let settings = IdentifySettings::default();
    let mut g = c.benchmark_group("stream");
    g.sample_size(10);
    g.throughput(criterion::Throughput::Bytes(bytes));
    g.bench_function("parse one case CSV (10 s, 512 Hz)", |b| {
        b.iter(|| read_case_csv_stamped(&file, true).unwrap())
    });
    g.finish();
    let mut g = c.benchmark_group("stream_pass");
    g.sample_size(10);
    g.bench_function("prepare_streaming, 64 cases x 10 s", |b| {
        b.iter(|| {
            prepare_streaming(
                &dir,
                &ReadOptions::default(),
                &PreprocessOptions::default(),
                &settings,
                &|_| {},
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench, bench_stream);
criterion_main!(benches);
