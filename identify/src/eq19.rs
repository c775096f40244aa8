//! Eq. 19: flutter derivatives and nonlinear N* from the nondimensional coefficients.
//!
//! Moment (DESIGN.md §2; lift identical with H1*..H4* and its own N1*..N3*):
//!
//! C_M = K_h A1* ḣ/U + K_α A2* Bα̇/U + K_α² A3* α + K_h² A4* h/B
//!       + K_α³ N1* (B/U) α α̇ + K_α⁶ N2* α³ + K_α³ N3* (B/U)³ α̇³
//!
//! so, with ξ the coefficient of a library term (variables α, Bα̇/U, h/B, ḣ/U):
//! A1* = ξ\[h_dot\]/K_h, A2* = ξ\[alpha_dot\]/K_α, A3* = ξ\[alpha\]/K_α², A4* = ξ\[h\]/K_h²,
//! N1* = ξ\[alpha*alpha_dot\]/K_α³, N2* = ξ\[alpha^3\]/K_α⁶, N3* = ξ\[alpha_dot^3\]/K_α³.
//!
//! A value is `None` (JSON `null`) when its reduced frequency is missing (no forcing of that
//! degree of freedom) or its term is not identifiable in the case; never a number then.
//! An identifiable term left out by the sparse regression has coefficient 0 and gives 0.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// Which reduced frequency a term (or a table of its values) is over.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ReducedFrequency {
    /// K_α = Bω_α/U (α-terms).
    KAlpha,
    /// K_h = Bω_h/U (h-terms).
    KH,
}

/// One term of Eq. 19: the library term, the reduced frequency and power that turn its
/// coefficient ξ into the Eq. 19 value (value = ξ / K^`k_power`), and its powers of the
/// library variables (α, Bα̇/U, h/B, ḣ/U).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Eq19Term {
    /// Library term name (DATA_FORMAT.md).
    pub name: &'static str,
    /// The reduced frequency that scales it.
    pub over: ReducedFrequency,
    /// Power of that reduced frequency.
    pub k_power: i32,
    /// Powers of (α, Bα̇/U, h/B, ḣ/U).
    pub powers: [u32; 4],
}

/// The seven Eq. 19 terms in the order (d1, d2, d3, d4, N1, N2, N3): the one table that
/// identification, the identified law and the figures read.
pub const EQ19: [Eq19Term; 7] = {
    use ReducedFrequency::{KAlpha, KH};
    const fn t(
        name: &'static str,
        over: ReducedFrequency,
        k_power: i32,
        powers: [u32; 4],
    ) -> Eq19Term {
        Eq19Term {
            name,
            over,
            k_power,
            powers,
        }
    }
    [
        t("h_dot", KH, 1, [0, 0, 0, 1]),
        t("alpha_dot", KAlpha, 1, [0, 1, 0, 0]),
        t("alpha", KAlpha, 2, [1, 0, 0, 0]),
        t("h", KH, 2, [0, 0, 1, 0]),
        t("alpha*alpha_dot", KAlpha, 3, [1, 1, 0, 0]),
        t("alpha^3", KAlpha, 6, [3, 0, 0, 0]),
        t("alpha_dot^3", KAlpha, 3, [0, 3, 0, 0]),
    ]
};

/// The names of [`EQ19`], in its order.
pub const EQ19_TERMS: [&str; 7] = [
    EQ19[0].name,
    EQ19[1].name,
    EQ19[2].name,
    EQ19[3].name,
    EQ19[4].name,
    EQ19[5].name,
    EQ19[6].name,
];

/// Names of the Eq. 19 values of the lift, in [`EQ19`] order (H1*..H4*, N1*..N3*).
pub const LIFT_NAMES: [&str; 7] = ["H1", "H2", "H3", "H4", "N1", "N2", "N3"];
/// Names of the Eq. 19 values of the moment, in [`EQ19`] order (A1*..A4*, N1*..N3*).
pub const MOMENT_NAMES: [&str; 7] = ["A1", "A2", "A3", "A4", "N1", "N2", "N3"];

/// The reduced frequency of `t` among (K_α, K_h).
fn k_of(t: &Eq19Term, k_alpha: Option<f64>, k_h: Option<f64>) -> Option<f64> {
    match t.over {
        ReducedFrequency::KAlpha => k_alpha,
        ReducedFrequency::KH => k_h,
    }
}

/// The Eq. 19 values of one force in order (d1, d2, d3, d4, N1, N2, N3), where d are
/// A1*..A4* (moment) or H1*..H4* (lift).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Eq19Values(pub [Option<f64>; 7]);

impl Eq19Values {
    /// Derivatives from the coefficients ξ of the seven terms of [`EQ19_TERMS`] (each
    /// `None` when unidentifiable) and the reduced frequencies K_α, K_h.
    pub fn from_coefficients(xi: [Option<f64>; 7], k_alpha: Option<f64>, k_h: Option<f64>) -> Self {
        let mut out = [None; 7];
        for (i, (t, x)) in EQ19.iter().zip(xi).enumerate() {
            out[i] = match (x, k_of(t, k_alpha, k_h)) {
                (Some(x), Some(k)) if k.is_finite() && k != 0.0 => Some(x / k.powi(t.k_power)),
                _ => None,
            };
        }
        Eq19Values(out)
    }

