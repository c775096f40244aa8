//! A Beddoes–Leishman-type dynamic-stall model of a thin plate in the state-space form of
//! Hansen, Gaunaa & Madsen (2004, Risø-R-1354, "A Beddoes–Leishman type dynamic stall model
//! in state-space and indicial formulations"), without its leading-edge-vortex lift.
//!
//! States (per unit span):
//! - x₁, x₂: Jones' (Wagner) attached-flow lag states, exactly as [`super::TheodorsenAero`]:
//!   the effective downwash w_c = (1 − A₁ − A₂) w + A₁β₁x₁ + A₂β₂x₂ with
//!   w = ḣ + Uα + b(½ − a)α̇ (three-quarter-chord downwash), effective angle α_E = w_c/U;
//! - x₃ = α_F: the effective angle lagged by the leading-edge pressure response,
//!   ẋ₃ = (α_E − x₃)/T_p, T_p = τ_p b/U;
//! - x₄ = 1 − f'': the separation deficit of the dynamic separation point f'' (Kirchhoff
//!   trailing-edge separation, 1 = attached), ẋ₄ = (1 − f_st(α_F) − x₄)/T_f, T_f = τ_f b/U.
//!
//! Lift (up) = 2πρUb·w_c·K + πρb²Uα̇ (+ apparent mass), with the Kirchhoff factor
//! K = f'' + (1 − f'')·(1 + 3s)/(4(1 + s)), s = √f_st(α_E): the attached lift weighted by
//! f'' plus Hansen's fully-separated lift weighted by 1 − f''. In steady flow (f'' = f_st,
//! α_E = α) this is K = ((1 + √f)/2)², Kirchhoff's static lift C_L = 2πα((1 + √f)/2)²
//! (Thwaites 1960; Leishman & Beddoes 1989). The circulatory lift acts at the quarter chord
//! moved aft by k_cp·(1 − f'')·B (centre of pressure of separated flow); the moment is about
//! the elastic axis at `a` semi-chords aft of mid-chord, sign conventions of DESIGN.md §2.
//!
//! Static separation curve (aeroform's choice for a thin plate at Re ≈ 10⁵, not fitted to a
//! measurement): f_st(α) = 1 / (1 + (α/α₁)^{2m}), α₁ = 10°, m = 4: f_st(0) = 1 with zero
//! slope, so the model's linearisation is exactly Theodorsen with Jones' lags; the static
//! C_L peaks at 0.82 near 9° and falls to the fully-separated 2πα/4 beyond ~15°.
//! Time constants τ_p = 1.7, τ_f = 3 semi-chord times (Leishman & Beddoes 1989).

use nalgebra::Matrix2;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::{thin_airfoil, thin_airfoil_apparent_mass, AeroModel, Flow, TheodorsenAero};
use crate::error::{finite, positive};
use crate::theodorsen::JONES_LAGS;
use crate::Result;

/// Beddoes–Leishman-type dynamic-stall model of a thin plate (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DynamicStallAero {
    /// Chord B \[m\].
    pub chord: f64,
    /// Elastic-axis position a in semi-chords aft of mid-chord.
    pub a: f64,
    /// Angle α₁ \[rad\] at which the static separation point is f_st = ½.
    pub alpha1: f64,
    /// Sharpness exponent m of f_st = 1/(1 + (α/α₁)^{2m}) (≥ 1).
    pub sharpness: f64,
    /// Pressure lag τ_p [semi-chord times b/U].
    pub tau_p: f64,
    /// Separation lag τ_f [semi-chord times b/U].
    pub tau_f: f64,
    /// Aft shift of the centre of pressure at full separation, in chords.
    pub k_cp: f64,
}

impl DynamicStallAero {
    /// The thin plate of the module docs: α₁ = 10°, m = 4, τ_p = 1.7, τ_f = 3, k_cp = 0.25.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for a non-positive `chord` or non-finite `a`.
    pub fn thin_plate(chord: f64, a: f64) -> Result<Self> {
        Self {
            chord,
            a,
            alpha1: 10f64.to_radians(),
            sharpness: 4.0,
            tau_p: 1.7,
            tau_f: 3.0,
            k_cp: 0.25,
        }
        .checked()
    }

    /// Checks every parameter.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] naming the parameter.
    pub fn checked(self) -> Result<Self> {
        positive("chord", self.chord)?;
        finite("a", self.a)?;
        positive("alpha1", self.alpha1)?;
        positive("tau_p", self.tau_p)?;
        positive("tau_f", self.tau_f)?;
        finite("k_cp", self.k_cp)?;
        if !(self.sharpness >= 1.0 && self.sharpness.is_finite()) {
            return Err(crate::Error::param(
                "sharpness",
                self.sharpness,
                "must be a finite number ≥ 1",
            ));
        }
        Ok(self)
    }

