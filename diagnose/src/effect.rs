//! The effect catalogue's names (DESIGN.md §5; each effect's entry is in
//! `crate::catalogue`) and the verdicts a diagnosis can reach.

use serde::{Deserialize, Serialize};

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

/// A candidate unmodelled effect of the catalogue (DESIGN.md §5, fixed names).
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
    /// Mean angle offset α₀ (the model sits at α + α₀ when the rig reads α): DC forces and,
    /// through the nonlinear terms, even harmonics.
    StaticOffset,
    /// Acceleration-proportional forces M_a q̈ as left by an imperfect wind–no-wind
    /// subtraction: absorbed by derivatives at the forcing frequency, visible across
    /// reduced frequency, as U → 0 and in free response.
    AddedMass,
    /// Forces lag the motion by a delay τ: a phase ωτ absorbed by derivatives at the forcing
    /// frequency, visible across frequencies and in free response.
    TimeDelay,
    /// Force terms outside the Eq. 19 library (quintic, cross-DOF…): harmonics beyond the
    /// third, amplitude dependence steeper than cubic.
    HigherOrder,
    /// Flow separation above a critical angle with lag and hysteresis: residuals that
    /// switch on above an amplitude threshold, many harmonics, loops in (α, C_M).
    DynamicStall,
    /// Narrow-band forcing at a Strouhal frequency f = St·U/D that moves with U and is not a
    /// combination tone of the motion.
    VortexShedding,
    /// Cubic structural stiffness (hardening or softening): amplitude-dependent frequency in
    /// free response, forced residuals clean.
    StructuralCubic,
    /// Pitch freeplay (a dead band of the spring): frequency falls at small amplitude.
    Freeplay,
    /// Dry (Coulomb) friction in the supports: linear, not exponential, amplitude decay.
    Friction,
    /// Structural stiffness polynomial with even and odd terms, k₂q² + k₃q³ per DOF (an
    /// asymmetric or softening–hardening spring: a subcritical Hopf with a fold).
    StructuralPolynomial,
    /// Amplitude-dependent structural damping, c₂q²q̇ per DOF (damping that grows with
    /// amplitude, the opposite trend of dry friction).
    StructuralDamping,
    /// A scale on the aerodynamic lift and moment (a 2-D model on a finite rig: tip
    /// losses, an uncertain effective span). Fitted at the bifurcation level only.
    AerodynamicScale,
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

/// The outcome of a diagnosis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Verdict {
    /// One catalogue effect explains the gap.
    Effect(Effect),
    /// The gap is at noise level.
    None,
    /// A significant gap that no candidate removes.
    Unexplained,
    /// A significant free-response gap that lies where the sim's tables are extrapolated
    /// (free runs outside the K or amplitude range of the forced cases, covered runs
    /// clean): a campaign to extend, not an unmodelled effect.
    Extrapolation,
}

impl Verdict {
    /// `verdict.effect` of `diagnosis.json`: a catalogue name, `none`, `unexplained` or
    /// `extrapolation`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Effect(e) => e.name(),
            Verdict::None => "none",
            Verdict::Unexplained => "unexplained",
            Verdict::Extrapolation => "extrapolation",
        }
    }

    /// A short column label for tables: [`Effect::short_label`], `none`, `unexpl`, `extrap`.
    pub fn short_label(self) -> &'static str {
        match self {
            Verdict::Effect(e) => e.short_label(),
            Verdict::None => "none",
            Verdict::Unexplained => "unexpl",
            Verdict::Extrapolation => "extrap",
        }
    }

    /// `verdict.level` of `diagnosis.json` (`structural` for `extrapolation`: a
    /// free-response finding).
    pub fn level(self) -> Level {
        match self {
            Verdict::Effect(e) => e.level(),
            Verdict::Extrapolation => Level::Structural,
            _ => Level::None,
        }
    }

    /// The verdict of a `verdict.effect` name.
    ///
    /// # Errors
    /// [`Error::UnknownEffect`] for anything else.
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "none" => Ok(Verdict::None),
            "unexplained" => Ok(Verdict::Unexplained),
            "extrapolation" => Ok(Verdict::Extrapolation),
            _ => Effect::from_name(name).map(Verdict::Effect),
        }
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Verdict {
    /// Every verdict: the catalogue's effects, then `none`, `unexplained`, `extrapolation`.
    pub fn all() -> impl Iterator<Item = Verdict> {
        Effect::ALL.into_iter().map(Verdict::Effect).chain([
            Verdict::None,
            Verdict::Unexplained,
            Verdict::Extrapolation,
        ])
    }
}

/// Written as its [`Verdict::name`] (`"added_mass"`, `"none"`, …): `verdict.effect` of
/// diagnosis.json and `verdict` of a benchmark outcome.
impl Serialize for Verdict {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// Read from its [`Verdict::name`]; any other string is an error naming it.
impl<'de> Deserialize<'de> for Verdict {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        Verdict::from_name(&s).map_err(serde::de::Error::custom)
    }
}

/// A string enum of every [`Verdict::name`].
impl schemars::JsonSchema for Verdict {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Verdict".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let names: Vec<&str> = Verdict::all().map(Verdict::name).collect();
        schemars::json_schema!({
            "description": "A catalogue effect, `none` (gap at noise level), `unexplained` \
                (a significant gap no candidate removes) or `extrapolation` (the gap lies \
                on free runs outside the forced range).",
            "type": "string",
            "enum": names,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_are_unique() {
        let mut names: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
        for e in Effect::ALL {
            assert_eq!(Effect::from_name(e.name()).unwrap(), e);
            assert_eq!(Verdict::from_name(e.name()).unwrap(), Verdict::Effect(e));
        }
        names.sort();
        names.dedup();
        assert_eq!(names.len(), 12);
        assert_eq!(Verdict::from_name("none").unwrap(), Verdict::None);
        assert_eq!(
            Verdict::from_name("unexplained").unwrap().level(),
            Level::None
        );
        let e = Effect::from_name("stall").unwrap_err().to_string();
        assert!(e.contains("stall") && e.contains("dynamic_stall"), "{e}");
    }

    #[test]
    fn structural_effects_are_the_five_structural_ones() {
        let s: Vec<Effect> = Effect::ALL
            .into_iter()
            .filter(|e| e.level() == Level::Structural)
            .collect();
        assert_eq!(
            s,
            [
                Effect::StructuralCubic,
                Effect::Freeplay,
                Effect::Friction,
                Effect::StructuralPolynomial,
                Effect::StructuralDamping
            ]
        );
    }
}
