//! Harmonic balance condensed onto the two structural displacements: the form
//! [`super::BranchMethod::HarmonicBalance`] takes when the aerodynamic model is linear and
//! independent of the reduced frequency (Theodorsen, Theodorsen–Jones, RFA tables). Then
//! the only nonlinear terms are the structure's springs and friction, which depend on
//! (h, α, ḣ, α̇) alone, and the velocities and lag states follow from (h, α) per harmonic.
//!
//! Split ż = A z − B_m g(q, q̇): A = ∂f/∂z at the origin (the equilibrium Jacobian the Hopf
//! points come from), B_m = (M_s − M_a)⁻¹ in the acceleration rows and g = R − S₀(q, q̇) the
//! structure's restoring force beyond its linearisation at rest. With q = (h, α) a series
//! of H harmonics in θ = ωt and s = ikω, harmonic k of the velocities is s q_k, of the lag
//! states x_k = L_k q_k with L_k = (sI − A_xx)⁻¹(A_xq + sA_xv), and the equations are
//!
//! D_k q_k + (M_s − M_a)⁻¹ G_k = 0,  D_k = s²I − A_vq − sA_vv − A_vx L_k,
//!
//! G_k the harmonics of g(q(θ), ωq'(θ)) by AFT (N = 8H + 4 samples), plus the phase
//! condition b_α1 = 0. This is the Galerkin system of the full harmonic balance
//! ([`super::harmonic`]) with every linear state solved exactly per harmonic: the same
//! orbit, in 2(2H + 1) + 2 unknowns instead of n(2H + 1) + 2 (test
//! `condensed_orbit_is_the_full_harmonic_balance_orbit`).
//!
//! Jacobian: the coefficient blocks exact (D_k and the AFT of the analytic ∂g,
//! [`crate::structure::Structure::restoring_derivatives`]), the ω column from
//! dD_k/ds = 2sI − A_vv − A_vx(sI − A_xx)⁻¹(A_xv − L_k) and the velocity terms of g, the U
//! column a forward difference.
//!
//! Floquet multipliers: the variational equation δż = A δz + B_m F(t) C₄ δz,
//! F = −∂g/∂(h, α, ḣ, α̇) along the orbit, by the exponential trapezoidal rule: e^{Ah} is
//! exact over each step and the forcing q = F C₄ Φ is linear between the step ends,
//! Φ_{j+1} = e^{Ah}Φ_j + (Γ₀ − Γ₁)q_j + Γ₁q_{j+1}, Γ₀ = ∫₀ʰ e^{A(h−τ)}dτ B_m,
//! Γ₁ = ∫₀ʰ e^{A(h−τ)} τ/h dτ B_m (implicit in q_{j+1}: a 2 × 2 solve per step). The rule is
//! symmetric, so its error is even in h and one Richardson step with N and N/2 steps,
//! (4M_N − M_{N/2})/3, makes it fourth order (measured: N = 32 → 64 reduces the multiplier
//! error 40-fold on the cubic-pitch HP-1 branch).
//!
//! Odd structures (every polynomial power odd; friction is odd) have half-wave symmetric
//! orbits: only odd harmonics are kept, the AFT samples half the period and the monodromy
//! is Φ(T/2)² (J(t) has period T/2). Polynomial structures are sampled alias-free with
//! N = (p + 1)H + 1 (p the largest power). For linear models A(U) is an exact quadratic in U
//! ([`QuadraticJacobian`], verified before use), which also gives the U column of the
//! Jacobian analytically. DECISIONS.md gives the measured effect of each.

use std::cell::RefCell;
use std::f64::consts::TAU;

use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;

use super::hopf::QuadraticJacobian;
use super::orbit::orbit_point;
use super::periodic::{stored_unknowns, PeriodicProblem};
use super::types::{BranchPoint, HopfPoint};
use crate::dynamics::SectionDynamics;
use crate::linalg::{doubled, propagators, ComplexLu};
use crate::section::Section;
use crate::{Error, Result};

/// Forces of g: heave F_h and pitch M_α.
const P: usize = 2;

/// Whether `section` can be condensed: aerodynamics linear and independent of K, and a
/// structure without a sharp freeplay (refused earlier anyway).
pub(super) fn applies(section: &Section) -> bool {
    section.aero.is_linear()
        && section.aero.reduced_frequency().is_none()
        && section.n_states() <= 20
        && section.structure.nonlinear.pitch_freeplay == 0.0
}

/// The linear part at one (ω, U): A, B_m, S₀, (M_s − M_a)⁻¹ and per harmonic k = 0 … H
/// the dynamic matrix D_k and the lag-state transfer L_k.
struct Linear {
    omega: f64,
    u: f64,
    /// A, row-major n × n.
    a: Vec<f64>,
    /// B_m, row-major n × 2.
    bm: Vec<f64>,
    /// ∂R/∂q₄ at rest.
    s0: [[f64; 4]; 2],
    /// (M_s − M_a)⁻¹.
    minv: [[f64; 2]; 2],
    /// D_k = s²I − A_vq − sA_vv − A_vx L_k, s = ikω (2 × 2 per harmonic).
    d: Vec<[[Complex64; 2]; 2]>,
    /// L_k = (sI − A_xx)⁻¹ (A_xq + sA_xv) (lag states × 2 per harmonic, row-major).
    lag: Vec<Vec<Complex64>>,
}

/// The condensed harmonic-balance problem of one section in scaled unknowns
/// Y = (heave and pitch coefficients, ω, U) / scales.
pub(super) struct CondensedBalance<'a> {
    section: &'a Section,
    n: usize,
    /// Coefficients per displacement, 2H + 1.
    w: usize,
    /// AFT samples N (over half the period for a symmetric structure).
    ns: usize,
    /// Steps of the variational integration per period (a multiple of 4).
    steps: usize,
    /// The harmonics kept: 0 … H, or only the odd ones when the structure is odd
    /// (half-wave symmetric orbits, `symmetric`).
    ks: Vec<usize>,
    /// Coefficient positions (cosine or constant, sine) of each kept harmonic.
    cpos: Vec<(usize, usize)>,
    /// Index of harmonic 1 in `ks`.
    k1: usize,
    /// Every structural term odd: z(θ + π) = −z(θ), J(t) of period T/2.
    symmetric: bool,
    friction: [f64; 4],
    /// Which of (h, α, ḣ, α̇) the nonlinear force g depends on.
    uses: [bool; 4],
    /// Which of g's components (F_h, M_α) is not identically zero.
    forces: [bool; 2],
    scales: Vec<f64>,
    /// Scale of each residual row (displacement scale × ω_Hopf²).
    row_scales: Vec<f64>,
    /// Q: basis[j·w + c].
    basis: Vec<f64>,
    /// d/dθ of the basis at the samples.
    dbasis: Vec<f64>,
    /// P: proj[c·N + j].
    proj: Vec<f64>,
    /// Points of the amplitude grid.
    fine_len: usize,
    /// e^{ikθ_j} at the amplitude grid (fine_len × (H + 1)).
    fine_trig: Vec<Complex64>,
    /// e^{ikθ_j} at the N + 1 ends of the variational steps ((N + 1) × (H + 1)).
    step_trig: Vec<Complex64>,
    /// The linear part of the last (ω, U) evaluated.
    cache: RefCell<Option<Linear>>,
    /// A(U) as an exact quadratic in U, when it is one (else central differences per U).
    quadratic: Option<QuadraticJacobian>,
    /// ∂R/∂q₄ at rest by the central differences A is built with (U-independent).
    s0_fd: [[f64; 4]; 2],
}

