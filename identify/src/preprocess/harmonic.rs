//! Least-squares harmonic fits, frequency refinement, spectral peaks and a noise estimate.
//!
//! Time inside a record is `t = i·dt` (seconds since the first sample): the fits and
//! their [`HarmonicFit::value`] / [`HarmonicFit::derivative`] use that time base.

use std::f64::consts::PI;

use realfft::RealFftPlanner;

use super::linsolve::cholesky_solve;
use crate::{Error, Result};

/// `cos(ω i dt), sin(ω i dt)` for i = 0, 1, 2, … by rotation, re-synchronised exactly
/// every 64 samples so that rounding does not drift.
struct Phasor {
    w: f64,
    cd: f64,
    sd: f64,
    i: usize,
    c: f64,
    s: f64,
}

impl Phasor {
    fn new(w: f64) -> Self {
        let (sd, cd) = w.sin_cos();
        Phasor {
            w,
            cd,
            sd,
            i: 0,
            c: 1.0,
            s: 0.0,
        }
    }

    /// The current (cos, sin), then advance one sample.
    #[inline]
    fn next(&mut self) -> (f64, f64) {
        let out = (self.c, self.s);
        self.i += 1;
        if self.i.is_multiple_of(64) {
            let (s, c) = (self.w * self.i as f64).sin_cos();
            self.c = c;
            self.s = s;
        } else {
            let c = self.c * self.cd - self.s * self.sd;
            self.s = self.s * self.cd + self.c * self.sd;
            self.c = c;
        }
        out
    }
}

/// Least-squares fit of `mean + Σₖ cosₖ·cos(2π fₖ t) + sinₖ·sin(2π fₖ t)` to a signal.
#[derive(Debug, Clone, PartialEq)]
pub struct HarmonicFit {
    /// Constant term (signal units).
    pub mean: f64,
    /// Frequencies fₖ [Hz].
    pub freqs: Vec<f64>,
    /// Cosine coefficients aₖ (signal units).
    pub cos: Vec<f64>,
    /// Sine coefficients bₖ (signal units).
    pub sin: Vec<f64>,
    /// Root-mean-square residual of the fit (signal units).
    pub rms_residual: f64,
}

impl HarmonicFit {
    /// The fitted signal at time `t` [s] since the first sample.
    pub fn value(&self, t: f64) -> f64 {
        let mut v = self.mean;
        for k in 0..self.freqs.len() {
            let (s, c) = (2.0 * PI * self.freqs[k] * t).sin_cos();
            v += self.cos[k] * c + self.sin[k] * s;
        }
        v
    }

    /// The time derivative of the fitted signal at `t` [s] (signal units per second):
    /// `Σₖ 2π fₖ (−aₖ sin(2π fₖ t) + bₖ cos(2π fₖ t))`.
    pub fn derivative(&self, t: f64) -> f64 {
        let mut v = 0.0;
        for k in 0..self.freqs.len() {
            let w = 2.0 * PI * self.freqs[k];
            let (s, c) = (w * t).sin_cos();
            v += w * (-self.cos[k] * s + self.sin[k] * c);
        }
        v
    }

    /// Amplitude √(aₖ² + bₖ²) of the k-th component.
    pub fn amplitude(&self, k: usize) -> f64 {
        self.cos[k].hypot(self.sin[k])
    }

    /// Values at `t = i·dt`, i = 0..n (by phasor rotation: O(n·K)).
    pub fn values(&self, n: usize, dt: f64) -> Vec<f64> {
        let mut v = vec![self.mean; n];
        for k in 0..self.freqs.len() {
            let mut ph = Phasor::new(2.0 * PI * self.freqs[k] * dt);
            for x in v.iter_mut() {
                let (c, s) = ph.next();
                *x += self.cos[k] * c + self.sin[k] * s;
            }
        }
        v
    }

    /// Derivatives at `t = i·dt`, i = 0..n.
    pub fn derivatives(&self, n: usize, dt: f64) -> Vec<f64> {
        let mut v = vec![0.0; n];
        for k in 0..self.freqs.len() {
            let w = 2.0 * PI * self.freqs[k];
            let mut ph = Phasor::new(w * dt);
            for x in v.iter_mut() {
                let (c, s) = ph.next();
                *x += w * (-self.cos[k] * s + self.sin[k] * c);
            }
        }
        v
    }
}

