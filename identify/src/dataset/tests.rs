//! Tests of the data-set reader and writer.

use super::*;
use crate::Error;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The manifest of DATA_FORMAT.md, verbatim.
const DOC_EXAMPLE: &str = r#"format = "aeroform-dataset/1"      # required, exact
name = "quasi-flat plate, configuration A"
description = "free text"            # optional

[section]                            # required
chord = 0.25                         # B [m]
span = 0.75                          # [m], used when forces are totals
air_density = 1.225                  # [kg/m^3]

[structure]                          # required when any case has kind = "free"; per unit span
mass = 1.09                          # [kg/m]
inertia = 0.0057                     # [kg m^2/m] about the elastic axis
static_unbalance = 0.0               # [kg m/m], + when mass centre is aft of elastic axis
freq_heave = 2.0                     # [Hz], still-air natural frequencies
freq_pitch = 3.0                     # [Hz]
damping_heave = 0.005                # ratio of critical
damping_pitch = 0.005

[units]                              # units of the CSV columns; all four required
heave = "mm"                         # "m" | "mm"
pitch = "deg"                        # "rad" | "deg"
lift = "N"                           # "N" (total over span) | "N/m"
moment = "N*m"                       # "N*m" (total over span) | "N*m/m"
# time is always seconds

[convention]                         # optional; every key optional, Scanlan's sense by default
heave = "down"                       # "down" | "up"
pitch = "nose-up"                    # "nose-up" | "nose-down" (also the sense of mean_pitch)
lift = "down"                        # "down" | "up"
moment = "nose-up"                   # "nose-up" | "nose-down"

[[case]]                             # one table per record; at least one
id = "A-U10-A24"                     # unique, [A-Za-z0-9._-]+
kind = "forced"                      # "forced" | "free"
file = "cases/A-U10-A24.csv"
wind_speed = 10.0                    # [m/s]
# optional descriptors of prescribed motion (forced cases)
config = "A"
amplitude = 24.0                     # pitch amplitude, in [units.pitch]
amplitude_ratio = 1.5                # heave amplitude / pitch amplitude, mm per deg as in the paper
freq_pitch = 2.0                     # [Hz]
freq_heave = 0.7                     # [Hz]
mean_pitch = 0.0                     # mean angle of attack, in [units.pitch]
nowind_file = "cases/A-U10-A24.still.csv"   # optional still-air run of the same motion:
                                     # then `lift`/`moment` in `file` are raw balance forces
                                     # and aerodynamic = wind − still air after alignment
"#;

/// A small valid manifest; line numbers below refer to it.
const SMALL: &str = "format = \"aeroform-dataset/1\"
name = \"small\"

[section]
chord = 0.25
span = 0.75
air_density = 1.225

[units]
heave = \"m\"
pitch = \"rad\"
lift = \"N/m\"
moment = \"N*m/m\"

[[case]]
id = \"a\"
kind = \"forced\"
file = \"a.csv\"
wind_speed = 5
";

fn p() -> &'static Path {
    Path::new("ds/manifest.toml")
}

fn manifest_err(text: &str) -> (usize, String, String) {
    match Manifest::parse(text, p()) {
        Err(e @ Error::Manifest { .. }) => {
            let s = e.to_string();
            let Error::Manifest { line, field, .. } = e else {
                unreachable!()
            };
            (line, field, s)
        }
        other => panic!("expected a manifest error, got {other:?}"),
    }
}

#[test]
fn doc_example_parses_with_the_documented_values() {
    let m = Manifest::parse(DOC_EXAMPLE, p()).unwrap();
    assert_eq!(m.name, "quasi-flat plate, configuration A");
    assert!(m.convention.is_scanlan());
    assert_eq!(m.section.span, 0.75);
    assert_eq!(m.structure.unwrap().inertia, 0.0057);
    assert_eq!(
        m.units,
        Units {
            heave: LengthUnit::Mm,
            pitch: AngleUnit::Deg,
            lift: ForceUnit::N,
            moment: MomentUnit::Nm
        }
    );
    let c = &m.cases[0];
    assert_eq!(c.id, "A-U10-A24");
    assert_eq!(c.kind, CaseKind::Forced);
    assert_eq!(c.file, PathBuf::from("cases/A-U10-A24.csv"));
    assert_eq!(c.amplitude, Some(24.0));
    assert_eq!(
        c.nowind_file.as_deref(),
        Some(Path::new("cases/A-U10-A24.still.csv"))
    );
    let meta = m.case_meta(c);
    assert!((meta.amplitude.unwrap() - 24f64.to_radians()).abs() < 1e-15);
    assert_eq!(meta.freq_heave, Some(0.7));
    assert_eq!(meta.amplitude_ratio, Some(1.5));
}

