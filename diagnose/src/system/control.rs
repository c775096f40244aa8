//! Controlled records (control-based continuation): the feedback controller's force as a
//! measured input of the free-response equation error.
//!
//! A record whose case file carries a control signal ([`identify::record::ControlSignal`];
//! DATA_FORMAT.md, "Controlled records") was not free: a shaker on the heave stage pushed
//! it. The force enters the heave equation like the aerodynamic lift,
//!
//! M_s q̈ + C_s q̇ + K_s q = F + (f_c, 0),
//!
//! seen through the residual's smoothing S like every other force term
//! ([`super::residual::smooth_as_acceleration`]). A calibrated signal (`control_force`,
//! N/m) is f_c itself and is part of the residual ([`super::residual::prepare_run`]). A raw
//! signal u (`control_raw`) gives f_c = g·u + o with a gain g \[N/m per unit\] and an
//! offset o \[N/m\], one pair for the data set, fitted by least squares on the training runs
//! only: alone for the level's gap (`apply_held_out`: every run's residual is the one
//! left by the (g, o) of the fold that holds it out) and jointly with each candidate's
//! linear coefficients (`candidates::control_columns`, appended to every candidate's columns like the
//! apparent-mass nuisances). The interval of g is the jackknife over the folds.
//!
//! Which DOF the controller acts on is checked from the data: the same held-out fit on
//! the heave and on the pitch residual alone ([`ControlReport::dof_check`]).

use serde::{Deserialize, Serialize};

use super::candidates::{
    self, control_columns as columns, control_columns_on as columns_on, raw_control as raw, Column,
    CONTROL_NAMES as NAMES,
};
use super::residual::RunResidual;

pub use super::residual::{PdLaw, RunControl};

/// A fitted coefficient with its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Interval {
    /// Value fitted on every run.
    pub value: f64,
    /// Jackknife standard error over the folds (leave one run out: over the runs).
    pub se: f64,
    /// Lower end: value − t₀.₉₇₅(k − 1)·se (k folds with a controlled training run).
    pub low: f64,
    /// Upper end: value + t₀.₉₇₅(k − 1)·se.
    pub high: f64,
}

/// The data's answer to "which DOF does the controller act on": a raw signal's gain and
/// offset fitted on one DOF's residual alone, held out like the level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DofCheck {
    /// `heave` or `pitch`.
    pub dof: String,
    /// Gain on that DOF \[N/m per unit\] (heave) or \[N·m/m per unit\] (pitch), fit sign: a
    /// force in the DOF's positive sense per unit of the signal.
    pub gain: Interval,
    /// Share of the DOF's residual energy on the controlled runs that the held-out fit
    /// removes, 1 − E_after/E_before (negative: the fit makes held-out runs worse).
    pub removed: f64,
}

/// Per controlled run: the gap per DOF (sqrt of the normalised residual energy, heave and
/// pitch) without the control force and with it (held out).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ControlRun {
    /// Case id.
    pub id: String,
    /// Wind speed \[m/s\].
    pub wind_speed: f64,
    /// \[heave, pitch\] gap without the control force.
    pub without: [f64; 2],
    /// \[heave, pitch\] gap with it (calibrated: as given; raw: (g, o) of the fold that
    /// holds the run out).
    pub with: [f64; 2],
    /// The feedback law reconstructed from `h_target`, when recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pd_law: Option<PdLaw>,
    /// \[heave, pitch\]: the share of the DOF's residual energy (without the control) that
    /// the signal removes with its own gain and offset fitted on this run and DOF alone, in
    /// sample — an upper bound of what any calibration of the signal could explain there
    /// (raw signal only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub best_share: Option<[f64; 2]>,
}

