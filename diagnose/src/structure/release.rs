//! Still-air releases of a model against measured decays, as time series: the release
//! simulated from a record's own initial state ([`release_of`], also the bifurcation
//! level's decay misfit), and the linear springs and dampers fitted to the records by
//! output error ([`fit_release`]) — the reading of a mode that no window of a record can
//! read (damped out within a few periods: DECISIONS, "A heavily damped mode read from the
//! release, round 35").

use aeroelastic::section::Section;
use aeroelastic::tunnel::{free_record, FreeOptions, SensorNoise};
use identify::preprocess::noise_sigma;
use identify::record::Record;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix4, Vector3};
use std::borrow::Borrow;

/// Samples of the least-squares quadratic through a record's start that gives its initial
/// state (value and slope at the first sample).
pub(crate) const START_SAMPLES: usize = 9;

/// RK4 steps per sample of the simulated release.
const SUBSTEPS: usize = 4;

/// Value and slope at the first sample of the least-squares quadratic through the first
/// [`START_SAMPLES`] samples of `x` (sample interval `dt` \[s\]); `None` when too short or
/// not finite.
pub(crate) fn start_of(x: &[f64], dt: f64) -> Option<(f64, f64)> {
    if x.len() < START_SAMPLES || dt.is_nan() || dt <= 0.0 {
        return None;
    }
    let mut a = Matrix3::zeros();
    let mut b = Vector3::zeros();
    for (i, &v) in x[..START_SAMPLES].iter().enumerate() {
        let t = i as f64;
        let row = Vector3::new(1.0, t, t * t);
        a += row * row.transpose();
        b += row * v;
    }
    let c = a.lu().solve(&b)?;
    (c[0].is_finite() && c[1].is_finite()).then_some((c[0], c[1] / dt))
}

/// A model's simulated still-air release against a record ([`release_of`]).
pub(crate) enum Release {
    /// The record's start cannot be read (too short, not finite).
    NoStart,
    /// The release overflowed or left the simulation's bounds within the record.
    Unbounded,
    /// The release's heave \[m\] and pitch \[rad\] at the record's first `n` samples.
    Bounded(Vec<f64>, Vec<f64>),
}

/// `section`'s still-air release from the initial state of `rec`'s first `n` samples
/// (value and slope of the least-squares quadratic through its first [`START_SAMPLES`]
/// samples), simulated without noise ([`SUBSTEPS`] RK4 steps a sample) at `rec`'s samples.
pub(crate) fn release_of(section: &Section, rec: &Record, n: usize) -> Release {
    let n = n.min(rec.h.len()).min(rec.alpha.len());
    let (Some((h0, hd0)), Some((a0, ad0))) = (
        start_of(&rec.h[..n], rec.dt),
        start_of(&rec.alpha[..n], rec.dt),
    ) else {
        return Release::NoStart;
    };
    let mut opts = FreeOptions::new(0);
    opts.rate = 1.0 / rec.dt;
    opts.duration = n as f64 * rec.dt;
    opts.initial = [h0, a0, hd0, ad0];
    opts.substeps = SUBSTEPS;
    opts.record_forces = false;
    opts.noise = SensorNoise::none();
    opts.bound_alpha = f64::MAX / 4.0;
    opts.bound_h = f64::MAX / 4.0;
    // A release that overflows (within three samples the simulation refuses it) or ends
    // early did not stay bounded: it misses the record entirely.
    match free_record(section, 0.0, &rec.meta.id, &opts, 0) {
        Ok((sim, _)) if sim.h.len() >= n && sim.alpha.len() >= n => {
            let (mut h, mut a) = (sim.h, sim.alpha);
            h.truncate(n);
            a.truncate(n);
            Release::Bounded(h, a)
        }
        _ => Release::Unbounded,
    }
}

