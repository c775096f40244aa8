//! The virtual wind tunnel (DESIGN.md §4): forced-motion and free-response records from
//! any [`AeroModel`](crate::aero::AeroModel), written as data sets (DATA_FORMAT.md) with
//! [`identify::dataset::write_dataset`].
//!
//! **Forced mode.** Prescribed h(t), α(t) (sums of sines: the paper's two-frequency
//! campaign, Tables I–II, or any multi-sine). Forces L, M = M_a q̈ + f(q, q̇, x) with the
//! model's lag states x integrated along the prescribed motion by classical RK4 (step
//! ≤ 0.05 / max(‖G‖∞, ω_max)); x starts **on the periodic solution** of the linearised lag
//! dynamics ẋ = E q + F q̇ + G x (exact for every model of this crate, whose lag dynamics
//! are linear), so no transient has to die out; an optional pre-roll integrates a further
//! `pre_roll` seconds before recording (for models with nonlinear lag dynamics). A model
//! whose coefficients depend on K
//! ([`AeroModel::with_reduced_frequency`](crate::aero::AeroModel::with_reduced_frequency))
//! is evaluated at the forcing K_α = Bω_α/U of the case (largest pitch component).
//!
//! **Sensor noise** like the paper's rig ([`SensorNoise`]): an absolute balance noise σ =
//! 0.1 % of the balance's range (±65 N, ±5 N·m: σ = 0.065 N, 0.005 N·m over the span),
//! readings quantised to the balance's resolution ([`BalanceNoise`]; the earlier model,
//! σ = 1e-3 × each record's peak |force|, is [`SensorNoise::paper_relative`]), laser
//! σ_h = 8 µm on h, and the
//! corresponding pitch noise σ_α = 2σ_h/s for two lasers s apart (α from their difference,
//! h from their mean: σ_laser = √2 σ_h, σ_α = √2 σ_laser / s); s defaults to the chord.
//!
//! **Still-air runs** ([`StillAir`]): the balance reads aerodynamic + inertial forces;
//! inertial = (m ḧ + S α̈, S ḧ + I α̈) from the rig's mass properties ([`RigMass`]). The
//! wind-on file then holds aerodynamic + inertial forces and the still-air file (named by
//! the case's `nowind_file`) the inertial forces of the same motion recorded with a random
//! time offset τ ∈ [0, 2·`max_offset`] (its record is 2·`max_offset` longer, so it covers
//! the whole wind-on record after alignment). Physically a still-air run also contains the
//! U-independent apparent-mass forces M_a q̈, so that wind − no-wind removes them from the
//! identified law; that is off by default (`apparent_mass = false`) and documented as a
//! sim-to-real effect.
//!
//! **Free mode.** The section on springs in the flow at a list of U, from an initial
//! perturbation, integrated by RK4 ([`crate::integrate::rk4`]) at `substeps` steps per
//! sample (Dop853's dense output
//! is unreliable in ode_solvers 0.6, see DESIGN notes), recording h and α (and optionally
//! L, M) as `kind = "free"` cases with the manifest `[structure]` table filled; a run that
//! leaves the bound is truncated there and the time is recorded in the case's `[extra]`.
//!
//! **Seeds.** Every random draw comes from a `ChaCha8Rng` seeded per case with
//! [`case_seed`]`(seed, index)`; the master seed (as a string, u64 is wider than TOML's
//! integers) is in the manifest's `[extra]`, each case's seed and still-air offset in the
//! case's `[extra]`.
//!
//! **Files.** `motion.rs` holds the motions and campaigns, `noise.rs` the sensor noise,
//! `forced.rs` and `free.rs` the two kinds of record and their data sets, `write.rs` the
//! units, manifest entries and writing; this one the progress report and the case seeds.

mod forced;
mod free;
mod motion;
mod noise;
mod plan;
mod write;

pub use forced::{forced_dataset, forced_forces, forced_record, ForcedOptions, RigMass, StillAir};
pub use free::{free_dataset, free_record, FreeOptions, FreeRun};
pub use motion::{
    caption_configurations, paper_configurations, reconstructed_configurations, Campaign,
    CampaignName, Configuration, ForcedCase, Motion, Sine,
};
pub use noise::{add_noise, peak, BalanceNoise, SensorNoise};
pub use plan::{CampaignPlan, PlanRow, PLAN_FORMAT};
pub use write::{paper_units, write};

/// Progress of a tunnel run, after each case.
#[derive(Debug, Clone, PartialEq)]
pub struct TunnelProgress {
    /// Cases done.
    pub done: usize,
    /// Total cases.
    pub total: usize,
    /// Id of the case just finished.
    pub id: String,
}

/// Seed of case `index` from the master seed (SplitMix64 of seed + (index+1)·φ·2⁶⁴), so
/// that cases are independent and the data set does not depend on the thread count.
pub fn case_seed(seed: u64, index: usize) -> u64 {
    identify::numerics::split_seed(seed, index as u64)
}
