//! Linear flutter-derivative tables H1*–H4*, A1*–A4* over K, with Roger's
//! rational-function approximation (RFA) for the time domain.

use nalgebra::{DMatrix, DVector, Matrix2};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::{AeroModel, Flow};
use crate::error::positive;
use crate::optim::nelder_mead;
use crate::theodorsen::{flat_plate_derivatives, Derivatives};
use crate::{Error, Result};
use identify::numerics::interp::Spline;

/// Roger's rational-function approximation of the nondimensional transfer matrix
/// (C_L, C_M)ᵀ = Q(p̄) (h/B, α)ᵀ, p̄ = iK (Laplace variable in units of U/B):
///
/// Q(p̄) ≈ A₀ + A₁ p̄ + A₂ p̄² + Σ_j A_{2+j} p̄ / (p̄ + γ_j).
///
/// The lag roots γ_j are shared by all entries and chosen by Nelder–Mead on log γ,
/// minimising the weighted least-squares misfit; for fixed γ the A's are linear least
/// squares over the tabulated K (real and imaginary parts stacked, each K weighted by
/// 1/‖Q(K)‖_F so that the fit is relative at every K).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RfaFit {
    /// Lag roots γ_j (nondimensional, in units of U/B).
    pub lags: Vec<f64>,
    /// Coefficient matrices A₀, A₁, A₂, A₃… (row = C_L/C_M, column = h/B, α).
    pub a: Vec<[[f64; 2]; 2]>,
    /// Largest relative misfit max_K ‖Q_fit − Q‖_F / ‖Q‖_F over the table.
    pub max_rel_error: f64,
    /// Root-mean-square relative misfit over the table.
    pub rms_rel_error: f64,
}

impl RfaFit {
    /// Fitted Q at reduced frequency K.
    pub fn q(&self, k: f64) -> [[Complex64; 2]; 2] {
        let p = Complex64::new(0.0, k);
        let mut out = [[Complex64::new(0.0, 0.0); 2]; 2];
        for (r, row) in out.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                let mut z = self.a[0][r][c] + self.a[1][r][c] * p + self.a[2][r][c] * p * p;
                for (j, g) in self.lags.iter().enumerate() {
                    z += self.a[3 + j][r][c] * p / (p + g);
                }
                *v = z;
            }
        }
        out
    }
}

/// Linear flutter-derivative table over K with cubic-spline interpolation and an RFA for
/// the time domain.
///
/// Frequency domain: the eight real functions K²H*, K²A* (the entries of Q, which are
/// smooth in K unlike H*, A* themselves) are interpolated by natural cubic splines in K
/// inside the table, held at the end values above it and extrapolated quasi-statically
/// below it ([`DerivativeTable::q`]; divergence uses K = 0). Time domain: [`RfaFit`] with 2 lag states per lag root
/// (ẋ_j = −γ_j (U/B) x_j + d/dt (h/B, α)).
#[derive(Debug, Clone)]
pub struct DerivativeTable {
    chord: f64,
    rows: Vec<Derivatives>,
    splines: Vec<Spline>,
    rfa: RfaFit,
}

fn q_frob(q: &[[Complex64; 2]; 2]) -> f64 {
    q.iter().flatten().map(|z| z.norm_sqr()).sum::<f64>().sqrt()
}

