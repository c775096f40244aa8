//! End-to-end tests of `aeroform run` and `aeroform plot`: the quickstart study writes every
//! result file, figure and report; a second run with the same study and seed is
//! byte-identical; `plot` redraws the same figures from the result files alone; bad study
//! files end with an error naming the key and the line; the shipped studies parse.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::common;
use common::aeroform;

/// Every file under `dir` (relative path → bytes).
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut m = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                m.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    m
}

fn run_quickstart(out: &Path) -> String {
    let (ok, stdout, err) = aeroform(&["run", "--out", out.to_str().unwrap(), "--json"]);
    assert!(ok, "quickstart failed: {err}");
    assert!(!err.contains("panicked"), "{err}");
    stdout
}

#[test]
fn quickstart_is_complete_and_byte_identical_on_a_second_run() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let stdout = run_quickstart(&a);
    let doc: serde_json::Value = serde_json::from_str(&stdout).expect("--json document");
    for stage in ["data", "identify", "flutter", "lco", "figures+report"] {
        assert!(
            doc["timings_s"][stage].as_f64().is_some_and(|t| t >= 0.0),
            "stage `{stage}` not timed: {stdout}"
        );
    }
    assert!(doc["total_s"].as_f64().is_some());
    // issue 16: CSV headers a numpy or MATLAB reader keeps, mapped back to the library terms
    let coef = std::fs::read_to_string(a.join("coefficients.csv")).unwrap();
    let header = coef.lines().next().unwrap();
    assert!(
        header
            .split(',')
            .all(|c| c.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_')),
        "{header}"
    );
    let cols: Vec<serde_json::Value> = serde_json::from_str(
        &std::fs::read_to_string(a.join("coefficients.columns.json")).unwrap(),
    )
    .unwrap();
    let id: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(a.join("identification.json")).unwrap())
            .unwrap();
    let terms = id["library"]["terms"].as_array().unwrap();
    assert_eq!(cols.len(), terms.len());
    for (c, t) in cols.iter().zip(terms) {
        assert_eq!(&c["term"], t);
        assert!(header
            .split(',')
            .any(|h| h == c["column"].as_str().unwrap()));
    }
    assert!(cols
        .iter()
        .any(|c| c["term"] == "alpha^3" && c["column"] == "alpha3"));
    run_quickstart(&b);
    let (ta, tb) = (tree(&a), tree(&b));
    for f in [
        "study.toml",
        "cases.json",
        "identification.json",
        "coefficients.csv",
        "derivatives.csv",
        "series/D-U4-A24.json",
        "flutter.json",
        "flutter_points.csv",
        "lco.json",
        "lco_amplitudes.csv",
        "figures.json",
        "report.html",
        "figures/bifurcation.png",
        "figures/bifurcation.svg",
    ] {
        assert!(ta.contains_key(Path::new(f)), "missing {f}");
    }
    assert_eq!(
        ta.keys().collect::<Vec<_>>(),
        tb.keys().collect::<Vec<_>>(),
        "different file sets"
    );
    for (k, v) in &ta {
        assert!(tb[k] == *v, "{} differs between two runs", k.display());
    }
    // no temporary file of the atomic writes is left behind
    assert!(
        ta.keys().all(|k| !k.to_string_lossy().ends_with(".tmp")),
        "temporary files left"
    );
    // every figure listed has its PNG and SVG, and the report embeds each once
    let figs: Vec<serde_json::Value> =
        serde_json::from_slice(&ta[Path::new("figures.json")]).unwrap();
    assert!(figs.len() >= 9, "{} figures", figs.len());
    for f in &figs {
        let stem = f["stem"].as_str().unwrap();
        for ext in ["png", "svg"] {
            assert!(ta.contains_key(&PathBuf::from(format!("figures/{stem}.{ext}"))));
        }
    }
    let html = String::from_utf8_lossy(&ta[Path::new("report.html")]).into_owned();
    assert_eq!(html.matches("<svg").count(), figs.len());
    assert!(html.contains("seed"), "report names the seed");
    assert!(html.contains(env!("CARGO_PKG_VERSION")));

    // the flutter point of the flat plate (published 2.0054 for the derivative model;
    // exact Theodorsen gives the same closed-form derivatives)
    let pts = String::from_utf8_lossy(&ta[Path::new("flutter_points.csv")]).into_owned();
    let row = pts.lines().nth(1).unwrap();
    let u_red: f64 = row.split(',').nth(5).unwrap().parse().unwrap();
    assert!(
        (u_red - 2.0054).abs() < 2e-3 * 2.0054,
        "U_F/(bω_α) = {u_red}"
    );

    // `plot` redraws the same figures and report from the result files alone
    std::fs::remove_dir_all(a.join("figures")).unwrap();
    std::fs::remove_file(a.join("report.html")).unwrap();
    let (ok, _, err) = aeroform(&["plot", a.to_str().unwrap()]);
    assert!(ok, "{err}");
    let tc = tree(&a);
    for (k, v) in &ta {
        assert!(tc.get(k) == Some(v), "{} differs after `plot`", k.display());
    }
}

