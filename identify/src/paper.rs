//! The paper's numerical verification (Table IV/V, Eq. 15/16) as cases for
//! [`crate::pipeline::identify`].
//!
//! F = H1 h + H2 ḣ + A1 α + A2 α̇ + N1 h ḣ α + N2 α² h + noise, with α = sin(2·2πt),
//! h = sin(1.3·2πt), Gaussian noise of standard deviation σ. The regression variables are
//! the physical ones (chord = U = 1, so the nondimensional variables α, Bα̇/U, h/B, ḣ/U
//! equal α, α̇, h, ḣ); the moment channel carries one parameter group and the lift channel
//! the other, each with its own noise.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::record::{CaseMeta, Forcing, NondimCase};
use crate::{Error, Result};

/// Library names of the six true terms, in the order of [`TableIvGroup::coefficients`].
pub const TABLE_IV_TERMS: [&str; 6] = [
    "alpha",
    "alpha_dot",
    "h",
    "h_dot",
    "alpha*h*h_dot",
    "alpha^2*h",
];

/// One parameter group (A1, A2, H1, H2, N1, N2): coefficients of α, α̇, h, ḣ, α h ḣ, α² h.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableIvGroup {
    /// Coefficients in the order of [`TABLE_IV_TERMS`].
    pub coefficients: [f64; 6],
}

impl TableIvGroup {
    /// The paper's group 1: (0.9, 0.1, −0.4, 0.03, 0.05, 0.3).
    pub const GROUP1: TableIvGroup = TableIvGroup {
        coefficients: [0.9, 0.1, -0.4, 0.03, 0.05, 0.3],
    };
    /// The paper's group 2: (0.1, 0.3, −0.1, 0.2, 0.5, 0.8).
    pub const GROUP2: TableIvGroup = TableIvGroup {
        coefficients: [0.1, 0.3, -0.1, 0.2, 0.5, 0.8],
    };
}

/// Sampling and noise of the verification.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableIvSampling {
    /// Sampling rate \[Hz\] (paper: 512).
    pub rate: f64,
    /// Duration \[s\] (paper: 20).
    pub duration: f64,
    /// Noise standard deviation σ (paper: 0.5).
    pub sigma: f64,
    /// Pitch frequency \[Hz\] (paper: 2).
    pub freq_pitch: f64,
    /// Heave frequency \[Hz\] (paper: 1.3).
    pub freq_heave: f64,
}

impl Default for TableIvSampling {
    fn default() -> Self {
        TableIvSampling {
            rate: 512.0,
            duration: 20.0,
            sigma: 0.5,
            freq_pitch: 2.0,
            freq_heave: 1.3,
        }
    }
}

