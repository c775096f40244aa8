//! The effect catalogue (DESIGN.md §5), one file per effect. Each file holds one
//! [`Entry`]: the effect's name and level, its fit at every level it applies to (force,
//! system, bifurcation), its term in the augmented simulation and its injection for the
//! withheld-effect generator. The levels and the benchmark reach an effect only through
//! [`Effect::entry`].
//!
//! **Adding an effect**: one new file here implementing [`Entry`] (and the level traits
//! it applies to), and one line (with its doc comment) in the registry below, which
//! generates the [`Effect`] variant, [`Effect::ALL`] and [`Effect::entry`]. The variant's
//! serde name is the catalogue name; registration order is the order of [`Effect::ALL`],
//! in which every level scores and reports its candidates.

mod entry;

pub(crate) use entry::Entry;
pub use entry::{log_map, DrawContext};

use aeroelastic::section::Section;
use serde::{Deserialize, Serialize};

use crate::bifurcation::scales::Scales;
use crate::{Error, Result};

/// Level at which an effect acts. `Aerodynamic` effects change the forces the section
/// feels (or the forces the balance reports); `Structural` effects change only the
/// structure's restoring forces, so they leave forced-motion residuals clean and show in
/// free response only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// Aerodynamic forces (including balance artefacts such as an imperfect wind–no-wind
    /// subtraction).
    Aerodynamic,
    /// Structural restoring forces (springs, gaps, friction).
    Structural,
    /// No effect (verdict `none` or `unexplained`).
    None,
}

impl Level {
    /// The name written in `diagnosis.json`.
    pub fn name(self) -> &'static str {
        match self {
            Level::Aerodynamic => "aerodynamic",
            Level::Structural => "structural",
            Level::None => "none",
        }
    }
}

macro_rules! registry {
    ($($(#[$doc:meta])* $variant:ident => $module:ident :: $entry:ident),* $(,)?) => {
        $(mod $module;)*

        /// A candidate unmodelled effect of the catalogue (DESIGN.md §5, fixed names),
        /// one variant per registered entry.
        #[derive(
            Debug,
            Clone,
            Copy,
            PartialEq,
            Eq,
            Hash,
            PartialOrd,
            Ord,
            Serialize,
            Deserialize,
            schemars::JsonSchema,
        )]
        #[serde(rename_all = "snake_case")]
        pub enum Effect {
            $($(#[$doc])* $variant,)*
        }

        impl Effect {
            /// The whole catalogue in registration order: DESIGN.md §5's nine effects,
            /// then the structural polynomial, amplitude-dependent damping and the
            /// aerodynamic scale added for real rigs.
            pub const ALL: [Effect; [$(Effect::$variant),*].len()] = [$(Effect::$variant),*];

            /// The effect's catalogue entry.
            pub(crate) fn entry(self) -> &'static dyn Entry {
                match self {
                    $(Effect::$variant => &$module::$entry,)*
                }
            }
        }
    };
}

registry! {
    /// Mean angle offset α₀ (the model sits at α + α₀ when the rig reads α): DC forces and,
    /// through the nonlinear terms, even harmonics.
    StaticOffset => static_offset::StaticOffset,
    /// Acceleration-proportional forces M_a q̈ as left by an imperfect wind–no-wind
    /// subtraction: absorbed by derivatives at the forcing frequency, visible across
    /// reduced frequency, as U → 0 and in free response.
    AddedMass => added_mass::AddedMass,
    /// Forces lag the motion by a delay τ: a phase ωτ absorbed by derivatives at the forcing
    /// frequency, visible across frequencies and in free response.
    TimeDelay => time_delay::TimeDelay,
    /// Force terms outside the Eq. 19 library (quintic, cross-DOF…): harmonics beyond the
    /// third, amplitude dependence steeper than cubic.
    HigherOrder => higher_order::HigherOrder,
    /// Flow separation above a critical angle with lag and hysteresis: residuals that
    /// switch on above an amplitude threshold, many harmonics, loops in (α, C_M).
    DynamicStall => dynamic_stall::DynamicStall,
    /// Narrow-band forcing at a Strouhal frequency f = St·U/D that moves with U and is not a
    /// combination tone of the motion.
    VortexShedding => vortex_shedding::VortexShedding,
    /// Cubic structural stiffness (hardening or softening): amplitude-dependent frequency in
    /// free response, forced residuals clean.
    StructuralCubic => structural_cubic::StructuralCubic,
    /// Pitch freeplay (a dead band of the spring): frequency falls at small amplitude.
    Freeplay => freeplay::Freeplay,
    /// Dry (Coulomb) friction in the supports: linear, not exponential, amplitude decay.
    Friction => friction::Friction,
    /// Structural stiffness polynomial with even and odd terms, k₂q² + k₃q³ per DOF (an
    /// asymmetric or softening–hardening spring: a subcritical Hopf with a fold).
    StructuralPolynomial => structural_polynomial::StructuralPolynomial,
    /// Amplitude-dependent structural damping, c₂q²q̇ per DOF (damping that grows with
    /// amplitude, the opposite trend of dry friction).
    StructuralDamping => structural_damping::StructuralDamping,
    /// A scale on the aerodynamic lift and moment (a 2-D model on a finite rig: tip
    /// losses, an uncertain effective span). Fitted at the bifurcation level only.
    AerodynamicScale => aerodynamic_scale::AerodynamicScale,
}

impl Effect {
    /// The fixed catalogue name (`static_offset`, …).
    pub fn name(self) -> &'static str {
        self.entry().name()
    }

    /// A short column label for tables (`offset`, `mass`, …).
    pub fn short_label(self) -> &'static str {
        self.entry().short_label()
    }

    /// The level the effect acts at.
    pub fn level(self) -> Level {
        self.entry().level()
    }

    /// Whether the system level may score the effect on free runs outside the forced
    /// range (with the apparent-mass nuisance of those runs fitted alongside): true for
    /// the structural effects, and for a static offset, whose evidence is the runs' mean
    /// force (K = 0), which no error of the law's extrapolation in K can produce from the
    /// zero-mean response of an effect-free section. The other aerodynamic effects are
    /// scored on covered runs only (issue 29, DECISIONS "Static offsets scored beyond
    /// coverage").
    pub fn scored_beyond_coverage(self) -> bool {
        self.entry().scored_beyond_coverage()
    }

    /// The simpler effect whose terms this one holds (`structural_polynomial` holds
    /// `structural_cubic`'s), if any.
    pub fn extends(self) -> Option<Effect> {
        self.entry().extends()
    }

    /// The effects the withheld-effect generator injects by default (DESIGN.md §5's
    /// nine), in catalogue order.
    pub fn generated() -> Vec<Effect> {
        Effect::ALL
            .into_iter()
            .filter(|e| e.entry().draw().is_some_and(|d| d.generated()))
            .collect()
    }

    /// Every effect the generator can inject: [`Effect::generated`] and those drawn only
    /// when asked by name (`structural_polynomial`, `structural_damping`).
    pub fn drawable() -> Vec<Effect> {
        Effect::ALL
            .into_iter()
            .filter(|e| e.entry().draw().is_some())
            .collect()
    }

    /// The parameter the withheld-effect generator draws for this effect in `form`: (name
    /// with unit, value at strength 0, value at strength 1), log-uniform between them
    /// ([`log_map`]); `None` for an effect the generator cannot inject.
    pub fn draw_range(self, form: aeroelastic::effects::Form) -> Option<(&'static str, f64, f64)> {
        self.entry().draw().map(|d| d.range(form))
    }

    /// The generator's injection of this effect at parameter value `p` (strength `s` ∈
    /// [0, 1], from [`Effect::draw_range`]) and the parameters its truth records (name with
    /// unit, value): the drawn one first when the effect records it, then the effect's own.
    /// `None` for an effect the generator cannot inject.
    pub fn draw_injection(
        self,
        p: f64,
        s: f64,
        form: aeroelastic::effects::Form,
        cx: &DrawContext,
    ) -> Option<(aeroelastic::effects::InjectedEffect, Vec<(String, f64)>)> {
        let d = self.entry().draw()?;
        let (e, more) = d.inject(p, s, form, cx);
        let drawn = d.writes_drawn().then(|| (d.range(form).0.to_string(), p));
        Some((e, drawn.into_iter().chain(more).collect()))
    }
}

