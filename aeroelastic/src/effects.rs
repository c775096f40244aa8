//! Unmodelled effects injected into the virtual wind tunnel (DESIGN.md §5, issue 5): the
//! catalogue effects `static_offset`, `added_mass`, `time_delay`, `higher_order`,
//! `dynamic_stall`, `vortex_shedding`, `structural_cubic`, `freeplay`, `friction` and the
//! outside effect `buffeting` (turbulent buffeting), each in a **primary** and an
//! **alternate** functional form ([`Form`]), one at a time or together, into forced-motion
//! records ([`forced_case_forces`]) and free-response runs ([`free_section`]).
//!
//! Where each effect acts:
//! * aerodynamic effects change the forces the section feels; in the time domain they are
//!   an [`AeroModel`] wrapper, [`EffectAero`], around the truth law (extra lag states: the
//!   stall separation variable, a Padé or first-order delay filter, a clock for
//!   time-dependent forcing);
//! * `added_mass` is an imperfect wind–no-wind subtraction: it exists only in the forced
//!   records (ΔM q̈ added to the recorded forces), never in the free response;
//! * structural effects change only the structure of the free response (primary forms
//!   through the [`crate::structure::Structure`] fields; alternate forms that [`crate::structure::Structure`] cannot express —
//!   a smoothed gap, a Stribeck friction law — as an extra generalised force carried by
//!   [`EffectAero`] in the free run only), never the forced records;
//! * time-dependent forcing (vortex shedding, buffeting) is added to the forced records
//!   sample by sample, and in the free response through a pre-generated coefficient
//!   series read by a clock lag state (rate 1).
//!
//! Conventions as DESIGN.md §2: h down, α nose-up, L down, M nose-up about the elastic
//! axis, per unit span, SI; q = ½ρU², B the chord; x_ea the elastic axis in chords from the
//! leading edge.

use std::sync::Arc;

use nalgebra::Matrix2;
use num_complex::Complex64;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::aero::{AeroModel, Flow};
use crate::section::Section;
use crate::structure::{Friction, PolyTerm};
use crate::tunnel::{forced_forces, Motion};
use crate::{Error, Result};

const TAU: f64 = 2.0 * std::f64::consts::PI;

/// Functional form of an injected effect: the same physics in two different shapes. The
/// blind benchmark uses `Primary`; `Alternate` checks that a diagnosis does not rely on
/// the exact shape.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Form {
    /// The first form of each effect (see [`InjectedEffect`]).
    #[default]
    Primary,
    /// The second form of each effect (see [`InjectedEffect`]).
    Alternate,
}

