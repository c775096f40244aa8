//! Property test: the data-set reader gives back what the writer wrote — random manifests
//! (optional fields, `[extra]` tables with awkward keys and strings, any units, free and
//! forced cases, still-air runs, random ids) and random finite column values from tiny to
//! huge magnitudes.
//!
//! Column values span every magnitude the reader accepts: from subnormals up to 100 in SI
//! (the reader refuses physically implausible values: |h| above 1 km, |α| above 1000 rad,
//! forces above 1e12 N/m; `identify::dataset::MAX_ABS_SI`).
//! With SI per-span units (m, rad, N/m, N·m/m) no conversion happens and every value comes
//! back bit-identical, subnormals included. With mm/deg/totals each value
//! goes through one multiplication and one division, so it comes back within a few ulps
//! (checked at 1e-14 relative); the time base is refitted by least squares (1e-9).

use identify::dataset::{
    read_dataset, write_dataset, AngleUnit, CaseSpec, ForceUnit, LengthUnit, Manifest,
    ModalStructure, MomentUnit, Units,
};
use identify::record::{CaseKind, Record, SectionGeometry};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

/// A positive magnitude m·10^e.
fn magnitude(lo: i32, hi: i32) -> impl Strategy<Value = f64> {
    (1.0f64..10.0, lo..hi).prop_map(|(m, e)| m * 10f64.powi(e))
}

/// Largest column value drawn [SI], inside every plausibility bound of the reader.
const COLUMN_MAX: f64 = 100.0;

/// Any finite column value up to [`COLUMN_MAX`]: zeros, subnormals, normals of any
/// smaller exponent, the extremes.
fn any_finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => (prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO)
            .prop_filter("plausible", |x| x.abs() <= COLUMN_MAX),
        1 => Just(COLUMN_MAX),
        1 => Just(-COLUMN_MAX),
        1 => Just(f64::MIN_POSITIVE),
        1 => Just(-0.0),
    ]
}

/// A column value with |x| in [1e-250, 100] or zero (safe under ×1000, ×180/π, ×span).
fn scaled_column() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => (magnitude(-250, 2), any::<bool>()).prop_map(|(m, neg)| if neg { -m } else { m }),
        1 => Just(0.0),
    ]
}

/// A finite value with |x| in [1e-250, 1e250] or zero (safe under ×1000, ×180/π, ×span).
fn scaled_finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => (magnitude(-250, 250), any::<bool>()).prop_map(|(m, neg)| if neg { -m } else { m }),
        1 => Just(0.0),
    ]
}

fn toml_value(depth: u32) -> BoxedStrategy<toml::Value> {
    let leaf = prop_oneof![
        "\\PC{0,12}".prop_map(toml::Value::String),
        "[a-z\"\\\\\n\t' ]{0,8}".prop_map(toml::Value::String),
        any::<i64>().prop_map(toml::Value::Integer),
        scaled_finite().prop_map(toml::Value::Float),
        any::<bool>().prop_map(toml::Value::Boolean),
    ];
    if depth == 0 {
        return leaf.boxed();
    }
    prop_oneof![
        4 => leaf,
        1 => prop::collection::vec(toml_value(depth - 1), 0..3).prop_map(toml::Value::Array),
        1 => toml_table(depth - 1).prop_map(toml::Value::Table),
    ]
    .boxed()
}

fn toml_table(depth: u32) -> BoxedStrategy<toml::Table> {
    prop::collection::btree_map(
        prop_oneof!["[a-z_]{1,6}", "[a-zA-Z0-9 .\"\\\\é-]{0,6}"],
        toml_value(depth),
        0..4,
    )
    .prop_map(|m| m.into_iter().collect())
    .boxed()
}

fn units_strategy() -> impl Strategy<Value = Units> {
    (any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>()).prop_map(|(a, b, c, d)| Units {
        heave: if a { LengthUnit::Mm } else { LengthUnit::M },
        pitch: if b { AngleUnit::Deg } else { AngleUnit::Rad },
        lift: if c { ForceUnit::N } else { ForceUnit::NPerM },
        moment: if d {
            MomentUnit::Nm
        } else {
            MomentUnit::NmPerM
        },
    })
}

/// Shape of one case before values are drawn.
#[derive(Debug, Clone)]
struct CaseShape {
    free: bool,
    forces: bool,
    still: bool,
    n: usize,
    still_n: usize,
    t0: f64,
    dt: f64,
}

fn case_shape() -> impl Strategy<Value = CaseShape> {
    (
        any::<bool>(),
        any::<bool>(),
        prop::bool::weighted(0.3),
        3usize..30,
        3usize..30,
        -10.0f64..10.0,
        magnitude(-4, 0),
    )
        .prop_map(|(free, forces, still, n, still_n, t0, dt)| CaseShape {
            free,
            forces: forces || !free,
            still,
            n,
            still_n,
            t0,
            dt,
        })
}

