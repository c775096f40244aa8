//! Withheld-effect benchmark at the bifurcation level: generated rigs whose measured
//! diagram is the continuation of a truth (the nominal section plus one withheld effect, or
//! none) with amplitude noise, 5–10 speeds, some unstable points missing and heave-only
//! tables in a third, diagnosed without the label.
//!
//! The truths' forms differ from the candidates' where the effect allows it (the diagnosis
//! could not have assumed them): the stiffness truth has a quartic term, the damping truth a
//! fourth-power term beside the square, the added-mass truth changes the mass only, the
//! friction truth has twice the default smoothing. Rigs are drawn nondimensionally (μ, r²,
//! σ, x_α, a, damping ratios, pitch frequency) with a known nonlinear pitch spring in the
//! nominal model (subcritical with a fold, or supercritical hardening), so that an
//! effect-free rig has limit cycles too.
//!
//! Every draw comes from SplitMix64-split seeds of the master seed (recorded in the report).

use std::sync::Arc;

use aeroelastic::aero::AeroModel;
use aeroelastic::aero::TheodorsenAero;
use aeroelastic::branch::{predicted_at, MeasuredAmplitude};
use aeroelastic::section::Section;
use aeroelastic::structure::{add_poly_term, Friction, NondimStructure, PolyTerm, Structure};
use identify::numerics::split_seed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use super::candidates::ScaledAero;
use super::{diagnose_branches, BifurcationOptions};
use crate::{Effect, Error, Result, Verdict};

/// Relative amplitude noise of the generated measured points.
pub const AMPLITUDE_NOISE: f64 = 0.02;

/// A set counts as strong when the nominal model's score on it is at least this (a 20 %
/// relative amplitude gap, ten times the noise).
pub const STRONG_SCORE: f64 = 0.2;

/// The withheld truth of a generated set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BranchTruth {
    /// Nothing withheld: the nominal model is the truth.
    None,
    /// Extra pitch stiffness k₂α² + k₃α³ + k₄α⁴.
    PitchPolynomial,
    /// Extra cubic pitch stiffness k₃α³.
    PitchCubic,
    /// Amplitude-dependent pitch damping (c₂α² + c₄α⁴)α̇.
    PitchDamping,
    /// Coulomb friction in pitch.
    PitchFriction,
    /// Extra heaving mass.
    AddedMass,
    /// A scale on the aerodynamic loads.
    AerodynamicScale,
}

impl BranchTruth {
    /// Every truth, drawn with equal probability.
    pub const ALL: [BranchTruth; 7] = [
        BranchTruth::None,
        BranchTruth::PitchPolynomial,
        BranchTruth::PitchCubic,
        BranchTruth::PitchDamping,
        BranchTruth::PitchFriction,
        BranchTruth::AddedMass,
        BranchTruth::AerodynamicScale,
    ];

    /// The catalogue effect a correct diagnosis names (`None`: verdict `none`).
    pub fn expected(self) -> Option<Effect> {
        match self {
            BranchTruth::None => None,
            BranchTruth::PitchPolynomial => Some(Effect::StructuralPolynomial),
            BranchTruth::PitchCubic => Some(Effect::StructuralCubic),
            BranchTruth::PitchDamping => Some(Effect::StructuralDamping),
            BranchTruth::PitchFriction => Some(Effect::Friction),
            BranchTruth::AddedMass => Some(Effect::AddedMass),
            BranchTruth::AerodynamicScale => Some(Effect::AerodynamicScale),
        }
    }
}

/// One generated set and its diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchOutcome {
    /// Set index.
    pub index: usize,
    /// The set's own seed (split from the master seed).
    pub seed: u64,
    /// The withheld truth.
    pub truth: BranchTruth,
    /// Its strength in [0, 1].
    pub strength: f64,
    /// Heave amplitudes only.
    pub heave_only: bool,
    /// Measured points.
    pub points: usize,
    /// The nominal model's score on the set (the size of the gap).
    pub nominal_score: f64,
    /// `nominal_score ≥ STRONG_SCORE`.
    pub strong: bool,
    /// The verdict (written by name).
    pub verdict: Verdict,
    /// Verdict equals the truth's expected effect (`none` for an effect-free set).
    pub correct: bool,
    /// Held-out shrink of the named candidate.
    pub shrink: Option<f64>,
    /// Wall time \[s\].
    pub seconds: f64,
}

