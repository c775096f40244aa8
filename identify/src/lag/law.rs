//! The lag law: the Eq. 19 idea with one internal separation state (Goman–Khrabrov / Øye
//! family), in nondimensional form so that identification ([`super`]) and flight
//! (`aeroelastic::aero::LagAero`) evaluate the same numbers.
//!
//! Variables (DESIGN.md §2, Scanlan signs): α \[rad\] nose-up, q = Bα̇/U, ḣ/U (h down),
//! semichord b = B/2, convective time s = tU/b.
//!
//! - Effective angle α_e = α + ḣ/U (a downward heave velocity raises the angle of attack),
//!   plus c·Bα̇/U with a fixed pitch-rate share c ([`LagLaw::rate_share`], default 0;
//!   (½ − a)/2 gives the three-quarter-chord downwash angle about an axis at a semichords).
//! - Input of the lag equation u = α_e − τ₂·(b α̇/U) = α_e − τ₂·q/2: the separation responds
//!   to the angle τ₂ convective times earlier (pitch rate only; the heave acceleration's
//!   share b ḧ/U² is left out, forced records do not carry it cleanly).
//! - Separation state x ∈ [0, 1] (1 = attached): τ₁ dx/ds + x = x₀(u), i.e.
//!   ẋ = (U/(b τ₁))·(x₀(u) − x) in physical time.
//! - Pressure lag ([`LagLaw::pressure_lag`] τ_p > 0, off by default): the separation follows
//!   the filtered input u_f, τ_p du_f/ds + u_f = u, instead of u (Beddoes–Leishman's
//!   leading-edge pressure lag; with it the fitted τ₂ tends to 0).
//! - Static separation curve x₀(α) = 1 / (1 + |α/α*|^{2m}) (α* the angle of half
//!   separation, m ≥ 1 its sharpness): x₀(0) = 1 with zero slope, so the law's
//!   linearisation about α = 0 is attached flow.
//! - Forces: C_L (down) and C_M (nose-up about the elastic axis) are each a linear
//!   combination of the columns [`LagColumn`]: a constant, α_e, the Kirchhoff lift
//!   α_e·((1 + √x)/2)², q, the separation deficit 1 − x and the Kirchhoff lift times it
//!   (centre-of-pressure travel), and the Kirchhoff lift of the *instantaneous* static
//!   separation α_e·κ(x₀(α_e)) (the share of the separated-flow lift that follows the angle
//!   without lag, as the fully separated term (1 − f″)(1 + 3s)/(4(1 + s)), s = √f_st(α_E),
//!   of Hansen, Gaunaa & Madsen 2004 does; not in the default support, see
//!   `LagFitOptions::lift_columns`), and the separated-flow blend of Hansen, Gaunaa & Madsen
//!   ([`LagColumn::Blend`], [`LagColumn::BlendSep`], also not in the default support). The
//!   thin-aerofoil apparent mass (acceleration terms) is
//!   not part of the law: flight adds it (`AeroModel::apparent_mass`).
//! - Attached-flow circulation lag (switch [`LagLaw::circulation_lag`], off in a document
//!   that does not name it): the circulation does not follow the angle at once (Wagner's
//!   indicial lift). With the switch on, every angle the law uses — the columns' α_e and the
//!   separation input u — is the circulatory angle
//!   α_c = (1 − A₁ − A₂)·α_e + A₁·z₁ + A₂·z₂, where z_i lags α_e in convective time,
//!   dz_i/ds = b_i·(α_e − z_i), with R. T. Jones' (1938) fixed approximation of Wagner's
//!   function, (A₁, b₁) = (0.165, 0.0455), (A₂, b₂) = (0.335, 0.3) ([`CIRCULATION_LAGS`]):
//!   published constants, not fitted. In steady flow z_i = α_e, so α_c = α_e and the static
//!   law is unchanged. Driving the separation by the lagged angle is Leishman & Beddoes
//!   (1989, "A semi-empirical model for dynamic stall", J. Am. Helicopter Soc. 34(3)) and
//!   Hansen, Gaunaa & Madsen (2004, Risø-R-1354): the separation point follows the effective
//!   (circulatory) angle, not the geometric one. The pitch-rate column q stays unlagged (it
//!   carries the noncirculatory and the rate terms together: the law does not know the
//!   records' elastic axis, so it cannot form the three-quarter-chord downwash).

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// A column of the lag law's force library, evaluated at (α_e, q, x).
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
pub enum LagColumn {
    /// 1 (a constant: camber, offsets).
    One,
    /// α_e = α + ḣ/U.
    AlphaE,
    /// Kirchhoff circulatory lift shape α_e·((1 + √x)/2)².
    Kirchhoff,
    /// q = Bα̇/U (pitch-rate lift and damping).
    Q,
    /// Separation deficit 1 − x.
    Sep,
    /// Kirchhoff lift times the separation deficit, α_e·((1 + √x)/2)²·(1 − x): the moment of
    /// a centre of pressure that travels aft with separation.
    KirchhoffSep,
    /// Kirchhoff lift of the instantaneous static separation, α_e·κ(x₀(α_e)): no lag (the
    /// law's angle α_e, or α_c with the circulation lag, in both places). In steady flow it
    /// equals α_e·κ(x), so beside [`LagColumn::Kirchhoff`] the two coefficients split one
    /// static lift slope into a lagged and an instantaneous share.
    KirchhoffStatic,
    /// Lift of the separated-flow blend of Hansen, Gaunaa & Madsen (2004, Risø-R-1354):
    /// α_e·(x + (1 − x)·(1 + 3s)/(4(1 + s))), s = √x₀(α_e): the attached lift weighted by the
    /// lagged separation x plus the fully separated lift, whose share follows the
    /// *instantaneous* static separation, weighted by 1 − x. In steady flow (x = x₀ = s²) it
    /// equals the Kirchhoff lift α_e·κ(x). Not in the default support (`--lag-blend`).
    Blend,
    /// The blend lift times the separation deficit, α_e·b(x, s)·(1 − x): the moment of a
    /// centre of pressure that travels aft with separation, on the blend lift.
    BlendSep,
}

