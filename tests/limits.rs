//! The limits table walked (issue 27): every entry of `identify::limits::TABLE` is exceeded
//! — a count by one, a bound by one unit — at every entry point that sets it (command-line
//! flags, study keys, sweep specifications, data-set manifests, structure and model files;
//! the Python arguments are walked by python/tests/test_limits.py). Each request is refused
//! with exit code 2, a message naming the flag, key or field, and no output folder.
//! A limit added to the table without an entry point here fails the coverage check.

use crate::common;

use identify::limits::{self, TABLE};
use std::collections::BTreeSet;
use std::path::Path;

const STRUCTURE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/plate-rig.structure.toml"
);
const MODEL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/plate-truth.model.toml"
);
const LCO_STUDY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/flat-plate-lco.toml");
const QUICKSTART: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/quickstart.toml");

/// A count one above its cap.
fn count(max: usize) -> String {
    (max + 1).to_string()
}

/// A bound one unit above it.
fn above(max: f64) -> String {
    (max + 1.0).to_string()
}

/// `n` comma-separated numbers `1, 2, …` (as a TOML or JSON array body).
fn list(n: usize) -> String {
    (1..=n)
        .map(|i| format!("{}", 1.0 + i as f64 * 1e-4))
        .collect::<Vec<_>>()
        .join(",")
}

struct Walk<'a> {
    dir: &'a Path,
    n: usize,
    covered: BTreeSet<&'static str>,
}

impl Walk<'_> {
    fn file(&mut self, ext: &str, body: &str) -> String {
        self.n += 1;
        let p = self.dir.join(format!("in{}.{ext}", self.n));
        std::fs::write(&p, body).unwrap();
        p.to_str().unwrap().to_string()
    }

    /// A data set whose manifest has `from` replaced by `to`.
    fn dataset(&mut self, from: &str, to: &str) -> String {
        self.n += 1;
        let root = self.dir.join(format!("ds{}", self.n));
        std::fs::create_dir_all(root.join("cases")).unwrap();
        let manifest = "format = \"aeroform-dataset/1\"\nname = \"limits\"\n\
             [section]\nchord = 0.25\nspan = 0.75\nair_density = 1.225\n\
             [units]\nheave = \"mm\"\npitch = \"deg\"\nlift = \"N\"\nmoment = \"N*m\"\n\
             [[case]]\nid = \"D-U6-A12\"\nkind = \"forced\"\nfile = \"cases/D-U6-A12.csv\"\n\
             wind_speed = 6.0\nconfig = \"D\"\nfreq_pitch = 2.0\nfreq_heave = 1.3\n";
        assert!(manifest.contains(from), "{from}");
        std::fs::write(root.join("manifest.toml"), manifest.replace(from, to)).unwrap();
        let mut csv = String::from("t,h,alpha,lift,moment\n");
        let tau = 2.0 * std::f64::consts::PI;
        for i in 0..2048 {
            let t = i as f64 / 512.0;
            let a = 12.0 * (tau * 2.0 * t).sin();
            let h = 18.0 * (tau * 1.3 * t).sin();
            let lift = -0.9 * a - 0.02 * h + 1e-3 * ((i * 7919) % 1000) as f64 / 1000.0;
            csv += &format!("{t},{h},{a},{lift},{}\n", 0.03 * a + 0.001 * h);
        }
        std::fs::write(root.join("cases/D-U6-A12.csv"), csv).unwrap();
        root.to_str().unwrap().to_string()
    }

    /// A study: `base` with `from` replaced by `to`.
    fn study(&mut self, base: &str, from: &str, to: &str) -> String {
        let text = std::fs::read_to_string(base).unwrap();
        assert!(text.contains(from), "{base}: {from}");
        let text = text.replace(from, to);
        self.file("toml", &text)
    }

    /// Runs `args` (with `--out` appended) and checks the refusal of `limit`.
    fn refused(&mut self, limit: &'static str, args: &[&str], names: &str) {
        assert!(limits::find(limit).is_some(), "{limit} is not in the table");
        let out = self.dir.join("out");
        let mut all: Vec<&str> = args.to_vec();
        all.extend(["--out", out.to_str().unwrap()]);
        let (code, _, stderr) = common::aeroform_code_in(self.dir, &all);
        let shown: Vec<String> = all
            .iter()
            .map(|a| a.chars().take(80).collect::<String>())
            .collect();
        assert_eq!(
            code,
            2,
            "{limit}: `aeroform {}` exited {code}: {stderr}",
            shown.join(" ")
        );
        assert!(
            stderr.contains(names),
            "{limit}: the message does not name `{names}`: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{limit}: {stderr}");
        println!("{limit}: {}", stderr.trim().replace('\n', " | "));
        assert!(
            !out.exists(),
            "{limit}: a refused request wrote {}",
            out.display()
        );
        self.covered.insert(limit);
    }
}

