//! What one catalogue effect carries: its name and level, its fit at each level it applies
//! to, its term in the equations of motion, and its injection and draw range for the
//! withheld-effect benchmark. Each effect implements [`Entry`] in its own file of
//! [`super`]; the levels reach it through [`crate::Effect::entry`].

use aeroelastic::effects::{Form, InjectedEffect};
use aeroelastic::section::Section;

use super::{Effect, Level};
use crate::bifurcation::candidates::{BranchCandidate, Scales};
use crate::force::candidates::ForceFit;
use crate::system::candidates::SystemTerm;

/// One effect of the catalogue (DESIGN.md §5). Every method but the three names has a
/// default: an effect that does not apply at a level returns `None` (or nothing) there.
pub(crate) trait Entry: Sync {
    /// The fixed catalogue name (`static_offset`, …; equal to the serde name of
    /// [`Effect`]).
    fn name(&self) -> &'static str;

    /// A short column label for tables (`offset`, `mass`, …).
    fn short_label(&self) -> &'static str;

    /// The level the effect acts at.
    fn level(&self) -> Level;

    /// Whether the system level may score the effect on free runs outside the forced
    /// range (see [`Effect::scored_beyond_coverage`]): the structural effects by default.
    fn scored_beyond_coverage(&self) -> bool {
        self.level() == Level::Structural
    }

    /// A simpler effect whose terms this one holds (the verdict's one-standard-error rule
    /// takes the simpler one when it is as good).
    fn extends(&self) -> Option<Effect> {
        None
    }

    /// The effect's fit at the force level (forced-motion records).
    fn force(&self) -> Option<&dyn ForceFit> {
        None
    }

    /// The effect's terms at the system level (free-response records) and in the
    /// augmented simulation.
    fn system(&self) -> Option<&dyn SystemTerm> {
        None
    }

    /// The effect's candidates at the bifurcation level, for the nominal section `base`
    /// and the measured amplitudes `s`, simplest first. A candidate may extend one of
    /// this effect's earlier candidates or one of an effect it [`Entry::extends`]
    /// ([`BranchCandidate::extends_key`]).
    fn bifurcation(&self, base: &Section, s: Scales) -> Vec<BranchCandidate> {
        let _ = (base, s);
        Vec::new()
    }

    /// Why the effect is not fitted at the bifurcation level, when it could be expected
    /// there (written in the bifurcation document's `not_fitted`).
    fn not_at_bifurcation(&self) -> Option<&'static str> {
        None
    }

    /// The effect's injection for the withheld-effect generator.
    fn draw(&self) -> Option<&dyn Draw> {
        None
    }
}

/// What a draw of the withheld-effect generator knows beyond the effect's own parameter.
#[derive(Debug, Clone, Copy)]
pub struct DrawContext {
    /// The rig's mass matrix [[m, S], [S, I]] per unit span.
    pub rig: [[f64; 2]; 2],
    /// Section depth D \[m\] (the shedding length).
    pub depth: f64,
    /// Elastic axis of the truth in chords from the leading edge.
    pub x_ea: f64,
    /// The set's seed (for draws of signs and forms).
    pub seed: u64,
}

/// An effect's injection into the withheld-effect generator's truth.
pub(crate) trait Draw: Sync {
    /// `true` for the nine effects of DESIGN.md §5 that the generator injects by default
    /// ([`Effect::generated`]); `false` for effects drawn only when asked by name.
    fn generated(&self) -> bool {
        true
    }

    /// The parameter drawn in `form`: (name with unit, value at strength 0, value at
    /// strength 1); the draw is log-uniform between them ([`log_map`]).
    fn range(&self, form: Form) -> (&'static str, f64, f64);

    /// Whether the truth records the drawn parameter itself (name from [`Draw::range`])
    /// before the ones [`Draw::inject`] returns.
    fn writes_drawn(&self) -> bool {
        true
    }

    /// The injected effect at parameter value `p` (strength `s` ∈ [0, 1], from
    /// [`Draw::range`]) and the further parameters written in the truth (name with unit,
    /// value).
    fn inject(
        &self,
        p: f64,
        s: f64,
        form: Form,
        cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>);
}

/// Log-uniform map of s ∈ [0, 1] onto [lo, hi] (lo, hi of the same sign).
pub fn log_map(s: f64, lo: f64, hi: f64) -> f64 {
    lo * (hi / lo).powf(s)
}