impl LagColumn {
    /// Every column, in library order.
    pub const ALL: [LagColumn; 9] = [
        LagColumn::One,
        LagColumn::AlphaE,
        LagColumn::Kirchhoff,
        LagColumn::Q,
        LagColumn::Sep,
        LagColumn::KirchhoffSep,
        LagColumn::KirchhoffStatic,
        LagColumn::Blend,
        LagColumn::BlendSep,
    ];

    /// The six columns of the law as first written (the default moment candidates): every
    /// column but [`LagColumn::KirchhoffStatic`].
    pub const LAGGED: [LagColumn; 6] = [
        LagColumn::One,
        LagColumn::AlphaE,
        LagColumn::Kirchhoff,
        LagColumn::Q,
        LagColumn::Sep,
        LagColumn::KirchhoffSep,
    ];

    /// The column's display name (`α_e·κ(x)` …).
    pub fn label(self) -> &'static str {
        match self {
            LagColumn::One => "1",
            LagColumn::AlphaE => "α_e",
            LagColumn::Kirchhoff => "α_e·κ(x)",
            LagColumn::Q => "Bα̇/U",
            LagColumn::Sep => "1−x",
            LagColumn::KirchhoffSep => "α_e·κ(x)·(1−x)",
            LagColumn::KirchhoffStatic => "α_e·κ(x₀(α_e))",
            LagColumn::Blend => "α_e·β(x,x₀(α_e))",
            LagColumn::BlendSep => "α_e·β(x,x₀(α_e))·(1−x)",
        }
    }

    /// The column's value at effective angle `alpha_e` \[rad\], q = Bα̇/U, separation
    /// state `x` and static separation `x_inst` = x₀(α_e) at the same angle (both clamped
    /// to \[0, 1\] inside the square root; `x_inst` is read by
    /// [`LagColumn::KirchhoffStatic`], [`LagColumn::Blend`] and [`LagColumn::BlendSep`]).
    #[inline]
    pub fn value(self, alpha_e: f64, q: f64, x: f64, x_inst: f64) -> f64 {
        match self {
            LagColumn::KirchhoffStatic => alpha_e * kirchhoff(x_inst),
            LagColumn::One => 1.0,
            LagColumn::AlphaE => alpha_e,
            LagColumn::Kirchhoff => alpha_e * kirchhoff(x),
            LagColumn::Q => q,
            LagColumn::Sep => 1.0 - x,
            LagColumn::KirchhoffSep => alpha_e * kirchhoff(x) * (1.0 - x),
            LagColumn::Blend => alpha_e * blend(x, x_inst),
            LagColumn::BlendSep => alpha_e * blend(x, x_inst) * (1.0 - x.clamp(0.0, 1.0)),
        }
    }

    /// ∂(value)/∂x at (α_e, q, x) (for linearisations and output-error gradients; the
    /// static separation x₀(α_e) of [`LagColumn::KirchhoffStatic`] and of the blend columns
    /// does not depend on x; the blend columns' derivative is taken at x_inst = x₀(α_e) =
    /// `x_inst`).
    #[inline]
    pub fn d_dx_at(self, alpha_e: f64, q: f64, x: f64, x_inst: f64) -> f64 {
        match self {
            LagColumn::Blend => alpha_e * (1.0 - blend_share(x_inst)),
            LagColumn::BlendSep => {
                let xc = x.clamp(0.0, 1.0);
                alpha_e * ((1.0 - blend_share(x_inst)) * (1.0 - xc) - blend(xc, x_inst))
            }
            _ => self.d_dx(alpha_e, q, x),
        }
    }

    /// ∂(value)/∂x at (α_e, q, x) for the columns that do not read x₀(α_e) (the blend
    /// columns are taken at x_inst = 1, attached: use [`LagColumn::d_dx_at`] for them).
    #[inline]
    pub fn d_dx(self, alpha_e: f64, _q: f64, x: f64) -> f64 {
        match self {
            LagColumn::One | LagColumn::AlphaE | LagColumn::Q | LagColumn::KirchhoffStatic => 0.0,
            LagColumn::Kirchhoff => alpha_e * kirchhoff_dx(x),
            LagColumn::Sep => -1.0,
            LagColumn::KirchhoffSep => alpha_e * (kirchhoff_dx(x) * (1.0 - x) - kirchhoff(x)),
            LagColumn::Blend | LagColumn::BlendSep => self.d_dx_at(alpha_e, _q, x, 1.0),
        }
    }
}