/// What the controlled records of a free-response level contributed (`control` of a
/// level in diagnosis.json).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ControlReport {
    /// `calibrated` (a force in N/m, no parameter) or `raw` (gain and offset fitted).
    pub signal: String,
    /// The DOF the force enters by the data format's contract: `heave`.
    pub dof: String,
    /// The DOF the data points at (see [`ControlReport::dof_check`]): `heave`, `pitch`
    /// or `undetermined` (no gain interval excludes zero).
    pub data_dof: String,
    /// Gain g \[N/m per unit of the signal\] on the heave DOF (raw signal only), fit sign:
    /// the force g·u + o acts like the lift, positive down.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain: Option<Interval>,
    /// Offset o \[N/m\] (raw signal only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<Interval>,
    /// The held-out gap of the level with the control force left out (the records read as
    /// if free), same metric as `before`.
    pub gap_without: f64,
    /// The held-out gap with it (the level's `before`).
    pub gap_with: f64,
    /// Per controlled run.
    pub runs: Vec<ControlRun>,
    /// The fit on the heave and on the pitch residual alone (raw signal only).
    pub dof_check: Vec<DofCheck>,
    /// Whether the controlled runs were simulated (closed loop) or left out of the
    /// simulated observables, and why.
    pub simulation: String,
}

/// Smallest share of a controlled record's variance a reconstructed feedback law must
/// reproduce on every run before the closed loop could be simulated.
pub const PD_SIMULABLE_R2: f64 = 0.9;

/// Two-sided 95 % Student-t quantile for `df` degrees of freedom (1.96 beyond 30).
fn t975(df: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::INFINITY,
        d if d <= 30 => T[d - 1],
        _ => 1.96,
    }
}

/// Held-out fit of the columns `cols[j]` (per run) over `folds`: per fold the least
/// squares on its training runs; returns the per-run energies after (held out), the fit on
/// every run and the jackknife intervals of the coefficients (over the folds that had a
/// training run with a nonzero column). `None` when no fit is possible.
fn held_out_fit(
    runs: &[RunResidual],
    cols: &[Vec<Column>],
    folds: &[usize],
) -> Option<(Vec<[f64; 2]>, Vec<Interval>)> {
    let names: Vec<String> = (0..cols.first()?.len()).map(|k| k.to_string()).collect();
    let v = candidates::Variant {
        grid: Vec::new(),
        names,
        moments: runs
            .iter()
            .zip(cols)
            .map(|(r, c)| candidates::moments(r, c))
            .collect(),
    };
    let n = runs.len();
    let used: Vec<bool> = cols
        .iter()
        .map(|c| c.iter().any(|x| !x[0].is_empty() || !x[1].is_empty()))
        .collect();
    let vars = std::slice::from_ref(&v);
    let all: Vec<usize> = (0..n).collect();
    let (_, theta, _) = candidates::fit(vars, &all)?;
    let mut after: Vec<[f64; 2]> = v.moments.iter().map(|m| m.e).collect();
    let mut jack: Vec<Vec<f64>> = Vec::new();
    let n_folds = folds.iter().max().map_or(0, |m| m + 1);
    for k in 0..n_folds {
        let train: Vec<usize> = (0..n).filter(|&j| folds[j] != k).collect();
        let held: Vec<usize> = (0..n).filter(|&j| folds[j] == k).collect();
        if !train.iter().any(|&j| used[j]) {
            continue;
        }
        let (_, th, _) = candidates::fit(vars, &train)?;
        for &j in &held {
            after[j] = candidates::energy_after(&v.moments[j], &th);
        }
        if held.iter().any(|&j| used[j]) {
            jack.push(th);
        }
    }
    let k = jack.len();
    let intervals = (0..theta.len())
        .map(|a| {
            let se = if k > 1 {
                let m = jack.iter().map(|t| t[a]).sum::<f64>() / k as f64;
                ((k as f64 - 1.0) / k as f64 * jack.iter().map(|t| (t[a] - m).powi(2)).sum::<f64>())
                    .sqrt()
            } else {
                f64::INFINITY
            };
            let w = t975(k.saturating_sub(1)) * se;
            Interval {
                value: theta[a],
                se,
                low: theta[a] - w,
                high: theta[a] + w,
            }
        })
        .collect();
    // per fold, held out: the residual a held-out run keeps
    Some((after, intervals))
}

