//! pysindy 2.1-compatible STLSQ: the peer tool's sparse regression, reproduced exactly so
//! that aeroform can be compared with it on the same library matrix.
//!
//! What pysindy 2.1.0 does (`pysindy/optimizers/stlsq.py`, `base.py`, with scikit-learn's
//! `ridge_regression` and `LinearRegression` as they are called there), and what
//! [`PysindyStlsq::fit`] reproduces, for one target `y` and a library `Θ` (n × p):
//!
//! 1. **Initial guess** (`BaseOptimizer.fit`): `np.linalg.lstsq(Θ, y)`. It is only used as the
//!    previous nonzero pattern by the convergence test of the first iteration; a least-squares
//!    solution has no exact zeros in practice, so it is taken as "all nonzero" here.
//! 2. **Iteration k = 0, 1, …, max_iter−1** on the current support S (initially all columns):
//!    if S is empty, the result is all zeros (pysindy warns "Sparsity parameter is too big …
//!    and eliminated all coefficients") and the loop stops. Otherwise a ridge fit on the
//!    columns of S,
//!    `w_S = argmin ‖y − Θ_S w‖² + α‖w‖²  =  (Θ_Sᵀ Θ_S + α I)⁻¹ Θ_Sᵀ y`
//!    (α exactly as given: no factor ½, no scaling by n), solved as scikit-learn's `"auto"`
//!    solver does for dense input without sample weights: `"cholesky"`, i.e. the p×p normal
//!    matrix with α added to its diagonal, factored by Cholesky; when that factorisation fails
//!    (not positive definite), scikit-learn falls back to the `"svd"` solver,
//!    `w = V diag(s/(s²+α)) Uᵀ y` keeping singular values `s > 1e-15`. When there are more
//!    columns than samples it solves the dual `(Θ Θᵀ + α I) d = y`, `w = Θᵀ d` instead.
//!    Then thresholding over **all** p entries (zeros outside S included):
//!    S ← {j : |w_j| ≥ threshold}, and w_j ← 0 outside S.
//! 3. **Stop** after the iteration when nothing was removed in the first iteration
//!    (`sum(ind) == n_features`), or when the nonzero pattern of w equals that of the previous
//!    iteration; otherwise after `max_iter` iterations (pysindy warns "STLSQ did not
//!    converge"). The coefficients are the thresholded ridge coefficients of the last
//!    iteration.
//! 4. **Unbias** (when `unbias`): support T = {j : |w_j| > 1e-14}; if T is not empty,
//!    `w_T = LinearRegression(fit_intercept=False).fit(Θ_T, y)`, which is
//!    `scipy.linalg.lstsq(Θ_T, y, cond=1e-6)` (LAPACK `gelsd`): the minimum-norm least-squares
//!    solution in which singular values `≤ 1e-6·s_max` are treated as zero. Entries outside T
//!    are 0. With an empty support the result stays all zeros.
//! 5. **normalize_columns** (only through [`PysindyStlsq::fit_normalized_columns`]): every
//!    column is divided by its 2-norm before steps 1–4 (threshold and α therefore apply to
//!    the normalised coefficients), and the final coefficients are divided by the norms.
//!
//! Consequences worth knowing (replicated, not fixed): the ridge term is not scaled with the
//! column norms, so a physically important but small-scale column (e.g. α³ or (Bα̇/U)³ with
//! α ≈ 0.3 rad, whose squared norm is far below α = 0.05) is shrunk below the threshold and
//! erased; and the threshold applies to raw coefficients, so it depends on the units of each
//! column.
//!
//! pysindy's `fit` also drops samples whose library row is entirely NaN or whose target is
//! NaN, and rejects any other non-finite value; [`PysindyStlsq::try_fit`] does the same.

use crate::numerics::mat::{a_at, at_a, at_y, Mat, MatRef};
use crate::numerics::{cholesky_solve, PivotFloor};

use crate::{Error, Result};

/// `LinearRegression` tolerance of scikit-learn (`tol=1e-6`), passed as `cond` to
/// `scipy.linalg.lstsq` in pysindy's unbias step: singular values `≤ UNBIAS_RCOND·s_max`
/// are treated as zero.
pub const UNBIAS_RCOND: f64 = 1e-6;

