//! Figures and the HTML report, drawn from the result files of an output folder only (so
//! `aeroform plot OUTDIR` redraws them without recomputing).

use std::path::Path;

use crate::adapters::aeroelastic::{
    amplitude_intervals, bifurcation_figure, flutter_interval, phase_figure, vg_figure, AxisScale,
};
use crate::adapters::identification::{
    delta_path_figure, derivative_figure, heatmap_figures, library_figure, mean_angle_figure,
    quality_histogram, spectrum_figure, time_series_figure, Force,
};
use crate::adapters::term_label;
use crate::{column_label, Figure, Report, Series, SeriesKind, TimePanel, TimeSeriesFigure};
use identify::pipeline::Identification;
use identify::record::CaseMeta;
use identify::series::CaseSeries;
use serde::{Deserialize, Serialize};

use crate::error::{Context, Error, Result};

use aeroelastic::aero::Channel;
use aeroelastic::documents::{FlutterDoc, LcoDoc};
use study::documents::run_model;
use study::files::{read_json, write_json};
use study::paper::{DeltaFit, DeltaFits, ForceDecomposition, ForceLoop, LoopSet, PaperFigures};
use study::run::names;
use study::spec::{Study, StudyModel};

/// One drawn figure, as listed in `figures.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FigureEntry {
    /// Figure kind (one of `spec::FIGURE_KINDS`).
    pub kind: String,
    /// File stem under `figures/` (`.png` and `.svg`).
    pub stem: String,
    /// Caption in the report.
    pub caption: String,
}

struct Drawn {
    entry: FigureEntry,
    svg: String,
}

struct Canvas<'a> {
    dir: &'a Path,
    kinds: Vec<String>,
    drawn: Vec<Drawn>,
}

impl Canvas<'_> {
    fn wants(&self, kind: &str) -> bool {
        self.kinds.iter().any(|k| k == kind)
    }

    fn draw<F: Figure>(&mut self, kind: &str, stem: &str, caption: String, fig: &F) -> Result<()> {
        let files =
            crate::save(fig, self.dir, stem).with_context(|| format!("drawing figure {stem}"))?;
        self.drawn.push(Drawn {
            entry: FigureEntry {
                kind: kind.into(),
                stem: stem.into(),
                caption,
            },
            svg: files.svg_text,
        });
        Ok(())
    }

    /// Embeds every figure of `kind` drawn so far into the report.
    fn embed(&self, report: &mut Report, kind: &str) {
        for d in self.drawn.iter().filter(|d| d.entry.kind == kind) {
            report.figure_svg(d.entry.caption.clone(), &d.svg);
        }
    }
}

fn safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// A number cell for the report: 5 significant digits (scientific outside 1e-3..1e5);
/// other cells unchanged.
fn pretty_cell(c: &str) -> String {
    match c.parse::<f64>() {
        Ok(0.0) => "0".into(),
        Ok(v) if v.is_finite() && (c.contains('.') || c.contains('e')) => {
            let a = v.abs();
            if (1e-3..1e5).contains(&a) {
                let digits = (4 - a.log10().floor() as i32).max(0) as usize;
                format!("{v:.digits$}")
            } else {
                format!("{v:.4e}")
            }
        }
        _ => c.to_string(),
    }
}

/// CSV text with its number cells shortened by [`pretty_cell`] (the files keep full
/// precision).
fn pretty_csv(text: &str) -> Vec<Vec<String>> {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            crate::report::split_csv_line(l)
                .iter()
                .map(|c| pretty_cell(c))
                .collect()
        })
        .collect()
}

/// Adds a result CSV file of `out` to the report as a table with shortened numbers and
/// display headers ([`column_label`]).
fn csv_file_table(report: &mut Report, caption: &str, path: &Path, reduced: bool) {
    csv_file_columns(report, caption, path, None, reduced);
}

/// The display header of a column; `U_m_s` becomes `U/(bω_α)` when the study's speeds are
/// reduced (the files keep the column name, the values are then U/(bω_α)).
fn header_label(name: &str, reduced: bool) -> String {
    match name {
        "U_m_s" if reduced => "U/(bω_α)".into(),
        _ => column_label(name),
    }
}

/// As [`csv_file_table`], keeping only the columns named in `keep` (in file order).
fn csv_file_columns(
    report: &mut Report,
    caption: &str,
    path: &Path,
    keep: Option<&[String]>,
    reduced: bool,
) {
    if let Ok(t) = std::fs::read_to_string(path) {
        let rows = pretty_csv(&t);
        if let Some((header, body)) = rows.split_first() {
            let idx: Vec<usize> = (0..header.len())
                .filter(|&i| keep.is_none_or(|k| k.contains(&header[i])))
                .collect();
            let pick = |r: &Vec<String>| -> Vec<String> {
                idx.iter()
                    .map(|&i| r.get(i).cloned().unwrap_or_default())
                    .collect()
            };
            let body: Vec<Vec<String>> = body.iter().map(pick).collect();
            let header: Vec<String> = pick(header)
                .iter()
                .map(|h| header_label(h, reduced))
                .collect();
            let caption = format!(
                "{caption} — {}",
                path.file_name()
                    .map(|f| f.to_string_lossy().into_owned())
                    .unwrap_or_default()
            );
            report.table(caption, &header, &body);
        } else {
            report.text(format!("{caption}: the file {} is empty.", path.display()));
        }
    } else {
        report.text(format!(
            "{caption}: {} was not written by this study.",
            path.file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default()
        ));
    }
}

