//! Identification results → figures.

use std::collections::{BTreeMap, BTreeSet};

use aeroelastic::theodorsen::Derivative;
use identify::pipeline::{CaseResult, GroupForce, Identification};
use identify::record::CaseMeta;
use identify::series::CaseSeries;

use super::{eq19_label, term_label};
use crate::{
    DeltaPathFigure, DerivativeFigure, DerivativePanel, DerivativePoints, FreqMarker,
    HeatmapGridFigure, HeatmapPanel, HistogramFigure, HistogramPanel, LibraryCell, LibraryFigure,
    Series, SeriesKind, SpectrumFigure, TimePanel, TimeSeriesFigure,
};

/// Force channel of a figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Force {
    /// Lift, C_L = L/(½ρU²B), positive down; derivatives H1*..H4*.
    Lift,
    /// Moment, C_M = M/(½ρU²B²), positive nose-up; derivatives A1*..A4*.
    Moment,
}

impl Force {
    /// `"lift"` / `"moment"`.
    pub fn name(self) -> &'static str {
        match self {
            Force::Lift => "lift",
            Force::Moment => "moment",
        }
    }

    /// `"C_L"` / `"C_M"`.
    pub fn symbol(self) -> &'static str {
        match self {
            Force::Lift => "C_L",
            Force::Moment => "C_M",
        }
    }

    fn group(self, g: &identify::pipeline::GroupResult) -> &GroupForce {
        match self {
            Force::Lift => &g.lift,
            Force::Moment => &g.moment,
        }
    }

    /// Eq. 19 names and values of a case, in the order H1..H4 (A1..A4), N1..N3.
    fn eq19(self, c: &CaseResult) -> [(&'static str, Option<f64>); 7] {
        use identify::eq19::{Eq19Values, LIFT_NAMES, MOMENT_NAMES};
        let (names, values) = match self {
            Force::Lift => (LIFT_NAMES, Eq19Values::from(c.lift.eq19)),
            Force::Moment => (MOMENT_NAMES, Eq19Values::from(c.moment.eq19)),
        };
        std::array::from_fn(|i| (names[i], values.0[i]))
    }
}

/// Case description used in titles: `"D-U4-A6 (U = 4 m/s, α₀ = 6°)"`.
fn case_title(s: &CaseSeries) -> String {
    match s.amplitude_deg {
        Some(a) => format!(
            "{} (U = {} m/s, α₀ = {}°)",
            s.id,
            crate::style::fmt_num(s.wind_speed),
            crate::style::fmt_num(a)
        ),
        None => format!("{} (U = {} m/s)", s.id, crate::style::fmt_num(s.wind_speed)),
    }
}

/// Time series of one case: α \[deg\], h \[mm\], then measured C_L and C_M with the identified
/// model overlaid (dashed), and the residuals measured − model of both in a last panel.
pub fn time_series_figure(s: &CaseSeries) -> TimeSeriesFigure {
    let t = &s.t;
    let model = "identified model";
    TimeSeriesFigure {
        title: format!("Case {}: motion and forces", case_title(s)),
        x_label: "t [s]".into(),
        panels: vec![
            TimePanel {
                y_label: "α [deg]".into(),
                series: vec![Series::new(
                    "measured",
                    SeriesKind::Measured,
                    t.clone(),
                    s.alpha_deg.clone(),
                )],
            },
            TimePanel {
                y_label: "h [mm]".into(),
                series: vec![Series::new(
                    "measured",
                    SeriesKind::Measured,
                    t.clone(),
                    s.h_mm.clone(),
                )],
            },
            TimePanel {
                y_label: "C_L [-]".into(),
                series: vec![
                    Series::new(
                        "measured",
                        SeriesKind::Measured,
                        t.clone(),
                        s.c_lift.clone(),
                    ),
                    Series::new(model, SeriesKind::Model, t.clone(), s.c_lift_model.clone()),
                ],
            },
            TimePanel {
                y_label: "C_M [-]".into(),
                series: vec![
                    Series::new(
                        "measured",
                        SeriesKind::Measured,
                        t.clone(),
                        s.c_moment.clone(),
                    ),
                    Series::new(
                        model,
                        SeriesKind::Model,
                        t.clone(),
                        s.c_moment_model.clone(),
                    ),
                ],
            },
            TimePanel {
                y_label: "residual [-]".into(),
                series: vec![
                    Series::new(
                        "C_L residual (measured − model)",
                        SeriesKind::Other,
                        t.clone(),
                        residual(&s.c_lift, &s.c_lift_model),
                    ),
                    Series::new(
                        "C_M residual (measured − model)",
                        SeriesKind::Other,
                        t.clone(),
                        residual(&s.c_moment, &s.c_moment_model),
                    ),
                ],
            },
        ],
    }
}

