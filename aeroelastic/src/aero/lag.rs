//! The lag law of `identify` ([`identify::lag::LagLaw`]: one separation state x, the
//! Goman–Khrabrov / Øye form, Kirchhoff lift, x-driven moment columns) as an
//! aerodynamic model of the heave/pitch section, so that `flutter`, `lco`, `branch` and
//! `tunnel` fly it like any other model (issue 41, item 4).
//!
//! Variables (DESIGN.md §2): h down, α nose-up, U > 0, B the chord, b = B/2.
//!
//! - Effective angle α_e = α₀ + α + ḣ/U and pitch rate q = Bα̇/U, with α₀ the trim angle
//!   ([`LagAero::with_mean_angle`]; 0 by default).
//! - Lag state: the **separation deficit about the trim**, y = x̄ − x with x̄ = x₀(α₀)
//!   the static separation at the trim (x̄ = x₀(0) = 1 exactly, attached flow, without a
//!   trim). So the section's equilibrium is the origin of (h, α, ḣ, α̇, y), which is what
//!   [`super::linearize`], the flutter analysis and the Hopf scan of the branches assume.
//!   Rate: ẏ = −ẋ = −(2U/B)·`law.x_rate`(α_e, q, x̄ − y) (the law's rate is per convective
//!   time b/U).
//! - Forces per unit span: L = ½ρU²B·(C_L − C̄_L) (down), M = ½ρU²B²·(C_M − C̄_M)
//!   (nose-up about the elastic axis the law was fitted about), (C_L, C_M) =
//!   `law.coefficients`(α_e, q, x). Without a trim C̄ = 0 (absolute forces); with a trim α₀,
//!   C̄ = `law.coefficients`(α₀, 0, x̄) is the static load at the trim, carried by the
//!   structure's preload (a rig set at a mean incidence), so that the forces vanish at the
//!   equilibrium.
//! - Apparent mass: the thin-aerofoil matrix ([`super::thin_airfoil_apparent_mass`]) about
//!   the elastic axis a when it is known, else zero. The law carries no acceleration
//!   column (forced records do not separate it cleanly from the structure's inertia), so
//!   the thin-aerofoil value is the one physical estimate there is; without an axis there
//!   is no way to place it, and zero is the law as fitted.
//! - Frequency response: the exact response of the model linearised about its equilibrium
//!   (α₀, x̄): with g = 2U/(Bτ₁), ŷ-free form x̂ = g·x₀'(α₀)·(α̂_e − τ₂q̂/2)/(iω + g),
//!   Ĉ = ∂C/∂α_e·α̂_e + ∂C/∂q·q̂ + ∂C/∂x·x̂, and −ω²M_a. About α₀ = 0 the static curve
//!   has zero slope (x₀'(0) = 0), the lag state decouples and the response is the law's
//!   attached-flow (quasi-steady) response; about a trim in stall it carries the lag.
//!   The columns of the law are affine in (α_e, q) at fixed x, so ∂C/∂α_e and ∂C/∂q are
//!   differences of the law's own evaluations, exact; a channel with the instantaneous
//!   static column α_e·κ(x₀(α_e)) takes its ∂C/∂α_e by a central difference (1e-6 rad).
//! - Circulation lag ([`LagLaw::circulation_lag`] on): two more lag states, the Jones
//!   states about the trim w_i = z_i − α₀ (lag = [y, w₁, w₂], `n_lag` = 3), with
//!   ẇ_i = (2U/B)·b_i·(α_e − α₀ − w_i), and the law takes the circulatory angle
//!   α_c = `circulatory_angle`(α_e, α₀ + w) instead of α_e in its columns and its separation
//!   input (identify's law module docs). All states are continuous and vanish at the
//!   equilibrium. In the frequency response α̂_e becomes C_J(iω)·α̂_e with
//!   C_J(p) = 1 − Σ A_i·p/(p + g_i), g_i = 2U b_i/B: R. T. Jones' approximation of
//!   Theodorsen's function, exactly the linearised state equation.
//! - Pressure lag ([`LagLaw::pressure_lag`] τ_p > 0): one more state, last in `lag`, the
//!   filtered separation input about the trim v = u_f − α₀ with
//!   v̇ = (2U/(Bτ_p))·(u − α₀ − v), u = α_c − τ₂q/2 the law's input; the separation then
//!   follows x₀(α₀ + v). In the frequency response û becomes û·g_p/(iω + g_p),
//!   g_p = 2U/(Bτ_p).

