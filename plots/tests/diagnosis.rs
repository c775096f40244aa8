//! Diagnosis figures and `diagnosis.html` from hand-built `Diagnosis` documents: a full one
//! (every field filled), a minimal one (no levels), one with NaN and empty inputs; files
//! exist, SVG and HTML are well-formed, bytes are identical across runs.

use std::path::{Path, PathBuf};

use diagnose::report::{
    Bifurcation, BifurcationPoint, CandidateScore, CaseGap, GapReport, ObservableGap,
    ResidualSpectrum, SignatureTest, VerdictReport, WhereShare, FORMAT,
};
use diagnose::{Diagnosis, Effect, Level, LevelResult};
use plots::adapters::diagnosis::{
    bifurcation_figure, gap_heatmap_figure, ranking_figure, residual_spectra_figure, shares_figure,
    MAX_SEGMENTS,
};
use plots::write_diagnosis_outputs;

// ---------------------------------------------------------------- fixtures

fn candidate(effect: Effect, level: Level, before: f64, after: f64, sig: bool) -> CandidateScore {
    CandidateScore {
        effect,
        level,
        before,
        after,
        shrink: 1.0 - after / before,
        n_params: 2,
        statistic: (before - after) / 0.01,
        threshold: 3.0,
        significant: sig,
        score: after,
        parameters: vec![("p0".into(), 0.01), ("tau_s".into(), 2.5e-3)],
        failure: None,
        convention: None,
        note: None,
        held_out_runs: vec![],
    }
}

fn share(split: &str, level: Level, channel: &str, harmonic: &str, s: f64) -> WhereShare {
    WhereShare {
        split: split.parse().unwrap(),
        level,
        channel: channel.parse().unwrap(),
        harmonic: harmonic.parse().unwrap(),
        wind_speed: [4.0, 10.0],
        amplitude: [6.0, 24.0],
        config: None,
        state: None,
        share: s,
    }
}

/// Spectrum with lines at the integer harmonics of `f1` on a floor; `after` = floor only
/// except a residual first harmonic.
fn spectrum(level: Level, channel: &str, unit: &str, f1: f64, f_max: f64) -> ResidualSpectrum {
    let n = 400;
    let frequency: Vec<f64> = (0..n).map(|i| f_max * i as f64 / (n - 1) as f64).collect();
    let line = |f: f64, k: f64| 0.2 / k * (-((f - k * f1) / (0.03 * f1)).powi(2)).exp();
    let before = frequency
        .iter()
        .map(|&f| 1e-3 + (1..=7).map(|k| line(f, k as f64)).sum::<f64>())
        .collect();
    let after = frequency
        .iter()
        .map(|&f| 1e-3 + 0.1 * line(f, 1.0))
        .collect();
    ResidualSpectrum {
        level,
        channel: channel.parse().unwrap(),
        frequency_unit: unit.into(),
        frequency,
        before,
        after,
    }
}

