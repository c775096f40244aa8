//! Flutter and LCO results → figures.

use aeroelastic::ensemble::{FlutterEnsemble, LcoEnsemble};
use aeroelastic::flutter::FlutterAnalysis;
use aeroelastic::lco::{Classification, LcoResult};
use aeroelastic::trajectory::Trajectory;

use crate::{
    AmplitudeInterval, BifurcationFigure, BifurcationPoint, BranchCurve, BranchDiagramFigure,
    DiagramPoint, FlutterPoint, ModeBranch, PhasePortraitFigure, ResponseClass, Series, SeriesKind,
    SpeedInterval, Sweep, VgFigure,
};

/// Axis scaling of speed and frequency in the aeroelastic figures.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisScale {
    /// Displayed speed = U · `u_factor`.
    pub u_factor: f64,
    /// Speed axis description.
    pub u_label: String,
    /// Speed unit for annotations (may be empty).
    pub u_unit: String,
    /// Displayed frequency = ω · `f_factor` (ω in rad/s).
    pub f_factor: f64,
    /// Frequency axis description.
    pub f_label: String,
    /// Frequency unit for annotations (may be empty).
    pub f_unit: String,
    /// V–g damping axis as structural damping g = 2ζ instead of the damping ratio ζ.
    pub damping_g: bool,
}

impl AxisScale {
    /// SI: U \[m/s\], f = ω/2π \[Hz\].
    pub fn si() -> Self {
        AxisScale {
            u_factor: 1.0,
            u_label: "U [m/s]".into(),
            u_unit: "m/s".into(),
            f_factor: 1.0 / std::f64::consts::TAU,
            f_label: "f [Hz]".into(),
            f_unit: "Hz".into(),
            damping_g: false,
        }
    }

    /// Reduced: U/(bω_α) and ω/ω_α, for semi-chord `b` \[m\] and pitch frequency
    /// `omega_alpha` \[rad/s\].
    pub fn reduced(b: f64, omega_alpha: f64) -> Self {
        AxisScale {
            u_factor: 1.0 / (b * omega_alpha),
            u_label: "U/(bω_α) [-]".into(),
            u_unit: String::new(),
            f_factor: 1.0 / omega_alpha,
            f_label: "ω/ω_α [-]".into(),
            f_unit: String::new(),
            damping_g: false,
        }
    }
}

/// V–g / V–f figure of a flutter analysis: damping ratio ζ = −Re p/|p| (or g = 2ζ with
/// [`AxisScale::damping_g`]) and frequency of every tracked branch, the flutter point marked.
pub fn vg_figure(a: &FlutterAnalysis, title: &str, scale: &AxisScale) -> VgFigure {
    VgFigure {
        title: title.into(),
        u_label: scale.u_label.clone(),
        g_label: if scale.damping_g {
            "structural damping g = 2ζ [-]".into()
        } else {
            "damping ratio ζ [-]".into()
        },
        f_label: scale.f_label.clone(),
        u_unit: scale.u_unit.clone(),
        f_unit: scale.f_unit.clone(),
        modes: a
            .branches
            .iter()
            .map(|b| ModeBranch {
                name: b.label.clone(),
                u: b.points.iter().map(|p| p.u * scale.u_factor).collect(),
                damping: b
                    .points
                    .iter()
                    .map(|p| {
                        if scale.damping_g {
                            2.0 * p.zeta
                        } else {
                            p.zeta
                        }
                    })
                    .collect(),
                freq: b.points.iter().map(|p| p.omega * scale.f_factor).collect(),
            })
            .collect(),
        flutter: a.flutter.map(|f| FlutterPoint {
            u: f.u * scale.u_factor,
            freq: f.omega * scale.f_factor,
        }),
        flutter_interval: None,
    }
}

/// The interval of the flutter speed of an ensemble ([`FlutterEnsemble`]) on the figure's
/// speed axis, if any member found flutter.
pub fn flutter_interval(e: &FlutterEnsemble, scale: &AxisScale) -> Option<SpeedInterval> {
    e.flutter_speed.interval.map(|i| SpeedInterval {
        lower: i.lower * scale.u_factor,
        upper: i.upper * scale.u_factor,
        level: e.level,
        found: e.flutter_speed.found,
        members: e.members,
    })
}

/// Error bars of the pitch amplitude \[deg\] of an LCO ensemble ([`LcoEnsemble`]) at every
/// speed where at least one member settles on an LCO, and the legend text naming the
/// level and the number of members.
pub fn amplitude_intervals(e: &LcoEnsemble, scale: &AxisScale) -> (Vec<AmplitudeInterval>, String) {
    let bars = e
        .points
        .iter()
        .filter_map(|p| {
            p.amplitude_alpha_deg.interval.map(|i| AmplitudeInterval {
                u: p.u * scale.u_factor,
                median: i.median,
                lower: i.lower,
                upper: i.upper,
            })
        })
        .collect();
    let label = format!(
        "{} % interval over the members in LCO ({} bootstrap members)",
        crate::style::fmt_num(100.0 * e.level),
        e.members
    );
    (bars, label)
}

