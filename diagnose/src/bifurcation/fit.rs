//! Fitting a candidate with continuation inside the fit, and scoring it by
//! leave-one-speed-out.
//!
//! Every evaluation continues the periodic orbits of the changed section from its Hopf
//! points ([`Section::lco_branches`], condensed harmonic balance where it applies) and
//! compares them with the measured points. The fit minimises, by Levenberg–Marquardt from
//! the best points of a coarse start grid, the residuals below. With the default
//! `differences` the Jacobian is a forward difference of whole diagrams and a covered
//! point's prediction interpolates between continuation points; with `sensitivities` (the
//! smooth objective) each covered point's orbit is corrected at its own speed
//! ([`Predicted::corrected`]) and the Jacobian comes from those orbits' sensitivities
//! ([`residual_jacobian`]: one corrected orbit per point instead of one diagram per
//! parameter; differences where they are not available).
//!
//! - per measured point and measured DOF d: (a_pred − a_meas) / max(a_meas, s_d/4), s_d the
//!   RMS measured amplitude of that DOF (relative errors: a measured amplitude scatters by
//!   a fraction of itself), on the branch segment of the same stability that covers the
//!   point's speed;
//! - per measured frequency f: (f_pred − f)/f on the same orbit;
//! - when none covers it: the same with the nearest predicted orbit of that stability (in
//!   the scaled (U, amplitude) plane), plus (U_orbit − U_meas)/s_U, s_U = 2 % of the mean
//!   measured speed, so that a branch whose fold moved past a measured speed is pulled
//!   back continuously instead of dropping out.
//!
//! - per measured onset (a row `onset`): w·(U_Hopf − U_onset)/σ_U for the model's first
//!   (lowest) Hopf point, w·(f_Hopf − f_onset)/σ_f when the frequency was measured, and 1
//!   when the criticality was measured and the model's differs (a linear section's is
//!   degenerate); w = the amplitude uncertainty (default 0.05), σ the row's stated
//!   uncertainty or the default relative one (1 %) times the value — one standard
//!   uncertainty of the onset weighs as much as one of an amplitude, and a wrong
//!   criticality as much as a missed amplitude;
//! - per "no LCO observed" row (`none`), per measured DOF: a_LCO/s_d when the model has a
//!   stable cycle at that speed that the rig would have reached (the equilibrium is
//!   unstable there, or the perturbation tried exceeds the unstable cycle below it, or no
//!   perturbation is stated), 1 when the equilibrium is unstable with no bounded cycle,
//!   else 0.
//!
//! The score that decides is the plain one at the measured speed (a point the model
//! leaves uncovered counts with predicted amplitude 0), on held-out speeds only.

use aeroelastic::branch::{
    BranchOptions, BranchSet, MeasuredAbsence, MeasuredAmplitude, MeasuredOnset, OrbitValues,
    SensitivityAt,
};
use aeroelastic::section::Section;
use nalgebra::{DMatrix, DVector};

/// Everything an evaluation needs besides the section.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Setting<'a> {
    /// Continuation options.
    pub branch: &'a BranchOptions,
    /// Continuation speed range [m/s].
    pub range: [f64; 2],
    /// Amplitude scales: pitch \[rad\], heave \[m\] (RMS of the measured amplitudes).
    pub s_alpha: f64,
    /// Heave scale \[m\].
    pub s_h: f64,
    /// Speed scale [m/s].
    pub s_u: f64,
    /// Amplitude uncertainty (relative): the weight w of an onset residual.
    pub noise: f64,
    /// Default relative uncertainty of a measured onset speed and frequency.
    pub onset_sd: f64,
    /// Whether the measured points hold pitch and heave amplitudes (the DOFs an absence
    /// row's residuals are taken in).
    pub dofs: [bool; 2],
    /// Smallest and largest speed of the onset and absence rows [m/s] (`[∞, −∞]` without
    /// any): they widen the measured extent.
    pub row_speeds: [f64; 2],
    /// The measured amplitude points whose orbits a prediction corrects at their own speed
    /// ([`Predicted::corrected`]); empty: predictions interpolate between continuation
    /// points.
    pub points: &'a [MeasuredAmplitude],
    /// Speed [m/s] past which a branch moving to higher speeds is not continued
    /// ([`Section::lco_branches_within`]): the fits' evaluations stop there, the
    /// diagrams reported are continued over the whole range (∞).
    pub reach: f64,
}

impl Setting<'_> {
    /// Divisor of a pitch amplitude error at measured amplitude `a` \[rad\].
    pub fn n_alpha(&self, a: f64) -> f64 {
        norm(a, self.s_alpha)
    }

    /// Divisor of a heave amplitude error at measured amplitude `h` \[m\].
    pub fn n_h(&self, h: f64) -> f64 {
        norm(h, self.s_h)
    }
}