fn case_spec(id: String, shape: &CaseShape) -> impl Strategy<Value = CaseSpec> {
    let kind = if shape.free {
        CaseKind::Free
    } else {
        CaseKind::Forced
    };
    let still = shape.still;
    // Forcing frequencies below the record's Nyquist frequency 1/(2 dt) (the reader refuses
    // others): up to 0.49/dt, down to 1e-6 of that.
    let dt = shape.dt;
    let below_nyquist = move || magnitude(-6, 0).prop_map(move |m| m * 0.049 / dt);
    (
        prop_oneof![Just(0.0), magnitude(-3, 3)],
        prop::option::of("[A-G]|\\PC{1,6}"),
        // angles within MAX_PITCH_DEG in either pitch unit (≤ 1 rad or 1°; |mean| < 1.5)
        prop::option::of(prop_oneof![Just(0.0), magnitude(-3, 0)]),
        prop::option::of(prop_oneof![Just(0.0), magnitude(-3, 3)]),
        prop::option::of(below_nyquist()),
        prop::option::of(below_nyquist()),
        prop::option::of(-1.5f64..1.5),
        prop::option::of(toml_table(2)),
    )
        .prop_map(
            move |(wind, config, amplitude, ratio, fp, fh, mean, extra)| CaseSpec {
                id: id.clone(),
                kind,
                file: format!("cases/{id}.csv").into(),
                wind_speed: wind,
                config,
                amplitude,
                amplitude_ratio: ratio,
                freq_pitch: fp,
                freq_heave: fh,
                mean_pitch: mean,
                nowind_file: still.then(|| format!("still/{id}.csv").into()),
                extra,
            },
        )
}

fn record(
    shape: &CaseShape,
    n: usize,
    forces: bool,
    values: BoxedStrategy<f64>,
) -> impl Strategy<Value = Record> {
    let (t0, dt, free) = (shape.t0, shape.dt, shape.free);
    let col = move || prop::collection::vec(values.clone(), n);
    let forces = if forces {
        (col(), col()).prop_map(Some).boxed()
    } else {
        Just(None).boxed()
    };
    (col(), col(), forces).prop_map(move |(h, alpha, f)| Record {
        kind: if free {
            CaseKind::Free
        } else {
            CaseKind::Forced
        },
        meta: Default::default(),
        t0,
        dt,
        h,
        alpha,
        lift: f.as_ref().map(|f| f.0.clone()),
        moment: f.map(|f| f.1),
        nowind: None,
        control: None,
    })
}

/// A manifest and its records (values in SI per span).
fn dataset() -> impl Strategy<Value = (Manifest, Vec<Record>)> {
    (
        prop::collection::btree_set("[A-Za-z0-9._-]{1,10}", 1..4),
        units_strategy(),
        "\\PC{0,20}",
        prop::option::of("\\PC{0,30}"),
        (magnitude(-3, 2), magnitude(-3, 2), magnitude(-3, 1)),
        prop::option::of(toml_table(2)),
        any::<bool>(),
    )
        .prop_flat_map(
            |(ids, units, name, description, (chord, span, rho), extra, exact)| {
                let ids: Vec<String> = ids.into_iter().collect();
                let shapes = prop::collection::vec(case_shape(), ids.len());
                (
                    Just(ids),
                    Just(units),
                    Just(name),
                    Just(description),
                    Just((chord, span, rho)),
                    Just(extra),
                    Just(exact),
                    shapes,
                )
            },
        )
        .prop_flat_map(
            |(ids, units, name, description, (chord, span, rho), extra, exact, shapes)| {
                let si = Units::default();
                let units = if exact { si } else { units };
                let values = move || {
                    if exact {
                        any_finite().boxed()
                    } else {
                        scaled_column().boxed()
                    }
                };
                let specs: Vec<_> = ids
                    .iter()
                    .zip(&shapes)
                    .map(|(id, s)| case_spec(id.clone(), s))
                    .collect();
                let recs: Vec<_> = ids
                    .iter()
                    .zip(&shapes)
                    .map(|(id, s)| {
                        let id = id.clone();
                        let still = s.still;
                        let still_shape = CaseShape {
                            n: s.still_n,
                            ..s.clone()
                        };
                        (
                            record(s, s.n, s.forces, values()),
                            record(&still_shape, s.still_n, true, values()),
                        )
                            .prop_map(move |(mut r, st)| {
                                r.meta.id = id.clone();
                                if still {
                                    r.nowind = Some(Box::new(st));
                                }
                                r
                            })
                    })
                    .collect();
                let any_free = shapes.iter().any(|s| s.free);
                let structure = (
                    magnitude(-3, 3),
                    magnitude(-3, 3),
                    -10.0f64..10.0,
                    magnitude(-2, 2),
                    magnitude(-2, 2),
                    0.0f64..1.0,
                    0.0f64..1.0,
                )
                    .prop_map(|(mass, inertia, su, fh, fp, zh, zp)| {
                        ModalStructure {
                            mass,
                            inertia,
                            static_unbalance: su,
                            freq_heave: fh,
                            freq_pitch: fp,
                            damping_heave: zh,
                            damping_pitch: zp,
                        }
                    });
                let structure = if any_free {
                    structure.prop_map(Some).boxed()
                } else {
                    prop::option::of(structure).boxed()
                };
                (specs, recs, structure).prop_map(move |(cases, records, structure)| {
                    (
                        Manifest {
                            name: name.clone(),
                            description: description.clone(),
                            section: SectionGeometry {
                                chord,
                                span,
                                air_density: rho,
                            },
                            structure,
                            units,
                            convention: Default::default(),
                            cases,
                            extra: extra.clone(),
                        },
                        records,
                    )
                })
            },
        )
}

