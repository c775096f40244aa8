//! Periodic orbits by harmonic balance (alternating frequency–time, AFT), the faster of the
//! two orbit discretisations of the continuation ([`super::BranchMethod`]).
//!
//! Each state is a truncated Fourier series in θ = ωt,
//! z_i(θ) = a_i0 + Σ_{k=1}^{H} (a_ik cos kθ + b_ik sin kθ),
//! and the equations are the Galerkin projection of ż = f(z; U) on those harmonics:
//! R_i = ω D X_i − P f_i(Q X) = 0, with Q the series evaluated at N equally spaced θ_j,
//! P the discrete Fourier projection back (exact for products up to degree (N − 1)/H − 1
//! without aliasing) and D the derivative d/dθ: (a_k, b_k) ↦ (k b_k, −k a_k). The phase
//! condition is b_α1 = 0 (the first pitch harmonic is a cosine). Unknowns: all
//! coefficients, ω and U.
//!
//! The Jacobian is exact up to the rate's own Jacobian: ∂R_i/∂X_c = ω D δ_ic −
//! P diag(J_ic(θ_j)) Q, where J = ∂f/∂z at the samples. For aerodynamic models that are
//! linear ([`crate::aero::AeroModel::is_linear`]) J is the equilibrium Jacobian plus the
//! structure's nonlinear stiffness, so only the few blocks that vary along the orbit are
//! projected; constant blocks are multiples of the identity. ∂R/∂U is a forward
//! difference.
//!
//! Floquet multipliers: the monodromy matrix of the variational equation Φ' = J(t) Φ over
//! one period, integrated by classical RK4 with `steps` steps along the harmonic-balance
//! orbit (J evaluated on the series, so no nonlinear integration is needed).

use std::f64::consts::TAU;

use nalgebra::{DMatrix, DVector};

use super::orbit::orbit_point;
use super::periodic::{stored_unknowns, PeriodicProblem};
use super::types::{BranchPoint, HopfPoint};
use crate::dynamics::SectionDynamics;
use crate::integrate::{OdeSystem, Rk4};
use crate::section::Section;
use crate::{Error, Result};

/// The harmonic-balance problem of one section in scaled unknowns
/// Y = (X, ω, U) / scales.
pub(super) struct HarmonicBalance<'a> {
    section: &'a Section,
    /// States.
    n: usize,
    /// Coefficients per state, 2H + 1.
    w: usize,
    /// AFT samples N.
    ns: usize,
    /// RK4 steps of the variational equation.
    steps: usize,
    scales: Vec<f64>,
    /// Scale of each residual row (state scale × ω at the Hopf point).
    row_scales: Vec<f64>,
    /// Q: basis[j·w + c] = value of coefficient c's function at θ_j.
    basis: Vec<f64>,
    /// P: proj[c·N + j].
    proj: Vec<f64>,
    /// Basis on the fine grid of the amplitudes (`fine_len` points).
    fine: Vec<f64>,
    /// Basis at the 2·steps + 1 points of the monodromy integration.
    var: Vec<f64>,
    k_dependent: bool,
    linear_aero: bool,
}

/// Value at θ of the function of coefficient `c` (0: 1; 2k − 1: cos kθ; 2k: sin kθ).
fn basis_fn(c: usize, theta: f64) -> f64 {
    if c == 0 {
        1.0
    } else {
        let k = c.div_ceil(2) as f64;
        if c % 2 == 1 {
            (k * theta).cos()
        } else {
            (k * theta).sin()
        }
    }
}

