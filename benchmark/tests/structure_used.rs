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
use aeroelastic::structure::{Friction, NondimStructure, PolyTerm, Structure};
use aeroelastic::tunnel::{free_dataset, FreeOptions};
use diagnose::bifurcation::structure_check;
use diagnose::structure::conform_to_decays;
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
    // every row is read from the pitch record (since round 27 the heave mode, which no
    // record then dominates, is read there as the record's second mode); the noise-only
    // heave record gives none and is listed as refused
    assert!(!check.modes.is_empty(), "{}", check.summary);
    assert!(
        check.modes.iter().all(|m| m.dof == "pitch"),
        "{}",
        check.summary
    );
    assert!(
        check.refused.iter().any(|r| r.contains("heave")),
        "{:?}",
        check.refused
    );
}

/// The truth's change that a decay cannot tell from the linear structure: a regularised
/// pitch friction (its slope at rest, T_c/ε, is a viscous damper there) or a heavier
/// heaving mass (read as a softer heave spring at the given mass).
fn changed(s: &Section, what: &str) -> Section {
    let mut st = s.structure.clone();
    match what {
        "friction" => {
            // as the benchmark's friction truth: ε a tenth of the reference orbit's peak
            // velocity; T_c/ε a damping ratio of about 0.8 % on the pitch spring
            st.nonlinear.friction = Some(Friction {
                heave_force: 0.0,
                pitch_moment: 0.005 * st.k_alpha * 0.05,
                heave_smoothing: None,
                pitch_smoothing: Some(0.1 * st.omega_alpha() * 0.05),
            })
        }
        _ => st.mass *= 1.2,
    }
    Section::new(st, s.aero.clone(), s.rho).unwrap()
}

/// Structure first for every candidate: a change that alters the model at rest (damping
/// from a friction's pre-sliding slope, mass) is conformed to the decays — the springs and
/// dampers re-identified under it — so that the identification's reading of the change
/// (a larger pitch damper, a softer heave spring) is not counted twice: the truth's own
/// change on the identified structure comes back with the truth's linear structure.
#[test]
fn a_change_at_rest_is_conformed_to_the_decays_and_gives_back_the_truths_structure() {
    let base = truth();
    for what in ["friction", "added mass"] {
        let t = changed(&base, what);
        let sets = decays(&t);
        let refs: Vec<&Dataset> = sets.iter().collect();
        let given = misgiven(&base, "pitch", 1.05);
        let check = structure_check(&refs, &given).expect("still-air decays");
        assert_eq!(
            serde_json::to_value(&check).unwrap()["used"],
            "identified",
            "{what}: {}",
            check.summary
        );
        let id = Section::new(
            check.used_structure(&given.structure),
            given.aero.clone(),
            given.rho,
        )
        .unwrap();
        // the truth's change applied on the identified structure, as a candidate is
        let mut st = id.structure.clone();
        if what == "friction" {
            st.nonlinear.friction = t.structure.nonlinear.friction;
        } else {
            st.mass = t.structure.mass;
        }
        let on_id = Section::new(st, id.aero.clone(), id.rho).unwrap();
        let conformed = conform_to_decays(&check, &id, on_id.clone()).expect("conformed");
        let (ts, is, cs) = (&t.structure, &id.structure, &conformed.structure);
        let (u_t, u_on, u_c) = (first_hopf(&t), first_hopf(&on_id), first_hopf(&conformed));
        eprintln!(
            "{what}: k_h truth {:.2} identified {:.2} conformed {:.2}; k_α {:.4} {:.4} {:.4}; \
             c_h {:.4} {:.4} {:.4}; c_α {:.5} {:.5} {:.5}; Hopf truth {u_t:.3}, change on \
             the identified {u_on:.3}, conformed {u_c:.3} m/s",
            ts.k_h,
            is.k_h,
            cs.k_h,
            ts.k_alpha,
            is.k_alpha,
            cs.k_alpha,
            ts.c_h,
            is.c_h,
            cs.c_h,
            ts.c_alpha,
            is.c_alpha,
            cs.c_alpha
        );
        if what == "friction" {
            // the decay reads the friction's slope at rest T_c/ε as pitch damping ...
            let f = ts.nonlinear.friction.unwrap();
            let slope = f.pitch_moment / f.pitch_smoothing.unwrap();
            assert!(
                (is.c_alpha - ts.c_alpha - slope).abs() < 0.2 * slope,
                "identified c_α {} truth {} slope {slope}",
                is.c_alpha,
                ts.c_alpha
            );
            // ... which the conformed friction candidate does not count twice
            assert!(
                (cs.c_alpha - ts.c_alpha).abs() < 0.2 * slope,
                "conformed c_α {} truth {} slope {slope}",
                cs.c_alpha,
                ts.c_alpha
            );
        } else {
            // a heavier heaving mass is read as a softer heave spring at the given mass ...
            assert!(
                is.k_h < 0.9 * ts.k_h,
                "identified k_h {} truth {}",
                is.k_h,
                ts.k_h
            );
            // ... which the conformed added mass gives back, with the truth's Hopf speed
            assert!(
                (cs.k_h / ts.k_h - 1.0).abs() < 0.01,
                "{} {}",
                cs.k_h,
                ts.k_h
            );
            assert!((u_on / u_t - 1.0).abs() > 0.01, "{what}: {u_on} vs {u_t}");
        }
        assert!((cs.k_alpha / ts.k_alpha - 1.0).abs() < 0.01);
        assert!((u_c / u_t - 1.0).abs() < 0.01, "{what}: {u_c} vs {u_t}");
        // nothing to conform: the identified section itself comes back unchanged
        let same = conform_to_decays(&check, &id, id.clone()).unwrap();
        assert_eq!(same.structure, id.structure);
    }
}

