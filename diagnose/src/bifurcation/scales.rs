//! The measured diagram's reference amplitudes ([`Scales`]) that scale the candidates'
//! parameters: below both `bifurcation::candidates` and the catalogue that draws them, so
//! the catalogue does not import the candidates' module that imports its `Effect` (issue
//! 40, docs/DECISIONS.md "No import circles, checked").

use serde::{Deserialize, Serialize};

/// Reference amplitudes of the measured diagram: the largest pitch \[rad\] and heave \[m\]
/// amplitudes (a default where a DOF is not measured).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Scales {
    /// Pitch \[rad\].
    pub alpha: f64,
    /// Heave \[m\].
    pub h: f64,
}
