//! Any linear model plus polynomial terms in the nondimensional variables — how the
//! identified Eq. 19 law (derivative tables + N* terms) plugs in.

use std::sync::Arc;

use nalgebra::Matrix2;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::{AeroModel, Flow};
use crate::{Error, Result};

/// Force channel of a nonlinear term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum Channel {
    /// Adds to C_L = L / (½ρU²B) (L positive down).
    Lift,
    /// Adds to C_M = M / (½ρU²B²) (M positive nose-up).
    Moment,
}

impl Channel {
    /// The name of the channel in input files: `lift` or `moment`.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Lift => "lift",
            Channel::Moment => "moment",
        }
    }

    /// The channel of an input-file name ([`Channel::name`]); `None` for anything else.
    pub fn from_name(name: &str) -> Option<Channel> {
        [Channel::Lift, Channel::Moment]
            .into_iter()
            .find(|c| c.name() == name)
    }
}

/// Serde form of a [`Channel`] in input files (model files, study `[aero]`): the string
/// `"lift"` or `"moment"`; for `#[serde(with = "…")]` on a field of type [`Channel`].
pub mod channel_name {
    use serde::{de::Error as _, Deserialize, Deserializer, Serializer};

    use super::Channel;

    /// Writes [`Channel::name`].
    ///
    /// # Errors
    /// The serializer's.
    pub fn serialize<S: Serializer>(c: &Channel, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(c.name())
    }

    /// Reads `lift` or `moment`.
    ///
    /// # Errors
    /// A custom error naming the value and the accepted names for anything else.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Channel, D::Error> {
        let s = String::deserialize(d)?;
        Channel::from_name(&s)
            .ok_or_else(|| D::Error::custom(format!("`{s}`: expected \"lift\" or \"moment\"")))
    }
}

/// Coefficient of a nonlinear term.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum Coefficient {
    /// A plain nondimensional coefficient (terms outside Eq. 19).
    Constant(f64),
    /// An Eq. 19 coefficient identified at several reduced frequencies: N*(K_i) at the
    /// identified K_i, multiplying K^`k_power` (e.g. N2* multiplies K⁶ α³, so
    /// `k_power = 6`).
    ///
    /// **Evaluation at K.** What is interpolated is the *effective* nondimensional
    /// coefficient ξ(K) = K^p N*(K) — the number the regression identified at each K_i —
    /// linearly in K between the identified K_i, and held at the end values ξ(K_min),
    /// ξ(K_max) outside their range (a fitted coefficient is never extrapolated). ξ rather
    /// than N* because N* = ξ/K^p varies like K^−p even when the law itself does not
    /// depend on frequency (a quasi-steady cubic): linear interpolation of 1/K³ between the
    /// paper campaign's K_α nodes 0.524 and 0.628 is 4 % off mid-way, of ξ exactly 0.
    OverK {
        /// Identified reduced frequencies K, strictly increasing.
        k: Vec<f64>,
        /// N* at each K.
        values: Vec<f64>,
        /// Power of K multiplying N*.
        k_power: i32,
    },
}

impl Coefficient {
    /// Effective coefficient of the nondimensional term at reduced frequency `k`
    /// (see the variants).
    pub fn at(&self, k: f64) -> f64 {
        match self {
            Coefficient::Constant(c) => *c,
            Coefficient::OverK {
                k: ks,
                values,
                k_power,
            } => {
                identify::numerics::interp::linear_held(ks, |i| values[i] * ks[i].powi(*k_power), k)
            }
        }
    }
}

/// One polynomial term c · α^p₀ (Bα̇/U)^p₁ (h/B)^p₂ (ḣ/U)^p₃ added to C_L or C_M.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NonlinearTerm {
    /// Channel (C_L or C_M).
    pub channel: Channel,
    /// Powers of (α, Bα̇/U, h/B, ḣ/U); total degree ≥ 2 (linear terms belong to the
    /// wrapped model).
    pub powers: [u32; 4],
    /// Coefficient.
    pub coefficient: Coefficient,
}

impl NonlinearTerm {
    /// Powers of (α, Bα̇/U, h/B, ḣ/U) of a term named as in DATA_FORMAT.md (`alpha`,
    /// `alpha_dot`, `h`, `h_dot` joined by `*`, powers `^2`, `^3`; e.g. `alpha*alpha_dot`,
    /// `alpha_dot^3`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `term` when the name does not parse (unknown
    /// factor, bad power, degree above 3).
    pub fn powers_of(name: &str) -> Result<[u32; 4]> {
        identify::library::Term::parse(name)
            .map(|t| t.powers.map(u32::from))
            .map_err(|e| Error::param("term", f64::NAN, e.to_string()))
    }

    /// The DATA_FORMAT.md name of this term's monomial, e.g. `alpha^3`.
    pub fn name(&self) -> String {
        term_name(self.powers)
    }
}

