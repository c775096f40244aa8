//! Householder QR, the one orthogonal factorisation of the workspace, in three entry points
//! sharing one reflector: [`householder_qr`] (in place, R only, the row-blocked
//! factorisation of a case's library), [`lstsq`] (a small least-squares solve with optional
//! ridge) and [`ThinQr`] (Q kept as reflectors, dependent columns dropped, for projections
//! of vectors that come later).

/// Solves min ‖A x − b‖² (+ λ‖x‖² when `ridge > 0`) for a small column-major `m × q`
/// matrix `a` by Householder QR ([`householder_qr`] of `[A; √λ I | b; 0]`). Returns
/// `(x, rss)` where `rss = ‖A x − b‖²` (the data misfit only, without the ridge penalty).
///
/// A column whose R_kk is zero or below 1e-14 of the largest |R_kk| (exactly or
/// numerically dependent, or empty) gets coefficient 0.
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
    let extra = if ridge > 0.0 { q } else { 0 };
    let mm = m + extra;
    let mut w = vec![0.0; mm * (q + 1)];
    for j in 0..q {
        w[j * mm..j * mm + m].copy_from_slice(&a[j * m..(j + 1) * m]);
        if extra > 0 {
            w[j * mm + m + j] = ridge.sqrt();
        }
    }
    w[q * mm..q * mm + m].copy_from_slice(b);
    let nref = q.min(mm);
    let diag = householder_qr(&mut w, mm, q + 1, nref);
    let rhs = &w[q * mm..];
    let mut x = vec![0.0; q];
    let scale = diag.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    for k in (0..nref).rev() {
        let d = diag[k];
        if d.abs() <= scale * 1e-14 || d == 0.0 {
            continue;
        }
        let mut s = rhs[k];
        for j in k + 1..q {
            s -= w[j * mm + k] * x[j];
        }
        x[k] = s / d;
    }
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
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above); as for AVX2 below,
            // only the instructions differ (the same operations, no fused multiply-add).
            return unsafe { householder_qr_avx512(a, n, ncols, nref) };
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above); the function
            // only differs from the portable one by the instructions the compiler may use.
            return unsafe { householder_qr_avx2(a, n, ncols, nref) };
        }
    }
    householder_qr_body(a, n, ncols, nref)
}

/// [`householder_qr_body`] compiled with AVX2 + FMA (runtime-dispatched: the release
/// profile targets baseline x86-64, and the dot/axpy loops are 3–4× faster with 256-bit
/// fused multiply-adds).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn householder_qr_avx2(a: &mut [f64], n: usize, ncols: usize, nref: usize) -> Vec<f64> {
    householder_qr_body(a, n, ncols, nref)
}

/// The factorisation of [`householder_qr`], one sweep over the trailing columns per
/// reflector, two columns at a time: right after reflector k updates a pair of columns,
/// their dot products with reflector k + 1 are taken (made from column k + 1 first, as
/// soon as that column is updated), while the pair is still in the first-level cache. Each column still gets, in the same order, exactly the operations of the
/// textbook loop "for k: make reflector k; for j > k: s = f·(v·c_j); c_j ← c_j − s v",
/// with every dot product summed as [`dot`] sums it, so the result is bit for bit that
/// loop's (`tests::fused_passes_equal_the_textbook_loop`); the trailing matrix is read
/// once per reflector from the second-level cache instead of twice.
/// [`householder_qr_body`] compiled with AVX-512F (twice the vector registers: the
/// sixteen partial sums of two dot products stay in four of them).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn householder_qr_avx512(a: &mut [f64], n: usize, ncols: usize, nref: usize) -> Vec<f64> {
    householder_qr_body(a, n, ncols, nref)
}

