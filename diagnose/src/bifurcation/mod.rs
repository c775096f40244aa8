//! The bifurcation level: the sim's bifurcation diagram (Hopf points, folds, stable and
//! unstable LCO branches by continuation) against a measured one, the catalogue
//! candidates fitted at this level with the continuation inside the fit, each scored by
//! leave-one-speed-out on the measured points (DESIGN §5; DECISIONS, "Diagnosis at the
//! bifurcation level").
//!
//! *Where*: Hopf speed and frequency, fold speeds, criticality, and the amplitude and
//! frequency error of every measured point against the predicted branch of the same
//! stability at its speed, per branch and per DOF. *Which*: every candidate of
//! [`catalogue`] fitted on all speeds but one and scored on that one; the
//! simplest candidate within one standard error of the best held-out score is named when
//! it removes at least `min_shrink` of the nominal model's held-out error. *How far*: the
//! held-out errors before and after, per branch and DOF.
//!
//! Still-air decays given with the measured diagram identify the structure first
//! ([`points::structure_check`]): the report states how the given structure's still-air
//! modes differ from the measured ones before any flow-dependent candidate, and when they
//! differ beyond their uncertainty the nominal model and every candidate are fitted on the
//! linear structure identified from them (`structure.used`, `structure.gap`: what the
//! correction alone did to the nominal score and Hopf speed).
//!
//! Units: U [m/s], pitch amplitudes \[rad\], heave amplitudes \[m\] (first harmonic, peak),
//! frequencies \[Hz\].

pub mod bench;
pub mod candidates;
mod fit;
pub mod points;
pub(crate) mod scales;

use aeroelastic::branch::{
    measured_distances, BranchMethod, BranchOptions, BranchSet, EventKind, MeasuredAmplitude,
    MeasuredDistance,
};
use aeroelastic::section::Section;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use crate::structure::{structure_check_records, StructureGap, StructureUsed};
use crate::{Effect, Error, Level, Result, Verdict};
use candidates::{BranchCandidate, ParameterSpec, Scales};
use fit::{diagram, levenberg_marquardt, residuals, start_grid, Setting};
pub use points::{points_from_records, structure_check, RecordRole, RecordUse, StructureCheck};

/// The `format` of a bifurcation-level diagnosis document.
pub const FORMAT: &str = "aeroform-bifurcation-diagnosis/1";

/// Starts of the grid from which a fit on all points runs Levenberg–Marquardt.
const START_POINTS: usize = 12;

/// Upper end of the continuation range as a multiple of the higher of the largest measured
/// speed and the nominal Hopf speed.
const HOPF_REACH: f64 = 2.0;

/// Settings of the bifurcation-level diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BifurcationOptions {
    /// Continuation settings (harmonic balance by default: condensed onto h, α for linear
    /// aerodynamics).
    pub branch: BranchOptions,
    /// Relative uncertainty of a measured amplitude (default 0.05): the nominal model's
    /// held-out error below twice this (in the same normalised units) is `none`.
    pub amplitude_noise: f64,
    /// Smallest fraction of the nominal held-out error the named candidate must remove
    /// (default 0.3, as the other levels).
    pub min_shrink: f64,
    /// Levenberg–Marquardt iterations of a fit on all points (folds take half).
    pub max_iterations: usize,
}

impl Default for BifurcationOptions {
    fn default() -> Self {
        BifurcationOptions {
            branch: BranchOptions {
                method: BranchMethod::HarmonicBalance,
                ..BranchOptions::default()
            },
            amplitude_noise: 0.05,
            min_shrink: 0.3,
            max_iterations: 30,
        }
    }
}

/// Which measured points an error row covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BranchKind {
    /// Points on the stable branch.
    Stable,
    /// Points on the unstable branch.
    Unstable,
    /// Every point.
    All,
}

/// The quantity of an error row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// First-harmonic pitch amplitude \[rad\].
    Pitch,
    /// First-harmonic heave amplitude \[m\].
    Heave,
    /// Frequency \[Hz\].
    Frequency,
}

/// RMS error of one quantity over one branch's points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ErrorRow {
    /// Points of this branch.
    pub branch: BranchKind,
    /// Quantity.
    pub quantity: Quantity,
    /// Points with this quantity measured.
    pub n: usize,
    /// Of those, points whose speed no predicted branch of their stability covers
    /// (amplitudes count with prediction 0; frequencies are left out).
    pub uncovered: usize,
    /// RMS of predicted − measured (rad, m or Hz); `null` when no point enters.
    pub rms: Option<f64>,
}