/// Kirchhoff factor κ(x) = ((1 + √x)/2)², x clamped to \[0, 1\].
#[inline]
pub fn kirchhoff(x: f64) -> f64 {
    let s = x.clamp(0.0, 1.0).sqrt();
    0.25 * (1.0 + s) * (1.0 + s)
}

/// Share (1 + 3s)/(4(1 + s)) of the attached lift that remains at full separation in the
/// blend of Hansen, Gaunaa & Madsen (2004), s = √x_inst (x_inst clamped to \[0, 1\]): ¼ at
/// x_inst = 0, ½ at x_inst = 1.
#[inline]
pub fn blend_share(x_inst: f64) -> f64 {
    let s = x_inst.clamp(0.0, 1.0).sqrt();
    (1.0 + 3.0 * s) / (4.0 * (1.0 + s))
}

/// Blend factor β(x, x_inst) = x + (1 − x)·(1 + 3s)/(4(1 + s)), s = √x_inst, x clamped to
/// \[0, 1\] (Hansen, Gaunaa & Madsen 2004): equal to the Kirchhoff factor κ(x) when
/// x = x_inst (steady flow).
#[inline]
pub fn blend(x: f64, x_inst: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x + (1.0 - x) * blend_share(x_inst)
}

/// dκ/dx = (1 + √x)/(4√x), with √x floored at 1e-3 (finite at full separation).
#[inline]
pub fn kirchhoff_dx(x: f64) -> f64 {
    let s = x.clamp(0.0, 1.0).sqrt().max(1e-3);
    (1.0 + s) / (4.0 * s)
}

/// One channel of the law: the columns it uses and their coefficients.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagChannel {
    /// (column, coefficient) pairs; a column appears at most once.
    pub terms: Vec<(LagColumn, f64)>,
}