    /// Inverse of [`Eq19Values::from_coefficients`]: the coefficients ξ of the seven terms
    /// of [`EQ19_TERMS`] at reduced frequencies K_α, K_h (`None` where the value or its K is
    /// missing).
    pub fn to_coefficients(&self, k_alpha: Option<f64>, k_h: Option<f64>) -> [Option<f64>; 7] {
        let mut out = [None; 7];
        for (i, (t, d)) in EQ19.iter().zip(self.0).enumerate() {
            out[i] = match (d, k_of(t, k_alpha, k_h)) {
                (Some(d), Some(k)) if k.is_finite() => Some(d * k.powi(t.k_power)),
                _ => None,
            };
        }
        out
    }

    /// Checks that every present value is finite.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming the first non-finite value (`eq19[i]`).
    pub fn validate(&self) -> Result<()> {
        for (i, v) in self.0.iter().enumerate() {
            if let Some(v) = v {
                if !v.is_finite() {
                    return Err(Error::InvalidOption {
                        name: format!("eq19[{i}]"),
                        message: format!("{v} is not finite"),
                    });
                }
            }
        }
        Ok(())
    }
}

/// Eq. 19 values of the moment: A1*..A4*, N1*..N3* (JSON keys `A1`…`N3`, `null` when not
/// identifiable).
#[allow(non_snake_case)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MomentEq19 {
    /// A1* (heave rate, K_h).
    pub A1: Option<f64>,
    /// A2* (pitch rate, K_α).
    pub A2: Option<f64>,
    /// A3* (pitch, K_α²).
    pub A3: Option<f64>,
    /// A4* (heave, K_h²).
    pub A4: Option<f64>,
    /// N1* (α α̇, K_α³).
    pub N1: Option<f64>,
    /// N2* (α³, K_α⁶).
    pub N2: Option<f64>,
    /// N3* (α̇³, K_α³).
    pub N3: Option<f64>,
}

/// Eq. 19 values of the lift: H1*..H4*, N1*..N3* (JSON keys `H1`…`N3`).
#[allow(non_snake_case)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LiftEq19 {
    /// H1* (heave rate, K_h).
    pub H1: Option<f64>,
    /// H2* (pitch rate, K_α).
    pub H2: Option<f64>,
    /// H3* (pitch, K_α²).
    pub H3: Option<f64>,
    /// H4* (heave, K_h²).
    pub H4: Option<f64>,
    /// N1* (α α̇, K_α³).
    pub N1: Option<f64>,
    /// N2* (α³, K_α⁶).
    pub N2: Option<f64>,
    /// N3* (α̇³, K_α³).
    pub N3: Option<f64>,
}

impl From<Eq19Values> for MomentEq19 {
    fn from(v: Eq19Values) -> Self {
        let [a1, a2, a3, a4, n1, n2, n3] = v.0;
        MomentEq19 {
            A1: a1,
            A2: a2,
            A3: a3,
            A4: a4,
            N1: n1,
            N2: n2,
            N3: n3,
        }
    }
}

impl From<MomentEq19> for Eq19Values {
    fn from(m: MomentEq19) -> Self {
        Eq19Values([m.A1, m.A2, m.A3, m.A4, m.N1, m.N2, m.N3])
    }
}

impl From<Eq19Values> for LiftEq19 {
    fn from(v: Eq19Values) -> Self {
        let [h1, h2, h3, h4, n1, n2, n3] = v.0;
        LiftEq19 {
            H1: h1,
            H2: h2,
            H3: h3,
            H4: h4,
            N1: n1,
            N2: n2,
            N3: n3,
        }
    }
}

impl From<LiftEq19> for Eq19Values {
    fn from(l: LiftEq19) -> Self {
        Eq19Values([l.H1, l.H2, l.H3, l.H4, l.N1, l.N2, l.N3])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forward_matches_the_formula_and_round_trips() {
        let xi = [
            Some(0.3),
            Some(-0.2),
            Some(1.1),
            None,
            Some(0.05),
            Some(-0.7),
            Some(0.0),
        ];
        let (ka, kh) = (0.8, 0.35);
        let d = Eq19Values::from_coefficients(xi, Some(ka), Some(kh));
        assert_eq!(d.0[0], Some(0.3 / kh));
        assert_eq!(d.0[1], Some(-0.2 / ka));
        assert!((d.0[2].unwrap() - 1.1 / (ka * ka)).abs() < 1e-15);
        assert_eq!(d.0[3], None, "unidentifiable stays None");
        assert!((d.0[5].unwrap() + 0.7 / ka.powi(6)).abs() < 1e-12);
        assert_eq!(d.0[6], Some(0.0));
        let back = d.to_coefficients(Some(ka), Some(kh));
        for (a, b) in back.iter().zip(xi) {
            match (a, b) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-14),
                (None, None) => {}
                _ => panic!("{a:?} vs {b:?}"),
            }
        }
        let m: MomentEq19 = d.into();
        assert_eq!(Eq19Values::from(m), d);
        let json = serde_json::to_string(&m).unwrap();
        assert!(
            json.contains("\"A4\":null") && json.contains("\"N3\":0.0"),
            "{json}"
        );
        let l: LiftEq19 = d.into();
        assert!(serde_json::to_string(&l).unwrap().contains("\"H1\""));
    }

    #[test]
    fn missing_reduced_frequency_gives_none() {
        let xi = [Some(1.0); 7];
        let d = Eq19Values::from_coefficients(xi, Some(0.5), None);
        assert_eq!(d.0[0], None);
        assert_eq!(d.0[3], None);
        assert!(d.0[1].is_some() && d.0[4].is_some());
        assert!(
            Eq19Values([Some(f64::NAN), None, None, None, None, None, None])
                .validate()
                .is_err()
        );
    }
}
