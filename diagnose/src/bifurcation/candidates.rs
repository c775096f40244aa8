//! The candidates of the bifurcation level (each effect's are in its file of
//! `crate::catalogue`): each candidate is a parametrised change of the nominal section (a structural term of [`aeroelastic::structure::Nonlinearities`], a mass
//! change, or a scale on the aerodynamic loads) that the continuation can follow. The fit
//! works on scaled parameters θ (value = scale · θ, scales from the nominal structure and
//! the measured amplitudes, so that θ = 1 is a change of the order of the linear term at
//! the largest measured amplitude).
//!
//! Sign conventions (DESIGN §2: h down, α nose-up; the extra forces are *restoring*, on
//! the left of M q̈ + R(q, q̇) = F_aero, so a positive stiffness coefficient resists the
//! displacement):
//! - stiffness: extra restoring force k₂h² + k₃h³ [N/m², N/m³], extra restoring moment
//!   k₂α² + k₃α³ [N m/rad², N m/rad³] (k₃ > 0 hardens);
//! - damping: extra damping force c₂h²ḣ, moment c₂α²α̇ (c₂ > 0 dissipates);
//! - friction: Coulomb moment T_c tanh(α̇/ε) opposing α̇ (T_c ≥ 0);
//! - added mass: Δm added to the heaving mass, ΔI_α to the pitch inertia;
//! - aerodynamic scale: lift and moment (and their apparent mass) times s.
//!
//! Not at this level: freeplay (a sharp gap is not a smooth vector field; continuation
//! refuses it) and a force delay (no delay states in the section model); the report lists
//! them as not fitted (`Entry::not_at_bifurcation`).

use std::sync::Arc;

use aeroelastic::aero::{AeroModel, Flow};
use aeroelastic::section::Section;
use aeroelastic::structure::{add_poly_term, Friction};
use nalgebra::Matrix2;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

pub use super::scales::Scales;
use crate::structure::{conform_to_decays, StructureCheck};
use crate::{Effect, Result};

/// One parameter of a candidate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ParameterSpec {
    /// Name (`k3_pitch`, …).
    pub name: String,
    /// SI unit per unit span.
    pub unit: String,
    /// What the value means, with its sign convention.
    pub convention: String,
    /// Value of θ = 1.
    pub scale: f64,
    /// An even stiffness term: q → −q maps the section with +k onto the one with −k, so
    /// amplitudes and frequencies cannot tell the sign of the even terms (jointly); the
    /// fit reports them with the first even term ≥ 0.
    #[serde(default)]
    pub even: bool,
}

/// Which change a candidate makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Change {
    /// Pitch stiffness terms of these powers.
    PitchStiffness(&'static [u32]),
    /// Pitch stiffness powers, then heave stiffness powers.
    PitchHeaveStiffness(&'static [u32], &'static [u32]),
    /// Pitch damping c₂α²α̇.
    PitchDamping,
    /// Pitch and heave damping c₂α²α̇, c₂h²ḣ.
    PitchHeaveDamping,
    /// Coulomb friction in pitch.
    PitchFriction,
    /// Coulomb friction in pitch with its regularisation velocity fitted.
    PitchFrictionSmoothing,
    /// Δm, ΔI_α.
    AddedMass,
    /// Scale on the aerodynamic loads.
    AeroScale,
}

/// A candidate of the bifurcation level.
#[derive(Debug, Clone)]
pub struct BranchCandidate {
    /// Catalogue effect.
    pub effect: Effect,
    /// Which DOFs or form (`pitch`, `pitch+heave`, …).
    pub variant: String,
    /// Parameters, in θ order.
    pub parameters: Vec<ParameterSpec>,
    /// Index of the candidate it extends (nested: its parameters are a prefix of these), if
    /// any.
    pub extends: Option<usize>,
    /// The (effect, variant) it extends, resolved to [`BranchCandidate::extends`] when the
    /// levels' candidates are gathered.
    pub(crate) extends_key: Option<(Effect, &'static str)>,
    change: Change,
    /// Largest measured pitch amplitude \[rad\] (friction's regularisation).
    reference_alpha: f64,
    /// The still-air decays' check when the level runs on the structure identified from
    /// them: every change is then conformed to the decays
    /// ([`crate::structure::conform_to_decays`]).
    decays: Option<Arc<StructureCheck>>,
}

/// A parameter of unit `unit` whose θ = 1 is `scale` (made positive when the
/// candidates are gathered).
pub(crate) fn param(name: &str, unit: &str, convention: &str, scale: f64) -> ParameterSpec {
    ParameterSpec {
        name: name.into(),
        unit: unit.into(),
        convention: convention.into(),
        scale,
        even: false,
    }
}

/// A degree of freedom of the section (heave positive down, pitch positive nose-up).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Dof {
    /// Heave h \[m\].
    Heave,
    /// Pitch α \[rad\].
    Pitch,
}

