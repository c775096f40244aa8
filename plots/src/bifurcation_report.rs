//! Figures and the self-contained `diagnosis.html` of a bifurcation-level diagnosis
//! ([`diagnose::bifurcation::BifurcationDiagnosis`], `aeroform diagnose
//! --measured-branch`). The report leads with the verdict and its own level: the measured
//! diagram against the sim's before and after the named effect, then the structure
//! (still-air decays), the candidates with their fitted parameters and sign conventions,
//! and every point held out.

use std::path::{Path, PathBuf};

use diagnose::bifurcation::{BifurcationDiagnosis, BranchKind, DiagramSummary, Errors, Quantity};

use crate::error::Result;
use crate::figures::branch_comparison::{BranchComparisonFigure, ComparisonDofPanel, DiagramLayer};
use crate::figures::branch_diagram::{BranchCurve, DiagramPoint};
use crate::figures::ranking::{RankingBar, RankingFigure, RankingPanel};
use crate::render::{render_pdf, save, Figure, FigureFiles};
use crate::report::Report;
use crate::report_parts::{structure_section, table, DIAGNOSIS_HTML, FIGURES_DIR};

/// File stems of the two figures.
pub const BIFURCATION_FIGURES: [&str; 2] = ["bifurcation_comparison", "bifurcation_ranking"];

#[derive(Clone, Copy)]
enum Dof {
    Pitch,
    Heave,
}

fn layer(s: &DiagramSummary, dof: Dof) -> DiagramLayer {
    let amp = |a: f64, h: f64| match dof {
        Dof::Pitch => a.to_degrees(),
        Dof::Heave => h * 1e3,
    };
    DiagramLayer {
        branches: s
            .branches
            .iter()
            .flat_map(|set| set.branches.iter())
            .map(|b| BranchCurve::of_branch(b, |p| amp(p.amplitude1_alpha, p.amplitude1_h)))
            .collect(),
        hopf: s.hopf.iter().map(|h| h.u).collect(),
        folds: s
            .folds
            .iter()
            .map(|f| DiagramPoint {
                u: f.u,
                amplitude: amp(f.amplitude1_alpha, f.amplitude1_h),
                stable: false,
            })
            .collect(),
    }
}

/// The comparison figure: the named candidate's diagram, or the best one's when nothing is
/// named.
pub fn comparison_figure(d: &BifurcationDiagnosis) -> BranchComparisonFigure {
    let after = d
        .verdict
        .candidate
        .or((!d.candidates.is_empty()).then_some(0))
        .map(|i| &d.candidates[i]);
    let panels = [Dof::Pitch, Dof::Heave]
        .into_iter()
        .filter_map(|dof| {
            let measured: Vec<DiagramPoint> = d
                .measured
                .iter()
                .filter_map(|m| {
                    let a = match dof {
                        Dof::Pitch => m.amplitude_alpha?.to_degrees(),
                        Dof::Heave => m.amplitude_h? * 1e3,
                    };
                    Some(DiagramPoint {
                        u: m.u,
                        amplitude: a,
                        stable: m.stable,
                    })
                })
                .collect();
            (!measured.is_empty()).then(|| ComparisonDofPanel {
                amplitude_label: match dof {
                    Dof::Pitch => "first-harmonic pitch amplitude [deg]".into(),
                    Dof::Heave => "first-harmonic heave amplitude [mm]".into(),
                },
                before: layer(&d.nominal, dof),
                after: after.map(|c| layer(&c.fit, dof)),
                measured,
            })
        })
        .collect();
    // the measured speeds, the nominal Hopf points and the shown diagram's folds
    let lo = d
        .speed_groups
        .first()
        .copied()
        .into_iter()
        .chain(after.iter().flat_map(|c| c.fit.folds.iter().map(|f| f.u)))
        .fold(f64::INFINITY, f64::min);
    let lo = if lo.is_finite() { lo } else { 0.0 };
    let hi = d
        .nominal
        .hopf
        .iter()
        .map(|h| h.u)
        .chain(d.speed_groups.last().copied())
        .fold(lo, f64::max);
    let pad = 0.08 * (hi - lo).max(0.1 * hi);
    BranchComparisonFigure {
        title: "Measured bifurcation diagram against the sim".into(),
        after_label: after.map_or("candidate".into(), |c| {
            if d.verdict.candidate.is_some() {
                format!("with {} (named)", c.label())
            } else {
                format!("with {} (best, not named)", c.label())
            }
        }),
        u_label: "U [m/s]".into(),
        panels,
        u_range: Some((lo - pad, hi + pad)),
    }
}