use nalgebra::Matrix2;
use num_complex::Complex64;

use super::{thin_airfoil_apparent_mass, AeroModel, Flow};
use crate::error::{finite, positive};
use crate::{Error, Result};
use identify::lag::{circulation_rates, circulatory_angle, LagLaw, CIRCULATION_LAGS};

/// The lag law flown as an aerodynamic model (see the module docs): the lag state y = x̄ − x
/// (the separation deficit about the trim), and with the law's circulation lag the two
/// Jones states w₁, w₂ about the trim.
#[derive(Debug, Clone, PartialEq)]
pub struct LagAero {
    law: LagLaw,
    chord: f64,
    elastic_axis: Option<f64>,
    mean_angle: Option<f64>,
    /// Static separation x̄ = x₀(α₀) at the trim (1 without a trim).
    x_bar: f64,
    /// Static coefficients (C̄_L, C̄_M) at the trim (0 without a trim).
    c_bar: [f64; 2],
}

impl LagAero {
    /// The law `law` (nondimensional) flown on a section of chord `chord` B \[m\]; the
    /// elastic axis `elastic_axis` a [semi-chords aft of mid-chord], when known, places
    /// the thin-aerofoil apparent mass (the law's moment is about the axis of its records).
    /// No trim: absolute forces, equilibrium at α = 0 in attached flow.
    ///
    /// # Errors
    /// [`Error::Identify`] when the law is outside its physical bounds
    /// ([`LagLaw::check`], naming the parameter); [`Error::InvalidParameter`] for a
    /// non-positive `chord` or a non-finite `elastic_axis`.
    pub fn new(law: LagLaw, chord: f64, elastic_axis: Option<f64>) -> Result<Self> {
        law.check().map_err(|source| Error::Identify {
            context: "lag law".into(),
            source,
        })?;
        positive("chord", chord)?;
        if let Some(a) = elastic_axis {
            finite("elastic_axis", a)?;
        }
        Ok(LagAero {
            law,
            chord,
            elastic_axis,
            mean_angle: None,
            x_bar: 1.0,
            c_bar: [0.0; 2],
        })
    }

    /// The same model trimmed at the mean angle `alpha0` α₀ \[rad\] (nose-up): the state
    /// and the forces are taken about the static equilibrium (α₀, x₀(α₀)) and the static
    /// load there is the structure's (module docs). Flutter is then linearised about the
    /// equilibrium of x at α₀.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`mean_angle`) unless |α₀| < π/2.
    pub fn with_mean_angle(mut self, alpha0: f64) -> Result<Self> {
        if !alpha0.is_finite() || alpha0.abs() >= std::f64::consts::FRAC_PI_2 {
            return Err(Error::param(
                "mean_angle",
                alpha0,
                "must be finite with |mean_angle| < π/2 rad",
            ));
        }
        self.mean_angle = Some(alpha0);
        self.x_bar = self.law.x_static(alpha0);
        self.c_bar = self.law.coefficients(alpha0, 0.0, self.x_bar);
        Ok(self)
    }

    /// The law.
    pub fn law(&self) -> &LagLaw {
        &self.law
    }

    /// The trim angle α₀ \[rad\], `None` without a trim.
    pub fn mean_angle(&self) -> Option<f64> {
        self.mean_angle
    }

    /// Static separation x̄ = x₀(α₀) at the equilibrium (1 without a trim): the separation
    /// state is x = x̄ − y for the model's lag state y.
    pub fn x_equilibrium(&self) -> f64 {
        self.x_bar
    }

    /// (α_e, q) at heave rate `qd[0]`, pitch `q[1]` and pitch rate `qd[1]` for speed `u`
    /// (α_e = α₀ + α + ḣ/U, q = Bα̇/U).
    #[inline]
    fn inputs(&self, u: f64, q: [f64; 2], qd: [f64; 2]) -> (f64, f64) {
        let qq = self.chord * qd[1] / u;
        (
            self.mean_angle.unwrap_or(0.0)
                + LagLaw::alpha_e(q[1], qd[0] / u)
                + self.law.rate_share * qq,
            qq,
        )
    }

