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

#[allow(dead_code)]
pub(crate) const _PI: f64 = PI;
