//! The effect catalogue (DESIGN.md §5), one file per effect. Each file holds one
//! [`Entry`]: the effect's name and level, its fit at every level it applies to (force,
//! system, bifurcation), its term in the augmented simulation and its injection for the
//! withheld-effect generator. The levels and the benchmark reach an effect only through
//! [`Effect::entry`].
//!
//! **Adding an effect**: a variant of [`Effect`] (its serde name is the catalogue name),
//! one new file here implementing [`Entry`] (and the level traits it applies to), and one
//! line in the registry below. Registration order is the order of [`Effect::ALL`], in
//! which every level scores and reports its candidates.

mod entry;

pub(crate) use entry::{log_map, DrawContext, Entry};

use aeroelastic::section::Section;

use crate::bifurcation::candidates::Scales;
use crate::effect::{Effect, Level};

macro_rules! registry {
    ($($variant:ident => $module:ident :: $entry:ident),* $(,)?) => {
        $(mod $module;)*

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
    StaticOffset => static_offset::StaticOffset,
    AddedMass => added_mass::AddedMass,
    TimeDelay => time_delay::TimeDelay,
    HigherOrder => higher_order::HigherOrder,
    DynamicStall => dynamic_stall::DynamicStall,
    VortexShedding => vortex_shedding::VortexShedding,
    StructuralCubic => structural_cubic::StructuralCubic,
    Freeplay => freeplay::Freeplay,
    Friction => friction::Friction,
    StructuralPolynomial => structural_polynomial::StructuralPolynomial,
    StructuralDamping => structural_damping::StructuralDamping,
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
        assert_eq!(Effect::drawable().len(), 11);
    }

    #[test]
    fn every_effect_applies_somewhere() {
        for e in Effect::ALL {
            let en = e.entry();
            assert!(
                en.force().is_some() || en.system().is_some() || en.name() == "aerodynamic_scale",
                "{e}"
            );
            if let Some(x) = en.extends() {
                assert_eq!(x.level(), e.level(), "{e} extends {x}");
            }
        }
    }
}