/// pysindy's cut-off below which a coefficient counts as outside the support before the
/// unbias refit (`self.ind_ = np.abs(self.coef_) > 1e-14`).
pub const SUPPORT_EPS: f64 = 1e-14;

/// Absolute singular-value cut-off of scikit-learn's `"svd"` ridge solver
/// (`idx = s > 1e-15`), used when the Cholesky factorisation fails.
pub const RIDGE_SVD_CUTOFF: f64 = 1e-15;

/// pysindy 2.1 STLSQ options (`pysindy.optimizers.STLSQ`), for one target.
///
/// Objective per iteration: `‖y − Θw‖² + alpha·‖w‖²` on the current support, then
/// coefficients with `|w_j| < threshold` are set to zero (see the module documentation for
/// the exact loop). Coefficients are in the units of `y` per unit of each library column
/// (they are whatever the columns make them; nothing is rescaled unless
/// [`PysindyStlsq::fit_normalized_columns`] is used).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PysindyStlsq {
    /// Minimum magnitude of a kept coefficient (`threshold`, pysindy default 0.1); must be
    /// ≥ 0.
    pub threshold: f64,
    /// Ridge penalty α in `‖y − Θw‖² + α‖w‖²` (`alpha`, pysindy default 0.05); must be ≥ 0.
    pub alpha: f64,
    /// Maximum number of thresholded ridge fits (`max_iter`, pysindy default 20); must be
    /// > 0.
    pub max_iter: usize,
    /// Refit the final support by unregularised least squares (`unbias`, pysindy default
    /// true).
    pub unbias: bool,
}

impl Default for PysindyStlsq {
    /// pysindy 2.1 defaults: threshold 0.1, alpha 0.05, max_iter 20, unbias true.
    fn default() -> Self {
        Self {
            threshold: 0.1,
            alpha: 0.05,
            max_iter: 20,
            unbias: true,
        }
    }
}

/// Which linear solver produced a ridge fit (scikit-learn's choice inside `ridge_regression`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RidgeSolver {
    /// Normal equations `(ΘᵀΘ + αI) w = Θᵀy` by Cholesky (scikit-learn `"cholesky"`).
    Cholesky,
    /// Dual `(ΘΘᵀ + αI) d = y`, `w = Θᵀd` (scikit-learn `"cholesky"` with more columns than
    /// samples).
    CholeskyDual,
    /// SVD fallback after a failed Cholesky (scikit-learn `"svd"`).
    Svd,
}

/// Result of a pysindy-compatible STLSQ fit with its bookkeeping.
#[derive(Debug, Clone, PartialEq)]
pub struct PysindyFit {
    /// Coefficients, one per library column, in the column order of Θ.
    pub coefficients: Vec<f64>,
    /// Number of thresholded ridge fits performed (= `len(STLSQ.history_) − 1` in pysindy).
    pub iterations: usize,
    /// `false` when the loop ran out of `max_iter` (pysindy's "STLSQ did not converge"
    /// warning).
    pub converged: bool,
    /// `true` when thresholding removed every column (pysindy's "Sparsity parameter is too
    /// big" warning); the coefficients are then all zero.
    pub emptied: bool,
    /// Solver used by each ridge fit, in order.
    pub solvers: Vec<RidgeSolver>,
}