/// One injected effect with its physical parameters (SI unless stated). The forms:
///
/// | effect | primary | alternate |
/// |---|---|---|
/// | static offset | the model sits at α + α₀ (whole law, incl. nonlinear terms) | zero-lift-angle shift of the steady thin-aerofoil force only: ΔC_L↑ = 2πα₀, ΔC_M = 2πα₀(x_ea − ¼) |
/// | added mass | ΔM = ε M_rig (rig mass matrix mis-subtracted) | ΔM = −ε_a M_a (air apparent mass of the thin aerofoil, in still air) |
/// | time delay | pure shift τ of the force (forced: exact; free: Padé (2,2)) | first-order lag τ |
/// | higher order | c α⁵ + c α³ h/B in C_M | c α⁴ (Bα̇/U) + c α² (h/B)² in C_M |
/// | dynamic stall | piecewise-exponential separation, Kirchhoff lift | tanh separation, linear lift loss |
/// | vortex shedding | St 0.12, 1 % band | St 0.20, 4 % band, 30 % envelope modulation |
/// | structural cubic | κ k_α d³ | ½κ k_α d³ + 10κ k_α d⁵ |
/// | freeplay | sharp gap (Structure) | smoothed gap (hyperbolic ramp, ε = δ/3) |
/// | friction | Coulomb, tanh-regularised (Structure) | Stribeck: static 1.6 × kinetic, v_s = 0.05 rad/s |
/// | buffeting | Dryden/von Kármán-like w, C_Lα = 2π | same w through a first-order Sears admittance |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum InjectedEffect {
    /// Mean angle offset α₀ \[rad\] (typical 0.05°–1.5°): the rig reads α while the model
    /// sits at α + α₀ (mounting or zero error).
    StaticOffset {
        /// Offset α₀ \[rad\].
        alpha0: f64,
    },
    /// Acceleration-proportional forces ΔM q̈ left by an imperfect wind–no-wind
    /// subtraction (forced records only). `fraction` ε: typical 0.5 %–15 % of the rig's
    /// mass matrix (primary) or 0.2–5 × the air's apparent mass (alternate).
    AddedMass {
        /// Fraction ε (see above), nondimensional.
        fraction: f64,
        /// The rig's mass matrix [[m, S], [S, I]] per unit span (primary form), rows.
        rig: [[f64; 2]; 2],
    },
    /// The force lags the motion by τ \[s\] (typical 0.5–20 ms: balance or flow latency).
    /// The apparent-mass reaction M_a q̈ stays instantaneous.
    TimeDelay {
        /// Delay or lag time constant τ \[s\].
        tau: f64,
    },
    /// Moment terms outside the Eq. 19 library (degree 4 and 5), coefficient c
    /// (nondimensional, typical |c| 0.05–20).
    HigherOrder {
        /// Coefficient c of both terms.
        c: f64,
    },
    /// Dynamic stall: separation above α_crit \[rad\] (typical 8°–22°) with a lagged
    /// separation variable s (0 attached, → 0.9 separated), ṡ = (s_ss(α_e) − s)/T,
    /// T = `lag_chords` · B/U (typical 1–4 chords), α_e = α + ḣ/U.
    DynamicStall {
        /// Critical angle α_crit \[rad\].
        alpha_crit: f64,
        /// Lag time constant in chord transit times B/U.
        lag_chords: f64,
        /// Elastic axis x_ea in chords from the leading edge.
        x_ea: f64,
    },
    /// Narrow-band shedding forcing at f = St·U/D: C_L,vs cos φ(t) and
    /// ¼ C_L,vs cos(φ + 0.7) in C_M with a slowly wandering phase.
    VortexShedding {
        /// Lift coefficient amplitude C_L,vs (typical 0.002–0.1).
        c_lift: f64,
        /// Section depth D \[m\] (thickness of the plate).
        depth: f64,
    },
    /// Cubic pitch spring κ k_α d³, κ [1/rad²] (typical 0.5–200, hardening).
    StructuralCubic {
        /// κ [1/rad²].
        kappa: f64,
    },
    /// Pitch freeplay of half gap δ \[rad\] (typical 0.02°–1°).
    Freeplay {
        /// Half gap δ \[rad\].
        half_gap: f64,
    },
    /// Dry friction in the pitch bearings, kinetic moment T_c \[N·m/m\] (typical 1e-5–5e-3
    /// for the plate rig, i.e. 4T_c/k_α from 0.001° to 0.4° amplitude loss per cycle).
    Friction {
        /// Kinetic friction moment T_c \[N·m/m\].
        moment: f64,
    },
    /// A pitch spring with even and odd terms, k_α(α + c₂α² + c₃α³) (primary) or
    /// k_α(α + c₂α² + c₃α³ + c₄α⁴) with c₄ = 2c₃ \[1/rad³\] (alternate): an asymmetric,
    /// hardening or softening spring. Signs are free.
    StructuralPolynomial {
        /// c₂ \[1/rad\].
        c2: f64,
        /// c₃ \[1/rad²\].
        c3: f64,
    },
    /// Amplitude-dependent pitch damping c_α(1 + d α²) α̇ (primary) or
    /// c_α(1 + d α⁴/α_r²) α̇ with α_r = 0.1 rad (alternate: the same extra damping at
    /// 5.7°, steeper in amplitude). d \[1/rad²\] > 0.
    StructuralDamping {
        /// d \[1/rad²\].
        d: f64,
    },
    /// Turbulent buffeting (outside the catalogue): vertical gust w/U with rms I_w (typical
    /// 0.1 %–6 %), Dryden/von Kármán-like spectrum of integral length L \[m\], quasi-steady
    /// forces C_L↑ = 2π w/U at the quarter chord.
    Buffeting {
        /// Turbulence intensity I_w = σ_w/U.
        intensity: f64,
        /// Integral length scale L \[m\].
        length_scale: f64,
        /// Elastic axis x_ea in chords from the leading edge.
        x_ea: f64,
    },
}

/// An effect in a form.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Injection {
    /// The effect and its parameters.
    pub effect: InjectedEffect,
    /// Its functional form.
    pub form: Form,
}

/// Shedding parameters of a form: (Strouhal number, relative bandwidth, envelope depth).
fn shedding_form(form: Form) -> (f64, f64, f64) {
    match form {
        Form::Primary => (0.12, 0.01, 0.0),
        Form::Alternate => (0.20, 0.04, 0.3),
    }
}

/// Shedding frequency f = St·U/D \[Hz\] of an effect in a form.
pub fn shedding_frequency(depth: f64, u: f64, form: Form) -> f64 {
    shedding_form(form).0 * u / depth
}

/// A pre-generated time-dependent force-coefficient series (ΔC_L, ΔC_M) at uniform
/// spacing `dt` from t = 0, linearly interpolated and held at the ends.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcingSeries {
    /// Sample interval \[s\].
    pub dt: f64,
    /// ΔC_L (L down) at t = i·dt.
    pub c_lift: Vec<f64>,
    /// ΔC_M (nose-up) at t = i·dt.
    pub c_moment: Vec<f64>,
}

impl ForcingSeries {
    /// (ΔC_L, ΔC_M) at time t \[s\].
    pub fn at(&self, t: f64) -> [f64; 2] {
        let n = self.c_lift.len();
        if n == 0 {
            return [0.0; 2];
        }
        let x = (t / self.dt).max(0.0);
        let i = (x.floor() as usize).min(n - 1);
        if i + 1 >= n {
            return [self.c_lift[n - 1], self.c_moment[n - 1]];
        }
        let w = x - i as f64;
        [
            self.c_lift[i] + w * (self.c_lift[i + 1] - self.c_lift[i]),
            self.c_moment[i] + w * (self.c_moment[i + 1] - self.c_moment[i]),
        ]
    }

    fn add(&mut self, other: &ForcingSeries) {
        for (a, b) in self.c_lift.iter_mut().zip(&other.c_lift) {
            *a += b;
        }
        for (a, b) in self.c_moment.iter_mut().zip(&other.c_moment) {
            *a += b;
        }
    }
}

