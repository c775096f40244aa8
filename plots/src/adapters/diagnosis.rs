//! `diagnose::Diagnosis` → the diagnosis figures: gap heat maps, residual spectra,
//! candidate ranking, predicted vs measured bifurcation diagram, where-shares.
//!
//! Each adapter returns `None` when the diagnosis holds nothing it could draw (no forced
//! level, no candidates, no free runs…); panels without finite data are kept and show a
//! "no data" note. No computation beyond grouping, ratios and labelling.

use std::collections::BTreeMap;

use diagnose::report::{CandidateScore, Channel, LevelResult, Split, WhereShare};
use diagnose::{Diagnosis, Level};

use crate::style::fmt_num;
use crate::{
    ComparisonFigure, ComparisonPanel, GapHeatmapFigure, GapHeatmapPanel, RankingBar,
    RankingFigure, RankingPanel, ResidualSpectraFigure, Series, SeriesKind, ShareBar, ShareSegment,
    SharesFigure, SpectraPanel,
};

/// Most segments drawn per where-bar; smaller cells are merged into "other".
pub const MAX_SEGMENTS: usize = 7;

/// Display name of a level in panel titles.
pub fn level_title(level: Level) -> &'static str {
    match level {
        Level::Aerodynamic => "aerodynamic level (forced records)",
        Level::Structural => "structural level (free response)",
        Level::None => "no level",
    }
}

/// Name of the best candidate of a level (first of its ranked list), if any was fitted.
pub fn best_candidate(level: &LevelResult) -> Option<&CandidateScore> {
    level
        .candidates
        .iter()
        .find(|c| c.failure.is_none() && c.after.is_finite())
}

fn first_level(diag: &Diagnosis, level: Level) -> Option<&LevelResult> {
    diag.levels.iter().find(|l| l.level == level)
}

/// Grid key of a float (1e-6 resolution) so equal grid values coincide.
fn key(v: f64) -> i64 {
    (v * 1e6).round() as i64
}

/// Gap heat maps of the aerodynamic level: one row of panels per configuration, columns
/// before / after the level's best candidate; cell = held-out gap / noise level of the
/// case at (amplitude, U); several cases in one cell are averaged.
///
/// `None` when the diagnosis has no aerodynamic level or it has no finite per-case gap.
pub fn gap_heatmap_figure(diag: &Diagnosis) -> Option<GapHeatmapFigure> {
    let lv = first_level(diag, Level::Aerodynamic)?;
    let cases: Vec<_> = lv
        .cases
        .iter()
        .filter(|c| c.wind_speed.is_finite() && c.amplitude.is_finite())
        .collect();
    if cases.is_empty() {
        return None;
    }
    let after_name = best_candidate(lv).map_or("no candidate".to_string(), |c| {
        format!("+ {}", c.effect.name())
    });
    let mut by_config: BTreeMap<String, Vec<_>> = BTreeMap::new();
    for c in &cases {
        by_config
            .entry(c.config.clone().unwrap_or_else(|| "all".into()))
            .or_default()
            .push(*c);
    }
    let mut panels = vec![];
    for (config, rows) in &by_config {
        let mut xs: Vec<i64> = rows.iter().map(|c| key(c.amplitude)).collect();
        let mut ys: Vec<i64> = rows.iter().map(|c| key(c.wind_speed)).collect();
        xs.sort_unstable();
        xs.dedup();
        ys.sort_unstable();
        ys.dedup();
        for (stage, after) in [("before", false), ("after", true)] {
            let mut sum = vec![vec![(0.0, 0usize); xs.len()]; ys.len()];
            for c in rows {
                let g = if after { c.after } else { c.before };
                let r = g / c.noise_level;
                if !(r.is_finite() && r > 0.0) {
                    continue;
                }
                let (Ok(ix), Ok(iy)) = (
                    xs.binary_search(&key(c.amplitude)),
                    ys.binary_search(&key(c.wind_speed)),
                ) else {
                    continue;
                };
                sum[iy][ix].0 += r;
                sum[iy][ix].1 += 1;
            }
            let values = sum
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|&(s, n)| (n > 0).then(|| s / n as f64))
                        .collect()
                })
                .collect();
            let title = if after {
                format!("config {config}: {stage} ({after_name})")
            } else {
                format!("config {config}: {stage}")
            };
            panels.push(GapHeatmapPanel {
                title,
                x_values: xs.iter().map(|&v| v as f64 * 1e-6).collect(),
                y_values: ys.iter().map(|&v| v as f64 * 1e-6).collect(),
                values,
            });
        }
    }
    Some(GapHeatmapFigure {
        title: "Held-out force gap / noise level over U × amplitude".into(),
        x_label: "pitch amplitude [deg]".into(),
        y_label: "U [m/s]".into(),
        columns: 2,
        panels,
    })
}

