//! End-to-end tests of the lag law in flight (issue 41, item 4): `flutter`, `lco`, `branch`
//! and `tunnel forced|free` take a `lag_law.json` (directly, or through a model file
//! `kind = "lag"`) like any model file. The law is the hand-set plate-rig law of
//! `scenarios/plate-lag.lag_law.json` on `scenarios/plate-rig.structure.toml`: attached,
//! it is the quasi-steady thin aerofoil about a = −0.3, so its linear flutter speed is that
//! model's; above it, separation (half at α* = 0.2 rad) limits the flutter to a stable
//! stall-flutter LCO. Measured on this commit: U_F = 4.1323 m/s (3.163 Hz), Hopf point at
//! the same speed, supercritical; LCO pitch amplitudes 13.2°, 16.4°, 22.6°, 28.4° at 4.5,
//! 5, 6, 7 m/s.

use std::path::{Path, PathBuf};

use crate::common;
use common::aeroform;

fn scenario(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
        .display()
        .to_string()
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn read_json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

const RIG: &str = "plate-rig.structure.toml";
const LAW: &str = "plate-lag.lag_law.json";
const LAG_MODEL: &str = "plate-lag.model.toml";

/// Runs `aeroform flutter` on the rig with `model`: the critical speed \[m/s\].
fn flutter_speed(model: &str, out: &Path) -> f64 {
    let (ok, stdout, stderr) = aeroform(&[
        "flutter",
        "--structure",
        &scenario(RIG),
        "--model",
        model,
        "--speeds",
        "2:8:61",
        "--out",
        &s(out),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    read_json(&out.join("flutter.json"))["critical"]["speed"]
        .as_f64()
        .unwrap_or_else(|| panic!("no flutter speed with {model}"))
}

/// The lag law's linear flutter is that of the model it reduces to in attached flow (the
/// quasi-steady thin aerofoil with its noncirculatory terms about the same axis), and the
/// law read directly (no elastic axis: no apparent mass) equals a model file without
/// `elastic_axis`.
#[test]
fn linear_flutter_is_the_attached_flow_law() {
    let dir = tempfile::tempdir().unwrap();
    let qs = dir.path().join("qs.model.toml");
    std::fs::write(
        &qs,
        "kind = \"quasi_steady\"\nchord = 0.25\nelastic_axis = -0.3\n",
    )
    .unwrap();
    let u_lag = flutter_speed(&scenario(LAG_MODEL), &dir.path().join("lag"));
    let u_qs = flutter_speed(&s(&qs), &dir.path().join("qs"));
    assert!(
        (u_lag - u_qs).abs() < 1e-6 * u_qs,
        "lag {u_lag} vs quasi-steady {u_qs}"
    );
    assert!((u_lag - 4.1323).abs() < 1e-3, "U_F {u_lag}");
    let no_axis = dir.path().join("noaxis.model.toml");
    std::fs::write(
        &no_axis,
        format!(
            "kind = \"lag\"\nfile = \"{}\"\n",
            scenario(LAW).replace('\\', "/")
        ),
    )
    .unwrap();
    let u_json = flutter_speed(&scenario(LAW), &dir.path().join("json"));
    let u_file = flutter_speed(&s(&no_axis), &dir.path().join("file"));
    assert_eq!(u_json, u_file);
    assert!(
        (u_json - u_lag).abs() > 1e-3,
        "the apparent mass matters: {u_json} vs {u_lag}"
    );
}

/// `branch` finds the Hopf point at the flutter speed (within 0.5 %), a supercritical
/// branch of stable cycles whose pitch amplitude grows with U and stays bounded, and
/// `lco` (time integration, sweeps up and down) lands on it: decay below the flutter
/// speed, the same amplitude up and down (no hysteresis), within 2 % of the branch.
#[test]
fn branch_and_lco_agree_on_a_supercritical_stall_flutter_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let out: PathBuf = dir.path().join("branch");
    let (ok, stdout, stderr) = aeroform(&[
        "branch",
        "--structure",
        &scenario(RIG),
        "--model",
        &scenario(LAG_MODEL),
        "--speeds",
        "3:7.5",
        "--max-points",
        "2000",
        "--out",
        &s(&out),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let json = read_json(&out.join("branch.json"));
    let hopf = json["hopf_points"][0]["u"].as_f64().unwrap();
    let u_f = flutter_speed(&scenario(LAG_MODEL), &dir.path().join("flutter"));
    assert!((hopf - u_f).abs() < 5e-3 * u_f, "Hopf {hopf} vs U_F {u_f}");
    let b = &json["branches"][0];
    assert_eq!(b["criticality"], "supercritical");
    // The onset is degenerate (x₀ − 1 = O(α^{2m}), m = 4: no cubic term), the branch
    // rises vertically at the Hopf speed; any fold the scan reports lies on that vertical.
    for f in json["folds"].as_array().unwrap() {
        let uf = f["U_m_s"].as_f64().unwrap();
        assert!((uf - hopf).abs() < 1e-6 * hopf, "fold away from onset: {f}");
    }
    let stable: Vec<(f64, f64)> = b["points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["stable"] == true && p["u"].as_f64().unwrap() > hopf + 0.05)
        .map(|p| {
            (
                p["u"].as_f64().unwrap(),
                p["amplitude_alpha"].as_f64().unwrap(),
            )
        })
        .collect();
    assert!(stable.len() > 50, "{} stable points", stable.len());
    for w in stable.windows(2) {
        assert!(w[1].0 > w[0].0 && w[1].1 > w[0].1, "not monotonic: {w:?}");
    }
    let branch_amp = |u: f64| {
        let i = stable
            .iter()
            .position(|p| p.0 >= u)
            .expect("speed on branch");
        let (p, q) = (stable[i - 1], stable[i]);
        p.1 + (q.1 - p.1) * (u - p.0) / (q.0 - p.0)
    };
    assert!(branch_amp(7.0) < 35f64.to_radians(), "bounded");

    let lco = dir.path().join("lco");
    let (ok, stdout, stderr) = aeroform(&[
        "lco",
        "--structure",
        &scenario(RIG),
        "--model",
        &scenario(LAG_MODEL),
        "--sweep",
        "3.5,4.5,5,6,7",
        "--out",
        &s(&lco),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let json = read_json(&lco.join("lco.json"));
    for dir in ["up", "down"] {
        let runs = json["sweep"][dir].as_array().unwrap();
        assert_eq!(runs.len(), 5);
        for r in runs {
            let u = r["u"].as_f64().unwrap();
            let amp = r["amplitude_alpha"].as_f64().unwrap();
            if u < u_f {
                assert_eq!(r["classification"], "Decay", "{dir} {u}: {r}");
            } else {
                assert_eq!(r["classification"], "Lco", "{dir} {u}: {r}");
                let want = branch_amp(u);
                assert!(
                    (amp - want).abs() < 0.02 * want,
                    "{dir} U = {u}: LCO {:.3}° vs branch {:.3}°",
                    amp.to_degrees(),
                    want.to_degrees()
                );
            }
        }
    }
}

/// The virtual wind tunnel flies the law (forced motion and free response) and a bad law
/// document is refused naming the file and the field, nothing written.
#[test]
fn tunnel_takes_the_law_and_bad_documents_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let forced = dir.path().join("forced");
    let (ok, stdout, stderr) = aeroform(&[
        "tunnel",
        "forced",
        "--model",
        &scenario(LAG_MODEL),
        "--campaign",
        "config=A",
        "--duration",
        "3",
        "--out",
        &s(&forced),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(forced.join("manifest.toml").exists());
    let free = dir.path().join("free");
    let (ok, stdout, stderr) = aeroform(&[
        "tunnel",
        "free",
        "--structure",
        &scenario(RIG),
        "--model",
        &scenario(LAW),
        "--speeds",
        "3,6",
        "--duration",
        "4",
        "--out",
        &s(&free),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(free.join("manifest.toml").exists());

    let text = std::fs::read_to_string(scenario(LAW)).unwrap();
    let bad = dir.path().join("bad.lag_law.json");
    std::fs::write(
        &bad,
        text.replace("\"alpha_star\": 0.2", "\"alpha_star\": 2.0"),
    )
    .unwrap();
    let out = dir.path().join("never");
    for (cmd, speeds) in [("flutter", "3:7:9"), ("branch", "3:7")] {
        let (ok, _, stderr) = aeroform(&[
            cmd,
            "--structure",
            &scenario(RIG),
            "--model",
            &s(&bad),
            "--speeds",
            speeds,
            "--out",
            &s(&out),
        ]);
        assert!(!ok);
        assert!(
            stderr.contains("bad.lag_law.json") && stderr.contains("alpha_star"),
            "{cmd}: {stderr}"
        );
        assert!(!out.exists(), "{cmd} wrote {}", out.display());
    }
}

/// LCO sweep of `model` on the rig at `speeds` (comma list): (U, classification, pitch
/// amplitude \[rad\]) of the upward runs.
fn lco_sweep(model: &str, speeds: &str, out: &Path) -> Vec<(f64, String, f64)> {
    let (ok, stdout, stderr) = aeroform(&[
        "lco",
        "--structure",
        &scenario(RIG),
        "--model",
        model,
        "--sweep",
        speeds,
        "--out",
        &s(out),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    read_json(&out.join("lco.json"))["sweep"]["up"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["u"].as_f64().unwrap(),
                r["classification"].as_str().unwrap().to_string(),
                r["amplitude_alpha"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// The truth side of the round trip (issue 41 item 4; fast): the project's stall truth
/// (`scenarios/plate-stall.model.toml`, Beddoes–Leishman type) on the plate rig has its
/// stall-flutter LCO above U_F = 6.595 m/s, supercritical, at ≥ 5 speeds. Measured on
/// this commit: decay at 6 and 6.5 m/s; 15.75°, 17.61°, 18.87°, 20.82° at 7, 7.5, 8,
/// 9 m/s. These are the amplitudes an identified lag law must reproduce within 5 %.
#[test]
fn stall_truth_lco_amplitudes_for_the_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let runs = lco_sweep(
        &scenario("plate-stall.model.toml"),
        "6,6.5,7,7.5,8,9",
        dir.path(),
    );
    let want = [0.0, 0.0, 15.75, 17.61, 18.87, 20.82];
    for ((u, class, amp), w) in runs.iter().zip(want) {
        if w == 0.0 {
            assert_eq!(class, "Decay", "{u}");
        } else {
            assert_eq!(class, "Lco", "{u}");
            assert!(
                (amp.to_degrees() - w).abs() < 0.01 * w,
                "U = {u}: {:.2}° vs {w}°",
                amp.to_degrees()
            );
        }
    }
}

/// The whole round trip (slow, about a minute: `cargo test --release --test lag_flight --
/// --ignored`): the stall truth → the paper's forced campaign (configurations A–G,
/// `tunnel forced`) → `identify --law lag` → the lag law flown on the plate rig
/// (`kind = "lag"`, elastic axis of the truth) → flutter onset and LCO amplitudes against
/// the truth's. Measured on this commit: onset 6.542 vs 6.595 m/s (−0.8 %); at 7 m/s
/// 15.96° vs 15.75° (+1.4 %), at 9 m/s 23.58° vs 20.82° (+13 %); at 7.5 and 8 m/s the lag
/// law's runs stop unsettled at the time cap. The acceptance (amplitudes within
/// 5 % at ≥ 5 speeds) is therefore not met yet; this test guards the onset (2 %) and the
/// amplitudes at the settled speeds (15 %).
#[test]
#[ignore = "slow: forced campaign and lag-law identification (about a minute)"]
fn round_trip_stall_truth_to_lag_law_lco() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("forced");
    let (ok, stdout, stderr) = aeroform(&[
        "tunnel",
        "forced",
        "--model",
        &scenario("plate-stall.model.toml"),
        "--campaign",
        "paper",
        "--out",
        &s(&data),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let id = dir.path().join("id");
    let (ok, stdout, stderr) = aeroform(&[
        "identify",
        &s(&data),
        "--law",
        "lag",
        "--out",
        &s(&id),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let model = dir.path().join("lag.model.toml");
    std::fs::write(
        &model,
        format!(
            "kind = \"lag\"\nfile = \"{}\"\nelastic_axis = -0.3\n",
            s(&id.join("lag_law.json")).replace('\\', "/")
        ),
    )
    .unwrap();
    let u_lag = flutter_speed(&s(&model), &dir.path().join("f-lag"));
    let u_truth = flutter_speed(
        &scenario("plate-stall.model.toml"),
        &dir.path().join("f-truth"),
    );
    assert!(
        (u_lag - u_truth).abs() < 0.02 * u_truth,
        "onset {u_lag} vs truth {u_truth}"
    );
    let speeds = "6,6.5,7,7.5,8,9";
    let lag = lco_sweep(&s(&model), speeds, &dir.path().join("l-lag"));
    let truth = lco_sweep(
        &scenario("plate-stall.model.toml"),
        speeds,
        &dir.path().join("l-truth"),
    );
    let mut compared = 0;
    for (l, t) in lag.iter().zip(&truth) {
        eprintln!(
            "U = {}: lag {} {:.2}°, truth {} {:.2}°",
            l.0,
            l.1,
            l.2.to_degrees(),
            t.1,
            t.2.to_degrees()
        );
        if l.1 == "Lco" && t.1 == "Lco" {
            assert!((l.2 - t.2).abs() < 0.15 * t.2, "U = {}", l.0);
            compared += 1;
        } else if t.1 == "Decay" {
            assert_eq!(l.1, "Decay", "U = {}", l.0);
        }
    }
    assert!(compared >= 2, "{compared} settled LCO speeds");
}

/// Pitch-only forced cases of the stall truth (`DynamicStallAero::thin_plate`, a = −0.3,
/// chord 0.25 m, U = 10 m/s), 100 samples per period, 3 periods after the lag states settle:
/// (id, K, mean°, amplitude°) each, in the lag law's nondimensional form.
fn truth_cases(grid: &[(f64, f64, f64)]) -> Vec<identify::record::NondimCase> {
    use aeroelastic::aero::{DynamicStallAero, Flow};
    use aeroelastic::tunnel::{forced_forces, Motion, Sine};
    use identify::record::{CaseMeta, Forcing, NondimCase};
    let (u, chord, rho) = (10.0, 0.25, 1.225);
    let model = DynamicStallAero::thin_plate(chord, -0.3).unwrap();
    let flow = Flow { rho, u };
    grid.iter()
        .map(|&(k, mean_deg, amp_deg)| {
            let f = k * u / (2.0 * std::f64::consts::PI * chord);
            let motion = Motion {
                pitch: vec![Sine {
                    freq: f,
                    amplitude: amp_deg.to_radians(),
                    phase: 0.0,
                }],
                heave: vec![],
                mean_pitch: mean_deg.to_radians(),
            };
            let dt = 1.0 / (f * 100.0);
            let n = 300;
            let pre_roll = 2.0 / f + 60.0 * 0.5 * chord / u;
            let (l, m) =
                forced_forces(&model, &flow, &motion, 0.0, dt, n, pre_roll, "truth").unwrap();
            let (mut a, mut ad) = (Vec::with_capacity(n), Vec::with_capacity(n));
            for i in 0..n {
                let (q, qd, _) = motion.eval(i as f64 * dt);
                a.push(q[1]);
                ad.push(chord * qd[1] / u);
            }
            let p = 0.5 * rho * u * u;
            NondimCase {
                meta: CaseMeta {
                    id: format!("K{k}-M{mean_deg}-A{amp_deg}"),
                    wind_speed: u,
                    mean_pitch: Some(mean_deg.to_radians()),
                    amplitude: Some(amp_deg.to_radians()),
                    freq_pitch: Some(f),
                    ..CaseMeta::default()
                },
                dt,
                chord,
                x: [a, ad, vec![0.0; n], vec![0.0; n]],
                c_lift: l.iter().map(|v| v / (p * chord)).collect(),
                c_moment: m.iter().map(|v| v / (p * chord * chord)).collect(),
                forcing: Forcing {
                    pitch: Some(f),
                    heave: None,
                },
            }
        })
        .collect()
}

/// Fits the lag law with `opts` on `grid` of the truth and writes it in `dir` as
/// `lag_law.json` and the model file `lag.model.toml` (elastic axis of the truth).
fn fit_and_write(grid: &[(f64, f64, f64)], opts: &identify::lag::LagFitOptions, dir: &Path) {
    let cases = truth_cases(grid);
    let fit = identify::lag::fit(&cases, opts).unwrap();
    eprintln!(
        "fitted: τ₁ {:.3} τ₂ {:.3} α* {:.2}° m {:.2}; lift {:?}; moment {:?}",
        fit.law.tau1,
        fit.law.tau2,
        fit.law.alpha_star.to_degrees(),
        fit.law.sharpness,
        fit.law.lift.terms,
        fit.law.moment.terms
    );
    let doc = identify::lag::LagLawDocument {
        format: identify::lag::LAG_LAW_FORMAT.into(),
        dataset: "stall truth".into(),
        chord: 0.25,
        law: fit.law.clone(),
        report: serde_json::Value::Null,
    };
    let law_path = dir.join("lag_law.json");
    std::fs::write(&law_path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    let model = dir.join("lag.model.toml");
    std::fs::write(
        &model,
        format!(
            "kind = \"lag\"\nfile = \"{}\"\nelastic_axis = -0.3\n",
            s(&law_path).replace('\\', "/")
        ),
    )
    .unwrap();
}

/// Fits the lag law on `grid` of the truth, writes it as a model file (elastic axis of the
/// truth) in `dir`, and compares its LCO sweep at `speeds` with the truth's: returns
/// (U, truth class, truth amplitude°, law class, law amplitude°) and prints them.
fn deep_stall_round_trip(
    grid: &[(f64, f64, f64)],
    speeds: &str,
    dir: &Path,
) -> Vec<(f64, String, f64, String, f64)> {
    fit_and_write(grid, &identify::lag::LagFitOptions::default(), dir);
    let model = dir.join("lag.model.toml");
    let u_lag = flutter_speed(&s(&model), &dir.join("f-lag"));
    let u_truth = flutter_speed(&scenario("plate-stall.model.toml"), &dir.join("f-truth"));
    eprintln!(
        "onset: lag {u_lag:.4} m/s, truth {u_truth:.4} m/s ({:+.2} %)",
        100.0 * (u_lag / u_truth - 1.0)
    );
    let lag = lco_sweep(&s(&model), speeds, &dir.join("l-lag"));
    let truth = lco_sweep(
        &scenario("plate-stall.model.toml"),
        speeds,
        &dir.join("l-truth"),
    );
    let rows: Vec<_> = lag
        .iter()
        .zip(&truth)
        .map(|(l, t)| {
            (
                l.0,
                t.1.clone(),
                t.2.to_degrees(),
                l.1.clone(),
                l.2.to_degrees(),
            )
        })
        .collect();
    for r in &rows {
        eprintln!(
            "U = {}: truth {} {:.2}°, lag {} {:.2}° ({:+.1} %)",
            r.0,
            r.1,
            r.2,
            r.3,
            r.4,
            100.0 * (r.4 / r.2 - 1.0)
        );
    }
    assert!((u_lag - u_truth).abs() < 0.02 * u_truth);
    rows
}

/// Periodic orbits of `branch` for `model` on the rig over `speeds` (`a:b`): every point of
/// branch 0 as (U, pitch amplitude°, stable, largest Floquet multiplier modulus).
fn branch_points(model: &str, speeds: &str, out: &Path) -> Vec<(f64, f64, bool, f64)> {
    let (ok, stdout, stderr) = aeroform(&[
        "branch",
        "--structure",
        &scenario(RIG),
        "--model",
        model,
        "--speeds",
        speeds,
        "--max-points",
        "3000",
        "--out",
        &s(out),
        "--quiet",
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    read_json(&out.join("branch.json"))["branches"][0]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p["u"].as_f64().unwrap(),
                p["amplitude_alpha"].as_f64().unwrap().to_degrees(),
                p["stable"] == true,
                p["max_floquet"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// The periodic orbit of `points` at speed `u` on the part of the branch above `floor`°
/// (past the vertical rise at the degenerate onset): (amplitude°, stable, max |μ|),
/// interpolated linearly between the two points that bracket `u`.
fn orbit_at(points: &[(f64, f64, bool, f64)], u: f64, floor: f64) -> Option<(f64, bool, f64)> {
    points.windows(2).find_map(|w| {
        let (p, q) = (w[0], w[1]);
        let brackets = (p.0 - u) * (q.0 - u) <= 0.0 && p.0 != q.0 && p.1 > floor;
        brackets.then(|| {
            let t = (u - p.0) / (q.0 - p.0);
            (p.1 + t * (q.1 - p.1), p.2 && q.2, p.3.max(q.3))
        })
    })
}

/// The deep-stall round trip's pitch-only campaign: (K, mean pitch [deg], amplitude [deg]):
/// 15° ± 8° and 0° ± 10°, 18°, 24° at K = 0.05, 0.1, 0.2, 0.4, 0.7 (20 cases).
fn deep_stall_grid() -> Vec<(f64, f64, f64)> {
    let mut grid = Vec::new();
    for k in [0.05, 0.1, 0.2, 0.4, 0.7] {
        grid.push((k, 15.0, 8.0));
        for a in [10.0, 18.0, 24.0] {
            grid.push((k, 0.0, a));
        }
    }
    grid
}

/// The deep-stall round trip of the issue (about 4 s, in CI): truth → pitch-only campaign at
/// K = 0.05, 0.1, 0.2, 0.4, 0.7 about 15° (± 8°) and, because the LCO about α = 0 passes
/// through stall on both sides, about 0° with amplitudes 10°, 18°, 24° (20 cases) → lag law
/// (circulation lag on) → flutter, LCO and branch on the plate rig against the truth's.
///
/// Measured on this commit: onset 6.6393 vs 6.6410 m/s (−0.03 %); decay at 6 and 6.5 m/s
/// for both; the periodic orbits (`branch`, shooting) at 7, 7.5, 8, 8.5, 9 m/s: 15.03°,
/// 17.18°, 18.62°, 19.84°, 20.97° against the truth's 15.75°, 17.61°, 18.87°, 19.90°,
/// 20.82° (−4.6, −2.4, −1.3, −0.3, +0.7 %): the 5 % at ≥ 5 speeds, met at the
/// level of the orbits. Their stability is not: the law's branch loses stability at a
/// Neimark–Sacker point at 7.35 m/s (max |μ| 1.07–1.17 at 7.5–9 m/s), so `lco`'s runs
/// there end `Unsettled` on a torus (pitch peaks 13.8–22.5° at 8 m/s), while the truth's
/// orbit keeps |μ| 0.92–0.99, itself close to the same bifurcation (docs/DECISIONS.md,
/// "Lag law: orbits right, their stability not"; round 29 measured that neither the
/// instantaneous static Kirchhoff share, the fitted constants, nor training on the truth's
/// own LCO removes it, while the pitch-rate share of the separation input moves the moduli:
/// `pitch_rate_share_moves_the_floquet_moduli_toward_the_truths`).
#[test]
fn deep_stall_round_trip_at_six_speeds() {
    let dir = tempfile::tempdir().unwrap();
    let grid = deep_stall_grid();
    let rows = deep_stall_round_trip(&grid, "6,6.5,7,7.5,8,9", dir.path());
    for r in &rows[..2] {
        assert!(r.1 == "Decay" && r.3 == "Decay", "{r:?}");
    }
    let r = &rows[2];
    assert!(r.1 == "Lco" && r.3 == "Lco", "{r:?}");
    assert!((r.4 - r.2).abs() < 0.05 * r.2, "{r:?}");
    let model = s(&dir.path().join("lag.model.toml"));
    let law = branch_points(&model, "6:9.5", &dir.path().join("b-lag"));
    let truth = branch_points(
        &scenario("plate-stall.model.toml"),
        "6:9.5",
        &dir.path().join("b-truth"),
    );
    for u in [7.0, 7.5, 8.0, 8.5, 9.0] {
        let l = orbit_at(&law, u, 3.0).unwrap_or_else(|| panic!("no law orbit at {u}"));
        let t = orbit_at(&truth, u, 3.0).unwrap_or_else(|| panic!("no truth orbit at {u}"));
        eprintln!(
            "U = {u}: orbit truth {:.2}° (stable {}, |μ| {:.3}), law {:.2}° (stable {}, |μ| {:.3}): {:+.1} %",
            t.0,
            t.1,
            t.2,
            l.0,
            l.1,
            l.2,
            100.0 * (l.0 / t.0 - 1.0)
        );
        assert!(t.1, "the truth's orbit at {u} m/s is stable");
        assert!((l.0 - t.0).abs() < 0.05 * t.0, "U = {u}: {l:?} vs {t:?}");
    }
}

/// Not the default (docs/DECISIONS.md, "Lag law: the Neimark–Sacker point, round 29"): the
/// same deep-stall campaign fitted with the effective angle of the three-quarter-chord
/// downwash, α_e = α + ḣ/U + c·Bα̇/U with c = (½ − a)/2 = 0.4 (a = −0.3, the truth's own
/// separation input): τ₂ comes out 0.82 (the truth's pressure lag τ_p = 1.7 less the
/// rate share 0.8, ≈ 0.9 at low K) and the largest Floquet modulus of the law's orbit falls
/// from 1.17 to 1.02 at 8 m/s and below 1 from 8.5 m/s (0.98, 0.94 at 8.5, 9 m/s), but the
/// onset moves to 6.117 m/s (−7.9 %, outside the 2 %): measured here so that the claim
/// stays true.
#[test]
fn pitch_rate_share_moves_the_floquet_moduli_toward_the_truths() {
    let dir = tempfile::tempdir().unwrap();
    let grid = deep_stall_grid();
    let opts = identify::lag::LagFitOptions {
        rate_share: 0.4,
        ..identify::lag::LagFitOptions::default()
    };
    fit_and_write(&grid, &opts, dir.path());
    let model = s(&dir.path().join("lag.model.toml"));
    let law = branch_points(&model, "6:9.5", &dir.path().join("b-lag"));
    let mut moduli = Vec::new();
    for u in [8.0, 8.5, 9.0] {
        let l = orbit_at(&law, u, 3.0).unwrap_or_else(|| panic!("no law orbit at {u}"));
        eprintln!("U = {u}: law {:.2}° (stable {}, |μ| {:.3})", l.0, l.1, l.2);
        moduli.push(l);
    }
    // default law: 1.17 at 8 m/s (deep_stall_round_trip_at_six_speeds)
    assert!(moduli[0].2 < 1.1, "{:?}", moduli[0]);
    for l in &moduli[1..] {
        assert!(l.1 && l.2 < 1.0, "{l:?}");
    }
    let u_lag = flutter_speed(&model, &dir.path().join("f-lag"));
    let u_truth = flutter_speed(
        &scenario("plate-stall.model.toml"),
        &dir.path().join("f-truth"),
    );
    eprintln!("onset: lag {u_lag:.4} m/s, truth {u_truth:.4} m/s");
    assert!(u_lag < 0.95 * u_truth, "{u_lag} vs {u_truth}");
}

/// Fits the deep-stall campaign with `opts`, flies the law on the rig and checks issue 41's
/// round-trip acceptance against the truth: onset (flutter) within 2 %; at 7, 7.5, 8, 8.5,
/// 9 m/s the law's periodic orbit (`branch`) within 5 % of the truth's and stable wherever
/// the truth's is; `lco` settles (`Lco`, within 5 % of the truth's `lco`) at 7, 7.5, 8 and
/// 9 m/s, and both decay at 6 and 6.5 m/s. Returns the fitted law.
fn assert_round_trip_acceptance(
    opts: &identify::lag::LagFitOptions,
    dir: &Path,
) -> identify::lag::LagLaw {
    let fit = identify::lag::fit(&truth_cases(&deep_stall_grid()), opts).unwrap();
    eprintln!("notes: {:?}", fit.report.notes);
    fit_and_write(&deep_stall_grid(), opts, dir);
    let model = s(&dir.join("lag.model.toml"));
    let u_lag = flutter_speed(&model, &dir.join("f-lag"));
    let u_truth = flutter_speed(&scenario("plate-stall.model.toml"), &dir.join("f-truth"));
    eprintln!(
        "onset: lag {u_lag:.4} m/s, truth {u_truth:.4} m/s ({:+.2} %)",
        100.0 * (u_lag / u_truth - 1.0)
    );
    let law = branch_points(&model, "6:9.5", &dir.join("b-lag"));
    let truth = branch_points(
        &scenario("plate-stall.model.toml"),
        "6:9.5",
        &dir.join("b-truth"),
    );
    let mut fails = Vec::new();
    if (u_lag - u_truth).abs() >= 0.02 * u_truth {
        fails.push(format!("onset {u_lag} vs {u_truth}"));
    }
    for u in [7.0, 7.5, 8.0, 8.5, 9.0] {
        let l = orbit_at(&law, u, 3.0).unwrap_or_else(|| panic!("no law orbit at {u}"));
        let t = orbit_at(&truth, u, 3.0).unwrap_or_else(|| panic!("no truth orbit at {u}"));
        eprintln!(
            "U = {u}: orbit truth {:.2}° (|μ| {:.3}), law {:.2}° (|μ| {:.3}): {:+.1} %",
            t.0,
            t.2,
            l.0,
            l.2,
            100.0 * (l.0 / t.0 - 1.0)
        );
        if (l.0 - t.0).abs() >= 0.05 * t.0 {
            fails.push(format!("orbit at {u}: {l:?} vs {t:?}"));
        }
        if t.1 && !(l.1 && l.2 < 1.0) {
            fails.push(format!("unstable orbit at {u}: {l:?} (truth {t:?})"));
        }
    }
    let speeds = "6,6.5,7,7.5,8,9";
    let lco_l = lco_sweep(&model, speeds, &dir.join("l-lag"));
    let lco_t = lco_sweep(
        &scenario("plate-stall.model.toml"),
        speeds,
        &dir.join("l-truth"),
    );
    for (l, t) in lco_l.iter().zip(&lco_t) {
        eprintln!(
            "lco U = {}: truth {} {:.2}°, lag {} {:.2}°",
            l.0,
            t.1,
            t.2.to_degrees(),
            l.1,
            l.2.to_degrees()
        );
        if t.1 != l.1 || (t.1 == "Lco" && (l.2 - t.2).abs() >= 0.05 * t.2) {
            fails.push(format!("lco at {}: {l:?} vs {t:?}", l.0));
        }
    }
    assert!(fails.is_empty(), "{fails:#?}");
    fit.law
}

/// Issue 41's round-trip acceptance (first bullet) with the rate share c and the pressure
/// lag τ_p *fitted* by output error on the 20 forced cases (`fit_rate_share`,
/// `fit_pressure_lag`: c and τ_p inside the Levenberg–Marquardt from three starts,
/// docs/DECISIONS.md, "issue 41 … round 31"; about 5 s, in CI since round 31). Measured:
/// c = 0.337, τ_p = 1.665 b/U, onset +0.28 %, orbits −3.0 … +2.4 %, all stable.
#[test]
fn fitted_rate_share_and_pressure_lag_meet_the_round_trip_acceptance() {
    let dir = tempfile::tempdir().unwrap();
    let opts = identify::lag::LagFitOptions {
        fit_rate_share: true,
        fit_pressure_lag: true,
        ..identify::lag::LagFitOptions::default()
    };
    let law = assert_round_trip_acceptance(&opts, dir.path());
    eprintln!("c {} τ_p {}", law.rate_share, law.pressure_lag);
}

/// The same campaign and acceptance with c and τ_p held fixed (the fixed-constant path) at
/// the values the round-30 profile found on this campaign (c = 0.339,
/// τ_p = 1.666 b/U, against the truth's (½ − a)/2 = 0.4 and τ_p = 1.7), every other constant
/// fitted. Measured: τ₂ → 0, onset 6.6563 vs 6.6410 m/s (+0.23 %), orbits −2.9, −0.8, +0.4,
/// +1.4, +2.3 % at 7–9 m/s with |μ| 0.659, 0.902, 0.951, 0.933, 0.898 (truth 0.706, 0.923,
/// 0.986, 0.988, 0.966), and `lco` settles on them.
#[test]
fn pressure_lag_and_rate_share_at_the_fitted_values_meet_the_round_trip_acceptance() {
    let dir = tempfile::tempdir().unwrap();
    let opts = identify::lag::LagFitOptions {
        rate_share: 0.339,
        pressure_lag: 1.666,
        ..identify::lag::LagFitOptions::default()
    };
    let law = assert_round_trip_acceptance(&opts, dir.path());
    assert!(law.tau2 < 0.1, "τ₂ {}: the lag replaces the lead", law.tau2);
}
