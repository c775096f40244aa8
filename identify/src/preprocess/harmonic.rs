//! Least-squares harmonic fits, frequency refinement, spectral peaks and a noise estimate.
//!
//! Time inside a record is `t = i·dt` (seconds since the first sample): the fits and
//! their [`HarmonicFit::value`] / [`HarmonicFit::derivative`] use that time base.
//!
//! Implementation: sines and cosines of `θᵢ = θ₀ + ω i` come from a rotation re-synchronised
//! exactly every 64 samples ([`for_each_phase`]). Internally the fits use the centred index
//! `u = i − (N−1)/2`; on that symmetric grid every odd sum vanishes and the Gram matrix of
//! the basis `[1, cos ωₖu, sin ωₖu]`, and the moments `Σ u·(…)`, `Σ u²·(…)` needed by the
//! Gauss–Newton frequency refinement, have closed forms in the Dirichlet kernel
//! `D(θ) = Σᵤ cos θu = sin(Nθ/2)/sin(θ/2)` and its derivatives ([`dirichlet`]). A fit or a
//! refinement step therefore reads the record only for `Σ x e^{jωu}` and `Σ u x e^{jωu}`.

use std::f64::consts::PI;

use crate::numerics::{cholesky_solve, PivotFloor};

/// Pivot floor of the small normal-equation solves here (1e-13 of the largest diagonal).
const FLOOR: PivotFloor = PivotFloor::RelativeToLargestDiagonal(1e-13);
use crate::{Error, Result};

/// Samples between exact re-synchronisations of the rotation in [`for_each_phase`] (a
/// multiple of [`LANES`]).
const RESYNC: usize = 64;
/// Independent rotation chains of [`for_each_phase`] (sample `i` is on lane `i % LANES`).
const LANES: usize = 4;

/// Calls `f(lane, i, cos θᵢ, sin θᵢ)` for `θᵢ = p0 + w·i`, i = 0..n in increasing order,
/// `lane = i % 4`. The values come from four interleaved rotations by `4w` (independent
/// dependency chains, so the loop is not latency-bound; a caller accumulating sums should
/// keep one accumulator per lane), re-synchronised with `sin_cos` every [`RESYNC`]
/// samples so that rounding does not drift (error ~1e-15).
#[inline(always)]
fn for_each_phase(n: usize, w: f64, p0: f64, mut f: impl FnMut(usize, usize, f64, f64)) {
    let (s4, c4) = (LANES as f64 * w).sin_cos();
    let steps: [(f64, f64); LANES] = std::array::from_fn(|l| (l as f64 * w).sin_cos());
    let mut start = 0;
    while start < n {
        let end = (start + RESYNC).min(n);
        let (s0, c0) = (p0 + w * start as f64).sin_cos();
        let mut c = [0.0; LANES];
        let mut s = [0.0; LANES];
        for l in 0..LANES {
            let (sl, cl) = steps[l];
            c[l] = c0 * cl - s0 * sl;
            s[l] = s0 * cl + c0 * sl;
        }
        let mut i = start;
        while i + LANES <= end {
            for l in 0..LANES {
                f(l, i + l, c[l], s[l]);
            }
            for l in 0..LANES {
                let c2 = c[l] * c4 - s[l] * s4;
                s[l] = s[l] * c4 + c[l] * s4;
                c[l] = c2;
            }
            i += LANES;
        }
        for l in 0..end - i {
            f(l, i + l, c[l], s[l]);
        }
        start = end;
    }
}

/// `[Σ x cos θᵢ, Σ x sin θᵢ, Σ y cos θᵢ, Σ y sin θᵢ]`, `θᵢ = p0 + w·i` (`y` may be empty:
/// its sums are then 0).
fn phase_sums(w: f64, p0: f64, x: &[f64], y: &[f64]) -> [f64; 4] {
    let n = x.len();
    let mut acc = [[0.0; 4]; LANES];
    if y.is_empty() {
        for_each_phase(n, w, p0, |l, i, c, s| {
            acc[l][0] += x[i] * c;
            acc[l][1] += x[i] * s;
        });
    } else {
        let y = &y[..n];
        for_each_phase(n, w, p0, |l, i, c, s| {
            acc[l][0] += x[i] * c;
            acc[l][1] += x[i] * s;
            acc[l][2] += y[i] * c;
            acc[l][3] += y[i] * s;
        });
    }
    std::array::from_fn(|j| acc.iter().map(|a| a[j]).sum())
}

/// `(D, S₁, C₂)(θ)` on the centred grid `u = i − (N−1)/2`, i = 0..N:
/// `D = Σ cos θu = sin(Nθ/2)/sin(θ/2)`, `S₁ = Σ u sin θu = −D′(θ)`,
/// `C₂ = Σ u² cos θu = −D″(θ)` (the odd sums `Σ sin θu`, `Σ u cos θu`, `Σ u² sin θu` are 0).
/// With `a = θ/2`, `f = sin Na`, `g = sin a`: `dD/da = (N cos Na · g − f cos a)/g²`,
/// `d²D/da² = f(1 − N²)/g − 2 cos a (dD/da)/g`. Where `|sin θ/2| < 1e-4` (θ near a
/// multiple of 2π, where the closed form loses digits) the sums are accumulated directly.
fn dirichlet(n: usize, theta: f64) -> (f64, f64, f64) {
    let nf = n as f64;
    if theta == 0.0 {
        return (nf, 0.0, nf * (nf * nf - 1.0) / 12.0);
    }
    let a = 0.5 * theta;
    let (g, ca) = a.sin_cos();
    if g.abs() < 1e-4 {
        let c0 = (nf - 1.0) / 2.0;
        let (mut d, mut s1, mut c2) = (0.0, 0.0, 0.0);
        for_each_phase(n, theta, -theta * c0, |_, i, c, s| {
            let u = i as f64 - c0;
            d += c;
            s1 += u * s;
            c2 += u * u * c;
        });
        return (d, s1, c2);
    }
    let (f, cna) = (nf * a).sin_cos();
    let d = f / g;
    let da = (nf * cna * g - f * ca) / (g * g);
    let daa = f * (1.0 - nf * nf) / g - 2.0 * ca * da / g;
    (d, -0.5 * da, -0.25 * daa)
}