/// Value at θ of cos kθ (`sine` false; 1 for k = 0) or sin kθ, and of its derivative.
fn basis_fn(k: usize, sine: bool, theta: f64) -> (f64, f64) {
    let kf = k as f64;
    let (s, co) = (kf * theta).sin_cos();
    if sine {
        (s, kf * co)
    } else {
        (co, -kf * s)
    }
}

impl<'a> CondensedBalance<'a> {
    /// `harmonics` H, `steps` variational steps per period; `scales` those of the shooting
    /// unknowns (one per state, T, U: [`super::continuation::branch_scales`]); ω is scaled
    /// by 0.1 ω_Hopf.
    pub(super) fn new(
        section: &'a Section,
        harmonics: usize,
        steps: usize,
        scales: &[f64],
        hopf: &HopfPoint,
    ) -> Self {
        let n = section.n_states();
        let (state_scales, u_scale) = (&scales[..n], scales[n + 1]);
        let (omega_hopf, u_hopf) = (hopf.omega, hopf.u);
        let nl = &section.structure.nonlinear;
        let symmetric = nl
            .heave_stiffness_terms
            .iter()
            .chain(&nl.pitch_stiffness_terms)
            .all(|t| t.power % 2 == 1)
            && nl
                .heave_damping_terms
                .iter()
                .chain(&nl.pitch_damping_terms)
                .all(|t| t.power % 2 == 0)
            && nl.pitch_freeplay == 0.0;
        let ks: Vec<usize> = (0..=harmonics)
            .filter(|k| !symmetric || k % 2 == 1)
            .collect();
        // (k, sine) of each coefficient; positions of each harmonic's pair.
        let mut coefs = Vec::new();
        let mut cpos = Vec::new();
        for &k in &ks {
            if k == 0 {
                cpos.push((coefs.len(), usize::MAX));
                coefs.push((0, false));
            } else {
                cpos.push((coefs.len(), coefs.len() + 1));
                coefs.push((k, false));
                coefs.push((k, true));
            }
        }
        let w = coefs.len();
        // AFT samples over the period: products of H harmonics up to degree p fold back onto
        // kept harmonics only with N ≤ (p + 1)H, so a polynomial structure of largest power
        // p takes (p + 1)H + 1 (rounded up to a multiple of 4) and is projected exactly;
        // friction (tanh, every degree) takes 8H + 4 as the full harmonic balance. A
        // half-wave symmetric g (and its even derivative) times an odd harmonic repeats
        // itself over the second half, so a symmetric structure needs only the first half,
        // with double weight.
        let degree = nl
            .heave_stiffness_terms
            .iter()
            .chain(&nl.pitch_stiffness_terms)
            .map(|t| t.power as usize)
            .chain(
                nl.heave_damping_terms
                    .iter()
                    .chain(&nl.pitch_damping_terms)
                    .map(|t| t.power as usize + 1),
            )
            .max()
            .unwrap_or(1);
        let period = if section.structure.friction_resolved()[0] > 0.0
            || section.structure.friction_resolved()[2] > 0.0
        {
            8 * harmonics + 4
        } else {
            ((degree + 1) * harmonics + 1).next_multiple_of(4)
        };
        let (ns, weight) = if symmetric {
            (period / 2, 2.0)
        } else {
            (period, 1.0)
        };
        let mut basis = vec![0.0; ns * w];
        let mut dbasis = vec![0.0; ns * w];
        let mut proj = vec![0.0; w * ns];
        for j in 0..ns {
            let th = TAU * j as f64 / period as f64;
            for (c, &(k, sine)) in coefs.iter().enumerate() {
                let (v, dv) = basis_fn(k, sine, th);
                basis[j * w + c] = v;
                dbasis[j * w + c] = dv;
                proj[c * ns + j] = weight * if k == 0 { 1.0 } else { 2.0 } / period as f64 * v;
            }
        }
        let mut own = Vec::with_capacity(2 * w + 2);
        let mut row_scales = Vec::with_capacity(2 * w);
        for &s in &state_scales[..2] {
            own.extend(std::iter::repeat_n(s, w));
            row_scales.extend(std::iter::repeat_n(s * omega_hopf * omega_hopf, w));
        }
        own.push(0.1 * omega_hopf);
        own.push(u_scale);
        let steps = steps.max(4).next_multiple_of(4);
        let fine_len = 16 * harmonics.max(4);
        let trig = |points: usize, len: usize| -> Vec<Complex64> {
            (0..points)
                .flat_map(|j| {
                    let th = TAU * j as f64 / len as f64;
                    (0..=harmonics).map(move |k| Complex64::from_polar(1.0, k as f64 * th))
                })
                .collect()
        };
        let friction = section.structure.friction_resolved();
        let uses = [
            !nl.heave_stiffness_terms.is_empty(),
            !nl.pitch_stiffness_terms.is_empty(),
            friction[0] > 0.0,
            friction[2] > 0.0,
        ];
        CondensedBalance {
            section,
            n: section.n_states(),
            uses,
            forces: [uses[0] || uses[2], uses[1] || uses[3]],
            friction,
            w,
            ns,
            steps,
            k1: ks.iter().position(|&k| k == 1).expect("H ≥ 1"),
            ks,
            cpos,
            symmetric,
            fine_trig: trig(fine_len, fine_len),
            step_trig: trig(steps + 1, steps),
            scales: own,
            row_scales,
            basis,
            dbasis,
            proj,
            fine_len,
            cache: RefCell::new(None),
            // Nodes around the Hopf speed; the fit is exact (checked) or not used.
            quadratic: QuadraticJacobian::fit(
                section,
                [0.5 * u_hopf, u_hopf, 1.5 * u_hopf],
                1.2 * u_hopf,
            )
            .ok()
            .flatten(),
            s0_fd: SectionDynamics::new(section, u_hopf)
                .map(|d| d.structure_jacobian(&[0.0; 4]))
                .unwrap_or_default(),
        }
    }

    fn m(&self) -> usize {
        2 * self.w
    }

    /// Complex amplitude of the `hi`-th kept harmonic of a coefficient vector `v` of one
    /// displacement (a_k − i b_k; a₀ for k = 0).
    fn cplx(&self, v: &[f64], hi: usize) -> Complex64 {
        let (c, s) = self.cpos[hi];
        if s == usize::MAX {
            Complex64::new(v[c], 0.0)
        } else {
            Complex64::new(v[c], -v[s])
        }
    }

    /// Adds the real coefficients of the complex amplitude `v` of the `hi`-th kept harmonic
    /// to `r` (one displacement's w values).
    fn add_harmonic(&self, r: &mut [f64], hi: usize, v: Complex64) {
        let (c, s) = self.cpos[hi];
        r[c] += v.re;
        if s != usize::MAX {
            r[s] -= v.im;
        }
    }

