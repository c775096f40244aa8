//! The 2-DOF heave/pitch section per unit span (DESIGN.md §4):
//!
//! m ḧ + S_α α̈ + c_h ḣ + F_h(h, ḣ) = L,   S_α ḧ + I_α α̈ + c_α α̇ + M_α(α, α̇) = M,
//!
//! h positive down \[m\], α positive nose-up \[rad\], L positive down \[N/m\], M nose-up about the
//! elastic axis \[N·m/m\]; S_α = m x_α > 0 when the mass centre is aft of the elastic axis.
//! The restoring terms are F_h = k_h h + Σ c_p h^p + F_c tanh(ḣ/ε_h) and
//! M_α = k_α d + Σ c_p d^p + T_c tanh(α̇/ε_α), with the spring deflection d = α for no
//! freeplay and d = α − δ sign α (|α| > δ), 0 (|α| ≤ δ) for a pitch freeplay of half gap δ.

use nalgebra::Matrix2;
use serde::{Deserialize, Serialize};

use identify::dataset::ModalStructure;

use crate::error::{finite, non_negative, positive};
use crate::{Error, Result};

/// One polynomial stiffness term c·x^p added to a linear spring.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PolyTerm {
    /// Power p ≥ 2 (3 = cubic, 5 = quintic…).
    pub power: u32,
    /// Coefficient c [N/m^p per unit span for heave, N·m/rad^p per unit span for pitch];
    /// c > 0 hardens an odd term, c < 0 softens it.
    pub coefficient: f64,
}

/// Adds `coefficient`·x^`power` to `terms`: to the term of that power when there is one,
/// as a new term otherwise.
pub fn add_poly_term(terms: &mut Vec<PolyTerm>, power: u32, coefficient: f64) {
    match terms.iter_mut().find(|t| t.power == power) {
        Some(t) => t.coefficient += coefficient,
        None => terms.push(PolyTerm { power, coefficient }),
    }
}

/// Coulomb (dry) friction, regularised as F_c tanh(v/ε) so that the explicit integrator is
/// not stiff: near v = 0 it acts as a viscous damper F_c/ε, and that slope is what sets
/// the stiffness. The default ε ([`Friction::default_smoothing`]) makes that slope equal
/// to a damping ratio of 5 on the uncoupled mode, which Dop853 integrates at ~30 steps per
/// cycle while the friction force reaches 99 % of F_c for |v| > 2.6 ε.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    /// Heave friction force F_c \[N/m\], ≥ 0.
    #[serde(default)]
    pub heave_force: f64,
    /// Pitch friction moment T_c \[N·m/m\], ≥ 0.
    #[serde(default)]
    pub pitch_moment: f64,
    /// Heave smoothing velocity ε_h \[m/s\]; `None` = [`Friction::default_smoothing`].
    #[serde(default)]
    pub heave_smoothing: Option<f64>,
    /// Pitch smoothing rate ε_α \[rad/s\]; `None` = [`Friction::default_smoothing`].
    #[serde(default)]
    pub pitch_smoothing: Option<f64>,
}

impl Friction {
    /// Default smoothing scale ε = F_c / (2·5·m ω) for a friction force `force` acting on a
    /// mode of generalised mass `mass` and natural frequency `omega` [rad/s]: the
    /// regularised slope F_c/ε then equals a viscous damping ratio of 5.
    pub fn default_smoothing(force: f64, mass: f64, omega: f64) -> f64 {
        (force / (10.0 * mass * omega)).max(f64::MIN_POSITIVE)
    }
}

/// Structural parameters of the section per unit span, SI units: the one resolved type every
/// analysis simulates with (and the [`StructureSpec::Si`] form).
///
/// Loadable from TOML ([`Structure::from_toml_str`]); unknown keys are rejected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Structure {
    /// Mass per unit span m \[kg/m\].
    pub mass: f64,
    /// Pitch inertia about the elastic axis I_α \[kg·m²/m\].
    pub inertia_alpha: f64,
    /// Static unbalance S_α = m x_α \[kg·m/m\], positive when the mass centre is aft of the
    /// elastic axis.
    #[serde(default)]
    pub static_unbalance: f64,
    /// Heave stiffness k_h [N/m per m span].
    pub k_h: f64,
    /// Pitch stiffness k_α [N·m/rad per m span].
    pub k_alpha: f64,
    /// Heave viscous damping c_h [N·s/m per m span].
    #[serde(default)]
    pub c_h: f64,
    /// Pitch viscous damping c_α [N·m·s/rad per m span].
    #[serde(default)]
    pub c_alpha: f64,
    /// The nonlinear restoring terms (polynomial stiffness, pitch freeplay, friction); none
    /// by default. In TOML the table `[nonlinear]`.
    #[serde(default)]
    pub nonlinear: Nonlinearities,
}

