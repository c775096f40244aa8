//! Single shooting ([`BranchMethod::Shooting`](super::BranchMethod::Shooting)): the flow
//! over one period by fixed RK4 steps, its periodicity and phase residuals, and the
//! finite-difference Jacobian whose state block is the monodromy matrix.

use nalgebra::{DMatrix, DVector};

use super::orbit::{first_harmonic, orbit_point};
use super::periodic::PeriodicProblem;
use super::types::{BranchPoint, HopfPoint};
use crate::dynamics::SectionDynamics;
use crate::integrate::Rk4;
use crate::section::Section;
use crate::{Error, Result};

/// The shooting problem of one section in scaled unknowns Y = (z₀, T, U) / scales.
pub(super) struct Shooting<'a> {
    section: &'a Section,
    n: usize,
    steps: usize,
    scales: Vec<f64>,
}

/// Result of one flow evaluation.
struct Flow {
    end: Vec<f64>,
    samples: Option<Vec<[f64; 2]>>,
}

impl<'a> Shooting<'a> {
    pub(super) fn new(section: &'a Section, steps: usize, scales: Vec<f64>) -> Self {
        Shooting {
            section,
            n: section.n_states(),
            steps,
            scales,
        }
    }

    fn unscale(&self, y: &DVector<f64>) -> (Vec<f64>, f64, f64) {
        let n = self.n;
        let z = (0..n).map(|i| y[i] * self.scales[i]).collect();
        (z, y[n] * self.scales[n], y[n + 1] * self.scales[n + 1])
    }

    /// φ_T(z₀; U) by `steps` RK4 steps; with `record`, (h, α) at every step.
    fn flow(&self, z0: &[f64], t: f64, u: f64, record: bool) -> Result<Flow> {
        if !(t.is_finite() && t > 0.0 && u.is_finite() && u > 0.0) {
            return Err(Error::numerical(
                "shooting",
                format!("non-physical iterate T = {t} s, U = {u} m/s"),
            ));
        }
        // K-dependent models at the orbit's own K = B(2π/T)/U
        let k = self.section.aero.chord() * (std::f64::consts::TAU / t) / u;
        let rebuilt = self.section.at_reduced_frequency(k)?;
        let dynamics = SectionDynamics::new(rebuilt.as_ref().unwrap_or(self.section), u)?;
        let dt = t / self.steps as f64;
        let mut z = z0.to_vec();
        let mut work = Rk4::new(self.n);
        let mut samples = record.then(|| Vec::with_capacity(self.steps + 1));
        for _ in 0..self.steps {
            if let Some(s) = samples.as_mut() {
                s.push([z[0], z[1]]);
            }
            work.step(&dynamics, 0.0, dt, &mut z);
        }
        if z.iter().any(|v| !v.is_finite()) {
            return Err(Error::numerical(
                "shooting",
                format!("orbit integration overflowed at U = {u} m/s"),
            ));
        }
        Ok(Flow { end: z, samples })
    }
}

impl PeriodicProblem for Shooting<'_> {
    fn unknowns(&self) -> usize {
        self.n + 2
    }

    fn amplitude_index(&self) -> usize {
        1
    }

    fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// Periodicity and phase residuals (n + 1 values, scaled).
    fn g(&self, y: &DVector<f64>) -> Result<DVector<f64>> {
        let (z, t, u) = self.unscale(y);
        let f = self.flow(&z, t, u, false)?;
        let n = self.n;
        let mut g = DVector::zeros(n + 1);
        for i in 0..n {
            g[i] = (f.end[i] - z[i]) / self.scales[i];
        }
        g[n] = y[3];
        Ok(g)
    }

    /// Forward-difference Jacobian of G at `y` given G(y).
    fn jac(&self, y: &DVector<f64>, g0: &DVector<f64>) -> Result<DMatrix<f64>> {
        let m = self.n + 2;
        let mut j = DMatrix::zeros(self.n + 1, m);
        for c in 0..m {
            let d = 1e-7 * (1.0 + y[c].abs());
            let mut yp = y.clone();
            yp[c] += d;
            let gp = self.g(&yp)?;
            j.set_column(c, &((gp - g0) / d));
        }
        Ok(j)
    }

    /// The orbit at `y` (converged) with its multipliers from the Jacobian `jg`.
    fn point(&self, y: &DVector<f64>, jg: &DMatrix<f64>) -> Result<BranchPoint> {
        let (z, t, u) = self.unscale(y);
        let f = self.flow(&z, t, u, true)?;
        let s = f.samples.unwrap_or_default();
        // Monodromy in scaled variables: M_s = S⁻¹ (∂φ/∂z₀) S = J_zz + I (same spectrum).
        let n = self.n;
        let mut mono = jg.view((0, 0), (n, n)).into_owned();
        for i in 0..n {
            mono[(i, i)] += 1.0;
        }
        let a1 = [first_harmonic(&s, 0), first_harmonic(&s, 1)];
        orbit_point(u, std::f64::consts::TAU / t, &s, a1, mono, z, y)
    }

    fn start(&self, hopf: &HopfPoint, a: f64) -> DVector<f64> {
        let n = self.n;
        let mut y = DVector::zeros(n + 2);
        for i in 0..n {
            y[i] = a * hopf.eigenvector[i].re / self.scales[i];
        }
        y[3] = 0.0;
        y[n] = std::f64::consts::TAU / hopf.omega / self.scales[n];
        y[n + 1] = hopf.u / self.scales[n + 1];
        y
    }

    fn scaled(&self, p: &BranchPoint) -> Result<DVector<f64>> {
        let n = self.n;
        let mut y = DVector::zeros(n + 2);
        for i in 0..n {
            y[i] = p.state[i] / self.scales[i];
        }
        y[n] = p.period / self.scales[n];
        y[n + 1] = p.u / self.scales[n + 1];
        Ok(y)
    }
}