fn aero_level() -> LevelResult {
    let mut cases = vec![];
    let mut ids = vec![];
    for (c, config) in ["B", "D"].iter().enumerate() {
        for (iu, u) in [4.0, 5.5, 7.0, 8.5, 10.0].iter().enumerate() {
            for (ia, a) in [6.0, 12.0, 18.0, 24.0].iter().enumerate() {
                let id = format!("{config}-U{u}-A{a}");
                // Gap grows with amplitude and U; the candidate removes most of it.
                let noise = 0.02;
                let before = noise * (1.0 + 0.4 * (ia * (iu + 1)) as f64 + 0.3 * c as f64);
                cases.push(CaseGap {
                    id: id.clone(),
                    level: Level::Aerodynamic,
                    config: Some(config.to_string()),
                    wind_speed: *u,
                    amplitude: *a,
                    fold: iu,
                    before,
                    after: noise * (0.9 + 0.05 * ia as f64),
                    noise_level: noise,
                });
                ids.push(id);
            }
        }
    }
    let mut candidates = vec![
        candidate(Effect::DynamicStall, Level::Aerodynamic, 0.12, 0.025, true),
        candidate(Effect::HigherOrder, Level::Aerodynamic, 0.12, 0.06, true),
        candidate(Effect::StaticOffset, Level::Aerodynamic, 0.12, 0.11, false),
        candidate(Effect::TimeDelay, Level::Aerodynamic, 0.12, 0.118, false),
        candidate(Effect::AddedMass, Level::Aerodynamic, 0.12, 0.121, false),
    ];
    let mut failed = candidate(
        Effect::VortexShedding,
        Level::Aerodynamic,
        0.12,
        f64::NAN,
        false,
    );
    failed.failure = Some("no off-harmonic line above the floor in any training case".into());
    candidates.push(failed);

    let mut where_ = vec![
        share("channel", Level::Aerodynamic, "moment", "all", 0.7),
        share("channel", Level::Aerodynamic, "lift", "all", 0.3),
    ];
    for (h, s) in [
        ("3*f_alpha", 0.35),
        ("5*f_alpha", 0.2),
        ("7*f_alpha", 0.15),
        ("1*f_alpha", 0.1),
        ("2*f_alpha+f_h", 0.08),
        ("DC", 0.05),
        ("9*f_alpha", 0.03),
        ("broadband", 0.02),
        ("2*f_alpha", 0.02),
    ] {
        where_.push(share("harmonic", Level::Aerodynamic, "moment", h, s));
    }
    // Region split: one cell per (config, U band); shares ∝ U².
    let us = [4.0, 5.5, 7.0, 8.5, 10.0];
    let total: f64 = 2.0 * us.iter().map(|u| u * u).sum::<f64>();
    for config in ["B", "D"] {
        for u in us {
            let mut w = share("region", Level::Aerodynamic, "all", "all", u * u / total);
            w.config = Some(config.into());
            w.wind_speed = [u, u];
            w.amplitude = [18.0, 24.0];
            where_.push(w);
        }
    }
    for (st, s) in [("|alpha| > 0.5 A", 0.8), ("|alpha| < 0.5 A", 0.2)] {
        let mut w = share("state", Level::Aerodynamic, "moment", "all", s);
        w.state = Some(st.into());
        where_.push(w);
    }
    LevelResult {
        interpolated_gap_statistic: None,
        model_level: None,
        level: Level::Aerodynamic,
        metric: "normalised force residual".into(),
        before: 0.12,
        noise_level: 0.02,
        significant_gap: true,
        gap_statistic: 42.0,
        gap_threshold: 3.0,
        held_out_cases: ids,
        candidates,
        where_,
        cases,
        spectra: vec![
            spectrum(Level::Aerodynamic, "lift", "f/f_alpha", 1.0, 10.0),
            spectrum(Level::Aerodynamic, "moment", "f/f_alpha", 1.0, 10.0),
        ],
        signatures: vec![
            SignatureTest {
                name: "odd_harmonics".into(),
                level: Level::Aerodynamic,
                statistic: 14.2,
                threshold: 3.0,
                detected: true,
                detail: "energy at 5f, 7f is 14.2× the floor".into(),
            },
            SignatureTest {
                name: "amplitude_threshold".into(),
                level: Level::Aerodynamic,
                statistic: 6.1,
                threshold: 3.0,
                detected: true,
                detail: "residual switches on above 15 deg".into(),
            },
            SignatureTest {
                name: "whiteness".into(),
                level: Level::Aerodynamic,
                statistic: 0.8,
                threshold: 2.0,
                detected: false,
                detail: "Ljung–Box ratio <1> & \"quoted\"".into(),
            },
        ],
        observables: vec![ObservableGap {
            name: "force residual".into(),
            level: Level::Aerodynamic,
            unit: "-".into(),
            before: 0.12,
            after: 0.025,
            shrink: 1.0 - 0.025 / 0.12,
        }],
        bifurcation: None,
        fold_scheme: None,
        coverage: None,
        structure: None,
        control: None,
    }
}