/// A JSON value as readable text: strings without quotes, objects as `key: value` pairs,
/// arrays comma-separated, null as "—".
fn readable(v: &serde_json::Value) -> String {
    use serde_json::Value;
    match v {
        Value::Null => "—".into(),
        Value::String(s) => s.clone(),
        Value::Array(a) if a.is_empty() => "none".into(),
        Value::Array(a) => a.iter().map(readable).collect::<Vec<_>>().join(", "),
        Value::Object(o) if o.is_empty() => "—".into(),
        Value::Object(o) => o
            .iter()
            .map(|(k, v)| format!("{k}: {}", readable(v)))
            .collect::<Vec<_>>()
            .join("; "),
        other => other.to_string(),
    }
}

/// The result files of `out` (not the report itself), relative paths, sorted: JSON and CSV
/// at the top level, the study file, then the figure files.
fn result_files(out: &Path) -> Vec<String> {
    let mut files = vec![];
    if let Ok(rd) = std::fs::read_dir(out) {
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let p = e.path();
            if p.is_file()
                && name != names::REPORT
                && name != names::FIGURE_LIST
                && !name.starts_with('.')
            {
                files.push(name);
            }
        }
    }
    // written right after the report is assembled; listed always so that `run` and `plot`
    // write the same page
    files.push(names::FIGURE_LIST.to_string());
    files.sort();
    if let Ok(rd) = std::fs::read_dir(out.join(names::SERIES)) {
        let mut v: Vec<String> = rd
            .flatten()
            .map(|e| format!("{}/{}", names::SERIES, e.file_name().to_string_lossy()))
            .collect();
        v.sort();
        files.extend(v);
    }
    files
}

/// The report section listing every result file and figure file as a link.
fn files_section(report: &mut Report, out: &Path, figures: &[FigureEntry]) {
    report.section("Files");
    report.text(
        "Every number in this report comes from these files (formats: docs/DATA_FORMAT.md); \
         links are relative to the report's folder.",
    );
    let files: Vec<(String, String)> = result_files(out)
        .into_iter()
        .map(|f| (f.clone(), f))
        .collect();
    report.links("Result files", &files);
    let figs: Vec<(String, String)> = figures
        .iter()
        .flat_map(|f| {
            ["png", "svg"].map(|ext| {
                let p = format!("{}/{}.{ext}", names::FIGURES, f.stem);
                (p.clone(), p)
            })
        })
        .collect();
    report.links("Figure files (PNG and SVG)", &figs);
}

/// The truth-vs-model table of `round_trip.csv` with the divergence speeds of the truth and
/// model flutter runs (from `flutter.json`) as a row after the flutter speed.
fn round_trip_table(report: &mut Report, out: &Path, reduced: bool) -> Result<()> {
    let path = out.join(names::ROUND_TRIP);
    let text = identify::io::read_text(&path).map_err(|source| Error::Io {
        context: format!("reading {}", path.display()),
        source,
    })?;
    let mut rows = pretty_csv(&text);
    if rows.is_empty() {
        report.text(format!("{} is empty.", names::ROUND_TRIP));
        return Ok(());
    }
    let runs: Vec<FlutterDoc> = if out.join(names::FLUTTER).exists() {
        read_json(&out.join(names::FLUTTER))?
    } else {
        vec![]
    };
    let truth = runs
        .iter()
        .find(|r| run_model(r) == Some(StudyModel::Truth));
    let model = runs
        .iter()
        .find(|r| run_model(r) != Some(StudyModel::Truth));
    if let (Some(t), Some(m)) = (truth, model) {
        let (td, md) = (t.analysis.divergence_speed, m.analysis.divergence_speed);
        let cell =
            |v: Option<f64>| v.map_or("none".to_string(), |x| pretty_cell(&format!("{x:e}")));
        let rel = match (td, md) {
            (Some(a), Some(b)) if a != 0.0 => pretty_cell(&format!("{:e}", b / a - 1.0)),
            _ => String::new(),
        };
        let at = rows
            .iter()
            .position(|r| r.first().is_some_and(|c| c == "flutter_speed_m_s"))
            .map_or(1, |i| i + 1);
        rows.insert(
            at,
            vec![
                "divergence_speed_m_s".into(),
                String::new(),
                cell(td),
                cell(md),
                rel,
            ],
        );
    }
    let header: Vec<String> = rows[0].iter().map(|h| header_label(h, reduced)).collect();
    let body: Vec<Vec<String>> = rows[1..]
        .iter()
        .map(|r| {
            r.iter()
                .enumerate()
                .map(|(i, c)| if i == 0 { column_label(c) } else { c.clone() })
                .collect()
        })
        .collect();
    report.table(
        format!(
            "Truth vs model: flutter and divergence speeds, LCO amplitudes — {} (divergence from {})",
            names::ROUND_TRIP,
            names::FLUTTER
        ),
        &header,
        &body,
    );
    Ok(())
}

