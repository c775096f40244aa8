//! Units of the CSV columns (manifest `[units]`) and their conversion to SI per unit span.

use serde::{Deserialize, Serialize};

/// Unit of the heave column `h`. Heave is positive down.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum LengthUnit {
    /// Metre, `"m"`.
    #[default]
    M,
    /// Millimetre, `"mm"` (1 mm = 1e-3 m).
    Mm,
}

/// Unit of the pitch column `alpha` and of the manifest's `amplitude` and `mean_pitch`.
/// Pitch is positive nose-up.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum AngleUnit {
    /// Radian, `"rad"`.
    #[default]
    Rad,
    /// Degree, `"deg"` (1° = π/180 rad).
    Deg,
}

/// Unit of the lift column `lift`. Lift is positive down.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum ForceUnit {
    /// Newton, total over the span of the model, `"N"` (divided by `section.span` on reading).
    N,
    /// Newton per metre of span, `"N/m"`.
    #[default]
    NPerM,
}

/// Unit of the moment column `moment` (about the elastic axis, positive nose-up).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub enum MomentUnit {
    /// Newton metre, total over the span of the model, `"N*m"` (divided by `section.span`).
    Nm,
    /// Newton metre per metre of span, `"N*m/m"`.
    #[default]
    NmPerM,
}

/// Units of the CSV columns of every case of a data set (manifest `[units]`, all four
/// required). Time is always in seconds.
///
/// `Default` is SI per unit span (m, rad, N/m, N·m/m).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub struct Units {
    /// Unit of `h`.
    pub heave: LengthUnit,
    /// Unit of `alpha`, `amplitude`, `mean_pitch`.
    pub pitch: AngleUnit,
    /// Unit of `lift`.
    pub lift: ForceUnit,
    /// Unit of `moment`.
    pub moment: MomentUnit,
}

/// A unit spelled as a fixed string in the manifest.
pub(crate) trait UnitName: Sized + Copy + 'static {
    /// Every variant with its manifest spelling.
    const ALL: &'static [(Self, &'static str)];

    /// The manifest spelling.
    fn name(self) -> &'static str
    where
        Self: PartialEq,
    {
        Self::ALL
            .iter()
            .find(|(u, _)| *u == self)
            .map(|(_, s)| *s)
            .unwrap_or("?")
    }

    /// Parses the manifest spelling (exact, case-sensitive).
    fn from_name(s: &str) -> Option<Self> {
        Self::ALL.iter().find(|(_, n)| *n == s).map(|(u, _)| *u)
    }

    /// The allowed spellings, quoted and comma-separated, for error messages.
    fn allowed() -> String {
        Self::ALL
            .iter()
            .map(|(_, n)| format!("\"{n}\""))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl UnitName for LengthUnit {
    const ALL: &'static [(Self, &'static str)] = &[(LengthUnit::M, "m"), (LengthUnit::Mm, "mm")];
}
impl UnitName for AngleUnit {
    const ALL: &'static [(Self, &'static str)] =
        &[(AngleUnit::Rad, "rad"), (AngleUnit::Deg, "deg")];
}
impl UnitName for ForceUnit {
    const ALL: &'static [(Self, &'static str)] = &[(ForceUnit::N, "N"), (ForceUnit::NPerM, "N/m")];
}
impl UnitName for MomentUnit {
    const ALL: &'static [(Self, &'static str)] =
        &[(MomentUnit::Nm, "N*m"), (MomentUnit::NmPerM, "N*m/m")];
}

impl LengthUnit {
    /// The manifest spelling (`"m"` or `"mm"`).
    pub fn as_str(self) -> &'static str {
        self.name()
    }
    /// Converts a value in this unit to metres.
    pub fn to_si(self, x: f64) -> f64 {
        match self {
            LengthUnit::M => x,
            LengthUnit::Mm => x * 1e-3,
        }
    }
    /// Converts metres to this unit (inverse of [`LengthUnit::to_si`]).
    pub fn from_si(self, x: f64) -> f64 {
        match self {
            LengthUnit::M => x,
            LengthUnit::Mm => x * 1e3,
        }
    }
}