impl LagChannel {
    /// The channel's coefficient (C_L or C_M) at (α_e, q, x) with the static separation
    /// `x_inst` = x₀(α_e) ([`LagColumn::value`]).
    #[inline]
    pub fn value(&self, alpha_e: f64, q: f64, x: f64, x_inst: f64) -> f64 {
        self.terms
            .iter()
            .map(|(c, k)| k * c.value(alpha_e, q, x, x_inst))
            .sum()
    }

    /// Whether the channel uses the instantaneous static separation x₀(α_e)
    /// ([`LagColumn::KirchhoffStatic`]), i.e. is not affine in α_e at fixed x.
    pub fn uses_static(&self) -> bool {
        self.terms.iter().any(|(c, _)| {
            matches!(
                c,
                LagColumn::KirchhoffStatic | LagColumn::Blend | LagColumn::BlendSep
            )
        })
    }

    /// ∂(value)/∂x at the static separation `x_inst` = x₀(α_e) ([`LagColumn::d_dx_at`]).
    #[inline]
    pub fn d_dx(&self, alpha_e: f64, q: f64, x: f64, x_inst: f64) -> f64 {
        self.terms
            .iter()
            .map(|(c, k)| k * c.d_dx_at(alpha_e, q, x, x_inst))
            .sum()
    }
}

/// R. T. Jones' (1938) two-term approximation of Wagner's indicial lift function,
/// φ(s) = 1 − A₁e^{−b₁s} − A₂e^{−b₂s} (s = tU/b): the pairs (A_i, b_i) of the circulation
/// lag (module docs). The same constants as `aeroelastic::theodorsen::JONES_LAGS`.
pub const CIRCULATION_LAGS: [(f64, f64); 2] = [(0.165, 0.0455), (0.335, 0.3)];

/// The circulatory angle α_c = (1 − A₁ − A₂)·α_e + A₁·z₁ + A₂·z₂ \[rad\] of the Jones states
/// z = (z₁, z₂) \[rad\] (module docs); α_c = α_e when z₁ = z₂ = α_e.
#[inline]
pub fn circulatory_angle(alpha_e: f64, z: [f64; 2]) -> f64 {
    let [(a1, _), (a2, _)] = CIRCULATION_LAGS;
    (1.0 - a1 - a2) * alpha_e + a1 * z[0] + a2 * z[1]
}

/// dz_i/ds = b_i·(α_e − z_i) of the Jones states in convective time s = tU/b; multiply by
/// 2U/B for d/dt.
#[inline]
pub fn circulation_rates(alpha_e: f64, z: [f64; 2]) -> [f64; 2] {
    [
        CIRCULATION_LAGS[0].1 * (alpha_e - z[0]),
        CIRCULATION_LAGS[1].1 * (alpha_e - z[1]),
    ]
}

/// The range of the forced data a law was fitted on (for extrapolation warnings).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FittedRange {
    /// Smallest and largest effective angle α_e seen \[rad\].
    pub alpha_e: [f64; 2],
    /// Smallest and largest reduced frequency K = Bω/U of the cases.
    pub k: [f64; 2],
}

