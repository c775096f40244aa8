//! Drawn truth physics of the drawn-shapes benchmark: a rig and an aerodynamic law per set,
//! so that the benchmark's truths do not share the diagnosis's assumptions.
//!
//! Before round 20 every benchmark set had the same plate rig (f_h 2.0 Hz, f_α 3.5 Hz,
//! U_F 6.6 m/s) and the same nonlinear law, written in exactly the Eq. 19 terms the
//! diagnosis identifies (0.5 α·Bα̇/U − 2α³ − 100(Bα̇/U)³). A generator written by other
//! hands has neither. Here each set draws:
//!
//! - **the rig**: frequency ratio f_α/f_h in 1.3–2.0, mass 0.7–1.6 × the plate rig's
//!   (inertia with it), mass centre 0.005–0.02 m aft of the elastic axis, damping ratios
//!   log-uniform in 0.003–0.02, and a target flutter speed U_F in 4.5–11 m/s (the forced
//!   campaign stays at 3–10 m/s, so the forced K range relative to the free runs varies
//!   from set to set). The frequencies are scaled to that U_F: at fixed mass ratio,
//!   frequency ratio and damping ratios the linear flutter speed is proportional to the
//!   frequencies ([`DrawnPhysics::scenario_files`]).
//! - **the nonlinear law** ([`DrawnLaw`]): for half of the sets a subset of the Eq. 19
//!   terms with drawn coefficients (the cubic α³ always, α·α̇ in half, α̇³ in two thirds of
//!   them); for the other half a cubic in the effective angle of attack
//!   α_e = α + ḣ/U + e·Bα̇/U (e in 0–0.6), C_M += m₃α_e³ + d·α_e²·Bα̇/U, C_L += l₃α_e³,
//!   which expands into up to twenty library monomials, most of them outside the Eq. 19
//!   form (the diagnosis's node law then needs terms that a single case cannot separate).
//!
//! The linear aerodynamics stays Theodorsen's flat plate with Jones' lags and its
//! apparent-mass terms, about a = −0.3 semi-chords (the effects' injections assume that
//! elastic axis).

use aeroelastic::aero::Channel;
use serde::{Deserialize, Serialize};

use identify::numerics::{split_seed, unit_interval};

/// The plate rig's mass per unit span \[kg/m\] (0.82 kg over 0.75 m).
const PLATE_MASS: f64 = 0.82 / 0.75;
/// Chord \[m\] of the plate (and of the truth model).
const CHORD: f64 = 0.25;
/// Air density \[kg/m³\].
const RHO: f64 = 1.225;

/// The nonlinear part of a drawn truth law (nondimensional: C_L = L/(½ρU²B), C_M =
/// M/(½ρU²B²), motion α, Bα̇/U, h/B, ḣ/U; lift positive down, moment positive nose-up).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum DrawnLaw {
    /// The Eq. 19 form: C_M += n₁ α·(Bα̇/U) + n₂ α³ + n₃ (Bα̇/U)³.
    Eq19 {
        /// n₁ (coefficient of α·Bα̇/U) \[-\].
        alpha_alpha_dot: f64,
        /// n₂ (coefficient of α³) \[-\].
        alpha3: f64,
        /// n₃ (coefficient of (Bα̇/U)³) \[-\].
        alpha_dot3: f64,
    },
    /// A cubic in the effective angle of attack α_e = α + ḣ/U + e·Bα̇/U:
    /// C_M += m₃ α_e³ + d α_e² (Bα̇/U), C_L += l₃ α_e³.
    EffectiveAngle {
        /// e, the lever of the pitch rate in α_e \[-\].
        lever: f64,
        /// m₃ \[-\] (< 0: a nose-down moment growing as α_e³).
        moment_cubic: f64,
        /// d \[-\] (< 0: moment opposing the pitch rate, growing with α_e²).
        moment_damping: f64,
        /// l₃ \[-\] (< 0 with lift positive down: lift-curve softening).
        lift_cubic: f64,
    },
}

