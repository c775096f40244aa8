//! Validation on what was not fitted: cases held out by reduced frequency, mean angle or
//! amplitude, and the memoryless law and the lag law, both fitted on the same training
//! cases, scored side by side on them.
//!
//! The memoryless baseline ([`MemorylessLaw`]) is the strongest polynomial law of the
//! project's library that one set of coefficients can give across all training cases:
//! plain least squares on a constant and the paper's 30 terms in
//! (α − ᾱ_train, Bα̇/U, h/B, ḣ/U), ᾱ_train the mean angle of all training samples (the
//! DECISIONS "Mean angle" convention, with one reference angle for the whole training set).
//! It is evaluated on a held-out case at that case's absolute angle (α − ᾱ_train, never
//! about the held-out case's own mean, which the law was not given). Columns that are
//! (numerically) dependent on earlier ones (relative tolerance [`MEMORYLESS_RANK_TOL`], e.g.
//! the heave terms of pitch-only records, or α̇² beside α² and the constant under one
//! sinusoid) get coefficient 0.

use serde::{Deserialize, Serialize};

use crate::library::{Library, LibraryKind};
use crate::numerics::qr::ThinQr;
use crate::record::NondimCase;
use crate::{Error, Result};

use super::fit::{fit, predict, LagFit, LagFitOptions};
pub use super::report::{HeldOutReport, HeldOutRow};

/// Relative tolerance below which a library column is dropped as dependent in the
/// memoryless baseline's least squares.
pub const MEMORYLESS_RANK_TOL: f64 = 1e-6;

/// Which cases are held out: those whose value is nearest the given one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", tag = "by", content = "value")]
pub enum HoldOut {
    /// Reduced frequency K = Bω/U.
    K(f64),
    /// Mean angle \[deg\].
    Mean(f64),
    /// Pitch amplitude \[deg\].
    Amplitude(f64),
}

impl std::fmt::Display for HoldOut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HoldOut::K(v) => write!(f, "k={v}"),
            HoldOut::Mean(v) => write!(f, "mean={v}"),
            HoldOut::Amplitude(v) => write!(f, "amplitude={v}"),
        }
    }
}

impl std::str::FromStr for HoldOut {
    type Err = Error;

    /// Parses `k=0.1`, `mean=15` (deg) or `amplitude=10` (deg).
    fn from_str(s: &str) -> Result<HoldOut> {
        let bad = || Error::InvalidOption {
            name: "hold-out".into(),
            message: format!("{s:?}: expected k=K, mean=DEG or amplitude=DEG with a finite number"),
        };
        let (key, val) = s.split_once('=').ok_or_else(bad)?;
        let v: f64 = val.trim().parse().map_err(|_| bad())?;
        if !v.is_finite() {
            return Err(bad());
        }
        match key.trim() {
            "k" | "K" => Ok(HoldOut::K(v)),
            "mean" => Ok(HoldOut::Mean(v)),
            "amplitude" => Ok(HoldOut::Amplitude(v)),
            _ => Err(bad()),
        }
    }
}

impl HoldOut {
    /// The case's value compared with the spec: K (pitch forcing, else heave), mean angle
    /// \[deg\] (manifest `mean_pitch`, else the record's mean α) or pitch amplitude \[deg\]
    /// (manifest `amplitude`, else half the peak-to-peak α).
    pub fn value_of(&self, case: &NondimCase) -> f64 {
        let a = &case.x[0];
        match self {
            HoldOut::K(_) => case.k_alpha().or_else(|| case.k_h()).unwrap_or(f64::NAN),
            HoldOut::Mean(_) => case
                .meta
                .mean_pitch
                .unwrap_or_else(|| a.iter().sum::<f64>() / a.len().max(1) as f64)
                .to_degrees(),
            HoldOut::Amplitude(_) => case
                .meta
                .amplitude
                .unwrap_or_else(|| {
                    let lo = a.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = a.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    0.5 * (hi - lo)
                })
                .to_degrees(),
        }
    }

    fn target(&self) -> f64 {
        match *self {
            HoldOut::K(v) | HoldOut::Mean(v) | HoldOut::Amplitude(v) => v,
        }
    }

    /// Splits `cases` into (training, held-out) indices: held out are the cases whose
    /// value is nearest the spec's (all of them on a tie, to 1e-6 relative).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] (`hold-out`) when no case has the value or every case would
    /// be held out.
    pub fn split(&self, cases: &[NondimCase]) -> Result<(Vec<usize>, Vec<usize>)> {
        let t = self.target();
        let d: Vec<f64> = cases.iter().map(|c| (self.value_of(c) - t).abs()).collect();
        let best = d
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(f64::INFINITY, f64::min);
        if !best.is_finite() {
            return Err(Error::InvalidOption {
                name: "hold-out".into(),
                message: format!("{self}: no case has this quantity"),
            });
        }
        let tol = 1e-6 * (t.abs() + best).max(1e-9);
        let (mut train, mut test) = (Vec::new(), Vec::new());
        for (i, v) in d.iter().enumerate() {
            if v.is_finite() && *v <= best + tol {
                test.push(i);
            } else {
                train.push(i);
            }
        }
        if train.is_empty() {
            return Err(Error::InvalidOption {
                name: "hold-out".into(),
                message: format!(
                    "{self}: every case ({}) would be held out, none left to fit on",
                    test.len()
                ),
            });
        }
        Ok((train, test))
    }
}

/// The memoryless baseline (module docs): C = c₀ + Σ ξⱼ θⱼ(α − ᾱ_train, Bα̇/U, h/B, ḣ/U).
#[derive(Debug, Clone, PartialEq)]
pub struct MemorylessLaw {
    /// Reference angle ᾱ_train \[rad\].
    pub alpha_ref: f64,
    /// Per force (lift, moment): the constant then one coefficient per library term
    /// (0 for a dropped column).
    pub coefficients: [Vec<f64>; 2],
    library: Library,
}