#[inline(always)]
fn householder_qr_body(a: &mut [f64], n: usize, ncols: usize, nref: usize) -> Vec<f64> {
    let mut diag = vec![0.0; nref];
    if nref == 0 {
        return diag;
    }
    // dots[j] = v_k · column j (rows k..), valid when `have_dots`
    let mut dots = vec![0.0; ncols];
    let mut have_dots = false;
    let mut cur = make_reflector(&mut a[..n]);
    for k in 0..nref {
        let (left, right) = a.split_at_mut((k + 1) * n);
        let v = &mut left[k * n + k..(k + 1) * n];
        let Some((alpha, f)) = cur else {
            // a zero column: no reflector; the next one comes from the untouched column
            if k + 1 < nref {
                cur = make_reflector(&mut right[k + 1..n]);
            }
            have_dots = false;
            continue;
        };
        diag[k] = alpha;
        let mut next = None;
        if f > 0.0 && k + 1 < ncols {
            let (c1, rest) = right.split_at_mut(n);
            // column k + 1 first: once updated it gives reflector k + 1
            let s = if have_dots {
                dots[k + 1]
            } else {
                dot(v, &c1[k..])
            } * f;
            for (y, x) in c1[k..].iter_mut().zip(v.iter()) {
                *y -= s * x;
            }
            if k + 1 < nref {
                next = make_reflector(&mut c1[k + 1..]);
            }
            let vn: Option<&[f64]> = match next {
                Some((_, g)) if g > 0.0 => Some(&c1[k + 1..]),
                _ => None,
            };
            let m = ncols - k - 2;
            let mut j = 0;
            // two columns at a time (one pass over the reflectors for both: independent
            // chains of additions), then the odd one
            while j + 2 <= m {
                let (ca, cb) = rest[j * n..(j + 2) * n].split_at_mut(n);
                let (ca, cb) = (&mut ca[k..], &mut cb[k..]);
                let (sa, sb) = if have_dots {
                    (dots[k + 2 + j], dots[k + 3 + j])
                } else {
                    dot2(v, ca, cb)
                };
                let (sa, sb) = (sa * f, sb * f);
                for ((y, z), x) in ca.iter_mut().zip(cb.iter_mut()).zip(v.iter()) {
                    *y -= sa * x;
                    *z -= sb * x;
                }
                if let Some(vn) = vn {
                    (dots[k + 2 + j], dots[k + 3 + j]) = dot2(vn, &ca[1..], &cb[1..]);
                }
                j += 2;
            }
            if j < m {
                let col = &mut rest[j * n + k..(j + 1) * n];
                let s = if have_dots {
                    dots[k + 2 + j]
                } else {
                    dot(v, col)
                } * f;
                for (y, x) in col.iter_mut().zip(v.iter()) {
                    *y -= s * x;
                }
                if let Some(vn) = vn {
                    dots[k + 2 + j] = dot(vn, &col[1..]);
                }
            }
            have_dots = vn.is_some();
        } else {
            // H = I (or no column after k): nothing changes
            if k + 1 < nref {
                next = make_reflector(&mut right[k + 1..n]);
            }
            have_dots = false;
        }
        // store R_kk in place of the reflector head (the reflector is no longer needed)
        v[0] = alpha;
        cur = next;
    }
    diag
}

/// ([`dot`]`(x, y)`, [`dot`]`(x, z)`) in one pass over `x` (all three of one length), each
/// summed exactly as [`dot`] sums it.
#[inline(always)]
fn dot2(x: &[f64], y: &[f64], z: &[f64]) -> (f64, f64) {
    let len = x.len().min(y.len()).min(z.len());
    let (x, y, z) = (&x[..len], &y[..len], &z[..len]);
    let mut ay = [0.0f64; 16];
    let mut az = [0.0f64; 16];
    for ((a, b), c) in x
        .chunks_exact(16)
        .zip(y.chunks_exact(16))
        .zip(z.chunks_exact(16))
    {
        for k in 0..16 {
            ay[k] += a[k] * b[k];
            az[k] += a[k] * c[k];
        }
    }
    let rem = len / 16 * 16;
    let (mut sy, mut sz) = (0.0, 0.0);
    for k in 0..4 {
        sy += (ay[k] + ay[k + 4]) + (ay[k + 8] + ay[k + 12]);
        sz += (az[k] + az[k + 4]) + (az[k + 8] + az[k + 12]);
    }
    for i in rem..len {
        sy += x[i] * y[i];
        sz += x[i] * z[i];
    }
    (sy, sz)
}

