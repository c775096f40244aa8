//! pysindy-compatible mode: per-case STLSQ with pysindy 2.1 semantics on the raw columns,
//! through [`super::pysindy::PysindyStlsq`].
//!
//! pysindy has no group fit and thresholds raw coefficients with a ridge on raw columns,
//! so this mode cannot be expressed as a reduction step of the shared routine
//! ([`super::fit_group`]) on normalised columns; it runs the peer implementation as is, on
//! the identifiable basis columns only (a fit on a rank-deficient library is never
//! reported). The δ path then sweeps pysindy's `threshold`.

use crate::numerics::mat::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use super::pysindy::PysindyStlsq;
use crate::{Error, Result};

/// Options of the pysindy-compatible mode (pysindy `STLSQ(alpha, max_iter, unbias)`; the
/// threshold comes from the δ grid).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PysindyOptions {
    /// Ridge parameter on raw columns (pysindy default 0.05).
    pub alpha: f64,
    /// Maximum iterations (pysindy default 20).
    pub max_iter: usize,
    /// Least-squares refit on the final support (pysindy default true).
    pub unbias: bool,
}

impl Default for PysindyOptions {
    fn default() -> Self {
        PysindyOptions {
            alpha: 0.05,
            max_iter: 20,
            unbias: true,
        }
    }
}

impl PysindyOptions {
    /// Checks the options.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `pysindy.alpha` or `pysindy.max_iter`.
    pub fn validate(&self) -> Result<()> {
        if !(self.alpha >= 0.0 && self.alpha.is_finite()) {
            return Err(Error::InvalidOption {
                name: "pysindy.alpha".to_string(),
                message: format!("{} must be finite and ≥ 0", self.alpha),
            });
        }
        if self.max_iter == 0 {
            return Err(Error::InvalidOption {
                name: "pysindy.max_iter".to_string(),
                message: "must be ≥ 1".to_string(),
            });
        }
        Ok(())
    }
}

/// pysindy fit of `y` on the library columns `basis` of `theta` (n × p raw library) at
/// `threshold`: the raw coefficients over the whole library (0 outside the basis).
pub fn fit_case(
    theta: MatRef<'_, f64>,
    basis: &[usize],
    y: &[f64],
    threshold: f64,
    opts: &PysindyOptions,
) -> Vec<f64> {
    let sub = Mat::from_fn(theta.nrows(), basis.len(), |i, c| theta[(i, basis[c])]);
    fit_sub(sub.as_ref(), theta.ncols(), basis, y, threshold, opts)
}

fn fit_sub(
    sub: MatRef<'_, f64>,
    p: usize,
    basis: &[usize],
    y: &[f64],
    threshold: f64,
    opts: &PysindyOptions,
) -> Vec<f64> {
    let est = PysindyStlsq {
        threshold,
        alpha: opts.alpha,
        max_iter: opts.max_iter,
        unbias: opts.unbias,
    };
    let xi = est.fit(sub, y);
    let mut full = vec![0.0; p];
    for (&j, v) in basis.iter().zip(xi) {
        full[j] = v;
    }
    full
}

/// pysindy fits of one case at every threshold of `deltas` (the basis sub-matrix is built
/// once): element `[d]` holds the raw coefficients over the library for `deltas[d]`.
pub fn path_case(
    theta: MatRef<'_, f64>,
    basis: &[usize],
    y: &[f64],
    deltas: &[f64],
    opts: &PysindyOptions,
) -> Vec<Vec<f64>> {
    let sub = Mat::from_fn(theta.nrows(), basis.len(), |i, c| theta[(i, basis[c])]);
    deltas
        .iter()
        .map(|&d| fit_sub(sub.as_ref(), theta.ncols(), basis, y, d, opts))
        .collect()
}
