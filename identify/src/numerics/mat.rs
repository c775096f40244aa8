//! A dense column-major `f64` matrix and its borrowed views, with the few products and the
//! singular value decomposition the workspace needs: Θ of a case (n samples × p library
//! terms), ΘᵀΘ and Θᵀy, and the singular values of small matrices.
//!
//! Own code in place of a linear-algebra crate: the general one this replaced compiled its
//! matrix-multiply kernels for four scalar types, about 130 unit-seconds of every fresh
//! build, for products of at most a few hundred columns (docs/DECISIONS.md, "faer
//! replaced by a small matrix module", round 43).
//!
//! Storage: column j of an `nrows × ncols` matrix is `data[j·cs .. j·cs + nrows]` (`cs` the
//! column stride, `nrows` for an owned matrix; a view of some rows keeps its parent's).

use std::ops::{Index, IndexMut};

/// An owned `nrows × ncols` matrix of `T`, column-major (only `T = f64` has methods).
#[derive(Debug, Clone, PartialEq)]
pub struct Mat<T> {
    data: Vec<T>,
    nrows: usize,
    ncols: usize,
}

/// A borrowed, read-only view of a column-major matrix (possibly some rows of a larger one).
#[derive(Debug, Clone, Copy)]
pub struct MatRef<'a, T> {
    data: &'a [T],
    nrows: usize,
    ncols: usize,
    cs: usize,
}

/// A borrowed, writable view of a column-major matrix (possibly some rows of a larger one).
#[derive(Debug)]
pub struct MatMut<'a, T> {
    data: &'a mut [T],
    nrows: usize,
    ncols: usize,
    cs: usize,
}

/// The slice length a view of `nrows × ncols` with column stride `cs` needs.
fn span(nrows: usize, ncols: usize, cs: usize) -> usize {
    if nrows == 0 || ncols == 0 {
        0
    } else {
        (ncols - 1) * cs + nrows
    }
}

impl Mat<f64> {
    /// The `nrows × ncols` zero matrix.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            data: vec![0.0; nrows * ncols],
            nrows,
            ncols,
        }
    }

    /// The `nrows × ncols` matrix with entry (i, j) = `f(i, j)`, filled column by column.
    pub fn from_fn(nrows: usize, ncols: usize, mut f: impl FnMut(usize, usize) -> f64) -> Self {
        let mut data = Vec::with_capacity(nrows * ncols);
        for j in 0..ncols {
            for i in 0..nrows {
                data.push(f(i, j));
            }
        }
        Self { data, nrows, ncols }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// (rows, columns).
    pub fn shape(&self) -> (usize, usize) {
        (self.nrows, self.ncols)
    }

    /// Column `j` as a slice.
    ///
    /// # Panics
    /// When `j ≥ ncols`.
    pub fn col(&self, j: usize) -> &[f64] {
        assert!(j < self.ncols, "column {j} of {}", self.ncols);
        &self.data[j * self.nrows..(j + 1) * self.nrows]
    }

    /// Column `j` as a writable slice.
    ///
    /// # Panics
    /// When `j ≥ ncols`.
    pub fn col_mut(&mut self, j: usize) -> &mut [f64] {
        assert!(j < self.ncols, "column {j} of {}", self.ncols);
        &mut self.data[j * self.nrows..(j + 1) * self.nrows]
    }

    /// A read-only view of the whole matrix.
    pub fn as_ref(&self) -> MatRef<'_, f64> {
        MatRef {
            data: &self.data,
            nrows: self.nrows,
            ncols: self.ncols,
            cs: self.nrows,
        }
    }

    /// A writable view of the whole matrix.
    pub fn as_mut(&mut self) -> MatMut<'_, f64> {
        MatMut {
            nrows: self.nrows,
            ncols: self.ncols,
            cs: self.nrows,
            data: &mut self.data,
        }
    }
}

impl Index<(usize, usize)> for Mat<f64> {
    type Output = f64;
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        assert!(
            i < self.nrows && j < self.ncols,
            "entry ({i}, {j}) out of bounds"
        );
        &self.data[j * self.nrows + i]
    }
}

