//! One QR factorisation per case, reused by every fit of the δ path.
//!
//! The library matrix Θ (n × p) of a case is column-normalised (each column divided by its
//! 2-norm; an all-zero column keeps scale 1) and its columns are permuted into the
//! identifiability priority order ([`crate::identifiability::priority_order`]). The targets
//! are appended as extra columns and the whole n × (p + t) matrix is factorised once,
//! `[Θ_s P | y_1 … y_t] = Q R_ext` (Householder, [`crate::numerics::qr::householder_qr`], row-blocked;
//! not a pivoting library QR, which reorders or skips dependent columns and leaves an echelon
//! form in which |R_kk| is no longer the greedy residual of column k). Then for any subset
//! S of columns,
//!
//! ‖Θ_s[:, S] ξ − y‖² = ‖R[:, S] ξ − Qᵀy‖² + r⊥²,
//!
//! where R is the leading p × p block of R_ext, Qᵀy the first p entries of the target's
//! column of R_ext and r⊥² the squared norm of the rest of that column (computed from the
//! entries below row p, so without cancellation). Every support fit is then a tiny
//! least-squares solve on at most p × p numbers, independent of the record length n.

use crate::numerics::mat::{Mat, MatMut, MatRef};

use crate::numerics::scratch::Scratch;
use crate::numerics::{cholesky_in_place, cholesky_solve_in_place, PivotFloor};
use crate::{Error, Result};

/// Rows per block of the row-blocked factorisation (at least twice the column count).
const ROW_BLOCK: usize = 256;
/// Rows of Θ requested per call of the `fill` closure of [`CaseFactor::from_row_blocks`]
/// (rounded down to a multiple of the factorisation block).
pub const FILL_BLOCK: usize = crate::library::EVAL_BLOCK;
/// Triangles stacked by the row-blocked factorisation before the stack is reduced to one
/// (128 × 32 × 32 × 8 B = 1 MB for the paper library with two targets).
pub const STACK_BLOCKS: usize = 128;

/// A p × p upper-triangular matrix held packed by columns (p(p + 1)/2 numbers, half of a
/// dense matrix: the per-case factor is most of what an identification keeps per case).
/// Indexing `(i, j)` gives entry i, j (0 below the diagonal).
#[derive(Debug, Clone, PartialEq)]
pub struct Upper {
    p: usize,
    data: Vec<f64>,
}

static ZERO: f64 = 0.0;

impl Upper {
    /// The matrix with entry (i, j) = `f(i, j)` for i ≤ j (called column by column, row
    /// by row inside a column; `f` may read entries already made only through its own
    /// captures).
    pub fn from_fn(p: usize, mut f: impl FnMut(usize, usize) -> f64) -> Self {
        let mut data = Vec::with_capacity(p * (p + 1) / 2);
        for j in 0..p {
            for i in 0..=j {
                data.push(f(i, j));
            }
        }
        Upper { p, data }
    }

    /// Order p.
    pub fn order(&self) -> usize {
        self.p
    }

    /// Entry (min(i, j), max(i, j)): the matrix read as the upper triangle of a symmetric
    /// one.
    ///
    /// # Panics
    /// When an index is ≥ p (a programming error).
    #[track_caller]
    pub fn sym(&self, i: usize, j: usize) -> f64 {
        let (a, b) = if i <= j { (i, j) } else { (j, i) };
        self[(a, b)]
    }

    /// Column j down to the diagonal: entries (0, j) … (j, j).
    ///
    /// # Panics
    /// When j ≥ p (a programming error).
    #[track_caller]
    pub fn col(&self, j: usize) -> &[f64] {
        assert!(j < self.p, "column {j} of a {0} × {0} matrix", self.p);
        &self.data[j * (j + 1) / 2..(j + 1) * (j + 2) / 2]
    }

    /// The dense p × p matrix (zeros below the diagonal).
    pub fn to_mat(&self) -> Mat<f64> {
        Mat::from_fn(self.p, self.p, |i, j| self[(i, j)])
    }
}

