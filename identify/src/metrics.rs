//! Goodness of fit: R², key frequencies, the Eq. 14 key-frequency loss and MFWA (Eq. 18).
//!
//! **Complex amplitudes.** A signal is written v(t) ≈ v̄ + Σ_i Re(A_i e^{iω_i t}) with t
//! measured from the first sample, i.e. A_i = a_i − i b_i for v ≈ v̄ + Σ a_i cos ω_i t +
//! b_i sin ω_i t. |A_i| is the amplitude of the tone, arg A_i its phase.
//!
//! **Key frequencies.** The candidate tones of a two-frequency forced motion are the
//! harmonics and combination tones |m f_α + n f_h|, 1 ≤ |m| + |n| ≤ N (default N = 5),
//! between 1/T and Nyquist − 1/T (T the record length), candidates closer than the
//! resolution 1/T merged into the one of lowest order. The complex amplitudes of all
//! candidates (and the mean) are fitted together by least squares ([`HarmonicProjector`]); unlike
//! FFT bins this is exact when the record is not a whole number of periods (no leakage
//! between the fitted tones). The key frequencies of a force are its k largest candidates
//! (default k = 6).
//!
//! **Eq. 14 loss** over the key frequencies, A measured, Â model:
//! L = Σ_i |A_i − Â_i|² / Σ_i |A_i|² (complex amplitudes: a phase error counts).
//!
//! **MFWA (Eq. 18)**: the amplitude ratio of each key frequency weighted by the measured
//! amplitude, w_i = |A_i| / Σ|A|: MFWA = Σ_i w_i |Â_i| / |A_i| = Σ_i |Â_i| / Σ_i |A_i|.
//! 1 for a model with the right amplitudes, < 1 when it under-predicts, > 1 when it
//! over-predicts; phase is ignored and errors of opposite sign on different lines cancel
//! (that is the paper's formula). The phase-aware variant [`mfwa_phase`] is aeroform's:
//! Σ_i w_i max(0, Re(Â_i Ā_i)) / max(|A_i|, |Â_i|)², in [0, 1], 1 only when amplitude and
//! phase of every line match.

use crate::numerics::mat::{add_at_b, Mat, MatMut, MatRef};
use crate::numerics::scratch::Scratch;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::numerics::{cholesky_in_place, cholesky_solve_in_place, PivotFloor};
use crate::record::Forcing;
use crate::{Error, Result};

/// Default highest order |m| + |n| of the candidate tones.
pub const DEFAULT_MAX_ORDER: u32 = 5;
/// Default number of key frequencies.
pub const DEFAULT_K_KEY: usize = 6;

/// Coefficient of determination R² = 1 − SS_res / SS_tot (SS_tot about the mean of y).
/// Returns 1 when both sums vanish and −∞ when only SS_tot does.
///
/// # Panics
/// When the lengths differ (a programming error).
#[track_caller]
pub fn r_squared(y: &[f64], y_hat: &[f64]) -> f64 {
    assert_eq!(y.len(), y_hat.len(), "R²: lengths differ");
    let n = y.len().max(1) as f64;
    let mean = y.iter().sum::<f64>() / n;
    let ss_tot: f64 = y.iter().map(|v| (v - mean) * (v - mean)).sum();
    let ss_res: f64 = y.iter().zip(y_hat).map(|(a, b)| (a - b) * (a - b)).sum();
    r_squared_from_sums(ss_res, ss_tot)
}

/// R² from the residual and total sums of squares (see [`r_squared`]).
pub fn r_squared_from_sums(ss_res: f64, ss_tot: f64) -> f64 {
    if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else if ss_res <= 0.0 {
        1.0
    } else {
        f64::NEG_INFINITY
    }
}

/// A candidate tone f = |m f_α + n f_h| \[Hz\].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Tone {
    /// Frequency \[Hz\].
    pub freq: f64,
    /// Multiple of the pitch forcing frequency.
    pub m: i32,
    /// Multiple of the heave forcing frequency.
    pub n: i32,
}

impl Tone {
    /// Order |m| + |n|.
    pub fn order(&self) -> u32 {
        self.m.unsigned_abs() + self.n.unsigned_abs()
    }

    /// Label such as `2*f_alpha-1*f_h`, `f_alpha`, `3*f_h`.
    pub fn label(&self) -> String {
        let part = |k: i32, name: &str| match k {
            0 => String::new(),
            1 => name.to_string(),
            -1 => format!("-{name}"),
            _ => format!("{k}*{name}"),
        };
        let a = part(self.m, "f_alpha");
        let h = part(self.n, "f_h");
        match (a.is_empty(), h.is_empty()) {
            (true, _) => h,
            (_, true) => a,
            _ if h.starts_with('-') => format!("{a}{h}"),
            _ => format!("{a}+{h}"),
        }
    }
}