impl IndexMut<(usize, usize)> for Mat<f64> {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        assert!(
            i < self.nrows && j < self.ncols,
            "entry ({i}, {j}) out of bounds"
        );
        &mut self.data[j * self.nrows + i]
    }
}

impl<'a> MatRef<'a, f64> {
    /// The `nrows × ncols` matrix stored column by column in `data`.
    ///
    /// # Panics
    /// When `data.len() != nrows · ncols`.
    #[track_caller]
    pub fn from_column_major_slice(data: &'a [f64], nrows: usize, ncols: usize) -> Self {
        assert_eq!(data.len(), nrows * ncols, "matrix view: slice length");
        Self {
            data,
            nrows,
            ncols,
            cs: nrows,
        }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// (rows, columns).
    pub fn shape(&self) -> (usize, usize) {
        (self.nrows, self.ncols)
    }

    /// Column `j` as a slice.
    ///
    /// # Panics
    /// When `j ≥ ncols`.
    pub fn col(self, j: usize) -> &'a [f64] {
        assert!(j < self.ncols, "column {j} of {}", self.ncols);
        &self.data[j * self.cs..j * self.cs + self.nrows]
    }

    /// Rows `r0 .. r0 + rows` of every column.
    ///
    /// # Panics
    /// When the rows are out of bounds.
    pub fn subrows(self, r0: usize, rows: usize) -> Self {
        assert!(
            r0 + rows <= self.nrows,
            "rows {r0}..{} of {}",
            r0 + rows,
            self.nrows
        );
        let start = r0.min(self.data.len());
        Self {
            data: &self.data[start..start + span(rows, self.ncols, self.cs)],
            nrows: rows,
            ncols: self.ncols,
            cs: self.cs,
        }
    }

    /// An owned copy.
    pub fn to_owned(self) -> Mat<f64> {
        Mat::from_fn(self.nrows, self.ncols, |i, j| self[(i, j)])
    }
}

impl Index<(usize, usize)> for MatRef<'_, f64> {
    type Output = f64;
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        assert!(
            i < self.nrows && j < self.ncols,
            "entry ({i}, {j}) out of bounds"
        );
        &self.data[j * self.cs + i]
    }
}

impl<'a> MatMut<'a, f64> {
    /// The `nrows × ncols` matrix stored column by column in `data`, writable.
    ///
    /// # Panics
    /// When `data.len() != nrows · ncols`.
    #[track_caller]
    pub fn from_column_major_slice_mut(data: &'a mut [f64], nrows: usize, ncols: usize) -> Self {
        assert_eq!(data.len(), nrows * ncols, "matrix view: slice length");
        Self {
            data,
            nrows,
            ncols,
            cs: nrows,
        }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// A shorter-lived writable view of the same entries.
    pub fn as_mut(&mut self) -> MatMut<'_, f64> {
        MatMut {
            data: self.data,
            nrows: self.nrows,
            ncols: self.ncols,
            cs: self.cs,
        }
    }