/// Refuses a case series whose arrays do not pair up (an edited or damaged result file that
/// `plot` reads), naming the file and the field, before a figure is drawn from it.
fn check_series(x: &CaseSeries, path: &Path) -> Result<()> {
    let (n, m) = (x.t.len(), x.freq.len());
    let fields = [
        ("alpha_deg", x.alpha_deg.len(), "t", n),
        ("h_mm", x.h_mm.len(), "t", n),
        ("c_lift", x.c_lift.len(), "t", n),
        ("c_lift_model", x.c_lift_model.len(), "t", n),
        ("c_moment", x.c_moment.len(), "t", n),
        ("c_moment_model", x.c_moment_model.len(), "t", n),
        ("lift_spectrum", x.lift_spectrum.len(), "freq", m),
        (
            "lift_model_spectrum",
            x.lift_model_spectrum.len(),
            "freq",
            m,
        ),
        ("moment_spectrum", x.moment_spectrum.len(), "freq", m),
        (
            "moment_model_spectrum",
            x.moment_model_spectrum.len(),
            "freq",
            m,
        ),
    ];
    for (field, len, of, want) in fields {
        if len != want {
            return Err(Error::Io {
                context: format!("reading {}", path.display()),
                source: identify::io::input_error(
                    std::io::ErrorKind::InvalidData,
                    format!("field `{field}`: {len} values where `{of}` has {want}"),
                ),
            });
        }
    }
    Ok(())
}

/// Draws every figure of the study from the results in `out`, writes `figures.json` and
/// `report.html`; returns the figure list. `version` is the text of the report's
/// `version` row (the binary's `aeroform <version> (<git describe>)`).
///
/// # Errors
/// A missing or malformed result file ([`Error::Study`], naming it), a figure that cannot
/// be drawn ([`Error::Context`] naming the figure), a write failure.
pub fn render_all(study: &Study, out: &Path, version: &str) -> Result<Vec<FigureEntry>> {
    render_all_from(study, out, out, version)
}

/// [`render_all`] reading the result files from `src` and writing the figures,
/// `figures.json` and the report into `out` (`aeroform plot` redraws a finished folder in a
/// staging copy: a refusal of a result file names the folder the user gave, not the staging
/// copy that is gone when the message is read, issue 39 row 7).
///
/// # Errors
/// As [`render_all`].
pub fn render_all_from(
    study: &Study,
    src: &Path,
    out: &Path,
    version: &str,
) -> Result<Vec<FigureEntry>> {
    let dir = out.join(names::FIGURES);
    identify::io::create_dir_below(out, Path::new(names::FIGURES))?;
    let mut cv = Canvas {
        dir: &dir,
        kinds: study.figure_kinds(),
        drawn: vec![],
    };
    let s = &study.spec;
    let reduced = s
        .flutter
        .as_ref()
        .is_some_and(|f| f.axes == study::spec::Axes::Reduced);
    let mut report = Report::new(format!("aeroform study: {}", s.name));
    report.section("Summary");
    if !s.description.is_empty() {
        report.text(s.description.clone());
    }
    let mut summary: Vec<(String, String)> = vec![
        ("study".into(), s.name.clone()),
        ("seed".into(), s.seed.to_string()),
        ("version".into(), version.to_string()),
    ];

    // ---- identification
    let id_path = src.join(names::IDENTIFICATION);
    let id: Option<Identification> = if s.data.is_some() {
        Some(
            Identification::read(&id_path)
                .with_context(|| format!("reading {}", id_path.display()))?,
        )
    } else {
        None
    };
    if let Some(id) = &id {
        summary.push(("data".into(), id.dataset.clone()));
        summary.push(("cases identified".into(), id.cases.len().to_string()));
        summary.push((
            "library rank".into(),
            format!("{} of {} terms", id.library.rank, id.library.terms.len()),
        ));
    }
    report.key_values("Study", &summary);

    if let Some(id) = &id {
        identification_section(&mut cv, &mut report, study, src, id)?;
    }
    let flutter_runs = flutter_section(&mut cv, &mut report, study, src)?;
    lco_section(&mut cv, &mut report, study, src, &flutter_runs, reduced)?;

    // ---- LCO branches by continuation
    if s.branch.is_some() {
        branch_section(&mut cv, &mut report, src, s.lco.is_some())?;
    }

    // ---- settings
    report.section("Settings");
    if let Some(id) = &id {
        let v = serde_json::to_value(&id.settings)?;
        let rows: Vec<(String, String)> = v
            .as_object()
            .map(|o| {
                o.iter()
                    .map(|(k, v)| (k.replace('_', " "), readable(v)))
                    .collect()
            })
            .unwrap_or_default();
        report.key_values("Identification settings", &rows);
    }
    report.pre(
        format!("Study file as run ({})", names::STUDY),
        study.text.clone(),
    );

    let entries: Vec<FigureEntry> = cv.drawn.iter().map(|d| d.entry.clone()).collect();
    files_section(&mut report, out, &entries);
    write_json(&out.join(names::FIGURE_LIST), &entries)?;
    report
        .write(&out.join(names::REPORT))
        .context("writing report.html")?;
    Ok(entries)
}