/// Candidate tones of a forcing: |m f_α + n f_h| for 1 ≤ |m| + |n| ≤ `max_order`, kept when
/// 1/T ≤ f ≤ f_Nyquist − 1/T, sorted by frequency, merged when closer than 1/T (the one of
/// lowest order, then lowest frequency, then fewest heave multiples, is kept). A missing forcing frequency contributes
/// no multiple.
pub fn candidate_tones(forcing: &Forcing, max_order: u32, duration: f64, dt: f64) -> Vec<Tone> {
    let res = 1.0 / duration;
    let nyq = 0.5 / dt;
    let fa = forcing.pitch.filter(|f| f.is_finite() && *f > 0.0);
    let fh = forcing.heave.filter(|f| f.is_finite() && *f > 0.0);
    let n_max = max_order as i32;
    let mut all = Vec::new();
    for m in -n_max..=n_max {
        for n in -n_max..=n_max {
            let order = m.unsigned_abs() + n.unsigned_abs();
            if order == 0 || order > max_order {
                continue;
            }
            // one of each ± pair: first nonzero index positive
            if m < 0 || (m == 0 && n < 0) {
                continue;
            }
            let f = match (fa, fh) {
                (Some(a), Some(h)) => m as f64 * a + n as f64 * h,
                (Some(a), None) if n == 0 => m as f64 * a,
                (None, Some(h)) if m == 0 => n as f64 * h,
                _ => continue,
            };
            let f = f.abs();
            if f >= res && f <= nyq - res {
                let (m, n) = if m as f64 * fa.unwrap_or(0.0) + n as f64 * fh.unwrap_or(0.0) < 0.0 {
                    (-m, -n)
                } else {
                    (m, n)
                };
                all.push(Tone { freq: f, m, n });
            }
        }
    }
    // lowest order first so that merging keeps the simplest explanation of a line
    all.sort_by(|a, b| {
        a.order()
            .cmp(&b.order())
            .then(a.freq.total_cmp(&b.freq))
            .then(a.n.abs().cmp(&b.n.abs()))
    });
    let mut kept: Vec<Tone> = Vec::new();
    for t in all {
        if kept.iter().all(|k| (k.freq - t.freq).abs() >= res) {
            kept.push(t);
        }
    }
    kept.sort_by(|a, b| a.freq.total_cmp(&b.freq));
    kept
}

/// Least-squares fit of a constant and cos/sin pairs at given frequencies to uniformly
/// sampled signals (t_k = k·dt, k = 0..n). The Gram matrix of the basis is computed in
/// closed form (Dirichlet sums) and Cholesky-factorised once. The basis itself is never
/// stored: it is generated in blocks of [`HARMONIC_BLOCK`] rows while projecting, so the
/// memory of a fit is O(tones² + block), independent of n.
#[derive(Debug, Clone)]
pub struct HarmonicProjector {
    freqs: Vec<f64>,
    n: usize,
    dt: f64,
    /// ω_i dt [rad per sample]
    theta: Vec<f64>,
    /// lower Cholesky factor of the Gram matrix, row-major m × m
    chol: Vec<f64>,
}

/// Rows of the harmonic basis generated at a time by [`HarmonicProjector`] (a multiple of the
/// 256-sample re-anchoring period of its rotation recurrence).
pub const HARMONIC_BLOCK: usize = 4096;
/// Samples between exact re-anchorings of the rotation recurrence of the basis.
const ANCHOR: usize = 256;
/// Tones whose basis recurrences [`HarmonicProjector`] advances together.
const BASIS_LANES: usize = 8;
/// Rows of the basis made in a cache-resident tile before they are copied to their columns.
const BASIS_TILE: usize = 64;

