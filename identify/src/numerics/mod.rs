//! Small numeric kernels shared by every crate of the workspace (it sits in `identify`, the
//! lowest one): dense symmetric positive-definite solves by Cholesky factorisation, the
//! Householder QR ([`qr`]), reused scratch buffers ([`scratch`]), interpolation ([`interp`]), the median and the median absolute
//! deviation, and the SplitMix64 seed mixer.
//!
//! Each kernel has one implementation and one failure signal: a solve that meets a
//! non-positive pivot returns [`NotPositiveDefinite`] naming the pivot, never a silent NaN.

pub mod interp;
pub mod mat;
pub mod qr;
pub mod scratch;

/// Golden-section maximisation of a unimodal `f` on `[a, b]`: the midpoint of the final
/// bracket, narrowed until it is at most `tol` wide (one evaluation of `f` per step,
/// the bracket shrinking by 0.618 each). Ties keep the left part.
pub fn golden_section_max(mut a: f64, mut b: f64, tol: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - r * (b - a);
    let mut d = a + r * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    while (b - a).abs() > tol {
        if fc >= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

/// A Cholesky factorisation met a pivot at or below its floor: the matrix is not
/// (numerically) positive definite, i.e. column `index` is (nearly) a combination of the
/// columns before it.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("matrix is not positive definite: pivot {index} is {pivot:e} (floor {floor:e})")]
pub struct NotPositiveDefinite {
    /// 0-based index of the failing pivot.
    pub index: usize,
    /// The pivot's value before the square root (NaN when the matrix held a NaN).
    pub pivot: f64,
    /// The floor it had to exceed.
    pub floor: f64,
}

/// The smallest acceptable Cholesky pivot d_j (the squared diagonal of L before its square
/// root). d_j / a_jj is 1 − R² of column j regressed on the columns before it, so
/// [`PivotFloor::RelativeToDiagonal`] is a scale-free dependence test; `Absolute` is for
/// callers that have already chosen a scale (e.g. the largest diagonal entry).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PivotFloor {
    /// d_j must exceed `tol · max(a_jj, f64::MIN_POSITIVE)` (a_jj the original diagonal).
    RelativeToDiagonal(f64),
    /// d_j must exceed `tol · max(maxᵢ a_ii, f64::MIN_POSITIVE)` (one floor for all pivots,
    /// set by the largest original diagonal entry).
    RelativeToLargestDiagonal(f64),
    /// d_j must exceed this value.
    Absolute(f64),
}

/// Factorises the symmetric `n × n` row-major matrix `a` in place into its lower Cholesky
/// factor L (A = L Lᵀ; only the lower triangle of `a` is read; on success the strict upper
/// triangle is set to zero, so `a` holds L).
///
/// # Errors
/// [`NotPositiveDefinite`] at the first pivot that is not finite or not above `floor`;
/// `a` is then partly overwritten.
///
/// # Panics
/// When `a.len() != n * n` (a programming error).
#[track_caller]
pub fn cholesky_in_place(
    a: &mut [f64],
    n: usize,
    floor: PivotFloor,
) -> Result<(), NotPositiveDefinite> {
    assert_eq!(a.len(), n * n, "Cholesky: matrix shape");
    let largest = (0..n)
        .map(|i| a[i * n + i].abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    for j in 0..n {
        let diag = a[j * n + j];
        let mut d = diag;
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        let fl = match floor {
            PivotFloor::RelativeToDiagonal(tol) => tol * diag.abs().max(f64::MIN_POSITIVE),
            PivotFloor::RelativeToLargestDiagonal(tol) => tol * largest,
            PivotFloor::Absolute(v) => v,
        };
        if !d.is_finite() || d <= fl {
            return Err(NotPositiveDefinite {
                index: j,
                pivot: d,
                floor: fl,
            });
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for i in 0..n {
        a[i * n + i + 1..(i + 1) * n].fill(0.0);
    }
    Ok(())
}

/// Solves L Lᵀ x = b in place (`x` holds b on entry) with the factor written by
/// [`cholesky_in_place`].
///
/// # Panics
/// When the shapes disagree (a programming error).
#[track_caller]
pub fn cholesky_solve_in_place(l: &[f64], n: usize, x: &mut [f64]) {
    assert_eq!(l.len(), n * n, "Cholesky: factor shape");
    assert_eq!(x.len(), n, "Cholesky: right-hand side length");
    for i in 0..n {
        let mut s = x[i];
        for k in 0..i {
            s -= l[i * n + k] * x[k];
        }
        x[i] = s / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in i + 1..n {
            s -= l[k * n + i] * x[k];
        }
        x[i] = s / l[i * n + i];
    }
}

/// Solves A X = B in place for a symmetric positive-definite `n × n` matrix `a` (row-major,
/// overwritten by its factor) and `nrhs` right-hand sides stored one after another in `b`
/// (`b[r·n .. (r+1)·n]`), overwritten by the solutions.
///
/// # Errors
/// [`NotPositiveDefinite`] as [`cholesky_in_place`]; `b` is then unchanged.
///
/// # Panics
/// When the shapes disagree (a programming error).
#[track_caller]
pub fn cholesky_solve(
    a: &mut [f64],
    n: usize,
    b: &mut [f64],
    nrhs: usize,
    floor: PivotFloor,
) -> Result<(), NotPositiveDefinite> {
    assert_eq!(b.len(), n * nrhs, "Cholesky: right-hand side shape");
    cholesky_in_place(a, n, floor)?;
    for x in b.chunks_exact_mut(n.max(1)).take(nrhs) {
        cholesky_solve_in_place(a, n, x);
    }
    Ok(())
}

/// Median of `v` (sorted in place by `total_cmp`); the mean of the two middle values for an
/// even length; NaN for an empty slice. NaNs sort last, so filter them first when they can
/// occur ([`median_finite`]).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Median of the finite values of `v`; NaN when there are none.
pub fn median_finite(v: &[f64]) -> f64 {
    let mut w: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    median(&mut w)
}

/// Median absolute deviation about `center`: median(|v − center|); NaN for an empty slice.
/// Multiply by 1.4826 for a robust standard deviation of Gaussian data.
pub fn mad(v: &[f64], center: f64) -> f64 {
    let mut d: Vec<f64> = v.iter().map(|x| (x - center).abs()).collect();
    median(&mut d)
}

/// SplitMix64 of `seed + (index + 1)·φ·2⁶⁴` (φ the golden ratio): a well-mixed, independent
/// 64-bit seed for stream `index` of a master `seed`, so that parallel work does not depend
/// on the thread count or the order of the items.
pub fn split_seed(seed: u64, index: u64) -> u64 {
    let mut z = seed.wrapping_add(index.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The 53 high bits of `bits` as a uniform number in [0, 1) (e.g. of a [`split_seed`]).
pub fn unit_interval(bits: u64) -> f64 {
    (bits >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_spd_and_names_the_dependent_pivot() {
        // G = AᵀA for A = [[1,2],[3,4],[5,7]]; x = [1,-2] → b = G x.
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
        let mut b: Vec<f64> = (0..2)
            .map(|i| g[i * 2] * x[0] + g[i * 2 + 1] * x[1])
            .collect();
        cholesky_solve(&mut g, 2, &mut b, 1, PivotFloor::RelativeToDiagonal(1e-13)).unwrap();
        assert!(
            (b[0] - 1.0).abs() < 1e-12 && (b[1] + 2.0).abs() < 1e-12,
            "{b:?}"
        );
        // Second column = 2 × first: pivot 1 is zero.
        let mut s = vec![1.0, 2.0, 2.0, 4.0];
        let e = cholesky_in_place(&mut s, 2, PivotFloor::RelativeToDiagonal(1e-13)).unwrap_err();
        assert_eq!(e.index, 1);
        let mut nan = vec![f64::NAN];
        assert_eq!(
            cholesky_in_place(&mut nan, 1, PivotFloor::Absolute(0.0))
                .unwrap_err()
                .index,
            0
        );
    }

    #[test]
    fn golden_section_finds_the_maximum() {
        let x = golden_section_max(-1.0, 3.0, 1e-10, |x| -(x - 0.7) * (x - 0.7));
        assert!((x - 0.7).abs() < 1e-9, "{x}");
    }

    #[test]
    fn median_mad_and_seeds() {
        assert!(median(&mut []).is_nan());
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median_finite(&[f64::NAN, 1.0, f64::INFINITY, 3.0]), 2.0);
        assert_eq!(mad(&[1.0, 2.0, 3.0, 4.0, 100.0], 3.0), 1.0);
        // Reference values of SplitMix64 (seed 0, first two outputs of the generator).
        assert_eq!(split_seed(0, 0), 0xE220_A839_7B1D_CDAF);
        assert_eq!(split_seed(0, 1), 0x6E78_9E6A_A1B9_65F4);
        assert_ne!(split_seed(7, 3), split_seed(7, 4));
    }
}