impl DerivativeTable {
    /// Builds the table from rows sorted by strictly increasing K > 0 and fits an RFA with
    /// `n_lag` lag roots (0–4; 3 or 4 recommended).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a bad chord or `n_lag`; [`Error::InvalidTable`] when
    /// K is not strictly increasing and positive, a value is non-finite, or there are
    /// fewer than 4 rows or too few rows for the RFA unknowns.
    pub fn new(chord: f64, rows: Vec<Derivatives>, n_lag: usize) -> Result<Self> {
        positive("chord", chord)?;
        if n_lag > 4 {
            return Err(Error::param("n_lag", n_lag as f64, "must be 0..=4"));
        }
        let bad = |m: String| Error::InvalidTable {
            table: "flutter derivatives".into(),
            message: m,
        };
        if rows.len() < 4 || 2 * rows.len() < 2 * (3 + n_lag) {
            return Err(bad(format!(
                "{} rows; need at least max(4, {}) rows",
                rows.len(),
                3 + n_lag
            )));
        }
        for (i, r) in rows.iter().enumerate() {
            let vals = [r.k, r.h1, r.h2, r.h3, r.h4, r.a1, r.a2, r.a3, r.a4];
            if vals.iter().any(|v| !v.is_finite()) || r.k <= 0.0 {
                return Err(bad(format!(
                    "row {i} (K = {}): non-finite value or K ≤ 0",
                    r.k
                )));
            }
            if i > 0 && r.k <= rows[i - 1].k {
                return Err(bad(format!(
                    "row {i}: K = {} not above previous K = {}",
                    r.k,
                    rows[i - 1].k
                )));
            }
        }
        let ks: Vec<f64> = rows.iter().map(|r| r.k).collect();
        let qs: Vec<[[Complex64; 2]; 2]> = rows.iter().map(|r| r.q_matrix()).collect();
        let mut splines = Vec::with_capacity(8);
        for r in 0..2 {
            for c in 0..2 {
                let re: Vec<f64> = qs.iter().map(|q| q[r][c].re).collect();
                let im: Vec<f64> = qs.iter().map(|q| q[r][c].im).collect();
                splines.push(Spline::new(&ks, &re));
                splines.push(Spline::new(&ks, &im));
            }
        }
        let mut table = DerivativeTable {
            chord,
            rows,
            splines,
            rfa: RfaFit {
                lags: Vec::new(),
                a: Vec::new(),
                max_rel_error: 0.0,
                rms_rel_error: 0.0,
            },
        };
        // The RFA is fitted to the table's rows and to the frequency-domain continuation
        // below the lowest K (`q`: K = 0 and 1/4, 1/2, 3/4 of it), so that the time domain
        // agrees with the frequency domain where slow motions (static divergence, the
        // start of a transient) live; without them a near-zero lag root could pair with a
        // large constant and make the quasi-static stiffness arbitrary (docs/DECISIONS.md).
        let k0 = ks[0];
        let mut fit_ks: Vec<f64> = [0.0, 0.25, 0.5, 0.75].iter().map(|f| f * k0).collect();
        let mut fit_qs: Vec<[[Complex64; 2]; 2]> = fit_ks.iter().map(|&k| table.q(k)).collect();
        fit_ks.extend_from_slice(&ks);
        fit_qs.extend_from_slice(&qs);
        table.rfa = fit_rfa(&fit_ks, &fit_qs, &ks, &qs, n_lag)?;
        Ok(table)
    }

    /// Table of the flat-plate closed forms ([`flat_plate_derivatives`]) at the given K.
    ///
    /// # Errors
    /// As [`DerivativeTable::new`].
    pub fn flat_plate(chord: f64, ks: &[f64], n_lag: usize) -> Result<Self> {
        Self::new(
            chord,
            ks.iter().map(|&k| flat_plate_derivatives(k)).collect(),
            n_lag,
        )
    }

    /// The tabulated rows.
    pub fn rows(&self) -> &[Derivatives] {
        &self.rows
    }

    /// The rational-function approximation used in the time domain, with its fit error.
    pub fn rfa(&self) -> &RfaFit {
        &self.rfa
    }

    /// Interpolated Q(K) (entries K²(H4* + iH1*) … as in [`Derivatives::q_matrix`]).
    ///
    /// Inside the table: natural cubic splines. Above the highest K: held at the end
    /// values. Below the lowest tabulated K₀ (quasi-static extrapolation, down to K = 0
    /// for divergence): the real parts (stiffness, K²H4*, K²A3* …) continue the straight
    /// line through the two lowest nodes — for the flat plate Re Q is linear in K near 0
    /// because F(k) = 1 − πk/2 + O(k² ln k) — and the imaginary parts (damping,
    /// K²H1* …) fall linearly to 0 at K = 0, since a damping force vanishes with the
    /// frequency (Im Q = O(K)).
    pub fn q(&self, k: f64) -> [[Complex64; 2]; 2] {
        let s = &self.splines;
        let k0 = self.rows[0].k;
        let entry = |i: usize| -> Complex64 {
            if k >= k0 {
                return Complex64::new(s[2 * i].eval(k), s[2 * i + 1].eval(k));
            }
            let k1 = self.rows[1].k;
            let (r0, r1) = (s[2 * i].eval(k0), s[2 * i].eval(k1));
            let re = r0 + (r1 - r0) / (k1 - k0) * (k - k0);
            let im = s[2 * i + 1].eval(k0) * k.max(0.0) / k0;
            Complex64::new(re, im)
        };
        [[entry(0), entry(1)], [entry(2), entry(3)]]
    }

    /// Interpolated derivatives at K.
    pub fn derivatives(&self, k: f64) -> Derivatives {
        Derivatives::from_q_matrix(k, self.q(k))
    }
}

