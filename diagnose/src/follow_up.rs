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
//! Rows are ranked by the held-out gap of the runs they cover over the level's noise level
//! (the share of the unexplained gap a row can settle).

use aeroelastic::tunnel::{CampaignPlan, Configuration, PlanRow, PLAN_FORMAT};
use identify::dataset::Dataset;

use crate::report::{Coverage, Diagnosis};

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
        let reason = format!(
            "covers {}: held-out gap {} against the noise level {}",
            covers.join(", "),
            gaps.iter()
                .map(|(_, g)| format!("{g:.3} ({:.1}×)", g / noise))
                .collect::<Vec<_>>()
                .join(", "),
            format_args!("{noise:.3}"),
        );
        rows.push((
            weight,
            PlanRow {
                rank: 0,
                configuration: cfg,
                wind_speeds,
                amplitudes_deg: amplitudes,
                covers,
                reason: Some(reason),
            },
        ));
    }
    if rows.is_empty() {
        return None;
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
             smallest; ranked by the held-out gap of the runs a row covers over the noise \
             level. Run: aeroform tunnel forced --campaign-file THIS_FILE --model M"
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

    #[test]
    fn close_speeds_merge_and_far_ones_stay() {
        assert_eq!(
            merge_speeds(vec![2.0, 1.0, 1.02, 1.5]),
            vec![1.01, 1.5, 2.0]
        );
        assert_eq!(merge_speeds(vec![]), Vec::<f64>::new());
    }
}