/// DATA_FORMAT.md name of the monomial α^p₀ α̇^p₁ h^p₂ ḣ^p₃ (`1` for the constant).
pub fn term_name(powers: [u32; 4]) -> String {
    const VARS: [&str; 4] = ["alpha", "alpha_dot", "h", "h_dot"];
    let parts: Vec<String> = powers
        .iter()
        .zip(VARS)
        .filter(|(p, _)| **p > 0)
        .map(|(p, v)| {
            if *p == 1 {
                v.to_string()
            } else {
                format!("{v}^{p}")
            }
        })
        .collect();
    if parts.is_empty() {
        "1".into()
    } else {
        parts.join("*")
    }
}

/// A linear aerodynamic model plus nonlinear polynomial terms.
///
/// **Evaluation away from the identified K.** A coefficient identified under forced
/// motion at reduced frequency K is, in a free response, evaluated at one reduced
/// frequency `k_eval` (set with [`NonlinearAero::with_k_eval`]); the LCO solver
/// ([`crate::section::Section::lco_run_k`]) updates it to the *current response
/// frequency* K = Bω_LCO/U by fixed-point iteration, so coefficients are interpolated in K
/// where the section actually oscillates, and held at the nearest identified K outside the
/// identified range (no extrapolation of a fitted coefficient). The nonlinear terms do not
/// enter the frequency response (they vanish on linearisation: degree ≥ 2).
#[derive(Debug, Clone)]
pub struct NonlinearAero {
    inner: Arc<dyn AeroModel>,
    terms: Vec<NonlinearTerm>,
    k_eval: f64,
    resolved: Vec<(usize, [i32; 4], f64)>,
}

impl NonlinearAero {
    /// Wraps `inner` with `terms`, evaluated at reduced frequency `k_eval`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `terms[i].powers` for a degree < 2,
    /// `terms[i].coefficient` for a malformed table (lengths, K not increasing, non-finite)
    /// or `k_eval` when it is not finite and > 0.
    pub fn new(inner: Arc<dyn AeroModel>, terms: Vec<NonlinearTerm>, k_eval: f64) -> Result<Self> {
        for (i, t) in terms.iter().enumerate() {
            let deg: u32 = t.powers.iter().sum();
            if deg < 2 {
                return Err(Error::param(
                    format!("terms[{i}].powers"),
                    deg as f64,
                    "total degree must be >= 2",
                ));
            }
            match &t.coefficient {
                Coefficient::Constant(c) => {
                    crate::error::finite(&format!("terms[{i}].coefficient"), *c)?
                }
                Coefficient::OverK { k, values, .. } => {
                    let ok = !k.is_empty()
                        && k.len() == values.len()
                        && k.iter().chain(values.iter()).all(|v| v.is_finite())
                        && k.windows(2).all(|w| w[1] > w[0])
                        && k[0] > 0.0;
                    if !ok {
                        return Err(Error::param(
                            format!("terms[{i}].coefficient"),
                            k.len() as f64,
                            "K table must be non-empty, positive, strictly increasing, finite, same length as values",
                        ));
                    }
                }
            }
        }
        let mut s = NonlinearAero {
            inner,
            terms,
            k_eval: 1.0,
            resolved: Vec::new(),
        };
        s.set_k_eval(k_eval)?;
        Ok(s)
    }

    /// The same model with the coefficients evaluated at reduced frequency `k`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-finite or non-positive `k`.
    pub fn with_k_eval(&self, k: f64) -> Result<Self> {
        let mut s = self.clone();
        s.set_k_eval(k)?;
        Ok(s)
    }

    fn set_k_eval(&mut self, k: f64) -> Result<()> {
        crate::error::positive("k_eval", k)?;
        self.k_eval = k;
        self.resolved = self
            .terms
            .iter()
            .map(|t| {
                let ch = match t.channel {
                    Channel::Lift => 0,
                    Channel::Moment => 1,
                };
                (ch, t.powers.map(|p| p as i32), t.coefficient.at(k))
            })
            .collect();
        Ok(())
    }

    /// Reduced frequency at which the coefficients are currently evaluated.
    pub fn k_eval(&self) -> f64 {
        self.k_eval
    }

    /// Whether any coefficient depends on K (so that K iteration matters).
    pub fn depends_on_k(&self) -> bool {
        self.terms
            .iter()
            .any(|t| matches!(t.coefficient, Coefficient::OverK { .. }))
    }

    /// The wrapped linear model.
    pub fn inner(&self) -> &Arc<dyn AeroModel> {
        &self.inner
    }

    /// The nonlinear terms.
    pub fn terms(&self) -> &[NonlinearTerm] {
        &self.terms
    }
}

