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
use identify::record::Record;

use crate::structure::release::{release_of, Release};

/// Squared residual and squared signal sums (normalised by `scale`) of `section`'s still-air
/// release against one record.
fn record_sums(section: &Section, rec: &Record, scale: [f64; 2]) -> Option<(f64, f64)> {
    let n = rec.h.len().min(rec.alpha.len());
    let signal: f64 = (0..n)
        .map(|i| (rec.h[i] / scale[0]).powi(2) + (rec.alpha[i] / scale[1]).powi(2))
        .sum();
    let (h, a) = match release_of(section, rec, n) {
        Release::NoStart => return None,
        Release::Unbounded => return Some((f64::INFINITY, signal)),
        Release::Bounded(h, a) => (h, a),
    };
    let mut r = 0.0;
    for i in 0..n {
        let (eh, ea) = (
            (h[i] - rec.h[i]) / scale[0],
            (a[i] - rec.alpha[i]) / scale[1],
        );
        r += eh * eh + ea * ea;
    }
    // a release that grows without bound within the record overflows the sum: a full miss
    signal
        .is_finite()
        .then_some((if r.is_finite() { r } else { f64::INFINITY }, signal))
}

/// Normalised error of `section`'s simulated still-air releases against `records` (module
/// docs; `scale` = [s_h \[m\], s_α \[rad\]]): 0 for a perfect model, about 1 for a release
/// that misses the record entirely, `∞` for one that leaves every bound. `None` without a
/// usable record (fewer than `structure::release::START_SAMPLES` samples, non-finite values).
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

pub(crate) use crate::structure::release::{decay_cycles, decay_noise_floor, energy_ratio_bar};

#[cfg(test)]
mod tests {
    use super::*;
    use aeroelastic::tunnel::{free_record, FreeOptions, SensorNoise};

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
