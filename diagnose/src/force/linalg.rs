//! Small dense least-squares helpers: an orthonormal basis of a few long columns (modified
//! Gram–Schmidt with re-orthogonalisation), projections and back-substitution. The
//! regressions of the force level have ≤ 40 columns of a few thousand samples; a thin QR
//! of this kind is exact to rounding and cheap.

use identify::numerics::{cholesky_in_place, cholesky_solve_in_place, PivotFloor};

/// Thin QR factorisation X = Q R of a tall matrix given by columns; columns whose part
/// orthogonal to the previous ones is below `rel_tol` of their norm are dropped (their
/// coefficient is 0).
#[derive(Debug, Clone)]
pub(crate) struct Qr {
    /// Orthonormal columns (only the kept ones).
    pub q: Vec<Vec<f64>>,
    /// R restricted to kept columns, row-major over kept columns: `r[k][l]`, l ≥ k.
    pub r: Vec<Vec<f64>>,
    /// Index in the input of each kept column.
    pub kept: Vec<usize>,
    /// Number of input columns.
    pub n_cols: usize,
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Qr {
    /// Factorises the columns `cols` (all of the same length).
    pub fn new(cols: &[&[f64]], rel_tol: f64) -> Self {
        let mut q: Vec<Vec<f64>> = Vec::with_capacity(cols.len());
        let mut r: Vec<Vec<f64>> = Vec::with_capacity(cols.len());
        let mut kept = Vec::with_capacity(cols.len());
        for (j, c) in cols.iter().enumerate() {
            let norm0 = dot(c, c).sqrt();
            let mut v = c.to_vec();
            let mut coefs = vec![0.0; q.len()];
            for _ in 0..2 {
                for (k, qk) in q.iter().enumerate() {
                    let a = dot(qk, &v);
                    coefs[k] += a;
                    v.iter_mut().zip(qk).for_each(|(x, y)| *x -= a * y);
                }
            }
            let nv = dot(&v, &v).sqrt();
            if norm0 == 0.0 || nv <= rel_tol * norm0 {
                continue;
            }
            v.iter_mut().for_each(|x| *x /= nv);
            for (k, c) in coefs.iter().enumerate() {
                r[k].push(*c);
            }
            r.push(vec![nv]);
            q.push(v);
            kept.push(j);
        }
        // r[k] holds R[k][k..]: first element pushed when k was created is the diagonal,
        // later pushes the entries of later kept columns.
        Qr {
            q,
            r,
            kept,
            n_cols: cols.len(),
        }
    }

    /// Qᵀ y.
    pub fn qt(&self, y: &[f64]) -> Vec<f64> {
        self.q.iter().map(|qk| dot(qk, y)).collect()
    }

    /// y − Q Qᵀ y (residual of the least-squares fit of y on the columns).
    pub fn residual(&self, y: &[f64]) -> Vec<f64> {
        let mut v = y.to_vec();
        for qk in &self.q {
            let a = dot(qk, &v);
            v.iter_mut().zip(qk).for_each(|(x, q)| *x -= a * q);
        }
        v
    }

    /// Least-squares coefficients of y on the input columns (0 for dropped columns).
    pub fn solve(&self, y: &[f64]) -> Vec<f64> {
        let b = self.qt(y);
        self.solve_qt(&b)
    }

    /// Coefficients from Qᵀ y.
    pub fn solve_qt(&self, b: &[f64]) -> Vec<f64> {
        let m = self.q.len();
        let mut x = vec![0.0; m];
        for k in (0..m).rev() {
            let mut s = b[k];
            for l in k + 1..m {
                s -= self.r[k][l - k] * x[l];
            }
            x[k] = s / self.r[k][0];
        }
        let mut out = vec![0.0; self.n_cols];
        for (k, &j) in self.kept.iter().enumerate() {
            out[j] = x[k];
        }
        out
    }
}

/// Solves the small symmetric positive semi-definite system G β = b with a relative ridge
/// `ridge · max diag(G)` (so that a direction the data do not determine gets β ≈ 0).
/// Returns None when G is empty or not finite.
pub(crate) fn solve_spd(g: &[Vec<f64>], b: &[f64], ridge: f64) -> Option<Vec<f64>> {
    let n = b.len();
    if n == 0 {
        return Some(Vec::new());
    }
    let dmax = (0..n).map(|i| g[i][i]).fold(0.0, f64::max);
    if !(dmax.is_finite() && dmax > 0.0) {
        return None;
    }
    // Jacobi scaling then Cholesky.
    let s: Vec<f64> = (0..n)
        .map(|i| {
            let d = g[i][i];
            if d > 0.0 {
                1.0 / d.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            a[i * n + j] = g[i][j] * s[i] * s[j];
        }
        a[i * n + i] += ridge.max(1e-12);
    }
    cholesky_in_place(&mut a, n, PivotFloor::Absolute(0.0)).ok()?;
    let mut x: Vec<f64> = (0..n).map(|i| b[i] * s[i]).collect();
    cholesky_solve_in_place(&a, n, &mut x);
    Some((0..n).map(|i| x[i] * s[i]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn qr_solves_and_drops_dependent_columns() {
        let n = 50;
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let c: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 2.0 * x - y).collect();
        let y: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 1.5 * x + 0.25 * y).collect();
        let qr = Qr::new(&[&a, &b, &c], 1e-10);
        assert_eq!(qr.kept, vec![0, 1]);
        let x = qr.solve(&y);
        assert!((x[0] - 1.5).abs() < 1e-12 && (x[1] - 0.25).abs() < 1e-12 && x[2] == 0.0);
        let r = qr.residual(&y);
        assert!(dot(&r, &r) < 1e-20);
    }

    #[test]
    fn spd_solver_matches_a_known_solution() {
        let g = vec![vec![4.0, 1.0], vec![1.0, 3.0]];
        let x = solve_spd(&g, &[1.0, 2.0], 0.0).unwrap();
        // exact: (4x + y = 1, x + 3y = 2) → x = 1/11, y = 7/11
        assert!((x[0] - 1.0 / 11.0).abs() < 1e-9 && (x[1] - 7.0 / 11.0).abs() < 1e-9);
    }
}