impl Dof {
    /// `heave` / `pitch` (in parameter names).
    fn name(self) -> &'static str {
        match self {
            Dof::Heave => "heave",
            Dof::Pitch => "pitch",
        }
    }
}

/// A stiffness term k·q^power of `dof`, scaled so that θ = 1 is the linear stiffness `k`
/// at the amplitude `amp`.
pub(crate) fn stiffness_param(dof: Dof, power: u32, k: f64, amp: f64) -> ParameterSpec {
    let (sym, unit, what, positive) = match dof {
        Dof::Pitch => ("α", format!("N m/rad^{power}"), "moment", "nose-up"),
        Dof::Heave => ("h", format!("N/m^{power}"), "force", "down"),
    };
    let mut q = param(
        &format!("k{power}_{}", dof.name()),
        &unit,
        &format!(
            "extra restoring {what} k{power}·{sym}^{power} ({sym} positive {positive}; k > 0 \
             resists positive {sym}{})",
            if power % 2 == 1 {
                ": hardening"
            } else {
                "; the sign of the even terms is fixed only by the orbit's mean deflection, \
                 which first-harmonic amplitudes do not carry: reported with the first even \
                 term ≥ 0"
            }
        ),
        k / amp.powi(power as i32 - 1),
    );
    q.even = power.is_multiple_of(2);
    q
}