/// Subtracts from each run's residual the fitted control force of the fold that holds it
/// out (raw signals), so that the level's gap is held out with the control as a known
/// input, and reports the control's part (`None` when no run is controlled). `runs` are
/// the level's runs (still air's apparent mass already removed), `folds` its folds.
pub(crate) fn apply_held_out(runs: &mut [RunResidual], folds: &[usize]) -> Option<ControlReport> {
    let controlled: Vec<usize> = (0..runs.len())
        .filter(|&j| runs[j].control.is_some())
        .collect();
    if controlled.is_empty() {
        return None;
    }
    let any_raw = runs.iter().any(raw);
    let comb = |e: [f64; 2]| (0.5 * (e[0] + e[1])).max(0.0).sqrt();
    // pooled as the level pools its gap (still-air runs out when runs in the wind exist)
    let weights = super::residual::run_weights(runs);
    let mean_e = |v: &[[f64; 2]]| -> [f64; 2] {
        let m = weights.iter().sum::<f64>().max(f64::MIN_POSITIVE);
        [0, 1].map(|c| v.iter().zip(&weights).map(|(e, w)| w * e[c]).sum::<f64>() / m)
    };
    let without: Vec<[f64; 2]> = runs.iter().map(calibrated_without).collect();
    let mut with: Vec<[f64; 2]> = runs.iter().map(|r| r.energy()).collect();
    let (mut gain, mut offset, mut dof_check) = (None, None, Vec::new());
    let mut data_dof = "heave".to_string();
    if any_raw {
        // the DOF check: the same fit on one DOF's residual alone
        for (d, name) in ["heave", "pitch"].into_iter().enumerate() {
            let cols: Vec<Vec<Column>> = runs.iter().map(|r| columns_on(r, d)).collect();
            if let Some((after, iv)) = held_out_fit(runs, &cols, folds) {
                let eb: f64 = controlled
                    .iter()
                    .filter(|&&j| raw(&runs[j]))
                    .map(|&j| without[j][d])
                    .sum();
                let ea: f64 = controlled
                    .iter()
                    .filter(|&&j| raw(&runs[j]))
                    .map(|&j| after[j][d])
                    .sum();
                dof_check.push(DofCheck {
                    dof: name.into(),
                    gain: iv[0],
                    removed: if eb > 0.0 { 1.0 - ea / eb } else { 0.0 },
                });
            }
        }
        let excludes_zero = |c: &DofCheck| c.gain.low > 0.0 || c.gain.high < 0.0;
        data_dof = dof_check
            .iter()
            .filter(|c| excludes_zero(c))
            .max_by(|a, b| a.removed.total_cmp(&b.removed))
            .map_or("undetermined".to_string(), |c| c.dof.clone());
        let cols: Vec<Vec<Column>> = runs.iter().map(columns).collect();
        if let Some((after, iv)) = held_out_fit(runs, &cols, folds) {
            gain = Some(iv[0]);
            offset = Some(iv[1]);
            // the residual each run keeps: that of its fold's fit (moments give the energy;
            // the series is rebuilt from the fold's coefficients)
            let n = runs.len();
            let n_folds = folds.iter().max().map_or(0, |m| m + 1);
            let v = candidates::Variant {
                grid: Vec::new(),
                names: NAMES.iter().map(|s| s.to_string()).collect(),
                moments: runs
                    .iter()
                    .zip(&cols)
                    .map(|(r, c)| candidates::moments(r, c))
                    .collect(),
            };
            for k in 0..n_folds {
                let train: Vec<usize> = (0..n).filter(|&j| folds[j] != k).collect();
                let Some((_, th, _)) = candidates::fit(std::slice::from_ref(&v), &train) else {
                    continue;
                };
                let held: Vec<usize> = (0..n).filter(|&j| folds[j] == k && raw(&runs[j])).collect();
                for j in held {
                    let r = &mut runs[j];
                    for (c, col) in cols[j].iter().enumerate() {
                        for (x, y) in r.r[0].iter_mut().zip(&col[0]) {
                            *x -= th[c] * y;
                        }
                    }
                }
            }
            with = after;
        }
    }
    let per_run = controlled
        .iter()
        .map(|&j| {
            let r = &runs[j];
            let sq = |e: [f64; 2]| e.map(|x| x.max(0.0).sqrt());
            ControlRun {
                id: r.id.clone(),
                wind_speed: r.u,
                without: sq(without[j]),
                with: sq(with[j]),
                pd_law: r.control.as_ref().and_then(|c| c.pd),
                best_share: raw(r).then(|| [0, 1].map(|d| best_share(r, d))),
            }
        })
        .collect::<Vec<_>>();
    let pd: Vec<Option<f64>> = controlled
        .iter()
        .map(|&j| runs[j].control.as_ref().and_then(|c| c.pd).map(|p| p.r2))
        .collect();
    let simulation = if pd.iter().all(|p| p.is_none()) {
        "controlled runs not simulated: no heave target recorded, the feedback law cannot \
         be reconstructed (their measured LCO points are kept, no simulated point)"
            .to_string()
    } else {
        let r2: Vec<f64> = pd.iter().map(|p| p.unwrap_or(f64::NAN)).collect();
        let (lo, hi) = r2
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if r2.iter().all(|&x| x >= PD_SIMULABLE_R2) {
            format!(
                "controlled runs not simulated: a PD law on h_target − h reproduces the \
                 control signal (R² {lo:.3}–{hi:.3} ≥ {PD_SIMULABLE_R2}), but the closed-loop \
                 simulation is not implemented yet; their measured LCO points are kept, no \
                 simulated point"
            )
        } else {
            format!(
                "controlled runs not simulated: a PD law on h_target − h reproduces the \
                 control signal with R² {lo:.3}–{hi:.3} only (needed ≥ {PD_SIMULABLE_R2} on \
                 every run), so the closed loop cannot be rebuilt; their measured LCO \
                 points are kept, no simulated point"
            )
        }
    };
    Some(ControlReport {
        signal: if any_raw { "raw" } else { "calibrated" }.into(),
        dof: "heave".into(),
        data_dof,
        gain,
        offset,
        gap_without: comb(mean_e(&without)),
        gap_with: comb(mean_e(&with)),
        runs: per_run,
        dof_check,
        simulation,
    })
}