fn class_of(c: Classification) -> ResponseClass {
    match c {
        Classification::Decay => ResponseClass::Decay,
        Classification::Lco => ResponseClass::Lco,
        // drawn at its last measured amplitude, with its stop reason in the legend
        Classification::Unsettled => ResponseClass::Unsettled,
        Classification::Divergent { .. } => ResponseClass::Divergent,
    }
}

/// Bifurcation diagram: pitch amplitude \[deg\] of the upward and downward sweeps against U,
/// the flutter speed (if given, in m/s) as a vertical line. `Unsettled` runs are drawn as
/// unsettled points at their last measured amplitude, their stop reasons in the legend.
pub fn bifurcation_figure(
    up: &[LcoResult],
    down: &[LcoResult],
    flutter_speed: Option<f64>,
    title: &str,
    scale: &AxisScale,
) -> BifurcationFigure {
    let pts = |rs: &[LcoResult], sweep: Sweep| -> Vec<BifurcationPoint> {
        rs.iter()
            .map(|r| BifurcationPoint {
                u: r.u * scale.u_factor,
                amplitude: r.amplitude_alpha.to_degrees(),
                sweep,
                class: class_of(r.classification),
                stop: r.stop.name(),
            })
            .collect()
    };
    let mut points = pts(up, Sweep::Up);
    points.extend(pts(down, Sweep::Down));
    BifurcationFigure {
        title: title.into(),
        u_label: scale.u_label.clone(),
        amplitude_label: "LCO pitch amplitude [deg]".into(),
        points,
        u_unit: scale.u_unit.clone(),
        flutter_speed: flutter_speed.map(|u| u * scale.u_factor),
        intervals: vec![],
        interval_label: String::new(),
        flutter_interval: None,
    }
}

/// Phase portrait α \[deg\] vs dα/dt \[deg/s\] of each trajectory (one curve per speed).
pub fn phase_figure(
    trajectories: &[Trajectory],
    title: &str,
    scale: &AxisScale,
) -> PhasePortraitFigure {
    PhasePortraitFigure {
        title: title.into(),
        x_label: "α [deg]".into(),
        y_label: "dα/dt [deg/s]".into(),
        trajectories: trajectories
            .iter()
            .map(|t| {
                let u = crate::style::fmt_num(t.u * scale.u_factor);
                let label = if scale.u_unit.is_empty() {
                    format!("{} = {u}", scale.u_label.split(' ').next().unwrap_or("U"))
                } else {
                    format!("U = {u} {}", scale.u_unit)
                };
                Series::new(
                    label,
                    SeriesKind::Other,
                    t.alpha.iter().map(|a| a.to_degrees()).collect(),
                    t.alpha_dot.iter().map(|a| a.to_degrees()).collect(),
                )
            })
            .collect(),
    }
}

/// The bifurcation diagram of an orbit continued in a parameter at a fixed speed
/// (`aeroform branch --parameter`): pitch amplitude (half peak-to-peak) against the
/// parameter, stable solid, unstable dashed, folds marked.
pub fn lens_figure(b: &aeroelastic::branch::LensBranch) -> BranchDiagramFigure {
    BranchDiagramFigure {
        title: format!("LCO continued in {} at U = {:.3} m/s", b.parameter, b.u),
        u_label: format!("{} [{}]", b.parameter, b.unit),
        amplitude_label: "pitch amplitude (half peak-to-peak) [deg]".into(),
        branches: vec![BranchCurve {
            u: b.points.iter().map(|p| p.value).collect(),
            amplitude: b
                .points
                .iter()
                .map(|p| p.orbit.amplitude_alpha.to_degrees())
                .collect(),
            stable: b.points.iter().map(|p| p.orbit.stable).collect(),
        }],
        hopf: vec![],
        folds: b
            .events
            .iter()
            .filter(|e| e.kind == aeroelastic::branch::EventKind::Fold)
            .map(|e| DiagramPoint {
                u: e.value,
                amplitude: e.amplitude_alpha.to_degrees(),
                stable: false,
            })
            .collect(),
        sweep: vec![],
        measured: vec![],
    }
}