impl BranchCandidate {
    /// A candidate of `effect` in form `variant`, extending the candidate `extends`
    /// (effect, variant) if any.
    pub(crate) fn new(
        effect: Effect,
        variant: &str,
        parameters: Vec<ParameterSpec>,
        extends: Option<(Effect, &'static str)>,
        change: Change,
    ) -> Self {
        BranchCandidate {
            effect,
            variant: variant.into(),
            parameters,
            extends: None,
            extends_key: extends,
            change,
            reference_alpha: 0.0,
            decays: None,
        }
    }

    /// With the largest measured pitch amplitude \[rad\] (friction's regularisation).
    pub(crate) fn with_reference_alpha(mut self, alpha: f64) -> Self {
        self.reference_alpha = alpha;
        self
    }

    /// With the still-air decays' check `decays` (structure first): when it uses the
    /// identified structure, [`BranchCandidate::apply`] re-identifies the linear springs
    /// and dampers under each change so that the changed model still reproduces the
    /// measured still-air modes ([`crate::structure::conform_to_decays`]).
    pub fn with_decays(mut self, decays: Option<Arc<StructureCheck>>) -> Self {
        self.decays = decays;
        self
    }

    /// The physical parameter values of the scaled `theta`.
    pub fn values(&self, theta: &[f64]) -> Vec<f64> {
        self.parameters
            .iter()
            .zip(theta)
            .enumerate()
            .map(|(i, (q, t))| match (self.change, i) {
                (Change::PitchFriction | Change::PitchFrictionSmoothing, 0) => q.scale * t.abs(),
                (Change::PitchFrictionSmoothing, _) => {
                    q.scale * 10f64.powf(t.clamp(-4.0, 4.0) / 2.0)
                }
                _ => q.scale * t,
            })
            .collect()
    }

    /// Label `effect (variant)`.
    pub fn label(&self) -> String {
        format!("{} ({})", self.effect.name(), self.variant)
    }

    /// The nominal section with this candidate's change at scaled parameters `theta`.
    ///
    /// With still-air decays ([`BranchCandidate::with_decays`]) the changed section's
    /// linear springs and dampers are re-identified from them
    /// ([`crate::structure::conform_to_decays`]).
    ///
    /// # Errors
    /// [`crate::Error::Aeroelastic`] when the changed structure is invalid (e.g. a mass
    /// change that makes the mass matrix indefinite); [`crate::Error::Data`] when no
    /// linear structure with the change reproduces the decays.
    pub fn apply(&self, base: &Section, theta: &[f64]) -> Result<Section> {
        let v = self.values(theta);
        let mut st = base.structure.clone();
        let mut aero = base.aero.clone();
        match self.change {
            Change::PitchStiffness(powers) => {
                for (pw, c) in powers.iter().zip(&v) {
                    add_poly_term(&mut st.nonlinear.pitch_stiffness_terms, *pw, *c);
                }
            }
            Change::PitchHeaveStiffness(pa, ph) => {
                for (pw, c) in pa.iter().zip(&v) {
                    add_poly_term(&mut st.nonlinear.pitch_stiffness_terms, *pw, *c);
                }
                for (pw, c) in ph.iter().zip(&v[pa.len()..]) {
                    add_poly_term(&mut st.nonlinear.heave_stiffness_terms, *pw, *c);
                }
            }
            Change::PitchDamping => add_poly_term(&mut st.nonlinear.pitch_damping_terms, 2, v[0]),
            Change::PitchHeaveDamping => {
                add_poly_term(&mut st.nonlinear.pitch_damping_terms, 2, v[0]);
                add_poly_term(&mut st.nonlinear.heave_damping_terms, 2, v[1]);
            }
            Change::PitchFriction => {
                // regularised over 5 % of the largest measured orbit's peak velocity, so
                // that its slope at rest, T_c/ε, vanishes with T_c (the default smoothing
                // is a fixed damping ratio of 5 there, which would remove flutter)
                let eps = 0.05 * st.omega_alpha() * self.reference_alpha;
                let f = st.nonlinear.friction.get_or_insert(Friction {
                    heave_force: 0.0,
                    pitch_moment: 0.0,
                    heave_smoothing: None,
                    pitch_smoothing: Some(eps),
                });
                f.pitch_moment += v[0];
            }
            Change::PitchFrictionSmoothing => {
                let f = st.nonlinear.friction.get_or_insert(Friction {
                    heave_force: 0.0,
                    pitch_moment: 0.0,
                    heave_smoothing: None,
                    pitch_smoothing: Some(v[1]),
                });
                f.pitch_moment += v[0];
                f.pitch_smoothing = Some(v[1]);
            }
            Change::AddedMass => {
                st.mass += v[0];
                st.inertia_alpha += v[1];
            }
            Change::AeroScale => {
                aero = Arc::new(ScaledAero {
                    inner: base.aero.clone(),
                    scale: 1.0 + v[0],
                });
            }
        }
        let s = Section::new(st, aero, base.rho)
            .map_err(|e| crate::Error::aeroelastic(self.label(), e))?;
        match &self.decays {
            Some(check) => conform_to_decays(check, base, s),
            None => Ok(s),
        }
    }
}

/// An aerodynamic model whose loads are those of `inner` times `scale` (lift and moment,
/// apparent mass included; lag states unchanged).
#[derive(Debug, Clone)]
pub struct ScaledAero {
    /// The model scaled.
    pub inner: Arc<dyn AeroModel>,
    /// Factor on every load.
    pub scale: f64,
}

impl AeroModel for ScaledAero {
    fn name(&self) -> String {
        format!("{} × {:.4}", self.inner.name(), self.scale)
    }
    fn chord(&self) -> f64 {
        self.inner.chord()
    }
    fn n_lag(&self) -> usize {
        self.inner.n_lag()
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        self.inner.apparent_mass(flow) * self.scale
    }
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        let f = self.inner.forces(flow, q, qd, lag);
        [f[0] * self.scale, f[1] * self.scale]
    }
    fn is_linear(&self) -> bool {
        self.inner.is_linear()
    }
    fn lag_rates(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]) {
        self.inner.lag_rates(flow, q, qd, lag, out)
    }
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        self.inner.frequency_response(flow, omega) * Complex64::new(self.scale, 0.0)
    }
    fn settle_time(&self, flow: &Flow) -> f64 {
        self.inner.settle_time(flow)
    }
    fn elastic_axis(&self) -> Option<f64> {
        self.inner.elastic_axis()
    }
}