impl<'a> HarmonicBalance<'a> {
    /// `harmonics` H, `steps` RK4 steps for the monodromy; scales of the state
    /// components (one per state), ω and U as for shooting.
    pub(super) fn new(
        section: &'a Section,
        harmonics: usize,
        steps: usize,
        state_scales: &[f64],
        omega_scale: f64,
        u_scale: f64,
        omega_hopf: f64,
    ) -> Self {
        let n = section.n_states();
        let nh = harmonics;
        let w = 2 * nh + 1;
        // Products up to degree 7 of H harmonics fold back onto harmonics > H only.
        let ns = 8 * nh + 4;
        let mut basis = vec![0.0; ns * w];
        let mut proj = vec![0.0; w * ns];
        for j in 0..ns {
            let th = TAU * j as f64 / ns as f64;
            for c in 0..w {
                let v = basis_fn(c, th);
                basis[j * w + c] = v;
                let weight = if c == 0 { 1.0 } else { 2.0 } / ns as f64;
                proj[c * ns + j] = weight * v;
            }
        }
        let table = |len: usize, points: usize| -> Vec<f64> {
            let mut t = vec![0.0; points * w];
            for q in 0..points {
                let th = TAU * q as f64 / len as f64;
                for c in 0..w {
                    t[q * w + c] = basis_fn(c, th);
                }
            }
            t
        };
        let fine_len = 16 * nh.max(4);
        let fine = table(fine_len, fine_len);
        let var = table(2 * steps, 2 * steps + 1);
        let mut scales = Vec::with_capacity(n * w + 2);
        let mut row_scales = Vec::with_capacity(n * w);
        for &s in state_scales.iter().take(n) {
            for _ in 0..w {
                scales.push(s);
                row_scales.push(s * omega_hopf);
            }
        }
        scales.push(omega_scale);
        scales.push(u_scale);
        HarmonicBalance {
            section,
            n,
            w,
            ns,
            steps,
            scales,
            row_scales,
            basis,
            proj,
            fine,
            var,
            k_dependent: section.aero.reduced_frequency().is_some(),
            linear_aero: section.aero.is_linear(),
        }
    }

    fn unscale(&self, y: &DVector<f64>) -> (Vec<f64>, f64, f64) {
        let m = self.n * self.w;
        let x = (0..m).map(|i| y[i] * self.scales[i]).collect();
        (x, y[m] * self.scales[m], y[m + 1] * self.scales[m + 1])
    }

    /// The section at the orbit's reduced frequency (K-dependent models) or itself.
    fn with_section<T>(
        &self,
        omega: f64,
        u: f64,
        f: impl FnOnce(&SectionDynamics) -> Result<T>,
    ) -> Result<T> {
        if !(omega.is_finite() && omega > 0.0 && u.is_finite() && u > 0.0) {
            return Err(Error::numerical(
                "harmonic balance",
                format!("non-physical iterate ω = {omega} rad/s, U = {u} m/s"),
            ));
        }
        let rebuilt = self
            .section
            .at_reduced_frequency(self.section.aero.chord() * omega / u)?;
        f(&SectionDynamics::new(
            rebuilt.as_ref().unwrap_or(self.section),
            u,
        )?)
    }

    /// States at the N samples, row-major N × n.
    fn samples(&self, x: &[f64]) -> Vec<f64> {
        self.states_on(&self.basis, x)
    }

    /// States at the points of a basis `table` (points × w), row-major points × n.
    fn states_on(&self, table: &[f64], x: &[f64]) -> Vec<f64> {
        let (n, w) = (self.n, self.w);
        let ns = table.len() / w;
        let mut z = vec![0.0; ns * n];
        for j in 0..ns {
            let b = &table[j * w..(j + 1) * w];
            for i in 0..n {
                let c = &x[i * w..(i + 1) * w];
                z[j * n + i] = b.iter().zip(c).map(|(p, q)| p * q).sum();
            }
        }
        z
    }

    /// Unscaled residual R = ω D X − P f(Q X) (n·w values).
    fn residual(&self, d: &SectionDynamics, x: &[f64], omega: f64) -> Result<Vec<f64>> {
        let (n, w, ns) = (self.n, self.w, self.ns);
        let z = self.samples(x);
        let mut f = vec![0.0; ns * n];
        for j in 0..ns {
            d.rate(&z[j * n..(j + 1) * n], &mut f[j * n..(j + 1) * n]);
        }
        let mut r = vec![0.0; n * w];
        for i in 0..n {
            for c in 0..w {
                let p = &self.proj[c * ns..(c + 1) * ns];
                let pf: f64 = (0..ns).map(|j| p[j] * f[j * n + i]).sum();
                r[i * w + c] = omega * self.derivative(x, i, c) - pf;
            }
        }
        if r.iter().any(|v| !v.is_finite()) {
            return Err(Error::numerical(
                "harmonic balance",
                format!("non-finite residual at U = {} m/s", d.u()),
            ));
        }
        Ok(r)
    }

    /// Coefficient `c` of d/dθ of state `i`.
    fn derivative(&self, x: &[f64], i: usize, c: usize) -> f64 {
        if c == 0 {
            return 0.0;
        }
        let k = c.div_ceil(2) as f64;
        let base = i * self.w;
        if c % 2 == 1 {
            k * x[base + c + 1]
        } else {
            -k * x[base + c - 1]
        }
    }