/// Normal equations of the basis `[1, cos 2πf₁t, sin 2πf₁t, …]` for several signals.
/// Returns the coefficient vectors and, per signal, the explained sum of squares `βᵀXᵀx`,
/// or `None` when the basis is numerically dependent (frequencies too close, or below the
/// record's resolution).
fn fit_basis(xs: &[&[f64]], dt: f64, freqs: &[f64]) -> Option<(Vec<Vec<f64>>, Vec<f64>)> {
    let p = 1 + 2 * freqs.len();
    let n = xs[0].len();
    let ns = xs.len();
    let mut g = vec![0.0; p * p];
    let mut b = vec![0.0; p * ns];
    let mut phasors: Vec<Phasor> = freqs
        .iter()
        .map(|f| Phasor::new(2.0 * PI * f * dt))
        .collect();
    let mut phi = vec![0.0; p];
    phi[0] = 1.0;
    for i in 0..n {
        for (k, ph) in phasors.iter_mut().enumerate() {
            let (c, s) = ph.next();
            phi[1 + 2 * k] = c;
            phi[2 + 2 * k] = s;
        }
        for r in 0..p {
            let pr = phi[r];
            for c in 0..=r {
                g[r * p + c] += pr * phi[c];
            }
        }
        for (s, x) in xs.iter().enumerate() {
            let xi = x[i];
            for r in 0..p {
                b[s * p + r] += phi[r] * xi;
            }
        }
    }
    let rhs = b.clone();
    if !cholesky_solve(&mut g, p, &mut b, ns) {
        return None;
    }
    let betas: Vec<Vec<f64>> = (0..ns).map(|s| b[s * p..(s + 1) * p].to_vec()).collect();
    let explained = (0..ns)
        .map(|s| (0..p).map(|r| betas[s][r] * rhs[s * p + r]).sum::<f64>())
        .collect();
    Some((betas, explained))
}

/// Least-squares fit of `mean + Σₖ aₖ cos(2π fₖ t) + bₖ sin(2π fₖ t)` to `x` sampled at
/// `t = i·dt`. Exact for records that are not a whole number of periods (it is a true
/// least-squares fit, not a DFT).
///
/// # Errors
/// [`Error::InvalidOption`] when `dt` or a frequency is not finite and positive;
/// [`Error::InvalidData`] when `x` has a non-finite value or fewer samples than
/// coefficients; [`Error::Numerical`] when the basis is numerically dependent (two
/// frequencies closer than the record resolves, or a frequency too low for its length).
pub fn harmonic_fit(x: &[f64], dt: f64, freqs: &[f64]) -> Result<HarmonicFit> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Error::InvalidOption {
            name: "dt".into(),
            message: format!("{dt} s must be finite and > 0"),
        });
    }
    if let Some(f) = freqs.iter().find(|f| !(f.is_finite() && **f > 0.0)) {
        return Err(Error::InvalidOption {
            name: "freqs".into(),
            message: format!("frequency {f} Hz must be finite and > 0"),
        });
    }
    let p = 1 + 2 * freqs.len();
    if x.len() < p {
        return Err(Error::InvalidData {
            case: String::new(),
            field: "x".into(),
            message: format!("{} samples for {p} coefficients", x.len()),
        });
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::InvalidData {
            case: String::new(),
            field: "x".into(),
            message: format!("non-finite value {} at sample {i}", x[i]),
        });
    }
    let (betas, _) = fit_basis(&[x], dt, freqs).ok_or_else(|| Error::Numerical {
        context: "harmonic_fit".into(),
        message: format!(
            "basis at {freqs:?} Hz is numerically dependent over {} s",
            x.len() as f64 * dt
        ),
    })?;
    let beta = &betas[0];
    let mut fit = HarmonicFit {
        mean: beta[0],
        freqs: freqs.to_vec(),
        cos: (0..freqs.len()).map(|k| beta[1 + 2 * k]).collect(),
        sin: (0..freqs.len()).map(|k| beta[2 + 2 * k]).collect(),
        rms_residual: 0.0,
    };
    let model = fit.values(x.len(), dt);
    let ss: f64 = x.iter().zip(&model).map(|(a, b)| (a - b) * (a - b)).sum();
    fit.rms_residual = (ss / x.len() as f64).sqrt();
    Ok(fit)
}

