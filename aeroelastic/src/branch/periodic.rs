//! The periodic-orbit problem every discretisation implements ([`PeriodicProblem`]), the
//! equation that closes it ([`Closure`]) and the stored unknowns of a point: below
//! `shooting`, `harmonic` and `condensed`, which implement it, and `continuation`, whose
//! factory names each of them (issue 40, docs/DECISIONS.md "No import circles, checked").

use nalgebra::{DMatrix, DVector};

use super::types::{BranchPoint, HopfPoint};
use crate::{Error, Result};

/// Which extra equation closes the periodic-orbit system.
pub(super) enum Closure<'a> {
    /// The pitch-amplitude unknown ([`PeriodicProblem::amplitude_index`]) equals the
    /// value (start from the Hopf point).
    Alpha(f64),
    /// Pseudo-arclength ⟨Y − Y_k, t_k⟩ = Δs.
    Arclength(&'a DVector<f64>, &'a DVector<f64>, f64),
    /// U fixed (scaled).
    Speed(f64),
}

/// A discretisation of the periodic orbits of a section: scaled unknowns Y whose last
/// component is U, and m − 1 equations G(Y) = 0 (periodicity and phase). The continuation
/// adds the m-th equation ([`Closure`]).
pub(super) trait PeriodicProblem {
    /// Number of unknowns m (U last).
    fn unknowns(&self) -> usize;
    /// Index of the unknown fixed by [`Closure::Alpha`] (a pitch amplitude).
    fn amplitude_index(&self) -> usize;
    /// Scale of each unknown.
    fn scales(&self) -> &[f64];
    /// G(Y), m − 1 values.
    fn g(&self, y: &DVector<f64>) -> Result<DVector<f64>>;
    /// ∂G/∂Y at `y` given G(y), (m − 1) × m.
    fn jac(&self, y: &DVector<f64>, g0: &DVector<f64>) -> Result<DMatrix<f64>>;
    /// The converged orbit at `y` with its multipliers.
    fn point(&self, y: &DVector<f64>, jg: &DMatrix<f64>) -> Result<BranchPoint>;
    /// Whether [`PeriodicProblem::point`] needs ∂G/∂Y at the solution itself (shooting: its
    /// block is the monodromy matrix). When not, Newton hands on the Jacobian of its last
    /// refresh, within the Newton tolerance of the solution, for the tangent.
    fn jacobian_at_solution(&self) -> bool {
        true
    }
    /// Initial guess at pitch amplitude `a` \[rad\] from the Hopf eigenvector.
    fn start(&self, hopf: &HopfPoint, a: f64) -> DVector<f64>;
    /// Scaled unknowns of a point of a branch of this problem.
    fn scaled(&self, p: &BranchPoint) -> Result<DVector<f64>>;
    /// The quantities a measured point is compared with (U, first-harmonic amplitudes,
    /// frequency) at `y` without the multipliers, when the discretisation holds them
    /// directly; `None`: take them from [`PeriodicProblem::point`].
    fn first_harmonics(&self, _y: &DVector<f64>) -> Option<super::types::OrbitValues> {
        None
    }
}

/// The scaled unknowns a harmonic-balance point stored, when they belong to a problem of `m`
/// unknowns.
///
/// # Errors
/// [`Error::Numerical`] when they do not (a branch read back from `branch.json`, whose
/// points keep no coefficients, or one of another method).
pub(super) fn stored_unknowns(p: &BranchPoint, m: usize) -> Result<DVector<f64>> {
    if p.unknowns.len() != m {
        return Err(Error::numerical(
            "orbit_on_branch",
            "the branch points carry no harmonic-balance coefficients of this problem (a \
             branch read back from branch.json, or of another method): continue the branch \
             again",
        ));
    }
    Ok(DVector::from_column_slice(&p.unknowns))
}
