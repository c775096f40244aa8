//! The branch's data ([`HopfPoint`], [`BranchPoint`], [`Branch`], [`BranchSet`], their
//! events and end reasons): below every file of `branch` that computes them, so no
//! discretisation imports the module that dispatches to it (issue 40, docs/DECISIONS.md
//! "No import circles, checked"). Re-exported as `aeroelastic::branch::*`.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::options::BranchOptions;

/// A Hopf point of the equilibrium: a complex pair λ = σ ± iω crosses σ = 0 at U.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HopfPoint {
    /// Wind speed [m/s].
    pub u: f64,
    /// Frequency of the crossing pair [rad/s].
    pub omega: f64,
    /// dσ/dU at the crossing [1/m]: > 0 when the equilibrium loses stability with
    /// increasing U (flutter onset), < 0 when it regains it.
    pub dsigma_du: f64,
    /// Hopf eigenvector, pitch component normalised to 1: (re, im) of each state.
    #[serde(skip)]
    pub eigenvector: Vec<Complex64>,
}

/// Kind of a bifurcation of the periodic orbits found on a branch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// Turning point in U (saddle-node of cycles): a Floquet multiplier crosses +1.
    Fold,
    /// A real Floquet multiplier crosses −1.
    PeriodDoubling,
    /// A complex pair of Floquet multipliers crosses the unit circle (torus).
    NeimarkSacker,
    /// A real multiplier crosses +1 without a turning point (branch point of cycles).
    BranchPoint,
}

/// A bifurcation located between two consecutive branch points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchEvent {
    /// Kind.
    pub kind: EventKind,
    /// Speed [m/s] (folds: vertex of the parabola U(s) through three points; others: the
    /// point after the crossing).
    pub u: f64,
    /// Pitch amplitude (half peak-to-peak) there \[rad\].
    pub amplitude_alpha: f64,
    /// Heave amplitude (half peak-to-peak) there \[m\].
    pub amplitude_h: f64,
    /// Index of the branch point after the crossing.
    pub index: usize,
}

/// One periodic orbit on a branch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchPoint {
    /// Wind speed [m/s].
    pub u: f64,
    /// Period T \[s\].
    pub period: f64,
    /// Frequency ω = 2π/T [rad/s].
    pub omega: f64,
    /// Pitch amplitude, half peak-to-peak \[rad\] (as the time-integration LCO runs report).
    pub amplitude_alpha: f64,
    /// Heave amplitude, half peak-to-peak \[m\].
    pub amplitude_h: f64,
    /// First-harmonic pitch amplitude \[rad\] (as the measured tables report).
    pub amplitude1_alpha: f64,
    /// First-harmonic heave amplitude \[m\].
    pub amplitude1_h: f64,
    /// Largest modulus of the non-trivial Floquet multipliers.
    pub max_floquet: f64,
    /// Stable orbit (every non-trivial multiplier inside the unit circle).
    pub stable: bool,
    /// Non-trivial Floquet multipliers (re, im).
    pub multipliers: Vec<[f64; 2]>,
    /// A state on the orbit: z₀ at t = 0 (shooting: α̇ = 0, a pitch extremum; harmonic
    /// balance: the phase where the first pitch harmonic is a cosine).
    pub state: Vec<f64>,
    /// The continuation's scaled unknowns of this orbit (method-specific; not written).
    #[serde(skip)]
    #[schemars(skip)]
    pub unknowns: Vec<f64>,
}

/// Why a branch ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum BranchEnd {
    /// U left the requested range.
    SpeedRange {
        /// Speed of the first point outside [m/s].
        u: f64,
    },
    /// The pitch amplitude exceeded `max_amplitude_alpha`.
    Amplitude {
        /// Amplitude reached \[rad\].
        amplitude_alpha: f64,
    },
    /// The branch came back to the equilibrium (another Hopf point).
    Equilibrium {
        /// Speed [m/s].
        u: f64,
    },
    /// `max_points` reached.
    MaxPoints,
    /// Newton did not converge even with the smallest step.
    NotConverged {
        /// Speed of the last converged point [m/s].
        u: f64,
        /// Its pitch amplitude \[rad\].
        amplitude_alpha: f64,
        /// What failed.
        message: String,
    },
}

/// A continued branch of periodic orbits from one Hopf point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Branch {
    /// The Hopf point it starts from.
    pub hopf: HopfPoint,
    /// Orbits in continuation order.
    pub points: Vec<BranchPoint>,
    /// Folds, period doublings, Neimark–Sacker points.
    pub events: Vec<BranchEvent>,
    /// Why it ended.
    pub stop: BranchEnd,
    /// `supercritical` (stable cycles born towards U where the equilibrium is unstable)
    /// or `subcritical`, from the first continued orbits.
    pub criticality: String,
    /// Scale of each unknown (state, T, U) used by the continuation.
    pub scales: Vec<f64>,
}

/// All branches of a speed range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchSet {
    /// Hopf points in the range, increasing U.
    pub hopf_points: Vec<HopfPoint>,
    /// One branch per Hopf point.
    pub branches: Vec<Branch>,
    /// Settings.
    pub options: BranchOptions,
    /// Speed range [m/s].
    pub u_range: [f64; 2],
}

/// Progress report after each branch point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchProgress {
    /// Branch index.
    pub branch: usize,
    /// Points so far on this branch.
    pub points: usize,
    /// Speed of the last point [m/s].
    pub u: f64,
    /// Its pitch amplitude \[rad\].
    pub amplitude_alpha: f64,
}

/// The quantities of an orbit a measured point is compared with.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OrbitValues {
    /// Speed U [m/s].
    pub u: f64,
    /// First-harmonic pitch amplitude \[rad\].
    pub amplitude1_alpha: f64,
    /// First-harmonic heave amplitude \[m\] (positive down).
    pub amplitude1_h: f64,
    /// Frequency \[Hz\].
    pub frequency_hz: f64,
}