/// Weighted LS for fixed lags; returns (coefficient matrices, weighted residual norm²).
fn rfa_linear(
    ks: &[f64],
    qs: &[[[Complex64; 2]; 2]],
    lags: &[f64],
) -> Option<(Vec<[[f64; 2]; 2]>, f64)> {
    let n_unk = 3 + lags.len();
    let n_eq = 2 * ks.len();
    let mut a = DMatrix::<f64>::zeros(n_eq, n_unk);
    for (i, &k) in ks.iter().enumerate() {
        let w = 1.0 / q_frob(&qs[i]).max(1e-300);
        // Re: a0 − a2 K² + Σ c_j K²/(K²+γ²);  Im: a1 K + Σ c_j K γ/(K²+γ²)
        a[(2 * i, 0)] = w;
        a[(2 * i, 2)] = -w * k * k;
        a[(2 * i + 1, 1)] = w * k;
        for (j, &g) in lags.iter().enumerate() {
            let d = k * k + g * g;
            a[(2 * i, 3 + j)] = w * k * k / d;
            a[(2 * i + 1, 3 + j)] = w * k * g / d;
        }
    }
    let svd = a.clone().svd(true, true);
    let mut coefs = vec![[[0.0; 2]; 2]; n_unk];
    let mut res2 = 0.0;
    for r in 0..2 {
        for c in 0..2 {
            let mut rhs = DVector::<f64>::zeros(n_eq);
            for (i, q) in qs.iter().enumerate() {
                let w = 1.0 / q_frob(q).max(1e-300);
                rhs[2 * i] = w * q[r][c].re;
                rhs[2 * i + 1] = w * q[r][c].im;
            }
            let x = svd.solve(&rhs, 1e-13).ok()?;
            res2 += (&a * &x - &rhs).norm_squared();
            for (u, v) in x.iter().enumerate() {
                coefs[u][r][c] = *v;
            }
        }
    }
    Some((coefs, res2))
}

/// Roger RFA fitted to (`ks`, `qs`) (K ≥ 0, increasing); the reported errors are over the
/// table rows (`rows_k`, `rows_q`). Lag roots stay within [K_min/10, 10 K_max] of the rows.
fn fit_rfa(
    ks: &[f64],
    qs: &[[[Complex64; 2]; 2]],
    rows_k: &[f64],
    rows_q: &[[[Complex64; 2]; 2]],
    n_lag: usize,
) -> Result<RfaFit> {
    let (kmin, kmax) = (rows_k[0], rows_k[rows_k.len() - 1]);
    let x0: Vec<f64> = (0..n_lag)
        .map(|j| kmin.ln() + (kmax / kmin).ln() * (j as f64 + 0.5) / n_lag as f64)
        .collect();
    let lags_of = |x: &[f64]| -> Vec<f64> { x.iter().map(|v| v.exp()).collect() };
    let lags = if n_lag == 0 {
        Vec::new()
    } else {
        let objective = |x: &[f64]| -> f64 {
            // Keep lags distinct and inside a broad band; coincident lags are redundant.
            let l = lags_of(x);
            for i in 0..l.len() {
                for j in 0..i {
                    if (l[i] / l[j]).ln().abs() < 0.05 {
                        return f64::MAX;
                    }
                }
                if l[i] < 0.1 * kmin || l[i] > 10.0 * kmax {
                    return f64::MAX;
                }
            }
            rfa_linear(ks, qs, &l).map(|(_, r)| r).unwrap_or(f64::MAX)
        };
        let (x, _) = nelder_mead(objective, &x0, 0.5, 400 * n_lag);
        let mut l = lags_of(&x);
        l.sort_by(f64::total_cmp);
        l
    };
    let (a, _) = rfa_linear(ks, qs, &lags).ok_or_else(|| {
        Error::numerical("RFA fit", format!("least squares failed for lags {lags:?}"))
    })?;
    let mut fit = RfaFit {
        lags,
        a,
        max_rel_error: 0.0,
        rms_rel_error: 0.0,
    };
    let mut sum = 0.0;
    for (k, q) in rows_k.iter().zip(rows_q) {
        let f = fit.q(*k);
        let mut d = 0.0;
        for r in 0..2 {
            for c in 0..2 {
                d += (f[r][c] - q[r][c]).norm_sqr();
            }
        }
        let rel = d.sqrt() / q_frob(q);
        fit.max_rel_error = fit.max_rel_error.max(rel);
        sum += rel * rel;
    }
    fit.rms_rel_error = (sum / rows_k.len() as f64).sqrt();
    Ok(fit)
}