#[test]
fn small_manifest_parses_integer_as_float() {
    let m = Manifest::parse(SMALL, p()).unwrap();
    assert_eq!(m.cases[0].wind_speed, 5.0);
    assert!(m.structure.is_none());
}

#[test]
fn unknown_manifest_key_names_key_and_line() {
    let text = SMALL.replace("span = 0.75", "spam = 0.75");
    let (line, field, msg) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (6, "section.spam"), "{msg}");
    assert!(
        msg.contains("manifest.toml:6") && msg.contains("`spam`"),
        "{msg}"
    );

    let text = format!("{SMALL}windspeed = 3\n");
    let (line, field, msg) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (20, "case[1].windspeed"), "{msg}");

    let text = SMALL.replace("name = \"small\"", "name = \"small\"\nversion = 2");
    let (line, field, _) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (3, "version"));
}

#[test]
fn unknown_keys_inside_extra_tables_are_kept() {
    let text = SMALL.replace(
        "[units]",
        "[extra]\nrig = \"tunnel 2\"\nwhatever = { a = 1 }\n\n[units]",
    ) + "\n[case.extra]\noperator = \"JM\"\ntemperature = 21.5\n";
    let m = Manifest::parse(&text, p()).unwrap();
    assert_eq!(m.extra.as_ref().unwrap()["rig"].as_str(), Some("tunnel 2"));
    assert_eq!(
        m.cases[0].extra.as_ref().unwrap()["temperature"].as_float(),
        Some(21.5)
    );
}

#[test]
fn unknown_unit_names_field_and_allowed_values() {
    let text = SMALL.replace("heave = \"m\"", "heave = \"inch\"");
    let (line, field, msg) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (10, "units.heave"), "{msg}");
    assert!(
        msg.contains("\"inch\"") && msg.contains("\"m\", \"mm\""),
        "{msg}"
    );
    let text = SMALL.replace("moment = \"N*m/m\"", "moment = \"Nm\"");
    let (_, field, msg) = manifest_err(&text);
    assert_eq!(field, "units.moment");
    assert!(msg.contains("\"N*m\", \"N*m/m\""), "{msg}");
}

#[test]
fn duplicate_case_id_names_second_occurrence() {
    let text = format!(
        "{SMALL}\n[[case]]\nid = \"a\"\nkind = \"forced\"\nfile = \"b.csv\"\nwind_speed = 6\n"
    );
    let (line, field, msg) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (22, "case[2].id"), "{msg}");
    assert!(
        msg.contains("duplicate") && msg.contains("line 16"),
        "{msg}"
    );
}

#[test]
fn invalid_case_id_and_kind() {
    let (line, field, _) = manifest_err(&SMALL.replace("id = \"a\"", "id = \"a b\""));
    assert_eq!((line, field.as_str()), (16, "case[1].id"));
    let (line, field, msg) = manifest_err(&SMALL.replace("\"forced\"", "\"forcd\""));
    assert_eq!((line, field.as_str()), (17, "case[1].kind"));
    assert!(msg.contains("\"forced\", \"free\""), "{msg}");
}

#[test]
fn free_case_without_structure_is_an_error() {
    let text = SMALL.replace("\"forced\"", "\"free\"");
    let (line, field, msg) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (17, "structure"), "{msg}");
    assert!(msg.contains("[structure]") && msg.contains("`a`"), "{msg}");
}

#[test]
fn toml_syntax_error_gives_line() {
    let text = SMALL.replace("chord = 0.25", "chord = = 0.25");
    let (line, _, msg) = manifest_err(&text);
    assert_eq!(line, 5, "{msg}");
    assert!(msg.contains("invalid TOML"), "{msg}");
    // Duplicate key is a TOML error too.
    let text = SMALL.replace("span = 0.75", "span = 0.75\nchord = 1");
    let (line, _, msg) = manifest_err(&text);
    assert_eq!(line, 7, "{msg}");
}