/// Errors of a predicted diagram at the measured points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Errors {
    /// Rows per (branch, quantity).
    pub rows: Vec<ErrorRow>,
    /// Normalised score: √(mean of ((pred − meas)/max(meas, s_d/4))²) over every measured
    /// amplitude (relative errors), s_d the RMS measured amplitude of DOF d (uncovered
    /// points predicted 0, i.e. an error of 1), and of (pred − meas)/meas over every
    /// measured frequency of a covered point.
    pub score: f64,
}

impl Errors {
    /// The RMS of `quantity` over `branch`, if any point enters.
    pub fn rms(&self, branch: BranchKind, quantity: Quantity) -> Option<f64> {
        self.rows
            .iter()
            .find(|r| r.branch == branch && r.quantity == quantity)
            .and_then(|r| r.rms)
    }
}

/// A Hopf point of a predicted diagram.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HopfSummary {
    /// Speed [m/s].
    pub u: f64,
    /// Frequency \[Hz\].
    pub frequency_hz: f64,
    /// `subcritical` / `supercritical` (from its branch).
    pub criticality: String,
    /// The speed lies outside the measured speeds' range ([`Extent`]): a prediction the
    /// data do not test (issue 42).
    #[serde(default)]
    pub extrapolation: bool,
}

/// A fold of cycles of a predicted diagram.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FoldSummary {
    /// Speed [m/s].
    pub u: f64,
    /// First-harmonic pitch amplitude of the orbit there \[rad\].
    pub amplitude1_alpha: f64,
    /// First-harmonic heave amplitude \[m\].
    pub amplitude1_h: f64,
    /// The fold lies outside the measured speeds' range or above the largest measured
    /// amplitude of a measured DOF ([`Extent`]): a turning point the data do not show.
    #[serde(default)]
    pub extrapolation: bool,
}

/// The part of the (speed, amplitude) plane the measured points span: a predicted Hopf
/// point outside [u_min, u_max], or a fold outside it or above the largest measured pitch or
/// heave amplitude, is an extrapolation (flagged, not scored).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extent {
    /// Smallest and largest measured speed [m/s].
    pub u: [f64; 2],
    /// Largest measured first-harmonic pitch amplitude \[rad\] (`None`: pitch not measured).
    pub alpha_max: Option<f64>,
    /// Largest measured first-harmonic heave amplitude \[m\] (`None`: heave not measured).
    pub h_max: Option<f64>,
}

impl Extent {
    /// The extent of `measured` (`None` when it is empty).
    pub fn of(measured: &[MeasuredAmplitude]) -> Option<Extent> {
        let first = measured.first()?;
        let mut e = Extent {
            u: [first.u, first.u],
            alpha_max: None,
            h_max: None,
        };
        for m in measured {
            e.u = [e.u[0].min(m.u), e.u[1].max(m.u)];
            if let Some(a) = m.amplitude_alpha {
                e.alpha_max = Some(e.alpha_max.map_or(a, |v| v.max(a)));
            }
            if let Some(h) = m.amplitude_h {
                e.h_max = Some(e.h_max.map_or(h, |v| v.max(h)));
            }
        }
        Some(e)
    }

    /// Whether speed `u` lies outside the measured speeds.
    pub fn outside_speeds(&self, u: f64) -> bool {
        u < self.u[0] || u > self.u[1]
    }

    /// Whether an orbit at speed `u` with amplitudes (`alpha`, `h`) lies outside the
    /// measured extent.
    pub fn outside(&self, u: f64, alpha: f64, h: f64) -> bool {
        self.outside_speeds(u)
            || self.alpha_max.is_some_and(|a| alpha > a)
            || self.h_max.is_some_and(|m| h > m)
    }
}

/// A predicted diagram against the measured points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DiagramSummary {
    /// Hopf points in the continuation range.
    pub hopf: Vec<HopfSummary>,
    /// Folds of cycles.
    pub folds: Vec<FoldSummary>,
    /// Each measured point against the branch of its stability.
    pub points: Vec<MeasuredDistance>,
    /// Errors over all points (in-sample for a fitted candidate).
    pub errors: Errors,
    /// The continued branches (for the figure); `null` when the section has no Hopf point
    /// in the range.
    pub branches: Option<BranchSet>,
}

/// A fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FittedParameter {
    /// Its specification (name, unit, sign convention, scale).
    #[serde(flatten)]
    pub spec: ParameterSpec,
    /// Value fitted on all points.
    pub value: f64,
    /// Values fitted in the leave-one-speed-out folds (same order as `speed_groups`).
    pub fold_values: Vec<f64>,
}

