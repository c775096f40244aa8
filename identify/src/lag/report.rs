//! The held-out comparison's document types (below both [`super::fit`](mod@super::fit), whose report
//! carries one, and [`super::holdout`], which computes it).

use serde::{Deserialize, Serialize};

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