/// The bifurcation diagram of `set`: stable branches solid, unstable dashed, Hopf points
/// and folds marked, `sweep` (time-integration points, pitch amplitude \[deg\]) and the
/// measured points of `dist` on top (first-harmonic amplitudes when measured points are
/// given, to compare like with like). Used by `aeroform branch` and the study
/// report ([`crate::study_report`]).
pub fn branch_figure(
    set: &aeroelastic::branch::BranchSet,
    dist: &[aeroelastic::branch::MeasuredDistance],
    sweep: Vec<DiagramPoint>,
) -> BranchDiagramFigure {
    // With measured points, compare like with like: first-harmonic amplitudes.
    let first = !dist.is_empty();
    let amp = |p: &aeroelastic::branch::BranchPoint| {
        if first {
            p.amplitude1_alpha.to_degrees()
        } else {
            p.amplitude_alpha.to_degrees()
        }
    };
    BranchDiagramFigure {
        title: "LCO branches by continuation".into(),
        u_label: "U [m/s]".into(),
        amplitude_label: if first {
            "first-harmonic pitch amplitude [deg]".into()
        } else {
            "pitch amplitude (half peak-to-peak) [deg]".into()
        },
        branches: set
            .branches
            .iter()
            .map(|b| BranchCurve::of_branch(b, amp))
            .collect(),
        hopf: set
            .hopf_points
            .iter()
            .map(|h| DiagramPoint {
                u: h.u,
                amplitude: 0.0,
                stable: false,
            })
            .collect(),
        folds: set
            .branches
            .iter()
            .flat_map(|b| {
                b.events
                    .iter()
                    .filter(|e| e.kind == aeroelastic::branch::EventKind::Fold)
                    .map(|e| DiagramPoint {
                        u: e.u,
                        amplitude: if first {
                            // first-harmonic amplitude of the orbit nearest the fold
                            amp(&b.points[e.index.saturating_sub(1)])
                        } else {
                            e.amplitude_alpha.to_degrees()
                        },
                        stable: false,
                    })
            })
            .collect(),
        sweep,
        measured: dist
            .iter()
            .filter_map(|d| {
                Some(DiagramPoint {
                    u: d.measured.u,
                    amplitude: d.measured.amplitude_alpha?.to_degrees(),
                    stable: d.measured.stable,
                })
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use aeroelastic::flutter::{FlutterMethod, ModePoint};
    use aeroelastic::integrate::{ObserverVerdict, SolverStop};

    use super::*;

    fn lco(u: f64, class: Classification, amp_rad: f64) -> LcoResult {
        LcoResult {
            u,
            classification: class,
            amplitude_alpha: amp_rad,
            amplitude_h: 0.0,
            omega: 0.0,
            cycles: 0,
            t_end: 0.0,
            rhs_evals: 0,
            steps: 0,
            stop: match class {
                Classification::Decay => ObserverVerdict::Decayed.into(),
                Classification::Lco => ObserverVerdict::Converged.into(),
                Classification::Divergent { .. } => ObserverVerdict::LeftBound.into(),
                Classification::Unsettled => SolverStop::TimeCap.into(),
            },
            final_state: vec![],
            k_eval: None,
            k_iterations: 1,
        }
    }

    #[test]
    fn vg_scales_speed_and_frequency() {
        let a = FlutterAnalysis {
            method: FlutterMethod::Pk,
            model: "m".into(),
            branches: vec![aeroelastic::flutter::ModeBranch {
                label: "mode 0".into(),
                points: vec![ModePoint {
                    u: 4.0,
                    sigma: -0.1,
                    omega: std::f64::consts::TAU,
                    zeta: 0.05,
                }],
                ended_at: None,
            }],
            flutter: Some(aeroelastic::flutter::FlutterPoint {
                u: 6.0,
                omega: 3.0,
                mode: 0,
                u_reduced: 0.0,
                omega_ratio: 0.0,
            }),
            divergence_speed: None,
            failed: vec![],
            unstable_at_u_min: false,
        };
        let si = vg_figure(&a, "t", &AxisScale::si());
        assert_eq!(si.modes[0].freq, vec![1.0]); // ω = 2π rad/s → 1 Hz
        assert_eq!(si.modes[0].damping, vec![0.05]);
        let red = vg_figure(&a, "t", &AxisScale::reduced(0.5, 2.0));
        assert_eq!(red.modes[0].u, vec![4.0]); // U/(bω_α) = 4/(0.5·2)
        let f = red.flutter.unwrap();
        assert_eq!((f.u, f.freq), (6.0, 1.5));
    }

    #[test]
    fn bifurcation_maps_classes_and_degrees() {
        let up = vec![
            lco(1.0, Classification::Decay, 0.0),
            lco(2.0, Classification::Lco, 0.1),
            lco(3.0, Classification::Unsettled, 0.2),
            lco(
                4.0,
                Classification::Divergent {
                    time_left_bound: 1.0,
                },
                1.0,
            ),
        ];
        let f = bifurcation_figure(&up, &[], Some(1.5), "t", &AxisScale::si());
        let classes: Vec<ResponseClass> = f.points.iter().map(|p| p.class).collect();
        assert_eq!(
            classes,
            vec![
                ResponseClass::Decay,
                ResponseClass::Lco,
                ResponseClass::Unsettled,
                ResponseClass::Divergent
            ]
        );
        assert!((f.points[1].amplitude - 0.1_f64.to_degrees()).abs() < 1e-12);
        assert!(f.points.iter().all(|p| p.sweep == Sweep::Up));
        assert_eq!(f.points[2].stop, "time_cap");
        assert_eq!(f.flutter_speed, Some(1.5));
    }
}