/// `measured − model`, sample by sample (NaN where either is missing).
fn residual(measured: &[f64], model: &[f64]) -> Vec<f64> {
    (0..measured.len())
        .map(|i| measured[i] - model.get(i).copied().unwrap_or(f64::NAN))
        .collect()
}

/// Name of a combination tone m·f_α + n·f_h matching `f` within 1 % (|m| + |n| ≤ 5), else
/// the frequency in Hz.
pub fn tone_label(f: f64, f_alpha: Option<f64>, f_h: Option<f64>) -> String {
    let mut best: Option<(i32, i32, f64)> = None;
    let fa = f_alpha.unwrap_or(0.0);
    let fh = f_h.unwrap_or(0.0);
    for order in 1..=5_i32 {
        for m in -order..=order {
            let n_abs = order - m.abs();
            for n in [n_abs, -n_abs] {
                if (m != 0 && f_alpha.is_none()) || (n != 0 && f_h.is_none()) {
                    continue;
                }
                let g = m as f64 * fa + n as f64 * fh;
                let err = (g - f).abs();
                if g > 0.0 && err <= 0.01 * f.max(1e-9) && best.is_none_or(|b| err < b.2) {
                    best = Some((m, n, err));
                }
            }
        }
        if best.is_some() {
            break;
        }
    }
    let part = |k: i32, s: &str| match k {
        1 => s.to_string(),
        -1 => format!("−{s}"),
        k if k < 0 => format!("−{}{s}", -k),
        k => format!("{k}{s}"),
    };
    match best {
        Some((m, 0, _)) => part(m, "f_α"),
        Some((0, n, _)) => part(n, "f_h"),
        Some((m, n, _)) if m > 0 => {
            let h = part(n.abs(), "f_h");
            if n > 0 {
                format!("{}+{h}", part(m, "f_α"))
            } else {
                format!("{}−{h}", part(m, "f_α"))
            }
        }
        Some((m, n, _)) => {
            let a = part(m.abs(), "f_α");
            format!("{}−{a}", part(n, "f_h"))
        }
        None => format!("{} Hz", crate::style::fmt_num(f)),
    }
}

/// Amplitude spectrum of measured and model C_L or C_M of one case, key frequencies of the
/// identification marked and named as combination tones of the forcing frequencies. The
/// model spectrum is clamped from below at a tenth of the lowest measured amplitude.
pub fn spectrum_figure(s: &CaseSeries, force: Force) -> SpectrumFigure {
    let (meas, model, keys) = match force {
        Force::Lift => (
            &s.lift_spectrum,
            &s.lift_model_spectrum,
            &s.lift_key_frequencies,
        ),
        Force::Moment => (
            &s.moment_spectrum,
            &s.moment_model_spectrum,
            &s.moment_key_frequencies,
        ),
    };
    let f_max = s.freq.last().copied();
    // A noise-free model has a floor at rounding level (~1e-16) that would stretch the log
    // axis over many empty decades: clamp it to a tenth of the lowest measured amplitude.
    let floor = meas
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(f64::INFINITY, f64::min)
        * 0.1;
    let model: Vec<f64> = if floor.is_finite() {
        model.iter().map(|v| v.max(floor)).collect()
    } else {
        model.clone()
    };
    SpectrumFigure {
        title: format!("Case {}: spectrum of {}", case_title(s), force.symbol()),
        x_label: "f [Hz]".into(),
        y_label: format!("|{}| amplitude [-]", force.symbol()),
        series: vec![
            Series::new(
                "measured",
                SeriesKind::Measured,
                s.freq.clone(),
                meas.clone(),
            ),
            Series::new("identified model", SeriesKind::Model, s.freq.clone(), model),
        ],
        markers: keys
            .iter()
            .map(|&f| FreqMarker {
                freq: f,
                label: tone_label(f, s.forcing_hz[0], s.forcing_hz[1]),
            })
            .collect(),
        f_max,
    }
}