/// Coefficient series of the time-dependent effects (shedding, buffeting) of `effects` at
/// wind speed `u` \[m/s\], `n` samples at `dt` \[s\], random phases from `seed`; `None` when
/// no effect is time-dependent.
///
/// Shedding: φ(t) = 2π f_s t + θ₀ + Σ₆ a_k sin(2π ν_k t + θ_k), ν_k uniform in
/// [0, bandwidth·f_s], a_k = 1/√6 rad (phase wander of ≈ 1 rad rms, instantaneous frequency
/// within ±bandwidth·f_s), ΔC_L = C_L,vs e(t) cos φ, ΔC_M = ¼ C_L,vs e(t) cos(φ + 0.7),
/// envelope e = 1 + depth sin(2π ν_e t + θ_e) (alternate form only).
///
/// Buffeting: w/U = I_w ξ(t), ξ unit-rms white noise through (1 + √3 T s)/(1 + T s)²,
/// T = L/U (the Dryden form of the von Kármán spectrum), normalised to unit rms over the
/// series; alternate form through a further Sears-like 1/(1 + s B/U) (normalised after);
/// ΔC_L = −2π w/U (lift up), ΔC_M = 2π (x_ea − ¼) w/U.
///
/// Returns `None` in still air (U ≤ 0) and when no effect forces.
pub fn forcing_series(
    effects: &[Injection],
    chord: f64,
    u: f64,
    dt: f64,
    n: usize,
    seed: u64,
) -> Option<ForcingSeries> {
    // no flow, no shedding and no gusts (still air: forces scale with U²)
    if !(u > 0.0 && u.is_finite()) {
        return None;
    }
    let mut total: Option<ForcingSeries> = None;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for inj in effects {
        let s = match &inj.effect {
            InjectedEffect::VortexShedding { c_lift, depth } => {
                let (st, bw, env) = shedding_form(inj.form);
                let fs = st * u / depth;
                let theta0 = rng.random_range(0.0..TAU);
                let wander: Vec<(f64, f64)> = (0..6)
                    .map(|_| (rng.random_range(0.0..bw * fs), rng.random_range(0.0..TAU)))
                    .collect();
                let (nu_e, th_e) = (rng.random_range(0.05..0.3), rng.random_range(0.0..TAU));
                let a = 1.0 / 6f64.sqrt();
                let mut cl = Vec::with_capacity(n);
                let mut cm = Vec::with_capacity(n);
                for i in 0..n {
                    let t = i as f64 * dt;
                    let mut phi = TAU * fs * t + theta0;
                    for (nu, th) in &wander {
                        phi += a * (TAU * nu * t + th).sin();
                    }
                    let e = 1.0 + env * (TAU * nu_e * t + th_e).sin();
                    cl.push(c_lift * e * phi.cos());
                    cm.push(0.25 * c_lift * e * (phi + 0.7).cos());
                }
                ForcingSeries {
                    dt,
                    c_lift: cl,
                    c_moment: cm,
                }
            }
            InjectedEffect::Buffeting {
                intensity,
                length_scale,
                x_ea,
            } => {
                let t_l = length_scale / u;
                let a = (-dt / t_l).exp();
                let (mut x1, mut x2, mut x3) = (0.0, 0.0, 0.0);
                let a_s = (-dt * u / chord).exp();
                let burn = (5.0 * t_l.max(chord / u) / dt).ceil() as usize;
                let mut w = Vec::with_capacity(n);
                for i in 0..n + burn {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    x1 = a * x1 + (1.0 - a) * z;
                    let x2_new = a * x2 + (1.0 - a) * x1;
                    // (1 + √3 T s) applied to the second stage: x2 + √3 T ẋ2 = x2 + √3 (x1 − x2).
                    let y = x2_new + 3f64.sqrt() * (x1 - x2_new);
                    x2 = x2_new;
                    x3 = a_s * x3 + (1.0 - a_s) * y;
                    if i >= burn {
                        w.push(if inj.form == Form::Alternate { x3 } else { y });
                    }
                }
                let rms = (w.iter().map(|v| v * v).sum::<f64>() / n.max(1) as f64).sqrt();
                let scale = if rms > 0.0 { intensity / rms } else { 0.0 };
                ForcingSeries {
                    dt,
                    c_lift: w.iter().map(|v| -TAU * v * scale).collect(),
                    c_moment: w.iter().map(|v| TAU * (x_ea - 0.25) * v * scale).collect(),
                }
            }
            _ => continue,
        };
        match &mut total {
            None => total = Some(s),
            Some(t) => t.add(&s),
        }
    }
    total
}