#[test]
fn quickstart_recovers_the_demo_law_support() {
    let tmp = tempfile::tempdir().unwrap();
    run_quickstart(tmp.path());
    let id: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(tmp.path().join("identification.json")).unwrap(),
    )
    .unwrap();
    let support: Vec<&str> = id["groups"][0]["moment"]["support"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    // identify::synthetic::PolynomialLaw::demo() moment terms
    let mut expected = vec![
        "alpha",
        "alpha_dot",
        "h",
        "h_dot",
        "alpha*alpha_dot",
        "alpha^3",
        "alpha_dot^3",
    ];
    let mut got = support.clone();
    got.sort_unstable();
    expected.sort_unstable();
    assert_eq!(got, expected);
}

fn study_fails(text: &str) -> String {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("bad.toml");
    std::fs::write(&p, text).unwrap();
    let out = tmp.path().join("out");
    let (ok, _, err) = aeroform(&["run", p.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!ok, "expected failure");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "nothing may be written for an invalid study");
    err
}

#[test]
fn unknown_key_in_a_study_names_key_and_line() {
    let err = study_fails("name = \"x\"\n\n[lco]\nspeeds = [1.0]\nup_dwn = true\n");
    assert!(
        err.contains("bad.toml:5") && err.contains("up_dwn"),
        "{err}"
    );
}

#[test]
fn out_of_range_value_names_dotted_key_and_line() {
    let err = study_fails(
        "name = \"x\"\n[data.synthetic]\namplitudes_deg = [6.0]\nspeeds = [4.0, -1.0]\n\
         [[data.synthetic.config]]\nname = \"D\"\nfreq_pitch = 2.0\nfreq_heave = 1.3\nmm_per_deg = 1.5\n",
    );
    assert!(
        err.contains("bad.toml:4") && err.contains("data.synthetic.speeds"),
        "{err}"
    );
}

#[test]
fn bad_virtual_source_and_identified_without_data_are_clear_errors() {
    let err = study_fails("name = \"x\"\n[data.virtual]\nconfig = \"A\"\n");
    assert!(
        err.contains("bad.toml:3") && err.contains("config"),
        "{err}"
    );
    let err = study_fails("name = \"x\"\n[data.virtual]\nstill_air = true\n");
    assert!(
        err.contains("bad.toml:2") && err.contains("data.virtual") && err.contains("model"),
        "{err}"
    );
    let err = study_fails(
        "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n[aero]\nmodel = \"identified\"\n",
    );
    assert!(
        err.contains("aero.model") && err.contains(":7") && err.contains("needs [data]"),
        "{err}"
    );
}