/// Errors are relative to the measured amplitude (the records' amplitudes scatter by a
/// fraction of themselves: DECISIONS), floored at a quarter of the DOF's RMS amplitude.
fn norm(a: f64, scale: f64) -> f64 {
    a.max(0.25 * scale)
}

/// The diagram of `section` over the setting's range; `None` when it has no Hopf point
/// there or the continuation cannot start.
pub(crate) fn diagram(section: &Section, s: &Setting) -> Option<BranchSet> {
    section
        .lco_branches_within(s.range[0], s.range[1], s.reach, s.branch, &|_| {})
        .ok()
}

/// The criticality written for a linear section's Hopf point.
pub(crate) const DEGENERATE: &str = "degenerate (linear section: no limit cycle)";

/// A Hopf point of a predicted diagram.
#[derive(Debug, Clone)]
pub(crate) struct HopfAt {
    /// Speed [m/s].
    pub u: f64,
    /// Frequency \[Hz\].
    pub frequency_hz: f64,
    /// dσ/dU at the crossing [1/m] (> 0: the equilibrium loses stability with U).
    pub dsigma_du: f64,
    /// `subcritical`, `supercritical` or [`DEGENERATE`].
    pub criticality: String,
}

/// A predicted diagram: its continued branches and Hopf points (increasing U).
#[derive(Debug, Clone, Default)]
pub(crate) struct Predicted {
    /// The continued branches (`None`: no Hopf point in range or no continuation).
    pub set: Option<BranchSet>,
    /// The Hopf points.
    pub hopf: Vec<HopfAt>,
    /// A linear section (no limit cycle: its "branch" is the neutral family).
    pub linear: bool,
    /// Per point of [`Setting::points`], the orbit of its covering segment corrected by
    /// Newton at the point's own speed (pitch \[rad\], heave \[m\], frequency \[Hz\];
    /// `None`: no segment of its stability covers its speed); empty when the setting holds
    /// no points. Smooth in the section's parameters, where the interpolation between
    /// continuation points jumps as the points move.
    pub corrected: Vec<Option<(f64, f64, f64)>>,
}

impl Predicted {
    /// The predicted orbit at measured point `m` (pitch \[rad\], heave \[m\], frequency
    /// \[Hz\]): the corrected orbit when `m` is one of the setting's points, else the
    /// linear interpolation of its covering segment ([`aeroelastic::branch::predicted_at`]).
    pub fn at(&self, m: &MeasuredAmplitude, s: &Setting) -> Option<(f64, f64, f64)> {
        let set = self.set.as_ref()?;
        if !self.corrected.is_empty() {
            if let Some(k) = s.points.iter().position(|q| same_point(q, m)) {
                return self.corrected[k];
            }
        }
        aeroelastic::branch::predicted_at(set, m)
    }
}

/// Whether two measured points are the same row (speed, stability, amplitudes).
fn same_point(a: &MeasuredAmplitude, b: &MeasuredAmplitude) -> bool {
    std::ptr::eq(a, b)
        || (a.u.to_bits() == b.u.to_bits()
            && a.stable == b.stable
            && a.amplitude_alpha.map(f64::to_bits) == b.amplitude_alpha.map(f64::to_bits)
            && a.amplitude_h.map(f64::to_bits) == b.amplitude_h.map(f64::to_bits))
}

/// The orbit of `set` (continued on `section`) at measured point `m`: its covering
/// segment's ([`aeroelastic::branch::covering_segment`]) orbit corrected by Newton at
/// `m.u` ([`Section::orbit_at`]); the segment's linear interpolation when Newton fails;
/// `None` when no segment of `m`'s stability covers its speed.
fn corrected_at(
    section: &Section,
    set: &BranchSet,
    m: &MeasuredAmplitude,
    opts: &BranchOptions,
) -> Option<(f64, f64, f64)> {
    let (bi, i) = aeroelastic::branch::covering_segment(set, m)?;
    match section.orbit_at(
        &set.branches[bi],
        SensitivityAt::Speed { index: i, u: m.u },
        opts,
    ) {
        Ok(v) => Some((v.amplitude1_alpha, v.amplitude1_h, v.frequency_hz)),
        Err(_) => aeroelastic::branch::predicted_at(set, m),
    }
}

