//! Small dense row-major linear algebra of the branch code (issue 40 item 6: it was
//! private to `branch::condensed`): a complex LU with partial pivoting for n ≤ 16, matrix
//! products with fixed-size kernels for the common state counts, and the exponential
//! propagators e^{Ah}, Γ₀, Γ₁ of a linear system with inputs held linear over a step.
//! Numbers are row-major slices; nothing allocates beyond the returned vectors.

use num_complex::Complex64;

/// Row interchanges of an LU factorisation, in place, of a small complex matrix (partial
/// pivoting, row-major; the factors stay in the matrix).
pub(crate) struct ComplexLu {
    n: usize,
    /// Row swapped with row k at step k.
    swaps: [usize; 16],
}

impl ComplexLu {
    /// Factors `a` (n × n, row-major) in place; `None` when singular or n > 16.
    pub(crate) fn new(a: &mut [Complex64], n: usize) -> Option<Self> {
        if n > 16 {
            return None;
        }
        let mut swaps = [0; 16];
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| a[i * n + k].l1_norm().total_cmp(&a[j * n + k].l1_norm()))?;
            let pivot = a[p * n + k].l1_norm();
            if pivot == 0.0 || !pivot.is_finite() {
                return None;
            }
            swaps[k] = p;
            if p != k {
                for c in 0..n {
                    a.swap(k * n + c, p * n + c);
                }
            }
            let d = a[k * n + k].inv();
            for i in k + 1..n {
                let f = a[i * n + k] * d;
                a[i * n + k] = f;
                for c in k + 1..n {
                    let v = a[k * n + c];
                    a[i * n + c] -= f * v;
                }
            }
        }
        Some(ComplexLu { n, swaps })
    }

    /// Solves in place for one right-hand side with the factors `lu` of [`ComplexLu::new`].
    pub(crate) fn solve(&self, lu: &[Complex64], b: &mut [Complex64]) {
        let n = self.n;
        for k in 0..n {
            b.swap(k, self.swaps[k]);
        }
        for i in 0..n {
            let mut s = b[i];
            for c in 0..i {
                s -= lu[i * n + c] * b[c];
            }
            b[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for c in i + 1..n {
                s -= lu[i * n + c] * b[c];
            }
            b[i] = s / lu[i * n + i];
        }
    }
}

/// Row-major product of an (r × k) and a (k × c) matrix.
pub(crate) fn matmul(a: &[f64], b: &[f64], r: usize, k: usize, c: usize) -> Vec<f64> {
    let mut out = vec![0.0; r * c];
    matmul_into(a, b, r, k, c, &mut out);
    out
}

/// `out` = a b (row-major, a r × k, b k × c); square products of the common state counts
/// by fixed-size arrays.
pub(crate) fn matmul_into(a: &[f64], b: &[f64], r: usize, k: usize, c: usize, out: &mut [f64]) {
    if r == k && k == c {
        match r {
            4 => return square::<4>(a, b, out),
            5 => return square::<5>(a, b, out),
            6 => return square::<6>(a, b, out),
            7 => return square::<7>(a, b, out),
            8 => return square::<8>(a, b, out),
            10 => return square::<10>(a, b, out),
            12 => return square::<12>(a, b, out),
            _ => {}
        }
    }
    out.fill(0.0);
    for i in 0..r {
        let o = &mut out[i * c..(i + 1) * c];
        for l in 0..k {
            let v = a[i * k + l];
            if v == 0.0 {
                continue;
            }
            for (o, x) in o.iter_mut().zip(&b[l * c..(l + 1) * c]) {
                *o += v * x;
            }
        }
    }
}

/// `out` = a b for N × N row-major matrices.
fn square<const N: usize>(a: &[f64], b: &[f64], out: &mut [f64]) {
    let mut bm = [[0.0; N]; N];
    for (r, row) in bm.iter_mut().enumerate() {
        row.copy_from_slice(&b[r * N..(r + 1) * N]);
    }
    for i in 0..N {
        let mut acc = [0.0; N];
        for (l, brow) in bm.iter().enumerate() {
            let v = a[i * N + l];
            for c in 0..N {
                acc[c] += v * brow[c];
            }
        }
        out[i * N..(i + 1) * N].copy_from_slice(&acc);
    }
}

