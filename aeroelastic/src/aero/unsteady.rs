//! Theodorsen's unsteady thin-aerofoil theory: exact C(k) in the frequency domain, Jones'
//! two-lag (Wagner) realisation in the time domain.

use nalgebra::Matrix2;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::{thin_airfoil, thin_airfoil_apparent_mass, thin_airfoil_response, AeroModel, Flow};
use crate::error::{finite, positive};
use crate::theodorsen::{theodorsen, JONES_LAGS};
use crate::Result;

/// Theodorsen aerodynamics about an elastic axis at `a` semi-chords aft of mid-chord.
///
/// - Frequency domain: exact C(k), k = bω/U (b = B/2).
/// - Time domain: the circulatory downwash w = ḣ + Uα + b(½ − a)α̇ is replaced by
///   w_c = (1 − A₁ − A₂) w + A₁β₁ x₁ + A₂β₂ x₂ with lag states
///   ẋ_i = (U/b)(w − β_i x_i), (A, β) = Jones' (0.165, 0.0455), (0.335, 0.3); its transfer
///   function is exactly [`crate::theodorsen::theodorsen_jones`] and its indicial response
///   Wagner's function in Jones' form. Two lag states; x_i carry units of w \[m/s\].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TheodorsenAero {
    /// Chord B \[m\].
    pub chord: f64,
    /// Elastic-axis position a in semi-chords aft of mid-chord.
    pub a: f64,
}

impl TheodorsenAero {
    /// Builds the model.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for a non-positive `chord` or non-finite `a`.
    pub fn new(chord: f64, a: f64) -> Result<Self> {
        positive("chord", chord)?;
        finite("a", a)?;
        Ok(TheodorsenAero { chord, a })
    }

    #[inline]
    fn downwash(&self, u: f64, q: [f64; 2], qd: [f64; 2]) -> f64 {
        qd[0] + u * q[1] + 0.5 * self.chord * (0.5 - self.a) * qd[1]
    }
}

impl AeroModel for TheodorsenAero {
    fn name(&self) -> String {
        "theodorsen".into()
    }
    fn chord(&self) -> f64 {
        self.chord
    }
    fn n_lag(&self) -> usize {
        2
    }
    fn is_linear(&self) -> bool {
        true
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        thin_airfoil_apparent_mass(flow.rho, 0.5 * self.chord, self.a)
    }
    #[inline]
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        let w = self.downwash(flow.u, q, qd);
        let (a1, b1) = JONES_LAGS[0];
        let (a2, b2) = JONES_LAGS[1];
        let wc = (1.0 - a1 - a2) * w + a1 * b1 * lag[0] + a2 * b2 * lag[1];
        thin_airfoil(flow.rho, flow.u, 0.5 * self.chord, self.a, wc, qd[1], true)
    }
    #[inline]
    fn lag_rates(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]) {
        let w = self.downwash(flow.u, q, qd);
        let s = flow.u / (0.5 * self.chord);
        out[0] = s * (w - JONES_LAGS[0].1 * lag[0]);
        out[1] = s * (w - JONES_LAGS[1].1 * lag[1]);
    }
    fn elastic_axis(&self) -> Option<f64> {
        Some(self.a)
    }
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        let b = 0.5 * self.chord;
        let k = if flow.u > 0.0 {
            b * omega / flow.u
        } else {
            f64::INFINITY
        };
        let c = if k.is_finite() {
            theodorsen(k)
        } else {
            Complex64::new(0.5, 0.0)
        };
        thin_airfoil_response(flow.rho, flow.u, b, self.a, omega, c, false, true)
    }
}

/// Thin-plate flutter derivatives about an elastic axis at `a` semi-chords aft of
/// mid-chord (exact Theodorsen, Scanlan convention of [`crate::theodorsen::Derivatives`]), from the
/// thin-aerofoil transfer matrix: Q = H(ω = K U/B)/(½ρU²·(1, B; B, B²)). At a = 0 these are
/// [`crate::theodorsen::flat_plate_derivatives`]. A non-positive `k` gives NaN fields.
pub fn thin_plate_derivatives(k: f64, a: f64) -> crate::theodorsen::Derivatives {
    if k.is_nan() || k <= 0.0 || !a.is_finite() {
        return crate::theodorsen::flat_plate_derivatives(f64::NAN);
    }
    // B = 1 m, U = 1 m/s, ρ = 2 kg/m³: ½ρU² = 1 and ω = K
    let m = TheodorsenAero { chord: 1.0, a };
    let h = m.frequency_response(&Flow { rho: 2.0, u: 1.0 }, k);
    crate::theodorsen::Derivatives::from_q_matrix(
        k,
        [[h[(0, 0)], h[(0, 1)]], [h[(1, 0)], h[(1, 1)]]],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::state_space_response;
    use crate::theodorsen::theodorsen_jones;

    #[test]
    fn time_domain_realisation_is_jones_transfer_function() {
        // The lag-state model's frequency response must equal the thin-aerofoil response
        // built with Jones' C(k), to rounding.
        let m = TheodorsenAero::new(0.4, -0.2).unwrap();
        let flow = Flow { rho: 1.2, u: 15.0 };
        for omega in [1.0, 10.0, 40.0, 200.0] {
            let ss = state_space_response(&m, &flow, omega).unwrap();
            let k = 0.2 * omega / 15.0;
            let want = thin_airfoil_response(
                1.2,
                15.0,
                0.2,
                -0.2,
                omega,
                theodorsen_jones(k),
                false,
                true,
            );
            let scale = want.iter().map(|z| z.norm()).fold(0.0, f64::max);
            for (g, w) in ss.iter().zip(want.iter()) {
                assert!((g - w).norm() < 1e-9 * scale, "ω = {omega}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn flat_plate_response_matches_closed_form_derivatives() {
        // a = 0: H(ω) in Scanlan's nondimensional form equals K²(H4* + iH1*) etc.
        let m = TheodorsenAero::new(0.3, 0.0).unwrap();
        let flow = Flow { rho: 1.2, u: 10.0 };
        let kk: f64 = 0.8;
        let omega = kk * flow.u / 0.3;
        let h = m.frequency_response(&flow, omega);
        let d = crate::theodorsen::flat_plate_derivatives(kk);
        let q = d.q_matrix();
        let qd = flow.q_dyn();
        let b = 0.3;
        let got = [
            [h[(0, 0)] * b / (qd * b), h[(0, 1)] / (qd * b)],
            [h[(1, 0)] * b / (qd * b * b), h[(1, 1)] / (qd * b * b)],
        ];
        for i in 0..2 {
            for j in 0..2 {
                assert!(
                    (got[i][j] - q[i][j]).norm() < 1e-12 * q[i][j].norm().max(1.0),
                    "{i}{j}: {} vs {}",
                    got[i][j],
                    q[i][j]
                );
            }
        }
    }
}
