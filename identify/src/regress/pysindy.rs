//! pysindy-compatible STLSQ.
//!
//! PLACEHOLDER written by the `regress` helper only so that its adapter
//! (`regress/adapter.rs`) compiles and its contract test runs: the real implementation is
//! owned by another helper and replaces this whole file at merge (take theirs). It keeps
//! the agreed signature and the rough semantics of pysindy 2.1 `STLSQ` (ridge on raw
//! columns, |ξ| < threshold removed, loop until the support is stable, optional unbiasing).

use faer::MatRef;

/// pysindy `STLSQ(threshold, alpha, max_iter, unbias)` on raw (unnormalised) columns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PysindyStlsq {
    /// Coefficient threshold.
    pub threshold: f64,
    /// Ridge parameter (sklearn `alpha`).
    pub alpha: f64,
    /// Maximum iterations.
    pub max_iter: usize,
    /// Least-squares refit on the final support.
    pub unbias: bool,
}

impl PysindyStlsq {
    /// Fits y ≈ Θ ξ; returns ξ (one per column).
    pub fn fit(&self, theta: MatRef<'_, f64>, y: &[f64]) -> Vec<f64> {
        let p = theta.ncols();
        let mut ind = vec![true; p];
        let mut coef = vec![0.0; p];
        for _ in 0..self.max_iter.max(1) {
            let cols: Vec<usize> = (0..p).filter(|&j| ind[j]).collect();
            if cols.is_empty() {
                break;
            }
            let x = solve(theta, y, &cols, self.alpha);
            coef = vec![0.0; p];
            for (&j, v) in cols.iter().zip(x) {
                coef[j] = v;
            }
            let before = cols.len();
            for j in 0..p {
                if coef[j].abs() < self.threshold {
                    ind[j] = false;
                    coef[j] = 0.0;
                }
            }
            if ind.iter().filter(|&&b| b).count() == before {
                break;
            }
        }
        if self.unbias {
            let cols: Vec<usize> = (0..p).filter(|&j| coef[j] != 0.0).collect();
            let x = solve(theta, y, &cols, 0.0);
            coef = vec![0.0; p];
            for (&j, v) in cols.iter().zip(x) {
                coef[j] = v;
            }
        }
        coef
    }
}

fn solve(theta: MatRef<'_, f64>, y: &[f64], cols: &[usize], alpha: f64) -> Vec<f64> {
    let q = cols.len();
    let mut g = vec![0.0; q * q];
    let mut b = vec![0.0; q];
    for (a, &ja) in cols.iter().enumerate() {
        b[a] = theta.col(ja).iter().zip(y).map(|(u, v)| u * v).sum();
        for (c, &jc) in cols.iter().enumerate() {
            g[a * q + c] = theta
                .col(ja)
                .iter()
                .zip(theta.col(jc).iter())
                .map(|(u, v)| u * v)
                .sum();
        }
        g[a * q + a] += alpha;
    }
    // Gaussian elimination with partial pivoting
    for k in 0..q {
        let piv = (k..q)
            .max_by(|&i, &j| g[i * q + k].abs().total_cmp(&g[j * q + k].abs()))
            .unwrap_or(k);
        if g[piv * q + k] == 0.0 {
            continue;
        }
        for c in 0..q {
            g.swap(k * q + c, piv * q + c);
        }
        b.swap(k, piv);
        for i in k + 1..q {
            let f = g[i * q + k] / g[k * q + k];
            for c in k..q {
                g[i * q + c] -= f * g[k * q + c];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; q];
    for k in (0..q).rev() {
        let s: f64 = b[k] - (k + 1..q).map(|c| g[k * q + c] * x[c]).sum::<f64>();
        x[k] = if g[k * q + k] == 0.0 {
            0.0
        } else {
            s / g[k * q + k]
        };
    }
    x
}