/// The identification's figures and tables of the study report (time series, spectra,
/// force decomposition, library, δ fits and paths, heatmaps, mean angle, histogram,
/// derivatives; coefficient and case tables).
fn identification_section(
    cv: &mut Canvas<'_>,
    report: &mut Report,
    study: &Study,
    src: &Path,
    id: &Identification,
) -> Result<()> {
    let s = &study.spec;
    let metas: Vec<CaseMeta> = read_json(&src.join(names::CASES))?;
    // series figures
    let mut series: Vec<CaseSeries> = vec![];
    let sdir = src.join(names::SERIES);
    let wanted: Vec<String> = if s.outputs.series_cases.is_empty() {
        let mut v = vec![metas[0].id.clone()];
        if metas.len() > 1 {
            v.push(metas[metas.len() - 1].id.clone());
        }
        v
    } else {
        s.outputs.series_cases.clone()
    };
    for w in &wanted {
        let path = sdir.join(format!("{w}.json"));
        let x: CaseSeries = read_json(&path)?;
        check_series(&x, &path)?;
        series.push(x);
    }
    if cv.wants("time_series") {
        for x in &series {
            cv.draw(
                "time_series",
                &format!("time_series_{}", safe(&x.id)),
                format!(
                    "Case {}: prescribed motion and measured forces (solid) with the identified model (dashed), first {} s.",
                    x.id,
                    x.t.last().copied().unwrap_or(0.0).round()
                ),
                &time_series_figure(x),
            )?;
        }
    }
    if cv.wants("spectrum") {
        for x in &series {
            for f in [Force::Moment, Force::Lift] {
                cv.draw(
                    "spectrum",
                    &format!("spectrum_{}_{}", safe(&x.id), f.name()),
                    format!(
                        "Case {}: amplitude spectrum of {} (Hann window), measured and identified model; the key frequencies of the Eq. 14 loss are marked.",
                        x.id,
                        f.symbol()
                    ),
                    &spectrum_figure(x, f),
                )?;
            }
        }
    }
    let paper: Option<PaperFigures> = src
        .join(names::PAPER_FIGURES)
        .exists()
        .then(|| read_json(&src.join(names::PAPER_FIGURES)))
        .transpose()?;
    let paper = paper.unwrap_or_default();
    if cv.wants("force_decomposition") {
        for f in &paper.forces {
            cv.draw(
                "force_decomposition",
                &format!("force_decomposition_{}", safe(&f.id)),
                format!(
                    "Case {} (U = {} m/s): balance forces with wind (solid), of the still-air run of the same motion (inertia of the model and balance), and their difference, the aerodynamic force that is identified (dashed); first {} s (paper Figs. 4/5).",
                    f.id,
                    pretty_cell(&format!("{}", f.wind_speed)),
                    f.t.last().copied().unwrap_or(0.0).round()
                ),
                &force_decomposition_figure(f),
            )?;
        }
    }
    if cv.wants("library") {
        cv.draw(
            "library",
            "library",
            format!(
                "The candidate library (paper Fig. 6): {} polynomial terms in α, Bα'/U, h/B and h'/U up to third order; per group and force, the selected terms, the identifiable ones and those that are linear combinations of others on the group's motion (numerical rank {}).",
                id.library.terms.len(),
                id.library.rank
            ),
            &library_figure(id),
        )?;
    }
    if cv.wants("delta_fits") {
        for d in &paper.delta_fits {
            cv.draw(
                "delta_fits",
                &format!("delta_fits_{}_{}", safe(&d.group), d.force.name()),
                format!(
                    "Group {}, case {}, {}: measured (solid) and least-squares fits (dashed) of the supports at a high δ ({} terms, R² {}), the selected δ ({} terms, R² {}) and a low δ ({} terms, R² {}) of the path (paper Figs. 7/8; coefficients in Table III below).",
                    d.group,
                    d.case,
                    d.force.name(),
                    d.fits[0].coefficients.len(),
                    pretty_cell(&format!("{:.4}", d.fits[0].r2)),
                    d.fits[1].coefficients.len(),
                    pretty_cell(&format!("{:.4}", d.fits[1].r2)),
                    d.fits[2].coefficients.len(),
                    pretty_cell(&format!("{:.4}", d.fits[2].r2)),
                ),
                &delta_fits_figure(d),
            )?;
        }
    }
    if cv.wants("force_loops") {
        for set in &paper.loops {
            cv.draw(
                "force_loops",
                &format!(
                    "force_loops_{}_{}",
                    safe(&set.config),
                    set.varied.replace(' ', "_")
                ),
                format!(
                    "Configuration {}, {}: lift and moment coefficients against pitch over the last two forcing periods, across {} (paper Figs. {}).",
                    set.config,
                    set.fixed,
                    set.varied,
                    if set.varied == "wind speed" { "14" } else { "15" }
                ),
                &force_loops_figure(set),
            )?;
        }
    }
    if cv.wants("delta_path") {
        let groups: Vec<String> = if s.outputs.delta_groups.is_empty() {
            id.groups.iter().take(4).map(|g| g.name.clone()).collect()
        } else {
            s.outputs.delta_groups.clone()
        };
        for g in &groups {
            for f in [Force::Moment, Force::Lift] {
                if let Some(fig) = delta_path_figure(id, g, f) {
                    cv.draw(
                        "delta_path",
                        &format!("delta_path_{}_{}", safe(g), f.name()),
                        format!(
                            "Group {g}, {}: number of terms and key-frequency loss along the δ path (Alg. 3); the sparsest support under the loss limit is selected.",
                            f.name()
                        ),
                        &fig,
                    )?;
                }
            }
        }
    }
    if cv.wants("heatmap") {
        for f in [Force::Moment, Force::Lift] {
            for (config, fig) in heatmap_figures(id, &metas, f) {
                cv.draw(
                    "heatmap",
                    &format!("heatmap_{}_{}", safe(&config), f.name()),
                    format!(
                        "Configuration {config}: Eq. 19 coefficients of {} over pitch amplitude × wind speed, one layer per coefficient; grey cells: term inactive.",
                        f.symbol()
                    ),
                    &fig,
                )?;
            }
        }
    }
    // the reference curves about the virtual truth's elastic axis, when there is one
    let elastic_axis = if cv.wants("mean_angle") || cv.wants("derivatives") {
        truth_axis(study)
    } else {
        0.0
    };
    if cv.wants("mean_angle") {
        if let Some(fig) = mean_angle_figure(id, &metas, elastic_axis) {
            cv.draw(
                "mean_angle",
                "mean_angle",
                format!("Identified flutter derivatives of the configurations forced about a mean angle of attack next to the same motion at zero mean (paper Fig. 28), with Theodorsen about a = {elastic_axis} (a zero-mean, small-amplitude reference)."),
                &fig,
            )?;
        }
    }
    if cv.wants("histogram") {
        cv.draw(
            "histogram",
            "histogram_quality",
            "Misfit of every case, moment and lift: 1 − R² and |1 − MFWA| (Eq. 18).".into(),
            &quality_histogram(id),
        )?;
    }
    if cv.wants("derivatives") {
        cv.draw(
            "derivatives",
            "derivatives",
            format!("Identified flutter derivatives against reduced frequency (h-terms at K_h, α-terms at K_α) with the thin-plate Theodorsen derivatives about the truth's elastic axis a = {elastic_axis} (0 when the data do not say)."),
            &derivative_figure(id, elastic_axis),
        )?;
    }

    report.section("Identification");
    let mut rows = vec![];
    for g in &id.groups {
        for (name, gf) in [("moment", &g.moment), ("lift", &g.lift)] {
            rows.push(vec![
                g.name.clone(),
                name.to_string(),
                g.cases.len().to_string(),
                gf.support.len().to_string(),
                gf.support
                    .iter()
                    .map(|t| term_label(t))
                    .collect::<Vec<_>>()
                    .join(", "),
                format!("{:.3e}", gf.loss),
                format!("{:.3e}", gf.loss_limit),
            ]);
        }
    }
    report.table(
        "Selected supports per group",
        &[
            "group",
            "force",
            "cases",
            "terms",
            "support",
            "loss",
            "loss limit",
        ]
        .map(String::from),
        &rows,
    );
    for d in &paper.delta_fits {
        table_iii(report, d);
    }
    if src.join(names::TABLE_IV).exists() {
        csv_file_table(
            report,
            "Table IV: identified vs true coefficients over the noise realisations",
            &src.join(names::TABLE_IV),
            false,
        );
    }
    if id.cases.len() <= 64 {
        csv_file_columns(
            report,
            &format!(
                "Eq. 19 flutter derivatives per case (N* and the other metrics in {})",
                names::DERIVATIVES
            ),
            &src.join(names::DERIVATIVES),
            Some(
                &["case", "U_m_s", "amplitude_deg", "K_alpha", "K_h"]
                    .into_iter()
                    .map(String::from)
                    .chain(names::derivative_columns(true))
                    .chain(["R2_lift".into(), "R2_moment".into()])
                    .collect::<Vec<String>>(),
            ),
            false, // the data set's wind speeds are in m/s
        );
    } else {
        report.text(format!(
            "{} cases: the per-case table is in {} and {}.",
            id.cases.len(),
            names::DERIVATIVES,
            names::COEFFICIENTS
        ));
    }
    for k in [
        "time_series",
        "spectrum",
        "force_decomposition",
        "library",
        "delta_fits",
        "force_loops",
        "mean_angle",
        "delta_path",
        "histogram",
        "heatmap",
        "derivatives",
    ] {
        cv.embed(report, k);
    }
    Ok(())
}