impl std::ops::Index<(usize, usize)> for Upper {
    type Output = f64;
    #[track_caller]
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        assert!(
            i < self.p && j < self.p,
            "({i}, {j}) out of a {0} × {0} matrix",
            self.p
        );
        if i > j {
            &ZERO
        } else {
            &self.data[j * (j + 1) / 2 + i]
        }
    }
}

/// What the factorisation does with Θ's rows r0..r0 + rows: `(r0, rows, src, ld)`, column j
/// at `src[j·ld .. j·ld + rows]`.
type BlockVisitor<'a> = dyn FnMut(usize, usize, &[f64], usize) + 'a;

/// Reduced form of one target (one force coefficient) of a case.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetFactor {
    /// Qᵀy (length p), in priority order.
    pub qty: Vec<f64>,
    /// Squared norm of the part of y orthogonal to every library column, r⊥².
    pub rss_perp: f64,
    /// ‖y‖².
    pub norm2: f64,
    /// Mean of y.
    pub mean: f64,
    /// Number of samples n.
    pub n: usize,
}

impl TargetFactor {
    /// Total sum of squares about the mean, Σ(y − ȳ)².
    pub fn ss_tot(&self) -> f64 {
        (self.norm2 - self.n as f64 * self.mean * self.mean).max(0.0)
    }
}

/// The reduced least-squares problem of one case: the triangular factor of its
/// column-normalised library in priority order, and its targets.
#[derive(Debug, Clone)]
pub struct CaseFactor {
    /// Number of samples.
    pub n: usize,
    /// `order[k]` = library column at priority position k.
    pub order: Vec<usize>,
    /// `pos[j]` = priority position of library column j.
    pub pos: Vec<usize>,
    /// Column scales d_j (2-norm of library column j; 1 for an all-zero column).
    pub scales: Vec<f64>,
    /// Whether library column j is identically zero.
    pub zero_column: Vec<bool>,
    /// p × p upper-triangular factor R of Θ_s in priority order (packed).
    pub r: Upper,
    /// One reduced target per target given to [`CaseFactor::new`].
    pub targets: Vec<TargetFactor>,
    /// Θ_sᵀ y = Rᵀ Qᵀy per target (priority order).
    pub gram_rhs: Vec<Vec<f64>>,
}

impl CaseFactor {
    /// Factorises the library matrix `theta` (n × p, library column order) of case `case`
    /// with the columns taken in priority order `order`, together with the `targets`.
    /// Same as [`CaseFactor::from_row_blocks`] reading the blocks from `theta`.
    ///
    /// # Errors
    /// [`Error::InvalidData`] when the case has fewer samples than p + number of targets
    /// (no least-squares problem can be posed), or when Θ or a target holds a non-finite
    /// value.
    ///
    /// # Panics
    /// When `order` is not a permutation of the columns or a target length differs from n
    /// (programming errors).
    #[track_caller]
    pub fn new(
        case: &str,
        theta: MatRef<'_, f64>,
        order: &[usize],
        targets: &[&[f64]],
    ) -> Result<Self> {
        let (n, p) = theta.shape();
        Self::from_row_blocks(case, n, p, order, targets, |r0, mut out| {
            let rows = out.nrows();
            out.copy_from(theta.subrows(r0, rows));
        })
    }

