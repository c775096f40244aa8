//! Runs the stages of a study: data → identification → flutter → LCO → branch, each
//! writing its result files (the figures and report are drawn from them by `plots`).
//! Orchestration only: every number comes from `identify` / `aeroelastic`.

use std::path::Path;
use std::time::Instant;

use crate::error::{Context, Error, Result};
use aeroelastic::documents::{FlutterDoc, LcoDoc, TruthSweeps};
use aeroelastic::ensemble::{flutter_ensemble, lco_ensemble, LcoEnsemble};
use aeroelastic::files::ModelKind;
use aeroelastic::flutter::{FlutterMethod, FlutterOptions};
use aeroelastic::lco::{Classification, KIteration, LcoOptions, LcoResult, SweepPlan};
use identify::pipeline::Identification;
use identify::series::{case_series, SeriesOptions};

use crate::build;
use crate::files::{ensure_dir, num, write_json, write_text, Csv};
use crate::observe::Observer;
use crate::paper::{self, PaperFigures};
use crate::spec::{Study, StudyModel};

/// File names of the results (relative to the output folder).
pub mod names {
    /// Copy of the study file.
    pub const STUDY: &str = "study.toml";
    /// Case descriptors (JSON list of `identify::record::CaseMeta`).
    pub const CASES: &str = "cases.json";
    /// Identification result.
    pub const IDENTIFICATION: &str = "identification.json";
    /// Raw coefficients of every library term, per case and force.
    pub const COEFFICIENTS: &str = "coefficients.csv";
    /// Eq. 19 derivatives and metrics per case (columns [`derivative_columns`]).
    pub const DERIVATIVES: &str = "derivatives.csv";

    /// The Eq. 19 columns of [`DERIVATIVES`], from `identify::eq19`'s names: the lift
    /// derivatives H1–H4 and the moment derivatives A1–A4 (`linear_only`), or all seven of
    /// each force with the nonlinear N1–N3 suffixed `_lift` and `_moment`.
    pub fn derivative_columns(linear_only: bool) -> Vec<String> {
        use identify::eq19::{LIFT_NAMES, MOMENT_NAMES};
        let mut out = Vec::new();
        for (names, force) in [(LIFT_NAMES, "lift"), (MOMENT_NAMES, "moment")] {
            out.extend(names[..4].iter().map(|n| n.to_string()));
            if !linear_only {
                out.extend(names[4..].iter().map(|n| format!("{n}_{force}")));
            }
        }
        out
    }
    /// Table IV: identified vs true coefficients.
    pub const TABLE_IV: &str = "table_iv.csv";
    /// Folder of the compact case series.
    pub const SERIES: &str = "series";
    /// Flutter analyses.
    pub const FLUTTER: &str = "flutter.json";
    /// Flutter and divergence points with the published values.
    pub const FLUTTER_POINTS: &str = "flutter_points.csv";
    /// LCO sweeps and phase-portrait trajectories.
    pub const LCO: &str = "lco.json";
    /// LCO amplitudes per speed and sweep.
    pub const LCO_AMPLITUDES: &str = "lco_amplitudes.csv";
    /// Column name → library term → display name of `coefficients.csv`'s term columns.
    pub const COEFFICIENT_COLUMNS: &str = "coefficients.columns.json";
    /// Data of the paper's force-decomposition, δ-fit and force-loop figures.
    pub const PAPER_FIGURES: &str = "paper_figures.json";
    /// LCO amplitude intervals of the identification ensemble per speed.
    pub const LCO_INTERVALS: &str = "lco_intervals.csv";
    /// LCO branches by continuation (`[branch]`), as `aeroform branch` writes it.
    pub const BRANCH: &str = "branch.json";
    /// One row per branch orbit (`[branch]`).
    pub const BRANCH_CSV: &str = "branch.csv";
    /// Truth vs identified: flutter speed and LCO amplitudes (`lco.compare_truth`).
    pub const ROUND_TRIP: &str = "round_trip.csv";
    /// Figure folder.
    pub const FIGURES: &str = "figures";
    /// List of the figures drawn.
    pub const FIGURE_LIST: &str = "figures.json";
    /// The HTML report.
    pub const REPORT: &str = "report.html";
}

/// How a study's result documents name its structure (`study.toml [structure]`).
fn structure_name() -> String {
    format!("{} [structure]", names::STUDY)
}

