//! One forced case in the lag law's variables, and the separation state x(t) it drives at
//! its periodic steady state.
//!
//! The lag equation τ₁ dx/ds + x = x₀(u) (s = tU/b convective time, [`super::law`]) is
//! integrated exactly per sample step with the input x₀(u) taken linear over the step (a
//! first-order-hold exponential integrator): with h = Δs/τ₁ and E = e^{−h},
//!
//! x_{n+1} = E·x_n + (1 − E)·f_n + (f_{n+1} − f_n)·(1 − (1 − E)/h),  f = x₀(u),
//!
//! a convex combination of x_n, f_n and f_{n+1}, so x stays in \[0, 1\].
//!
//! Periodic steady state: the equation is linear in x, so with x_p the solution started at
//! x(0) = 0 and T the forcing period in convective time, x(0)* = x_p(T)/(1 − e^{−T/τ₁}).
//! That needs the motion to repeat with the forcing period (α_e(t + T) = α_e(t) to
//! [`PERIODIC_TOLERANCE`] of the amplitude). Otherwise x starts on the static curve and the
//! first [`SETTLE_TIMES`]·τ₁ convective times are dropped; at least one forcing period (or,
//! without a known period, half the record) must remain.

use crate::record::NondimCase;
use crate::{Error, Result};

use super::law::{circulatory_angle, LagLaw, CIRCULATION_LAGS};

/// RMS of α_e(t + T) − α_e(t) allowed for a periodic record, as a fraction of the amplitude
/// (half the peak-to-peak α_e).
pub const PERIODIC_TOLERANCE: f64 = 0.1;

/// Number of separation lags τ₁ dropped from a record that is not periodic.
pub const SETTLE_TIMES: f64 = 5.0;

/// One forced case in the lag law's variables.
#[derive(Debug, Clone, PartialEq)]
pub struct LagSeries {
    /// Case id.
    pub id: String,
    /// Effective angle α_e = α + ḣ/U \[rad\] (absolute: the mean angle included).
    pub alpha_e: Vec<f64>,
    /// q = Bα̇/U.
    pub q: Vec<f64>,
    /// C_L (positive down).
    pub c_lift: Vec<f64>,
    /// C_M (positive nose-up).
    pub c_moment: Vec<f64>,
    /// Sample interval \[s\].
    pub dt: f64,
    /// Convective step Δs = dt·2U/B per sample.
    pub ds: f64,
    /// Forcing period in samples (T/dt), when a forcing frequency is known.
    pub period_samples: Option<f64>,
    /// Whether the motion repeats with the forcing period (module docs).
    pub periodic: bool,
    /// RMS of α_e(t + T) − α_e(t) over the amplitude (0 when no period is known).
    pub periodic_misfit: f64,
    /// Reduced frequency K = Bω/U of the forcing (pitch first, else heave; 0 if none).
    pub k: f64,
    /// Mean of α \[rad\].
    pub mean_alpha: f64,
    /// Circulatory angle α_c \[rad\] of the Jones circulation lag ([`super::law`] module
    /// docs) at every sample: at the periodic steady state of a periodic record (each Jones
    /// state z_i is the first-order lag of α_e with τ = 1/b_i, computed like x), otherwise
    /// with both states started at the record's mean α_e (the slow state's own settling,
    /// 5/b₁ ≈ 110 b/U, is longer than most records).
    pub alpha_c: Vec<f64>,
    /// Half the peak-to-peak α \[rad\].
    pub amplitude: f64,
}

impl LagSeries {
    /// The lag law's variables of a nondimensional case.
    ///
    /// # Errors
    /// [`Error::InvalidData`] naming the case for fewer than 8 samples, a non-positive dt,
    /// chord or wind speed, series of unequal length or a non-finite value.
    pub fn new(case: &NondimCase) -> Result<LagSeries> {
        Self::with_rate_share(case, 0.0)
    }