/// Turns `v` (the part of a column on and below the diagonal) into a Householder reflector
/// H = I − f v vᵀ with H x = α e₁, α = −sign(x₀)‖x‖ (no cancellation). Returns `(α, f)`,
/// f = 2/‖v‖² (f = 0 when x is already α e₁: H = I), or `None` for a zero column (no
/// reflector, R_kk = 0).
#[inline(always)]
fn make_reflector(v: &mut [f64]) -> Option<(f64, f64)> {
    let norm = dot(v, v).sqrt();
    if norm == 0.0 {
        return None;
    }
    let alpha = if v[0] > 0.0 { -norm } else { norm };
    v[0] -= alpha;
    let vv = dot(v, v);
    Some((alpha, if vv == 0.0 { 0.0 } else { 2.0 / vv }))
}

/// Applies the reflector (v, f) of [`make_reflector`] to `c` (the same rows as `v`):
/// c ← c − f (v·c) v.
#[inline(always)]
fn reflect(v: &[f64], f: f64, c: &mut [f64]) {
    let s = dot(v, c) * f;
    for (y, x) in c.iter_mut().zip(v) {
        *y -= s * x;
    }
}

/// Dot product x·y over the shorter length, with sixteen accumulators (lets the compiler keep several vector
/// registers of partial sums in flight).
#[inline(always)]
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0f64; 16];
    let mut it = x.chunks_exact(16).zip(y.chunks_exact(16));
    for (a, b) in &mut it {
        for k in 0..16 {
            acc[k] += a[k] * b[k];
        }
    }
    let rem = x.len().min(y.len()) / 16 * 16;
    let mut s = 0.0;
    for k in 0..4 {
        s += (acc[k] + acc[k + 4]) + (acc[k + 8] + acc[k + 12]);
    }
    for i in rem..x.len().min(y.len()) {
        s += x[i] * y[i];
    }
    s
}

/// Thin QR factorisation X = Q R of a few long columns that keeps Q (as its reflectors),
/// for least-squares fits and projections of vectors that arrive later. Columns are taken
/// in order (left-looking Householder, the same reflectors as [`householder_qr`]); a column
/// whose part orthogonal to the kept columns before it is at most `rel_tol` of its norm is
/// dropped (its coefficient is 0), so R over the kept columns is well conditioned.
#[derive(Debug, Clone)]
pub struct ThinQr {
    /// Reflector k (rows k.. of the column), with its factor f = 2/‖v‖².
    reflectors: Vec<(Vec<f64>, f64)>,
    /// R over kept columns by column: `r[l][k]`, k ≤ l.
    r: Vec<Vec<f64>>,
    /// Index in the input of each kept column.
    kept: Vec<usize>,
    /// Number of input columns.
    n_cols: usize,
}

/// x ← H_{m−1} ⋯ H₀ x (`reverse`: H₀ ⋯ H_{m−1} x) for the reflectors (v_k, f_k) of a
/// [`ThinQr`], reflector k acting on x\[k..\]. Runtime-dispatched to an AVX-512F or an AVX2
/// build like [`householder_qr`]: the same IEEE operations in the same order (Rust never
/// contracts `a * b + c` into a fused multiply-add), so bit for bit the portable result.
fn apply_reflectors(reflectors: &[(Vec<f64>, f64)], x: &mut [f64], reverse: bool) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above).
            return unsafe { apply_reflectors_avx512(reflectors, x, reverse) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { apply_reflectors_avx2(reflectors, x, reverse) };
        }
    }
    apply_reflectors_body(reflectors, x, reverse);
}