    /// A read-only view of the same entries.
    pub fn as_ref(&self) -> MatRef<'_, f64> {
        MatRef {
            data: self.data,
            nrows: self.nrows,
            ncols: self.ncols,
            cs: self.cs,
        }
    }

    /// Column `j` as a writable slice.
    ///
    /// # Panics
    /// When `j ≥ ncols`.
    pub fn col_mut(self, j: usize) -> &'a mut [f64] {
        assert!(j < self.ncols, "column {j} of {}", self.ncols);
        &mut self.data[j * self.cs..j * self.cs + self.nrows]
    }

    /// Rows `r0 .. r0 + rows` of every column, writable.
    ///
    /// # Panics
    /// When the rows are out of bounds.
    pub fn subrows_mut(self, r0: usize, rows: usize) -> Self {
        assert!(
            r0 + rows <= self.nrows,
            "rows {r0}..{} of {}",
            r0 + rows,
            self.nrows
        );
        let start = r0.min(self.data.len());
        let len = span(rows, self.ncols, self.cs);
        Self {
            data: &mut self.data[start..start + len],
            nrows: rows,
            ncols: self.ncols,
            cs: self.cs,
        }
    }

    /// Columns `c0 .. c0 + cols`, writable.
    ///
    /// # Panics
    /// When the columns are out of bounds.
    pub fn subcols_mut(self, c0: usize, cols: usize) -> Self {
        assert!(
            c0 + cols <= self.ncols,
            "columns {c0}..{} of {}",
            c0 + cols,
            self.ncols
        );
        let start = (c0 * self.cs).min(self.data.len());
        let len = span(self.nrows, cols, self.cs);
        Self {
            data: &mut self.data[start..start + len],
            nrows: self.nrows,
            ncols: cols,
            cs: self.cs,
        }
    }

    /// Overwrites every entry with the same-shaped `src`.
    ///
    /// # Panics
    /// When the shapes differ.
    #[track_caller]
    pub fn copy_from(&mut self, src: MatRef<'_, f64>) {
        assert_eq!(
            (self.nrows, self.ncols),
            (src.nrows, src.ncols),
            "copy between matrices of different shapes"
        );
        for j in 0..self.ncols {
            self.data[j * self.cs..j * self.cs + self.nrows].copy_from_slice(src.col(j));
        }
    }
}

impl Index<(usize, usize)> for MatMut<'_, f64> {
    type Output = f64;
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        assert!(
            i < self.nrows && j < self.ncols,
            "entry ({i}, {j}) out of bounds"
        );
        &self.data[j * self.cs + i]
    }
}

impl IndexMut<(usize, usize)> for MatMut<'_, f64> {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        assert!(
            i < self.nrows && j < self.ncols,
            "entry ({i}, {j}) out of bounds"
        );
        &mut self.data[j * self.cs + i]
    }
}

/// Partial sums per dot product: lane l sums the products of the entries i ≡ l (mod 8),
/// then the lanes are added as ((l0 + l4) + (l2 + l6)) + ((l1 + l5) + (l3 + l7)), then the
/// tail in order. Every product
/// of this module uses this one order, so [`add_at_b`] and [`at_a`] give [`dot`]'s value
/// bit for bit, on any CPU.
const LANES: usize = 8;

/// `Σ_i a_i b_i` over the common length of the slices: eight partial sums (lane l sums the
/// products of the entries i ≡ l mod 8), added as ((l0 + l4) + (l2 + l6)) + ((l1 + l5) +
/// (l3 + l7)), then the tail in order. Kept beside [`crate::numerics::qr::dot`] (sixteen
/// lanes) because [`add_at_b`] must equal this order bit for bit, tile by tile.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let full = n / LANES * LANES;
    let mut acc = [[[0.0f64; LANES]; 1]; 1];
    lanes::<1, 1>(&mut acc, [&a[..full]], [&b[..full]]);
    finish(&acc[0][0], &a[full..n], &b[full..n])
}

/// The eight lanes of one product reduced in the order of [`LANES`], then the tail.
#[inline(always)]
fn finish(c: &[f64; LANES], ta: &[f64], tb: &[f64]) -> f64 {
    let mut s = ((c[0] + c[4]) + (c[2] + c[6])) + ((c[1] + c[5]) + (c[3] + c[7]));
    for (x, y) in ta.iter().zip(tb) {
        s += x * y;
    }
    s
}

