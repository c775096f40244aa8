//! Tiny dense least-squares solves (at most a few dozen columns) on plain slices.
//!
//! The δ path solves thousands of least-squares problems on the p × p triangular factor of
//! a case; calling a general library for a 30 × 10 problem costs more in set-up than in
//! arithmetic, so these few loops do it directly (Householder QR, column-major storage).

/// Solves min ‖A x − b‖² (+ λ‖x‖² when `ridge > 0`) for a small column-major `m × q`
/// matrix `a` by Householder QR. Returns `(x, rss)` where `rss = ‖A x − b‖²` (the data
/// misfit only, without the ridge penalty).
///
/// A column whose remaining norm is zero (exactly dependent or empty) gets coefficient 0.
///
/// # Panics
/// When `a.len() != m * q` or `b.len() != m` (programming errors).
#[track_caller]
pub fn lstsq(a: &[f64], m: usize, q: usize, b: &[f64], ridge: f64) -> (Vec<f64>, f64) {
    assert_eq!(a.len(), m * q, "matrix storage does not match shape");
    assert_eq!(b.len(), m, "right-hand side length does not match rows");
    if q == 0 {
        return (Vec::new(), b.iter().map(|v| v * v).sum());
    }
    // working copy, with sqrt(λ) I appended below when ridge > 0
    let extra = if ridge > 0.0 { q } else { 0 };
    let mm = m + extra;
    let mut w = vec![0.0; mm * q];
    for j in 0..q {
        w[j * mm..j * mm + m].copy_from_slice(&a[j * m..(j + 1) * m]);
        if extra > 0 {
            w[j * mm + m + j] = ridge.sqrt();
        }
    }
    let mut rhs = vec![0.0; mm];
    rhs[..m].copy_from_slice(b);
    let mut diag = vec![0.0; q];
    for k in 0..q.min(mm) {
        let col = &mut w[k * mm..(k + 1) * mm];
        let norm = col[k..].iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 {
            diag[k] = 0.0;
            continue;
        }
        let alpha = if col[k] > 0.0 { -norm } else { norm };
        // v = x − alpha e_k, stored in col[k..]
        col[k] -= alpha;
        let vnorm2: f64 = col[k..].iter().map(|v| v * v).sum();
        diag[k] = alpha;
        if vnorm2 == 0.0 {
            continue;
        }
        let v: Vec<f64> = col[k..].to_vec();
        for j in k + 1..q {
            let cj = &mut w[j * mm + k..(j + 1) * mm];
            let s: f64 = v.iter().zip(cj.iter()).map(|(a, b)| a * b).sum::<f64>() * 2.0 / vnorm2;
            for (c, vi) in cj.iter_mut().zip(&v) {
                *c -= s * vi;
            }
        }
        let s: f64 = v.iter().zip(&rhs[k..]).map(|(a, b)| a * b).sum::<f64>() * 2.0 / vnorm2;
        for (c, vi) in rhs[k..].iter_mut().zip(&v) {
            *c -= s * vi;
        }
    }
    // back substitution R x = (Qᵀ b)[..q]; R's off-diagonal entries are w[j*mm + i], i < j
    let mut x = vec![0.0; q];
    let scale = diag.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    for k in (0..q.min(mm)).rev() {
        let d = diag[k];
        if d.abs() <= scale * 1e-14 || d == 0.0 {
            x[k] = 0.0;
            continue;
        }
        let mut s = rhs[k];
        for j in k + 1..q {
            s -= w[j * mm + k] * x[j];
        }
        x[k] = s / d;
    }
    // data misfit with the original matrix
    let mut rss = 0.0;
    for i in 0..m {
        let mut r = -b[i];
        for j in 0..q {
            r += a[j * m + i] * x[j];
        }
        rss += r * r;
    }
    (x, rss)
}

/// In-place Householder QR of the first `nref` columns of the column-major `n × ncols`
/// matrix `a`, the reflectors being applied to every column (so the trailing columns become
/// Qᵀ times themselves). Returns the diagonal of R. Afterwards the entries `a[j*n + i]`,
/// `i < min(j, nref)`, and the returned diagonal hold R (for `j < nref`) or Qᵀ·column; for a
/// trailing column, the entries below row `nref` are its component orthogonal to the first
/// `nref` columns. An exactly zero remaining column gets R_kk = 0 (no reflector).
///
/// Unlike a rank-revealing factorisation, no column is ever skipped, so R is always
/// upper triangular with |R_kk| the distance of column k to the span of columns 0..k.
///
/// # Panics
/// When `a.len() != n * ncols` or `nref > min(n, ncols)` (programming errors).
#[track_caller]
pub fn householder_qr(a: &mut [f64], n: usize, ncols: usize, nref: usize) -> Vec<f64> {
    assert_eq!(a.len(), n * ncols, "matrix storage does not match shape");
    assert!(nref <= n.min(ncols), "more reflectors than rows or columns");
    let mut diag = vec![0.0; nref];
    for k in 0..nref {
        let (left, right) = a.split_at_mut((k + 1) * n);
        let v = &mut left[k * n + k..(k + 1) * n];
        let norm = dot(v, v).sqrt();
        if norm == 0.0 {
            continue;
        }
        let alpha = if v[0] > 0.0 { -norm } else { norm };
        v[0] -= alpha;
        let vv = dot(v, v);
        diag[k] = alpha;
        if vv == 0.0 {
            v[0] = alpha;
            continue;
        }
        let f = 2.0 / vv;
        for j in 0..(ncols - k - 1) {
            let c = &mut right[j * n + k..(j + 1) * n];
            let s = dot(v, c) * f;
            for (y, x) in c.iter_mut().zip(v.iter()) {
                *y -= s * x;
            }
        }
        // store R_kk in place of the reflector head (the reflector is no longer needed)
        v[0] = alpha;
    }
    diag
}

