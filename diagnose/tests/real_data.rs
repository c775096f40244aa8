//! End-to-end diagnosis of real measured data (reduced copies in `tests/data`, see its
//! README.md): the Bristol rig's free response against its authors' linear model, and
//! pitch-only dynamic-stall campaigns with two and one (configuration, wind speed) groups.

use std::path::PathBuf;
use std::sync::Arc;

use aeroelastic::aero::AeroModel;
use aeroelastic::files::LoadedModel;
use diagnose::pipeline::{diagnose, diagnose_free, merge_free, DiagnoseOptions};
use diagnose::{Effect, Level};
use identify::dataset::read_dataset;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn bristol_model() -> Arc<dyn AeroModel> {
    let p =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenarios/bristol-spring1.model.toml");
    LoadedModel::load(&p, None).unwrap().model
}

/// The measured amplitudes table: (branch, U, pitch amplitude \[rad\], frequency \[Hz\]) of the
/// rows fitted from the time series.
fn amplitudes_table() -> Vec<(String, f64, f64, f64)> {
    let text = std::fs::read_to_string(data("bristol-spring1-lco-amplitudes.csv")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("spring"))
        .filter(|l| l.contains("time series"))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[1].to_string(),
                f[2].parse().unwrap(),
                f[4].parse().unwrap(),
                f[5].parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn bristol_free_response_against_the_rigs_linear_model() {
    let t = std::time::Instant::now();
    let lco = read_dataset(&data("bristol-spring1")).unwrap();
    let still = read_dataset(&data("bristol-spring1-still-air")).unwrap();
    let free = merge_free(&[still, lco]).unwrap();
    let d = diagnose_free(&free, &bristol_model(), &DiagnoseOptions::new(1), "test").unwrap();
    assert!(t.elapsed().as_secs_f64() < 60.0, "{:?}", t.elapsed());
    let l = &d.levels[0];
    assert_eq!(l.level, Level::Structural);
    // every run held out once, the still-air run included
    let fs = l.fold_scheme.as_ref().unwrap();
    assert_eq!((fs.scheme.as_str(), fs.folds), ("leave_one_run_out", 10));
    assert!(l.cases.iter().any(|c| c.wind_speed == 0.0));
    // where: a significant gap, most of it in pitch
    assert!(
        l.significant_gap && l.gap_statistic > 10.0,
        "{}",
        l.gap_statistic
    );
    let pitch = l
        .where_
        .iter()
        .find(|w| {
            w.split == diagnose::report::Split::Channel
                && w.channel == diagnose::report::Channel::Pitch
        })
        .unwrap();
    assert!(pitch.share > 0.5, "pitch share {}", pitch.share);
    // which: the stiffness polynomial is a significant candidate, fitted on training runs
    // and scored on held-out runs; a hardening cubic pitch spring (k3 > 0 in the reported
    // restoring-force convention)
    let poly = l
        .candidates
        .iter()
        .find(|c| c.effect == Effect::StructuralPolynomial)
        .unwrap();
    assert!(poly.significant && poly.shrink > 0.05, "{poly:?}");
    let k3 = poly
        .parameters
        .iter()
        .find(|p| p.0 == "k3_pitch_Nm_per_rad3")
        .unwrap()
        .1;
    assert!(k3 > 0.0, "k_alpha3 {k3}");
    // the measured LCOs the report compares with are the authors' table: amplitude within
    // 5 % (peak over the record's end vs first-harmonic fit) and frequency within 1 %
    let bif = l.bifurcation.as_ref().unwrap();
    let table = amplitudes_table();
    assert_eq!(table.len(), 9);
    let mut matched = 0;
    for (_, u, amp, f) in &table {
        let best = bif
            .measured
            .iter()
            .filter(|p| (p.wind_speed - u).abs() < 0.15)
            .min_by(|a, b| {
                (a.amplitude - amp.to_degrees())
                    .abs()
                    .total_cmp(&(b.amplitude - amp.to_degrees()).abs())
            })
            .unwrap();
        let ea = (best.amplitude / amp.to_degrees() - 1.0).abs();
        let ef = (best.frequency / f - 1.0).abs();
        assert!(
            ea < 0.05 && ef < 0.01,
            "U {u}: {best:?} vs {amp} rad {f} Hz"
        );
        matched += 1;
    }
    assert_eq!(matched, 9);

    // issue 42 item 3: the nine LCO records were taken under feedback control; the
    // controller's raw output enters the heave equation as g·u + o, fitted held out
    let c = l.control.as_ref().expect("controlled records");
    assert_eq!((c.signal.as_str(), c.dof.as_str()), ("raw", "heave"));
    assert_eq!(c.runs.len(), 9);
    assert!(c.runs.iter().all(|r| r.wind_speed > 0.0));
    // the data show no heave force of the controller: the gain's interval holds zero
    // (full records: 30 ± 677 N/m per unit), the held-out heave fit removes nothing, and
    // even a gain and offset fitted on each run alone remove at most 18 % of a run's
    // heave residual energy (full records; 2 of 9 runs above 10 %)
    let g = c.gain.unwrap();
    assert!(g.low < 0.0 && g.high > 0.0, "{g:?}");
    let heave = c.dof_check.iter().find(|d| d.dof == "heave").unwrap();
    assert!(heave.removed < 0.02, "{heave:?}");
    for r in &c.runs {
        let best = r.best_share.unwrap();
        assert!(best[0] < 0.25, "{r:?}");
    }
    // so the gap stays where it was, within 1 %, and every LCO record keeps 0.7–0.9 of its
    // heave and 1.0–1.2 of its pitch structural force
    assert!(
        (c.gap_with / c.gap_without - 1.0).abs() < 0.01,
        "{} vs {}",
        c.gap_with,
        c.gap_without
    );
    assert!((l.before - c.gap_with).abs() < 1e-12);
    // the feedback law cannot be rebuilt (a PD law on h_target − h reproduces 8–92 % of
    // the signal's variance): the controlled runs are not simulated as if free — only the
    // still-air decay has a simulated point, and the nine measured points are kept
    assert!(c.runs.iter().any(|r| r.pd_law.unwrap().r2 < 0.5));
    assert!(c.simulation.contains("not simulated"));
    assert_eq!(bif.measured.len(), 10);
    assert_eq!(bif.predicted_before.len(), 1);
    assert_eq!(bif.predicted_before[0].wind_speed, 0.0);
}

/// The still-air decay has no control column: its residual, its gap and the structure
/// check are those of the same diagnosis with the LCO records' control columns dropped.
#[test]
fn bristol_still_air_decay_is_unaffected_by_the_control_columns() {
    let lco = read_dataset(&data("bristol-spring1")).unwrap();
    let mut bare = lco.clone();
    for r in &mut bare.records {
        r.control = None;
    }
    let still = read_dataset(&data("bristol-spring1-still-air")).unwrap();
    let opts = DiagnoseOptions::new(1);
    let with = diagnose_free(
        &merge_free(&[still.clone(), lco]).unwrap(),
        &bristol_model(),
        &opts,
        "test",
    )
    .unwrap();
    let without = diagnose_free(
        &merge_free(&[still, bare]).unwrap(),
        &bristol_model(),
        &opts,
        "test",
    )
    .unwrap();
    let (a, b) = (&with.levels[0], &without.levels[0]);
    assert!(b.control.is_none());
    let still_case =
        |l: &diagnose::LevelResult| l.cases.iter().find(|c| c.wind_speed == 0.0).unwrap().before;
    assert_eq!(still_case(a), still_case(b));
    assert_eq!(a.structure, b.structure);
    // the records read as if free give the controlled level's `gap_without`
    let c = a.control.as_ref().unwrap();
    assert!(
        (b.before - c.gap_without).abs() < 1e-12,
        "{} {}",
        b.before,
        c.gap_without
    );
}

#[test]
fn pitch_only_campaign_with_two_groups_is_diagnosed_leave_one_group_out() {
    let ds = read_dataset(&data("osu-ls417")).unwrap();
    let d = diagnose(&ds, None, &DiagnoseOptions::new(1), "test").unwrap();
    let fs = d.levels[0].fold_scheme.as_ref().unwrap();
    assert_eq!(
        (fs.scheme.as_str(), fs.folds, fs.groups),
        ("leave_one_group_out", 2, 2)
    );
    assert_eq!(d.levels[0].cases.len(), 2);
    assert!(d.levels[0].before.is_finite() && d.levels[0].before > 0.0);
}

/// The memoryless law misses the LS417's dynamic stall (held-out lift R² 0.20 and 0.43): the
/// force level's gap stands significantly above its noise level. The noise level is not read
/// from the records' broadband content above fs/16 (a spectral floor alone read 0.133
/// there, against 0.043, and declared the gap noise: DECISIONS, "The follow-up loop's
/// remaining misses (round 35)").
#[test]
fn a_law_error_on_real_stall_records_is_not_read_as_noise() {
    let ds = read_dataset(&data("osu-ls417")).unwrap();
    let d = diagnose(&ds, None, &DiagnoseOptions::new(1), "test").unwrap();
    let l = &d.levels[0];
    assert!(
        l.significant_gap && l.gap_statistic > l.gap_threshold,
        "gap {} noise {} statistic {} threshold {}",
        l.before,
        l.noise_level,
        l.gap_statistic,
        l.gap_threshold
    );
    assert!(l.noise_level < 0.1, "{}", l.noise_level);
}

/// The law with memory as the `dynamic_stall` form (issue 41 item 5): on the deep-stall
/// S809 pair (18.8° ± 10.7°, K = 0.05 and 0.1) each record is predicted from a lag law
/// fitted on the other, and that beats the section's memoryless law by more than the naming
/// rule's 30 % of the excess; the verdict carries the fitted constants.
#[test]
fn deep_stall_records_are_named_dynamic_stall_by_the_law_with_memory() {
    let ds = read_dataset(&data("osu-s809")).unwrap();
    let d = diagnose(&ds, None, &DiagnoseOptions::new(1), "test").unwrap();
    assert_eq!(
        d.verdict.effect,
        diagnose::Verdict::Effect(Effect::DynamicStall),
        "{:?}",
        d.verdict
    );
    let c = d.levels[0]
        .candidates
        .iter()
        .find(|c| c.effect == Effect::DynamicStall)
        .unwrap();
    assert!(c.significant && c.shrink > 0.25, "{c:?}");
    let tau1: Vec<f64> = c
        .parameters
        .iter()
        .filter(|(n, _)| n.contains("lag_law_tau1"))
        .map(|p| p.1)
        .collect();
    assert_eq!(tau1.len(), 2, "{:?}", c.parameters);
    assert!(tau1.iter().all(|t| *t > 0.5 && *t < 100.0), "{tau1:?}");
}

#[test]
fn one_group_is_a_clear_error() {
    let ds = read_dataset(&data("gu-naca0015")).unwrap();
    let e = diagnose(&ds, None, &DiagnoseOptions::new(1), "test")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("1 (configuration, wind speed) group") && e.contains("at least 2"),
        "{e}"
    );
}
