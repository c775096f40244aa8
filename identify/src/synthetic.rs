//! Synthetic forced-motion records from a known force law, for tests, benchmarks and the
//! built-in demonstration study.
//!
//! This is a deliberately small generator: prescribed two-frequency harmonic motion, forces
//! from a polynomial law in the nondimensional variables (α, Bα̇/U, h/B, ḣ/U) with constant
//! coefficients, and Gaussian sensor noise. The full virtual wind tunnel (aerodynamic models,
//! still-air runs, rig noise) lives in the `aeroelastic` crate.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::record::{CaseKind, CaseMeta, Record, SectionGeometry};
use crate::{Error, Result};

/// A monomial term of the law: powers of (α, Bα̇/U, h/B, ḣ/U) and its coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawTerm {
    /// Powers of α, Bα̇/U, h/B, ḣ/U.
    pub powers: [u8; 4],
    /// Nondimensional coefficient (of C_L or C_M).
    pub coefficient: f64,
}

/// A force law: C_L and C_M as sums of monomials in the nondimensional variables.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PolynomialLaw {
    /// Terms of C_L (positive down).
    pub lift: Vec<LawTerm>,
    /// Terms of C_M (positive nose-up).
    pub moment: Vec<LawTerm>,
}

impl PolynomialLaw {
    /// Evaluates Σ c·Π xᵢ^pᵢ for one channel at one sample.
    fn eval(terms: &[LawTerm], x: [f64; 4]) -> f64 {
        terms
            .iter()
            .map(|t| {
                t.coefficient
                    * (0..4)
                        .map(|i| x[i].powi(i32::from(t.powers[i])))
                        .product::<f64>()
            })
            .sum()
    }

    /// A quasi-flat-plate-like demonstration law: linear part of the order of a flat plate at
    /// K ≈ 0.3 plus the paper's three nonlinear moment terms α·Bα̇/U, α³, (Bα̇/U)³.
    pub fn demo() -> Self {
        let t = |powers, coefficient| LawTerm {
            powers,
            coefficient,
        };
        PolynomialLaw {
            lift: vec![
                t([1, 0, 0, 0], -5.8),
                t([0, 1, 0, 0], -1.6),
                t([0, 0, 1, 0], 0.3),
                t([0, 0, 0, 1], -5.9),
                t([3, 0, 0, 0], 4.0),
            ],
            moment: vec![
                t([1, 0, 0, 0], 1.45),
                t([0, 1, 0, 0], -0.25),
                t([0, 0, 1, 0], 0.05),
                t([0, 0, 0, 1], 1.3),
                t([1, 1, 0, 0], 0.4),
                t([3, 0, 0, 0], -1.2),
                t([0, 3, 0, 0], -2.0),
            ],
        }
    }
}

/// Prescribed harmonic motion α = ᾱ + A sin(2πf_α t), h = H sin(2πf_h t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicMotion {
    /// Pitch frequency f_α \[Hz\].
    pub freq_pitch: f64,
    /// Heave frequency f_h \[Hz\].
    pub freq_heave: f64,
    /// Pitch amplitude A \[rad\].
    pub amp_pitch: f64,
    /// Heave amplitude H \[m\].
    pub amp_heave: f64,
    /// Mean pitch ᾱ \[rad\].
    pub mean_pitch: f64,
}

/// Sampling and noise of a synthetic record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// Sampling rate \[Hz\].
    pub rate: f64,
    /// Duration \[s\].
    pub duration: f64,
    /// Standard deviation of force noise relative to each channel's peak force (the paper's
    /// balance: 0.1 % of range → 1e-3).
    pub force_noise: f64,
    /// Standard deviation of heave noise \[m\] (the paper's laser: 8 µm).
    pub heave_noise: f64,
    /// Standard deviation of pitch noise \[rad\].
    pub pitch_noise: f64,
}

impl Default for Sampling {
    fn default() -> Self {
        Sampling {
            rate: 512.0,
            duration: 10.0,
            force_noise: 1e-3,
            heave_noise: 8e-6,
            pitch_noise: 1e-4,
        }
    }
}