fn structural_level() -> LevelResult {
    let uf = 6.595;
    let us: Vec<f64> = [0.5, 0.7, 0.85, 0.95, 1.05, 1.15]
        .iter()
        .map(|r| r * uf)
        .collect();
    let pt = |u: f64, a: f64, f: f64| BifurcationPoint {
        wind_speed: u,
        amplitude: a,
        frequency: f,
    };
    let lco = |u: f64, cap: f64| {
        if u > uf {
            cap * ((u - uf) / uf).sqrt() * 3.0
        } else {
            0.05
        }
    };
    let cases = us
        .iter()
        .enumerate()
        .map(|(i, &u)| CaseGap {
            id: format!("free-{i}"),
            level: Level::Structural,
            config: None,
            wind_speed: u,
            amplitude: 4.0,
            fold: i,
            before: 0.05,
            after: 0.04,
            noise_level: 0.03,
        })
        .collect();
    LevelResult {
        interpolated_gap_statistic: None,
        model_level: None,
        level: Level::Structural,
        metric: "normalised free-response residual".into(),
        before: 0.05,
        noise_level: 0.03,
        significant_gap: false,
        gap_statistic: 1.2,
        gap_threshold: 3.0,
        held_out_cases: (0..6).map(|i| format!("free-{i}")).collect(),
        candidates: vec![
            candidate(
                Effect::StructuralCubic,
                Level::Structural,
                0.05,
                0.045,
                false,
            ),
            candidate(Effect::Freeplay, Level::Structural, 0.05, 0.049, false),
            candidate(Effect::Friction, Level::Structural, 0.05, 0.051, false),
        ],
        where_: vec![share("channel", Level::Structural, "pitch", "all", 1.0)],
        cases,
        spectra: vec![
            spectrum(Level::Structural, "heave", "Hz", 2.0, 20.0),
            spectrum(Level::Structural, "pitch", "Hz", 3.5, 20.0),
        ],
        signatures: vec![SignatureTest {
            name: "amplitude_dependent_frequency".into(),
            level: Level::Structural,
            statistic: 0.4,
            threshold: 3.0,
            detected: false,
            detail: "no frequency drift".into(),
        }],
        observables: vec![
            ObservableGap {
                name: "LCO pitch amplitude".into(),
                level: Level::Structural,
                unit: "deg".into(),
                before: 4.1,
                after: 0.6,
                shrink: 1.0 - 0.6 / 4.1,
            },
            ObservableGap {
                name: "flutter speed".into(),
                level: Level::Structural,
                unit: "m/s".into(),
                before: 0.3,
                after: 0.05,
                shrink: 1.0 - 0.05 / 0.3,
            },
        ],
        bifurcation: Some(Bifurcation {
            measured: us
                .iter()
                .map(|&u| pt(u, lco(u, 4.0), 2.9 + 0.02 * u))
                .chain([pt(f64::NAN, 1.0, 1.0)])
                .collect(),
            predicted_before: us
                .iter()
                .map(|&u| pt(u, lco(u, 7.0), 2.85 + 0.02 * u))
                .collect(),
            predicted_after: us
                .iter()
                .map(|&u| pt(u, lco(u, 4.3), 2.9 + 0.021 * u))
                .collect(),
        }),
        fold_scheme: None,
        coverage: None,
        structure: None,
        control: None,
    }
}

