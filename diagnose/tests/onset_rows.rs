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
/// the structure given to the diagnosis with the truth's uncoupled frequency of `dof` (`pitch` or `heave`) times `factor`
/// (the nonlinear spring known): the given structure's Hopf speed is off by several %.
fn misgiven_dof_case(
    dof: &str,
    factor: f64,
    speeds: &[f64],
) -> (MeasuredDiagram, (f64, f64, String), Section) {
    let truth = with_pitch_terms(&linear_section(), &[(2, 800.0), (3, 6000.0)]);
    let given = if dof == "pitch" {
        pitch_frequency_times(&truth, factor)
    } else {
        let mut st = truth.structure.clone();
        st.k_h *= factor * factor;
        st.c_h *= factor;
        Section::new(st, truth.aero.clone(), truth.rho).unwrap()
    };
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

/// Issue 42's acceptance on a generated rig whose given pitch frequency is off by `factor`
/// (given Hopf +19 % at 1.06, −17 % at 0.94) and whose measured cycles lie in the lower
/// part of the subcritical range: without the onset the named model keeps a Hopf speed more
/// than 1 % off the truth's; with the truth's onset (speed, frequency, criticality) the
/// onset corrects the structure first (`structure.used` = identified, `structure.gap` from
/// the given to the truth's Hopf speed) and the named model's Hopf point lies within 1 %
/// of the truth's with its criticality. Every onset residual is w·ΔU/σ_U of the diagram's
/// first Hopf point.
fn the_named_models_hopf_meets_the_onset(factor: f64, speeds: &[f64]) {
    named_hopf_meets_the_onset("pitch", factor, speeds, true);
}

/// [`the_named_models_hopf_meets_the_onset`] with `dof`'s frequency off; `baseline`: also
/// diagnose without the onset and require its named Hopf point more than 1 % off.
fn named_hopf_meets_the_onset(dof: &str, factor: f64, speeds: &[f64], baseline: bool) {
    let (mut d, h, given) = misgiven_dof_case(dof, factor, speeds);
    let u_given = given.hopf_points(8.0, 30.0, 400).unwrap()[0].u;
    assert!((u_given / h.0 - 1.0).abs() > 0.03, "{u_given} vs {}", h.0);
    let without = baseline.then(|| run(&d, &given));
    if let Some(without) = &without {
        let (u0, _) = named_hopf(without);
        assert!(
            (u0 / h.0 - 1.0).abs() > 0.01,
            "without the onset the named model's Hopf {u0} is already within 1 % of {}",
            h.0
        );
    }
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
    }
    let st = with
        .structure
        .as_ref()
        .expect("the onset's structure check");
    assert_eq!(
        st.used,
        diagnose::structure::StructureUsed::Identified,
        "{}",
        st.reason
    );
    let gap = st.gap.as_ref().expect("what the correction alone did");
    assert!(
        (gap.hopf_given.unwrap() / u_given - 1.0).abs() < 1e-3,
        "{gap:?}"
    );
    assert!(
        (gap.hopf_identified.unwrap() / h.0 - 1.0).abs() < 1e-3,
        "{gap:?}"
    );
    let (u1, crit) = named_hopf(&with);
    eprintln!(
        "{dof} factor {factor}: truth Hopf {:.3} ({}); given {u_given:.3}; named without {:?}, \
         with ({u1:.3}, {crit}) ({:?}: {}); gap {gap:?}",
        h.0,
        h.2,
        without.as_ref().map(|w| (named_hopf(w), w.verdict.name)),
        with.verdict.name,
        with.verdict.explanation
    );
    assert!(
        (u1 / h.0 - 1.0).abs() < 0.01,
        "named model's Hopf {u1} vs the truth's {}",
        h.0
    );
    assert_eq!(crit, h.2, "criticality");
    assert_eq!(with.nominal.onsets[0].criticality_right, Some(true));
}

/// Acceptance, given pitch frequency 6 % high (two full diagnoses, several minutes on the
/// shared 2 cores): `#[ignore]`d; the structure correction itself runs in CI
/// (`a_measured_onset_corrects_the_structure_and_one_within_its_uncertainty_does_not`).
#[test]
#[ignore]
fn the_named_models_hopf_meets_an_onset_with_the_pitch_frequency_given_high() {
    the_named_models_hopf_meets_the_onset(1.06, &[15.0, 15.3, 15.6, 15.9]);
}

/// Acceptance, given pitch frequency 6 % low, six speeds.
#[test]
#[ignore]
fn the_named_models_hopf_meets_an_onset_with_the_pitch_frequency_given_low() {
    the_named_models_hopf_meets_the_onset(0.94, &[15.0, 15.3, 15.6, 15.9, 16.2, 16.5]);
}