impl PysindyStlsq {
    /// Checks the options as pysindy's constructor does.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `threshold` or `alpha` when negative or not finite
    /// (pysindy: "threshold cannot be negative", "alpha cannot be negative"), or `max_iter`
    /// when 0 ("max_iter must be positive").
    pub fn check(&self) -> Result<()> {
        if !(self.threshold.is_finite() && self.threshold >= 0.0) {
            return Err(Error::InvalidOption {
                name: "threshold".into(),
                message: format!("must be finite and >= 0, got {}", self.threshold),
            });
        }
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return Err(Error::InvalidOption {
                name: "alpha".into(),
                message: format!("must be finite and >= 0, got {}", self.alpha),
            });
        }
        if self.max_iter == 0 {
            return Err(Error::InvalidOption {
                name: "max_iter".into(),
                message: "must be positive, got 0".into(),
            });
        }
        Ok(())
    }

    /// Coefficients (length = theta.ncols()), pysindy 2.1 semantics
    /// (`STLSQ(threshold, alpha, max_iter, unbias=unbias).fit(theta, y).coef_[0]` with
    /// `normalize_columns=False`).
    ///
    /// The options and data are not validated (use [`PysindyStlsq::try_fit`] for that):
    /// non-finite input gives non-finite coefficients, `max_iter = 0` gives zeros.
    ///
    /// # Panics
    /// When `y.len() != theta.nrows()` (a programming error).
    #[track_caller]
    pub fn fit(&self, theta: MatRef<'_, f64>, y: &[f64]) -> Vec<f64> {
        self.fit_report(theta, y, false).coefficients
    }

    /// Like [`PysindyStlsq::fit`] with pysindy's `normalize_columns=True`: the columns are
    /// divided by their 2-norms before the regression (threshold and α act on the
    /// normalised coefficients) and the coefficients are returned in the original units.
    /// A zero column gives non-finite coefficients, as in pysindy.
    ///
    /// # Panics
    /// When `y.len() != theta.nrows()` (a programming error).
    #[track_caller]
    pub fn fit_normalized_columns(&self, theta: MatRef<'_, f64>, y: &[f64]) -> Vec<f64> {
        self.fit_report(theta, y, true).coefficients
    }

    /// Validates the options and the data as pysindy does, then fits.
    ///
    /// Rows whose library entries are all NaN, or whose target is NaN, are dropped
    /// (pysindy's `drop_nan_samples`); any other non-finite value is an error (pysindy's
    /// `check_X_y`).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] from [`PysindyStlsq::check`]; [`Error::InvalidData`] naming
    /// the row and column of the first non-finite value, or when no row is left.
    ///
    /// # Panics
    /// When `y.len() != theta.nrows()` (a programming error).
    #[track_caller]
    pub fn try_fit(
        &self,
        theta: MatRef<'_, f64>,
        y: &[f64],
        normalize_columns: bool,
    ) -> Result<PysindyFit> {
        self.check()?;
        assert_eq!(y.len(), theta.nrows(), "theta rows and y length differ");
        let keep: Vec<usize> = (0..theta.nrows())
            .filter(|&i| !y[i].is_nan() && (0..theta.ncols()).any(|j| !theta[(i, j)].is_nan()))
            .collect();
        if keep.is_empty() {
            return Err(Error::InvalidData {
                case: "pysindy STLSQ input".into(),
                field: "theta".into(),
                message: format!("no sample left out of {} after dropping NaN rows", y.len()),
            });
        }
        for &i in &keep {
            if !y[i].is_finite() {
                return Err(Error::InvalidData {
                    case: "pysindy STLSQ input".into(),
                    field: format!("y[{i}]"),
                    message: format!("non-finite target {}", y[i]),
                });
            }
            for j in 0..theta.ncols() {
                let v = theta[(i, j)];
                if !v.is_finite() {
                    return Err(Error::InvalidData {
                        case: "pysindy STLSQ input".into(),
                        field: format!("theta[{i}, {j}]"),
                        message: format!("non-finite library value {v}"),
                    });
                }
            }
        }
        if keep.len() == theta.nrows() {
            return Ok(self.fit_report(theta, y, normalize_columns));
        }
        let sub = Mat::from_fn(keep.len(), theta.ncols(), |i, j| theta[(keep[i], j)]);
        let ys: Vec<f64> = keep.iter().map(|&i| y[i]).collect();
        Ok(self.fit_report(sub.as_ref(), &ys, normalize_columns))
    }

    /// The fit with its bookkeeping (iterations, convergence, emptied support, solvers).
    /// `normalize_columns` is pysindy's option of the same name. Options and data are not
    /// validated (see [`PysindyStlsq::try_fit`]).
    ///
    /// # Panics
    /// When `y.len() != theta.nrows()` (a programming error).
    #[track_caller]
    pub fn fit_report(
        &self,
        theta: MatRef<'_, f64>,
        y: &[f64],
        normalize_columns: bool,
    ) -> PysindyFit {
        assert_eq!(y.len(), theta.nrows(), "theta rows and y length differ");
        let p = theta.ncols();
        if normalize_columns {
            let norms: Vec<f64> = (0..p)
                .map(|j| {
                    (0..theta.nrows())
                        .map(|i| theta[(i, j)] * theta[(i, j)])
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            let x = Mat::from_fn(theta.nrows(), p, |i, j| theta[(i, j)] / norms[j]);
            let mut fit = self.fit_raw(x.as_ref(), y);
            for (c, n) in fit.coefficients.iter_mut().zip(&norms) {
                *c /= n;
            }
            fit
        } else {
            self.fit_raw(theta, y)
        }
    }

    /// Steps 1–4 of the module documentation on the given columns.
    fn fit_raw(&self, x: MatRef<'_, f64>, y: &[f64]) -> PysindyFit {
        let p = x.ncols();
        let mut ind = vec![true; p];
        // Nonzero pattern of the previous coefficients; the initial least-squares guess is
        // taken as all nonzero (module documentation, step 1).
        let mut prev_nonzero = vec![true; p];
        let mut coef = vec![0.0; p];
        let mut iterations = 0;
        let mut converged = false;
        let mut emptied = false;
        let mut solvers = Vec::new();
        let ridge = RidgeProblem::new(x, y);
        for _ in 0..self.max_iter {
            if !ind.iter().any(|&b| b) {
                coef = vec![0.0; p];
                emptied = true;
                converged = true;
                break;
            }
            let cols: Vec<usize> = (0..p).filter(|&j| ind[j]).collect();
            let (sub, solver) = ridge.solve(&cols, self.alpha);
            solvers.push(solver);
            iterations += 1;
            let mut c = vec![0.0; p];
            for (&j, &v) in cols.iter().zip(&sub) {
                c[j] = v;
            }
            for j in 0..p {
                // `np.abs(c) >= threshold` over every entry, NaN fails it.
                ind[j] = c[j].abs() >= self.threshold;
                if !ind[j] {
                    c[j] = 0.0;
                }
            }
            let nonzero: Vec<bool> = c.iter().map(|&v| v != 0.0).collect();
            let nothing_removed = ind.iter().filter(|&&b| b).count() == p;
            coef = c;
            if nothing_removed || nonzero == prev_nonzero {
                converged = true;
                break;
            }
            prev_nonzero = nonzero;
        }
        if !ind.iter().any(|&b| b) {
            emptied = true;
        }
        if self.unbias {
            let support: Vec<usize> = (0..p).filter(|&j| coef[j].abs() > SUPPORT_EPS).collect();
            if !support.is_empty() {
                let xs = select_columns(x, &support);
                let w = lstsq_min_norm(xs.as_ref(), y, UNBIAS_RCOND);
                coef = vec![0.0; p];
                for (&j, &v) in support.iter().zip(&w) {
                    coef[j] = v;
                }
            }
        }
        PysindyFit {
            coefficients: coef,
            iterations,
            converged,
            emptied,
            solvers,
        }
    }
}

/// Ridge regressions of one target on column subsets of one matrix. The Gram matrix ΘᵀΘ and
/// Θᵀy are formed once; each subset reads its block (the same dot products scikit-learn
/// forms for the subset, up to summation order).
struct RidgeProblem<'a> {
    x: MatRef<'a, f64>,
    y: &'a [f64],
    gram: Mat<f64>,
    xty: Vec<f64>,
}

