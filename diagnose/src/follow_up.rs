//! The forced tests that would settle an extrapolation (issue 42 item 4).
//!
//! When free runs oscillate at reduced frequencies K = B·2πf/U outside the forced campaign's
//! range, the system level's coverage (`system::coverage`) suggests per run and DOF the
//! configuration whose forcing frequency reaches the run's K at the wind speed nearest the
//! run's own. [`plan`] turns those suggestions into a campaign a tunnel engineer runs
//! (`aeroform tunnel forced --campaign-file`): one row per configuration, with
//! - its declared forcing frequencies, amplitude ratio and mean angle (from the forced data
//!   set's manifest, what the rig is set to),
//! - the suggested wind speeds, rescaled to the declared frequency and merged when within
//!   [`MERGE`] of each other (their K then differ by less than the coverage margin),
//!   rounded to 0.01 m/s,
//! - the covered runs' pitch amplitudes rounded to 0.5° and the campaign's smallest
//!   amplitude (two amplitudes at least, so that the new node's linear part is not carried
//!   by one record).
//!
//! Rows are ranked by their predicted discrimination (round 34): how far the force level's
//! consistent candidate (its best candidate, when significant) and the baseline differ at
//! the row's records relative to the noise. At each measured forced case i that difference
//! is the held-out residual energy the candidate removes over the case's noise energy,
//! dᵢ = (beforeᵢ² − afterᵢ²)/noiseᵢ² (`CaseGap`); at a planned speed U it is predicted by
//! a power law d̂(U) = a·Uᵖ fitted by least squares in log–log on the measured cases with
//! dᵢ > 0 (a shedding tone or a delay grows with q = ½ρU² against a fixed balance noise, an
//! added mass does not: p is read from the data, not assumed). Without such a candidate (or
//! fewer than three measured speeds with dᵢ > 0) rows are ranked by the held-out gap of the
//! runs they cover over the level's noise level, as before.
//!
//! When the force level's gap is not significant but that candidate is, the plan adds a
//! row that settles it (`settle_row`): the configuration of the most discriminating
//! measured case, at its speeds and amplitudes with dᵢ ≥ ½ max d, repeated (`repeats`) the
//! fewest times that bring the predicted pooled gap statistic of the forced level, with
//! the coverage rows' cases included, to its threshold (at most [`MAX_REPEATS`] repeats and
//! no more records than the campaign already has: the follow-up at most doubles the tunnel
//! time). When the measured speeds cannot reach it, one speed above the most
//! discriminating case's (+10 % steps, at most [`MAX_SPEED_FACTOR`]×) with the
//! configuration's forcing frequencies scaled by the same factor, so that the records sit
//! at the same reduced frequencies (the same law node, inside the identified range) at a
//! higher dynamic pressure, at the predicted d̂(U), flagged in the row's reason; the row is
//! left out when neither reaches it.

use aeroelastic::tunnel::{CampaignPlan, Configuration, PlanRow, PLAN_FORMAT};
use identify::dataset::Dataset;

use crate::effect::Level;
use crate::report::{Coverage, Diagnosis, LevelResult};

/// Largest number of repeats of one condition the settling row asks for (a tunnel budget:
/// eight records of one condition per configuration and speed).
pub const MAX_REPEATS: usize = 8;

/// Highest speed the settling row may ask for, as a multiple of its most discriminating
/// case's speed
/// (tried in steps of 10 %; beyond the measured speeds the discrimination is the fitted
/// law's extrapolation, and the row says so).
pub const MAX_SPEED_FACTOR: f64 = 1.5;

/// The force level's measured discrimination: the consistent candidate's name, the
/// level's gap threshold, and per forced case (configuration, U \[m/s\], pitch amplitude
/// \[deg\], before²/noise², dᵢ).
struct Evidence {
    candidate: String,
    threshold: f64,
    cases: Vec<(String, f64, f64, f64, f64)>,
    /// Power law (a, p) of d̂(U), when fitted.
    law: Option<(f64, f64)>,
}

