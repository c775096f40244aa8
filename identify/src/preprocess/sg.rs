//! Savitzky–Golay smoothing differentiator with asymmetric end windows.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use crate::numerics::{cholesky_solve, PivotFloor};
use crate::{Error, Result};

/// Weights `w` such that `Σⱼ wⱼ x[j]` is the first derivative (per sample) at position
/// `c` of the least-squares polynomial of degree `order` through the `len` samples.
fn derivative_weights(len: usize, c: usize, order: usize) -> Option<Vec<f64>> {
    let p = order + 1;
    let scale = ((len - 1) as f64 / 2.0).max(1.0);
    let z: Vec<f64> = (0..len).map(|j| (j as f64 - c as f64) / scale).collect();
    let mut g = vec![0.0; p * p];
    for &zj in &z {
        let mut pow = vec![1.0; p];
        for k in 1..p {
            pow[k] = pow[k - 1] * zj;
        }
        for r in 0..p {
            for s in 0..=r {
                g[r * p + s] += pow[r] * pow[s];
            }
        }
    }
    // g_coef = G⁻¹ e₁ (coefficient of z¹); the derivative at z = 0 is that coefficient.
    let mut e1 = vec![0.0; p];
    e1[1] = 1.0;
    if cholesky_solve(
        &mut g,
        p,
        &mut e1,
        1,
        PivotFloor::RelativeToLargestDiagonal(1e-13),
    )
    .is_err()
    {
        return None;
    }
    Some(
        z.iter()
            .map(|&zj| {
                let mut pow = 1.0;
                let mut s = 0.0;
                for v in &e1 {
                    s += v * pow;
                    pow *= zj;
                }
                s / scale
            })
            .collect(),
    )
}

/// The weights of one window (`2·half_window + 1` samples, polynomial degree `order`):
/// the centred window's, and for every position `c` of an end sample the off-centre ones
/// (`ends[c]`, derivative at position `c`; `ends[m]` is unused and empty).
#[derive(Debug)]
struct WindowWeights {
    centre: Vec<f64>,
    ends: Vec<Vec<f64>>,
}

/// The weights of every (half window, degree) computed so far ([`window_weights`]).
type WeightCache = Mutex<HashMap<(usize, usize), Arc<WindowWeights>>>;

/// Most windows kept by [`window_weights`] (a run uses one or two; beyond this the weights
/// are computed and not kept, so the cache stays bounded).
const WEIGHT_CACHE_MAX: usize = 32;

/// The weights of [`savitzky_golay_derivative`] for (`half_window`, `order`), computed once
/// per process and shared (they depend on nothing else; the free-response diagnosis
/// differentiates hundreds of series with the same window, and computing the 2·half_window
/// end weights was two thirds of each call, DECISIONS round 32). `None` when a window's normal
/// equations are singular.
fn window_weights(half_window: usize, order: usize) -> Option<Arc<WindowWeights>> {
    static CACHE: OnceLock<WeightCache> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(w) = cache
        .lock()
        .ok()
        .and_then(|c| c.get(&(half_window, order)).cloned())
    {
        return Some(w);
    }
    let len = 2 * half_window + 1;
    let m = half_window;
    let centre = derivative_weights(len, m, order)?;
    let mut ends = vec![Vec::new(); len];
    for c in 0..m {
        ends[c] = derivative_weights(len, c, order)?;
        ends[len - 1 - c] = derivative_weights(len, len - 1 - c, order)?;
    }
    let w = Arc::new(WindowWeights { centre, ends });
    if let Ok(mut c) = cache.lock() {
        if c.len() < WEIGHT_CACHE_MAX {
            c.entry((half_window, order)).or_insert_with(|| w.clone());
        }
    }
    Some(w)
}

/// Outputs computed side by side in the interior of [`savitzky_golay_derivative`].
const LANES: usize = 8;

/// Σⱼ wⱼ xⱼ in order (the reference of the interior's side-by-side sums).
fn window_sum(w: &[f64], x: &[f64]) -> f64 {
    w.iter().zip(x).map(|(a, b)| a * b).sum::<f64>()
}

