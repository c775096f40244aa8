//! Theodorsen's function, its Jones (Wagner) two-lag approximation, and the flat-plate
//! flutter derivatives in closed form (DESIGN.md §2).
//!
//! Reduced frequencies: Theodorsen's k = bω/U uses the semi-chord b = B/2; Scanlan's
//! K = Bω/U uses the full chord B, so K = 2k and the derivatives use C(K/2).

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::bessel::bessel01;

/// Theodorsen's function C(k) = F + iG = H1⁽²⁾(k) / (H1⁽²⁾(k) + i H0⁽²⁾(k)),
/// H_n⁽²⁾ = J_n − i Y_n, k = bω/U (semi-chord reduced frequency).
///
/// Exact to ~1e-13 (see [`crate::bessel`]). `C(0) = 1`; for `k < 0` the conjugate
/// symmetry C(−k) = conj C(k) is used; a non-finite `k` gives NaN.
pub fn theodorsen(k: f64) -> Complex64 {
    if k == 0.0 {
        return Complex64::new(1.0, 0.0);
    }
    if k < 0.0 {
        return theodorsen(-k).conj();
    }
    let b = bessel01(k);
    let h1 = Complex64::new(b.j1, -b.y1);
    let h0 = Complex64::new(b.j0, -b.y0);
    h1 / (h1 + Complex64::i() * h0)
}

/// R.T. Jones' two-lag approximation of Theodorsen's function,
/// C(k) ≈ 1 − 0.165/(1 − 0.0455 i/k) − 0.335/(1 − 0.3 i/k), k = bω/U; `C(0) = 1`.
///
/// It is the Fourier transform of the Wagner function approximation [`wagner_jones`]
/// and is what the time-domain Theodorsen model integrates (see [`JONES_LAGS`]).
pub fn theodorsen_jones(k: f64) -> Complex64 {
    if k == 0.0 {
        return Complex64::new(1.0, 0.0);
    }
    let mut c = Complex64::new(1.0, 0.0);
    for (amp, beta) in JONES_LAGS {
        c -= amp / (Complex64::new(1.0, 0.0) - Complex64::i() * beta / k);
    }
    c
}

/// Jones' lag terms (A_i, β_i) of the Wagner approximation
/// φ(s) = 1 − Σ A_i e^{−β_i s}, s = U t / b (semi-chords travelled).
pub const JONES_LAGS: [(f64, f64); 2] = [(0.165, 0.0455), (0.335, 0.3)];

/// Wagner's indicial lift function in Jones' approximation,
/// φ(s) = 1 − 0.165 e^{−0.0455 s} − 0.335 e^{−0.3 s}, s = U t / b; φ(0) = 1/2, φ(∞) = 1.
pub fn wagner_jones(s: f64) -> f64 {
    1.0 - JONES_LAGS
        .iter()
        .map(|(a, b)| a * (-b * s).exp())
        .sum::<f64>()
}

/// The eight Scanlan flutter derivatives at one reduced frequency K = Bω/U
/// (DESIGN.md §2 convention: h down, α nose-up, L down, M nose-up).
///
/// L = ½ρU²B [K H1* ḣ/U + K H2* Bα̇/U + K² H3* α + K² H4* h/B],
/// M = ½ρU²B² [K A1* ḣ/U + K A2* Bα̇/U + K² A3* α + K² A4* h/B].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Derivatives {
    /// Reduced frequency K = Bω/U.
    pub k: f64,
    /// H1* (lift from heave velocity).
    pub h1: f64,
    /// H2* (lift from pitch velocity).
    pub h2: f64,
    /// H3* (lift from pitch).
    pub h3: f64,
    /// H4* (lift from heave).
    pub h4: f64,
    /// A1* (moment from heave velocity).
    pub a1: f64,
    /// A2* (moment from pitch velocity; > 0 means negative torsional damping).
    pub a2: f64,
    /// A3* (moment from pitch).
    pub a3: f64,
    /// A4* (moment from heave).
    pub a4: f64,
}

/// One of the eight Scanlan flutter derivatives H1*…H4*, A1*…A4* (lift H, moment A;
/// 1 heave velocity, 2 pitch velocity, 3 pitch, 4 heave), named as in the result files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Derivative {
    /// H1*: lift from heave velocity.
    H1,
    /// H2*: lift from pitch velocity.
    H2,
    /// H3*: lift from pitch.
    H3,
    /// H4*: lift from heave.
    H4,
    /// A1*: moment from heave velocity.
    A1,
    /// A2*: moment from pitch velocity.
    A2,
    /// A3*: moment from pitch.
    A3,
    /// A4*: moment from heave.
    A4,
}

impl Derivative {
    /// All eight, lift first, in file order.
    pub const ALL: [Derivative; 8] = [
        Derivative::H1,
        Derivative::H2,
        Derivative::H3,
        Derivative::H4,
        Derivative::A1,
        Derivative::A2,
        Derivative::A3,
        Derivative::A4,
    ];