#[test]
fn wrong_format_missing_keys_and_bad_numbers() {
    let (line, field, _) = manifest_err(&SMALL.replace("dataset/1", "dataset/2"));
    assert_eq!((line, field.as_str()), (1, "format"));
    let (line, field, msg) = manifest_err(&SMALL.replace("span = 0.75\n", ""));
    assert_eq!((line, field.as_str()), (4, "section.span"), "{msg}");
    assert!(msg.contains("missing"), "{msg}");
    let (line, field, msg) = manifest_err(&SMALL.replace("chord = 0.25", "chord = -0.25"));
    assert_eq!((line, field.as_str()), (5, "section.chord"), "{msg}");
    assert!(msg.contains("> 0"), "{msg}");
    let (line, field, msg) = manifest_err(&SMALL.replace("wind_speed = 5", "wind_speed = nan"));
    assert_eq!((line, field.as_str()), (19, "case[1].wind_speed"), "{msg}");
    let (_, field, msg) = manifest_err(&SMALL.replace("wind_speed = 5", "wind_speed = \"5\""));
    assert_eq!(field, "case[1].wind_speed");
    assert!(msg.contains("expected a number"), "{msg}");
    let (_, field, _) = manifest_err(&SMALL.replace("[units]", "[unit]"));
    assert_eq!(field, "unit");
    let text = SMALL.replace("[units]\nheave = \"m\"\n", "[units]\n");
    let (line, field, _) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (9, "units.heave"));
    let no_case = &SMALL[..SMALL.find("[[case]]").unwrap()];
    let (_, field, _) = manifest_err(no_case);
    assert_eq!(field, "case");
    let (_, field, _) =
        manifest_err(&SMALL.replace("wind_speed = 5", "wind_speed = 5\nfreq_pitch = 0"));
    assert_eq!(field, "case[1].freq_pitch");
}

fn full_manifest() -> Manifest {
    let mut extra = toml::Table::new();
    extra.insert(
        "rig".into(),
        toml::Value::String("tunnel \"2\"\nnew".into()),
    );
    extra.insert("odd key".into(), toml::Value::Integer(3));
    let mut nested = toml::Table::new();
    nested.insert("x".into(), toml::Value::Float(0.1));
    nested.insert(
        "note".into(),
        toml::Value::String("two\nlines 'q' \"d\"".into()),
    );
    nested.insert(
        "list".into(),
        toml::Value::Array(vec![toml::Value::Boolean(true), toml::Value::Float(2.5)]),
    );
    extra.insert("nested".into(), toml::Value::Table(nested));
    let mut case_extra = toml::Table::new();
    case_extra.insert("temperature".into(), toml::Value::Float(21.25));
    Manifest {
        name: "mixed \u{00e9} units".into(),
        description: Some("line one\nline \"two\"".into()),
        section: SectionGeometry {
            chord: 0.25,
            span: 0.75,
            air_density: 1.225,
        },
        structure: Some(ModalStructure {
            mass: 1.09,
            inertia: 0.0057,
            static_unbalance: -0.01,
            freq_heave: 2.0,
            freq_pitch: 3.0,
            damping_heave: 0.005,
            damping_pitch: 0.0,
        }),
        units: Units {
            heave: LengthUnit::Mm,
            pitch: AngleUnit::Deg,
            lift: ForceUnit::N,
            moment: MomentUnit::Nm,
        },
        convention: Convention {
            lift: Linear::Up,
            pitch: Angular::NoseDown,
            ..Convention::default()
        },
        cases: vec![
            CaseSpec {
                config: Some("A".into()),
                amplitude: Some(24.0),
                amplitude_ratio: Some(1.5),
                freq_pitch: Some(2.0),
                freq_heave: Some(0.7),
                mean_pitch: Some(-1.0 / 3.0),
                nowind_file: Some("cases/f1.still.csv".into()),
                extra: Some(case_extra),
                ..CaseSpec::forced("f1", "cases/f1.csv", 10.0)
            },
            CaseSpec {
                kind: CaseKind::Free,
                ..CaseSpec::forced("free.2", "free/free 2.csv", 0.1 + 0.2)
            },
        ],
        extra: Some(extra),
    }
}

#[test]
fn manifest_to_toml_parse_round_trip_with_extra() {
    let m = full_manifest();
    let text = m.to_toml();
    if std::env::var_os("SHOW_TOML").is_some() {
        eprintln!("{text}");
    }
    let back = Manifest::parse(&text, p()).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(back, m, "{text}");
    // Keys appear in the documented order.
    let pos = |k: &str| text.find(k).unwrap();
    assert!(pos("format") < pos("[section]") && pos("[section]") < pos("[structure]"));
    assert!(pos("[units]") < pos("[[case]]"));
}