/// Gram matrix `G = ΦᵀΦ` (`p × p`, row-major, full) of the centred basis
/// `Φ = [1, cos ω₁u, sin ω₁u, …]` (ω in rad per sample), in closed form:
/// `Σ cₖ = D(ωₖ)`, `Σ cₖcₗ = ½[D(ωₖ−ωₗ) + D(ωₖ+ωₗ)]`, `Σ sₖsₗ = ½[D(ωₖ−ωₗ) − D(ωₖ+ωₗ)]`,
/// every sum with an odd integrand 0.
fn centred_gram(n: usize, omegas: &[f64]) -> Vec<f64> {
    let kf = omegas.len();
    let p = 1 + 2 * kf;
    let mut g = vec![0.0; p * p];
    g[0] = n as f64;
    for k in 0..kf {
        let dk = dirichlet(n, omegas[k]).0;
        g[(1 + 2 * k) * p] = dk;
        g[1 + 2 * k] = dk;
        for l in 0..=k {
            let dm = dirichlet(n, omegas[k] - omegas[l]).0;
            let dp = dirichlet(n, omegas[k] + omegas[l]).0;
            let (cc, ss) = (0.5 * (dm + dp), 0.5 * (dm - dp));
            for (r, c, v) in [(1 + 2 * k, 1 + 2 * l, cc), (2 + 2 * k, 2 + 2 * l, ss)] {
                g[r * p + c] = v;
                g[c * p + r] = v;
            }
        }
    }
    g
}

/// Least-squares fit of `mean + Σₖ cosₖ·cos(2π fₖ t) + sinₖ·sin(2π fₖ t)` to a signal.
#[derive(Debug, Clone, PartialEq)]
pub struct HarmonicFit {
    /// Constant term (signal units).
    pub mean: f64,
    /// Frequencies fₖ \[Hz\].
    pub freqs: Vec<f64>,
    /// Cosine coefficients aₖ (signal units).
    pub cos: Vec<f64>,
    /// Sine coefficients bₖ (signal units).
    pub sin: Vec<f64>,
    /// Root-mean-square residual of the fit (signal units).
    pub rms_residual: f64,
}

impl HarmonicFit {
    /// The fitted signal at time `t` \[s\] since the first sample.
    pub fn value(&self, t: f64) -> f64 {
        let mut v = self.mean;
        for k in 0..self.freqs.len() {
            let (s, c) = (2.0 * PI * self.freqs[k] * t).sin_cos();
            v += self.cos[k] * c + self.sin[k] * s;
        }
        v
    }

    /// The time derivative of the fitted signal at `t` \[s\] (signal units per second):
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

    /// Values at `t = i·dt`, i = 0..n (by rotation: O(n·K)).
    pub fn values(&self, n: usize, dt: f64) -> Vec<f64> {
        let mut v = vec![self.mean; n];
        for k in 0..self.freqs.len() {
            let (a, b) = (self.cos[k], self.sin[k]);
            for_each_phase(n, 2.0 * PI * self.freqs[k] * dt, 0.0, |_, i, c, s| {
                v[i] += a * c + b * s;
            });
        }
        v
    }

    /// Derivatives at `t = i·dt`, i = 0..n (signal units per second).
    pub fn derivatives(&self, n: usize, dt: f64) -> Vec<f64> {
        let mut v = vec![0.0; n];
        for k in 0..self.freqs.len() {
            let w = 2.0 * PI * self.freqs[k];
            let (a, b) = (w * self.cos[k], w * self.sin[k]);
            for_each_phase(n, w * dt, 0.0, |_, i, c, s| {
                v[i] += b * c - a * s;
            });
        }
        v
    }