/// Nondimensional description of a typical section (Hodges & Pierce notation) plus the
/// dimensional scales needed to build a [`Structure`]: the linear part of the
/// [`StructureSpec::Nondimensional`] form (a study file's `[structure]`).
///
/// Serde form: the keys below, unknown keys rejected; `mu`, `r_alpha2` and `sigma` are
/// required, `semi_chord`, `omega_alpha` and `rho` default to 1 (a problem in units of b,
/// 1/ω_α and ρ), `x_alpha` and the damping ratios to 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NondimStructure {
    /// Mass ratio μ = m / (πρb²), > 0.
    pub mu: f64,
    /// Squared radius of gyration about the elastic axis r² = I_α / (m b²), > x_α².
    pub r_alpha2: f64,
    /// Frequency ratio σ = ω_h / ω_α (uncoupled), ≥ 0.
    pub sigma: f64,
    /// Mass-centre offset aft of the elastic axis x_α in semi-chords (x_α = e − a).
    #[serde(default)]
    pub x_alpha: f64,
    /// Semi-chord b = B/2 \[m\], > 0.
    #[serde(default = "one")]
    pub semi_chord: f64,
    /// Uncoupled pitch natural frequency ω_α = sqrt(k_α/I_α) \[rad/s\], > 0.
    #[serde(default = "one")]
    pub omega_alpha: f64,
    /// Air density ρ \[kg/m³\] used in μ, > 0.
    #[serde(default = "one")]
    pub rho: f64,
    /// Heave damping ratio ζ_h (c_h = 2 ζ_h m ω_h), ≥ 0.
    #[serde(default)]
    pub zeta_h: f64,
    /// Pitch damping ratio ζ_α (c_α = 2 ζ_α I_α ω_α), ≥ 0.
    #[serde(default)]
    pub zeta_alpha: f64,
}

fn one() -> f64 {
    1.0
}

impl NondimStructure {
    /// Mass per unit span m = μπρb² \[kg/m\].
    pub fn mass(&self) -> f64 {
        let b = self.semi_chord;
        self.mu * std::f64::consts::PI * self.rho * b * b
    }

    /// Pitch inertia about the elastic axis I_α = r² m b² \[kg·m²/m\].
    pub fn inertia_alpha(&self) -> f64 {
        let b = self.semi_chord;
        self.r_alpha2 * self.mass() * b * b
    }

    /// Pitch stiffness k_α = I_α ω_α² \[N·m/rad per m span\] (what a relative pitch
    /// cubic k multiplies: the term k_α k α³).
    pub fn k_alpha(&self) -> f64 {
        self.inertia_alpha() * self.omega_alpha * self.omega_alpha
    }

    /// The nondimensional form of the modal (frequency) form `m` for air density `rho`
    /// \[kg/m³\] and semi-chord `semi_chord` \[m\]: μ = m/(πρb²), σ = f_h/f_α,
    /// x_α = S_α/(m b), r² = I_α/(m b²), ω_α = 2πf_α, the damping ratios kept. The inverse
    /// of [`NondimStructure::modal`]; no check (see [`Structure::from_nondimensional`]).
    pub fn from_modal(m: &ModalStructure, rho: f64, semi_chord: f64) -> Self {
        let b = semi_chord;
        NondimStructure {
            mu: m.mass / (std::f64::consts::PI * rho * b * b),
            r_alpha2: m.inertia / (m.mass * b * b),
            sigma: m.freq_heave / m.freq_pitch,
            x_alpha: m.static_unbalance / (m.mass * b),
            semi_chord: b,
            omega_alpha: 2.0 * std::f64::consts::PI * m.freq_pitch,
            rho,
            zeta_h: m.damping_heave,
            zeta_alpha: m.damping_pitch,
        }
    }

    /// The modal (frequency) form: m = μπρb², I_α = r² m b², S_α = x_α m b,
    /// f_α = ω_α/2π, f_h = σ f_α, the damping ratios kept.
    pub fn modal(&self) -> ModalStructure {
        let m = self.mass();
        let f_alpha = self.omega_alpha / (2.0 * std::f64::consts::PI);
        ModalStructure {
            mass: m,
            inertia: self.inertia_alpha(),
            static_unbalance: self.x_alpha * m * self.semi_chord,
            freq_heave: self.sigma * f_alpha,
            freq_pitch: f_alpha,
            damping_heave: self.zeta_h,
            damping_pitch: self.zeta_alpha,
        }
    }
}

/// The nonlinear restoring terms of a structure, declared once for every
/// [`StructureSpec`] form and held by [`Structure::nonlinear`]: polynomial stiffness terms
/// (heave on h \[m\], pitch on the spring deflection d \[rad\]), pitch freeplay and Coulomb
/// friction (the restoring terms of the module docs).
///
/// Serde form: the keys below (all optional), unknown keys rejected.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Nonlinearities {
    /// Extra heave stiffness terms Σ c_p h^p.
    #[serde(default)]
    pub heave_stiffness_terms: Vec<PolyTerm>,
    /// Extra pitch stiffness terms Σ c_p d^p on the spring deflection d.
    #[serde(default)]
    pub pitch_stiffness_terms: Vec<PolyTerm>,
    /// Amplitude-dependent heave damping Σ c_p h^p ḣ [N s/m^(p+1)] (power p ≥ 1; p = 2 is
    /// the damping c_h(1 + d h²) with c_2 = c_h d); c > 0 dissipates.
    #[serde(default)]
    pub heave_damping_terms: Vec<PolyTerm>,
    /// Amplitude-dependent pitch damping Σ c_p α^p α̇ [N m s/rad^(p+1)] (power p ≥ 1, on α,
    /// not on the freeplay deflection); c > 0 dissipates.
    #[serde(default)]
    pub pitch_damping_terms: Vec<PolyTerm>,
    /// Pitch freeplay half gap δ \[rad\] (zero stiffness for |α| < δ); 0 = none.
    #[serde(default)]
    pub pitch_freeplay: f64,
    /// Coulomb friction, if any.
    #[serde(default)]
    pub friction: Option<Friction>,
}