/// The flutter runs' V–g figures and tables of the study report; returns the runs (the LCO
/// section's figure takes the identified model's flutter-speed interval from them).
fn flutter_section(
    cv: &mut Canvas<'_>,
    report: &mut Report,
    study: &Study,
    src: &Path,
) -> Result<Option<Vec<FlutterDoc>>> {
    let s = &study.spec;
    let flutter_runs: Option<Vec<FlutterDoc>> = s
        .flutter
        .is_some()
        .then(|| read_json(&src.join(names::FLUTTER)))
        .transpose()?;
    if let (Some(f), Some(runs)) = (&s.flutter, &flutter_runs) {
        if cv.wants("vg") {
            for (i, r) in runs.iter().enumerate() {
                let label = r.label.as_deref().unwrap_or_default();
                let mut scale = if f.axes == study::spec::Axes::Reduced {
                    AxisScale::reduced(0.5 * r.chord, r.omega_alpha)
                } else {
                    AxisScale::si()
                };
                scale.damping_g = f.damping == study::spec::DampingAxis::G;
                cv.draw(
                    "vg",
                    &format!("vg_{i}"),
                    format!(
                        "{}: damping ratio and frequency of the aeroelastic modes against wind speed.{}",
                        label,
                        r.ensemble.as_ref().map_or(String::new(), |e| format!(
                            " Shaded band and error bar: the flutter speed's {} % interval over {} block-bootstrap members of the identification ({} with flutter in the scan).",
                            pretty_cell(&format!("{}", 100.0 * e.level)),
                            e.members,
                            e.flutter_speed.found
                        ))
                    ),
                    &crate::VgFigure {
                        flutter_interval: r
                            .ensemble
                            .as_ref()
                            .and_then(|e| flutter_interval(e, &scale)),
                        ..vg_figure(&r.analysis, &format!("V–g / V–f: {label}"), &scale)
                    },
                )?;
            }
        }
        report.section("Flutter");
        // compact view; every column is in flutter_points.csv
        let cell = |v: Option<f64>| v.map_or(String::new(), |x| pretty_cell(&format!("{x:e}")));
        let rows: Vec<Vec<String>> = runs
            .iter()
            .map(|r| {
                let scale = 0.5 * r.chord * r.omega_alpha;
                let fl = r.analysis.flutter;
                let ud = r.analysis.divergence_speed.map(|u| u / scale);
                let rf = r.reference;
                let rel = match (fl, rf.and_then(|x| x.u_reduced)) {
                    (Some(f), Some(x)) => Some((f.u_reduced - x) / x),
                    _ => None,
                };
                vec![
                    r.label.clone().unwrap_or_default(),
                    cell(fl.map(|f| f.u_reduced)),
                    cell(fl.map(|f| f.omega_ratio)),
                    cell(ud),
                    cell(rf.and_then(|x| x.u_reduced)),
                    cell(rf.and_then(|x| x.omega_ratio)),
                    cell(rf.and_then(|x| x.divergence)),
                    cell(rel),
                ]
            })
            .collect();
        report.table(
            format!(
                "Flutter and divergence (U/(bω_α), ω/ω_α; all columns in {})",
                names::FLUTTER_POINTS
            ),
            &[
                "run",
                "U_F",
                "ω_F/ω_α",
                "U_D",
                "published U_F",
                "published ω_F/ω_α",
                "published U_D",
                "rel. error U_F",
            ]
            .map(String::from),
            &rows,
        );
        ensemble_flutter_table(report, runs);
        cv.embed(report, "vg");
    }
    Ok(flutter_runs)
}