/// One forced-motion record with forces from `law`, SI per unit span.
///
/// Velocities are analytic; forces are evaluated on the true motion, then noise is added to
/// motion and forces. `meta.wind_speed` must be > 0.
///
/// # Errors
/// [`Error::InvalidOption`] for a non-positive rate, duration, chord or wind speed.
pub fn forced_record(
    meta: CaseMeta,
    section: &SectionGeometry,
    motion: &HarmonicMotion,
    law: &PolynomialLaw,
    sampling: &Sampling,
    seed: u64,
) -> Result<Record> {
    let u = meta.wind_speed;
    let b = section.chord;
    for (name, v) in [
        ("rate", sampling.rate),
        ("duration", sampling.duration),
        ("chord", b),
        ("wind_speed", u),
        ("air_density", section.air_density),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::InvalidOption {
                name: name.to_string(),
                message: format!("{v} must be finite and > 0"),
            });
        }
    }
    let n = (sampling.rate * sampling.duration).round() as usize;
    let dt = 1.0 / sampling.rate;
    let q = 0.5 * section.air_density * u * u;
    let (wa, wh) = (
        2.0 * std::f64::consts::PI * motion.freq_pitch,
        2.0 * std::f64::consts::PI * motion.freq_heave,
    );
    let mut alpha = Vec::with_capacity(n);
    let mut h = Vec::with_capacity(n);
    let mut lift = Vec::with_capacity(n);
    let mut moment = Vec::with_capacity(n);
    for i in 0..n {
        let t = i as f64 * dt;
        let a = motion.mean_pitch + motion.amp_pitch * (wa * t).sin();
        let a_dot = motion.amp_pitch * wa * (wa * t).cos();
        let hh = motion.amp_heave * (wh * t).sin();
        let h_dot = motion.amp_heave * wh * (wh * t).cos();
        let x = [a, b * a_dot / u, hh / b, h_dot / u];
        alpha.push(a);
        h.push(hh);
        lift.push(q * b * PolynomialLaw::eval(&law.lift, x));
        moment.push(q * b * b * PolynomialLaw::eval(&law.moment, x));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut add_noise = |v: &mut [f64], sd: f64| {
        if sd > 0.0 {
            // sd is finite and > 0, so the distribution exists.
            if let Ok(normal) = Normal::new(0.0, sd) {
                for x in v.iter_mut() {
                    *x += normal.sample(&mut rng);
                }
            }
        }
    };
    let peak = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let (pl, pm) = (peak(&lift), peak(&moment));
    add_noise(&mut lift, sampling.force_noise * pl);
    add_noise(&mut moment, sampling.force_noise * pm);
    add_noise(&mut h, sampling.heave_noise);
    add_noise(&mut alpha, sampling.pitch_noise);
    Ok(Record {
        kind: CaseKind::Forced,
        meta,
        t0: 0.0,
        dt,
        h,
        alpha,
        lift: Some(lift),
        moment: Some(moment),
        nowind: None,
        control: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forces_follow_the_law_without_noise() {
        let section = SectionGeometry {
            chord: 0.25,
            span: 0.75,
            air_density: 1.225,
        };
        let law = PolynomialLaw {
            lift: vec![LawTerm {
                powers: [1, 0, 0, 0],
                coefficient: 2.0,
            }],
            moment: vec![],
        };
        let motion = HarmonicMotion {
            freq_pitch: 2.0,
            freq_heave: 1.3,
            amp_pitch: 0.1,
            amp_heave: 0.01,
            mean_pitch: 0.0,
        };
        let sampling = Sampling {
            force_noise: 0.0,
            heave_noise: 0.0,
            pitch_noise: 0.0,
            ..Sampling::default()
        };
        let meta = CaseMeta {
            id: "x".into(),
            wind_speed: 5.0,
            ..CaseMeta::default()
        };
        let r = forced_record(meta, &section, &motion, &law, &sampling, 1).unwrap();
        assert_eq!(r.len(), 5120);
        let q = 0.5 * 1.225 * 25.0;
        let lift = r.lift.unwrap();
        for i in [0, 17, 4000] {
            assert!((lift[i] - q * 0.25 * 2.0 * r.alpha[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn zero_wind_speed_is_rejected() {
        let section = SectionGeometry {
            chord: 0.25,
            span: 0.75,
            air_density: 1.225,
        };
        let motion = HarmonicMotion {
            freq_pitch: 2.0,
            freq_heave: 1.3,
            amp_pitch: 0.1,
            amp_heave: 0.01,
            mean_pitch: 0.0,
        };
        let e = forced_record(
            CaseMeta::default(),
            &section,
            &motion,
            &PolynomialLaw::demo(),
            &Sampling::default(),
            0,
        )
        .unwrap_err();
        assert!(e.to_string().contains("wind_speed"), "{e}");
    }
}