impl Nonlinearities {
    /// The keys of the nonlinear terms, in documented order.
    pub const KEYS: [&'static str; 6] = [
        "heave_stiffness_terms",
        "pitch_stiffness_terms",
        "heave_damping_terms",
        "pitch_damping_terms",
        "pitch_freeplay",
        "friction",
    ];

    /// No nonlinear term (a linear structure).
    pub fn none() -> Self {
        Self::default()
    }

    /// Whether there is no nonlinear term at all (no polynomial term, no freeplay, no
    /// friction table).
    pub fn is_empty(&self) -> bool {
        self.heave_stiffness_terms.is_empty()
            && self.pitch_stiffness_terms.is_empty()
            && self.heave_damping_terms.is_empty()
            && self.pitch_damping_terms.is_empty()
            && self.pitch_freeplay == 0.0
            && self.friction.is_none()
    }
}

/// The structure of the section in one of its three input forms, each resolving to the one
/// SI working type [`Structure`] ([`StructureSpec::resolve`]).
///
/// - [`StructureSpec::Si`]: springs and dampers in SI, i.e. a [`Structure`] itself (with
///   its own nonlinear fields).
/// - [`StructureSpec::Modal`]: masses, uncoupled frequencies \[Hz\] and damping ratios
///   ([`ModalStructure`]: a structure file, a data-set manifest's `[structure]`).
/// - [`StructureSpec::Nondimensional`]: Hodges & Pierce parameters ([`NondimStructure`]:
///   a study file's `[structure]`).
///
/// Serde form: externally tagged (`{ modal = { linear = {…}, nonlinear = {…} } }`); the
/// files keep their flat layouts and build the spec in code.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum StructureSpec {
    /// SI springs and dampers (and nonlinear terms): the structure as it is simulated.
    Si(Structure),
    /// Frequency form: k = m (2πf)², c = 2ζ m 2πf per DOF (m → I_α in pitch).
    Modal {
        /// The linear structure.
        linear: ModalStructure,
        /// The nonlinear terms.
        #[serde(default)]
        nonlinear: Nonlinearities,
    },
    /// Nondimensional form (see [`Structure::from_nondimensional`]).
    Nondimensional {
        /// The linear structure (with its dimensional scales b, ω_α, ρ).
        linear: NondimStructure,
        /// The nonlinear terms, SI.
        #[serde(default)]
        nonlinear: Nonlinearities,
    },
}

impl StructureSpec {
    /// The SI structure this spec describes, validated.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad field in the spec's own key names:
    /// `mass`, `inertia`, `freq_pitch`… for the modal form ([`Structure::from_modal`]),
    /// `mu`, `r_alpha2`… for the nondimensional form, the [`Structure`] field names for the
    /// SI form and for the nonlinear terms (`pitch_stiffness_terms[1].power`…; see
    /// [`Structure::validate`]).
    pub fn resolve(&self) -> Result<Structure> {
        let (linear, nonlinear) = match self {
            StructureSpec::Si(s) => {
                s.validate()?;
                return Ok(s.clone());
            }
            StructureSpec::Modal { linear, nonlinear } => {
                (Structure::from_modal(linear)?, nonlinear)
            }
            StructureSpec::Nondimensional { linear, nonlinear } => {
                (Structure::from_nondimensional(linear)?, nonlinear)
            }
        };
        let s = Structure {
            nonlinear: nonlinear.clone(),
            ..linear
        };
        s.validate().map_err(|e| match self {
            StructureSpec::Modal { .. } => modal_field_names(e),
            _ => e,
        })?;
        Ok(s)
    }

    /// The nonlinear terms of the spec (those of the [`Structure`] for the SI form).
    pub fn nonlinearities(&self) -> Nonlinearities {
        match self {
            StructureSpec::Si(s) => s.nonlinear.clone(),
            StructureSpec::Modal { nonlinear, .. }
            | StructureSpec::Nondimensional { nonlinear, .. } => nonlinear.clone(),
        }
    }
}

/// A [`Structure::validate`] error in the key names of the modal form (`inertia_alpha` →
/// `inertia`).
fn modal_field_names(e: Error) -> Error {
    e.map_field(|field| match field.as_str() {
        "inertia_alpha" => "inertia".into(),
        _ => field,
    })
}

impl Structure {
    /// Builds a linear structure from SI rig values (mass m, pitch inertia about the elastic
    /// axis I_α, mass-centre offset x_α \[m\] aft of the elastic axis, springs and dampers).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad field (see [`Structure::validate`]).
    #[allow(clippy::too_many_arguments)]
    pub fn from_rig(
        mass: f64,
        inertia_alpha: f64,
        x_alpha_m: f64,
        k_h: f64,
        k_alpha: f64,
        c_h: f64,
        c_alpha: f64,
    ) -> Result<Self> {
        finite("x_alpha_m", x_alpha_m)?;
        let s = Structure {
            mass,
            inertia_alpha,
            static_unbalance: mass * x_alpha_m,
            k_h,
            k_alpha,
            c_h,
            c_alpha,
            nonlinear: Nonlinearities::none(),
        };
        s.validate()?;
        Ok(s)
    }