impl Evidence {
    fn predict(&self, u: f64) -> Option<f64> {
        self.law.map(|(a, p)| a * u.powf(p))
    }
}

/// The force level's evidence (module docs), when its best candidate is significant.
fn evidence(diag: &Diagnosis) -> Option<Evidence> {
    let l: &LevelResult = diag.levels.iter().find(|l| l.level == Level::Aerodynamic)?;
    let best = l
        .candidates
        .first()
        .filter(|c| c.significant && c.failure.is_none())?;
    let cases: Vec<(String, f64, f64, f64, f64)> = l
        .cases
        .iter()
        .filter(|c| c.noise_level > 0.0 && c.before.is_finite() && c.after.is_finite())
        .map(|c| {
            let n2 = c.noise_level * c.noise_level;
            (
                c.config.clone().unwrap_or_default(),
                c.wind_speed,
                c.amplitude,
                c.before * c.before / n2,
                ((c.before * c.before - c.after * c.after) / n2).max(0.0),
            )
        })
        .collect();
    if cases.is_empty() {
        return None;
    }
    let pts: Vec<(f64, f64)> = cases
        .iter()
        .filter(|c| c.4 > 0.0 && c.1 > 0.0)
        .map(|c| (c.1.ln(), c.4.ln()))
        .collect();
    let mut speeds: Vec<f64> = cases.iter().filter(|c| c.4 > 0.0).map(|c| c.1).collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    let law = (speeds.len() >= 3).then(|| power_law(&pts)).flatten();
    Some(Evidence {
        candidate: best.effect.name().to_string(),
        threshold: l.gap_threshold,
        cases,
        law,
    })
}