    /// Static separation point f_st(α) = 1 / (1 + (α/α₁)^{2m}) ∈ (0, 1].
    pub fn f_static(&self, alpha: f64) -> f64 {
        1.0 / (1.0 + (alpha / self.alpha1).abs().powf(2.0 * self.sharpness))
    }

    /// Static lift coefficient (Kirchhoff) C_L = 2πα((1 + √f_st)/2)², positive up.
    pub fn cl_static(&self, alpha: f64) -> f64 {
        let s = self.f_static(alpha).sqrt();
        2.0 * std::f64::consts::PI * alpha * 0.25 * (1.0 + s) * (1.0 + s)
    }

    #[inline]
    fn downwash(&self, u: f64, q: [f64; 2], qd: [f64; 2]) -> f64 {
        qd[0] + u * q[1] + 0.5 * self.chord * (0.5 - self.a) * qd[1]
    }

    #[inline]
    fn effective_downwash(&self, w: f64, lag: &[f64]) -> f64 {
        let (a1, b1) = JONES_LAGS[0];
        let (a2, b2) = JONES_LAGS[1];
        (1.0 - a1 - a2) * w + a1 * b1 * lag[0] + a2 * b2 * lag[1]
    }

    fn theodorsen(&self) -> TheodorsenAero {
        TheodorsenAero {
            chord: self.chord,
            a: self.a,
        }
    }
}