    /// Builds a linear structure from nondimensional parameters:
    /// m = μπρb², I_α = r² m b², S_α = m x_α b, k_α = I_α ω_α², k_h = m (σ ω_α)²,
    /// c_h = 2 ζ_h m σ ω_α, c_α = 2 ζ_α I_α ω_α.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad nondimensional field (`mu`, `r_alpha2`…).
    pub fn from_nondimensional(p: &NondimStructure) -> Result<Self> {
        positive("mu", p.mu)?;
        positive("r_alpha2", p.r_alpha2)?;
        non_negative("sigma", p.sigma)?;
        finite("x_alpha", p.x_alpha)?;
        positive("semi_chord", p.semi_chord)?;
        positive("omega_alpha", p.omega_alpha)?;
        positive("rho", p.rho)?;
        non_negative("zeta_h", p.zeta_h)?;
        non_negative("zeta_alpha", p.zeta_alpha)?;
        if p.r_alpha2 <= p.x_alpha * p.x_alpha {
            return Err(Error::param(
                "r_alpha2",
                p.r_alpha2,
                format!(
                    "must exceed x_alpha² = {} (positive-definite mass matrix)",
                    p.x_alpha * p.x_alpha
                ),
            ));
        }
        let b = p.semi_chord;
        let m = p.mass();
        let i_a = p.inertia_alpha();
        let w_h = p.sigma * p.omega_alpha;
        let s = Structure {
            mass: m,
            inertia_alpha: i_a,
            static_unbalance: m * p.x_alpha * b,
            k_h: m * w_h * w_h,
            k_alpha: p.k_alpha(),
            c_h: 2.0 * p.zeta_h * m * w_h,
            c_alpha: 2.0 * p.zeta_alpha * i_a * p.omega_alpha,
            nonlinear: Nonlinearities::none(),
        };
        s.validate()?;
        Ok(s)
    }

    /// Builds a linear structure from the modal (frequency) form: k_h = m (2πf_h)²,
    /// k_α = I_α (2πf_α)², c_h = 2ζ_h m 2πf_h, c_α = 2ζ_α I_α 2πf_α.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad modal key: `mass` or `inertia` ≤ 0,
    /// `freq_heave` < 0, `freq_pitch` ≤ 0, a damping ratio < 0, `static_unbalance` with
    /// S_α² ≥ m I_α (see [`Structure::validate`]).
    pub fn from_modal(p: &ModalStructure) -> Result<Self> {
        positive("mass", p.mass)?;
        positive("inertia", p.inertia)?;
        non_negative("freq_heave", p.freq_heave)?;
        positive("freq_pitch", p.freq_pitch)?;
        non_negative("damping_heave", p.damping_heave)?;
        non_negative("damping_pitch", p.damping_pitch)?;
        use identify::limits::{show, MAX_DAMPING_RATIO};
        for (name, zeta) in [
            ("damping_heave", p.damping_heave),
            ("damping_pitch", p.damping_pitch),
        ] {
            if zeta > MAX_DAMPING_RATIO {
                return Err(Error::param(
                    name,
                    zeta,
                    format!(
                        "a damping ratio must be ≤ {} (critical damping: an overdamped \
                         mode does not oscillate)",
                        show(MAX_DAMPING_RATIO)
                    ),
                ));
            }
        }
        let tau = 2.0 * std::f64::consts::PI;
        let (wh, wa) = (tau * p.freq_heave, tau * p.freq_pitch);
        // the springs and dampers derived from the fields must be representable: named by
        // the fields they come from (before: `k_alpha = 0` for freq_pitch = 1e-300)
        let derived = [
            (
                "freq_heave",
                p.freq_heave,
                "mass",
                p.mass,
                p.mass * wh * wh,
                p.freq_heave > 0.0,
            ),
            (
                "freq_pitch",
                p.freq_pitch,
                "inertia",
                p.inertia,
                p.inertia * wa * wa,
                true,
            ),
        ];
        for (f, fv, m, mv, k, must_be_positive) in derived {
            if !k.is_finite() || (must_be_positive && k <= 0.0) {
                return Err(Error::param(
                    f,
                    fv,
                    format!(
                        "with {m} = {} the spring {m}·(2π·{f})² = {} is not a finite \
                         positive number",
                        show(mv),
                        show(k)
                    ),
                ));
            }
        }
        let s = Structure {
            mass: p.mass,
            inertia_alpha: p.inertia,
            static_unbalance: p.static_unbalance,
            k_h: p.mass * wh * wh,
            k_alpha: p.inertia * wa * wa,
            c_h: 2.0 * p.damping_heave * p.mass * wh,
            c_alpha: 2.0 * p.damping_pitch * p.inertia * wa,
            nonlinear: Nonlinearities::none(),
        };
        s.validate().map_err(modal_field_names)?;
        Ok(s)
    }