/// The LCO runs' figures (sweeps, truth sweeps, phase portraits) and tables of the study
/// report.
fn lco_section(
    cv: &mut Canvas<'_>,
    report: &mut Report,
    study: &Study,
    src: &Path,
    flutter_runs: &Option<Vec<FlutterDoc>>,
    reduced: bool,
) -> Result<()> {
    let s = &study.spec;
    if let Some(l) = &s.lco {
        let stage: LcoDoc = read_json(&src.join(names::LCO))?;
        let empty = aeroelastic::lco::Hysteresis {
            up: vec![],
            down: vec![],
        };
        let sweep = stage.sweep.as_ref().unwrap_or(&empty);
        let scale = if s
            .flutter
            .as_ref()
            .is_some_and(|f| f.axes == study::spec::Axes::Reduced)
        {
            AxisScale::reduced(0.5 * stage.chord, stage.omega_alpha)
        } else {
            AxisScale::si()
        };
        if cv.wants("bifurcation") {
            let mut fig = bifurcation_figure(
                &sweep.up,
                &sweep.down,
                stage.flutter_speed,
                "LCO sweeps",
                &scale,
            );
            let mut caption = format!(
                "LCO pitch amplitude against wind speed, upward (▲) and downward (▼) sweeps{}; model: {}.",
                if stage.flutter_speed.is_some() { ", linear flutter speed marked" } else { "" },
                stage.model_name
            );
            if let Some(e) = &stage.ensemble {
                (fig.intervals, fig.interval_label) = amplitude_intervals(e, &scale);
                // the identified model's flutter run carries the flutter-speed interval
                fig.flutter_interval = flutter_runs
                    .iter()
                    .flatten()
                    .filter(|r| run_model(r) == Some(StudyModel::IDENTIFIED))
                    .find_map(|r| r.ensemble.as_ref())
                    .and_then(|e| flutter_interval(e, &scale));
                caption.push_str(&format!(
                    " Error bars: {} % interval of the pitch amplitude over the identification's {} block-bootstrap members that settle on an LCO (each run from the same perturbation; median as a tick); shaded: the flutter speed's interval. Values in {}.",
                    pretty_cell(&format!("{}", 100.0 * e.level)),
                    e.members,
                    names::LCO_INTERVALS
                ));
            }
            cv.draw("bifurcation", "bifurcation", caption, &fig)?;
            if let Some(truth) = stage.truth.as_ref().filter(|t| !t.sweep.up.is_empty()) {
                cv.draw(
                    "bifurcation",
                    "bifurcation-truth",
                    "LCO pitch amplitude against wind speed of the truth model of the virtual campaign (same structure, same sweeps), truth linear flutter speed marked.".to_string(),
                    &bifurcation_figure(
                        &truth.sweep.up,
                        &truth.sweep.down,
                        truth.flutter_speed,
                        "LCO sweeps of the truth model",
                        &scale,
                    ),
                )?;
            }
        }
        if cv.wants("phase") && !stage.phase.is_empty() {
            cv.draw(
                "phase",
                "phase",
                format!(
                    "Phase portraits of the limit cycles ({} pitch periods from the end of the upward-sweep run).",
                    l.phase_periods
                ),
                &phase_figure(&stage.phase, "Limit cycles: pitch phase portraits", &scale),
            )?;
        }
        report.section("Limit-cycle oscillations");
        csv_file_table(
            report,
            "LCO runs",
            &src.join(names::LCO_AMPLITUDES),
            reduced,
        );
        if l.compare_truth {
            round_trip_table(report, src, reduced)?;
        }
        if stage.ensemble.is_some() {
            csv_file_table(
                report,
                "LCO amplitude intervals over the identification ensemble",
                &src.join(names::LCO_INTERVALS),
                reduced,
            );
        }
        cv.embed(report, "bifurcation");
        cv.embed(report, "phase");
    }
    Ok(())
}

