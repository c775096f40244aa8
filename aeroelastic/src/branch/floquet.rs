//! Floquet multipliers of a periodic orbit: the eigenvalues of its monodromy matrix with
//! the trivial multiplier removed ([`floquet`]), and the allocation-free eigenvalues of the
//! common 6 × 6 case ([`eigenvalues6`]).

use nalgebra::DMatrix;
use num_complex::Complex64;

use crate::flutter::eigenvalues;
use crate::{Error, Result};

/// Non-trivial Floquet multipliers of a monodromy matrix (the trivial multiplier 1 removed
/// as the eigenvalue closest to 1) and their largest modulus.
pub(super) fn floquet(mono: DMatrix<f64>) -> Result<(Vec<Complex64>, f64)> {
    let mut mu = match mono.nrows() {
        6 => eigenvalues6(&mono)?,
        _ => eigenvalues(&mono)?,
    };
    if let Some((k, _)) = mu
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1 - 1.0).norm().total_cmp(&(b.1 - 1.0).norm()))
    {
        mu.remove(k);
    }
    let max_floquet = mu.iter().map(|m| m.norm()).fold(0.0, f64::max);
    Ok((mu, max_floquet))
}

/// Eigenvalues of a 6 × 6 matrix (two DOFs and two lag states, the common case) by the
/// fixed-size Schur decomposition: no allocation, the same algorithm as [`eigenvalues`].
pub(super) fn eigenvalues6(a: &DMatrix<f64>) -> Result<Vec<Complex64>> {
    if a.iter().any(|v| !v.is_finite()) {
        return Err(Error::numerical(
            "eigenvalues",
            "non-finite monodromy matrix",
        ));
    }
    let m = nalgebra::Matrix6::<f64>::from_fn(|r, c| a[(r, c)]);
    let s = nalgebra::Schur::try_new(m, f64::EPSILON, 100_000)
        .ok_or_else(|| Error::numerical("eigenvalues", "Schur decomposition did not converge"))?;
    Ok(s.complex_eigenvalues().iter().copied().collect())
}