impl<'a> RidgeProblem<'a> {
    fn new(x: MatRef<'a, f64>, y: &'a [f64]) -> Self {
        let (n, p) = (x.nrows(), x.ncols());
        let (gram, xty) = if p <= n {
            (at_a(x), at_y(x, y))
        } else {
            (Mat::zeros(0, 0), Vec::new())
        };
        Self { x, y, gram, xty }
    }

    /// scikit-learn `ridge_regression(Θ[:, cols], y, alpha)` with the `"auto"` solver.
    fn solve(&self, cols: &[usize], alpha: f64) -> (Vec<f64>, RidgeSolver) {
        let k = cols.len();
        let n = self.x.nrows();
        if k > n {
            let xs = select_columns(self.x, cols);
            return ridge_dual(xs.as_ref(), self.y, alpha);
        }
        // row-major k × k (symmetric: the same either way)
        let mut a: Vec<f64> = (0..k * k)
            .map(|e| self.gram[(cols[e / k], cols[e % k])])
            .collect();
        for i in 0..k {
            a[i * k + i] += alpha;
        }
        let mut rhs: Vec<f64> = cols.iter().map(|&c| self.xty[c]).collect();
        if cholesky_solve(&mut a, k, &mut rhs, 1, PivotFloor::Absolute(0.0)).is_ok() {
            return (rhs, RidgeSolver::Cholesky);
        }
        let xs = select_columns(self.x, cols);
        (ridge_svd(xs.as_ref(), self.y, alpha), RidgeSolver::Svd)
    }
}