/// The diagram of `section` and its Hopf points; when the continuation gives no branches
/// and `hopf_anyway`, the Hopf points by the eigenvalue scan alone (for onset and absence
/// rows).
pub(crate) fn predict(section: Option<&Section>, s: &Setting, hopf_anyway: bool) -> Predicted {
    let Some(section) = section else {
        return Predicted::default();
    };
    let linear = section.structure.is_linear() && section.aero.is_linear();
    let set = diagram(section, s);
    let hopf = match &set {
        Some(set) => set
            .branches
            .iter()
            .map(|b| HopfAt {
                u: b.hopf.u,
                frequency_hz: b.hopf.omega / std::f64::consts::TAU,
                dsigma_du: b.hopf.dsigma_du,
                criticality: if linear {
                    DEGENERATE.into()
                } else {
                    b.criticality.clone()
                },
            })
            .collect(),
        None if hopf_anyway => hopf_scan(section, s, linear),
        None => Vec::new(),
    };
    let corrected = match &set {
        Some(set) if !linear => s
            .points
            .iter()
            .map(|m| corrected_at(section, set, m, s.branch))
            .collect(),
        _ => Vec::new(),
    };
    Predicted {
        set,
        hopf,
        linear,
        corrected,
    }
}

/// The Hopf points of `section` by the eigenvalue scan alone (criticality unknown unless
/// linear).
pub(crate) fn hopf_scan(section: &Section, s: &Setting, linear: bool) -> Vec<HopfAt> {
    section
        .hopf_points(s.range[0], s.range[1], s.branch.n_scan)
        .unwrap_or_default()
        .iter()
        .map(|h| HopfAt {
            u: h.u,
            frequency_hz: h.omega / std::f64::consts::TAU,
            dsigma_du: h.dsigma_du,
            criticality: if linear {
                DEGENERATE.into()
            } else {
                "unknown (no continued branch)".into()
            },
        })
        .collect()
}

/// The Hopf point a measured onset is compared with: the model's first (lowest-speed) one,
/// where its equilibrium first loses stability.
pub(crate) fn first_hopf(p: &Predicted) -> Option<&HopfAt> {
    p.hopf.iter().min_by(|a, b| a.u.total_cmp(&b.u))
}

/// Residuals of a measured onset against `p` (layout: speed, frequency if measured,
/// criticality if measured; module documentation).
pub(crate) fn onset_residuals(p: &Predicted, o: &MeasuredOnset, s: &Setting) -> Vec<f64> {
    let h = first_hopf(p);
    let w = s.noise;
    let sd_u = o.u_sd.unwrap_or(s.onset_sd * o.u);
    let mut r = Vec::with_capacity(3);
    r.push(match h {
        Some(h) => w * (h.u - o.u) / sd_u,
        // no Hopf point in range: as far as the range's end
        None => w * (s.range[1] - o.u).abs().max(s.range[1] - s.range[0]) / sd_u,
    });
    if let Some(f) = o.frequency_hz {
        let sd_f = o.frequency_sd_hz.unwrap_or(s.onset_sd * f);
        // no Hopf point: the speed residual carries it
        r.push(h.map_or(0.0, |h| w * (h.frequency_hz - f) / sd_f));
    }
    if let Some(c) = o.criticality {
        r.push(if h.is_some_and(|h| h.criticality == c.name()) {
            0.0
        } else {
            1.0
        });
    }
    r
}

/// What a model predicts at a speed where no LCO was observed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AbsenceFinding {
    /// The equilibrium is stable there (fewer destabilising than restabilising Hopf
    /// points below).
    pub equilibrium_stable: bool,
    /// The smallest stable cycle there: first-harmonic pitch \[rad\] and heave \[m\].
    pub lco: Option<(f64, f64)>,
    /// The unstable cycle below it (the edge of the rest state's basin), if any.
    pub threshold: Option<(f64, f64)>,
    /// The rig would have shown a cycle (or a divergence) with the perturbation tried.
    pub predicts_lco: bool,
}

/// The model's cycles at an absence row's speed ([`AbsenceFinding`]).
pub(crate) fn absence_finding(p: &Predicted, a: &MeasuredAbsence) -> AbsenceFinding {
    let crossings: f64 = p
        .hopf
        .iter()
        .filter(|h| h.u < a.u)
        .map(|h| h.dsigma_du.signum())
        .sum();
    let equilibrium_stable = crossings <= 0.0;
    let probe = |stable: bool| MeasuredAmplitude {
        line: 0,
        stable,
        u: a.u,
        amplitude_h: Some(0.0),
        amplitude_alpha: Some(0.0),
        frequency_hz: None,
    };
    let at = |stable: bool| {
        p.set
            .as_ref()
            .filter(|_| !p.linear)
            .and_then(|set| aeroelastic::branch::predicted_at(set, &probe(stable)))
            .map(|(al, h, _)| (al, h))
    };
    let lco = at(true);
    let threshold = at(false).filter(|t| lco.is_some_and(|l| t.0 < l.0));
    let predicts_lco = if !equilibrium_stable {
        true
    } else {
        match (lco, threshold) {
            (None, _) => false,
            // no basin edge below the cycle, or no perturbation stated: reached
            (Some(_), None) => true,
            (Some(_), Some(t)) => {
                if a.max_perturbation_alpha.is_none() && a.max_perturbation_h.is_none() {
                    true
                } else {
                    a.max_perturbation_alpha.is_some_and(|x| x >= t.0)
                        || a.max_perturbation_h.is_some_and(|x| x >= t.1)
                }
            }
        }
    };
    AbsenceFinding {
        equilibrium_stable,
        lco,
        threshold,
        predicts_lco,
    }
}