/// The ranking figure: held-out score of every candidate against the nominal model's.
pub fn ranking_figure(d: &BifurcationDiagnosis) -> RankingFigure {
    RankingFigure {
        title: "Candidates at the bifurcation level (leave one speed out)".into(),
        panels: vec![RankingPanel {
            title: "held-out relative amplitude error".into(),
            x_label: "held-out score after the candidate [-]".into(),
            bars: d
                .candidates
                .iter()
                .enumerate()
                .map(|(i, c)| RankingBar {
                    label: format!(
                        "{} {} ({}p)",
                        c.effect.short_label(),
                        c.variant,
                        c.parameters.len()
                    ),
                    value: c.held_out.score,
                    highlight: d.verdict.candidate == Some(i),
                    note: "no value".into(),
                })
                .collect(),
            baseline: Some(d.nominal.errors.score),
            noise_level: Some(2.0 * d.options.amplitude_noise),
        }],
        highlight_legend: Some(("named".into(), "not named".into())),
    }
}

fn save_all<F: Figure>(f: &F, dir: &Path, stem: &str) -> Result<(FigureFiles, PathBuf)> {
    let files = save(f, dir, stem)?;
    let pdf = dir.join(format!("{stem}.pdf"));
    if files.pdf.is_none() {
        identify::io::write_atomic(&pdf, &render_pdf(f)?)?;
    }
    Ok((files, pdf))
}

fn deg(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{:.3}", x.to_degrees()))
}

fn mm(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{:.2}", x * 1e3))
}

fn hz(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{:.3}", x))
}

fn error_rows(name: &str, e: &Errors) -> Vec<Vec<String>> {
    [BranchKind::Stable, BranchKind::Unstable, BranchKind::All]
        .into_iter()
        .map(|b| {
            let unc = e
                .rows
                .iter()
                .filter(|r| r.branch == b && r.quantity != Quantity::Frequency)
                .map(|r| r.uncovered)
                .max()
                .unwrap_or(0);
            vec![
                name.to_string(),
                format!("{b:?}").to_lowercase(),
                deg(e.rms(b, Quantity::Pitch)),
                mm(e.rms(b, Quantity::Heave)),
                hz(e.rms(b, Quantity::Frequency)),
                unc.to_string(),
            ]
        })
        .collect()
}

fn diagram_rows(name: &str, s: &DiagramSummary) -> Vec<String> {
    vec![
        name.to_string(),
        s.hopf
            .iter()
            .map(|h| {
                format!(
                    "{:.3} m/s, {:.3} Hz{}",
                    h.u,
                    h.frequency_hz,
                    if h.extrapolation {
                        " (extrapolation)"
                    } else {
                        ""
                    }
                )
            })
            .collect::<Vec<_>>()
            .join("; "),
        s.hopf
            .iter()
            .map(|h| h.criticality.clone())
            .collect::<Vec<_>>()
            .join("; "),
        s.folds
            .iter()
            .map(|f| {
                format!(
                    "{:.3} m/s ({:.2}°){}",
                    f.u,
                    f.amplitude1_alpha.to_degrees(),
                    if f.extrapolation {
                        " (extrapolation)"
                    } else {
                        ""
                    }
                )
            })
            .collect::<Vec<_>>()
            .join("; "),
    ]
}