    /// [`LagSeries::new`] with the effective angle α_e = α + ḣ/U + c·Bα̇/U
    /// ([`LagLaw::rate_share`] c).
    ///
    /// # Errors
    /// As [`LagSeries::new`].
    pub fn with_rate_share(case: &NondimCase, c: f64) -> Result<LagSeries> {
        let id = case.meta.id.clone();
        let bad = |field: &str, message: String| Error::InvalidData {
            case: id.clone(),
            field: field.to_string(),
            message,
        };
        let n = case.c_lift.len();
        if n < 8 {
            return Err(bad(
                "samples",
                format!("{n} samples; the lag law needs ≥ 8"),
            ));
        }
        if case.x.iter().any(|v| v.len() != n) || case.c_moment.len() != n {
            return Err(bad("samples", "series of unequal length".to_string()));
        }
        let u = case.meta.wind_speed;
        if !(u.is_finite() && u > 0.0) {
            return Err(bad("wind_speed", format!("{u} m/s must be > 0")));
        }
        if !(case.chord.is_finite() && case.chord > 0.0) {
            return Err(bad("chord", format!("{} m must be > 0", case.chord)));
        }
        if !(case.dt.is_finite() && case.dt > 0.0) {
            return Err(bad("dt", format!("{} s must be > 0", case.dt)));
        }
        let alpha_e: Vec<f64> = case.x[0]
            .iter()
            .zip(&case.x[3])
            .zip(&case.x[1])
            .map(|((a, h), q)| a + h + c * q)
            .collect();
        for (name, v) in [
            ("alpha_e", &alpha_e),
            ("q", &case.x[1]),
            ("c_lift", &case.c_lift),
            ("c_moment", &case.c_moment),
        ] {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(bad(name, format!("non-finite value at sample {i}")));
            }
        }
        let ds = case.dt * 2.0 * u / case.chord;
        let freq = case
            .forcing
            .pitch
            .or(case.meta.freq_pitch)
            .or(case.forcing.heave)
            .filter(|f| f.is_finite() && *f > 0.0);
        let k = freq.map_or(0.0, |f| case.chord * 2.0 * std::f64::consts::PI * f / u);
        let period_samples = freq.map(|f| 1.0 / (f * case.dt));
        let (lo, hi) = alpha_e
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let amp_e = 0.5 * (hi - lo);
        let (periodic, periodic_misfit) = match period_samples {
            Some(p) if p + 1.0 < n as f64 && amp_e > 0.0 => {
                let m = periodic_misfit(&alpha_e, p) / amp_e;
                (m <= PERIODIC_TOLERANCE, m)
            }
            _ => (false, 0.0),
        };
        let alpha = &case.x[0];
        let mean_alpha = alpha.iter().sum::<f64>() / n as f64;
        let (alo, ahi) = alpha
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let mean_e = alpha_e.iter().sum::<f64>() / n as f64;
        let mut z = [vec![0.0; n], vec![0.0; n]];
        for (zi, (_, b)) in z.iter_mut().zip(CIRCULATION_LAGS) {
            let per = if periodic { period_samples } else { None };
            first_order(&alpha_e, ds * b, per, mean_e, zi);
        }
        let alpha_c: Vec<f64> = (0..n)
            .map(|i| circulatory_angle(alpha_e[i], [z[0][i], z[1][i]]))
            .collect();
        Ok(LagSeries {
            alpha_c,
            id: id.clone(),
            alpha_e,
            q: case.x[1].clone(),
            c_lift: case.c_lift.clone(),
            c_moment: case.c_moment.clone(),
            dt: case.dt,
            ds,
            period_samples,
            periodic,
            periodic_misfit,
            k,
            mean_alpha,
            amplitude: 0.5 * (ahi - alo),
        })
    }

    /// The angle `law` takes at every sample \[rad\]: α_c with its circulation lag on, α_e
    /// otherwise.
    pub fn angle(&self, law: &LagLaw) -> &[f64] {
        if law.circulation_lag {
            &self.alpha_c
        } else {
            &self.alpha_e
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.alpha_e.len()
    }

    /// True without samples.
    pub fn is_empty(&self) -> bool {
        self.alpha_e.is_empty()
    }

    /// Separation state x at every sample for `law`'s (τ₁, τ₂, α*, m) (module docs), into
    /// `x` (resized to the record). Returns the first sample at which x is settled (0 for a
    /// periodic record).
    ///
    /// # Errors
    /// [`Error::TooShort`] naming the case when a record that is not periodic keeps less
    /// than one forcing period (half the record without a known period) after the
    /// [`SETTLE_TIMES`]·τ₁ it needs to settle.
    pub fn simulate(&self, law: &LagLaw, x: &mut Vec<f64>) -> Result<usize> {
        self.simulate_angle(law, self.angle(law), x)
    }

    /// The forcing period in samples when the record is periodic (the periodic steady state
    /// is used), else `None`.
    fn period(&self) -> Option<f64> {
        if self.periodic {
            self.period_samples
        } else {
            None
        }
    }

    /// The separation input u = angle − τ₂·q/2 at every sample, and the filtered input u_f
    /// (module docs of [`LagLaw::pressure_lag`]; `None` without a pressure lag).
    fn inputs(&self, law: &LagLaw, angle: &[f64]) -> (Vec<f64>, Option<Vec<f64>>) {
        let u: Vec<f64> = angle
            .iter()
            .zip(&self.q)
            .map(|(&a, &q)| law.input(a, q))
            .collect();
        // the pressure lag filters the input first (periodic like x, or from its first value)
        let uf = (law.pressure_lag > 0.0).then(|| {
            let mut uf = vec![0.0; u.len()];
            first_order(&u, self.ds / law.pressure_lag, self.period(), u[0], &mut uf);
            uf
        });
        (u, uf)
    }

    /// [`LagSeries::simulate`] driven by `angle` (one value per sample \[rad\]) instead of
    /// [`LagSeries::angle`] (the output-error fit moves the rate share c, which moves the
    /// angle).
    ///
    /// # Errors
    /// As [`LagSeries::simulate`].
    pub(crate) fn simulate_angle(
        &self,
        law: &LagLaw,
        angle: &[f64],
        x: &mut Vec<f64>,
    ) -> Result<usize> {
        let n = self.len();
        let (u, uf) = self.inputs(law, angle);
        let u = uf.unwrap_or(u);
        let f: Vec<f64> = u.iter().map(|&v| law.x_static(v)).collect();
        x.clear();
        x.resize(n, 0.0);
        let h = self.ds / law.tau1;
        if self.periodic {
            first_order(&f, h, self.period_samples, f[0], x);
            // the periodic solution lies in [0, 1]; rounding must not put it outside
            for v in x.iter_mut() {
                *v = v.clamp(0.0, 1.0);
            }
            return Ok(0);
        }
        first_order(&f, h, None, f[0], x);
        let drop = (SETTLE_TIMES * (law.tau1 + law.pressure_lag) / self.ds).ceil();
        let need = self.period_samples.unwrap_or(0.5 * n as f64).max(1.0);
        let left = n as f64 - drop;
        if left < need {
            let why = match self.period_samples {
                Some(_) if self.periodic_misfit > 0.0 => format!(
                    "the motion is not periodic (α(t+T) differs from α(t) by {:.3} of the amplitude, \
                     tolerance {PERIODIC_TOLERANCE}), so the separation state must settle from a \
                     start: {SETTLE_TIMES}·τ₁ = {:.3} s (τ₁ = {:.3} b/U), then one forcing period",
                    self.periodic_misfit,
                    drop * self.dt,
                    law.tau1
                ),
                Some(_) => format!(
                    "the record holds less than two forcing periods, so the separation state must \
                     settle from a start: {SETTLE_TIMES}·τ₁ = {:.3} s (τ₁ = {:.3} b/U), then one forcing period",
                    drop * self.dt,
                    law.tau1
                ),
                None => format!(
                    "no forcing frequency: the separation state must settle from a start, \
                     {SETTLE_TIMES}·τ₁ = {:.3} s (τ₁ = {:.3} b/U), then half the record",
                    drop * self.dt,
                    law.tau1
                ),
            };
            return Err(Error::TooShort {
                case: self.id.clone(),
                duration: n as f64 * self.dt,
                needed: (drop + need) * self.dt,
                reason: format!("record too short for the separation state to settle: {why}"),
            });
        }
        Ok(drop as usize)
    }
}