/// One part of an [`EffectAero`] (built by [`forced_model`] and [`free_section`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Part {
    /// The law is evaluated at α + α₀ \[rad\].
    AngleOffset(f64),
    /// Constant steady forces of a zero-lift-angle shift α₀ \[rad\] (x_ea in chords).
    SteadyOffset {
        /// α₀ \[rad\].
        alpha0: f64,
        /// Elastic axis in chords from the leading edge.
        x_ea: f64,
    },
    /// Moment polynomial terms c·α^p₀ (Bα̇/U)^p₁ (h/B)^p₂ (ḣ/U)^p₃.
    Polynomial(Vec<([i32; 4], f64)>),
    /// Dynamic stall with one separation state (see [`InjectedEffect::DynamicStall`]).
    Stall {
        /// α_crit \[rad\].
        alpha_crit: f64,
        /// T = lag_chords B/U.
        lag_chords: f64,
        /// Elastic axis in chords from the leading edge.
        x_ea: f64,
        /// Form (separation curve and force mapping).
        form: Form,
    },
    /// Padé (2,2) delay of τ \[s\] on (L, M) without apparent mass (4 states).
    PadeDelay(f64),
    /// First-order lag of time constant τ \[s\] on (L, M) without apparent mass (2 states).
    FirstOrderLag(f64),
    /// Time-dependent coefficients read with a clock state (1 state).
    Forcing(Arc<ForcingSeries>),
    /// Smoothed pitch freeplay: spring k_α d_s(α) instead of k_α α (the linear spring of the
    /// structure stays, this part adds k_α (α − d_s)).
    SmoothFreeplay {
        /// k_α [N·m/rad per m].
        k_alpha: f64,
        /// Half gap δ \[rad\].
        delta: f64,
        /// Smoothing ε \[rad\].
        eps: f64,
    },
    /// Stribeck pitch friction −[T_c + (T_s − T_c) e^{−(α̇/v_s)²}] tanh(α̇/ε).
    Stribeck {
        /// Kinetic moment T_c \[N·m/m\].
        kinetic: f64,
        /// Static moment T_s \[N·m/m\].
        breakaway: f64,
        /// Stribeck velocity v_s \[rad/s\].
        v_s: f64,
        /// Regularisation ε \[rad/s\].
        eps: f64,
    },
}

/// The truth law wrapped with effect [`Part`]s; an [`AeroModel`] whose lag states are the
/// inner model's, then the stall state, the delay filter states, the clock.
///
/// Force: f = f_inner(q + (0, α₀), q̇, x) + polynomial + stall + steady offset, delayed (Padé
/// or first-order lag, the apparent-mass part M_a q̈ is not delayed), then the forcing
/// q B ΔC(t) and the structural parts added undelayed.
#[derive(Debug, Clone)]
pub struct EffectAero {
    inner: Arc<dyn AeroModel>,
    parts: Vec<Part>,
    n_inner: usize,
    stall: Option<usize>,
    delay: Option<(usize, bool, f64)>,
    clock: Option<usize>,
    n_lag: usize,
}

impl EffectAero {
    /// Wraps `inner` with `parts` (at most one delay, one stall, one forcing).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the part for a non-finite or out-of-range value
    /// (τ ≤ 0, α_crit ≤ 0, lag ≤ 0, ε ≤ 0) or a repeated delay / stall / forcing part.
    pub fn new(inner: Arc<dyn AeroModel>, parts: Vec<Part>) -> Result<Self> {
        let n_inner = inner.n_lag();
        let mut n = n_inner;
        let (mut stall, mut delay, mut clock) = (None, None, None);
        let dup = |name: &str| Error::param(format!("parts.{name}"), f64::NAN, "repeated");
        for p in &parts {
            match p {
                Part::AngleOffset(a) => crate::error::finite("parts.angle_offset", *a)?,
                Part::SteadyOffset { alpha0, x_ea } => {
                    crate::error::finite("parts.steady_offset.alpha0", *alpha0)?;
                    crate::error::finite("parts.steady_offset.x_ea", *x_ea)?;
                }
                Part::Polynomial(t) => {
                    for (i, (_, c)) in t.iter().enumerate() {
                        crate::error::finite(&format!("parts.polynomial[{i}]"), *c)?;
                    }
                }
                Part::Stall {
                    alpha_crit,
                    lag_chords,
                    ..
                } => {
                    crate::error::positive("parts.stall.alpha_crit", *alpha_crit)?;
                    crate::error::positive("parts.stall.lag_chords", *lag_chords)?;
                    if stall.is_some() {
                        return Err(dup("stall"));
                    }
                    stall = Some(n);
                    n += 1;
                }
                Part::PadeDelay(tau) | Part::FirstOrderLag(tau) => {
                    crate::error::positive("parts.delay.tau", *tau)?;
                    if delay.is_some() {
                        return Err(dup("delay"));
                    }
                    let pade = matches!(p, Part::PadeDelay(_));
                    delay = Some((n, pade, *tau));
                    n += if pade { 4 } else { 2 };
                }
                Part::Forcing(s) => {
                    crate::error::positive("parts.forcing.dt", s.dt)?;
                    if clock.is_some() {
                        return Err(dup("forcing"));
                    }
                    clock = Some(n);
                    n += 1;
                }
                Part::SmoothFreeplay { delta, eps, .. } => {
                    crate::error::non_negative("parts.smooth_freeplay.delta", *delta)?;
                    crate::error::positive("parts.smooth_freeplay.eps", *eps)?;
                }
                Part::Stribeck { v_s, eps, .. } => {
                    crate::error::positive("parts.stribeck.v_s", *v_s)?;
                    crate::error::positive("parts.stribeck.eps", *eps)?;
                }
            }
        }
        Ok(EffectAero {
            inner,
            parts,
            n_inner,
            stall,
            delay,
            clock,
            n_lag: n,
        })
    }

    /// The parts.
    pub fn parts(&self) -> &[Part] {
        &self.parts
    }

    fn offset(&self) -> f64 {
        self.parts
            .iter()
            .map(|p| match p {
                Part::AngleOffset(a) => *a,
                _ => 0.0,
            })
            .sum()
    }