/// δ path of one group and force (Alg. 3): each distinct support is drawn at both ends of
/// its δ interval (a staircase), the selected support marked, the group basis as the rows
/// of the occupancy strip. `None` when the group does not exist or its path is empty.
pub fn delta_path_figure(
    id: &Identification,
    group: &str,
    force: Force,
) -> Option<DeltaPathFigure> {
    let g = id.groups.iter().find(|g| g.name == group)?;
    let gf = force.group(g);
    if gf.path.is_empty() {
        return None;
    }
    let basis = &g.basis;
    let mut fig = DeltaPathFigure {
        title: format!(
            "Group {group}: δ path of {} ({})",
            force.symbol(),
            force.name()
        ),
        delta_label: match id.settings.effective_measure() {
            identify::regress::Measure::Contribution => {
                "threshold δ (relative contribution) [-]".into()
            }
            identify::regress::Measure::Coefficient => "threshold δ (|coefficient|) [-]".into(),
        },
        loss_label: "loss, Eq. 14 [-]".into(),
        loss_limit: Some(gf.loss_limit),
        term_names: basis.iter().map(|t| term_label(t)).collect(),
        ..DeltaPathFigure::default()
    };
    for e in &gf.path {
        let occupancy: Vec<bool> = basis.iter().map(|t| e.support.contains(t)).collect();
        let is_selected = e.support == gf.support;
        let ends: &[f64] = if e.delta[1] > e.delta[0] {
            &e.delta
        } else {
            &e.delta[..1]
        };
        for (j, &d) in ends.iter().enumerate() {
            if is_selected && j == 0 {
                fig.selected = Some(fig.deltas.len());
            }
            fig.deltas.push(d);
            fig.n_terms.push(e.n_terms);
            fig.loss.push(e.loss);
            fig.support.push(occupancy.clone());
        }
    }
    Some(fig)
}