/// Virtual campaign of configuration D on the truth of `scenarios/plate-truth.model.toml`
/// (C_M += 0.5 α(Bα̇/U) − 2 α³ − 100 (Bα̇/U)³, no lift terms) with still-air runs: the
/// identification must select exactly the truth's nonlinear moment terms (plus the four
/// linear ones), none in lift, and recover ξ = K³N1* ≈ 0.5, K⁶N2* ≈ −2, K³N3* ≈ −100:
/// the median over the 64 cases within 1 % (measured 0.14 %, 0.005 %, 0.05 %), and every
/// case of amplitude ≥ 12° whose moment fit has R² ≥ 0.99 within 15 % (measured worst
/// 10.7 %, α³ at 3 m/s, 15°). With Table I's absolute balance noise (0.1 % of ±5 N·m) a
/// cubic term at 3–9° is a few noise σ (R² ≈ 0.5 at 3 m/s, 3°; up to 23 % error on α³ at
/// 6° even with R² ≥ 0.99), so small amplitudes are held to the median only. Before round
/// 10 every case was held to 5 %, under balance noise relative to each record's peak.
#[test]
fn virtual_campaign_recovers_the_truth_support() {
    let tmp = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    let p = tmp.path().join("v.toml");
    std::fs::write(
        &p,
        format!(
            "name = \"virtual-d\"\n[data.virtual]\nmodel = \"{root}/scenarios/plate-truth.model.toml\"\n\
             campaign = \"config=D\"\nstill_air = true\n[outputs]\nfigures = []\n"
        ),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (ok, _, err) = aeroform(&[
        "run",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(ok, "{err}");
    let id: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("identification.json")).unwrap())
            .unwrap();
    let support = |ch: &str| -> Vec<String> {
        let mut v: Vec<String> = id["groups"][0][ch]["support"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        v.sort_unstable();
        v
    };
    let mut want_m = vec![
        "alpha",
        "alpha_dot",
        "h",
        "h_dot",
        "alpha*alpha_dot",
        "alpha^3",
        "alpha_dot^3",
    ];
    want_m.sort_unstable();
    let mut want_l = vec!["alpha", "alpha_dot", "h", "h_dot"];
    want_l.sort_unstable();
    assert_eq!(support("moment"), want_m);
    assert_eq!(support("lift"), want_l);
    assert_eq!(id["cases"].as_array().unwrap().len(), 64);
    let cases = id["cases"].as_array().unwrap();
    let mut checked = 0;
    for (name, p, want) in [("N1", 3, 0.5), ("N2", 6, -2.0), ("N3", 3, -100.0)] {
        let mut all = Vec::new();
        let mut worst: f64 = 0.0;
        for c in cases {
            let k = c["k_alpha"].as_f64().unwrap();
            let xi = c["moment"]["eq19"][name].as_f64().unwrap() * k.powi(p);
            all.push(xi);
            let amp = c["id"].as_str().unwrap().rsplit("-A").next().unwrap();
            let amp: f64 = amp.parse().unwrap();
            if amp >= 12.0 && c["moment"]["r2"].as_f64().unwrap() >= 0.99 {
                checked += 1;
                worst = worst.max((xi / want - 1.0).abs());
                eprintln!("{} {name}: ξ = {xi:.4} vs {want}", c["id"]);
            }
        }
        all.sort_by(f64::total_cmp);
        let median = 0.5 * (all[31] + all[32]);
        eprintln!("{name}: median ξ {median:.4} (truth {want}), worst relative error {worst:.3}");
        assert!(worst < 0.15, "{name}: worst relative error {worst}");
        assert!(
            (median / want - 1.0).abs() < 0.01,
            "{name}: median ξ {median}"
        );
    }
    assert!(
        checked >= 3 * 32,
        "only {} large-amplitude cases with R² ≥ 0.99",
        checked / 3
    );
}

/// `scenarios/plate-round-trip.toml`: truth → virtual campaign D → identification →
/// identified Eq. 19 model. Flutter speed within 2 % and LCO amplitudes within 10 % of the
/// truth's (the tolerances of tests/round_trip.rs, which checks the same chain through the
/// library API), at least four LCO speeds per sweep.
#[test]
fn plate_round_trip_study_matches_the_truth() {
    let tmp = tempfile::tempdir().unwrap();
    let study = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/plate-round-trip.toml"
    );
    let (ok, _, err) = aeroform(&["run", study, "--out", tmp.path().to_str().unwrap()]);
    assert!(ok, "{err}");
    let csv = std::fs::read_to_string(tmp.path().join("round_trip.csv")).unwrap();
    let mut lco = 0;
    let mut decays_at_6_4 = 0;
    for row in csv.lines().skip(1) {
        let c: Vec<&str> = row.split(',').collect();
        // issue 13: no run may end `unsettled` (the stiffness detector used to abort three)
        assert!(!row.contains("unsettled"), "unsettled run: {row}");
        if c[1] == "6.4" {
            // below the identified flutter speed both models decay
            assert_eq!((c[5], c[6]), ("decay", "decay"), "{row}");
            decays_at_6_4 += 1;
        }
        if c[0] == "flutter_speed_m_s" {
            let e: f64 = c[4].parse().unwrap();
            assert!(e.abs() < 0.02, "flutter speed error {e}");
        } else if c[5] == "lco" && c[6] == "lco" {
            lco += 1;
            let e: f64 = c[4].parse().unwrap();
            assert!(e.abs() < 0.10, "LCO amplitude error {e} at U = {}", c[1]);
        }
    }
    assert!(lco >= 8, "only {lco} LCO pairs:\n{csv}");
    assert_eq!(decays_at_6_4, 2, "{csv}");
    // `[identify] ensemble = 20`: intervals of the identified law's flutter speed and LCO
    // amplitudes (issue 15), in the CSVs, the figures and the report
    let pts = std::fs::read_to_string(tmp.path().join("flutter_points.csv")).unwrap();
    let header: Vec<&str> = pts.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let mut truth_uf = f64::NAN;
    let mut interval = None;
    for row in pts.lines().skip(1) {
        let c: Vec<&str> = row.split(',').collect();
        let uf: f64 = c[col("U_F_m_s")].parse().unwrap();
        if c[col("model")] == "truth" {
            truth_uf = uf;
            assert_eq!(c[col("U_F_lower_m_s")], "", "the truth has no ensemble");
        } else {
            let lo: f64 = c[col("U_F_lower_m_s")].parse().unwrap();
            let hi: f64 = c[col("U_F_upper_m_s")].parse().unwrap();
            assert_eq!(c[col("ensemble_members")], "20");
            assert_eq!(c[col("ensemble_with_flutter")], "20");
            assert!(lo < uf && uf < hi, "nominal {uf} outside [{lo}, {hi}]");
            assert!(hi - lo < 0.05 * uf, "[{lo}, {hi}]");
            interval = Some((lo, hi));
        }
    }
    let (lo, hi) = interval.expect("identified run");
    // the truth's flutter speed lies in the 90 % interval (seed 1: 6.595 in [6.588, 6.620])
    assert!(
        lo <= truth_uf && truth_uf <= hi,
        "truth {truth_uf} outside [{lo}, {hi}]"
    );
    let li = std::fs::read_to_string(tmp.path().join("lco_intervals.csv")).unwrap();
    let nominal: std::collections::HashMap<String, f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|c| c[0] == "lco_amplitude_deg_up")
        .map(|c| (c[1].to_string(), c[3].parse().unwrap()))
        .collect();
    let mut bars = 0;
    for row in li.lines().skip(1) {
        let c: Vec<&str> = row.split(',').collect();
        assert_eq!(c[2], "20", "{row}");
        if c[3] == "0" {
            assert_eq!(c[0], "6.4", "{row}");
            assert_eq!(c[4], "20", "every member decays at 6.4 m/s: {row}");
            continue;
        }
        let v: Vec<f64> = c[7..10].iter().map(|x| x.parse().unwrap()).collect();
        let nom = nominal[c[0]];
        assert!(v[1] <= v[0] && v[0] <= v[2], "{row}");
        assert!(
            v[1] <= nom && nom <= v[2],
            "nominal {nom} outside the interval: {row}"
        );
        bars += 1;
    }
    assert_eq!(bars, 5, "{li}");
    let report = std::fs::read_to_string(tmp.path().join("report.html")).unwrap();
    assert!(report.contains("Propagated identification uncertainty"));
    assert!(report.contains("LCO amplitude intervals over the identification ensemble"));
    let figs = std::fs::read_to_string(tmp.path().join("figures.json")).unwrap();
    assert!(figs.contains("Error bars: 90 % interval"), "{figs}");
    let lco_json = std::fs::read_to_string(tmp.path().join("lco.json")).unwrap();
    assert!(
        !lco_json.contains("\"Unsettled\""),
        "lco.json has an unsettled run"
    );
    assert!(tmp.path().join("figures/bifurcation-truth.svg").exists());
}

