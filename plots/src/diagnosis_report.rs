//! Figures and the self-contained `diagnosis.html` of a [`diagnose::Diagnosis`]
//! (`aeroform diagnose`, DESIGN.md §5): verdict, gap, where, candidates, observables,
//! signature tests, and the five diagnosis figures inline.
//!
//! [`write_diagnosis_outputs`] is the one-call entry point; [`save_diagnosis_figures`] and
//! [`diagnosis_section`] let another report (the study report) embed the same content.

use std::path::{Path, PathBuf};

use diagnose::Diagnosis;

use crate::adapters::diagnosis::{
    bifurcation_figure, gap_heatmap_figure, ranking_figure, residual_spectra_figure, shares_figure,
    where_cell_label,
};
use crate::error::Result;
use crate::render::{save, FigureFiles};
use crate::report::Report;
use crate::report_parts::structure_section;
pub use crate::report_parts::{DIAGNOSIS_HTML, FIGURES_DIR};

/// Kind, file stem and what is missing when it is not drawn, of each diagnosis figure, in
/// report order.
pub const DIAGNOSIS_FIGURE_KINDS: [(&str, &str, &str); 5] = [
    (
        "gap_heatmap",
        "diagnosis_gap_heatmap",
        "no forced-record (aerodynamic) level with per-case gaps",
    ),
    (
        "residual_spectra",
        "diagnosis_residual_spectra",
        "no residual spectrum reported",
    ),
    (
        "candidate_ranking",
        "diagnosis_candidate_ranking",
        "no candidate scored",
    ),
    (
        "bifurcation",
        "diagnosis_bifurcation",
        "no free-response level with a bifurcation diagram",
    ),
    (
        "where_shares",
        "diagnosis_where_shares",
        "no where-split reported",
    ),
];

/// One drawn diagnosis figure.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagnosisFigure {
    /// Kind (first column of [`DIAGNOSIS_FIGURE_KINDS`]).
    pub kind: &'static str,
    /// Caption in the report.
    pub caption: String,
    /// Written files and SVG text.
    pub files: FigureFiles,
}

/// Draws every diagnosis figure that has data into `dir` (PNG + SVG each, atomically,
/// stems of [`DIAGNOSIS_FIGURE_KINDS`]); figures without data are skipped (not an error).
///
/// # Errors
/// [`crate::Error::Write`] naming the file when `dir` is missing or unwritable; drawing
/// errors of [`crate::save`] (not expected: adapters only pass drawable data).
pub fn save_diagnosis_figures(diag: &Diagnosis, dir: &Path) -> Result<Vec<DiagnosisFigure>> {
    let mut out = vec![];
    let stem = |k: &str| {
        DIAGNOSIS_FIGURE_KINDS
            .iter()
            .find(|(kind, _, _)| *kind == k)
            .map(|(_, s, _)| *s)
            .expect("known kind")
    };
    if let Some(f) = gap_heatmap_figure(diag) {
        out.push(DiagnosisFigure {
            kind: "gap_heatmap",
            caption: "Held-out force gap of each forced case divided by its noise-level gap, \
                      over pitch amplitude × wind speed, per configuration, before and after \
                      the best aerodynamic candidate (white = noise level; red = above, \
                      blue = below; logarithmic colour scale)."
                .into(),
            files: save(&f, dir, stem("gap_heatmap"))?,
        });
    }
    if let Some(f) = residual_spectra_figure(diag) {
        out.push(DiagnosisFigure {
            kind: "residual_spectra",
            caption: "Mean residual amplitude spectrum over the held-out cases, per channel, \
                      before (baseline, solid) and after the level's best candidate (dashed)."
                .into(),
            files: save(&f, dir, stem("residual_spectra"))?,
        });
    }
    if let Some(f) = ranking_figure(diag) {
        out.push(DiagnosisFigure {
            kind: "candidate_ranking",
            caption: "Held-out gap after each candidate augmentation, best first (number of \
                      added parameters in brackets); significant improvements in green, \
                      the baseline gap dashed black, the noise level dashed red."
                .into(),
            files: save(&f, dir, stem("candidate_ranking"))?,
        });
    }
    if let Some(f) = bifurcation_figure(diag) {
        out.push(DiagnosisFigure {
            kind: "bifurcation",
            caption: "Free response: pitch amplitude at the end of the record and dominant \
                      pitch frequency against wind speed, measured (markers), predicted by \
                      the baseline model (dashed) and with the winning augmentation."
                .into(),
            files: save(&f, dir, stem("bifurcation"))?,
        });
    }
    if let Some(f) = shares_figure(diag) {
        out.push(DiagnosisFigure {
            kind: "where_shares",
            caption: "Where the held-out gap lies: shares of the excess residual per split \
                      (largest cells first; small cells merged into \"other\"; all cells in \
                      the where table)."
                .into(),
            files: save(&f, dir, stem("where_shares"))?,
        });
    }
    Ok(out)
}

