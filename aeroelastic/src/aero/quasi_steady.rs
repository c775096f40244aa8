//! Steady and quasi-steady thin-aerofoil aerodynamics (Theodorsen's form with C ≡ 1).

use nalgebra::Matrix2;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::{thin_airfoil, thin_airfoil_apparent_mass, thin_airfoil_response, AeroModel, Flow};
use crate::error::{finite, positive};
use crate::Result;

/// Which quasi-steady variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum QuasiSteadyKind {
    /// Steady aerodynamics: L↑ = 2πρU²b α, M = (½+a) b L↑ — the angle of attack is the
    /// pitch angle only (Hodges & Pierce §5.3 "steady-flow theory"); no damping terms.
    Steady,
    /// Quasi-steady: C(k) ≡ 1 with the full 3/4-chord downwash
    /// w = ḣ + Uα + b(½ − a)α̇ (aerodynamic damping included).
    QuasiSteady,
}

/// Steady / quasi-steady thin aerofoil about an elastic axis at `a` semi-chords aft of
/// mid-chord, optionally with the noncirculatory (apparent-mass and πρb²Uα̇) terms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct QuasiSteady {
    /// Chord B \[m\].
    pub chord: f64,
    /// Elastic-axis position a in semi-chords aft of mid-chord.
    pub a: f64,
    /// Variant.
    pub kind: QuasiSteadyKind,
    /// Include the noncirculatory terms (apparent mass, πρb²Uα̇).
    pub noncirculatory: bool,
}

impl QuasiSteady {
    /// Builds the model.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for a non-positive `chord` or non-finite `a`.
    pub fn new(chord: f64, a: f64, kind: QuasiSteadyKind, noncirculatory: bool) -> Result<Self> {
        positive("chord", chord)?;
        finite("a", a)?;
        Ok(QuasiSteady {
            chord,
            a,
            kind,
            noncirculatory,
        })
    }
}

impl AeroModel for QuasiSteady {
    fn name(&self) -> String {
        match (self.kind, self.noncirculatory) {
            (QuasiSteadyKind::Steady, false) => "steady".into(),
            (QuasiSteadyKind::Steady, true) => "steady+noncirculatory".into(),
            (QuasiSteadyKind::QuasiSteady, false) => "quasi-steady".into(),
            (QuasiSteadyKind::QuasiSteady, true) => "quasi-steady+noncirculatory".into(),
        }
    }
    fn chord(&self) -> f64 {
        self.chord
    }
    fn n_lag(&self) -> usize {
        0
    }
    fn is_linear(&self) -> bool {
        true
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        if self.noncirculatory {
            thin_airfoil_apparent_mass(flow.rho, 0.5 * self.chord, self.a)
        } else {
            Matrix2::zeros()
        }
    }
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], _lag: &[f64]) -> [f64; 2] {
        let b = 0.5 * self.chord;
        let u = flow.u;
        let w = match self.kind {
            QuasiSteadyKind::Steady => u * q[1],
            QuasiSteadyKind::QuasiSteady => qd[0] + u * q[1] + b * (0.5 - self.a) * qd[1],
        };
        thin_airfoil(flow.rho, u, b, self.a, w, qd[1], self.noncirculatory)
    }
    fn lag_rates(&self, _flow: &Flow, _q: [f64; 2], _qd: [f64; 2], _lag: &[f64], _out: &mut [f64]) {
    }
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        thin_airfoil_response(
            flow.rho,
            flow.u,
            0.5 * self.chord,
            self.a,
            omega,
            Complex64::new(1.0, 0.0),
            self.kind == QuasiSteadyKind::Steady,
            self.noncirculatory,
        )
    }
}