    /// The modal (frequency) form of this structure's linear part, the inverse of
    /// [`Structure::from_modal`]: frequencies sqrt(k/m)/2π of the uncoupled modes and
    /// damping ratios c/(2 m ω) (a data-set manifest's `[structure]`; the nonlinear terms
    /// are not part of it).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `structure.k_h` when k_h = 0 (a free heave DOF
    /// has no natural frequency).
    pub fn modal(&self) -> Result<ModalStructure> {
        positive("structure.k_h", self.k_h)?;
        let (wh, wa) = (self.omega_h(), self.omega_alpha());
        Ok(ModalStructure {
            mass: self.mass,
            inertia: self.inertia_alpha,
            static_unbalance: self.static_unbalance,
            freq_heave: wh / (2.0 * std::f64::consts::PI),
            freq_pitch: wa / (2.0 * std::f64::consts::PI),
            damping_heave: self.c_h / (2.0 * self.mass * wh),
            damping_pitch: self.c_alpha / (2.0 * self.inertia_alpha * wa),
        })
    }

    /// Parses a TOML table with the fields of [`Structure`] (SI), rejecting unknown keys,
    /// then validates it.
    ///
    /// # Errors
    /// [`Error::Toml`] with the parser's line/column for syntax, type or unknown-key errors;
    /// [`Error::InvalidParameter`] for values out of range.
    pub fn from_toml_str(s: &str) -> Result<Self> {
        let st: Structure = toml::from_str(s).map_err(|e| Error::Toml {
            source_name: "<structure>".into(),
            message: e.to_string(),
        })?;
        st.validate()?;
        Ok(st)
    }

    /// Checks every field: masses and inertia > 0, m I_α > S_α² (positive-definite mass
    /// matrix), stiffnesses and dampers ≥ 0, polynomial powers ≥ 2 with finite
    /// coefficients, freeplay ≥ 0, friction forces ≥ 0 and smoothing scales > 0.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad field, e.g.
    /// `pitch_stiffness_terms[1].power`.
    pub fn validate(&self) -> Result<()> {
        positive("mass", self.mass)?;
        positive("inertia_alpha", self.inertia_alpha)?;
        finite("static_unbalance", self.static_unbalance)?;
        if self.mass * self.inertia_alpha <= self.static_unbalance * self.static_unbalance {
            return Err(Error::param(
                "static_unbalance",
                self.static_unbalance,
                format!(
                    "S_α² must be < m I_α = {} (positive-definite mass matrix)",
                    identify::limits::show(self.mass * self.inertia_alpha)
                ),
            ));
        }
        non_negative("k_h", self.k_h)?;
        positive("k_alpha", self.k_alpha)?;
        non_negative("c_h", self.c_h)?;
        non_negative("c_alpha", self.c_alpha)?;
        for (name, terms) in [
            (
                "heave_stiffness_terms",
                &self.nonlinear.heave_stiffness_terms,
            ),
            (
                "pitch_stiffness_terms",
                &self.nonlinear.pitch_stiffness_terms,
            ),
        ] {
            for (i, t) in terms.iter().enumerate() {
                if t.power < 2 {
                    return Err(Error::param(
                        format!("{name}[{i}].power"),
                        t.power as f64,
                        "must be >= 2 (the linear term is k_h / k_alpha)",
                    ));
                }
                finite(&format!("{name}[{i}].coefficient"), t.coefficient)?;
            }
        }
        for (name, terms) in [
            ("heave_damping_terms", &self.nonlinear.heave_damping_terms),
            ("pitch_damping_terms", &self.nonlinear.pitch_damping_terms),
        ] {
            for (i, t) in terms.iter().enumerate() {
                if t.power < 1 {
                    return Err(Error::param(
                        format!("{name}[{i}].power"),
                        t.power as f64,
                        "must be >= 1 (the constant term is c_h / c_alpha)",
                    ));
                }
                finite(&format!("{name}[{i}].coefficient"), t.coefficient)?;
            }
        }
        non_negative("pitch_freeplay", self.nonlinear.pitch_freeplay)?;
        if let Some(f) = &self.nonlinear.friction {
            non_negative("friction.heave_force", f.heave_force)?;
            non_negative("friction.pitch_moment", f.pitch_moment)?;
            if let Some(e) = f.heave_smoothing {
                positive("friction.heave_smoothing", e)?;
            }
            if let Some(e) = f.pitch_smoothing {
                positive("friction.pitch_smoothing", e)?;
            }
        }
        Ok(())
    }

    /// Uncoupled pitch natural frequency ω_α = sqrt(k_α / I_α) \[rad/s\].
    pub fn omega_alpha(&self) -> f64 {
        (self.k_alpha / self.inertia_alpha).sqrt()
    }

    /// Uncoupled heave natural frequency ω_h = sqrt(k_h / m) \[rad/s\].
    pub fn omega_h(&self) -> f64 {
        (self.k_h / self.mass).sqrt()
    }

    /// Mass matrix [[m, S_α], [S_α, I_α]].
    pub fn mass_matrix(&self) -> Matrix2<f64> {
        Matrix2::new(
            self.mass,
            self.static_unbalance,
            self.static_unbalance,
            self.inertia_alpha,
        )
    }

    /// Linear damping matrix diag(c_h, c_α).
    pub fn damping_matrix(&self) -> Matrix2<f64> {
        Matrix2::new(self.c_h, 0.0, 0.0, self.c_alpha)
    }

    /// Linear stiffness matrix diag(k_h, k_α) about the origin. Flutter analysis uses it:
    /// polynomial terms vanish there, freeplay and friction are nonsmooth and are ignored
    /// (the nominal spring k_α is used, i.e. the large-amplitude linear system).
    pub fn stiffness_matrix(&self) -> Matrix2<f64> {
        Matrix2::new(self.k_h, 0.0, 0.0, self.k_alpha)
    }