/// The lag law (module docs): separation dynamics and the two force channels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagLaw {
    /// Separation lag τ₁ \[convective times b/U\], in (0, 100].
    pub tau1: f64,
    /// Separation input lead τ₂ \[convective times b/U\], in \[0, 100\].
    pub tau2: f64,
    /// Angle of half separation α* \[rad\], in (0, π/2).
    pub alpha_star: f64,
    /// Sharpness m ≥ 1 of the static separation curve.
    pub sharpness: f64,
    /// Lift coefficient C_L (positive down, Scanlan).
    pub lift: LagChannel,
    /// Moment coefficient C_M (positive nose-up, about the elastic axis of the records).
    pub moment: LagChannel,
    /// Range of the data the law was fitted on.
    pub range: FittedRange,
    /// Attached-flow circulation lag on (module docs): the columns and the separation input
    /// take the circulatory angle α_c instead of α_e. Absent in a document = off (the law as
    /// first written).
    #[serde(default)]
    pub circulation_lag: bool,
    /// Pitch-rate share c of the effective angle, α_e = α + ḣ/U + c·Bα̇/U (c = (½ − a)/2
    /// for the three-quarter-chord downwash about an elastic axis a semichords aft of
    /// mid-chord); fixed, not fitted. Absent in a document = 0.
    #[serde(default)]
    pub rate_share: f64,
    /// Pressure lag τ_p \[convective times b/U\] of the separation input, in \[0, 100\]
    /// (0 = off): with τ_p > 0 the separation responds to the filtered input u_f,
    /// τ_p du_f/ds + u_f = u, u = α_c − τ₂·q/2, i.e. τ₁ dx/ds + x = x₀(u_f) (the leading-edge
    /// pressure response of Beddoes–Leishman's T_p, Leishman & Beddoes 1989; Hansen, Gaunaa
    /// & Madsen 2004). The columns keep the unfiltered angle. Absent in a document = 0.
    #[serde(default)]
    pub pressure_lag: f64,
}

impl LagLaw {
    /// Checks the physical bounds of every parameter.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming the parameter and its bound.
    pub fn check(&self) -> Result<()> {
        let bad = |name: &str, v: f64, bound: &str| {
            Err(Error::InvalidOption {
                name: format!("lag law {name}"),
                message: format!("{v}: must be {bound}"),
            })
        };
        if !(self.tau1 > 0.0 && self.tau1 <= 100.0) {
            return bad("tau1", self.tau1, "in (0, 100] convective times");
        }
        if !(self.tau2 >= 0.0 && self.tau2 <= 100.0) {
            return bad("tau2", self.tau2, "in [0, 100] convective times");
        }
        if !(self.alpha_star > 0.0 && self.alpha_star < std::f64::consts::FRAC_PI_2) {
            return bad("alpha_star", self.alpha_star, "in (0, π/2) rad");
        }
        if !(self.pressure_lag >= 0.0 && self.pressure_lag <= 100.0) {
            return bad(
                "pressure_lag",
                self.pressure_lag,
                "in [0, 100] convective times",
            );
        }
        if !(self.rate_share.is_finite() && self.rate_share.abs() <= 1.0) {
            return bad("rate_share", self.rate_share, "in [-1, 1]");
        }
        if !(self.sharpness >= 1.0 && self.sharpness <= 50.0) {
            return bad("sharpness", self.sharpness, "in [1, 50]");
        }
        for (name, ch) in [("lift", &self.lift), ("moment", &self.moment)] {
            for (c, k) in &ch.terms {
                if !k.is_finite() {
                    return bad(
                        &format!("{name} coefficient of {}", c.label()),
                        *k,
                        "finite",
                    );
                }
            }
        }
        Ok(())
    }

    /// Static separation curve x₀(α) = 1/(1 + |α/α*|^{2m}) ∈ (0, 1].
    #[inline]
    pub fn x_static(&self, alpha: f64) -> f64 {
        1.0 / (1.0 + (alpha / self.alpha_star).abs().powf(2.0 * self.sharpness))
    }

    /// Effective angle α_e = α + ḣ/U \[rad\].
    #[inline]
    pub fn alpha_e(alpha: f64, h_dot_over_u: f64) -> f64 {
        alpha + h_dot_over_u
    }

    /// Input of the lag equation u = α_e − τ₂·q/2 \[rad\] (q = Bα̇/U).
    #[inline]
    pub fn input(&self, alpha_e: f64, q: f64) -> f64 {
        alpha_e - 0.5 * self.tau2 * q
    }

    /// dx/ds in convective time s = tU/b without a pressure lag: (x₀(u) − x)/τ₁, u the
    /// input at (α_e, q). Multiply by 2U/B for d/dt. With a pressure lag the separation
    /// follows the filtered input ([`LagLaw::x_rate_filtered`]).
    #[inline]
    pub fn x_rate(&self, alpha_e: f64, q: f64, x: f64) -> f64 {
        (self.x_static(self.input(alpha_e, q)) - x) / self.tau1
    }