/// A set's drawn rig and law ([`DrawnPhysics::draw`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DrawnPhysics {
    /// Target linear flutter speed U_F \[m/s\] (the free runs' speed unit).
    pub flutter_speed: f64,
    /// Frequency ratio f_α/f_h of the uncoupled still-air frequencies \[-\].
    pub frequency_ratio: f64,
    /// Mass per unit span relative to the plate rig's \[-\].
    pub mass_factor: f64,
    /// Mass centre aft of the elastic axis \[m\].
    pub unbalance_m: f64,
    /// Heave damping ratio \[-\].
    pub damping_heave: f64,
    /// Pitch damping ratio \[-\].
    pub damping_pitch: f64,
    /// The nonlinear aerodynamic law.
    pub law: DrawnLaw,
}

/// Uniform draw in [lo, hi] from the 53 high bits of `bits`.
fn uniform(bits: u64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * unit_interval(bits)
}

impl DrawnPhysics {
    /// The physics of the set with seed `seed` (its own stream: `split_seed(seed, 60 …)`).
    pub fn draw(seed: u64) -> Self {
        let u = |k: u64, lo: f64, hi: f64| uniform(split_seed(seed, 60 + k), lo, hi);
        let log = |k: u64, lo: f64, hi: f64| (u(k, lo.ln(), hi.ln())).exp();
        let law = if split_seed(seed, 59).is_multiple_of(2) {
            // a subset of the three terms: the cubic always, α·α̇ in half of these sets,
            // α̇³ in two thirds
            let bits = split_seed(seed, 58);
            DrawnLaw::Eq19 {
                alpha_alpha_dot: if bits & 1 == 0 { u(7, 0.1, 1.0) } else { 0.0 },
                alpha3: u(8, -4.0, -0.5),
                alpha_dot3: if !(bits >> 1).is_multiple_of(3) {
                    -log(9, 30.0, 200.0)
                } else {
                    0.0
                },
            }
        } else {
            DrawnLaw::EffectiveAngle {
                lever: u(10, 0.0, 0.6),
                moment_cubic: u(11, -4.0, -0.5),
                moment_damping: -log(12, 30.0, 200.0),
                lift_cubic: u(13, -3.0, 0.0),
            }
        };
        DrawnPhysics {
            flutter_speed: (u(0, 4.5, 11.0) * 100.0).round() / 100.0,
            frequency_ratio: u(1, 1.3, 2.0),
            mass_factor: u(2, 0.7, 1.6),
            unbalance_m: u(3, 0.005, 0.02),
            damping_heave: log(4, 0.003, 0.02),
            damping_pitch: log(5, 0.003, 0.02),
            law,
        }
    }

    /// The rig as a structure file (`*.structure.toml`) with heave frequency `freq_heave`
    /// \[Hz\] (pitch at [`DrawnPhysics::frequency_ratio`] times it).
    pub fn rig_toml_at(&self, freq_heave: f64) -> String {
        let m = PLATE_MASS * self.mass_factor;
        let x = self.unbalance_m;
        format!(
            "air_density = {RHO}\nchord = {CHORD}\nmass = {m}\ninertia = {}\n\
             static_unbalance = {}\nfreq_heave = {freq_heave}\nfreq_pitch = {}\n\
             damping_heave = {}\ndamping_pitch = {}\n",
            m * (CHORD * CHORD / 12.0 + x * x),
            m * x,
            freq_heave * self.frequency_ratio,
            self.damping_heave,
            self.damping_pitch
        )
    }