    /// Whether the restoring forces are exactly linear (no polynomial, freeplay, friction).
    pub fn is_linear(&self) -> bool {
        self.nonlinear.heave_stiffness_terms.is_empty()
            && self.nonlinear.pitch_stiffness_terms.is_empty()
            && self.nonlinear.heave_damping_terms.is_empty()
            && self.nonlinear.pitch_damping_terms.is_empty()
            && self.nonlinear.pitch_freeplay == 0.0
            && self
                .nonlinear
                .friction
                .is_none_or(|f| f.heave_force == 0.0 && f.pitch_moment == 0.0)
    }

    /// Resolved friction (F_c, ε_h, T_c, ε_α) with defaults applied; zeros when absent.
    pub(crate) fn friction_resolved(&self) -> [f64; 4] {
        match &self.nonlinear.friction {
            None => [0.0, 1.0, 0.0, 1.0],
            Some(f) => {
                let eh = f.heave_smoothing.unwrap_or_else(|| {
                    Friction::default_smoothing(f.heave_force, self.mass, self.omega_h().max(1e-12))
                });
                let ea = f.pitch_smoothing.unwrap_or_else(|| {
                    Friction::default_smoothing(
                        f.pitch_moment,
                        self.inertia_alpha,
                        self.omega_alpha(),
                    )
                });
                [f.heave_force, eh, f.pitch_moment, ea]
            }
        }
    }

    /// Total structural restoring forces (F_h, M_α) — damping, springs, polynomial terms,
    /// freeplay and regularised friction — at displacement `q = (h, α)` and velocity
    /// `qd = (ḣ, α̇)`; the equations of motion are M q̈ + (F_h, M_α) = (L, M).
    pub fn restoring(&self, q: [f64; 2], qd: [f64; 2]) -> [f64; 2] {
        let friction = self.friction_resolved();
        self.restoring_with(q, qd, &friction)
    }

    /// [`Structure::restoring`] with friction already resolved (hot path of integration).
    #[inline]
    pub(crate) fn restoring_with(&self, q: [f64; 2], qd: [f64; 2], fr: &[f64; 4]) -> [f64; 2] {
        let h = q[0];
        let mut fh = self.c_h * qd[0] + self.k_h * h;
        for t in &self.nonlinear.heave_stiffness_terms {
            fh += t.coefficient * h.powi(t.power as i32);
        }
        for t in &self.nonlinear.heave_damping_terms {
            fh += t.coefficient * h.powi(t.power as i32) * qd[0];
        }
        let a = q[1];
        let d = if self.nonlinear.pitch_freeplay > 0.0 {
            if a > self.nonlinear.pitch_freeplay {
                a - self.nonlinear.pitch_freeplay
            } else if a < -self.nonlinear.pitch_freeplay {
                a + self.nonlinear.pitch_freeplay
            } else {
                0.0
            }
        } else {
            a
        };
        let mut ma = self.c_alpha * qd[1] + self.k_alpha * d;
        for t in &self.nonlinear.pitch_stiffness_terms {
            ma += t.coefficient * d.powi(t.power as i32);
        }
        for t in &self.nonlinear.pitch_damping_terms {
            ma += t.coefficient * a.powi(t.power as i32) * qd[1];
        }
        if fr[0] > 0.0 {
            fh += fr[0] * (qd[0] / fr[1]).tanh();
        }
        if fr[2] > 0.0 {
            ma += fr[2] * (qd[1] / fr[3]).tanh();
        }
        [fh, ma]
    }

