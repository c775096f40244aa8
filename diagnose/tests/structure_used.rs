//! Structure first, used (issue 42, item 1): still-air decays of a rig whose given
//! structure is off by a few per cent in one frequency identify the linear structure
//! (stiffness and damping per DOF, masses held, with intervals), which then carries the
//! Hopf speed; a correct structure is kept; a noise-only record is no mode.
//!
//! The fast test reads the check through its JSON form only (`used`, `identified.modal`),
//! so that it compiles on the code before the structure was used and fails there by its
//! assertions. The slow one (`#[ignore]`) is the generated benchmark's acceptance:
//! `cargo test --release -p diagnose --test structure_used -- --ignored`.

use std::sync::Arc;

use aeroelastic::aero::{AeroModel, TheodorsenAero};
use aeroelastic::section::Section;
use aeroelastic::structure::{NondimStructure, PolyTerm, Structure};
use aeroelastic::tunnel::{free_dataset, FreeOptions};
use diagnose::bifurcation::structure_check;
use identify::dataset::{Dataset, ModalStructure};

/// A rig as the bifurcation benchmark draws them, with a hardening cubic pitch spring (a
/// fifth of the reference amplitude 0.05 rad stiffens the spring by 3 %).
fn truth() -> Section {
    let p = NondimStructure {
        mu: 50.0,
        r_alpha2: 0.3,
        sigma: 0.6,
        x_alpha: 0.2,
        semi_chord: 0.15,
        omega_alpha: std::f64::consts::TAU * 3.0,
        rho: 1.2,
        zeta_h: 0.01,
        zeta_alpha: 0.015,
    };
    let mut st = Structure::from_nondimensional(&p).unwrap();
    st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
        power: 3,
        coefficient: st.k_alpha / (0.05 * 0.05),
    });
    let aero: Arc<dyn AeroModel> = Arc::new(TheodorsenAero::new(0.3, -0.4).unwrap());
    Section::new(st, aero, 1.2).unwrap()
}

/// `s` with the uncoupled frequency of `dof` times `factor` (damping ratio kept).
fn misgiven(s: &Section, dof: &str, factor: f64) -> Section {
    let mut st = s.structure.clone();
    if dof == "pitch" {
        st.k_alpha *= factor * factor;
        st.c_alpha *= factor;
    } else {
        st.k_h *= factor * factor;
        st.c_h *= factor;
    }
    Section::new(st, s.aero.clone(), s.rho).unwrap()
}

/// Still-air decays of `s` released in pitch (0.01 rad) and in heave (1.5 mm), 20 s at
/// 200 Hz with the paper's sensor noise.
fn decays(s: &Section) -> Vec<Dataset> {
    [[0.0, 0.01, 0.0, 0.0], [0.0015, 0.0, 0.0, 0.0]]
        .iter()
        .enumerate()
        .map(|(i, init)| {
            let mut o = FreeOptions::new(42 + i as u64);
            o.rate = 200.0;
            o.duration = 20.0;
            o.record_forces = false;
            o.initial = *init;
            let (manifest, records, _) = free_dataset(s, &[0.0], &o, &|_| {}).unwrap();
            Dataset {
                root: std::path::PathBuf::new(),
                manifest,
                records,
            }
        })
        .collect()
}

fn first_hopf(s: &Section) -> f64 {
    s.hopf_points(0.5, 200.0, 400).unwrap()[0].u
}