/// The linear springs and dampers fitted to still-air records by output error
/// ([`fit_release`]).
#[derive(Debug, Clone)]
pub(crate) struct ReleaseFit {
    /// k_h \[N/m²\], k_α \[N m/rad/m\], c_h \[N s/m²\], c_α \[N m s/rad/m\].
    pub values: [f64; 4],
    /// Covariance of (ln k_h, ln k_α, ln c_h, ln c_α): s²(JᵀJ)⁻¹ × the residuals' AR(1)
    /// inflation (1 + ρ)/(1 − ρ) (serially correlated residuals carry fewer independent
    /// samples than they have).
    pub covariance: Matrix4<f64>,
    /// √(Σ residual² / Σ signal²) over the records (normalised as in the fit).
    pub misfit: f64,
}

/// Iterations of Levenberg–Marquardt per window.
const LM_ITERATIONS: usize = 30;

/// Step of the forward differences in ln k, ln c.
const STEP: f64 = 1e-4;

/// Parameters of the fit: ln k_h, ln k_α, ln c_h, ln c_α relative to the start.
const P: usize = 4;

/// Fits k_h, k_α, c_h, c_α of `section` (its masses, aerodynamic model at rest and
/// nonlinear terms held) to the still-air `records` by output error: the simulated release
/// from each record's initial state ([`release_of`]) against the record, heave and pitch
/// divided by `scale` (m, rad), least squares in the logarithms of the four parameters by
/// Levenberg–Marquardt with forward-difference Jacobians, started from `section`'s values.
///
/// The records are fitted over a window that doubles from `first_window` \[s\] to their
/// length, each stage started from the last: a release whose frequency is a few per cent
/// off drifts by whole periods over a long record, and output error has a local minimum at
/// every period; over a short window the phase drift stays below a period. Returns `None`
/// when no record has a readable start, a release leaves the bounds at the start values,
/// or the normal equations are singular.
pub(crate) fn fit_release(
    section: &Section,
    records: &[&Record],
    scale: [f64; 2],
    first_window: f64,
    held: [bool; 4],
) -> Option<ReleaseFit> {
    let st0 = &section.structure;
    let start = [st0.k_h, st0.k_alpha, st0.c_h, st0.c_alpha];
    if records.is_empty()
        || start.iter().any(|v| v.is_nan() || *v <= 0.0)
        || scale.iter().any(|v| v.is_nan() || *v <= 0.0)
    {
        return None;
    }
    let longest = records
        .iter()
        .map(|r| r.h.len().min(r.alpha.len()) as f64 * r.dt)
        .fold(0.0, f64::max);
    let base = Base {
        section,
        start,
        held,
    };
    let mut theta = DVector::zeros(P);
    let mut window = first_window.max(0.0).min(longest);
    loop {
        theta = lm_stage(&base, records, scale, theta, window)?;
        if window >= longest {
            break;
        }
        window = (2.0 * window).min(longest);
    }
    let (r, j, signal) = residuals_and_jacobian(&base, records, scale, &theta, longest)?;
    let n = r.len();
    let ssr = r.norm_squared();
    let jtj = j.transpose() * &j;
    let inv = {
        // a held parameter has no variance: invert the free block alone
        let free: Vec<usize> = (0..P).filter(|&d| !held[d]).collect();
        let sub = DMatrix::from_fn(free.len(), free.len(), |a, b| jtj[(free[a], free[b])]);
        let si = sub.try_inverse()?;
        let mut inv = DMatrix::zeros(P, P);
        for (a, &fa) in free.iter().enumerate() {
            for (b, &fb) in free.iter().enumerate() {
                inv[(fa, fb)] = si[(a, b)];
            }
        }
        inv
    };
    let n_free = held.iter().filter(|h| !**h).count();
    let s2 = ssr / (n.saturating_sub(n_free)).max(1) as f64;
    let rho = lag_one(&r).clamp(0.0, 0.99);
    let covariance = Matrix4::from_fn(|a, b| inv[(a, b)]) * (s2 * (1.0 + rho) / (1.0 - rho));
    let values = [0, 1, 2, 3].map(|i| start[i] * theta[i].exp());
    Some(ReleaseFit {
        values,
        covariance,
        misfit: (ssr / signal).sqrt(),
    })
}