/// Adds to the lanes of the A × B products of the columns `a` with the columns `b` (all
/// of one length, a multiple of [`LANES`]) in one pass over the rows: each chunk of a
/// column is loaded once for all the products it enters.
#[inline(always)]
fn lanes<const A: usize, const B: usize>(
    acc: &mut [[[f64; LANES]; B]; A],
    a: [&[f64]; A],
    b: [&[f64]; B],
) {
    let full = a.first().map_or(0, |c| c.len());
    let xa: [&[f64]; A] = std::array::from_fn(|k| &a[k][..full]);
    let xb: [&[f64]; B] = std::array::from_fn(|k| &b[k][..full]);
    let mut o = 0;
    while o + LANES <= full {
        let ys: [[f64; LANES]; B] = std::array::from_fn(|q| {
            let mut y = [0.0; LANES];
            y.copy_from_slice(&xb[q][o..o + LANES]);
            y
        });
        for (ac, col) in acc.iter_mut().zip(&xa) {
            let mut x = [0.0; LANES];
            x.copy_from_slice(&col[o..o + LANES]);
            for (aq, y) in ac.iter_mut().zip(&ys) {
                for l in 0..LANES {
                    aq[l] += x[l] * y[l];
                }
            }
        }
        o += LANES;
    }
}

/// Rows per tile of [`add_at_b`]: 256 rows of the columns of one block stay in the core's
/// L1 cache while every pair of the block is accumulated.
const TILE: usize = 256;

/// `acc += aᵀ b`: entry (i, j) gains the eight-lane dot product of column i of `a` and column j of `b` (`a`
/// and `b` with the same rows), bit for bit: the same lanes, updated in the same row order,
/// only visited tile by tile (256 rows, several columns of `a` by several of `b` per pass).
///
/// # Panics
/// When the shapes disagree.
#[track_caller]
pub fn add_at_b(acc: &mut MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    assert_eq!(a.nrows, b.nrows, "aᵀb: row counts");
    assert_eq!(
        (acc.nrows, acc.ncols),
        (a.ncols, b.ncols),
        "aᵀb: result shape"
    );
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above).
            return unsafe { add_at_b_avx512(acc, a, b) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { add_at_b_avx2(acc, a, b) };
        }
    }
    add_at_b_body::<2, 2>(acc, a, b);
}

/// [`add_at_b_body`] compiled with AVX-512F: sixteen products of four columns by four, one
/// register of eight lanes each. The same IEEE operations in the same order on every path
/// (Rust never fuses a multiply and an add), so the same values on any CPU.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn add_at_b_avx512(acc: &mut MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    add_at_b_body::<4, 4>(acc, a, b);
}

/// [`add_at_b_body`] compiled with AVX2 (the release profile targets baseline x86-64): two
/// columns by two, two registers of four lanes each.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn add_at_b_avx2(acc: &mut MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    add_at_b_body::<2, 2>(acc, a, b);
}

/// Tile by tile of rows, the products `W` columns of `a` by `V` of `b` at a time (4 × 4 or
/// 2 × 2; narrower blocks at the edges), each product's lanes kept between tiles.
#[inline(always)]
fn add_at_b_body<const W: usize, const V: usize>(
    acc: &mut MatMut<'_, f64>,
    a: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
) {
    let (n, p, q) = (a.nrows, a.ncols, b.ncols);
    let full = n / LANES * LANES;
    let mut lane = vec![[0.0f64; LANES]; p * q];
    let mut r0 = 0;
    while r0 < full {
        let r1 = (r0 + TILE).min(full);
        let mut j = 0;
        while j < q {
            let jw = match (q - j).min(V) {
                3 => 2,
                w => w,
            };
            let mut i = 0;
            while i < p {
                let iw = (p - i).min(W);
                macro_rules! block {
                    ($na:literal, $nb:literal) => {{
                        let mut ac: [[[f64; LANES]; $nb]; $na] = std::array::from_fn(|k| {
                            std::array::from_fn(|l| lane[(j + l) * p + i + k])
                        });
                        lanes::<$na, $nb>(
                            &mut ac,
                            std::array::from_fn(|k| &a.col(i + k)[r0..r1]),
                            std::array::from_fn(|k| &b.col(j + k)[r0..r1]),
                        );
                        for (k, row) in ac.iter().enumerate() {
                            for (l, v) in row.iter().enumerate() {
                                lane[(j + l) * p + i + k] = *v;
                            }
                        }
                        $na
                    }};
                }
                i += match (iw, jw) {
                    // `jw` is 4, 2 or 1, and every arm covers all `jw` columns of `b`
                    (4, 4) => block!(4, 4),
                    (4, 2) => block!(4, 2),
                    (4, _) => block!(4, 1),
                    (2, 4) => block!(2, 4),
                    (2, 2) => block!(2, 2),
                    (2, _) => block!(2, 1),
                    (_, 4) => block!(1, 4),
                    (_, 2) => block!(1, 2),
                    _ => block!(1, 1),
                };
            }
            j += jw;
        }
        r0 = r1;
    }
    for jj in 0..q {
        for ii in 0..p {
            let v = finish(&lane[jj * p + ii], &a.col(ii)[full..n], &b.col(jj)[full..n]);
            acc[(ii, jj)] += v;
        }
    }
}