    /// Root-mean-square of `x[i] − fit(i·dt)` over the samples of `x` (signal units).
    pub fn rms_residual_of(&self, x: &[f64], dt: f64) -> f64 {
        if x.is_empty() {
            return 0.0;
        }
        let mut r: Vec<f64> = x.iter().map(|v| v - self.mean).collect();
        for k in 0..self.freqs.len() {
            let (a, b) = (self.cos[k], self.sin[k]);
            for_each_phase(r.len(), 2.0 * PI * self.freqs[k] * dt, 0.0, |_, i, c, s| {
                r[i] -= a * c + b * s;
            });
        }
        (r.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
    }
}

/// Least-squares fit of `mean + Σₖ aₖ cos(2π fₖ t) + bₖ sin(2π fₖ t)` to `x` sampled at
/// `t = i·dt`. Exact for records that are not a whole number of periods (it is a true
/// least-squares fit, not a DFT). An empty `freqs` fits the mean alone.
///
/// # Errors
/// [`Error::InvalidOption`] when `dt` or a frequency is not finite and positive;
/// [`Error::InvalidData`] when `x` has a non-finite value or fewer samples than
/// coefficients; [`Error::Numerical`] when the basis is numerically dependent (two
/// frequencies closer than the record resolves, or a frequency too low for its length).
pub fn harmonic_fit(x: &[f64], dt: f64, freqs: &[f64]) -> Result<HarmonicFit> {
    fit_with_covariance(x, dt, freqs).map(|(fit, _)| fit)
}

/// [`harmonic_fit`], also returning, per component, the 2 × 2 block `[Cₐₐ, Cₐᵦ, Cᵦᵦ]` of
/// `G⁻¹` (`G` the Gram matrix of the basis) for its (cos, sin) coefficients in the centred
/// time base: the coefficient covariance is `σ² G⁻¹` for white noise of variance σ², and
/// the amplitude's variance is invariant under the change of time origin.
fn fit_with_covariance(x: &[f64], dt: f64, freqs: &[f64]) -> Result<(HarmonicFit, Vec<[f64; 3]>)> {
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
    let kf = freqs.len();
    let p = 1 + 2 * kf;
    let n = x.len();
    if n < p {
        return Err(Error::InvalidData {
            case: String::new(),
            field: "x".into(),
            message: format!("{n} samples for {p} coefficients"),
        });
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::InvalidData {
            case: String::new(),
            field: "x".into(),
            message: format!("non-finite value {} at sample {i}", x[i]),
        });
    }
    let c0 = (n as f64 - 1.0) / 2.0;
    let omegas: Vec<f64> = freqs.iter().map(|f| 2.0 * PI * f * dt).collect();
    let mut g = centred_gram(n, &omegas);
    // Right-hand sides: Φᵀx, then the unit vectors of the cos/sin coefficients (columns
    // of G⁻¹).
    let mut rhs = vec![0.0; p * (1 + 2 * kf)];
    rhs[0] = x.iter().sum();
    for (k, &w) in omegas.iter().enumerate() {
        let [xc, xs, _, _] = phase_sums(w, -w * c0, x, &[]);
        rhs[1 + 2 * k] = xc;
        rhs[2 + 2 * k] = xs;
    }
    for j in 0..2 * kf {
        rhs[p * (1 + j) + 1 + j] = 1.0;
    }
    if cholesky_solve(&mut g, p, &mut rhs, 1 + 2 * kf, FLOOR).is_err() {
        return Err(Error::Numerical {
            context: "harmonic_fit".into(),
            message: format!(
                "basis at {freqs:?} Hz is numerically dependent over {} s",
                n as f64 * dt
            ),
        });
    }
    let col = |j: usize, r: usize| rhs[p * (1 + j) + r];
    let blocks = (0..kf)
        .map(|k| {
            let (ja, jb) = (2 * k, 2 * k + 1);
            [
                col(ja, 1 + ja),
                0.5 * (col(ja, 1 + jb) + col(jb, 1 + ja)),
                col(jb, 1 + jb),
            ]
        })
        .collect();
    // Back to t = i·dt: a' cos ω(i − c0) + b' sin ω(i − c0) = a cos ωi + b sin ωi with
    // (a, b) = R(ωc0)(a', b').
    let (mut cos, mut sin) = (Vec::with_capacity(kf), Vec::with_capacity(kf));
    for (k, &w) in omegas.iter().enumerate() {
        let (a, b) = (rhs[1 + 2 * k], rhs[2 + 2 * k]);
        let (sp, cp) = (w * c0).sin_cos();
        cos.push(a * cp - b * sp);
        sin.push(a * sp + b * cp);
    }
    let mut fit = HarmonicFit {
        mean: rhs[0],
        freqs: freqs.to_vec(),
        cos,
        sin,
        rms_residual: 0.0,
    };
    fit.rms_residual = fit.rms_residual_of(x, dt);
    Ok((fit, blocks))
}

/// One candidate component of a harmonic fit and whether [`significant_harmonic_fit`]
/// kept it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicComponent {
    /// Frequency \[Hz\].
    pub freq: f64,
    /// Amplitude √(a² + b²) in the fit at all candidate frequencies (signal units).
    pub amplitude: f64,
    /// Standard error of that amplitude (signal units), from the residual variance
    /// `σ̂² = SS_res/(N − p)` and the Gram matrix `G` of the basis: `σ̂ √(uᵀ C u)` with `C`
    /// the component's 2 × 2 block of `G⁻¹` and `u = (a, b)/A` (delta method; ≈ σ̂ √(2/N)
    /// for frequencies resolved by the record).
    pub std_error: f64,
    /// True when the component passed both tests of [`significant_harmonic_fit`].
    pub kept: bool,
}