/// Least-squares line through (ln U, ln d) points: (a, p) of d = a·Uᵖ, `None` when not
/// finite or no points.
fn power_law(pts: &[(f64, f64)]) -> Option<(f64, f64)> {
    if pts.is_empty() {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let p = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let a = (my - p * mx).exp();
    (a.is_finite() && p.is_finite()).then_some((a, p))
}

/// The row that settles the force level's candidate (module docs), with its predicted
/// pooled gap statistic; `other_cases` are the coverage rows' (U) cases.
fn settle_row(
    ev: &Evidence,
    declared: impl Fn(&str) -> Option<Configuration>,
    other_cases: &[f64],
    duration: Option<f64>,
) -> Option<(PlanRow, f64)> {
    let top = ev.cases.iter().max_by(|a, b| a.4.total_cmp(&b.4))?;
    if top.4 <= 0.0 {
        return None;
    }
    let sel: Vec<_> = ev
        .cases
        .iter()
        .filter(|c| c.0 == top.0 && c.4 >= 0.5 * top.4)
        .collect();
    let mut speeds: Vec<f64> = sel.iter().map(|c| (c.1 * 100.0).round() / 100.0).collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    let mut amps: Vec<f64> = sel.iter().map(|c| (c.2 * 2.0).round() / 2.0).collect();
    amps.sort_by(f64::total_cmp);
    amps.dedup();
    amps.retain(|a| *a > 0.0);
    // each grid case's predicted before²/noise²: 1 + the measured d of that condition
    // (the candidate's part only), 1 where the grid point was not measured
    let grid: Vec<f64> = speeds
        .iter()
        .flat_map(|u| amps.iter().map(move |a| (*u, *a)))
        .map(|(u, a)| {
            1.0 + ev
                .cases
                .iter()
                .filter(|c| c.0 == top.0 && (c.1 - u).abs() < 0.006 && (c.2 - a).abs() < 0.26)
                .map(|c| c.4)
                .fold(0.0, f64::max)
        })
        .collect();
    let num0: f64 = ev.cases.iter().map(|c| c.3).sum::<f64>()
        + other_cases
            .iter()
            .map(|u| 1.0 + ev.predict(*u).unwrap_or(0.0))
            .sum::<f64>();
    let den0 = (ev.cases.len() + other_cases.len()) as f64;
    let target = ev.threshold * ev.threshold;
    let budget = ev.cases.len();
    // the fewest repeats of a grid (its cases' predicted before²/noise²) that reach the
    // target within the budget
    let reach = |grid: &[f64]| -> Option<(usize, f64)> {
        let (gn, gd) = (grid.iter().sum::<f64>(), grid.len() as f64);
        (1..=MAX_REPEATS)
            .take_while(|m| m * grid.len() <= budget.max(grid.len()))
            .map(|m| (m, (num0 + m as f64 * gn) / (den0 + m as f64 * gd)))
            .find(|(_, s)| *s >= target)
    };
    let (speeds, grid, m, stat2, above) = match reach(&grid) {
        Some((m, s2)) => (speeds, grid, m, s2, None),
        None => {
            // one speed above the most discriminating case's, its forcing frequencies
            // scaled by the same factor: the same reduced frequencies K = B·2πf/U (the
            // same law node, inside the identified range) at a higher q, the
            // discrimination predicted by the fitted law
            ev.law?;
            (1..=5)
                .map(|k| ((top.1 * (1.0 + 0.1 * k as f64)) * 100.0).round() / 100.0)
                .filter(|u| *u <= MAX_SPEED_FACTOR * top.1 + 1e-9)
                .find_map(|u| {
                    let g: Vec<f64> = amps
                        .iter()
                        .map(|_| 1.0 + ev.predict(u).unwrap_or(0.0))
                        .collect();
                    reach(&g).map(|(m, s2)| (vec![u], g, m, s2, Some(u)))
                })?
        }
    };
    let (gn, gd) = (grid.iter().sum::<f64>(), grid.len() as f64);
    let mut cfg = declared(&top.0)?;
    let disc = m as f64 * (gn - gd);
    let at = match above {
        None => String::new(),
        Some(u) => {
            let scale = u / top.1;
            cfg.freq_pitch *= scale;
            cfg.freq_heave *= scale;
            format!(
                "; at {u} m/s with the configuration's frequencies ×{scale:.3} (the same K as \
                 at {} m/s), above the measured speed (predicted d = {:.2} from the fitted law \
                 d ∝ U^{:.2}): check that the tunnel and the rig reach it",
                top.1,
                ev.predict(u).unwrap_or(f64::NAN),
                ev.law.map_or(f64::NAN, |l| l.1)
            )
        }
    };
    let reason = format!(
        "settles `{}` (significant at the force level, gap not): measured discrimination \
         d = {:.2} × noise energy at U = {} m/s, A = {}°; {m} repeats bring the predicted \
         forced-level gap statistic to {:.2} (threshold {:.2}){at}",
        ev.candidate,
        top.4,
        top.1,
        top.2,
        stat2.sqrt(),
        ev.threshold
    );
    Some((
        PlanRow {
            rank: 0,
            configuration: cfg,
            wind_speeds: speeds,
            amplitudes_deg: amps,
            covers: vec![],
            reason: Some(reason),
            repeats: Some(m),
            record_duration_s: duration,
            discrimination: Some(disc),
        },
        stat2.sqrt(),
    ))
}

/// The forced records' length \[s\] (median over the records with forces).
fn record_duration(forced: &Dataset) -> Option<f64> {
    let d: Vec<f64> = forced
        .records
        .iter()
        .filter(|r| r.lift.is_some())
        .map(|r| r.h.len() as f64 * r.dt)
        .filter(|d| d.is_finite() && *d > 0.0 && *d <= 3600.0)
        .collect();
    let m = identify::numerics::median_finite(&d);
    (m.is_finite() && m > 0.0).then_some((m * 1000.0).round() / 1000.0)
}

/// Relative distance within which suggested wind speeds are merged into one (their mean):
/// K differs by at most half of it, well inside the coverage margin
/// (`system::coverage::MARGIN`, 10 %).
pub const MERGE: f64 = 0.03;

/// The level coverage with suggestions, and its noise level.
fn coverage_of(diag: &Diagnosis) -> Option<(&Coverage, f64)> {
    diag.levels.iter().find_map(|l| {
        l.coverage
            .as_ref()
            .filter(|c| !c.suggestions.is_empty())
            .map(|c| (c, l.noise_level))
    })
}

/// The configuration `name` as declared in the forced data set (first case of it with
/// both forcing frequencies), in the tunnel's units (Hz, mm/deg, deg).
fn declared(forced: &Dataset, name: &str) -> Option<Configuration> {
    forced.records.iter().find_map(|r| {
        let m = &r.meta;
        (m.config.as_deref() == Some(name)).then_some(())?;
        Some(Configuration {
            name: name.to_string(),
            freq_pitch: m.freq_pitch?,
            freq_heave: m.freq_heave?,
            amplitude_ratio: m.amplitude_ratio.unwrap_or(0.0),
            mean_pitch_deg: m.mean_pitch.unwrap_or(0.0).to_degrees(),
        })
    })
}

/// Merges sorted positive speeds within [`MERGE`] of the first of each cluster; returns
/// each cluster's mean rounded to 0.01 m/s.
fn merge_speeds(mut u: Vec<f64>) -> Vec<f64> {
    u.sort_by(f64::total_cmp);
    let mut out: Vec<Vec<f64>> = Vec::new();
    for v in u {
        match out.last_mut() {
            Some(c) if v <= c[0] * (1.0 + MERGE) => c.push(v),
            _ => out.push(vec![v]),
        }
    }
    let mut speeds: Vec<f64> = out
        .iter()
        .map(|c| (c.iter().sum::<f64>() / c.len() as f64 * 100.0).round() / 100.0)
        .filter(|u| *u > 0.0)
        .collect();
    speeds.dedup();
    speeds
}

/// The follow-up campaign of a diagnosis (module docs), or `None` when no free run is
/// outside the forced range (or no suggested configuration is declared in `forced`).
pub fn plan(diag: &Diagnosis, forced: &Dataset) -> Option<CampaignPlan> {
    let (cov, noise) = coverage_of(diag)?;
    let ev = evidence(diag);
    let force_gap_significant = diag
        .levels
        .iter()
        .any(|l| l.level == Level::Aerodynamic && l.significant_gap);
    let duration = record_duration(forced);
    let smallest = forced
        .records
        .iter()
        .filter_map(|r| r.meta.amplitude)
        .map(f64::to_degrees)
        .filter(|a| a.is_finite() && *a > 0.0)
        .fold(f64::INFINITY, f64::min);
    let mut names: Vec<&str> = cov
        .suggestions
        .iter()
        .map(|s| s.configuration.as_str())
        .collect();
    names.sort_unstable();
    names.dedup();
    let mut rows: Vec<(f64, PlanRow)> = Vec::new();
    for name in names {
        let Some(cfg) = declared(forced, name) else {
            continue;
        };
        let sugg: Vec<_> = cov
            .suggestions
            .iter()
            .filter(|s| s.configuration == name)
            .collect();
        let speeds: Vec<f64> = sugg
            .iter()
            .filter(|s| s.frequency_hz > 0.0 && s.wind_speed.is_finite())
            .map(|s| {
                let declared_f = if s.dof == "heave" {
                    cfg.freq_heave
                } else {
                    cfg.freq_pitch
                };
                s.wind_speed * declared_f / s.frequency_hz
            })
            .filter(|u| u.is_finite() && *u > 0.0 && *u <= identify::limits::MAX_SPEED)
            .collect();
        let wind_speeds = merge_speeds(speeds);
        if wind_speeds.is_empty() {
            continue;
        }
        let mut amplitudes: Vec<f64> = sugg
            .iter()
            .map(|s| ((s.amplitude_alpha_deg * 2.0).round() / 2.0).max(0.5))
            .filter(|a| a.is_finite() && *a <= identify::limits::MAX_PITCH_DEG)
            .collect();
        if smallest.is_finite() {
            amplitudes.push((smallest * 2.0).round() / 2.0);
        }
        amplitudes.sort_by(f64::total_cmp);
        amplitudes.dedup();
        let mut covers: Vec<String> = sugg.iter().map(|s| s.run.clone()).collect();
        covers.dedup();
        let gaps: Vec<(String, f64)> = covers
            .iter()
            .filter_map(|id| cov.runs.iter().find(|r| &r.id == id))
            .map(|r| (r.id.clone(), r.before))
            .collect();
        let weight: f64 = gaps.iter().map(|(_, g)| g * g).sum::<f64>().sqrt();
        let discrimination = ev.as_ref().and_then(|e| {
            wind_speeds
                .iter()
                .map(|u| e.predict(*u).map(|d| d * amplitudes.len() as f64))
                .sum::<Option<f64>>()
        });
        let reason = format!(
            "covers {}: held-out gap {} against the noise level {}",
            covers.join(", "),
            gaps.iter()
                .map(|(_, g)| format!("{g:.3} ({:.1}×)", g / noise))
                .collect::<Vec<_>>()
                .join(", "),
            format_args!("{noise:.3}"),
        );
        let reason = match discrimination {
            Some(d) => format!(
                "{reason}; predicted discrimination of `{}` {d:.2} × one record's noise energy",
                ev.as_ref().map_or("", |e| e.candidate.as_str())
            ),
            None => reason,
        };
        rows.push((
            discrimination.unwrap_or(weight),
            PlanRow {
                rank: 0,
                configuration: cfg,
                wind_speeds,
                amplitudes_deg: amplitudes,
                covers,
                reason: Some(reason),
                repeats: None,
                record_duration_s: duration,
                discrimination,
            },
        ));
    }
    if rows.is_empty() {
        return None;
    }
    // the rows are ranked by one key: the predicted discrimination when every row has one,
    // else the covered runs' held-out gap
    let by_discrimination = rows.iter().all(|r| r.1.discrimination.is_some());
    let settle = match (&ev, force_gap_significant) {
        (Some(e), false) => {
            let other: Vec<f64> = rows
                .iter()
                .flat_map(|(_, r)| {
                    r.wind_speeds
                        .iter()
                        .flat_map(move |u| r.amplitudes_deg.iter().map(move |_| *u))
                })
                .collect();
            settle_row(e, |n| declared(forced, n), &other, duration)
        }
        _ => None,
    };
    if let Some((row, _)) = settle {
        let key = row.discrimination.unwrap_or(0.0);
        // not comparable with the covered runs' gaps: after the coverage rows
        rows.push((
            if by_discrimination {
                key
            } else {
                f64::NEG_INFINITY
            },
            row,
        ));
    }
    rows.sort_by(|a, b| b.0.total_cmp(&a.0));
    let rows: Vec<PlanRow> = rows
        .into_iter()
        .enumerate()
        .map(|(i, (_, mut r))| {
            r.rank = i + 1;
            r
        })
        .collect();
    let plan = CampaignPlan {
        format: PLAN_FORMAT.into(),
        note: Some(
            "Forced tests that cover the free runs outside the forced range: each \
             configuration's forcing frequencies at the wind speeds giving the runs' reduced \
             frequencies K = B·2πf/U, at the runs' pitch amplitudes and the campaign's \
             smallest; with a row of repeated records that settles a candidate significant \
             at the force level whose gap is not. Ranked by the predicted discrimination \
             between the force level's consistent candidate and the baseline over the \
             noise (else by the held-out gap of the runs a row covers). Each record \
             `record_duration_s` long. Run: aeroform tunnel forced --campaign-file \
             THIS_FILE --model M"
                .into(),
        ),
        rows,
    };
    plan.check("follow-up plan").ok()?;
    Some(plan)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(name: &str) -> Option<Configuration> {
        Some(Configuration {
            name: name.to_string(),
            freq_pitch: 2.0,
            freq_heave: 1.3,
            amplitude_ratio: 0.0,
            mean_pitch_deg: 0.0,
        })
    }

    /// Evidence of one configuration at 4…10 m/s × two amplitudes with d = d10·(U/10)⁴.
    fn evidence_of(d10: f64, threshold: f64) -> Evidence {
        let cases: Vec<(String, f64, f64, f64, f64)> = [4.0, 6.0, 8.0, 10.0]
            .iter()
            .flat_map(|&u| {
                [2.0, 6.0].map(|a| {
                    let d = d10 * (u / 10.0f64).powi(4);
                    ("C".to_string(), u, a, 1.0 + d, d)
                })
            })
            .collect();
        let pts: Vec<(f64, f64)> = cases.iter().map(|c| (c.1.ln(), c.4.ln())).collect();
        Evidence {
            candidate: "vortex_shedding".into(),
            threshold,
            law: power_law(&pts),
            cases,
        }
    }

    #[test]
    fn the_power_law_reads_the_exponent_from_the_cases() {
        let ev = evidence_of(3.0, 1.8);
        let (a, p) = ev.law.unwrap();
        assert!((p - 4.0).abs() < 1e-9, "{p}");
        assert!((a * 10f64.powf(p) - 3.0).abs() < 1e-9);
        assert!((ev.predict(12.0).unwrap() - 3.0 * 1.2f64.powi(4)).abs() < 1e-9);
        assert_eq!(power_law(&[]), None);
    }

    #[test]
    fn the_settling_row_repeats_the_most_discriminating_conditions() {
        // measured d = 8 at 10 m/s: repeats of the measured speed reach a threshold of 2.5
        let ev = evidence_of(8.0, 2.5);
        let (row, stat) = settle_row(&ev, config, &[], Some(8.0)).unwrap();
        assert_eq!(row.wind_speeds, vec![10.0], "{row:?}");
        assert_eq!(row.amplitudes_deg, vec![2.0, 6.0]);
        assert!(stat >= 2.5, "{stat}");
        let m = row.repeats.unwrap();
        assert!(m > 1, "{m}");
        // the fewest: one repeat fewer does not reach it
        let num0: f64 = ev.cases.iter().map(|c| c.3).sum();
        let den0 = ev.cases.len() as f64;
        let fewer = (num0 + (m - 1) as f64 * 2.0 * 9.0) / (den0 + (m - 1) as f64 * 2.0);
        assert!(fewer < 2.5 * 2.5, "{m} {fewer}");
        assert_eq!(row.configuration.freq_pitch, 2.0);
        assert_eq!(row.record_duration_s, Some(8.0));
        assert!(row.covers.is_empty());
    }

    #[test]
    fn above_the_measured_speed_the_frequencies_keep_the_reduced_frequency() {
        // d = 3 at 10 m/s cannot bring the pooled statistic to 2.2 at the measured speeds
        let ev = evidence_of(3.0, 2.2);
        let (row, stat) = settle_row(&ev, config, &[], None).unwrap();
        let u = row.wind_speeds[0];
        assert!(u > 10.0 && u <= MAX_SPEED_FACTOR * 10.0 + 1e-9, "{row:?}");
        assert!(stat >= 2.2);
        // same K = B·2πf/U as the measured node at 10 m/s
        assert!((row.configuration.freq_pitch / u - 2.0 / 10.0).abs() < 1e-12);
        assert!((row.configuration.freq_heave / u - 1.3 / 10.0).abs() < 1e-12);
        assert!(row.reason.unwrap().contains("check that the tunnel"));
        // nothing within the budget: no row
        assert!(settle_row(&evidence_of(0.05, 2.2), config, &[], None).is_none());
        // coverage cases at low speed dilute the pooled statistic: more repeats or a higher
        // speed
        let (diluted, _) = settle_row(&evidence_of(8.0, 2.5), config, &[2.0; 6], None).unwrap();
        let (alone, _) = settle_row(&evidence_of(8.0, 2.5), config, &[], None).unwrap();
        assert!(
            diluted.wind_speeds[0] > alone.wind_speeds[0]
                || diluted.repeats.unwrap() > alone.repeats.unwrap(),
            "{diluted:?} {alone:?}"
        );
    }

    #[test]
    fn close_speeds_merge_and_far_ones_stay() {
        assert_eq!(
            merge_speeds(vec![2.0, 1.0, 1.02, 1.5]),
            vec![1.01, 1.5, 2.0]
        );
        assert_eq!(merge_speeds(vec![]), Vec::<f64>::new());
    }
}