    /// Index of the phase-condition unknown b_α1.
    fn phase_index(&self) -> usize {
        self.w + self.cpos[self.k1].1
    }

    fn unscale(&self, y: &DVector<f64>) -> (Vec<f64>, f64, f64) {
        let m = self.m();
        let x = (0..m).map(|i| y[i] * self.scales[i]).collect();
        (x, y[m] * self.scales[m], y[m + 1] * self.scales[m + 1])
    }

    /// Runs `f` on the linear part at (ω, U) (rebuilt when either changed).
    fn linear<T>(&self, omega: f64, u: f64, f: impl FnOnce(&Linear) -> T) -> Result<T> {
        if !(omega.is_finite() && omega > 0.0 && u.is_finite() && u > 0.0) {
            return Err(Error::numerical(
                "harmonic balance",
                format!("non-physical iterate ω = {omega} rad/s, U = {u} m/s"),
            ));
        }
        let mut cache = self.cache.borrow_mut();
        let lin = match cache.take() {
            Some(l) if l.u == u && l.omega == omega => l,
            Some(l) if l.u == u => self.harmonics_at(l, omega)?,
            old => self.build_linear(omega, u, old)?,
        };
        let out = f(&lin);
        *cache = Some(lin);
        Ok(out)
    }

    /// The linear part at (ω, U), in the storage of `old` when given.
    fn build_linear(&self, omega: f64, u: f64, old: Option<Linear>) -> Result<Linear> {
        let n = self.n;
        let d = SectionDynamics::new(self.section, u)?;
        let (mut a, mut bm, dm, lag) = match old {
            Some(l) => (l.a, l.bm, l.d, l.lag),
            None => (vec![0.0; n * n], vec![0.0; n * P], Vec::new(), Vec::new()),
        };
        match &self.quadratic {
            Some(q) => q.at(u, &mut a),
            None => d.jacobian(&vec![0.0; n], &mut a, &mut vec![0.0; 3 * n]),
        }
        // The analytic S₀ (so that g has no spurious linear part); A's structural part is
        // made consistent with it (they differ by the central differences' rounding).
        let s0 = self
            .section
            .structure
            .restoring_derivatives([0.0; 2], [0.0; 2], &self.friction);
        let s0_fd = self.s0_fd;
        let mi = d.mass_inverse();
        let minv = [[mi[(0, 0)], mi[(0, 1)]], [mi[(1, 0)], mi[(1, 1)]]];
        for r in 0..2 {
            for c in 0..4 {
                a[(2 + r) * n + c] -= (0..2)
                    .map(|p| minv[r][p] * (s0[p][c] - s0_fd[p][c]))
                    .sum::<f64>();
            }
        }
        for r in 0..2 {
            for p in 0..P {
                bm[(2 + r) * P + p] = minv[r][p];
            }
        }
        let lin = Linear {
            omega: f64::NAN,
            u,
            a,
            bm,
            s0,
            minv,
            d: dm,
            lag,
        };
        self.harmonics_at(lin, omega)
    }

    /// D_k and L_k of `lin` at frequency ω.
    fn harmonics_at(&self, mut lin: Linear, omega: f64) -> Result<Linear> {
        let (n, nl) = (self.n, self.n - 4);
        let zero = Complex64::new(0.0, 0.0);
        lin.d.clear();
        lin.lag.resize_with(self.ks.len(), Vec::new);
        let mut x = vec![zero; nl * nl];
        let mut col = vec![zero; nl];
        for (hi, &k) in self.ks.iter().enumerate() {
            let s = Complex64::new(0.0, k as f64 * omega);
            // L = (sI − A_xx)⁻¹(A_xq + sA_xv).
            let mut l = std::mem::take(&mut lin.lag[hi]);
            l.clear();
            l.resize(nl * 2, zero);
            if nl > 0 {
                let lu = self.lag_factors(&lin, s, &mut x)?;
                for q in 0..2 {
                    for (r, v) in col.iter_mut().enumerate() {
                        *v = lin.a[(4 + r) * n + q] + s * lin.a[(4 + r) * n + 2 + q];
                    }
                    lu.solve(&x, &mut col);
                    for r in 0..nl {
                        l[r * 2 + q] = col[r];
                    }
                }
            }
            let a = &lin.a;
            let mut d = [[zero; 2]; 2];
            for r in 0..2 {
                for q in 0..2 {
                    let mut v = -a[(2 + r) * n + q] - s * a[(2 + r) * n + 2 + q];
                    for i in 0..nl {
                        v -= a[(2 + r) * n + 4 + i] * l[i * 2 + q];
                    }
                    if r == q {
                        v += s * s;
                    }
                    d[r][q] = v;
                }
            }
            lin.d.push(d);
            lin.lag[hi] = l;
        }
        lin.omega = omega;
        Ok(lin)
    }

    /// Factors of sI − A_xx into `x` (lag states × lag states).
    fn lag_factors(&self, lin: &Linear, s: Complex64, x: &mut [Complex64]) -> Result<ComplexLu> {
        let (n, nl) = (self.n, self.n - 4);
        for r in 0..nl {
            for c in 0..nl {
                let diag = if r == c { s } else { Complex64::new(0.0, 0.0) };
                x[r * nl + c] = diag - lin.a[(4 + r) * n + 4 + c];
            }
        }
        ComplexLu::new(x, nl).ok_or_else(|| {
            Error::numerical(
                "harmonic balance",
                format!(
                    "the lag states resonate at s = {s} (ω = {} rad/s, U = {} m/s): sI − A_xx \
                     is singular",
                    lin.omega, lin.u
                ),
            )
        })
    }

    /// (sI − A_xx)⁻¹ applied to the two columns `rhs(r, q)` (r a lag state, q ∈ {h, α}),
    /// written into `out` (lag states × 2, row-major); `x` (lag states²) and `col` (lag
    /// states) are scratch.
    fn lag_solve(
        &self,
        lin: &Linear,
        s: Complex64,
        rhs: impl Fn(usize, usize) -> Complex64,
        (x, col, out): (&mut [Complex64], &mut [Complex64], &mut [Complex64]),
    ) -> Result<()> {
        if self.n == 4 {
            return Ok(());
        }
        let lu = self.lag_factors(lin, s, x)?;
        for q in 0..2 {
            for (r, v) in col.iter_mut().enumerate() {
                *v = rhs(r, q);
            }
            lu.solve(x, col);
            for (r, v) in col.iter().enumerate() {
                out[r * 2 + q] = *v;
            }
        }
        Ok(())
    }

