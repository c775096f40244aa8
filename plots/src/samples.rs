//! Synthetic sample figures for tests and the preview render (no randomness: deterministic
//! closed forms).

use crate::*;
use std::f64::consts::{PI, TAU};

pub(crate) fn time_series() -> TimeSeriesFigure {
    let t: Vec<f64> = (0..2048).map(|i| i as f64 / 512.0).collect();
    let (fa, fh) = (2.0, 1.3);
    let alpha: Vec<f64> = t.iter().map(|t| 3.0 * (TAU * fa * t).sin()).collect();
    let h: Vec<f64> = t.iter().map(|t| 10.0 * (TAU * fh * t).sin()).collect();
    let cm: Vec<f64> = t
        .iter()
        .map(|t| 0.05 * (TAU * fa * t + 0.4).sin() + 0.01 * (TAU * (fa + fh) * t).sin() + 0.004 * (TAU * 37.0 * t).sin())
        .collect();
    let cm_model: Vec<f64> = t
        .iter()
        .map(|t| 0.05 * (TAU * fa * t + 0.4).sin() + 0.009 * (TAU * (fa + fh) * t).sin())
        .collect();
    let cl: Vec<f64> = t.iter().map(|t| 0.4 * (TAU * fh * t + 1.0).sin() + 0.1 * (TAU * fa * t).sin()).collect();
    let mut cl_model = cl.iter().map(|v| 0.97 * v).collect::<Vec<_>>();
    cl_model[700] = f64::NAN; // a gap
    TimeSeriesFigure {
        title: "Case A-3: forced motion and forces".into(),
        x_label: "t [s]".into(),
        panels: vec![
            TimePanel {
                y_label: "α [deg]".into(),
                series: vec![Series::new("measured", SeriesKind::Measured, t.clone(), alpha)],
            },
            TimePanel {
                y_label: "h [mm]".into(),
                series: vec![Series::new("measured", SeriesKind::Measured, t.clone(), h)],
            },
            TimePanel {
                y_label: "C_L [-]".into(),
                series: vec![
                    Series::new("measured", SeriesKind::Measured, t.clone(), cl),
                    Series::new("model (Eq. 19)", SeriesKind::Model, t.clone(), cl_model),
                ],
            },
            TimePanel {
                y_label: "C_M [-]".into(),
                series: vec![
                    Series::new("measured", SeriesKind::Measured, t.clone(), cm),
                    Series::new("model (Eq. 19)", SeriesKind::Model, t, cm_model),
                ],
            },
        ],
    }
}

/// Amplitude spectrum of a synthetic two-tone signal with harmonics (closed-form peaks on a
/// smooth floor), for test and model.
pub(crate) fn spectrum() -> SpectrumFigure {
    let f: Vec<f64> = (0..2000).map(|i| i as f64 * 0.01).collect();
    let peak = |f: f64, f0: f64, a: f64| a / (1.0 + ((f - f0) / 0.03).powi(2));
    let tones = [(2.0, 0.05), (1.3, 0.02), (4.0, 0.004), (3.3, 0.006), (0.7, 0.002), (6.0, 0.0008)];
    let test: Vec<f64> = f
        .iter()
        .map(|&x| 1e-5 * (1.0 + 0.5 * (x * 7.0).sin().abs()) + tones.iter().map(|&(f0, a)| peak(x, f0, a)).sum::<f64>())
        .collect();
    let model: Vec<f64> = f
        .iter()
        .map(|&x| 1e-6 + tones[..4].iter().map(|&(f0, a)| peak(x, f0, 0.9 * a)).sum::<f64>())
        .collect();
    let mk = |f: f64, l: &str| FreqMarker { freq: f, label: l.into() };
    SpectrumFigure {
        title: "Case A-3: spectrum of C_M".into(),
        x_label: "f [Hz]".into(),
        y_label: "|C_M| amplitude [-]".into(),
        series: vec![
            Series::new("measured", SeriesKind::Measured, f.clone(), test),
            Series::new("model (Eq. 19)", SeriesKind::Model, f, model),
        ],
        markers: vec![
            mk(2.0, "f_α"),
            mk(1.3, "f_h"),
            mk(4.0, "2f_α"),
            mk(3.3, "f_α+f_h"),
            mk(0.7, "f_α−f_h"),
            mk(6.0, "3f_α"),
            mk(2.6, "2f_h"),
        ],
        f_max: Some(10.0),
    }
}

pub(crate) fn term_names() -> Vec<String> {
    [
        "α", "Bα̇/U", "h/B", "ḣ/U", "α²", "α·Bα̇/U", "α·h/B", "α·ḣ/U", "(Bα̇/U)²", "h/B·ḣ/U",
        "α³", "α²·h/B", "α·(Bα̇/U)·h/B", "(Bα̇/U)³", "(h/B)³", "(ḣ/U)³", "α·h/B·ḣ/U", "α²·ḣ/U",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

pub(crate) fn delta_path() -> DeltaPathFigure {
    let names = term_names();
    let nt = names.len();
    let deltas: Vec<f64> = (0..30).map(|i| 1e-4 * 10f64.powf(i as f64 * 4.0 / 29.0)).collect();
    // Term j survives up to a threshold that decreases with j (closed form, no randomness).
    let survive: Vec<f64> = (0..nt).map(|j| 0.5 * 10f64.powf(-(j as f64) * 3.5 / nt as f64)).collect();
    let support: Vec<Vec<bool>> = deltas
        .iter()
        .map(|&d| survive.iter().enumerate().map(|(j, &s)| j < 4 || d < s).collect())
        .collect();
    let n_terms: Vec<usize> = support.iter().map(|r| r.iter().filter(|b| **b).count()).collect();
    let loss: Vec<f64> = n_terms.iter().map(|&k| 1e-3 * 10f64.powf((nt - k) as f64 * 0.25)).collect();
    DeltaPathFigure {
        title: "Group A: δ path (sequential thresholding)".into(),
        delta_label: "threshold δ (relative contribution) [-]".into(),
        deltas,
        n_terms,
        loss,
        loss_label: "key-freq. loss [-]".into(),
        loss_limit: Some(0.05),
        selected: Some(11),
        term_names: names,
        support,
    }
}

pub(crate) fn heatmap() -> HeatmapGridFigure {
    let amps: Vec<f64> = (1..=8).map(|i| i as f64).collect();
    let speeds: Vec<f64> = (0..8).map(|i| 4.0 + 2.0 * i as f64).collect();
    let terms = ["H1*", "H2*", "H3*", "H4*", "A1*", "A2*", "A3*", "A4*", "N1*", "N2*"];
    let panels = terms
        .iter()
        .enumerate()
        .map(|(k, &t)| HeatmapPanel {
            term: t.into(),
            values: speeds
                .iter()
                .map(|&u| {
                    amps.iter()
                        .map(|&a| {
                            let v = ((k as f64 + 1.0) * 0.3 * a).sin() * (u / 10.0) - 0.2 * k as f64;
                            // Nonlinear terms inactive at small amplitude.
                            if k >= 8 && a < 4.0 { None } else if k == 3 && u > 14.0 { Some(0.0) } else { Some(v) }
                        })
                        .collect()
                })
                .collect(),
        })
        .collect();
    HeatmapGridFigure {
        title: "Configuration A: Eq. 19 coefficients (moment)".into(),
        x_label: "amplitude α₀ [deg]".into(),
        y_label: "U [m/s]".into(),
        x_values: amps,
        y_values: speeds,
        panels,
    }
}

#[allow(dead_code)]
pub(crate) const _PI: f64 = PI;