/// Harmonic fit restricted to the significant components (the rule of docs/DECISIONS.md
/// "exact harmonic motion per degree of freedom"): `x` is first fitted at all `freqs`
/// ([`harmonic_fit`]); a component is kept when its amplitude `A` is **both** above
/// `n_se` standard errors ([`HarmonicComponent::std_error`]) **and** at least
/// `rel_floor` × the largest amplitude of the fit; `x` is then refitted at the kept
/// frequencies only (the mean alone when none is kept). Dropping a spurious component
/// (noise fitted at another DOF's frequency) makes the fitted motion exactly single-
/// frequency, so the exact identities of harmonic motion (e.g. α̇² = ω²(A² − (α − ᾱ)²))
/// hold to rounding.
///
/// For a pure-noise component `A/std_error` is Rayleigh distributed, so `n_se = 5` keeps
/// one by chance with probability `exp(−25/2) ≈ 4·10⁻⁶`.
///
/// Returns the refitted [`HarmonicFit`] and every candidate component.
///
/// # Errors
/// As [`harmonic_fit`] (the first fit, then the refit).
pub fn significant_harmonic_fit(
    x: &[f64],
    dt: f64,
    freqs: &[f64],
    n_se: f64,
    rel_floor: f64,
) -> Result<(HarmonicFit, Vec<HarmonicComponent>)> {
    let (full, blocks) = fit_with_covariance(x, dt, freqs)?;
    let n = x.len();
    let p = 1 + 2 * freqs.len();
    let dof = (n - p).max(1) as f64;
    let var = full.rms_residual * full.rms_residual * n as f64 / dof;
    let a_max = (0..freqs.len())
        .map(|k| full.amplitude(k))
        .fold(0.0, f64::max);
    let c0 = (n as f64 - 1.0) / 2.0;
    let comps: Vec<HarmonicComponent> = (0..freqs.len())
        .map(|k| {
            // Coefficients in the centred time base of the covariance blocks.
            let (sp, cp) = (2.0 * PI * freqs[k] * dt * c0).sin_cos();
            let (a, b) = (full.cos[k], full.sin[k]);
            let (a, b) = (a * cp + b * sp, -a * sp + b * cp);
            let amp = full.amplitude(k);
            let [caa, cab, cbb] = blocks[k];
            let quad = if amp > 0.0 {
                (a * a * caa + 2.0 * a * b * cab + b * b * cbb) / (amp * amp)
            } else {
                0.5 * (caa + cbb)
            };
            let se = (var * quad.max(0.0)).sqrt();
            HarmonicComponent {
                freq: freqs[k],
                amplitude: amp,
                std_error: se,
                kept: amp > n_se * se && amp >= rel_floor * a_max,
            }
        })
        .collect();
    if comps.iter().all(|c| c.kept) {
        return Ok((full, comps));
    }
    let kept: Vec<f64> = comps.iter().filter(|c| c.kept).map(|c| c.freq).collect();
    Ok((harmonic_fit(x, dt, &kept)?, comps))
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

/// Normalised cost and Gauss–Newton step of the variable-projection problem at `omegas`
/// (angular frequencies per sample); see [`refine_vp`].
struct VpPoint {
    /// `Σₛ ‖xₛ − Φβₛ‖² / ‖xₛ‖²` (the unexplained fractions, summed).
    cost: f64,
    /// Gauss–Newton step in ω (rad per sample); `None` when its normal matrix is singular.
    step: Option<Vec<f64>>,
}

/// The centred signals of a refinement: `xₛ` (mean removed), `u·xₛ`, `‖xₛ‖²`, `Σ xₛ`.
struct VpSignals {
    x: Vec<Vec<f64>>,
    ux: Vec<Vec<f64>>,
    norms: Vec<f64>,
    sums: Vec<f64>,
}

/// The least-squares fit of the centred signals on `Φ = [1, cos ωₖu, sin ωₖu]` (ω in rad
/// per sample, u = i − (N−1)/2, so the derivative columns are nearly orthogonal to Φ), its
/// cost, and the Gauss–Newton step of the variable-projection (Golub–Pereyra, Kaufman's
/// Jacobian) problem `min_ω Σₛ wₛ ‖P⊥(ω) xₛ‖²`, `wₛ = 1/‖xₛ‖²`.
///
/// With `dₛₖ = ∂(Φβₛ)/∂ωₖ = aₛₖ qₖ,c + bₛₖ qₖ,s`, `qₖ,c = −u sin ωₖu`, `qₖ,s = u cos ωₖu`: the
/// gradient is `∂F/∂ωₖ = −2 Σₛ wₛ dₛₖᵀ rₛ` (exact), the Gauss–Newton matrix
/// `Hₖₗ = Σₛ wₛ dₛₖᵀ P⊥ dₛₗ = Σₛ wₛ (dₛₖᵀdₛₗ − (Φᵀdₛₖ)ᵀ G⁻¹ (Φᵀdₛₗ))`, and the step
/// `Δω = H⁻¹ g`, `gₖ = Σₛ wₛ (dₛₖᵀxₛ − (Φᵀdₛₖ)ᵀβₛ)`. `G`, `Φᵀq` and `qᵀq` are closed forms
/// in [`dirichlet`] (`Σ u sₖcₗ = ½[S₁(ωₖ+ωₗ) + S₁(ωₖ−ωₗ)]`, `Σ u² sₖsₗ = ½[C₂(ωₖ−ωₗ) −
/// C₂(ωₖ+ωₗ)]`, `Σ u² cₖcₗ = ½[C₂(ωₖ−ωₗ) + C₂(ωₖ+ωₗ)]`, odd sums 0); the record is read
/// once per frequency for `Σ xₛ e^{jωu}` and `Σ u xₛ e^{jωu}`.
fn vp_point(sig: &VpSignals, omegas: &[f64]) -> Option<VpPoint> {
    let n = sig.x[0].len();
    let ns = sig.x.len();
    let kf = omegas.len();
    let p = 1 + 2 * kf;
    let m2 = 2 * kf;
    let c0 = (n as f64 - 1.0) / 2.0;
    let mut g = centred_gram(n, omegas);
    // Q[m][r] = Σ qₘ φᵣ and QQ[m][m'] = Σ qₘ qₘ'.
    let mut q = vec![0.0; m2 * p];
    let mut qq = vec![0.0; m2 * m2];
    for k in 0..kf {
        let s1k = dirichlet(n, omegas[k]).1;
        q[(2 * k) * p] = -s1k; // Σ (−u sₖ)·1
        for l in 0..kf {
            let (_, s1p, c2p) = dirichlet(n, omegas[k] + omegas[l]);
            let (_, s1m, c2m) = dirichlet(n, omegas[k] - omegas[l]);
            // Σ (−u sₖ) cₗ = −½[S₁(ωₖ+ωₗ) + S₁(ωₖ−ωₗ)]; Σ (u cₖ) sₗ = ½[S₁(ωₖ+ωₗ) − S₁(ωₖ−ωₗ)].
            q[(2 * k) * p + 1 + 2 * l] = -0.5 * (s1p + s1m);
            q[(2 * k + 1) * p + 2 + 2 * l] = 0.5 * (s1p - s1m);
            qq[(2 * k) * m2 + 2 * l] = 0.5 * (c2m - c2p);
            qq[(2 * k + 1) * m2 + 2 * l + 1] = 0.5 * (c2m + c2p);
        }
    }
    // Φᵀxₛ and Qᵀxₛ from one pass per frequency and signal.
    let mut b = vec![0.0; ns * p];
    let mut qx = vec![0.0; ns * m2];
    for s in 0..ns {
        b[s * p] = sig.sums[s];
        for (k, &w) in omegas.iter().enumerate() {
            let [xc, xs, uxc, uxs] = phase_sums(w, -w * c0, &sig.x[s], &sig.ux[s]);
            b[s * p + 1 + 2 * k] = xc;
            b[s * p + 2 + 2 * k] = xs;
            qx[s * m2 + 2 * k] = -uxs;
            qx[s * m2 + 2 * k + 1] = uxc;
        }
    }
    // G [βₛ | Zₘ] = [Φᵀxₛ | Qₘ].
    let mut rhs = Vec::with_capacity((ns + m2) * p);
    rhs.extend_from_slice(&b);
    rhs.extend_from_slice(&q);
    if cholesky_solve(&mut g, p, &mut rhs, ns + m2, FLOOR).is_err() {
        return None;
    }
    let beta = |s: usize| &rhs[s * p..(s + 1) * p];
    let z = |m: usize| &rhs[(ns + m) * p..(ns + m + 1) * p];
    let qm = |m: usize| &q[m * p..(m + 1) * p];
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    // (QQ − QᵀG⁻¹Q)[m][m'].
    let mut proj = vec![0.0; m2 * m2];
    for m in 0..m2 {
        for m_ in 0..m2 {
            proj[m * m2 + m_] = qq[m * m2 + m_] - dot(qm(m), z(m_));
        }
    }
    let mut cost = 0.0;
    let mut h = vec![0.0; kf * kf];
    let mut grad = vec![0.0; kf];
    for s in 0..ns {
        let bs = beta(s);
        let w = 1.0 / sig.norms[s];
        cost += 1.0 - dot(bs, &b[s * p..(s + 1) * p]) * w;
        // dₛₖ = Σ_{m ∈ {2k, 2k+1}} coef[m] qₘ with coef = (aₛₖ, bₛₖ).
        let coef = &bs[1..];
        for k in 0..kf {
            let mut gk = 0.0;
            for m in [2 * k, 2 * k + 1] {
                gk += coef[m] * (qx[s * m2 + m] - dot(qm(m), bs));
            }
            grad[k] += w * gk;
            for l in 0..=k {
                let mut hkl = 0.0;
                for m in [2 * k, 2 * k + 1] {
                    for m_ in [2 * l, 2 * l + 1] {
                        hkl += coef[m] * coef[m_] * proj[m * m2 + m_];
                    }
                }
                h[k * kf + l] += w * hkl;
            }
        }
    }
    let step = cholesky_solve(&mut h, kf, &mut grad, 1, FLOOR)
        .is_ok()
        .then_some(grad);
    Some(VpPoint { cost, step })
}

/// Largest Gauss–Newton step of [`refine_vp`], in resolution cells `1/T`.
const VP_MAX_STEP: f64 = 0.25;
/// Convergence of [`refine_vp`]: last step below this many resolution cells `1/T`.
const VP_TOL: f64 = 1e-9;
/// Most passes over the record in [`refine_vp`].
const VP_MAX_PASSES: usize = 60;

/// Frequencies \[Hz\] minimising `Σₛ ‖P⊥(f) xₛ‖² / ‖xₛ − x̄ₛ‖²` (the unexplained variance
/// fractions of a least-squares fit of all signals at all frequencies, plus means),
/// starting from `freqs`: Gauss–Newton on the variable-projection problem ([`vp_point`];
/// one pass over the record per iteration), each step limited to `VP_MAX_STEP/T` and
/// halved until the cost does not increase, stopping when a step is below `tol/T`
/// (T = n·dt) or after `VP_MAX_PASSES` passes. Frequencies stay in `(0.25/T, Nyquist)`.
fn refine_vp(xs: &[&[f64]], dt: f64, freqs: &[f64], tol: f64) -> Vec<f64> {
    let n = xs[0].len();
    let c0 = (n as f64 - 1.0) / 2.0;
    let (x, norms) = centred(xs);
    let ux = x
        .iter()
        .map(|v| {
            v.iter()
                .enumerate()
                .map(|(i, a)| (i as f64 - c0) * a)
                .collect()
        })
        .collect();
    let sums = x.iter().map(|v| v.iter().sum()).collect();
    let sig = VpSignals { x, ux, norms, sums };
    let cell = 2.0 * PI / n as f64; // 1/T in rad per sample
    let (lo, hi) = (0.25 * cell, PI);
    let mut w: Vec<f64> = freqs.iter().map(|f| 2.0 * PI * f * dt).collect();
    let to_hz = |w: &[f64]| w.iter().map(|x| x / (2.0 * PI * dt)).collect::<Vec<f64>>();
    let Some(mut cur) = vp_point(&sig, &w) else {
        return freqs.to_vec();
    };
    let mut passes = 1;
    'outer: while passes < VP_MAX_PASSES {
        let Some(step) = cur.step.take() else {
            break;
        };
        let step: Vec<f64> = step
            .iter()
            .map(|s| s.clamp(-VP_MAX_STEP * cell, VP_MAX_STEP * cell))
            .collect();
        let size = step.iter().fold(0.0f64, |m, s| m.max(s.abs())) / cell;
        if size < tol {
            // Quadratic regime: apply without another pass.
            w.iter_mut().zip(&step).for_each(|(x, s)| *x += s);
            break;
        }
        let mut lambda = 1.0;
        loop {
            if lambda < 1e-3 || passes >= VP_MAX_PASSES {
                break 'outer;
            }
            let trial: Vec<f64> = w.iter().zip(&step).map(|(x, s)| x + lambda * s).collect();
            if trial.iter().all(|x| *x > lo && *x < hi) {
                passes += 1;
                if let Some(pt) = vp_point(&sig, &trial) {
                    // The cost carries ~1e-16 rounding per signal.
                    if pt.cost <= cur.cost + 1e-14 * xs.len() as f64 {
                        w = trial;
                        cur = pt;
                        break;
                    }
                }
            }
            lambda *= 0.5;
        }
        if lambda * size < tol {
            break;
        }
    }
    to_hz(&w)
}

