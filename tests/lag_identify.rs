//! The lag law identified from forced records of the project's stall truth (issue 41):
//! held-out prediction of a reduced frequency against the memoryless law, the CLI's
//! `--law lag` document and its refusals (nothing written).

use crate::common;

use std::path::Path;

use aeroelastic::aero::{DynamicStallAero, Flow};
use aeroelastic::tunnel::{forced_forces, Motion, Sine};
use identify::lag::{compare, HoldOut, LagFitOptions, LagLawDocument};
use identify::record::{CaseMeta, Forcing, NondimCase};

const U: f64 = 10.0;
const CHORD: f64 = 0.25;
const RHO: f64 = 1.225;
const SAMPLES_PER_CYCLE: usize = 100;
const CYCLES: usize = 3;

/// One forced pitching case of the truth (`scenarios/plate-stall.model.toml`: the thin
/// plate's dynamic-stall model, elastic axis a = −0.3) at reduced frequency `k`, mean and
/// amplitude in degrees: (time, α, α̇, L, M), SI.
fn truth_case(
    k: f64,
    mean_deg: f64,
    amp_deg: f64,
) -> (f64, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let model = DynamicStallAero::thin_plate(CHORD, -0.3).unwrap();
    let flow = Flow { rho: RHO, u: U };
    let f = k * U / (2.0 * std::f64::consts::PI * CHORD);
    let motion = Motion {
        pitch: vec![Sine {
            freq: f,
            amplitude: amp_deg.to_radians(),
            phase: 0.0,
        }],
        heave: vec![],
        mean_pitch: mean_deg.to_radians(),
    };
    let dt = 1.0 / (f * SAMPLES_PER_CYCLE as f64);
    let n = SAMPLES_PER_CYCLE * CYCLES;
    // the lag states start on the attached-flow periodic solution: let the stall states settle
    let pre_roll = 2.0 / f + 60.0 * 0.5 * CHORD / U;
    let (l, m) = forced_forces(&model, &flow, &motion, 0.0, dt, n, pre_roll, "truth").unwrap();
    let mut a = Vec::with_capacity(n);
    let mut ad = Vec::with_capacity(n);
    for i in 0..n {
        let (q, qd, _) = motion.eval(i as f64 * dt);
        a.push(q[1]);
        ad.push(qd[1]);
    }
    (dt, a, ad, l, m)
}

fn nondim(id: &str, k: f64, mean_deg: f64, amp_deg: f64) -> NondimCase {
    let (dt, a, ad, l, m) = truth_case(k, mean_deg, amp_deg);
    let n = a.len();
    let q = 0.5 * RHO * U * U;
    NondimCase {
        meta: CaseMeta {
            id: id.into(),
            wind_speed: U,
            mean_pitch: Some(mean_deg.to_radians()),
            amplitude: Some(amp_deg.to_radians()),
            freq_pitch: Some(k * U / (2.0 * std::f64::consts::PI * CHORD)),
            ..CaseMeta::default()
        },
        dt,
        chord: CHORD,
        x: [
            a,
            ad.iter().map(|v| CHORD * v / U).collect(),
            vec![0.0; n],
            vec![0.0; n],
        ],
        c_lift: l.iter().map(|v| v / (q * CHORD)).collect(),
        c_moment: m.iter().map(|v| v / (q * CHORD * CHORD)).collect(),
        forcing: Forcing {
            pitch: Some(k * U / (2.0 * std::f64::consts::PI * CHORD)),
            heave: None,
        },
    }
}

/// The held-out comparison of the virtual acceptance: the truth in deep stall about
/// 15° (± 8°), fitted at K = 0.05 and 0.2, predicting K = 0.1; `circulation_lag` switches
/// the law's attached-flow (Jones) circulation lag.
fn virtual_held_out(
    circulation_lag: bool,
) -> (identify::lag::LagFit, identify::lag::HeldOutReport) {
    virtual_held_out_with(&LagFitOptions {
        circulation_lag,
        ..LagFitOptions::default()
    })
}