/// [`apply_reflectors_body`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn apply_reflectors_avx2(reflectors: &[(Vec<f64>, f64)], x: &mut [f64], reverse: bool) {
    apply_reflectors_body(reflectors, x, reverse);
}

/// [`apply_reflectors_body`] compiled with AVX-512F (the sixteen partial sums of a dot
/// product in two registers).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn apply_reflectors_avx512(reflectors: &[(Vec<f64>, f64)], x: &mut [f64], reverse: bool) {
    apply_reflectors_body(reflectors, x, reverse);
}

#[inline(always)]
fn apply_reflectors_body(reflectors: &[(Vec<f64>, f64)], x: &mut [f64], reverse: bool) {
    if reverse {
        for (k, (v, f)) in reflectors.iter().enumerate().rev() {
            reflect(v, *f, &mut x[k..]);
        }
    } else {
        for (k, (v, f)) in reflectors.iter().enumerate() {
            reflect(v, *f, &mut x[k..]);
        }
    }
}

/// Four columns at a time: each x_b ← H_{m−1} ⋯ H₀ x_b (`reverse`: H₀ ⋯ H_{m−1} x_b), with
/// each reflector's rows read once for the four. Every column gets exactly the operations
/// of [`apply_reflectors`] in the same order (its own sixteen partial sums of each dot
/// product, reduced the same way), so bit for bit its result. Dispatched like it.
fn apply_reflectors4(reflectors: &[(Vec<f64>, f64)], xs: [&mut [f64]; 4], reverse: bool) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above).
            return unsafe { apply_reflectors4_avx512(reflectors, xs, reverse) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { apply_reflectors4_avx2(reflectors, xs, reverse) };
        }
    }
    apply_reflectors4_body(reflectors, xs, reverse);
}

/// [`apply_reflectors4_body`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn apply_reflectors4_avx2(
    reflectors: &[(Vec<f64>, f64)],
    xs: [&mut [f64]; 4],
    reverse: bool,
) {
    apply_reflectors4_body(reflectors, xs, reverse);
}

/// [`apply_reflectors4_body`] compiled with AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn apply_reflectors4_avx512(
    reflectors: &[(Vec<f64>, f64)],
    xs: [&mut [f64]; 4],
    reverse: bool,
) {
    apply_reflectors4_body(reflectors, xs, reverse);
}

#[inline(always)]
fn apply_reflectors4_body(reflectors: &[(Vec<f64>, f64)], xs: [&mut [f64]; 4], reverse: bool) {
    let [x0, x1, x2, x3] = xs;
    let m = reflectors.len();
    // no closure: a closure is not compiled with its caller's target features
    for i in 0..m {
        let k = if reverse { m - 1 - i } else { i };
        let (v, f) = &reflectors[k];
        reflect4(
            v,
            *f,
            &mut x0[k..],
            &mut x1[k..],
            &mut x2[k..],
            &mut x3[k..],
        );
    }
}