fn full_diagnosis() -> Diagnosis {
    let aero = aero_level();
    let st = structural_level();
    let mut where_ = vec![
        share("level", Level::Aerodynamic, "all", "all", 0.9),
        share("level", Level::Structural, "all", "all", 0.1),
    ];
    where_.extend(aero.where_.iter().cloned());
    where_.extend(st.where_.iter().cloned());
    let mut candidates = aero.candidates.clone();
    candidates.extend(st.candidates.iter().cloned());
    Diagnosis {
        format: FORMAT.into(),
        verdict: VerdictReport {
            effect: diagnose::Verdict::Effect(Effect::DynamicStall),
            level: Level::Aerodynamic,
            confidence: 0.93,
            reason: "dynamic_stall removes 79 % of the held-out force gap (significant, \
                     statistic 9.5 > 3); residual switches on above 15 deg <amplitude>."
                .into(),
        },
        gap: GapReport {
            metric: aero.metric.clone(),
            before: 0.12,
            after: 0.025,
            shrink: 1.0 - 0.025 / 0.12,
            excess_shrink: 1.0 - (0.025f64.powi(2) - 0.0004).sqrt() / (0.0144f64 - 0.0004).sqrt(),
            noise_level: 0.02,
            held_out_cases: aero.held_out_cases.clone(),
        },
        where_,
        candidates,
        levels: vec![aero, st],
        seed: 7,
        version: "aeroform 0.1.0 (test)".into(),
        inputs: vec!["blind/forced".into(), "blind/free".into()],
        follow_up: None,
    }
}

fn minimal_diagnosis() -> Diagnosis {
    Diagnosis {
        format: FORMAT.into(),
        verdict: VerdictReport {
            effect: diagnose::Verdict::None,
            level: Level::None,
            confidence: f64::NAN,
            reason: "no level given".into(),
        },
        gap: GapReport {
            metric: "normalised force residual".into(),
            before: f64::NAN,
            after: f64::NAN,
            shrink: f64::NAN,
            excess_shrink: f64::NAN,
            noise_level: 0.0,
            held_out_cases: vec![],
        },
        where_: vec![],
        candidates: vec![],
        levels: vec![],
        seed: 0,
        version: String::new(),
        inputs: vec![],
        follow_up: None,
    }
}

/// Levels present but every value unusable: NaN gaps, zero noise, empty spectra, a
/// bifurcation with only NaN points, a where-split with NaN shares.
fn nan_diagnosis() -> Diagnosis {
    let mut d = full_diagnosis();
    for lv in &mut d.levels {
        for c in &mut lv.cases {
            c.before = f64::NAN;
            c.noise_level = 0.0;
        }
        for c in &mut lv.candidates {
            c.after = f64::NAN;
        }
        lv.before = f64::NAN;
        for s in &mut lv.spectra {
            s.before.iter_mut().for_each(|v| *v = f64::NAN);
            s.after.clear();
        }
        if let Some(b) = &mut lv.bifurcation {
            for p in b.measured.iter_mut().chain(&mut b.predicted_before) {
                p.amplitude = f64::NAN;
                p.frequency = f64::NAN;
            }
            b.predicted_after.clear();
        }
    }
    d.levels[1].spectra.push(ResidualSpectrum {
        level: Level::Structural,
        channel: diagnose::report::Channel::Pitch,
        frequency_unit: "Hz".into(),
        frequency: vec![],
        before: vec![],
        after: vec![],
    });
    for w in &mut d.where_ {
        w.share = f64::NAN;
    }
    d
}

// ---------------------------------------------------------------- well-formedness

/// Minimal XML well-formedness check: balanced, properly nested tags; quoted attributes;
/// known entities only. `void` lists HTML elements without a closing tag.
fn check_markup(text: &str, void: &[&str]) -> Result<usize, String> {
    let mut stack: Vec<String> = vec![];
    let mut n = 0;
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'<' => {
                let rest = &text[i..];
                if rest.starts_with("<!--") {
                    i += rest.find("-->").ok_or("open comment")? + 3;
                    continue;
                }
                let end = rest.find('>').ok_or_else(|| format!("open tag at {i}"))?;
                let tag = &rest[1..end];
                i += end + 1;
                if tag.starts_with('?') || tag.starts_with('!') {
                    continue;
                }
                if let Some(name) = tag.strip_prefix('/') {
                    let top = stack.pop().ok_or_else(|| format!("stray </{name}>"))?;
                    if top != name.trim() {
                        return Err(format!("</{name}> closes <{top}>"));
                    }
                    continue;
                }
                let self_closing = tag.ends_with('/');
                let body = tag.trim_end_matches('/');
                let name = body.split_whitespace().next().ok_or("empty tag")?;
                if !body.matches('"').count().is_multiple_of(2) {
                    return Err(format!(
                        "unbalanced quotes in <{}>",
                        &body[..body.len().min(60)]
                    ));
                }
                n += 1;
                if !self_closing && !void.contains(&name.to_ascii_lowercase().as_str()) {
                    stack.push(name.to_string());
                }
            }
            b'&' => {
                let rest = &text[i..];
                let end = rest.find(';').ok_or("open entity")?;
                let ent = &rest[1..end];
                let ok = matches!(ent, "amp" | "lt" | "gt" | "quot" | "apos" | "#39")
                    || (ent.starts_with('#')
                        && ent[1..].chars().all(|c| c.is_ascii_alphanumeric()));
                if !ok {
                    return Err(format!("unknown entity &{ent};"));
                }
                i += end + 1;
            }
            _ => i += 1,
        }
    }
    if let Some(open) = stack.pop() {
        return Err(format!("<{open}> never closed"));
    }
    Ok(n)
}

