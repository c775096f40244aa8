//! The force level's small numeric kernels: an SPD solve with a relative ridge (the thin QR
//! of its regressions is `identify::numerics::qr::ThinQr`) and a zero-padded periodogram.

use identify::numerics::{cholesky_in_place, cholesky_solve_in_place, PivotFloor};

pub(crate) use identify::numerics::qr::dot;

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

/// |DFT|² of x zero-padded to m points.
pub(crate) fn periodogram_full(x: &[f64], m: usize) -> Vec<f64> {
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(m);
    let mut input = vec![0.0; m];
    input[..x.len()].copy_from_slice(x);
    let mut out = fft.make_output_vec();
    if fft.process(&mut input, &mut out).is_err() {
        return vec![0.0; m / 2 + 1];
    }
    out.iter().map(|z| z.norm_sqr()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spd_solver_matches_a_known_solution() {
        let g = vec![vec![4.0, 1.0], vec![1.0, 3.0]];
        let x = solve_spd(&g, &[1.0, 2.0], 0.0).unwrap();
        // exact: (4x + y = 1, x + 3y = 2) → x = 1/11, y = 7/11
        assert!((x[0] - 1.0 / 11.0).abs() < 1e-9 && (x[1] - 7.0 / 11.0).abs() < 1e-9);
    }
}
