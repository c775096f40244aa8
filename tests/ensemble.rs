//! Ensemble uncertainty end to end: virtual forced campaign (truth: scenarios/plate-truth,
//! configuration D) → identify → block-bootstrap ensemble → flutter / divergence intervals
//! of the identified laws on the plate rig; coverage of the flutter-speed interval over
//! independent noise seeds; and the CLI (`identify|flutter|lco --ensemble N`).

use std::path::Path;
use std::sync::Arc;

use aeroelastic::ensemble::{flutter_ensemble, member_laws};
use aeroelastic::files::{LoadedModel, StructureFile};
use aeroelastic::flutter::{FlutterMethod, FlutterOptions};
use aeroelastic::identified::{IdentifiedLaw, IdentifiedOptions};
use aeroelastic::section::Section;
use aeroelastic::tunnel::{self, Campaign, ForcedOptions, SensorNoise};
use identify::ensemble::{bootstrap, EnsembleSettings};
use identify::pipeline::{identify, Identification, IdentifySettings};
use identify::preprocess::PreprocessOptions;

const CHORD: f64 = 0.25;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn rig() -> (aeroelastic::structure::Structure, f64) {
    let f = StructureFile::read(&root().join("scenarios/plate-rig.structure.toml")).unwrap();
    (f.structure().unwrap(), f.air_density)
}

fn flutter_opts() -> FlutterOptions {
    FlutterOptions {
        u_min: 3.0,
        u_max: 10.0,
        n_speeds: 57,
        tol_rel: 1e-8,
    }
}

/// Configuration D, pitch amplitudes 12° and 24°, U = 3..10 m/s (16 cases), paper noise
/// from `seed` (or none), identified with default settings, with an ensemble of `members`.
fn identified(dir: &Path, seed: u64, noise: bool, members: usize) -> Identification {
    let truth = LoadedModel::load(&root().join("scenarios/plate-truth.model.toml"), None)
        .unwrap()
        .nonlinear
        .unwrap();
    let mut campaign = Campaign::paper_config("D").unwrap();
    campaign.amplitudes_deg = vec![12.0, 24.0];
    campaign.wind_speeds = (3..=10).map(f64::from).collect();
    let mut opts = ForcedOptions::paper(seed);
    if !noise {
        opts.noise = SensorNoise::none();
    }
    let (manifest, records) =
        tunnel::forced_dataset(&truth, &campaign.cases(), &opts, &|_| {}).unwrap();
    tunnel::write(dir, &manifest, &records).unwrap();
    let ds = identify::dataset::read_dataset(dir).unwrap();
    let prepared = identify::workflow::prepare_dataset(&ds, &PreprocessOptions::default()).unwrap();
    let mut id = identify(
        &prepared.cases,
        &IdentifySettings::default(),
        &ds.manifest.name,
        &|_| {},
    )
    .unwrap();
    if members > 0 {
        let t = std::time::Instant::now();
        id.ensemble =
            Some(bootstrap(&prepared.cases, &id, &EnsembleSettings::new(members, seed)).unwrap());
        eprintln!(
            "bootstrap of {members} members over {} cases: {:.3} s",
            prepared.cases.len(),
            t.elapsed().as_secs_f64()
        );
    }
    id
}

fn flutter_speed(law: &IdentifiedLaw) -> f64 {
    flutter_and_divergence(law).0
}

fn flutter_and_divergence(law: &IdentifiedLaw) -> (f64, Option<f64>) {
    let (st, rho) = rig();
    let fa = Section::new(st, Arc::new(law.model().clone()), rho)
        .unwrap()
        .flutter(FlutterMethod::Pk, &flutter_opts())
        .unwrap();
    (fa.flutter.unwrap().u, fa.divergence_speed)
}

/// Truth U_F (p-method on the truth's own time-domain realisation, as tests/round_trip.rs)
/// and divergence speed.
fn truth_flutter_speed() -> (f64, Option<f64>) {
    let (st, rho) = rig();
    let truth = LoadedModel::load(&root().join("scenarios/plate-truth.model.toml"), None)
        .unwrap()
        .model;
    let fo = FlutterOptions {
        tol_rel: 1e-10,
        ..flutter_opts()
    };
    let fa = Section::new(st, truth, rho)
        .unwrap()
        .flutter(FlutterMethod::P, &fo)
        .unwrap();
    (fa.flutter.unwrap().u, fa.divergence_speed)
}