/// Wall time of each stage \[s\].
pub type Timings = Vec<(&'static str, f64)>;

fn timed<T>(
    timings: &mut Timings,
    stage: &'static str,
    f: impl FnOnce() -> Result<T>,
) -> Result<T> {
    let t = Instant::now();
    let r = f()?;
    timings.push((stage, t.elapsed().as_secs_f64()));
    Ok(r)
}

/// Runs the stages of `study` (data, identify, flutter, LCO, branch — those the study has)
/// and writes their result files under `out`; returns the wall time of each stage \[s\].
/// Progress bars and the lines a terminal shows go to `obs`. The figures and the report
/// are not drawn here: the caller draws them from the result files
/// (`plots::study_report::render_all`).
///
/// # Errors
/// The first failing stage, with its context ([`crate::Error`]); an
/// `outputs.series_cases` id not in the data is [`crate::Error::Usage`]. Files written
/// before the failure are complete (atomic writes), nothing half-written remains.
pub fn run_study(study: &Study, out: &Path, obs: &dyn Observer) -> Result<Timings> {
    ensure_dir(out)?;
    let mut timings = Timings::new();
    let cases = timed(&mut timings, "data", || build::cases(study, out, obs))?;
    if let Some(cases) = &cases {
        // the last check of the spec that needs the data: before any result is written
        series_case_indices(study, cases)?;
    }
    write_text(&out.join(names::STUDY), &study.text)?;
    let mut derived = build::Derived::default();
    if let Some(cases) = &cases {
        obs.say(&format!(
            "data: {} cases; {}",
            cases.cases.len(),
            cases.source
        ));
        let id = timed(&mut timings, "identify", || {
            identify_stage(study, cases, out, obs)
        })?;
        obs.say(&id.summary_table());
        let s = &study.spec;
        let wants_identified = s
            .aero
            .as_ref()
            .is_some_and(|a| a.kind == ModelKind::Identified)
            || s.flutter.as_ref().is_some_and(|f| {
                f.run
                    .iter()
                    .any(|r| r.model == Some(StudyModel::IDENTIFIED))
            });
        if wants_identified {
            derived.identified = Some(timed(&mut timings, "identified model", || {
                build::identified_model(study, &id)
            })?);
            if id.ensemble.is_some() {
                derived.members = Some(timed(&mut timings, "ensemble laws", || {
                    build::member_laws(study, &id)
                })?);
            }
        }
    }
    let mut flutter_speed = None;
    let mut truth_flutter_speed = None;
    if study.spec.flutter.is_some() {
        let runs = timed(&mut timings, "flutter", || {
            flutter_stage(study, out, &derived, obs)
        })?;
        let model = study.spec.aero.as_ref().map(|a| StudyModel::Kind(a.kind));
        let speed_of = |m: Option<StudyModel>| {
            runs.iter()
                .find(|(model, _)| Some(*model) == m)
                .and_then(|(_, r)| r.analysis.flutter.map(|f| f.u))
        };
        flutter_speed = speed_of(model);
        truth_flutter_speed = speed_of(Some(StudyModel::Truth));
        for (_, r) in &runs {
            let label = r.label.as_deref().unwrap_or_default();
            match r.analysis.flutter {
                Some(f) => obs.say(&format!(
                    "flutter [{label}]: U_F = {:.4} m/s (U/(bω_α) = {:.4}), ω_F/ω_α = {:.4}",
                    f.u, f.u_reduced, f.omega_ratio
                )),
                None => obs.say(&format!("flutter [{label}]: stable over the scan")),
            }
        }
    }
    if study.spec.lco.is_some() {
        timed(&mut timings, "lco", || {
            lco_stage(
                study,
                out,
                [flutter_speed, truth_flutter_speed],
                &derived,
                obs,
            )
        })?;
    }
    if study.spec.branch.is_some() {
        let set = timed(&mut timings, "branch", || {
            branch_stage(study, out, &derived)
        })?;
        for (i, b) in set.branches.iter().enumerate() {
            let folds = b
                .events
                .iter()
                .filter(|e| e.kind == aeroelastic::branch::EventKind::Fold)
                .count();
            obs.say(&format!(
                "branch {i}: Hopf point U = {:.4} m/s ({}), {} orbits, {folds} fold(s)",
                b.hopf.u,
                b.criticality,
                b.points.len()
            ));
        }
    }
    Ok(timings)
}

/// Indices of the cases whose series are saved: `outputs.series_cases`, or the first and
/// the last case.
///
/// # Errors
/// A listed case id that is not in the data ([`Error::Usage`], naming the key).
fn series_case_indices(study: &Study, cases: &build::Cases) -> Result<Vec<usize>> {
    let wanted = &study.spec.outputs.series_cases;
    if wanted.is_empty() {
        let mut v = vec![0];
        if cases.cases.len() > 1 {
            v.push(cases.cases.len() - 1);
        }
        return Ok(v);
    }
    wanted
        .iter()
        .map(|w| {
            cases
                .cases
                .iter()
                .position(|c| &c.meta.id == w)
                .ok_or_else(|| {
                    Error::Usage(format!(
                        "{}: key `outputs.series_cases`: no case `{w}` in the data",
                        study.path.display()
                    ))
                })
        })
        .collect()
}

fn identify_stage(
    study: &Study,
    cases: &build::Cases,
    out: &Path,
    obs: &dyn Observer,
) -> Result<Identification> {
    let settings = study.spec.identify.clone().unwrap_or_default().settings;
    if let Some(n) = study.spec.identify.as_ref().and_then(|i| i.ensemble) {
        // a `[data] dataset`'s cases are known only now (the generated campaigns are
        // checked with the study): before the identification, not after it
        crate::limits::ensemble_fits("identify.ensemble", n, cases.cases.len() as u128)
            .map_err(|e| Error::Usage(e.to_string()))?;
    }
    let result =
        identify::pipeline::identify(&cases.cases, &settings, &cases.name, &|p| obs.identify(p));
    obs.identify_done();
    let mut id = result.context("identification")?;
    let spec = study.spec.identify.clone().unwrap_or_default();
    if let Some(n) = spec.ensemble {
        let mut es = identify::ensemble::EnsembleSettings::new(n, study.spec.seed);
        es.level = spec.ensemble_level;
        id.ensemble = Some(
            identify::ensemble::bootstrap(&cases.cases, &id, &es)
                .context("identification ensemble (block bootstrap)")?,
        );
    }
    id.write(&out.join(names::IDENTIFICATION))?;
    write_json(&out.join(names::CASES), &cases.metas())?;

    // coefficients per case and force (wide: one column per library term, under a name CSV
    // readers keep: `alpha2_h` for `alpha^2*h`; the mapping in coefficients.columns.json)
    let safe: Vec<String> = id
        .library
        .terms
        .iter()
        .map(|t| {
            identify::library::Term::parse(t)
                .map(|p| p.safe_name())
                .unwrap_or_else(|_| t.replace(|c: char| !c.is_ascii_alphanumeric(), "_"))
        })
        .collect();
    let columns: Vec<crate::documents::CoefficientColumn> = safe
        .iter()
        .zip(&id.library.terms)
        .map(|(s, t)| crate::documents::CoefficientColumn {
            column: s.clone(),
            term: t.clone(),
            display: crate::documents::term_label(t),
        })
        .collect();
    write_json(&out.join(names::COEFFICIENT_COLUMNS), &columns)?;
    let mut coef = Csv::new(
        &["case", "group", "force", "U_m_s", "amplitude_deg"]
            .iter()
            .map(|s| s.to_string())
            .chain(safe.iter().cloned())
            .collect::<Vec<_>>(),
    );
    let text = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let mut der = Csv::new(
        &[
            text(&["case", "group", "U_m_s", "amplitude_deg", "K_alpha", "K_h"]),
            names::derivative_columns(false),
            text(&[
                "R2_lift",
                "R2_moment",
                "MFWA_lift",
                "MFWA_moment",
                "loss_lift",
                "loss_moment",
            ]),
        ]
        .concat(),
    );
    for (c, nc) in id.cases.iter().zip(&cases.cases) {
        // degrees → radians → degrees: round off the last-bit noise (6.000000000000001)
        let amp = nc
            .meta
            .amplitude
            .map(|a| (a.to_degrees() * 1e9).round() / 1e9);
        for (force, terms) in [("lift", &c.lift.terms), ("moment", &c.moment.terms)] {
            let mut row = vec![
                c.id.clone(),
                c.group.clone(),
                force.to_string(),
                num(Some(c.wind_speed)),
                num(amp),
            ];
            row.extend(id.library.terms.iter().map(|t| num(terms.get(t))));
            coef.rows.push(row);
        }
        let l = &c.lift.eq19;
        let m = &c.moment.eq19;
        der.rows.push(
            [
                vec![c.id.clone(), c.group.clone()],
                [
                    Some(c.wind_speed),
                    amp,
                    c.k_alpha,
                    c.k_h,
                    l.H1,
                    l.H2,
                    l.H3,
                    l.H4,
                    l.N1,
                    l.N2,
                    l.N3,
                    m.A1,
                    m.A2,
                    m.A3,
                    m.A4,
                    m.N1,
                    m.N2,
                    m.N3,
                    c.lift.r2,
                    c.moment.r2,
                    c.lift.mfwa,
                    c.moment.mfwa,
                    c.lift.key_frequency_loss,
                    c.moment.key_frequency_loss,
                ]
                .into_iter()
                .map(num)
                .collect(),
            ]
            .concat(),
        );
    }
    coef.write(&out.join(names::COEFFICIENTS))?;
    der.write(&out.join(names::DERIVATIVES))?;

    // compact series of the shown cases
    let dir = out.join(names::SERIES);
    identify::io::create_dir_below(out, Path::new(names::SERIES))?;
    for i in series_case_indices(study, cases)? {
        let w = &cases.cases[i].meta.id;
        let s = case_series(&cases.cases[i], &id.cases[i], &SeriesOptions::default())
            .with_context(|| format!("series of case {w}"))?;
        write_json(&dir.join(format!("{w}.json")), &s)?;
    }

    if let Some(t) = study.spec.data.as_ref().and_then(|d| d.table_iv.as_ref()) {
        table_iv(&id, t, out)?;
    }
    let paper = paper_figures(study, cases, &id);
    if !paper.is_empty() {
        write_json(&out.join(names::PAPER_FIGURES), &paper)?;
    }
    Ok(id)
}

/// The data of the paper's force-decomposition, δ-fit and force-loop figures, for the kinds
/// the study draws. The δ fits use the first of `outputs.delta_groups` (else the first
/// group) and in it a shown case (`outputs.series_cases`) or else the case of largest
/// amplitude at the highest wind speed; the loops use that case's configuration.
fn paper_figures(study: &Study, cases: &build::Cases, id: &Identification) -> PaperFigures {
    let kinds = study.figure_kinds();
    let wants = |k: &str| kinds.iter().any(|x| x == k);
    let mut p = PaperFigures::default();
    if wants("force_decomposition") {
        p.forces = cases.forces.clone();
    }
    let group = study
        .spec
        .outputs
        .delta_groups
        .first()
        .cloned()
        .or_else(|| id.groups.first().map(|g| g.name.clone()));
    let Some(group) = group else {
        return p;
    };
    let in_group: Vec<&identify::pipeline::CaseResult> =
        id.cases.iter().filter(|c| c.group == group).collect();
    let shown = in_group
        .iter()
        .find(|c| study.spec.outputs.series_cases.contains(&c.id));
    let strongest = || {
        let amp = |c: &&&identify::pipeline::CaseResult| {
            cases
                .cases
                .iter()
                .find(|n| n.meta.id == c.id)
                .and_then(|n| n.meta.amplitude)
                .unwrap_or(0.0)
        };
        in_group.iter().max_by(|a, b| {
            a.wind_speed
                .total_cmp(&b.wind_speed)
                .then(amp(a).total_cmp(&amp(b)))
        })
    };
    let Some(case) = shown.or_else(strongest) else {
        return p;
    };
    if wants("delta_fits") {
        p.delta_fits = paper::delta_fits(id, &cases.cases, &group, &case.id);
    }
    if wants("force_loops") {
        let config = cases
            .cases
            .iter()
            .find(|n| n.meta.id == case.id)
            .and_then(|n| n.meta.config.clone());
        if let Some(c) = config {
            p.loops = paper::loop_sets(&cases.cases, &c);
        }
    }
    p
}

/// Table IV: per channel and true term, the true value and the mean and standard deviation
/// of the identified coefficient over the noise realisations, how often the term was
/// selected, and how often the whole support was exactly the true one.
fn table_iv(id: &Identification, t: &crate::spec::TableIvSpec, out: &Path) -> Result<()> {
    let mut csv = Csv::new(&[
        "channel",
        "term",
        "true",
        "mean",
        "std",
        "selected_in",
        "realisations",
        "exact_support_in",
    ]);
    let truth = identify::paper::TABLE_IV_TERMS;
    type GroupForce = fn(&identify::pipeline::GroupResult) -> &identify::pipeline::GroupForce;
    type CaseTerms = fn(&identify::pipeline::CaseResult) -> &identify::pipeline::TermMap;
    let channels: [(&str, _, GroupForce, CaseTerms); 2] = [
        ("moment", t.moment, |g| &g.moment, |c| &c.moment.terms),
        ("lift", t.lift, |g| &g.lift, |c| &c.lift.terms),
    ];
    for (channel, coefs, group_force, case_terms) in channels {
        let n = id.cases.len();
        let mut exact = 0;
        for g in &id.groups {
            let s = &group_force(g).support;
            let mut s: Vec<&str> = s.iter().map(String::as_str).collect();
            s.sort_unstable();
            let mut tr = truth.to_vec();
            tr.sort_unstable();
            if s == tr {
                exact += 1;
            }
        }
        for (k, term) in truth.iter().enumerate() {
            let vals: Vec<f64> = id
                .cases
                .iter()
                .map(|c| case_terms(c).get(term).unwrap_or(0.0))
                .collect();
            let mean = vals.iter().sum::<f64>() / n as f64;
            let sd = if n > 1 {
                (vals.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
            } else {
                f64::NAN
            };
            let selected = vals.iter().filter(|v| **v != 0.0).count();
            csv.rows.push(vec![
                channel.into(),
                term.to_string(),
                num(Some(coefs[k])),
                num(Some(mean)),
                num(Some(sd)),
                selected.to_string(),
                n.to_string(),
                exact.to_string(),
            ]);
        }
    }
    csv.write(&out.join(names::TABLE_IV))
}

fn flutter_stage(
    study: &Study,
    out: &Path,
    derived: &build::Derived,
    obs: &dyn Observer,
) -> Result<Vec<(StudyModel, FlutterDoc)>> {
    let (Some(f), Some(_), Some(a)) =
        (&study.spec.flutter, &study.spec.structure, &study.spec.aero)
    else {
        return Err(Error::Study(
            "[flutter] needs [structure] and [aero]".into(),
        ));
    };
    let runs: Vec<crate::spec::FlutterRunSpec> = if f.run.is_empty() {
        vec![crate::spec::FlutterRunSpec {
            label: format!("{} (p-k)", a.kind),
            model: None,
            method: FlutterMethod::Pk,
            reference: None,
        }]
    } else {
        f.run.clone()
    };
    let opts = FlutterOptions {
        u_min: f.u_min,
        u_max: f.u_max,
        n_speeds: f.n_speeds,
        tol_rel: f.tol_rel,
    };
    let bar = obs.counter("flutter", runs.len());
    let mut results = Vec::new();
    for r in &runs {
        let model = r.model.unwrap_or(StudyModel::Kind(a.kind));
        let section = build::linear_section(study, model, derived)?;
        let method = r.method;
        let analysis = section
            .flutter(method, &opts)
            .with_context(|| format!("flutter run `{}`", r.label))?;
        let ensemble = match (&derived.members, model) {
            (Some(m), StudyModel::IDENTIFIED) => Some(
                flutter_ensemble(
                    &section.structure,
                    &m.laws,
                    &m.ensemble,
                    section.rho,
                    method,
                    &opts,
                )
                .with_context(|| format!("flutter run `{}`: ensemble", r.label))?,
            ),
            _ => None,
        };
        bar.inc(1);
        let doc = FlutterDoc {
            label: Some(r.label.clone()),
            reference: r.reference,
            ensemble,
            ..FlutterDoc::new(&structure_name(), model.name(), &section, &analysis, None)
        };
        results.push((model, doc));
    }
    bar.finish();
    let docs: Vec<&FlutterDoc> = results.iter().map(|(_, d)| d).collect();
    write_json(&out.join(names::FLUTTER), &docs)?;
    let mut csv = Csv::new(&[
        "run",
        "model",
        "method",
        "U_F_m_s",
        "omega_F_rad_s",
        "U_F_reduced",
        "omega_ratio",
        "U_D_m_s",
        "U_D_reduced",
        "ref_U_F_reduced",
        "ref_omega_ratio",
        "ref_U_D_reduced",
        "rel_err_U_F",
        "rel_err_U_D",
        "U_F_lower_m_s",
        "U_F_upper_m_s",
        "U_D_lower_m_s",
        "U_D_upper_m_s",
        "ensemble_level",
        "ensemble_members",
        "ensemble_with_flutter",
    ]);
    for (_, r) in &results {
        let scale = 0.5 * r.chord * r.omega_alpha;
        let fl = r.analysis.flutter;
        let ud = r.analysis.divergence_speed;
        let rf = r.reference;
        let rel = |v: Option<f64>, reference: Option<f64>| match (v, reference) {
            (Some(v), Some(x)) => Some((v - x) / x),
            _ => None,
        };
        let mut row = vec![
            r.label.clone().unwrap_or_default(),
            r.model.clone(),
            format!("{:?}", r.analysis.method),
            num(fl.map(|f| f.u)),
            num(fl.map(|f| f.omega)),
            num(fl.map(|f| f.u_reduced)),
            num(fl.map(|f| f.omega_ratio)),
            num(ud),
            num(ud.map(|u| u / scale)),
            num(rf.and_then(|x| x.u_reduced)),
            num(rf.and_then(|x| x.omega_ratio)),
            num(rf.and_then(|x| x.divergence)),
            num(rel(fl.map(|f| f.u_reduced), rf.and_then(|x| x.u_reduced))),
            num(rel(ud.map(|u| u / scale), rf.and_then(|x| x.divergence))),
        ];
        let e = r.ensemble.as_ref();
        let uf_i = e.and_then(|e| e.flutter_speed.interval);
        let ud_i = e.and_then(|e| e.divergence_speed.interval);
        row.extend([
            num(uf_i.map(|i| i.lower)),
            num(uf_i.map(|i| i.upper)),
            num(ud_i.map(|i| i.lower)),
            num(ud_i.map(|i| i.upper)),
            num(e.map(|e| e.level)),
            e.map_or(String::new(), |e| e.members.to_string()),
            e.map_or(String::new(), |e| e.flutter_speed.found.to_string()),
        ]);
        csv.rows.push(row);
    }
    csv.write(&out.join(names::FLUTTER_POINTS))?;
    Ok(results)
}

/// `[flutter_speed, truth_flutter_speed]` of the linear analyses, if any.
fn lco_stage(
    study: &Study,
    out: &Path,
    [flutter_speed, truth_flutter_speed]: [Option<f64>; 2],
    derived: &build::Derived,
    obs: &dyn Observer,
) -> Result<()> {
    let (Some(l), Some(s)) = (&study.spec.lco, &study.spec.structure) else {
        return Err(Error::Study("[lco] needs [structure]".into()));
    };
    let section = build::nonlinear_section(study, derived)?;
    let opts = LcoOptions {
        rtol: l.rtol,
        atol: l.atol,
        max_periods: l.max_periods,
        ..LcoOptions::default()
    };
    let total = l.speeds.len() * if l.up_down { 2 } else { 1 };
    let bar = obs.counter("LCO", total * if l.compare_truth { 2 } else { 1 });
    let observer = |p| bar.sweep(p);
    // One sweep API for every model: K-dependent models (the identified law) iterate K
    // to each limit cycle's own, the others are run once per speed.
    let plan = |sec: &aeroelastic::section::Section| SweepPlan {
        perturbation_up: sec.perturbation(l.perturbation_deg.to_radians()),
        perturbation_down: l
            .up_down
            .then(|| sec.perturbation(l.perturbation_down_deg.to_radians())),
        k_iteration: KIteration::default(),
    };
    let h = section
        .lco_sweeps(&l.speeds, &plan(&section), &opts, &observer)
        .context("LCO sweeps")?;
    let truth = if l.compare_truth {
        let truth = aeroelastic::section::Section::new(
            build::structure(s)?,
            build::truth_model(study, s)?,
            s.linear.rho,
        )?;
        let sweep = truth
            .lco_sweeps(&l.speeds, &plan(&truth), &opts, &observer)
            .context("LCO sweeps of the truth model")?;
        Some(TruthSweeps {
            flutter_speed: truth_flutter_speed,
            sweep,
        })
    } else {
        None
    };
    bar.finish();
    // phase portraits: a few cycles from the final state of the nearest upward run
    let mut phase = Vec::new();
    for &u in &l.phase_speeds {
        let Some(r) =
            h.up.iter()
                .min_by(|a, b| (a.u - u).abs().total_cmp(&(b.u - u).abs()))
        else {
            continue;
        };
        if !matches!(
            r.classification,
            Classification::Lco | Classification::Unsettled
        ) {
            continue;
        }
        let omega = if r.omega > 0.0 {
            r.omega
        } else {
            s.linear.omega_alpha
        };
        let period = std::f64::consts::TAU / omega;
        let steps = (l.phase_periods * 400.0).ceil() as usize;
        phase.push(
            section
                .trajectory(r.u, &r.final_state, l.phase_periods * period, steps)
                .with_context(|| format!("phase portrait at U = {}", r.u))?,
        );
    }
    let ensemble = match (&derived.members, study.spec.aero.as_ref()) {
        (Some(m), Some(a)) if a.kind == ModelKind::Identified => Some(
            lco_ensemble(
                &section.structure,
                &m.laws,
                &m.ensemble,
                section.rho,
                &l.speeds,
                l.perturbation_deg.to_radians(),
                &opts,
            )
            .context("LCO runs of the ensemble")?,
        ),
        _ => None,
    };
    let model = study
        .spec
        .aero
        .as_ref()
        .map_or_else(|| section.aero.name(), |a| a.kind.to_string());
    let stage = LcoDoc {
        flutter_speed,
        phase,
        truth,
        ensemble,
        ..LcoDoc::new(&structure_name(), &model, &section).with_sweep(h)
    };
    write_json(&out.join(names::LCO), &stage)?;
    if let Some(e) = &stage.ensemble {
        lco_intervals(e, out)?;
    }
    let mut csv = Csv::new(&[
        "sweep",
        "U_m_s",
        "class",
        "amplitude_alpha_deg",
        "amplitude_h_m",
        "omega_rad_s",
        "cycles",
        "t_end_s",
        "stop",
        "steps",
        "rhs_evals",
        "k_eval",
    ]);
    let (sweep, truth) = (stage.sweep.as_ref(), stage.truth.as_ref().map(|t| &t.sweep));
    for (name, rs) in [
        ("up", sweep.map(|h| &h.up)),
        ("down", sweep.map(|h| &h.down)),
        ("truth-up", truth.map(|h| &h.up)),
        ("truth-down", truth.map(|h| &h.down)),
    ] {
        let Some(rs) = rs else { continue };
        for r in rs.iter() {
            let class = match r.classification {
                Classification::Decay => "decay",
                Classification::Lco => "lco",
                Classification::Divergent { .. } => "divergent",
                Classification::Unsettled => "unsettled",
            };
            csv.rows.push(vec![
                name.into(),
                num(Some(r.u)),
                class.into(),
                num(Some(r.amplitude_alpha.to_degrees())),
                num(Some(r.amplitude_h)),
                num(Some(r.omega)),
                r.cycles.to_string(),
                num(Some(r.t_end)),
                r.stop.name().into(),
                r.steps.to_string(),
                r.rhs_evals.to_string(),
                num(r.k_eval),
            ]);
        }
    }
    csv.write(&out.join(names::LCO_AMPLITUDES))?;
    if l.compare_truth {
        round_trip_table(&stage, out)?;
    }
    Ok(())
}

/// `lco_intervals.csv`: per speed, the pitch and heave amplitude intervals of the
/// ensemble members that settle on an LCO, and how many decay, diverge or do not settle.
fn lco_intervals(e: &LcoEnsemble, out: &Path) -> Result<()> {
    let mut csv = Csv::new(&[
        "U_m_s",
        "level",
        "members",
        "lco",
        "decay",
        "divergent",
        "unsettled",
        "amplitude_alpha_deg_median",
        "amplitude_alpha_deg_lower",
        "amplitude_alpha_deg_upper",
        "amplitude_h_mm_median",
        "amplitude_h_mm_lower",
        "amplitude_h_mm_upper",
    ]);
    for p in &e.points {
        let (a, h) = (p.amplitude_alpha_deg.interval, p.amplitude_h_mm.interval);
        csv.rows.push(vec![
            num(Some(p.u)),
            num(Some(e.level)),
            e.members.to_string(),
            p.amplitude_alpha_deg.found.to_string(),
            p.decay.to_string(),
            p.divergent.to_string(),
            p.unsettled.to_string(),
            num(a.map(|i| i.median)),
            num(a.map(|i| i.lower)),
            num(a.map(|i| i.upper)),
            num(h.map(|i| i.median)),
            num(h.map(|i| i.lower)),
            num(h.map(|i| i.upper)),
        ]);
    }
    csv.write(&out.join(names::LCO_INTERVALS))
}

/// `round_trip.csv`: truth vs `[aero]` model, flutter speed and LCO pitch amplitude per
/// speed and sweep, with the relative error (model/truth − 1).
fn round_trip_table(stage: &LcoDoc, out: &Path) -> Result<()> {
    let (Some(model), Some(truth)) = (&stage.sweep, &stage.truth) else {
        return Ok(());
    };
    let mut csv = Csv::new(&[
        "quantity",
        "U_m_s",
        "truth",
        "model",
        "rel_err",
        "truth_class",
        "model_class",
    ]);
    let rel = |t: Option<f64>, m: Option<f64>| match (t, m) {
        (Some(t), Some(m)) if t != 0.0 => Some(m / t - 1.0),
        _ => None,
    };
    csv.rows.push(vec![
        "flutter_speed_m_s".into(),
        String::new(),
        num(truth.flutter_speed),
        num(stage.flutter_speed),
        num(rel(truth.flutter_speed, stage.flutter_speed)),
        String::new(),
        String::new(),
    ]);
    let class = |r: &LcoResult| {
        match r.classification {
            Classification::Decay => "decay",
            Classification::Lco => "lco",
            Classification::Divergent { .. } => "divergent",
            Classification::Unsettled => "unsettled",
        }
        .to_string()
    };
    for (q, truth, model) in [
        ("lco_amplitude_deg_up", &truth.sweep.up, &model.up),
        ("lco_amplitude_deg_down", &truth.sweep.down, &model.down),
    ] {
        for (t, m) in truth.iter().zip(model.iter()) {
            let (ta, ma) = (
                t.amplitude_alpha.to_degrees(),
                m.amplitude_alpha.to_degrees(),
            );
            let both_lco =
                t.classification == Classification::Lco && m.classification == Classification::Lco;
            csv.rows.push(vec![
                q.into(),
                num(Some(t.u)),
                num(Some(ta)),
                num(Some(ma)),
                num(if both_lco {
                    rel(Some(ta), Some(ma))
                } else {
                    None
                }),
                class(t),
                class(m),
            ]);
        }
    }
    csv.write(&out.join(names::ROUND_TRIP))
}

/// The `[branch]` stage: LCO branches by continuation on the section of `[structure]` and
/// `[aero]` (the identified law when `aero.model = "identified"`), written as
/// `branch.json` / `branch.csv` with the same documents as `aeroform branch`.
///
/// # Errors
/// A missing `[structure]`/`[aero]`, an unreadable measured file (named), no Hopf point in
/// the range or a branch that cannot start (the library's message).
fn branch_stage(
    study: &Study,
    out: &Path,
    derived: &build::Derived,
) -> Result<aeroelastic::branch::BranchSet> {
    let Some(b) = &study.spec.branch else {
        return Err(Error::Study("no [branch] stage".into()));
    };
    let section = build::nonlinear_section(study, derived)?;
    let opts = aeroelastic::branch::BranchOptions {
        max_points: b.max_points,
        steps_per_period: b.steps_per_period,
        method: b.method,
        harmonics: b.harmonics,
        ..aeroelastic::branch::BranchOptions::default()
    };
    let measured = match &b.measured {
        Some(p) => {
            let path = study.base.join(p);
            Some(
                aeroelastic::branch::read_measured_amplitudes(&path)
                    .with_context(|| format!("branch.measured ({})", path.display()))?,
            )
        }
        None => None,
    };
    let [u_min, u_max] = b.speeds;
    let set = section
        .lco_branches(u_min, u_max, &opts, &|_| {})
        .with_context(|| format!("[branch]: LCO branches in U = {u_min}…{u_max} m/s"))?;
    let dist = measured
        .as_deref()
        .map(|m| aeroelastic::branch::measured_distances(&set, m))
        .unwrap_or_default();
    let model = study
        .spec
        .aero
        .as_ref()
        .map_or_else(|| section.aero.name(), |a| a.kind.to_string());
    let doc = aeroelastic::documents::branch_document(&structure_name(), &model, &set, &dist);
    write_text(&out.join(names::BRANCH), &format!("{:#}\n", doc.to_value()))?;
    write_text(
        &out.join(names::BRANCH_CSV),
        &aeroelastic::documents::branch_csv(&set),
    )?;
    Ok(set)
}

#[cfg(test)]
mod tests {
    use super::names::derivative_columns;

    #[test]
    fn derivative_columns_are_the_eq19_names() {
        assert_eq!(
            derivative_columns(false),
            [
                "H1",
                "H2",
                "H3",
                "H4",
                "N1_lift",
                "N2_lift",
                "N3_lift",
                "A1",
                "A2",
                "A3",
                "A4",
                "N1_moment",
                "N2_moment",
                "N3_moment"
            ]
        );
        assert_eq!(
            derivative_columns(true),
            ["H1", "H2", "H3", "H4", "A1", "A2", "A3", "A4"]
        );
    }
}