/// Fraction of the variance of the signals (each normalised by its own variance about
/// the mean, then summed) explained by a least-squares fit at `freqs`; −∞ when the basis
/// is dependent.
fn explained_fraction(xs: &[&[f64]], norms: &[f64], dt: f64, freqs: &[f64]) -> f64 {
    match fit_basis(xs, dt, freqs) {
        None => f64::NEG_INFINITY,
        Some((_, explained)) => explained.iter().zip(norms).map(|(e, n)| e / n).sum(),
    }
}

/// Golden-section maximisation of `f` on `[a, b]` to an absolute tolerance `tol`.
fn golden_max(mut a: f64, mut b: f64, tol: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - r * (b - a);
    let mut d = a + r * (b - a);
    let mut fc = f(c);
    let mut fd = f(d);
    for _ in 0..200 {
        if (b - a).abs() <= tol {
            break;
        }
        if fc >= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    if fc >= fd {
        c
    } else {
        d
    }
}

/// Signals centred on their mean, and their sums of squares (for normalisation).
fn centred(xs: &[&[f64]]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let mut out = Vec::with_capacity(xs.len());
    let mut norms = Vec::with_capacity(xs.len());
    for x in xs {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let c: Vec<f64> = x.iter().map(|v| v - m).collect();
        norms.push(c.iter().map(|v| v * v).sum::<f64>().max(f64::MIN_POSITIVE));
        out.push(c);
    }
    (out, norms)
}

/// Refines a frequency estimate `f0` [Hz] of the dominant sinusoid of `x` (sampled every
/// `dt` s): maximises the power of the least-squares fit of `mean + a cos 2πft + b sin 2πft`
/// (not a DFT, so it is exact for records that are not a whole number of periods). A grid
/// of 17 points over `f0 ± 1/T` (T = n·dt, the main-lobe half-width) picks the peak, then a
/// golden-section search on ± one grid step converges to 1e-9/T.
///
/// Returns `f0` unchanged when the input cannot be refined (`f0` or `dt` not finite and
/// positive, fewer than 4 samples, non-finite samples).
pub fn refine_frequency(x: &[f64], dt: f64, f0: f64) -> f64 {
    if !(f0.is_finite() && f0 > 0.0 && dt.is_finite() && dt > 0.0)
        || x.len() < 4
        || x.iter().any(|v| !v.is_finite())
    {
        return f0;
    }
    let (c, norms) = centred(&[x]);
    let xs = [c[0].as_slice()];
    refine_one(&xs, &norms, dt, &[f0], 0, 1.0)
}

/// Refines `freqs[k]` with the others fixed, maximising the summed explained fraction of
/// `xs`; the search covers `± span/T` around the current value.
fn refine_one(xs: &[&[f64]], norms: &[f64], dt: f64, freqs: &[f64], k: usize, span: f64) -> f64 {
    let n = xs[0].len();
    let t = n as f64 * dt;
    let nyq = 0.5 / dt;
    let f0 = freqs[k];
    let w = span / t;
    let lo_lim = 0.25 / t;
    let mut trial = freqs.to_vec();
    let mut obj = |f: f64| -> f64 {
        if !(f > lo_lim && f < nyq) {
            return f64::NEG_INFINITY;
        }
        trial[k] = f;
        explained_fraction(xs, norms, dt, &trial)
    };
    let steps = 16;
    let h = 2.0 * w / steps as f64;
    let mut best = (f0, obj(f0));
    for j in 0..=steps {
        let f = f0 - w + j as f64 * h;
        let v = obj(f);
        if v > best.1 {
            best = (f, v);
        }
    }
    let fb = best.0;
    let tol = 1e-9 / t;
    golden_max(fb - h, fb + h, tol, obj)
}

/// Joint refinement of several frequencies for several signals: coordinate ascent on the
/// summed explained fraction of a least-squares fit at all `freqs` (each signal normalised
/// by its variance). Removes the bias that a single-sinusoid refinement suffers from
/// leakage of the other components.
pub(crate) fn refine_frequencies(xs: &[&[f64]], dt: f64, freqs: &[f64]) -> Vec<f64> {
    let (c, norms) = centred(xs);
    let views: Vec<&[f64]> = c.iter().map(|v| v.as_slice()).collect();
    let mut f = freqs.to_vec();
    for pass in 0..4 {
        let span = if pass == 0 { 0.25 } else { 0.05 };
        let mut change = 0.0f64;
        for k in 0..f.len() {
            let new = refine_one(&views, &norms, dt, &f, k, span);
            change = change.max((new - f[k]).abs());
            f[k] = new;
        }
        if change * (xs[0].len() as f64 * dt) < 1e-8 {
            break;
        }
    }
    f
}

/// Fraction of the variance of `x` explained by one sinusoid at `f` (plus the mean), and its
/// amplitude.
pub(crate) fn sinusoid_share(x: &[f64], dt: f64, f: f64) -> Option<(f64, f64)> {
    let fit = harmonic_fit(x, dt, &[f]).ok()?;
    let m = x.iter().sum::<f64>() / x.len() as f64;
    let var: f64 = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len() as f64;
    let res2 = fit.rms_residual * fit.rms_residual;
    let share = if var > 0.0 { 1.0 - res2 / var } else { 0.0 };
    Some((share, fit.amplitude(0)))
}

/// Frequency [Hz] of the largest spectral peak of `x` (mean removed, Hann window, zero
/// padding to ≥ 4n points, parabolic interpolation of the peak), searching above `0.5/T`.
/// `None` for a constant signal or fewer than 4 samples.
pub fn dominant_frequency(x: &[f64], dt: f64) -> Option<f64> {
    let n = x.len();
    if n < 4 || dt.is_nan() || dt <= 0.0 {
        return None;
    }
    let m = x.iter().sum::<f64>() / n as f64;
    let len = (4 * n).next_power_of_two();
    let mut buf = vec![0.0; len];
    for (i, v) in x.iter().enumerate() {
        let w = 0.5 - 0.5 * (2.0 * PI * i as f64 / (n - 1) as f64).cos();
        buf[i] = (v - m) * w;
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(len);
    let mut spec = fft.make_output_vec();
    fft.process(&mut buf, &mut spec).ok()?;
    let mag: Vec<f64> = spec.iter().map(|c| c.norm()).collect();
    let df = 1.0 / (len as f64 * dt);
    let t = n as f64 * dt;
    let k_lo = ((0.5 / t) / df).ceil().max(1.0) as usize;
    let (k, &peak) = mag
        .iter()
        .enumerate()
        .skip(k_lo)
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    if peak.is_nan() || peak <= 0.0 {
        return None;
    }
    let mut off = 0.0;
    if k > 0 && k + 1 < mag.len() {
        let (a, b, c) = (mag[k - 1], mag[k], mag[k + 1]);
        let den = a - 2.0 * b + c;
        if den < 0.0 {
            off = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
        }
    }
    Some((k as f64 + off) * df)
}

/// Robust estimate of the standard deviation of white sensor noise in `x`: the median
/// absolute third difference, `σ̂ = 1.4826 · median|Δ³x| / √20` (Var Δ³ε = 20σ² for white
/// ε; a smooth signal contributes only ~(ω dt)³ of its amplitude).
pub fn noise_sigma(x: &[f64]) -> f64 {
    if x.len() < 8 {
        return 0.0;
    }
    let mut d: Vec<f64> = x
        .windows(4)
        .map(|w| (w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]).abs())
        .collect();
    let mid = d.len() / 2;
    let (_, &mut med, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    1.4826 * med / 20f64.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    fn signal(n: usize, dt: f64, comps: &[(f64, f64, f64)], sigma: f64, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 1.0).unwrap();
        (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                comps
                    .iter()
                    .map(|&(a, f, ph)| a * (2.0 * PI * f * t + ph).sin())
                    .sum::<f64>()
                    + sigma * noise.sample(&mut rng)
            })
            .collect()
    }

    #[test]
    fn phasor_matches_sin_cos() {
        let w = 0.0377;
        let mut ph = Phasor::new(w);
        for i in 0..5000 {
            let (c, s) = ph.next();
            let (se, ce) = (w * i as f64).sin_cos();
            assert!((c - ce).abs() < 1e-13 && (s - se).abs() < 1e-13, "{i}");
        }
    }

    #[test]
    fn harmonic_fit_recovers_coefficients_non_whole_periods() {
        let dt = 1.0 / 512.0;
        let n = (20.3 / dt) as usize;
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                0.3 + 1.5 * (2.0 * PI * 2.0 * t).cos() - 0.7 * (2.0 * PI * 2.0 * t).sin()
                    + 0.2 * (2.0 * PI * 1.3 * t).sin()
            })
            .collect();
        let fit = harmonic_fit(&x, dt, &[2.0, 1.3]).unwrap();
        assert!((fit.mean - 0.3).abs() < 1e-12);
        assert!((fit.cos[0] - 1.5).abs() < 1e-12 && (fit.sin[0] + 0.7).abs() < 1e-12);
        assert!(fit.cos[1].abs() < 1e-12 && (fit.sin[1] - 0.2).abs() < 1e-12);
        assert!(fit.rms_residual < 1e-12);
        let t = 3.7;
        let d_exact = 2.0 * PI * 2.0 * (-1.5 * (4.0 * PI * t).sin() - 0.7 * (4.0 * PI * t).cos())
            + 0.2 * 2.0 * PI * 1.3 * (2.0 * PI * 1.3 * t).cos();
        assert!((fit.derivative(t) - d_exact).abs() < 1e-10);
        let ds = fit.derivatives(n, dt);
        let i = 1234;
        assert!((ds[i] - fit.derivative(i as f64 * dt)).abs() < 1e-10);
    }

    #[test]
    fn harmonic_fit_rejects_dependent_basis_and_bad_input() {
        let x = vec![1.0; 100];
        assert!(matches!(
            harmonic_fit(&x, 0.01, &[2.0, 2.0]),
            Err(Error::Numerical { .. })
        ));
        assert!(matches!(
            harmonic_fit(&x, 0.01, &[-1.0]),
            Err(Error::InvalidOption { .. })
        ));
        let mut y = x.clone();
        y[5] = f64::NAN;
        assert!(matches!(
            harmonic_fit(&y, 0.01, &[1.0]),
            Err(Error::InvalidData { .. })
        ));
    }

    #[test]
    fn refine_single_frequency_with_noise_20_3_s() {
        let dt = 1.0 / 512.0;
        let n = (20.3 / dt) as usize;
        let f_true = 2.0137;
        let x = signal(n, dt, &[(1.0, f_true, 0.4)], 0.02, 3);
        let f0 = dominant_frequency(&x, dt).unwrap();
        assert!((f0 - f_true).abs() < 0.02, "{f0}");
        let f = refine_frequency(&x, dt, f0);
        assert!((f - f_true).abs() < 1e-4, "error {}", f - f_true);
        // Starting from a nominal value half a resolution cell away.
        let f = refine_frequency(&x, dt, f_true + 0.5 / 20.3);
        assert!((f - f_true).abs() < 1e-4, "error {}", f - f_true);
    }

    #[test]
    fn joint_refinement_two_frequencies_two_signals() {
        let dt = 1.0 / 512.0;
        let n = (20.3 / dt) as usize;
        let (fa, fh) = (2.0021, 1.2987);
        let a = signal(n, dt, &[(0.2, fa, 0.3), (0.05, fh, 1.0)], 0.002, 5);
        let h = signal(n, dt, &[(0.01, fh, 0.1), (0.003, fa, 2.0)], 0.0001, 6);
        let f = refine_frequencies(&[&a, &h], dt, &[2.0, 1.3]);
        assert!(
            (f[0] - fa).abs() < 1e-4 && (f[1] - fh).abs() < 1e-4,
            "{f:?}"
        );
    }

    #[test]
    fn noise_estimate_is_close_for_white_noise_on_a_smooth_signal() {
        let dt = 1.0 / 512.0;
        let x = signal(10_000, dt, &[(1.0, 2.0, 0.0)], 0.01, 9);
        let s = noise_sigma(&x);
        assert!((s / 0.01 - 1.0).abs() < 0.05, "{s}");
    }
}