#[test]
fn a_misgiven_frequency_is_identified_from_the_decays_and_carries_the_hopf_speed() {
    let t = truth();
    let sets = decays(&t);
    let refs: Vec<&Dataset> = sets.iter().collect();
    let u_truth = first_hopf(&t);
    for (dof, factor) in [("pitch", 1.05), ("heave", 0.95), ("pitch", 0.97)] {
        let given = misgiven(&t, dof, factor);
        let u_given = first_hopf(&given);
        let check = structure_check(&refs, &given).expect("still-air decays");
        let v = serde_json::to_value(&check).unwrap();
        assert_eq!(
            v["used"], "identified",
            "{dof} × {factor}: {}",
            check.summary
        );
        let modal: ModalStructure =
            serde_json::from_value(v["identified"]["modal"].clone()).expect("identified.modal");
        let mut st = Structure::from_modal(&modal).unwrap();
        st.nonlinear = given.structure.nonlinear.clone();
        let id = Section::new(st, t.aero.clone(), t.rho).unwrap();
        let u_id = first_hopf(&id);
        eprintln!(
            "{dof} × {factor}: Hopf truth {u_truth:.3}, given {u_given:.3}, identified \
             {u_id:.3} m/s"
        );
        // the setting matters: the given structure's Hopf speed is off by more than 1 %
        assert!(
            (u_given / u_truth - 1.0).abs() > 0.01,
            "{u_given} {u_truth}"
        );
        // acceptance: within 1 % of the truth's after the correction
        assert!((u_id / u_truth - 1.0).abs() < 0.01, "{u_id} vs {u_truth}");
        // the intervals hold the truth's stiffnesses
        for p in v["identified"]["parameters"].as_array().unwrap() {
            let name = p["name"].as_str().unwrap();
            let truth = match name {
                "k_h" => t.structure.k_h,
                "k_alpha" => t.structure.k_alpha,
                _ => continue,
            };
            let lo = p["interval"][0].as_f64().unwrap();
            let hi = p["interval"][1].as_f64().unwrap();
            if !p["held"].as_bool().unwrap() {
                assert!(
                    lo <= truth && truth <= hi,
                    "{name}: truth {truth} outside [{lo}, {hi}]"
                );
                assert!(hi / lo < 1.02, "{name}: interval [{lo}, {hi}] too wide");
            }
        }
    }
}

#[test]
fn a_correct_structure_is_kept_and_a_noise_only_record_is_no_mode() {
    let t = truth();
    let mut sets = decays(&t);
    let refs: Vec<&Dataset> = sets.iter().collect();
    let check = structure_check(&refs, &t).expect("still-air decays");
    let v = serde_json::to_value(&check).unwrap();
    assert_eq!(v["used"], "given", "{}", check.summary);
    // The heave record of a pitch release replaced by sensor noise alone (8 µm, 200 Hz):
    // no row of it, nothing at the Nyquist frequency.
    let rec = &mut sets[0].records[0];
    let mut k = 0u64;
    for v in rec.h.iter_mut() {
        k += 1;
        let u = identify::numerics::split_seed(7, k);
        *v = 8e-6 * ((u >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * 3f64.sqrt();
    }
    let dt = rec.dt;
    let refs: Vec<&Dataset> = sets.iter().collect();
    let check = structure_check(&refs[..1], &t).expect("still-air decay");
    for m in &check.modes {
        assert!(
            m.measured_hz < 0.4 / dt,
            "{} {}: a mode at {} Hz (Nyquist {})",
            m.case,
            m.dof,
            m.measured_hz,
            0.5 / dt
        );
    }
    assert_eq!(check.modes.len(), 1, "{}", check.summary);
    assert_eq!(check.modes[0].dof, "pitch");
}

/// The generated benchmark's acceptance (issue 42): rigs whose given structure is off by
/// 3–8 % in one frequency, with two still-air decays of the truth. After the correction the
/// named model's Hopf speed lies within 1 % of the truth's with its criticality in ≥ 90 % of
/// the sets, and no effect-free set is named an effect. About 20 s a set on 2 cores.
#[test]
#[ignore = "slow: 20 generated rigs at the bifurcation level (about 7 min)"]
fn misgiven_structures_of_the_generated_benchmark_are_corrected() {
    use diagnose::bifurcation::bench::{run_bench_with, BranchBenchOptions};
    let opts = BranchBenchOptions {
        misgiven_structure: true,
        hold_given: false,
    };
    let r = run_bench_with(20, 2026, &opts, &|o| {
        eprintln!(
            "set {} {:?} → {} ({:?}): truth Hopf {:?}, named {:?}",
            o.index, o.truth, o.verdict, o.structure_used, o.truth_hopf, o.named_hopf
        )
    })
    .unwrap();
    eprintln!(
        "Hopf within 1 %: {:.3}, criticality right: {:.3}, both: {:.3}, effect-free named: {}",
        r.hopf_within_tolerance,
        r.criticality_right,
        r.hopf_and_criticality_right,
        r.effect_free_named
    );
    assert!(
        r.hopf_and_criticality_right >= 0.9,
        "{}",
        r.hopf_and_criticality_right
    );
    assert_eq!(r.effect_free_named, 0);
}