/// [`reflect`] of four columns of `v`'s length: the four dot products in one pass over `v`
/// (each with the sixteen partial sums of [`dot`], reduced as it does), then the four
/// updates in one pass.
#[inline(always)]
fn reflect4(v: &[f64], f: f64, c0: &mut [f64], c1: &mut [f64], c2: &mut [f64], c3: &mut [f64]) {
    // four `&mut` parameters (not an array of them): each carries the promise that it
    // aliases nothing else, without which the updates below would not be vectorised
    let n = v.len();
    let (c0, c1, c2, c3) = (&mut c0[..n], &mut c1[..n], &mut c2[..n], &mut c3[..n]);
    let mut acc = [[0.0f64; 16]; 4];
    let full = n / 16 * 16;
    for ((((a, b0), b1), b2), b3) in v[..full]
        .chunks_exact(16)
        .zip(c0.chunks_exact(16))
        .zip(c1.chunks_exact(16))
        .zip(c2.chunks_exact(16))
        .zip(c3.chunks_exact(16))
    {
        for l in 0..16 {
            acc[0][l] += a[l] * b0[l];
            acc[1][l] += a[l] * b1[l];
            acc[2][l] += a[l] * b2[l];
            acc[3][l] += a[l] * b3[l];
        }
    }
    let tails: [&[f64]; 4] = [&c0[full..], &c1[full..], &c2[full..], &c3[full..]];
    let s: [f64; 4] = std::array::from_fn(|b| {
        let ac = &acc[b];
        let mut s = 0.0;
        for k in 0..4 {
            s += (ac[k] + ac[k + 4]) + (ac[k + 8] + ac[k + 12]);
        }
        for (x, y) in v[full..].iter().zip(tails[b]) {
            s += x * y;
        }
        s * f
    });
    for ((((x, y0), y1), y2), y3) in v
        .iter()
        .zip(c0.iter_mut())
        .zip(c1.iter_mut())
        .zip(c2.iter_mut())
        .zip(c3.iter_mut())
    {
        *y0 -= s[0] * x;
        *y1 -= s[1] * x;
        *y2 -= s[2] * x;
        *y3 -= s[3] * x;
    }
}

impl ThinQr {
    /// Factorises the columns `cols` (all of one length n), dropping dependent ones (see
    /// the type). A non-finite column is dropped too.
    ///
    /// # Panics
    /// When the columns differ in length (a programming error).
    #[track_caller]
    pub fn new(cols: &[&[f64]], rel_tol: f64) -> Self {
        let n = cols.first().map_or(0, |c| c.len());
        assert!(
            cols.iter().all(|c| c.len() == n),
            "ThinQr: columns of unequal length"
        );
        let mut qr = ThinQr {
            reflectors: Vec::new(),
            r: Vec::new(),
            kept: Vec::new(),
            n_cols: cols.len(),
        };
        for (j, c) in cols.iter().enumerate() {
            let m = qr.reflectors.len();
            if m == n {
                break;
            }
            let norm0 = dot(c, c).sqrt();
            let mut x = c.to_vec();
            qr.apply_qt(&mut x);
            let tail_norm = dot(&x[m..], &x[m..]).sqrt();
            if !(norm0.is_finite() && norm0 > 0.0 && tail_norm > rel_tol * norm0) {
                continue;
            }
            // R's column above the diagonal, then the reflector in place of x (its rows
            // m.. moved to the front: no second copy of the column)
            let mut col = x[..m].to_vec();
            x.copy_within(m.., 0);
            x.truncate(n - m);
            let mut v = x;
            let Some((alpha, f)) = make_reflector(&mut v) else {
                continue;
            };
            col.push(alpha);
            qr.r.push(col);
            qr.reflectors.push((v, f));
            qr.kept.push(j);
        }
        qr
    }

    /// Indices (in the input) of the kept columns, in order.
    pub fn kept(&self) -> &[usize] {
        &self.kept
    }

    /// x ← Qᵀ x (full length: the first `kept().len()` entries are the coordinates on the
    /// kept columns' span, the rest the orthogonal part).
    fn apply_qt(&self, x: &mut [f64]) {
        apply_reflectors(&self.reflectors, x, false);
    }

    /// y − Q Qᵀ y: the residual of the least-squares fit of `y` on the columns.
    ///
    /// # Panics
    /// When `y` is not of the columns' length (a programming error).
    pub fn residual(&self, y: &[f64]) -> Vec<f64> {
        let mut z = y.to_vec();
        self.apply_qt(&mut z);
        z[..self.reflectors.len()].fill(0.0);
        apply_reflectors(&self.reflectors, &mut z, true);
        z
    }