fn random_record(rng: &mut ChaCha8Rng, id: &str, kind: CaseKind, n: usize, forces: bool) -> Record {
    let mut v = |scale: f64| -> Vec<f64> {
        (0..n)
            .map(|_| scale * (rng.random::<f64>() - 0.5) * 10f64.powi(rng.random_range(-3..3)))
            .collect()
    };
    let h = v(0.01);
    let alpha = v(0.2);
    let lift = forces.then(|| v(5.0));
    let moment = forces.then(|| v(0.3));
    Record {
        kind,
        meta: CaseMeta {
            id: id.into(),
            ..Default::default()
        },
        t0: 0.123,
        dt: 1.0 / 512.0,
        h,
        alpha,
        lift,
        moment,
        nowind: None,
        control: None,
    }
}

fn rel_close(a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tol * x.abs().max(y.abs()),
            "sample {i}: {x} vs {y}"
        );
    }
}

fn assert_records_close(a: &Record, b: &Record) {
    assert_eq!(a.kind, b.kind);
    assert!((a.dt - b.dt).abs() <= 1e-12 * a.dt, "{} {}", a.dt, b.dt);
    assert!((a.t0 - b.t0).abs() <= 1e-12 * a.t0.abs().max(1.0));
    rel_close(&a.h, &b.h, 1e-12);
    rel_close(&a.alpha, &b.alpha, 1e-12);
    assert_eq!(a.lift.is_some(), b.lift.is_some());
    if let (Some(x), Some(y)) = (&a.lift, &b.lift) {
        rel_close(x, y, 1e-12);
    }
    if let (Some(x), Some(y)) = (&a.moment, &b.moment) {
        rel_close(x, y, 1e-12);
    }
    assert_eq!(a.nowind.is_some(), b.nowind.is_some());
    if let (Some(x), Some(y)) = (&a.nowind, &b.nowind) {
        assert_records_close(x, y);
    }
    assert_eq!(a.control.is_some(), b.control.is_some());
    if let (Some(x), Some(y)) = (&a.control, &b.control) {
        assert_eq!(x.calibrated, y.calibrated);
        rel_close(&x.values, &y.values, 1e-12);
        assert_eq!(x.h_target.is_some(), y.h_target.is_some());
        if let (Some(p), Some(q)) = (&x.h_target, &y.h_target) {
            rel_close(p, q, 1e-12);
        }
    }
}

#[test]
fn dataset_round_trip_mixed_units_and_si() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let m = full_manifest();
    let mut forced = random_record(&mut rng, "f1", CaseKind::Forced, 700, true);
    forced.meta = m.case_meta(&m.cases[0]);
    let mut still = random_record(&mut rng, "f1", CaseKind::Forced, 650, true);
    still.meta = forced.meta.clone();
    still.t0 = 0.0;
    forced.nowind = Some(Box::new(still));
    let mut free = random_record(&mut rng, "free.2", CaseKind::Free, 300, false);
    free.meta = m.case_meta(&m.cases[1]);
    // a controlled record: a calibrated control force (converted like lift) and its target
    // (converted like heave) survive the round trip in either units
    free.control = Some(crate::record::ControlSignal {
        calibrated: true,
        values: free.h.iter().map(|h| 2.0 + 300.0 * h).collect(),
        h_target: Some(free.h.iter().map(|h| 0.9 * h).collect()),
    });
    let mut raw = random_record(&mut rng, "free.2", CaseKind::Free, 300, false);
    raw.control = Some(crate::record::ControlSignal {
        calibrated: false,
        values: raw.alpha.clone(),
        h_target: None,
    });
    let raw_csv = super::write::case_csv_text(&m, &raw);
    let raw_back = parse_case_csv(&raw_csv, Path::new("raw.csv"), false).unwrap();
    // a raw signal is written in its own units, untouched by the manifest's
    rel_close(&raw_back.control_raw.unwrap(), &raw.alpha, 1e-12);
    assert!(raw_back.control_force.is_none() && raw_back.h_target.is_none());
    let records = vec![forced, free];

    let dir = tempfile::tempdir().unwrap();
    let mixed = dir.path().join("mixed");
    write_dataset(&mixed, &m, &records).unwrap();
    let back = read_dataset(&mixed).unwrap();
    assert_eq!(back.manifest, m);
    for (a, b) in records.iter().zip(&back.records) {
        assert_eq!(a.meta, b.meta);
        assert_records_close(a, b);
    }
    // The mixed-unit file really holds totals in mm / deg, pitch nose-down and lift up.
    let csv = std::fs::read_to_string(mixed.join("cases/f1.csv")).unwrap();
    let row: Vec<f64> = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert!((row[1] - records[0].h[0] * 1e3).abs() <= 1e-12 * row[1].abs());
    assert!((row[2] + records[0].alpha[0].to_degrees()).abs() <= 1e-12 * row[2].abs());
    let l = records[0].lift.as_ref().unwrap()[0];
    assert!((row[3] + l * 0.75).abs() <= 1e-12 * row[3].abs());

    // Same physical data in SI units reads back the same SI.
    let mut si = m.clone();
    si.units = Units::default();
    // the manifest's angles in the new unit too (24 read as radians is beyond MAX_PITCH_DEG)
    for c in &mut si.cases {
        c.amplitude = c.amplitude.map(f64::to_radians);
        c.mean_pitch = c.mean_pitch.map(f64::to_radians);
    }
    let si_dir = dir.path().join("si");
    write_dataset(&si_dir, &si, &records).unwrap();
    let back_si = read_dataset(&si_dir).unwrap();
    for (a, b) in back.records.iter().zip(&back_si.records) {
        assert_records_close(a, b);
    }
}