/// A number for a table cell: 4 significant digits, scientific outside [1e-3, 1e5), `–`
/// when not finite.
fn num(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.3e}")
    }
}

/// A compact number (up to 4 significant digits, no trailing zeros) for ranges and
/// parameters; `–` when not finite.
fn short(v: f64) -> String {
    if v.is_finite() {
        crate::style::fmt_num(v)
    } else {
        "–".into()
    }
}

/// A percentage with a non-breaking space before `%`.
fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{:.1}\u{a0}%", 100.0 * v)
    } else {
        "–".into()
    }
}

fn range(r: [f64; 2]) -> String {
    if r[0] == r[1] {
        short(r[0])
    } else {
        format!("{}–{}", short(r[0]), short(r[1]))
    }
}

fn yes(b: bool) -> String {
    if b { "yes" } else { "no" }.into()
}

/// Appends the diagnosis sections to `report`: verdict, gap, where, candidates,
/// observables, signature tests and `figures` (with a note for each figure kind that was
/// not drawn).
pub fn diagnosis_section(report: &mut Report, diag: &Diagnosis, figures: &[DiagnosisFigure]) {
    let v = &diag.verdict;
    report.section("Verdict").key_values(
        "",
        &[
            ("effect", v.effect.name().to_string()),
            ("level", v.level.name().to_string()),
            ("confidence", num(v.confidence)),
            ("reason", v.reason.clone()),
            ("inputs", diag.inputs.join(", ")),
            ("seed", diag.seed.to_string()),
            ("version", diag.version.clone()),
            ("format", diag.format.clone()),
        ],
    );

    let g = &diag.gap;
    let header = [
        "level",
        "metric",
        "before",
        "after",
        "shrink",
        "noise level",
        "before / noise",
        "significant gap (statistic / threshold)",
        "held-out cases",
    ];
    let mut rows = vec![vec![
        "headline (verdict level)".to_string(),
        g.metric.clone(),
        num(g.before),
        num(g.after),
        pct(g.shrink),
        num(g.noise_level),
        num(g.before / g.noise_level),
        String::new(),
        g.held_out_cases.len().to_string(),
    ]];
    for lv in &diag.levels {
        let after = crate::adapters::diagnosis::best_candidate(lv).map(|c| c.after);
        let (after_s, shrink_s) = match after {
            Some(a) => (num(a), pct(1.0 - a / lv.before)),
            None => ("–".into(), "–".into()),
        };
        rows.push(vec![
            lv.level.name().to_string(),
            lv.metric.clone(),
            num(lv.before),
            after_s,
            shrink_s,
            num(lv.noise_level),
            num(lv.before / lv.noise_level),
            format!(
                "{} ({} / {})",
                yes(lv.significant_gap),
                num(lv.gap_statistic),
                num(lv.gap_threshold)
            ),
            lv.held_out_cases.len().to_string(),
        ]);
    }
    report.section("Gap").table(
        "Held-out gap before and after the best candidate of each level",
        &header.map(String::from),
        &rows,
    );

    let mut where_all: Vec<_> = if diag.where_.is_empty() {
        diag.levels.iter().flat_map(|l| &l.where_).collect()
    } else {
        diag.where_.iter().collect()
    };
    // The verdict's own level leads: its figure first (the gap map of the forced records
    // for an aerodynamic verdict, the bifurcation diagram of the free runs for a structural
    // one), and its where-cells before the other level's.
    let lead = diag.verdict.level;
    where_all.sort_by_key(|w| w.level != lead);
    let lead_figure = if lead == diagnose::Level::Structural {
        "bifurcation"
    } else {
        "gap_heatmap"
    };
    report.section("Where");
    for f in figures.iter().filter(|f| f.kind == lead_figure) {
        report.figure(f.caption.clone(), &f.files);
    }
    if where_all.is_empty() {
        report.text("No where-split reported (diagnosis.json has no `where` cells).");
    } else {
        let rows: Vec<Vec<String>> = where_all
            .iter()
            .map(|w| {
                vec![
                    w.split.to_string(),
                    w.level.name().to_string(),
                    where_cell_label(w),
                    w.channel.to_string(),
                    w.harmonic.label(),
                    w.config.clone().unwrap_or_default(),
                    range(w.wind_speed),
                    range(w.amplitude),
                    w.state.clone().unwrap_or_default(),
                    pct(w.share),
                ]
            })
            .collect();
        report.table(
            "Shares of the held-out gap (each split sums to 100 %)",
            &[
                "split",
                "level",
                "cell",
                "channel",
                "harmonic",
                "config",
                "U [m/s]",
                "amplitude [deg]",
                "state",
                "share",
            ]
            .map(String::from),
            &rows,
        );
    }

    if let Some(cov) = diag.levels.iter().find_map(|l| l.coverage.as_ref()) {
        coverage_section(report, cov);
    }
    if let Some(plan) = &diag.follow_up {
        follow_up_section(report, plan);
    }
    if let Some(level) = diag
        .levels
        .iter()
        .find(|l| l.level == diagnose::Level::Structural)
    {
        report.section("Structure first: still-air decays");
        structure_section(
            report,
            level.structure.as_ref(),
            "No still-air decay (U = 0) among the free runs: the structure is taken as \
             given, and only the flow runs' amplitude dependence informs the structural \
             candidates.",
        );
    }

    let cands: Vec<_> = if diag.candidates.is_empty() {
        diag.levels.iter().flat_map(|l| &l.candidates).collect()
    } else {
        diag.candidates.iter().collect()
    };
    report.section("Candidates");
    if cands.is_empty() {
        report.text("No candidate scored.");
    } else {
        let rows: Vec<Vec<String>> = cands
            .iter()
            .enumerate()
            .map(|(i, c)| {
                vec![
                    (i + 1).to_string(),
                    c.effect.name().to_string(),
                    c.level.name().to_string(),
                    num(c.before),
                    num(c.after),
                    pct(c.shrink),
                    c.n_params.to_string(),
                    num(c.statistic),
                    num(c.threshold),
                    yes(c.significant),
                    num(c.score),
                    match &c.failure {
                        Some(f) => format!("not fitted: {f}"),
                        None => c
                            .parameters
                            .iter()
                            .map(|(k, v)| format!("{k}\u{a0}=\u{a0}{}", short(*v)))
                            .collect::<Vec<_>>()
                            .join(", "),
                    },
                ]
            })
            .collect();
        report.table(
            "Every candidate augmentation, fitted on training folds and scored on held-out cases (best first)",
            &[
                "rank",
                "effect",
                "level",
                "before",
                "after",
                "shrink",
                "params",
                "statistic",
                "threshold",
                "significant",
                "score",
                "fitted parameters (SI) or failure",
            ]
            .map(String::from),
            &rows,
        );
    }

    let obs: Vec<_> = diag.levels.iter().flat_map(|l| &l.observables).collect();
    report.section("Observables");
    if obs.is_empty() {
        report.text("No observable reported.");
    } else {
        let rows: Vec<Vec<String>> = obs
            .iter()
            .map(|o| {
                vec![
                    o.name.clone(),
                    o.level.name().to_string(),
                    o.unit.clone(),
                    num(o.before),
                    num(o.after),
                    pct(o.shrink),
                ]
            })
            .collect();
        report.table(
            "Held-out gap per observable before and after the winning augmentation",
            &["observable", "level", "unit", "before", "after", "shrink"].map(String::from),
            &rows,
        );
    }

    let sig: Vec<_> = diag.levels.iter().flat_map(|l| &l.signatures).collect();
    report.section("Signature tests");
    if sig.is_empty() {
        report.text("No signature test reported.");
    } else {
        let rows: Vec<Vec<String>> = sig
            .iter()
            .map(|s| {
                vec![
                    s.name.clone(),
                    s.level.name().to_string(),
                    num(s.statistic),
                    num(s.threshold),
                    yes(s.detected),
                    s.detail.clone(),
                ]
            })
            .collect();
        report.table(
            "Residual signature tests (detected = statistic > threshold)",
            &[
                "test",
                "level",
                "statistic",
                "threshold",
                "detected",
                "detail",
            ]
            .map(String::from),
            &rows,
        );
    }

    report.section("Figures");
    let missing: Vec<String> = DIAGNOSIS_FIGURE_KINDS
        .iter()
        .filter(|(k, _, _)| !figures.iter().any(|f| f.kind == *k))
        .map(|(k, _, why)| format!("{k} ({why})"))
        .collect();
    if !missing.is_empty() {
        report.text(format!("Not drawn: {}.", missing.join("; ")));
    }
    for f in figures.iter().filter(|f| f.kind != lead_figure) {
        report.figure(f.caption.clone(), &f.files);
    }
}

