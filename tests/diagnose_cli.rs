//! End-to-end tests of `aeroform diagnose` on data sets written to disk in the public format
//! (DATA_FORMAT.md), as another program would hand them over: the blind generator writes
//! `forced/`, `free/` and a separate `truth.json` that the command never reads.

use std::path::Path;

use aeroelastic::effects::Form;
use benchmark::blind::{generate, write_blind, BlindEffect, BlindScenario};
use diagnose::Effect;

use crate::common;
use common::aeroform;

fn write_set(dir: &Path, effect: BlindEffect, strength: f64, seed: u64) {
    let set = generate(
        effect,
        strength,
        Form::Primary,
        seed,
        &BlindScenario::default(),
    )
    .unwrap();
    write_blind(dir, &set).unwrap();
}

#[test]
fn diagnose_writes_a_complete_diagnosis_from_folders() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("set");
    write_set(&data, BlindEffect::Catalogue(Effect::StaticOffset), 0.9, 21);
    let out = tmp.path().join("out");
    let (ok, stdout, stderr) = aeroform(&[
        "diagnose",
        data.join("forced").to_str().unwrap(),
        "--free",
        data.join("free").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--seed",
        "5",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let text = std::fs::read_to_string(out.join("diagnosis.json")).unwrap();
    let d: diagnose::Diagnosis = serde_json::from_str(&text).unwrap();
    assert_eq!(d.format, "aeroform-diagnosis/1");
    assert_eq!(d.seed, 5);
    assert_eq!(d.levels.len(), 2);
    assert_eq!(
        d.verdict.effect,
        diagnose::Verdict::Effect(diagnose::Effect::StaticOffset),
        "{stdout}"
    );
    assert!(d.gap.after < d.gap.before);
    // Every forced case is held out exactly once.
    let held = &d.levels[0].held_out_cases;
    let mut sorted = held.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), held.len());
    assert_eq!(held.len(), 40);
    assert!(out.join("diagnosis.html").is_file());
    assert!(out.join("figures/diagnosis_gap_heatmap.png").is_file());
    assert!(stdout.contains("verdict: static_offset"), "{stdout}");
    // The truth file exists beside the data sets, and the diagnosis never names it.
    assert!(data.join("truth.json").is_file());
    assert!(!text.contains("truth.json"));
}