impl AeroModel for DerivativeTable {
    fn name(&self) -> String {
        format!(
            "derivative table ({} K, RFA {} lags)",
            self.rows.len(),
            self.rfa.lags.len()
        )
    }
    fn chord(&self) -> f64 {
        self.chord
    }
    fn n_lag(&self) -> usize {
        2 * self.rfa.lags.len()
    }
    fn is_linear(&self) -> bool {
        true
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        let a2 = &self.rfa.a[2];
        let c = 0.5 * flow.rho * self.chord * self.chord;
        let bb = self.chord;
        Matrix2::new(
            c * a2[0][0],
            c * bb * a2[0][1],
            c * bb * a2[1][0],
            c * bb * bb * a2[1][1],
        )
    }
    #[inline]
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        let bb = self.chord;
        let u = flow.u;
        let qn = [q[0] / bb, q[1]];
        let qdn = [qd[0] / bb * (bb / u), qd[1] * (bb / u)];
        let a = &self.rfa.a;
        let mut c = [0.0; 2];
        for (r, cr) in c.iter_mut().enumerate() {
            let mut v =
                a[0][r][0] * qn[0] + a[0][r][1] * qn[1] + a[1][r][0] * qdn[0] + a[1][r][1] * qdn[1];
            for j in 0..self.rfa.lags.len() {
                v += a[3 + j][r][0] * lag[2 * j] + a[3 + j][r][1] * lag[2 * j + 1];
            }
            *cr = v;
        }
        let qdyn = flow.q_dyn();
        [qdyn * bb * c[0], qdyn * bb * bb * c[1]]
    }
    #[inline]
    fn lag_rates(&self, flow: &Flow, _q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]) {
        let bb = self.chord;
        let s = flow.u / bb;
        for (j, g) in self.rfa.lags.iter().enumerate() {
            out[2 * j] = -g * s * lag[2 * j] + qd[0] / bb;
            out[2 * j + 1] = -g * s * lag[2 * j + 1] + qd[1];
        }
    }
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        let bb = self.chord;
        let k = bb * omega / flow.u;
        let q = self.q(k);
        let qd = flow.q_dyn();
        Matrix2::new(
            qd * q[0][0],
            qd * bb * q[0][1],
            qd * bb * q[1][0],
            qd * bb * bb * q[1][1],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::state_space_response;

    fn grid() -> Vec<f64> {
        (1..=60).map(|i| 0.05 * i as f64).collect()
    }

    #[test]
    fn interpolation_reproduces_closed_form_between_knots() {
        let t = DerivativeTable::flat_plate(0.5, &grid(), 3).unwrap();
        for k in [0.33, 0.71, 1.37, 2.52] {
            let d = t.derivatives(k);
            let e = flat_plate_derivatives(k);
            for (g, w) in [
                (d.h1, e.h1),
                (d.h3, e.h3),
                (d.a2, e.a2),
                (d.a3, e.a3),
                (d.h4, e.h4),
            ] {
                assert!(
                    (g - w).abs() < 2e-4 * w.abs().max(1.0),
                    "K = {k}: {g} vs {w}"
                );
            }
        }
    }

    #[test]
    fn rfa_fit_error_is_small_and_time_domain_matches_it() {
        let t = DerivativeTable::flat_plate(0.5, &grid(), 4).unwrap();
        let fit = t.rfa();
        assert!(
            fit.max_rel_error < 0.01,
            "RFA max relative error {}",
            fit.max_rel_error
        );
        // The lag-state realisation reproduces the fitted Q (checks the state-space wiring).
        let flow = Flow { rho: 1.2, u: 10.0 };
        for kk in [0.2, 0.7, 1.5] {
            let omega = kk * flow.u / 0.5;
            let ss = state_space_response(&t, &flow, omega).unwrap();
            let q = fit.q(kk);
            let qd = flow.q_dyn();
            let want = Matrix2::new(
                qd * q[0][0],
                qd * 0.5 * q[0][1],
                qd * 0.5 * q[1][0],
                qd * 0.25 * q[1][1],
            );
            let scale = want.iter().map(|z| z.norm()).fold(0.0, f64::max);
            for (g, w) in ss.iter().zip(want.iter()) {
                assert!((g - w).norm() < 1e-8 * scale, "K = {kk}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn bad_tables_are_rejected_with_the_row() {
        let mut rows: Vec<Derivatives> =
            grid().iter().map(|&k| flat_plate_derivatives(k)).collect();
        rows.swap(3, 4);
        let e = DerivativeTable::new(0.5, rows, 2).unwrap_err();
        assert!(e.to_string().contains("row 4"), "{e}");
        let e = DerivativeTable::new(
            0.5,
            grid()[..3]
                .iter()
                .map(|&k| flat_plate_derivatives(k))
                .collect(),
            2,
        )
        .unwrap_err();
        assert!(e.to_string().contains("3 rows"), "{e}");
    }
}