impl AeroModel for DynamicStallAero {
    fn name(&self) -> String {
        "dynamic_stall".into()
    }
    fn chord(&self) -> f64 {
        self.chord
    }
    fn n_lag(&self) -> usize {
        4
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        thin_airfoil_apparent_mass(flow.rho, 0.5 * self.chord, self.a)
    }
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        let b = 0.5 * self.chord;
        let wc = self.effective_downwash(self.downwash(flow.u, q, qd), lag);
        let alpha_e = if flow.u != 0.0 { wc / flow.u } else { 0.0 };
        let s = self.f_static(alpha_e).sqrt();
        let f2 = (1.0 - lag[3]).clamp(0.0, 1.0);
        let k = f2 + (1.0 - f2) * (1.0 + 3.0 * s) / (4.0 * (1.0 + s));
        let [l, m] = thin_airfoil(flow.rho, flow.u, b, self.a, wc * k, qd[1], true);
        // circulatory lift (up) moved aft by k_cp (1 − f'') B: nose-down moment
        let l_circ_up = 2.0 * std::f64::consts::PI * flow.rho * flow.u * b * wc * k;
        [l, m - l_circ_up * self.k_cp * (1.0 - f2) * self.chord]
    }
    fn lag_rates(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]) {
        let b = 0.5 * self.chord;
        let w = self.downwash(flow.u, q, qd);
        let s = flow.u / b;
        out[0] = s * (w - JONES_LAGS[0].1 * lag[0]);
        out[1] = s * (w - JONES_LAGS[1].1 * lag[1]);
        let alpha_e = if flow.u != 0.0 {
            self.effective_downwash(w, lag) / flow.u
        } else {
            0.0
        };
        out[2] = s / self.tau_p * (alpha_e - lag[2]);
        out[3] = s / self.tau_f * (1.0 - self.f_static(lag[2]) - lag[3]);
    }
    /// The linearisation about α = 0 is attached flow (f_st(0) = 1, zero slope), so the
    /// frequency response is Theodorsen's exact one.
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        self.theodorsen().frequency_response(flow, omega)
    }
    fn elastic_axis(&self) -> Option<f64> {
        Some(self.a)
    }
    fn settle_time(&self, flow: &Flow) -> f64 {
        // ten of the slowest nonlinear time constants (τ_p + τ_f) b/U
        if flow.u > 0.0 {
            10.0 * (self.tau_p + self.tau_f) * 0.5 * self.chord / flow.u
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tunnel::{forced_forces, Motion};

    const RHO: f64 = 1.225;

    fn coeffs(l: &[f64], flow: &Flow, b_c: f64) -> Vec<f64> {
        // lift coefficient, positive up
        l.iter().map(|v| -v / (flow.q_dyn() * b_c)).collect()
    }

    /// Linear limit: at 0.05° the model is Theodorsen with Jones' lags (the time-domain
    /// realisation of Wagner's function) to 1e-6 of the force amplitude.
    #[test]
    fn small_amplitude_equals_theodorsen_jones() {
        let m = DynamicStallAero::thin_plate(0.25, -0.3).unwrap();
        let t = m.theodorsen();
        let flow = Flow { rho: RHO, u: 5.0 };
        let motion = Motion::two_frequency(1.3, 2.0, 0.05f64.to_radians(), 5e-5);
        let dt = 1.0 / 512.0;
        let (ls, ms) = forced_forces(&m, &flow, &motion, 0.0, dt, 1024, 1.0, "s").unwrap();
        let (lt, mt) = forced_forces(&t, &flow, &motion, 0.0, dt, 1024, 1.0, "t").unwrap();
        for (a, b) in [(&ls, &lt), (&ms, &mt)] {
            let pk = b.iter().fold(0.0_f64, |x, v| x.max(v.abs()));
            let err = a
                .iter()
                .zip(b)
                .fold(0.0_f64, |x, (p, q)| x.max((p - q).abs()));
            assert!(err < 1e-6 * pk, "error {} of peak", err / pk);
        }
    }

    /// Static limit: held at a constant angle the lift settles on Kirchhoff's
    /// C_L = 2πα((1 + √f)/2)² (Thwaites 1960; Leishman & Beddoes 1989).
    #[test]
    fn steady_lift_is_kirchhoff() {
        let m = DynamicStallAero::thin_plate(0.25, -0.5).unwrap();
        let flow = Flow { rho: RHO, u: 8.0 };
        for deg in [2.0, 8.0, 10.0, 14.0, 20.0] {
            let motion = Motion {
                pitch: vec![],
                heave: vec![],
                mean_pitch: f64::to_radians(deg),
            };
            let (l, mo) = forced_forces(&m, &flow, &motion, 0.0, 1e-3, 3, 3.0, "st").unwrap();
            let cl = coeffs(&l, &flow, 0.25)[2];
            let want = m.cl_static(f64::to_radians(deg));
            assert!((cl - want).abs() < 1e-6, "{deg}°: {cl} vs {want}");
            // about the quarter chord (a = −½) the moment is the cp shift only
            let f = m.f_static(f64::to_radians(deg));
            let cm = mo[2] / (flow.q_dyn() * 0.0625);
            assert!(
                (cm + cl * 0.25 * (1.0 - f)).abs() < 1e-6,
                "{deg}°: C_M {cm}"
            );
        }
        // stall: the static curve peaks near 9° at about 0.82 and falls beyond
        let peak = (0..300)
            .map(|i| m.cl_static(f64::to_radians(i as f64 * 0.1)))
            .fold(0.0, f64::max);
        assert!((0.80..0.85).contains(&peak), "C_L,max {peak}");
        assert!(m.cl_static(f64::to_radians(15.0)) < 0.8 * peak);
    }

    /// Dynamic stall (the qualitative result of pitching-aerofoil experiments, e.g.
    /// McAlister, Carr & McCroskey 1978, reproduced by every Beddoes–Leishman model):
    /// pitching through stall at K = bω/U = 0.1 the lift overshoots the static maximum on
    /// the upstroke and the C_L(α) loop runs clockwise (upstroke above downstroke).
    #[test]
    fn pitching_through_stall_overshoots_and_loops_clockwise() {
        let m = DynamicStallAero::thin_plate(0.25, -0.5).unwrap();
        let flow = Flow { rho: RHO, u: 5.0 };
        let freq = 0.1 * flow.u / 0.125 / (2.0 * std::f64::consts::PI);
        let motion = Motion {
            mean_pitch: 10f64.to_radians(),
            ..Motion::two_frequency(freq, 1.0, 10f64.to_radians(), 0.0)
        };
        let n = 2000;
        let period = 1.0 / freq;
        let dt = period / n as f64;
        let (l, _) = forced_forces(&m, &flow, &motion, 0.0, dt, n + 1, 5.0 * period, "d").unwrap();
        let cl = coeffs(&l, &flow, 0.25);
        let alpha: Vec<f64> = (0..=n).map(|i| motion.eval(i as f64 * dt).0[1]).collect();
        let static_max = (0..300)
            .map(|i| m.cl_static(f64::to_radians(i as f64 * 0.1)))
            .fold(0.0, f64::max);
        let dyn_max = cl.iter().fold(0.0_f64, |x, v| x.max(*v));
        assert!(
            dyn_max > 1.2 * static_max,
            "{dyn_max} vs static {static_max}"
        );
        // ∮ C_L dα = ∫_up C_L dα − ∫_down C_L dα > 0 when the upstroke lies above the
        // downstroke (a clockwise loop in the (α, C_L) plane)
        let area: f64 = (0..n)
            .map(|i| 0.5 * (cl[i] + cl[i + 1]) * (alpha[i + 1] - alpha[i]))
            .sum();
        assert!(area > 0.02, "loop integral {area}");
    }
}