    /// Aerodynamic force before the delay filter and the stall rate input.
    fn undelayed(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        let a = q[1] + self.offset();
        let qe = [q[0], a];
        let mut f = self.inner.forces(flow, qe, qd, &lag[..self.n_inner]);
        let b = self.inner.chord();
        let u = flow.u;
        let qb = flow.q_dyn() * b;
        for p in &self.parts {
            match p {
                Part::SteadyOffset { alpha0, x_ea } => {
                    f[0] -= qb * TAU * alpha0;
                    f[1] += qb * b * TAU * alpha0 * (x_ea - 0.25);
                }
                Part::Polynomial(terms) => {
                    let v = [a, b * qd[1] / u, q[0] / b, qd[0] / u];
                    for (pw, c) in terms {
                        let mut t = *c;
                        for i in 0..4 {
                            if pw[i] != 0 {
                                t *= v[i].powi(pw[i]);
                            }
                        }
                        f[1] += qb * b * t;
                    }
                }
                Part::Stall { x_ea, form, .. } => {
                    let s = lag[self.stall.unwrap_or(0)].clamp(0.0, 1.0);
                    let ae = a + qd[0] / u;
                    let cn_att = TAU * ae;
                    let (k, xcp) = match form {
                        Form::Primary => {
                            let r = (1.0 + (1.0 - s).sqrt()) / 2.0;
                            (r * r, 0.25 + 0.25 * s)
                        }
                        Form::Alternate => (1.0 - 0.8 * s, 0.25 + 0.2 * s),
                    };
                    let dcn = cn_att * (k - 1.0);
                    let dcm = cn_att * k * (x_ea - xcp) - cn_att * (x_ea - 0.25);
                    f[0] -= qb * dcn;
                    f[1] += qb * b * dcm;
                }
                _ => {}
            }
        }
        f
    }

    /// Steady separation s_ss(α_e) of a stall part.
    fn s_ss(alpha_e: f64, alpha_crit: f64, form: Form) -> f64 {
        let x = alpha_e.abs() - alpha_crit;
        let s_max = 0.9;
        match form {
            Form::Primary => {
                if x <= 0.0 {
                    0.0
                } else {
                    s_max * (1.0 - (-x / 2f64.to_radians()).exp())
                }
            }
            Form::Alternate => s_max * 0.5 * (1.0 + (x / 1.5f64.to_radians()).tanh()),
        }
    }
}

impl AeroModel for EffectAero {
    fn name(&self) -> String {
        format!("{} + {} effect parts", self.inner.name(), self.parts.len())
    }
    fn chord(&self) -> f64 {
        self.inner.chord()
    }
    fn n_lag(&self) -> usize {
        self.n_lag
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        self.inner.apparent_mass(flow)
    }
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        let mut f = self.undelayed(flow, q, qd, lag);
        if let Some((i, pade, _)) = self.delay {
            if pade {
                // y = u − √12 x₂ (see lag_rates).
                f[0] -= 12f64.sqrt() * lag[i + 1];
                f[1] -= 12f64.sqrt() * lag[i + 3];
            } else {
                f = [lag[i], lag[i + 1]];
            }
        }
        let b = self.inner.chord();
        let qb = flow.q_dyn() * b;
        for p in &self.parts {
            match p {
                Part::Forcing(s) => {
                    let c = s.at(lag[self.clock.unwrap_or(0)]);
                    f[0] += qb * c[0];
                    f[1] += qb * b * c[1];
                }
                Part::SmoothFreeplay {
                    k_alpha,
                    delta,
                    eps,
                } => {
                    let a = q[1];
                    let ds = 0.5 * ((a - delta) + ((a - delta).powi(2) + eps * eps).sqrt())
                        + 0.5 * ((a + delta) - ((a + delta).powi(2) + eps * eps).sqrt());
                    f[1] += k_alpha * (a - ds);
                }
                Part::Stribeck {
                    kinetic,
                    breakaway,
                    v_s,
                    eps,
                } => {
                    let v = qd[1];
                    let t = kinetic + (breakaway - kinetic) * (-(v / v_s).powi(2)).exp();
                    f[1] -= t * (v / eps).tanh();
                }
                _ => {}
            }
        }
        f
    }
    fn lag_rates(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]) {
        let qe = [q[0], q[1] + self.offset()];
        self.inner
            .lag_rates(flow, qe, qd, &lag[..self.n_inner], &mut out[..self.n_inner]);
        for p in &self.parts {
            if let Part::Stall {
                alpha_crit,
                lag_chords,
                form,
                ..
            } = p
            {
                let i = self.stall.unwrap_or(0);
                let t = lag_chords * self.inner.chord() / flow.u;
                let ae = qe[1] + qd[0] / flow.u;
                out[i] = (Self::s_ss(ae, *alpha_crit, *form) - lag[i]) / t;
            }
        }
        if let Some((i, pade, tau)) = self.delay {
            let f = self.undelayed(flow, q, qd, lag);
            if pade {
                // H(s) = 1 − √12 X₂/U: x₁' = ω₀x₂, x₂' = ω₀(u − x₁) − (6/τ)x₂, ω₀ = √12/τ.
                let w0 = 12f64.sqrt() / tau;
                for c in 0..2 {
                    let (x1, x2) = (lag[i + 2 * c], lag[i + 2 * c + 1]);
                    out[i + 2 * c] = w0 * x2;
                    out[i + 2 * c + 1] = w0 * (f[c] - x1) - 6.0 / tau * x2;
                }
            } else {
                out[i] = (f[0] - lag[i]) / tau;
                out[i + 1] = (f[1] - lag[i + 1]) / tau;
            }
        }
        if let Some(i) = self.clock {
            out[i] = 1.0;
        }
    }
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        // Linear parts only: the delay multiplies the non-apparent-mass part.
        let mut h = self.inner.frequency_response(flow, omega);
        if let Some((_, pade, tau)) = self.delay {
            let iw = Complex64::new(0.0, omega);
            let g = if pade {
                let num = 1.0 - iw * tau / 2.0 + iw * iw * tau * tau / 12.0;
                let den = 1.0 + iw * tau / 2.0 + iw * iw * tau * tau / 12.0;
                num / den
            } else {
                1.0 / (1.0 + iw * tau)
            };
            let ma = self.inner.apparent_mass(flow);
            for r in 0..2 {
                for c in 0..2 {
                    let acc = Complex64::new(-omega * omega * ma[(r, c)], 0.0);
                    h[(r, c)] = acc + g * (h[(r, c)] - acc);
                }
            }
        }
        h
    }
}