/// Elastic axis a of the virtual truth, when the data come from one (0 otherwise).
fn truth_axis(study: &Study) -> f64 {
    study
        .spec
        .data
        .as_ref()
        .and_then(|d| d.virtual_tunnel.as_ref())
        .and_then(|v| study::build::virtual_model(study, v, 0.25).ok())
        .and_then(|m| m.elastic_axis())
        .unwrap_or(0.0)
}

/// Paper Figs. 4/5: wind-on, still-air and aerodynamic (difference) lift and moment.
fn force_decomposition_figure(f: &ForceDecomposition) -> TimeSeriesFigure {
    let panel = |name: &str, unit: &str, on: &[f64], still: &[f64]| TimePanel {
        y_label: format!("{name} [{unit}]"),
        series: vec![
            Series::new("wind on", SeriesKind::Measured, f.t.clone(), on.to_vec()),
            Series::new("still air", SeriesKind::Other, f.t.clone(), still.to_vec()),
            Series::new(
                "aerodynamic (difference)",
                SeriesKind::Model,
                f.t.clone(),
                on.iter().zip(still).map(|(a, b)| a - b).collect(),
            ),
        ],
    };
    TimeSeriesFigure {
        title: format!("Force decomposition: case {}", f.id),
        x_label: "t [s]".into(),
        panels: vec![
            panel("lift L", "N/m", &f.lift_wind_on, &f.lift_still_air),
            panel("moment M", "N·m/m", &f.moment_wind_on, &f.moment_still_air),
        ],
    }
}

/// Paper Figs. 7/8: the case's measured coefficient against the fits at three δ.
fn delta_fits_figure(d: &DeltaFits) -> TimeSeriesFigure {
    let symbol = match d.force {
        Channel::Lift => "C_L",
        Channel::Moment => "C_M",
    };
    TimeSeriesFigure {
        title: format!(
            "Fits along the δ path: group {}, case {}, {symbol}",
            d.group, d.case
        ),
        x_label: "t [s]".into(),
        panels: d
            .fits
            .iter()
            .map(|f| TimePanel {
                y_label: format!("{symbol}, {} ({} terms)", f.label, f.coefficients.len()),
                series: vec![
                    Series::new(
                        "measured",
                        SeriesKind::Measured,
                        d.t.clone(),
                        d.measured.clone(),
                    ),
                    Series::new("fit", SeriesKind::Model, d.t.clone(), f.model.clone()),
                ],
            })
            .collect(),
    }
}

/// Paper Figs. 14/15: C_L and C_M against α, one loop per wind speed or amplitude.
fn force_loops_figure(set: &LoopSet) -> TimeSeriesFigure {
    let panel = |name: &str, pick: fn(&ForceLoop) -> &Vec<f64>| TimePanel {
        y_label: name.into(),
        series: set
            .loops
            .iter()
            .map(|l| {
                Series::new(
                    l.label.clone(),
                    SeriesKind::Other,
                    l.alpha_deg.clone(),
                    pick(l).clone(),
                )
            })
            .collect(),
    };
    TimeSeriesFigure {
        title: format!(
            "Configuration {} at {}: forces across {}",
            set.config, set.fixed, set.varied
        ),
        x_label: "α [deg]".into(),
        panels: vec![
            panel("C_L [-]", |l| &l.c_lift),
            panel("C_M [-]", |l| &l.c_moment),
        ],
    }
}

/// Table III: the terms and least-squares coefficients of the three supports of a δ fit.
fn table_iii(report: &mut Report, d: &DeltaFits) {
    let mut terms: Vec<&String> = d
        .fits
        .iter()
        .flat_map(|f| f.coefficients.iter().map(|(t, _)| t))
        .collect();
    terms.sort_by_key(|t| d.fits[2].coefficients.iter().position(|(x, _)| x == *t));
    terms.dedup();
    let mut rows: Vec<Vec<String>> = terms
        .iter()
        .map(|t| {
            let mut row = vec![term_label(t)];
            row.extend(d.fits.iter().map(|f| {
                f.coefficients
                    .iter()
                    .find(|(x, _)| x == *t)
                    .map_or(String::new(), |(_, c)| pretty_cell(&format!("{c:e}")))
            }));
            row
        })
        .collect();
    let mut last = |name: &str, v: &dyn Fn(&DeltaFit) -> String| {
        let mut row = vec![name.to_string()];
        row.extend(d.fits.iter().map(v));
        rows.push(row);
    };
    last("terms", &|f| f.coefficients.len().to_string());
    last("δ range", &|f| {
        format!(
            "{} … {}",
            pretty_cell(&format!("{:e}", f.delta[0])),
            pretty_cell(&format!("{:e}", f.delta[1]))
        )
    });
    last("R² (whole record)", &|f| {
        pretty_cell(&format!("{:.6}", f.r2))
    });
    let header: Vec<String> = std::iter::once("term".to_string())
        .chain(d.fits.iter().map(|f| f.label.clone()))
        .collect();
    report.table(
        format!(
            "Table III: supports of group {} at three δ of the path, least-squares coefficients of case {}, {} (empty: term not in the support)",
            d.group,
            d.case,
            d.force.name()
        ),
        &header,
        &rows,
    );
}