fn frequency_label(unit: &str) -> String {
    match unit {
        "f/f_alpha" => "f / f_α [-]".into(),
        "" => "frequency".into(),
        u => format!("f [{u}]"),
    }
}

/// Residual amplitude spectra before (solid) and after (dashed) the best candidate, one
/// panel per (level, channel) in the order of the diagnosis.
///
/// `None` when no level reports a spectrum.
pub fn residual_spectra_figure(diag: &Diagnosis) -> Option<ResidualSpectraFigure> {
    let mut panels = vec![];
    for lv in &diag.levels {
        let after = best_candidate(lv).map_or("after (no candidate)".to_string(), |c| {
            format!("after + {}", c.effect.name())
        });
        for s in &lv.spectra {
            let mut series = vec![Series::new(
                "before (baseline)",
                SeriesKind::Measured,
                s.frequency.clone(),
                s.before.clone(),
            )];
            if !s.after.is_empty() {
                // Label without the effect name, so both levels share one legend entry.
                series.push(Series::new(
                    "after best candidate",
                    SeriesKind::Model,
                    s.frequency.clone(),
                    s.after.clone(),
                ));
            }
            panels.push(SpectraPanel {
                title: format!("{}: {} ({after})", s.level.name(), s.channel),
                x_label: frequency_label(&s.frequency_unit),
                y_label: "residual amplitude / rms [-]".into(),
                series,
            });
        }
    }
    (!panels.is_empty()).then(|| ResidualSpectraFigure {
        title: "Held-out residual spectra before and after the best candidate".into(),
        panels,
    })
}

/// Candidate ranking: per level, the held-out gap after each candidate (best first),
/// significant candidates highlighted, the level's baseline gap and noise level as lines.
/// Levels come from `diag.levels`; without levels, `diag.candidates` grouped by level
/// (no baseline line then unless the candidates carry one).
///
/// `None` when no candidate was scored at all.
pub fn ranking_figure(diag: &Diagnosis) -> Option<RankingFigure> {
    let bar = |c: &CandidateScore| RankingBar {
        label: format!("{} ({}p)", c.effect.name(), c.n_params),
        value: c.after,
        highlight: c.significant,
        note: c.failure.as_ref().map_or("no value".into(), |f| {
            format!("not fitted: {}", clip(f, 60))
        }),
    };
    let x_label = "held-out gap after the candidate [-]".to_string();
    let mut panels: Vec<RankingPanel> = diag
        .levels
        .iter()
        .filter(|lv| !lv.candidates.is_empty())
        .map(|lv| RankingPanel {
            title: format!("{} — {}", level_title(lv.level), lv.metric),
            x_label: x_label.clone(),
            bars: lv.candidates.iter().map(bar).collect(),
            baseline: Some(lv.before),
            noise_level: Some(lv.noise_level),
        })
        .collect();
    if panels.is_empty() {
        let mut by_level: Vec<(Level, Vec<&CandidateScore>)> = vec![];
        for c in &diag.candidates {
            match by_level.iter_mut().find(|(l, _)| *l == c.level) {
                Some((_, v)) => v.push(c),
                None => by_level.push((c.level, vec![c])),
            }
        }
        panels = by_level
            .into_iter()
            .map(|(level, cs)| RankingPanel {
                title: level_title(level).into(),
                x_label: x_label.clone(),
                baseline: cs.first().map(|c| c.before),
                noise_level: None,
                bars: cs.into_iter().map(bar).collect(),
            })
            .collect();
    }
    (!panels.is_empty()).then(|| RankingFigure {
        title: "Candidate ranking: held-out gap after each augmentation".into(),
        panels,
        highlight_legend: None,
    })
}