#[test]
fn writer_rejects_records_that_do_not_match_the_manifest() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let m = full_manifest();
    let dir = tempfile::tempdir().unwrap();
    let r = random_record(&mut rng, "f1", CaseKind::Forced, 10, true);
    let e = write_dataset(dir.path(), &m, std::slice::from_ref(&r)).unwrap_err();
    assert!(e.to_string().contains("1 records for 2"), "{e}");
    let free = random_record(&mut rng, "free.2", CaseKind::Free, 10, false);
    // f1 names a nowind_file but the record has none.
    let e = write_dataset(dir.path(), &m, &[r.clone(), free.clone()]).unwrap_err();
    assert!(
        matches!(&e, Error::InvalidData { field, .. } if field == "nowind_file"),
        "{e:?}"
    );
    let mut bad = r;
    bad.nowind = Some(Box::new(bad.clone()));
    bad.alpha[3] = f64::NAN;
    let e = write_dataset(dir.path(), &m, &[bad, free]).unwrap_err();
    assert!(
        matches!(&e, Error::InvalidData { field, .. } if field == "alpha"),
        "{e:?}"
    );
    assert!(!dir.path().join("manifest.toml").exists());
}

#[test]
fn absolute_or_parent_paths_are_rejected_with_field_and_line() {
    for bad in [
        "/etc/a.csv",
        "../a.csv",
        "cases/../../a.csv",
        "C:/data/a.csv",
        "\\\\server\\a.csv",
        "cases\\..\\a.csv",
    ] {
        let text = SMALL.replace("file = \"a.csv\"", &format!("file = '{bad}'"));
        let (line, field, msg) = manifest_err(&text);
        assert_eq!((line, field.as_str()), (18, "case[1].file"), "{bad}: {msg}");
        assert!(msg.contains(bad), "{msg}");
    }
    let text = format!("{SMALL}nowind_file = \"../still.csv\"\n");
    let (line, field, msg) = manifest_err(&text);
    assert_eq!((line, field.as_str()), (20, "case[1].nowind_file"), "{msg}");
    assert!(msg.contains("`..`"), "{msg}");
    // Inner `.` components and dotted names are fine.
    for ok in ["./a.csv", "cases/./a..b.csv", "..a.csv"] {
        let text = SMALL.replace("file = \"a.csv\"", &format!("file = \"{ok}\""));
        assert!(Manifest::parse(&text, p()).is_ok(), "{ok}");
    }
    // The writer refuses to write outside the folder.
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let mut m = Manifest::parse(SMALL, p()).unwrap();
    m.cases[0].file = PathBuf::from("../escape.csv");
    let r = random_record(&mut rng, "a", CaseKind::Forced, 10, true);
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("ds");
    let e = write_dataset(&sub, &m, &[r]).unwrap_err();
    assert!(
        matches!(&e, Error::InvalidData { field, .. } if field == "file"),
        "{e:?}"
    );
    assert!(!dir.path().join("escape.csv").exists());
}

fn write_small(dir: &Path, csv: &str) {
    std::fs::write(dir.join("manifest.toml"), SMALL).unwrap();
    std::fs::write(dir.join("a.csv"), csv).unwrap();
}