/// Residuals of an absence row (one per measured DOF; module documentation).
pub(crate) fn absence_residuals(f: &AbsenceFinding, s: &Setting) -> Vec<f64> {
    let mut r = Vec::with_capacity(2);
    for (k, scale) in [(0, s.s_alpha), (1, s.s_h)] {
        if !s.dofs[k] {
            continue;
        }
        r.push(match (f.predicts_lco, f.lco) {
            (false, _) => 0.0,
            (true, Some(l)) => [l.0, l.1][k] / scale,
            // unstable equilibrium without a bounded cycle: the rig would have fluttered
            (true, None) => 1.0,
        });
    }
    r
}

/// The rows a fit or a held-out score sees.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rows<'a> {
    /// Amplitude points.
    pub points: &'a [&'a MeasuredAmplitude],
    /// Measured onsets.
    pub onsets: &'a [&'a MeasuredOnset],
    /// Speeds where no LCO was observed.
    pub absences: &'a [&'a MeasuredAbsence],
}

impl Rows<'_> {
    /// Whether the rows hold an onset or an absence (the Hopf points are needed).
    pub fn need_hopf(&self) -> bool {
        !self.onsets.is_empty() || !self.absences.is_empty()
    }
}

/// Every residual of `rows` against `p`: the points' ([`residuals`]), then the onsets',
/// then the absences'.
pub(crate) fn all_residuals(p: &Predicted, rows: &Rows, s: &Setting) -> Vec<f64> {
    let mut r = residuals(p, rows.points, s);
    for o in rows.onsets {
        r.extend(onset_residuals(p, o, s));
    }
    for a in rows.absences {
        r.extend(absence_residuals(&absence_finding(p, a), s));
    }
    r
}

/// Residuals of the measured points `pts` against the prediction `p` (a covered point's
/// orbit from [`Predicted::at`]; layout per point: pitch if measured, heave if measured,
/// frequency if measured, speed).
pub(crate) fn residuals(p: &Predicted, pts: &[&MeasuredAmplitude], s: &Setting) -> Vec<f64> {
    let set = p.set.as_ref();
    let mut r = Vec::with_capacity(3 * pts.len());
    for m in pts {
        let covered = p.at(m, s);
        let (pa, ph, pf, du) = match covered {
            Some((a, h, f)) => (a, h, f, 0.0),
            None => {
                // nearest orbit of the same stability in the scaled plane
                match set
                    .and_then(|set| nearest(set, m, s).map(|(bi, i)| &set.branches[bi].points[i]))
                {
                    Some(p) => (
                        p.amplitude1_alpha,
                        p.amplitude1_h,
                        p.omega / std::f64::consts::TAU,
                        p.u - m.u,
                    ),
                    // no orbit of this stability at all: predicted 0 at the far end of the
                    // range
                    None => (0.0, 0.0, f64::NAN, s.range[1] - s.range[0]),
                }
            }
        };
        if let Some(a) = m.amplitude_alpha {
            r.push((pa - a) / s.n_alpha(a));
        }
        if let Some(h) = m.amplitude_h {
            r.push((ph - h) / s.n_h(h));
        }
        if let Some(f) = m.frequency_hz {
            // relative, as the amplitudes; no orbit at all: the speed residual carries it
            r.push(if pf.is_finite() { (pf - f) / f } else { 0.0 });
        }
        r.push(du / s.s_u);
    }
    r
}

fn cost(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// The branch point [`residuals`] takes for an uncovered measured point: the nearest orbit
/// of the same stability in the scaled (U, amplitude) plane (the first on a tie).
pub(crate) fn nearest(
    set: &BranchSet,
    m: &MeasuredAmplitude,
    s: &Setting,
) -> Option<(usize, usize)> {
    let mut best: Option<(f64, (usize, usize))> = None;
    for (bi, b) in set.branches.iter().enumerate() {
        for (i, p) in b.points.iter().enumerate() {
            if p.stable != m.stable {
                continue;
            }
            let mut d = ((p.u - m.u) / s.s_u).powi(2);
            if let Some(a) = m.amplitude_alpha {
                d += ((p.amplitude1_alpha - a) / s.n_alpha(a)).powi(2);
            }
            if let Some(h) = m.amplitude_h {
                d += ((p.amplitude1_h - h) / s.n_h(h)).powi(2);
            }
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, (bi, i)));
            }
        }
    }
    best.map(|b| b.1)
}

