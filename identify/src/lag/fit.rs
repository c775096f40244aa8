//! Identification of the lag law ([`super::law`]) from forced-motion records.
//!
//! Variable projection: the nonlinear parameters θ = (τ₁, τ₂, α*, m) set the separation
//! state x(t) of every case at its periodic steady state ([`super::series`]); given θ, the
//! force coefficients are linear least squares on the columns ([`LagColumn`]) — the lift on
//! a fixed support (default 1, α_e·κ(x), Bα̇/U), the moment on a support selected sparsely
//! from all six columns by the δ path of [`crate::regress::path`] (STLSQ with the
//! scale-free contribution threshold, the sparsest support whose loss 1 − R² is within the
//! path's limit of the full fit).
//!
//! 1. Initial values from the data ([`initial_guess`]): the attached slope C_Lα from the
//!    samples with |α_e| ≤ 0.12 rad (−2π, lift down, when there are too few or the slope is
//!    implausible); the hidden state from the Kirchhoff relation κ(x) = C_L/(C_Lα α_e)
//!    clamped to \[¼, 1\], x = (2√κ − 1)²; (α*, m) on a grid minimising Σ(x − x₀(α_e))²;
//!    (τ₁, τ₂) by linear least squares of the lag equation
//!    x − x₀(α_e) = −τ₁ dx/ds − τ₂ (q/2) x₀′(α_e).
//! 2. Output error: Levenberg–Marquardt on θ (forward-difference Jacobian of the projected
//!    residual, box bounds by clamping) minimising
//!    Σ r_L²/SS_L + Σ r_M²/SS_M = (1 − R²_L) + (1 − R²_M) over all training samples,
//!    first with the full moment support, then again on the selected one.
//! 3. Report ([`LagReport`]): per-case R², θ with units and Gauss–Newton standard errors and
//!    correlations from (JᵀJ)⁻¹ at the optimum.

use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::numerics::qr::ThinQr;
use crate::numerics::{cholesky_solve, PivotFloor};
use crate::record::NondimCase;
use crate::regress::path::PathOptions;
use crate::regress::plugin::{run_path, FitSettings, GroupInput, RegressorChoice};
use crate::regress::plugins;
use crate::regress::{CaseFactor, CaseProblem, Measure, Stlsq};
use crate::{Error, Result};

use super::law::{FittedRange, LagChannel, LagColumn, LagLaw};
use super::series::LagSeries;

/// Bounds of θ = (τ₁ \[b/U\], τ₂ \[b/U\], α* \[rad\], m): τ₁ ∈ (0.05, 100], τ₂ ∈ \[0, 100\],
/// α* ∈ (0.02, 1.2), m ∈ \[1, 20\]. A fit ending on an open bound is refused.
pub const BOUNDS: [(f64, f64); 4] = [(0.05, 100.0), (0.0, 100.0), (0.02, 1.2), (1.0, 20.0)];

/// Names, symbols and units of θ.
pub const PARAMETERS: [(&str, &str, &str); 4] = [
    ("tau1", "τ₁", "b/U (convective times)"),
    ("tau2", "τ₂", "b/U (convective times)"),
    ("alpha_star", "α*", "rad"),
    ("sharpness", "m", "1"),
];

/// |corr(τ₁, τ₂)| above which the report says the data cannot separate the two lags.
pub const COLLINEAR_CORRELATION: f64 = 0.9;

/// Options of [`fit`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagFitOptions {
    /// Lift support (default 1, α_e·κ(x), Bα̇/U).
    pub lift_columns: Vec<LagColumn>,
    /// Candidate moment columns of the sparse selection (default the six lagged columns,
    /// [`LagColumn::LAGGED`]).
    pub moment_columns: Vec<LagColumn>,
    /// Levenberg–Marquardt iterations per stage.
    pub max_iter: usize,
    /// δ path of the moment selection (contribution measure).
    pub path: PathOptions,
    /// Fit the law with its attached-flow circulation lag ([`LagLaw::circulation_lag`],
    /// default on: fixed published constants, no parameter fitted).
    #[serde(default = "default_true")]
    pub circulation_lag: bool,
    /// Pitch-rate share c of the effective angle α_e = α + ḣ/U + c·Bα̇/U
    /// ([`LagLaw::rate_share`]), fixed, in \[−1, 1\]; default 0. (½ − a)/2 is the
    /// three-quarter-chord downwash of records whose moment is about a semichords aft of
    /// mid-chord.
    #[serde(default)]
    pub rate_share: f64,
    /// Pressure lag τ_p \[b/U\] of the separation input ([`LagLaw::pressure_lag`]), in
    /// \[0, 100\]; 0 (default) = off. The start value when `fit_pressure_lag` is set.
    #[serde(default)]
    pub pressure_lag: f64,
    /// Fit the rate share c by output error ([`fit`]: the objective profiled over c ∈
    /// \[0, 1\], every other constant refitted at each c) instead of holding it at
    /// `rate_share`.
    #[serde(default)]
    pub fit_rate_share: bool,
    /// Fit the pressure lag τ_p by output error (the objective profiled over τ_p ∈
    /// \[0, [`PROFILE_PRESSURE_LAG_MAX`]\]) instead of holding it at `pressure_lag`.
    #[serde(default)]
    pub fit_pressure_lag: bool,
}

/// Largest pressure lag τ_p \[b/U\] the profile of [`fit`] searches (Beddoes–Leishman's
/// T_p is 1.5–2 convective times for aerofoils; three times that leaves room).
pub const PROFILE_PRESSURE_LAG_MAX: f64 = 6.0;

fn default_true() -> bool {
    true
}

impl Default for LagFitOptions {
    fn default() -> Self {
        LagFitOptions {
            lift_columns: vec![LagColumn::One, LagColumn::Kirchhoff, LagColumn::Q],
            moment_columns: LagColumn::LAGGED.to_vec(),
            max_iter: 40,
            path: PathOptions::for_measure(Measure::Contribution),
            circulation_lag: true,
            rate_share: 0.0,
            pressure_lag: 0.0,
            fit_rate_share: false,
            fit_pressure_lag: false,
        }
    }
}

impl LagFitOptions {
    /// The same options with the Kirchhoff columns replaced by the separated-flow blend of
    /// Hansen, Gaunaa & Madsen (2004): [`LagColumn::Kirchhoff`] → [`LagColumn::Blend`] and
    /// [`LagColumn::KirchhoffSep`] → [`LagColumn::BlendSep`] in the lift support and the
    /// moment candidates (a column already present is not repeated).
    pub fn with_blend(mut self) -> Self {
        for cols in [&mut self.lift_columns, &mut self.moment_columns] {
            let mut out: Vec<LagColumn> = Vec::with_capacity(cols.len());
            for c in cols.iter() {
                let n = match c {
                    LagColumn::Kirchhoff => LagColumn::Blend,
                    LagColumn::KirchhoffSep => LagColumn::BlendSep,
                    other => *other,
                };
                if !out.contains(&n) {
                    out.push(n);
                }
            }
            *cols = out;
        }
        self
    }