type Intervals = Vec<(
    f64,
    identify::ensemble::Interval,
    Option<identify::ensemble::Interval>,
)>;

/// Per seed: (nominal U_F, interval of U_F, interval of U_D) of the ensemble.
fn flutter_intervals(seeds: std::ops::Range<u64>, members: usize) -> Intervals {
    let (st, rho) = rig();
    seeds
        .map(|seed| {
            let dir = tempfile::tempdir().unwrap();
            let id = identified(dir.path(), 100 + seed, true, members);
            let opts = IdentifiedOptions::new(CHORD);
            let nominal = flutter_speed(&IdentifiedLaw::from_identification(&id, &opts).unwrap());
            let t = std::time::Instant::now();
            let (laws, e) = member_laws(&id, &opts, None).unwrap();
            let fe =
                flutter_ensemble(&st, &laws, e, rho, FlutterMethod::Pk, &flutter_opts()).unwrap();
            assert!(fe.failures.is_empty(), "{:?}", fe.failures);
            assert_eq!(fe.flutter_speed.found, members);
            let iv = fe.flutter_speed.interval.unwrap();
            eprintln!(
                "seed {seed}: U_F nominal {nominal:.5}, ensemble median {:.5} [{:.5}, {:.5}] \
                 (laws + flutter of {members} members {:.2} s); U_D {:?}",
                iv.median,
                iv.lower,
                iv.upper,
                t.elapsed().as_secs_f64(),
                fe.divergence_speed.interval
            );
            (nominal, iv, fe.divergence_speed.interval)
        })
        .collect()
}

fn coverage(v: &[identify::ensemble::Interval], truth: f64, label: &str) -> f64 {
    let hits = v.iter().filter(|iv| iv.contains(truth)).count();
    let p = hits as f64 / v.len() as f64;
    eprintln!(
        "coverage against {label} ({truth:.5} m/s): {hits}/{} = {p:.3} ± {:.3}",
        v.len(),
        (p * (1.0 - p) / v.len() as f64).sqrt()
    );
    p
}

/// Fast variant (CI): two noise seeds, 30 members. The interval brackets the nominal
/// estimate, has a width set by the noise (not 0, not the whole scan), every member
/// flutters inside the scan; coverage is printed against the noise-free estimate.
#[test]
fn flutter_speed_interval_from_the_ensemble() {
    let dir = tempfile::tempdir().unwrap();
    let clean = identified(dir.path(), 1, false, 0);
    let uf_clean = flutter_speed(
        &IdentifiedLaw::from_identification(&clean, &IdentifiedOptions::new(CHORD)).unwrap(),
    );
    let v = flutter_intervals(0..2, 30);
    for (nominal, iv, _) in &v {
        assert!(iv.lower < iv.upper, "{iv:?}");
        assert!(iv.contains(*nominal), "nominal {nominal} outside {iv:?}");
        let rel = (iv.upper - iv.lower) / iv.median;
        assert!(rel > 1e-5 && rel < 0.05, "relative width {rel}");
    }
    let uf: Vec<_> = v.iter().map(|x| x.1).collect();
    coverage(&uf, uf_clean, "the noise-free identification");
}

/// Full check (ignored, a few minutes): 60 noise seeds, 100 members, nominal 90 %.
/// Coverage against the noise-free identification's U_F (what the intervals claim:
/// the spread due to noise) and against the truth's U_F (adds the K-interpolation bias of
/// the derivative tables, not in the intervals). Numbers in docs/DECISIONS.md.
#[test]
#[ignore]
fn flutter_speed_interval_coverage_full() {
    let dir = tempfile::tempdir().unwrap();
    let clean = identified(dir.path(), 1, false, 0);
    let (uf_clean, ud_clean) = flutter_and_divergence(
        &IdentifiedLaw::from_identification(&clean, &IdentifiedOptions::new(CHORD)).unwrap(),
    );
    let (uf_truth, ud_truth) = truth_flutter_speed();
    let v = flutter_intervals(0..60, 100);
    let uf: Vec<_> = v.iter().map(|x| x.1).collect();
    let p = coverage(&uf, uf_clean, "the noise-free identification (U_F)");
    coverage(&uf, uf_truth, "the truth (U_F)");
    let ud: Vec<_> = v.iter().filter_map(|x| x.2).collect();
    eprintln!("U_D (outside the campaign's K range): noise-free {ud_clean:?}, truth {ud_truth:?}");
    if let Some(u) = ud_clean {
        coverage(&ud, u, "the noise-free identification (U_D)");
    }
    if let Some(u) = ud_truth {
        coverage(&ud, u, "the truth (U_D)");
    }
    let se = (0.09f64 / v.len() as f64).sqrt();
    assert!((p - 0.9).abs() < 0.03 + 2.0 * se, "coverage {p}");
}