    /// Analytic ∂R/∂(h, α, ḣ, α̇) of [`Structure::restoring_with`] (rows F_h, M_α): the
    /// linear springs and dampers, p·c·x^(p−1) of each polynomial term, F_c/ε·sech²(v/ε) of
    /// the regularised friction `fr` (as [`Structure::friction_resolved`]); inside a freeplay
    /// gap the pitch spring's slope is 0 (one-sided at its edges).
    pub(crate) fn restoring_derivatives(
        &self,
        q: [f64; 2],
        qd: [f64; 2],
        fr: &[f64; 4],
    ) -> [[f64; 4]; 2] {
        let mut out = [[0.0; 4]; 2];
        let h = q[0];
        out[0][0] = self.k_h;
        for t in &self.nonlinear.heave_stiffness_terms {
            out[0][0] += t.coefficient * t.power as f64 * h.powi(t.power as i32 - 1);
        }
        out[0][2] = self.c_h;
        for t in &self.nonlinear.heave_damping_terms {
            let p = t.power as i32;
            out[0][0] += t.coefficient * p as f64 * h.powi(p - 1) * qd[0];
            out[0][2] += t.coefficient * h.powi(p);
        }
        let a = q[1];
        let gap = self.nonlinear.pitch_freeplay;
        let (d, slope) = if gap > 0.0 {
            if a > gap {
                (a - gap, 1.0)
            } else if a < -gap {
                (a + gap, 1.0)
            } else {
                (0.0, 0.0)
            }
        } else {
            (a, 1.0)
        };
        let mut ka = self.k_alpha;
        for t in &self.nonlinear.pitch_stiffness_terms {
            ka += t.coefficient * t.power as f64 * d.powi(t.power as i32 - 1);
        }
        out[1][1] = slope * ka;
        out[1][3] = self.c_alpha;
        for t in &self.nonlinear.pitch_damping_terms {
            let p = t.power as i32;
            out[1][1] += t.coefficient * p as f64 * a.powi(p - 1) * qd[1];
            out[1][3] += t.coefficient * a.powi(p);
        }
        if fr[0] > 0.0 {
            let c = (qd[0] / fr[1]).cosh();
            out[0][2] += fr[0] / fr[1] / (c * c);
        }
        if fr[2] > 0.0 {
            let c = (qd[1] / fr[3]).cosh();
            out[1][3] += fr[2] / fr[3] / (c * c);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hp1() -> NondimStructure {
        NondimStructure {
            mu: 20.0,
            r_alpha2: 6.0 / 25.0,
            sigma: 0.4,
            x_alpha: 0.1,
            semi_chord: 0.5,
            omega_alpha: 10.0,
            rho: 1.225,
            zeta_h: 0.0,
            zeta_alpha: 0.0,
        }
    }

    #[test]
    fn nondimensional_constructor_reproduces_its_parameters() {
        let p = hp1();
        let s = Structure::from_nondimensional(&p).unwrap();
        let b = p.semi_chord;
        let mu = s.mass / (std::f64::consts::PI * p.rho * b * b);
        assert!((mu - 20.0).abs() < 1e-12);
        assert!((s.inertia_alpha / (s.mass * b * b) - 0.24).abs() < 1e-12);
        assert!((s.omega_h() / s.omega_alpha() - 0.4).abs() < 1e-12);
        assert!((s.static_unbalance / (s.mass * b) - 0.1).abs() < 1e-12);
        assert!((s.omega_alpha() - 10.0).abs() < 1e-12);
    }

    #[test]
    fn nondimensional_and_modal_forms_are_inverse() {
        let p = NondimStructure {
            zeta_h: 0.01,
            zeta_alpha: 0.02,
            ..hp1()
        };
        let m = p.modal();
        // the modal form resolves to the structure the nondimensional form resolves to
        let (a, b) = (
            Structure::from_nondimensional(&p).unwrap(),
            Structure::from_modal(&m).unwrap(),
        );
        for (x, y) in [
            (a.mass, b.mass),
            (a.inertia_alpha, b.inertia_alpha),
            (a.static_unbalance, b.static_unbalance),
            (a.k_h, b.k_h),
            (a.k_alpha, b.k_alpha),
            (a.c_h, b.c_h),
            (a.c_alpha, b.c_alpha),
        ] {
            assert!((x - y).abs() <= 1e-12 * x.abs().max(1e-300), "{x} vs {y}");
        }
        let q = NondimStructure::from_modal(&m, p.rho, p.semi_chord);
        for (x, y) in [
            (p.mu, q.mu),
            (p.r_alpha2, q.r_alpha2),
            (p.sigma, q.sigma),
            (p.x_alpha, q.x_alpha),
            (p.omega_alpha, q.omega_alpha),
            (p.zeta_h, q.zeta_h),
            (p.zeta_alpha, q.zeta_alpha),
        ] {
            assert!((x - y).abs() <= 1e-14 * x.abs(), "{x} vs {y}");
        }
    }

    #[test]
    fn validation_names_the_field() {
        let mut p = hp1();
        p.mu = -1.0;
        let e = Structure::from_nondimensional(&p).unwrap_err();
        assert!(e.to_string().contains("`mu`"), "{e}");
        let mut p = hp1();
        p.x_alpha = 0.6; // x² = 0.36 > r² = 0.24
        let e = Structure::from_nondimensional(&p).unwrap_err();
        assert!(e.to_string().contains("r_alpha2"), "{e}");
        let mut s = Structure::from_nondimensional(&hp1()).unwrap();
        s.nonlinear.pitch_stiffness_terms.push(PolyTerm {
            power: 1,
            coefficient: 3.0,
        });
        let e = s.validate().unwrap_err();
        assert!(
            e.to_string().contains("pitch_stiffness_terms[0].power"),
            "{e}"
        );
        let e = Structure::from_rig(1.0, 1.0, 0.0, 1.0, f64::NAN, 0.0, 0.0).unwrap_err();
        assert!(e.to_string().contains("k_alpha"), "{e}");
        // modal fields whose springs under- or overflow, and overdamped modes, are named
        // by the field the user wrote (issue 27, row 17: `k_alpha = 0` before)
        let modal = ModalStructure {
            mass: 1.0,
            inertia: 0.01,
            static_unbalance: 0.0,
            freq_heave: 2.0,
            freq_pitch: 3.5,
            damping_heave: 0.005,
            damping_pitch: 0.005,
        };
        assert!(Structure::from_modal(&modal).is_ok());
        for (m, field) in [
            (
                ModalStructure {
                    freq_pitch: 1e-300,
                    ..modal
                },
                "freq_pitch",
            ),
            (
                ModalStructure {
                    freq_pitch: 1e300,
                    ..modal
                },
                "freq_pitch",
            ),
            (
                ModalStructure {
                    freq_heave: 1e300,
                    ..modal
                },
                "freq_heave",
            ),
            (
                ModalStructure {
                    damping_pitch: 2.0,
                    ..modal
                },
                "damping_pitch",
            ),
            (
                ModalStructure {
                    damping_heave: 1e300,
                    ..modal
                },
                "damping_heave",
            ),
        ] {
            let e = Structure::from_modal(&m).unwrap_err().to_string();
            assert!(e.contains(field) && !e.contains("k_alpha"), "{field}: {e}");
        }
    }

    #[test]
    fn toml_round_trip_and_unknown_key_rejected() {
        let text = r#"
            mass = 3.0
            inertia_alpha = 0.02
            static_unbalance = 0.01
            k_h = 1000.0
            k_alpha = 50.0
            c_alpha = 0.1
            [nonlinear]
            pitch_freeplay = 0.01
            [[nonlinear.pitch_stiffness_terms]]
            power = 3
            coefficient = 500.0
            [nonlinear.friction]
            pitch_moment = 0.05
        "#;
        let s = Structure::from_toml_str(text).unwrap();
        assert_eq!(s.nonlinear.pitch_stiffness_terms[0].power, 3);
        assert_eq!(s.c_h, 0.0);
        let back = Structure::from_toml_str(&toml::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
        let e = Structure::from_toml_str(
            "mass = 1.0\ninertia_alpha = 1.0\nk_h = 1.0\nk_alpha = 1.0\nk_beta = 2.0\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("k_beta"), "{e}");
        let e = Structure::from_toml_str(
            "mass = 1.0\ninertia_alpha = 1.0\nk_h = 1.0\nk_alpha = 1.0\n[nonlinear]\nfreeplay = 0.1\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("freeplay"), "{e}");
        let e = Structure::from_toml_str(
            "mass = -1.0\ninertia_alpha = 1.0\nk_h = 1.0\nk_alpha = 1.0\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("`mass`"), "{e}");
    }

    #[test]
    fn spec_forms_resolve_to_the_same_structure() {
        let p = hp1();
        let s = Structure::from_nondimensional(&p).unwrap();
        let cubic = Nonlinearities {
            pitch_stiffness_terms: vec![PolyTerm {
                power: 3,
                coefficient: 2.0 * p.k_alpha(),
            }],
            ..Nonlinearities::none()
        };
        let nd = StructureSpec::Nondimensional {
            linear: p,
            nonlinear: cubic.clone(),
        }
        .resolve()
        .unwrap();
        assert_eq!(nd.k_alpha, s.k_alpha);
        assert_eq!(
            nd.nonlinear.pitch_stiffness_terms[0].coefficient,
            2.0 * s.k_alpha
        );
        assert_eq!(StructureSpec::Si(nd.clone()).resolve().unwrap(), nd);
        let tau = 2.0 * std::f64::consts::PI;
        let modal = ModalStructure {
            mass: s.mass,
            inertia: s.inertia_alpha,
            static_unbalance: s.static_unbalance,
            freq_heave: s.omega_h() / tau,
            freq_pitch: s.omega_alpha() / tau,
            damping_heave: 0.0,
            damping_pitch: 0.0,
        };
        let m = StructureSpec::Modal {
            linear: modal,
            nonlinear: cubic,
        }
        .resolve()
        .unwrap();
        assert!((m.k_alpha / s.k_alpha - 1.0).abs() < 1e-12);
        assert!((m.k_h / s.k_h - 1.0).abs() < 1e-12);
        assert_eq!(m.nonlinear, nd.nonlinear);
        let mut bad = modal;
        bad.inertia = -1.0;
        let e = Structure::from_modal(&bad).unwrap_err();
        assert!(e.to_string().contains("`inertia`"), "{e}");
        // the study's defaults
        let d: NondimStructure = toml::from_str("mu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5").unwrap();
        assert_eq!(
            (d.semi_chord, d.omega_alpha, d.rho, d.x_alpha),
            (1.0, 1.0, 1.0, 0.0)
        );
    }

    #[test]
    fn freeplay_polynomial_and_friction_restoring() {
        let mut s = Structure::from_rig(2.0, 0.1, 0.0, 100.0, 10.0, 0.0, 0.0).unwrap();
        s.nonlinear.pitch_freeplay = 0.02;
        s.nonlinear.pitch_stiffness_terms.push(PolyTerm {
            power: 3,
            coefficient: 1000.0,
        });
        assert_eq!(
            s.restoring([0.0, 0.015], [0.0, 0.0])[1],
            0.0,
            "inside the gap"
        );
        let d: f64 = 0.05 - 0.02;
        let want = 10.0 * d + 1000.0 * d.powi(3);
        assert!((s.restoring([0.0, 0.05], [0.0, 0.0])[1] - want).abs() < 1e-14);
        assert!((s.restoring([0.0, -0.05], [0.0, 0.0])[1] + want).abs() < 1e-14);
        s.nonlinear.friction = Some(Friction {
            heave_force: 0.0,
            pitch_moment: 0.3,
            heave_smoothing: None,
            pitch_smoothing: None,
        });
        assert!(!s.is_linear());
        let eps = s.friction_resolved()[3];
        // Default smoothing: slope T_c/ε = 2·5·I_α ω_α.
        assert!((0.3 / eps - 10.0 * 0.1 * s.omega_alpha()).abs() < 1e-9);
        let m_fast = s.restoring([0.0, 0.0], [0.0, 100.0 * eps])[1];
        assert!((m_fast - 0.3).abs() < 1e-9, "saturated friction {m_fast}");
    }
}