/// Index of each nonlinear constant in the sensitivity arrays of
/// [`LagSeries::sensitivities`]: θ = (τ₁, τ₂, α*, m, c, τ_p).
pub(crate) const N_THETA: usize = 6;

impl LagSeries {
    /// ∂(angle)/∂c of the law's angle with respect to the rate share c (α_e = α + ḣ/U + c·q
    /// is affine in c): q itself, or with the circulation lag the Jones response of q
    /// (α_c is linear in α_e, its states started like [`LagSeries::with_rate_share`]'s),
    /// so that angle(c) = angle(c₀) + (c − c₀)·∂(angle)/∂c.
    pub(crate) fn rate_share_tangent(&self, circulation_lag: bool) -> Vec<f64> {
        if !circulation_lag {
            return self.q.clone();
        }
        let n = self.len();
        let mean_q = self.q.iter().sum::<f64>() / n as f64;
        let mut z = [vec![0.0; n], vec![0.0; n]];
        for (zi, (_, b)) in z.iter_mut().zip(CIRCULATION_LAGS) {
            first_order(&self.q, self.ds * b, self.period(), mean_q, zi);
        }
        (0..n)
            .map(|i| circulatory_angle(self.q[i], [z[0][i], z[1][i]]))
            .collect()
    }

    /// Forward sensitivities ∂x/∂θ_j of the separation state that
    /// [`LagSeries::simulate_angle`] computed into `x` (same `law` and `angle`), for every
    /// j with `free[j]` (an empty vector otherwise), θ = (τ₁, τ₂, α*, m, c, τ_p):
    /// the tangent of the discrete integration (the same exponential step differentiated,
    /// including its dependence on h = Δs/τ and the periodic start), so each is the exact
    /// derivative of the simulated x, not of the continuous state. `d_angle_dc` is
    /// [`LagSeries::rate_share_tangent`] (read only when c is free). The clamp of the
    /// periodic state to \[0, 1\] (rounding only) is not differentiated.
    pub(crate) fn sensitivities(
        &self,
        law: &LagLaw,
        angle: &[f64],
        d_angle_dc: &[f64],
        free: [bool; N_THETA],
        x: &[f64],
    ) -> [Vec<f64>; N_THETA] {
        let n = self.len();
        let per = self.period();
        let (u, uf) = self.inputs(law, angle);
        // tangents of the separation input u (before the pressure lag) per parameter
        let du: [Option<Vec<f64>>; N_THETA] = [
            None,
            free[1].then(|| self.q.iter().map(|q| -0.5 * q).collect()),
            None,
            None,
            free[4].then(|| d_angle_dc.to_vec()),
            None,
        ];
        // tangents of the filtered input u_f (what x₀ reads)
        let mut duf: [Option<Vec<f64>>; N_THETA] = Default::default();
        match &uf {
            Some(ufv) => {
                let hp = self.ds / law.pressure_lag;
                for j in 0..N_THETA {
                    if !free[j] {
                        continue;
                    }
                    if let Some(d) = &du[j] {
                        let mut out = vec![0.0; n];
                        first_order_tangent(&u, ufv, Some(d), hp, 0.0, per, d[0], &mut out);
                        duf[j] = Some(out);
                    }
                }
                if free[5] {
                    let mut out = vec![0.0; n];
                    let dh = -hp / law.pressure_lag;
                    first_order_tangent(&u, ufv, None, hp, dh, per, 0.0, &mut out);
                    duf[5] = Some(out);
                }
            }
            None => {
                duf.clone_from(&du);
                if free[5] {
                    // τ_p → 0⁺: the filter's tangent tends to −du/ds; taken at a lag of
                    // 10⁻⁶ convective steps (the discrete limit to rounding)
                    let tp = 1e-6 * self.ds;
                    let hp = self.ds / tp;
                    let mut ufv = vec![0.0; n];
                    first_order(&u, hp, per, u[0], &mut ufv);
                    let mut out = vec![0.0; n];
                    first_order_tangent(&u, &ufv, None, hp, -hp / tp, per, 0.0, &mut out);
                    duf[5] = Some(out);
                }
            }
        }
        let ue = uf.as_deref().unwrap_or(&u);
        // f = x₀(u_f) and its tangents
        // one power per sample for both (the same operations as `law.x_static`)
        let (f, parts): (Vec<f64>, Vec<[f64; 3]>) =
            ue.iter().map(|&v| x_static_with_partials(law, v)).unzip();
        let mut df: [Option<Vec<f64>>; N_THETA] = Default::default();
        for j in 1..N_THETA {
            if !free[j] {
                continue;
            }
            df[j] = Some(match j {
                2 => parts.iter().map(|p| p[1]).collect(),
                3 => parts.iter().map(|p| p[2]).collect(),
                _ => match &duf[j] {
                    Some(d) => parts.iter().zip(d).map(|(p, d)| p[0] * d).collect(),
                    None => vec![0.0; n],
                },
            });
        }
        let h = self.ds / law.tau1;
        let mut out: [Vec<f64>; N_THETA] = Default::default();
        for j in 0..N_THETA {
            if !free[j] {
                continue;
            }
            let mut dx = vec![0.0; n];
            let dh = if j == 0 { -h / law.tau1 } else { 0.0 };
            let d = df[j].as_deref();
            first_order_tangent(&f, x, d, h, dh, per, d.map_or(0.0, |d| d[0]), &mut dx);
            out[j] = dx;
        }
        out
    }
}