    /// The name used in the result files (`"H1"` … `"A4"`).
    pub fn name(self) -> &'static str {
        match self {
            Derivative::H1 => "H1",
            Derivative::H2 => "H2",
            Derivative::H3 => "H3",
            Derivative::H4 => "H4",
            Derivative::A1 => "A1",
            Derivative::A2 => "A2",
            Derivative::A3 => "A3",
            Derivative::A4 => "A4",
        }
    }

    /// The derivative named `name` (`"H1"` … `"A4"`); `None` for any other name (an Eq. 19
    /// nonlinear coefficient such as `"N1"` is not a flutter derivative).
    pub fn parse(name: &str) -> Option<Derivative> {
        Derivative::ALL.into_iter().find(|d| d.name() == name)
    }
}

impl Derivatives {
    /// The value of derivative `d`.
    pub fn get(&self, d: Derivative) -> f64 {
        match d {
            Derivative::H1 => self.h1,
            Derivative::H2 => self.h2,
            Derivative::H3 => self.h3,
            Derivative::H4 => self.h4,
            Derivative::A1 => self.a1,
            Derivative::A2 => self.a2,
            Derivative::A3 => self.a3,
            Derivative::A4 => self.a4,
        }
    }

    /// Complex aerodynamic transfer matrix in nondimensional coordinates:
    /// (C_L, C_M)ᵀ = Q(K) (h/B, α)ᵀ for harmonic motion e^{iωt}, with
    /// Q = K² [[H4* + iH1*, H3* + iH2*], [A4* + iA1*, A3* + iA2*]].
    pub fn q_matrix(&self) -> [[Complex64; 2]; 2] {
        let k2 = self.k * self.k;
        [
            [
                Complex64::new(k2 * self.h4, k2 * self.h1),
                Complex64::new(k2 * self.h3, k2 * self.h2),
            ],
            [
                Complex64::new(k2 * self.a4, k2 * self.a1),
                Complex64::new(k2 * self.a3, k2 * self.a2),
            ],
        ]
    }

    /// Inverse of [`Derivatives::q_matrix`]: the derivatives at `k` whose Q matrix is `q`.
    pub fn from_q_matrix(k: f64, q: [[Complex64; 2]; 2]) -> Self {
        let k2 = k * k;
        Derivatives {
            k,
            h1: q[0][0].im / k2,
            h2: q[0][1].im / k2,
            h3: q[0][1].re / k2,
            h4: q[0][0].re / k2,
            a1: q[1][0].im / k2,
            a2: q[1][1].im / k2,
            a3: q[1][1].re / k2,
            a4: q[1][0].re / k2,
        }
    }
}