/// The CLI: `identify --ensemble` writes the section with its seed; `flutter --ensemble`
/// and `lco --ensemble` write intervals; asking for more members than stored is an error
/// naming the count.
#[test]
fn cli_ensemble_flags() {
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    identified(&data, 5, true, 0);
    let out = dir.path().join("out");
    let bin = env!("CARGO_BIN_EXE_aeroform");
    let run = |args: &[&str]| {
        let o = Command::new(bin).args(args).output().unwrap();
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr),
        )
    };
    let (ok, text) = run(&[
        "identify",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--ensemble",
        "12",
        "--seed",
        "77",
        "--quiet",
    ]);
    assert!(ok, "{text}");
    let idf = out.join("identification.json");
    let id = Identification::read(&idf).unwrap();
    let e = id.ensemble.as_ref().unwrap();
    assert_eq!((e.settings.members, e.settings.seed), (12, 77));
    // the derivative figure carries the ensemble intervals as error bars around each point
    let fig = plots::adapters::identification::derivative_figure(&id, 0.0);
    let mut bars = 0;
    for p in &fig.panels {
        for g in &p.points {
            assert_eq!(g.interval.len(), g.k.len(), "{}", p.name);
            for (v, [lo, hi]) in g.value.iter().zip(&g.interval) {
                assert!(lo < hi, "{}: [{lo}, {hi}]", p.name);
                // the nominal value is the full-data fit, near the ensemble median
                assert!(
                    *lo - (hi - lo) < *v && *v < hi + (hi - lo),
                    "{}: {v} vs [{lo}, {hi}]",
                    p.name
                );
                bars += 1;
            }
        }
    }
    assert_eq!(bars, 8 * 16);
    let fig_dir = std::env::var_os("AEROFORM_FIGURE_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| dir.path().to_path_buf());
    plots::render::save(&fig, &fig_dir, "derivatives_ensemble").unwrap();
    let rig = root().join("scenarios/plate-rig.structure.toml");
    let (ok, text) = run(&[
        "flutter",
        "--structure",
        rig.to_str().unwrap(),
        "--model",
        idf.to_str().unwrap(),
        "--speeds",
        "3:10:29",
        "--out",
        out.to_str().unwrap(),
        "--ensemble",
        "12",
    ]);
    assert!(ok, "{text}");
    let fj: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("flutter.json")).unwrap()).unwrap();
    let iv = &fj["ensemble"]["flutter_speed"]["interval"];
    assert!(
        iv["lower"].as_f64().unwrap() < iv["upper"].as_f64().unwrap(),
        "{fj:#}"
    );
    assert_eq!(fj["ensemble"]["seed"], "77");
    let (ok, text) = run(&[
        "lco",
        "--structure",
        rig.to_str().unwrap(),
        "--model",
        idf.to_str().unwrap(),
        "--speed",
        "7.2",
        "--out",
        out.to_str().unwrap(),
        "--ensemble",
        "4",
    ]);
    assert!(ok, "{text}");
    let lj: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("lco.json")).unwrap()).unwrap();
    // Every member is accounted for (a member's run may end divergent: with the campaign of
    // Table I one of these four members leaves the bound at 7.2 m/s), and the interval comes
    // from the members in LCO.
    let p = &lj["ensemble"]["points"][0];
    let found = p["amplitude_alpha_deg"]["found"].as_u64().unwrap();
    let others: u64 = ["decay", "divergent", "unsettled"]
        .iter()
        .map(|k| p[*k].as_u64().unwrap_or(0))
        .sum();
    assert_eq!(found + others, 4, "{lj:#}");
    assert!(found >= 2, "{lj:#}");
    let (ok, text) = run(&[
        "flutter",
        "--structure",
        rig.to_str().unwrap(),
        "--model",
        idf.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--ensemble",
        "50",
    ]);
    assert!(!ok);
    assert!(
        text.contains("asked for 50 members; the identification holds 12"),
        "{text}"
    );
}