impl AeroModel for NonlinearAero {
    fn name(&self) -> String {
        format!(
            "{} + {} nonlinear terms",
            self.inner.name(),
            self.terms.len()
        )
    }
    fn chord(&self) -> f64 {
        self.inner.chord()
    }
    fn n_lag(&self) -> usize {
        self.inner.n_lag()
    }
    fn apparent_mass(&self, flow: &Flow) -> Matrix2<f64> {
        self.inner.apparent_mass(flow)
    }
    #[inline]
    fn forces(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64]) -> [f64; 2] {
        let mut f = self.inner.forces(flow, q, qd, lag);
        let bb = self.inner.chord();
        let u = flow.u;
        let vars = [q[1], bb * qd[1] / u, q[0] / bb, qd[0] / u];
        let mut c = [0.0; 2];
        for (ch, p, coef) in &self.resolved {
            let mut v = *coef;
            for i in 0..4 {
                if p[i] != 0 {
                    v *= vars[i].powi(p[i]);
                }
            }
            c[*ch] += v;
        }
        let qdyn = flow.q_dyn();
        f[0] += qdyn * bb * c[0];
        f[1] += qdyn * bb * bb * c[1];
        f
    }
    #[inline]
    fn lag_rates(&self, flow: &Flow, q: [f64; 2], qd: [f64; 2], lag: &[f64], out: &mut [f64]) {
        self.inner.lag_rates(flow, q, qd, lag, out)
    }
    fn frequency_response(&self, flow: &Flow, omega: f64) -> Matrix2<Complex64> {
        self.inner.frequency_response(flow, omega)
    }
    fn reduced_frequency(&self) -> Option<f64> {
        self.depends_on_k().then_some(self.k_eval)
    }
    fn settle_time(&self, flow: &Flow) -> f64 {
        self.inner.settle_time(flow)
    }
    fn elastic_axis(&self) -> Option<f64> {
        self.inner.elastic_axis()
    }
    fn with_reduced_frequency(&self, k: f64) -> Option<Arc<dyn AeroModel>> {
        if !self.depends_on_k() {
            return None;
        }
        self.with_k_eval(k)
            .ok()
            .map(|m| Arc::new(m) as Arc<dyn AeroModel>)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::TheodorsenAero;

    #[test]
    fn coefficient_interpolates_and_holds_ends() {
        let c = Coefficient::OverK {
            k: vec![0.5, 1.0],
            values: vec![2.0, 4.0],
            k_power: 3,
        };
        // ξ = K³ N*: 0.25 at K = 0.5, 4 at K = 1; linear in between, held outside.
        assert!((c.at(0.75) - 0.5 * (0.25 + 4.0)).abs() < 1e-15);
        assert!((c.at(0.1) - 0.25).abs() < 1e-15);
        assert!((c.at(3.0) - 4.0).abs() < 1e-15);
        // A frequency-independent ξ tabulated as N* = ξ/K³ is reproduced exactly between
        // nodes (interpolating N* itself would be 4 % off here).
        let ks = [0.524, 0.628];
        let c = Coefficient::OverK {
            k: ks.to_vec(),
            values: ks.iter().map(|k| -2.0 / k.powi(3)).collect(),
            k_power: 3,
        };
        assert!((c.at(0.576) + 2.0).abs() < 1e-13);
    }

    #[test]
    fn term_names_round_trip() {
        for (name, p) in [
            ("alpha*alpha_dot", [1, 1, 0, 0]),
            ("alpha^3", [3, 0, 0, 0]),
            ("alpha_dot^3", [0, 3, 0, 0]),
            ("alpha^2*h", [2, 0, 1, 0]),
        ] {
            assert_eq!(NonlinearTerm::powers_of(name).unwrap(), p);
            assert_eq!(term_name(p), name);
        }
        let e = NonlinearTerm::powers_of("alpha*beta").unwrap_err();
        assert!(e.to_string().contains("beta"), "{e}");
    }

    #[test]
    fn cubic_moment_term_adds_expected_force_and_validation_names_term() {
        let inner: Arc<dyn AeroModel> = Arc::new(TheodorsenAero::new(0.4, 0.0).unwrap());
        let t = NonlinearTerm {
            channel: Channel::Moment,
            powers: [0, 3, 0, 0],
            coefficient: Coefficient::Constant(-2.0),
        };
        let m = NonlinearAero::new(inner.clone(), vec![t], 1.0).unwrap();
        let flow = Flow { rho: 1.2, u: 10.0 };
        let (q, qd, lag) = ([0.0, 0.0], [0.0, 5.0], [0.0, 0.0]);
        let f0 = inner.forces(&flow, q, qd, &lag);
        let f1 = m.forces(&flow, q, qd, &lag);
        let want = flow.q_dyn() * 0.16 * (-2.0) * (0.4 * 5.0 / 10.0f64).powi(3);
        assert!((f1[1] - f0[1] - want).abs() < 1e-12 && f1[0] == f0[0]);
        let bad = NonlinearTerm {
            channel: Channel::Lift,
            powers: [1, 0, 0, 0],
            coefficient: Coefficient::Constant(1.0),
        };
        let e = NonlinearAero::new(inner, vec![bad], 1.0).unwrap_err();
        assert!(e.to_string().contains("terms[0].powers"), "{e}");
    }
}