/// The report of a bifurcation-level diagnosis with its two figures.
pub fn bifurcation_report(
    d: &BifurcationDiagnosis,
    comparison: Option<&FigureFiles>,
    ranking: Option<&FigureFiles>,
) -> Report {
    let mut r = Report::new(format!(
        "aeroform diagnosis (bifurcation level): {}",
        d.verdict.name
    ));
    r.section("Verdict");
    r.text(d.verdict.explanation.clone());
    if !d.verdict.richer.is_empty() {
        r.text(format!(
            "Richer candidates within one standard error, passed over for the simpler one: {}.",
            d.verdict.richer.join(", ")
        ));
    }
    let named = d.verdict.candidate.map(|i| &d.candidates[i]);
    r.section("Where: the bifurcation diagram");
    if let Some(f) = comparison {
        r.figure(
            "Measured first-harmonic amplitudes (filled: stable branch, open: unstable) on the \
             sim's branches by continuation (solid stable, dashed unstable), grey before and \
             coloured after the named effect (fitted on all points); Hopf points ▲, folds ◆.",
            f,
        );
    }
    let mut rows = vec![diagram_rows("nominal", &d.nominal)];
    if let Some(c) = named {
        rows.push(diagram_rows(&format!("with {}", c.label()), &c.fit));
    }
    table(
        &mut r,
        "Hopf points, criticality and folds of the sim's diagram",
        &[
            "model",
            "Hopf (speed, frequency)",
            "criticality",
            "folds (speed, pitch amplitude); extrapolation = outside the measured speeds or \
             amplitudes",
        ],
        &rows,
    );
    let mut rows = error_rows("nominal", &d.nominal.errors);
    if let Some(c) = named {
        rows.extend(error_rows(
            &format!("{} (held out)", c.label()),
            &c.held_out,
        ));
    }
    table(
        &mut r,
        "RMS error at the measured points, per branch: pitch [deg], heave [mm], frequency \
         [Hz]; uncovered = points whose speed no predicted branch of their stability reaches \
         (amplitudes counted as predicted 0, frequencies left out)",
        &[
            "model",
            "branch",
            "pitch",
            "heave",
            "frequency",
            "uncovered",
        ],
        &rows,
    );
    let held: Vec<Vec<String>> = d
        .nominal
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let h = named.map(|c| &c.held_out_points[i]);
            vec![
                format!("{:.3}", p.measured.u),
                if p.measured.stable {
                    "stable"
                } else {
                    "unstable"
                }
                .to_string(),
                deg(p.measured.amplitude_alpha),
                deg(p.predicted_alpha),
                deg(h.and_then(|h| h.predicted_alpha)),
                mm(p.measured.amplitude_h),
                mm(h.and_then(|h| h.predicted_h)),
                hz(p.measured.frequency_hz),
                hz(h.and_then(|h| h.predicted_frequency_hz)),
            ]
        })
        .collect();
    table(
        &mut r,
        "Each measured point: measured, nominal and held-out prediction of the named effect \
         (fitted without the point's speed)",
        &[
            "U [m/s]",
            "branch",
            "pitch [deg]",
            "nominal",
            "held out",
            "heave [mm]",
            "held out",
            "freq [Hz]",
            "held out",
        ],
        &held,
    );
    r.section("Structure first: still-air decays");
    structure_section(
        &mut r,
        d.structure.as_ref(),
        "No still-air decay was given: the structure is taken as given, and only the \
         flow records' amplitude dependence informs the structural candidates.",
    );
    r.section("Which effect: candidates");
    if let Some(f) = ranking {
        r.figure(
            "Held-out score (relative amplitude error, leave one speed out) after each \
             candidate; the named one highlighted, the nominal model dashed black, twice the \
             amplitude uncertainty dashed red.",
            f,
        );
    }
    let rows: Vec<Vec<String>> = d
        .candidates
        .iter()
        .map(|c| {
            vec![
                c.label(),
                c.parameters.len().to_string(),
                format!("{:.3} ± {:.3}", c.held_out.score, c.score_se),
                format!("{:.1} %", 100.0 * c.shrink),
                deg(c.held_out.rms(BranchKind::All, Quantity::Pitch)),
                mm(c.held_out.rms(BranchKind::All, Quantity::Heave)),
                c.fit
                    .folds
                    .iter()
                    .map(|f| format!("{:.2}{}", f.u, if f.extrapolation { "*" } else { "" }))
                    .collect::<Vec<_>>()
                    .join(", "),
                c.parameters
                    .iter()
                    .map(|p| format!("{} = {:.4e} {}", p.spec.name, p.value, p.spec.unit))
                    .collect::<Vec<_>>()
                    .join("; "),
            ]
        })
        .collect();
    table(
        &mut r,
        "Candidates, best held-out score first (pitch [deg] and heave [mm] RMS held out; \
         folds [m/s], * outside the measured speeds or amplitudes, and parameters of the fit \
         on all points)",
        &[
            "candidate",
            "params",
            "score ± SE",
            "shrink",
            "pitch",
            "heave",
            "folds",
            "parameters",
        ],
        &rows,
    );
    let conv: Vec<(String, String)> = d
        .candidates
        .iter()
        .flat_map(|c| c.parameters.iter())
        .map(|p| {
            (
                format!("{} [{}]", p.spec.name, p.spec.unit),
                p.spec.convention.clone(),
            )
        })
        .collect::<std::collections::BTreeMap<_, _>>()
        .into_iter()
        .collect();
    r.key_values("Sign conventions of the parameters", &conv);
    if !d.not_fitted.is_empty() {
        r.text(format!(
            "Not fitted at this level: {}.",
            d.not_fitted.join("; ")
        ));
    }
    r.section("Inputs");
    let mut kv: Vec<(String, String)> = d
        .inputs
        .iter()
        .map(|i| match i.split_once(": ") {
            Some((k, v)) => (k.to_string(), v.to_string()),
            None => ("input".into(), i.clone()),
        })
        .collect();
    kv.push(("version".into(), d.version.clone()));
    kv.push((
        "speed groups (folds)".into(),
        d.speed_groups
            .iter()
            .map(|u| format!("{u:.3}"))
            .collect::<Vec<_>>()
            .join(", "),
    ));
    kv.push(("wall time".into(), format!("{:.2} s", d.seconds)));
    r.key_values("Inputs and settings", &kv);
    if !d.records.is_empty() {
        let rows: Vec<Vec<String>> = d
            .records
            .iter()
            .map(|u| {
                vec![
                    u.case.clone(),
                    format!("{:.3}", u.wind_speed),
                    format!("{:?}", u.used_as).to_lowercase(),
                    u.note.clone(),
                ]
            })
            .collect();
        table(
            &mut r,
            "Records",
            &["case", "U [m/s]", "used as", "note"],
            &rows,
        );
    }
    r
}