/// Step in θ of the perturbed sections whose residual G(Y; θ + h) gives ∂G/∂θ (G is linear
/// in every stiffness and damping coefficient, so the step only has to stay above
/// rounding).
const SENSITIVITY_STEP: f64 = 1e-3;

/// The Jacobian ∂r/∂θ of [`all_residuals`] of `rows` at `theta`, whose prediction is `p`,
/// from orbit sensitivities ([`Section::orbit_sensitivity`]: dY/dθ = −[G_Y; c]⁻¹[G_θ; 0] at
/// each measured point's orbit, no continuation of a perturbed section), row for row in
/// the layout of [`all_residuals`]:
///
/// - a point its branch covers: the orbit at the measured speed (U fixed), d(pred)/dθ over
///   the residual's divisor, 0 for the speed residual;
/// - an uncovered point: the nearest orbit at its own pitch-amplitude unknown (U free),
///   so that the speed residual carries dU/dθ (how a fold moves);
/// - a point no orbit of its stability approaches, a criticality: 0 (piecewise constant);
/// - an onset's speed and frequency: a forward difference of the first Hopf point of the
///   perturbed sections (an eigenvalue scan, no continuation);
/// - an absence row: the derivative of the stable cycle it counts, 0 when none counts.
///
/// `section_at` builds the candidate's section at θ. `None` (the caller then takes forward
/// differences of whole diagrams) for a linear section (its neutral family is no
/// diagram), a section that cannot be built, or a sensitivity that fails.
pub(crate) fn residual_jacobian(
    section_at: &dyn Fn(&[f64]) -> Option<Section>,
    theta: &[f64],
    p: &Predicted,
    rows: &Rows,
    s: &Setting,
) -> Option<DMatrix<f64>> {
    if p.linear {
        return None;
    }
    let n = theta.len();
    let base = section_at(theta)?;
    let perturbed: Vec<(Section, f64)> = (0..n)
        .map(|k| {
            let mut t = theta.to_vec();
            t[k] += SENSITIVITY_STEP;
            section_at(&t).map(|sec| (sec, SENSITIVITY_STEP))
        })
        .collect::<Option<_>>()?;
    let sens = |bi: usize, at: SensitivityAt| -> Option<Vec<OrbitValues>> {
        let set = p.set.as_ref()?;
        base.orbit_sensitivity(&set.branches[bi], at, &perturbed, s.branch)
            .ok()
            .map(|o| o.derivatives)
    };
    let mut rows_out: Vec<Vec<f64>> = Vec::new();
    for m in rows.points {
        let d: Option<(Vec<OrbitValues>, bool)> = match p.set.as_ref() {
            None => None,
            Some(set) => match aeroelastic::branch::covering_segment(set, m) {
                Some((bi, i)) => {
                    Some((sens(bi, SensitivityAt::Speed { index: i, u: m.u })?, false))
                }
                None => match nearest(set, m, s) {
                    Some((bi, i)) => Some((sens(bi, SensitivityAt::Amplitude { index: i })?, true)),
                    None => None,
                },
            },
        };
        let zero = vec![OrbitValues::default(); n];
        let (d, speed) = d.unwrap_or((zero, false));
        if let Some(a) = m.amplitude_alpha {
            rows_out.push(
                d.iter()
                    .map(|v| v.amplitude1_alpha / s.n_alpha(a))
                    .collect(),
            );
        }
        if let Some(h) = m.amplitude_h {
            rows_out.push(d.iter().map(|v| v.amplitude1_h / s.n_h(h)).collect());
        }
        if let Some(f) = m.frequency_hz {
            rows_out.push(d.iter().map(|v| v.frequency_hz / f).collect());
        }
        rows_out.push(
            d.iter()
                .map(|v| if speed { v.u / s.s_u } else { 0.0 })
                .collect(),
        );
    }
    if !rows.onsets.is_empty() {
        let h0 = first_hopf(p).cloned();
        let dh: Vec<Option<(f64, f64)>> = perturbed
            .iter()
            .map(|(sec, d)| {
                let h0 = h0.as_ref()?;
                let h = hopf_scan(sec, s, false)
                    .into_iter()
                    .min_by(|a, b| a.u.total_cmp(&b.u))?;
                Some(((h.u - h0.u) / d, (h.frequency_hz - h0.frequency_hz) / d))
            })
            .collect();
        for o in rows.onsets {
            let w = s.noise;
            let sd_u = o.u_sd.unwrap_or(s.onset_sd * o.u);
            rows_out.push(
                dh.iter()
                    .map(|d| d.map_or(0.0, |d| w * d.0 / sd_u))
                    .collect(),
            );
            if let Some(f) = o.frequency_hz {
                let sd_f = o.frequency_sd_hz.unwrap_or(s.onset_sd * f);
                rows_out.push(
                    dh.iter()
                        .map(|d| d.map_or(0.0, |d| w * d.1 / sd_f))
                        .collect(),
                );
            }
            if o.criticality.is_some() {
                rows_out.push(vec![0.0; n]);
            }
        }
    }
    for a in rows.absences {
        let f = absence_finding(p, a);
        let counted = f.predicts_lco && f.lco.is_some();
        let d = match (counted, p.set.as_ref()) {
            (true, Some(set)) => {
                let probe = MeasuredAmplitude {
                    line: 0,
                    stable: true,
                    u: a.u,
                    amplitude_h: Some(0.0),
                    amplitude_alpha: Some(0.0),
                    frequency_hz: None,
                };
                match aeroelastic::branch::covering_segment(set, &probe) {
                    Some((bi, i)) => sens(bi, SensitivityAt::Speed { index: i, u: a.u })?,
                    None => vec![OrbitValues::default(); n],
                }
            }
            _ => vec![OrbitValues::default(); n],
        };
        for (k, scale) in [(0, s.s_alpha), (1, s.s_h)] {
            if !s.dofs[k] {
                continue;
            }
            rows_out.push(
                d.iter()
                    .map(|v| [v.amplitude1_alpha, v.amplitude1_h][k] / scale)
                    .collect(),
            );
        }
    }
    let m = rows_out.len();
    let j = DMatrix::from_fn(m, n, |i, k| rows_out[i][k]);
    j.iter().all(|v| v.is_finite()).then_some(j)
}