    /// dx/ds in convective time at the filtered separation input `u_f` \[rad\]:
    /// (x₀(u_f) − x)/τ₁ (module docs of [`LagLaw::pressure_lag`]).
    #[inline]
    pub fn x_rate_filtered(&self, u_f: f64, x: f64) -> f64 {
        (self.x_static(u_f) - x) / self.tau1
    }

    /// (C_L, C_M) at (α_e, q, x) (the static separation of [`LagColumn::KirchhoffStatic`]
    /// taken at α_e).
    #[inline]
    pub fn coefficients(&self, alpha_e: f64, q: f64, x: f64) -> [f64; 2] {
        let xi = self.x_static(alpha_e);
        [
            self.lift.value(alpha_e, q, x, xi),
            self.moment.value(alpha_e, q, x, xi),
        ]
    }
}

/// Format tag of a lag-law document (`lag_law.json`).
pub const LAG_LAW_FORMAT: &str = "aeroform-lag-law/1";

/// The document `identify --law lag` writes (`lag_law.json`) and the model readers of
/// `flutter`, `lco`, `branch` and `tunnel` accept: the law and what it is dimensional with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LagLawDocument {
    /// Always [`LAG_LAW_FORMAT`].
    pub format: String,
    /// Name of the data set the law was fitted on.
    pub dataset: String,
    /// Chord B \[m\] of the records (the law itself is nondimensional).
    pub chord: f64,
    /// The fitted law.
    pub law: LagLaw,
    /// The fit's report (per-case R², parameter intervals and correlations, held-out
    /// comparison), as written by the identification; readers of the law ignore it.
    #[serde(default)]
    pub report: serde_json::Value,
}

