//! System level on virtual data: the base scenario of the blind data sets (truth
//! `scenarios/plate-truth.model.toml`, rig `scenarios/plate-rig.structure.toml`, forced
//! campaign B + D × 4 amplitudes × 5 speeds, 8 s; free runs at 6 speeds around U_F, 12 s,
//! α₀ = 4°, paper noise) with structural effects injected through the `Structure` fields
//! and added mass through the forced forces only.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aeroelastic::aero::AeroModel;
use aeroelastic::files::{LoadedModel, StructureFile};
use aeroelastic::section::Section;
use aeroelastic::structure::{Friction, PolyTerm, Structure};
use aeroelastic::tunnel::{self, Campaign, ForcedOptions, FreeOptions, TunnelProgress};
use diagnose::system::{system_level, SystemOptions};
use diagnose::Effect;
use identify::dataset::Dataset;

const U_F: f64 = 6.595;

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios")
}

fn truth() -> Arc<dyn AeroModel> {
    LoadedModel::load(&scenarios().join("plate-truth.model.toml"), None)
        .unwrap()
        .model
}

fn rig() -> (Structure, f64) {
    let f = StructureFile::read(&scenarios().join("plate-rig.structure.toml")).unwrap();
    (f.structure().unwrap(), f.air_density)
}

fn no_obs(_: TunnelProgress) {}

/// An injected effect (test data only).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Inject {
    None,
    /// Pitch cubic spring coefficient [N·m/rad³ per m].
    Cubic(f64),
    /// Pitch freeplay half gap [rad].
    Freeplay(f64),
    /// Pitch Coulomb friction moment [N·m/m].
    Friction(f64),
    /// Diagonal ΔM (heave [kg/m], pitch [kg·m²/m]) added to the forced forces only.
    AddedMass(f64, f64),
}

fn forced_set(seed: u64, inject: Inject) -> Dataset {
    let model = truth();
    let campaign = Campaign {
        configurations: tunnel::paper_configurations()
            .into_iter()
            .filter(|c| c.name == "B" || c.name == "D")
            .collect(),
        amplitudes_deg: vec![6.0, 12.0, 18.0, 24.0],
        wind_speeds: vec![4.0, 5.5, 7.0, 8.5, 10.0],
    };
    let cases = campaign.cases();
    let mut opts = ForcedOptions::paper(seed);
    opts.duration = 8.0;
    let (manifest, mut records) =
        tunnel::forced_dataset(model.as_ref(), &cases, &opts, &no_obs).unwrap();
    if let Inject::AddedMass(dm_h, dm_a) = inject {
        for (rec, case) in records.iter_mut().zip(&cases) {
            let n = rec.len();
            let (l, m) = (rec.lift.as_mut().unwrap(), rec.moment.as_mut().unwrap());
            for i in 0..n {
                let (_, _, qdd) = case.motion.eval(i as f64 * rec.dt);
                l[i] += dm_h * qdd[0];
                m[i] += dm_a * qdd[1];
            }
        }
    }
    Dataset {
        root: PathBuf::from("<memory>"),
        manifest,
        records,
    }
}

fn free_set(seed: u64, inject: Inject) -> Dataset {
    let (mut st, rho) = rig();
    match inject {
        Inject::Cubic(c) => st.pitch_stiffness_terms.push(PolyTerm {
            power: 3,
            coefficient: c,
        }),
        Inject::Freeplay(d) => st.pitch_freeplay = d,
        Inject::Friction(t) => {
            st.friction = Some(Friction {
                heave_force: 0.0,
                pitch_moment: t,
                heave_smoothing: None,
                pitch_smoothing: None,
            })
        }
        _ => {}
    }
    let section = Section::new(st, truth(), rho).unwrap();
    let mut o = FreeOptions::new(seed ^ 0x5eed);
    o.duration = 12.0;
    o.initial = [0.0, 4f64.to_radians(), 0.0, 0.0];
    o.record_forces = false;
    let speeds: Vec<f64> = [0.5, 0.7, 0.85, 0.95, 1.05, 1.15]
        .iter()
        .map(|f| f * U_F)
        .collect();
    let (manifest, records, _) = tunnel::free_dataset(&section, &speeds, &o, &no_obs).unwrap();
    Dataset {
        root: PathBuf::from("<memory>"),
        manifest,
        records,
    }
}

#[test]
#[ignore]
fn explore() {
    for inject in [
        Inject::None,
        Inject::Cubic(30.0),
        Inject::Freeplay(0.5f64.to_radians()),
        Inject::Friction(0.002),
        Inject::AddedMass(0.05, 2e-4),
    ] {
        let t = std::time::Instant::now();
        let forced = forced_set(1, inject);
        let free = free_set(1, inject);
        let tg = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let res = system_level(&forced, &free, &SystemOptions::default()).unwrap();
        eprintln!(
            "{inject:?}: gen {tg:.2}s diag {:.2}s before {:.4} noise {:.4} stat {:.2}",
            t.elapsed().as_secs_f64(),
            res.before,
            res.noise_level,
            res.gap_statistic
        );
        for c in &res.candidates {
            eprintln!(
                "   {:>16} after {:.4} stat {:.3} thr {:.3} sig {} {:?}",
                c.effect.name(),
                c.after,
                c.statistic,
                c.threshold,
                c.significant,
                c.parameters
            );
        }
        for c in &res.cases {
            eprintln!(
                "   case {} U {:.2} amp {:.2} before {:.4} after {:.4} noise {:.4}",
                c.id, c.wind_speed, c.amplitude, c.before, c.after, c.noise_level
            );
        }
        let _ = Effect::ALL;
    }
}