const HTML_VOID: &[&str] = &["meta", "br", "hr", "img", "link", "input", "!doctype"];

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}

fn names(paths: &[PathBuf]) -> Vec<String> {
    paths
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect()
}

// ---------------------------------------------------------------- tests

#[test]
fn checker_rejects_broken_markup() {
    assert!(check_markup("<a><b></a></b>", &[]).is_err());
    assert!(check_markup("<a>", &[]).is_err());
    assert!(check_markup("<a>x &foo; y</a>", &[]).is_err());
    assert_eq!(check_markup("<a x=\"1\"><b/>&amp;</a>", &[]), Ok(2));
}

#[test]
fn full_diagnosis_writes_every_figure_and_a_wellformed_report() {
    let dir = tempfile::tempdir().unwrap();
    let paths = write_diagnosis_outputs(&full_diagnosis(), dir.path()).unwrap();
    let n = names(&paths);
    for stem in [
        "diagnosis_gap_heatmap",
        "diagnosis_residual_spectra",
        "diagnosis_candidate_ranking",
        "diagnosis_bifurcation",
        "diagnosis_where_shares",
    ] {
        for ext in ["png", "svg"] {
            assert!(
                n.contains(&format!("{stem}.{ext}")),
                "{stem}.{ext} in {n:?}"
            );
        }
    }
    assert_eq!(n.last().unwrap(), "diagnosis.html");
    assert_eq!(paths.len(), 11);
    for p in &paths {
        assert!(p.is_file(), "{}", p.display());
        let len = std::fs::metadata(p).unwrap().len();
        assert!(len > 1000, "{} has only {len} bytes", p.display());
        if p.extension().unwrap() == "svg" {
            let svg = read(p);
            check_markup(&svg, &[]).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert!(svg.trim_start().starts_with("<svg"));
        }
        if p.extension().unwrap() == "png" {
            assert_eq!(&std::fs::read(p).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
        }
    }
    // No temporary files left behind.
    let left: Vec<_> = std::fs::read_dir(dir.path().join("figures"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| !f.ends_with(".png") && !f.ends_with(".svg"))
        .collect();
    assert!(left.is_empty(), "{left:?}");

    let html = read(&dir.path().join("diagnosis.html"));
    let tags = check_markup(&html, HTML_VOID).unwrap();
    assert!(tags > 500, "{tags} tags");
    assert_eq!(html.matches("<svg").count(), 5);
    assert_eq!(html.matches("<figcaption>").count(), 5);
    assert!(!html.contains("Not drawn"));
    for s in [
        "<h2 id=\"verdict\">Verdict</h2>",
        "<h2 id=\"gap\">Gap</h2>",
        "<h2 id=\"where\">Where</h2>",
        "<h2 id=\"candidates\">Candidates</h2>",
        "<h2 id=\"observables\">Observables</h2>",
        "<h2 id=\"signature-tests\">Signature tests</h2>",
        "<h2 id=\"figures\">Figures</h2>",
        "dynamic_stall",
        "above 15 deg &lt;amplitude&gt;.",
        "Ljung–Box ratio &lt;1&gt; &amp; &quot;quoted&quot;",
        "no off-harmonic line above the floor",
        "LCO pitch amplitude",
        "2*f_alpha+f_h",
        "|alpha| &gt; 0.5 A",
        "tau_s\u{a0}=\u{a0}0.0025",
        "not fitted: no off-harmonic line",
    ] {
        assert!(html.contains(s), "report lacks {s:?}");
    }
    for bad in ["<script", "<link", "src=", "@import", "url("] {
        assert!(!html.contains(bad), "external resource marker {bad}");
    }
    // links only to anchors of the page (the navigation bar)
    assert_eq!(
        html.matches("href=").count(),
        html.matches("href=\"#").count()
    );
    // Gap table: before / noise of the aerodynamic level = 0.12 / 0.02.
    assert!(
        html.contains("<td class=\"num\">6.000</td>"),
        "before/noise ratio"
    );
}

#[test]
fn minimal_diagnosis_writes_only_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let paths = write_diagnosis_outputs(&minimal_diagnosis(), dir.path()).unwrap();
    assert_eq!(names(&paths), vec!["diagnosis.html"]);
    let html = read(&paths[0]);
    check_markup(&html, HTML_VOID).unwrap();
    assert_eq!(html.matches("<svg").count(), 0);
    for s in [
        "Not drawn: gap_heatmap",
        "candidate_ranking (no candidate scored)",
        "No candidate scored.",
        "No where-split reported (diagnosis.json has no `where` cells).",
        "No signature test reported.",
        "<td>–</td>",
    ] {
        assert!(html.contains(s), "report lacks {s:?}");
    }
}

#[test]
fn nan_and_empty_inputs_draw_notes_not_panics() {
    let d = nan_diagnosis();
    // Every adapter still yields a figure (levels exist), whose panels show notes.
    let hm = gap_heatmap_figure(&d).unwrap();
    assert!(hm
        .panels
        .iter()
        .all(|p| p.values.iter().flatten().all(Option::is_none)));
    let dir = tempfile::tempdir().unwrap();
    let paths = write_diagnosis_outputs(&d, dir.path()).unwrap();
    assert_eq!(paths.len(), 11, "{:?}", names(&paths));
    let svg = read(&dir.path().join("figures/diagnosis_gap_heatmap.svg"));
    assert!(
        svg.matches("no data").count() >= 4,
        "one note per empty panel"
    );
    let svg = read(&dir.path().join("figures/diagnosis_residual_spectra.svg"));
    assert_eq!(
        svg.matches("no data").count(),
        5,
        "every spectrum panel empty"
    );
    let svg = read(&dir.path().join("figures/diagnosis_candidate_ranking.svg"));
    assert!(svg.contains("no value") && svg.contains("not fitted"));
    for p in &paths {
        if p.extension().unwrap() == "svg" {
            check_markup(&read(p), &[]).unwrap();
        }
    }
}

#[test]
fn outputs_are_byte_identical_across_runs() {
    let d = full_diagnosis();
    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    let pa = write_diagnosis_outputs(&d, a.path()).unwrap();
    let pb = write_diagnosis_outputs(&d, b.path()).unwrap();
    assert_eq!(names(&pa), names(&pb));
    for (x, y) in pa.iter().zip(&pb) {
        assert!(
            std::fs::read(x).unwrap() == std::fs::read(y).unwrap(),
            "{} differs between runs",
            x.display()
        );
    }
}

#[test]
fn missing_output_folder_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope");
    let e = write_diagnosis_outputs(&full_diagnosis(), &missing).unwrap_err();
    assert!(e.to_string().contains("nope"), "{e}");
    assert!(!missing.exists());
}