impl LagLawDocument {
    /// Parses and checks a lag-law document.
    ///
    /// # Errors
    /// [`Error::Json`] for text that is not the document, a wrong `format` or a non-positive chord; the law's bounds
    /// ([`LagLaw::check`]).
    pub fn from_json(text: &str, path: &std::path::Path) -> Result<LagLawDocument> {
        let doc: LagLawDocument = serde_json::from_str(text).map_err(|e| Error::Json {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let bad = |field: &str, message: String| Error::Json {
            path: path.to_path_buf(),
            message: format!("field `{field}`: {message}"),
        };
        if doc.format != LAG_LAW_FORMAT {
            return Err(bad(
                "format",
                format!("{:?}, expected {LAG_LAW_FORMAT:?}", doc.format),
            ));
        }
        if !(doc.chord > 0.0 && doc.chord.is_finite()) {
            return Err(bad(
                "chord",
                format!("{} must be a positive length [m]", doc.chord),
            ));
        }
        doc.law.check()?;
        Ok(doc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> LagLaw {
        LagLaw {
            tau1: 3.0,
            tau2: 1.0,
            alpha_star: 0.25,
            sharpness: 4.0,
            lift: LagChannel {
                terms: vec![(LagColumn::Kirchhoff, -6.0)],
            },
            moment: LagChannel {
                terms: vec![(LagColumn::KirchhoffSep, -1.5), (LagColumn::Q, -0.5)],
            },
            range: FittedRange {
                alpha_e: [0.0, 0.5],
                k: [0.05, 0.2],
            },
            circulation_lag: false,
            rate_share: 0.0,
            pressure_lag: 0.0,
        }
    }

    #[test]
    fn circulation_lag_is_jones_and_steady_neutral() {
        // steady: α_c = α_e
        assert!((circulatory_angle(0.3, [0.3, 0.3]) - 0.3).abs() < 1e-15);
        assert_eq!(circulation_rates(0.3, [0.3, 0.3]), [0.0, 0.0]);
        // step response from rest is Wagner–Jones φ(s) = 1 − A₁e^{−b₁s} − A₂e^{−b₂s}
        let (mut z, ds) = ([0.0, 0.0], 1e-3);
        for _ in 0..20_000 {
            let r = circulation_rates(1.0, z);
            z = [z[0] + ds * r[0], z[1] + ds * r[1]];
        }
        let s: f64 = 20.0;
        let phi = 1.0 - 0.165 * (-0.0455 * s).exp() - 0.335 * (-0.3 * s).exp();
        assert!((circulatory_angle(1.0, z) - phi).abs() < 1e-3);
        // a document without the field keeps its meaning (off)
        let mut v = serde_json::to_value(law()).unwrap();
        v.as_object_mut().unwrap().remove("circulation_lag");
        let l: LagLaw = serde_json::from_value(v).unwrap();
        assert!(!l.circulation_lag);
    }

    #[test]
    fn instantaneous_static_column_is_the_kirchhoff_lift_in_steady_flow() {
        let mut l = law();
        l.lift.terms = vec![(LagColumn::KirchhoffStatic, -6.0)];
        for a in [0.0, 0.1, 0.25, 0.4] {
            let x0 = l.x_static(a);
            let steady = LagColumn::Kirchhoff.value(a, 0.0, x0, 1.0);
            assert!((l.coefficients(a, 0.0, x0)[0] + 6.0 * steady).abs() < 1e-12);
            // and it does not follow the lagged state
            assert_eq!(
                l.coefficients(a, 0.0, 0.0)[0],
                l.coefficients(a, 0.0, 1.0)[0]
            );
        }
        assert!(l.lift.uses_static() && !law().lift.uses_static());
        // documents written before the rate share read as 0; out of range is refused
        let mut v = serde_json::to_value(law()).unwrap();
        v.as_object_mut().unwrap().remove("rate_share");
        let r: LagLaw = serde_json::from_value(v).unwrap();
        assert_eq!(r.rate_share, 0.0);
        let mut v = serde_json::to_value(law()).unwrap();
        v.as_object_mut().unwrap().remove("pressure_lag");
        let r: LagLaw = serde_json::from_value(v).unwrap();
        assert_eq!(r.pressure_lag, 0.0);
        let mut l = law();
        l.pressure_lag = -0.1;
        assert!(l.check().unwrap_err().to_string().contains("pressure_lag"));
        // the blend is Kirchhoff's factor in steady flow, ¼ + … at full separation
        for x in [0.0, 0.2, 0.5, 1.0] {
            assert!((blend(x, x) - kirchhoff(x)).abs() < 1e-12, "{x}");
        }
        assert!((blend(0.0, 0.0) - 0.25).abs() < 1e-12);
        assert_eq!(blend(1.0, 0.3), 1.0);
        let mut l = law();
        l.rate_share = 1.5;
        assert!(l.check().unwrap_err().to_string().contains("rate_share"));
    }

    #[test]
    fn static_curve_is_attached_at_zero_and_half_at_alpha_star() {
        let l = law();
        assert_eq!(l.x_static(0.0), 1.0);
        assert!((l.x_static(0.25) - 0.5).abs() < 1e-12);
        assert!((l.x_static(-0.25) - 0.5).abs() < 1e-12);
        assert!(l.x_static(0.6) < 0.01);
        assert!(l.check().is_ok());
    }

    #[test]
    fn kirchhoff_is_one_attached_and_a_quarter_separated() {
        assert_eq!(kirchhoff(1.0), 1.0);
        assert_eq!(kirchhoff(0.0), 0.25);
        for &x in &[0.1, 0.5, 0.9] {
            let d = (kirchhoff(x + 1e-6) - kirchhoff(x - 1e-6)) / 2e-6;
            assert!((d - kirchhoff_dx(x)).abs() < 1e-6, "{x}: {d}");
        }
    }

    #[test]
    fn column_derivatives_match_differences() {
        for c in LagColumn::ALL {
            let (a, q, x) = (0.3, 0.05, 0.4);
            let d = (c.value(a, q, x + 1e-6, 0.7) - c.value(a, q, x - 1e-6, 0.7)) / 2e-6;
            assert!((d - c.d_dx_at(a, q, x, 0.7)).abs() < 1e-6, "{c:?}");
        }
    }

    #[test]
    fn bounds_are_checked_by_name() {
        let mut l = law();
        l.tau1 = -1.0;
        assert!(l.check().unwrap_err().to_string().contains("tau1"));
        let mut l = law();
        l.sharpness = 0.5;
        assert!(l.check().unwrap_err().to_string().contains("sharpness"));
    }
}
