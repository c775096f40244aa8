//! Synthetic sample figures for tests and the preview render (no randomness: deterministic
//! closed forms).

use crate::*;
use std::f64::consts::{PI, TAU};

pub fn time_series() -> TimeSeriesFigure {
    let t: Vec<f64> = (0..2048).map(|i| i as f64 / 512.0).collect();
    let (fa, fh) = (2.0, 1.3);
    let alpha: Vec<f64> = t.iter().map(|t| 3.0 * (TAU * fa * t).sin()).collect();
    let h: Vec<f64> = t.iter().map(|t| 10.0 * (TAU * fh * t).sin()).collect();
    let cm: Vec<f64> = t
        .iter()
        .map(|t| {
            0.05 * (TAU * fa * t + 0.4).sin()
                + 0.01 * (TAU * (fa + fh) * t).sin()
                + 0.004 * (TAU * 37.0 * t).sin()
        })
        .collect();
    let cm_model: Vec<f64> = t
        .iter()
        .map(|t| 0.05 * (TAU * fa * t + 0.4).sin() + 0.009 * (TAU * (fa + fh) * t).sin())
        .collect();
    let cl: Vec<f64> = t
        .iter()
        .map(|t| 0.4 * (TAU * fh * t + 1.0).sin() + 0.1 * (TAU * fa * t).sin())
        .collect();
    let mut cl_model = cl.iter().map(|v| 0.97 * v).collect::<Vec<_>>();
    cl_model[700] = f64::NAN; // a gap
    TimeSeriesFigure {
        title: "Case A-3: forced motion and forces".into(),
        x_label: "t [s]".into(),
        panels: vec![
            TimePanel {
                y_label: "α [deg]".into(),
                series: vec![Series::new(
                    "measured",
                    SeriesKind::Measured,
                    t.clone(),
                    alpha,
                )],
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
pub fn spectrum() -> SpectrumFigure {
    let f: Vec<f64> = (0..2000).map(|i| i as f64 * 0.01).collect();
    let peak = |f: f64, f0: f64, a: f64| a / (1.0 + ((f - f0) / 0.03).powi(2));
    let tones = [
        (2.0, 0.05),
        (1.3, 0.02),
        (4.0, 0.004),
        (3.3, 0.006),
        (0.7, 0.002),
        (6.0, 0.0008),
    ];
    let test: Vec<f64> = f
        .iter()
        .map(|&x| {
            1e-5 * (1.0 + 0.5 * (x * 7.0).sin().abs())
                + tones.iter().map(|&(f0, a)| peak(x, f0, a)).sum::<f64>()
        })
        .collect();
    let model: Vec<f64> = f
        .iter()
        .map(|&x| {
            1e-6 + tones[..4]
                .iter()
                .map(|&(f0, a)| peak(x, f0, 0.9 * a))
                .sum::<f64>()
        })
        .collect();
    let mk = |f: f64, l: &str| FreqMarker {
        freq: f,
        label: l.into(),
    };
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

pub fn term_names() -> Vec<String> {
    [
        "α",
        "Bα̇/U",
        "h/B",
        "ḣ/U",
        "α²",
        "α·Bα̇/U",
        "α·h/B",
        "α·ḣ/U",
        "(Bα̇/U)²",
        "h/B·ḣ/U",
        "α³",
        "α²·h/B",
        "α·(Bα̇/U)·h/B",
        "(Bα̇/U)³",
        "(h/B)³",
        "(ḣ/U)³",
        "α·h/B·ḣ/U",
        "α²·ḣ/U",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

pub fn delta_path() -> DeltaPathFigure {
    let names = term_names();
    let nt = names.len();
    let deltas: Vec<f64> = (0..30)
        .map(|i| 1e-4 * 10f64.powf(i as f64 * 4.0 / 29.0))
        .collect();
    // Term j survives up to a threshold that decreases with j (closed form, no randomness).
    let survive: Vec<f64> = (0..nt)
        .map(|j| 0.5 * 10f64.powf(-(j as f64) * 3.5 / nt as f64))
        .collect();
    let support: Vec<Vec<bool>> = deltas
        .iter()
        .map(|&d| {
            survive
                .iter()
                .enumerate()
                .map(|(j, &s)| j < 4 || d < s)
                .collect()
        })
        .collect();
    let n_terms: Vec<usize> = support
        .iter()
        .map(|r| r.iter().filter(|b| **b).count())
        .collect();
    let loss: Vec<f64> = n_terms
        .iter()
        .map(|&k| 1e-3 * 10f64.powf((nt - k) as f64 * 0.25))
        .collect();
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

pub fn heatmap() -> HeatmapGridFigure {
    let amps: Vec<f64> = (1..=8).map(|i| i as f64).collect();
    let speeds: Vec<f64> = (0..8).map(|i| 4.0 + 2.0 * i as f64).collect();
    let terms = [
        "H1*", "H2*", "H3*", "H4*", "A1*", "A2*", "A3*", "A4*", "N1*", "N2*",
    ];
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
                            let v =
                                ((k as f64 + 1.0) * 0.3 * a).sin() * (u / 10.0) - 0.2 * k as f64;
                            // Nonlinear terms inactive at small amplitude.
                            if k >= 8 && a < 4.0 {
                                None
                            } else if k == 3 && u > 14.0 {
                                Some(0.0)
                            } else {
                                Some(v)
                            }
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
        value_label: "coefficient value [-]".into(),
    }
}

pub fn histogram() -> HistogramFigure {
    // Deterministic spread of values (golden-ratio sequence), one outlier, one NaN.
    let u: Vec<f64> = (0..64)
        .map(|i| (i as f64 * 0.618_033_988_75).fract())
        .collect();
    let mut r2: Vec<f64> = u.iter().map(|x| 1.0 - 0.08 * x * x).collect();
    r2.push(0.55);
    r2.push(f64::NAN);
    let mfwa: Vec<f64> = u.iter().map(|x| 0.85 + 0.15 * x.sqrt()).collect();
    HistogramFigure {
        title: "Identification quality over 64 cases".into(),
        panels: vec![
            HistogramPanel {
                x_label: "R² [-]".into(),
                values: r2,
                bins: 20,
                range: Some((0.9, 1.0)),
            },
            HistogramPanel {
                x_label: "MFWA [-]".into(),
                values: mfwa,
                bins: 15,
                range: None,
            },
        ],
    }
}

pub fn vg() -> VgFigure {
    let u: Vec<f64> = (0..60).map(|i| 2.0 + 0.5 * i as f64).collect();
    let uf = 23.4;
    let heave_g: Vec<f64> = u.iter().map(|u| 0.01 + 0.004 * u).collect();
    let pitch_g: Vec<f64> = u
        .iter()
        .map(|u| 0.02 + 0.0006 * u - 0.0001 * (u - 2.0) * (u - 2.0) / 2.2 + 0.0)
        .collect();
    // Shift pitch damping so that it crosses zero at U_F exactly.
    let g_at = 0.02 + 0.0006 * uf - 0.0001 * (uf - 2.0) * (uf - 2.0) / 2.2;
    let pitch_g: Vec<f64> = pitch_g.iter().map(|g| g - g_at).collect();
    let heave_f: Vec<f64> = u.iter().map(|u| 1.3 + 0.02 * u).collect();
    let pitch_f: Vec<f64> = u.iter().map(|u| 3.0 - 0.0012 * u * u).collect();
    VgFigure {
        title: "Flutter analysis: V–g and V–f".into(),
        u_label: "U [m/s]".into(),
        g_label: "damping ratio g [-]".into(),
        f_label: "f [Hz]".into(),
        u_unit: "m/s".into(),
        f_unit: "Hz".into(),
        modes: vec![
            ModeBranch {
                name: "heave mode".into(),
                u: u.clone(),
                damping: heave_g,
                freq: heave_f,
            },
            ModeBranch {
                name: "pitch mode".into(),
                u,
                damping: pitch_g,
                freq: pitch_f,
            },
        ],
        flutter: Some(FlutterPoint {
            u: uf,
            freq: 3.0 - 0.0012 * uf * uf,
        }),
        flutter_interval: Some(SpeedInterval {
            lower: 22.6,
            upper: 24.5,
            level: 0.9,
            found: 20,
            members: 20,
        }),
    }
}

pub fn bifurcation() -> BifurcationFigure {
    let mut points = vec![];
    let uf = 20.0;
    let us = 17.0; // subcritical: LCO persists down to 17 m/s on the downward sweep
    let lco = |u: f64| 4.0 + 6.0 * ((u - us) / 10.0).max(0.0).sqrt();
    for i in 0..=20 {
        let u = 10.0 + 0.75 * i as f64;
        let (class, amp) = if u > 24.5 {
            (ResponseClass::Divergent, f64::INFINITY)
        } else if u >= uf {
            (ResponseClass::Lco, lco(u))
        } else {
            (ResponseClass::Decay, 0.0)
        };
        points.push(BifurcationPoint {
            u,
            amplitude: amp,
            sweep: Sweep::Up,
            class,
            stop: "",
        });
    }
    for i in 0..=18 {
        let u = 24.0 - 0.75 * i as f64;
        let (class, amp) = if u >= us {
            (ResponseClass::Lco, lco(u))
        } else {
            (ResponseClass::Decay, f64::NAN)
        };
        points.push(BifurcationPoint {
            u,
            amplitude: amp,
            sweep: Sweep::Down,
            class,
            stop: "",
        });
    }
    BifurcationFigure {
        title: "LCO sweeps: hysteresis".into(),
        u_label: "U [m/s]".into(),
        amplitude_label: "LCO amplitude α [deg]".into(),
        points,
        u_unit: "m/s".into(),
        flutter_speed: Some(uf),
        intervals: (0..6)
            .map(|i| {
                let u = 20.0 + 0.75 * i as f64;
                let m = lco(u);
                AmplitudeInterval {
                    u,
                    median: m,
                    lower: 0.93 * m,
                    upper: 1.05 * m,
                }
            })
            .collect(),
        interval_label: "90 % interval over 20 bootstrap members".into(),
        flutter_interval: Some(SpeedInterval {
            lower: 19.4,
            upper: 20.7,
            level: 0.9,
            found: 20,
            members: 20,
        }),
    }
}

pub fn phase() -> PhasePortraitFigure {
    let t: Vec<f64> = (0..1600).map(|i| i as f64 / 200.0).collect();
    // Growing spiral onto a limit cycle of amplitude 5 deg at 3 Hz, and a model at 4.6 deg.
    let traj = |a_lc: f64| {
        let a: Vec<f64> = t
            .iter()
            .map(|&t| a_lc * (1.0 - (-t / 1.2).exp() * 0.9))
            .collect();
        let x: Vec<f64> = t
            .iter()
            .zip(&a)
            .map(|(&t, &a)| a * (TAU * 3.0 * t).cos())
            .collect();
        let v: Vec<f64> = t
            .iter()
            .zip(&a)
            .map(|(&t, &a)| -a * TAU * 3.0 * (TAU * 3.0 * t).sin())
            .collect();
        (x, v)
    };
    let (x1, v1) = traj(5.0);
    let (x2, v2) = traj(4.6);
    PhasePortraitFigure {
        title: "Phase portrait at U = 22 m/s".into(),
        x_label: "α [deg]".into(),
        y_label: "α̇ [deg/s]".into(),
        trajectories: vec![
            Series::new("measured (free response)", SeriesKind::Measured, x1, v1),
            Series::new("model", SeriesKind::Model, x2, v2),
        ],
    }
}

/// Flat-plate derivatives from R. T. Jones' approximation of Theodorsen's function (sample
/// data only; the real closed forms live in `aeroelastic`).
fn flat_plate(k_red: f64) -> [f64; 8] {
    let k = k_red / 2.0;
    // C(k) ≈ 1 − 0.165/(1 − 0.0455 i/k) − 0.335/(1 − 0.3 i/k)
    let term = |a: f64, b: f64| {
        let (re, im) = (1.0, -b / k);
        let d = re * re + im * im;
        (a * re / d, -a * im / d)
    };
    let (r1, i1) = term(0.165, 0.0455);
    let (r2, i2) = term(0.335, 0.3);
    let f = 1.0 - r1 - r2;
    let g = -i1 - i2;
    let kk = k_red;
    [
        -2.0 * PI * f / kk,
        -(PI / (2.0 * kk)) * (1.0 + f + 4.0 * g / kk),
        -(2.0 * PI / (kk * kk)) * (f - kk * g / 4.0),
        (PI / 2.0) * (1.0 + 4.0 * g / kk),
        PI * f / (2.0 * kk),
        -(PI / (8.0 * kk)) * (1.0 - f - 4.0 * g / kk),
        (PI / (2.0 * kk * kk)) * (kk * kk / 32.0 + f - kk * g / 4.0),
        -PI * g / (2.0 * kk),
    ]
}

pub fn derivatives() -> DerivativeFigure {
    let names = ["H1*", "H2*", "H3*", "H4*", "A1*", "A2*", "A3*", "A4*"];
    let kr: Vec<f64> = (0..60).map(|i| 0.3 + 0.03 * i as f64).collect();
    let kp: Vec<f64> = (0..8).map(|i| 0.4 + 0.2 * i as f64).collect();
    let panels = names
        .iter()
        .enumerate()
        .map(|(j, &n)| {
            let rv: Vec<f64> = kr.iter().map(|&k| flat_plate(k)[j]).collect();
            let pa: Vec<f64> = kp
                .iter()
                .enumerate()
                .map(|(i, &k)| flat_plate(k)[j] * (1.0 + 0.06 * ((i + j) as f64).sin()))
                .collect();
            let pb: Vec<f64> = kp
                .iter()
                .enumerate()
                .map(|(i, &k)| flat_plate(k + 0.05)[j] * (1.0 - 0.08 * ((i * 3 + j) as f64).cos()))
                .collect();
            let spread: Vec<f64> = pa.iter().map(|v| 0.05 * v.abs() + 0.02).collect();
            DerivativePanel {
                name: n.into(),
                points: vec![
                    DerivativePoints {
                        label: "configuration A".into(),
                        k: kp.clone(),
                        value: pa,
                        spread,
                        interval: vec![],
                    },
                    DerivativePoints {
                        label: "configuration B".into(),
                        k: kp.iter().map(|k| k + 0.05).collect(),
                        value: pb,
                        spread: vec![],
                        interval: vec![],
                    },
                ],
                reference_k: kr.clone(),
                reference_value: rv,
            }
        })
        .collect();
    DerivativeFigure {
        title: "Flutter derivatives vs reduced frequency".into(),
        k_label: "K = Bω/U [-]".into(),
        reference_label: "flat plate (Theodorsen)".into(),
        panels,
    }
}