/// [`virtual_held_out`] with the given fit options.
fn virtual_held_out_with(
    opts: &LagFitOptions,
) -> (identify::lag::LagFit, identify::lag::HeldOutReport) {
    let train = vec![
        nondim("k005", 0.05, 15.0, 8.0),
        nondim("k020", 0.2, 15.0, 8.0),
    ];
    let test = vec![nondim("k010", 0.1, 15.0, 8.0)];
    compare(&train, &test, "k=0.1", opts).unwrap()
}

/// The same virtual held-out acceptance (lift R² ≥ 0.98, moment ≥ 0.95, not loosened) for
/// the optioned law of the stall-flutter round trip: rate share c and pressure lag τ_p
/// fitted by output error (`fit_rate_share`, `fit_pressure_lag`), the memoryless law
/// The held-out targets, not loosened: lift R² ≥ 0.98, moment R² ≥ 0.95, each
/// above the memoryless law's on the same held-out case.
fn assert_held_out_acceptance(row: &identify::lag::HeldOutRow) {
    assert!(
        row.lag_r2_lift >= 0.98,
        "held-out lift R² {}",
        row.lag_r2_lift
    );
    assert!(
        row.lag_r2_moment >= 0.95,
        "held-out moment R² {}",
        row.lag_r2_moment
    );
    assert!(row.lag_r2_lift > row.memoryless_r2_lift);
    assert!(row.lag_r2_moment > row.memoryless_r2_moment);
}

/// fitted on the same two cases beside it.
#[test]
fn optioned_law_fitted_on_two_frequencies_predicts_a_third() {
    let (fit, h) = virtual_held_out_with(&LagFitOptions {
        fit_rate_share: true,
        fit_pressure_lag: true,
        ..LagFitOptions::default()
    });
    let row = &h.rows[0];
    eprintln!(
        "optioned law, held out K = 0.1 at 15° ± 8°: lift R² memoryless {:.4} lag {:.4}; \
         moment R² memoryless {:.4} lag {:.4}; τ₁ {:.3} τ₂ {:.3} α* {:.2}° m {:.3} c {:.3} \
         τ_p {:.3}; notes {:?}",
        row.memoryless_r2_lift,
        row.lag_r2_lift,
        row.memoryless_r2_moment,
        row.lag_r2_moment,
        fit.law.tau1,
        fit.law.tau2,
        fit.law.alpha_star.to_degrees(),
        fit.law.sharpness,
        fit.law.rate_share,
        fit.law.pressure_lag,
        fit.report.notes
    );
    assert!(fit.law.check().is_ok());
    assert_held_out_acceptance(row);
}

/// The targets (held-out R² ≥ 0.98 lift, ≥ 0.95 moment), not loosened, with the
/// law as `identify --law lag` fits it (circulation lag on). Measured on this build: lift
/// 0.9871, moment 0.9974 (memoryless cubic on the same cases 0.9282, 0.9459); without the
/// circulation lag 0.962 / 0.973 (DECISIONS "The lag law's circulation lag and the
/// deep-stall round trip").
#[test]
fn stall_truth_fitted_on_two_frequencies_predicts_a_third() {
    let (fit, h) = virtual_held_out(true);
    let row = &h.rows[0];
    let (fit0, h0) = virtual_held_out(false);
    let row0 = &h0.rows[0];
    eprintln!(
        "held out K = 0.1 at 15° ± 8°: lift R² memoryless {:.4} lag {:.4} (no circulation lag {:.4}); \
         moment R² memoryless {:.4} lag {:.4} (no circulation lag {:.4}); \
         τ₁ {:.3} τ₂ {:.3} α* {:.4} m {:.3}; corr(τ₁, τ₂) {:?}; moment {:?}",
        row.memoryless_r2_lift,
        row.lag_r2_lift,
        row0.lag_r2_lift,
        row.memoryless_r2_moment,
        row.lag_r2_moment,
        row0.lag_r2_moment,
        fit.law.tau1,
        fit.law.tau2,
        fit.law.alpha_star,
        fit.law.sharpness,
        fit.report.tau_correlation,
        fit.report.moment_selection.selected
    );
    assert!(fit.law.check().is_ok() && fit0.law.check().is_ok());
    assert!(fit.law.circulation_lag && !fit0.law.circulation_lag);
    assert_held_out_acceptance(row);
    // the circulation lag is what closes the gap
    assert!(row.lag_r2_lift > row0.lag_r2_lift + 0.01);
    // the truth's constants (α₁ = 10°, m = 4, τ_f = 3, τ_p = 1.7): recovered in kind
    assert!((fit.law.alpha_star.to_degrees() - 10.0).abs() < 1.0);
    assert!(fit.law.tau1 > 1.0 && fit.law.tau1 < 5.0);
}