    /// dD_k/ds = 2sI − A_vv − A_vx dL_k/ds, dL_k/ds = (sI − A_xx)⁻¹(A_xv − L_k), for the
    /// kept harmonics.
    fn dynamic_derivatives(&self, lin: &Linear) -> Result<Vec<[[Complex64; 2]; 2]>> {
        let (n, nl) = (self.n, self.n - 4);
        let zero = Complex64::new(0.0, 0.0);
        let a = &lin.a;
        let (mut x, mut col, mut dls) = (vec![zero; nl * nl], vec![zero; nl], vec![zero; 2 * nl]);
        let mut out = Vec::with_capacity(lin.lag.len());
        for (&k, l) in self.ks.iter().zip(&lin.lag) {
            let s = Complex64::new(0.0, k as f64 * lin.omega);
            self.lag_solve(
                lin,
                s,
                |r, q| a[(4 + r) * n + 2 + q] - l[r * 2 + q],
                (&mut x, &mut col, &mut dls),
            )?;
            let mut dd = [[zero; 2]; 2];
            for r in 0..2 {
                for q in 0..2 {
                    let mut dv = Complex64::new(-a[(2 + r) * n + 2 + q], 0.0);
                    for i in 0..nl {
                        dv -= a[(2 + r) * n + 4 + i] * dls[i * 2 + q];
                    }
                    if r == q {
                        dv += 2.0 * s;
                    }
                    dd[r][q] = dv;
                }
            }
            out.push(dd);
        }
        Ok(out)
    }

    /// ∂D_k/∂U = −dA_vq − s dA_vv − dA_vx L_k − A_vx ∂L_k/∂U with
    /// ∂L_k/∂U = (sI − A_xx)⁻¹(dA_xq + s dA_xv + dA_xx L_k), dA = dA/dU of the quadratic
    /// A(U), for the kept harmonics; `None` without a quadratic A(U). (M_s − M_a)⁻¹ is then
    /// constant, so the residual's U dependence is all in D_k.
    fn speed_derivatives(&self, lin: &Linear) -> Result<Option<Vec<[[Complex64; 2]; 2]>>> {
        let Some(quad) = &self.quadratic else {
            return Ok(None);
        };
        let (n, nl) = (self.n, self.n - 4);
        let a = &lin.a;
        let mut da = vec![0.0; n * n];
        quad.derivative_at(lin.u, &mut da);
        let zero = Complex64::new(0.0, 0.0);
        let (mut x, mut col, mut dl) = (vec![zero; nl * nl], vec![zero; nl], vec![zero; 2 * nl]);
        let mut out = Vec::with_capacity(lin.lag.len());
        for (&k, l) in self.ks.iter().zip(&lin.lag) {
            let s = Complex64::new(0.0, k as f64 * lin.omega);
            self.lag_solve(
                lin,
                s,
                |r, q| {
                    let row = (4 + r) * n;
                    da[row + q]
                        + s * da[row + 2 + q]
                        + (0..nl)
                            .map(|i| da[row + 4 + i] * l[i * 2 + q])
                            .sum::<Complex64>()
                },
                (&mut x, &mut col, &mut dl),
            )?;
            let du: [[Complex64; 2]; 2] = std::array::from_fn(|r| {
                let row = (2 + r) * n;
                std::array::from_fn(|q| {
                    let mut v = -da[row + q] - s * da[row + 2 + q];
                    for i in 0..nl {
                        v -= da[row + 4 + i] * l[i * 2 + q] + a[row + 4 + i] * dl[i * 2 + q];
                    }
                    v
                })
            });
            out.push(du);
        }
        Ok(Some(out))
    }

    /// The four structural states (h, α, ḣ, α̇) at the AFT samples (those g does not use
    /// left 0).
    fn samples(&self, x: &[f64], omega: f64) -> Vec<[f64; 4]> {
        let w = self.w;
        let mut out = vec![[0.0; 4]; self.ns];
        for (c, table, factor) in [
            (0, &self.basis, 1.0),
            (1, &self.basis, 1.0),
            (2, &self.dbasis, omega),
            (3, &self.dbasis, omega),
        ] {
            if !self.uses[c] {
                continue;
            }
            let xc = &x[(c % 2) * w..(c % 2 + 1) * w];
            for (o, b) in out.iter_mut().zip(table.chunks_exact(w)) {
                o[c] = factor * b.iter().zip(xc).map(|(p, v)| p * v).sum::<f64>();
            }
        }
        out
    }

    /// g = R − S₀q₄ at a structural state.
    fn force(&self, s0: &[[f64; 4]; 2], q: &[f64; 4]) -> [f64; 2] {
        let r = self
            .section
            .structure
            .restoring_with([q[0], q[1]], [q[2], q[3]], &self.friction);
        let mut g = [0.0; 2];
        for p in 0..P {
            g[p] = r[p] - (0..4).map(|c| s0[p][c] * q[c]).sum::<f64>();
        }
        g
    }

    /// ∂g/∂(h, α, ḣ, α̇) = ∂R/∂q₄ − S₀ at a structural state (rows F_h, M_α).
    fn slopes(&self, s0: &[[f64; 4]; 2], q: &[f64; 4]) -> [[f64; 4]; 2] {
        let d = self.section.structure.restoring_derivatives(
            [q[0], q[1]],
            [q[2], q[3]],
            &self.friction,
        );
        std::array::from_fn(|p| std::array::from_fn(|c| d[p][c] - s0[p][c]))
    }

    /// Harmonic coefficients of g (P × w) from the displacement coefficients.
    fn force_harmonics(&self, lin: &Linear, x: &[f64]) -> Vec<f64> {
        let (w, ns) = (self.w, self.ns);
        let g: Vec<[f64; 2]> = self
            .samples(x, lin.omega)
            .iter()
            .map(|q| self.force(&lin.s0, q))
            .collect();
        let mut out = vec![0.0; P * w];
        for p in (0..P).filter(|&p| self.forces[p]) {
            for (o, pr) in out[p * w..(p + 1) * w]
                .iter_mut()
                .zip(self.proj.chunks_exact(ns))
            {
                *o = pr.iter().zip(&g).map(|(a, b)| a * b[p]).sum();
            }
        }
        out
    }

    /// Unscaled residual D_k Q_k + (M_s − M_a)⁻¹ G_k as real coefficients (2w values).
    fn residual(&self, x: &[f64], omega: f64, u: f64) -> Result<Vec<f64>> {
        let w = self.w;
        let r = self.linear(omega, u, |lin| {
            let gh = self.force_harmonics(lin, x);
            let mut r = vec![0.0; 2 * w];
            for r_ in 0..2 {
                for c in 0..w {
                    r[r_ * w + c] = (0..P).map(|p| lin.minv[r_][p] * gh[p * w + c]).sum();
                }
            }
            for (hi, d) in lin.d.iter().enumerate() {
                for (r_, row) in d.iter().enumerate() {
                    let v: Complex64 = (0..2)
                        .map(|q| row[q] * self.cplx(&x[q * w..(q + 1) * w], hi))
                        .sum();
                    self.add_harmonic(&mut r[r_ * w..(r_ + 1) * w], hi, v);
                }
            }
            r
        })?;
        if r.iter().any(|v| !v.is_finite()) {
            return Err(Error::numerical(
                "harmonic balance",
                format!("non-finite residual at U = {u} m/s"),
            ));
        }
        Ok(r)
    }

    /// Every state's harmonics z_k = (q_k, ikω q_k, L_k q_k) of the kept harmonics.
    fn states(&self, lin: &Linear, x: &[f64]) -> Vec<Vec<Complex64>> {
        let (n, w) = (self.n, self.w);
        self.ks
            .iter()
            .enumerate()
            .map(|(hi, &k)| {
                let s = Complex64::new(0.0, k as f64 * lin.omega);
                let q = [self.cplx(&x[..w], hi), self.cplx(&x[w..], hi)];
                let mut z = vec![q[0], q[1], s * q[0], s * q[1]];
                let l = &lin.lag[hi];
                z.extend((0..n - 4).map(|i| l[i * 2] * q[0] + l[i * 2 + 1] * q[1]));
                z
            })
            .collect()
    }