impl HarmonicProjector {
    /// Prepares the fit for `n` samples at interval `dt` \[s\] and tones `freqs` \[Hz\].
    ///
    /// # Errors
    /// [`Error::Numerical`] when the basis is numerically singular (two frequencies closer
    /// than the resolution 1/(n dt), a frequency at 0 or Nyquist, or more parameters than
    /// samples).
    pub fn new(freqs: &[f64], n: usize, dt: f64) -> Result<Self> {
        let m = 1 + 2 * freqs.len();
        let fail = |message: String| Error::Numerical {
            context: "harmonic fit".to_string(),
            message,
        };
        if n < m {
            return Err(fail(format!("{n} samples for {m} harmonic parameters")));
        }
        let theta: Vec<f64> = freqs
            .iter()
            .map(|f| 2.0 * std::f64::consts::PI * f * dt)
            .collect();
        // Σ_k e^{iφk}, k = 0..n
        let s = |phi: f64| -> Complex64 {
            let half = 0.5 * phi;
            let den = half.sin();
            let d = if den.abs() < 1e-300 {
                n as f64
            } else {
                (n as f64 * half).sin() / den
            };
            Complex64::from_polar(1.0, half * (n as f64 - 1.0)) * d
        };
        let mut g = vec![0.0; m * m];
        g[0] = n as f64;
        for (i, &ti) in theta.iter().enumerate() {
            let e = s(ti);
            let (ci, si) = (1 + 2 * i, 2 + 2 * i);
            g[ci * m] = e.re;
            g[si * m] = e.im;
            for (j, &tj) in theta.iter().enumerate().take(i + 1) {
                let (cj, sj) = (1 + 2 * j, 2 + 2 * j);
                let dm = if i == j {
                    Complex64::new(n as f64, 0.0)
                } else {
                    s(ti - tj)
                };
                let sp = s(ti + tj);
                // Σ cos a cos b, Σ sin a sin b, Σ cos a sin b, Σ sin a cos b
                g[ci * m + cj] = 0.5 * (dm.re + sp.re);
                g[si * m + sj] = 0.5 * (dm.re - sp.re);
                g[ci * m + sj] = 0.5 * (sp.im - dm.im);
                g[si * m + cj] = 0.5 * (sp.im + dm.im);
            }
        }
        // symmetrise from the lower triangle
        for r in 0..m {
            for c in 0..r {
                g[c * m + r] = g[r * m + c];
            }
        }
        let mut chol = g;
        cholesky_in_place(&mut chol, m, PivotFloor::RelativeToDiagonal(1e-12)).map_err(|e| {
            fail(format!(
                "Gram matrix of {} tones over {n} samples is not positive definite ({e})",
                freqs.len()
            ))
        })?;
        Ok(HarmonicProjector {
            freqs: freqs.to_vec(),
            n,
            dt,
            theta,
            chol,
        })
    }