/// Heat maps of the Eq. 19 coefficients over pitch amplitude (x, deg) × U (y, m/s), one
/// figure per configuration (cases grouped by `config` of `cases`, else by their group),
/// one panel per coefficient; a coefficient that is missing or zero (term removed by the
/// sparse regression) is drawn grey. Configurations in name order.
pub fn heatmap_figures(
    id: &Identification,
    cases: &[CaseMeta],
    force: Force,
) -> Vec<(String, HeatmapGridFigure)> {
    let meta: BTreeMap<&str, &CaseMeta> = cases.iter().map(|m| (m.id.as_str(), m)).collect();
    let mut by_config: BTreeMap<String, Vec<(&CaseResult, f64)>> = BTreeMap::new();
    for c in &id.cases {
        let m = meta.get(c.id.as_str());
        let config = m
            .and_then(|m| m.config.clone())
            .unwrap_or_else(|| c.group.clone());
        let amp = m.and_then(|m| m.amplitude).map(f64::to_degrees);
        if let Some(a) = amp {
            by_config.entry(config).or_default().push((c, a));
        }
    }
    let key = |v: f64| (v * 1e6).round() as i64;
    by_config
        .into_iter()
        .map(|(config, rows)| {
            let xs: BTreeSet<i64> = rows.iter().map(|(_, a)| key(*a)).collect();
            let ys: BTreeSet<i64> = rows.iter().map(|(c, _)| key(c.wind_speed)).collect();
            let xs: Vec<i64> = xs.into_iter().collect();
            let ys: Vec<i64> = ys.into_iter().collect();
            let names = rows
                .first()
                .map(|(c, _)| force.eq19(c).map(|(n, _)| n))
                .unwrap_or_default();
            let panels = names
                .iter()
                .enumerate()
                .map(|(k, n)| {
                    let mut values = vec![vec![None; xs.len()]; ys.len()];
                    for (c, a) in &rows {
                        let (Ok(ix), Ok(iy)) = (
                            xs.binary_search(&key(*a)),
                            ys.binary_search(&key(c.wind_speed)),
                        ) else {
                            continue;
                        };
                        values[iy][ix] = force.eq19(c)[k].1.filter(|v| *v != 0.0);
                    }
                    HeatmapPanel {
                        term: eq19_label(n),
                        values,
                    }
                })
                .collect();
            let fig = HeatmapGridFigure {
                title: format!(
                    "Configuration {config}: Eq. 19 coefficients of {} (grey: inactive)",
                    force.symbol()
                ),
                x_label: "amplitude α₀ [deg]".into(),
                y_label: "U [m/s]".into(),
                x_values: xs.iter().map(|&v| v as f64 * 1e-6).collect(),
                y_values: ys.iter().map(|&v| v as f64 * 1e-6).collect(),
                panels,
                value_label: "coefficient value [-]".into(),
            };
            (config, fig)
        })
        .collect()
}

/// Histograms of the misfit of every case, moment and lift: 1 − R² and |1 − MFWA| (Eq. 18).
/// Misfits rather than R² and MFWA themselves: good fits crowd R² and MFWA against 1 where
/// tick labels cannot tell the bins apart, while their misfits spread over decades.
pub fn quality_histogram(id: &Identification) -> HistogramFigure {
    let col = |f: &dyn Fn(&CaseResult) -> Option<f64>| -> Vec<f64> {
        id.cases.iter().map(|c| f(c).unwrap_or(f64::NAN)).collect()
    };
    let bins = (id.cases.len() / 3).clamp(5, 30);
    let panel = |x_label: &str, values: Vec<f64>| HistogramPanel {
        x_label: x_label.into(),
        values,
        bins,
        range: None,
    };
    HistogramFigure {
        title: format!("Identification misfit over {} cases", id.cases.len()),
        panels: vec![
            panel("1 − R² of C_M [-]", col(&|c| c.moment.r2.map(|r| 1.0 - r))),
            panel(
                "|1 − MFWA| of C_M [-]",
                col(&|c| c.moment.mfwa.map(|m| (1.0 - m).abs())),
            ),
            panel("1 − R² of C_L [-]", col(&|c| c.lift.r2.map(|r| 1.0 - r))),
            panel(
                "|1 − MFWA| of C_L [-]",
                col(&|c| c.lift.mfwa.map(|m| (1.0 - m).abs())),
            ),
        ],
    }
}

/// The ensemble interval [lower, upper] of derivative `name` of case `i` ([NaN, NaN] when
/// the identification has no ensemble or the derivative no interval).
fn ensemble_bar(id: &Identification, i: usize, force: Force, name: &str) -> [f64; 2] {
    let e = id.ensemble.as_ref().and_then(|e| e.cases.get(i));
    let f = e.map(|e| match force {
        Force::Lift => &e.lift,
        Force::Moment => &e.moment,
    });
    match f.and_then(|f| f.eq19.get(name)) {
        Some(iv) => [iv.lower, iv.upper],
        None => [f64::NAN, f64::NAN],
    }
}