#[test]
fn read_dataset_errors_name_the_case_file() {
    let dir = tempfile::tempdir().unwrap();
    write_small(dir.path(), "t,h,alpha,lift\n0,0,0,0\n1,0,0,0\n2,0,0,0\n");
    let e = read_dataset(dir.path()).unwrap_err();
    assert!(
        matches!(&e, Error::Csv { field, line: 1, .. } if field == "moment"),
        "{e:?}"
    );
    assert!(e.to_string().contains("a.csv:1"), "{e}");

    write_small(
        dir.path(),
        "t,h,alpha,lift,moment\n0,0,0,0,0\n0.1,0,0,0,0\n0.2,0,0,0,0\n0.35,0,0,0,0\n0.45,0,0,0,0\n",
    );
    let e = read_dataset(dir.path()).unwrap_err();
    assert!(
        matches!(&e, Error::NonUniformSampling { line: 5, .. }),
        "{e:?}"
    );

    write_small(
        dir.path(),
        "t,h,alpha,lift,moment\n0,0,0,0,0\n0.1,0,0,0,0\n0.2,0,0,0,0\n",
    );
    let ds = read_dataset(dir.path()).unwrap();
    assert!((ds.records[0].dt - 0.1).abs() < 1e-15);
    let e = read_dataset(&dir.path().join("nope")).unwrap_err();
    assert!(matches!(e, Error::Io { .. }));
}

#[test]
fn convention_table_is_optional_checked_and_named_in_errors() {
    let m = Manifest::parse(SMALL, p()).unwrap();
    assert!(m.convention.is_scanlan());
    let text = SMALL.replace(
        "[[case]]",
        "[convention]\nlift = \"up\"\npitch = \"nose-down\"\n\n[[case]]",
    );
    let m = Manifest::parse(&text, p()).unwrap();
    assert_eq!(m.convention.lift, Linear::Up);
    assert_eq!(m.convention.pitch, Angular::NoseDown);
    assert_eq!(m.convention.heave, Linear::Down);
    assert_eq!(Manifest::parse(&m.to_toml(), p()).unwrap(), m);
    let (line, field, msg) =
        manifest_err(&SMALL.replace("[[case]]", "[convention]\nlift = \"upward\"\n\n[[case]]"));
    assert_eq!((line, field.as_str()), (16, "convention.lift"), "{msg}");
    assert!(msg.contains("\"down\", \"up\""), "{msg}");
    let (_, field, _) =
        manifest_err(&SMALL.replace("[[case]]", "[convention]\ndrag = \"up\"\n\n[[case]]"));
    assert_eq!(field, "convention.drag");
}

#[test]
fn json_manifest_is_the_toml_one_and_errors_name_json_lines() {
    let m = Manifest::parse(SMALL, p()).unwrap();
    let json = r#"{
  "format": "aeroform-dataset/1",
  "name": "small",
  "section": {"chord": 0.25, "span": 0.75, "air_density": 1.225},
  "units": {"heave": "m", "pitch": "rad", "lift": "N/m", "moment": "N*m/m"},
  "case": [
    {"id": "a", "kind": "forced", "file": "a.csv", "wind_speed": 5}
  ]
}"#;
    let jp = Path::new("ds/manifest.json");
    assert_eq!(Manifest::parse_json(json, jp).unwrap(), m);
    let bad = json.replace("\"wind_speed\": 5", "\"wind_speed\": -5");
    let e = Manifest::parse_json(&bad, jp).unwrap_err();
    let Error::Manifest { line, field, .. } = &e else {
        panic!("{e}")
    };
    assert_eq!((*line, field.as_str()), (7, "case[1].wind_speed"), "{e}");
    assert!(e.to_string().contains("manifest.json"), "{e}");
    let null = json.replace("\"chord\": 0.25", "\"chord\": null");
    let e = Manifest::parse_json(&null, jp).unwrap_err();
    assert!(e.to_string().contains(":4: field `section.chord`"), "{e}");
    let e = Manifest::parse_json("{\"format\": ", jp).unwrap_err();
    assert!(e.to_string().contains("invalid JSON"), "{e}");
    // a repeated key is refused with its line, as TOML does (issue 27, row 13)
    let dup = json.replace("\"chord\": 0.25", "\"chord\": 0.25, \"chord\": 5");
    let e = Manifest::parse_json(&dup, jp).unwrap_err();
    let Error::Manifest { line, .. } = &e else {
        panic!("{e}")
    };
    assert!(
        e.to_string().contains("duplicate key `chord`") && *line == 4,
        "{e}"
    );
}