    /// Sum of the kept harmonics `zk` of component `c` at the point of a trig table row
    /// (e^{ikθ}, k = 0 … H).
    fn at(&self, zk: &[Vec<Complex64>], trig: &[Complex64], c: usize) -> f64 {
        zk.iter()
            .zip(&self.ks)
            .map(|(z, &k)| (z[c] * trig[k]).re)
            .sum()
    }

    /// Monodromy matrix of the variational equation along the orbit with state harmonics
    /// `zk`, by the Richardson-extrapolated exponential trapezoidal rule. For a symmetric
    /// structure J(t) has period T/2 and M = Φ(T/2)², so half a period is integrated.
    fn monodromy(&self, lin: &Linear, zk: &[Vec<Complex64>]) -> Result<DMatrix<f64>> {
        let n = self.n;
        let steps = self.steps;
        let nh = self.step_trig.len() / (steps + 1);
        let h = TAU / lin.omega / steps as f64;
        let span = if self.symmetric { steps / 2 } else { steps };
        // F_j = −(∂R/∂q₄ − S₀) at θ_j = 2πj/N, j = 0 … span.
        let f: Vec<[[f64; 4]; 2]> = (0..=span)
            .map(|j| {
                let trig = &self.step_trig[j * nh..(j + 1) * nh];
                let q: [f64; 4] = std::array::from_fn(|c| self.at(zk, trig, c));
                self.slopes(&lin.s0, &q).map(|row| row.map(|v| -v))
            })
            .collect();
        let (e, g0, g1) = propagators(&lin.a, &lin.bm, n, P, h);
        let steps_of = |e: &[f64], g0: &[f64], g1: &[f64], stride: usize| {
            trapezoid(n, e, g0, g1, &f, stride, self.forces).ok_or_else(|| {
                Error::numerical(
                    "harmonic balance",
                    format!("{n} states: the condensed form takes 4 to 20"),
                )
            })
        };
        let fine = steps_of(&e, &g0, &g1, 1)?;
        let (e2, g02, g12) = doubled(n, P, &e, &g0, &g1);
        let coarse = steps_of(&e2, &g02, &g12, 2)?;
        let mut m = DMatrix::zeros(n, n);
        for r in 0..n {
            for c in 0..n {
                m[(r, c)] = (4.0 * fine[r * n + c] - coarse[r * n + c]) / 3.0;
            }
        }
        Ok(if self.symmetric { &m * &m } else { m })
    }
}

/// Monodromy (row-major) of Φ' = AΦ + B F(t) C₄ Φ by the exponential trapezoidal rule with
/// propagators (E, Γ₀, Γ₁) of one step, using every `stride`-th sample of `f`: per step
/// Φ_{j+1} = EΦ_j + (Γ₀ − Γ₁)q_j + Γ₁q_{j+1}, q = F C₄ Φ, (I − F_{j+1}C₄Γ₁) q_{j+1} =
/// F_{j+1}C₄(EΦ_j + (Γ₀ − Γ₁)q_j), on fixed-size arrays; `None` for a state count outside
/// 4 … 20.
fn trapezoid(
    n: usize,
    e: &[f64],
    g0: &[f64],
    g1: &[f64],
    f: &[[[f64; 4]; 2]],
    stride: usize,
    active: [bool; P],
) -> Option<Vec<f64>> {
    #[cfg(target_arch = "x86_64")]
    let avx2 = std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    let avx2 = false;
    macro_rules! sizes {
        ($($k:literal),*) => {
            match n {
                $($k => Some(if avx2 {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the CPU supports AVX2 (checked above)
                    unsafe {
                        trapezoid_n_avx2::<$k>(e, g0, g1, f, stride, active)
                    }
                    #[cfg(not(target_arch = "x86_64"))]
                    unreachable!()
                } else {
                    trapezoid_n::<$k>(e, g0, g1, f, stride, active)
                }),)*
                _ => None,
            }
        };
    }
    // Every state count the condensed form takes (`applies`: 4 + at most 16 lag states).
    sizes!(4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20)
}

/// [`trapezoid_n`] compiled with AVX2 (runtime-dispatched: the release profile targets
/// baseline x86-64, two lanes per instruction): each entry gets the same IEEE operations in
/// the same order (Rust never contracts `a * b + c` into a fused multiply-add), so bit for
/// bit the portable result, at four lanes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn trapezoid_n_avx2<const N: usize>(
    e: &[f64],
    g0: &[f64],
    g1: &[f64],
    f: &[[[f64; 4]; 2]],
    stride: usize,
    active: [bool; P],
) -> Vec<f64> {
    trapezoid_n::<N>(e, g0, g1, f, stride, active)
}

#[inline(always)]
fn trapezoid_n<const N: usize>(
    e: &[f64],
    g0: &[f64],
    g1: &[f64],
    f: &[[[f64; 4]; 2]],
    stride: usize,
    active: [bool; P],
) -> Vec<f64> {
    let mut em = [[0.0; N]; N];
    let mut ga = [[0.0; P]; N];
    let mut gb = [[0.0; P]; N];
    for r in 0..N {
        for c in 0..N {
            em[r][c] = e[r * N + c];
        }
        for p in 0..P {
            ga[r][p] = g0[r * P + p] - g1[r * P + p];
            gb[r][p] = g1[r * P + p];
        }
    }
    // a function, not a closure: a closure is not compiled with its caller's target
    // features (the AVX2 build above)
    #[inline(always)]
    fn forcing<const N: usize>(fj: &[[f64; 4]; 2], phi: &[[f64; N]; N]) -> [[f64; N]; P] {
        let mut q = [[0.0; N]; P];
        for p in 0..P {
            for c in 0..4 {
                let v = fj[p][c];
                if v != 0.0 {
                    for col in 0..N {
                        q[p][col] += v * phi[c][col];
                    }
                }
            }
        }
        q
    }
    let mut phi = [[0.0; N]; N];
    for (i, row) in phi.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let mut q = forcing(&f[0], &phi);
    let steps = (f.len() - 1) / stride;
    for j in 0..steps {
        let fj = &f[(j + 1) * stride];
        let mut x = [[0.0; N]; N];
        for r in 0..N {
            for l in 0..N {
                let v = em[r][l];
                for col in 0..N {
                    x[r][col] += v * phi[l][col];
                }
            }
            for p in (0..P).filter(|&p| active[p]) {
                let v = ga[r][p];
                for col in 0..N {
                    x[r][col] += v * q[p][col];
                }
            }
        }
        let rhs = forcing(fj, &x);
        let mut k = [[0.0; P]; P];
        for p in 0..P {
            for r in 0..P {
                let fc: f64 = (0..4).map(|c| fj[p][c] * gb[c][r]).sum();
                k[p][r] = if p == r { 1.0 } else { 0.0 } - fc;
            }
        }
        let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
        let mut qn = [[0.0; N]; P];
        for col in 0..N {
            let (r0, r1) = (rhs[0][col], rhs[1][col]);
            qn[0][col] = (k[1][1] * r0 - k[0][1] * r1) / det;
            qn[1][col] = (k[0][0] * r1 - k[1][0] * r0) / det;
        }
        for r in 0..N {
            for p in (0..P).filter(|&p| active[p]) {
                let v = gb[r][p];
                for col in 0..N {
                    x[r][col] += v * qn[p][col];
                }
            }
        }
        phi = x;
        q = qn;
    }
    phi.iter().flatten().copied().collect()
}