impl MemorylessLaw {
    /// Fits the baseline on `cases` by least squares (one set of coefficients for all).
    ///
    /// # Errors
    /// [`Error::InvalidData`] for no case or no sample.
    pub fn fit(cases: &[&NondimCase]) -> Result<MemorylessLaw> {
        let n: usize = cases.iter().map(|c| c.len()).sum();
        if n == 0 {
            return Err(Error::InvalidData {
                case: "-".into(),
                field: "cases".into(),
                message: "no sample to fit the memoryless law on".into(),
            });
        }
        let alpha_ref = cases.iter().flat_map(|c| c.x[0].iter()).sum::<f64>() / n as f64;
        let library = Library::new(LibraryKind::Paper30, false);
        let p = library.len();
        let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(n); p + 1];
        let mut y = [Vec::with_capacity(n), Vec::with_capacity(n)];
        for c in cases {
            let theta = library.evaluate(&shifted(c, alpha_ref));
            cols[0].extend(std::iter::repeat_n(1.0, c.len()));
            for j in 0..p {
                cols[j + 1].extend(theta.col(j).iter().copied());
            }
            y[0].extend_from_slice(&c.c_lift);
            y[1].extend_from_slice(&c.c_moment);
        }
        let refs: Vec<&[f64]> = cols.iter().map(|v| v.as_slice()).collect();
        let qr = ThinQr::new(&refs, MEMORYLESS_RANK_TOL);
        Ok(MemorylessLaw {
            alpha_ref,
            coefficients: [qr.solve(&y[0]), qr.solve(&y[1])],
            library,
        })
    }

    /// Predicted (C_L, C_M) of `case` at its absolute angle.
    pub fn predict(&self, case: &NondimCase) -> [Vec<f64>; 2] {
        let theta = self.library.evaluate(&shifted(case, self.alpha_ref));
        let mut out = [vec![0.0; case.len()], vec![0.0; case.len()]];
        for (k, o) in out.iter_mut().enumerate() {
            let c = &self.coefficients[k];
            for (i, v) in o.iter_mut().enumerate() {
                *v = c[0]
                    + (0..self.library.len())
                        .map(|j| c[j + 1] * theta[(i, j)])
                        .sum::<f64>();
            }
        }
        out
    }
}

fn shifted(c: &NondimCase, alpha_ref: f64) -> [Vec<f64>; 4] {
    [
        c.x[0].iter().map(|a| a - alpha_ref).collect(),
        c.x[1].clone(),
        c.x[2].clone(),
        c.x[3].clone(),
    ]
}

/// Fits both laws on `train` and scores them on `test` (both scored on the same samples:
/// those the lag law's state has settled on). The returned fit's report carries the
/// comparison.
///
/// # Errors
/// As [`fit`] and [`predict`] (a held-out case with a mean angle outside the training
/// angles is [`Error::OutsideFittedRange`]); [`Error::InvalidData`] for an empty side.
pub fn compare(
    train: &[NondimCase],
    test: &[NondimCase],
    spec: &str,
    opts: &LagFitOptions,
) -> Result<(LagFit, HeldOutReport)> {
    if test.is_empty() {
        return Err(Error::InvalidData {
            case: "-".into(),
            field: "held-out cases".into(),
            message: "no case held out".into(),
        });
    }
    let mut lag = fit(train, opts)?;
    let refs: Vec<&NondimCase> = train.iter().collect();
    let memoryless = MemorylessLaw::fit(&refs)?;
    let mut rows = Vec::with_capacity(test.len());
    for c in test {
        let p = predict(&lag.law, c)?;
        let m = memoryless.predict(c);
        let st = p.start;
        rows.push(HeldOutRow {
            id: c.meta.id.clone(),
            k: p.score.k,
            mean_deg: p.score.mean_deg,
            amplitude_deg: p.score.amplitude_deg,
            memoryless_r2_lift: crate::metrics::r_squared(&c.c_lift[st..], &m[0][st..]),
            memoryless_r2_moment: crate::metrics::r_squared(&c.c_moment[st..], &m[1][st..]),
            lag_r2_lift: p.score.r2_lift,
            lag_r2_moment: p.score.r2_moment,
        });
    }
    let mean = |f: &dyn Fn(&HeldOutRow) -> f64| rows.iter().map(f).sum::<f64>() / rows.len() as f64;
    let report = HeldOutReport {
        spec: spec.to_string(),
        training: train.iter().map(|c| c.meta.id.clone()).collect(),
        mean_r2_lift: [mean(&|r| r.memoryless_r2_lift), mean(&|r| r.lag_r2_lift)],
        mean_r2_moment: [
            mean(&|r| r.memoryless_r2_moment),
            mean(&|r| r.lag_r2_moment),
        ],
        rows,
    };
    lag.report.held_out = Some(report.clone());
    Ok((lag, report))
}

/// Splits `cases` by `spec` ([`HoldOut::split`]) and runs [`compare`].
///
/// # Errors
/// As [`HoldOut::split`] and [`compare`].
pub fn held_out(
    cases: &[NondimCase],
    spec: HoldOut,
    opts: &LagFitOptions,
) -> Result<(LagFit, HeldOutReport)> {
    let (train, test) = spec.split(cases)?;
    let tr: Vec<NondimCase> = train.iter().map(|&i| cases[i].clone()).collect();
    let te: Vec<NondimCase> = test.iter().map(|&i| cases[i].clone()).collect();
    compare(&tr, &te, &spec.to_string(), opts)
}
