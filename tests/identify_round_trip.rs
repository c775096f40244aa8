//! Round trip through the data-set format: a known nonlinear law → synthetic forced-motion
//! records with rig-like noise → written in mm/deg/N/N·m totals → read back → preprocessed →
//! identified. The selected support must be the law's, and the coefficients close to it.

use identify::dataset::{
    read_dataset, write_dataset, AngleUnit, CaseSpec, ForceUnit, LengthUnit, Manifest, MomentUnit,
    Units,
};
use identify::pipeline::{identify, IdentifySettings};
use identify::preprocess::PreprocessOptions;
use identify::record::{CaseMeta, Section};
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
    let section = Section {
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