    /// As [`CaseFactor::new`] for an n × p library matrix Θ that is never held whole:
    /// `fill(r0, out)` writes the rows `r0 .. r0 + out.nrows()` of Θ (library column order)
    /// into `out` (`out.nrows()` × p). It is called for consecutive blocks of at most
    /// [`FILL_BLOCK`] rows covering 0..n, twice (column norms, then the factorisation), so
    /// memory beyond the targets is O(p² + [`FILL_BLOCK`]·p), independent of n.
    ///
    /// The row-blocked factorisation stacks the triangles of blocks of 256 rows; once
    /// [`STACK_BLOCKS`] triangles are stacked, the stack is factorised into one triangle
    /// and filling continues. Up to `STACK_BLOCKS · 256` = 32768 rows (64 s at 512 Hz) this
    /// never happens and the result is bit for bit that of a single stack; beyond, R and
    /// Qᵀy change by rounding only (the same orthogonal reduction in another order).
    ///
    /// # Errors
    /// As [`CaseFactor::new`].
    ///
    /// # Panics
    /// As [`CaseFactor::new`], and when `fill` changes the shape of `out`.
    #[track_caller]
    pub fn from_row_blocks(
        case: &str,
        n: usize,
        p: usize,
        order: &[usize],
        targets: &[&[f64]],
        fill: impl FnMut(usize, MatMut<'_, f64>),
    ) -> Result<Self> {
        Self::factorise(case, n, p, order, targets, None, fill)
    }

    /// [`CaseFactor::new`] for an n × p library matrix Θ held column-major in `theta`
    /// (column j at `theta[j·n .. (j + 1)·n]`), read in place: the numbers of
    /// [`CaseFactor::from_row_blocks`] without its block buffer and copies.
    ///
    /// # Errors
    /// As [`CaseFactor::new`].
    ///
    /// # Panics
    /// As [`CaseFactor::new`], and when `theta.len() != n·p`.
    #[track_caller]
    pub fn from_columns(
        case: &str,
        theta: &[f64],
        n: usize,
        p: usize,
        order: &[usize],
        targets: &[&[f64]],
    ) -> Result<Self> {
        assert_eq!(theta.len(), n * p, "matrix storage does not match shape");
        Self::factorise(case, n, p, order, targets, Some(theta), |_, _| {})
    }

    /// The factorisation behind [`CaseFactor::from_row_blocks`] (`held` = None) and
    /// [`CaseFactor::from_columns`] (Θ in `held`; `fill` unused).
    #[track_caller]
    fn factorise(
        case: &str,
        n: usize,
        p: usize,
        order: &[usize],
        targets: &[&[f64]],
        held: Option<&[f64]>,
        mut fill: impl FnMut(usize, MatMut<'_, f64>),
    ) -> Result<Self> {
        assert_eq!(order.len(), p, "priority order must cover every column");
        let mut pos = vec![usize::MAX; p];
        for (k, &j) in order.iter().enumerate() {
            assert!(j < p && pos[j] == usize::MAX, "order is not a permutation");
            pos[j] = k;
        }
        for t in targets {
            assert_eq!(t.len(), n, "target length differs from the library rows");
        }
        let nt = targets.len();
        if n < p + nt {
            return Err(Error::InvalidData {
                case: case.to_string(),
                field: "samples".to_string(),
                message: format!(
                    "{n} samples cannot determine {p} library coefficients (need at least {})",
                    p + nt
                ),
            });
        }
        let ncols = p + nt;
        let bs = ROW_BLOCK.max(2 * ncols);
        // rows per call of `fill`: a multiple of the factorisation block
        let chunk = bs * (FILL_BLOCK / bs).max(1);
        let mut block = Scratch::zeroed(if held.is_some() { 0 } else { chunk * p });
        // Calls `visit(r0, rows, src, ld)` with Θ's rows r0..r0+rows, column j at
        // src[j*ld..j*ld + rows] (the block buffer, or the held matrix in place).
        let mut blocks = |visit: &mut BlockVisitor<'_>| {
            let mut r0 = 0;
            while r0 < n {
                let rows = chunk.min(n - r0);
                match held {
                    Some(t) => visit(r0, rows, &t[r0..], n),
                    None => {
                        let buf = &mut block[..rows * p];
                        fill(r0, MatMut::from_column_major_slice_mut(buf, rows, p));
                        visit(r0, rows, buf, rows);
                    }
                }
                r0 += rows;
            }
        };
        // Column norms, accumulated in row order (the same sums as over the whole column).
        let mut sums = vec![0.0; p];
        // first row at which a column's value or its running sum of squares is not finite
        let mut first_bad: Vec<Option<usize>> = vec![None; p];
        blocks(&mut |r0, rows, buf, ld| {
            // Four columns at a time, row by row: four independent chains of additions
            // (each column's sum still runs in row order, so the same numbers), the
            // finiteness checked once per block and the block replayed only for a column
            // that became non-finite in it.
            let before = sums.clone();
            let mut j = 0;
            while j + 4 <= p {
                let c = |k: usize| &buf[(j + k) * ld..(j + k) * ld + rows];
                let (c0, c1, c2, c3) = (c(0), c(1), c(2), c(3));
                let mut acc = [sums[j], sums[j + 1], sums[j + 2], sums[j + 3]];
                for i in 0..rows {
                    acc[0] += c0[i] * c0[i];
                    acc[1] += c1[i] * c1[i];
                    acc[2] += c2[i] * c2[i];
                    acc[3] += c3[i] * c3[i];
                }
                sums[j..j + 4].copy_from_slice(&acc);
                j += 4;
            }
            for (jj, s) in sums.iter_mut().enumerate().skip(j) {
                for v in &buf[jj * ld..jj * ld + rows] {
                    *s += v * v;
                }
            }
            for (jj, s) in sums.iter().enumerate() {
                if first_bad[jj].is_none() && !s.is_finite() {
                    let mut t = before[jj];
                    for (i, v) in buf[jj * ld..jj * ld + rows].iter().enumerate() {
                        t += v * v;
                        if !t.is_finite() {
                            first_bad[jj] = Some(r0 + i);
                            break;
                        }
                    }
                }
            }
        });
        let mut scales = vec![1.0; p];
        let mut zero_column = vec![false; p];
        for (j, &s) in sums.iter().enumerate() {
            if !s.is_finite() {
                return Err(Error::InvalidData {
                    case: case.to_string(),
                    field: "library".to_string(),
                    message: format!(
                        "library column {j} (library term order) is not finite or overflows \
                         its sum of squares at sample {} (row {} of the case file when the \
                         record was not trimmed, header on line 1)",
                        first_bad[j].unwrap_or(0),
                        first_bad[j].unwrap_or(0) + 2
                    ),
                });
            }
            if s > 0.0 {
                scales[j] = s.sqrt();
            } else {
                zero_column[j] = true;
            }
        }
        let mut stats = Vec::with_capacity(nt);
        for (t, y) in targets.iter().enumerate() {
            let mut norm2 = 0.0;
            let mut sum = 0.0;
            for v in y.iter() {
                norm2 += v * v;
                sum += v;
            }
            if !norm2.is_finite() {
                return Err(Error::InvalidData {
                    case: case.to_string(),
                    field: "target".to_string(),
                    message: format!("target {t} holds a non-finite value"),
                });
            }
            stats.push((norm2, sum / n as f64));
        }
        // Row-blocked ("TSQR") factorisation: each block of rows is triangularised in a
        // cache-resident buffer (reflectors on every column, targets included, so nothing
        // of a block is lost but its zero rows), the triangles are stacked and the stack is
        // factorised again. Same R and Qᵀy as one factorisation of the whole matrix, at
        // about twice the speed for 5120 × 32 (the whole matrix does not stay in cache).
        // A full stack of STACK_BLOCKS triangles is reduced to one triangle (bounded
        // memory for long records).
        let nblocks = n / bs;
        let rem = n - nblocks * bs;
        let inv: Vec<f64> = scales.iter().map(|s| 1.0 / s).collect();
        // copies Θ_s rows (block rows i0..i0+rows, global r0+i0..) and the targets into
        // dst (leading dimension ld, starting at row off)
        let copy = |dst: &mut [f64],
                    ld: usize,
                    off: usize,
                    src: &[f64],
                    src_ld: usize,
                    r0: usize,
                    i0: usize,
                    rows: usize| {
            for (k, &j) in order.iter().enumerate() {
                let col = &src[j * src_ld + i0..j * src_ld + i0 + rows];
                for (d, v) in dst[k * ld + off..k * ld + off + rows].iter_mut().zip(col) {
                    *d = v * inv[j];
                }
            }
            for (t, y) in targets.iter().enumerate() {
                dst[(p + t) * ld + off..(p + t) * ld + off + rows]
                    .copy_from_slice(&y[r0 + i0..r0 + i0 + rows]);
            }
        };
        // the stack holds at most STACK_BLOCKS triangles; a shorter record needs (and
        // zeroes) only the rows of its own blocks (its stack is never reduced in place)
        let sm = STACK_BLOCKS.min(nblocks.max(1)) * ncols;
        let mut stack = Scratch::zeroed(sm * ncols);
        let mut stacked = 0usize;
        // `copy` writes every value of these
        let mut buf = Scratch::overwritten(bs * ncols);
        let mut tail = Scratch::overwritten(rem * ncols);
        blocks(&mut |r0, rows, src, src_ld| {
            let mut i0 = 0;
            while i0 + bs <= rows {
                copy(&mut buf, bs, 0, src, src_ld, r0, i0, bs);
                crate::numerics::qr::householder_qr(&mut buf, bs, ncols, ncols);
                if stacked == STACK_BLOCKS {
                    crate::numerics::qr::householder_qr(&mut stack, sm, ncols, ncols);
                    for c in 0..ncols {
                        let col = &mut stack[c * sm..(c + 1) * sm];
                        col[c + 1..].fill(0.0);
                    }
                    stacked = 1;
                }
                for c in 0..ncols {
                    for i in 0..=c {
                        stack[c * sm + stacked * ncols + i] = buf[c * bs + i];
                    }
                }
                stacked += 1;
                i0 += bs;
            }
            if i0 < rows {
                // the last rows of the record (fewer than a block)
                copy(&mut tail, rem, 0, src, src_ld, r0, i0, rows - i0);
            }
        });
        let m = stacked * ncols + rem;
        let mut a = Scratch::zeroed(m * ncols);
        for c in 0..ncols {
            for b in 0..stacked {
                for i in 0..=c {
                    a[c * m + b * ncols + i] = stack[c * sm + b * ncols + i];
                }
            }
            a[c * m + stacked * ncols..(c + 1) * m].copy_from_slice(&tail[c * rem..(c + 1) * rem]);
        }
        drop(stack);
        crate::numerics::qr::householder_qr(&mut a, m, ncols, p);
        let r = Upper::from_fn(p, |i, j| a[j * m + i]);
        let targets: Vec<TargetFactor> = (0..nt)
            .map(|t| {
                let col = &a[(p + t) * m..(p + t + 1) * m];
                TargetFactor {
                    qty: col[..p].to_vec(),
                    rss_perp: col[p..].iter().map(|v| v * v).sum(),
                    norm2: stats[t].0,
                    mean: stats[t].1,
                    n,
                }
            })
            .collect();
        let gram_rhs = targets
            .iter()
            .map(|t: &TargetFactor| {
                (0..p)
                    .map(|j| (0..=j).map(|k| r[(k, j)] * t.qty[k]).sum())
                    .collect()
            })
            .collect();
        Ok(CaseFactor {
            n,
            order: order.to_vec(),
            pos,
            scales,
            zero_column,
            r,
            targets,
            gram_rhs,
        })
    }

    /// Number of library columns p.
    pub fn n_columns(&self) -> usize {
        self.order.len()
    }

    /// Entry (a, b) of the Gram matrix RᵀR = Θ_sᵀΘ_s (priority positions; symmetric):
    /// Σ_{k ≤ min(a, b)} R_ka R_kb, computed from R when asked (not held: it would double
    /// the factor's memory), always in this order, so always the same number.
    ///
    /// # Panics
    /// When a position is ≥ p (a programming error).
    #[track_caller]
    pub fn gram(&self, a: usize, b: usize) -> f64 {
        let (i, j) = if a <= b { (a, b) } else { (b, a) };
        // R_ki R_kj for k = 0 … i, summed in that order (column slices: no index checks)
        let (ci, cj) = (self.r.col(i), &self.r.col(j)[..=i]);
        ci.iter().zip(cj).map(|(x, y)| x * y).sum()
    }

    /// Least-squares (or ridge, `ridge > 0`, on the column-normalised matrix) fit of target
    /// `t` on the library columns `support` (library indices, any order). Returns the
    /// scaled coefficients (one per support entry, in the order given: coefficient of the
    /// column-normalised term) and the residual sum of squares ‖Θ ξ − y‖².
    ///
    /// # Panics
    /// When `t` or a column index is out of range (programming errors).
    #[track_caller]
    pub fn fit(&self, t: usize, support: &[usize], ridge: f64) -> (Vec<f64>, f64) {
        let tf = &self.targets[t];
        if support.is_empty() {
            return (Vec::new(), tf.norm2);
        }
        // order the support by priority position so that the sub-block is as triangular as
        // possible, then keep only the rows that can be nonzero
        let mut cols: Vec<(usize, usize)> = support
            .iter()
            .enumerate()
            .map(|(i, &j)| (self.pos[j], i))
            .collect();
        cols.sort_unstable();
        let m = cols.last().map(|c| c.0 + 1).unwrap_or(0);
        let q = cols.len();
        let mut a = vec![0.0; m * q];
        for (c, &(k, _)) in cols.iter().enumerate() {
            a[c * m..c * m + k + 1].copy_from_slice(self.r.col(k));
        }
        let (x, rss_rows) = crate::numerics::qr::lstsq(&a, m, q, &tf.qty[..m], ridge);
        let tail: f64 = tf.qty[m..].iter().map(|v| v * v).sum();
        let mut out = vec![0.0; q];
        for (c, &(_, i)) in cols.iter().enumerate() {
            out[i] = x[c];
        }
        (out, rss_rows + tail + tf.rss_perp)
    }
}

impl CaseFactor {
    /// Fast fit for the δ path: solves the normal equations (Θ_sᵀΘ_s + λI) ξ = Θ_sᵀy on
    /// `support` by Cholesky of the Gram sub-matrix (q³/3 flops instead of the QR's
    /// 2pq²). Returns the scaled coefficients in the order of `support`, or `None` when the
    /// Cholesky factorisation meets a pivot below 1e-13 of the diagonal (condition number
    /// beyond ~3·10⁶, where the squared conditioning of the normal equations would cost
    /// accuracy): use [`CaseFactor::fit`] then.
    ///
    /// # Panics
    /// When `t` or a column index is out of range (programming errors).
    #[track_caller]
    pub fn fit_gram(&self, t: usize, support: &[usize], ridge: f64) -> Option<Vec<f64>> {
        let q = support.len();
        let b = &self.gram_rhs[t];
        let k: Vec<usize> = support.iter().map(|&j| self.pos[j]).collect();
        let mut l = vec![0.0; q * q];
        for i in 0..q {
            for j in 0..=i {
                l[i * q + j] = self.gram(k[i], k[j]) + if i == j { ridge } else { 0.0 };
            }
        }
        cholesky_in_place(&mut l, q, PivotFloor::RelativeToDiagonal(1e-13)).ok()?;
        let mut x: Vec<f64> = k.iter().map(|&kk| b[kk]).collect();
        cholesky_solve_in_place(&l, q, &mut x);
        Some(x)
    }