/// `aᵀ a`, symmetric (each pair computed once, in the same order).
pub fn at_a(a: MatRef<'_, f64>) -> Mat<f64> {
    let p = a.ncols;
    let mut g = Mat::zeros(p, p);
    add_at_b(&mut g.as_mut(), a, a);
    g
}

/// `a aᵀ`, symmetric, accumulated column by column of `a`.
pub fn a_at(a: MatRef<'_, f64>) -> Mat<f64> {
    let n = a.nrows;
    let mut k = Mat::zeros(n, n);
    for c in 0..a.ncols {
        let col = a.col(c);
        for j in 0..n {
            let x = col[j];
            for i in j..n {
                k[(i, j)] += col[i] * x;
            }
        }
    }
    for j in 0..n {
        for i in j + 1..n {
            k[(j, i)] = k[(i, j)];
        }
    }
    k
}

/// `aᵀ y` for a column `y` of `a`'s rows.
///
/// # Panics
/// When `y` is not of `a`'s row count.
#[track_caller]
pub fn at_y(a: MatRef<'_, f64>, y: &[f64]) -> Vec<f64> {
    assert_eq!(a.nrows, y.len(), "aᵀy: lengths");
    (0..a.ncols).map(|j| dot(a.col(j), y)).collect()
}

/// Thin singular value decomposition `a = U diag(s) Vᵀ` (U: n × r, V: p × r, r = min(n,
/// p)), singular values descending, by one-sided Jacobi rotations (Hestenes) on the
/// columns of `a` (of `aᵀ` when it has more columns than rows): rotations are applied
/// until every pair of columns is orthogonal to `n·ε` relative, so the singular values
/// carry high relative accuracy.
///
/// Returns `None` when an entry is not finite or the sweeps do not converge (60 sweeps).
pub fn thin_svd(a: MatRef<'_, f64>) -> Option<(Mat<f64>, Vec<f64>, Mat<f64>)> {
    let (n, p) = (a.nrows, a.ncols);
    if n < p {
        let at = Mat::from_fn(p, n, |i, j| a[(j, i)]);
        let (u, s, v) = thin_svd(at.as_ref())?;
        return Some((v, s, u));
    }
    let (w, norms, v) = jacobi(a, true)?;
    let mut order: Vec<usize> = (0..p).collect();
    order.sort_by(|&x, &y| norms[y].total_cmp(&norms[x]));
    let s: Vec<f64> = order.iter().map(|&j| norms[j]).collect();
    let u = Mat::from_fn(n, p, |i, c| {
        let j = order[c];
        if norms[j] > 0.0 {
            w[(i, j)] / norms[j]
        } else {
            0.0
        }
    });
    let vs = Mat::from_fn(p, p, |i, c| v[(i, order[c])]);
    Some((u, s, vs))
}

