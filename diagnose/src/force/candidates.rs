//! Candidate augmentations of the force level (generic forms, fitted on training folds,
//! scored on held-out folds).

use crate::effect::Effect;

use super::data::{CaseData, Node};
use super::{Fold, ForceOptions};

/// Default significance threshold (see module docs).
pub const DEFAULT_SIGNIFICANCE: f64 = 3.0;
/// Default minimum share of the excess residual energy removed.
pub const DEFAULT_MIN_SHRINK: f64 = 0.3;

/// The candidate augmentations of the force level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CandidateKind {
    /// DC force per dynamic pressure plus even terms, shared across wind speeds.
    StaticOffset,
    /// Shared acceleration terms.
    AddedMass,
    /// A shared time shift of the forces.
    TimeDelay,
    /// Sparse terms outside the library (quintic, quartic cross-DOF).
    HigherOrder,
    /// Threshold-activated regressors with a first-order lag.
    DynamicStall,
    /// A line at f = S·U/B.
    VortexShedding,
}

impl CandidateKind {
    /// Every candidate.
    pub const ALL: [CandidateKind; 6] = [
        CandidateKind::StaticOffset,
        CandidateKind::AddedMass,
        CandidateKind::TimeDelay,
        CandidateKind::HigherOrder,
        CandidateKind::DynamicStall,
        CandidateKind::VortexShedding,
    ];

    /// The catalogue effect the candidate stands for.
    pub fn effect(self) -> Effect {
        match self {
            CandidateKind::StaticOffset => Effect::StaticOffset,
            CandidateKind::AddedMass => Effect::AddedMass,
            CandidateKind::TimeDelay => Effect::TimeDelay,
            CandidateKind::HigherOrder => Effect::HigherOrder,
            CandidateKind::DynamicStall => Effect::DynamicStall,
            CandidateKind::VortexShedding => Effect::VortexShedding,
        }
    }
}

/// A scored candidate: its held-out residuals and fitted parameters.
#[derive(Debug, Clone)]
pub(crate) struct Scored {
    pub kind: CandidateKind,
    pub residuals: Vec<[Vec<f64>; 2]>,
    pub n_params: usize,
    pub n_nuisance: usize,
    pub parameters: Vec<(String, f64)>,
    pub failure: Option<String>,
}

/// Scores every candidate of `opts`.
pub(crate) fn score_all(
    _cases: &[CaseData],
    _nodes: &[Node],
    _folds: &[Fold],
    _before: &[[Vec<f64>; 2]],
    _opts: &ForceOptions,
) -> Vec<Scored> {
    Vec::new()
}