#[test]
fn plot_on_a_folder_without_results_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let (ok, _, err) = aeroform(&["plot", tmp.path().to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("not a study output folder"), "{err}");
}

#[test]
fn hp1_study_matches_the_published_flutter_and_divergence_speeds() {
    let tmp = tempfile::tempdir().unwrap();
    let study = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/hp1-flutter.toml");
    let (ok, _, err) = aeroform(&["run", study, "--out", tmp.path().to_str().unwrap()]);
    assert!(ok, "{err}");
    let pts = std::fs::read_to_string(tmp.path().join("flutter_points.csv")).unwrap();
    let rows: Vec<Vec<&str>> = pts
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 3);
    // published (DESIGN.md §6): 2.1839, 2.1704, 1.8425; divergence 2.8284
    for (r, (uf, ud)) in rows
        .iter()
        .zip([(2.1839, 2.8284), (2.1704, 2.8284), (1.8425, 2.8284)])
    {
        let got_uf: f64 = r[5].parse().unwrap();
        let got_ud: f64 = r[8].parse().unwrap();
        assert!(
            (got_uf - uf).abs() < 2e-3 * uf,
            "{}: {got_uf} vs {uf}",
            r[0]
        );
        assert!(
            (got_ud - ud).abs() < 2e-3 * ud,
            "{}: {got_ud} vs {ud}",
            r[0]
        );
    }
}

