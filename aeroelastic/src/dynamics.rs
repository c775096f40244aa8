//! The section's equations of motion, once: the rate of the full first-order state of the
//! nonlinear section at one wind speed. Every time integration (LCO runs, trajectories,
//! free-response records, continuation of periodic orbits) evaluates this and nothing else.
//!
//! State z = (h, α, ḣ, α̇, x₁ … x_n): h heave \[m\] positive down, α pitch \[rad\] positive
//! nose-up, x the aerodynamic model's lag states. Equations (DESIGN.md §4):
//!
//! (M_s − M_a) q̈ = F_aero(q, q̇, x) − R(q, q̇),   ẋ = lag rates of the model,
//!
//! with M_a the model's apparent mass, F_aero = (L, M) per unit span (L positive down,
//! M nose-up about the elastic axis) and R the structure's restoring force including its
//! nonlinear springs, freeplay and (smoothed) friction. A caller's [`ExtraTerms`] (the
//! diagnosis's fitted augmentations) enter the same equations: a mass ΔM moved to the
//! right-hand side and a change of the applied force,
//! (M_s − M_a − ΔM) q̈ = F̃(q, q̇, F_aero) − R(q, q̇).

use nalgebra::Matrix2;

use crate::aero::Flow;
use crate::section::Section;
use crate::{Error, Result};

/// Terms a caller adds to the section's equations of motion (DESIGN.md §5: the
/// diagnosis's fitted effects are terms of this one rate function, not a second equation
/// of motion).
pub trait ExtraTerms: Sync + std::fmt::Debug {
    /// The mass ΔM moved to the right-hand side, ΔM q̈ (the equations carry
    /// M_s − M_a − ΔM on the left), rows \[kg/m, kg; kg, kg·m\] per unit span.
    fn mass(&self) -> Matrix2<f64>;

    /// The applied generalised force F̃ (lift positive down \[N/m\], moment nose-up
    /// \[N·m/m\]) at heave and pitch `q`, rates `qd`, given the aerodynamic model's force
    /// `f` (zero in still air): `f` itself when the caller adds nothing.
    fn applied(&self, q: [f64; 2], qd: [f64; 2], f: [f64; 2]) -> [f64; 2];
}

/// Right-hand side ż = f(z) of the nonlinear section at a fixed wind speed.
///
/// Built once per speed (it inverts the total mass matrix and resolves the friction
/// parameters); [`SectionDynamics::rate`] is then allocation-free.
#[derive(Debug, Clone)]
pub struct SectionDynamics<'a> {
    section: &'a Section,
    flow: Flow,
    minv: Matrix2<f64>,
    friction: [f64; 4],
    nlag: usize,
    extra: Option<&'a dyn ExtraTerms>,
}

impl<'a> SectionDynamics<'a> {
    /// Dynamics of `section` at wind speed `u` \[m/s\] (`u = 0` is still air: the zero-speed
    /// limit of every model, its apparent mass M_a with no other force and frozen lag
    /// states — models written in U-normalised variables cannot be evaluated at U = 0; a
    /// force a model would carry at zero speed, such as a constant offset of
    /// [`crate::effects`], is dropped with the rest).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when `u` is negative or not finite;
    /// [`Error::Numerical`] when M_s − M_a is singular at `u`.
    pub fn new(section: &'a Section, u: f64) -> Result<Self> {
        Self::build(section, u, None)
    }

    /// [`SectionDynamics::new`] with a caller's `extra` terms in the equations.
    ///
    /// # Errors
    /// As [`SectionDynamics::new`]; [`Error::Numerical`] when M_s − M_a − ΔM is singular.
    pub fn with_extra(section: &'a Section, u: f64, extra: &'a dyn ExtraTerms) -> Result<Self> {
        Self::build(section, u, Some(extra))
    }

    fn build(section: &'a Section, u: f64, extra: Option<&'a dyn ExtraTerms>) -> Result<Self> {
        if !u.is_finite() || u < 0.0 {
            return Err(Error::param("u", u, "must be finite and ≥ 0"));
        }
        let mut total = section.total_mass(u);
        if let Some(x) = extra {
            total -= x.mass();
        }
        let minv = total.try_inverse().ok_or_else(|| {
            Error::numerical(
                "SectionDynamics",
                format!("total mass M_s − M_a (− ΔM) singular at U = {u}"),
            )
        })?;
        Ok(SectionDynamics {
            section,
            flow: section.flow(u),
            minv,
            friction: section.structure.friction_resolved(),
            nlag: section.aero.n_lag(),
            extra,
        })
    }

