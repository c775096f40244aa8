//! The held-out comparison's document types (below both [`super::fit`](mod@super::fit), whose report
//! carries one, and [`super::holdout`], which computes it).

use serde::{Deserialize, Serialize};

use crate::ensemble::Interval;

/// One held-out case: the memoryless law and the lag law side by side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HeldOutRow {
    /// Case id.
    pub id: String,
    /// Reduced frequency K = Bω/U.
    pub k: f64,
    /// Mean angle \[deg\].
    pub mean_deg: f64,
    /// Pitch amplitude \[deg\].
    pub amplitude_deg: f64,
    /// Memoryless law: R² of C_L.
    pub memoryless_r2_lift: f64,
    /// Memoryless law: R² of C_M.
    pub memoryless_r2_moment: f64,
    /// Lag law: R² of C_L.
    pub lag_r2_lift: f64,
    /// Lag law: R² of C_M.
    pub lag_r2_moment: f64,
}

/// The held-out comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HeldOutReport {
    /// The hold-out spec (`k=0.1` …).
    pub spec: String,
    /// Training case ids.
    pub training: Vec<String>,
    /// Held-out cases.
    pub rows: Vec<HeldOutRow>,
    /// Mean over held-out cases of the lift R²: (memoryless, lag).
    pub mean_r2_lift: [f64; 2],
    /// Mean over held-out cases of the moment R²: (memoryless, lag).
    pub mean_r2_moment: [f64; 2],
}

/// A constant's ensemble interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagParameterInterval {
    /// Name (`tau1`, `tau2`, `alpha_star`, `sharpness`).
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Median and percentile interval of the members' values.
    pub interval: Interval,
}

/// The ensemble of a lag-law fit ([`super::ensemble`]: residual block bootstrap).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagEnsemble {
    /// Members asked for.
    pub members: usize,
    /// Master seed of the draws (a string: a u64 does not fit every JSON reader).
    pub seed: String,
    /// Confidence level of the intervals.
    pub level: f64,
    /// Members whose fit was refused (not in the intervals).
    pub refused: usize,
    /// Intervals of τ₁, τ₂, α*, m.
    pub parameters: Vec<LagParameterInterval>,
}
