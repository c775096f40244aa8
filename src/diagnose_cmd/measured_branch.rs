//! `aeroform diagnose --measured-branch`: the sim's bifurcation diagram against a measured
//! one (Hopf, folds, LCO branches), the catalogue candidates fitted with continuation
//! inside the fit and scored by leave-one-speed-out (`bifurcation.json`, figures,
//! `diagnosis.html`).

use std::path::Path;

use diagnose::bifurcation::inputs::MeasuredBranchRequest;
use diagnose::bifurcation::{BifurcationDiagnosis, BifurcationOptions, BranchKind, Quantity};
use identify::io::write_atomic;

use super::args::DiagnoseArgs;

/// Runs the bifurcation-level diagnosis of `measured` (a CSV table or a data-set folder).
pub fn run(args: &DiagnoseArgs, measured: &Path) -> anyhow::Result<()> {
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| std::path::PathBuf::from("out/bifurcation"));
    // before the inputs are read and the candidates fitted (`OutDir::begin` checks it again)
    crate::outdir::refuse_overlap(&out, "--out", &args.inputs())?;
    let Some(model_path) = &args.model else {
        crate::exit::refuse!("--measured-branch needs --model M (the sim's aerodynamic model)");
    };
    // Every input is read and checked before the output folder is touched; which reader
    // the measured input needs and where the structure comes from are the library's
    // choices (`diagnose::bifurcation::inputs`, shared with Python).
    let prepared = MeasuredBranchRequest {
        measured,
        model: model_path,
        structure: args.structure.as_deref(),
        free: &args.free,
        onsets: &args.onset,
        no_lco: &args.no_lco,
    }
    .prepare()?;
    for w in &prepared.model_warnings {
        crate::ui::warning!("warning: {}: {w}", model_path.display());
    }
    let dir = crate::outdir::OutDir::begin(
        &out,
        "diagnose --measured-branch",
        args.force,
        &args.inputs(),
    )?;
    let spinner = crate::progress::Spinner::new(
        "diagnose",
        "continuation of every candidate, leave-one-speed-out",
    );
    let opts = BifurcationOptions {
        jacobian: args.fit.into(),
        ..BifurcationOptions::default()
    };
    let d = prepared.diagnose(&opts, &crate::version());
    spinner.finish();
    let d = d?;
    let mut text = serde_json::to_string_pretty(&d)?;
    text.push('\n');
    write_atomic(&dir.path().join("bifurcation.json"), text.as_bytes())?;
    let files = plots::write_bifurcation_outputs(&d, dir.path())?;
    dir.commit()?;
    print(&d);
    crate::ui::say!(
        "wrote {} and {} figure/report files to {}",
        out.join("bifurcation.json").display(),
        files.len(),
        out.display()
    );
    crate::ui::document(&d)
}

fn deg(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{:.3}°", x.to_degrees()))
}

fn mm(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{:.2} mm", x * 1e3))
}