    /// Residual sum of squares ‖Θ_s[:, support] ξ_s − y‖² of target `t` for given scaled
    /// coefficients (any ξ, not only the least-squares one), computed on the factor.
    ///
    /// # Panics
    /// When the lengths differ or an index is out of range (programming errors).
    #[track_caller]
    pub fn rss_of(&self, t: usize, support: &[usize], scaled: &[f64]) -> f64 {
        assert_eq!(
            support.len(),
            scaled.len(),
            "one coefficient per support term"
        );
        let tf = &self.targets[t];
        let mut r = tf.qty.iter().map(|v| -v).collect::<Vec<f64>>();
        for (&j, &c) in support.iter().zip(scaled) {
            let k = self.pos[j];
            for (ri, rik) in r.iter_mut().zip(self.r.col(k)) {
                *ri += rik * c;
            }
        }
        r.iter().map(|v| v * v).sum::<f64>() + tf.rss_perp
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduced_fit_equals_direct_least_squares() {
        // Θ with 3 columns, y = 2 θ0 − θ2 + small residual
        let n = 50;
        let mut theta = Mat::<f64>::zeros(n, 3);
        let mut y = vec![0.0; n];
        for i in 0..n {
            let t = i as f64 * 0.1;
            theta[(i, 0)] = t.sin();
            theta[(i, 1)] = 10.0 * t.cos();
            theta[(i, 2)] = 0.01 * t * t;
            y[i] = 2.0 * theta[(i, 0)] - theta[(i, 2)] + 0.05 * (3.7 * t).sin();
        }
        let f = CaseFactor::new("c", theta.as_ref(), &[2, 0, 1], &[&y]).unwrap();
        let (xs, rss) = f.fit(0, &[0, 2], 0.0);
        // direct normal equations on the raw columns
        let g = |a: usize, b: usize| (0..n).map(|i| theta[(i, a)] * theta[(i, b)]).sum::<f64>();
        let gy = |a: usize| (0..n).map(|i| theta[(i, a)] * y[i]).sum::<f64>();
        let det = g(0, 0) * g(2, 2) - g(0, 2) * g(0, 2);
        let x0 = (g(2, 2) * gy(0) - g(0, 2) * gy(2)) / det;
        let x2 = (g(0, 0) * gy(2) - g(0, 2) * gy(0)) / det;
        assert!(
            (xs[0] / f.scales[0] - x0).abs() < 1e-10,
            "{} {}",
            xs[0] / f.scales[0],
            x0
        );
        assert!((xs[1] / f.scales[2] - x2).abs() < 1e-9);
        let direct: f64 = (0..n)
            .map(|i| (x0 * theta[(i, 0)] + x2 * theta[(i, 2)] - y[i]).powi(2))
            .sum();
        assert!(
            (rss - direct).abs() < 1e-10 * direct.max(1e-12),
            "{rss} {direct}"
        );
        let xg = f.fit_gram(0, &[2, 0], 0.0).unwrap();
        assert!((xg[1] - xs[0]).abs() < 1e-9 && (xg[0] - xs[1]).abs() < 1e-9);
        assert!((f.rss_of(0, &[0, 2], &xs) - rss).abs() < 1e-10 * rss);
        let (_, rss_empty) = f.fit(0, &[], 0.0);
        assert!((rss_empty - y.iter().map(|v| v * v).sum::<f64>()).abs() < 1e-10);
    }

    /// A record longer than `STACK_BLOCKS` factorisation blocks (the stack is reduced
    /// twice) with a remainder of rows: the Gram matrix, Θ_sᵀy, r⊥² and the least-squares
    /// fit agree with direct accumulation over the rows to 1e-12 relative, and blocks
    /// given by `fill` and the held matrix read in place equal the whole-matrix constructor.
    #[test]
    fn stack_reduction_matches_direct_normal_equations() {
        let n = 2 * STACK_BLOCKS * ROW_BLOCK + 3 * ROW_BLOCK + 77;
        let p = 4;
        let theta = Mat::<f64>::from_fn(n, p, |i, j| {
            let t = i as f64 * 0.002;
            match j {
                0 => t.sin(),
                1 => 3.0 * (1.7 * t).cos(),
                2 => 0.1 * (t * 0.3).sin().powi(2),
                _ => 1.0,
            }
        });
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * 0.002;
                0.5 * theta[(i, 0)] - 2.0 * theta[(i, 2)] + 0.3 + 0.01 * (7.3 * t).sin()
            })
            .collect();
        let order = [3, 1, 0, 2];
        let f = CaseFactor::new("c", theta.as_ref(), &order, &[&y]).unwrap();
        let g = CaseFactor::from_row_blocks("c", n, p, &order, &[&y], |r0, mut out| {
            for i in 0..out.nrows() {
                for j in 0..p {
                    out[(i, j)] = theta[(r0 + i, j)];
                }
            }
        })
        .unwrap();
        assert_eq!(f.r, g.r);
        assert_eq!(f.targets, g.targets);
        // the held matrix read in place: the same numbers to the bit
        let held: Vec<f64> = (0..p)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .map(|(i, j)| theta[(i, j)])
            .collect();
        let h = CaseFactor::from_columns("c", &held, n, p, &order, &[&y]).unwrap();
        assert_eq!(f.r, h.r);
        assert_eq!(f.targets, h.targets);
        assert_eq!(f.scales, h.scales);
        // relative to `scale` (1 for the Gram matrix of unit columns, ‖y‖ for Θ_sᵀy)
        let close = |a: f64, b: f64, scale: f64, what: &str| {
            assert!((a - b).abs() <= 1e-12 * scale, "{what}: {a} vs {b}");
        };
        let ynorm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        // direct sums on the scaled columns, priority order
        let col = |k: usize, i: usize| theta[(i, order[k])] / f.scales[order[k]];
        for a in 0..p {
            close(
                f.scales[a],
                (0..n).map(|i| theta[(i, a)].powi(2)).sum::<f64>().sqrt(),
                f.scales[a],
                "scale",
            );
            for b in 0..p {
                let direct: f64 = (0..n).map(|i| col(a, i) * col(b, i)).sum();
                close(f.gram(a, b), direct, 1.0, "gram");
            }
            let direct: f64 = (0..n).map(|i| col(a, i) * y[i]).sum();
            close(f.gram_rhs[0][a], direct, ynorm, "gram_rhs");
        }
        // full least-squares fit: coefficients and residual
        let support = [0, 1, 2, 3];
        let (xs, rss) = f.fit(0, &support, 0.0);
        let raw: Vec<f64> = (0..p).map(|j| xs[j] / f.scales[j]).collect();
        for (j, want) in [(0, 0.5), (2, -2.0), (3, 0.3)] {
            assert!((raw[j] - want).abs() < 1e-2, "coefficient {j}: {}", raw[j]);
        }
        let direct: f64 = (0..n)
            .map(|i| ((0..p).map(|j| raw[j] * theta[(i, j)]).sum::<f64>() - y[i]).powi(2))
            .sum();
        assert!((rss - direct).abs() <= 1e-9 * direct, "{rss} vs {direct}");
        close(f.targets[0].rss_perp, rss, rss, "rss_perp");
    }

    #[test]
    fn packed_triangle_reads_as_the_dense_one() {
        let u = Upper::from_fn(3, |i, j| (10 * i + j) as f64 + 1.0);
        let d = u.to_mat();
        for i in 0..3 {
            for j in 0..3 {
                let want = if i <= j {
                    (10 * i + j) as f64 + 1.0
                } else {
                    0.0
                };
                assert_eq!(u[(i, j)], want);
                assert_eq!(d[(i, j)], want);
                assert_eq!(u.sym(i, j), u.sym(j, i));
            }
        }
        assert_eq!(u.order(), 3);
        assert_eq!(u.col(2), &[3.0, 13.0, 23.0]);
        assert!(std::panic::catch_unwind(|| u[(3, 0)]).is_err());
    }

    #[test]
    fn too_few_samples_is_an_error() {
        let theta = Mat::<f64>::zeros(3, 3);
        let y = vec![0.0; 3];
        let e = CaseFactor::new("X-1", theta.as_ref(), &[0, 1, 2], &[&y]).unwrap_err();
        assert!(e.to_string().contains("X-1"), "{e}");
    }
}