/// The "Coverage" section: every free run's response K and amplitude against the forced
/// range, how the gap changes with Theodorsen-shaped tails, and the forced cases that would
/// cover the runs outside.
/// The recommended forced tests (`follow_up.campaign.toml`), one row per configuration.
fn follow_up_section(report: &mut Report, plan: &aeroelastic::tunnel::CampaignPlan) {
    let list = |v: &[f64]| v.iter().map(|x| short(*x)).collect::<Vec<_>>().join(", ");
    let rows: Vec<Vec<String>> = plan
        .rows
        .iter()
        .map(|r| {
            let c = &r.configuration;
            vec![
                r.rank.to_string(),
                c.name.clone(),
                short(c.freq_pitch),
                short(c.freq_heave),
                short(c.amplitude_ratio),
                short(c.mean_pitch_deg),
                list(&r.wind_speeds),
                list(&r.amplitudes_deg),
                r.repeats.unwrap_or(1).to_string(),
                r.record_duration_s.map_or("-".into(), short),
                r.discrimination.map_or("-".into(), short),
                r.reason.clone().unwrap_or_default(),
            ]
        })
        .collect();
    report.table(
        "Recommended forced tests (follow_up.campaign.toml; run with `aeroform tunnel forced --campaign-file`): each row's configuration at every listed wind speed and pitch amplitude, each case recorded `records` times for `T` seconds; ranked by the predicted discrimination between the force level's consistent candidate and the baseline over the noise (else by the held-out gap of the free runs a row covers)",
        &[
            "rank",
            "configuration",
            "f_α [Hz]",
            "f_h [Hz]",
            "r_A [mm/deg]",
            "ᾱ [deg]",
            "U [m/s]",
            "α amplitude [deg]",
            "records",
            "T [s]",
            "discrimination",
            "why",
        ]
        .map(String::from),
        &rows,
    );
}

