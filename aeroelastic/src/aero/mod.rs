//! Aerodynamic models behind one trait, [`AeroModel`].
//!
//! A model gives the forces per unit span L (down), M (nose-up about the elastic axis) in
//! two forms:
//! - **time domain**: L, M = M_a q̈ + f(q, q̇, x), where q = (h, α), M_a is the
//!   apparent-mass matrix ([`AeroModel::apparent_mass`]) and x the model's internal lag
//!   states with their own rates ẋ = g(q, q̇, x) ([`AeroModel::lag_rates`]);
//! - **frequency domain**: for harmonic motion q = q̂ e^{iωt}, f̂ = H(ω) q̂
//!   ([`AeroModel::frequency_response`]), exact where the model has an exact form
//!   (Theodorsen's C(k), tabulated flutter derivatives) — this is what p-k flutter uses.
//!
//! Implementations: [`QuasiSteady`] (steady or quasi-steady thin aerofoil),
//! [`TheodorsenAero`] (exact C(k) / Jones–Wagner lag states), [`DerivativeTable`]
//! (Scanlan H*, A* tables / Roger rational-function approximation), [`DynamicStallAero`]
//! (Beddoes–Leishman-type dynamic stall of a thin plate), [`LagAero`] (the identified lag
//! law of `identify::lag`: one separation state, Kirchhoff lift) and [`NonlinearAero`]
//! (any model plus polynomial terms in α, Bα̇/U, h/B, ḣ/U — the Eq. 19 N* terms).

mod lag;
mod nonlinear;
mod quasi_steady;
mod stall;
mod table;
mod unsteady;

pub use lag::LagAero;
pub use nonlinear::{channel_name, term_name, Channel, Coefficient, NonlinearAero, NonlinearTerm};
pub use quasi_steady::{QuasiSteady, QuasiSteadyKind};
pub use stall::DynamicStallAero;
pub use table::{DerivativeTable, RfaFit};
pub use unsteady::{thin_plate_derivatives, TheodorsenAero};

use nalgebra::{DMatrix, Matrix2};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// Flow condition: air density ρ \[kg/m³\] and wind speed U \[m/s\].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Flow {
    /// Air density ρ \[kg/m³\].
    pub rho: f64,
    /// Wind speed U \[m/s\], > 0 for the unsteady models.
    pub u: f64,
}

impl Flow {
    /// Dynamic pressure ½ρU² \[Pa\].
    pub fn q_dyn(&self) -> f64 {
        0.5 * self.rho * self.u * self.u
    }
}

/// An aerodynamic force model for the heave/pitch section (see the module docs).
///
/// Conventions (DESIGN.md §2): h down, α nose-up, L down, M nose-up about the elastic axis,
/// per unit span, SI units.
pub trait AeroModel: Send + Sync + std::fmt::Debug {
    /// Short human-readable name (for reports).
    fn name(&self) -> String;

    /// Chord B \[m\].
    fn chord(&self) -> f64;

    /// Number of internal lag states.
    fn n_lag(&self) -> usize;

    /// Apparent-mass matrix M_a: the forces contain M_a (ḧ, α̈)ᵀ [kg/m, kg, kg·m].
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64>;

    /// Forces (L, M) without the apparent-mass part, from q = (h, α), q̇ = (ḣ, α̇) and the
    /// lag states `lag` (length [`AeroModel::n_lag`]).
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2];

    /// Whether the forces and lag rates are linear in (q, q̇, lag) at a fixed flow. Then the
    /// Jacobian of the section's rate changes along an orbit only through the structure's
    /// nonlinear terms (harmonic balance uses this). Default `false`, always safe: callers
    /// then difference the full rate.
    fn is_linear(&self) -> bool {
        false
    }

    /// Rates of the lag states, written to `out` (length [`AeroModel::n_lag`]).
    fn lag_rates(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]);

    /// Frequency-domain transfer matrix H(ω): (L̂, M̂)ᵀ = H (ĥ, α̂)ᵀ for q = q̂ e^{iωt},
    /// ω ≥ 0 \[rad/s\], including apparent-mass and all linear terms (nonlinear terms are
    /// not part of it).
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64>;

    /// The model with its frequency-dependent coefficients evaluated at reduced frequency
    /// `k` = Bω/U, or `None` when nothing in it depends on K (the default). Used where the
    /// motion has one dominant frequency (forced motion at K_α; a limit cycle at its own
    /// frequency) — see [`NonlinearAero`] for identified N* coefficients.
    fn with_reduced_frequency(&self, _k: f64) -> Option<std::sync::Arc<dyn AeroModel>> {
        None
    }

    /// Reduced frequency K = Bω/U at which the frequency-dependent coefficients are
    /// currently evaluated, or `None` when nothing in the model depends on K (the
    /// default). A model returning `Some` must also implement
    /// [`AeroModel::with_reduced_frequency`]; the LCO solver then iterates K to each limit
    /// cycle's own frequency ([`crate::lco::KIteration`]).
    fn reduced_frequency(&self) -> Option<f64> {
        None
    }

    /// Time \[s\] a forced run needs before recording for the model's nonlinear lag states to
    /// forget their start (the virtual wind tunnel starts lag states on the periodic
    /// solution of the *linearised* lag dynamics, exact for linear lags: 0, the default).
    fn settle_time(&self, _flow: &Flow) -> f64 {
        0.0
    }

    /// Elastic-axis position a [semi-chords aft of mid-chord] about which the moment is
    /// taken, when the model has one (thin-aerofoil models); `None` otherwise.
    fn elastic_axis(&self) -> Option<f64> {
        None
    }
}

