//! Criterion benchmark of `identify::preprocess::prepare` on one demo-like forced case:
//! configuration D (f_α = 2.0 Hz, f_h = 1.3 Hz, 12° and 18 mm), 10 s at 512 Hz, pitch noise
//! 1e-4 rad, heave noise 8 µm, force noise 0.1 % (the `aeroform run` demo), with and
//! without the manifest frequencies.

use criterion::{criterion_group, criterion_main, Criterion};
use identify::preprocess::{prepare, PreprocessOptions};
use identify::record::{CaseMeta, SectionGeometry};
use identify::synthetic::{forced_record, HarmonicMotion, PolynomialLaw, Sampling};
use std::hint::black_box;

fn demo_case(with_freqs: bool) -> identify::record::Record {
    let section = SectionGeometry {
        chord: 0.25,
        span: 0.75,
        air_density: 1.225,
    };
    let motion = HarmonicMotion {
        freq_pitch: 2.0,
        freq_heave: 1.3,
        amp_pitch: 12f64.to_radians(),
        amp_heave: 0.018,
        mean_pitch: 0.0,
    };
    let mut meta = CaseMeta {
        id: "D-U8-A12".into(),
        wind_speed: 8.0,
        ..Default::default()
    };
    if with_freqs {
        meta.freq_pitch = Some(2.0);
        meta.freq_heave = Some(1.3);
    }
    forced_record(
        meta,
        &section,
        &motion,
        &PolynomialLaw::demo(),
        &Sampling::default(),
        7,
    )
    .expect("valid demo case")
}

fn bench(c: &mut Criterion) {
    let opts = PreprocessOptions::default();
    for (name, with) in [
        ("prepare_10s_512Hz_manifest_freqs", true),
        ("prepare_10s_512Hz_spectral_freqs", false),
    ] {
        let rec = demo_case(with);
        c.bench_function(name, |b| {
            b.iter(|| prepare(black_box(&rec), &opts).expect("prepare"))
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