    /// The law's angle at (α_e, lag): α_c of the Jones states α₀ + w with the circulation
    /// lag on, α_e otherwise.
    #[inline]
    fn angle(&self, alpha_e: f64, lag: &[f64]) -> f64 {
        if self.law.circulation_lag {
            let a0 = self.mean_angle.unwrap_or(0.0);
            circulatory_angle(alpha_e, [a0 + lag[1], a0 + lag[2]])
        } else {
            alpha_e
        }
    }

    /// Slope dx₀/dα of the static separation curve at `alpha` (0 at α = 0, m ≥ 1).
    fn x_static_slope(&self, alpha: f64) -> f64 {
        if alpha == 0.0 {
            return 0.0;
        }
        let m2 = 2.0 * self.law.sharpness;
        let r = (alpha / self.law.alpha_star).abs().powf(m2);
        -m2 * r / alpha / ((1.0 + r) * (1.0 + r))
    }
}

impl AeroModel for LagAero {
    fn name(&self) -> String {
        "lag_law".into()
    }
    fn chord(&self) -> f64 {
        self.chord
    }
    fn n_lag(&self) -> usize {
        let jones = if self.law.circulation_lag { 2 } else { 0 };
        let pressure = usize::from(self.law.pressure_lag > 0.0);
        1 + jones + pressure
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        match self.elastic_axis {
            Some(a) => thin_airfoil_apparent_mass(flow.rho, 0.5 * self.chord, a),
            None => Matrix2::zeros(),
        }
    }
    /// L = ½ρU²B(C_L − C̄_L), M = ½ρU²B²(C_M − C̄_M) at x = x̄ − y; zero at U ≤ 0 (the law
    /// is written in U-normalised variables).
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        if flow.u <= 0.0 {
            return [0.0; 2];
        }
        let (ae, qq) = self.inputs(flow.u, q, qd);
        let ac = self.angle(ae, lag);
        let [cl, cm] = self.law.coefficients(ac, qq, self.x_bar - lag[0]);
        let p = flow.q_dyn() * self.chord;
        [
            p * (cl - self.c_bar[0]),
            p * self.chord * (cm - self.c_bar[1]),
        ]
    }
    /// ẏ = −(2U/B)·x_rate(α_c, q, x̄ − y) \[1/s\] and, with the circulation lag,
    /// ẇ_i = (2U/B)·b_i·(α_e − α₀ − w_i) \[rad/s\]; with the pressure lag
    /// ẏ = −(2U/B)·(x₀(α₀ + v) − x)/τ₁ and v̇ = (2U/(Bτ_p))·(u − α₀ − v) (module docs); zero
    /// at U ≤ 0 (frozen states).
    fn lag_rates(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]) {
        if flow.u <= 0.0 {
            out.iter_mut().for_each(|v| *v = 0.0);
            return;
        }
        let (ae, qq) = self.inputs(flow.u, q, qd);
        let g = 2.0 * flow.u / self.chord;
        let ac = self.angle(ae, lag);
        let x = self.x_bar - lag[0];
        if self.law.pressure_lag > 0.0 {
            let a0 = self.mean_angle.unwrap_or(0.0);
            let iv = out.len() - 1;
            let v = lag[iv];
            out[0] = -g * self.law.x_rate_filtered(a0 + v, x);
            out[iv] = g / self.law.pressure_lag * (self.law.input(ac, qq) - a0 - v);
        } else {
            out[0] = -g * self.law.x_rate(ac, qq, x);
        }
        if self.law.circulation_lag {
            let a0 = self.mean_angle.unwrap_or(0.0);
            let r = circulation_rates(ae, [a0 + lag[1], a0 + lag[2]]);
            out[1] = g * r[0];
            out[2] = g * r[1];
        }
    }
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        let u = flow.u;
        let b_c = self.chord;
        let a0 = self.mean_angle.unwrap_or(0.0);
        let xb = self.x_bar;
        let iw = Complex64::new(0.0, omega);
        // Jones' lag of the circulatory angle, C_J(iω) = 1 − Σ A_i iω/(iω + g_i)
        let cj = if self.law.circulation_lag {
            CIRCULATION_LAGS
                .iter()
                .fold(Complex64::new(1.0, 0.0), |c, &(a, b)| {
                    c - a * iw / (iw + 2.0 * u * b / b_c)
                })
        } else {
            Complex64::new(1.0, 0.0)
        };
        // per unit ĥ: α̂_e = iω/U, q̂ = 0; per unit α̂: α̂_e = 1, q̂ = iωB/U (α̂_c = C_J α̂_e)
        let c = self.law.rate_share;
        let inputs = [
            (cj * iw / u, Complex64::new(0.0, 0.0)),
            (cj * (1.0 + c * iw * b_c / u), iw * b_c / u),
        ];
        let g = 2.0 * u / (b_c * self.law.tau1);
        let mut gain = g * self.x_static_slope(self.law.input(a0, 0.0)) / (iw + g);
        if self.law.pressure_lag > 0.0 {
            let gp = 2.0 * u / (b_c * self.law.pressure_lag);
            gain *= gp / (iw + gp);
        }
        let ma = self.apparent_mass(flow);
        let scale = [flow.q_dyn() * b_c, flow.q_dyn() * b_c * b_c];
        let mut h = Matrix2::<Complex64>::zeros();
        for (i, ch) in [&self.law.lift, &self.law.moment].into_iter().enumerate() {
            let xs = |a: f64| self.law.x_static(a);
            let c0 = ch.value(a0, 0.0, xb, xs(a0));
            // the columns are affine in α_e and q at fixed x, except the instantaneous
            // static Kirchhoff lift α_e·κ(x₀(α_e)): its slope by a central difference
            let c_a = if ch.uses_static() {
                let d = 1e-6;
                (ch.value(a0 + d, 0.0, xb, xs(a0 + d)) - ch.value(a0 - d, 0.0, xb, xs(a0 - d)))
                    / (2.0 * d)
            } else {
                ch.value(a0 + 1.0, 0.0, xb, xs(a0)) - c0
            };
            let c_q = ch.value(a0, 1.0, xb, xs(a0)) - c0;
            let c_x = ch.d_dx(a0, 0.0, xb, xs(a0));
            for (j, &(ae, qq)) in inputs.iter().enumerate() {
                let x_hat = gain * (ae - 0.5 * self.law.tau2 * qq);
                h[(i, j)] =
                    scale[i] * (c_a * ae + c_q * qq + c_x * x_hat) - omega * omega * ma[(i, j)];
            }
        }
        h
    }
    fn elastic_axis(&self) -> Option<f64> {
        self.elastic_axis
    }
    /// Ten separation lags plus the input lead and the pressure lag, 10(τ₁ + τ₂ + τ_p)·b/U
    /// \[s\] (the Jones states
    /// are linear and weak, A₁ = 0.165 on the slow one: not counted, as for the stall
    /// truth).
    fn settle_time(&self, flow: &Flow) -> f64 {
        if flow.u > 0.0 {
            10.0 * (self.law.tau1 + self.law.tau2 + self.law.pressure_lag) * 0.5 * self.chord
                / flow.u
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::{linearize, state_space_response, QuasiSteady, QuasiSteadyKind};
    use identify::lag::{FittedRange, LagChannel, LagColumn};

    const RHO: f64 = 1.225;

    /// The example law of `scenarios/plate-lag.lag_law.json`: attached-flow part equal to
    /// the quasi-steady thin aerofoil about a = −0.3.
    fn plate_law() -> LagLaw {
        use std::f64::consts::PI;
        LagLaw {
            tau1: 3.0,
            tau2: 1.0,
            alpha_star: 0.2,
            sharpness: 4.0,
            lift: LagChannel {
                terms: vec![(LagColumn::Kirchhoff, -2.0 * PI), (LagColumn::Q, -1.3 * PI)],
            },
            moment: LagChannel {
                terms: vec![
                    (LagColumn::Kirchhoff, 0.2 * PI),
                    (LagColumn::Q, -0.12 * PI),
                    (LagColumn::KirchhoffSep, -0.5 * PI),
                ],
            },
            range: FittedRange {
                alpha_e: [-0.5, 0.5],
                k: [0.05, 1.5],
            },
            circulation_lag: false,
            rate_share: 0.0,
            pressure_lag: 0.0,
        }
    }

    fn model() -> LagAero {
        LagAero::new(plate_law(), 0.25, Some(-0.3)).unwrap()
    }

    /// The example law with its circulation lag on, a pitch-rate share 0.4 of the effective
    /// angle and part of its lift on the instantaneous static Kirchhoff column.
    fn rate_static() -> LagAero {
        let mut l = plate_law();
        l.circulation_lag = true;
        l.rate_share = 0.4;
        l.lift.terms = vec![
            (LagColumn::Kirchhoff, -5.0),
            (LagColumn::KirchhoffStatic, -1.28),
            (LagColumn::Q, -1.3 * std::f64::consts::PI),
        ];
        LagAero::new(l, 0.25, Some(-0.3)).unwrap()
    }

    /// The example law with its circulation lag, a rate share 0.4, a pressure lag τ_p = 1.7
    /// and the separated-flow blend columns in both channels.
    fn pressure_blend() -> LagAero {
        let mut l = plate_law();
        l.circulation_lag = true;
        l.rate_share = 0.4;
        l.pressure_lag = 1.7;
        l.lift.terms = vec![
            (LagColumn::Blend, -2.0 * std::f64::consts::PI),
            (LagColumn::Q, -0.5 * std::f64::consts::PI),
        ];
        l.moment.terms = vec![
            (LagColumn::Blend, 0.2 * std::f64::consts::PI),
            (LagColumn::BlendSep, -0.5 * std::f64::consts::PI),
            (LagColumn::Q, -0.2 * std::f64::consts::PI),
        ];
        LagAero::new(l, 0.25, Some(-0.3)).unwrap()
    }

    /// The example law with its circulation lag on.
    fn lagged() -> LagAero {
        let mut l = plate_law();
        l.circulation_lag = true;
        LagAero::new(l, 0.25, Some(-0.3)).unwrap()
    }

    /// With the circulation lag the model has the two Jones states; attached, about α = 0,
    /// its frequency response is the thin aerofoil's with Jones' approximation of
    /// Theodorsen's function on the circulatory angle (no three-quarter-chord pitch-rate
    /// term: the law's q column is unlagged); the states vanish at the (trimmed) equilibrium.
    #[test]
    fn circulation_lag_states_are_jones_and_zero_at_the_equilibrium() {
        assert_eq!(CIRCULATION_LAGS, crate::theodorsen::JONES_LAGS);
        let m = lagged();
        assert_eq!(m.n_lag(), 3);
        assert_eq!(model().n_lag(), 1);
        let flow = Flow { rho: RHO, u: 6.0 };
        let g = 2.0 * 6.0 / 0.25;
        let mut r = [0.0; 3];
        for t in [lagged(), lagged().with_mean_angle(0.22).unwrap()] {
            let z = t.forces(&flow, [0.0; 2], [0.0; 2], &[0.0; 3]);
            assert!(z[0].abs() < 1e-12 && z[1].abs() < 1e-12, "{z:?}");
            t.lag_rates(&flow, [0.0; 2], [0.0; 2], &[0.0; 3], &mut r);
            assert!(r.iter().all(|v| v.abs() < 1e-12), "{r:?}");
        }
        // ẇ_i = g b_i (α_e − α₀ − w_i); the force sees α_c
        let (q, qd, lag) = ([0.0, 0.1], [0.0; 2], [0.0, 0.02, -0.01]);
        m.lag_rates(&flow, q, qd, &lag, &mut r);
        assert!((r[1] - g * 0.0455 * (0.1 - 0.02)).abs() < 1e-12);
        assert!((r[2] - g * 0.3 * (0.1 + 0.01)).abs() < 1e-12);
        let ac = (1.0 - 0.165 - 0.335) * 0.1 + 0.165 * 0.02 - 0.335 * 0.01;
        let mut l = plate_law();
        l.circulation_lag = true;
        let p = 0.5 * RHO * 36.0 * 0.25;
        let f = m.forces(&flow, q, qd, &lag);
        assert!((f[0] - p * l.coefficients(ac, 0.0, 1.0)[0]).abs() < 1e-12 * p);
        // attached response: −2πC_J(k) on the angle
        let omega = 20.0;
        let h = m.frequency_response(&flow, omega);
        let k = omega * 0.125 / 6.0;
        let ik = Complex64::new(0.0, k);
        let cj = Complex64::new(1.0, 0.0) - 0.165 * ik / (ik + 0.0455) - 0.335 * ik / (ik + 0.3);
        let h0 = model().frequency_response(&flow, omega);
        let circ = -2.0 * std::f64::consts::PI * p;
        let want = h0[(0, 1)] - circ + circ * cj;
        assert!(
            (h[(0, 1)] - want).norm() < 1e-9 * p,
            "{} vs {want}",
            h[(0, 1)]
        );
    }

    #[test]
    fn forces_and_rates_are_the_law_evaluated_directly() {
        let m = model();
        let flow = Flow { rho: RHO, u: 6.0 };
        let (q, qd, y) = ([0.01, 0.3], [0.2, 1.5], 0.4);
        let ae = 0.3 + 0.2 / 6.0;
        let qq = 0.25 * 1.5 / 6.0;
        let x = 1.0 - y;
        let [cl, cm] = plate_law().coefficients(ae, qq, x);
        let f = m.forces(&flow, q, qd, &[y]);
        let p = 0.5 * RHO * 36.0 * 0.25;
        assert!((f[0] - p * cl).abs() < 1e-12 * p);
        assert!((f[1] - p * 0.25 * cm).abs() < 1e-12 * p);
        let mut r = [0.0];
        m.lag_rates(&flow, q, qd, &[y], &mut r);
        let want = -(2.0 * 6.0 / 0.25) * (plate_law().x_static(ae - 0.5 * qq) - x) / 3.0;
        assert!(
            (r[0] - want).abs() < 1e-12 * want.abs(),
            "{} vs {want}",
            r[0]
        );
        // the origin is the equilibrium: no force, no rate
        assert_eq!(m.forces(&flow, [0.0; 2], [0.0; 2], &[0.0]), [0.0, 0.0]);
        m.lag_rates(&flow, [0.0; 2], [0.0; 2], &[0.0], &mut r);
        assert_eq!(r[0], 0.0);
        // trimmed: forces relative to the static load at the trim, zero at the origin
        let t = model().with_mean_angle(0.25).unwrap();
        let z = t.forces(&flow, [0.0; 2], [0.0; 2], &[0.0]);
        assert!(z[0].abs() < 1e-12 && z[1].abs() < 1e-12, "{z:?}");
        t.lag_rates(&flow, [0.0; 2], [0.0; 2], &[0.0], &mut r);
        assert!(r[0].abs() < 1e-12);
        let f = t.forces(&flow, [0.0, 0.05], [0.0; 2], &[0.0]);
        let xb = plate_law().x_static(0.25);
        let want = p
            * (plate_law().coefficients(0.3, 0.0, xb)[0]
                - plate_law().coefficients(0.25, 0.0, xb)[0]);
        assert!((f[0] - want).abs() < 1e-12 * p);
    }

    /// The exact frequency response equals the time-domain realisation linearised by
    /// finite differences ([`state_space_response`]), attached and trimmed in stall.
    #[test]
    fn frequency_response_equals_the_linearised_time_domain_form() {
        for m in [
            model(),
            model().with_mean_angle(0.22).unwrap(),
            lagged(),
            lagged().with_mean_angle(0.22).unwrap(),
            rate_static(),
            rate_static().with_mean_angle(0.22).unwrap(),
            pressure_blend(),
            pressure_blend().with_mean_angle(0.22).unwrap(),
        ] {
            let flow = Flow { rho: RHO, u: 7.0 };
            for omega in [0.0, 3.0, 20.0, 80.0] {
                let h = m.frequency_response(&flow, omega);
                let s = state_space_response(&m, &flow, omega).unwrap();
                let pk = h.iter().fold(0.0_f64, |a, v| a.max(v.norm()));
                for (a, b) in h.iter().zip(s.iter()) {
                    assert!((a - b).norm() < 1e-6 * pk, "ω {omega}: {a} vs {b}");
                }
            }
        }
    }

    /// The linearisation by differences: lag rate −g y (g = 2U/(Bτ₁)), decoupled from the
    /// motion about α = 0 (x₀'(0) = 0); about a stalled trim the lag is driven by α with
    /// gain g·x₀'(α₀) and τ₂ lead, and the force by ∂C/∂x.
    #[test]
    fn linearisation_matches_finite_differences_of_the_law() {
        let flow = Flow { rho: RHO, u: 5.0 };
        let g = 2.0 * 5.0 / (0.25 * 3.0);
        let lin = linearize(&model(), &flow);
        assert!((lin.g[(0, 0)] + g).abs() < 1e-6 * g);
        assert!(lin.e.iter().chain(lin.f.iter()).all(|v| v.abs() < 1e-6));
        let a0 = 0.22;
        let t = model().with_mean_angle(a0).unwrap();
        let lin = linearize(&t, &flow);
        let law = plate_law();
        let d = 1e-6;
        let slope = (law.x_static(a0 + d) - law.x_static(a0 - d)) / (2.0 * d);
        // ẏ = −ẋ: ∂ẏ/∂α = −g x₀', ∂ẏ/∂α̇ = +g x₀' τ₂ B/(2U)
        assert!((lin.e[(0, 1)] + g * slope).abs() < 1e-5 * g * slope.abs());
        let want_f = g * slope * 0.5 * 1.0 * 0.25 / 5.0;
        assert!((lin.f[(0, 1)] - want_f).abs() < 1e-5 * want_f.abs());
        // ∂L/∂y = −½ρU²B ∂C_L/∂x
        let xb = law.x_static(a0);
        let p = 0.5 * RHO * 25.0 * 0.25;
        let want_d = -p * law.lift.d_dx(a0, 0.0, xb, law.x_static(a0));
        assert!((lin.d[(0, 0)] - want_d).abs() < 1e-6 * want_d.abs());
    }

    /// At k → 0 the response is the static slope of the law's static forces
    /// C(α, 0, x₀(α)) at the equilibrium; attached, it is the thin aerofoil's 2π.
    #[test]
    fn zero_frequency_response_is_the_static_slope() {
        let flow = Flow { rho: RHO, u: 6.0 };
        let law = plate_law();
        let p = 0.5 * RHO * 36.0 * 0.25;
        for (a0, lag) in [0.0, 0.15, 0.2, 0.3]
            .into_iter()
            .flat_map(|a| [(a, false), (a, true)])
        {
            let m = if lag { lagged() } else { model() }
                .with_mean_angle(a0)
                .unwrap();
            let h = m.frequency_response(&flow, 1e-9);
            let d = 1e-6;
            let stat = |a: f64| law.coefficients(a, 0.0, law.x_static(a));
            let (cp, cm) = (stat(a0 + d), stat(a0 - d));
            for i in 0..2 {
                let s = (cp[i] - cm[i]) / (2.0 * d) * p * if i == 1 { 0.25 } else { 1.0 };
                assert!(
                    (h[(i, 1)].re - s).abs() < 1e-5 * p,
                    "α₀ {a0} row {i}: {} vs {s}",
                    h[(i, 1)].re
                );
                assert!(h[(i, 0)].norm() < 1e-6 * p);
            }
        }
        let h = model().frequency_response(&flow, 0.0);
        assert!((h[(0, 1)].re + 2.0 * std::f64::consts::PI * p).abs() < 1e-9 * p);
    }

    /// About α = 0 the example law is the quasi-steady thin aerofoil with its
    /// noncirculatory terms (same a): equal frequency responses at every ω.
    #[test]
    fn attached_example_law_is_the_quasi_steady_thin_aerofoil() {
        let qs = QuasiSteady::new(0.25, -0.3, QuasiSteadyKind::QuasiSteady, true).unwrap();
        let flow = Flow { rho: RHO, u: 4.0 };
        for omega in [0.0, 5.0, 22.0, 100.0] {
            let a = model().frequency_response(&flow, omega);
            let b = qs.frequency_response(&flow, omega);
            let pk = b.iter().fold(0.0_f64, |x, v| x.max(v.norm()));
            for (x, y) in a.iter().zip(b.iter()) {
                assert!((x - y).norm() < 1e-12 * pk, "ω {omega}: {x} vs {y}");
            }
        }
        // without an axis, no apparent mass
        let m = LagAero::new(plate_law(), 0.25, None).unwrap();
        assert_eq!(m.apparent_mass(&flow), Matrix2::zeros());
    }

    #[test]
    fn bad_parameters_are_refused_by_name() {
        let mut l = plate_law();
        l.tau1 = 0.0;
        let e = LagAero::new(l, 0.25, None).unwrap_err().to_string();
        assert!(e.contains("tau1"), "{e}");
        let e = LagAero::new(plate_law(), -1.0, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("chord"), "{e}");
        let e = LagAero::new(plate_law(), 0.25, Some(f64::NAN))
            .unwrap_err()
            .to_string();
        assert!(e.contains("elastic_axis"), "{e}");
        let e = model().with_mean_angle(2.0).unwrap_err().to_string();
        assert!(e.contains("mean_angle"), "{e}");
    }
}