impl PeriodicProblem for CondensedBalance<'_> {
    fn unknowns(&self) -> usize {
        self.m() + 2
    }

    fn amplitude_index(&self) -> usize {
        self.w + self.cpos[self.k1].0
    }

    fn scales(&self) -> &[f64] {
        &self.scales
    }

    fn g(&self, y: &DVector<f64>) -> Result<DVector<f64>> {
        let (x, omega, u) = self.unscale(y);
        let r = self.residual(&x, omega, u)?;
        let m = self.m();
        let mut g = DVector::zeros(m + 1);
        for i in 0..m {
            g[i] = r[i] / self.row_scales[i];
        }
        g[m] = y[self.phase_index()];
        Ok(g)
    }

    /// Exact in the coefficients (the dynamic matrices and the AFT of the analytic ∂g), in ω
    /// (dD_k/ds and the velocity terms of g) and, when A(U) is the exact quadratic, in U
    /// (∂D_k/∂U); otherwise a forward difference in U.
    fn jac(&self, y: &DVector<f64>, g0: &DVector<f64>) -> Result<DMatrix<f64>> {
        let (x, omega, u) = self.unscale(y);
        let (w, ns) = (self.w, self.ns);
        let m = self.m();
        let mut out = DMatrix::zeros(m + 1, m + 2);
        let mut analytic_u = false;
        self.linear(omega, u, |lin| {
            let q = self.samples(&x, omega);
            // ∂g_p/∂(q_c, v_c) at the samples.
            let dg: Vec<[[f64; 4]; 2]> = q.iter().map(|q| self.slopes(&lin.s0, q)).collect();
            // ∂G_p/∂X_c = P diag(∂g_p/∂q_c) Q + ω P diag(∂g_p/∂v_c) Q' (w × w).
            let mut dgx = vec![0.0; P * 2 * w * w];
            let mut pv = vec![0.0; ns];
            for p in (0..P).filter(|&p| self.forces[p]) {
                for c in 0..2 {
                    let blk = &mut dgx[(p * 2 + c) * w * w..(p * 2 + c + 1) * w * w];
                    for (var, table, factor) in
                        [(c, &self.basis, 1.0), (2 + c, &self.dbasis, omega)]
                    {
                        if !self.uses[var] {
                            continue;
                        }
                        for r in 0..w {
                            let pr = &self.proj[r * ns..(r + 1) * ns];
                            for (j, v) in pv.iter_mut().enumerate() {
                                *v = factor * pr[j] * dg[j][p][var];
                            }
                            let row = &mut blk[r * w..(r + 1) * w];
                            for (v, b) in pv.iter().zip(table.chunks_exact(w)) {
                                for (o, bs) in row.iter_mut().zip(b) {
                                    *o += v * bs;
                                }
                            }
                        }
                    }
                }
            }
            // ∂/∂ω: Σ_k ik dD_k/ds Q_k, plus P diag(∂g/∂v_c) Q'X_c of velocity terms.
            let mut dw = vec![0.0; 2 * w];
            for (hi, dd) in self.dynamic_derivatives(lin)?.iter().enumerate() {
                let ik = Complex64::new(0.0, self.ks[hi] as f64);
                for (r, row) in dd.iter().enumerate() {
                    let v: Complex64 = (0..2)
                        .map(|c| ik * row[c] * self.cplx(&x[c * w..(c + 1) * w], hi))
                        .sum();
                    self.add_harmonic(&mut dw[r * w..(r + 1) * w], hi, v);
                }
            }
            for c in (0..2).filter(|&c| self.uses[2 + c]) {
                let xc = &x[c * w..(c + 1) * w];
                let dv: Vec<f64> = self
                    .dbasis
                    .chunks_exact(w)
                    .map(|b| b.iter().zip(xc).map(|(p, v)| p * v).sum())
                    .collect();
                for p in (0..P).filter(|&p| self.forces[p]) {
                    for (i, pr) in self.proj.chunks_exact(ns).enumerate() {
                        let gv: f64 = (0..ns).map(|j| pr[j] * dg[j][p][2 + c] * dv[j]).sum();
                        for r in 0..2 {
                            dw[r * w + i] += lin.minv[r][p] * gv;
                        }
                    }
                }
            }
            for (i, v) in dw.iter().enumerate() {
                out[(i, m)] = *v;
            }
            // ∂/∂U: Σ_k ∂D_k/∂U Q_k when A(U) is the exact quadratic.
            if let Some(du) = self.speed_derivatives(lin)? {
                let mut col = vec![0.0; 2 * w];
                for (hi, d) in du.iter().enumerate() {
                    for (r, row) in d.iter().enumerate() {
                        let v: Complex64 = (0..2)
                            .map(|c| row[c] * self.cplx(&x[c * w..(c + 1) * w], hi))
                            .sum();
                        self.add_harmonic(&mut col[r * w..(r + 1) * w], hi, v);
                    }
                }
                for (i, v) in col.iter().enumerate() {
                    out[(i, m + 1)] = *v;
                }
                analytic_u = true;
            }
            for r in 0..2 {
                for c in 0..2 {
                    for p in 0..P {
                        let mi = lin.minv[r][p];
                        if mi == 0.0 {
                            continue;
                        }
                        let blk = &dgx[(p * 2 + c) * w * w..(p * 2 + c + 1) * w * w];
                        for i in 0..w {
                            for s in 0..w {
                                out[(r * w + i, c * w + s)] += mi * blk[i * w + s];
                            }
                        }
                    }
                    // D_k mixes the (cos, sin) pair of harmonic k.
                    for (hi, d) in lin.d.iter().enumerate() {
                        let v = d[r][c];
                        let (ca, sb) = self.cpos[hi];
                        if sb == usize::MAX {
                            out[(r * w + ca, c * w + ca)] += v.re;
                        } else {
                            out[(r * w + ca, c * w + ca)] += v.re;
                            out[(r * w + ca, c * w + sb)] += v.im;
                            out[(r * w + sb, c * w + ca)] -= v.im;
                            out[(r * w + sb, c * w + sb)] += v.re;
                        }
                    }
                }
            }
            Ok::<(), Error>(())
        })??;
        let last = if analytic_u { m + 1 } else { m };
        for c in 0..=last {
            for r in 0..m {
                out[(r, c)] *= self.scales[c] / self.row_scales[r];
            }
        }
        if !analytic_u {
            let d = 1e-7 * (1.0 + y[m + 1].abs());
            let mut yp = y.clone();
            yp[m + 1] += d;
            let gp = self.g(&yp)?;
            out.set_column(m + 1, &((gp - g0) / d));
        }
        out[(m, self.phase_index())] = 1.0;
        Ok(out)
    }

    fn jacobian_at_solution(&self) -> bool {
        false
    }

    fn point(&self, y: &DVector<f64>, _jg: &DMatrix<f64>) -> Result<BranchPoint> {
        let (x, omega, u) = self.unscale(y);
        let n = self.n;
        let (zk, mono) = self.linear(omega, u, |lin| {
            let zk = self.states(lin, &x);
            let mono = self.monodromy(lin, &zk);
            mono.map(|m| (zk, m))
        })??;
        let nh = self.fine_trig.len() / self.fine_len;
        let s: Vec<[f64; 2]> = (0..self.fine_len)
            .map(|q| {
                let trig = &self.fine_trig[q * nh..(q + 1) * nh];
                [self.at(&zk, trig, 0), self.at(&zk, trig, 1)]
            })
            .collect();
        let state: Vec<f64> = (0..n).map(|i| zk.iter().map(|z| z[i].re).sum()).collect();
        let a1 = [zk[self.k1][0].norm(), zk[self.k1][1].norm()];
        orbit_point(u, omega, &s, a1, mono, state, y)
    }

    fn start(&self, hopf: &HopfPoint, a: f64) -> DVector<f64> {
        let m = self.m();
        let w = self.w;
        let mut y = DVector::zeros(m + 2);
        let (ca, sb) = self.cpos[self.k1];
        for c in 0..2 {
            let v = hopf.eigenvector[c];
            y[c * w + ca] = a * v.re / self.scales[c * w + ca];
            y[c * w + sb] = -a * v.im / self.scales[c * w + sb];
        }
        y[self.phase_index()] = 0.0;
        y[m] = hopf.omega / self.scales[m];
        y[m + 1] = hopf.u / self.scales[m + 1];
        y
    }

    fn scaled(&self, p: &BranchPoint) -> Result<DVector<f64>> {
        stored_unknowns(p, self.unknowns())
    }

    fn first_harmonics(&self, y: &DVector<f64>) -> Option<super::types::OrbitValues> {
        let (x, omega, u) = self.unscale(y);
        let w = self.w;
        Some(super::types::OrbitValues {
            u,
            amplitude1_alpha: self.cplx(&x[w..], self.k1).norm(),
            amplitude1_h: self.cplx(&x[..w], self.k1).norm(),
            frequency_hz: omega / TAU,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::continuation::{branch_scales, newton};
    use super::super::harmonic::HarmonicBalance;
    use super::super::periodic::Closure;
    use super::*;
    use crate::linalg::matmul_into;
    use crate::reference::hp1_cubic_pitch;
    use crate::structure::{Friction, PolyTerm};

    /// HP-1 with every kind of smooth structural term: cubic pitch, quadratic pitch (a mean
    /// offset), cubic heave and light regularised friction in both DOFs (velocity channels).
    fn every_term() -> Section {
        let mut s = hp1_cubic_pitch();
        let st = &mut s.structure;
        let (kh, ka) = (st.k_h, st.k_alpha);
        st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
            power: 2,
            coefficient: 2.0 * ka,
        });
        st.nonlinear.heave_stiffness_terms.push(PolyTerm {
            power: 3,
            coefficient: 50.0 * kh,
        });
        st.nonlinear.friction = Some(Friction {
            heave_force: 1e-4 * kh,
            pitch_moment: 1e-3 * ka,
            heave_smoothing: Some(0.5),
            pitch_smoothing: Some(0.5),
        });
        s
    }

    /// Scales as the continuation sets them, the Hopf point below 4 m/s.
    fn set_up(s: &Section) -> (HopfPoint, Vec<f64>) {
        let hopf = s.hopf_points(1.0, 4.0, 100).unwrap().remove(0);
        let scales = branch_scales(&hopf, 0.05);
        (hopf, scales)
    }

    /// The orbit of pitch cosine amplitude `a` by `p` from the Hopf eigenvector.
    fn orbit(p: &dyn PeriodicProblem, hopf: &HopfPoint, a: f64) -> BranchPoint {
        let c = Closure::Alpha(a / p.scales()[p.amplitude_index()]);
        let (y, j, _, _) = newton(p, p.start(hopf, a), &c, None, 1e-11, 60).unwrap();
        p.point(&y, &j).unwrap()
    }

    /// The condensed problem is the full harmonic balance with the linear states solved
    /// per harmonic: the same orbit (ω, U, amplitudes) to rounding, and its multipliers
    /// (exponential trapezoid, Richardson) equal the full problem's (RK4 on the variational
    /// equation, 512 steps).
    #[test]
    fn condensed_orbit_is_the_full_harmonic_balance_orbit() {
        for (name, s) in [
            ("cubic pitch", hp1_cubic_pitch()),
            ("every term", every_term()),
        ] {
            assert!(applies(&s));
            let (hopf, sc) = set_up(&s);
            let n = s.n_states();
            let full = HarmonicBalance::new(
                &s,
                5,
                512,
                &sc[..n],
                0.1 * hopf.omega,
                sc[n + 1],
                hopf.omega,
            );
            let cond = CondensedBalance::new(&s, 5, 128, &sc, &hopf);
            assert!(cond.unknowns() < full.unknowns());
            let a = 0.06;
            let pf = orbit(&full, &hopf, a);
            let pc = orbit(&cond, &hopf, a);
            let rel = |x: f64, y: f64| (x - y).abs() / y.abs();
            assert!(
                (pc.u - hopf.u).abs() > 1e-3 * hopf.u,
                "{name}: U {} at the Hopf point {}",
                pc.u,
                hopf.u
            );
            assert!(rel(pc.u, pf.u) < 1e-9, "{name}: U {} vs {}", pc.u, pf.u);
            assert!(
                rel(pc.omega, pf.omega) < 1e-9,
                "{name}: ω {} vs {}",
                pc.omega,
                pf.omega
            );
            assert!(
                rel(pc.amplitude_alpha, pf.amplitude_alpha) < 1e-9
                    && rel(pc.amplitude_h, pf.amplitude_h) < 1e-8,
                "{name}: amplitudes {} {} vs {} {}",
                pc.amplitude_alpha,
                pc.amplitude_h,
                pf.amplitude_alpha,
                pf.amplitude_h
            );
            let mut mc: Vec<f64> = pc.multipliers.iter().map(|m| m[0].hypot(m[1])).collect();
            let mut mf: Vec<f64> = pf.multipliers.iter().map(|m| m[0].hypot(m[1])).collect();
            mc.sort_by(f64::total_cmp);
            mf.sort_by(f64::total_cmp);
            for (x, y) in mc.iter().zip(&mf) {
                assert!((x - y).abs() < 1e-6, "{name}: multipliers {mc:?} vs {mf:?}");
            }
        }
    }

    /// The analytic Jacobian (coefficient blocks, ω column with dD/ds and the friction's
    /// velocity terms) equals central differences of G.
    #[test]
    fn condensed_jacobian_matches_finite_differences() {
        for s in [every_term(), hp1_cubic_pitch()] {
            jacobian_matches_finite_differences(&s);
        }
    }

    fn jacobian_matches_finite_differences(s: &Section) {
        let (hopf, sc) = set_up(s);
        let cond = CondensedBalance::new(s, 4, 64, &sc, &hopf);
        let c = Closure::Alpha(0.08 / cond.scales()[cond.amplitude_index()]);
        let (mut y, _, _, _) = newton(&cond, cond.start(&hopf, 0.08), &c, None, 1e-11, 60).unwrap();
        // off the solution, so that every term of the residual is exercised
        for i in 0..y.len() - 2 {
            y[i] += 0.01 * ((i * 7 % 5) as f64 - 2.0);
        }
        let g0 = cond.g(&y).unwrap();
        let j = cond.jac(&y, &g0).unwrap();
        for col in 0..y.len() {
            let d = 1e-6 * (1.0 + y[col].abs());
            let (mut yp, mut ym) = (y.clone(), y.clone());
            yp[col] += d;
            ym[col] -= d;
            let fd = (cond.g(&yp).unwrap() - cond.g(&ym).unwrap()) / (2.0 * d);
            let scale = fd.amax().max(1e-3);
            for r in 0..fd.len() {
                let tol = 1e-6;
                assert!(
                    (j[(r, col)] - fd[r]).abs() < tol * scale,
                    "∂G_{r}/∂Y_{col}: {} vs {}",
                    j[(r, col)],
                    fd[r]
                );
            }
        }
    }

    /// E, Γ₀, Γ₁ equal the blocks of the exponential of the augmented matrix
    /// [[Ah, Bh, 0], [0, 0, I], [0, 0, 0]] (Van Loan), with and without doublings.
    #[test]
    fn propagators_are_the_augmented_exponential() {
        let n = 6;
        let a: Vec<f64> = (0..n * n)
            .map(|i| {
                ((i * 37 % 23) as f64 / 23.0 - 0.5) * 3.0 - if i % (n + 1) == 0 { 0.4 } else { 0.0 }
            })
            .collect();
        let b: Vec<f64> = (0..n * P)
            .map(|i| ((i * 11 % 7) as f64 / 7.0) - 0.3)
            .collect();
        for h in [0.05, 0.4, 1.3] {
            let (e, g0, g1) = propagators(&a, &b, n, P, h);
            let dim = n + 2 * P;
            let mut z = DMatrix::zeros(dim, dim);
            for r in 0..n {
                for c in 0..n {
                    z[(r, c)] = a[r * n + c] * h;
                }
                for p in 0..P {
                    z[(r, n + p)] = b[r * P + p] * h;
                }
            }
            for p in 0..P {
                z[(n + p, n + P + p)] = 1.0;
            }
            let ez = z.exp();
            for r in 0..n {
                for c in 0..n {
                    assert!(
                        (e[r * n + c] - ez[(r, c)]).abs() < 1e-12,
                        "h {h} E[{r}][{c}]"
                    );
                }
                for p in 0..P {
                    assert!(
                        (g0[r * P + p] - ez[(r, n + p)]).abs() < 1e-12,
                        "h {h} Γ₀[{r}][{p}]"
                    );
                    assert!(
                        (g1[r * P + p] - ez[(r, n + P + p)]).abs() < 1e-12,
                        "h {h} Γ₁[{r}][{p}]"
                    );
                }
            }
        }
    }

    /// A plain dynamic-size implementation of [`trapezoid`]'s rule, the reference of
    /// `fixed_size_steps_equal_the_dynamic_steps`.
    fn trapezoid_dyn(
        n: usize,
        e: &[f64],
        g0: &[f64],
        g1: &[f64],
        f: &[[[f64; 4]; 2]],
        stride: usize,
    ) -> Vec<f64> {
        let ga: Vec<f64> = g0.iter().zip(g1).map(|(a, b)| a - b).collect();
        let forcing = |fj: &[[f64; 4]; 2], phi: &[f64], q: &mut [f64]| {
            q.fill(0.0);
            for p in 0..P {
                for c in 0..4 {
                    let v = fj[p][c];
                    if v != 0.0 {
                        for (o, x) in q[p * n..(p + 1) * n]
                            .iter_mut()
                            .zip(&phi[c * n..(c + 1) * n])
                        {
                            *o += v * x;
                        }
                    }
                }
            }
        };
        let add = |g: &[f64], q: &[f64], x: &mut [f64]| {
            for r in 0..n {
                for p in 0..P {
                    let v = g[r * P + p];
                    for (o, w) in x[r * n..(r + 1) * n].iter_mut().zip(&q[p * n..(p + 1) * n]) {
                        *o += v * w;
                    }
                }
            }
        };
        let mut phi = vec![0.0; n * n];
        for i in 0..n {
            phi[i * n + i] = 1.0;
        }
        let (mut q, mut qn, mut rhs) = (vec![0.0; P * n], vec![0.0; P * n], vec![0.0; P * n]);
        let mut x = vec![0.0; n * n];
        forcing(&f[0], &phi, &mut q);
        for j in 0..(f.len() - 1) / stride {
            let fj = &f[(j + 1) * stride];
            matmul_into(e, &phi, n, n, n, &mut x);
            add(&ga, &q, &mut x);
            forcing(fj, &x, &mut rhs);
            let mut k = [[0.0; P]; P];
            for p in 0..P {
                for r in 0..P {
                    let fc: f64 = (0..4).map(|c| fj[p][c] * g1[c * P + r]).sum();
                    k[p][r] = if p == r { 1.0 } else { 0.0 } - fc;
                }
            }
            let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
            for col in 0..n {
                let (r0, r1) = (rhs[col], rhs[n + col]);
                qn[col] = (k[1][1] * r0 - k[0][1] * r1) / det;
                qn[n + col] = (k[0][0] * r1 - k[1][0] * r0) / det;
            }
            add(g1, &qn, &mut x);
            std::mem::swap(&mut phi, &mut x);
            std::mem::swap(&mut q, &mut qn);
        }
        phi
    }

    /// The fixed-size variational stepping is the dynamic one.
    #[test]
    fn fixed_size_steps_equal_the_dynamic_steps() {
        let n = 6;
        let v = |i: usize, s: f64| ((i * 37 % 101) as f64 / 101.0 - 0.5) * s;
        let e: Vec<f64> = (0..n * n)
            .map(|i| v(i, 0.2) + if i % (n + 1) == 0 { 1.0 } else { 0.0 })
            .collect();
        let g0: Vec<f64> = (0..n * P).map(|i| v(i + 3, 0.1)).collect();
        let g1: Vec<f64> = (0..n * P).map(|i| v(i + 9, 0.05)).collect();
        let f: Vec<[[f64; 4]; 2]> = (0..17)
            .map(|j| std::array::from_fn(|p| std::array::from_fn(|c| v(j * 8 + p * 4 + c, 0.3))))
            .collect();
        let a = trapezoid(n, &e, &g0, &g1, &f, 2, [true, true]).unwrap();
        let b = trapezoid_dyn(n, &e, &g0, &g1, &f, 2);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-13 * (1.0 + y.abs()), "{x} vs {y}");
        }
        // the dispatched build (AVX2 where the CPU has it) is the portable one bit for bit
        let portable = trapezoid_n::<6>(&e, &g0, &g1, &f, 2, [true, true]);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&portable));
    }
}
