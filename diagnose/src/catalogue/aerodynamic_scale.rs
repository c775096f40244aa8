//! `aerodynamic_scale`: a scale on the aerodynamic lift and moment (a 2-D model on a
//! finite rig: tip losses, an uncertain effective span). Fitted at the bifurcation level
//! only: lift and moment, with their apparent mass, times 1 + s.

use aeroelastic::section::Section;

use super::entry::Entry;
use crate::bifurcation::candidates::{param, BranchCandidate, Change, Scales};
use super::{Effect, Level};

/// The `aerodynamic_scale` entry.
pub(crate) struct AerodynamicScale;

impl Entry for AerodynamicScale {
    fn name(&self) -> &'static str {
        "aerodynamic_scale"
    }
    fn short_label(&self) -> &'static str {
        "a.scale"
    }
    fn level(&self) -> Level {
        Level::Aerodynamic
    }
    fn bifurcation(&self, _base: &Section, _s: Scales) -> Vec<BranchCandidate> {
        vec![BranchCandidate::new(
            Effect::AerodynamicScale,
            "lift+moment",
            vec![param(
                "aero_scale_minus_1",
                "1",
                "aerodynamic lift and moment (with their apparent mass) times 1 + value \
                 (value < 0: less load than the 2-D model, e.g. a finite span)",
                0.1,
            )],
            None,
            Change::AeroScale,
        )]
    }
}