/// Lag-one autocorrelation of `r` (consecutive samples; the records' joins count as
/// neighbours, negligible against their length).
fn lag_one(r: &DVector<f64>) -> f64 {
    let e0 = r.norm_squared();
    if e0 <= 0.0 {
        return 0.0;
    }
    r.as_slice().windows(2).map(|w| w[0] * w[1]).sum::<f64>() / e0
}

/// What the fit's parameters are relative to: the section and its start values of k_h,
/// k_α, c_h, c_α.
struct Base<'a> {
    section: &'a Section,
    start: [f64; 4],
    /// Parameters held at their start values (their Jacobian columns zero, their steps 0).
    held: [bool; 4],
}

/// The section with k_h, k_α, c_h, c_α = start × exp(θ).
fn with_theta(base: &Base, theta: &DVector<f64>) -> Option<Section> {
    let mut st = base.section.structure.clone();
    st.k_h = base.start[0] * theta[0].exp();
    st.k_alpha = base.start[1] * theta[1].exp();
    st.c_h = base.start[2] * theta[2].exp();
    st.c_alpha = base.start[3] * theta[3].exp();
    Section::new(st, base.section.aero.clone(), base.section.rho).ok()
}

/// Normalised residuals of the releases at θ over the first `window` seconds of each
/// record, and the normalised signal energy; `None` when a release has no start or leaves
/// the bounds.
fn residuals(
    base: &Base,
    records: &[&Record],
    scale: [f64; 2],
    theta: &DVector<f64>,
    window: f64,
) -> Option<(Vec<f64>, f64)> {
    let sec = with_theta(base, theta)?;
    let mut out = Vec::new();
    let mut signal = 0.0;
    for rec in records {
        let n = ((window / rec.dt).round() as usize)
            .min(rec.h.len())
            .min(rec.alpha.len());
        let Release::Bounded(h, a) = release_of(&sec, rec, n) else {
            return None;
        };
        for i in 0..n {
            out.push((h[i] - rec.h[i]) / scale[0]);
            out.push((a[i] - rec.alpha[i]) / scale[1]);
            signal += (rec.h[i] / scale[0]).powi(2) + (rec.alpha[i] / scale[1]).powi(2);
        }
    }
    (out.iter().all(|v| v.is_finite()) && signal > 0.0).then_some((out, signal))
}

/// Residuals, their forward-difference Jacobian in θ and the signal energy.
fn residuals_and_jacobian(
    base: &Base,
    records: &[&Record],
    scale: [f64; 2],
    theta: &DVector<f64>,
    window: f64,
) -> Option<(DVector<f64>, DMatrix<f64>, f64)> {
    let (r, signal) = residuals(base, records, scale, theta, window)?;
    let mut j = DMatrix::zeros(r.len(), P);
    for p in (0..P).filter(|&p| !base.held[p]) {
        let mut t = theta.clone();
        t[p] += STEP;
        let (rp, _) = residuals(base, records, scale, &t, window)?;
        for (i, (a, b)) in rp.iter().zip(&r).enumerate() {
            j[(i, p)] = (a - b) / STEP;
        }
    }
    Some((DVector::from_vec(r), j, signal))
}