/// Acceptance over further mis-given structures (pitch frequency ±3 %, heave frequency
/// ±5 %), with the onset only (about 2 min each on the shared 2 cores).
#[test]
#[ignore]
fn the_named_models_hopf_meets_an_onset_over_further_misgivings() {
    let speeds = [15.0, 15.3, 15.6, 15.9];
    for (dof, factor) in [
        ("pitch", 1.03),
        ("pitch", 0.97),
        ("heave", 1.05),
        ("heave", 0.95),
    ] {
        named_hopf_meets_the_onset(dof, factor, &speeds, false);
    }
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

/// The truth's first Hopf point (speed, frequency) from the nominal scan.
fn truth_hopf(s: &Section) -> (f64, f64) {
    let h = s
        .hopf_points(8.0, 30.0, 400)
        .unwrap()
        .into_iter()
        .min_by(|a, b| a.u.total_cmp(&b.u))
        .unwrap();
    (h.u, h.omega / std::f64::consts::TAU)
}

/// Structure first with a measured onset (issue 42, round 28; fast, no candidate fitted):
/// on the generated rig with the given pitch frequency ±6 % (given Hopf +19 % / −17 %), an
/// onset of the truth corrects the linear structure so that the nominal Hopf point meets it
/// — speed and frequency: k_h and k_α; speed alone: the stiffness the Hopf speed is most
/// sensitive to (here k_α) — and an onset within its uncertainty changes nothing.
#[test]
fn a_measured_onset_corrects_the_structure_and_one_within_its_uncertainty_does_not() {
    use diagnose::structure::{with_onsets, StructureUsed};
    let truth = with_pitch_terms(&linear_section(), &[(2, 800.0), (3, 6000.0)]);
    let (u_t, f_t) = truth_hopf(&truth);
    for factor in [1.06, 0.94] {
        let given = pitch_frequency_times(&truth, factor);
        let (u_g, _) = truth_hopf(&given);
        assert!((u_g / u_t - 1.0).abs() > 0.1, "{u_g} vs {u_t}");
        for with_freq in [true, false] {
            let onset = MeasuredOnset {
                line: 0,
                u: u_t,
                u_sd: None,
                frequency_hz: with_freq.then_some(f_t),
                frequency_sd_hz: None,
                criticality: Some(Criticality::Subcritical),
            };
            let c = with_onsets(None, &given, &[onset], 0.01).expect("a check");
            assert_eq!(c.used, StructureUsed::Identified, "{}", c.reason);
            let id = c.identified.as_ref().unwrap();
            assert!(id.onsets_used && id.converged, "{id:?}");
            let s = id.hopf_sensitivity.unwrap();
            // the Hopf speed of this rig is most sensitive to the pitch spring
            assert!(s[1].abs() > s[0].abs(), "{s:?}");
            let held: Vec<bool> = id.parameters.iter().map(|p| p.held).collect();
            assert_eq!(
                held,
                vec![!with_freq, false, true, true],
                "{:?}",
                id.parameters
            );
            let used = Section::new(
                c.used_structure(&given.structure),
                given.aero.clone(),
                given.rho,
            )
            .unwrap();
            let (u, f) = truth_hopf(&used);
            assert!(
                (u / u_t - 1.0).abs() < 1e-3,
                "{factor} {with_freq}: {u} vs {u_t}"
            );
            if with_freq {
                assert!((f / f_t - 1.0).abs() < 1e-3, "{f} vs {f_t}");
            }
            let o = &c.onsets[0];
            assert!((o.given_u.unwrap() - u_g).abs() < 1e-6 * u_g);
            assert!((o.used_u.unwrap() - u).abs() < 1e-6 * u);
            // the identified pitch stiffness is the truth's within 2 % (the given c_α,
            // also off by the factor, is held)
            let ka = id.parameters[1].identified;
            eprintln!(
                "factor {factor} freq {with_freq}: k_h {:.3} → {:.3} (truth {:.3}), k_α {:.4} → \
                 {ka:.4} (truth {:.4}); Hopf {u_g:.3} → {u:.3} (truth {u_t:.3}); sens {s:?}",
                id.parameters[0].given,
                id.parameters[0].identified,
                truth.structure.k_h,
                id.parameters[1].given,
                truth.structure.k_alpha
            );
            assert!(
                (ka / truth.structure.k_alpha - 1.0).abs() < 0.02,
                "{ka} vs {}",
                truth.structure.k_alpha
            );
            // a candidate that moves the Hopf point (10 % more heaving mass) is conformed
            // to the onset as to a decay: its springs re-identified, its Hopf point the
            // onset's again
            let mut heavier = used.structure.clone();
            heavier.mass *= 1.1;
            let heavier = Section::new(heavier, used.aero.clone(), used.rho).unwrap();
            let (u_heavy, _) = truth_hopf(&heavier);
            assert!((u_heavy / u_t - 1.0).abs() > 0.01, "{u_heavy} vs {u_t}");
            let conformed = diagnose::structure::conform_to_decays(&c, &used, heavier).unwrap();
            let (u_c, _) = truth_hopf(&conformed);
            assert!((u_c / u_t - 1.0).abs() < 1e-3, "conformed {u_c} vs {u_t}");
            assert_eq!(conformed.structure.mass, used.structure.mass * 1.1);
        }
    }
    // an onset within its uncertainty (0.5 % and 0.5 % off, σ = 1 %) changes nothing
    let onset = MeasuredOnset {
        line: 0,
        u: u_t * 1.005,
        u_sd: None,
        frequency_hz: Some(f_t * 0.995),
        frequency_sd_hz: None,
        criticality: None,
    };
    let c = with_onsets(None, &truth, &[onset], 0.01).unwrap();
    assert_eq!(c.used, StructureUsed::Given, "{}", c.reason);
    assert_eq!(c.used_structure(&truth.structure), truth.structure);
}