    /// Checks the options.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] for an empty or repeated column list, `max_iter` = 0, a
    /// `rate_share` outside \[−1, 1\] or bad path options.
    pub fn validate(&self) -> Result<()> {
        for (name, cols) in [
            ("lift_columns", &self.lift_columns),
            ("moment_columns", &self.moment_columns),
        ] {
            let mut c = cols.clone();
            c.sort();
            c.dedup();
            if cols.is_empty() || c.len() != cols.len() {
                return Err(Error::InvalidOption {
                    name: name.into(),
                    message: "must list at least one column, each once".into(),
                });
            }
        }
        if !(self.rate_share.is_finite() && self.rate_share.abs() <= 1.0) {
            return Err(Error::InvalidOption {
                name: "rate_share".into(),
                message: format!("{}: must be in [-1, 1]", self.rate_share),
            });
        }
        if !(self.pressure_lag >= 0.0 && self.pressure_lag <= 100.0) {
            return Err(Error::InvalidOption {
                name: "pressure_lag".into(),
                message: format!(
                    "{}: must be in [0, 100] convective times",
                    self.pressure_lag
                ),
            });
        }
        if self.max_iter == 0 {
            return Err(Error::InvalidOption {
                name: "max_iter".into(),
                message: "must be ≥ 1".into(),
            });
        }
        self.path.validate()
    }
}

/// One parameter of θ in the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagParameter {
    /// Name (`tau1`, `tau2`, `alpha_star`, `sharpness`).
    pub name: String,
    /// Symbol (τ₁ …).
    pub symbol: String,
    /// Value.
    pub value: f64,
    /// Unit.
    pub unit: String,
    /// Gauss–Newton standard error s·√((JᵀJ)⁻¹)ᵢᵢ (white-residual assumption: optimistic
    /// for correlated residuals); `None` when JᵀJ is singular.
    pub standard_error: Option<f64>,
}

/// Score of one case under a lag law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagCaseScore {
    /// Case id.
    pub id: String,
    /// Reduced frequency K = Bω/U.
    pub k: f64,
    /// Mean angle \[deg\].
    pub mean_deg: f64,
    /// Pitch amplitude (half peak-to-peak) \[deg\].
    pub amplitude_deg: f64,
    /// Whether the periodic steady state was used (else a settled start).
    pub periodic: bool,
    /// Samples scored (after any settling).
    pub samples: usize,
    /// R² of C_L.
    pub r2_lift: f64,
    /// R² of C_M.
    pub r2_moment: f64,
}

/// The moment support selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MomentSelection {
    /// Candidate columns.
    pub candidates: Vec<LagColumn>,
    /// Selected columns.
    pub selected: Vec<LagColumn>,
    /// Loss 1 − R² of the full support.
    pub loss_full: f64,
    /// Loss 1 − R² of the selected support.
    pub loss_selected: f64,
    /// Loss limit of the path.
    pub limit: f64,
}

/// What [`fit`] reports beside the law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagReport {
    /// θ with units and standard errors.
    pub parameters: Vec<LagParameter>,
    /// Correlation matrix of θ (order of `parameters`) from (JᵀJ)⁻¹; `None` if singular.
    pub correlation: Option<[[f64; 4]; 4]>,
    /// corr(τ₁, τ₂).
    pub tau_correlation: Option<f64>,
    /// |corr(τ₁, τ₂)| > [`COLLINEAR_CORRELATION`]: the data fix little more than a
    /// combination of the two lags (typical at low K).
    pub tau_collinear: bool,
    /// Per training case.
    pub cases: Vec<LagCaseScore>,
    /// Moment support selection.
    pub moment_selection: MomentSelection,
    /// Initial θ (from the data, before output error).
    pub initial: [f64; 4],
    /// Final objective (1 − R²_L) + (1 − R²_M) over all training samples.
    pub objective: f64,
    /// Levenberg–Marquardt iterations (both stages).
    pub iterations: usize,
    /// Parameters held fixed (not fitted), by name.
    #[serde(default)]
    pub fixed: Vec<String>,
    /// What the fit had to decide (e.g. a parameter fixed because the records cannot
    /// separate it).
    #[serde(default)]
    pub notes: Vec<String>,
    /// Held-out comparison, when one was asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out: Option<super::report::HeldOutReport>,
    /// Residual block-bootstrap intervals of the constants, when an ensemble was asked for
    /// ([`super::ensemble::bootstrap`](crate::lag::ensemble::bootstrap)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<super::report::LagEnsemble>,
}

/// A fitted lag law and its report.
#[derive(Debug, Clone, PartialEq)]
pub struct LagFit {
    /// The law.
    pub law: LagLaw,
    /// The report.
    pub report: LagReport,
}

/// The law with θ and empty channels (the separation dynamics only).
pub(crate) fn law_of(theta: [f64; 4], circulation_lag: bool, pressure_lag: f64) -> LagLaw {
    LagLaw {
        tau1: theta[0],
        tau2: theta[1],
        alpha_star: theta[2],
        sharpness: theta[3],
        lift: LagChannel { terms: Vec::new() },
        moment: LagChannel { terms: Vec::new() },
        range: FittedRange {
            alpha_e: [0.0, 0.0],
            k: [0.0, 0.0],
        },
        circulation_lag,
        rate_share: 0.0,
        pressure_lag,
    }
}

fn clamp_theta(t: [f64; 4]) -> [f64; 4] {
    let mut o = t;
    for (v, (lo, hi)) in o.iter_mut().zip(BOUNDS) {
        *v = v.clamp(lo, hi);
    }
    o
}

/// The output-error problem of a set of cases.
struct Problem<'a> {
    series: &'a [LagSeries],
    lift: Vec<LagColumn>,
    moment: Vec<LagColumn>,
    /// Which of θ are fitted (a fixed one keeps its start value).
    free: [bool; 4],
    /// The law's circulation lag.
    circ: bool,
    /// The law's pressure lag τ_p (fixed in this problem).
    tau_p: f64,
}

/// One evaluation of the projected problem at θ.
struct Eval {
    theta: [f64; 4],
    cost: f64,
    residual: Vec<f64>,
    lift: Vec<f64>,
    moment: Vec<f64>,
    xs: Vec<Vec<f64>>,
    starts: Vec<usize>,
    ss: [f64; 2],
}

fn ss_about_mean(y: &[f64]) -> f64 {
    if y.is_empty() {
        return 0.0;
    }
    let m = y.iter().sum::<f64>() / y.len() as f64;
    y.iter().map(|v| (v - m) * (v - m)).sum()
}