fn print(d: &BifurcationDiagnosis) {
    crate::ui::say!("verdict: {}", d.verdict.name);
    crate::ui::say!("  {}", d.verdict.explanation);
    if let Some(s) = &d.structure {
        crate::ui::say!("structure (still-air decays): {}", s.summary);
        crate::ui::say!("structure used: {:?}: {}", s.used, s.reason);
        let hz = |v: Option<f64>| v.map_or("–".into(), |x| format!("{x:.3} Hz"));
        let ms = |v: Option<f64>| v.map_or("–".into(), |x| format!("{x:.3} m/s"));
        for o in &s.onsets {
            crate::ui::say!(
                "  onset {:.3} ± {:.3} m/s{}: Hopf point of the given structure {} at {} ({}), \
                 of the structure used {} at {}",
                o.u,
                o.u_sd,
                o.frequency_hz
                    .map_or(String::new(), |f| format!(" at {f:.3} Hz")),
                ms(o.given_u),
                hz(o.given_frequency_hz),
                o.u_z.map_or("–".into(), |z| format!("{z:+.1} σ")),
                ms(o.used_u),
                hz(o.used_frequency_hz)
            );
        }
        if let Some(id) = &s.identified {
            for p in &id.parameters {
                crate::ui::say!(
                    "  {:<8} given {:.6e}  identified {:.6e}  [{:.6e}, {:.6e}] {}{}",
                    p.name,
                    p.given,
                    p.identified,
                    p.interval[0],
                    p.interval[1],
                    p.unit,
                    if p.held { " (held)" } else { "" }
                );
            }
        }
        if let Some(g) = &s.gap {
            crate::ui::say!(
                "  the correction alone: nominal score {:.3} → {:.3}; Hopf {} → {} m/s",
                g.given,
                g.identified,
                g.hopf_given.map_or("–".into(), |u| format!("{u:.3}")),
                g.hopf_identified.map_or("–".into(), |u| format!("{u:.3}"))
            );
        }
    }
    let extrapolated = |x: bool| if x { " [extrapolation]" } else { "" };
    let diag = |name: &str, s: &diagnose::bifurcation::DiagramSummary| {
        let hopf: Vec<String> = s
            .hopf
            .iter()
            .map(|h| {
                format!(
                    "{:.3} m/s {:.3} Hz {}{}",
                    h.u,
                    h.frequency_hz,
                    h.criticality,
                    extrapolated(h.extrapolation)
                )
            })
            .collect();
        let folds: Vec<String> = s
            .folds
            .iter()
            .map(|f| {
                format!(
                    "{:.3} m/s ({:.2}°){}",
                    f.u,
                    f.amplitude1_alpha.to_degrees(),
                    extrapolated(f.extrapolation)
                )
            })
            .collect();
        crate::ui::say!(
            "{name}: Hopf {}; folds {}",
            if hopf.is_empty() {
                "none".into()
            } else {
                hopf.join(", ")
            },
            if folds.is_empty() {
                "none".into()
            } else {
                folds.join(", ")
            }
        );
    };
    diag("nominal", &d.nominal);
    if let Some(i) = d.verdict.candidate {
        diag("named", &d.candidates[i].fit);
    }
    for (k, o) in d.onsets.iter().enumerate() {
        crate::ui::say!(
            "measured onset {:.3} m/s{}{}: first Hopf point of each model (fitted on all points; \
             held out)",
            o.u,
            o.frequency_hz
                .map_or(String::new(), |f| format!(" {f:.3} Hz")),
            o.criticality
                .map_or(String::new(), |c| format!(" {}", c.name()))
        );
        let row = |name: &str, x: Option<&diagnose::bifurcation::OnsetDistance>| {
            let Some(x) = x else { return };
            crate::ui::say!(
                "  {:<42} {}{}",
                name,
                match (x.predicted_u, x.predicted_frequency_hz) {
                    (Some(u), Some(f)) => format!(
                        "{u:.3} m/s ({:+.2} %) {f:.3} Hz {}",
                        100.0 * (u / o.u - 1.0),
                        x.predicted_criticality.as_deref().unwrap_or("")
                    ),
                    _ => "no Hopf point in range".into(),
                },
                match x.criticality_right {
                    Some(false) => " [criticality wrong]",
                    _ => "",
                }
            );
        };
        row("nominal", d.nominal.onsets.get(k));
        for c in &d.candidates {
            row(&c.label(), c.fit.onsets.get(k));
        }
    }
    for (k, a) in d.absences.iter().enumerate() {
        crate::ui::say!(
            "no LCO observed at {:.3} m/s: models that predict one there",
            a.u
        );
        let mut any = false;
        for (name, x) in std::iter::once(("nominal".to_string(), d.nominal.absences.get(k))).chain(
            d.candidates
                .iter()
                .map(|c| (c.label(), c.fit.absences.get(k))),
        ) {
            if let Some(x) = x.filter(|x| x.predicts_lco) {
                any = true;
                crate::ui::say!(
                    "  {:<42} {}",
                    name,
                    x.lco_alpha
                        .map_or("flutter without a bounded cycle".into(), |a| format!(
                            "stable cycle {:.3}°",
                            a.to_degrees()
                        ))
                );
            }
        }
        if !any {
            crate::ui::say!("  none");
        }
    }
    crate::ui::say!(
        "{:<44} {:>9} {:>8} {:>11} {:>11}",
        "candidate (held-out, leave one speed out)",
        "score",
        "shrink",
        "pitch RMS",
        "heave RMS"
    );
    crate::ui::say!(
        "{:<44} {:>9.3} {:>8} {:>11} {:>11}",
        "nominal",
        d.nominal.errors.score,
        "",
        deg(d.nominal.errors.rms(BranchKind::All, Quantity::Pitch)),
        mm(d.nominal.errors.rms(BranchKind::All, Quantity::Heave))
    );
    for c in &d.candidates {
        crate::ui::say!(
            "{:<44} {:>9.3} {:>7.1}% {:>11} {:>11}",
            c.label(),
            c.held_out.score,
            100.0 * c.shrink,
            deg(c.held_out.rms(BranchKind::All, Quantity::Pitch)),
            mm(c.held_out.rms(BranchKind::All, Quantity::Heave))
        );
    }
    crate::ui::say!("diagnosed in {:.2} s", d.seconds);
}

/// `diagnose --blind N --branch-level`: the generated benchmark at the bifurcation level.
pub fn blind(
    n: usize,
    seed: u64,
    bench: &benchmark::branch_bench::BranchBenchOptions,
    out: &Path,
    force: bool,
) -> anyhow::Result<()> {
    use benchmark::branch_bench::{run_bench_with, BranchOutcome, HOPF_TOLERANCE, STRONG_SCORE};
    let dir = crate::outdir::OutDir::begin(out, "diagnose --blind --branch-level", force, &[])?;
    let bar = crate::progress::CountBar::new("branch-level sets", n);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let obs = |o: &BranchOutcome| {
        let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        bar.set(k, format!("set {}: {:?} → {}", o.index, o.truth, o.verdict));
    };
    let r = run_bench_with(n, seed, bench, &obs);
    bar.finish();
    let r = r?;
    let mut text = serde_json::to_string_pretty(&r)?;
    text.push('\n');
    write_atomic(&dir.path().join("branch-blind.json"), text.as_bytes())?;
    dir.commit()?;
    crate::ui::say!(
        "{:<20} {:>5} {:>7} {:>15} {:>8}",
        "truth",
        "sets",
        "strong",
        "strong correct",
        "correct"
    );
    for t in &r.per_truth {
        crate::ui::say!(
            "{:<20} {:>5} {:>7} {:>15} {:>8}",
            format!("{:?}", t.truth),
            t.sets,
            t.strong,
            t.strong_correct,
            t.correct
        );
    }
    crate::ui::say!(
        "top-1 on strong sets (nominal score ≥ {STRONG_SCORE}): {:.1} %; effect-free sets `none`: {:.1} %",
        100.0 * r.top1_strong,
        100.0 * r.none_on_effect_free
    );
    crate::ui::say!(
        "named model's Hopf speed within {:.0} % of the truth's: {:.1} %; criticality right: \
         {:.1} %; both: {:.1} %; effect-free sets named an effect: {}",
        100.0 * HOPF_TOLERANCE,
        100.0 * r.hopf_within_tolerance,
        100.0 * r.criticality_right,
        100.0 * r.hopf_and_criticality_right,
        r.effect_free_named
    );
    crate::ui::say!("wrote {}", out.join("branch-blind.json").display());
    crate::ui::document(&r)
}