/// One-sided Jacobi on the columns of `a` (n ≥ p): the rotated columns W = A V, their
/// norms (the singular values, unordered) and V when `vectors` (else an empty matrix).
/// Each sweep starts from exact squared norms and updates them by the rotations (α' = α −
/// tγ, β' = β + tγ), so a pair costs one dot product.
fn jacobi(a: MatRef<'_, f64>, vectors: bool) -> Option<(Mat<f64>, Vec<f64>, Mat<f64>)> {
    let p = a.ncols;
    if (0..p).any(|j| a.col(j).iter().any(|x| !x.is_finite())) {
        return None;
    }
    let mut w = a.to_owned();
    let mut v = if vectors {
        Mat::from_fn(p, p, |i, j| if i == j { 1.0 } else { 0.0 })
    } else {
        Mat::zeros(0, 0)
    };
    let tol = (a.nrows.max(1) as f64) * f64::EPSILON;
    let mut converged = p < 2;
    for _ in 0..60 {
        let mut sq: Vec<f64> = (0..p).map(|j| dot(w.col(j), w.col(j))).collect();
        let mut rotated = false;
        for j in 0..p {
            for k in j + 1..p {
                let (alpha, beta) = (sq[j], sq[k]);
                let gamma = dot(w.col(j), w.col(k));
                if gamma == 0.0 || gamma.abs() <= tol * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                rotate(&mut w, j, k, c, s);
                if vectors {
                    rotate(&mut v, j, k, c, s);
                }
                sq[j] = (alpha - t * gamma).max(0.0);
                sq[k] = beta + t * gamma;
            }
        }
        if !rotated {
            converged = true;
            break;
        }
    }
    if !converged {
        return None;
    }
    let norms = (0..p).map(|j| dot(w.col(j), w.col(j)).sqrt()).collect();
    Some((w, norms, v))
}

/// Columns j and k of `m` rotated: (x_j, x_k) ← (c x_j − s x_k, s x_j + c x_k).
fn rotate(m: &mut Mat<f64>, j: usize, k: usize, c: f64, s: f64) {
    let n = m.nrows;
    for i in 0..n {
        let (x, y) = (m.data[j * n + i], m.data[k * n + i]);
        m.data[j * n + i] = c * x - s * y;
        m.data[k * n + i] = s * x + c * y;
    }
}

