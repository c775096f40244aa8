//! Round trip through the data-set format: a known nonlinear law → synthetic forced-motion
//! records with rig-like noise → written in mm/deg/N/N·m totals → read back → preprocessed →
//! identified. The selected support must be the law's, and the coefficients close to it.

use identify::dataset::{
    read_dataset, write_dataset, AngleUnit, CaseSpec, ForceUnit, LengthUnit, Manifest, MomentUnit,
    Units,
};
use identify::pipeline::{identify, IdentifySettings};
use identify::preprocess::PreprocessOptions;
use identify::record::{CaseMeta, SectionGeometry};
use identify::synthetic::{forced_record, HarmonicMotion, PolynomialLaw, Sampling};
use identify::workflow::prepare_dataset;

fn term_name(p: [u8; 4]) -> String {
    let names = ["alpha", "alpha_dot", "h", "h_dot"];
    let mut parts = Vec::new();
    for (i, &k) in p.iter().enumerate() {
        match k {
            0 => {}
            1 => parts.push(names[i].to_string()),
            k => parts.push(format!("{}^{k}", names[i])),
        }
    }
    parts.join("*")
}

#[test]
fn demo_law_is_recovered_from_a_written_data_set() {
    let tmp = tempfile::tempdir().unwrap();
    let section = SectionGeometry {
        chord: 0.25,
        span: 0.75,
        air_density: 1.225,
    };
    let law = PolynomialLaw::demo();
    let mut cases = Vec::new();
    let mut records = Vec::new();
    for (i, u) in [4.0, 7.0, 10.0].into_iter().enumerate() {
        for (j, amp) in [8.0_f64, 16.0, 24.0].into_iter().enumerate() {
            let id = format!("D-U{u}-A{amp}");
            let mut spec = CaseSpec::forced(&id, format!("cases/{id}.csv"), u);
            spec.config = Some("D".into());
            spec.amplitude = Some(amp);
            spec.freq_pitch = Some(2.0);
            spec.freq_heave = Some(1.3);
            let motion = HarmonicMotion {
                freq_pitch: 2.0,
                freq_heave: 1.3,
                amp_pitch: amp.to_radians(),
                amp_heave: 1.5 * amp * 1e-3,
                mean_pitch: 0.0,
            };
            let meta = CaseMeta {
                id: id.clone(),
                wind_speed: u,
                config: Some("D".into()),
                ..CaseMeta::default()
            };
            let seed = (10 * i + j) as u64;
            records.push(
                forced_record(meta, &section, &motion, &law, &Sampling::default(), seed).unwrap(),
            );
            cases.push(spec);
        }
    }
    let manifest = Manifest {
        name: "round trip".into(),
        description: None,
        section,
        structure: None,
        units: Units {
            heave: LengthUnit::Mm,
            pitch: AngleUnit::Deg,
            lift: ForceUnit::N,
            moment: MomentUnit::Nm,
        },
        convention: Default::default(),
        cases,
        extra: None,
    };
    let dir = tmp.path().join("ds");
    write_dataset(&dir, &manifest, &records).unwrap();
    let ds = read_dataset(&dir).unwrap();
    let prepared = prepare_dataset(&ds, &PreprocessOptions::default()).unwrap();
    let result = identify(
        &prepared.cases,
        &IdentifySettings::default(),
        "round trip",
        &|_| {},
    )
    .unwrap();
    assert_eq!(result.library.rank, 25);
    for (channel, truth) in [("moment", &law.moment), ("lift", &law.lift)] {
        let group = &result.groups[0];
        let support = if channel == "moment" {
            &group.moment.support
        } else {
            &group.lift.support
        };
        let mut want: Vec<String> = truth.iter().map(|t| term_name(t.powers)).collect();
        let mut got = support.clone();
        want.sort();
        got.sort();
        assert_eq!(got, want, "{channel} support");
        for (case, nd) in result.cases.iter().zip(&prepared.cases) {
            let (f, target) = if channel == "moment" {
                (&case.moment.terms, &nd.c_moment)
            } else {
                (&case.lift.terms, &nd.c_lift)
            };
            let range = target.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for t in truth.iter() {
                let name = term_name(t.powers);
                let c = f.get(&name).unwrap();
                // Peak of the term's column on this case's motion.
                let peak = (0..nd.len())
                    .map(|i| {
                        (0..4)
                            .map(|k| nd.x[k][i].powi(i32::from(t.powers[k])))
                            .product::<f64>()
                            .abs()
                    })
                    .fold(0.0_f64, f64::max);
                // The coefficient error, seen in the force, stays below the balance noise
                // (0.1 % of range): a term far below the noise is not required to be exact.
                let err = (c - t.coefficient).abs() * peak / range;
                assert!(
                    err < 1e-3,
                    "{} {channel} {name}: {c} vs {} (force-level error {err:.2e} of range)",
                    case.id,
                    t.coefficient
                );
            }
        }
    }
}

