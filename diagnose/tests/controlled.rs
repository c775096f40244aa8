//! Controlled records (issue 42 item 3): a virtual rig held on target orbits by a known PD
//! controller on heave (control-based continuation), its truth a hardening pitch cubic.
//! The records carry `control_raw` = force / G + O (a known gain and offset) and
//! `h_target`, written and read back through the data-set format. The free-response level
//! must take the control force as a measured input: recover the gain G within its
//! interval, find that the controller acts on heave, name the cubic, and leave the records
//! without the control column unchanged.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use aeroelastic::aero::{AeroModel, QuasiSteady, QuasiSteadyKind};
use aeroelastic::dynamics::{ExtraTerms, SectionDynamics};
use aeroelastic::section::Section;
use aeroelastic::structure::{NondimStructure, PolyTerm, Structure};
use aeroelastic::tunnel::{free_dataset, FreeOptions};
use diagnose::pipeline::{diagnose_free, DiagnoseOptions};
use diagnose::{Effect, Verdict};
use identify::dataset::{read_dataset, write_dataset, Dataset};
use identify::record::ControlSignal;
use nalgebra::Matrix2;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// The gain G \[N/m per unit\] and offset O \[unit\] of the virtual controller's output:
/// control_raw = force / G + O.
const G: f64 = 2500.0;
const O: f64 = 0.04;

/// A rig as the bifurcation benchmark draws them, with a hardening cubic pitch spring
/// (at 0.05 rad the cubic doubles the spring's force).
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
    Section::new(st, model(), 1.2).unwrap()
}

/// PD control on heave toward the target h_t(t) = a·sin(ωt): F = k_p(h_t − h) + k_d(ḣ_t − ḣ).
/// The integrator sets the time before each evaluation.
#[derive(Debug)]
struct Pd {
    kp: f64,
    kd: f64,
    a: f64,
    w: f64,
    t: AtomicU64,
}

impl Pd {
    fn target(&self, t: f64) -> (f64, f64) {
        (
            self.a * (self.w * t).sin(),
            self.a * self.w * (self.w * t).cos(),
        )
    }
    fn force(&self, t: f64, h: f64, hd: f64) -> f64 {
        let (ht, htd) = self.target(t);
        self.kp * (ht - h) + self.kd * (htd - hd)
    }
}

impl ExtraTerms for Pd {
    fn mass(&self) -> Matrix2<f64> {
        Matrix2::zeros()
    }
    fn applied(&self, q: [f64; 2], qd: [f64; 2], f: [f64; 2]) -> [f64; 2] {
        let t = f64::from_bits(self.t.load(Ordering::Relaxed));
        [f[0] + self.force(t, q[0], qd[0]), f[1]]
    }
}

