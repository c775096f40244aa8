//! Each fitted model's still-air releases against the measured decays (issue 42 item 1;
//! DECISIONS, "The decays as time series, round 34").
//!
//! The structure check reads the decays as linear modes, and every candidate is conformed
//! to those modes at rest. What the modes do not carry — how a release decays through the
//! amplitudes it passes (a friction's Coulomb regime and its slope at rest, a spring's
//! backbone) — each candidate still predicts. [`decay_misfit`] simulates the model's own
//! still-air release from each record's initial state and returns the normalised error
//! against the record:
//!
//! e² = Σ_records Σ_t Σ_d ((x̂_d − x_d)/s_d)² / Σ_records Σ_t Σ_d (x_d/s_d)²,
//!
//! d over heave and pitch, s_d the level's normalisation scales (m, rad), so that the two
//! DOFs weigh as in the amplitude score.

use std::sync::Arc;

use aeroelastic::section::Section;
use aeroelastic::tunnel::{free_record, FreeOptions, SensorNoise};
use identify::preprocess::noise_sigma;
use identify::record::Record;
use nalgebra::{Matrix3, Vector3};

/// Samples of the least-squares quadratic through a record's start that gives its initial
/// state (value and slope at the first sample).
const START_SAMPLES: usize = 9;

/// RK4 steps per sample of the simulated release.
const SUBSTEPS: usize = 4;

/// Value and slope at the first sample of the least-squares quadratic through the first
/// [`START_SAMPLES`] samples of `x` (sample interval `dt` \[s\]); `None` when too short or
/// not finite.
fn start_of(x: &[f64], dt: f64) -> Option<(f64, f64)> {
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

/// Squared residual and squared signal sums (normalised by `scale`) of `section`'s still-air
/// release against one record.
fn record_sums(section: &Section, rec: &Record, scale: [f64; 2]) -> Option<(f64, f64)> {
    let n = rec.h.len().min(rec.alpha.len());
    let (h0, hd0) = start_of(&rec.h[..n], rec.dt)?;
    let (a0, ad0) = start_of(&rec.alpha[..n], rec.dt)?;
    let mut opts = FreeOptions::new(0);
    opts.rate = 1.0 / rec.dt;
    opts.duration = n as f64 * rec.dt;
    opts.initial = [h0, a0, hd0, ad0];
    opts.substeps = SUBSTEPS;
    opts.record_forces = false;
    opts.noise = SensorNoise::none();
    opts.bound_alpha = f64::MAX / 4.0;
    opts.bound_h = f64::MAX / 4.0;
    let signal: f64 = (0..n)
        .map(|i| (rec.h[i] / scale[0]).powi(2) + (rec.alpha[i] / scale[1]).powi(2))
        .sum();
    // A release that overflows (within three samples the simulation refuses it) or ends
    // early did not stay bounded: it misses the record entirely.
    let sim = match free_record(section, 0.0, &rec.meta.id, &opts, 0) {
        Ok((sim, _)) if sim.h.len() >= n => sim,
        _ => return Some((f64::INFINITY, signal)),
    };
    let (mut r, mut s) = (0.0, 0.0);
    for i in 0..n {
        let (eh, ea) = (
            (sim.h[i] - rec.h[i]) / scale[0],
            (sim.alpha[i] - rec.alpha[i]) / scale[1],
        );
        r += eh * eh + ea * ea;
        s += (rec.h[i] / scale[0]).powi(2) + (rec.alpha[i] / scale[1]).powi(2);
    }
    // a release that grows without bound within the record overflows the sum: a full miss
    s.is_finite()
        .then_some((if r.is_finite() { r } else { f64::INFINITY }, s))
}

/// Normalised error of `section`'s simulated still-air releases against `records` (module
/// docs; `scale` = [s_h \[m\], s_α \[rad\]]): 0 for a perfect model, about 1 for a release
/// that misses the record entirely, `∞` for one that leaves every bound. `None` without a
/// usable record (fewer than [`START_SAMPLES`] samples, non-finite values).
pub(crate) fn decay_misfit(
    section: &Section,
    records: &[Arc<Record>],
    scale: [f64; 2],
) -> Option<f64> {
    if records.is_empty() || !(scale[0] > 0.0 && scale[1] > 0.0) {
        return None;
    }
    let (mut r, mut s) = (0.0, 0.0);
    for rec in records {
        let (ri, si) = record_sums(section, rec, scale)?;
        r += ri;
        s += si;
    }
    (s > 0.0).then(|| (r / s).sqrt())
}

/// The misfit white sensor noise alone leaves: a perfect model's [`decay_misfit`], from
/// each record's noise σ̂ per DOF ([`noise_sigma`]) over the same normalised signal energy.
/// `None` without a usable record.
pub(crate) fn decay_noise_floor(records: &[Arc<Record>], scale: [f64; 2]) -> Option<f64> {
    if records.is_empty() || !(scale[0] > 0.0 && scale[1] > 0.0) {
        return None;
    }
    let (mut r, mut s) = (0.0, 0.0);
    for rec in records {
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
pub(crate) fn decay_cycles(records: &[Arc<Record>], scale: [f64; 2]) -> f64 {
    let mut cycles = 0.0;
    for rec in records {
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

    /// A noise-free still-air release of the cubic-pitch reference section against itself,
    /// against the section with a 5 % stiffer pitch spring, and against one whose softening
    /// spring turns negative within the release (it overflows).
    #[test]
    fn a_model_reproduces_its_own_release_and_misses_a_stiffer_one() {
        let truth = aeroelastic::reference::hp1_cubic_pitch();
        let mut opts = FreeOptions::new(0);
        opts.rate = 200.0;
        opts.duration = 10.0;
        opts.initial = [0.0, 0.05, 0.0, 0.0];
        opts.noise = SensorNoise::none();
        opts.record_forces = false;
        let (rec, _) = free_record(&truth, 0.0, "decay-pitch", &opts, 0).expect("a release");
        let recs = vec![Arc::new(rec)];
        let scale = [0.01, 0.05];
        let own = decay_misfit(&truth, &recs, scale).expect("a misfit");
        assert!(own < 1e-3, "{own}");
        let mut st = truth.structure.clone();
        st.k_alpha *= 1.05;
        let stiffer = Section::new(st, truth.aero.clone(), truth.rho).expect("a section");
        let e = decay_misfit(&stiffer, &recs, scale).expect("a misfit");
        // a 2.5 % frequency error: 0.115 here, a hundred times the model's own
        assert!(e > 100.0 * own && e > 0.05 && e.is_finite(), "{e} vs {own}");
        let mut st = truth.structure.clone();
        let k3 = -4.0 * st.k_alpha / (0.05 * 0.05);
        aeroelastic::structure::add_poly_term(&mut st.nonlinear.pitch_stiffness_terms, 3, k3);
        let soft = Section::new(st, truth.aero.clone(), truth.rho).expect("a section");
        assert_eq!(decay_misfit(&soft, &recs, scale), Some(f64::INFINITY));
    }
}