/// Per truth: sets, strong sets, correct among the strong ones, correct overall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct TruthRow {
    /// Truth.
    pub truth: BranchTruth,
    /// Sets drawn.
    pub sets: usize,
    /// Of those, strong.
    pub strong: usize,
    /// Strong sets named correctly.
    pub strong_correct: usize,
    /// All sets named correctly.
    pub correct: usize,
}

/// The bifurcation-level benchmark report (`branch-blind.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchBenchReport {
    /// `aeroform-branch-blind/1`.
    pub format: String,
    /// Master seed.
    pub seed: u64,
    /// Sets.
    pub outcomes: Vec<BranchOutcome>,
    /// Per truth.
    pub per_truth: Vec<TruthRow>,
    /// Correct top-1 among strong sets with an effect.
    pub top1_strong: f64,
    /// Effect-free sets called `none`.
    pub none_on_effect_free: f64,
}

/// A drawn rig: the nominal section (known nonlinear pitch spring) and its reference
/// amplitude \[rad\].
fn draw_rig(rng: &mut ChaCha8Rng) -> Result<(Section, f64)> {
    let b = 0.15;
    let x_alpha: f64 = rng.random_range(0.05..0.3);
    let r2: f64 = rng.random_range((x_alpha * x_alpha + 0.1).max(0.2)..0.4);
    let p = NondimStructure {
        mu: rng.random_range(20.0..120.0),
        r_alpha2: r2,
        sigma: rng.random_range(0.45..0.85),
        x_alpha,
        semi_chord: b,
        omega_alpha: std::f64::consts::TAU * rng.random_range(2.0..4.0),
        rho: 1.2,
        zeta_h: rng.random_range(0.005..0.03),
        zeta_alpha: rng.random_range(0.005..0.03),
    };
    let mut st = Structure::from_nondimensional(&p).map_err(|e| Error::aeroelastic("rig", e))?;
    let a_ref = 0.05;
    let k3 = rng.random_range(0.5..2.0) * st.k_alpha / (a_ref * a_ref);
    st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
        power: 3,
        coefficient: k3,
    });
    if rng.random_bool(0.5) {
        // an even term strong enough for a subcritical Hopf with a fold
        let k2 = rng.random_range(1.0..2.0) * (k3 * st.k_alpha).sqrt();
        st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
            power: 2,
            coefficient: k2,
        });
    }
    let a: f64 = rng.random_range(-0.5..-0.2);
    let aero: Arc<dyn AeroModel> =
        Arc::new(TheodorsenAero::new(2.0 * b, a).map_err(|e| Error::aeroelastic("rig", e))?);
    let s = Section::new(st, aero, p.rho).map_err(|e| Error::aeroelastic("rig", e))?;
    Ok((s, a_ref))
}