fn coverage_section(report: &mut Report, cov: &diagnose::report::Coverage) {
    report.section("Coverage");
    let outside = cov.runs.iter().filter(|r| !r.covered).count();
    report.key_values(
        "Free runs against the range the forced cases identified",
        &[
            (
                "K_h range of the forced cases".to_string(),
                range(cov.k_h_range),
            ),
            (
                "K_α range of the forced cases".to_string(),
                range(cov.k_alpha_range),
            ),
            (
                "pitch amplitude range [deg]".to_string(),
                range(cov.amplitude_alpha_deg_range),
            ),
            (
                "runs outside (margin)".to_string(),
                format!("{outside} of {} ({})", cov.runs.len(), pct(cov.margin)),
            ),
            (
                "share of the gap's excess in runs outside".to_string(),
                pct(cov.extrapolated_share),
            ),
            (
                "gap statistic of the covered runs alone".to_string(),
                cov.covered_gap_statistic
                    .map_or("no run covered".into(), num),
            ),
            (
                "gap, tables extended by straight lines".to_string(),
                format!(
                    "{} ({}× noise)",
                    num(cov.linear_before),
                    short(cov.linear_gap_statistic)
                ),
            ),
            (
                "gap, Theodorsen-shaped tails".to_string(),
                match (cov.tails_before, cov.tails_shrink) {
                    (Some(t), Some(s)) => format!("{} (shrink {})", num(t), pct(s)),
                    _ => "–".into(),
                },
            ),
            (
                "tails' apparent heave mass (flat plate πρb²)".to_string(),
                match (cov.tails_apparent_mass, cov.plate_apparent_mass) {
                    (Some(m), Some(p)) => format!("{} kg/m ({} kg/m)", num(m), num(p)),
                    _ => "–".into(),
                },
            ),
            (
                "tables the candidates used".to_string(),
                cov.sim_tables.replace('_', " "),
            ),
            (
                "put down to extrapolation".to_string(),
                yes(cov.explains_gap),
            ),
        ],
    );
    let opt = |v: Option<f64>| v.map_or("–".to_string(), short);
    let rows: Vec<Vec<String>> = cov
        .runs
        .iter()
        .map(|r| {
            vec![
                r.id.clone(),
                short(r.wind_speed),
                opt(r.k_h),
                opt(r.k_alpha),
                short(r.amplitude_alpha_deg),
                num(r.before),
                yes(r.covered),
                r.outside.join("; "),
            ]
        })
        .collect();
    report.table(
        "Each free run: response reduced frequency K = B·2πf/U per DOF, pitch amplitude, held-out gap",
        &[
            "run",
            "U [m/s]",
            "K_h",
            "K_α",
            "α amplitude [deg]",
            "gap",
            "covered",
            "outside the range",
        ]
        .map(String::from),
        &rows,
    );
    if !cov.suggestions.is_empty() {
        let rows: Vec<Vec<String>> = cov
            .suggestions
            .iter()
            .map(|s| {
                vec![
                    s.run.clone(),
                    s.dof.clone(),
                    s.configuration.clone(),
                    short(s.frequency_hz),
                    short(s.wind_speed),
                    short(s.amplitude_alpha_deg),
                    short(s.k),
                ]
            })
            .collect();
        report.table(
            "Forced cases that would cover the runs outside (the configuration's forcing frequency at the wind speed giving the run's K)",
            &[
                "run",
                "DOF",
                "configuration",
                "f [Hz]",
                "U [m/s]",
                "α amplitude [deg]",
                "K",
            ]
            .map(String::from),
            &rows,
        );
    }
}

