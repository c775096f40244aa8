//! The verdicts a diagnosis can reach. The effect names ([`Effect`]) and their levels
//! ([`Level`]) are the catalogue's (`crate::catalogue`, DESIGN.md §5): its registry
//! generates [`Effect`], one variant per entry.

use serde::{Deserialize, Serialize};

pub use crate::catalogue::{log_map, DrawContext, Effect, Level};
use crate::Result;

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
    /// [`crate::Error::UnknownEffect`] for anything else.
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
        assert_eq!(names.len(), Effect::ALL.len());
        assert_eq!(Verdict::from_name("none").unwrap(), Verdict::None);
        assert_eq!(
            Verdict::from_name("unexplained").unwrap().level(),
            Level::None
        );
        let e = Effect::from_name("stall").unwrap_err().to_string();
        assert!(e.contains("stall") && e.contains("dynamic_stall"), "{e}");
    }

    #[test]
    fn structural_effects_leave_forced_residuals_clean() {
        // DESIGN.md §5: a structural effect changes only the restoring forces, so it has
        // no force-level fit, and its evidence is the free response.
        for e in Effect::ALL
            .into_iter()
            .filter(|e| e.level() == Level::Structural)
        {
            assert!(e.entry().force().is_none(), "{e}");
        }
        for e in [
            Effect::StructuralCubic,
            Effect::Freeplay,
            Effect::Friction,
            Effect::StructuralPolynomial,
            Effect::StructuralDamping,
        ] {
            assert_eq!(e.level(), Level::Structural, "{e}");
        }
    }
}