/// The static separation curve x₀(u) = 1/(1 + |u/α*|^{2m}) ([`LagLaw::x_static`], by the
/// same operations, so bit for bit its value) and its partials (∂x₀/∂u, ∂x₀/∂α*, ∂x₀/∂m) at
/// `u` \[rad\], from one power P = |u/α*|^{2m}: ∂x₀/∂u = −x₀²·2mP/u,
/// ∂x₀/∂α* = x₀²·2mP/α*, ∂x₀/∂m = −x₀²·2P·ln|u/α*| (x₀ = 1 and all partials 0 at u = 0).
pub(crate) fn x_static_with_partials(law: &LagLaw, u: f64) -> (f64, [f64; 3]) {
    let r = (u / law.alpha_star).abs();
    let p = r.powf(2.0 * law.sharpness);
    let x0 = 1.0 / (1.0 + p);
    if r == 0.0 {
        return (x0, [0.0; 3]);
    }
    let x2 = x0 * x0;
    let m2 = 2.0 * law.sharpness;
    (
        x0,
        [
            -x2 * m2 * p / u,
            x2 * m2 * p / law.alpha_star,
            -x2 * 2.0 * p * r.ln(),
        ],
    )
}

/// The first-order lag τ dx/ds + x = f sampled at every sample of `f` into `x` (resized
/// by the caller to f's length), h = Δs/τ, by the first-order-hold exponential step (module
/// docs). With `period` (samples) x starts on the periodic solution
/// x(0)* = x_p(T)/(1 − e^{−hT}) (x_p started at 0), otherwise at `start`.
fn first_order(f: &[f64], h: f64, period: Option<f64>, start: f64, x: &mut [f64]) {
    let n = f.len();
    let e = (-h).exp();
    let c0 = 1.0 - e;
    let c1 = 1.0 - c0 / h;
    let step = |xn: f64, f0: f64, f1: f64| e * xn + c0 * f0 + (f1 - f0) * c1;
    x[0] = start;
    if let Some(p) = period {
        let whole = p.floor() as usize;
        let frac = p - whole as f64;
        let mut xp = 0.0;
        for i in 0..whole.min(n.saturating_sub(1)) {
            xp = step(xp, f[i], f[i + 1]);
        }
        if frac > 0.0 && whole + 1 < n {
            // the fractional step to T, the input linear over it
            let hf = h * frac;
            let ef = (-hf).exp();
            let f1 = f[whole] + frac * (f[whole + 1] - f[whole]);
            xp = ef * xp + (1.0 - ef) * f[whole] + (f1 - f[whole]) * (1.0 - (1.0 - ef) / hf);
        }
        x[0] = xp / (1.0 - (-h * p).exp());
    }
    for i in 1..n {
        x[i] = step(x[i - 1], f[i - 1], f[i]);
    }
}