#[test]
fn shipped_studies_parse() {
    // a study with an unknown key fails before anything runs; here every shipped study
    // must get past parsing: run them with an invalid --out parent to stop right after.
    for s in [
        "quickstart",
        "paper-table-iv",
        "hp1-flutter",
        "paper-campaign",
        "flat-plate-lco",
        "plate-round-trip",
    ] {
        let path = format!("{}/scenarios/{s}.toml", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        let v: toml::Table = text.parse().unwrap_or_else(|e| panic!("{s}: {e}"));
        assert_eq!(
            v["name"].as_str(),
            Some(s),
            "{s}: name must match the file name"
        );
        let (ok, _, err) = aeroform(&["run", &path, "--out", "/dev/null/x"]);
        assert!(!ok);
        assert!(
            err.contains("cannot create output folder"),
            "{s} should parse and fail only on the folder: {err}"
        );
    }
}

/// The series case does not exist: the whole study is checked against the data before
/// any result is written, and a failed run leaves no output folder at all (results are
/// written in a staging folder that replaces `--out` only when complete).
#[test]
fn a_failing_stage_names_its_cause_and_leaves_no_partial_file() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("s.toml");
    std::fs::write(
        &p,
        "name = \"fails-late\"\n[data.synthetic]\namplitudes_deg = [12.0]\nspeeds = [6.0]\n\
         duration = 4.0\n[[data.synthetic.config]]\nname = \"D\"\nfreq_pitch = 2.0\n\
         freq_heave = 1.3\nmm_per_deg = 1.5\n[outputs]\nseries_cases = [\"nope\"]\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (ok, _, err) = aeroform(&["run", p.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains("series_cases") && err.contains("nope"),
        "{err}"
    );
    assert!(!out.exists(), "a failed run left {}", out.display());
    assert!(tree(tmp.path()).keys().all(|k| k == Path::new("s.toml")));
}

/// `[branch]` in `scenarios/flat-plate-lco.toml`: branch.json / branch.csv written with the
/// CLI's documents, the Hopf point near the linear flutter speed of the study's p-k run,
/// the upward sweep's time-integration LCOs on the branch (linear interpolation between
/// orbits: 0.5 %), the diagram listed and embedded in the report, and `aeroform plot`
/// redraws it from the files.
#[test]
fn branch_stage_writes_the_branch_and_its_figure() {
    let tmp = tempfile::tempdir().unwrap();
    let study = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/flat-plate-lco.toml");
    let out = tmp.path().join("out");
    let (ok, stdout, err) = aeroform(&["run", study, "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(stdout.contains("branch 0: Hopf point"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("branch.json")).unwrap()).unwrap();
    assert_eq!(json["format"], "aeroform-branch/1");
    let hopf = json["hopf_points"][0]["u"].as_f64().unwrap();
    let fl: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("flutter.json")).unwrap()).unwrap();
    let uf = fl[0]["analysis"]["flutter"]["u"].as_f64().unwrap();
    // The Hopf point is the onset of the time-domain realisation (Jones' two lags), the
    // study's run is p-k on exact Theodorsen: 0.10 % apart (measured 2.0074 vs 2.0054).
    assert!((hopf / uf - 1.0).abs() < 2e-3, "Hopf {hopf} vs U_F {uf}");
    // branch.csv: U, stable, amplitude_alpha_deg, …
    let rows: Vec<(f64, f64)> = std::fs::read_to_string(out.join("branch.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            assert_eq!(c[1], "true", "supercritical: every orbit stable ({l})");
            (c[0].parse().unwrap(), c[2].parse().unwrap())
        })
        .collect();
    assert!(rows.len() >= 20, "{} orbits", rows.len());
    let lco: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("lco.json")).unwrap()).unwrap();
    let mut compared = 0;
    for r in lco["sweep"]["up"].as_array().unwrap() {
        if r["classification"] != "Lco" {
            continue;
        }
        let (u, a) = (
            r["u"].as_f64().unwrap(),
            r["amplitude_alpha"].as_f64().unwrap().to_degrees(),
        );
        let Some(w) = rows.windows(2).find(|w| w[0].0 <= u && u <= w[1].0) else {
            continue;
        };
        let t = (u - w[0].0) / (w[1].0 - w[0].0);
        let b = w[0].1 + t * (w[1].1 - w[0].1);
        assert!(
            (b / a - 1.0).abs() < 5e-3,
            "U = {u}: branch {b}° vs sweep {a}°"
        );
        compared += 1;
    }
    assert!(compared >= 6, "only {compared} sweep LCOs on the branch");
    let figs = std::fs::read_to_string(out.join("figures.json")).unwrap();
    assert!(figs.contains("branch_diagram"), "{figs}");
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("LCO branches by continuation"));
    std::fs::remove_file(out.join("figures/branch_diagram.svg")).unwrap();
    let (ok, _, err) = aeroform(&["plot", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.join("figures/branch_diagram.svg").exists());
}

