//! The settings of a continuation ([`BranchOptions`]) and the discretisation of its
//! periodic orbits ([`BranchMethod`]), with their checks against the limits table.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};
use identify::limits::MAX_HARMONICS;

/// Settings of the continuation. Scaled variables: the state is divided by
/// `amplitude_scale` times the Hopf eigenvector's magnitude of each component (pitch
/// normalised to 1), T by 0.1 T_Hopf, U by 0.1 U_Hopf; Δs is measured in these units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchOptions {
    /// How each periodic orbit is discretised (DECISIONS.md: harmonic balance is the
    /// faster, shooting the reference).
    #[serde(default)]
    pub method: BranchMethod,
    /// Harmonics H of the harmonic-balance series (ignored by shooting).
    #[serde(default = "default_harmonics")]
    pub harmonics: usize,
    /// Fixed steps per period: RK4 steps of the shooting integration, or the steps of the
    /// variational equation that gives harmonic balance its Floquet multipliers (RK4, or
    /// the exponential trapezoidal rule of the condensed form for linear aerodynamics).
    pub steps_per_period: usize,
    /// Largest number of branch points per Hopf point.
    pub max_points: usize,
    /// Initial arclength step (scaled).
    pub ds: f64,
    /// Smallest arclength step before the branch is declared not converging.
    pub ds_min: f64,
    /// Largest arclength step.
    pub ds_max: f64,
    /// Newton tolerance on the scaled residual (max norm).
    pub newton_tol: f64,
    /// Newton iterations per point before the step is halved.
    pub max_newton: usize,
    /// Pitch amplitude of the first orbit, started from the Hopf eigenvector \[rad\].
    pub start_amplitude: f64,
    /// Reference pitch amplitude of the scaling \[rad\].
    pub amplitude_scale: f64,
    /// The branch stops when the pitch amplitude exceeds this \[rad\].
    pub max_amplitude_alpha: f64,
    /// Speeds of the Hopf scan over the range (sign of det(2A⊙I); each bracket then solved
    /// by regula falsi).
    pub n_scan: usize,
}

/// Discretisation of the periodic orbits of a branch.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum BranchMethod {
    /// Single shooting: the flow over one period by fixed RK4 steps; multipliers from the
    /// finite-difference monodromy matrix.
    #[default]
    Shooting,
    /// Harmonic balance (AFT) with `harmonics` harmonics; multipliers from the variational
    /// equation along the series. With linear aerodynamics independent of K it is condensed
    /// onto heave and pitch (DECISIONS.md).
    HarmonicBalance,
}

impl std::str::FromStr for BranchMethod {
    type Err = Error;

    /// A method by its serde name, `shooting` or `harmonic_balance` (`-` read as `_`).
    ///
    /// # Errors
    /// [`Error::Toml`] (source `method`) naming the unknown value and the known ones.
    fn from_str(s: &str) -> Result<Self> {
        use serde::de::IntoDeserializer;
        let name = s.replace('-', "_");
        let d: serde::de::value::StrDeserializer<serde::de::value::Error> =
            name.as_str().into_deserializer();
        Self::deserialize(d).map_err(|e| Error::Toml {
            source_name: "method".into(),
            message: e.to_string(),
        })
    }
}

fn default_harmonics() -> usize {
    5
}

impl Default for BranchOptions {
    fn default() -> Self {
        BranchOptions {
            method: BranchMethod::default(),
            harmonics: default_harmonics(),
            steps_per_period: 128,
            max_points: 200,
            ds: 0.05,
            ds_min: 1e-5,
            ds_max: 0.5,
            newton_tol: 1e-9,
            max_newton: 8,
            start_amplitude: 1e-3,
            amplitude_scale: 0.05,
            max_amplitude_alpha: 0.6,
            n_scan: 200,
        }
    }
}

impl BranchOptions {
    /// Checks the options.
    ///
    /// Counts are capped by the limits table (`identify::limits`: steps per period, points,
    /// scan speeds, Newton iterations, harmonics) so that no request allocates without bound.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad option and its allowed range.
    pub fn check(&self) -> Result<()> {
        use crate::error::positive;
        positive("branch.ds", self.ds)?;
        positive("branch.ds_min", self.ds_min)?;
        positive("branch.ds_max", self.ds_max)?;
        positive("branch.newton_tol", self.newton_tol)?;
        positive("branch.start_amplitude", self.start_amplitude)?;
        positive("branch.amplitude_scale", self.amplitude_scale)?;
        positive("branch.max_amplitude_alpha", self.max_amplitude_alpha)?;
        if self.ds_min > self.ds || self.ds > self.ds_max {
            return Err(Error::param(
                "branch.ds",
                self.ds,
                format!(
                    "must lie in [ds_min, ds_max] = [{}, {}]",
                    self.ds_min, self.ds_max
                ),
            ));
        }
        use identify::limits as l;
        for (name, v, min, max) in [
            (
                "branch.steps_per_period",
                self.steps_per_period,
                16,
                l::MAX_STEPS_PER_PERIOD,
            ),
            (
                "branch.max_points",
                self.max_points,
                2,
                l::MAX_BRANCH_POINTS,
            ),
            (
                "branch.max_newton",
                self.max_newton,
                2,
                l::MAX_NEWTON_ITERATIONS,
            ),
            ("branch.n_scan", self.n_scan, 2, l::MAX_SCAN_SPEEDS),
            ("branch.harmonics", self.harmonics, 1, MAX_HARMONICS),
        ] {
            if v < min || v > max {
                return Err(Error::param(
                    name,
                    v as f64,
                    format!("must lie in {min} … {max}"),
                ));
            }
        }
        Ok(())
    }
}