/// Linearisation of a model's time-domain form about the origin:
/// f ≈ M_a q̈ + K_q q + C_q q̇ + D x, ẋ ≈ E q + F q̇ + G x.
#[derive(Debug, Clone)]
pub struct LinearAero {
    /// Apparent mass M_a.
    pub m_a: Matrix2<f64>,
    /// ∂f/∂q (aerodynamic stiffness).
    pub k_q: Matrix2<f64>,
    /// ∂f/∂q̇ (aerodynamic damping).
    pub c_q: Matrix2<f64>,
    /// ∂f/∂x (2 × n).
    pub d: DMatrix<f64>,
    /// ∂ẋ/∂q (n × 2).
    pub e: DMatrix<f64>,
    /// ∂ẋ/∂q̇ (n × 2).
    pub f: DMatrix<f64>,
    /// ∂ẋ/∂x (n × n).
    pub g: DMatrix<f64>,
}

/// Linearises `model` about q = q̇ = x = 0 by central differences. Linear parts are exact
/// to rounding (f(δ) − f(−δ) = 2Jδ for a linear map, whatever δ); polynomial terms of
/// degree ≥ 2 contribute O(δ²) with δ = 1e-5 in nondimensional units (h/B, α, ḣ/U, Bα̇/U).
pub fn linearize(model: &dyn AeroModel, flow: &Flow) -> LinearAero {
    let n = model.n_lag();
    let b_c = model.chord();
    let u = flow.u.abs().max(1e-12);
    let delta = 1e-5;
    // Variables: h, α, ḣ, α̇, x_1..x_n
    let scales: Vec<f64> = [b_c, 1.0, u, u / b_c]
        .into_iter()
        .chain(std::iter::repeat_n(1.0, n))
        .collect();
    let nv = 4 + n;
    let mut jf = DMatrix::<f64>::zeros(2, nv);
    let mut jg = DMatrix::<f64>::zeros(n, nv);
    let mut vars = vec![0.0; nv];
    let mut out_p = vec![0.0; n];
    let mut out_m = vec![0.0; n];
    for j in 0..nv {
        let s = delta * scales[j];
        vars[j] = s;
        let fp = model.forces(flow, [vars[0], vars[1]], [vars[2], vars[3]], &vars[4..]);
        model.lag_rates(
            flow,
            [vars[0], vars[1]],
            [vars[2], vars[3]],
            &vars[4..],
            &mut out_p,
        );
        vars[j] = -s;
        let fm = model.forces(flow, [vars[0], vars[1]], [vars[2], vars[3]], &vars[4..]);
        model.lag_rates(
            flow,
            [vars[0], vars[1]],
            [vars[2], vars[3]],
            &vars[4..],
            &mut out_m,
        );
        vars[j] = 0.0;
        for i in 0..2 {
            jf[(i, j)] = (fp[i] - fm[i]) / (2.0 * s);
        }
        for i in 0..n {
            jg[(i, j)] = (out_p[i] - out_m[i]) / (2.0 * s);
        }
    }
    LinearAero {
        m_a: model.apparent_mass(flow),
        k_q: Matrix2::new(jf[(0, 0)], jf[(0, 1)], jf[(1, 0)], jf[(1, 1)]),
        c_q: Matrix2::new(jf[(0, 2)], jf[(0, 3)], jf[(1, 2)], jf[(1, 3)]),
        d: jf.columns(4, n).into_owned(),
        e: jg.columns(0, 2).into_owned(),
        f: jg.columns(2, 2).into_owned(),
        g: jg.columns(4, n).into_owned(),
    }
}

