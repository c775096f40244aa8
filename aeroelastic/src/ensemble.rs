//! Flutter speed, divergence speed and LCO amplitudes of an ensemble of identified laws
//! (the `ensemble` section of an `identification.json`, [`identify::ensemble`]).
//!
//! Each member of the block bootstrap is an identification of its own; it is turned into an
//! [`IdentifiedLaw`] exactly as the nominal one, coupled to the same structure, and analysed
//! with the same options. The spread of the members' results is the propagated
//! identification uncertainty: percentile intervals at the ensemble's level
//! ([`identify::ensemble::Interval`]). A member whose law cannot be built or whose analysis
//! fails is counted and its message kept, never dropped silently; a member without flutter
//! (or divergence, or LCO) in the analysed range is counted separately. The intervals are
//! over the members that have the quantity, so `found` must be read with them.

use std::sync::Arc;

use identify::ensemble::{Ensemble, Interval};
use identify::pipeline::Identification;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::aero::NonlinearAero;
use crate::flutter::{FlutterMethod, FlutterOptions};
use crate::identified::{IdentifiedLaw, IdentifiedOptions};
use crate::lco::{Classification, KIteration, LcoOptions};
use crate::section::Section;
use crate::structure::Structure;
use crate::{Error, Result};

/// The first `n` members of the ensemble of `id` as laws (`None`: all members).
///
/// Returns per member the law or the message of why it could not be built.
///
/// # Errors
/// [`Error::InvalidParameter`] naming `ensemble` when `id` has no ensemble section, or
/// `ensemble.members` when `n` exceeds the stored members or is < 2;
/// [`Error::Identify`] when the section does not match the cases (a damaged file).
pub fn member_laws<'a>(
    id: &'a Identification,
    opts: &IdentifiedOptions,
    n: Option<usize>,
) -> Result<(
    Vec<std::result::Result<IdentifiedLaw, String>>,
    &'a Ensemble,
)> {
    let e = id.ensemble.as_ref().ok_or_else(|| {
        Error::param(
            "ensemble",
            f64::NAN,
            "the identification has no ensemble section (run `aeroform identify --ensemble N`)",
        )
    })?;
    e.check(id).map_err(|source| Error::Identify {
        context: "ensemble section".to_string(),
        source,
    })?;
    let n = n.unwrap_or(e.members());
    if n < 2 || n > e.members() {
        return Err(Error::param(
            "ensemble.members",
            n as f64,
            format!(
                "asked for {n} members; the identification holds {}",
                e.members()
            ),
        ));
    }
    let laws = (0..n)
        .into_par_iter()
        .map(|m| {
            let member = e.member(id, m).map_err(|err| err.to_string())?;
            IdentifiedLaw::from_identification(&member, opts)
                .map_err(|err| format!("member {m}: {err}"))
        })
        .collect();
    Ok((laws, e))
}

/// Distribution of one scalar result over the members.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MemberQuantity {
    /// Percentile interval over the members that have the quantity (`None` when none has).
    pub interval: Option<Interval>,
    /// Members that have the quantity (e.g. flutter inside the scanned range).
    pub found: usize,
    /// Per member, in member order (`None`: not found or failed).
    pub members: Vec<Option<f64>>,
}

impl MemberQuantity {
    fn new(members: Vec<Option<f64>>, level: f64) -> Self {
        let v: Vec<f64> = members.iter().flatten().copied().collect();
        MemberQuantity {
            interval: Interval::from_samples(&v, level),
            found: v.len(),
            members,
        }
    }
}

/// Flutter and divergence over an ensemble of laws.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FlutterEnsemble {
    /// Members analysed.
    pub members: usize,
    /// Seed of the bootstrap that made the members (string: u64).
    pub seed: String,
    /// Interval level.
    pub level: f64,
    /// Flutter speed U_F [m/s].
    pub flutter_speed: MemberQuantity,
    /// Flutter frequency \[Hz\].
    pub flutter_frequency_hz: MemberQuantity,
    /// Static divergence speed U_D [m/s].
    pub divergence_speed: MemberQuantity,
    /// Members whose law or analysis failed, with the reason.
    pub failures: Vec<String>,
}

/// Flutter analysis of every law of `laws` (from [`member_laws`]) on `structure` with air
/// density `rho`, in parallel; intervals at `ensemble.settings.level`.
///
/// # Errors
/// [`Error::InvalidParameter`] for `rho` ≤ 0. A member's failure is recorded in
/// `failures`, not returned.
pub fn flutter_ensemble(
    structure: &Structure,
    laws: &[std::result::Result<IdentifiedLaw, String>],
    ensemble: &Ensemble,
    rho: f64,
    method: FlutterMethod,
    opts: &FlutterOptions,
) -> Result<FlutterEnsemble> {
    crate::error::positive("rho", rho)?;
    /// (flutter (U_F, f_F), U_D) of one member, or why it failed.
    type Member = std::result::Result<(Option<(f64, f64)>, Option<f64>), String>;
    let out: Vec<Member> = laws
        .par_iter()
        .enumerate()
        .map(|(m, law)| {
            let law = law.as_ref().map_err(Clone::clone)?;
            let s = Section::new(structure.clone(), Arc::new(law.model().clone()), rho)
                .map_err(|e| format!("member {m}: {e}"))?;
            let fa = s
                .flutter(method, opts)
                .map_err(|e| format!("member {m}: flutter: {e}"))?;
            Ok((
                fa.flutter
                    .map(|f| (f.u, f.omega / (2.0 * std::f64::consts::PI))),
                fa.divergence_speed,
            ))
        })
        .collect();
    let level = ensemble.settings.level;
    let mut failures = Vec::new();
    let (mut uf, mut ff, mut ud) = (Vec::new(), Vec::new(), Vec::new());
    for r in out {
        match r {
            Ok((f, d)) => {
                uf.push(f.map(|x| x.0));
                ff.push(f.map(|x| x.1));
                ud.push(d);
            }
            Err(e) => {
                failures.push(e);
                uf.push(None);
                ff.push(None);
                ud.push(None);
            }
        }
    }
    Ok(FlutterEnsemble {
        members: laws.len(),
        seed: ensemble.settings.seed.to_string(),
        level,
        flutter_speed: MemberQuantity::new(uf, level),
        flutter_frequency_hz: MemberQuantity::new(ff, level),
        divergence_speed: MemberQuantity::new(ud, level),
        failures,
    })
}