/// Copy of the given columns of `x`, in the given order.
fn select_columns(x: MatRef<'_, f64>, cols: &[usize]) -> Mat<f64> {
    Mat::from_fn(x.nrows(), cols.len(), |i, j| x[(i, cols[j])])
}

/// Thin SVD `x = U diag(s) Vᵀ` as (U, s, V); `None` when the SVD does not converge
/// (non-finite input).
fn thin_svd(x: MatRef<'_, f64>) -> Option<(Mat<f64>, Vec<f64>, Mat<f64>)> {
    crate::numerics::mat::thin_svd(x)
}

/// `V f(s) Uᵀ y` for a thin SVD, with `f` applied to each singular value.
fn svd_apply(u: &Mat<f64>, s: &[f64], v: &Mat<f64>, y: &[f64], f: impl Fn(f64) -> f64) -> Vec<f64> {
    let (n, r) = (u.nrows(), s.len());
    let uty: Vec<f64> = (0..r)
        .map(|k| (0..n).map(|i| u[(i, k)] * y[i]).sum::<f64>() * f(s[k]))
        .collect();
    (0..v.nrows())
        .map(|j| (0..r).map(|k| v[(j, k)] * uty[k]).sum())
        .collect()
}

/// scikit-learn `_solve_svd`: `w = V diag(d) Uᵀ y`, `d = s/(s²+α)` for `s > 1e-15`, else 0.
fn ridge_svd(x: MatRef<'_, f64>, y: &[f64], alpha: f64) -> Vec<f64> {
    match thin_svd(x) {
        Some((u, s, v)) => svd_apply(&u, &s, &v, y, |s| {
            if s > RIDGE_SVD_CUTOFF {
                s / (s * s + alpha)
            } else {
                0.0
            }
        }),
        None => vec![f64::NAN; x.ncols()],
    }
}

/// scikit-learn `_solve_cholesky_kernel` (more columns than samples): `(XXᵀ + αI) d = y`,
/// `w = Xᵀd`; a failed Cholesky falls back to `scipy.linalg.lstsq(K, y)` (relative cut-off
/// machine epsilon).
fn ridge_dual(x: MatRef<'_, f64>, y: &[f64], alpha: f64) -> (Vec<f64>, RidgeSolver) {
    let n = x.nrows();
    let mut k = a_at(x);
    for i in 0..n {
        k[(i, i)] += alpha;
    }
    // row-major (symmetric: the same either way)
    let mut a: Vec<f64> = (0..n * n).map(|e| k[(e / n, e % n)]).collect();
    let mut rhs = y.to_vec();
    let dual = match cholesky_solve(&mut a, n, &mut rhs, 1, PivotFloor::Absolute(0.0)) {
        Ok(()) => rhs,
        Err(_) => lstsq_min_norm(k.as_ref(), y, f64::EPSILON),
    };
    let w = (0..x.ncols())
        .map(|j| (0..n).map(|i| x[(i, j)] * dual[i]).sum())
        .collect();
    (w, RidgeSolver::CholeskyDual)
}