/// Flat-plate flutter derivatives (elastic axis at mid-chord) in closed form, DESIGN.md §2,
/// with F + iG = C(K/2) (exact Theodorsen):
/// H1* = −2πF/K, H2* = −(π/2K)(1 + F + 4G/K), H3* = −(2π/K²)(F − KG/4),
/// H4* = (π/2)(1 + 4G/K), A1* = πF/(2K), A2* = −(π/8K)(1 − F − 4G/K),
/// A3* = (π/2K²)(K²/32 + F − KG/4), A4* = −πG/(2K).
///
/// `k` is K = Bω/U and must be > 0 (the derivatives are singular at K = 0); a
/// non-positive `k` gives NaN fields.
pub fn flat_plate_derivatives(k: f64) -> Derivatives {
    if k.is_nan() || k <= 0.0 {
        let n = f64::NAN;
        return Derivatives {
            k,
            h1: n,
            h2: n,
            h3: n,
            h4: n,
            a1: n,
            a2: n,
            a3: n,
            a4: n,
        };
    }
    let c = theodorsen(0.5 * k);
    let (f, g) = (c.re, c.im);
    let pi = std::f64::consts::PI;
    Derivatives {
        k,
        h1: -2.0 * pi * f / k,
        h2: -(pi / (2.0 * k)) * (1.0 + f + 4.0 * g / k),
        h3: -(2.0 * pi / (k * k)) * (f - k * g / 4.0),
        h4: (pi / 2.0) * (1.0 + 4.0 * g / k),
        a1: pi * f / (2.0 * k),
        a2: -(pi / (8.0 * k)) * (1.0 - f - 4.0 * g / k),
        a3: (pi / (2.0 * k * k)) * (k * k / 32.0 + f - k * g / 4.0),
        a4: -pi * g / (2.0 * k),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_names_round_trip_and_select_the_field() {
        let d = Derivatives {
            k: 0.5,
            h1: 1.0,
            h2: 2.0,
            h3: 3.0,
            h4: 4.0,
            a1: 5.0,
            a2: 6.0,
            a3: 7.0,
            a4: 8.0,
        };
        for (i, x) in Derivative::ALL.into_iter().enumerate() {
            assert_eq!(Derivative::parse(x.name()), Some(x));
            assert_eq!(d.get(x), (i + 1) as f64);
        }
        assert_eq!(Derivative::parse("N1"), None);
        assert_eq!(Derivative::parse("a4"), None);
    }

    #[test]
    fn theodorsen_matches_design_reference_values() {
        // DESIGN.md §6 (5 decimals).
        for (k, f, g) in [
            (0.1, 0.83192, -0.17230),
            (0.5, 0.59794, -0.15071),
            (1.0, 0.53943, -0.10027),
        ] {
            let c = theodorsen(k);
            assert!(
                (c.re - f).abs() < 1e-4 && (c.im - g).abs() < 1e-4,
                "C({k}) = {c}"
            );
            // Rounded to 5 decimals the values must agree to half a unit in the last place.
            assert!(
                (c.re - f).abs() <= 5.1e-6 && (c.im - g).abs() <= 5.1e-6,
                "C({k}) = {c}"
            );
        }
    }

    #[test]
    fn theodorsen_limits() {
        // k → 0: C → 1; k → ∞: C → 1/2 (F → 1/2, G → 0).
        let c = theodorsen(1e-6);
        assert!((c.re - 1.0).abs() < 1e-4, "{c}");
        let c = theodorsen(1e4);
        assert!((c.re - 0.5).abs() < 1e-4 && c.im.abs() < 1e-4, "{c}");
        assert_eq!(theodorsen(-0.5), theodorsen(0.5).conj());
    }

    #[test]
    fn jones_is_close_to_exact_and_consistent_with_wagner() {
        for k in [0.05, 0.1, 0.3, 0.5, 1.0, 2.0] {
            let e = theodorsen(k);
            let j = theodorsen_jones(k);
            // Jones' approximation is known to be within about 0.02 of the exact function.
            assert!((e - j).norm() < 0.02, "k = {k}: exact {e}, Jones {j}");
        }
        assert!((wagner_jones(0.0) - 0.5).abs() < 1e-15);
        assert!((wagner_jones(1e6) - 1.0).abs() < 1e-12);
        // C(k→∞) = φ(0) = 1/2 and C(0) = φ(∞) = 1.
        assert!((theodorsen_jones(1e9).re - 0.5).abs() < 1e-8);
    }

    #[test]
    fn flat_plate_derivatives_match_design_reference_values() {
        let cases = [
            (
                1.0,
                [
                    -3.7569, -1.5631, -3.9937, 0.6239, 0.9392, -0.3946, 1.0475, 0.2367,
                ],
            ),
            (
                0.5,
                [
                    -8.7029, -0.6615, -17.9877, -0.7571, 2.1757, -1.4054, 4.5460, 0.5820,
                ],
            ),
        ];
        for (k, want) in cases {
            let d = flat_plate_derivatives(k);
            let got = [d.h1, d.h2, d.h3, d.h4, d.a1, d.a2, d.a3, d.a4];
            for (i, (g, w)) in got.iter().zip(want).enumerate() {
                assert!((g - w).abs() < 1e-4, "K = {k}, derivative #{i}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn q_matrix_round_trip() {
        let d = flat_plate_derivatives(0.7);
        let back = Derivatives::from_q_matrix(0.7, d.q_matrix());
        assert!((back.a2 - d.a2).abs() < 1e-14 && (back.h3 - d.h3).abs() < 1e-14);
    }

    #[test]
    fn non_positive_k_is_nan() {
        assert!(flat_plate_derivatives(0.0).h1.is_nan());
    }

    #[test]
    fn thin_plate_derivatives_at_mid_chord_are_the_closed_forms_and_move_with_the_axis() {
        for k in [0.3, 0.5, 1.0, 2.0] {
            let (d, c) = (
                crate::aero::thin_plate_derivatives(k, 0.0),
                flat_plate_derivatives(k),
            );
            for (x, y) in [
                (d.h1, c.h1),
                (d.h2, c.h2),
                (d.h3, c.h3),
                (d.h4, c.h4),
                (d.a1, c.a1),
                (d.a2, c.a2),
                (d.a3, c.a3),
                (d.a4, c.a4),
            ] {
                assert!(
                    (x - y).abs() < 1e-12 * y.abs().max(1.0),
                    "K {k}: {x} vs {y}"
                );
            }
        }
        // a = −0.3: heave-driven lift is unchanged, the pitch-rate downwash and the moment arm
        // of the circulatory lift about the axis (b/2 → 0.2 b) change
        let (d, c) = (
            crate::aero::thin_plate_derivatives(1.0, -0.3),
            flat_plate_derivatives(1.0),
        );
        assert!(
            (d.h3 - c.h3).abs() > 1e-3,
            "H3* depends on the axis through α̇ lift"
        );
        assert!((d.h4 - c.h4).abs() < 1e-12 && (d.h1 - c.h1).abs() < 1e-12);
        assert!(d.a3 < 0.7 * c.a3, "A3* {} vs mid-chord {}", d.a3, c.a3);
    }
}