#[test]
fn branch_stage_errors_name_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/flat-plate-lco.toml"
    ))
    .unwrap();
    for (bad, key) in [
        ("speeds = [2.3, 1.5]", "branch.speeds"),
        ("speeds = [0.0, 1.5]", "branch.speeds[0]"),
        ("speeds = [1.5, 2.3]\nmax_points = 0", "branch.max_points"),
        (
            "speeds = [1.5, 2.3]\nmeasured = \"missing.csv\"",
            "missing.csv",
        ),
    ] {
        let p = tmp.path().join("s.toml");
        std::fs::write(&p, text.replace("speeds = [1.5, 2.3]", bad)).unwrap();
        let out = tmp.path().join("o");
        let (ok, _, err) = aeroform(&["run", p.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert!(!ok, "{bad}");
        assert!(err.contains(key), "{bad}: {err}");
        assert!(!out.exists(), "{bad}: a failed run leaves no folder");
    }
}

/// Issue 12: `scenarios/paper-campaign.toml` draws every figure type of the seed paper's
/// results section. The list is the paper's (docs/PAPER.md, "Results, item by item"): each
/// entry names the paper's figure or table and the aeroform figure stems that stand for it.
#[test]
fn paper_campaign_draws_every_results_section_figure() {
    let tmp = tempfile::tempdir().unwrap();
    let study = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/paper-campaign.toml");
    let (ok, _, err) = aeroform(&["run", study, "--out", tmp.path().to_str().unwrap()]);
    assert!(ok, "{err}");
    let list: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("figures.json")).unwrap())
            .unwrap();
    let stems: Vec<&str> = list.iter().map(|e| e["stem"].as_str().unwrap()).collect();
    let paper: [(&str, &[&str]); 12] = [
        (
            "Figs. 4/5 (wind-on, still-air, aerodynamic force)",
            &["force_decomposition_D-U4-A6"],
        ),
        ("Fig. 6 (candidate library)", &["library"]),
        (
            "Figs. 7/8 (fits at high, middle, low δ)",
            &["delta_fits_D_lift", "delta_fits_D_moment"],
        ),
        (
            "δ path (Alg. 3)",
            &["delta_path_D_lift", "delta_path_D_moment"],
        ),
        ("time series of a case", &["time_series_D-U4-A6"]),
        (
            "spectra of a case",
            &["spectrum_D-U4-A6_lift", "spectrum_D-U4-A6_moment"],
        ),
        (
            "coefficient heat maps per configuration",
            &[
                "heatmap_A_moment",
                "heatmap_B_moment",
                "heatmap_C_moment",
                "heatmap_D_moment",
                "heatmap_E_moment",
                "heatmap_F_moment",
                "heatmap_G_moment",
                "heatmap_D_lift",
            ],
        ),
        ("Fig. 14 (forces across U)", &["force_loops_D_wind_speed"]),
        (
            "Fig. 15 (forces across amplitude)",
            &["force_loops_D_amplitude"],
        ),
        ("fit quality (R², MFWA)", &["histogram_quality"]),
        ("flutter derivatives vs K", &["derivatives"]),
        ("Fig. 28 (angle of attack)", &["mean_angle"]),
    ];
    for (item, want) in paper {
        for w in want {
            assert!(stems.contains(w), "{item}: no figure `{w}` in {stems:?}");
            for ext in ["png", "svg"] {
                assert!(
                    tmp.path().join(format!("figures/{w}.{ext}")).exists(),
                    "{w}.{ext}"
                );
            }
        }
    }
    let report = std::fs::read_to_string(tmp.path().join("report.html")).unwrap();
    // Table III: the supports at three δ; high δ is sparser than the selected support,
    // which is sparser than low δ
    assert!(
        report.contains("Table III: supports of group D"),
        "no Table III"
    );
    let paper: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(tmp.path().join("paper_figures.json")).unwrap(),
    )
    .unwrap();
    for d in paper["delta_fits"].as_array().unwrap() {
        let n: Vec<usize> = d["fits"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["coefficients"].as_array().unwrap().len())
            .collect();
        assert!(n[0] <= n[1] && n[1] <= n[2], "{}: {n:?}", d["force"]);
        let r2: Vec<f64> = d["fits"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["r2"].as_f64().unwrap())
            .collect();
        // nested least squares on the same record: more terms never fit worse
        assert!(r2[0] <= r2[1] + 1e-12 && r2[1] <= r2[2] + 1e-12, "{r2:?}");
    }
    // the decomposition is exact: aerodynamic = wind on − still air is what identification
    // sees before filtering; the still-air run is not zero (inertia of the 0.82 kg plate)
    let f = &paper["forces"][0];
    let still: Vec<f64> = f["lift_still_air"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(still.iter().map(|v| v.abs()).fold(0.0, f64::max) > 0.1);
}

