//! Measured onsets and "no LCO observed" rows at the bifurcation level (issue 42 item 2):
//! generated rigs whose measured diagram is the continuation of a known truth.

use std::path::PathBuf;

use aeroelastic::branch::{
    predicted_at, Criticality, MeasuredAbsence, MeasuredAmplitude, MeasuredDiagram, MeasuredOnset,
};
use aeroelastic::files::{LoadedModel, StructureFile};
use aeroelastic::section::Section;
use aeroelastic::structure::PolyTerm;
use diagnose::bifurcation::{diagnose_diagram, BifurcationDiagnosis, BifurcationOptions};

fn scenario(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(name)
}

/// The Bristol rig's linear section (structure file's linear part, Theodorsen–Jones).
fn linear_section() -> Section {
    let sf = StructureFile::read(&scenario("bristol-spring1.structure.toml")).unwrap();
    let model = LoadedModel::load(&scenario("bristol-spring1.model.toml"), sf.chord).unwrap();
    let st = aeroelastic::structure::Structure::from_modal(&sf.linear).unwrap();
    Section::new(st, model.model, sf.air_density).unwrap()
}

fn with_pitch_terms(s: &Section, terms: &[(u32, f64)]) -> Section {
    let mut st = s.structure.clone();
    st.nonlinear.pitch_stiffness_terms = terms
        .iter()
        .map(|&(power, coefficient)| PolyTerm { power, coefficient })
        .collect();
    Section::new(st, s.aero.clone(), s.rho).unwrap()
}

/// `s` with its uncoupled pitch frequency times `factor` (damping ratio kept).
fn pitch_frequency_times(s: &Section, factor: f64) -> Section {
    let mut st = s.structure.clone();
    st.k_alpha *= factor * factor;
    st.c_alpha *= factor;
    Section::new(st, s.aero.clone(), s.rho).unwrap()
}