/// Aerodynamic parts of `effects` that act in the model (not the forcing, not the
/// structural alternates); `free`: the pure delay becomes a Padé filter (in forced records
/// it is an exact shift, see [`forced_case_forces`]).
fn aero_parts(effects: &[Injection], free: bool) -> Vec<Part> {
    let mut parts = Vec::new();
    for inj in effects {
        match (&inj.effect, inj.form) {
            (InjectedEffect::StaticOffset { alpha0 }, Form::Primary) if free => {
                parts.push(Part::AngleOffset(*alpha0))
            }
            (InjectedEffect::StaticOffset { alpha0 }, Form::Alternate) => {
                parts.push(Part::SteadyOffset {
                    alpha0: *alpha0,
                    x_ea: 0.35,
                })
            }
            (InjectedEffect::HigherOrder { c }, Form::Primary) => {
                parts.push(Part::Polynomial(vec![
                    ([5, 0, 0, 0], *c),
                    ([3, 0, 1, 0], *c),
                ]))
            }
            (InjectedEffect::HigherOrder { c }, Form::Alternate) => {
                parts.push(Part::Polynomial(vec![
                    ([4, 1, 0, 0], *c),
                    ([2, 0, 2, 0], *c),
                ]))
            }
            (
                InjectedEffect::DynamicStall {
                    alpha_crit,
                    lag_chords,
                    x_ea,
                },
                form,
            ) => parts.push(Part::Stall {
                alpha_crit: *alpha_crit,
                lag_chords: *lag_chords,
                x_ea: *x_ea,
                form,
            }),
            (InjectedEffect::TimeDelay { tau }, Form::Primary) if free => {
                parts.push(Part::PadeDelay(*tau))
            }
            (InjectedEffect::TimeDelay { tau }, Form::Alternate) => {
                parts.push(Part::FirstOrderLag(*tau))
            }
            _ => {}
        }
    }
    parts
}

/// The static offset of the forced records' model (primary form): carried by the motion's
/// mean pitch so that the lag states start on their periodic orbit.
fn primary_offset(effects: &[Injection]) -> f64 {
    effects
        .iter()
        .map(|i| match (&i.effect, i.form) {
            (InjectedEffect::StaticOffset { alpha0 }, Form::Primary) => *alpha0,
            _ => 0.0,
        })
        .sum()
}

/// The model of forced-motion records with `effects` ([`EffectAero`] around `truth`, or
/// `truth` itself when no effect acts in the model).
///
/// # Errors
/// As [`EffectAero::new`].
pub fn forced_model(
    truth: Arc<dyn AeroModel>,
    effects: &[Injection],
) -> Result<Arc<dyn AeroModel>> {
    let parts = aero_parts(effects, false);
    if parts.is_empty() {
        return Ok(truth);
    }
    Ok(Arc::new(EffectAero::new(truth, parts)?))
}

/// Noise-free aerodynamic forces (L, M) [N/m, N·m/m] of one forced case with `effects`,
/// n samples at dt from t = 0, the effects' random parts seeded by `seed`:
/// * the model of [`forced_model`], with the primary static offset as the motion's mean
///   pitch (the rig reads α, the model sits at α + α₀), a 2 s pre-roll when a stall or lag
///   state is present;
/// * the primary delay as an exact shift: f(t − τ) + M_a (q̈(t) − q̈(t − τ));
/// * added mass ΔM q̈(t) (ΔM = ε M_rig, or −ε M_a(ρ) for the alternate form);
/// * shedding and buffeting coefficients q B ΔC(t) of [`forcing_series`].
///
/// # Errors
/// As [`forced_model`] and [`forced_forces`].
#[allow(clippy::too_many_arguments)]
pub fn forced_case_forces(
    truth: &Arc<dyn AeroModel>,
    effects: &[Injection],
    flow: &Flow,
    motion: &Motion,
    dt: f64,
    n: usize,
    seed: u64,
    case: &str,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let model = forced_model(truth.clone(), effects)?;
    let mut m = motion.clone();
    m.mean_pitch += primary_offset(effects);
    let tau: f64 = effects
        .iter()
        .map(|i| match (&i.effect, i.form) {
            (InjectedEffect::TimeDelay { tau }, Form::Primary) => *tau,
            _ => 0.0,
        })
        .sum();
    let pre_roll = if model.n_lag() > truth.n_lag() {
        2.0
    } else {
        0.0
    };
    let (mut lift, mut moment) =
        forced_forces(model.as_ref(), flow, &m, -tau, dt, n, pre_roll, case)?;
    let ma = model.apparent_mass(flow);
    let b = truth.chord();
    let mut dm = Matrix2::zeros();
    if tau != 0.0 {
        dm += ma;
    }
    for inj in effects {
        if let InjectedEffect::AddedMass { fraction, rig } = &inj.effect {
            dm += match inj.form {
                Form::Primary => {
                    Matrix2::new(rig[0][0], rig[0][1], rig[1][0], rig[1][1]) * *fraction
                }
                Form::Alternate => -model.apparent_mass(flow) * *fraction,
            };
        }
    }
    let has_added = effects
        .iter()
        .any(|i| matches!(i.effect, InjectedEffect::AddedMass { .. }));
    if tau != 0.0 || has_added {
        for i in 0..n {
            let t = i as f64 * dt;
            let (_, _, a) = m.eval(t);
            let mut acc = nalgebra::Vector2::new(a[0], a[1]);
            let mut extra = dm * acc;
            if tau != 0.0 {
                let (_, _, ad) = m.eval(t - tau);
                acc = nalgebra::Vector2::new(ad[0], ad[1]);
                extra -= ma * acc;
            }
            lift[i] += extra[0];
            moment[i] += extra[1];
        }
    }
    if let Some(s) = forcing_series(effects, b, flow.u, dt, n, seed) {
        let qb = flow.q_dyn() * b;
        for i in 0..n {
            lift[i] += qb * s.c_lift[i];
            moment[i] += qb * b * s.c_moment[i];
        }
    }
    Ok((lift, moment))
}