/// Writes a pitch-only data set of the truth (DATA_FORMAT.md) with the given cases
/// (id, K, mean°, amplitude°) and `cycles` periods per record.
fn write_dataset(dir: &Path, cases: &[(&str, f64, f64, f64)], cycles: f64) {
    write_dataset_with(dir, cases, cycles, false)
}

/// [`write_dataset`]; with `chirp` the angle column is replaced by a motion whose frequency
/// drifts by 40 % over the record (not periodic; the forces are left as they are).
fn write_dataset_with(dir: &Path, cases: &[(&str, f64, f64, f64)], cycles: f64, chirp: bool) {
    std::fs::create_dir_all(dir.join("cases")).unwrap();
    let mut manifest = String::from(
        "format = \"aeroform-dataset/1\"\nname = \"stall truth\"\n\n[section]\nchord = 0.25\nspan = 1.0\nair_density = 1.225\n\n\
         [units]\nheave = \"m\"\npitch = \"rad\"\nlift = \"N/m\"\nmoment = \"N*m/m\"\n",
    );
    for &(id, k, mean, amp) in cases {
        let (dt, a, _, l, m) = truth_case(k, mean, amp);
        let n = ((cycles * SAMPLES_PER_CYCLE as f64) as usize).min(a.len());
        let mut csv = String::from("t,h,alpha,lift,moment\n");
        let f = k * U / (2.0 * std::f64::consts::PI * CHORD);
        let dur = n as f64 * dt;
        for i in 0..n {
            let t = i as f64 * dt;
            let alpha = if chirp {
                (mean + amp * (2.0 * std::f64::consts::PI * f * t * (1.0 + 0.4 * t / dur)).sin())
                    .to_radians()
            } else {
                a[i]
            };
            csv.push_str(&format!("{t},0,{alpha},{},{}\n", l[i], m[i]));
        }
        std::fs::write(dir.join(format!("cases/{id}.csv")), csv).unwrap();
        manifest.push_str(&format!(
            "\n[[case]]\nid = \"{id}\"\nkind = \"forced\"\nfile = \"cases/{id}.csv\"\nwind_speed = {U}\n\
             amplitude = {}\nfreq_pitch = {f}\nmean_pitch = {}\n",
            amp.to_radians(),
            mean.to_radians()
        ));
    }
    std::fs::write(dir.join("manifest.toml"), manifest).unwrap();
}