/// Writes the two figures (PNG, SVG and PDF each) into `<out_dir>/figures/` and
/// `<out_dir>/diagnosis.html`, every file atomically. Returns the written paths.
///
/// # Errors
/// [`crate::Error::Write`] naming the folder or file when `out_dir` is missing or not
/// writable; drawing errors naming the figure.
pub fn write_bifurcation_outputs(d: &BifurcationDiagnosis, out_dir: &Path) -> Result<Vec<PathBuf>> {
    let fig_dir = out_dir.join(FIGURES_DIR);
    identify::io::create_dir_below(out_dir, Path::new(FIGURES_DIR))?;
    let mut paths = Vec::new();
    let comp = comparison_figure(d);
    let comp = if comp.panels.is_empty() {
        None
    } else {
        let (f, pdf) = save_all(&comp, &fig_dir, BIFURCATION_FIGURES[0])?;
        paths.extend([f.png.clone(), f.svg.clone(), pdf]);
        Some(f)
    };
    let rank = if d.candidates.is_empty() {
        None
    } else {
        let (f, pdf) = save_all(&ranking_figure(d), &fig_dir, BIFURCATION_FIGURES[1])?;
        paths.extend([f.png.clone(), f.svg.clone(), pdf]);
        Some(f)
    };
    let html = out_dir.join(DIAGNOSIS_HTML);
    bifurcation_report(d, comp.as_ref(), rank.as_ref()).write(&html)?;
    paths.push(html);
    Ok(paths)
}