fn clip(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(n).collect::<String>())
    }
}

/// Predicted vs measured bifurcation diagram of the first level that carries one: pitch
/// amplitude vs U and dominant frequency vs U; measured markers, baseline prediction
/// dashed, prediction with the winning augmentation (the verdict's effect, else the
/// level's best candidate) solid.
///
/// `None` when no level has a bifurcation diagram with a point.
pub fn bifurcation_figure(diag: &Diagnosis) -> Option<ComparisonFigure> {
    let (lv, b) = diag
        .levels
        .iter()
        .find_map(|l| l.bifurcation.as_ref().map(|b| (l, b)))?;
    if b.measured.is_empty() && b.predicted_before.is_empty() && b.predicted_after.is_empty() {
        return None;
    }
    // The free-response sim "after" carries the winning augmentation: the verdict's effect
    // when it names one, else the level's best candidate.
    let winner = match diag.verdict.effect {
        diagnose::Verdict::Effect(e) => Some(e),
        _ => best_candidate(lv).map(|c| c.effect),
    };
    let after_label = match winner {
        Some(e) => format!("predicted + {}", e.name()),
        None => "predicted with augmentation".into(),
    };
    let series =
        |label: &str, kind: SeriesKind, pts: &[diagnose::report::BifurcationPoint], amp: bool| {
            Series::new(
                label,
                kind,
                pts.iter().map(|p| p.wind_speed).collect(),
                pts.iter()
                    .map(|p| if amp { p.amplitude } else { p.frequency })
                    .collect(),
            )
        };
    let panel = |amp: bool, y_label: &str| {
        let mut predicted = vec![];
        if !b.predicted_before.is_empty() {
            predicted.push(series(
                "predicted (baseline)",
                SeriesKind::Model,
                &b.predicted_before,
                amp,
            ));
        }
        if !b.predicted_after.is_empty() {
            predicted.push(series(
                &after_label,
                SeriesKind::Other,
                &b.predicted_after,
                amp,
            ));
        }
        ComparisonPanel {
            y_label: y_label.into(),
            include_zero: amp,
            measured: series("measured", SeriesKind::Measured, &b.measured, amp),
            predicted,
        }
    };
    Some(ComparisonFigure {
        title: "Bifurcation diagram: measured vs predicted free response".into(),
        x_label: "U [m/s]".into(),
        panels: vec![
            panel(true, "pitch amplitude [deg]"),
            panel(false, "pitch frequency [Hz]"),
        ],
    })
}

fn range(r: [f64; 2]) -> String {
    if r[0] == r[1] {
        fmt_num(r[0])
    } else {
        format!("{}–{}", fmt_num(r[0]), fmt_num(r[1]))
    }
}