    /// Qᵀy with its first `kept().len()` entries (the coordinates on the kept columns' span)
    /// set to 0: the orthogonal part of `y` in the reflectors' basis, so that
    /// (P⊥x)ᵀ(P⊥y) = `orthogonal_coordinates(x)`ᵀ`orthogonal_coordinates(y)` for the
    /// projector P⊥ = I − QQᵀ of [`ThinQr::residual`], at half its work (Q is not applied
    /// back).
    ///
    /// # Panics
    /// When `y` is not of the columns' length (a programming error).
    pub fn orthogonal_coordinates(&self, y: &[f64]) -> Vec<f64> {
        let mut z = y.to_vec();
        self.apply_qt(&mut z);
        z[..self.reflectors.len()].fill(0.0);
        z
    }

    /// Least-squares coefficients of `y` on the input columns (0 for dropped columns).
    ///
    /// # Panics
    /// When `y` is not of the columns' length (a programming error).
    pub fn solve(&self, y: &[f64]) -> Vec<f64> {
        let mut z = y.to_vec();
        self.apply_qt(&mut z);
        self.coefficients(&z)
    }

    /// ([`ThinQr::residual`], [`ThinQr::solve`]) of `y` from one application of Qᵀ (both
    /// start from Qᵀy): bit for bit the two calls' values, for two thirds of their work.
    ///
    /// # Panics
    /// When `y` is not of the columns' length (a programming error).
    pub fn residual_and_solve(&self, y: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut z = y.to_vec();
        let coefficients = self.residual_and_solve_in_place(&mut z);
        (z, coefficients)
    }

    /// [`ThinQr::residual_and_solve`] with `z` replaced in place by its residual; returns
    /// the coefficients.
    fn residual_and_solve_in_place(&self, z: &mut [f64]) -> Vec<f64> {
        self.apply_qt(z);
        let coefficients = self.coefficients(z);
        z[..self.reflectors.len()].fill(0.0);
        apply_reflectors(&self.reflectors, z, true);
        coefficients
    }

    /// [`ThinQr::residual_and_solve`] of every column of `ys`, each replaced in place by its
    /// residual; returns the coefficients, column by column. Columns go four at a time
    /// through the reflectors (each reflector read once for four columns), every column bit
    /// for bit its [`ThinQr::residual_and_solve`].
    ///
    /// # Panics
    /// When a column is not of the factorised columns' length (a programming error).
    #[track_caller]
    pub fn residuals_and_solves(&self, ys: &mut [Vec<f64>]) -> Vec<Vec<f64>> {
        let n = self.reflectors.first().map(|(v, _)| v.len());
        assert!(
            n.is_none_or(|n| ys.iter().all(|y| y.len() == n)),
            "ThinQr: a column of another length"
        );
        let m = self.reflectors.len();
        let mut out = Vec::with_capacity(ys.len());
        let mut blocks = ys.chunks_exact_mut(4);
        for blk in &mut blocks {
            let [a, b, c, d] = blk else { unreachable!() };
            apply_reflectors4(&self.reflectors, [a, b, c, d], false);
            for y in blk.iter_mut() {
                out.push(self.coefficients(y));
                y[..m].fill(0.0);
            }
            let [a, b, c, d] = blk else { unreachable!() };
            apply_reflectors4(&self.reflectors, [a, b, c, d], true);
        }
        for y in blocks.into_remainder() {
            out.push(self.residual_and_solve_in_place(y));
        }
        out
    }

    /// The coefficients on the input columns (0 for dropped ones) from z = Qᵀy, by back
    /// substitution in R.
    fn coefficients(&self, z: &[f64]) -> Vec<f64> {
        let m = self.kept.len();
        let mut x = vec![0.0; m];
        for k in (0..m).rev() {
            let s: f64 = (k + 1..m).map(|l| self.r[l][k] * x[l]).sum();
            x[k] = (z[k] - s) / self.r[k][k];
        }
        let mut out = vec![0.0; self.n_cols];
        for (k, &j) in self.kept.iter().enumerate() {
            out[j] = x[k];
        }
        out
    }