/// The truth: the nominal section with `truth` at `strength` ∈ [0, 1].
fn truth_section(
    nominal: &Section,
    truth: BranchTruth,
    s: f64,
    sign: f64,
    a_ref: f64,
) -> Result<Section> {
    let mut st = nominal.structure.clone();
    let mut aero = nominal.aero.clone();
    let lerp = |lo: f64, hi: f64| lo + (hi - lo) * s;
    let ka = st.k_alpha;
    let ca = 2.0 * 0.01 * (ka * st.inertia_alpha).sqrt();
    match truth {
        BranchTruth::None => {}
        BranchTruth::PitchPolynomial => {
            let k2 = sign * lerp(0.3, 1.5) * ka / a_ref;
            add_poly_term(&mut st.nonlinear.pitch_stiffness_terms, 2, k2);
            add_poly_term(
                &mut st.nonlinear.pitch_stiffness_terms,
                3,
                0.3 * k2.abs() / a_ref,
            );
            add_poly_term(
                &mut st.nonlinear.pitch_stiffness_terms,
                4,
                0.2 * k2 / (a_ref * a_ref),
            );
        }
        BranchTruth::PitchCubic => {
            let k3 = sign * lerp(0.3, 1.5) * ka / (a_ref * a_ref);
            add_poly_term(&mut st.nonlinear.pitch_stiffness_terms, 3, k3);
        }
        BranchTruth::PitchDamping => {
            let c2 = sign * lerp(3.0, 40.0) * ca / (a_ref * a_ref);
            add_poly_term(&mut st.nonlinear.pitch_damping_terms, 2, c2);
            add_poly_term(
                &mut st.nonlinear.pitch_damping_terms,
                4,
                0.3 * c2 / (a_ref * a_ref),
            );
        }
        BranchTruth::PitchFriction => {
            let tc = lerp(0.003, 0.03) * ka * a_ref;
            // regularised over 10 % of the reference orbit's peak velocity (the default
            // smoothing, a damping ratio of 5 at rest, leaves no flutter to measure)
            let eps = 0.1 * st.omega_alpha() * a_ref;
            st.nonlinear.friction = Some(Friction {
                heave_force: 0.0,
                pitch_moment: tc,
                heave_smoothing: None,
                pitch_smoothing: Some(eps),
            });
        }
        BranchTruth::AddedMass => st.mass *= 1.0 + lerp(0.05, 0.4),
        BranchTruth::AerodynamicScale => {
            aero = Arc::new(ScaledAero {
                inner: nominal.aero.clone(),
                scale: 1.0 + sign * lerp(0.05, 0.3),
            });
        }
    }
    Section::new(st, aero, nominal.rho).map_err(|e| Error::aeroelastic("truth", e))
}

/// The measured diagram of `truth`: `n` speeds across its orbits' speed range, both
/// branches where they exist (an unstable point kept with probability 0.7), amplitudes with
/// relative Gaussian noise, heave only when `heave_only`.
fn measure(
    truth: &Section,
    n: usize,
    heave_only: bool,
    rng: &mut ChaCha8Rng,
) -> Option<Vec<MeasuredAmplitude>> {
    let opts = BifurcationOptions::default().branch;
    let hopf = truth.hopf_points(0.5, 200.0, 400).ok()?;
    let uh = hopf.first()?.u;
    let set = truth
        .lco_branches(0.5 * uh, 1.3 * uh, &opts, &|_| {})
        .ok()?;
    let pts: Vec<f64> = set
        .branches
        .iter()
        .flat_map(|b| b.points.iter())
        .filter(|p| p.amplitude_alpha < 0.25 && p.amplitude_alpha > 0.003)
        .map(|p| p.u)
        .collect();
    let lo = pts.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = pts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !hi.is_finite() || !lo.is_finite() || hi <= lo * 1.02 {
        return None;
    }
    let mut out = Vec::new();
    for i in 0..n {
        let u = lo + (hi - lo) * (i as f64 + 0.5) / n as f64;
        for stable in [true, false] {
            if !stable && !rng.random_bool(0.7) {
                continue;
            }
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
            let mut noisy = |v: f64, sd: f64| {
                let z: f64 = StandardNormal.sample(rng);
                v * (1.0 + sd * z)
            };
            let a = noisy(a, AMPLITUDE_NOISE);
            let h = noisy(h, AMPLITUDE_NOISE);
            let f = noisy(f, 0.1 * AMPLITUDE_NOISE);
            out.push(MeasuredAmplitude {
                amplitude_alpha: (!heave_only).then_some(a),
                amplitude_h: Some(h),
                frequency_hz: Some(f),
                ..probe
            });
        }
    }
    let speeds = {
        let mut u: Vec<f64> = out.iter().map(|m| m.u).collect();
        u.dedup();
        u.len()
    };
    (out.len() >= 4 && speeds >= 3).then_some(out)
}

