//! One converged periodic orbit as a [`BranchPoint`]: its amplitudes (half peak-to-peak of
//! one period of samples, first harmonic) and its Floquet multipliers, for every
//! discretisation ([`orbit_point`]).

use nalgebra::{DMatrix, DVector};

use super::floquet::floquet;
use super::types::BranchPoint;
use crate::Result;

/// One orbit of either discretisation as a [`BranchPoint`]: speed `u` [m/s], frequency
/// `omega` [rad/s], one period of (h, α) samples (half peak-to-peak amplitudes), the
/// first-harmonic amplitudes (h, α), the monodromy matrix, a state on the orbit and the
/// scaled unknowns.
pub(super) fn orbit_point(
    u: f64,
    omega: f64,
    samples: &[[f64; 2]],
    first_harmonic: [f64; 2],
    monodromy: DMatrix<f64>,
    state: Vec<f64>,
    y: &DVector<f64>,
) -> Result<BranchPoint> {
    let (mu, max_floquet) = floquet(monodromy)?;
    Ok(BranchPoint {
        u,
        period: std::f64::consts::TAU / omega,
        omega,
        amplitude_alpha: half_peak_to_peak(samples, 1),
        amplitude_h: half_peak_to_peak(samples, 0),
        amplitude1_alpha: first_harmonic[1],
        amplitude1_h: first_harmonic[0],
        max_floquet,
        stable: max_floquet < 1.0,
        multipliers: mu.iter().map(|m| [m.re, m.im]).collect(),
        state,
        unknowns: y.iter().copied().collect(),
    })
}

/// Half peak-to-peak of channel `c` of one period of samples, each extremum refined by the
/// parabola through the extreme sample and its two (periodic) neighbours.
fn half_peak_to_peak(s: &[[f64; 2]], c: usize) -> f64 {
    let n = s.len();
    if n < 3 {
        return 0.0;
    }
    let refine = |k: usize| {
        let (a, b, d) = (s[(k + n - 1) % n][c], s[k][c], s[(k + 1) % n][c]);
        let den = a - 2.0 * b + d;
        if den.abs() < 1e-300 {
            b
        } else {
            b - 0.125 * (d - a) * (d - a) / den
        }
    };
    let (mut kmax, mut kmin) = (0, 0);
    for k in 0..n {
        if s[k][c] > s[kmax][c] {
            kmax = k;
        }
        if s[k][c] < s[kmin][c] {
            kmin = k;
        }
    }
    0.5 * (refine(kmax) - refine(kmin))
}

/// First-harmonic amplitude |c₁| of channel `c` over one period of uniform samples:
/// (2/N)|Σ x_k e^{−2πik/N}| (exact for periodic signals up to aliasing).
pub(super) fn first_harmonic(s: &[[f64; 2]], c: usize) -> f64 {
    let n = s.len() as f64;
    let (mut re, mut im) = (0.0, 0.0);
    for (k, v) in s.iter().enumerate() {
        let th = std::f64::consts::TAU * k as f64 / n;
        re += v[c] * th.cos();
        im -= v[c] * th.sin();
    }
    2.0 / n * (re * re + im * im).sqrt()
}