/// One candidate at the bifurcation level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CandidateResult {
    /// Catalogue effect.
    pub effect: Effect,
    /// Level of the effect.
    pub level: Level,
    /// Form (`pitch`, `pitch+heave`, …).
    pub variant: String,
    /// Label of the candidate it extends (nested), if any.
    pub extends: Option<String>,
    /// Fitted parameters.
    pub parameters: Vec<FittedParameter>,
    /// The diagram with the parameters fitted on all points.
    pub fit: DiagramSummary,
    /// Held-out predictions: each point predicted by the fit without its speed.
    pub held_out_points: Vec<MeasuredDistance>,
    /// Held-out errors.
    pub held_out: Errors,
    /// Standard error of the held-out score over the speed groups, at least the amplitude
    /// uncertainty over √(number of held-out residuals).
    pub score_se: f64,
    /// 1 − held-out score / nominal held-out score.
    pub shrink: f64,
    /// Continuations run for this candidate.
    pub evaluations: usize,
    /// Scaled parameters of the fit on all points.
    #[serde(skip)]
    #[schemars(skip)]
    pub theta: Vec<f64>,
}

impl CandidateResult {
    /// `effect (variant)`.
    pub fn label(&self) -> String {
        format!("{} ({})", self.effect.name(), self.variant)
    }
}

/// The verdict at the bifurcation level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchVerdict {
    /// The catalogue effect named, if any.
    pub effect: Option<Effect>,
    /// The verdict: the effect named, `none` or `unexplained` (written by name).
    pub name: Verdict,
    /// Index of the named candidate in `candidates`.
    pub candidate: Option<usize>,
    /// Candidates with a better held-out score within one standard error of the best
    /// (the richer ones the one-standard-error rule passed over).
    pub richer: Vec<String>,
    /// Held-out shrink of the named candidate.
    pub shrink: Option<f64>,
    /// Why, in words.
    pub explanation: String,
}

/// The bifurcation-level diagnosis (`bifurcation.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BifurcationDiagnosis {
    /// `aeroform-bifurcation-diagnosis/1`.
    pub format: String,
    /// aeroform version that wrote it.
    pub version: String,
    /// Inputs (measured diagram, structure, model, decays).
    pub inputs: Vec<String>,
    /// Settings.
    pub options: BifurcationOptions,
    /// The measured points.
    pub measured: Vec<MeasuredAmplitude>,
    /// What became of each record (points extracted from records, decays).
    pub records: Vec<RecordUse>,
    /// The distinct measured speeds: the folds of leave-one-speed-out.
    pub speed_groups: Vec<f64>,
    /// Normalising amplitudes: RMS measured pitch \[rad\] and heave \[m\].
    pub normalisation: Scales,
    /// Continuation range [m/s].
    pub speed_range: [f64; 2],
    /// The still-air decays against the given structure (structure first), when given:
    /// the modes, the structure identified from them with intervals, which structure the
    /// level used (`used`) and what the correction alone did (`gap`).
    pub structure: Option<StructureCheck>,
    /// The nominal model's diagram (nothing fitted: its errors are held-out errors).
    pub nominal: DiagramSummary,
    /// Candidates, best held-out score first.
    pub candidates: Vec<CandidateResult>,
    /// Effects of the catalogue not fitted at this level, and why.
    pub not_fitted: Vec<String>,
    /// The verdict.
    pub verdict: BranchVerdict,
    /// Wall time \[s\].
    pub seconds: f64,
}

/// Groups of equal measured speed (within 1e-6 relative), increasing.
fn speed_groups(measured: &[MeasuredAmplitude]) -> Vec<f64> {
    let mut u: Vec<f64> = measured.iter().map(|m| m.u).collect();
    u.sort_by(f64::total_cmp);
    u.dedup_by(|a, b| (*a - *b).abs() <= 1e-6 * b.abs().max(1.0));
    u
}

fn same_speed(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * b.abs().max(1.0)
}