#[test]
fn every_limit_exceeded_at_every_entry_point_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mut w = Walk {
        dir: tmp.path(),
        n: 0,
        covered: BTreeSet::new(),
    };
    let st = |args: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        v.extend(["--structure".into(), STRUCTURE.into()]);
        v.extend(["--model".into(), MODEL.into()]);
        v
    };
    let run = |w: &mut Walk, limit: &'static str, args: Vec<String>, names: &str| {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        w.refused(limit, &refs, names);
    };
    let structure = std::fs::read_to_string(STRUCTURE).unwrap();
    let model = std::fs::read_to_string(MODEL).unwrap();

    // MAX_SPEED
    let u = above(limits::MAX_SPEED);
    let u_list = format!("5:{u}:3");
    run(
        &mut w,
        "MAX_SPEED",
        st(&["flutter", "--speeds", &u_list]),
        "--speeds",
    );
    run(&mut w, "MAX_SPEED", st(&["lco", "--speed", &u]), "--speed");
    run(
        &mut w,
        "MAX_SPEED",
        st(&["lco", "--sweep", &u_list]),
        "--sweep",
    );
    run(
        &mut w,
        "MAX_SPEED",
        st(&["branch", "--speeds", &format!("5:{u}")]),
        "speeds",
    );
    run(
        &mut w,
        "MAX_SPEED",
        st(&["tunnel", "free", "--speeds", &u]),
        "--speeds",
    );
    let ds = w.dataset("wind_speed = 6.0", &format!("wind_speed = {u}"));
    run(
        &mut w,
        "MAX_SPEED",
        vec!["identify".into(), ds],
        "wind_speed",
    );
    let s = w.study(LCO_STUDY, "speeds = [1.8,", &format!("speeds = [{u},"));
    run(&mut w, "MAX_SPEED", vec!["run".into(), s], "lco.speeds");
    let s = w.study(QUICKSTART, "u_max = 4.0", &format!("u_max = {u}"));
    run(&mut w, "MAX_SPEED", vec!["run".into(), s], "flutter.u_max");
    let sw = w.file(
        "json",
        &format!(
            "{{\"kind\":\"flutter_map\",\"structure\":\"{STRUCTURE}\",\"model\":\"{MODEL}\",\
             \"speeds\":[1.0,{u}],\"grid\":{{\"mu\":[20.0]}}}}"
        ),
    );
    run(&mut w, "MAX_SPEED", vec!["sweep".into(), sw], "speeds");

    // MAX_CHORD
    let c = above(limits::MAX_CHORD);
    let s = w.file(
        "toml",
        &structure.replace("chord = 0.25", &format!("chord = {c}")),
    );
    run(
        &mut w,
        "MAX_CHORD",
        vec![
            "flutter".into(),
            "--structure".into(),
            s,
            "--model".into(),
            MODEL.into(),
        ],
        "chord",
    );
    run(
        &mut w,
        "MAX_CHORD",
        st(&["flutter", "--chord", &c]),
        "chord",
    );
    let ds = w.dataset("chord = 0.25", &format!("chord = {c}"));
    run(&mut w, "MAX_CHORD", vec!["identify".into(), ds], "chord");

    // MAX_SPAN, MAX_AIR_DENSITY
    let ds = w.dataset(
        "span = 0.75",
        &format!("span = {}", above(limits::MAX_SPAN)),
    );
    run(&mut w, "MAX_SPAN", vec!["identify".into(), ds], "span");
    let rho = above(limits::MAX_AIR_DENSITY);
    let ds = w.dataset("air_density = 1.225", &format!("air_density = {rho}"));
    run(
        &mut w,
        "MAX_AIR_DENSITY",
        vec!["identify".into(), ds],
        "air_density",
    );
    let s = w.file(
        "toml",
        &structure.replace("air_density = 1.225", &format!("air_density = {rho}")),
    );
    run(
        &mut w,
        "MAX_AIR_DENSITY",
        vec![
            "flutter".into(),
            "--structure".into(),
            s,
            "--model".into(),
            MODEL.into(),
        ],
        "air_density",
    );

    // MAX_DAMPING_RATIO
    for field in ["damping_heave", "damping_pitch"] {
        let z = above(limits::MAX_DAMPING_RATIO);
        let s = w.file(
            "toml",
            &structure.replace(&format!("{field} = 0.005"), &format!("{field} = {z}")),
        );
        run(
            &mut w,
            "MAX_DAMPING_RATIO",
            vec![
                "flutter".into(),
                "--structure".into(),
                s,
                "--model".into(),
                MODEL.into(),
            ],
            field,
        );
    }

    // MAX_ELASTIC_AXIS
    let m = w.file(
        "toml",
        &model.replace(
            "elastic_axis = -0.3",
            &format!("elastic_axis = {}", above(limits::MAX_ELASTIC_AXIS)),
        ),
    );
    run(
        &mut w,
        "MAX_ELASTIC_AXIS",
        vec![
            "flutter".into(),
            "--structure".into(),
            STRUCTURE.into(),
            "--model".into(),
            m,
        ],
        "elastic_axis",
    );

    // MAX_PITCH_DEG
    let a = above(limits::MAX_PITCH_DEG);
    run(
        &mut w,
        "MAX_PITCH_DEG",
        st(&["lco", "--speed", "7", "--alpha0", &a]),
        "--alpha0",
    );
    run(
        &mut w,
        "MAX_PITCH_DEG",
        st(&["lco", "--sweep", "6:8:3", "--alpha0-down", &a]),
        "--alpha0-down",
    );
    run(
        &mut w,
        "MAX_PITCH_DEG",
        st(&["tunnel", "free", "--speeds", "7", "--alpha0", &a]),
        "--alpha0",
    );
    let s = w.study(
        LCO_STUDY,
        "perturbation_deg = 0.5",
        &format!("perturbation_deg = {a}"),
    );
    run(
        &mut w,
        "MAX_PITCH_DEG",
        vec!["run".into(), s],
        "lco.perturbation_deg",
    );
    let sw = w.file(
        "json",
        &format!(
            "{{\"kind\":\"flutter_map\",\"structure\":\"{STRUCTURE}\",\"model\":\"{MODEL}\",\
             \"speeds\":[1.0,2.0],\"grid\":{{\"mu\":[20.0]}},\"lco_speeds\":[5.0],\"alpha0\":{a}}}"
        ),
    );
    run(&mut w, "MAX_PITCH_DEG", vec!["sweep".into(), sw], "alpha0");

    // MAX_NONLINEAR_COEFFICIENT
    let k = format!("{:.1}", limits::MAX_NONLINEAR_COEFFICIENT + 1.0);
    let m = w.file(
        "toml",
        &model.replace("coefficient = -2.0", &format!("coefficient = {k}")),
    );
    run(
        &mut w,
        "MAX_NONLINEAR_COEFFICIENT",
        vec![
            "flutter".into(),
            "--structure".into(),
            STRUCTURE.into(),
            "--model".into(),
            m,
        ],
        "coefficient",
    );
    let s = w.study(
        QUICKSTART,
        "coefficient = -40.0",
        &format!("coefficient = {k}"),
    );
    run(
        &mut w,
        "MAX_NONLINEAR_COEFFICIENT",
        vec!["run".into(), s],
        "coefficient",
    );

    // MAX_FORCE_COEFFICIENT: a coefficient under its own cap whose forces blow up
    let m = w.file(
        "toml",
        &model.replace("coefficient = -2.0", "coefficient = 1e8"),
    );
    run(
        &mut w,
        "MAX_FORCE_COEFFICIENT",
        vec![
            "tunnel".into(),
            "forced".into(),
            "--model".into(),
            m,
            "--campaign".into(),
            "config=A".into(),
            "--duration".into(),
            "2".into(),
        ],
        "MAX_FORCE_COEFFICIENT",
    );

    // MAX_SPEEDS
    let n = count(limits::MAX_SPEEDS);
    let range = format!("1:2:{n}");
    let long = list(limits::MAX_SPEEDS + 1);
    run(
        &mut w,
        "MAX_SPEEDS",
        st(&["flutter", "--speeds", &range]),
        "--speeds",
    );
    run(
        &mut w,
        "MAX_SPEEDS",
        st(&["flutter", "--speeds", &long]),
        "--speeds",
    );
    run(
        &mut w,
        "MAX_SPEEDS",
        st(&["lco", "--sweep", &range]),
        "--sweep",
    );
    run(
        &mut w,
        "MAX_SPEEDS",
        st(&["tunnel", "free", "--speeds", &range]),
        "--speeds",
    );
    let s = w.study(QUICKSTART, "n_speeds = 60", &format!("n_speeds = {n}"));
    run(
        &mut w,
        "MAX_SPEEDS",
        vec!["run".into(), s],
        "flutter.n_speeds",
    );
    let s = w.study(LCO_STUDY, "speeds = [1.8,", &format!("speeds = [{long},"));
    run(&mut w, "MAX_SPEEDS", vec!["run".into(), s], "lco.speeds");
    let sw = w.file(
        "json",
        &format!(
            "{{\"kind\":\"flutter_map\",\"structure\":\"{STRUCTURE}\",\"model\":\"{MODEL}\",\
             \"speeds\":[{long}],\"grid\":{{\"mu\":[20.0]}}}}"
        ),
    );
    run(&mut w, "MAX_SPEEDS", vec!["sweep".into(), sw], "speeds");

    // MAX_BLIND_SETS
    let n = count(limits::MAX_BLIND_SETS);
    run(
        &mut w,
        "MAX_BLIND_SETS",
        vec!["diagnose".into(), "--blind".into(), n.clone()],
        "--blind",
    );
    let sw = w.file(
        "json",
        &format!("{{\"kind\":\"blind\",\"n\":{n},\"seed\":1}}"),
    );
    run(&mut w, "MAX_BLIND_SETS", vec!["sweep".into(), sw], "n");

    // MAX_CASES: 2 amplitudes × (MAX_CASES / 2 + 1) speeds, one case above the cap; the
    // refusal names the key and the limit (round 29: lowered to what `run` holds in 1 GB)
    assert_eq!(limits::MAX_CASES % 2, 0);
    let n = limits::MAX_CASES / 2 + 1;
    assert!(n <= limits::MAX_SPEEDS);
    let s = w.study(
        QUICKSTART,
        "amplitudes_deg = [6.0, 12.0, 18.0, 24.0]\nspeeds = [4.0, 6.0, 8.0, 10.0]",
        &format!("amplitudes_deg = [{}]\nspeeds = [{}]", list(2), list(n)),
    );
    run(
        &mut w,
        "MAX_CASES",
        vec!["run".into(), s.clone()],
        "data.synthetic.speeds",
    );
    run(&mut w, "MAX_CASES", vec!["run".into(), s], "MAX_CASES");
    let s = w.study(
        QUICKSTART,
        "[data.synthetic]",
        &format!(
            "[data.table_iv]\nrepeats = {}\nsigma = 0.5\nrate = 512.0\nduration = 0.1\n\
             moment = [0.9, 0.1, -0.4, 0.03, 0.05, 0.3]\n\
             lift = [0.1, 0.3, -0.1, 0.2, 0.5, 0.8]\n[unused]",
            count(limits::MAX_CASES)
        ),
    );
    let s = {
        // the quickstart's [data.synthetic] body is left under an unused table: drop it
        let text = std::fs::read_to_string(&s).unwrap();
        let head = text.split("[unused]").next().unwrap().to_string();
        let tail = text.split("[identify.settings]").nth(1).unwrap();
        std::fs::write(&s, format!("{head}[identify.settings]{tail}")).unwrap();
        s
    };
    run(
        &mut w,
        "MAX_CASES",
        vec!["run".into(), s.clone()],
        "data.table_iv.repeats",
    );
    run(&mut w, "MAX_CASES", vec!["run".into(), s], "MAX_CASES");

    // MAX_SAMPLES: 16 cases × 512 Hz × d s just above 25 M samples
    let d = (limits::MAX_SAMPLES / (16.0 * 512.0)).floor() + 1.0;
    let s = w.study(QUICKSTART, "duration = 10.0", &format!("duration = {d}"));
    run(&mut w, "MAX_SAMPLES", vec!["run".into(), s], "duration");
    run(
        &mut w,
        "MAX_SAMPLES",
        vec![
            "tunnel".into(),
            "forced".into(),
            "--model".into(),
            MODEL.into(),
            "--duration".into(),
            "100000".into(),
        ],
        "--duration",
    );

    // MAX_DURATION, MAX_RATE
    let d = above(limits::MAX_DURATION);
    run(
        &mut w,
        "MAX_DURATION",
        vec![
            "tunnel".into(),
            "forced".into(),
            "--model".into(),
            MODEL.into(),
            "--duration".into(),
            d.clone(),
        ],
        "--duration",
    );
    let s = w.study(QUICKSTART, "duration = 10.0", &format!("duration = {d}"));
    run(&mut w, "MAX_DURATION", vec!["run".into(), s], "duration");
    let r = above(limits::MAX_RATE);
    let s = w.study(QUICKSTART, "rate = 512.0", &format!("rate = {r}"));
    run(&mut w, "MAX_RATE", vec!["run".into(), s], "rate");

    // MAX_PERIODS, MAX_PHASE_PERIODS
    let s = w.study(
        LCO_STUDY,
        "max_periods = 800.0",
        &format!("max_periods = {}", above(limits::MAX_PERIODS)),
    );
    run(
        &mut w,
        "MAX_PERIODS",
        vec!["run".into(), s],
        "lco.max_periods",
    );
    let s = w.study(
        LCO_STUDY,
        "max_periods = 800.0",
        &format!(
            "max_periods = 800.0\nphase_periods = {}",
            above(limits::MAX_PHASE_PERIODS)
        ),
    );
    run(
        &mut w,
        "MAX_PHASE_PERIODS",
        vec!["run".into(), s],
        "lco.phase_periods",
    );

    // MAX_ENSEMBLE, MAX_N_DELTA
    let ds = w.dataset("wind_speed = 6.0", "wind_speed = 6.0");
    let n = count(limits::MAX_ENSEMBLE);
    run(
        &mut w,
        "MAX_ENSEMBLE",
        vec![
            "identify".into(),
            ds.clone(),
            "--ensemble".into(),
            n.clone(),
        ],
        "--ensemble",
    );
    let s = w.study(
        QUICKSTART,
        "[identify.settings]",
        &format!("[identify]\nensemble = {n}\n[identify.settings]"),
    );
    run(&mut w, "MAX_ENSEMBLE", vec!["run".into(), s], "ensemble");
    // MAX_ENSEMBLE_FITS: members × cases; the quickstart's 16 cases, a data set of 6
    let members = limits::MAX_ENSEMBLE_FITS / 16 + 1;
    assert!(members <= limits::MAX_ENSEMBLE);
    let s = w.study(
        QUICKSTART,
        "[identify.settings]",
        &format!("[identify]\nensemble = {members}\n[identify.settings]"),
    );
    run(
        &mut w,
        "MAX_ENSEMBLE_FITS",
        vec!["run".into(), s.clone()],
        "identify.ensemble",
    );
    run(
        &mut w,
        "MAX_ENSEMBLE_FITS",
        vec!["run".into(), s],
        "MAX_ENSEMBLE_FITS",
    );
    let extra: String = (1..6)
        .map(|k| {
            format!(
                "[[case]]\nid = \"D-U6-A12-{k}\"\nkind = \"forced\"\n\
                 file = \"cases/c{k}.csv\"\nwind_speed = 6.0\nconfig = \"D\"\n\
                 freq_pitch = 2.0\nfreq_heave = 1.3\n"
            )
        })
        .collect();
    let ds6 = w.dataset("freq_heave = 1.3\n", &format!("freq_heave = 1.3\n{extra}"));
    for k in 1..6 {
        let d = Path::new(&ds6);
        std::fs::copy(
            d.join("cases/D-U6-A12.csv"),
            d.join(format!("cases/c{k}.csv")),
        )
        .unwrap();
    }
    let members = (limits::MAX_ENSEMBLE_FITS / 6 + 1).to_string();
    run(
        &mut w,
        "MAX_ENSEMBLE_FITS",
        vec![
            "identify".into(),
            ds6.clone(),
            "--ensemble".into(),
            members.clone(),
        ],
        "--ensemble",
    );
    run(
        &mut w,
        "MAX_ENSEMBLE_FITS",
        vec!["identify".into(), ds6, "--ensemble".into(), members],
        "MAX_ENSEMBLE_FITS",
    );
    let n = count(limits::MAX_N_DELTA);
    run(
        &mut w,
        "MAX_N_DELTA",
        vec!["identify".into(), ds, "--n-delta".into(), n.clone()],
        "n_delta",
    );
    let s = w.study(
        QUICKSTART,
        "group_by = \"config\"",
        &format!("group_by = \"config\"\nn_delta = {n}"),
    );
    run(&mut w, "MAX_N_DELTA", vec!["run".into(), s], "n_delta");

    // MAX_GRID_POINTS: 11 μ × 9091 σ = 100 001 points
    assert_eq!(11 * 9091, limits::MAX_GRID_POINTS + 1);
    let sw = w.file(
        "json",
        &format!(
            "{{\"kind\":\"flutter_map\",\"structure\":\"{STRUCTURE}\",\"model\":\"{MODEL}\",\
             \"speeds\":[1.0,2.0],\"grid\":{{\"mu\":[{}],\"sigma\":[{}]}}}}",
            list(11),
            list(9091)
        ),
    );
    run(&mut w, "MAX_GRID_POINTS", vec!["sweep".into(), sw], "grid");

    // branch counts: flags and study keys
    for (limit, max, flag, key) in [
        (
            "MAX_HARMONICS",
            limits::MAX_HARMONICS,
            "--harmonics",
            "harmonics",
        ),
        (
            "MAX_STEPS_PER_PERIOD",
            limits::MAX_STEPS_PER_PERIOD,
            "--steps-per-period",
            "steps_per_period",
        ),
        (
            "MAX_BRANCH_POINTS",
            limits::MAX_BRANCH_POINTS,
            "--max-points",
            "max_points",
        ),
    ] {
        let n = count(max);
        run(
            &mut w,
            limit,
            st(&[
                "branch",
                "--speeds",
                "5:9",
                "--method",
                "harmonic_balance",
                flag,
                &n,
            ]),
            flag,
        );
        let s = w.study(
            LCO_STUDY,
            "speeds = [1.5, 2.3]",
            &format!("speeds = [1.5, 2.3]\nmethod = \"harmonic_balance\"\n{key} = {n}"),
        );
        run(
            &mut w,
            limit,
            vec!["run".into(), s],
            &format!("branch.{key}"),
        );
    }

    // Readers' caps (issue 39, row 5): a text file one byte beyond MAX_TEXT_FILE_BYTES
    // (sparse: no disk used) as a manifest, a study, a sweep specification and a measured
    // table; a case-file line beyond MAX_CSV_LINE_BYTES; MAX_DATASET_CASES + 1 cases;
    // MAX_MEASURED_POINTS + 1 measured rows
    let big = |w: &mut Walk, ext: &str| -> String {
        let p = w.file(ext, "");
        let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
        f.set_len(limits::MAX_TEXT_FILE_BYTES as u64 + 1).unwrap();
        p
    };
    let ds = w.dataset("wind_speed = 6.0", "wind_speed = 6.0");
    let m = Path::new(&ds).join("manifest.toml");
    std::fs::OpenOptions::new()
        .write(true)
        .open(&m)
        .unwrap()
        .set_len(limits::MAX_TEXT_FILE_BYTES as u64 + 1)
        .unwrap();
    run(
        &mut w,
        "MAX_TEXT_FILE_BYTES",
        vec!["identify".into(), ds],
        "MAX_TEXT_FILE_BYTES",
    );
    let s = big(&mut w, "toml");
    run(
        &mut w,
        "MAX_TEXT_FILE_BYTES",
        vec!["run".into(), s],
        "MAX_TEXT_FILE_BYTES",
    );
    let s = big(&mut w, "json");
    run(
        &mut w,
        "MAX_TEXT_FILE_BYTES",
        vec!["sweep".into(), s],
        "MAX_TEXT_FILE_BYTES",
    );
    let s = big(&mut w, "csv");
    run(
        &mut w,
        "MAX_TEXT_FILE_BYTES",
        st(&["diagnose", "--measured-branch", &s]),
        "MAX_TEXT_FILE_BYTES",
    );
    // MAX_RESULT_FILE_BYTES (round 29): aeroform's own identification.json is read back
    // under its own cap: above MAX_TEXT_FILE_BYTES it is accepted (a large study no longer
    // fails reading back what it wrote), one byte above the result cap it is refused
    common::forced_set(w.dir, "flyable", "3", "2");
    let id_dir = w.dir.join("id-out");
    let (code, _, stderr) = common::aeroform_code_in(
        w.dir,
        &[
            "--quiet",
            "identify",
            "flyable",
            "--out",
            id_dir.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let id_json = id_dir.join("identification.json");
    let mut text = std::fs::read_to_string(&id_json).unwrap();
    text.push_str(&" ".repeat(limits::MAX_TEXT_FILE_BYTES as usize + 1 - text.len()));
    let padded = w.dir.join("padded.identification.json");
    std::fs::write(&padded, text).unwrap();
    let rig = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/plate-rig.structure.toml");
    let fl = w.dir.join("fl-out");
    let (code, _, stderr) = common::aeroform_code_in(
        w.dir,
        &[
            "flutter",
            "--structure",
            rig.to_str().unwrap(),
            "--model",
            padded.to_str().unwrap(),
            "--chord",
            "0.25",
            "--out",
            fl.to_str().unwrap(),
        ],
    );
    assert_eq!(
        code, 0,
        "an identification.json above MAX_TEXT_FILE_BYTES: {stderr}"
    );
    let huge = w.file("json", "");
    std::fs::OpenOptions::new()
        .write(true)
        .open(&huge)
        .unwrap()
        .set_len(limits::MAX_RESULT_FILE_BYTES as u64 + 1)
        .unwrap();
    w.refused(
        "MAX_RESULT_FILE_BYTES",
        &[
            "flutter",
            "--structure",
            rig.to_str().unwrap(),
            "--model",
            &huge,
            "--chord",
            "0.25",
        ],
        "MAX_RESULT_FILE_BYTES",
    );
    let ds = w.dataset("wind_speed = 6.0", "wind_speed = 6.0");
    let case = Path::new(&ds).join("cases/D-U6-A12.csv");
    let mut text = std::fs::read_to_string(&case).unwrap();
    text.push_str(&"1".repeat(limits::MAX_CSV_LINE_BYTES + 1));
    text.push('\n');
    std::fs::write(&case, text).unwrap();
    run(
        &mut w,
        "MAX_CSV_LINE_BYTES",
        vec!["identify".into(), ds],
        "MAX_CSV_LINE_BYTES",
    );
    let one = "[[case]]\nid = \"D-U6-A12\"\nkind = \"forced\"\nfile = \"cases/D-U6-A12.csv\"\n\
               wind_speed = 6.0\nconfig = \"D\"\nfreq_pitch = 2.0\nfreq_heave = 1.3\n";
    let mut cases = String::with_capacity(200 * (limits::MAX_DATASET_CASES + 1));
    for i in 0..=limits::MAX_DATASET_CASES {
        cases.push_str(&one.replace("id = \"D-U6-A12\"", &format!("id = \"c{i}\"")));
    }
    let ds = w.dataset(one, &cases);
    run(
        &mut w,
        "MAX_DATASET_CASES",
        vec!["identify".into(), ds],
        "MAX_DATASET_CASES",
    );
    let mut table = String::from("branch,wind_speed_m_s,pitch_amp_rad\n");
    for i in 0..=limits::MAX_MEASURED_POINTS {
        table.push_str(&format!("stable,{},0.05\n", 10.0 + i as f64 * 1e-5));
    }
    let t = w.file("csv", &table);
    run(
        &mut w,
        "MAX_MEASURED_POINTS",
        st(&["diagnose", "--measured-branch", &t]),
        "MAX_MEASURED_POINTS",
    );

    // MAX_LABEL_CHARS: a `config` label one character beyond the cap; and a manifest
    // `mean_pitch` one degree beyond MAX_PITCH_DEG
    let long = "D".repeat(limits::MAX_LABEL_CHARS + 1);
    let ds = w.dataset("config = \"D\"", &format!("config = \"{long}\""));
    run(
        &mut w,
        "MAX_LABEL_CHARS",
        vec!["identify".into(), ds],
        "config",
    );
    let ds = w.dataset(
        "wind_speed = 6.0",
        &format!(
            "wind_speed = 6.0\nmean_pitch = {}",
            above(limits::MAX_PITCH_DEG)
        ),
    );
    run(
        &mut w,
        "MAX_PITCH_DEG",
        vec!["identify".into(), ds],
        "mean_pitch",
    );

    // Set only through the Rust API (`BranchOptions`): checked by `check()`.
    for (limit, name) in [
        ("MAX_SCAN_SPEEDS", "branch.n_scan"),
        ("MAX_NEWTON_ITERATIONS", "branch.max_newton"),
    ] {
        let mut o = aeroelastic::branch::BranchOptions::default();
        match limit {
            "MAX_SCAN_SPEEDS" => o.n_scan = limits::MAX_SCAN_SPEEDS + 1,
            _ => o.max_newton = limits::MAX_NEWTON_ITERATIONS + 1,
        }
        let e = o.check().unwrap_err().to_string();
        assert!(e.contains(name), "{limit}: {e}");
        w.covered.insert(limit);
    }

    let all: BTreeSet<&str> = TABLE.iter().map(|l| l.name).collect();
    let missing: Vec<_> = all.difference(&w.covered).collect();
    assert!(
        missing.is_empty(),
        "limits without an entry point walked: {missing:?}"
    );
}