/// Short name of a where-cell within its split: the channel for `channel`, the tone for
/// `harmonic`, configuration + U and amplitude ranges for `region`, the state-space
/// condition for `state` and `amplitude`, the level for `level`.
pub fn where_cell_label(w: &WhereShare) -> String {
    match w.split {
        Split::Level => w.level.name().into(),
        Split::Channel => w.channel.name().into(),
        Split::Harmonic if w.channel != Channel::All => format!("{} {}", w.channel, w.harmonic),
        Split::Harmonic => w.harmonic.label(),
        Split::Region => {
            let mut parts = vec![];
            if let Some(c) = &w.config {
                parts.push(c.clone());
            }
            if w.wind_speed.iter().all(|v| v.is_finite()) {
                parts.push(format!("U {}", range(w.wind_speed)));
            }
            if w.amplitude.iter().all(|v| v.is_finite()) {
                parts.push(format!("A {}", range(w.amplitude)));
            }
            parts.join(", ")
        }
        Split::State => w.state.clone().unwrap_or_else(|| "state".into()),
        // the band's condition (|α| against half the run's largest), else its range
        Split::Amplitude => w
            .state
            .clone()
            .unwrap_or_else(|| format!("A {}", range(w.amplitude))),
    }
}

/// (level, split) of a where-bar; `None` level for the `level` split.
type SplitKey = (Option<Level>, Split);

/// Where-shares: one stacked bar per (level, split) in order of first appearance, cells
/// sorted by share, at most [`MAX_SEGMENTS`] drawn (the rest merged into "other").
///
/// `None` when the diagnosis reports no where-share.
pub fn shares_figure(diag: &Diagnosis) -> Option<SharesFigure> {
    let source: Vec<&WhereShare> = if diag.where_.is_empty() {
        diag.levels.iter().flat_map(|l| &l.where_).collect()
    } else {
        diag.where_.iter().collect()
    };
    // The `level` split compares levels: one bar over all of them.
    let mut groups: Vec<(SplitKey, Vec<&WhereShare>)> = vec![];
    for w in source {
        let lv = (w.split != Split::Level).then_some(w.level);
        let k = (lv, w.split);
        match groups.iter_mut().find(|(g, _)| *g == k) {
            Some((_, v)) => v.push(w),
            None => groups.push((k, vec![w])),
        }
    }
    if groups.is_empty() {
        return None;
    }
    let bars = groups
        .into_iter()
        .map(|((level, split), mut cells)| {
            cells.sort_by(|a, b| b.share.total_cmp(&a.share));
            let mut segments: Vec<ShareSegment> = cells
                .iter()
                .take(MAX_SEGMENTS)
                .map(|w| ShareSegment {
                    label: where_cell_label(w),
                    share: w.share,
                })
                .collect();
            if cells.len() > MAX_SEGMENTS {
                let rest = &cells[MAX_SEGMENTS..];
                segments.push(ShareSegment {
                    label: format!("other ({})", rest.len()),
                    share: rest.iter().map(|w| w.share).filter(|s| s.is_finite()).sum(),
                });
            }
            ShareBar {
                label: match level {
                    Some(l) => format!("{}: {split}", l.name()),
                    None => split.to_string(),
                },
                segments,
            }
        })
        .collect();
    Some(SharesFigure {
        title: "Where the held-out gap lies (shares of each split sum to 100 %)".into(),
        bars,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use diagnose::report::Harmonic;

    fn w(split: Split) -> WhereShare {
        WhereShare {
            split,
            level: Level::Aerodynamic,
            channel: Channel::Moment,
            harmonic: Harmonic::Tone { m: 3, n: 0 },
            wind_speed: [4.0, 5.5],
            amplitude: [6.0, 6.0],
            config: Some("B".into()),
            state: Some("alpha_dot > 0".into()),
            share: 0.5,
        }
    }

    #[test]
    fn where_cells_are_named_by_their_split() {
        assert_eq!(where_cell_label(&w(Split::Level)), "aerodynamic");
        assert_eq!(where_cell_label(&w(Split::Channel)), "moment");
        assert_eq!(where_cell_label(&w(Split::Harmonic)), "moment 3*f_alpha");
        assert_eq!(where_cell_label(&w(Split::Region)), "B, U 4–5.5, A 6");
        assert_eq!(where_cell_label(&w(Split::State)), "alpha_dot > 0");
        let mut h = w(Split::Harmonic);
        h.channel = Channel::All;
        assert_eq!(where_cell_label(&h), "3*f_alpha");
    }
}