/// `scipy.linalg.lstsq(x, y, cond=rcond)` (LAPACK `gelsd`): minimum-norm least squares with
/// singular values `≤ rcond·s_max` treated as zero. Non-finite input gives NaN.
fn lstsq_min_norm(x: MatRef<'_, f64>, y: &[f64], rcond: f64) -> Vec<f64> {
    match thin_svd(x) {
        Some((u, s, v)) => {
            let cut = rcond * s.iter().copied().fold(0.0, f64::max);
            svd_apply(&u, &s, &v, y, |s| if s > cut { 1.0 / s } else { 0.0 })
        }
        None => vec![f64::NAN; x.ncols()],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// n × p matrix of seeded standard normal draws.
    fn randn(n: usize, p: usize, seed: u64) -> Mat<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let d = Normal::new(0.0, 1.0).unwrap();
        Mat::from_fn(n, p, |_, _| d.sample(&mut rng))
    }

    fn matvec(x: &Mat<f64>, w: &[f64]) -> Vec<f64> {
        (0..x.nrows())
            .map(|i| (0..x.ncols()).map(|j| x[(i, j)] * w[j]).sum())
            .collect()
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
    }

    #[test]
    fn defaults_are_pysindy_defaults() {
        let d = PysindyStlsq::default();
        assert_eq!(
            (d.threshold, d.alpha, d.max_iter, d.unbias),
            (0.1, 0.05, 20, true)
        );
        assert!(d.check().is_ok());
    }

    #[test]
    fn ridge_penalty_is_alpha_times_squared_norm() {
        // One column, no thresholding, no unbias: w = xᵀy / (xᵀx + α) exactly (a factor ½
        // or n on α would change it).
        let x = Mat::from_fn(4, 1, |i, _| [1.0, 2.0, -1.0, 0.5][i]);
        let y = [2.0, 3.0, -1.0, 1.0];
        let xtx = 1.0 + 4.0 + 1.0 + 0.25;
        let xty = 2.0 + 6.0 + 1.0 + 0.5;
        let o = PysindyStlsq {
            threshold: 0.0,
            alpha: 0.7,
            max_iter: 20,
            unbias: false,
        };
        let w = o.fit(x.as_ref(), &y);
        assert!(close(w[0], xty / (xtx + 0.7), 1e-14), "{w:?}");
    }

    #[test]
    fn exact_sparse_law_is_recovered_with_unbias() {
        let x = randn(200, 6, 1);
        let truth = [2.0, 0.0, -0.5, 0.0, 0.0, 1.5];
        let y = matvec(&x, &truth);
        let fit = PysindyStlsq::default().fit_report(x.as_ref(), &y, false);
        for (w, t) in fit.coefficients.iter().zip(&truth) {
            if *t == 0.0 {
                assert_eq!(*w, 0.0);
            } else {
                assert!(close(*w, *t, 1e-12), "{w} vs {t}");
            }
        }
        assert!(fit.converged && !fit.emptied);
        assert!(fit.solvers.iter().all(|s| *s == RidgeSolver::Cholesky));
    }

    #[test]
    fn without_unbias_result_is_ridge_on_final_support() {
        let x = randn(100, 5, 2);
        let y = matvec(&x, &[1.0, 0.0, 0.0, -2.0, 0.0]);
        let o = PysindyStlsq {
            unbias: false,
            ..PysindyStlsq::default()
        };
        let w = o.fit(x.as_ref(), &y);
        // Closed form on the support {0, 3}: (X_Sᵀ X_S + αI)⁻¹ X_Sᵀ y, 2×2 by hand.
        let dot = |a: usize, b: usize| (0..100).map(|i| x[(i, a)] * x[(i, b)]).sum::<f64>();
        let dy = |a: usize| (0..100).map(|i| x[(i, a)] * y[i]).sum::<f64>();
        let (a11, a12, a22) = (dot(0, 0) + 0.05, dot(0, 3), dot(3, 3) + 0.05);
        let det = a11 * a22 - a12 * a12;
        let w0 = (a22 * dy(0) - a12 * dy(3)) / det;
        let w3 = (a11 * dy(3) - a12 * dy(0)) / det;
        assert!(close(w[0], w0, 1e-12) && close(w[3], w3, 1e-12), "{w:?}");
        assert!(
            w[0] < 1.0 && w[3] > -2.0,
            "ridge shrinks toward zero: {w:?}"
        );
        assert_eq!((w[1], w[2], w[4]), (0.0, 0.0, 0.0));
    }

    #[test]
    fn small_scale_column_is_erased_by_ridge() {
        // Column 1 has squared norm 0.005 ≪ α = 0.05 and true coefficient 1: ridge gives
        // ≈ 0.005/(0.005+0.05) ≈ 0.09 < 0.1, so pysindy drops it; with α = 0 it survives.
        let n = 400;
        let base = randn(n, 2, 3);
        let s0 = (0..n).map(|i| base[(i, 0)].powi(2)).sum::<f64>().sqrt();
        let s1 = (0..n).map(|i| base[(i, 1)].powi(2)).sum::<f64>().sqrt();
        let x = Mat::from_fn(n, 2, |i, j| {
            if j == 0 {
                base[(i, 0)] / s0 * 10.0
            } else {
                base[(i, 1)] / s1 * 0.005f64.sqrt()
            }
        });
        let y = matvec(&x, &[0.5, 1.0]);
        let w = PysindyStlsq::default().fit(x.as_ref(), &y);
        assert_eq!(w[1], 0.0, "{w:?}");
        let w0 = PysindyStlsq {
            alpha: 0.0,
            ..PysindyStlsq::default()
        }
        .fit(x.as_ref(), &y);
        assert!(close(w0[1], 1.0, 1e-10), "{w0:?}");
    }

    #[test]
    fn huge_threshold_empties_support_and_returns_zeros() {
        let x = randn(50, 4, 4);
        let y = matvec(&x, &[1.0, 2.0, 3.0, 4.0]);
        for unbias in [true, false] {
            let o = PysindyStlsq {
                threshold: 1e3,
                unbias,
                ..PysindyStlsq::default()
            };
            let fit = o.fit_report(x.as_ref(), &y, false);
            assert_eq!(fit.coefficients, vec![0.0; 4]);
            assert!(fit.emptied);
            assert_eq!(
                fit.iterations, 1,
                "one ridge fit, then the empty support stops"
            );
        }
    }

    #[test]
    fn max_iter_one_returns_first_thresholded_ridge() {
        let x = randn(80, 3, 5);
        let y = matvec(&x, &[1.0, 0.05, -1.0]);
        let o = PysindyStlsq {
            max_iter: 1,
            unbias: false,
            ..PysindyStlsq::default()
        };
        let fit = o.fit_report(x.as_ref(), &y, false);
        let full = PysindyStlsq {
            threshold: 0.0,
            max_iter: 1,
            unbias: false,
            ..o
        };
        let ridge = full.fit(x.as_ref(), &y);
        assert!(
            !fit.converged,
            "column 1 was removed, a second iteration was needed"
        );
        assert_eq!(fit.coefficients[0], ridge[0]);
        assert_eq!(fit.coefficients[1], 0.0);
        assert_eq!(fit.coefficients[2], ridge[2]);
    }

    #[test]
    fn zero_column_with_zero_alpha_falls_back_to_svd() {
        // ΘᵀΘ is singular (zero row/column) so Cholesky fails; scikit-learn's SVD solver
        // returns the minimum-norm solution, 0 for the zero column.
        let base = randn(60, 2, 6);
        let x = Mat::from_fn(60, 3, |i, j| if j == 1 { 0.0 } else { base[(i, j / 2)] });
        let y = matvec(&x, &[1.0, 0.0, -3.0]);
        let o = PysindyStlsq {
            alpha: 0.0,
            threshold: 0.0,
            unbias: false,
            max_iter: 5,
        };
        let fit = o.fit_report(x.as_ref(), &y, false);
        assert_eq!(fit.solvers[0], RidgeSolver::Svd);
        assert!(close(fit.coefficients[0], 1.0, 1e-12) && close(fit.coefficients[2], -3.0, 1e-12));
        assert_eq!(fit.coefficients[1], 0.0);
    }

    #[test]
    fn more_columns_than_samples_uses_dual_ridge() {
        // w = Xᵀ(XXᵀ + αI)⁻¹y equals (XᵀX + αI)⁻¹Xᵀy; check the primal normal equations.
        let x = randn(5, 8, 7);
        let y = [1.0, -2.0, 0.5, 3.0, 0.0];
        let o = PysindyStlsq {
            threshold: 0.0,
            alpha: 0.3,
            max_iter: 1,
            unbias: false,
        };
        let fit = o.fit_report(x.as_ref(), &y, false);
        assert_eq!(fit.solvers[0], RidgeSolver::CholeskyDual);
        let w = &fit.coefficients;
        let r: Vec<f64> = matvec(&x, w).iter().zip(&y).map(|(a, b)| a - b).collect();
        for j in 0..8 {
            let g = (0..5).map(|i| x[(i, j)] * r[i]).sum::<f64>() + 0.3 * w[j];
            assert!(g.abs() < 1e-12, "gradient {j} = {g}");
        }
    }

    #[test]
    fn unbias_truncates_singular_values_like_gelsd() {
        // Two nearly identical columns (relative difference 1e-9 ⇒ s_min/s_max ≈ 1e-9 <
        // 1e-6): gelsd with cond = 1e-6 returns the minimum-norm split, not the exact
        // (huge, opposite-sign) least-squares solution.
        let base = randn(100, 2, 8);
        let x = Mat::from_fn(100, 2, |i, j| {
            base[(i, 0)] + if j == 1 { 1e-9 * base[(i, 1)] } else { 0.0 }
        });
        let y: Vec<f64> = (0..100)
            .map(|i| 2.0 * base[(i, 0)] + 0.1 * base[(i, 1)])
            .collect();
        let o = PysindyStlsq {
            threshold: 0.0,
            alpha: 1.0,
            max_iter: 1,
            unbias: true,
        };
        let w = o.fit(x.as_ref(), &y);
        assert!((w[0] - w[1]).abs() < 1e-6, "minimum-norm split: {w:?}");
        assert!((w[0] - 1.0).abs() < 0.05, "{w:?}");
    }

    #[test]
    fn normalized_columns_make_threshold_scale_free() {
        // Column 1 has scale 1e-3 (squared norm ≈ 3e-4) and coefficient 10. Raw: ridge gives
        // ≈ 10·3e-4/(3e-4 + 0.05) ≈ 0.06 < 0.1, erased. Normalised: its coefficient is
        // 10·‖x₁‖ ≈ 0.17, ridge ≈ 0.17/1.05 > 0.1, kept, and unbias recovers 10 exactly.
        let base = randn(300, 2, 9);
        let x = Mat::from_fn(300, 2, |i, j| {
            if j == 0 {
                base[(i, 0)]
            } else {
                1e-3 * base[(i, 1)]
            }
        });
        let y = matvec(&x, &[1.0, 10.0]);
        let o = PysindyStlsq::default();
        let raw = o.fit(x.as_ref(), &y);
        assert_eq!(
            raw[1], 0.0,
            "raw: the ridge erases the small column: {raw:?}"
        );
        let w = o.fit_normalized_columns(x.as_ref(), &y);
        assert!(close(w[0], 1.0, 1e-10) && close(w[1], 10.0, 1e-10), "{w:?}");
    }

    #[test]
    fn try_fit_validates_like_pysindy() {
        let x = randn(20, 2, 10);
        let mut y = matvec(&x, &[1.0, -1.0]);
        let bad = PysindyStlsq {
            threshold: -1.0,
            ..PysindyStlsq::default()
        };
        assert!(bad
            .try_fit(x.as_ref(), &y, false)
            .unwrap_err()
            .to_string()
            .contains("threshold"));
        let bad = PysindyStlsq {
            max_iter: 0,
            ..PysindyStlsq::default()
        };
        assert!(bad
            .try_fit(x.as_ref(), &y, false)
            .unwrap_err()
            .to_string()
            .contains("max_iter"));
        // A NaN target row is dropped (pysindy drop_nan_samples), result unchanged in law.
        y[3] = f64::NAN;
        let fit = PysindyStlsq::default()
            .try_fit(x.as_ref(), &y, false)
            .unwrap();
        assert!(
            close(fit.coefficients[0], 1.0, 1e-12),
            "{:?}",
            fit.coefficients
        );
        // A partially non-finite library row is an error naming the entry.
        let mut x2 = x.clone();
        x2[(5, 1)] = f64::INFINITY;
        let e = PysindyStlsq::default()
            .try_fit(x2.as_ref(), &y, false)
            .unwrap_err();
        assert!(e.to_string().contains("theta[5, 1]"), "{e}");
    }
}