    /// The fitted frequencies \[Hz\].
    pub fn freqs(&self) -> &[f64] {
        &self.freqs
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True when no sample (never for a constructed fit).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Sample interval \[s\].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Mean and complex amplitudes (one per frequency) of `v`.
    ///
    /// # Panics
    /// When `v.len()` differs from n (a programming error).
    #[track_caller]
    pub fn amplitudes(&self, v: &[f64]) -> (f64, Vec<Complex64>) {
        assert_eq!(v.len(), self.n, "harmonic fit: signal length differs");
        let x = self.solve_many(&[v], 0, |_, _| {}).0.remove(0);
        (x[0], to_amplitudes(&x))
    }

    /// Rows `r0 .. r0 + rows` of the basis `[1, cos ω_1 t, sin ω_1 t, …]` into `out`
    /// (column-major, leading dimension `rows`). The rotation recurrence is re-anchored
    /// with `from_polar` at every multiple of 256 samples, so any block gives the same
    /// values as the whole basis.
    ///
    /// The recurrences of [`BASIS_LANES`] tones advance together (independent chains, so
    /// the processor overlaps them instead of waiting on one complex product per sample);
    /// each tone's values are those of its own recurrence z ← z·e^{iθ} with the complex
    /// product of `num_complex` written out (re = a·c − b·d, im = a·d + b·c; Rust never
    /// fuses them into a multiply-add), so bit for bit the one-tone-at-a-time result.
    fn basis_rows(&self, r0: usize, rows: usize, out: &mut [f64]) {
        out[..rows].fill(1.0);
        let start = r0 - r0 % ANCHOR;
        // values of the group's tones for BASIS_TILE consecutive rows, row-major
        let mut tile_re = [[0.0f64; BASIS_LANES]; BASIS_TILE];
        let mut tile_im = [[0.0f64; BASIS_LANES]; BASIS_TILE];
        for (g, group) in self.theta.chunks(BASIS_LANES).enumerate() {
            let lanes = group.len();
            let mut step_re = [0.0; BASIS_LANES];
            let mut step_im = [0.0; BASIS_LANES];
            for (l, &ti) in group.iter().enumerate() {
                let s = Complex64::from_polar(1.0, ti);
                step_re[l] = s.re;
                step_im[l] = s.im;
            }
            let cols = &mut out
                [(1 + 2 * BASIS_LANES * g) * rows..(1 + 2 * (BASIS_LANES * g + lanes)) * rows];
            let mut z_re = [1.0; BASIS_LANES];
            let mut z_im = [0.0; BASIS_LANES];
            let step = |z_re: &mut [f64; BASIS_LANES], z_im: &mut [f64; BASIS_LANES]| {
                for l in 0..BASIS_LANES {
                    let (a, b) = (z_re[l], z_im[l]);
                    z_re[l] = a * step_re[l] - b * step_im[l];
                    z_im[l] = a * step_im[l] + b * step_re[l];
                }
            };
            let mut k = start;
            while k < r0 + rows {
                // k is a multiple of ANCHOR here: re-anchor exactly
                for (l, &ti) in group.iter().enumerate() {
                    let z = Complex64::from_polar(1.0, ti * k as f64);
                    z_re[l] = z.re;
                    z_im[l] = z.im;
                }
                let end = (k + ANCHOR).min(r0 + rows);
                while k < r0 {
                    step(&mut z_re, &mut z_im);
                    k += 1;
                }
                while k < end {
                    let t = (end - k).min(BASIS_TILE);
                    for (re, im) in tile_re.iter_mut().zip(tile_im.iter_mut()).take(t) {
                        *re = z_re;
                        *im = z_im;
                        step(&mut z_re, &mut z_im);
                    }
                    let i0 = k - r0;
                    for l in 0..lanes {
                        let (c, rest) = cols[2 * l * rows..(2 * l + 2) * rows].split_at_mut(rows);
                        for (i, (dc, ds)) in c[i0..i0 + t]
                            .iter_mut()
                            .zip(&mut rest[i0..i0 + t])
                            .enumerate()
                        {
                            *dc = tile_re[i][l];
                            *ds = tile_im[i][l];
                        }
                    }
                    k += t;
                }
            }
        }
    }

    /// Least-squares coefficients (mean, cos, sin, …) of every column of an n × p matrix
    /// given block by block: `fill(r0, out)` writes its rows `r0 .. r0 + out.nrows()`.
    /// Hᵀ Θ is accumulated over blocks of [`HARMONIC_BLOCK`] rows.
    fn solve_columns(&self, p: usize, fill: impl FnMut(usize, MatMut<'_, f64>)) -> Vec<Vec<f64>> {
        self.solve_many(&[], p, fill).1
    }

    /// [`HarmonicProjector::solve_columns`] for the n × `p` matrix of `fill` and, beside
    /// it, for each of the `signals` alone (each as the one column of its own n × 1
    /// matrix, so with the very products [`HarmonicProjector::amplitudes`] makes), the
    /// basis of each block generated once for all of them. Returns (per signal, per
    /// column) coefficients.
    fn solve_many(
        &self,
        signals: &[&[f64]],
        p: usize,
        mut fill: impl FnMut(usize, MatMut<'_, f64>),
    ) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let m = 1 + 2 * self.theta.len();
        let mut htv = Mat::<f64>::zeros(m, p);
        let mut hts: Vec<Mat<f64>> = signals.iter().map(|_| Mat::zeros(m, 1)).collect();
        let block = HARMONIC_BLOCK.min(self.n);
        // every value of the basis and signal buffers is written before it is read (the
        // matrix buffer is zeroed: it is the caller's `fill` that writes it)
        let mut hb = Scratch::overwritten(block * m);
        let mut tb = Scratch::zeroed(block * p);
        let mut sb = Scratch::overwritten(if signals.is_empty() { 0 } else { block });
        let mut r0 = 0;
        while r0 < self.n {
            let rows = block.min(self.n - r0);
            self.basis_rows(r0, rows, &mut hb[..rows * m]);
            let h = MatRef::from_column_major_slice(&hb[..rows * m], rows, m);
            for (acc, v) in hts.iter_mut().zip(signals) {
                sb[..rows].copy_from_slice(&v[r0..r0 + rows]);
                add_at_b(
                    &mut acc.as_mut(),
                    h,
                    MatRef::from_column_major_slice(&sb[..rows], rows, 1),
                );
            }
            if p > 0 {
                fill(
                    r0,
                    MatMut::from_column_major_slice_mut(&mut tb[..rows * p], rows, p),
                );
                add_at_b(
                    &mut htv.as_mut(),
                    h,
                    MatRef::from_column_major_slice(&tb[..rows * p], rows, p),
                );
            }
            r0 += rows;
        }
        let solve = |acc: &Mat<f64>, j: usize| {
            let mut x: Vec<f64> = (0..m).map(|i| acc[(i, j)]).collect();
            cholesky_solve_in_place(&self.chol, m, &mut x);
            x
        };
        (
            hts.iter().map(|acc| solve(acc, 0)).collect(),
            (0..p).map(|j| solve(&htv, j)).collect(),
        )
    }

    /// [`HarmonicProjector::amplitudes`] of each of `signals` and
    /// [`HarmonicProjector::column_amplitudes_with`] of the n × `p` matrix of `fill`, in one
    /// pass that generates each block of the basis once for all of them (the same numbers
    /// as the separate calls, at about a third of the basis cost for two signals).
    ///
    /// # Panics
    /// When a signal's length differs from n, or `fill` changes the shape of `out`
    /// (programming errors).
    #[track_caller]
    pub fn amplitudes_and_columns_with(
        &self,
        signals: &[&[f64]],
        p: usize,
        fill: impl FnMut(usize, MatMut<'_, f64>),
    ) -> (Vec<SignalAmplitudes>, Vec<Vec<Complex64>>) {
        for v in signals {
            assert_eq!(v.len(), self.n, "harmonic fit: signal length differs");
        }
        let (sig, cols) = self.solve_many(signals, p, fill);
        (
            sig.iter().map(|x| (x[0], to_amplitudes(x))).collect(),
            cols.iter().map(|x| to_amplitudes(x)).collect(),
        )
    }

    /// Complex amplitudes of every column of `theta` (n × p): element `[j][i]` is the
    /// amplitude of column j at frequency i. Hᵀ Θ accumulated over row blocks, sequential.
    ///
    /// # Panics
    /// When `theta` does not have n rows (a programming error).
    #[track_caller]
    pub fn column_amplitudes(&self, theta: MatRef<'_, f64>) -> Vec<Vec<Complex64>> {
        assert_eq!(theta.nrows(), self.n, "harmonic fit: matrix rows differ");
        self.column_amplitudes_with(theta.ncols(), |r0, mut out| {
            let rows = out.nrows();
            out.copy_from(theta.subrows(r0, rows));
        })
    }

    /// As [`HarmonicProjector::column_amplitudes`] for an n × `p` matrix that is never held
    /// whole: `fill(r0, out)` writes its rows `r0 .. r0 + out.nrows()` into `out`
    /// (`out.nrows()` × `p`), for consecutive blocks of at most [`HARMONIC_BLOCK`] rows
    /// covering 0..n, once each. Memory: O(([`HARMONIC_BLOCK`])·(p + tones)).
    ///
    /// # Panics
    /// When `fill` changes the shape of `out` (a programming error).
    #[track_caller]
    pub fn column_amplitudes_with(
        &self,
        p: usize,
        fill: impl FnMut(usize, MatMut<'_, f64>),
    ) -> Vec<Vec<Complex64>> {
        self.solve_columns(p, fill)
            .iter()
            .map(|x| to_amplitudes(x))
            .collect()
    }
}

/// The mean and the complex amplitudes (one per frequency) of a signal, as
/// [`HarmonicProjector::amplitudes`] returns them.
pub type SignalAmplitudes = (f64, Vec<Complex64>);

fn to_amplitudes(x: &[f64]) -> Vec<Complex64> {
    (0..(x.len() - 1) / 2)
        .map(|i| Complex64::new(x[1 + 2 * i], -x[2 + 2 * i]))
        .collect()
}

/// The key frequencies of one force signal.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyFrequencies {
    /// The key tones, largest measured amplitude first.
    pub tones: Vec<Tone>,
    /// Index of each key tone in the candidate list of the [`HarmonicProjector`].
    pub index: Vec<usize>,
    /// Measured complex amplitudes A_i at the key tones.
    pub amplitudes: Vec<Complex64>,
}

/// Picks the `k` candidates of largest amplitude from the amplitudes of all candidates
/// (`all[i]` belongs to `tones[i]`); ties broken by lower frequency.
///
/// # Panics
/// When the two slices differ in length (a programming error).
#[track_caller]
pub fn select_key_frequencies(tones: &[Tone], all: &[Complex64], k: usize) -> KeyFrequencies {
    assert_eq!(tones.len(), all.len(), "one amplitude per tone");
    let mut idx: Vec<usize> = (0..tones.len()).collect();
    idx.sort_by(|&a, &b| all[b].norm().total_cmp(&all[a].norm()).then(a.cmp(&b)));
    idx.truncate(k);
    KeyFrequencies {
        tones: idx.iter().map(|&i| tones[i]).collect(),
        amplitudes: idx.iter().map(|&i| all[i]).collect(),
        index: idx,
    }
}

/// Eq. 14 key-frequency loss Σ|A_i − Â_i|² / Σ|A_i|² (A measured, Â model). Returns 0 when
/// both are zero and +∞ when only the measured amplitudes are.
///
/// # Panics
/// When the lengths differ (a programming error).
#[track_caller]
pub fn key_frequency_loss(a: &[Complex64], a_hat: &[Complex64]) -> f64 {
    assert_eq!(a.len(), a_hat.len(), "loss: lengths differ");
    let num: f64 = a.iter().zip(a_hat).map(|(x, y)| (x - y).norm_sqr()).sum();
    let den: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    if den > 0.0 {
        num / den
    } else if num == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// MFWA (paper Eq. 18): Σ_i w_i |Â_i|/|A_i| with w_i = |A_i|/Σ|A|, i.e. Σ|Â_i| / Σ|A_i|
/// (A measured, Â model, at the key frequencies). 1 = right amplitudes; may exceed 1.
/// Returns 0 when all measured amplitudes vanish.
///
/// # Panics
/// When the lengths differ (a programming error).
#[track_caller]
pub fn mfwa(a: &[Complex64], a_hat: &[Complex64]) -> f64 {
    assert_eq!(a.len(), a_hat.len(), "MFWA: lengths differ");
    let total: f64 = a.iter().map(|x| x.norm()).sum();
    if total <= 0.0 {
        return 0.0;
    }
    a_hat.iter().map(|x| x.norm()).sum::<f64>() / total
}

/// Phase-aware MFWA: Σ w_i max(0, Re(Â_i Ā_i)) / max(|A_i|,|Â_i|)². In [0, 1]; a line
/// counts fully only when amplitude and phase match.
///
/// # Panics
/// When the lengths differ (a programming error).
#[track_caller]
pub fn mfwa_phase(a: &[Complex64], a_hat: &[Complex64]) -> f64 {
    weighted(a, a_hat, |x, y| {
        let hi = x.norm().max(y.norm());
        if hi > 0.0 {
            (y * x.conj()).re.max(0.0) / (hi * hi)
        } else {
            1.0
        }
    })
}

#[track_caller]
fn weighted(
    a: &[Complex64],
    a_hat: &[Complex64],
    score: impl Fn(Complex64, Complex64) -> f64,
) -> f64 {
    assert_eq!(a.len(), a_hat.len(), "MFWA: lengths differ");
    let total: f64 = a.iter().map(|x| x.norm()).sum();
    if total <= 0.0 {
        return 0.0;
    }
    a.iter()
        .zip(a_hat)
        .map(|(x, y)| x.norm() / total * score(*x, *y))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn forcing(a: f64, h: f64) -> Forcing {
        Forcing {
            pitch: Some(a),
            heave: Some(h),
        }
    }

    #[test]
    fn tones_cover_combinations_and_merge() {
        let t = candidate_tones(&forcing(2.0, 1.3), 3, 20.0, 1.0 / 512.0);
        let has = |f: f64| t.iter().any(|x| (x.freq - f).abs() < 1e-9);
        for f in [
            2.0,
            1.3,
            0.7,
            3.3,
            4.0,
            2.6,
            6.0,
            3.9,
            2.0 + 2.6,
            4.0 - 1.3,
            4.0 + 1.3,
        ] {
            assert!(has(f), "{f}");
        }
        // 1:1 forcing: f_alpha - f_h = 0 is excluded, 2 f_alpha and f_alpha + f_h merge
        let t = candidate_tones(&forcing(2.0, 2.0), 3, 20.0, 1.0 / 512.0);
        let freqs: Vec<f64> = t.iter().map(|x| x.freq).collect();
        assert_eq!(freqs, vec![2.0, 4.0, 6.0]);
        assert_eq!(t[0].label(), "f_alpha");
        let only_pitch = Forcing {
            pitch: Some(1.5),
            heave: None,
        };
        let t = candidate_tones(&only_pitch, 5, 10.0, 0.01);
        assert_eq!(t.len(), 5);
        assert_eq!(
            Tone {
                freq: 0.7,
                m: 2,
                n: -1
            }
            .label(),
            "2*f_alpha-f_h"
        );
    }

    #[test]
    fn harmonic_gram_closed_form_matches_direct_sums() {
        let freqs = [0.7, 1.3, 2.0, 3.3];
        let fit = HarmonicProjector::new(&freqs, 777, 1.0 / 100.0).unwrap();
        let m = 1 + 2 * freqs.len();
        let mut b = vec![0.0; 777 * m];
        fit.basis_rows(0, 777, &mut b);
        let basis = |k: usize, i: usize| b[i * 777 + k];
        let mut g = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                g[i * m + j] = (0..777).map(|k| basis(k, i) * basis(k, j)).sum();
            }
        }
        // L Lᵀ = G
        for i in 0..m {
            for j in 0..m {
                let llt: f64 = (0..m)
                    .map(|k| fit.chol[i * m + k] * fit.chol[j * m + k])
                    .sum();
                assert!(
                    (llt - g[i * m + j]).abs() < 1e-9 * 777.0,
                    "{i} {j}: {llt} {}",
                    g[i * m + j]
                );
            }
        }
    }

    /// Basis blocks at any offset equal cos/sin of ω t to 1e-12; the block-wise projection
    /// over several [`HARMONIC_BLOCK`]s recovers known amplitudes of a signal and of a
    /// matrix column to 1e-12, and the matrix and closure forms agree.
    #[test]
    fn blocked_basis_and_projection_are_exact() {
        let freqs = [0.7, 1.3, 2.0];
        let dt = 1.0 / 512.0;
        let n = 2 * HARMONIC_BLOCK + 1000;
        let fit = HarmonicProjector::new(&freqs, n, dt).unwrap();
        let m = 1 + 2 * freqs.len();
        for (r0, rows) in [(0, 300), (255, 2), (1000, 5000), (n - 7, 7)] {
            let mut b = vec![0.0; rows * m];
            fit.basis_rows(r0, rows, &mut b);
            for k in 0..rows {
                assert_eq!(b[k], 1.0);
                for (i, f) in freqs.iter().enumerate() {
                    let w = 2.0 * std::f64::consts::PI * f * dt * (r0 + k) as f64;
                    assert!((b[(1 + 2 * i) * rows + k] - w.cos()).abs() < 1e-12);
                    assert!((b[(2 + 2 * i) * rows + k] - w.sin()).abs() < 1e-12);
                }
            }
        }
        let parts = [
            (0.7, Complex64::new(0.3, -0.1)),
            (1.3, Complex64::new(-1.0, 0.25)),
            (2.0, Complex64::new(0.0, 2.0)),
        ];
        let v = signal(n, dt, &parts, 0.4);
        let (mean, a) = fit.amplitudes(&v);
        assert!((mean - 0.4).abs() < 1e-12, "{mean}");
        for (i, (_, want)) in parts.iter().enumerate() {
            assert!((a[i] - want).norm() < 1e-12, "{i}: {} vs {want}", a[i]);
        }
        let theta = Mat::<f64>::from_fn(n, 2, |k, j| if j == 0 { v[k] } else { 2.0 * v[k] });
        let cols = fit.column_amplitudes(theta.as_ref());
        for i in 0..freqs.len() {
            assert!((cols[0][i] - a[i]).norm() < 1e-12);
            assert!((cols[1][i] - 2.0 * a[i]).norm() < 1e-12);
        }
    }

    fn signal(n: usize, dt: f64, parts: &[(f64, Complex64)], mean: f64) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 * dt;
                mean + parts
                    .iter()
                    .map(|(f, a)| {
                        (a * Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * f * t)).re
                    })
                    .sum::<f64>()
            })
            .collect()
    }

    #[test]
    fn amplitudes_are_exact_for_non_integer_periods() {
        let fc = forcing(2.0, 1.3);
        let parts = [
            (2.0, Complex64::new(1.0, -0.5)),
            (1.3, Complex64::new(-0.3, 0.2)),
            (0.7, Complex64::new(0.05, 0.1)),
            (3.3, Complex64::new(0.2, 0.0)),
        ];
        let dt = 1.0 / 512.0;
        // 20 and 20.37 periods of the pitch forcing
        let mut losses = Vec::new();
        for periods in [20.0f64, 20.37] {
            let n = (periods / 2.0 / dt).round() as usize;
            let dur = n as f64 * dt;
            let tones = candidate_tones(&fc, 5, dur, dt);
            let freqs: Vec<f64> = tones.iter().map(|t| t.freq).collect();
            let fit = HarmonicProjector::new(&freqs, n, dt).unwrap();
            let y = signal(n, dt, &parts, 0.4);
            let (mean, all) = fit.amplitudes(&y);
            assert!((mean - 0.4).abs() < 1e-10);
            for (f, a) in &parts {
                let i = freqs.iter().position(|x| (x - f).abs() < 1e-9).unwrap();
                assert!((all[i] - a).norm() < 1e-10, "{periods}: {f} {} {a}", all[i]);
            }
            let key = select_key_frequencies(&tones, &all, 4);
            assert!((key.tones[0].freq - 2.0).abs() < 1e-12);
            // a model 10 % too small on the 2 Hz line
            let y_hat = signal(
                n,
                dt,
                &[(2.0, parts[0].1 * 0.9), parts[1], parts[2], parts[3]],
                0.4,
            );
            let (_, all_hat) = fit.amplitudes(&y_hat);
            let a_hat: Vec<Complex64> = key.index.iter().map(|&i| all_hat[i]).collect();
            losses.push(key_frequency_loss(&key.amplitudes, &a_hat));
        }
        let expected = (0.1f64 * parts[0].1.norm()).powi(2)
            / parts.iter().map(|p| p.1.norm_sqr()).sum::<f64>();
        for l in &losses {
            assert!((l - expected).abs() < 1e-10 * expected, "{l} vs {expected}");
        }
    }

    #[test]
    fn fft_bin_version_would_leak() {
        // guard for the claim above: a plain DFT bin at 2 Hz of a 20.37-period record is
        // off by more than 0.5 % while the least-squares fit is exact
        let dt = 1.0 / 512.0;
        let n = (20.37f64 / 2.0 / dt).round() as usize;
        let y = signal(
            n,
            dt,
            &[
                (2.0, Complex64::new(1.0, 0.0)),
                (1.3, Complex64::new(0.8, 0.0)),
            ],
            0.0,
        );
        let w = 2.0 * std::f64::consts::PI * 2.0 * dt;
        let bin: Complex64 = y
            .iter()
            .enumerate()
            .map(|(k, v)| Complex64::from_polar(*v, -w * k as f64))
            .sum::<Complex64>()
            * (2.0 / n as f64);
        assert!((bin.norm() - 1.0).abs() > 0.005, "{}", bin.norm());
    }

    #[test]
    fn mfwa_bounds_and_reduction() {
        let a = [
            Complex64::new(1.0, 0.0),
            Complex64::new(0.0, 0.5),
            Complex64::new(0.2, 0.2),
        ];
        assert!((mfwa(&a, &a) - 1.0).abs() < 1e-15);
        assert!((mfwa_phase(&a, &a) - 1.0).abs() < 1e-15);
        // Eq. 18: Σ w_i |Â_i|/|A_i| with w_i = |A_i|/Σ|A|, written out term by term
        let under: Vec<Complex64> = a.iter().zip([0.5, 0.9, 0.1]).map(|(x, s)| x * s).collect();
        let total: f64 = a.iter().map(|x| x.norm()).sum();
        let by_terms: f64 = a
            .iter()
            .zip(&under)
            .map(|(x, y)| x.norm() / total * (y.norm() / x.norm()))
            .sum();
        assert!((mfwa(&a, &under) - by_terms).abs() < 1e-14);
        // over-prediction gives MFWA > 1 (the paper's formula is not bounded by 1)
        let over: Vec<Complex64> = a.iter().map(|x| x * 3.0).collect();
        assert!((mfwa(&a, &over) - 3.0).abs() < 1e-14);
        // opposite errors on two lines cancel in Eq. 18 (a known blind spot)
        let mixed = [
            a[0] * 1.2,
            a[1],
            a[2] - a[2] * (0.2 * a[0].norm() / a[2].norm()),
        ];
        assert!((mfwa(&a, &mixed) - 1.0).abs() < 1e-14);
        // a phase flip keeps MFWA but zeroes the phase-aware variant
        let flipped: Vec<Complex64> = a.iter().map(|x| -x).collect();
        assert!((mfwa(&a, &flipped) - 1.0).abs() < 1e-15);
        assert_eq!(mfwa_phase(&a, &flipped), 0.0);
        assert_eq!(
            mfwa(&[Complex64::new(0.0, 0.0)], &[Complex64::new(1.0, 0.0)]),
            0.0
        );
        let quarter: Vec<Complex64> = a.iter().map(|x| x * Complex64::new(0.0, 1.0)).collect();
        assert!(mfwa_phase(&a, &quarter).abs() < 1e-15);
        for s in [0.0, 0.3, 1.7] {
            let b: Vec<Complex64> = a.iter().map(|x| x * Complex64::from_polar(s, s)).collect();
            let v = mfwa_phase(&a, &b);
            assert!((0.0..=1.0 + 1e-15).contains(&v));
        }
    }

    #[test]
    fn r_squared_basics() {
        let y = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(r_squared(&y, &y), 1.0);
        assert!((r_squared(&y, &[2.5; 4]) - 0.0).abs() < 1e-15);
        assert!(r_squared(&y, &[0.0; 4]) < 0.0);
    }
}