#[test]
fn adapters_map_values_without_computation() {
    let d = full_diagnosis();
    // Heat map: 2 configs × (before, after); cell = before / noise of that case.
    let hm = gap_heatmap_figure(&d).unwrap();
    assert_eq!(hm.panels.len(), 4);
    assert_eq!(hm.panels[0].title, "config B: before");
    assert_eq!(hm.panels[1].title, "config B: after (+ dynamic_stall)");
    assert_eq!(hm.panels[0].x_values, vec![6.0, 12.0, 18.0, 24.0]);
    assert_eq!(hm.panels[0].y_values, vec![4.0, 5.5, 7.0, 8.5, 10.0]);
    // Case B, U = 10 (iu = 4), A = 24 (ia = 3): before = noise·(1 + 0.4·3·5).
    let r = hm.panels[0].values[4][3].unwrap();
    assert!((r - 7.0).abs() < 1e-12, "{r}");
    let r_after = hm.panels[1].values[0][0].unwrap();
    assert!((r_after - 0.9).abs() < 1e-12, "{r_after}");

    // Ranking: one panel per level, best first, significance carried over.
    let rk = ranking_figure(&d).unwrap();
    assert_eq!(rk.panels.len(), 2);
    assert_eq!(rk.panels[0].bars.len(), 6);
    assert!(rk.panels[0].bars[0].label.starts_with("dynamic_stall"));
    assert!(rk.panels[0].bars[0].highlight && !rk.panels[0].bars[2].highlight);
    assert!(rk.panels[0].bars[5].value.is_nan());
    assert!(rk.panels[0].bars[5].note.starts_with("not fitted"));
    assert_eq!(rk.panels[0].baseline, Some(0.12));
    assert_eq!(rk.panels[0].noise_level, Some(0.02));

    // Shares: harmonic split has 9 cells → MAX_SEGMENTS kept + "other" summing the rest.
    let sh = shares_figure(&d).unwrap();
    let harm = sh
        .bars
        .iter()
        .find(|b| b.label == "aerodynamic: harmonic")
        .unwrap();
    assert_eq!(harm.segments.len(), MAX_SEGMENTS + 1);
    assert_eq!(harm.segments[0].label, "moment 3*f_alpha");
    let last = harm.segments.last().unwrap();
    assert_eq!(last.label, "other (2)");
    assert!((last.share - 0.04).abs() < 1e-12);
    let total: f64 = harm.segments.iter().map(|s| s.share).sum();
    assert!((total - 1.0).abs() < 1e-12, "{total}");
    let region = sh
        .bars
        .iter()
        .find(|b| b.label == "aerodynamic: region")
        .unwrap();
    assert_eq!(region.segments[0].label, "B, U 10, A 18–24");

    // Spectra: one panel per (level, channel).
    let sp = residual_spectra_figure(&d).unwrap();
    assert_eq!(sp.panels.len(), 4);
    assert_eq!(sp.panels[0].x_label, "f / f_α [-]");
    assert_eq!(sp.panels[3].x_label, "f [Hz]");

    // Bifurcation: amplitude and frequency panels, three curves.
    let bf = bifurcation_figure(&d).unwrap();
    assert_eq!(bf.panels.len(), 2);
    assert_eq!(bf.panels[0].predicted.len(), 2);
    assert_eq!(bf.panels[1].measured.y[0], 2.9 + 0.02 * 0.5 * 6.595);

    // Nothing to draw → None.
    let m = minimal_diagnosis();
    assert!(gap_heatmap_figure(&m).is_none());
    assert!(ranking_figure(&m).is_none());
    assert!(shares_figure(&m).is_none());
    assert!(residual_spectra_figure(&m).is_none());
    assert!(bifurcation_figure(&m).is_none());
}

/// Writes the full, minimal and NaN diagnoses into `$AEROFORM_PREVIEW` (default: the
/// temporary folder) for a human to look at.
#[test]
#[ignore = "writes preview files for a human to look at"]
fn render_diagnosis_previews() {
    let root = std::env::var_os("AEROFORM_PREVIEW")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("aeroform-diagnosis-preview"));
    for (name, d) in [
        ("full", full_diagnosis()),
        ("minimal", minimal_diagnosis()),
        ("nan", nan_diagnosis()),
    ] {
        let dir = root.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        write_diagnosis_outputs(&d, &dir).unwrap();
    }
}