/// Refines a frequency estimate `f0` \[Hz\] of the dominant sinusoid of `x` (sampled every
/// `dt` s): maximises the power of the least-squares fit of `mean + a cos 2πft + b sin 2πft`
/// (not a DFT, so it is exact for records that are not a whole number of periods) by
/// Gauss–Newton with step control from `f0` (each step at most 0.25/T, T = n·dt), to a
/// last step below 1e-9/T. It climbs the main lobe (half-width ≈ 1/T) that contains `f0`.
///
/// Returns `f0` unchanged when the input cannot be refined (`f0` or `dt` not finite and
/// positive, fewer than 4 samples, non-finite samples).
pub fn refine_frequency(x: &[f64], dt: f64, f0: f64) -> f64 {
    refine_frequency_to(x, dt, f0, VP_TOL)
}

/// [`refine_frequency`] to a last step below `tol/T`.
pub(crate) fn refine_frequency_to(x: &[f64], dt: f64, f0: f64, tol: f64) -> f64 {
    if !(f0.is_finite() && f0 > 0.0 && dt.is_finite() && dt > 0.0)
        || x.len() < 4
        || x.iter().any(|v| !v.is_finite())
    {
        return f0;
    }
    refine_vp(&[x], dt, &[f0], tol)[0]
}

