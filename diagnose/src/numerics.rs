//! The diagnosis's small numeric kernels, shared by its levels: the one ridge solve of the
//! small normal equations (force-level shared coefficients, system-level candidate fits)
//! and a zero-padded periodogram. The thin QR of the force level's regressions is
//! `identify::numerics::qr::ThinQr`.

use identify::numerics::{cholesky_in_place, cholesky_solve_in_place, PivotFloor};

pub(crate) use identify::numerics::qr::dot;

/// Solves the small symmetric positive semi-definite system (G + λ diag G) x = b, with
/// G = `g(i, j)` of size `b.len()` and λ = max(`ridge`, 1e-12): by Jacobi scaling
/// (S G S + λ I, S = diag G^(−1/2)) and Cholesky, so that a direction the data do not
/// determine gets x ≈ 0, and a column with a zero diagonal (empty on the data) gets x = 0.
/// `None` when G's largest diagonal is not finite and positive, or the factorisation fails.
pub(crate) fn ridge_solve(
    g: impl Fn(usize, usize) -> f64,
    b: &[f64],
    ridge: f64,
) -> Option<Vec<f64>> {
    let n = b.len();
    if n == 0 {
        return Some(Vec::new());
    }
    let dmax = (0..n).map(|i| g(i, i)).fold(0.0, f64::max);
    if !(dmax.is_finite() && dmax > 0.0) {
        return None;
    }
    // Jacobi scaling then Cholesky.
    let s: Vec<f64> = (0..n)
        .map(|i| {
            let d = g(i, i);
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
            a[i * n + j] = g(i, j) * s[i] * s[j];
        }
        a[i * n + i] += ridge.max(1e-12);
    }
    cholesky_in_place(&mut a, n, PivotFloor::Absolute(0.0)).ok()?;
    let mut x: Vec<f64> = (0..n).map(|i| b[i] * s[i]).collect();
    cholesky_solve_in_place(&a, n, &mut x);
    Some((0..n).map(|i| x[i] * s[i]).collect())
}

/// Forward real FFT of length `m`, planned once per process and length and shared (the
/// planner picks the algorithm from the length alone: bit for bit the plan a fresh planner
/// makes; planning computes every twiddle factor, 1.7 % of job 1's CPU in round 32's
/// profile).
fn forward_plan(m: usize) -> std::sync::Arc<dyn realfft::RealToComplex<f64>> {
    use std::sync::{Mutex, OnceLock};
    static PLANNER: OnceLock<Mutex<realfft::RealFftPlanner<f64>>> = OnceLock::new();
    let planner = PLANNER.get_or_init(|| Mutex::new(realfft::RealFftPlanner::new()));
    match planner.lock() {
        Ok(mut p) => p.plan_fft_forward(m),
        Err(_) => realfft::RealFftPlanner::new().plan_fft_forward(m),
    }
}

/// |DFT|² of x zero-padded to m points.
pub(crate) fn periodogram_full(x: &[f64], m: usize) -> Vec<f64> {
    let fft = forward_plan(m);
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
        let g = [[4.0, 1.0], [1.0, 3.0]];
        let x = ridge_solve(|i, j| g[i][j], &[1.0, 2.0], 0.0).unwrap();
        // exact: (4x + y = 1, x + 3y = 2) → x = 1/11, y = 7/11
        assert!((x[0] - 1.0 / 11.0).abs() < 1e-9 && (x[1] - 7.0 / 11.0).abs() < 1e-9);
        // a column with a zero diagonal (empty on the data) gets 0
        let g0 = [4.0, 0.0, 0.0, 0.0];
        let x = ridge_solve(|i, j| g0[i * 2 + j], &[1.0, 5.0], 1e-10).unwrap();
        assert!((x[0] - 0.25).abs() < 1e-9 && x[1] == 0.0, "{x:?}");
        assert!(ridge_solve(|_, _| 0.0, &[1.0, 1.0], 1e-10).is_none());
        assert!(ridge_solve(|_, _| f64::NAN, &[1.0], 1e-10).is_none());
    }

    #[test]
    fn solve_does_not_depend_on_column_scale() {
        // A column in rad³ at 0.05 rad (an α³ stiffness term) is ~1e-4 of a column in
        // rad: its diagonal is ~1e-8 of the largest. A pivot floor relative to the
        // largest diagonal refused such a system (DECISIONS "One ridge solve"); the Jacobi
        // scaling solves it as if the columns were of one scale.
        let g = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let b = [1.0, 2.0, 0.5];
        let x = ridge_solve(|i, j| g[i][j], &b, 1e-10).unwrap();
        for c in [1e-4, 1e-7] {
            let sc = [1.0, 1.0, c];
            let xs = ridge_solve(
                |i, j| g[i][j] * sc[i] * sc[j],
                &[b[0], b[1], b[2] * c],
                1e-10,
            )
            .unwrap();
            for k in 0..3 {
                assert!(
                    (xs[k] * sc[k] - x[k]).abs() < 1e-9 * x[k].abs().max(1.0),
                    "{c}: {xs:?}"
                );
            }
        }
    }
}