/// Frequency response of a model's **time-domain** realisation (lag states included):
/// H_ss(ω) = −ω² M_a + K_q + iω C_q + D (iω I − G)⁻¹ (E + iω F).
///
/// Compared with [`AeroModel::frequency_response`] it measures how well the time-domain
/// form (Jones' lags, Roger's approximation) reproduces the exact one.
///
/// # Errors
/// [`crate::Error::Numerical`] when iω I − G is singular.
pub fn state_space_response(
    model: &dyn AeroModel,
    flow: &Flow,
    omega: f64,
) -> crate::Result<Matrix2<Complex64>> {
    let lin = linearize(model, flow);
    let iw = Complex64::new(0.0, omega);
    let mut h = Matrix2::<Complex64>::zeros();
    for i in 0..2 {
        for j in 0..2 {
            h[(i, j)] = lin.k_q[(i, j)] + iw * lin.c_q[(i, j)] - omega * omega * lin.m_a[(i, j)];
        }
    }
    let n = model.n_lag();
    if n > 0 {
        let mut a = DMatrix::<Complex64>::zeros(n, n);
        let mut rhs = DMatrix::<Complex64>::zeros(n, 2);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = Complex64::new(-lin.g[(i, j)], 0.0);
            }
            a[(i, i)] += iw;
            for j in 0..2 {
                rhs[(i, j)] = lin.e[(i, j)] + iw * lin.f[(i, j)];
            }
        }
        let x = a.lu().solve(&rhs).ok_or_else(|| {
            crate::Error::numerical(
                "state_space_response",
                format!("iωI − G singular at ω = {omega}"),
            )
        })?;
        for i in 0..2 {
            for j in 0..2 {
                for l in 0..n {
                    h[(i, j)] += lin.d[(i, l)] * x[(l, j)];
                }
            }
        }
    }
    Ok(h)
}

/// Thin-aerofoil forces in Theodorsen's form, converted to DESIGN.md §2 signs.
///
/// With w_c the circulatory (C-weighted) 3/4-chord downwash, Theodorsen's lift (up) is
/// L↑ = 2πρUb w_c + πρb²(ḧ + Uα̇ − baα̈) and the moment
/// M = (½+a) b 2πρUb w_c + πρb²(baḧ − Ub(½−a)α̇ − b²(⅛+a²)α̈). This returns
/// (L, M) = (−L↑, M) without the acceleration terms; `noncirc` adds the πρb²U α̇ terms.
#[inline]
pub(crate) fn thin_airfoil(
    rho: f64,
    u: f64,
    b: f64,
    a: f64,
    wc: f64,
    alpha_dot: f64,
    noncirc: bool,
) -> [f64; 2] {
    let pi = std::f64::consts::PI;
    let circ = 2.0 * pi * rho * u * b * wc;
    let mut l_up = circ;
    let mut m = (0.5 + a) * b * circ;
    if noncirc {
        l_up += pi * rho * b * b * u * alpha_dot;
        m -= pi * rho * b * b * b * u * (0.5 - a) * alpha_dot;
    }
    [-l_up, m]
}

/// Apparent-mass matrix of the thin aerofoil (L down, M nose-up):
/// [[−πρb², πρb³a], [πρb³a, −πρb⁴(⅛+a²)]].
pub(crate) fn thin_airfoil_apparent_mass(rho: f64, b: f64, a: f64) -> Matrix2<f64> {
    let pi = std::f64::consts::PI;
    let c = pi * rho * b * b;
    Matrix2::new(-c, c * b * a, c * b * a, -c * b * b * (0.125 + a * a))
}

/// Frequency response of the thin aerofoil with circulation function `c` (C(k) exact,
/// Jones' approximation or 1) for harmonic motion at ω; `noncirc` adds all πρb² terms.
#[allow(clippy::too_many_arguments)]
pub(crate) fn thin_airfoil_response(
    rho: f64,
    u: f64,
    b: f64,
    a: f64,
    omega: f64,
    c: Complex64,
    steady_only: bool,
    noncirc: bool,
) -> Matrix2<Complex64> {
    let iw = Complex64::new(0.0, omega);
    // w = iω h + U α + b(½ − a) iω α  (per unit ĥ and per unit α̂)
    let (w_h, w_a) = if steady_only {
        (Complex64::new(0.0, 0.0), Complex64::new(u, 0.0))
    } else {
        (iw, u + b * (0.5 - a) * iw)
    };
    let pi = std::f64::consts::PI;
    let k2 = 2.0 * pi * rho * u * b;
    let mut h = Matrix2::new(
        -k2 * c * w_h,
        -k2 * c * w_a,
        (0.5 + a) * b * k2 * c * w_h,
        (0.5 + a) * b * k2 * c * w_a,
    );
    if noncirc {
        let ma = thin_airfoil_apparent_mass(rho, b, a);
        let nc = pi * rho * b * b;
        for i in 0..2 {
            for j in 0..2 {
                h[(i, j)] -= omega * omega * ma[(i, j)];
            }
        }
        h[(0, 1)] -= nc * u * iw;
        h[(1, 1)] -= nc * b * u * (0.5 - a) * iw;
    }
    h
}