/// Singular values of `a`, descending ([`thin_svd`] without the vectors' use).
///
/// # Errors
/// A message when an entry is not finite or the sweeps do not converge.
pub fn singular_values(a: MatRef<'_, f64>) -> Result<Vec<f64>, String> {
    if a.nrows == 0 || a.ncols == 0 {
        return Ok(Vec::new());
    }
    let at;
    let a = if a.nrows < a.ncols {
        at = Mat::from_fn(a.ncols, a.nrows, |i, j| a[(j, i)]);
        at.as_ref()
    } else {
        a
    };
    jacobi(a, false)
        .map(|(_, mut s, _)| {
            s.sort_by(|x, y| y.total_cmp(x));
            s
        })
        .ok_or_else(|| "singular value decomposition: non-finite entry or no convergence".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    }

    #[test]
    fn views_index_like_the_parent_and_products_match_loops() {
        let mut seed = 7;
        let a = Mat::from_fn(37, 5, |_, _| lcg(&mut seed));
        let b = Mat::from_fn(37, 3, |_, _| lcg(&mut seed));
        let sub = a.as_ref().subrows(4, 20);
        assert_eq!(sub.shape(), (20, 5));
        assert_eq!(sub[(3, 2)], a[(7, 2)]);
        assert_eq!(sub.col(4)[19], a[(23, 4)]);
        let mut acc = Mat::zeros(5, 3);
        add_at_b(&mut acc.as_mut(), a.as_ref(), b.as_ref());
        let g = at_a(a.as_ref());
        let k = a_at(a.as_ref());
        for i in 0..5 {
            for j in 0..3 {
                let d: f64 = (0..37).map(|r| a[(r, i)] * b[(r, j)]).sum();
                assert!((acc[(i, j)] - d).abs() < 1e-14, "{i} {j}");
            }
            for j in 0..5 {
                let d: f64 = (0..37).map(|r| a[(r, i)] * a[(r, j)]).sum();
                assert!((g[(i, j)] - d).abs() < 1e-14);
            }
        }
        let d: f64 = (0..5).map(|c| a[(3, c)] * a[(30, c)]).sum();
        assert!((k[(3, 30)] - d).abs() < 1e-14 && k[(3, 30)] == k[(30, 3)]);
        let mut m = Mat::zeros(6, 2);
        m.as_mut().subrows_mut(2, 3).col_mut(1)[0] = 4.0;
        assert_eq!(m[(2, 1)], 4.0);
        let mut t = m.clone();
        let src = Mat::from_fn(4, 2, |i, j| a[(i, j)]);
        t.as_mut().subrows_mut(1, 4).copy_from(src.as_ref());
        assert_eq!(t[(1, 0)], a[(0, 0)]);
        assert_eq!(t[(4, 1)], a[(3, 1)]);
        assert_eq!(t[(0, 0)], 0.0);
    }

    /// Every block shape, several tiles and a tail: each entry is `dot`'s value bit for bit
    /// (the tiles keep each product's lanes and their order), and `dot` is the plain sum to
    /// rounding.
    #[test]
    fn tiled_products_are_dot_bit_for_bit_across_tiles_and_tails() {
        let mut seed = 3;
        for (n, p, q) in [
            (1003, 7, 5),
            (512, 4, 4),
            (9, 3, 1),
            (2050, 1, 6),
            (7, 2, 3),
        ] {
            let a = Mat::from_fn(n, p, |_, _| lcg(&mut seed));
            let b = Mat::from_fn(n, q, |_, _| lcg(&mut seed));
            let mut acc = Mat::from_fn(p, q, |i, j| (i + 2 * j) as f64);
            add_at_b(&mut acc.as_mut(), a.as_ref(), b.as_ref());
            let mut body = Mat::from_fn(p, q, |i, j| (i + 2 * j) as f64);
            add_at_b_body::<2, 2>(&mut body.as_mut(), a.as_ref(), b.as_ref());
            for i in 0..p {
                for j in 0..q {
                    let d = dot(a.col(i), b.col(j));
                    assert_eq!(acc[(i, j)].to_bits(), ((i + 2 * j) as f64 + d).to_bits());
                    assert_eq!(body[(i, j)].to_bits(), acc[(i, j)].to_bits());
                    let plain: f64 = (0..n).map(|r| a[(r, i)] * b[(r, j)]).sum();
                    assert!((d - plain).abs() < 1e-12, "({n},{p},{q}) {i} {j}");
                }
            }
        }
    }

    #[test]
    fn svd_reconstructs_and_orders_values_for_tall_wide_and_rank_deficient() {
        let mut seed = 11;
        for (n, p) in [(9, 4), (3, 7), (6, 6)] {
            let mut a = Mat::from_fn(n, p, |_, _| lcg(&mut seed));
            if p > 2 {
                for i in 0..n {
                    a[(i, 2)] = a[(i, 0)] - 3.0 * a[(i, 1)];
                }
            }
            let (u, s, v) = thin_svd(a.as_ref()).unwrap();
            let r = n.min(p);
            assert_eq!((u.shape(), s.len(), v.shape()), ((n, r), r, (p, r)));
            assert!(s.windows(2).all(|w| w[0] >= w[1]));
            if p <= n {
                assert!(s[r - 1] < 1e-12 * s[0], "rank deficient: {s:?}");
            }
            for i in 0..n {
                for j in 0..p {
                    let x: f64 = (0..r).map(|k| u[(i, k)] * s[k] * v[(j, k)]).sum();
                    assert!((x - a[(i, j)]).abs() < 1e-13, "({n},{p}) {i} {j}");
                }
            }
        }
        let d = Mat::from_fn(3, 3, |i, j| if i == j { [2.0, 5.0, 1.0][i] } else { 0.0 });
        assert_eq!(singular_values(d.as_ref()).unwrap(), vec![5.0, 2.0, 1.0]);
        let mut bad = Mat::zeros(2, 2);
        bad[(0, 1)] = f64::NAN;
        assert!(singular_values(bad.as_ref()).is_err());
    }
}
