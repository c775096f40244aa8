//! The aeroelastic section: a [`Structure`] in the flow with an [`AeroModel`].

use std::sync::Arc;

use nalgebra::{DMatrix, Matrix2};

use crate::aero::{linearize, AeroModel, Flow};
use crate::error::positive;
use crate::structure::Structure;
use crate::{Error, Result};

/// A 2-DOF section: structure + aerodynamic model + air density.
///
/// First-order state z = (h, α, ḣ, α̇, x₁ … x_n) with x the model's lag states.
#[derive(Debug, Clone)]
pub struct Section {
    /// Structural model.
    pub structure: Structure,
    /// Aerodynamic model.
    pub aero: Arc<dyn AeroModel>,
    /// Air density ρ \[kg/m³\].
    pub rho: f64,
}

impl Section {
    /// Builds a section after validating the structure and ρ.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad field (`rho`, `structure.*`).
    pub fn new(structure: Structure, aero: Arc<dyn AeroModel>, rho: f64) -> Result<Self> {
        positive("rho", rho)?;
        structure.validate().map_err(|e| match e {
            Error::InvalidParameter {
                field,
                value,
                message,
            } => Error::InvalidParameter {
                field: format!("structure.{field}"),
                value,
                message,
            },
            other => other,
        })?;
        Ok(Section {
            structure,
            aero,
            rho,
        })
    }

    /// Flow at wind speed `u`.
    pub fn flow(&self, u: f64) -> Flow {
        Flow { rho: self.rho, u }
    }

    /// Number of first-order states, 4 + lag states.
    pub fn n_states(&self) -> usize {
        4 + self.aero.n_lag()
    }

    /// Semi-chord b = B/2 \[m\].
    pub fn semi_chord(&self) -> f64 {
        0.5 * self.aero.chord()
    }

    /// Total mass matrix M_s − M_a at speed `u` (structure plus apparent mass).
    pub fn total_mass(&self, u: f64) -> Matrix2<f64> {
        self.structure.mass_matrix() - self.aero.apparent_mass(&self.flow(u))
    }

    /// State matrix A of the linearised first-order system ż = A z at speed `u`
    /// (linear springs and dampers of the structure, see
    /// [`Structure::stiffness_matrix`]; aerodynamics linearised about the origin):
    /// q̈ = (M_s − M_a)⁻¹ [(K_q − K_s) q + (C_q − C_s) q̇ + D x], ẋ = E q + F q̇ + G x.
    ///
    /// # Errors
    /// [`Error::Numerical`] when M_s − M_a is singular.
    pub fn state_matrix(&self, u: f64) -> Result<DMatrix<f64>> {
        let flow = self.flow(u);
        let lin = linearize(self.aero.as_ref(), &flow);
        let minv = (self.structure.mass_matrix() - lin.m_a)
            .try_inverse()
            .ok_or_else(|| {
                Error::numerical("state_matrix", format!("M_s − M_a singular at U = {u}"))
            })?;
        let n = self.aero.n_lag();
        let nz = 4 + n;
        let mut a = DMatrix::<f64>::zeros(nz, nz);
        a[(0, 2)] = 1.0;
        a[(1, 3)] = 1.0;
        let kk = minv * (lin.k_q - self.structure.stiffness_matrix());
        let cc = minv * (lin.c_q - self.structure.damping_matrix());
        let dd = DMatrix::from_iterator(2, 2, minv.iter().copied()) * &lin.d;
        for i in 0..2 {
            for j in 0..2 {
                a[(2 + i, j)] = kk[(i, j)];
                a[(2 + i, 2 + j)] = cc[(i, j)];
            }
            for j in 0..n {
                a[(2 + i, 4 + j)] = dd[(i, j)];
            }
        }
        for i in 0..n {
            for j in 0..2 {
                a[(4 + i, j)] = lin.e[(i, j)];
                a[(4 + i, 2 + j)] = lin.f[(i, j)];
            }
            for j in 0..n {
                a[(4 + i, 4 + j)] = lin.g[(i, j)];
            }
        }
        Ok(a)
    }
}