/// Dot product with four accumulators (lets the compiler vectorise).
#[inline]
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let (mut s0, mut s1, mut s2, mut s3) = (0.0, 0.0, 0.0, 0.0);
    let mut it = x.chunks_exact(4).zip(y.chunks_exact(4));
    for (a, b) in &mut it {
        s0 += a[0] * b[0];
        s1 += a[1] * b[1];
        s2 += a[2] * b[2];
        s3 += a[3] * b[3];
    }
    let rem = x.len() / 4 * 4;
    let mut s = (s0 + s1) + (s2 + s3);
    for i in rem..x.len().min(y.len()) {
        s += x[i] * y[i];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_overdetermined_system() {
        // columns (1,1,1,1) and (0,1,2,3); b = 1 + 2 t exactly, then perturbed
        let a = [1.0, 1.0, 1.0, 1.0, 0.0, 1.0, 2.0, 3.0];
        let b = [1.0, 3.0, 5.0, 7.0];
        let (x, rss) = lstsq(&a, 4, 2, &b, 0.0);
        assert!((x[0] - 1.0).abs() < 1e-13 && (x[1] - 2.0).abs() < 1e-13);
        assert!(rss < 1e-24);
        let b2 = [1.0, 3.5, 5.0, 7.0];
        let (x2, rss2) = lstsq(&a, 4, 2, &b2, 0.0);
        // normal equations: [4 6; 6 14] x = [16.5, 34.5]
        let det = 4.0 * 14.0 - 36.0;
        let e0 = (14.0 * 16.5 - 6.0 * 34.5) / det;
        let e1 = (4.0 * 34.5 - 6.0 * 16.5) / det;
        assert!((x2[0] - e0).abs() < 1e-12 && (x2[1] - e1).abs() < 1e-12);
        let manual: f64 = (0..4).map(|i| (e0 + e1 * i as f64 - b2[i]).powi(2)).sum();
        assert!((rss2 - manual).abs() < 1e-12);
    }

    #[test]
    fn ridge_matches_normal_equations() {
        let a = [1.0, 2.0, 0.5, -1.0, 0.3, 0.2];
        let b = [1.0, 0.0, 2.0];
        let lam = 0.7;
        let (x, _) = lstsq(&a, 3, 2, &b, lam);
        // (AᵀA + λI) x = Aᵀb
        let g00 = 1.0 + 4.0 + 0.25 + lam;
        let g01 = -1.0 + 0.6 + 0.1;
        let g11 = 1.0 + 0.09 + 0.04 + lam;
        let r0 = 1.0 + 1.0;
        let r1 = -1.0 + 0.4;
        let det = g00 * g11 - g01 * g01;
        assert!((x[0] - (g11 * r0 - g01 * r1) / det).abs() < 1e-12);
        assert!((x[1] - (g00 * r1 - g01 * r0) / det).abs() < 1e-12);
    }

    #[test]
    fn householder_r_has_the_gram_of_a() {
        let (n, q) = (7, 3);
        let a0: Vec<f64> = (0..n * q).map(|i| ((i * i) as f64 * 0.31).sin()).collect();
        let mut a = a0.clone();
        let d = householder_qr(&mut a, n, q, 2);
        // R (2 × 2 part + column 2's Qᵀ part): RᵀR = AᵀA for the first two columns
        let r = |i: usize, j: usize| if i == j { d[i] } else { a[j * n + i] };
        let g = |x: usize, y: usize| (0..n).map(|i| a0[x * n + i] * a0[y * n + i]).sum::<f64>();
        assert!((r(0, 0).powi(2) - g(0, 0)).abs() < 1e-12);
        assert!((r(0, 0) * r(0, 1) - g(0, 1)).abs() < 1e-12);
        assert!((r(0, 1).powi(2) + r(1, 1).powi(2) - g(1, 1)).abs() < 1e-12);
        // trailing column keeps its norm and its inner products
        let c2: f64 = (0..n).map(|i| a[2 * n + i].powi(2)).sum();
        assert!((c2 - g(2, 2)).abs() < 1e-12);
        assert!((r(0, 0) * a[2 * n] - g(0, 2)).abs() < 1e-12);
    }

    #[test]
    fn zero_column_gets_zero_coefficient() {
        let a = [1.0, 2.0, 3.0, 0.0, 0.0, 0.0];
        let b = [2.0, 4.0, 6.0];
        let (x, rss) = lstsq(&a, 3, 2, &b, 0.0);
        assert!((x[0] - 2.0).abs() < 1e-13);
        assert_eq!(x[1], 0.0);
        assert!(rss < 1e-20);
    }
}
