//! Small dense symmetric positive-definite solves (normal equations of at most a few dozen
//! unknowns), by Cholesky factorisation.

/// Solves `G X = B` in place for symmetric positive-definite `G` (`p × p`, row-major, only
/// the lower triangle is read) and `nrhs` right-hand sides stored one after another in `b`
/// (`b[r*p..(r+1)*p]`). Returns `false` (and leaves `b` unspecified) when a pivot is below
/// `1e-13 ·` the largest diagonal entry, i.e. the columns are numerically dependent.
pub(crate) fn cholesky_solve(g: &mut [f64], p: usize, b: &mut [f64], nrhs: usize) -> bool {
    assert_eq!(g.len(), p * p, "Gram matrix shape");
    assert_eq!(b.len(), p * nrhs, "right-hand side shape");
    let dmax = (0..p).map(|i| g[i * p + i].abs()).fold(0.0, f64::max);
    let tol = 1e-13 * dmax.max(f64::MIN_POSITIVE);
    for j in 0..p {
        let mut d = g[j * p + j];
        for k in 0..j {
            d -= g[j * p + k] * g[j * p + k];
        }
        if d.is_nan() || d <= tol {
            return false;
        }
        let d = d.sqrt();
        g[j * p + j] = d;
        for i in j + 1..p {
            let mut s = g[i * p + j];
            for k in 0..j {
                s -= g[i * p + k] * g[j * p + k];
            }
            g[i * p + j] = s / d;
        }
    }
    for r in 0..nrhs {
        let x = &mut b[r * p..(r + 1) * p];
        for i in 0..p {
            let mut s = x[i];
            for k in 0..i {
                s -= g[i * p + k] * x[k];
            }
            x[i] = s / g[i * p + i];
        }
        for i in (0..p).rev() {
            let mut s = x[i];
            for k in i + 1..p {
                s -= g[k * p + i] * x[k];
            }
            x[i] = s / g[i * p + i];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_spd_and_detects_singular() {
        // G = A^T A for A = [[1,2],[3,4],[5,7]]; x = [1,-2] → b = G x.
        let a = [[1.0, 2.0], [3.0, 4.0], [5.0, 7.0]];
        let mut g = vec![0.0; 4];
        for r in &a {
            for i in 0..2 {
                for j in 0..2 {
                    g[i * 2 + j] += r[i] * r[j];
                }
            }
        }
        let x = [1.0, -2.0];
        let mut b = vec![g[0] * x[0] + g[1] * x[1], g[2] * x[0] + g[3] * x[1]];
        assert!(cholesky_solve(&mut g.clone(), 2, &mut b, 1));
        assert!(
            (b[0] - 1.0).abs() < 1e-12 && (b[1] + 2.0).abs() < 1e-12,
            "{b:?}"
        );
        let mut s = vec![1.0, 2.0, 2.0, 4.0];
        assert!(!cholesky_solve(&mut s, 2, &mut [1.0, 1.0], 1));
    }
}