/// Errors of predictions `d` (one per measured point).
fn errors(d: &[MeasuredDistance], s: &Setting) -> Errors {
    let mut rows = Vec::new();
    for branch in [BranchKind::Stable, BranchKind::Unstable, BranchKind::All] {
        let sel: Vec<&MeasuredDistance> = d
            .iter()
            .filter(|x| match branch {
                BranchKind::Stable => x.measured.stable,
                BranchKind::Unstable => !x.measured.stable,
                BranchKind::All => true,
            })
            .collect();
        for quantity in [Quantity::Pitch, Quantity::Heave, Quantity::Frequency] {
            let mut sq = Vec::new();
            let mut n = 0;
            let mut uncovered = 0;
            for x in &sel {
                let (meas, pred) = match quantity {
                    Quantity::Pitch => (x.measured.amplitude_alpha, x.predicted_alpha),
                    Quantity::Heave => (x.measured.amplitude_h, x.predicted_h),
                    Quantity::Frequency => (x.measured.frequency_hz, x.predicted_frequency_hz),
                };
                let Some(m) = meas else { continue };
                n += 1;
                match pred {
                    Some(p) => sq.push((p - m) * (p - m)),
                    None => {
                        uncovered += 1;
                        if quantity != Quantity::Frequency {
                            sq.push(m * m);
                        }
                    }
                }
            }
            if n > 0 {
                rows.push(ErrorRow {
                    branch,
                    quantity,
                    n,
                    uncovered,
                    rms: (!sq.is_empty())
                        .then(|| (sq.iter().sum::<f64>() / sq.len() as f64).sqrt()),
                });
            }
        }
    }
    let z = normalised(d, s);
    let score = if z.is_empty() {
        0.0
    } else {
        (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt()
    };
    Errors { rows, score }
}

/// Normalised errors of predictions `d`: relative amplitude errors (uncovered: predicted
/// 0) and relative frequency errors of covered points.
fn normalised(d: &[MeasuredDistance], s: &Setting) -> Vec<f64> {
    let mut z = Vec::new();
    for x in d {
        if let Some(m) = x.measured.amplitude_alpha {
            z.push((x.predicted_alpha.unwrap_or(0.0) - m) / s.n_alpha(m));
        }
        if let Some(m) = x.measured.amplitude_h {
            z.push((x.predicted_h.unwrap_or(0.0) - m) / s.n_h(m));
        }
        if let (Some(m), Some(p)) = (x.measured.frequency_hz, x.predicted_frequency_hz) {
            z.push((p - m) / m);
        }
    }
    z
}

fn summary(set: Option<BranchSet>, measured: &[MeasuredAmplitude], s: &Setting) -> DiagramSummary {
    let points = match &set {
        Some(set) => measured_distances(set, measured),
        None => measured
            .iter()
            .map(|m| MeasuredDistance {
                measured: m.clone(),
                predicted_alpha: None,
                predicted_h: None,
                predicted_frequency_hz: None,
                d_alpha: None,
                d_h: None,
                speed_gap: None,
            })
            .collect(),
    };
    let extent = Extent::of(measured);
    let outside_speeds = |u: f64| extent.is_some_and(|e| e.outside_speeds(u));
    let outside = |u: f64, a: f64, h: f64| extent.is_some_and(|e| e.outside(u, a, h));
    let (hopf, folds) = match &set {
        Some(set) => (
            set.branches
                .iter()
                .map(|b| HopfSummary {
                    u: b.hopf.u,
                    frequency_hz: b.hopf.omega / std::f64::consts::TAU,
                    criticality: b.criticality.clone(),
                    extrapolation: outside_speeds(b.hopf.u),
                })
                .collect(),
            set.branches
                .iter()
                .flat_map(|b| {
                    b.events
                        .iter()
                        .filter(|e| e.kind == EventKind::Fold)
                        .map(|e| {
                            let p = &b.points[e.index.saturating_sub(1)];
                            FoldSummary {
                                u: e.u,
                                amplitude1_alpha: p.amplitude1_alpha,
                                amplitude1_h: p.amplitude1_h,
                                extrapolation: outside(e.u, p.amplitude1_alpha, p.amplitude1_h),
                            }
                        })
                })
                .collect(),
        ),
        None => (Vec::new(), Vec::new()),
    };
    let errors = errors(&points, s);
    DiagramSummary {
        hopf,
        folds,
        points,
        errors,
        branches: set,
    }
}

/// Diagnoses the measured bifurcation diagram `measured` against the nominal `section`.
/// `structure` is the still-air decays' check ([`structure_check`], structure first):
/// when its `used` is `identified`, the nominal model and every candidate use the
/// identified linear structure (the given one's nonlinear terms kept) and its `gap` is
/// filled; `records` says where the measured points came from (empty for a table).
///
/// # Errors
/// [`Error::Data`] for a measured diagram with fewer than two distinct speeds (nothing
/// to hold out) or non-finite values; [`Error::Setting`] for bad options;
/// [`Error::Aeroelastic`] when the identified structure makes no valid section.
pub fn diagnose_branches(
    measured: &[MeasuredAmplitude],
    section: &Section,
    structure: Option<StructureCheck>,
    records: Vec<RecordUse>,
    opts: &BifurcationOptions,
    inputs: Vec<String>,
    version: &str,
) -> Result<BifurcationDiagnosis> {
    let t0 = std::time::Instant::now();
    // Structure first: the candidates are fitted on the structure identified from the
    // still-air decays when they differ from the given one beyond their uncertainty.
    let mut structure = structure;
    let given_section = section;
    let identified_section;
    let section: &Section = match structure.as_ref() {
        Some(c) if c.used == StructureUsed::Identified => {
            identified_section = Section::new(
                c.used_structure(&section.structure),
                section.aero.clone(),
                section.rho,
            )
            .map_err(|e| Error::aeroelastic("the structure identified from the decays", e))?;
            &identified_section
        }
        _ => section,
    };
    opts.branch
        .check()
        .map_err(|e| Error::aeroelastic("bifurcation options", e))?;
    for (name, v) in [
        ("amplitude_noise", opts.amplitude_noise),
        ("min_shrink", opts.min_shrink),
    ] {
        if !(v.is_finite() && v > 0.0 && v < 1.0) {
            return Err(Error::setting(name, v, "must lie in (0, 1)"));
        }
    }
    let groups = speed_groups(measured);
    if groups.len() < 2 {
        return Err(Error::data(
            "measured diagram",
            format!(
                "{} point(s) at {} distinct speed(s): leave-one-speed-out needs at least two \
                 speeds",
                measured.len(),
                groups.len()
            ),
        ));
    }
    let rms_of = |f: &dyn Fn(&MeasuredAmplitude) -> Option<f64>| {
        let v: Vec<f64> = measured.iter().filter_map(f).collect();
        (!v.is_empty()).then(|| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt())
    };
    let s_alpha = rms_of(&|m| m.amplitude_alpha);
    let s_h = rms_of(&|m| m.amplitude_h);
    let max_of = |f: &dyn Fn(&MeasuredAmplitude) -> Option<f64>| {
        measured.iter().filter_map(f).fold(0.0, f64::max)
    };
    // A DOF not measured gets a scale from the other through the structure's radius of
    // gyration (it only sizes the candidates' parameters).
    let rg = (section.structure.inertia_alpha / section.structure.mass).sqrt();
    let (s_alpha, s_h) = match (s_alpha, s_h) {
        (Some(a), Some(h)) => (a, h),
        (Some(a), None) => (a, a * rg),
        (None, Some(h)) => (h / rg, h),
        (None, None) => {
            return Err(Error::data(
                "measured diagram",
                "no point has a pitch or heave amplitude",
            ))
        }
    };
    if !(s_alpha > 0.0 && s_h > 0.0) {
        return Err(Error::data(
            "measured diagram",
            "every measured amplitude is zero",
        ));
    }
    let u_max_meas = groups[groups.len() - 1];
    let u_min_meas = groups[0];
    let mean_u = measured.iter().map(|m| m.u).sum::<f64>() / measured.len() as f64;
    // Range: the measured speeds widened, and the nominal Hopf point when it lies above.
    let mut branch = opts.branch;
    let amax = max_of(&|m| m.amplitude_alpha).max(max_of(&|m| m.amplitude_h) / rg);
    branch.max_amplitude_alpha = branch.max_amplitude_alpha.min((4.0 * amax).max(0.02));
    let probe = Setting {
        branch: &branch,
        range: [0.5 * u_min_meas, 1.5 * u_max_meas],
        s_alpha,
        s_h,
        s_u: 0.02 * mean_u,
    };
    let hopf_nominal = section
        .hopf_points(probe.range[0], probe.range[1], branch.n_scan)
        .unwrap_or_default();
    // Up to twice the higher of the measured speeds and the nominal Hopf speed: a candidate
    // that adds damping at rest (added mass, regularised friction) moves its Hopf point up,
    // and its branch must still start inside the range (4× changed no verdict of the
    // generated benchmark's friction sets: DECISIONS).
    let hi = HOPF_REACH
        * hopf_nominal
            .iter()
            .map(|h| h.u)
            .fold(u_max_meas, f64::max)
            .min(1.5 * u_max_meas);
    let range = [0.7 * u_min_meas, hi];
    let setting = Setting { range, ..probe };
    let all: Vec<&MeasuredAmplitude> = measured.iter().collect();
    // A linear section has no limit cycle: its "branch" is the vertical family of
    // neutral orbits at the Hopf speed, not a diagram; only its Hopf points are reported.
    let nominal_of = |section: &Section| {
        if section.structure.is_linear() && section.aero.is_linear() {
            let mut s = summary(None, measured, &setting);
            s.hopf = section
                .hopf_points(range[0], range[1], branch.n_scan)
                .unwrap_or_default()
                .iter()
                .map(|h| HopfSummary {
                    u: h.u,
                    frequency_hz: h.omega / std::f64::consts::TAU,
                    criticality: "degenerate (linear section: no limit cycle)".into(),
                    extrapolation: Extent::of(measured).is_some_and(|e| e.outside_speeds(h.u)),
                })
                .collect();
            s
        } else {
            summary(diagram(section, &setting), measured, &setting)
        }
    };
    let nominal = nominal_of(section);
    let nominal_score = nominal.errors.score;
    if let Some(c) = structure.as_mut() {
        if c.used == StructureUsed::Identified {
            let g = nominal_of(given_section);
            c.gap = Some(StructureGap {
                metric: "normalised score of the nominal model at the measured points".into(),
                given: g.errors.score,
                identified: nominal_score,
                hopf_given: g.hopf.first().map(|h| h.u),
                hopf_identified: nominal.hopf.first().map(|h| h.u),
            });
        }
    }
    let scales = Scales {
        alpha: max_of(&|m| m.amplitude_alpha).max(s_alpha),
        h: max_of(&|m| m.amplitude_h).max(s_h),
    };
    // Structure first, for every candidate: on the identified structure each change is
    // conformed to the decays (its springs and dampers re-identified under it).
    let decays = structure
        .as_ref()
        .filter(|c| c.used == StructureUsed::Identified)
        .map(|c| std::sync::Arc::new(c.clone()));
    let cat: Vec<BranchCandidate> = catalogue(section, scales)
        .into_iter()
        .map(|c| c.with_decays(decays.clone()))
        .collect();
    // Nested candidates start from the optimum of the one they extend: fit by depth.
    let depth = |mut i: usize| {
        let mut d = 0;
        while let Some(p) = cat[i].extends {
            i = p;
            d += 1;
        }
        d
    };
    let mut done: Vec<Option<CandidateResult>> = vec![None; cat.len()];
    for d in 0..cat.len() {
        let level: Vec<usize> = (0..cat.len()).filter(|&i| depth(i) == d).collect();
        if level.is_empty() {
            break;
        }
        let fitted: Vec<(usize, Result<CandidateResult>)> = level
            .par_iter()
            .map(|&i| {
                let parent = cat[i].extends.and_then(|p| done[p].as_ref());
                let start = parent.map(|p| p.theta.clone());
                let r = fit_candidate(
                    &cat[i],
                    &cat,
                    section,
                    measured,
                    &all,
                    &groups,
                    &setting,
                    opts,
                    nominal_score,
                    start,
                );
                (i, r)
            })
            .collect();
        for (i, r) in fitted {
            done[i] = Some(r?);
        }
    }
    let mut candidates: Vec<CandidateResult> = done.into_iter().flatten().collect();
    candidates.sort_by(|a, b| a.held_out.score.total_cmp(&b.held_out.score));
    let mut verdict = verdict(&candidates, nominal_score, opts);
    verdict
        .explanation
        .push_str(&structure_sentence(structure.as_ref()));
    Ok(BifurcationDiagnosis {
        format: FORMAT.into(),
        version: version.into(),
        inputs,
        options: opts.clone(),
        measured: measured.to_vec(),
        records,
        speed_groups: groups,
        normalisation: Scales {
            alpha: s_alpha,
            h: s_h,
        },
        speed_range: range,
        structure,
        nominal,
        candidates,
        not_fitted: not_fitted(),
        verdict,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The verdict's sentence on the structure it used (empty without still-air decays).
fn structure_sentence(c: Option<&StructureCheck>) -> String {
    let Some(c) = c else {
        return String::new();
    };
    match (c.used, &c.gap) {
        (StructureUsed::Identified, Some(g)) => format!(
            "; on the structure identified from the still-air decays (the correction alone \
             moves the nominal score {:.3} → {:.3}{})",
            g.given,
            g.identified,
            match (g.hopf_given, g.hopf_identified) {
                (Some(a), Some(b)) => format!(" and its Hopf speed {a:.3} → {b:.3} m/s"),
                _ => String::new(),
            }
        ),
        _ => "; on the given structure".to_string(),
    }
}

/// The candidates of every catalogue effect for `base` and measured amplitudes `s`, in
/// catalogue order, each nested one after the one it extends (whose parameters come
/// first in its own); parameter scales made positive.
pub fn catalogue(base: &Section, s: Scales) -> Vec<BranchCandidate> {
    let mut out: Vec<BranchCandidate> = Effect::ALL
        .into_iter()
        .flat_map(|e| e.entry().bifurcation(base, s))
        .collect();
    for i in 0..out.len() {
        out[i].extends = out[i].extends_key.and_then(|(e, v)| {
            out[..i]
                .iter()
                .position(|c| c.effect == e && c.variant == v)
        });
        out[i]
            .parameters
            .iter_mut()
            .for_each(|q| q.scale = q.scale.abs());
    }
    out
}

/// Why each catalogue effect that is not fitted at this level is not, in catalogue order.
fn not_fitted() -> Vec<String> {
    Effect::ALL
        .into_iter()
        .filter_map(|e| e.entry().not_at_bifurcation())
        .map(String::from)
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn fit_candidate(
    c: &BranchCandidate,
    cat: &[BranchCandidate],
    section: &Section,
    measured: &[MeasuredAmplitude],
    all: &[&MeasuredAmplitude],
    groups: &[f64],
    setting: &Setting,
    opts: &BifurcationOptions,
    nominal_score: f64,
    parent: Option<Vec<f64>>,
) -> Result<CandidateResult> {
    let evals = std::sync::atomic::AtomicUsize::new(0);
    let eval = |theta: &[f64], pts: &[&MeasuredAmplitude]| -> Vec<f64> {
        evals.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let set = c
            .apply(section, theta)
            .ok()
            .and_then(|s| diagram(&s, setting));
        residuals(set.as_ref(), pts, setting)
    };
    let n = c.parameters.len();
    // Start: the best point of the grid (and the origin's neighbourhood).
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut starts = start_grid(n);
    starts.push(vec![0.0; n]);
    if let Some(mut p) = parent {
        p.resize(n, 0.0);
        starts.push(p);
    }
    let mut ranked: Vec<(f64, Vec<f64>)> = starts
        .iter()
        .map(|s| (cost(&eval(s, all)), s.clone()))
        .collect();
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Levenberg–Marquardt from the best few starts (the landscape has several basins:
    // a fold can form from softening or from an even term), the best end kept.
    let f_all = |th: &[f64]| eval(th, all);
    let full = ranked
        .iter()
        .take(START_POINTS)
        .map(|(_, s)| levenberg_marquardt(&f_all, s, opts.max_iterations))
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .expect("at least one start");
    // Even terms jointly to the sign convention (first even term ≥ 0): the diagram is the
    // same (q → −q symmetry of the linear section).
    let even: Vec<usize> = (0..n).filter(|&k| c.parameters[k].even).collect();
    let flip = |v: &mut [f64]| {
        if even.first().is_some_and(|&k| v[k] < 0.0) {
            even.iter().for_each(|&k| v[k] = -v[k]);
        }
    };
    // Leave one speed out, each fold from the all-points optimum.
    let mut held = vec![None; measured.len()];
    let mut fold_values = vec![Vec::new(); n];
    for &g in groups {
        let train: Vec<&MeasuredAmplitude> = all
            .iter()
            .copied()
            .filter(|m| !same_speed(m.u, g))
            .collect();
        let f_train = |th: &[f64]| eval(th, &train);
        let r = levenberg_marquardt(&f_train, &full.theta, opts.max_iterations / 2);
        let mut v = c.values(&r.theta);
        flip(&mut v);
        for (k, v) in v.into_iter().enumerate() {
            fold_values[k].push(v);
        }
        let test: Vec<MeasuredAmplitude> = measured
            .iter()
            .filter(|m| same_speed(m.u, g))
            .cloned()
            .collect();
        let set = c
            .apply(section, &r.theta)
            .ok()
            .and_then(|s| diagram(&s, setting));
        evals.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let d = match &set {
            Some(set) => measured_distances(set, &test),
            None => summary(None, &test, setting).points,
        };
        let mut it = d.into_iter();
        for (i, m) in measured.iter().enumerate() {
            if same_speed(m.u, g) {
                held[i] = it.next();
            }
        }
    }
    let held: Vec<MeasuredDistance> = held
        .into_iter()
        .map(|d| d.expect("every point held out once"))
        .collect();
    let held_out = errors(&held, setting);
    // Standard error of the score over the speed groups (delta method on its square).
    let per_group: Vec<f64> = groups
        .iter()
        .map(|&g| {
            let d: Vec<MeasuredDistance> = held
                .iter()
                .filter(|x| same_speed(x.measured.u, g))
                .cloned()
                .collect();
            let z = normalised(&d, setting);
            z.iter().map(|v| v * v).sum::<f64>() / z.len().max(1) as f64
        })
        .collect();
    let g = per_group.len() as f64;
    let mean = per_group.iter().sum::<f64>() / g;
    let var = per_group.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (g - 1.0).max(1.0);
    let se_sq = (var / g).sqrt();
    // Floored at the resolution the measurement allows: the amplitude uncertainty over the
    // number of held-out residuals (noise-free points would otherwise leave no standard
    // error and let a richer candidate win by a rounding difference).
    let n_res = normalised(&held, setting).len().max(1) as f64;
    let resolution = opts.amplitude_noise / n_res.sqrt();
    let score_se = if held_out.score > 0.0 {
        (se_sq / (2.0 * held_out.score)).max(resolution)
    } else {
        resolution
    };
    let set_all = c
        .apply(section, &full.theta)
        .ok()
        .and_then(|s| diagram(&s, setting));
    let fit = summary(set_all, measured, setting);
    let mut values = c.values(&full.theta);
    flip(&mut values);
    Ok(CandidateResult {
        effect: c.effect,
        level: c.effect.level(),
        variant: c.variant.clone(),
        extends: c.extends.map(|i| cat[i].label()),
        parameters: c
            .parameters
            .iter()
            .zip(values)
            .zip(fold_values)
            .map(|((spec, value), fold_values)| FittedParameter {
                spec: spec.clone(),
                value,
                fold_values,
            })
            .collect(),
        fit,
        held_out_points: held,
        shrink: if nominal_score > 0.0 {
            1.0 - held_out.score / nominal_score
        } else {
            0.0
        },
        held_out,
        score_se,
        evaluations: evals.load(std::sync::atomic::Ordering::Relaxed) + 1,
        theta: full.theta,
    })
}

/// The one-standard-error rule over `ranked` (best held-out score first) and the naming
/// rule.
fn verdict(ranked: &[CandidateResult], nominal: f64, opts: &BifurcationOptions) -> BranchVerdict {
    if nominal <= 2.0 * opts.amplitude_noise {
        return BranchVerdict {
            effect: None,
            name: Verdict::None,
            candidate: None,
            richer: Vec::new(),
            shrink: None,
            explanation: format!(
                "the nominal model's error at the measured points ({nominal:.3} of the RMS \
                 amplitude) is within twice the amplitude uncertainty ({:.3})",
                opts.amplitude_noise
            ),
        };
    }
    let Some(best) = ranked.first() else {
        return BranchVerdict {
            effect: None,
            name: Verdict::Unexplained,
            candidate: None,
            richer: Vec::new(),
            shrink: None,
            explanation: "no candidate could be fitted".into(),
        };
    };
    let bar = best.held_out.score + best.score_se;
    let (idx, chosen) = ranked
        .iter()
        .enumerate()
        .filter(|(_, c)| c.held_out.score <= bar)
        .min_by(|(_, a), (_, b)| {
            a.parameters
                .len()
                .cmp(&b.parameters.len())
                .then(a.held_out.score.total_cmp(&b.held_out.score))
        })
        // a non-finite score leaves no candidate under the bar: the best stands
        .unwrap_or((0, best));
    let richer: Vec<String> = ranked[..idx].iter().map(|c| c.label()).collect();
    if chosen.shrink >= opts.min_shrink {
        BranchVerdict {
            effect: Some(chosen.effect),
            name: Verdict::Effect(chosen.effect),
            candidate: Some(idx),
            richer,
            shrink: Some(chosen.shrink),
            explanation: format!(
                "{} removes {:.1} % of the nominal held-out error ({:.3} → {:.3} of the RMS \
                 amplitude); it is the simplest candidate within one standard error ({:.3}) \
                 of the best held-out score",
                chosen.label(),
                100.0 * chosen.shrink,
                nominal,
                chosen.held_out.score,
                best.score_se
            ),
        }
    } else {
        BranchVerdict {
            effect: None,
            name: Verdict::Unexplained,
            candidate: None,
            richer: Vec::new(),
            shrink: Some(best.shrink),
            explanation: format!(
                "the nominal error ({nominal:.3}) is significant but the best candidate, {}, \
                 removes only {:.1} % of it on held-out speeds (the rule asks {:.0} %)",
                best.label(),
                100.0 * best.shrink,
                100.0 * opts.min_shrink
            ),
        }
    }
}

#[cfg(test)]
mod extent_tests {
    use super::*;

    fn point(u: f64, a: Option<f64>) -> MeasuredAmplitude {
        MeasuredAmplitude {
            line: 0,
            stable: true,
            u,
            amplitude_h: None,
            amplitude_alpha: a,
            frequency_hz: None,
        }
    }

    /// The measured extent: speeds [min, max], the largest amplitude of each measured DOF; a
    /// fold beyond either is flagged, one inside is not; a DOF that was not measured does
    /// not bound.
    #[test]
    fn folds_and_hopf_points_outside_the_measured_points_are_extrapolations() {
        let m = [
            point(14.9, Some(0.05)),
            point(17.3, Some(0.08)),
            point(15.6, Some(0.01)),
        ];
        let e = Extent::of(&m).unwrap();
        assert_eq!(e.u, [14.9, 17.3]);
        assert_eq!(e.alpha_max, Some(0.08));
        assert_eq!(e.h_max, None);
        assert!(!e.outside(16.0, 0.07, 1.0), "inside; heave not measured");
        assert!(
            e.outside(16.0, 0.09, 0.0),
            "above the largest pitch amplitude"
        );
        assert!(
            e.outside(14.6, 0.04, 0.0),
            "below the slowest measured speed"
        );
        assert!(e.outside_speeds(17.957) && !e.outside_speeds(17.3));
        assert!(Extent::of(&[]).is_none());
    }
}