/// One controlled record: `seconds` at `rate` Hz (RK4, 8 substeps), from rest, with
/// sensor noise on h, α and the controller output; (h, α, control_raw, h_target).
#[allow(clippy::type_complexity)]
fn controlled_run(
    s: &Section,
    u: f64,
    pd: &Pd,
    seconds: f64,
    rate: f64,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let dynamics = SectionDynamics::with_extra(s, u, pd).unwrap();
    let n = (seconds * rate) as usize;
    let sub = 8;
    let dt = 1.0 / rate;
    let hs = dt / sub as f64;
    let dim = dynamics.dim();
    let mut z = vec![0.0; dim];
    let (mut k1, mut k2, mut k3, mut k4) = (
        vec![0.0; dim],
        vec![0.0; dim],
        vec![0.0; dim],
        vec![0.0; dim],
    );
    let mut tmp = vec![0.0; dim];
    let rate_at = |t: f64, z: &[f64], out: &mut [f64]| {
        pd.t.store(t.to_bits(), Ordering::Relaxed);
        dynamics.rate(z, out);
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let nh = Normal::new(0.0, 2e-5).unwrap();
    let na = Normal::new(0.0, 2e-4).unwrap();
    let nu = Normal::new(0.0, 2e-4).unwrap();
    let (mut h, mut a, mut c, mut ht) = (vec![], vec![], vec![], vec![]);
    let mut t = 0.0;
    for i in 0..n {
        if i > 0 {
            for _ in 0..sub {
                rate_at(t, &z, &mut k1);
                for j in 0..dim {
                    tmp[j] = z[j] + 0.5 * hs * k1[j];
                }
                rate_at(t + 0.5 * hs, &tmp, &mut k2);
                for j in 0..dim {
                    tmp[j] = z[j] + 0.5 * hs * k2[j];
                }
                rate_at(t + 0.5 * hs, &tmp, &mut k3);
                for j in 0..dim {
                    tmp[j] = z[j] + hs * k3[j];
                }
                rate_at(t + hs, &tmp, &mut k4);
                for j in 0..dim {
                    z[j] += hs / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
                }
                t += hs;
            }
        }
        let f = pd.force(t, z[0], z[2]);
        h.push(z[0] + nh.sample(&mut rng));
        a.push(z[1] + na.sample(&mut rng));
        c.push(f / G + O + nu.sample(&mut rng));
        ht.push(pd.target(t).0);
    }
    (h, a, c, ht)
}

/// The virtual campaign: two free decays (no controller) and six controlled orbits below
/// the flutter speed, written with `write_dataset` and read back. `controlled`: whether
/// the controlled records keep their control columns.
fn campaign(dir: &std::path::Path, controlled: bool) -> Dataset {
    let s = truth();
    let uf = s.hopf_points(0.5, 200.0, 400).unwrap()[0].u;
    let (kh, m) = (s.structure.k_h, s.structure.mass);
    let ctl = [
        (0.70, 0.010, 2.3),
        (0.75, 0.016, 2.4),
        (0.80, 0.022, 2.5),
        (0.85, 0.012, 2.6),
        (0.90, 0.018, 2.5),
        (0.95, 0.024, 2.4),
    ];
    let at = |f: f64| (f * uf * 100.0).round() / 100.0;
    let speeds: Vec<f64> = [0.55, 0.65]
        .into_iter()
        .chain(ctl.iter().map(|c| c.0))
        .map(at)
        .collect();
    let mut o = FreeOptions::new(11);
    o.rate = 200.0;
    o.duration = 12.0;
    o.record_forces = false;
    o.initial = [0.01, 0.04, 0.0, 0.0];
    let (manifest, mut records, _) = free_dataset(&s, &speeds, &o, &|_| {}).unwrap();
    for (k, &(f, amp, hz)) in ctl.iter().enumerate() {
        let pd = Pd {
            kp: 0.4 * kh,
            kd: 0.2 * (kh * m).sqrt(),
            a: amp,
            w: std::f64::consts::TAU * hz,
            t: AtomicU64::new(0),
        };
        let (h, a, c, ht) = controlled_run(&s, at(f), &pd, 12.0, 200.0, 100 + k as u64);
        let r = &mut records[2 + k];
        r.h = h;
        r.alpha = a;
        r.control = controlled.then_some(ControlSignal {
            calibrated: false,
            values: c,
            h_target: Some(ht),
        });
    }
    write_dataset(dir, &manifest, &records).unwrap();
    read_dataset(dir).unwrap()
}

/// The aerodynamics of the truth and of the sim: quasi-steady thin aerofoil with the
/// apparent mass, whose time-domain form and frequency response are the same law (the
/// residual evaluates H(ω); Theodorsen's exact C(k) there against the Jones lags of the
/// simulated truth leaves a model error common to every run, DECISIONS round 28).
fn model() -> Arc<dyn AeroModel> {
    Arc::new(QuasiSteady::new(0.3, -0.4, QuasiSteadyKind::QuasiSteady, true).unwrap())
}

#[test]
fn a_known_pd_controller_on_heave_is_recovered_and_the_pitch_cubic_named() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = campaign(&tmp.path().join("ctl"), true);
    // the reader kept the controller's columns
    assert_eq!(ds.records.iter().filter(|r| r.control.is_some()).count(), 6);
    let d = diagnose_free(&ds, &model(), &DiagnoseOptions::new(3), "test").unwrap();
    let l = &d.levels[0];
    let c = l.control.as_ref().expect("control report");
    eprintln!("{}", serde_json::to_string_pretty(c).unwrap());
    eprintln!("verdict {:?}: {}", d.verdict.effect, d.verdict.reason);
    for k in &l.candidates {
        eprintln!(
            "{:?} sig {} shrink {:.3} {:?}",
            k.effect, k.significant, k.shrink, k.parameters
        );
    }
    let g = c.gain.unwrap();
    // the known gain lies in the interval, which excludes zero
    assert!(g.low < G && G < g.high, "{g:?}");
    assert!(g.low > 0.0, "{g:?}");
    // and the offset: o = −G·O
    let o = c.offset.unwrap();
    assert!(o.low < -G * O && -G * O < o.high, "{o:?}");
    // the data say heave
    assert_eq!(c.data_dof, "heave");
    // the control input removes the heave gap the controller made (0.82–0.91 of the
    // structural force without it, 0.03–0.07 with it), and leaves pitch alone
    for r in &c.runs {
        assert!(r.with[0] < 0.1 * r.without[0], "{r:?}");
        assert_eq!(r.with[1], r.without[1], "{r:?}");
    }
    // the PD law is rebuilt from h_target, h and the signal (R² 0.95–0.99: the signal's
    // sensor noise), well enough for the closed loop by the rule
    assert!(c.runs.iter().all(|r| r
        .pd_law
        .is_some_and(|p| p.r2 > diagnose::system::control::PD_SIMULABLE_R2)));
    // the cubic is named, with the truth's coefficient (k_α/0.05² in the restoring sense)
    let k3_true = truth().structure.k_alpha / (0.05 * 0.05);
    let k3 = l
        .candidates
        .iter()
        .find(|k| k.effect == Effect::StructuralCubic)
        .and_then(|k| k.parameters.iter().find(|p| p.0 == "k3_pitch_Nm_per_rad3"))
        .unwrap()
        .1;
    assert!((k3 / k3_true - 1.0).abs() < 0.05, "k3 {k3} vs {k3_true}");
    assert!(
        matches!(
            d.verdict.effect,
            Verdict::Effect(Effect::StructuralCubic)
                | Verdict::Effect(Effect::StructuralPolynomial)
        ),
        "{:?}: {}",
        d.verdict.effect,
        d.verdict.reason
    );

    // the same records without their control columns are read as if free: no control
    // report, and their gap is the controlled level's `gap_without`
    let free = campaign(&tmp.path().join("free"), false);
    assert!(free.records.iter().all(|r| r.control.is_none()));
    let f = diagnose_free(&free, &model(), &DiagnoseOptions::new(3), "test").unwrap();
    let fl = &f.levels[0];
    assert!(fl.control.is_none());
    assert!(
        (fl.before - c.gap_without).abs() < 1e-12 * fl.before,
        "{} vs {}",
        fl.before,
        c.gap_without
    );
    // and the uncontrolled runs' gaps are the same in both diagnoses
    for (a, b) in l.cases.iter().zip(&fl.cases).take(2) {
        assert_eq!((a.id.as_str(), a.before), (b.id.as_str(), b.before));
    }
    eprintln!("as if free: {:?}: {}", f.verdict.effect, f.verdict.reason);
}