/// Joint refinement of several frequencies for several signals: maximises the summed
/// explained fraction of a least-squares fit at all `freqs` (each signal normalised by its
/// variance), all frequencies at once ([`refine_vp`], to a last step below 1e-9/T).
/// Removes the bias that a single-sinusoid refinement suffers from leakage of the other
/// components.
pub(crate) fn refine_frequencies(xs: &[&[f64]], dt: f64, freqs: &[f64]) -> Vec<f64> {
    refine_vp(xs, dt, freqs, VP_TOL)
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

/// Frequency \[Hz\] of the largest spectral peak of `x` (mean removed, Hann window, zero
/// padding to ≥ 4n points, parabolic interpolation of the peak), searching above `0.5/T`:
/// [`spectral_peak`] with [`PeakSearch::FORCED`]. `None` for a constant signal or fewer
/// than 4 samples.
pub fn dominant_frequency(x: &[f64], dt: f64) -> Option<f64> {
    spectral_peak(x, dt, PeakSearch::FORCED)
}

/// The window of a spectral estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Window {
    /// Hann, 0.5 − 0.5 cos(2πi/(n−1)): low leakage, for steady (forced) records.
    Hann,
    /// None: a decaying transient lives at the start of the record, where a taper would
    /// remove it (free decays).
    Rectangular,
}

/// How [`spectral_peak`] looks for the peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakSearch {
    /// Window applied after removing the mean.
    pub window: Window,
    /// Lowest frequency searched, in cycles per record (bins below are trends).
    pub min_cycles: f64,
}

impl PeakSearch {
    /// Steady forced records: Hann window, above half a cycle per record.
    pub const FORCED: PeakSearch = PeakSearch {
        window: Window::Hann,
        min_cycles: 0.5,
    };
    /// Free responses (decays, growing or limit-cycle oscillations): no window, above two
    /// cycles per record.
    pub const FREE: PeakSearch = PeakSearch {
        window: Window::Rectangular,
        min_cycles: 2.0,
    };
}