impl AngleUnit {
    /// The manifest spelling (`"rad"` or `"deg"`).
    pub fn as_str(self) -> &'static str {
        self.name()
    }
    /// Converts a value in this unit to radians.
    pub fn to_si(self, x: f64) -> f64 {
        match self {
            AngleUnit::Rad => x,
            AngleUnit::Deg => x.to_radians(),
        }
    }
    /// Converts radians to this unit (inverse of [`AngleUnit::to_si`]).
    pub fn from_si(self, x: f64) -> f64 {
        match self {
            AngleUnit::Rad => x,
            AngleUnit::Deg => x.to_degrees(),
        }
    }
}

impl ForceUnit {
    /// The manifest spelling (`"N"` or `"N/m"`).
    pub fn as_str(self) -> &'static str {
        self.name()
    }
    /// Converts a value in this unit to N/m of span (`span` \[m\] divides totals).
    pub fn to_si(self, x: f64, span: f64) -> f64 {
        match self {
            ForceUnit::N => x / span,
            ForceUnit::NPerM => x,
        }
    }
    /// Converts N/m of span to this unit (inverse of [`ForceUnit::to_si`]).
    pub fn from_si(self, x: f64, span: f64) -> f64 {
        match self {
            ForceUnit::N => x * span,
            ForceUnit::NPerM => x,
        }
    }
}

impl MomentUnit {
    /// The manifest spelling (`"N*m"` or `"N*m/m"`).
    pub fn as_str(self) -> &'static str {
        self.name()
    }
    /// Converts a value in this unit to N·m/m of span (`span` \[m\] divides totals).
    pub fn to_si(self, x: f64, span: f64) -> f64 {
        match self {
            MomentUnit::Nm => x / span,
            MomentUnit::NmPerM => x,
        }
    }
    /// Converts N·m/m of span to this unit (inverse of [`MomentUnit::to_si`]).
    pub fn from_si(self, x: f64, span: f64) -> f64 {
        match self {
            MomentUnit::Nm => x * span,
            MomentUnit::NmPerM => x,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_round_trip_and_reject_unknown() {
        for (u, s) in LengthUnit::ALL {
            assert_eq!(LengthUnit::from_name(s), Some(*u));
            assert_eq!(u.as_str(), *s);
        }
        for (u, s) in MomentUnit::ALL {
            assert_eq!(MomentUnit::from_name(s), Some(*u));
        }
        assert_eq!(LengthUnit::from_name("inch"), None);
        assert_eq!(ForceUnit::from_name("n"), None, "case-sensitive");
        assert_eq!(AngleUnit::allowed(), "\"rad\", \"deg\"");
    }

    #[test]
    fn conversions_are_exact_inverses_and_use_the_right_factor() {
        assert_eq!(LengthUnit::Mm.to_si(1500.0), 1.5);
        assert!((AngleUnit::Deg.to_si(180.0) - std::f64::consts::PI).abs() < 1e-15);
        assert_eq!(ForceUnit::N.to_si(3.0, 0.75), 4.0);
        assert_eq!(MomentUnit::Nm.to_si(1.5, 0.75), 2.0);
        for x in [0.1, -3.7, 12345.678, 1e-9] {
            assert!((LengthUnit::Mm.from_si(LengthUnit::Mm.to_si(x)) - x).abs() <= 1e-15 * x.abs());
            assert!((AngleUnit::Deg.from_si(AngleUnit::Deg.to_si(x)) - x).abs() <= 1e-15 * x.abs());
            assert!(
                (ForceUnit::N.from_si(ForceUnit::N.to_si(x, 0.7), 0.7) - x).abs()
                    <= 1e-15 * x.abs()
            );
        }
    }
}