/// LCO over an ensemble at one wind speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LcoEnsemblePoint {
    /// Wind speed U [m/s].
    pub u: f64,
    /// Pitch amplitude \[deg\] of the members that settle on an LCO.
    pub amplitude_alpha_deg: MemberQuantity,
    /// Heave amplitude \[mm\] of the same members.
    pub amplitude_h_mm: MemberQuantity,
    /// LCO frequency \[Hz\] of the same members.
    pub frequency_hz: MemberQuantity,
    /// Members that decay, diverge or do not settle (not in the intervals).
    pub decay: usize,
    /// Members that leave the bound.
    pub divergent: usize,
    /// Members that do not settle within the time cap.
    pub unsettled: usize,
}

/// LCO amplitudes over an ensemble.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LcoEnsemble {
    /// Members analysed.
    pub members: usize,
    /// Seed of the bootstrap that made the members.
    pub seed: String,
    /// Interval level.
    pub level: f64,
    /// One point per speed, in the given order.
    pub points: Vec<LcoEnsemblePoint>,
    /// Members (and speeds) whose law or run failed, with the reason.
    pub failures: Vec<String>,
}

/// K-iterated LCO runs ([`Section::lco_run_k`] with the default [`KIteration`]) of every
/// law at every speed of `speeds` from the perturbation `alpha0` \[rad\] in pitch, in
/// parallel over (member, speed).
///
/// # Errors
/// [`Error::InvalidParameter`] for `rho` ≤ 0 or invalid LCO options. A member's failure is
/// recorded in `failures`.
pub fn lco_ensemble(
    structure: &Structure,
    laws: &[std::result::Result<IdentifiedLaw, String>],
    ensemble: &Ensemble,
    rho: f64,
    speeds: &[f64],
    alpha0: f64,
    opts: &LcoOptions,
) -> Result<LcoEnsemble> {
    crate::error::positive("rho", rho)?;
    opts.check()?;
    let tasks: Vec<(usize, usize)> = (0..laws.len())
        .flat_map(|m| (0..speeds.len()).map(move |k| (m, k)))
        .collect();
    type Run = std::result::Result<(Classification, f64, f64, f64), String>;
    let runs: Vec<Run> = tasks
        .par_iter()
        .map(|&(m, k)| {
            let law = laws[m].as_ref().map_err(Clone::clone)?;
            let model: &NonlinearAero = law.model();
            let s = Section::new(structure.clone(), Arc::new(model.clone()), rho)
                .map_err(|e| format!("member {m}: {e}"))?;
            let r = s
                .lco_run_k(
                    speeds[k],
                    &s.perturbation(alpha0),
                    opts,
                    &KIteration::default(),
                )
                .map_err(|e| format!("member {m}, U = {} m/s: {e}", speeds[k]))?;
            Ok((
                r.classification,
                r.amplitude_alpha.to_degrees(),
                r.amplitude_h * 1e3,
                r.omega / (2.0 * std::f64::consts::PI),
            ))
        })
        .collect();
    let level = ensemble.settings.level;
    let mut failures = Vec::new();
    let mut points = Vec::with_capacity(speeds.len());
    for (k, &u) in speeds.iter().enumerate() {
        let (mut a, mut h, mut f) = (Vec::new(), Vec::new(), Vec::new());
        let (mut decay, mut divergent, mut unsettled) = (0, 0, 0);
        for m in 0..laws.len() {
            let lco = match &runs[m * speeds.len() + k] {
                Ok((Classification::Lco, aa, hh, ff)) => Some((*aa, *hh, *ff)),
                Ok((c, ..)) => {
                    match c {
                        Classification::Decay => decay += 1,
                        Classification::Divergent { .. } => divergent += 1,
                        _ => unsettled += 1,
                    }
                    None
                }
                Err(e) => {
                    if k == 0 || !e.starts_with(&format!("member {m}:")) {
                        failures.push(e.clone());
                    }
                    None
                }
            };
            a.push(lco.map(|x| x.0));
            h.push(lco.map(|x| x.1));
            f.push(lco.map(|x| x.2));
        }
        points.push(LcoEnsemblePoint {
            u,
            amplitude_alpha_deg: MemberQuantity::new(a, level),
            amplitude_h_mm: MemberQuantity::new(h, level),
            frequency_hz: MemberQuantity::new(f, level),
            decay,
            divergent,
            unsettled,
        });
    }
    Ok(LcoEnsemble {
        members: laws.len(),
        seed: ensemble.settings.seed.to_string(),
        level,
        points,
        failures,
    })
}