/// The whole diagnosis report (title with the verdict, then [`diagnosis_section`]).
pub fn diagnosis_report(diag: &Diagnosis, figures: &[DiagnosisFigure]) -> Report {
    let mut r = Report::new(format!("aeroform diagnosis: {}", diag.verdict.effect));
    diagnosis_section(&mut r, diag, figures);
    r
}

/// Writes the diagnosis figures into `<out_dir>/figures/` (created if missing) and the
/// self-contained `<out_dir>/diagnosis.html` with the figures inline, every file
/// atomically. Returns the written paths (PNG and SVG of each figure, then the HTML).
/// Figures without data are skipped and named in the report.
///
/// # Errors
/// [`crate::Error::Write`] naming the folder or file when `out_dir` is missing or not
/// writable.
pub fn write_diagnosis_outputs(diag: &Diagnosis, out_dir: &Path) -> Result<Vec<PathBuf>> {
    let fig_dir = out_dir.join(FIGURES_DIR);
    if !out_dir.is_dir() {
        return Err(identify::Error::Io {
            path: out_dir.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "output folder missing"),
        }
        .into());
    }
    identify::io::create_dir_below(out_dir, Path::new(FIGURES_DIR))?;
    let figures = save_diagnosis_figures(diag, &fig_dir)?;
    let html = out_dir.join(DIAGNOSIS_HTML);
    diagnosis_report(diag, &figures).write(&html)?;
    let mut paths: Vec<PathBuf> = figures
        .iter()
        .flat_map(|f| [f.files.png.clone(), f.files.svg.clone()])
        .collect();
    paths.push(html);
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_numbers_are_short_and_nan_is_a_dash() {
        assert_eq!(num(0.025), "0.02500");
        assert_eq!(num(6.0), "6.000");
        assert_eq!(num(1.5e6), "1.500e6");
        assert_eq!(num(f64::NAN), "–");
        assert_eq!(pct(0.7917), "79.2\u{a0}%");
        assert_eq!(pct(f64::INFINITY), "–");
        assert_eq!(range([4.0, 10.0]), "4–10");
        assert_eq!(range([7.0, 7.0]), "7");
    }
}