/// Identified flutter derivatives H1*..H4*, A1*..A4* against K (h-terms at K_h, α-terms at
/// K_α), one point set per group (with the ensemble's percentile intervals as error bars
/// when the identification has an ensemble), with the thin-plate (Theodorsen) derivatives
/// about the elastic axis at `elastic_axis` semi-chords aft of mid-chord
/// ([`aeroelastic::aero::thin_plate_derivatives`]; 0 = the flat-plate closed forms)
/// over the identified K range.
pub fn derivative_figure(id: &Identification, elastic_axis: f64) -> DerivativeFigure {
    let mut groups: Vec<&str> = id.cases.iter().map(|c| c.group.as_str()).collect();
    groups.sort_unstable();
    groups.dedup();
    let groups: Vec<(String, String)> = groups
        .iter()
        .map(|g| (g.to_string(), format!("group {g}")))
        .collect();
    derivative_figure_of(id, elastic_axis, &groups)
}

/// The mean-angle comparison (paper Fig. 28): the derivatives of every group forced about a
/// non-zero mean pitch next to those of the group with the same motion at zero mean (same
/// pitch and heave frequencies and amplitude ratio), against Theodorsen about
/// `elastic_axis`. `None` when no group has a mean angle or none has a zero-mean twin.
pub fn mean_angle_figure(
    id: &Identification,
    metas: &[CaseMeta],
    elastic_axis: f64,
) -> Option<DerivativeFigure> {
    let meta_of = |group: &str| -> Vec<&CaseMeta> {
        id.cases
            .iter()
            .filter(|c| c.group == group)
            .filter_map(|c| metas.iter().find(|m| m.id == c.id))
            .collect()
    };
    let mean = |m: &CaseMeta| m.mean_pitch.unwrap_or(0.0);
    let motion = |m: &CaseMeta| (m.freq_pitch, m.freq_heave, m.amplitude_ratio);
    let mut pairs: Vec<(String, String)> = vec![];
    for g in &id.groups {
        let ms = meta_of(&g.name);
        let Some(first) = ms.first() else { continue };
        if mean(first) == 0.0 {
            continue;
        }
        let twin = id.groups.iter().find(|b| {
            let bm = meta_of(&b.name);
            bm.first()
                .is_some_and(|f| mean(f) == 0.0 && motion(f) == motion(first))
        });
        if let Some(b) = twin {
            if !pairs.iter().any(|(n, _)| *n == b.name) {
                pairs.push((b.name.clone(), format!("{} (zero mean)", b.name)));
            }
            pairs.push((
                g.name.clone(),
                format!(
                    "{} (mean {}°)",
                    g.name,
                    crate::style::fmt_num(mean(first).to_degrees())
                ),
            ));
        }
    }
    if pairs.len() < 2 {
        return None;
    }
    let mut f = derivative_figure_of(id, elastic_axis, &pairs);
    f.title = "Flutter derivatives at a mean angle of attack vs zero mean".into();
    Some(f)
}

