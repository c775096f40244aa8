//! Sign conventions of the CSV columns (manifest `[convention]`) and their conversion to the
//! Scanlan convention of DESIGN.md §2 (h and L positive down, α and M positive nose-up).
//!
//! A data set in another convention declares it; the reader multiplies each column by the
//! sign that takes it to Scanlan, once, at the boundary. Without a declaration a file is read
//! as Scanlan: nothing is detected or guessed (DATA_FORMAT.md says what a wrong sign does).

use serde::{Deserialize, Serialize};

use super::units::UnitName;

/// Positive direction of a translation (heave `h`) or a force (`lift`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Linear {
    /// Positive downward (Scanlan), `"down"`.
    #[default]
    Down,
    /// Positive upward, `"up"`.
    Up,
}

/// Positive direction of a rotation (pitch `alpha`) or a moment (`moment`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Angular {
    /// Positive nose-up (Scanlan), `"nose-up"`.
    #[default]
    NoseUp,
    /// Positive nose-down, `"nose-down"`.
    NoseDown,
}

impl UnitName for Linear {
    const ALL: &'static [(Self, &'static str)] = &[(Linear::Down, "down"), (Linear::Up, "up")];
}
impl UnitName for Angular {
    const ALL: &'static [(Self, &'static str)] = &[
        (Angular::NoseUp, "nose-up"),
        (Angular::NoseDown, "nose-down"),
    ];
}

impl Linear {
    /// The manifest spelling (`"down"` or `"up"`).
    pub fn as_str(self) -> &'static str {
        self.name()
    }
    /// Factor from this convention to Scanlan's (positive down): +1 or −1.
    pub fn sign(self) -> f64 {
        match self {
            Linear::Down => 1.0,
            Linear::Up => -1.0,
        }
    }
    /// The other direction.
    pub fn flipped(self) -> Self {
        match self {
            Linear::Down => Linear::Up,
            Linear::Up => Linear::Down,
        }
    }
}

impl Angular {
    /// The manifest spelling (`"nose-up"` or `"nose-down"`).
    pub fn as_str(self) -> &'static str {
        self.name()
    }
    /// Factor from this convention to Scanlan's (positive nose-up): +1 or −1.
    pub fn sign(self) -> f64 {
        match self {
            Angular::NoseUp => 1.0,
            Angular::NoseDown => -1.0,
        }
    }
}

/// Positive directions of the four CSV columns (manifest `[convention]`, every key optional).
///
/// `Default` is Scanlan's (DESIGN.md §2): h and lift down, α and moment nose-up. The reader
/// multiplies each column by [`Linear::sign`] / [`Angular::sign`]; the writer divides.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
pub struct Convention {
    /// Positive direction of `h`.
    pub heave: Linear,
    /// Positive direction of `alpha` (and of the manifest's `mean_pitch`).
    pub pitch: Angular,
    /// Positive direction of `lift`.
    pub lift: Linear,
    /// Positive direction of `moment`.
    pub moment: Angular,
}

impl Convention {
    /// True for Scanlan's convention (no column changes sign on reading).
    pub fn is_scanlan(&self) -> bool {
        *self == Convention::default()
    }

    /// The same convention with the lift direction reversed (the `--flip-lift` flag).
    pub fn with_lift_flipped(self) -> Self {
        Convention {
            lift: self.lift.flipped(),
            ..self
        }
    }

    /// One line for messages and reports, e.g. `h down, alpha nose-up, lift up, moment nose-up`.
    pub fn describe(&self) -> String {
        format!(
            "h {}, alpha {}, lift {}, moment {}",
            self.heave.as_str(),
            self.pitch.as_str(),
            self.lift.as_str(),
            self.moment.as_str()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scanlan_is_the_default_and_signs_are_right() {
        let c = Convention::default();
        assert!(c.is_scanlan());
        assert_eq!(c.heave.sign(), 1.0);
        assert_eq!(c.pitch.sign(), 1.0);
        let up = c.with_lift_flipped();
        assert!(!up.is_scanlan());
        assert_eq!(up.lift.sign(), -1.0);
        assert_eq!(up.with_lift_flipped(), c);
        assert_eq!(Angular::NoseDown.sign(), -1.0);
        assert_eq!(Linear::from_name("up"), Some(Linear::Up));
        assert_eq!(Angular::from_name("nose-down"), Some(Angular::NoseDown));
        assert_eq!(Angular::allowed(), "\"nose-up\", \"nose-down\"");
        assert_eq!(
            up.describe(),
            "h down, alpha nose-up, lift up, moment nose-up"
        );
    }
}