    /// Rate Jacobians at the states `z` (row-major, each n × n).
    fn jacobians(&self, d: &SectionDynamics, z: &[f64]) -> Vec<f64> {
        let n = self.n;
        let count = z.len() / n;
        let mut out = vec![0.0; count * n * n];
        let mut work = vec![0.0; 3 * n];
        if self.linear_aero {
            let zero = vec![0.0; n];
            let mut j0 = vec![0.0; n * n];
            d.jacobian(&zero, &mut j0, &mut work);
            let s0 = d.structure_jacobian(&zero);
            let minv = d.mass_inverse();
            for (j, jac) in out.chunks_mut(n * n).enumerate() {
                jac.copy_from_slice(&j0);
                let sj = d.structure_jacobian(&z[j * n..(j + 1) * n]);
                for c in 0..4 {
                    let ds = [sj[0][c] - s0[0][c], sj[1][c] - s0[1][c]];
                    if ds[0] == 0.0 && ds[1] == 0.0 {
                        continue;
                    }
                    for r in 0..2 {
                        jac[(2 + r) * n + c] -= minv[(r, 0)] * ds[0] + minv[(r, 1)] * ds[1];
                    }
                }
            }
        } else {
            for (j, jac) in out.chunks_mut(n * n).enumerate() {
                d.jacobian(&z[j * n..(j + 1) * n], jac, &mut work);
            }
        }
        out
    }

    /// Unscaled ∂R/∂X (n·w × n·w), column-major for nalgebra.
    fn coefficient_jacobian(&self, d: &SectionDynamics, x: &[f64], omega: f64) -> DMatrix<f64> {
        let (n, w, ns) = (self.n, self.w, self.ns);
        let z = self.samples(x);
        let jac = self.jacobians(d, &z);
        let mut a = DMatrix::zeros(n * w, n * w);
        let mut v = vec![0.0; ns];
        let mut pv = vec![0.0; w * ns];
        for i in 0..n {
            for k in 0..n {
                for (j, vj) in v.iter_mut().enumerate() {
                    *vj = jac[j * n * n + i * n + k];
                }
                let (lo, hi) = v
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
                        (l.min(x), h.max(x))
                    });
                if hi - lo <= 1e-13 * lo.abs().max(hi.abs()) {
                    if v[0] != 0.0 {
                        for c in 0..w {
                            a[(i * w + c, k * w + c)] -= v[0];
                        }
                    }
                    continue;
                }
                // Block −P diag(v) Q.
                for r in 0..w {
                    let p = &self.proj[r * ns..(r + 1) * ns];
                    for j in 0..ns {
                        pv[r * ns + j] = p[j] * v[j];
                    }
                }
                for s in 0..w {
                    for r in 0..w {
                        let mut acc = 0.0;
                        for j in 0..ns {
                            acc += pv[r * ns + j] * self.basis[j * w + s];
                        }
                        a[(i * w + r, k * w + s)] -= acc;
                    }
                }
            }
            for c in 1..w {
                let kf = c.div_ceil(2) as f64;
                if c % 2 == 1 {
                    a[(i * w + c, i * w + c + 1)] += omega * kf;
                } else {
                    a[(i * w + c, i * w + c - 1)] -= omega * kf;
                }
            }
        }
        a
    }

    /// Monodromy matrix of Φ' = J(t)Φ over one period along the orbit `x`.
    fn monodromy(&self, d: &SectionDynamics, x: &[f64], omega: f64) -> DMatrix<f64> {
        let n = self.n;
        let nn = n * n;
        let z = self.states_on(&self.var, x);
        let jac = self.jacobians(d, &z);
        let h = TAU / omega / self.steps as f64;
        let sys = Variational {
            n,
            half_step: 0.5 * h,
            jacobians: &jac,
        };
        let mut phi = vec![0.0; nn];
        for i in 0..n {
            phi[i * n + i] = 1.0;
        }
        let mut rk4 = Rk4::new(nn);
        for step in 0..self.steps {
            rk4.step(&sys, step as f64 * h, h, &mut phi);
        }
        DMatrix::from_row_slice(n, n, &phi)
    }
}