/// The truth's measured diagram at `speeds` (both branches where they exist, relative
/// amplitude noise `noise` from a fixed SplitMix64 sequence of seed 2027) and its first
/// Hopf point (speed, frequency, criticality).
fn measured_from(
    truth: &Section,
    speeds: &[f64],
    noise: f64,
) -> (Vec<MeasuredAmplitude>, (f64, f64, String)) {
    let opts = BifurcationOptions::default().branch;
    let set = truth.lco_branches(8.0, 26.0, &opts, &|_| {}).unwrap();
    let b = &set.branches[0];
    let hopf = (
        b.hopf.u,
        b.hopf.omega / std::f64::consts::TAU,
        b.criticality.clone(),
    );
    let mut out = Vec::new();
    let mut k = 0u64;
    let mut next = || {
        k += 1;
        let x = identify::numerics::split_seed(2027, k);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for &u in speeds {
        for stable in [true, false] {
            let probe = MeasuredAmplitude {
                line: 0,
                stable,
                u,
                amplitude_h: Some(0.0),
                amplitude_alpha: Some(0.0),
                frequency_hz: None,
            };
            let Some((a, h, f)) = predicted_at(&set, &probe) else {
                continue;
            };
            out.push(MeasuredAmplitude {
                amplitude_alpha: Some(a * (1.0 + noise * next())),
                amplitude_h: Some(h * (1.0 + noise * next())),
                frequency_hz: Some(f),
                ..probe
            });
        }
    }
    (out, hopf)
}

fn run(d: &MeasuredDiagram, given: &Section) -> BifurcationDiagnosis {
    diagnose_diagram(
        d,
        given,
        None,
        vec![],
        &BifurcationOptions::default(),
        vec![],
        "t",
    )
    .unwrap()
}

/// The named model's first Hopf point (the nominal's when nothing is named).
fn named_hopf(d: &BifurcationDiagnosis) -> (f64, String) {
    let s = match d.verdict.candidate {
        Some(i) => &d.candidates[i].fit,
        None => &d.nominal,
    };
    let h = s
        .hopf
        .iter()
        .min_by(|a, b| a.u.total_cmp(&b.u))
        .expect("a Hopf point");
    (h.u, h.criticality.clone())
}

fn onset_of(h: &(f64, f64, String), sd: Option<f64>) -> MeasuredOnset {
    MeasuredOnset {
        line: 0,
        u: h.0,
        u_sd: sd,
        frequency_hz: Some(h.1),
        frequency_sd_hz: None,
        criticality: Some(if h.2 == "subcritical" {
            Criticality::Subcritical
        } else {
            Criticality::Supercritical
        }),
    }
}

/// The truth (the Bristol linear section with k₂α² + k₃α³), its diagram at `speeds`, and
/// the structure given to the diagnosis with the truth's pitch frequency times `factor`
/// (the nonlinear spring known): the given structure's Hopf speed is off by several %.
fn misgiven_case(factor: f64, speeds: &[f64]) -> (MeasuredDiagram, (f64, f64, String), Section) {
    let truth = with_pitch_terms(&linear_section(), &[(2, 800.0), (3, 6000.0)]);
    let given = pitch_frequency_times(&truth, factor);
    let (points, h) = measured_from(&truth, speeds, 0.02);
    (
        MeasuredDiagram {
            points,
            ..Default::default()
        },
        h,
        given,
    )
}

/// What an onset row does to a rig whose given pitch frequency is 6 % high (Hopf +19 %) and
/// whose measured cycles lie in the lower half of the subcritical range: it enters every
/// diagram's report and the held-out score as w·ΔU/σ_U; a stiffness candidate keeps the given
/// structure's Hopf point and pays for it; the verdict without the row keeps a Hopf speed more
/// than 1 % off the truth's. (With the row the named model's Hopf is not yet within 1 %:
/// DECISIONS, "Measured onsets … round 27".)
fn onset_row_costs_a_wrong_hopf_speed(factor: f64, speeds: &[f64]) {
    let (mut d, h, given) = misgiven_case(factor, speeds);
    let u_given = given.hopf_points(8.0, 30.0, 400).unwrap()[0].u;
    assert!((u_given / h.0 - 1.0).abs() > 0.03, "{u_given} vs {}", h.0);
    let without = run(&d, &given);
    let (u0, _) = named_hopf(&without);
    assert!(
        (u0 / h.0 - 1.0).abs() > 0.01,
        "without the onset the named model's Hopf {u0} is already within 1 % of {}",
        h.0
    );
    d.onsets.push(onset_of(&h, None));
    let with = run(&d, &given);
    let w = BifurcationOptions::default().amplitude_noise;
    for c in &with.candidates {
        let o = &c.fit.onsets[0];
        let hopf = c.fit.hopf.iter().map(|h| h.u).fold(f64::INFINITY, f64::min);
        assert!(
            (o.predicted_u.unwrap() - hopf).abs() < 1e-9,
            "{}",
            c.label()
        );
        let held = &c.held_out_onsets[0];
        let z = w * held.d_u.unwrap() / (0.01 * h.0);
        assert!((held.z[0] - z).abs() < 1e-9, "{}: {:?}", c.label(), held.z);
        let before = without
            .candidates
            .iter()
            .find(|b| b.label() == c.label())
            .unwrap();
        // a stiffness term cannot move a Hopf point: a polynomial keeps the given structure's
        if c.effect == diagnose::Effect::StructuralPolynomial
            || c.effect == diagnose::Effect::StructuralCubic
        {
            assert!(
                (held.predicted_u.unwrap() - u_given).abs() < 1e-6 * u_given,
                "{}: {:?} vs {u_given}",
                c.label(),
                held.predicted_u
            );
        }
        // a held-out onset worse than the candidate's RMS residual without it raises its score
        if held.z[0].abs() > 1.2 * before.held_out.score {
            assert!(
                c.held_out.score > before.held_out.score,
                "{}: {} → {}",
                c.label(),
                before.held_out.score,
                c.held_out.score
            );
        }
    }
    assert_eq!(with.onsets.len(), 1);
    assert_eq!(with.nominal.onsets[0].criticality_right, Some(true));
    eprintln!(
        "factor {factor}: truth Hopf {:.3}; named without {:?} ({}), with {:?} ({})",
        h.0,
        named_hopf(&without),
        without.verdict.name,
        named_hopf(&with),
        with.verdict.name
    );
}

/// Two full bifurcation-level diagnoses (≈ 100 s on 2 cores): `#[ignore]`d to keep CI within
/// its budget; the onset residuals and their held-out weighting run in CI as unit tests of
/// `diagnose::bifurcation::fit` and `::mod`.
#[test]
#[ignore]
fn an_onset_row_costs_a_model_that_keeps_a_wrong_hopf_speed() {
    onset_row_costs_a_wrong_hopf_speed(1.06, &[15.0, 15.3, 15.6, 15.9]);
}

/// Slow variant: the other sign, six speeds.
#[test]
#[ignore]
fn an_onset_row_costs_a_wrong_hopf_speed_slow() {
    onset_row_costs_a_wrong_hopf_speed(0.94, &[15.0, 15.3, 15.6, 15.9, 16.2, 16.5]);
}

/// Absence rows on a supercritical rig (hardening cubic, cycles above the Hopf point only):
/// absence rows below the Hopf point are consistent with the named model and with the
/// linear nominal one (no false contradiction).
#[test]
fn absence_rows_against_a_supercritical_rig() {
    let nominal = linear_section();
    let truth = with_pitch_terms(&nominal, &[(3, 6000.0)]);
    let (points, h) = measured_from(&truth, &[18.3, 18.7, 19.1, 19.5, 19.9], 0.02);
    assert_eq!(h.2, "supercritical");
    let mut d = MeasuredDiagram {
        points,
        ..Default::default()
    };
    for u in [16.0, 17.6] {
        d.absences.push(MeasuredAbsence {
            line: 0,
            u,
            max_perturbation_alpha: None,
            max_perturbation_h: None,
        });
    }
    let r = run(&d, &nominal);
    let c = &r.candidates[r.verdict.candidate.expect("named")];
    assert_eq!(c.fit.contradicted_absences(), 0, "{:?}", c.fit.absences);
    assert!(r.verdict.contradicting.is_empty());
    // the nominal linear model is stable below its Hopf point: no contradiction either
    assert_eq!(r.nominal.contradicted_absences(), 0);
}