/// First derivative of `x` (sampled every `dt` s) by a Savitzky–Golay smoothing
/// differentiator: at every sample, the least-squares polynomial of degree `order` over a
/// window of `2·half_window + 1` samples is differentiated. In the interior the window is
/// centred; within `half_window` samples of either end the same-length window is anchored
/// at the end and the polynomial is differentiated off-centre (asymmetric fit), so every
/// sample gets a derivative and none is dropped. Units: `x` units per second.
///
/// # Errors
/// [`Error::InvalidOption`] when `order` is 0 or `order ≥ 2·half_window + 1` (fewer
/// samples than coefficients), `half_window` is 0, or `dt` is not finite and positive;
/// [`Error::InvalidData`] (field `x`) when `x` is shorter than the window or has a
/// non-finite value.
pub fn savitzky_golay_derivative(
    x: &[f64],
    dt: f64,
    half_window: usize,
    order: usize,
) -> Result<Vec<f64>> {
    let len = 2 * half_window + 1;
    if half_window == 0 || order == 0 || order >= len {
        return Err(Error::InvalidOption {
            name: "savitzky_golay".into(),
            message: format!(
                "half_window {half_window}, order {order}: need half_window ≥ 1 and \
                 1 ≤ order < 2·half_window + 1 = {len}"
            ),
        });
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Error::InvalidOption {
            name: "dt".into(),
            message: format!("{dt} s must be finite and > 0"),
        });
    }
    let n = x.len();
    if n < len {
        return Err(Error::InvalidData {
            case: String::new(),
            field: "x".into(),
            message: format!("{n} samples, shorter than the Savitzky–Golay window of {len}"),
        });
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::InvalidData {
            case: String::new(),
            field: "x".into(),
            message: format!("non-finite value {} at sample {i}", x[i]),
        });
    }
    let numerical = || Error::Numerical {
        context: "savitzky_golay_derivative".into(),
        message: format!("singular normal equations (window {len}, order {order})"),
    };
    let m = half_window;
    let mut out = vec![0.0; n];
    let wts = window_weights(half_window, order).ok_or_else(numerical)?;
    let centre = &wts.centre;
    // interior: LANES outputs at a time, each its own sum in the window's order from −0.0
    // (the start of `Iterator::sum` for f64), so every output is bit for bit the sequential
    // sum below, with LANES independent additions in flight instead of one
    let mut i = m;
    while i + LANES <= n - m {
        let mut acc = [-0.0f64; LANES];
        for (j, &c) in centre.iter().enumerate() {
            let xs = &x[i - m + j..i - m + j + LANES];
            for l in 0..LANES {
                acc[l] += c * xs[l];
            }
        }
        for (o, a) in out[i..i + LANES].iter_mut().zip(acc) {
            *o = a / dt;
        }
        i += LANES;
    }
    for i in i..n - m {
        out[i] = window_sum(centre, &x[i - m..=i + m]) / dt;
    }
    for c in 0..m {
        out[c] = wts.ends[c]
            .iter()
            .zip(&x[..len])
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / dt;
        out[n - 1 - c] = wts.ends[len - 1 - c]
            .iter()
            .zip(&x[n - len..])
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / dt;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn interior_lanes_are_the_sequential_sum_bit_for_bit() {
        // lengths around the lane count, zeros (the sign of an all-zero sum), mixed scales
        let mut rng = ChaCha8Rng::seed_from_u64(43);
        let nrm = Normal::new(0.0, 1.0).unwrap();
        for (n, hw, order) in [
            (31usize, 15usize, 3usize),
            (40, 5, 2),
            (203, 12, 4),
            (1000, 50, 3),
        ] {
            for zeros in [false, true] {
                let x: Vec<f64> = (0..n)
                    .map(|i| {
                        if zeros {
                            0.0
                        } else {
                            nrm.sample(&mut rng) * 10f64.powi((i % 7) as i32 - 3)
                        }
                    })
                    .collect();
                let dt = 1.0 / 512.0;
                let d = savitzky_golay_derivative(&x, dt, hw, order).unwrap();
                let w = derivative_weights(2 * hw + 1, hw, order).unwrap();
                for i in hw..n - hw {
                    let want = window_sum(&w, &x[i - hw..=i + hw]) / dt;
                    assert_eq!(d[i].to_bits(), want.to_bits(), "n {n} hw {hw} sample {i}");
                }
            }
        }
    }
    #[test]
    fn cached_window_weights_are_the_direct_ones_bit_for_bit() {
        for (hw, order) in [(3usize, 2usize), (12, 4), (40, 3)] {
            let len = 2 * hw + 1;
            // first call computes, second comes from the cache: both the direct weights
            for _ in 0..2 {
                let w = window_weights(hw, order).unwrap();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let direct = |c: usize| bits(&derivative_weights(len, c, order).unwrap());
                assert_eq!(bits(&w.centre), direct(hw));
                for c in (0..hw).chain(hw + 1..len) {
                    assert_eq!(bits(&w.ends[c]), direct(c), "hw {hw} position {c}");
                }
                assert!(w.ends[hw].is_empty());
            }
        }
        // a singular window (order ≥ samples) is refused, not cached as weights
        assert!(window_weights(1, 3).is_none());
    }
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};
    use std::f64::consts::PI;

    #[test]
    fn exact_for_polynomials_up_to_order_including_ends() {
        let dt = 0.01;
        let x: Vec<f64> = (0..50)
            .map(|i| {
                let t = i as f64 * dt;
                1.0 - 2.0 * t + 3.0 * t * t - 4.0 * t * t * t
            })
            .collect();
        let d = savitzky_golay_derivative(&x, dt, 4, 3).unwrap();
        for (i, v) in d.iter().enumerate() {
            let t = i as f64 * dt;
            let e = -2.0 + 6.0 * t - 12.0 * t * t;
            assert!((v - e).abs() < 1e-9, "{i}: {v} vs {e}");
        }
    }

    #[test]
    fn rejects_bad_options() {
        let x = vec![0.0; 10];
        assert!(matches!(
            savitzky_golay_derivative(&x, 0.1, 2, 5),
            Err(Error::InvalidOption { .. })
        ));
        assert!(matches!(
            savitzky_golay_derivative(&x, 0.1, 6, 2),
            Err(Error::InvalidData { .. })
        ));
    }

    /// Multi-sine with noise: the derivative error is small against the analytic one,
    /// including the end windows.
    /// Σ a·sin(2πft + φ) plus seeded Gaussian noise of std `sigma`, and its exact derivative.
    pub(super) fn noisy_multisine(
        comps: &[(f64, f64, f64)],
        sigma: f64,
        n: usize,
        dt: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let noise = Normal::new(0.0, sigma).unwrap();
        let t = |i: usize| i as f64 * dt;
        let x = (0..n)
            .map(|i| {
                comps
                    .iter()
                    .map(|&(a, f, p)| a * (2.0 * PI * f * t(i) + p).sin())
                    .sum::<f64>()
                    + noise.sample(&mut rng)
            })
            .collect();
        let dx = (0..n)
            .map(|i| {
                comps
                    .iter()
                    .map(|&(a, f, p)| a * 2.0 * PI * f * (2.0 * PI * f * t(i) + p).cos())
                    .sum::<f64>()
            })
            .collect();
        (x, dx)
    }

    #[test]
    fn multisine_with_noise_including_ends() {
        let dt = 1.0 / 512.0;
        let n = 5120;
        let comps = [(1.0, 0.9, 0.2), (0.6, 2.3, 1.0), (0.3, 4.1, 2.0)];
        let (x, exact) = noisy_multisine(&comps, 0.005, n, dt);
        let rms_v = (exact.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let d = savitzky_golay_derivative(
            &x,
            dt,
            super::super::DEFAULT_SG_HALF_WINDOW,
            super::super::DEFAULT_SG_ORDER,
        )
        .unwrap();
        let err: Vec<f64> = d.iter().zip(&exact).map(|(a, b)| a - b).collect();
        let rms_e = (err.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let hw = super::super::DEFAULT_SG_HALF_WINDOW;
        let ends = err[..hw].iter().chain(&err[n - hw..]);
        let (max_end, ss_end) = ends.fold((0.0f64, 0.0), |(m, s), v| (m.max(v.abs()), s + v * v));
        let rms_end = (ss_end / (2 * hw) as f64).sqrt();
        // Noise 0.5 % of the largest amplitude; expected rms error ≈ 0.8 %, ends a few %.
        assert!(
            rms_e / rms_v < 0.015,
            "rms relative error {}",
            rms_e / rms_v
        );
        assert!(rms_end / rms_v < 0.05, "rms end error {}", rms_end / rms_v);
        assert!(max_end / rms_v < 0.15, "max end error {}", max_end / rms_v);
    }
}

#[cfg(test)]
mod sweep {
    use super::tests::noisy_multisine;
    use super::*;

    /// Evidence for the default window/order: prints rms and end errors for a grid.
    #[test]
    #[ignore]
    fn sg_parameter_sweep() {
        let dt = 1.0 / 512.0;
        let n = 5120;
        for (label, comps, sigma) in [
            (
                "paper-like 2+1.3 Hz, noise 0.5%",
                vec![(1.0, 2.0, 0.2), (0.5, 1.3, 1.0)],
                0.005,
            ),
            (
                "multisine to 4.1 Hz, noise 0.5%",
                vec![(1.0, 0.9, 0.2), (0.6, 2.3, 1.0), (0.3, 4.1, 2.0)],
                0.005,
            ),
            (
                "multisine to 4.1 Hz, noise 2%",
                vec![(1.0, 0.9, 0.2), (0.6, 2.3, 1.0), (0.3, 4.1, 2.0)],
                0.02,
            ),
            ("free 6 Hz, noise 0.5%", vec![(1.0, 6.0, 0.2)], 0.005),
        ] {
            println!("{label}");
            let (x, ex) = noisy_multisine(&comps, sigma, n, dt);
            let rms_v = (ex.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
            for p in [2usize, 3, 4, 5] {
                let mut line = format!("  order {p}:");
                for m in [8usize, 12, 16, 25, 35, 50] {
                    if p > 2 * m {
                        continue;
                    }
                    let d = savitzky_golay_derivative(&x, dt, m, p).unwrap();
                    let e: Vec<f64> = d.iter().zip(&ex).map(|(a, b)| a - b).collect();
                    let rms = (e.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt() / rms_v;
                    let end = e[..m]
                        .iter()
                        .chain(&e[n - m..])
                        .fold(0.0f64, |a, v| a.max(v.abs()))
                        / rms_v;
                    line += &format!(" m{m}: {:.4}/{:.3}", rms, end);
                }
                println!("{line}");
            }
        }
    }
}