/// A study flies the law with memory (issue 41 item 4): `[aero] model = "lag"` with the
/// lag_law.json as `file`, relative to the study file. In attached flow the plate-rig law
/// is the quasi-steady thin aerofoil about the same axis (tests/lag_flight.rs), so the
/// study's flutter run of `quasi_steady` (the same [aero] table) has the same speed; above
/// it the LCO stage finds the stall-flutter cycle, below it a decay.
#[test]
fn a_study_flies_the_lag_law() {
    let tmp = tempfile::tempdir().unwrap();
    let law = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/plate-lag.lag_law.json"
    );
    std::fs::copy(law, tmp.path().join("law.json")).unwrap();
    let study = tmp.path().join("lag.toml");
    // the plate rig (scenarios/plate-rig.structure.toml) in nondimensional form
    std::fs::write(
        &study,
        "name = \"lag\"\n\
         [structure]\nmu = 18.19\nr_alpha2 = 0.3397\nsigma = 0.5714\nx_alpha = 0.08\n\
         semi_chord = 0.125\nomega_alpha = 21.99\nrho = 1.225\n\
         [aero]\nmodel = \"lag\"\nfile = \"law.json\"\nelastic_axis = -0.3\n\
         [flutter]\nu_min = 2.0\nu_max = 8.0\nn_speeds = 61\n\
         [[flutter.run]]\nlabel = \"lag law\"\nmethod = \"pk\"\n\
         [[flutter.run]]\nlabel = \"quasi-steady\"\nmethod = \"pk\"\nmodel = \"quasi_steady\"\n\
         [lco]\nspeeds = [3.0, 6.0]\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (ok, stdout, err) = aeroform(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{err}");
    let fl: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("flutter.json")).unwrap()).unwrap();
    let u = |i: usize| fl[i]["analysis"]["flutter"]["u"].as_f64().unwrap();
    assert!(
        (u(0) - u(1)).abs() < 1e-6 * u(1),
        "lag {} vs quasi-steady {}",
        u(0),
        u(1)
    );
    let lco: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("lco.json")).unwrap()).unwrap();
    eprintln!("U_F {}; lco {}", u(0), lco);
    let runs = lco["sweep"]["up"].as_array().unwrap();
    assert_eq!(runs[0]["classification"], "Decay", "{lco}");
    assert_eq!(runs[1]["classification"], "Lco", "{lco}");
    assert!(runs[1]["amplitude_alpha"].as_f64().unwrap() > 5f64.to_radians());
}
