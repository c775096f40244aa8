//! The FFT plans against a direct DFT, and a shared plan against itself planned again
//! after other lengths (the library has no unit-test copy: Cargo.toml).

use fft::{forward, forward_and_inverse, inverse};

/// X_k = Σ_j x_j e^{−2πijk/n}, directly.
fn dft(x: &[f64]) -> Vec<(f64, f64)> {
    let n = x.len();
    (0..=n / 2)
        .map(|k| {
            x.iter().enumerate().fold((0.0, 0.0), |(re, im), (j, v)| {
                let a = -std::f64::consts::TAU * (j * k) as f64 / n as f64;
                (re + v * a.cos(), im + v * a.sin())
            })
        })
        .collect()
}

/// Lengths with the odd-sized butterflies and a power of two: the forward plan equals the
/// direct DFT to 1e-9 of the signal's sum of magnitudes, and the inverse gives back n·x.
#[test]
fn forward_is_the_dft_and_inverse_gives_back_n_times_the_signal() {
    for n in [16, 2 * 3 * 29, 5 * 31, 1024] {
        let x: Vec<f64> = (0..n).map(|j| ((j * 7919) % 101) as f64 - 50.0).collect();
        let scale: f64 = x.iter().map(|v| v.abs()).sum();
        let (fwd, inv) = forward_and_inverse(n);
        let mut input = x.clone();
        let mut spec = fwd.make_output_vec();
        fwd.process(&mut input, &mut spec).unwrap();
        assert_eq!(spec.len(), n / 2 + 1);
        for (k, (z, d)) in spec.iter().zip(dft(&x)).enumerate() {
            assert!(
                (z.re - d.0).abs() < 1e-9 * scale && (z.im - d.1).abs() < 1e-9 * scale,
                "n {n} bin {k}: {z} against {d:?}"
            );
        }
        let mut back = inv.make_output_vec();
        inv.process(&mut spec, &mut back).unwrap();
        for (a, b) in back.iter().zip(&x) {
            assert!((a - n as f64 * b).abs() < 1e-9 * scale, "n {n}");
        }
    }
}

/// A plan taken again after other lengths were planned is the same transform, bit for bit.
#[test]
fn a_shared_plan_gives_the_same_bits_every_time() {
    let n = 2 * 3 * 29;
    let x: Vec<f64> = (0..n).map(|j| (j as f64 * 0.37).sin()).collect();
    let run = |plan: &std::sync::Arc<dyn fft::RealToComplex<f64>>| {
        let mut input = x.clone();
        let mut spec = plan.make_output_vec();
        plan.process(&mut input, &mut spec).unwrap();
        spec
    };
    let first = run(&forward(n));
    let _ = (forward(4096), inverse(4096), inverse(n));
    let again = run(&forward(n));
    assert!(first
        .iter()
        .zip(&again)
        .all(|(p, q)| p.re.to_bits() == q.re.to_bits() && p.im.to_bits() == q.im.to_bits()));
}

/// A spectrum with a non-zero imaginary DC bin is refused by the inverse, not inverted.
#[test]
fn an_inverse_of_a_non_real_dc_bin_is_an_error() {
    let inv = inverse(8);
    let mut spec = inv.make_input_vec();
    spec[0].im = 1.0;
    let mut out = inv.make_output_vec();
    assert!(inv.process(&mut spec, &mut out).is_err());
}