/// Frequency \[Hz\] of the largest spectral peak of `x` sampled every `dt` \[s\]: mean
/// removed, `search.window` applied, zero padding to ≥ 4n points (a power of two), the
/// largest bin at or above `search.min_cycles` cycles per record, refined by a parabola
/// through the magnitudes around it. The one dominant-frequency estimator of the
/// workspace. `None` for a constant signal, fewer than 4 samples or a bad `dt`.
pub fn spectral_peak(x: &[f64], dt: f64, search: PeakSearch) -> Option<f64> {
    let n = x.len();
    if n < 4 || dt.is_nan() || dt <= 0.0 {
        return None;
    }
    let m = x.iter().sum::<f64>() / n as f64;
    let len = (4 * n).next_power_of_two();
    let mut buf = vec![0.0; len];
    match search.window {
        // Hann window 0.5 − 0.5 cos(2πi/(n−1)).
        Window::Hann => for_each_phase(n, 2.0 * PI / (n - 1) as f64, 0.0, |_, i, c, _| {
            buf[i] = (x[i] - m) * (0.5 - 0.5 * c);
        }),
        Window::Rectangular => {
            for (b, v) in buf.iter_mut().zip(x) {
                *b = v - m;
            }
        }
    }
    let fft = fft::forward(len);
    let mut spec = fft.make_output_vec();
    fft.process(&mut buf, &mut spec).ok()?;
    let power: Vec<f64> = spec.iter().map(|c| c.norm_sqr()).collect();
    let df = 1.0 / (len as f64 * dt);
    let t = n as f64 * dt;
    let k_lo = ((search.min_cycles / t) / df).ceil().max(1.0) as usize;
    let (k, &peak) = power
        .iter()
        .enumerate()
        .skip(k_lo)
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    if peak.is_nan() || peak <= 0.0 {
        return None;
    }
    let mut off = 0.0;
    if k > 0 && k + 1 < power.len() {
        // Parabola through the magnitudes around the peak.
        let (a, b, c) = (power[k - 1].sqrt(), peak.sqrt(), power[k + 1].sqrt());
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
    fn rotation_matches_sin_cos() {
        let (w, p0) = (0.0377, -3.1);
        let mut count = 0;
        for_each_phase(5003, w, p0, |l, i, c, s| {
            assert_eq!(l, i % 4);
            let (se, ce) = (p0 + w * i as f64).sin_cos();
            assert!((c - ce).abs() < 1e-13 && (s - se).abs() < 1e-13, "{i}");
            assert_eq!(i, count);
            count += 1;
        });
        assert_eq!(count, 5003);
    }

    /// Direct accumulation of the normal equations `G`, `Φᵀx` in the centred time base.
    fn direct_normal_equations(xs: &[&[f64]], omegas: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let n = xs[0].len();
        let c0 = (n as f64 - 1.0) / 2.0;
        let p = 1 + 2 * omegas.len();
        let mut g = vec![0.0; p * p];
        let mut b = vec![0.0; p * xs.len()];
        // Basis columns (rotation checked against sin_cos in `rotation_matches_sin_cos`).
        let mut cols = vec![vec![1.0; n]];
        for &w in omegas {
            let (mut cc, mut ss) = (vec![0.0; n], vec![0.0; n]);
            for_each_phase(n, w, -w * c0, |_, i, c, s| {
                cc[i] = c;
                ss[i] = s;
            });
            cols.push(cc);
            cols.push(ss);
        }
        for i in 0..n {
            let phi: Vec<f64> = cols.iter().map(|c| c[i]).collect();
            for r in 0..p {
                for c in 0..p {
                    g[r * p + c] += phi[r] * phi[c];
                }
                for (s, x) in xs.iter().enumerate() {
                    b[s * p + r] += phi[r] * x[i];
                }
            }
        }
        (g, b)
    }

    /// Least-squares coefficients and explained sums of squares by direct accumulation
    /// (reference for the closed forms).
    fn fit_basis(xs: &[&[f64]], dt: f64, freqs: &[f64]) -> Option<(Vec<Vec<f64>>, Vec<f64>)> {
        let omegas: Vec<f64> = freqs.iter().map(|f| 2.0 * PI * f * dt).collect();
        let p = 1 + 2 * freqs.len();
        let ns = xs.len();
        let (mut g, mut b) = direct_normal_equations(xs, &omegas);
        let rhs = b.clone();
        if cholesky_solve(&mut g, p, &mut b, ns, FLOOR).is_err() {
            return None;
        }
        let betas: Vec<Vec<f64>> = (0..ns).map(|s| b[s * p..(s + 1) * p].to_vec()).collect();
        let explained = (0..ns)
            .map(|s| (0..p).map(|r| betas[s][r] * rhs[s * p + r]).sum::<f64>())
            .collect();
        Some((betas, explained))
    }

    /// The closed forms of the Dirichlet sums and of the Gram matrix agree with direct
    /// summation (even and odd N, small and large angles, near 2π).
    #[test]
    fn closed_form_sums_match_direct_summation() {
        for n in [5120usize, 5121, 37] {
            let c0 = (n as f64 - 1.0) / 2.0;
            for theta in [
                0.0,
                1e-7,
                2.0 * PI / n as f64,
                0.0245,
                0.7,
                3.0,
                2.0 * PI - 1e-5,
            ] {
                let (d, s1, c2) = dirichlet(n, theta);
                let (mut ed, mut es1, mut ec2) = (0.0, 0.0, 0.0);
                for i in 0..n {
                    let u = i as f64 - c0;
                    ed += (theta * u).cos();
                    es1 += u * (theta * u).sin();
                    ec2 += u * u * (theta * u).cos();
                }
                let nf = n as f64;
                assert!(
                    (d - ed).abs() < 1e-11 * nf,
                    "D n={n} θ={theta}: {d} vs {ed}"
                );
                assert!(
                    (s1 - es1).abs() < 1e-11 * nf * nf,
                    "S1 n={n} θ={theta}: {s1} vs {es1}"
                );
                assert!(
                    (c2 - ec2).abs() < 1e-11 * nf * nf * nf,
                    "C2 n={n} θ={theta}: {c2} vs {ec2}"
                );
            }
            let omegas = [0.0245, 0.0159, 0.3];
            let g = centred_gram(n, &omegas);
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let (ge, _) = direct_normal_equations(&[&x], &omegas);
            for (a, b) in g.iter().zip(&ge) {
                assert!((a - b).abs() < 1e-11 * n as f64, "{a} vs {b}");
            }
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

    /// Fraction of the variance of the signals explained by a least-squares fit at `freqs`
    /// (each normalised by its sum of squares about the mean); −∞ for a dependent basis.
    fn explained_fraction(xs: &[&[f64]], norms: &[f64], dt: f64, freqs: &[f64]) -> f64 {
        match fit_basis(xs, dt, freqs) {
            None => f64::NEG_INFINITY,
            Some((_, explained)) => explained.iter().zip(norms).map(|(e, n)| e / n).sum(),
        }
    }

    /// Reference maximiser (the previous implementation, derivative-free): coordinate
    /// ascent, each coordinate by a 17-point grid over ±span/T then golden section.
    fn reference_refine(xs: &[&[f64]], dt: f64, freqs: &[f64], span: f64) -> Vec<f64> {
        let (c, norms) = centred(xs);
        let views: Vec<&[f64]> = c.iter().map(|v| v.as_slice()).collect();
        let t = xs[0].len() as f64 * dt;
        let mut f = freqs.to_vec();
        for pass in 0..8 {
            let w = if pass == 0 { span } else { 0.05 } / t;
            for k in 0..f.len() {
                let mut trial = f.clone();
                let mut obj = |x: f64| {
                    trial[k] = x;
                    explained_fraction(&views, &norms, dt, &trial)
                };
                let h = 2.0 * w / 16.0;
                let f0 = f[k];
                let fb = (0..=16)
                    .map(|j| f0 - w + j as f64 * h)
                    .max_by(|a, b| obj(*a).total_cmp(&obj(*b)))
                    .unwrap();
                f[k] = crate::numerics::golden_section_max(fb - h, fb + h, 1e-10 / t, obj);
            }
        }
        f
    }

    /// The Gauss–Newton variable-projection refinement finds the same maximiser as the
    /// brute-force search (to 1e-6 of a resolution cell, far below the statistical error),
    /// and its explained fraction is not lower.
    #[test]
    fn gauss_newton_matches_brute_force_maximiser() {
        let dt = 1.0 / 512.0;
        for (dur, seed) in [(10.0, 1u64), (20.3, 2)] {
            let n = (dur / dt) as usize;
            let t = n as f64 * dt;
            let (fa, fh) = (2.0021, 1.2987);
            let a = signal(n, dt, &[(0.2, fa, 0.3), (0.05, fh, 1.0)], 0.002, seed);
            let h = signal(n, dt, &[(0.01, fh, 0.1), (0.003, fa, 2.0)], 1e-4, seed + 10);
            let xs: [&[f64]; 2] = [&a, &h];
            let gn = refine_frequencies(&xs, dt, &[2.0, 1.3]);
            let rf = reference_refine(&xs, dt, &[2.0, 1.3], 0.25);
            let (c, norms) = centred(&xs);
            let views: Vec<&[f64]> = c.iter().map(|v| v.as_slice()).collect();
            let e_gn = explained_fraction(&views, &norms, dt, &gn);
            let e_rf = explained_fraction(&views, &norms, dt, &rf);
            for k in 0..2 {
                assert!(
                    ((gn[k] - rf[k]) * t).abs() < 1e-6,
                    "{dur} s: GN {gn:?} vs reference {rf:?}"
                );
            }
            assert!(e_gn >= e_rf - 1e-14, "{e_gn} < {e_rf}");
            // Single signal, single frequency, from the nominal value.
            let g1 = refine_frequency(&a, dt, 2.0);
            let r1 = reference_refine(&[&a], dt, &[2.0], 1.0)[0];
            assert!(((g1 - r1) * t).abs() < 1e-6, "{g1} vs {r1}");
        }
    }

    /// Gauss–Newton with step control climbs the main lobe from up to 0.9/T away, with a
    /// second component of a third of the amplitude 0.7 Hz away.
    #[test]
    fn refine_frequency_converges_from_far_in_the_main_lobe() {
        let dt = 1.0 / 512.0;
        let n = 5120;
        let t = n as f64 * dt;
        let f_true = 2.0137;
        let x = signal(n, dt, &[(1.0, f_true, 0.4), (0.3, 1.31, 2.0)], 0.01, 4);
        let reference = refine_frequency(&x, dt, f_true);
        assert!((reference - f_true).abs() < 1e-3, "{reference}");
        for off in [-0.9, -0.6, -0.3, 0.3, 0.6, 0.9] {
            let f = refine_frequency(&x, dt, f_true + off / t);
            assert!(
                ((f - reference) * t).abs() < 1e-6,
                "start {off}/T: {f} vs {reference}"
            );
        }
    }

    /// The significance rule: a noise-only component at another frequency is dropped (and
    /// the refit has no such component), a small but real one is kept, one below the
    /// relative floor is dropped; the standard error matches σ√(2/N).
    #[test]
    fn significant_fit_keeps_real_components_and_drops_noise() {
        let dt = 1.0 / 512.0;
        let n = 5120;
        let sigma = 1e-4;
        // Noise only at 1.3 Hz.
        let x = signal(n, dt, &[(0.2, 2.0, 0.3)], sigma, 21);
        let (fit, comps) = significant_harmonic_fit(&x, dt, &[2.0, 1.3], 5.0, 1e-3).unwrap();
        assert!(comps[0].kept && !comps[1].kept, "{comps:?}");
        assert_eq!(fit.freqs, vec![2.0]);
        let se_expected = sigma * (2.0 / n as f64).sqrt();
        for c in &comps {
            assert!(
                (c.std_error / se_expected - 1.0).abs() < 0.05,
                "se {} vs {se_expected}",
                c.std_error
            );
        }
        // A real 1 % component at 1.3 Hz (50 standard errors... far above 5): kept.
        let x = signal(n, dt, &[(0.2, 2.0, 0.3), (0.002, 1.3, 1.0)], sigma, 22);
        let (fit, comps) = significant_harmonic_fit(&x, dt, &[2.0, 1.3], 5.0, 1e-3).unwrap();
        assert!(comps.iter().all(|c| c.kept), "{comps:?}");
        assert_eq!(fit.freqs.len(), 2);
        assert!((fit.amplitude(1) - 0.002).abs() < 5.0 * se_expected);
        // Statistically significant (1e-4 / 2e-6 = 50 se) but below the 1e-3 floor.
        let x = signal(n, dt, &[(0.2, 2.0, 0.3), (1e-4, 1.3, 1.0)], 1e-5, 23);
        let (_, comps) = significant_harmonic_fit(&x, dt, &[2.0, 1.3], 5.0, 1e-3).unwrap();
        assert!(comps[0].kept && !comps[1].kept, "{comps:?}");
        assert!(comps[1].amplitude > 5.0 * comps[1].std_error);
        // Pure noise: nothing kept, the refit is the mean.
        let x = signal(n, dt, &[], sigma, 24);
        let (fit, comps) = significant_harmonic_fit(&x, dt, &[2.0, 1.3], 5.0, 1e-3).unwrap();
        assert!(comps.iter().all(|c| !c.kept), "{comps:?}");
        assert!(fit.freqs.is_empty());
        assert!((fit.rms_residual / sigma - 1.0).abs() < 0.05);
    }

    #[test]
    fn noise_estimate_is_close_for_white_noise_on_a_smooth_signal() {
        let dt = 1.0 / 512.0;
        let x = signal(10_000, dt, &[(1.0, 2.0, 0.0)], 0.01, 9);
        let s = noise_sigma(&x);
        assert!((s / 0.01 - 1.0).abs() < 0.05, "{s}");
    }
}