/// Tangent of [`first_order`]: `dx` (same length as `f`) ← the derivative of its output
/// `x` (already computed from `f`, h, `period`) for an input change `df` (`None` = 0), a
/// change `dh` of h = Δs/τ and a change `dstart` of the start (read without a period): the
/// same recursion differentiated, x_{n+1} = E·x_n + (1 − E)·f_n + (f_{n+1} − f_n)·c₁ with
/// E = e^{−h}, c₁ = 1 − (1 − E)/h, dE = −E·dh, dc₁ = ((1 − E) − E·h)/h²·dh, and the periodic
/// start x(0)* = x_p(T)/(1 − e^{−hT}) differentiated through x_p and the fractional step.
#[allow(clippy::too_many_arguments)]
fn first_order_tangent(
    f: &[f64],
    x: &[f64],
    df: Option<&[f64]>,
    h: f64,
    dh: f64,
    period: Option<f64>,
    dstart: f64,
    dx: &mut [f64],
) {
    let n = f.len();
    let e = (-h).exp();
    let c0 = 1.0 - e;
    let c1 = 1.0 - c0 / h;
    let de = -e * dh;
    let dc0 = e * dh;
    let dc1 = (c0 - e * h) / (h * h) * dh;
    let dfi = |i: usize| df.map_or(0.0, |d| d[i]);
    let step = |xn: f64, f0: f64, f1: f64| e * xn + c0 * f0 + (f1 - f0) * c1;
    let dstep = |xn: f64, dxn: f64, f0: f64, f1: f64, df0: f64, df1: f64| {
        e * dxn + de * xn + c0 * df0 + dc0 * f0 + (df1 - df0) * c1 + (f1 - f0) * dc1
    };
    dx[0] = dstart;
    if let Some(p) = period {
        let whole = p.floor() as usize;
        let frac = p - whole as f64;
        let (mut xp, mut dxp) = (0.0, 0.0);
        for i in 0..whole.min(n.saturating_sub(1)) {
            dxp = dstep(xp, dxp, f[i], f[i + 1], dfi(i), dfi(i + 1));
            xp = step(xp, f[i], f[i + 1]);
        }
        if frac > 0.0 && whole + 1 < n {
            let hf = h * frac;
            let dhf = dh * frac;
            let ef = (-hf).exp();
            let c0f = 1.0 - ef;
            let c1f = 1.0 - c0f / hf;
            let f1 = f[whole] + frac * (f[whole + 1] - f[whole]);
            let df1 = dfi(whole) + frac * (dfi(whole + 1) - dfi(whole));
            let dxn = ef * dxp - ef * dhf * xp
                + c0f * dfi(whole)
                + ef * dhf * f[whole]
                + (df1 - dfi(whole)) * c1f
                + (f1 - f[whole]) * (c0f - ef * hf) / (hf * hf) * dhf;
            xp = ef * xp + (1.0 - ef) * f[whole] + (f1 - f[whole]) * (1.0 - (1.0 - ef) / hf);
            dxp = dxn;
        }
        let et = (-h * p).exp();
        let den = 1.0 - et;
        dx[0] = dxp / den - xp * p * et * dh / (den * den);
    }
    for i in 1..n {
        dx[i] = dstep(x[i - 1], dx[i - 1], f[i - 1], f[i], dfi(i - 1), dfi(i));
    }
}