impl Problem<'_> {
    /// Separation states of every case (parallel, in case order).
    fn states(&self, theta: [f64; 4]) -> Result<(Vec<Vec<f64>>, Vec<usize>)> {
        let law = law_of(theta, self.circ, self.tau_p);
        let out: Vec<Result<(Vec<f64>, usize)>> = self
            .series
            .par_iter()
            .map(|s| {
                let mut x = Vec::new();
                let start = s.simulate(&law, &mut x)?;
                Ok((x, start))
            })
            .collect();
        let mut xs = Vec::with_capacity(out.len());
        let mut starts = Vec::with_capacity(out.len());
        for r in out {
            let (x, s) = r?;
            xs.push(x);
            starts.push(s);
        }
        Ok((xs, starts))
    }

    /// Stacked columns and target of one channel over the scored samples.
    #[allow(clippy::needless_range_loop)] // parallel series indexed together
    fn stack(
        &self,
        theta: [f64; 4],
        cols: &[LagColumn],
        xs: &[Vec<f64>],
        starts: &[usize],
        lift: bool,
    ) -> (Vec<Vec<f64>>, Vec<f64>) {
        let total: usize = self
            .series
            .iter()
            .zip(starts)
            .map(|(s, &st)| s.len() - st.min(s.len()))
            .sum();
        let mut c: Vec<Vec<f64>> = cols.iter().map(|_| Vec::with_capacity(total)).collect();
        let mut y = Vec::with_capacity(total);
        let law = law_of(theta, self.circ, self.tau_p);
        let inst = cols.iter().any(|c| {
            matches!(
                c,
                LagColumn::KirchhoffStatic | LagColumn::Blend | LagColumn::BlendSep
            )
        });
        for ((s, x), &st) in self.series.iter().zip(xs).zip(starts) {
            let a = s.angle(&law);
            for i in st..s.len() {
                let xi = if inst { law.x_static(a[i]) } else { 1.0 };
                for (cv, col) in c.iter_mut().zip(cols) {
                    cv.push(col.value(a[i], s.q[i], x[i], xi));
                }
                y.push(if lift { s.c_lift[i] } else { s.c_moment[i] });
            }
        }
        (c, y)
    }

    /// Projected evaluation at θ; `fixed` = (starts, SS) of a base point for Jacobian
    /// columns (so that the residual vector keeps its length and scaling).
    fn eval(&self, theta: [f64; 4], fixed: Option<(&[usize], [f64; 2])>) -> Result<Eval> {
        let (xs, mut starts) = self.states(theta)?;
        if let Some((st, _)) = fixed {
            starts = st.to_vec();
        }
        let mut residual = Vec::new();
        let mut coefs = [Vec::new(), Vec::new()];
        let mut ss = [0.0; 2];
        let mut cost = 0.0;
        for (k, cols) in [&self.lift, &self.moment].into_iter().enumerate() {
            let (c, y) = self.stack(theta, cols, &xs, &starts, k == 0);
            let refs: Vec<&[f64]> = c.iter().map(|v| v.as_slice()).collect();
            let qr = ThinQr::new(&refs, 1e-10);
            let r = qr.residual(&y);
            coefs[k] = qr.solve(&y);
            ss[k] = match fixed {
                Some((_, s)) => s[k],
                None => ss_about_mean(&y),
            };
            let scale = if ss[k] > 0.0 { 1.0 / ss[k].sqrt() } else { 1.0 };
            for v in r {
                let w = v * scale;
                cost += w * w;
                residual.push(w);
            }
        }
        if !cost.is_finite() {
            return Err(Error::Numerical {
                context: "lag law output error".into(),
                message: format!("non-finite objective at θ = {theta:?}"),
            });
        }
        let [lift, moment] = coefs;
        Ok(Eval {
            theta,
            cost,
            residual,
            lift,
            moment,
            xs,
            starts,
            ss,
        })
    }

    /// Forward-difference Jacobian (column-major, 4 columns) of the residual at `base`.
    fn jacobian(&self, theta: [f64; 4], base: &Eval) -> Result<Vec<Vec<f64>>> {
        let typical = [1.0, 1.0, 0.1, 1.0];
        let mut jac = Vec::with_capacity(4);
        for j in 0..4 {
            if !self.free[j] {
                jac.push(vec![0.0; base.residual.len()]);
                continue;
            }
            let mut h = 1e-6 * theta[j].abs().max(typical[j]);
            if theta[j] + h > BOUNDS[j].1 {
                h = -h;
            }
            let mut t = theta;
            t[j] += h;
            let e = self.eval(t, Some((&base.starts, base.ss)))?;
            jac.push(
                e.residual
                    .iter()
                    .zip(&base.residual)
                    .map(|(a, b)| (a - b) / h)
                    .collect(),
            );
        }
        Ok(jac)
    }

    /// Levenberg–Marquardt from θ₀ (box bounds by clamping). Returns (θ, eval, iterations).
    fn minimise(&self, theta0: [f64; 4], max_iter: usize) -> Result<([f64; 4], Eval, usize)> {
        let mut theta = clamp_theta(theta0);
        let mut cur = self.eval(theta, None)?;
        let mut lambda = 1e-3;
        let mut iters = 0;
        'outer: for _ in 0..max_iter {
            iters += 1;
            let jac = self.jacobian(theta, &cur)?;
            let (a, g) = normal_equations(&jac, &cur.residual);
            loop {
                let mut m = a;
                for i in 0..4 {
                    m[i * 4 + i] += lambda * a[i * 4 + i].max(1e-12) + 1e-14;
                    if !self.free[i] {
                        m[i * 4 + i] = 1.0;
                    }
                }
                let mut d = [-g[0], -g[1], -g[2], -g[3]];
                let ok = cholesky_solve(
                    &mut m,
                    4,
                    &mut d,
                    1,
                    PivotFloor::RelativeToLargestDiagonal(1e-15),
                )
                .is_ok();
                if ok {
                    let mut cand = theta;
                    for i in 0..4 {
                        cand[i] += d[i];
                    }
                    let cand = clamp_theta(cand);
                    let moved = (0..4)
                        .any(|i| (cand[i] - theta[i]).abs() > 1e-12 * theta[i].abs().max(1.0));
                    if !moved {
                        break 'outer;
                    }
                    // a trial point where a record cannot settle is a rejected step
                    if let Ok(e) = self.eval(cand, None) {
                        if e.cost < cur.cost {
                            let gain = cur.cost - e.cost;
                            theta = cand;
                            cur = e;
                            lambda = (lambda / 3.0).max(1e-9);
                            if gain <= 1e-9 * cur.cost.max(1e-12) {
                                break 'outer;
                            }
                            continue 'outer;
                        }
                    }
                }
                lambda *= 4.0;
                if lambda > 1e10 {
                    break 'outer;
                }
            }
        }
        Ok((theta, cur, iters))
    }
}