/// The share of run `r`'s residual energy on DOF `dof` that its raw signal removes with
/// a gain and offset fitted on that run and DOF alone (in sample; 0 when singular).
fn best_share(r: &RunResidual, dof: usize) -> f64 {
    let m = candidates::moments(r, &columns_on(r, dof));
    let (g, b) = (&m.g[dof], &m.b[dof]);
    let e = m.e[dof];
    match candidates::solve(g, b) {
        Some(th) if e > 0.0 => (th.iter().zip(b).map(|(t, y)| t * y).sum::<f64>() / e).max(0.0),
        _ => 0.0,
    }
}

/// A run's residual energy without its control force: a calibrated run's residual with
/// S(f_c) added back on the heave DOF; any other run's own energy.
fn calibrated_without(r: &RunResidual) -> [f64; 2] {
    let Some(c) = r.control.as_ref().filter(|c| c.calibrated) else {
        return r.energy();
    };
    let n = r.len().max(1) as f64;
    let h: f64 = r.r[0]
        .iter()
        .zip(&c.column)
        .map(|(x, u)| (x + u).powi(2))
        .sum::<f64>()
        / (n * r.norm[0].powi(2));
    [h, r.energy()[1]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::residual::pd_law;

    #[test]
    fn pd_law_recovers_known_gains_and_reports_a_poor_fit() {
        let n = 2000;
        let dt = 0.004;
        let e: Vec<f64> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * 2.5 * i as f64 * dt).sin() * 1e-3)
            .collect();
        let ed: Vec<f64> = (0..n)
            .map(|i| {
                2.0 * std::f64::consts::PI
                    * 2.5
                    * (2.0 * std::f64::consts::PI * 2.5 * i as f64 * dt).cos()
                    * 1e-3
            })
            .collect();
        let u: Vec<f64> = (0..n).map(|i| 3.0 * e[i] + 0.2 * ed[i] - 0.01).collect();
        let p = pd_law(&u, &e, &ed).unwrap();
        assert!(
            (p.kp - 3.0).abs() < 1e-9 && (p.kd - 0.2).abs() < 1e-9,
            "{p:?}"
        );
        assert!((p.offset + 0.01).abs() < 1e-12 && p.r2 > 1.0 - 1e-12);
        // a signal the law does not make: a cosine at another frequency
        let w: Vec<f64> = (0..n).map(|i| (7.0 * i as f64 * dt).cos()).collect();
        let q = pd_law(&w, &e, &ed).unwrap();
        assert!(q.r2 < 0.1, "{q:?}");
    }

    #[test]
    fn student_t_quantiles() {
        assert!((t975(8) - 2.306).abs() < 1e-9);
        assert_eq!(t975(100), 1.96);
        assert!(t975(0).is_infinite());
    }
}