/// RMS of v(t + T) − v(t) over the samples where t + T is inside the record (T = `p`
/// samples, v linearly interpolated).
fn periodic_misfit(v: &[f64], p: f64) -> f64 {
    let n = v.len();
    let whole = p.floor() as usize;
    let frac = p - whole as f64;
    let mut ss = 0.0;
    let mut count = 0usize;
    for i in 0..n {
        let j = i + whole;
        if j + 1 >= n {
            break;
        }
        let vt = v[j] + frac * (v[j + 1] - v[j]);
        ss += (vt - v[i]).powi(2);
        count += 1;
    }
    if count == 0 {
        return f64::INFINITY;
    }
    (ss / count as f64).sqrt()
}

#[cfg(test)]
mod tests {

    #[test]
    fn static_curve_and_partials_from_one_power_are_the_separate_ones_bit_for_bit() {
        let law = crate::lag::fit::tests::truth();
        for k in -40..=40 {
            let u = f64::from(k) * 0.013;
            let (x0, p) = x_static_with_partials(&law, u);
            assert_eq!(x0.to_bits(), law.x_static(u).to_bits(), "u {u}");
            let r = (u / law.alpha_star).abs();
            if r == 0.0 {
                assert_eq!(p, [0.0; 3]);
                continue;
            }
            // the partials against central differences of x₀ in u, α*, m
            let h = 1e-6;
            let at = |u: f64, a: f64, m: f64| {
                let mut l = law.clone();
                l.alpha_star = a;
                l.sharpness = m;
                l.x_static(u)
            };
            let (a, m) = (law.alpha_star, law.sharpness);
            let fd = [
                (at(u + h, a, m) - at(u - h, a, m)) / (2.0 * h),
                (at(u, a + h, m) - at(u, a - h, m)) / (2.0 * h),
                (at(u, a, m + h) - at(u, a, m - h)) / (2.0 * h),
            ];
            for (d, f) in p.iter().zip(fd) {
                assert!((d - f).abs() <= 1e-6 * (1.0 + f.abs()), "u {u}: {d} vs {f}");
            }
        }
    }