/// Negates column `column` of a case CSV written by `write_dataset` (text edit, so the
/// test does not rely on the writer's own sign handling).
fn negate_column(path: &std::path::Path, column: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let k = header.split(',').position(|c| c == column).unwrap();
    let mut out = format!("{header}\n");
    for l in lines {
        let cells: Vec<String> = l
            .split(',')
            .enumerate()
            .map(|(i, c)| match (i == k, c.strip_prefix('-')) {
                (false, _) => c.to_string(),
                (true, Some(pos)) => pos.to_string(),
                (true, None) if c.parse::<f64>().unwrap() == 0.0 => c.to_string(),
                (true, None) => format!("-{c}"),
            })
            .collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    std::fs::write(path, out).unwrap();
}

/// Identification of the data set in `dir` read with `options`, as JSON without the
/// data-set name.
fn identify_json(
    dir: &std::path::Path,
    options: &identify::dataset::ReadOptions,
) -> serde_json::Value {
    let ds = identify::dataset::read_dataset_with(dir, options).unwrap();
    let prepared = prepare_dataset(&ds, &PreprocessOptions::default()).unwrap();
    let result = identify(&prepared.cases, &IdentifySettings::default(), "x", &|_| {}).unwrap();
    serde_json::to_value(&result).unwrap()
}

/// Issue 16 acceptance: a data set exported lift-positive-up (and one with every column in
/// the opposite sense) identifies to exactly the Scanlan derivatives when the convention is
/// declared in `[convention]` or by `--flip-lift`; undeclared, every lift coefficient (H1*..H4*,
/// lift N*) comes out with the opposite sign and the moment is unchanged — as DATA_FORMAT.md
/// says.
#[test]
fn lift_up_data_set_declared_as_such_identifies_like_scanlan() {
    let tmp = tempfile::tempdir().unwrap();
    let section = SectionGeometry {
        chord: 0.25,
        span: 0.75,
        air_density: 1.225,
    };
    let law = PolynomialLaw::demo();
    let (mut cases, mut records) = (vec![], vec![]);
    for (i, u) in [5.0, 9.0].into_iter().enumerate() {
        for (j, amp) in [10.0_f64, 20.0].into_iter().enumerate() {
            let id = format!("D-U{u}-A{amp}");
            let mut spec = CaseSpec::forced(&id, format!("cases/{id}.csv"), u);
            spec.config = Some("D".into());
            spec.amplitude = Some(amp.to_radians()); // the manifest is in SI (rad)
            let motion = HarmonicMotion {
                freq_pitch: 2.0,
                freq_heave: 1.3,
                amp_pitch: amp.to_radians(),
                amp_heave: 1.5 * amp * 1e-3,
                mean_pitch: 0.0,
            };
            let meta = CaseMeta {
                id: id.clone(),
                wind_speed: u,
                config: Some("D".into()),
                ..CaseMeta::default()
            };
            let seed = (10 * i + j) as u64;
            records.push(
                forced_record(meta, &section, &motion, &law, &Sampling::default(), seed).unwrap(),
            );
            cases.push(spec);
        }
    }
    let manifest = Manifest {
        name: "convention".into(),
        description: None,
        section,
        structure: None,
        units: Units::default(),
        convention: Default::default(),
        cases,
        extra: None,
    };
    let scanlan = tmp.path().join("scanlan");
    write_dataset(&scanlan, &manifest, &records).unwrap();
    let opts = identify::dataset::ReadOptions::default();
    let want = identify_json(&scanlan, &opts);

    // lift positive up: the lift column negated by hand, the manifest declaring it
    let copy = |name: &str, columns: &[&str], declaration: &str| {
        let dir = tmp.path().join(name);
        write_dataset(&dir, &manifest, &records).unwrap();
        for c in &manifest.cases {
            for col in columns {
                negate_column(&dir.join(&c.file), col);
            }
        }
        let m = dir.join("manifest.toml");
        let text = std::fs::read_to_string(&m).unwrap();
        let text = text.replacen("\n[[case]]", &format!("\n{declaration}\n[[case]]"), 1);
        std::fs::write(&m, text).unwrap();
        dir
    };
    let lift_up = copy("lift-up", &["lift"], "[convention]\nlift = \"up\"\n");
    assert_eq!(identify_json(&lift_up, &opts), want, "declared lift up");

    let all = copy(
        "all-flipped",
        &["h", "alpha", "lift", "moment"],
        "[convention]\nheave = \"up\"\npitch = \"nose-down\"\nlift = \"up\"\nmoment = \"nose-down\"\n",
    );
    assert_eq!(identify_json(&all, &opts), want, "every column flipped");

    // undeclared: read as Scanlan, so lift coefficients change sign, moment does not
    let undeclared = copy("undeclared", &["lift"], "");
    let got = identify_json(&undeclared, &opts);
    let flip = identify::dataset::ReadOptions { flip_lift: true };
    assert_eq!(identify_json(&undeclared, &flip), want, "--flip-lift");
    let mut n_checked = 0;
    for (g, w) in got["cases"]
        .as_array()
        .unwrap()
        .iter()
        .zip(want["cases"].as_array().unwrap())
    {
        assert_eq!(g["moment"]["eq19"], w["moment"]["eq19"]);
        for (k, wv) in w["lift"]["eq19"].as_object().unwrap() {
            if let Some(wv) = wv.as_f64() {
                assert_eq!(g["lift"]["eq19"][k].as_f64(), Some(-wv), "{k}");
                n_checked += 1;
            }
        }
    }
    assert!(n_checked >= 16, "{n_checked} lift derivatives compared");
}