/// One case per seed: `c_moment` from `moment`, `c_lift` from `lift`, noise drawn from
/// `ChaCha8Rng::seed_from_u64(seed)` (moment first, then lift). Case ids `seed-NNN`.
///
/// # Errors
/// [`Error::InvalidOption`] for a non-positive rate, duration or frequency, a negative σ,
/// or fewer than 16 samples.
pub fn table_iv_cases(
    moment: &TableIvGroup,
    lift: &TableIvGroup,
    sampling: &TableIvSampling,
    seeds: &[u64],
) -> Result<Vec<NondimCase>> {
    for (name, v) in [
        ("rate", sampling.rate),
        ("duration", sampling.duration),
        ("freq_pitch", sampling.freq_pitch),
        ("freq_heave", sampling.freq_heave),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::InvalidOption {
                name: name.into(),
                message: format!("{v} must be finite and > 0"),
            });
        }
    }
    if !(sampling.sigma.is_finite() && sampling.sigma >= 0.0) {
        return Err(Error::InvalidOption {
            name: "sigma".into(),
            message: format!("{} must be finite and ≥ 0", sampling.sigma),
        });
    }
    let n = (sampling.rate * sampling.duration).round() as usize;
    if n < 16 {
        return Err(Error::InvalidOption {
            name: "duration".into(),
            message: format!("{n} samples; need at least 16"),
        });
    }
    let (wa, wh) = (
        std::f64::consts::TAU * sampling.freq_pitch,
        std::f64::consts::TAU * sampling.freq_heave,
    );
    let t: Vec<f64> = (0..n).map(|i| i as f64 / sampling.rate).collect();
    let x: [Vec<f64>; 4] = [
        t.iter().map(|t| (wa * t).sin()).collect(),
        t.iter().map(|t| wa * (wa * t).cos()).collect(),
        t.iter().map(|t| (wh * t).sin()).collect(),
        t.iter().map(|t| wh * (wh * t).cos()).collect(),
    ];
    let column = |i: usize| -> [f64; 6] {
        [
            x[0][i],
            x[1][i],
            x[2][i],
            x[3][i],
            x[0][i] * x[2][i] * x[3][i],
            x[0][i] * x[0][i] * x[2][i],
        ]
    };
    let law = |g: &TableIvGroup, i: usize| -> f64 {
        column(i)
            .iter()
            .zip(g.coefficients)
            .map(|(c, k)| c * k)
            .sum()
    };
    Ok(seeds
        .iter()
        .map(|&seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut noisy = |g: &TableIvGroup| -> Vec<f64> {
                let normal = Normal::new(0.0, sampling.sigma).ok();
                (0..n)
                    .map(|i| law(g, i) + normal.map_or(0.0, |d| d.sample(&mut rng)))
                    .collect()
            };
            let c_moment = noisy(moment);
            let c_lift = noisy(lift);
            NondimCase {
                meta: CaseMeta {
                    id: format!("seed-{seed:03}"),
                    wind_speed: 1.0,
                    freq_pitch: Some(sampling.freq_pitch),
                    freq_heave: Some(sampling.freq_heave),
                    ..CaseMeta::default()
                },
                dt: 1.0 / sampling.rate,
                chord: 1.0,
                x: x.clone(),
                c_lift,
                c_moment,
                forcing: Forcing {
                    pitch: Some(sampling.freq_pitch),
                    heave: Some(sampling.freq_heave),
                },
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_free_cases_follow_the_law_exactly() {
        let s = TableIvSampling {
            sigma: 0.0,
            duration: 1.0,
            ..TableIvSampling::default()
        };
        let cs = table_iv_cases(&TableIvGroup::GROUP1, &TableIvGroup::GROUP2, &s, &[3]).unwrap();
        assert_eq!(cs.len(), 1);
        let c = &cs[0];
        assert_eq!(c.meta.id, "seed-003");
        let i = 77;
        let t = i as f64 / 512.0;
        let (a, h) = (
            (std::f64::consts::TAU * 2.0 * t).sin(),
            (std::f64::consts::TAU * 1.3 * t).sin(),
        );
        let ad = std::f64::consts::TAU * 2.0 * (std::f64::consts::TAU * 2.0 * t).cos();
        let hd = std::f64::consts::TAU * 1.3 * (std::f64::consts::TAU * 1.3 * t).cos();
        let g = TableIvGroup::GROUP1.coefficients;
        let expect =
            g[0] * a + g[1] * ad + g[2] * h + g[3] * hd + g[4] * a * h * hd + g[5] * a * a * h;
        assert!((c.c_moment[i] - expect).abs() < 1e-12);
    }

    #[test]
    fn noise_has_the_requested_spread_and_depends_on_the_seed() {
        let s = TableIvSampling::default();
        let z = TableIvSampling { sigma: 0.0, ..s };
        let g = TableIvGroup::GROUP1;
        let noisy = table_iv_cases(&g, &g, &s, &[1, 2]).unwrap();
        let clean = table_iv_cases(&g, &g, &z, &[1]).unwrap();
        let r: Vec<f64> = noisy[0]
            .c_moment
            .iter()
            .zip(&clean[0].c_moment)
            .map(|(a, b)| a - b)
            .collect();
        let sd = (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
        // 10240 samples: the sample sd is within a few % of 0.5
        assert!((sd - 0.5).abs() < 0.02, "sd {sd}");
        assert_ne!(noisy[0].c_moment, noisy[1].c_moment);
        assert!(table_iv_cases(&g, &g, &TableIvSampling { rate: 0.0, ..s }, &[1]).is_err());
    }
}