/// [`derivative_figure`] for the groups `groups` (name, legend label), in that order.
pub fn derivative_figure_of(
    id: &Identification,
    elastic_axis: f64,
    groups: &[(String, String)],
) -> DerivativeFigure {
    // (name, force, index in eq19 array, uses K_alpha)
    let defs: [(Derivative, Force, usize, bool); 8] = [
        (Derivative::H1, Force::Lift, 0, false),
        (Derivative::H2, Force::Lift, 1, true),
        (Derivative::H3, Force::Lift, 2, true),
        (Derivative::H4, Force::Lift, 3, false),
        (Derivative::A1, Force::Moment, 0, false),
        (Derivative::A2, Force::Moment, 1, true),
        (Derivative::A3, Force::Moment, 2, true),
        (Derivative::A4, Force::Moment, 3, false),
    ];
    let ks = id
        .cases
        .iter()
        .flat_map(|c| [c.k_alpha, c.k_h])
        .flatten()
        .filter(|k| k.is_finite() && *k > 0.0);
    let (k_lo, k_hi) = ks.fold((f64::INFINITY, 0.0_f64), |(a, b), k| (a.min(k), b.max(k)));
    let (k_lo, k_hi) = if k_lo.is_finite() && k_hi > k_lo {
        (k_lo * 0.9, k_hi * 1.1)
    } else {
        (0.1, 2.0)
    };
    let reference_k: Vec<f64> = (0..=120)
        .map(|i| k_lo * (k_hi / k_lo).powf(i as f64 / 120.0))
        .collect();
    let panels = defs
        .iter()
        .map(|&(derivative, force, idx, uses_alpha)| {
            let name = derivative.name();
            let points = groups
                .iter()
                .map(|(g, label)| {
                    let mut k = vec![];
                    let mut value = vec![];
                    let mut interval = vec![];
                    for (i, c) in id.cases.iter().enumerate().filter(|(_, c)| c.group == *g) {
                        let kk = if uses_alpha { c.k_alpha } else { c.k_h };
                        if let (Some(kk), Some(v)) = (kk, force.eq19(c)[idx].1) {
                            k.push(kk);
                            value.push(v);
                            interval.push(ensemble_bar(id, i, force, name));
                        }
                    }
                    if interval.iter().all(|b| b[0].is_nan()) {
                        interval.clear();
                    }
                    DerivativePoints {
                        label: label.clone(),
                        k,
                        value,
                        spread: vec![],
                        interval,
                    }
                })
                .filter(|p| !p.k.is_empty())
                .collect();
            let reference_value = reference_k
                .iter()
                .map(|&k| {
                    let d = aeroelastic::aero::thin_plate_derivatives(k, elastic_axis);
                    d.get(derivative)
                })
                .collect();
            DerivativePanel {
                name: eq19_label(name),
                points,
                reference_k: reference_k.clone(),
                reference_value,
            }
        })
        .collect();
    DerivativeFigure {
        title: "Flutter derivatives vs reduced frequency".into(),
        k_label: "K = Bω/U [-]".into(),
        reference_label: if elastic_axis == 0.0 {
            "flat plate (Theodorsen)".into()
        } else {
            format!("thin plate (Theodorsen), axis a = {elastic_axis}")
        },
        panels,
    }
}

/// The candidate library against every group's selection (paper Fig. 6): one row per
/// library term, a lift and a moment column per group.
pub fn library_figure(id: &Identification) -> LibraryFigure {
    let mut columns = vec![];
    let mut cells = vec![];
    for g in &id.groups {
        for (f, gf) in [(Force::Lift, &g.lift), (Force::Moment, &g.moment)] {
            columns.push(format!("{} {}", g.name, f.symbol()));
            cells.push(
                id.library
                    .terms
                    .iter()
                    .map(|t| {
                        if gf.support.contains(t) {
                            LibraryCell::Selected
                        } else if g.basis.contains(t) {
                            LibraryCell::Basis
                        } else {
                            LibraryCell::NotIdentifiable
                        }
                    })
                    .collect(),
            );
        }
    }
    LibraryFigure {
        title: format!(
            "Candidate library: {} terms (rank {}) and the selected supports",
            id.library.terms.len(),
            id.library.rank
        ),
        terms: id.library.terms.iter().map(|t| term_label(t)).collect(),
        columns,
        cells,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_labels_name_combinations() {
        assert_eq!(tone_label(2.0, Some(2.0), Some(1.3)), "f_α");
        assert_eq!(tone_label(3.3, Some(2.0), Some(1.3)), "f_α+f_h");
        assert_eq!(tone_label(0.7, Some(2.0), Some(1.3)), "f_α−f_h");
        assert_eq!(tone_label(2.6, Some(2.0), Some(1.3)), "2f_h");
        assert_eq!(tone_label(6.0, Some(2.0), None), "3f_α");
        assert_eq!(tone_label(9.87, None, None), "9.87 Hz");
    }
}