#[test]
fn diagnose_bad_inputs_are_clear_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let missing = tmp.path().join("nope");
    let (ok, _, stderr) = aeroform(&[
        "diagnose",
        missing.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(stderr.contains("nope"), "{stderr}");
    assert!(!out.join("diagnosis.json").exists());

    // A free data set given as the forced one: no forced cases.
    let data = tmp.path().join("set");
    write_set(&data, BlindEffect::None, 0.0, 3);
    let (ok, _, stderr) = aeroform(&[
        "diagnose",
        data.join("free").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(stderr.contains("forced"), "{stderr}");
    assert!(!out.join("diagnosis.json").exists());

    let (ok, _, stderr) = aeroform(&["diagnose", "--blind", "0", "--out", out.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        stderr.contains("--blind") && stderr.contains("1..="),
        "{stderr}"
    );
}

/// Free runs beyond the forced K range (forced wind speeds cut to 7–10 m/s, free runs at
/// 4.6–7.6 m/s): the command says `extrapolation`, and the report's Coverage section lists
/// every run with its K and the forced cases that would cover it.
#[test]
fn diagnose_reports_coverage_and_extrapolation() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("set");
    let mut scenario = BlindScenario::default();
    scenario.campaign.wind_speeds = vec![7.0, 8.5, 10.0];
    let set = generate(BlindEffect::None, 0.0, Form::Primary, 3, &scenario).unwrap();
    write_blind(&data, &set).unwrap();
    let out = tmp.path().join("diag");
    let (ok, stdout, stderr) = aeroform(&[
        "diagnose",
        data.join("forced").to_str().unwrap(),
        "--free",
        data.join("free").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap())
            .unwrap();
    assert_eq!(doc["verdict"]["effect"], "extrapolation", "{stdout}");
    let cov = &doc["levels"][1]["coverage"];
    assert_eq!(cov["explains_gap"], true);
    assert_eq!(cov["runs"].as_array().unwrap().len(), 6);
    assert!(!cov["suggestions"].as_array().unwrap().is_empty());
    let html = std::fs::read_to_string(out.join("diagnosis.html")).unwrap();
    for s in [
        "Coverage",
        "Forced cases that would cover",
        "free-1",
        "K_α range",
        "Recommended forced tests",
    ] {
        assert!(html.contains(s), "report lacks {s:?}");
    }
    // the recommendation is a campaign file the virtual tunnel runs (issue 42 item 4)
    let plan_file = out.join("follow_up.campaign.toml");
    let plan = aeroelastic::tunnel::CampaignPlan::parse(
        &std::fs::read_to_string(&plan_file).unwrap(),
        "follow_up.campaign.toml",
    )
    .unwrap();
    assert_eq!(serde_json::to_value(&plan).unwrap(), doc["follow_up"]);
    let tests = tmp.path().join("follow-up");
    let (ok, stdout, stderr) = aeroform(&[
        "tunnel",
        "forced",
        "--model",
        "scenarios/plate-truth.model.toml",
        "--campaign-file",
        plan_file.to_str().unwrap(),
        "--duration",
        "1",
        "--out",
        tests.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let manifest = std::fs::read_to_string(tests.join("manifest.toml")).unwrap();
    assert_eq!(manifest.matches("[[case]]").count(), plan.cases().len());
    // a plan with a bad speed is refused naming the field
    let bad = tmp.path().join("bad.campaign.toml");
    std::fs::write(
        &bad,
        std::fs::read_to_string(&plan_file).unwrap().replacen(
            "wind_speeds = [",
            "wind_speeds = [-1.0, ",
            1,
        ),
    )
    .unwrap();
    let (ok, _, stderr) = aeroform(&[
        "tunnel",
        "forced",
        "--model",
        "scenarios/plate-truth.model.toml",
        "--campaign-file",
        bad.to_str().unwrap(),
        "--out",
        tmp.path().join("bad-out").to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("wind_speeds[0]"), "{stderr}");
    // every row states the record length it assumes; without --duration the tunnel
    // records at it (round 34)
    assert!(plan.rows.iter().all(|r| r.record_duration_s.is_some()));
    let mut short = plan.clone();
    for r in &mut short.rows {
        r.record_duration_s = Some(0.5);
    }
    let short_file = tmp.path().join("short.campaign.toml");
    std::fs::write(&short_file, short.to_toml().unwrap()).unwrap();
    let short_out = tmp.path().join("short-out");
    let (ok, stdout, stderr) = aeroform(&[
        "tunnel",
        "forced",
        "--model",
        "scenarios/plate-truth.model.toml",
        "--campaign-file",
        short_file.to_str().unwrap(),
        "--out",
        short_out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let set = identify::dataset::read_dataset(&short_out).unwrap();
    let r = &set.records[0];
    assert!(
        (r.h.len() as f64 * r.dt - 0.5).abs() < 2.0 * r.dt,
        "{} samples at {}",
        r.h.len(),
        r.dt
    );
    // a row asking for no records is refused naming the field
    let mut zero = plan.clone();
    zero.rows[0].repeats = Some(0);
    let zero_file = tmp.path().join("zero.campaign.toml");
    std::fs::write(&zero_file, toml::to_string(&zero).unwrap()).unwrap();
    let (ok, _, stderr) = aeroform(&[
        "tunnel",
        "forced",
        "--model",
        "scenarios/plate-truth.model.toml",
        "--campaign-file",
        zero_file.to_str().unwrap(),
        "--out",
        tmp.path().join("zero-out").to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("rows[0].repeats"), "{stderr}");
}