impl Effect {
    /// The effect of a catalogue name.
    ///
    /// # Errors
    /// [`Error::UnknownEffect`] listing the accepted names.
    pub fn from_name(name: &str) -> Result<Self> {
        Effect::ALL
            .into_iter()
            .find(|e| e.name() == name)
            .ok_or_else(|| Error::UnknownEffect {
                name: name.to_string(),
                expected: Effect::ALL.map(Effect::name).join(", "),
            })
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The forms of a structural term with one coefficient per DOF (heave 0, pitch 1):
/// pitch only, heave only, both.
fn dof_forms() -> Vec<(&'static str, Vec<usize>)> {
    vec![
        ("pitch", vec![1]),
        ("heave", vec![0]),
        ("pitch+heave", vec![0, 1]),
    ]
}

/// The heave stiffness that scales the bifurcation level's heave terms: k_h, at least
/// 1e-3 k_α / h_ref² (a rig without a heave spring).
fn heave_stiffness_scale(base: &Section, s: Scales) -> f64 {
    let st = &base.structure;
    st.k_h.max(1e-3 * st.k_alpha / (s.h * s.h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_names_are_the_serde_names() {
        for e in Effect::ALL {
            let json = serde_json::to_string(&e).unwrap();
            assert_eq!(json, format!("\"{}\"", e.name()), "{e:?}");
        }
    }

    #[test]
    fn generated_are_design_sections_nine() {
        use Effect::*;
        assert_eq!(
            Effect::generated(),
            [
                StaticOffset,
                AddedMass,
                TimeDelay,
                HigherOrder,
                DynamicStall,
                VortexShedding,
                StructuralCubic,
                Freeplay,
                Friction
            ]
        );
        let drawable = Effect::drawable();
        assert!(Effect::generated().iter().all(|e| drawable.contains(e)));
        assert!(drawable.contains(&StructuralPolynomial) && drawable.contains(&StructuralDamping));
    }

    #[test]
    fn every_effect_applies_somewhere() {
        let base = aeroelastic::reference::hp1_theodorsen();
        let s = Scales {
            alpha: 0.1,
            h: 0.01,
        };
        for e in Effect::ALL {
            let en = e.entry();
            let branch = en.bifurcation(&base, s);
            assert!(
                en.force().is_some() || en.system().is_some() || !branch.is_empty(),
                "{e} is fitted at no level"
            );
            assert!(
                branch.is_empty() || en.not_at_bifurcation().is_none(),
                "{e} has bifurcation candidates and a reason not to be fitted there"
            );
            if let Some(x) = en.extends() {
                assert_eq!(x.level(), e.level(), "{e} extends {x}");
            }
        }
    }
}