/// The variational equation Φ' = J(t) Φ of an orbit for the fixed-step RK4 of
/// [`HarmonicBalance`]'s monodromy: Φ row-major n × n, J(t) the rate's Jacobian sampled on
/// the half steps of the grid (`jacobians[k]` at t = k·h/2, row-major n × n each).
struct Variational<'a> {
    n: usize,
    half_step: f64,
    jacobians: &'a [f64],
}

impl OdeSystem for Variational<'_> {
    fn dim(&self) -> usize {
        self.n * self.n
    }

    fn rate(&self, t: f64, phi: &[f64], out: &mut [f64]) {
        let (n, nn) = (self.n, self.n * self.n);
        let k = (t / self.half_step).round() as usize;
        let j = &self.jacobians[k * nn..(k + 1) * nn];
        for r in 0..n {
            for col in 0..n {
                out[r * n + col] = (0..n).map(|m| j[r * n + m] * phi[m * n + col]).sum();
            }
        }
    }
}

impl PeriodicProblem for HarmonicBalance<'_> {
    fn unknowns(&self) -> usize {
        self.n * self.w + 2
    }

    fn amplitude_index(&self) -> usize {
        self.w + 1
    }

    fn scales(&self) -> &[f64] {
        &self.scales
    }

    fn g(&self, y: &DVector<f64>) -> Result<DVector<f64>> {
        let (x, omega, u) = self.unscale(y);
        let r = self.with_section(omega, u, |d| self.residual(d, &x, omega))?;
        let m = self.n * self.w;
        let mut g = DVector::zeros(m + 1);
        for i in 0..m {
            g[i] = r[i] / self.row_scales[i];
        }
        g[m] = y[self.w + 2];
        Ok(g)
    }

    fn jac(&self, y: &DVector<f64>, g0: &DVector<f64>) -> Result<DMatrix<f64>> {
        let (x, omega, u) = self.unscale(y);
        let m = self.n * self.w;
        let mut out = DMatrix::zeros(m + 1, m + 2);
        let a = self.with_section(omega, u, |d| Ok(self.coefficient_jacobian(d, &x, omega)))?;
        for c in 0..m {
            for r in 0..m {
                out[(r, c)] = a[(r, c)] * self.scales[c] / self.row_scales[r];
            }
        }
        // ω column: D X (plus the model's own K dependence by a forward difference).
        if self.k_dependent {
            let d = 1e-7 * (1.0 + y[m].abs());
            let mut yp = y.clone();
            yp[m] += d;
            let gp = self.g(&yp)?;
            out.set_column(m, &((gp - g0) / d));
        } else {
            for i in 0..self.n {
                for c in 0..self.w {
                    out[(i * self.w + c, m)] = self.derivative(&x, i, c) * self.scales[m]
                        / self.row_scales[i * self.w + c];
                }
            }
        }
        let d = 1e-7 * (1.0 + y[m + 1].abs());
        let mut yp = y.clone();
        yp[m + 1] += d;
        let gp = self.g(&yp)?;
        out.set_column(m + 1, &((gp - g0) / d));
        out[(m, self.w + 2)] = 1.0;
        Ok(out)
    }

    fn point(&self, y: &DVector<f64>, _jg: &DMatrix<f64>) -> Result<BranchPoint> {
        let (x, omega, u) = self.unscale(y);
        let n = self.n;
        let zf = self.states_on(&self.fine, &x);
        let s: Vec<[f64; 2]> = zf.chunks(n).map(|z| [z[0], z[1]]).collect();
        let mono = self.with_section(omega, u, |d| Ok(self.monodromy(d, &x, omega)))?;
        let w = self.w;
        let a1 = [x[1].hypot(x[2]), x[w + 1].hypot(x[w + 2])];
        orbit_point(u, omega, &s, a1, mono, zf[..n].to_vec(), y)
    }

    fn start(&self, hopf: &HopfPoint, a: f64) -> DVector<f64> {
        let m = self.n * self.w;
        let mut y = DVector::zeros(m + 2);
        for i in 0..self.n {
            let v = hopf.eigenvector[i];
            y[i * self.w + 1] = a * v.re / self.scales[i * self.w + 1];
            y[i * self.w + 2] = -a * v.im / self.scales[i * self.w + 2];
        }
        y[self.w + 2] = 0.0;
        y[m] = hopf.omega / self.scales[m];
        y[m + 1] = hopf.u / self.scales[m + 1];
        y
    }

    fn scaled(&self, p: &BranchPoint) -> Result<DVector<f64>> {
        stored_unknowns(p, self.unknowns())
    }
}