    /// The scenario's rig and truth model files: the rig at a reference heave frequency of
    /// 2 Hz, its linear flutter speed U_ref with the truth model (p-k, Theodorsen–Jones;
    /// the law's nonlinear terms have no linear part), then the frequencies scaled by
    /// U_F / U_ref, which puts the flutter speed at the drawn U_F (the reduced flutter
    /// speed U/(Bω) is fixed by the mass ratio, frequency ratio and damping ratios).
    ///
    /// # Errors
    /// [`crate::Error::Aeroelastic`] when the files do not parse or the flutter analysis
    /// fails; [`crate::Error::Data`] when the rig does not flutter below 100 m/s at the
    /// reference frequency.
    pub fn scenario_files(&self) -> crate::Result<(String, String)> {
        use aeroelastic::files::{LoadedModel, StructureFile};
        use aeroelastic::flutter::{FlutterMethod, FlutterOptions};
        let ae = |what: &'static str| {
            move |e: aeroelastic::Error| {
                crate::Error::aeroelastic(format!("drawn truth: {what}"), e)
            }
        };
        let model = self.model_toml();
        let reference = 2.0;
        let rig =
            StructureFile::parse(&self.rig_toml_at(reference), "drawn rig").map_err(ae("rig"))?;
        let law = LoadedModel::parse(&model, "drawn truth model", std::path::Path::new("."), None)
            .map_err(ae("model"))?;
        let section = aeroelastic::section::Section::new(
            rig.structure().map_err(ae("rig"))?,
            law.model,
            rig.air_density,
        )
        .map_err(ae("section"))?;
        let opts = FlutterOptions {
            u_min: 0.2,
            u_max: 100.0,
            n_speeds: 200,
            tol_rel: 1e-9,
        };
        let u_ref = section
            .flutter(FlutterMethod::Pk, &opts)
            .map_err(ae("flutter"))?
            .flutter
            .map(|f| f.u)
            .ok_or_else(|| {
                crate::Error::data(
                    "drawn truth",
                    format!("the drawn rig {self:?} does not flutter below 100 m/s"),
                )
            })?;
        let scaled = reference * self.flutter_speed / u_ref;
        Ok((self.rig_toml_at(scaled), model))
    }

    /// The truth model file (`*.model.toml`): Theodorsen with Jones' lags about a = −0.3
    /// and the law's terms ([`DrawnPhysics::terms`]).
    pub fn model_toml(&self) -> String {
        let mut s = format!("kind = \"theodorsen\"\nchord = {CHORD}\nelastic_axis = -0.3\n");
        for (term, channel, c) in self.terms() {
            s.push_str(&format!(
                "\n[[nonlinear]]\nterm = \"{term}\"\nchannel = \"{}\"\ncoefficient = {c:e}\n",
                channel.name()
            ));
        }
        s
    }

    /// The law's library monomials (term name, channel, coefficient), the effective-angle
    /// cubics expanded by the multinomial theorem; terms below 1e-12 dropped.
    pub fn terms(&self) -> Vec<(String, Channel, f64)> {
        match &self.law {
            DrawnLaw::Eq19 {
                alpha_alpha_dot,
                alpha3,
                alpha_dot3,
            } => vec![
                ("alpha*alpha_dot".into(), Channel::Moment, *alpha_alpha_dot),
                ("alpha^3".into(), Channel::Moment, *alpha3),
                ("alpha_dot^3".into(), Channel::Moment, *alpha_dot3),
            ]
            .into_iter()
            .filter(|t| t.2.abs() > 1e-12)
            .collect(),
            DrawnLaw::EffectiveAngle {
                lever,
                moment_cubic,
                moment_damping,
                lift_cubic,
            } => {
                // α_e^n = Σ n!/(i! j! k!) e^j α^i (Bα̇/U)^j (ḣ/U)^k over i + j + k = n
                let fact = |n: u32| (1..=n).product::<u32>() as f64;
                let mut out: Vec<(String, Channel, f64)> = Vec::new();
                let mut add = |powers: [u32; 3], channel: Channel, c: f64| {
                    if c.abs() <= 1e-12 {
                        return;
                    }
                    let name = monomial(powers);
                    match out.iter_mut().find(|t| t.0 == name && t.1 == channel) {
                        Some(t) => t.2 += c,
                        None => out.push((name, channel, c)),
                    }
                };
                for n in [3u32, 2] {
                    for i in 0..=n {
                        for j in 0..=(n - i) {
                            let k = n - i - j;
                            let w = fact(n) / (fact(i) * fact(j) * fact(k)) * lever.powi(j as i32);
                            if n == 3 {
                                add([i, j, k], Channel::Moment, moment_cubic * w);
                                add([i, j, k], Channel::Lift, lift_cubic * w);
                            } else {
                                add([i, j + 1, k], Channel::Moment, moment_damping * w);
                            }
                        }
                    }
                }
                out
            }
        }
    }
}

