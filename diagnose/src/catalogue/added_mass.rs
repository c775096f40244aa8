//! `added_mass`: acceleration-proportional forces M_a q̈ as left by an imperfect
//! wind–no-wind subtraction: absorbed by derivatives at the forcing frequency, visible
//! across reduced frequency, as U → 0 and in free response.
//!
//! * Force level: Z = [B²α̈/U², Bḧ/U²] (acceleration forces with a mass shared across U).
//! * System level: ΔM q̈ with a general 2×2 ΔM (4 coefficients: a mass error or a spurious
//!   apparent mass of the identified law).
//! * Bifurcation level: Δm added to the heaving mass, ΔI_α to the pitch inertia.
//! * Generator: 0.2 %–20 % of the rig's mass matrix (primary form) or 0.05–5 × the air's
//!   apparent mass (alternate).

use aeroelastic::effects::{Form, InjectedEffect};
use aeroelastic::section::Section;

use super::entry::{Draw, DrawContext, Entry};
use crate::bifurcation::candidates::{param, BranchCandidate, Change, Scales};
use super::{Effect, Level};
use crate::force::candidates::{shared, Context, ForceFit, Scored};
use crate::force::data::CaseData;
use crate::system::candidates::{kept, Column, SystemTerm};
use crate::system::residual::RunResidual;

/// The `added_mass` entry.
pub(crate) struct AddedMass;

impl Entry for AddedMass {
    fn name(&self) -> &'static str {
        "added_mass"
    }
    fn short_label(&self) -> &'static str {
        "mass"
    }
    fn level(&self) -> Level {
        Level::Aerodynamic
    }
    fn force(&self) -> Option<&dyn ForceFit> {
        Some(self)
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn bifurcation(&self, base: &Section, _s: Scales) -> Vec<BranchCandidate> {
        let st = &base.structure;
        vec![BranchCandidate::new(
            Effect::AddedMass,
            "heave+pitch",
            vec![
                param(
                    "added_mass",
                    "kg",
                    "mass added to the heaving mass m",
                    0.1 * st.mass,
                ),
                param(
                    "added_inertia",
                    "kg m^2",
                    "inertia added to I_α about the elastic axis",
                    0.1 * st.inertia_alpha,
                ),
            ],
            None,
            Change::AddedMass,
        )]
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl ForceFit for AddedMass {
    fn fit(&self, cx: &Context<'_>) -> Scored {
        shared(cx, &|c: &CaseData, _| c.accelerations().to_vec())
    }
}

impl SystemTerm for AddedMass {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &["dM_hh_kg_per_m", "dM_ha_kg", "dM_ah_kg", "dM_aa_kg_m"]
    }
    fn columns(&self, _grid: &[f64], run: &RunResidual, _rho: f64, _chord: f64) -> Vec<Column> {
        let (hdd, add) = (kept(run, &run.qdd[0]), kept(run, &run.qdd[1]));
        vec![
            [hdd.clone(), Vec::new()],
            [add.clone(), Vec::new()],
            [Vec::new(), hdd],
            [Vec::new(), add],
        ]
    }
    fn convention(&self) -> &'static str {
        "extra force dM·q̈ on the right of M q̈ + C q̇ + K q = F: dM < 0 is mass the \
         sim lacks (e.g. apparent mass), dM > 0 mass it has too much of"
    }
    fn mass(&self, theta: &[f64]) -> [[f64; 2]; 2] {
        [[theta[0], theta[1]], [theta[2], theta[3]]]
    }
}

impl Draw for AddedMass {
    fn range(&self, form: Form) -> (&'static str, f64, f64) {
        match form {
            Form::Primary => ("fraction of rig mass [-]", 0.002, 0.2),
            Form::Alternate => ("fraction of air apparent mass [-]", 0.05, 5.0),
        }
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::AddedMass {
                fraction: p,
                rig: cx.rig,
            },
            Vec::new(),
        )
    }
}