/// Largest eigenvalue magnitude \[1/s\] of the effect states of `effects` in a free run
/// (Padé delay √12/τ, first-order lag 1/τ; 0 when there are none): an explicit RK4 step h
/// is stable for h·rate ≲ 2, so a free run needs at least rate·dt/2 steps per sample.
pub fn stiffest_rate(effects: &[Injection]) -> f64 {
    effects
        .iter()
        .map(|i| match (&i.effect, i.form) {
            (InjectedEffect::TimeDelay { tau }, Form::Primary) => 12f64.sqrt() / tau,
            (InjectedEffect::TimeDelay { tau }, Form::Alternate) => 1.0 / tau,
            _ => 0.0,
        })
        .fold(0.0, f64::max)
}

/// The section of a free run at wind speed `u` with `effects`: structure with the primary
/// structural effects (pitch cubic κ k_α d³ or ½κ k_α d³ + 10κ k_α d⁵, freeplay δ,
/// Coulomb friction T_c with the default regularisation), aerodynamics an [`EffectAero`]
/// with the aerodynamic parts (primary delay as Padé (2,2)), the forcing series at
/// `forcing_dt` over `duration` (seeded by `seed`), and the alternate structural laws
/// (smoothed gap ε = δ/3; Stribeck T_s = 1.6 T_c, v_s = 0.05 rad/s, ε = the default
/// regularisation). Added mass does not act in a free run.
///
/// # Errors
/// As [`EffectAero::new`] and [`Section::new`].
pub fn free_section(
    base: &Section,
    effects: &[Injection],
    u: f64,
    forcing_dt: f64,
    duration: f64,
    seed: u64,
) -> Result<Section> {
    let mut st = base.structure.clone();
    let mut parts = aero_parts(effects, true);
    let k_a = st.k_alpha;
    let eps_default = |t: f64, s: &crate::structure::Structure| {
        Friction::default_smoothing(t, s.inertia_alpha, s.omega_alpha())
    };
    for inj in effects {
        match (&inj.effect, inj.form) {
            (InjectedEffect::StructuralCubic { kappa }, Form::Primary) => {
                st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
                    power: 3,
                    coefficient: kappa * k_a,
                })
            }
            (InjectedEffect::StructuralCubic { kappa }, Form::Alternate) => {
                st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
                    power: 3,
                    coefficient: 0.5 * kappa * k_a,
                });
                st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
                    power: 5,
                    coefficient: 10.0 * kappa * k_a,
                });
            }
            (InjectedEffect::StructuralPolynomial { c2, c3 }, form) => {
                let mut terms = vec![(2, c2 * k_a), (3, c3 * k_a)];
                if form == Form::Alternate {
                    terms.push((4, 2.0 * c3 * k_a));
                }
                for (power, coefficient) in terms {
                    st.nonlinear
                        .pitch_stiffness_terms
                        .push(PolyTerm { power, coefficient });
                }
            }
            (InjectedEffect::StructuralDamping { d }, form) => {
                let c_a = st.c_alpha;
                let (power, coefficient) = match form {
                    Form::Primary => (2, c_a * d),
                    Form::Alternate => (4, c_a * d / 0.01),
                };
                st.nonlinear
                    .pitch_damping_terms
                    .push(PolyTerm { power, coefficient });
            }
            (InjectedEffect::Freeplay { half_gap }, Form::Primary) => {
                st.nonlinear.pitch_freeplay = *half_gap
            }
            (InjectedEffect::Freeplay { half_gap }, Form::Alternate) => {
                parts.push(Part::SmoothFreeplay {
                    k_alpha: k_a,
                    delta: *half_gap,
                    eps: (half_gap / 3.0).max(1e-9),
                })
            }
            (InjectedEffect::Friction { moment }, Form::Primary) => {
                st.nonlinear.friction = Some(Friction {
                    heave_force: 0.0,
                    pitch_moment: *moment,
                    heave_smoothing: None,
                    pitch_smoothing: None,
                })
            }
            (InjectedEffect::Friction { moment }, Form::Alternate) => parts.push(Part::Stribeck {
                kinetic: *moment,
                breakaway: 1.6 * moment,
                v_s: 0.05,
                eps: eps_default(*moment, &st),
            }),
            _ => {}
        }
    }
    let n = (duration / forcing_dt).ceil() as usize + 2;
    if let Some(s) = forcing_series(effects, base.aero.chord(), u, forcing_dt, n, seed) {
        parts.push(Part::Forcing(Arc::new(s)));
    }
    let aero: Arc<dyn AeroModel> = if parts.is_empty() {
        base.aero.clone()
    } else {
        Arc::new(EffectAero::new(base.aero.clone(), parts)?)
    };
    Section::new(st, aero, base.rho)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::{state_space_response, TheodorsenAero};

    fn plate() -> Arc<dyn AeroModel> {
        Arc::new(TheodorsenAero::new(0.25, -0.3).unwrap())
    }

    #[test]
    fn pade_delay_state_space_matches_its_transfer_function() {
        // The time-domain realisation of the Padé filter reproduces its frequency response
        // (1 − sτ/2 + s²τ²/12)/(1 + sτ/2 + s²τ²/12) times the inner non-apparent-mass part.
        let tau = 0.01;
        let m = EffectAero::new(plate(), vec![Part::PadeDelay(tau)]).unwrap();
        let flow = Flow { rho: 1.225, u: 6.0 };
        for w in [3.0, 20.0, 80.0] {
            let iw = Complex64::new(0.0, w);
            let g = (1.0 - iw * tau / 2.0 + iw * iw * tau * tau / 12.0)
                / (1.0 + iw * tau / 2.0 + iw * iw * tau * tau / 12.0);
            // Unit gain, phase ≈ −ωτ for ωτ ≪ 1.
            assert!((g.norm() - 1.0).abs() < 1e-12);
            if w * tau < 0.5 {
                assert!(
                    (g.arg() + w * tau).abs() < 1e-3 * w * tau,
                    "phase {}",
                    g.arg()
                );
            }
            let ss = state_space_response(&m, &flow, w).unwrap();
            let inner = state_space_response(plate().as_ref(), &flow, w).unwrap();
            let ma = plate().apparent_mass(&flow);
            for r in 0..2 {
                for c in 0..2 {
                    let acc = Complex64::new(-w * w * ma[(r, c)], 0.0);
                    let want = acc + g * (inner[(r, c)] - acc);
                    assert!(
                        (ss[(r, c)] - want).norm() < 1e-6 * want.norm(),
                        "w {w}: {} vs {}",
                        ss[(r, c)],
                        want
                    );
                }
            }
        }
    }

    #[test]
    fn stall_separation_is_zero_below_alpha_crit_in_the_primary_form() {
        let ac = 10f64.to_radians();
        assert_eq!(
            EffectAero::s_ss(9.9f64.to_radians(), ac, Form::Primary),
            0.0
        );
        assert!(EffectAero::s_ss(14f64.to_radians(), ac, Form::Primary) > 0.5);
        assert!(EffectAero::s_ss(9f64.to_radians(), ac, Form::Alternate) > 0.0);
        // Attached (s = 0): no force change.
        let m = EffectAero::new(
            plate(),
            vec![Part::Stall {
                alpha_crit: ac,
                lag_chords: 2.0,
                x_ea: 0.35,
                form: Form::Primary,
            }],
        )
        .unwrap();
        let flow = Flow { rho: 1.225, u: 6.0 };
        let lag = vec![0.0; m.n_lag()];
        let f0 = plate().forces(&flow, [0.01, 0.3], [0.1, 1.0], &lag[..2]);
        let f1 = m.forces(&flow, [0.01, 0.3], [0.1, 1.0], &lag);
        assert_eq!(f0, f1);
        // Fully separated: lift magnitude reduced, centre of pressure aft (nose-down).
        let mut lag_s = lag.clone();
        lag_s[2] = 0.9;
        let f2 = m.forces(&flow, [0.0, 0.3], [0.0, 0.0], &lag_s);
        let f0 = plate().forces(&flow, [0.0, 0.3], [0.0, 0.0], &lag[..2]);
        assert!(f2[0].abs() < 0.6 * f0[0].abs() && f2[1] < f0[1]);
    }

    #[test]
    fn forcing_series_interpolates_and_buffeting_has_the_requested_rms() {
        let s = ForcingSeries {
            dt: 0.5,
            c_lift: vec![0.0, 1.0, 3.0],
            c_moment: vec![0.0, 0.0, 0.0],
        };
        assert_eq!(s.at(0.25)[0], 0.5);
        assert_eq!(s.at(0.75)[0], 2.0);
        assert_eq!(s.at(10.0)[0], 3.0);
        let inj = [Injection {
            effect: InjectedEffect::Buffeting {
                intensity: 0.02,
                length_scale: 0.1,
                x_ea: 0.35,
            },
            form: Form::Primary,
        }];
        let b = forcing_series(&inj, 0.25, 6.0, 1.0 / 512.0, 8192, 3).unwrap();
        let rms = (b.c_lift.iter().map(|v| v * v).sum::<f64>() / 8192.0).sqrt();
        assert!((rms - TAU * 0.02).abs() < 1e-12 * rms);
        let b2 = forcing_series(&inj, 0.25, 6.0, 1.0 / 512.0, 8192, 3).unwrap();
        assert_eq!(b, b2);
        let b3 = forcing_series(&inj, 0.25, 6.0, 1.0 / 512.0, 8192, 4).unwrap();
        assert_ne!(b.c_lift, b3.c_lift);
    }
}