/// The generated benchmark's acceptance (issue 42): rigs whose given structure is off by
/// 3–8 % in one frequency, with two still-air decays of the truth. After the correction the
/// named model's Hopf speed lies within 1 % of the truth's with its criticality in ≥ 90 % of
/// the sets, and no effect-free set is named an effect. About 20 s a set on 2 cores.
#[test]
#[ignore = "slow: 20 generated rigs at the bifurcation level (about 7 min)"]
fn misgiven_structures_of_the_generated_benchmark_are_corrected() {
    use benchmark::branch_bench::{run_bench_with, BranchBenchOptions};
    let opts = BranchBenchOptions {
        misgiven_structure: true,
        hold_given: false,
        ..BranchBenchOptions::default()
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

/// Issue 42 item 1, the decays as time series (round 34): set 5 of seed 2027, a Coulomb
/// friction in pitch whose heave frequency is given 6 % low. Both friction candidates fit
/// the measured amplitudes within one standard error; the one-parameter form (ε fixed at
/// 5 % of the largest orbit's peak pitch velocity) puts the Hopf point 13 % high, its slope
/// at rest being twice the truth's. Its own still-air releases miss the measured decays
/// with 4.7 times the residual energy of the ε-fitted form's (0.164 against 0.075), so it
/// is passed over and the named model's Hopf point is the truth's within 1 %, with its
/// criticality. About 40 s on 2 cores.
#[test]
fn the_decays_pass_over_a_friction_whose_own_release_misses_them() {
    use benchmark::branch_bench::{run_set_diagnosis, BranchBenchOptions};
    let opts = BranchBenchOptions {
        misgiven_structure: true,
        hold_given: false,
        ..BranchBenchOptions::default()
    };
    let (o, d) = run_set_diagnosis(5, 2027, &opts).unwrap();
    assert_eq!(
        o.verdict.to_string(),
        "friction",
        "{}",
        d.verdict.explanation
    );
    let named = d.verdict.candidate.map(|i| &d.candidates[i]).unwrap();
    assert_eq!(
        named.variant, "pitch, ε fitted",
        "{}",
        d.verdict.explanation
    );
    assert_eq!(
        d.verdict.decays_contradicting,
        vec!["friction (pitch)".to_string()],
        "{}",
        d.verdict.explanation
    );
    let (truth, named_hopf) = (o.truth_hopf.unwrap(), o.named_hopf.unwrap());
    assert!(
        (named_hopf.0 / truth.0 - 1.0).abs() < 0.01 && named_hopf.1 == truth.1,
        "{named_hopf:?} vs {truth:?}"
    );
    // every misfit is measured, and the friction forms reproduce the decays best
    let e = |label: &str| {
        d.candidates
            .iter()
            .find(|c| c.label() == label)
            .and_then(|c| c.decay_misfit)
            .unwrap()
    };
    assert!(e("friction (pitch, ε fitted)") < 0.5 * e("friction (pitch)"));
    assert!(e("friction (pitch)") < d.nominal_decay_misfit.unwrap());
}

/// Issue 42 item 5: a still-air decay among the free runs of a forced-and-free set must
/// not raise the free-response level's null (the noise and the sim's own jackknife
/// uncertainty) nor hide the flow runs' gap: the project's own generator, effect-free
/// truth, four limit-cycle runs at 1.05–1.2 U_F, with and without a still-air decay.
///
/// Round 27 measured (plain mean of the runs' normalised energies): null 0.0028 → 0.0106
/// (3.8×) and gap statistic 2.1 → 1.15 when the decay is added — a decay sunk into its
/// noise has a normalised noise energy ten times a limit cycle's and set both. Round 29:
/// each run weighs by the inverse of its own noise energy (docs/DECISIONS.md, round 29).
#[test]
fn a_still_air_decay_does_not_raise_the_free_response_levels_null() {
    use benchmark::blind::{generate, BlindEffect, BlindScenario};
    use diagnose::system::{null_level, system_level, SystemOptions};
    // limit cycles above the flutter speed: runs whose signal stands far above the noise
    let plain = BlindScenario {
        free_speed_factors: vec![1.05, 1.1, 1.15, 1.2],
        ..BlindScenario::default()
    };
    let mut with = plain.clone();
    with.free_speed_factors.insert(0, 0.0);
    let mut o = SystemOptions {
        simulate: false,
        ..SystemOptions::default()
    };
    o.seed = 5;
    let mut nulls = Vec::new();
    let mut stats = Vec::new();
    for sc in [&plain, &with] {
        let set = generate(
            BlindEffect::None,
            0.0,
            aeroelastic::effects::Form::Primary,
            5,
            sc,
        )
        .unwrap();
        let level = system_level(&set.forced, &set.free, &o).unwrap();
        eprintln!(
            "{} free runs: noise {:.4}, model {:?}, null {:.4}, before {:.4}, statistic {:.3}",
            set.free.records.len(),
            level.noise_level,
            level.model_level,
            null_level(&level),
            level.before,
            level.gap_statistic
        );
        for c in &level.cases {
            eprintln!(
                "  {} U {:.2}: before {:.4} noise {:.4}",
                c.id, c.wind_speed, c.before, c.noise_level
            );
        }
        nulls.push(null_level(&level));
        stats.push(level.gap_statistic);
    }
    assert!(
        nulls[1] < 1.5 * nulls[0],
        "null {} → {}",
        nulls[0],
        nulls[1]
    );
    // the decay counts as one run of five: the gap statistic keeps most of its size
    assert!(
        stats[1] > 0.75 * stats[0] && stats[1] < 1.25 * stats[0],
        "gap statistic {} → {}",
        stats[0],
        stats[1]
    );
}

/// A pitch mode damped out within a few periods (a regularised friction's slope at rest,
/// ζ ≈ 0.17 as on generated set 7 of seed 2027) leaves no window of the decays to read: it
/// is read from the releases by output error where they contradict the held spring
/// (DECISIONS, "A heavily damped mode read from the release, round 35"). Pitch given 4 %
/// low: k_α identified within 1 % of the truth's (held at the given value, −8 %, before)
/// and the Hopf speed's error at least halved; heave given 5 % low with the pitch right: the releases do
/// not contradict the given pitch spring, the mode stays unread with a note, and k_α keeps
/// its given (true) value, although a linear fit to the friction's decay alone would move
/// it.
#[test]
fn a_heavily_damped_pitch_mode_is_read_from_the_releases() {
    let base = truth();
    let mut st = base.structure.clone();
    let a_ref = 0.05;
    st.nonlinear.friction = Some(Friction {
        heave_force: 0.0,
        pitch_moment: 0.028 * st.k_alpha * a_ref,
        heave_smoothing: None,
        pitch_smoothing: Some(0.1 * st.omega_alpha() * a_ref),
    });
    let t = Section::new(st, base.aero.clone(), base.rho).unwrap();
    let sets = decays(&t);
    let refs: Vec<&Dataset> = sets.iter().collect();
    // the nominal model knows no friction: the given sections are the truth's without it
    let mut plain = t.structure.clone();
    plain.nonlinear.friction = None;
    let plain = Section::new(plain, t.aero.clone(), t.rho).unwrap();
    for (dof, factor, read) in [("pitch", 0.96, true), ("heave", 0.95, false)] {
        let given = misgiven(&plain, dof, factor);
        let check = structure_check(&refs, &given).expect("still-air decays");
        let row = check.modes.iter().find(|r| r.given_mode == 1);
        if read {
            let row =
                row.unwrap_or_else(|| panic!("the pitch mode is not read: {}", check.summary));
            assert!(row.signature.contains("output error"), "{}", row.signature);
            assert!(row.linear_zeta.is_none(), "{:?}", row.linear_zeta);
        } else {
            assert!(row.is_none(), "{}", check.summary);
            assert!(
                check
                    .refused
                    .iter()
                    .any(|w| w.contains("do not contradict")),
                "{:?}",
                check.refused
            );
        }
        let mut used = check.used_structure(&given.structure);
        let err = used.k_alpha / t.structure.k_alpha - 1.0;
        // the structure's part of the Hopf speed: the identified springs and dampers with
        // the truth's friction (the candidate that would name it)
        used.nonlinear.friction = t.structure.nonlinear.friction;
        let id = Section::new(used, t.aero.clone(), t.rho).unwrap();
        let (u_t, u_g, u_id) = (first_hopf(&t), first_hopf(&given), first_hopf(&id));
        eprintln!(
            "{dof} × {factor}: k_α {:+.3} %, Hopf truth {u_t:.3} given {u_g:.3} identified \
             {u_id:.3} m/s",
            100.0 * err,
        );
        // read: the linear fit's bias against the friction's decay (−0.7 %) against the
        // −7.8 % held before; not read: the given value
        assert!(
            err.abs() < if read { 0.01 } else { 1e-3 },
            "{dof}: k_α off by {err}"
        );
        // the correction moves the Hopf speed towards the truth's (read: −5.5 % given,
        // +1.2 % identified here, the k_α bias through a Hopf speed that moves 1.7 % per
        // 1 % of k_α; the end-to-end figure is the generated set's, DECISIONS)
        assert!(
            (u_id / u_t - 1.0).abs() < 0.5 * (u_g / u_t - 1.0).abs(),
            "{dof}: {u_id} vs {u_t} (given {u_g})"
        );
    }
}

/// A mode read only as a record's second spectral peak moves its DOF's spring only where
/// the releases contradict the held one (DECISIONS, "A heavily damped mode read from the
/// release, round 35"): generated set 4 of seed 2026 (effect-free, heave given 6 % high,
/// pitch right) read the pitch mode as a second mode ± 0.0043 Hz and moved k_α by +2.1 %
/// (its Hopf point +1.03 %); now the row is dropped with a note and k_α keeps its given,
/// true value. Set 14 (pitch given 7.8 % low, read the same way) keeps its row and its
/// corrected k_α.
#[test]
fn a_second_mode_moves_its_spring_only_where_the_releases_contradict_it() {
    use benchmark::branch_bench::{draw_set, BranchBenchOptions};
    let opts = BranchBenchOptions {
        misgiven_structure: true,
        ..BranchBenchOptions::default()
    };
    for (index, dropped) in [(4, true), (14, false)] {
        let set = draw_set(index, 2026, &opts).expect("a drawn set");
        let check = set.check.expect("still-air decays");
        let note = check
            .refused
            .iter()
            .any(|w| w.contains("read only as a record's second mode"));
        let second = check
            .modes
            .iter()
            .any(|r| r.signature.contains("second mode of the record"));
        assert_eq!(note, dropped, "set {index}: {:?}", check.refused);
        assert_eq!(second, !dropped, "set {index}: {}", check.summary);
        let used = check.used_structure(&set.given.structure);
        let err = used.k_alpha / set.truth.structure.k_alpha - 1.0;
        eprintln!("set {index}: k_α {:+.3} %", 100.0 * err);
        // the given pitch spring is the truth's on set 4 (round 34 read +2.08 %); set 14's
        // was given 15 % low in stiffness and is corrected to within 1 %
        assert!(
            err.abs() < if dropped { 1e-9 } else { 0.01 },
            "set {index}: {err}"
        );
    }
}