/// The intervals of the flutter runs that have an ensemble (`[identify] ensemble`): U_F,
/// f_F and U_D, median and interval, and how many members found each.
fn ensemble_flutter_table(report: &mut Report, runs: &[FlutterDoc]) {
    let rows: Vec<Vec<String>> = runs
        .iter()
        .filter_map(|r| r.ensemble.as_ref().map(|e| (r, e)))
        .flat_map(|(r, e)| {
            [
                ("U_F [m/s]", &e.flutter_speed),
                ("f_F [Hz]", &e.flutter_frequency_hz),
                ("U_D [m/s]", &e.divergence_speed),
            ]
            .map(|(name, q)| {
                let cell =
                    |v: Option<f64>| v.map_or("—".into(), |x| pretty_cell(&format!("{x:e}")));
                vec![
                    r.label.clone().unwrap_or_default(),
                    name.to_string(),
                    cell(q.interval.map(|i| i.median)),
                    cell(q.interval.map(|i| i.lower)),
                    cell(q.interval.map(|i| i.upper)),
                    format!("{} of {}", q.found, e.members),
                ]
            })
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    let level = runs
        .iter()
        .find_map(|r| r.ensemble.as_ref())
        .map_or(0.0, |e| e.level);
    report.table(
        format!(
            "Propagated identification uncertainty: {} % percentile intervals over the block-bootstrap members of the identified law (members without flutter or divergence in the scan are counted, not in the interval; columns U_F_lower_m_s … in {})",
            pretty_cell(&format!("{}", 100.0 * level)),
            names::FLUTTER_POINTS
        ),
        &["run", "quantity", "median", "lower", "upper", "members with it"].map(String::from),
        &rows,
    );
}

/// The `[branch]` section of the report from `branch.json` (and the upward LCO sweep of
/// `lco.json` on top of the branches when the study has an `[lco]` stage): the
/// bifurcation diagram and the table of Hopf points and folds.
fn branch_section(
    cv: &mut Canvas<'_>,
    report: &mut Report,
    out: &Path,
    with_sweep: bool,
) -> Result<()> {
    use aeroelastic::branch::{Branch, BranchOptions, BranchSet, HopfPoint, MeasuredDistance};
    #[derive(serde::Deserialize)]
    struct Settings {
        options: BranchOptions,
        u_range_m_s: [f64; 2],
    }
    #[derive(serde::Deserialize)]
    struct Doc {
        settings: Settings,
        hopf_points: Vec<HopfPoint>,
        branches: Vec<Branch>,
        measured: Vec<MeasuredDistance>,
    }
    let doc: Doc = read_json(&out.join(names::BRANCH))?;
    let set = BranchSet {
        hopf_points: doc.hopf_points,
        branches: doc.branches,
        options: doc.settings.options,
        u_range: doc.settings.u_range_m_s,
    };
    let sweep = if with_sweep {
        let stage: LcoDoc = read_json(&out.join(names::LCO))?;
        stage
            .sweep
            .map(|h| h.up)
            .unwrap_or_default()
            .iter()
            .filter(|r| r.classification == aeroelastic::lco::Classification::Lco)
            .map(|r| crate::DiagramPoint {
                u: r.u,
                amplitude: r.amplitude_alpha.to_degrees(),
                stable: true,
            })
            .collect()
    } else {
        Vec::new()
    };
    let n_sweep = sweep.len();
    if cv.wants("branch_diagram") {
        cv.draw(
            "branch_diagram",
            "branch_diagram",
            format!(
                "LCO branches by continuation (single shooting + pseudo-arclength): stable orbits solid, unstable dashed (Floquet multipliers), Hopf points and folds marked{}{}.",
                if n_sweep > 0 { format!(", {n_sweep} time-integration LCOs of the upward sweep on top") } else { String::new() },
                if doc.measured.is_empty() { String::new() } else { format!(", {} measured points", doc.measured.len()) }
            ),
            &crate::adapters::aeroelastic::branch_figure(&set, &doc.measured, sweep),
        )?;
    }
    report.section("LCO branches by continuation");
    let mut rows: Vec<Vec<String>> = Vec::new();
    for (i, b) in set.branches.iter().enumerate() {
        rows.push(vec![
            i.to_string(),
            "Hopf".into(),
            format!("{:.4}", b.hopf.u),
            "0".into(),
            format!("{} ({} orbits)", b.criticality, b.points.len()),
        ]);
        for e in &b.events {
            rows.push(vec![
                i.to_string(),
                format!("{:?}", e.kind),
                format!("{:.4}", e.u),
                format!("{:.3}", e.amplitude_alpha.to_degrees()),
                String::new(),
            ]);
        }
    }
    report.table(
        "Hopf points and bifurcations of the branches (branch.json, branch.csv)",
        &[
            "branch",
            "point",
            "U [m/s]",
            "pitch amplitude [deg]",
            "note",
        ]
        .map(String::from),
        &rows,
    );
    cv.embed(report, "branch_diagram");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_numbers_are_shortened_and_text_kept() {
        assert_eq!(pretty_cell("6.000000000000001"), "6.0000");
        assert_eq!(pretty_cell("-23.096456178436412"), "-23.096");
        assert_eq!(pretty_cell("0.000006850861010712863"), "6.8509e-6");
        assert_eq!(pretty_cell("4"), "4");
        assert_eq!(pretty_cell("0"), "0");
        assert_eq!(pretty_cell("D-U4-A6"), "D-U4-A6");
        assert_eq!(
            crate::report::split_csv_line("a,\"b,c\",\"d\"\"e\""),
            vec!["a", "b,c", "d\"e"]
        );
    }
}