/// JᵀJ (row-major 4×4) and Jᵀr.
fn normal_equations(jac: &[Vec<f64>], r: &[f64]) -> ([f64; 16], [f64; 4]) {
    let mut a = [0.0; 16];
    let mut g = [0.0; 4];
    for i in 0..4 {
        g[i] = crate::numerics::qr::dot(&jac[i], r);
        for j in 0..=i {
            let v = crate::numerics::qr::dot(&jac[i], &jac[j]);
            a[i * 4 + j] = v;
            a[j * 4 + i] = v;
        }
    }
    (a, g)
}

/// Standard errors and correlation of the free parameters of θ from J at the optimum
/// (`None` if JᵀJ is singular); a fixed parameter has standard error 0 and correlation 0
/// with the others.
#[allow(clippy::needless_range_loop)] // parallel series indexed together
fn covariance(
    jac: &[Vec<f64>],
    cost: f64,
    dof: usize,
    free: [bool; 4],
) -> Option<([f64; 4], [[f64; 4]; 4])> {
    let (a, _) = normal_equations(jac, &vec![0.0; jac[0].len()]);
    let idx: Vec<usize> = (0..4).filter(|&i| free[i]).collect();
    let k = idx.len();
    let mut m: Vec<f64> = idx
        .iter()
        .flat_map(|&i| idx.iter().map(move |&j| a[i * 4 + j]))
        .collect();
    let mut inv = vec![0.0; k * k];
    for i in 0..k {
        inv[i * k + i] = 1.0;
    }
    cholesky_solve(
        &mut m,
        k,
        &mut inv,
        k,
        PivotFloor::RelativeToLargestDiagonal(1e-13),
    )
    .ok()?;
    let s2 = cost / dof.max(1) as f64;
    let mut se = [0.0; 4];
    let mut corr = [[0.0; 4]; 4];
    for i in 0..4 {
        corr[i][i] = 1.0;
    }
    for (p, &i) in idx.iter().enumerate() {
        se[i] = (s2 * inv[p * k + p]).sqrt();
        for (q, &j) in idx.iter().enumerate() {
            corr[i][j] = inv[p * k + q] / (inv[p * k + p] * inv[q * k + q]).sqrt();
        }
    }
    if se.iter().all(|v| v.is_finite()) && corr.iter().flatten().all(|v| v.is_finite()) {
        Some((se, corr))
    } else {
        None
    }
}