/// Library name of α^i (Bα̇/U)^j (ḣ/U)^k, e.g. `alpha^2*alpha_dot`.
fn monomial(powers: [u32; 3]) -> String {
    ["alpha", "alpha_dot", "h_dot"]
        .iter()
        .zip(powers)
        .filter(|(_, p)| *p > 0)
        .map(|(n, p)| {
            if p == 1 {
                n.to_string()
            } else {
                format!("{n}^{p}")
            }
        })
        .collect::<Vec<_>>()
        .join("*")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effective_angle_law_expands_to_the_cubic_it_states() {
        let p = DrawnPhysics {
            law: DrawnLaw::EffectiveAngle {
                lever: 0.4,
                moment_cubic: -2.0,
                moment_damping: -50.0,
                lift_cubic: -1.0,
            },
            ..DrawnPhysics::draw(1)
        };
        let (a, ad, hd) = (0.07, -0.03, 0.02);
        let ae = a + hd + 0.4 * ad;
        let mut cm = 0.0;
        let mut cl = 0.0;
        for (name, ch, c) in p.terms() {
            let t = identify::library::Term::parse(&name).unwrap();
            let v = t.eval_at([a, ad, 0.0, hd]);
            if ch == Channel::Moment {
                cm += c * v;
            } else {
                cl += c * v;
            }
        }
        assert!((cm - (-2.0 * ae.powi(3) - 50.0 * ae * ae * ad)).abs() < 1e-14);
        assert!((cl - (-ae.powi(3))).abs() < 1e-15);
    }

    #[test]
    fn draws_are_in_range_reproducible_and_both_laws_occur() {
        let all: Vec<DrawnPhysics> = (0..300)
            .map(|i| DrawnPhysics::draw(split_seed(5, i)))
            .collect();
        for p in &all {
            assert!((4.5..=11.0).contains(&p.flutter_speed), "{p:?}");
            assert!((1.3..=2.0).contains(&p.frequency_ratio), "{p:?}");
            assert!((0.003..=0.02).contains(&p.damping_pitch), "{p:?}");
        }
        let eq19 = all
            .iter()
            .filter(|p| matches!(p.law, DrawnLaw::Eq19 { .. }))
            .count();
        assert!(
            (120..180).contains(&eq19),
            "{eq19} of 300 in the Eq. 19 form"
        );
        assert_eq!(DrawnPhysics::draw(split_seed(5, 7)), all[7]);
    }

    /// The scaled rig flutters at the drawn U_F (a p-k analysis of the written files).
    #[test]
    fn the_scaled_rig_flutters_at_the_drawn_speed() {
        use aeroelastic::files::{LoadedModel, StructureFile};
        use aeroelastic::flutter::{FlutterMethod, FlutterOptions};
        for i in 0..4 {
            let p = DrawnPhysics::draw(split_seed(11, i));
            let (rig, model) = p.scenario_files().unwrap();
            let rig = StructureFile::parse(&rig, "rig").unwrap();
            let law = LoadedModel::parse(&model, "law", std::path::Path::new("."), None).unwrap();
            let s = aeroelastic::section::Section::new(rig.structure().unwrap(), law.model, 1.225)
                .unwrap();
            let o = FlutterOptions {
                u_min: 0.5,
                u_max: 30.0,
                n_speeds: 120,
                tol_rel: 1e-9,
            };
            let u = s.flutter(FlutterMethod::Pk, &o).unwrap().flutter.unwrap().u;
            assert!(
                (u / p.flutter_speed - 1.0).abs() < 1e-4,
                "{u} vs {}",
                p.flutter_speed
            );
        }
    }
}