/// e^{Ah}, Γ₀ = ∫₀ʰ e^{A(h−τ)} dτ B and Γ₁ = ∫₀ʰ e^{A(h−τ)} τ/h dτ B (B n × p, row-major) by a Taylor
/// series to degree 15 on h/2^s with ‖A‖₁h/2^s ≤ 1/2 (remainder below 1e-16), then s
/// doublings. The matrix series is summed by Paterson–Stockmeyer (X², X³, X⁴, then Horner
/// in X⁴: six products instead of fifteen).
pub(crate) fn propagators(
    a: &[f64],
    b: &[f64],
    n: usize,
    p: usize,
    h: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let norm = (0..n)
        .map(|c| (0..n).map(|r| a[r * n + c].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut s = 0;
    while norm * h / f64::from(1u32 << s) > 0.5 && s < 30 {
        s += 1;
    }
    let hs = h / f64::from(1u32 << s);
    let x: Vec<f64> = a.iter().map(|v| v * hs).collect();
    let x2 = matmul(&x, &x, n, n, n);
    let x3 = matmul(&x2, &x, n, n, n);
    let x4 = matmul(&x2, &x2, n, n, n);
    let mut fact = [1.0; 17];
    for k in 1..17 {
        fact[k] = fact[k - 1] * k as f64;
    }
    // Block j: Σ_{i<4} X^i / (4j + i)!.
    let block = |j: usize, out: &mut [f64]| {
        for (o, ((p1, p2), p3)) in out.iter_mut().zip(x.iter().zip(&x2).zip(&x3)) {
            *o = p1 / fact[4 * j + 1] + p2 / fact[4 * j + 2] + p3 / fact[4 * j + 3];
        }
        for i in 0..n {
            out[i * n + i] += 1.0 / fact[4 * j];
        }
    };
    let mut e = vec![0.0; n * n];
    let mut t = vec![0.0; n * n];
    let mut bj = vec![0.0; n * n];
    block(3, &mut e);
    for j in (0..3).rev() {
        matmul_into(&x4, &e, n, n, n, &mut t);
        block(j, &mut bj);
        for (ei, (ti, bi)) in e.iter_mut().zip(t.iter().zip(&bj)) {
            *ei = ti + bi;
        }
    }
    // Γ₀ = hs Σ X^k/(k+1)! B, Γ₁ = hs Σ X^k/(k+2)! B.
    let mut g0 = vec![0.0; n * p];
    let mut g1 = vec![0.0; n * p];
    let mut v = b.to_vec();
    let mut w = vec![0.0; n * p];
    for k in 0..15 {
        for (i, y) in v.iter().enumerate() {
            g0[i] += hs * y / fact[k + 1];
            g1[i] += hs * y / fact[k + 2];
        }
        matmul_into(&x, &v, n, n, p, &mut w);
        std::mem::swap(&mut v, &mut w);
    }
    for _ in 0..s {
        (e, g0, g1) = doubled(n, p, &e, &g0, &g1);
    }
    (e, g0, g1)
}

/// The propagators of step 2h from those of step h: e^{2Ah} = E², Γ₀(2h) = EΓ₀ + Γ₀,
/// Γ₁(2h) = (EΓ₁ + Γ₀ + Γ₁)/2.
pub(crate) fn doubled(
    n: usize,
    p: usize,
    e: &[f64],
    g0: &[f64],
    g1: &[f64],
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let eg0 = matmul(e, g0, n, n, p);
    let eg1 = matmul(e, g1, n, n, p);
    let n1 = (0..n * p).map(|i| 0.5 * (eg1[i] + g0[i] + g1[i])).collect();
    let n0 = (0..n * p).map(|i| eg0[i] + g0[i]).collect();
    (matmul(e, e, n, n, n), n0, n1)
}