    /// R a: the kept columns' part of the coefficient vector `a` (indexed like the input
    /// columns) mapped by R, so that ‖X a‖ = ‖R a‖ for any `a` zero on dropped columns.
    pub fn r_times(&self, a: &[f64]) -> Vec<f64> {
        let m = self.kept.len();
        (0..m)
            .map(|k| (k..m).map(|l| self.r[l][k] * a[self.kept[l]]).sum())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook loop the fused factorisation must reproduce bit for bit.
    fn textbook_qr(a: &mut [f64], n: usize, ncols: usize, nref: usize) -> Vec<f64> {
        let mut diag = vec![0.0; nref];
        for k in 0..nref {
            let (left, right) = a.split_at_mut((k + 1) * n);
            let v = &mut left[k * n + k..(k + 1) * n];
            let Some((alpha, f)) = make_reflector(v) else {
                continue;
            };
            diag[k] = alpha;
            if f > 0.0 {
                for j in 0..(ncols - k - 1) {
                    reflect(v, f, &mut right[j * n + k..(j + 1) * n]);
                }
            }
            v[0] = alpha;
        }
        diag
    }

    /// Random matrices of several shapes (row counts that are and are not multiples of the
    /// 16-wide accumulation, fewer reflectors than columns, zero and repeated columns, a
    /// column already of the form α e₁): the fused factorisation gives the textbook loop's
    /// numbers bit for bit, in the portable and the dispatched build.
    #[test]
    fn fused_passes_equal_the_textbook_loop() {
        let mut state = 0x2545_f491_4f6c_dd1du64; // fixed seed
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for &(n, ncols, nref) in &[
            (256, 32, 32),
            (640, 32, 30),
            (37, 9, 9),
            (17, 17, 17),
            (5, 3, 2),
            (1, 1, 1),
            (300, 6, 4),
        ] {
            for variant in 0..4 {
                let mut a: Vec<f64> = (0..n * ncols).map(|_| next()).collect();
                if variant == 1 && ncols > 2 {
                    a[n..2 * n].fill(0.0); // a zero column
                }
                if variant == 2 && ncols > 3 {
                    let c: Vec<f64> = a[..n].to_vec();
                    a[2 * n..3 * n].copy_from_slice(&c); // a repeated column
                }
                if variant == 3 {
                    a[1..n].fill(0.0); // column 0 already α e₁
                }
                let mut b = a.clone();
                let mut c = a.clone();
                let d_ref = textbook_qr(&mut a, n, ncols, nref);
                let d_port = householder_qr_body(&mut b, n, ncols, nref);
                let d_disp = householder_qr(&mut c, n, ncols, nref);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&d_ref), bits(&d_port), "{n}×{ncols}/{nref} v{variant}");
                assert_eq!(bits(&a), bits(&b), "{n}×{ncols}/{nref} v{variant}");
                assert_eq!(bits(&d_ref), bits(&d_disp), "{n}×{ncols}/{nref} v{variant}");
                assert_eq!(bits(&a), bits(&c), "{n}×{ncols}/{nref} v{variant}");
            }
        }
    }

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

    #[test]
    fn thin_qr_solves_projects_and_drops_dependent_columns() {
        let n = 50;
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let c: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 2.0 * x - y).collect();
        let y: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 1.5 * x + 0.25 * y).collect();
        let qr = ThinQr::new(&[&a, &b, &c], 1e-10);
        assert_eq!(qr.kept(), &[0, 1]);
        let x = qr.solve(&y);
        assert!((x[0] - 1.5).abs() < 1e-12 && (x[1] - 0.25).abs() < 1e-12 && x[2] == 0.0);
        let r = qr.residual(&y);
        assert!(dot(&r, &r) < 1e-20);
        // a vector off the span: its residual is orthogonal to both columns and the fit
        // plus the residual gives it back; ‖X a‖ = ‖R a‖
        let z: Vec<f64> = (0..n).map(|i| ((i * i) as f64 * 0.07).sin()).collect();
        let (rz, xz) = (qr.residual(&z), qr.solve(&z));
        assert!(dot(&rz, &a).abs() < 1e-12 && dot(&rz, &b).abs() < 1e-12);
        for i in 0..n {
            let fit = xz[0] * a[i] + xz[1] * b[i];
            assert!((fit + rz[i] - z[i]).abs() < 1e-12);
        }
        let xa: Vec<f64> = (0..n).map(|i| 0.3 * a[i] - 2.0 * b[i]).collect();
        let ra = qr.r_times(&[0.3, -2.0, 0.0]);
        assert!((dot(&ra, &ra) - dot(&xa, &xa)).abs() < 1e-10 * dot(&xa, &xa));
    }

    #[test]
    fn residual_and_solve_is_the_two_calls_and_dispatch_is_portable_bit_for_bit() {
        // long uneven columns (not a multiple of sixteen), one of them nearly dependent
        let n = 1037;
        let cols: Vec<Vec<f64>> = (0..5)
            .map(|j| {
                (0..n)
                    .map(|i| ((i * (j + 2)) as f64 * 0.013 + j as f64).sin() + 0.1 * j as f64)
                    .collect()
            })
            .collect();
        let mut cols = cols;
        cols[3] = cols[0]
            .iter()
            .zip(&cols[1])
            .map(|(a, b)| a - 0.5 * b + 1e-7 * a * a)
            .collect();
        let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
        let qr = ThinQr::new(&refs, 1e-10);
        let y: Vec<f64> = (0..n).map(|i| ((i * i) as f64 * 0.003).cos()).collect();
        let (r, x) = qr.residual_and_solve(&y);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&r), bits(&qr.residual(&y)));
        assert_eq!(bits(&x), bits(&qr.solve(&y)));
        // the dispatched reflectors (AVX-512F or AVX2 where the CPU has them) against the
        // portable loop, both directions
        for reverse in [false, true] {
            let mut a = y.clone();
            let mut b = y.clone();
            apply_reflectors(&qr.reflectors, &mut a, reverse);
            apply_reflectors_body(&qr.reflectors, &mut b, reverse);
            assert_eq!(bits(&a), bits(&b), "reverse = {reverse}");
        }
        // four at a time and the rest one by one (six columns: one block, two left over),
        // each column its own `residual_and_solve`; the portable four-column loop too
        let ys: Vec<Vec<f64>> = (0..6)
            .map(|j| {
                y.iter()
                    .enumerate()
                    .map(|(i, v)| v * (1.0 + 0.1 * (i * j) as f64))
                    .collect()
            })
            .collect();
        let mut rs = ys.clone();
        let xs = qr.residuals_and_solves(&mut rs);
        for (j, yj) in ys.iter().enumerate() {
            let (r, x) = qr.residual_and_solve(yj);
            assert_eq!(bits(&rs[j]), bits(&r), "column {j}");
            assert_eq!(bits(&xs[j]), bits(&x), "column {j}");
        }
        for reverse in [false, true] {
            let mut a = ys[..4].to_vec();
            let mut b = ys[..4].to_vec();
            let [a0, a1, a2, a3] = &mut a[..] else {
                unreachable!()
            };
            apply_reflectors4(&qr.reflectors, [a0, a1, a2, a3], reverse);
            let [b0, b1, b2, b3] = &mut b[..] else {
                unreachable!()
            };
            apply_reflectors4_body(&qr.reflectors, [b0, b1, b2, b3], reverse);
            for (p, q) in a.iter().zip(&b) {
                assert_eq!(bits(p), bits(q), "reverse = {reverse}");
            }
        }
    }
}