    use super::*;
    use crate::lag::{FittedRange, LagChannel};
    use crate::record::{CaseMeta, Forcing};

    pub(crate) fn law(tau1: f64, tau2: f64) -> LagLaw {
        LagLaw {
            tau1,
            tau2,
            alpha_star: 0.25,
            sharpness: 3.0,
            lift: LagChannel { terms: vec![] },
            moment: LagChannel { terms: vec![] },
            range: FittedRange {
                alpha_e: [0.0, 0.5],
                k: [0.0, 1.0],
            },
            circulation_lag: false,
            rate_share: 0.0,
            pressure_lag: 0.0,
        }
    }

    fn case(cycles: f64, phase_jump: bool) -> NondimCase {
        let (u, b, f) = (10.0, 0.25, 2.0);
        let dt = 1.0 / (f * 40.0);
        let n = (cycles * 40.0) as usize;
        let w = 2.0 * std::f64::consts::PI * f;
        let alpha: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                let wi = if phase_jump && i > n / 2 { 1.37 * w } else { w };
                0.25 + 0.15 * (wi * t).sin()
            })
            .collect();
        let q: Vec<f64> = (0..n)
            .map(|i| b * 0.15 * w * (w * i as f64 * dt).cos() / u)
            .collect();
        NondimCase {
            meta: CaseMeta {
                id: "c1".into(),
                wind_speed: u,
                ..CaseMeta::default()
            },
            dt,
            chord: b,
            x: [alpha, q, vec![0.0; n], vec![0.0; n]],
            c_lift: vec![0.0; n],
            c_moment: vec![0.0; n],
            forcing: Forcing {
                pitch: Some(f),
                heave: None,
            },
        }
    }

    #[test]
    fn periodic_state_repeats_after_one_period() {
        let s = LagSeries::new(&case(3.0, false)).unwrap();
        assert!(s.periodic);
        assert!((s.k - 0.25 * 2.0 * std::f64::consts::PI * 2.0 / 10.0).abs() < 1e-12);
        let mut x = Vec::new();
        assert_eq!(s.simulate(&law(3.0, 1.0), &mut x).unwrap(), 0);
        for i in 0..40 {
            assert!(
                (x[i] - x[i + 40]).abs() < 1e-9,
                "{i}: {} {}",
                x[i],
                x[i + 40]
            );
            assert!((0.0..=1.0).contains(&x[i]));
        }
    }

    #[test]
    fn circulatory_angle_is_the_jones_response_at_the_periodic_steady_state() {
        // α_e = 0.25 + 0.15 sin(ωt): α_c = 0.25 + 0.15·Im(C_J(k) e^{iωt}),
        // C_J(k) = 1 − Σ A_i·ik/(ik + b_i), k = ωb/U (convective frequency)
        let s = LagSeries::new(&case(3.0, false)).unwrap();
        let (u, b, f) = (10.0, 0.125, 2.0);
        let w = 2.0 * std::f64::consts::PI * f;
        let k = w * b / u;
        let mut c = num_complex::Complex64::new(1.0, 0.0);
        for (a, bi) in CIRCULATION_LAGS {
            let ik = num_complex::Complex64::new(0.0, k);
            c -= a * ik / (ik + bi);
        }
        for i in 0..s.len() {
            let t = i as f64 * s.dt;
            let e = num_complex::Complex64::from_polar(1.0, w * t);
            let want = 0.25 + 0.15 * (c * e).im;
            assert!(
                (s.alpha_c[i] - want).abs() < 2e-4,
                "{i}: {} {want}",
                s.alpha_c[i]
            );
        }
        // the switch selects the angle
        let mut l = law(3.0, 1.0);
        assert_eq!(s.angle(&l).as_ptr(), s.alpha_e.as_ptr());
        l.circulation_lag = true;
        assert_eq!(s.angle(&l).as_ptr(), s.alpha_c.as_ptr());
    }

    #[test]
    fn integrator_is_exact_for_a_ramp() {
        // τ dx/ds + x = f with f linear in s: x = f − τ f' + C e^{−s/τ}
        let s = LagSeries::new(&case(3.0, false)).unwrap();
        let mut l = law(2.0, 0.0);
        l.alpha_star = 1e3; // x₀ ≈ 1 everywhere
        let mut x = Vec::new();
        s.simulate(&l, &mut x).unwrap();
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-9));
    }

    #[test]
    fn non_periodic_short_record_names_the_case_and_the_numbers() {
        let s = LagSeries::new(&case(1.5, true)).unwrap();
        assert!(!s.periodic);
        let mut x = Vec::new();
        let e = s.simulate(&law(20.0, 1.0), &mut x).unwrap_err().to_string();
        assert!(
            e.contains("c1") && e.contains("too short") && e.contains("not periodic"),
            "{e}"
        );
        // long enough and a short lag: settles
        let s = LagSeries::new(&case(40.0, true)).unwrap();
        assert!(!s.periodic);
        assert!(s.simulate(&law(0.5, 0.0), &mut x).unwrap() > 0);
    }
}