#[test]
fn cli_writes_the_lag_law_document_with_the_held_out_table() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    write_dataset(
        &data,
        &[
            ("a", 0.05, 15.0, 8.0),
            ("b", 0.1, 15.0, 8.0),
            ("c", 0.2, 15.0, 8.0),
        ],
        3.0,
    );
    let out = tmp.path().join("out");
    let (ok, stdout, stderr) = common::aeroform(&[
        "identify",
        data.to_str().unwrap(),
        "--law",
        "lag",
        "--hold-out",
        "k=0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("τ₁") && stdout.contains("held out (k=0.1)"),
        "{stdout}"
    );
    let path = out.join("lag_law.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let doc = LagLawDocument::from_json(&text, &path).unwrap();
    assert_eq!(doc.format, "aeroform-lag-law/1");
    assert!((doc.chord - CHORD).abs() < 1e-12);
    assert!(doc.report["held_out"]["rows"][0]["id"] == "b");
    assert!(!out.join("identification.json").exists());

    // bad options: exit 2, nothing written
    let out2 = tmp.path().join("out2");
    for args in [
        vec!["--hold-out", "k=0.1"],
        vec!["--law", "lag", "--hold-out", "speed=3"],
        vec!["--law", "lag", "--ensemble", "10", "--hold-out", "k=0.1"],
        vec!["--law", "lag", "--ensemble", "1"],
    ] {
        let mut a = vec![
            "identify",
            data.to_str().unwrap(),
            "--out",
            out2.to_str().unwrap(),
        ];
        a.extend(args.iter().copied());
        let (code, _, err) = common::aeroform_code_in(tmp.path(), &a);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(!out2.exists(), "{args:?} wrote {}", out2.display());
    }
    let _ = HoldOut::K(0.1);

    // the residual block-bootstrap ensemble: intervals of the four constants, seed recorded,
    // the fitted value inside each interval
    let out3 = tmp.path().join("out3");
    let (ok, stdout, stderr) = common::aeroform(&[
        "identify",
        data.to_str().unwrap(),
        "--law",
        "lag",
        "--ensemble",
        "8",
        "--seed",
        "11",
        "--out",
        out3.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("90 % interval"), "{stdout}");
    let path = out3.join("lag_law.json");
    let doc = LagLawDocument::from_json(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let e = &doc.report["ensemble"];
    assert_eq!(e["members"], 8);
    assert_eq!(e["seed"], "11");
    let fitted = [
        doc.law.tau1,
        doc.law.tau2,
        doc.law.alpha_star,
        doc.law.sharpness,
    ];
    for (p, v) in e["parameters"].as_array().unwrap().iter().zip(fitted) {
        let i = &p["interval"];
        let (lo, hi) = (i["lower"].as_f64().unwrap(), i["upper"].as_f64().unwrap());
        assert!(lo <= hi, "{p}");
        // the members refit the fitted law plus resampled residuals: they scatter about it
        let pad = 0.05 * v.abs().max(1e-3);
        assert!(
            lo - pad <= v && v <= hi + pad,
            "{} = {v} outside {p}",
            p["name"]
        );
    }
}

#[test]
fn bad_records_are_refused_by_case_and_nothing_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    // a motion that does not repeat, 1.05 periods: too short for the state to settle
    let short = tmp.path().join("short");
    write_dataset_with(
        &short,
        &[("brief", 0.2, 15.0, 8.0), ("brief2", 0.2, 15.0, 8.0)],
        1.05,
        true,
    );
    let out = tmp.path().join("out");
    let (code, stdout, err) = common::aeroform_code_in(
        tmp.path(),
        &[
            "identify",
            short.to_str().unwrap(),
            "--law",
            "lag",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 2, "{stdout}\n{err}");
    assert!(
        err.contains("too short for the separation state to settle") && err.contains("brief"),
        "{err}"
    );
    assert!(!out.exists());

    // a held-out mean angle outside the fitted angles
    let far = tmp.path().join("far");
    write_dataset(
        &far,
        &[
            ("m15a", 0.05, 15.0, 3.0),
            ("m15b", 0.2, 15.0, 3.0),
            ("m40", 0.1, 40.0, 3.0),
        ],
        3.0,
    );
    let (code, _, err) = common::aeroform_code_in(
        tmp.path(),
        &[
            "identify",
            far.to_str().unwrap(),
            "--law",
            "lag",
            "--hold-out",
            "mean=40",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("m40") && err.contains("outside the range"),
        "{err}"
    );
    assert!(!out.exists());
}