fn same(a: f64, b: f64, exact: bool) -> bool {
    if exact {
        a.to_bits() == b.to_bits() || (a == 0.0 && b == 0.0)
    } else {
        (a - b).abs() <= 1e-14 * a.abs().max(b.abs())
    }
}

fn check_column(what: &str, a: &[f64], b: &[f64], exact: bool) -> Result<(), TestCaseError> {
    prop_assert_eq!(a.len(), b.len(), "{}: length", what);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        prop_assert!(
            same(*x, *y, exact),
            "{}[{}]: wrote {:e}, read {:e}",
            what,
            i,
            x,
            y
        );
    }
    Ok(())
}

fn check_record(id: &str, a: &Record, b: &Record, exact: bool) -> Result<(), TestCaseError> {
    prop_assert_eq!(a.kind, b.kind);
    let n = a.len() as f64;
    prop_assert!(
        (a.dt - b.dt).abs() <= 1e-9 * a.dt,
        "{}: dt {} vs {}",
        id,
        a.dt,
        b.dt
    );
    prop_assert!(
        (a.t0 - b.t0).abs() <= 1e-9 * a.t0.abs().max(n * a.dt),
        "{}: t0 {} vs {}",
        id,
        a.t0,
        b.t0
    );
    check_column(&format!("{id}.h"), &a.h, &b.h, exact)?;
    check_column(&format!("{id}.alpha"), &a.alpha, &b.alpha, exact)?;
    prop_assert_eq!(a.lift.is_some(), b.lift.is_some());
    prop_assert_eq!(a.moment.is_some(), b.moment.is_some());
    if let (Some(x), Some(y)) = (&a.lift, &b.lift) {
        check_column(&format!("{id}.lift"), x, y, exact)?;
    }
    if let (Some(x), Some(y)) = (&a.moment, &b.moment) {
        check_column(&format!("{id}.moment"), x, y, exact)?;
    }
    prop_assert_eq!(a.nowind.is_some(), b.nowind.is_some());
    if let (Some(x), Some(y)) = (&a.nowind, &b.nowind) {
        check_record(&format!("{id} (still air)"), x, y, exact)?;
    }
    Ok(())
}

fn round_trip(manifest: &Manifest, records: &[Record]) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("ds");
    write_dataset(&root, manifest, records)
        .map_err(|e| TestCaseError::fail(format!("write: {e}")))?;
    let ds = read_dataset(&root).map_err(|e| {
        let text = std::fs::read_to_string(root.join("manifest.toml")).unwrap_or_default();
        TestCaseError::fail(format!("read: {e}\n--- manifest ---\n{text}"))
    })?;
    prop_assert_eq!(&ds.manifest, manifest);
    let exact = manifest.units == Units::default();
    prop_assert_eq!(ds.records.len(), records.len());
    for ((c, a), b) in manifest.cases.iter().zip(records).zip(&ds.records) {
        let mut want = a.clone();
        want.meta = manifest.case_meta(c);
        prop_assert_eq!(&b.meta, &want.meta);
        check_record(&c.id, &want, b, exact)?;
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: RngSeed::Fixed(20261123), ..ProptestConfig::default() })]

    #[test]
    fn reader_round_trips_what_the_writer_wrote((manifest, records) in dataset()) {
        round_trip(&manifest, &records)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, rng_seed: RngSeed::Fixed(20261123), ..ProptestConfig::default() })]

    #[test]
    #[ignore]
    fn reader_round_trips_what_the_writer_wrote_many((manifest, records) in dataset()) {
        round_trip(&manifest, &records)?;
    }
}