/// Runs set `index` of the benchmark with master seed `seed`.
///
/// # Errors
/// [`Error::Data`] when no rig with a measurable diagram was drawn in 30 tries; the
/// errors of [`diagnose_branches`].
pub fn run_set(index: usize, seed: u64) -> Result<BranchOutcome> {
    let set_seed = split_seed(seed, index as u64);
    let mut rng = ChaCha8Rng::seed_from_u64(set_seed);
    let truth = BranchTruth::ALL[rng.random_range(0..BranchTruth::ALL.len())];
    let heave_only = rng.random_bool(1.0 / 3.0);
    let n_speeds = rng.random_range(5..=10);
    let mut why = Vec::new();
    for _ in 0..30 {
        // strength and sign are redrawn with the rig: some combinations leave no
        // measurable diagram (no Hopf point in range, a branch that cannot start)
        let strength: f64 = rng.random();
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let (nominal, a_ref) = draw_rig(&mut rng)?;
        let t = match truth_section(&nominal, truth, strength, sign, a_ref) {
            Ok(t) => t,
            Err(e) => {
                why.push(e.to_string());
                continue;
            }
        };
        let Some(points) = measure(&t, n_speeds, heave_only, &mut rng) else {
            why.push(format!(
                "strength {strength:.2} sign {sign}: no measurable diagram"
            ));
            continue;
        };
        let t0 = std::time::Instant::now();
        let opts = BifurcationOptions::default();
        let d = diagnose_branches(&points, &nominal, None, vec![], &opts, vec![], "bench")?;
        let nominal_score = d.nominal.errors.score;
        let correct = match truth.expected() {
            None => d.verdict.effect.is_none() && d.verdict.name == Verdict::None,
            Some(e) => d.verdict.effect == Some(e),
        };
        return Ok(BranchOutcome {
            index,
            seed: set_seed,
            truth,
            strength,
            heave_only,
            points: points.len(),
            nominal_score,
            strong: nominal_score >= STRONG_SCORE,
            verdict: d.verdict.name,
            correct,
            shrink: d.verdict.shrink,
            seconds: t0.elapsed().as_secs_f64(),
        });
    }
    Err(Error::data(
        "bifurcation benchmark",
        format!(
            "set {index} ({truth:?}): no rig with a measurable diagram in 30 draws: {}",
            why.iter().take(3).cloned().collect::<Vec<_>>().join("; ")
        ),
    ))
}

/// Runs `n` sets with master seed `seed`; `observer` sees each outcome.
///
/// # Errors
/// As [`run_set`].
pub fn run_bench(
    n: usize,
    seed: u64,
    observer: &dyn Fn(&BranchOutcome),
) -> Result<BranchBenchReport> {
    let mut outcomes = Vec::with_capacity(n);
    for i in 0..n {
        let o = run_set(i, seed)?;
        observer(&o);
        outcomes.push(o);
    }
    let per_truth: Vec<TruthRow> = BranchTruth::ALL
        .iter()
        .map(|&t| {
            let of: Vec<&BranchOutcome> = outcomes.iter().filter(|o| o.truth == t).collect();
            TruthRow {
                truth: t,
                sets: of.len(),
                strong: of.iter().filter(|o| o.strong).count(),
                strong_correct: of.iter().filter(|o| o.strong && o.correct).count(),
                correct: of.iter().filter(|o| o.correct).count(),
            }
        })
        .collect();
    let strong: Vec<&BranchOutcome> = outcomes
        .iter()
        .filter(|o| o.truth != BranchTruth::None && o.strong)
        .collect();
    let free: Vec<&BranchOutcome> = outcomes
        .iter()
        .filter(|o| o.truth == BranchTruth::None)
        .collect();
    let frac = |v: &[&BranchOutcome]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().filter(|o| o.correct).count() as f64 / v.len() as f64
        }
    };
    Ok(BranchBenchReport {
        format: "aeroform-branch-blind/1".into(),
        seed,
        top1_strong: frac(&strong),
        none_on_effect_free: frac(&free),
        outcomes,
        per_truth,
    })
}
