//! Time histories of the nonlinear section at one speed, for phase portraits: a fixed-step
//! classical Runge–Kutta integration ([`crate::integrate::rk4`]) from a given state,
//! sampled at every step.
//!
//! The LCO solver ([`crate::lco`]) classifies and measures cycles without storing the
//! response; this module re-integrates a short window (typically a few cycles from the
//! final state of an LCO run, which lies on the cycle) to draw it. A fixed step keeps the
//! output deterministic and uniformly sampled; with ≥ 200 steps per period the RK4 error
//! per cycle is far below a line width.

use serde::{Deserialize, Serialize};

use crate::dynamics::SectionDynamics;
use crate::integrate::{rk4, Bound, Control};
use crate::section::Section;
use crate::{Error, Result};

/// A sampled response: h \[m\] positive down, α \[rad\] positive nose-up, and their rates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Trajectory {
    /// Wind speed U \[m/s\].
    pub u: f64,
    /// Time \[s\] from the initial state.
    pub t: Vec<f64>,
    /// Heave h \[m\].
    pub h: Vec<f64>,
    /// Pitch α \[rad\].
    pub alpha: Vec<f64>,
    /// Heave rate ḣ \[m/s\].
    pub h_dot: Vec<f64>,
    /// Pitch rate α̇ \[rad/s\].
    pub alpha_dot: Vec<f64>,
}

impl Section {
    /// Integrates from `y0` at speed `u` for `duration` seconds with `steps` RK4 steps and
    /// returns every step (`steps + 1` samples including the initial state). Integration
    /// stops early (shorter output) if |α| exceeds 1.5 rad or a value becomes non-finite.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for `u ≤ 0`, a non-positive `duration`, `steps = 0`, or
    /// a `y0` of the wrong length or non-finite; [`Error::Numerical`] when M_s − M_a is
    /// singular at `u`.
    pub fn trajectory(
        &self,
        u: f64,
        y0: &[f64],
        duration: f64,
        steps: usize,
    ) -> Result<Trajectory> {
        crate::error::positive("u", u)?;
        crate::error::positive("duration", duration)?;
        if steps == 0 {
            return Err(Error::param("steps", 0.0, "must be > 0"));
        }
        let n = self.n_states();
        if y0.len() != n || y0.iter().any(|v| !v.is_finite()) {
            return Err(Error::param(
                "y0",
                y0.len() as f64,
                format!("must hold {n} finite values"),
            ));
        }
        let dynamics = SectionDynamics::new(self, u)?;
        let dt = duration / steps as f64;
        let mut z = y0.to_vec();
        let mut out = Trajectory {
            u,
            t: Vec::with_capacity(steps + 1),
            h: Vec::with_capacity(steps + 1),
            alpha: Vec::with_capacity(steps + 1),
            h_dot: Vec::with_capacity(steps + 1),
            alpha_dot: Vec::with_capacity(steps + 1),
        };
        let push = |out: &mut Trajectory, t: f64, z: &[f64]| {
            out.t.push(t);
            out.h.push(z[0]);
            out.alpha.push(z[1]);
            out.h_dot.push(z[2]);
            out.alpha_dot.push(z[3]);
        };
        push(&mut out, 0.0, &z);
        // The sample time is s·dt (not the driver's accumulated t) for exact grids.
        rk4(
            &dynamics,
            0.0,
            &mut z,
            dt,
            steps,
            Some(Bound::alpha(1.5)),
            &mut |s, _t, z| {
                push(&mut out, s as f64 * dt, z);
                Control::Continue
            },
        )?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::aero::{AeroModel, QuasiSteady, QuasiSteadyKind};
    use crate::reference::hp1_structure;

    /// Undamped structure in a near-zero flow with steady aerodynamics (no aerodynamic
    /// damping, negligible stiffness at U = 1e-6): free pitch oscillation at the coupled
    /// natural frequency conserves energy; RK4 with 400 steps per period keeps the pitch
    /// amplitude to 1e-6 relative over one period and returns to the initial state.
    #[test]
    fn free_oscillation_returns_to_its_start_after_one_period() {
        let mut st = hp1_structure();
        st.static_unbalance = 0.0; // uncoupled: pure pitch at ω_α = 1 rad/s
        let aero: Arc<dyn AeroModel> =
            Arc::new(QuasiSteady::new(2.0, -0.2, QuasiSteadyKind::Steady, false).unwrap());
        let sec = Section::new(st, aero, 1.0).unwrap();
        let y0 = sec.perturbation(0.1);
        let period = std::f64::consts::TAU; // ω_α = 1; aero stiffness ∝ U² ≈ 1e-12
        let tr = sec.trajectory(1e-6, &y0, period, 400).unwrap();
        assert_eq!(tr.t.len(), 401);
        let last = tr.alpha.len() - 1;
        assert!(
            (tr.alpha[last] - 0.1).abs() < 1e-6,
            "α(T) = {}",
            tr.alpha[last]
        );
        assert!(tr.alpha_dot[last].abs() < 1e-6);
        let min = tr.alpha.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((min + 0.1).abs() < 1e-6, "min α = {min}");
        assert!(sec.trajectory(1.0, &y0, 1.0, 0).is_err());
        assert!(sec.trajectory(1.0, &y0[..2], 1.0, 10).is_err());
    }
}