/// One Levenberg–Marquardt stage over `window` seconds from θ₀.
fn lm_stage(
    base: &Base,
    records: &[&Record],
    scale: [f64; 2],
    theta0: DVector<f64>,
    window: f64,
) -> Option<DVector<f64>> {
    let mut theta = theta0;
    let mut lambda = 1e-3;
    for _ in 0..LM_ITERATIONS {
        let (r, j, _) = residuals_and_jacobian(base, records, scale, &theta, window)?;
        let cost = r.norm_squared();
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        let mut improved = false;
        for _ in 0..8 {
            let mut a = jtj.clone();
            for d in 0..P {
                // a held parameter's zero column: a unit diagonal keeps its step at 0
                a[(d, d)] += if base.held[d] {
                    1.0
                } else {
                    lambda * jtj[(d, d)].max(1e-12)
                };
            }
            let Some(step) = a.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let trial = &theta + &step;
            let better = residuals(base, records, scale, &trial, window)
                .map(|(rt, _)| rt.iter().map(|v| v * v).sum::<f64>())
                .is_some_and(|c| c < cost);
            if better {
                let gain = step.amax();
                theta = trial;
                lambda = (lambda / 10.0).max(1e-9);
                improved = true;
                if gain < 1e-7 {
                    return Some(theta);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some(theta)
}

/// The misfit white sensor noise alone leaves: a perfect model's decay misfit (`bifurcation::decays::decay_misfit`), from
/// each record's noise σ̂ per DOF ([`noise_sigma`]) over the same normalised signal energy.
/// `None` without a usable record.
pub(crate) fn decay_noise_floor<R: Borrow<Record>>(records: &[R], scale: [f64; 2]) -> Option<f64> {
    if records.is_empty() || !(scale[0] > 0.0 && scale[1] > 0.0) {
        return None;
    }
    let (mut r, mut s) = (0.0, 0.0);
    for rec in records {
        let rec: &Record = rec.borrow();
        let n = rec.h.len().min(rec.alpha.len());
        let (sh, sa) = (
            noise_sigma(&rec.h[..n]) / scale[0],
            noise_sigma(&rec.alpha[..n]) / scale[1],
        );
        r += n as f64 * (sh * sh + sa * sa);
        s += (0..n)
            .map(|i| (rec.h[i] / scale[0]).powi(2) + (rec.alpha[i] / scale[1]).powi(2))
            .sum::<f64>();
    }
    (s > 0.0 && r.is_finite()).then(|| (r / s).sqrt())
}

/// Effective number of independent residual patterns in the decays: half the sign changes
/// of each record's dominant DOF (larger normalised energy) among its samples above three
/// noise σ̂ — the oscillation cycles the release shows before it sinks into the noise —
/// summed over the records; at least 1.
pub(crate) fn decay_cycles<R: Borrow<Record>>(records: &[R], scale: [f64; 2]) -> f64 {
    let mut cycles = 0.0;
    for rec in records {
        let rec: &Record = rec.borrow();
        let n = rec.h.len().min(rec.alpha.len());
        let energy = |x: &[f64], s: f64| x.iter().map(|v| (v / s).powi(2)).sum::<f64>();
        let x = if energy(&rec.h[..n], scale[0]) > energy(&rec.alpha[..n], scale[1]) {
            &rec.h[..n]
        } else {
            &rec.alpha[..n]
        };
        let floor = 3.0 * noise_sigma(x);
        let kept: Vec<f64> = x.iter().copied().filter(|v| v.abs() > floor).collect();
        let changes = kept.windows(2).filter(|w| w[0] * w[1] < 0.0).count();
        cycles += changes as f64 / 2.0;
    }
    cycles.max(1.0)
}

/// One-sided 95 % point of the ratio of two residual energies with `nu` effective degrees
/// of freedom each (ln F(ν, ν) has variance ≈ 4/ν): exp(1.645 · 2/√ν).
pub(crate) fn energy_ratio_bar(nu: f64) -> f64 {
    (1.645 * 2.0 / nu.max(1.0).sqrt()).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_start_of_a_quadratic_is_its_value_and_slope() {
        let dt = 0.01;
        let x: Vec<f64> = (0..20)
            .map(|i| {
                let t = i as f64 * dt;
                0.3 - 2.0 * t + 5.0 * t * t
            })
            .collect();
        let (v, d) = start_of(&x, dt).expect("a start");
        assert!((v - 0.3).abs() < 1e-12, "{v}");
        assert!((d + 2.0).abs() < 1e-9, "{d}");
        assert!(start_of(&x[..5], dt).is_none());
    }
}