/// ∂r/∂θ at θ from its prediction (`None`: not available there).
pub(crate) type JacobianFn<'a> = dyn Fn(&[f64], &Predicted) -> Option<DMatrix<f64>> + 'a;

/// What a least-squares fit minimises: the prediction at θ (one diagram), the residuals of
/// a prediction, and optionally their Jacobian from the prediction's sensitivities
/// ([`residual_jacobian`]; `None` from it, or no function: forward differences of whole
/// predictions, step 1e-2 in θ).
pub(crate) struct Objective<'a> {
    /// The prediction at θ.
    pub predict: &'a dyn Fn(&[f64]) -> Predicted,
    /// Its residuals.
    pub residuals: &'a dyn Fn(&Predicted) -> Vec<f64>,
    /// ∂r/∂θ at θ from its prediction.
    pub jacobian: Option<&'a JacobianFn<'a>>,
}

/// Result of one fit.
#[derive(Debug, Clone)]
pub(crate) struct FitResult {
    /// Scaled parameters.
    pub theta: Vec<f64>,
    /// Sum of squared residuals at `theta`.
    pub cost: f64,
    /// The prediction at `theta`.
    pub predicted: Predicted,
    /// The damping λ the fit ended with (a next stage goes on from it).
    pub lambda: f64,
    /// Whether the stop rule ended the fit (no lower cost, a gain ≤ 1e-6, or no slope);
    /// `false` when the iteration budget ran out first.
    pub stopped: bool,
}

/// The damping λ a fit starts with.
pub(crate) const INITIAL_DAMPING: f64 = 1e-2;