    /// The section.
    pub fn section(&self) -> &'a Section {
        self.section
    }

    /// Wind speed U \[m/s\].
    pub fn u(&self) -> f64 {
        self.flow.u
    }

    /// Flow (ρ, U).
    pub fn flow(&self) -> &Flow {
        &self.flow
    }

    /// Number of first-order states, 4 + lag states.
    pub fn dim(&self) -> usize {
        4 + self.nlag
    }

    /// Inverse of the total mass matrix (M_s − M_a)⁻¹ at this speed.
    pub(crate) fn mass_inverse(&self) -> &Matrix2<f64> {
        &self.minv
    }

    /// ∂R/∂(h, α, ḣ, α̇) of the structure's restoring force R = (F_h, M_α) at state `z`, by
    /// central differences (steps 1e-6·max(1, |z_c|), below 1e-3 of a friction velocity
    /// scale so the smoothed friction is resolved).
    pub(crate) fn structure_jacobian(&self, z: &[f64]) -> [[f64; 4]; 2] {
        let mut out = [[0.0; 4]; 2];
        for c in 0..4 {
            let h = self.step(z, c);
            let mut x = [z[0], z[1], z[2], z[3]];
            x[c] = z[c] + h;
            let rp =
                self.section
                    .structure
                    .restoring_with([x[0], x[1]], [x[2], x[3]], &self.friction);
            x[c] = z[c] - h;
            let rm =
                self.section
                    .structure
                    .restoring_with([x[0], x[1]], [x[2], x[3]], &self.friction);
            for r in 0..2 {
                out[r][c] = (rp[r] - rm[r]) / (2.0 * h);
            }
        }
        out
    }

    /// Central-difference step of state `c` at `z`.
    fn step(&self, z: &[f64], c: usize) -> f64 {
        let mut h = 1e-6 * z[c].abs().max(1.0);
        if c == 2 && self.friction[0] > 0.0 {
            h = h.min(1e-3 * self.friction[1]);
        }
        if c == 3 && self.friction[2] > 0.0 {
            h = h.min(1e-3 * self.friction[3]);
        }
        h
    }

    /// Jacobian ∂ż/∂z of [`SectionDynamics::rate`] at `z` by central differences, written
    /// row-major into `jac` (dim × dim values; `work` holds 3·dim scratch values).
    pub fn jacobian(&self, z: &[f64], jac: &mut [f64], work: &mut [f64]) {
        let n = self.dim();
        let (x, rest) = work.split_at_mut(n);
        let (fp, fm) = rest.split_at_mut(n);
        x.copy_from_slice(&z[..n]);
        for c in 0..n {
            let h = self.step(z, c);
            x[c] = z[c] + h;
            self.rate(x, fp);
            x[c] = z[c] - h;
            self.rate(x, fm);
            x[c] = z[c];
            for r in 0..n {
                jac[r * n + c] = (fp[r] - fm[r]) / (2.0 * h);
            }
        }
    }

    /// Aerodynamic forces (L, M) per unit span at state `z` [N/m, N·m/m].
    #[inline]
    pub fn aero_forces(&self, z: &[f64]) -> [f64; 2] {
        if self.flow.u == 0.0 {
            return [0.0; 2];
        }
        self.section
            .aero
            .forces(&self.flow, [z[0], z[1]], [z[2], z[3]], &z[4..4 + self.nlag])
    }

    /// Writes ż = f(z) into `dz`. Both slices hold [`SectionDynamics::dim`] values
    /// (a shorter slice is a bug and panics).
    #[inline]
    pub fn rate(&self, z: &[f64], dz: &mut [f64]) {
        let q = [z[0], z[1]];
        let qd = [z[2], z[3]];
        let lag = &z[4..4 + self.nlag];
        let still = self.flow.u == 0.0;
        let f = if still {
            [0.0; 2]
        } else {
            self.section.aero.forces(&self.flow, q, qd, lag)
        };
        let f = match self.extra {
            Some(x) => x.applied(q, qd, f),
            None => f,
        };
        let r = self.section.structure.restoring_with(q, qd, &self.friction);
        let g = [f[0] - r[0], f[1] - r[1]];
        dz[0] = qd[0];
        dz[1] = qd[1];
        dz[2] = self.minv[(0, 0)] * g[0] + self.minv[(0, 1)] * g[1];
        dz[3] = self.minv[(1, 0)] * g[0] + self.minv[(1, 1)] * g[1];
        if still {
            dz[4..4 + self.nlag].fill(0.0);
        } else {
            self.section
                .aero
                .lag_rates(&self.flow, q, qd, lag, &mut dz[4..4 + self.nlag]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::flat_plate_table;
    use crate::tunnel::{free_record, FreeOptions};

    /// A derivative table is written in U-normalised variables (q̇B/U): evaluated at U = 0
    /// its forces are 0·∞ = NaN. Still air is the zero-speed limit instead: the structure
    /// with the total mass M_s − M_a, no other force, frozen lag states.
    #[test]
    fn still_air_is_the_apparent_mass_limit_for_every_model() {
        let s = flat_plate_table(2);
        let d = SectionDynamics::new(&s, 0.0).unwrap();
        let n = d.dim();
        let z: Vec<f64> = (0..n).map(|i| 0.01 * (i as f64 + 1.0)).collect();
        let mut dz = vec![0.0; n];
        d.rate(&z, &mut dz);
        assert!(dz.iter().all(|v| v.is_finite()), "{dz:?}");
        assert!(dz[4..].iter().all(|&v| v == 0.0), "lag rates {dz:?}");
        let r = s.structure.restoring([z[0], z[1]], [z[2], z[3]]);
        let minv = s.total_mass(0.0).try_inverse().unwrap();
        for c in 0..2 {
            let want = -(minv[(c, 0)] * r[0] + minv[(c, 1)] * r[1]);
            assert!(
                (dz[2 + c] - want).abs() <= 1e-12 * want.abs(),
                "{c}: {} vs {want}",
                dz[2 + c]
            );
        }
        // and the virtual tunnel records a still-air decay of it
        let opts = FreeOptions {
            duration: 2.0,
            initial: [0.0, 0.05, 0.0, 0.0],
            ..FreeOptions::new(1)
        };
        let (rec, run) = free_record(&s, 0.0, "still", &opts, 1).unwrap();
        assert!(run.left_bound_at.is_none());
        assert!(rec.alpha.iter().all(|v| v.is_finite()));
        assert_eq!(
            rec.alpha.len(),
            (opts.rate * opts.duration).round() as usize
        );
    }
}