/// Initial θ from the data (module docs, step 1).
pub fn initial_guess(series: &[LagSeries]) -> [f64; 4] {
    // attached slope C_Lα (lift down: negative for a positive angle)
    let (mut sxy, mut sxx, mut n_low, mut n_all, mut sign_acc) = (0.0, 0.0, 0usize, 0usize, 0.0);
    for s in series {
        for (a, c) in s.alpha_e.iter().zip(&s.c_lift) {
            n_all += 1;
            sign_acc += a * c;
            if a.abs() <= 0.12 {
                sxy += a * c;
                sxx += a * a;
                n_low += 1;
            }
        }
    }
    let sign = if sign_acc < 0.0 { -1.0 } else { 1.0 };
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut slope = sign * two_pi;
    if n_low * 20 >= n_all && sxx > 0.0 {
        let s = sxy / sxx;
        if s * sign > 0.25 * two_pi && s * sign < 2.0 * two_pi {
            slope = s;
        }
    }
    // reconstructed state, smoothed, and its rate
    let mut pts: Vec<(f64, f64, f64, f64)> = Vec::new(); // (α_e, q, x, dx/ds)
    for s in series {
        let n = s.len();
        let xr: Vec<f64> = s
            .alpha_e
            .iter()
            .zip(&s.c_lift)
            .map(|(&a, &c)| {
                let kappa = if a.abs() >= 0.03 {
                    (c / (slope * a)).clamp(0.25, 1.0)
                } else {
                    1.0
                };
                (2.0 * kappa.sqrt() - 1.0).powi(2).clamp(0.0, 1.0)
            })
            .collect();
        let w = s
            .period_samples
            .map_or(2, |p| ((p / 40.0).round() as usize).max(1));
        let sm: Vec<f64> = (0..n)
            .map(|i| {
                let (lo, hi) = (i.saturating_sub(w), (i + w).min(n - 1));
                xr[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64
            })
            .collect();
        let stride = (series.iter().map(|s| s.len()).sum::<usize>() / 6000).max(1);
        for i in (1..n - 1).step_by(stride) {
            if s.alpha_e[i].abs() < 0.03 {
                continue;
            }
            let d = (sm[i + 1] - sm[i - 1]) / (2.0 * s.ds);
            pts.push((s.alpha_e[i], s.q[i], sm[i], d));
        }
    }
    if pts.len() < 8 {
        return [3.0, 1.0, 0.3, 3.0];
    }
    // (α*, m) on a grid
    let (mut best, mut best_ss) = ((0.3, 3.0), f64::INFINITY);
    let ms = [1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 14.0, 20.0];
    for ia in 0..30 {
        let a_star = (0.03f64.ln() + (1.15f64.ln() - 0.03f64.ln()) * ia as f64 / 29.0).exp();
        for &m in &ms {
            let ss: f64 = pts
                .iter()
                .map(|&(a, _, x, _)| {
                    let x0 = 1.0 / (1.0 + (a / a_star).abs().powf(2.0 * m));
                    (x - x0) * (x - x0)
                })
                .sum();
            if ss < best_ss {
                best_ss = ss;
                best = (a_star, m);
            }
        }
    }
    let (a_star, m) = best;
    let x0 = |a: f64| 1.0 / (1.0 + (a / a_star).abs().powf(2.0 * m));
    // (τ₁, τ₂) by least squares of the lag equation
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(a, q, x, d) in &pts {
        let dx0 = (x0(a + 1e-5) - x0(a - 1e-5)) / 2e-5;
        let c1 = -d;
        let c2 = -0.5 * q * dx0;
        let y = x - x0(a);
        a11 += c1 * c1;
        a12 += c1 * c2;
        a22 += c2 * c2;
        b1 += c1 * y;
        b2 += c2 * y;
    }
    let det = a11 * a22 - a12 * a12;
    let (mut t1, mut t2) = if det > 1e-12 * (a11 * a22).max(1e-300) {
        ((b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det)
    } else if a11 > 0.0 {
        (b1 / a11, 0.0)
    } else {
        (3.0, 1.0)
    };
    if !(t1.is_finite() && t1 > 0.0) {
        t1 = 3.0;
    }
    if !(t2.is_finite() && t2 >= 0.0) {
        t2 = 0.0;
    }
    [t1.clamp(0.3, 50.0), t2.min(50.0), a_star, m]
}

/// Per-case R² (lift, moment) at an evaluation.
fn case_scores(p: &Problem<'_>, e: &Eval) -> Vec<LagCaseScore> {
    p.series
        .iter()
        .zip(&e.xs)
        .zip(&e.starts)
        .map(|((s, x), &st)| {
            let law = law_of(e.theta, p.circ, p.tau_p);
            let a = s.angle(&law);
            let mut r2 = [0.0; 2];
            for (k, (cols, coef)) in [(&p.lift, &e.lift), (&p.moment, &e.moment)]
                .into_iter()
                .enumerate()
            {
                let y = if k == 0 { &s.c_lift } else { &s.c_moment };
                let pred: Vec<f64> = (st..s.len())
                    .map(|i| {
                        cols.iter()
                            .zip(coef)
                            .map(|(c, v)| v * c.value(a[i], s.q[i], x[i], law.x_static(a[i])))
                            .sum()
                    })
                    .collect();
                r2[k] = crate::metrics::r_squared(&y[st..], &pred);
            }
            LagCaseScore {
                id: s.id.clone(),
                k: s.k,
                mean_deg: s.mean_alpha.to_degrees(),
                amplitude_deg: s.amplitude.to_degrees(),
                periodic: s.periodic,
                samples: s.len() - st,
                r2_lift: r2[0],
                r2_moment: r2[1],
            }
        })
        .collect()
}

/// The moment support chosen by the δ path at θ (module docs).
fn select_moment(
    p: &Problem<'_>,
    e: &Eval,
    opts: &LagFitOptions,
) -> Result<(Vec<LagColumn>, MomentSelection)> {
    let (cols, y) = p.stack(e.theta, &opts.moment_columns, &e.xs, &e.starts, false);
    let n = y.len();
    let ncol = cols.len();
    let theta = Mat::<f64>::from_fn(n, ncol, |i, j| cols[j][i]);
    let order: Vec<usize> = (0..ncol).collect();
    let factor = CaseFactor::new("lag law moment", theta.as_ref(), &order, &[&y])?;
    let problem = [CaseProblem {
        factor: &factor,
        target: 0,
    }];
    // the registered STLSQ plug-in (default shared settings: contribution measure, no
    // ridge), found by name like every regressor
    let d = Stlsq::default();
    let shared = FitSettings {
        measure: d.measure,
        group_rule: d.group_rule,
        ridge: d.ridge,
        max_iter: d.max_iter,
    };
    let (reg, options, _) = RegressorChoice::new("stlsq").resolve(plugins::registry(), &shared)?;
    let basis: u64 = (1u64 << ncol) - 1;
    let group = GroupInput {
        cases: &problem,
        keys: &[None],
        data: &[None],
        target: 0,
        basis,
        kept: 0,
        shared,
        options: &options,
    };
    let (path, _) = run_path(reg, &group, &opts.path);
    let sel = path.selected_support();
    let selected: Vec<LagColumn> = sel
        .support
        .iter()
        .map(|&j| opts.moment_columns[j])
        .collect();
    let full = path
        .supports
        .iter()
        .max_by_key(|s| s.support.len())
        .map_or(f64::NAN, |s| s.loss);
    Ok((
        selected.clone(),
        MomentSelection {
            candidates: opts.moment_columns.clone(),
            selected,
            loss_full: full,
            loss_selected: sel.loss,
            limit: path.limit,
        },
    ))
}

/// The output-error stages from the best of `starts`: LM with the full moment support, the
/// δ-path selection, LM again on the selected support. Returns (θ, evaluation, iterations,
/// selection); `p.moment` is left on the selected support.
fn stages(
    p: &mut Problem<'_>,
    starts: &[[f64; 4]],
    opts: &LagFitOptions,
) -> Result<([f64; 4], Eval, usize, MomentSelection)> {
    let mut best: Option<([f64; 4], f64)> = None;
    let mut first_err = None;
    for &s in starts {
        let s = clamp_theta(s);
        match p.eval(s, None) {
            Ok(e) => {
                if best.is_none_or(|(_, c)| e.cost < c) {
                    best = Some((s, e.cost));
                }
            }
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    let Some((theta0, _)) = best else {
        return Err(first_err.unwrap_or_else(|| Error::Numerical {
            context: "lag law".into(),
            message: "no starting point".into(),
        }));
    };
    let (theta1, e1, it1) = p.minimise(theta0, opts.max_iter)?;
    let (moment_cols, selection) = select_moment(p, &e1, opts)?;
    p.moment = moment_cols;
    let (theta, e, it2) = p.minimise(theta1, opts.max_iter)?;
    Ok((theta, e, it1 + it2, selection))
}

/// Fits a lag law to the forced cases `cases` (module docs).
///
/// # Errors
/// [`Error::InvalidOption`] for bad options; [`Error::InvalidData`] naming a case for
/// unusable series or an empty input; [`Error::TooShort`] naming the case and the numbers
/// when a record is too short for the separation state to settle; [`Error::Unphysical`]
/// when a constant ends on an open bound of its range (α* at 0.02 or 1.2 rad, τ₁ at 0.05)
/// or the state leaves \[0, 1\]; [`Error::Numerical`] for a non-finite objective.
pub fn fit(cases: &[NondimCase], opts: &LagFitOptions) -> Result<LagFit> {
    opts.validate()?;
    if cases.is_empty() {
        return Err(Error::InvalidData {
            case: "-".into(),
            field: "cases".into(),
            message: "no case to fit the lag law on".into(),
        });
    }
    if opts.fit_rate_share || opts.fit_pressure_lag {
        return fit_profiled(cases, opts);
    }
    fit_fixed(cases, opts)
}

/// [`fit`] at the options' fixed rate share and pressure lag.
fn fit_fixed(cases: &[NondimCase], opts: &LagFitOptions) -> Result<LagFit> {
    let series: Vec<LagSeries> = cases
        .iter()
        .map(|c| LagSeries::with_rate_share(c, opts.rate_share))
        .collect::<Result<_>>()?;
    fit_series(&series, opts)
}

/// Nelder–Mead minimum of `f` over the box `lo`..`hi` (points clamped into it) from `x0`
/// with initial steps `step`, at most `max_eval` evaluations: (argmin, value). Non-finite
/// values count as +∞.
fn nelder_mead(
    f: &mut dyn FnMut([f64; 2]) -> f64,
    x0: [f64; 2],
    step: [f64; 2],
    lo: [f64; 2],
    hi: [f64; 2],
    max_eval: usize,
) -> ([f64; 2], f64) {
    let clamp = |p: [f64; 2]| [p[0].clamp(lo[0], hi[0]), p[1].clamp(lo[1], hi[1])];
    let mut n_eval = 0usize;
    let mut ev = |p: [f64; 2], n: &mut usize| {
        *n += 1;
        let v = f(p);
        if v.is_finite() {
            v
        } else {
            f64::INFINITY
        }
    };
    let mut simplex: Vec<([f64; 2], f64)> = Vec::with_capacity(3);
    for d in [[0.0, 0.0], [step[0], 0.0], [0.0, step[1]]] {
        let mut p = clamp([x0[0] + d[0], x0[1] + d[1]]);
        if p == x0 && d != [0.0, 0.0] {
            // on the box edge: step the other way
            p = clamp([x0[0] - d[0], x0[1] - d[1]]);
        }
        let v = ev(p, &mut n_eval);
        simplex.push((p, v));
    }
    while n_eval < max_eval {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (best, worst) = (simplex[0], simplex[2]);
        let c = [
            0.5 * (simplex[0].0[0] + simplex[1].0[0]),
            0.5 * (simplex[0].0[1] + simplex[1].0[1]),
        ];
        let along = |t: f64| {
            clamp([
                c[0] + t * (worst.0[0] - c[0]),
                c[1] + t * (worst.0[1] - c[1]),
            ])
        };
        let r = along(-1.0);
        let fr = ev(r, &mut n_eval);
        if fr < best.1 {
            let e = along(-2.0);
            let fe = ev(e, &mut n_eval);
            simplex[2] = if fe < fr { (e, fe) } else { (r, fr) };
        } else if fr < simplex[1].1 {
            simplex[2] = (r, fr);
        } else {
            let k = along(if fr < worst.1 { -0.5 } else { 0.5 });
            let fk = ev(k, &mut n_eval);
            if fk < worst.1.min(fr) {
                simplex[2] = (k, fk);
            } else {
                // shrink toward the best point
                for v in simplex.iter_mut().skip(1) {
                    let p = clamp([
                        best.0[0] + 0.5 * (v.0[0] - best.0[0]),
                        best.0[1] + 0.5 * (v.0[1] - best.0[1]),
                    ]);
                    *v = (p, ev(p, &mut n_eval));
                }
            }
        }
        let size = simplex
            .iter()
            .map(|v| {
                ((v.0[0] - simplex[0].0[0]) / step[0]).abs()
                    + ((v.0[1] - simplex[0].0[1]) / step[1]).abs()
            })
            .fold(0.0, f64::max);
        if size < 1e-2 {
            break;
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex[0]
}

/// Grid of the rate-share profile (c) and of the pressure-lag profile (τ_p \[b/U\]).
const PROFILE_GRID: ([f64; 6], [f64; 8]) = (
    [0.0, 0.2, 0.4, 0.6, 0.8, 1.0],
    [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, PROFILE_PRESSURE_LAG_MAX],
);

/// [`fit`] with the rate share and/or the pressure lag fitted by output error: the
/// objective (1 − R²_L) + (1 − R²_M) of the fixed-constant fit (every other constant and
/// coefficient refitted at each point), profiled over c ∈ \[0, 1\] and τ_p ∈
/// \[0, [`PROFILE_PRESSURE_LAG_MAX`]\]: the best point of a coarse grid
/// ([`PROFILE_GRID`]; the two are correlated, so jointly), then Nelder–Mead from it (steps
/// 0.1 and 0.25 b/U, at most 40 fits). A point whose fit is refused counts as +∞.
fn fit_profiled(cases: &[NondimCase], opts: &LagFitOptions) -> Result<LagFit> {
    let fixed = |p: [f64; 2]| {
        let mut o = opts.clone();
        o.fit_rate_share = false;
        o.fit_pressure_lag = false;
        o.rate_share = p[0];
        o.pressure_lag = p[1];
        fit_fixed(cases, &o)
    };
    let cs: Vec<f64> = if opts.fit_rate_share {
        PROFILE_GRID.0.to_vec()
    } else {
        vec![opts.rate_share]
    };
    let ts: Vec<f64> = if opts.fit_pressure_lag {
        PROFILE_GRID.1.to_vec()
    } else {
        vec![opts.pressure_lag]
    };
    let mut evaluations = 0usize;
    let mut objective = |p: [f64; 2]| {
        evaluations += 1;
        fixed(p).map_or(f64::INFINITY, |f| f.report.objective)
    };
    let mut start = ([opts.rate_share, opts.pressure_lag], f64::INFINITY);
    for &c in &cs {
        for &t in &ts {
            let v = objective([c, t]);
            if v < start.1 {
                start = ([c, t], v);
            }
        }
    }
    let lo = [
        if opts.fit_rate_share {
            0.0
        } else {
            opts.rate_share
        },
        if opts.fit_pressure_lag {
            0.0
        } else {
            opts.pressure_lag
        },
    ];
    let hi = [
        if opts.fit_rate_share {
            1.0
        } else {
            opts.rate_share
        },
        if opts.fit_pressure_lag {
            PROFILE_PRESSURE_LAG_MAX
        } else {
            opts.pressure_lag
        },
    ];
    let (p, _) = if start.1.is_finite() {
        nelder_mead(&mut objective, start.0, [0.1, 0.25], lo, hi, 40)
    } else {
        start
    };
    let mut out = fixed(p)?;
    out.report.notes.push(format!(
        "fitted by output error (objective profiled over {evaluations} fixed-constant fits): \
         rate share c = {:.3}{}, pressure lag τ_p = {:.3} b/U{}",
        p[0],
        if opts.fit_rate_share { "" } else { " (fixed)" },
        p[1],
        if opts.fit_pressure_lag {
            ""
        } else {
            " (fixed)"
        },
    ));
    Ok(out)
}

/// [`fit`] on cases already in the lag law's variables (built with
/// [`LagSeries::with_rate_share`] at `opts.rate_share`, which the law records).
///
/// # Errors
/// As [`fit`].
pub fn fit_series(series: &[LagSeries], opts: &LagFitOptions) -> Result<LagFit> {
    opts.validate()?;
    let init = initial_guess(series);
    // a record that is not periodic must settle at the data's own lag (not only at the
    // shortest lag the optimiser could run to)
    let mut x = Vec::new();
    for s in series.iter().filter(|s| !s.periodic) {
        s.simulate(
            &law_of(clamp_theta(init), opts.circulation_lag, opts.pressure_lag),
            &mut x,
        )?;
    }
    let mut p = Problem {
        series,
        lift: opts.lift_columns.clone(),
        moment: opts.moment_columns.clone(),
        free: [true; 4],
        circ: opts.circulation_lag,
        tau_p: opts.pressure_lag,
    };
    // a few starts around the data's guess; the best by output error goes on
    let mut starts = vec![init];
    for t1 in [1.0, 3.0, 8.0] {
        for t2f in [0.0, 0.5] {
            starts.push([t1, t1 * t2f, init[2], init[3]]);
        }
    }
    let (mut theta, mut e, mut iterations, mut selection) = stages(&mut p, &starts, opts)?;
    let mut notes = Vec::new();
    let lo1 = BOUNDS[0].0 + 1e-3;
    if theta[0] <= lo1 && theta[1] > 0.0 {
        // the lag ran to its open bound with the input lead carrying the delay: at one or
        // two close frequencies the two enter the loop nearly as one delay; the nested law
        // with τ₂ = 0 (a pure separation lag) is fitted instead
        p.free = [true, false, true, true];
        p.moment = opts.moment_columns.clone();
        let sum = (init[0] + init[1]).clamp(0.3, 50.0);
        let starts: Vec<[f64; 4]> = [sum, 1.0, 3.0, 8.0, 20.0]
            .iter()
            .map(|&t1| [t1, 0.0, init[2], init[3]])
            .collect();
        let (t, e2, it, sel) = stages(&mut p, &starts, opts)?;
        notes.push(format!(
            "with τ₂ free the fit ran τ₁ to its lower bound {} (τ₂ = {:.3} b/U carried the whole \
             delay): τ₁ and τ₂ are not separable on these records, τ₂ is fixed at 0",
            BOUNDS[0].0, theta[1]
        ));
        theta = t;
        e = e2;
        iterations += it;
        selection = sel;
    }

    // refusals: open bounds and the state's range
    for (i, (lo, hi)) in BOUNDS.iter().enumerate() {
        let open_lo = i == 0 || i == 2;
        let open_hi = i == 2;
        let tol = 1e-3 * (hi - lo).abs().min(1.0);
        let (name, _, unit) = PARAMETERS[i];
        if open_lo && theta[i] <= lo + tol {
            return Err(Error::Unphysical {
                parameter: format!("{name} [{unit}]"),
                value: theta[i],
                reason: format!(
                    "the fit ran to the lower bound {lo} of its open range: the records do not \
                     show this constant (no measurable separation lag, or no separation)"
                ),
            });
        }
        if open_hi && theta[i] >= hi - tol {
            return Err(Error::Unphysical {
                parameter: format!("{name} [{unit}]"),
                value: theta[i],
                reason: format!(
                    "the fit ran to the upper bound {hi} of its open range: the records do not \
                     reach separation"
                ),
            });
        }
    }
    for (s, x) in series.iter().zip(&e.xs) {
        if let Some(v) = x.iter().find(|v| !(0.0..=1.0).contains(*v)) {
            return Err(Error::Unphysical {
                parameter: format!("x (case `{}`)", s.id),
                value: *v,
                reason: "the separation state left [0, 1]".into(),
            });
        }
    }

    let jac = p.jacobian(theta, &e)?;
    let n_lin = p.lift.len() + p.moment.len();
    let dof = e.residual.len().saturating_sub(4 + n_lin);
    let cov = covariance(&jac, e.cost, dof, p.free);
    let parameters = PARAMETERS
        .iter()
        .enumerate()
        .map(|(i, (name, sym, unit))| LagParameter {
            name: name.to_string(),
            symbol: sym.to_string(),
            value: theta[i],
            unit: unit.to_string(),
            standard_error: cov.map(|c| c.0[i]).filter(|_| p.free[i]),
        })
        .collect();
    let correlation = cov.map(|c| c.1);
    let tau_correlation = correlation
        .filter(|_| p.free[0] && p.free[1])
        .map(|c| c[0][1]);
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for (s, &st) in series.iter().zip(&e.starts) {
        for &a in &s.alpha_e[st..] {
            lo = lo.min(a);
            hi = hi.max(a);
        }
    }
    let kmin = series.iter().map(|s| s.k).fold(f64::INFINITY, f64::min);
    let kmax = series.iter().map(|s| s.k).fold(f64::NEG_INFINITY, f64::max);
    let terms = |cols: &[LagColumn], c: &[f64]| LagChannel {
        terms: cols.iter().copied().zip(c.iter().copied()).collect(),
    };
    let law = LagLaw {
        tau1: theta[0],
        tau2: theta[1],
        alpha_star: theta[2],
        sharpness: theta[3],
        lift: terms(&p.lift, &e.lift),
        moment: terms(&p.moment, &e.moment),
        range: FittedRange {
            alpha_e: [lo, hi],
            k: [kmin, kmax],
        },
        circulation_lag: p.circ,
        rate_share: opts.rate_share,
        pressure_lag: opts.pressure_lag,
    };
    law.check()?;
    let report = LagReport {
        parameters,
        correlation,
        tau_correlation,
        tau_collinear: tau_correlation.is_some_and(|c| c.abs() > COLLINEAR_CORRELATION),
        cases: case_scores(&p, &e),
        moment_selection: selection,
        initial: init,
        objective: e.cost,
        iterations,
        fixed: PARAMETERS
            .iter()
            .zip(p.free)
            .filter(|(_, f)| !f)
            .map(|(n, _)| n.0.to_string())
            .collect(),
        notes,
        held_out: None,
        ensemble: None,
    };
    Ok(LagFit { law, report })
}

/// A lag law's prediction of one case.
#[derive(Debug, Clone, PartialEq)]
pub struct LagPrediction {
    /// Separation state at every sample.
    pub x: Vec<f64>,
    /// First scored sample (0 at the periodic steady state).
    pub start: usize,
    /// Predicted C_L at every sample.
    pub c_lift: Vec<f64>,
    /// Predicted C_M at every sample.
    pub c_moment: Vec<f64>,
    /// Score on the samples from `start`.
    pub score: LagCaseScore,
}

/// Predicts the forces of `case` with `law` at the periodic steady state of its motion.
///
/// # Errors
/// As [`LagSeries::new`] and [`LagSeries::simulate`]; [`Error::OutsideFittedRange`] naming
/// the case when its mean effective angle lies outside the angles the law was fitted on.
pub fn predict(law: &LagLaw, case: &NondimCase) -> Result<LagPrediction> {
    let s = LagSeries::with_rate_share(case, law.rate_share)?;
    predict_series(law, &s)
}

/// [`predict`] on a case already in the lag law's variables.
///
/// # Errors
/// As [`predict`].
#[allow(clippy::needless_range_loop)] // parallel series indexed together
pub fn predict_series(law: &LagLaw, s: &LagSeries) -> Result<LagPrediction> {
    law.check()?;
    let mean_e = s.alpha_e.iter().sum::<f64>() / s.len().max(1) as f64;
    let [lo, hi] = law.range.alpha_e;
    if !(mean_e >= lo && mean_e <= hi) {
        return Err(Error::OutsideFittedRange {
            case: s.id.clone(),
            quantity: "mean angle [deg]".into(),
            value: mean_e.to_degrees(),
            low: lo.to_degrees(),
            high: hi.to_degrees(),
        });
    }
    let mut x = Vec::new();
    let start = s.simulate(law, &mut x)?;
    let a = s.angle(law);
    let mut cl = Vec::with_capacity(s.len());
    let mut cm = Vec::with_capacity(s.len());
    for i in 0..s.len() {
        let [l, m] = law.coefficients(a[i], s.q[i], x[i]);
        cl.push(l);
        cm.push(m);
    }
    let score = LagCaseScore {
        id: s.id.clone(),
        k: s.k,
        mean_deg: s.mean_alpha.to_degrees(),
        amplitude_deg: s.amplitude.to_degrees(),
        periodic: s.periodic,
        samples: s.len() - start,
        r2_lift: crate::metrics::r_squared(&s.c_lift[start..], &cl[start..]),
        r2_moment: crate::metrics::r_squared(&s.c_moment[start..], &cm[start..]),
    };
    Ok(LagPrediction {
        x,
        start,
        c_lift: cl,
        c_moment: cm,
        score,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn nelder_mead_finds_a_tilted_valley_inside_the_box() {
        // a correlated valley like the (c, τ_p) profile's, minimum at (0.35, 1.7)
        let mut f = |p: [f64; 2]| {
            let (u, v) = (p[0] - 0.35, p[1] - 1.7);
            (u - 0.25 * v).powi(2) * 40.0 + 0.05 * v * v
        };
        let (p, v) = nelder_mead(&mut f, [0.4, 1.5], [0.1, 0.25], [0.0, 0.0], [1.0, 6.0], 200);
        assert!(
            (p[0] - 0.35).abs() < 0.02 && (p[1] - 1.7).abs() < 0.1,
            "{p:?}"
        );
        assert!(v < 1e-3);
        // the box holds: a minimum outside it ends on the edge
        let mut g = |p: [f64; 2]| (p[0] + 0.5).powi(2) + (p[1] - 1.0).powi(2);
        let (p, _) = nelder_mead(&mut g, [0.3, 2.0], [0.1, 0.25], [0.0, 0.0], [1.0, 6.0], 200);
        assert!(p[0] < 0.02 && (p[1] - 1.0).abs() < 0.05, "{p:?}");
    }
    use crate::record::{CaseMeta, Forcing};

    pub(crate) fn truth() -> LagLaw {
        LagLaw {
            tau1: 3.0,
            tau2: 1.5,
            alpha_star: 0.22,
            sharpness: 3.0,
            lift: LagChannel {
                terms: vec![
                    (LagColumn::One, 0.02),
                    (LagColumn::Kirchhoff, -6.0),
                    (LagColumn::Q, -0.8),
                ],
            },
            moment: LagChannel {
                terms: vec![(LagColumn::KirchhoffSep, -1.5), (LagColumn::Q, -0.3)],
            },
            range: FittedRange {
                alpha_e: [0.0, 0.5],
                k: [0.0, 1.0],
            },
            circulation_lag: true,
            rate_share: 0.0,
            pressure_lag: 0.0,
        }
    }

    /// A pitching case of `law` at reduced frequency `k`, mean `mean` and amplitude `amp`
    /// \[rad\], `cycles` periods of 60 samples.
    #[allow(clippy::needless_range_loop)] // parallel series indexed together
    pub(crate) fn case_of(law: &LagLaw, id: &str, k: f64, mean: f64, amp: f64) -> NondimCase {
        let (u, b) = (10.0, 0.25);
        let f = k * u / (2.0 * std::f64::consts::PI * b);
        let dt = 1.0 / (60.0 * f);
        let n = 180;
        let w = 2.0 * std::f64::consts::PI * f;
        let alpha: Vec<f64> = (0..n)
            .map(|i| mean + amp * (w * i as f64 * dt).sin())
            .collect();
        let q: Vec<f64> = (0..n)
            .map(|i| b * amp * w * (w * i as f64 * dt).cos() / u)
            .collect();
        let mut c = NondimCase {
            meta: CaseMeta {
                id: id.into(),
                wind_speed: u,
                mean_pitch: Some(mean),
                amplitude: Some(amp),
                ..CaseMeta::default()
            },
            dt,
            chord: b,
            x: [alpha, q, vec![0.0; n], vec![0.0; n]],
            c_lift: vec![0.0; n],
            c_moment: vec![0.0; n],
            forcing: Forcing {
                pitch: Some(f),
                heave: None,
            },
        };
        let s = LagSeries::new(&c).unwrap();
        let mut x = Vec::new();
        s.simulate(law, &mut x).unwrap();
        let a = s.angle(law);
        for i in 0..n {
            let [l, m] = law.coefficients(a[i], s.q[i], x[i]);
            c.c_lift[i] = l;
            c.c_moment[i] = m;
        }
        c
    }

    #[test]
    fn recovers_its_own_law_from_three_frequencies() {
        let t = truth();
        let cases: Vec<NondimCase> = [0.05, 0.1, 0.2]
            .iter()
            .enumerate()
            .map(|(i, &k)| case_of(&t, &format!("c{i}"), k, 0.25, 0.15))
            .collect();
        let f = fit(&cases, &LagFitOptions::default()).unwrap();
        for c in &f.report.cases {
            assert!(c.r2_lift > 0.9999 && c.r2_moment > 0.9999, "{c:?}");
        }
        assert!((f.law.tau1 - 3.0).abs() < 0.05, "{:?}", f.report.parameters);
        assert!((f.law.tau2 - 1.5).abs() < 0.05, "{:?}", f.report.parameters);
        assert!((f.law.alpha_star - 0.22).abs() < 0.005);
        assert!((f.law.sharpness - 3.0).abs() < 0.1);
        assert!(f.report.correlation.is_some());
        assert_eq!(f.report.parameters[0].unit, "b/U (convective times)");
        let sel = &f.report.moment_selection.selected;
        assert!(
            sel.contains(&LagColumn::KirchhoffSep) && sel.contains(&LagColumn::Q),
            "{sel:?}"
        );
        // prediction of an unseen frequency
        let other = case_of(&t, "c9", 0.15, 0.25, 0.15);
        let p = predict(&f.law, &other).unwrap();
        assert!(
            p.score.r2_lift > 0.999 && p.score.r2_moment > 0.999,
            "{:?}",
            p.score
        );
    }

    #[test]
    fn prediction_outside_the_fitted_angles_is_refused_by_name() {
        let t = truth();
        let cases = vec![
            case_of(&t, "a", 0.1, 0.25, 0.15),
            case_of(&t, "b", 0.2, 0.25, 0.15),
        ];
        let f = fit(&cases, &LagFitOptions::default()).unwrap();
        let far = case_of(&t, "far", 0.1, 0.6, 0.05);
        let e = predict(&f.law, &far).unwrap_err();
        assert!(matches!(e, Error::OutsideFittedRange { .. }));
        assert!(
            e.to_string().contains("far") && e.to_string().contains("mean angle"),
            "{e}"
        );
    }

    #[test]
    fn attached_flow_only_is_refused_with_the_reason() {
        // angles far below α*: nothing separates, α* runs to its upper bound or the fit
        // cannot tell τ₁: either way a typed refusal or a law that checks
        let mut t = truth();
        t.alpha_star = 1.5;
        let cases = vec![
            case_of(&t, "a", 0.1, 0.02, 0.03),
            case_of(&t, "b", 0.2, 0.02, 0.03),
        ];
        match fit(&cases, &LagFitOptions::default()) {
            Err(Error::Unphysical { .. }) => {}
            Ok(f) => assert!(f.law.check().is_ok()),
            Err(e) => panic!("{e}"),
        }
    }
}