/// Levenberg–Marquardt on `obj` from `x0` (whose prediction `p0` may be at hand) with
/// damping `lambda` ([`INITIAL_DAMPING`] for a new fit; a fit cut into stages goes on with
/// the [`FitResult::lambda`] of the last and ends where one run of the summed budget ends,
/// bit for bit), at most `max_iter` iterations. Each iteration takes the objective's
/// Jacobian from sensitivities when it gives one, forward differences (step 1e-2 in θ)
/// otherwise, and tries up to eight damped steps (λ × 4 after each that does not lower the
/// cost); the fit stops when an iteration finds no lower cost or gains at most 1e-6 of it,
/// or the slope is zero.
pub(crate) fn levenberg_marquardt(
    obj: &Objective,
    x0: &[f64],
    p0: Option<Predicted>,
    mut lambda: f64,
    max_iter: usize,
) -> FitResult {
    let n = x0.len();
    let mut x = x0.to_vec();
    let mut p = p0.unwrap_or_else(|| (obj.predict)(&x));
    let mut r = (obj.residuals)(&p);
    let mut c = cost(&r);
    let mut stopped = false;
    let h = 1e-2;
    let differences = |x: &[f64], r: &[f64]| {
        let m = r.len();
        let mut j = DMatrix::<f64>::zeros(m, n);
        for k in 0..n {
            let mut xp = x.to_vec();
            xp[k] += h;
            let rp = (obj.residuals)(&(obj.predict)(&xp));
            for i in 0..m {
                j[(i, k)] = (rp[i] - r[i]) / h;
            }
        }
        j
    };
    let mut iter = 0;
    while iter < max_iter {
        let analytic = obj
            .jacobian
            .and_then(|jf| jf(&x, &p))
            .filter(|j| j.nrows() == r.len() && j.ncols() == n);
        let j = analytic.unwrap_or_else(|| differences(&x, &r));
        let rv = DVector::from_column_slice(&r);
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &rv;
        if g.iter().all(|v| *v == 0.0) {
            // no slope: every step is zero and gives the same prediction, so no trial can
            // lower the cost (the fit ends where the eight trials would have left it)
            stopped = true;
            break;
        }
        let mut gain = None;
        for _ in 0..8 {
            let mut a = jtj.clone();
            for k in 0..n {
                a[(k, k)] += lambda * (jtj[(k, k)].max(1e-9));
            }
            let Some(step) = a.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let xn: Vec<f64> = x.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            let pn = (obj.predict)(&xn);
            let rn = (obj.residuals)(&pn);
            let cn = cost(&rn);
            if cn.is_finite() && cn < c {
                gain = Some((c - cn) / c.max(1e-300));
                x = xn;
                p = pn;
                r = rn;
                c = cn;
                lambda = (lambda / 3.0).max(1e-7);
                break;
            }
            lambda *= 4.0;
        }
        iter += 1;
        if gain.is_none_or(|g| g <= 1e-6) {
            stopped = true;
            break;
        }
    }
    FitResult {
        theta: x,
        cost: c,
        predicted: p,
        lambda,
        stopped,
    }
}

/// Start points of a fit with `n` scaled parameters: every combination of a few values
/// per parameter, log-spaced over two decades for one or two parameters (θ = 1 is a change
/// of the order of the linear term at the largest measured amplitude, but a truth may sit
/// ten times above or below), fewer beyond; the origin excluded.
pub(crate) fn start_grid(n: usize) -> Vec<Vec<f64>> {
    let values: &[f64] = match n {
        0 | 1 => &[
            -20.0, -10.0, -5.0, -2.0, -1.0, -0.5, -0.2, -0.1, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0,
            20.0,
        ],
        2 => &[-10.0, -3.0, -1.0, -0.3, 0.3, 1.0, 3.0, 10.0],
        3 => &[-3.0, -1.0, 0.0, 1.0, 3.0],
        _ => &[-1.0, 0.0, 1.0],
    };
    let mut out: Vec<Vec<f64>> = vec![vec![]];
    for _ in 0..n {
        out = out
            .into_iter()
            .flat_map(|v| {
                values.iter().map(move |x| {
                    let mut w = v.clone();
                    w.push(*x);
                    w
                })
            })
            .collect();
    }
    out.retain(|v| v.iter().any(|x| *x != 0.0));
    out
}

/// The setting of the unit tests: range 10–30 m/s, pitch scale 0.05 rad, heave 0.015 m,
/// speed 0.3 m/s, pitch measured only, no points (the difference fits' objective).
#[cfg(test)]
pub(crate) fn test_setting(opts: &BranchOptions) -> Setting<'_> {
    Setting {
        branch: opts,
        range: [10.0, 30.0],
        s_alpha: 0.05,
        s_h: 0.015,
        s_u: 0.3,
        noise: 0.05,
        onset_sd: 0.01,
        dofs: [true, false],
        row_speeds: [f64::INFINITY, f64::NEG_INFINITY],
        points: &[],
        reach: f64::INFINITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroelastic::branch::{Branch, BranchEnd, BranchPoint, Criticality, HopfPoint};

    fn point(u: f64, a: f64, stable: bool) -> BranchPoint {
        BranchPoint {
            u,
            period: 0.4,
            omega: std::f64::consts::TAU * 2.5,
            amplitude_alpha: a,
            amplitude_h: 0.3 * a,
            amplitude1_alpha: a,
            amplitude1_h: 0.3 * a,
            max_floquet: 1.0,
            stable,
            multipliers: Vec::new(),
            state: Vec::new(),
            unknowns: Vec::new(),
        }
    }

    /// A subcritical diagram: Hopf at 18 m/s (2.5 Hz), the unstable branch down to a fold
    /// at 15 m/s (0.03 rad), the stable branch from there up to 17.5 m/s.
    fn subcritical(opts: &BranchOptions) -> Predicted {
        let hopf = HopfPoint {
            u: 18.0,
            omega: std::f64::consts::TAU * 2.5,
            dsigma_du: 0.1,
            eigenvector: Vec::new(),
        };
        let points = vec![
            point(18.0, 0.0, false),
            point(16.5, 0.015, false),
            point(15.0, 0.03, false),
            point(15.0, 0.03, true),
            point(16.5, 0.06, true),
            point(17.5, 0.08, true),
        ];
        let set = BranchSet {
            hopf_points: vec![hopf.clone()],
            branches: vec![Branch {
                hopf,
                points,
                events: Vec::new(),
                stop: BranchEnd::MaxPoints,
                criticality: "subcritical".into(),
                scales: Vec::new(),
            }],
            options: *opts,
            u_range: [10.0, 30.0],
        };
        Predicted {
            hopf: vec![HopfAt {
                u: 18.0,
                frequency_hz: 2.5,
                dsigma_du: 0.1,
                criticality: "subcritical".into(),
            }],
            set: Some(set),
            linear: false,
            corrected: Vec::new(),
        }
    }

    fn setting(opts: &BranchOptions) -> Setting<'_> {
        test_setting(opts)
    }

    /// An onset row: one stated uncertainty of speed or frequency costs the amplitude
    /// uncertainty; a wrong criticality costs 1; no Hopf point at all costs more than any
    /// Hopf point in range.
    #[test]
    fn onset_residuals_weigh_speed_frequency_and_criticality() {
        let opts = BranchOptions::default();
        let s = setting(&opts);
        let p = subcritical(&opts);
        let mut o = MeasuredOnset {
            line: 0,
            u: 18.0 / 0.99,
            u_sd: None,
            frequency_hz: Some(2.5 / 1.01),
            frequency_sd_hz: None,
            criticality: Some(Criticality::Subcritical),
        };
        let z = onset_residuals(&p, &o, &s);
        assert_eq!(z.len(), 3);
        // (18 − 18/0.99) / (0.01 · 18/0.99) = −1 standard uncertainty
        assert!((z[0] + 0.05).abs() < 1e-9, "{z:?}");
        assert!((z[1] - 0.05).abs() < 1e-9, "{z:?}");
        assert_eq!(z[2], 0.0);
        o.criticality = Some(Criticality::Supercritical);
        o.u_sd = Some(18.0 / 0.99 * 0.005);
        let z = onset_residuals(&p, &o, &s);
        assert!((z[0] + 0.1).abs() < 1e-9, "a stated uncertainty: {z:?}");
        assert_eq!(z[2], 1.0, "wrong criticality");
        let none = Predicted::default();
        let z = onset_residuals(&none, &o, &s);
        assert!(z[0] > 10.0 && z[1] == 0.0 && z[2] == 1.0, "{z:?}");
    }

    /// An absence row: a stable cycle coexisting with a stable equilibrium is reached when
    /// the perturbation tried exceeds the unstable cycle below it (or none is stated);
    /// above the Hopf point the equilibrium is unstable; below the fold nothing is
    /// predicted.
    #[test]
    fn absence_rows_see_reachable_cycles_only() {
        let opts = BranchOptions::default();
        let s = setting(&opts);
        let p = subcritical(&opts);
        let row = |u: f64, pa: Option<f64>| MeasuredAbsence {
            line: 0,
            u,
            max_perturbation_alpha: pa,
            max_perturbation_h: None,
        };
        let f = absence_finding(&p, &row(16.5, None));
        assert!(f.equilibrium_stable && f.predicts_lco, "{f:?}");
        assert!((f.lco.unwrap().0 - 0.06).abs() < 1e-12);
        assert!((f.threshold.unwrap().0 - 0.015).abs() < 1e-12);
        assert_eq!(absence_residuals(&f, &s), vec![0.06 / 0.05]);
        // kicked to 0.01 rad only: below the unstable cycle, no contradiction
        let f = absence_finding(&p, &row(16.5, Some(0.01)));
        assert!(!f.predicts_lco);
        assert_eq!(absence_residuals(&f, &s), vec![0.0]);
        assert!(absence_finding(&p, &row(16.5, Some(0.02))).predicts_lco);
        // below the fold
        let f = absence_finding(&p, &row(14.0, None));
        assert!(f.equilibrium_stable && !f.predicts_lco && f.lco.is_none());
        // above the Hopf point: flutter without a bounded cycle in the diagram
        let f = absence_finding(&p, &row(19.0, Some(0.001)));
        assert!(!f.equilibrium_stable && f.predicts_lco && f.lco.is_none());
        assert_eq!(absence_residuals(&f, &s), vec![1.0]);
        // a linear section has no cycle: only its equilibrium counts
        let lin = Predicted {
            linear: true,
            ..subcritical(&opts)
        };
        assert!(!absence_finding(&lin, &row(16.5, None)).predicts_lco);
        assert!(absence_finding(&lin, &row(18.5, None)).predicts_lco);
    }
}
