//! Continuation of periodic orbits in a parameter other than the wind speed (issue 40
//! item 5; the idea of BifurcationKit's `@optic` lens): at a fixed U, the orbit of a
//! section is followed while one named parameter of the section moves — a stiffness, a
//! damping, a polynomial coefficient of the structure, the air density — with the same
//! discretisations, Newton corrector, pseudo-arclength steps, folds and Floquet
//! multipliers as the continuation in U.
//!
//! A [`Lens`] reads a parameter of a [`Section`] and builds the section with another value
//! of it. [`SectionParameter`] is the lens of every scalar of the section a user or a
//! candidate of the diagnosis fits; a caller may write its own (a candidate's parameter
//! that maps onto several fields) by implementing the trait.
//!
//! Method: the unknowns of the problem of [`BranchOptions::method`] keep their meaning
//! except the last, which is the parameter p (scaled) instead of U; every evaluation of the
//! residual builds the section at p and evaluates the U-problem at the fixed U. The column
//! ∂G/∂p of the Jacobian is a forward difference in p (the other columns are the method's
//! own). Folds are turning points in p; stability changes as in U.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::continuation::{branch_scales, crossing, newton, parabola_vertex, problem, tangent};
use super::options::BranchOptions;
use super::periodic::{Closure, PeriodicProblem};
use super::types::{BranchPoint, BranchSet, EventKind, HopfPoint};
use crate::section::Section;
use crate::structure::PolyTerm;
use crate::{Error, Result};

/// A scalar parameter of a [`Section`] that continuation may move.
pub trait Lens: Send + Sync {
    /// Dotted name of the parameter (`structure.k_alpha`, `rho`…), as the outputs write it.
    fn name(&self) -> String;
    /// Unit of the parameter's value (SI, per metre of span), e.g. `N m/rad`.
    fn unit(&self) -> String;
    /// The parameter's value in `section`, in its own unit.
    fn get(&self, section: &Section) -> f64;
    /// `section` with the parameter set to `value`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when the section is not valid with that value (a
    /// negative stiffness, a zero density).
    fn set(&self, section: &Section, value: f64) -> Result<Section>;
}

/// The scalars of a section a lens can name (units of [`crate::structure::Structure`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SectionParameter {
    /// Heave stiffness k_h [N/m per m span].
    KH,
    /// Pitch stiffness k_α [N·m/rad per m span].
    KAlpha,
    /// Heave viscous damping c_h [N·s/m per m span].
    CH,
    /// Pitch viscous damping c_α [N·m·s/rad per m span].
    CAlpha,
    /// Air density ρ [kg/m³] (scales every aerodynamic force at a fixed U).
    Rho,
    /// Coefficient of h^p of the heave stiffness polynomial [N/m^p per m span].
    HeaveStiffness(u32),
    /// Coefficient of α^p of the pitch stiffness polynomial [N·m/rad^p per m span].
    PitchStiffness(u32),
    /// Coefficient c_p of the heave damping term c_p h^p ḣ [N s/m^(p+1) per m span].
    HeaveDamping(u32),
    /// Coefficient c_p of the pitch damping term c_p α^p α̇ [N m s/rad^(p+1) per m span].
    PitchDamping(u32),
}

impl SectionParameter {
    /// The names [`SectionParameter::parse`] accepts (`P` a power: 2 … 15 for a
    /// stiffness, 1 … 15 for a damping term).
    pub const NAMES: [&'static str; 9] = [
        "k_h",
        "k_alpha",
        "c_h",
        "c_alpha",
        "rho",
        "heave_stiffness[P]",
        "pitch_stiffness[P]",
        "heave_damping[P]",
        "pitch_damping[P]",
    ];

    /// Parses a name of [`SectionParameter::NAMES`] (`structure.` prefix optional).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `parameter` for an unknown name or a power out of
    /// its range.
    pub fn parse(name: &str) -> Result<Self> {
        let bad = |why: String| Error::param("parameter", f64::NAN, why);
        let n = name.trim();
        let n = n.strip_prefix("structure.").unwrap_or(n);
        let simple = match n {
            "k_h" => Some(SectionParameter::KH),
            "k_alpha" => Some(SectionParameter::KAlpha),
            "c_h" => Some(SectionParameter::CH),
            "c_alpha" => Some(SectionParameter::CAlpha),
            "rho" => Some(SectionParameter::Rho),
            _ => None,
        };
        if let Some(p) = simple {
            return Ok(p);
        }
        let (head, rest) = n.split_once('[').ok_or_else(|| {
            bad(format!(
                "`{name}`: expected one of {}",
                Self::NAMES.join(", ")
            ))
        })?;
        let lowest = if head.ends_with("damping") { 1 } else { 2 };
        let power: u32 = rest
            .strip_suffix(']')
            .and_then(|p| p.trim().parse().ok())
            .filter(|p| (lowest..=15).contains(p))
            .ok_or_else(|| bad(format!("`{name}`: the power in [P] must be {lowest} … 15")))?;
        match head {
            "heave_stiffness" => Ok(SectionParameter::HeaveStiffness(power)),
            "pitch_stiffness" => Ok(SectionParameter::PitchStiffness(power)),
            "heave_damping" => Ok(SectionParameter::HeaveDamping(power)),
            "pitch_damping" => Ok(SectionParameter::PitchDamping(power)),
            _ => Err(bad(format!(
                "`{name}`: expected one of {}",
                Self::NAMES.join(", ")
            ))),
        }
    }

    fn terms(self, section: &Section) -> Option<(&Vec<PolyTerm>, u32)> {
        let nl = &section.structure.nonlinear;
        match self {
            SectionParameter::HeaveStiffness(p) => Some((&nl.heave_stiffness_terms, p)),
            SectionParameter::PitchStiffness(p) => Some((&nl.pitch_stiffness_terms, p)),
            SectionParameter::HeaveDamping(p) => Some((&nl.heave_damping_terms, p)),
            SectionParameter::PitchDamping(p) => Some((&nl.pitch_damping_terms, p)),
            _ => None,
        }
    }
}

impl Lens for SectionParameter {
    fn name(&self) -> String {
        match self {
            SectionParameter::KH => "structure.k_h".into(),
            SectionParameter::KAlpha => "structure.k_alpha".into(),
            SectionParameter::CH => "structure.c_h".into(),
            SectionParameter::CAlpha => "structure.c_alpha".into(),
            SectionParameter::Rho => "rho".into(),
            SectionParameter::HeaveStiffness(p) => format!("structure.heave_stiffness[{p}]"),
            SectionParameter::PitchStiffness(p) => format!("structure.pitch_stiffness[{p}]"),
            SectionParameter::HeaveDamping(p) => format!("structure.heave_damping[{p}]"),
            SectionParameter::PitchDamping(p) => format!("structure.pitch_damping[{p}]"),
        }
    }

    fn unit(&self) -> String {
        match self {
            SectionParameter::KH => "N/m".into(),
            SectionParameter::KAlpha => "N m/rad".into(),
            SectionParameter::CH => "N s/m".into(),
            SectionParameter::CAlpha => "N m s/rad".into(),
            SectionParameter::Rho => "kg/m^3".into(),
            SectionParameter::HeaveStiffness(p) => format!("N/m^{p}"),
            SectionParameter::PitchStiffness(p) => format!("N m/rad^{p}"),
            SectionParameter::HeaveDamping(p) => format!("N s/m^{}", p + 1),
            SectionParameter::PitchDamping(p) => format!("N m s/rad^{}", p + 1),
        }
    }

    fn get(&self, s: &Section) -> f64 {
        let st = &s.structure;
        match self {
            SectionParameter::KH => st.k_h,
            SectionParameter::KAlpha => st.k_alpha,
            SectionParameter::CH => st.c_h,
            SectionParameter::CAlpha => st.c_alpha,
            SectionParameter::Rho => s.rho,
            _ => self
                .terms(s)
                .map(|(t, p)| {
                    t.iter()
                        .filter(|t| t.power == p)
                        .map(|t| t.coefficient)
                        .sum()
                })
                .unwrap_or(0.0),
        }
    }

    fn set(&self, s: &Section, value: f64) -> Result<Section> {
        let mut st = s.structure.clone();
        let mut rho = s.rho;
        let set_term = |terms: &mut Vec<PolyTerm>, power: u32| {
            terms.retain(|t| t.power != power);
            terms.push(PolyTerm {
                power,
                coefficient: value,
            });
        };
        let nl = &mut st.nonlinear;
        match *self {
            SectionParameter::KH => st.k_h = value,
            SectionParameter::KAlpha => st.k_alpha = value,
            SectionParameter::CH => st.c_h = value,
            SectionParameter::CAlpha => st.c_alpha = value,
            SectionParameter::Rho => rho = value,
            SectionParameter::HeaveStiffness(p) => set_term(&mut nl.heave_stiffness_terms, p),
            SectionParameter::PitchStiffness(p) => set_term(&mut nl.pitch_stiffness_terms, p),
            SectionParameter::HeaveDamping(p) => set_term(&mut nl.heave_damping_terms, p),
            SectionParameter::PitchDamping(p) => set_term(&mut nl.pitch_damping_terms, p),
        }
        Section::new(st, s.aero.clone(), rho)
    }
}

/// A point of a branch continued in a parameter: the parameter's value and the orbit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LensPoint {
    /// The parameter's value (its own unit).
    pub value: f64,
    /// The orbit at that value (its `u` is the branch's fixed speed).
    pub orbit: BranchPoint,
}

/// A fold or a change of stability between two points of a parameter branch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LensEvent {
    /// Fold (turning point in the parameter), period doubling, Neimark–Sacker or branch
    /// point.
    pub kind: EventKind,
    /// The parameter's value there (a fold's from the parabola through three points).
    pub value: f64,
    /// Pitch amplitude there \[rad\].
    pub amplitude_alpha: f64,
    /// Index of the first point after the event in [`LensBranch::points`].
    pub index: usize,
}

/// Why one direction of a parameter branch ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum LensEnd {
    /// The parameter left the requested range.
    Range {
        /// Value of the first point outside.
        value: f64,
    },
    /// The pitch amplitude exceeded `max_amplitude_alpha`.
    Amplitude {
        /// Amplitude reached \[rad\].
        amplitude_alpha: f64,
    },
    /// The orbit shrank to the equilibrium (a Hopf point in the parameter).
    Equilibrium {
        /// Value of the parameter there.
        value: f64,
    },
    /// `max_points` reached.
    MaxPoints,
    /// Newton did not converge even with the smallest step.
    NotConverged {
        /// Value of the last converged point.
        value: f64,
        /// What failed.
        message: String,
    },
}

/// The periodic orbits of a section at a fixed speed, continued in one parameter through
/// a given orbit, in both directions; points in arclength order, from the end of the
/// direction that first decreased the parameter (past a fold the parameter turns back).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LensBranch {
    /// [`Lens::name`] of the parameter.
    pub parameter: String,
    /// [`Lens::unit`] of its values.
    pub unit: String,
    /// The fixed wind speed [m/s].
    pub u: f64,
    /// The parameter's value of the section the orbit came from.
    pub start_value: f64,
    /// Index of the start orbit in `points`.
    pub start_index: usize,
    /// The points: the decreasing direction's last point first, the start orbit, the
    /// increasing direction's last point last.
    pub points: Vec<LensPoint>,
    /// Folds and stability changes, indices into `points`.
    pub events: Vec<LensEvent>,
    /// Why the decreasing and the increasing directions ended.
    pub stops: [LensEnd; 2],
}

/// The problem of one method at a fixed U, its last unknown the parameter p (scaled).
struct LensProblem<'a> {
    section: &'a Section,
    lens: &'a dyn Lens,
    opts: BranchOptions,
    hopf: &'a HopfPoint,
    /// The method's own scales (state, T, U).
    inner_scales: Vec<f64>,
    /// The same with p's scale last.
    scales: Vec<f64>,
    /// U scaled by the method's U scale.
    u_scaled: f64,
    m: usize,
    amplitude_index: usize,
    at_solution: bool,
}

impl LensProblem<'_> {
    fn value(&self, y: &DVector<f64>) -> f64 {
        y[self.m - 1] * self.scales[self.m - 1]
    }

    /// The section at y's p and y with U in place of p.
    fn at(&self, y: &DVector<f64>) -> Result<(Section, DVector<f64>)> {
        let s = self.lens.set(self.section, self.value(y))?;
        let mut z = y.clone();
        z[self.m - 1] = self.u_scaled;
        Ok((s, z))
    }
}

impl PeriodicProblem for LensProblem<'_> {
    fn unknowns(&self) -> usize {
        self.m
    }

    fn amplitude_index(&self) -> usize {
        self.amplitude_index
    }

    fn scales(&self) -> &[f64] {
        &self.scales
    }

    fn g(&self, y: &DVector<f64>) -> Result<DVector<f64>> {
        let (s, z) = self.at(y)?;
        let g = problem(&s, &self.opts, &self.inner_scales, self.hopf).g(&z);
        g
    }

    fn jac(&self, y: &DVector<f64>, g0: &DVector<f64>) -> Result<DMatrix<f64>> {
        let (s, z) = self.at(y)?;
        let mut j = problem(&s, &self.opts, &self.inner_scales, self.hopf).jac(&z, g0)?;
        let c = self.m - 1;
        let d = 1e-7 * (1.0 + y[c].abs());
        let mut yp = y.clone();
        yp[c] += d;
        let gp = self.g(&yp)?;
        j.set_column(c, &((gp - g0) / d));
        Ok(j)
    }

    fn point(&self, y: &DVector<f64>, jg: &DMatrix<f64>) -> Result<BranchPoint> {
        let (s, z) = self.at(y)?;
        let point = problem(&s, &self.opts, &self.inner_scales, self.hopf).point(&z, jg);
        point
    }

    fn jacobian_at_solution(&self) -> bool {
        self.at_solution
    }

    fn start(&self, hopf: &HopfPoint, a: f64) -> DVector<f64> {
        let mut y = problem(self.section, &self.opts, &self.inner_scales, self.hopf).start(hopf, a);
        y[self.m - 1] = self.lens.get(self.section) / self.scales[self.m - 1];
        y
    }

    /// The point's unknowns with the parameter of the lens's section (the value a point
    /// does not carry).
    fn scaled(&self, p: &BranchPoint) -> Result<DVector<f64>> {
        let mut y = problem(self.section, &self.opts, &self.inner_scales, self.hopf).scaled(p)?;
        y[self.m - 1] = self.lens.get(self.section) / self.scales[self.m - 1];
        Ok(y)
    }
}

impl Section {
    /// Continues the periodic orbit `start` of this section (a point of a branch in U from
    /// `hopf`, e.g. [`Section::orbit_on_branch`]) at its speed U in the parameter of `lens`,
    /// within `range` = [p_min, p_max] (which holds the section's own value), both ways.
    ///
    /// The parameter's scale is a tenth of the larger of |p₀| and the range's width.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for bad options, a non-smooth structure
    /// ([`Section::check_smooth`]), a range that is empty, not finite or does not hold the
    /// section's value (field `range`); [`Error::Numerical`] when the start orbit does
    /// not converge at its own parameter value. A direction that stops converging later
    /// ends with [`LensEnd::NotConverged`] and keeps its points.
    pub fn continue_in(
        &self,
        lens: &dyn Lens,
        hopf: &HopfPoint,
        start: &BranchPoint,
        range: [f64; 2],
        opts: &BranchOptions,
    ) -> Result<LensBranch> {
        opts.check()?;
        self.check_smooth()?;
        let p0 = lens.get(self);
        let [lo, hi] = range;
        if !(lo.is_finite() && hi.is_finite() && lo < hi && lo <= p0 && p0 <= hi) {
            return Err(Error::param(
                "range",
                lo,
                format!(
                    "[{lo}, {hi}] must be finite, increasing and hold the section's {} = {p0}",
                    lens.name()
                ),
            ));
        }
        let inner_scales = branch_scales(hopf, opts.amplitude_scale);
        let mut scales = inner_scales.clone();
        let m = scales.len();
        scales[m - 1] = 0.1 * p0.abs().max(hi - lo);
        let inner = problem(self, opts, &inner_scales, hopf);
        let pr = LensProblem {
            section: self,
            lens,
            opts: *opts,
            hopf,
            inner_scales: inner_scales.clone(),
            scales,
            u_scaled: start.u / inner_scales[m - 1],
            m,
            amplitude_index: inner.amplitude_index(),
            at_solution: inner.jacobian_at_solution(),
        };
        let y = pr.scaled(start)?;
        let c = Closure::Speed(y[m - 1]);
        let (y0, j0, _, _) = newton(&pr, y, &c, None, opts.newton_tol, 3 * opts.max_newton)
            .map_err(|e| {
                Error::numerical(
                    "continue_in",
                    format!(
                        "the start orbit (U = {:.6} m/s, pitch amplitude {:.4e} rad) did not \
                         converge at {} = {p0}: {e}",
                        start.u,
                        start.amplitude_alpha,
                        lens.name()
                    ),
                )
            })?;
        let first = LensPoint {
            value: p0,
            orbit: pr.point(&y0, &j0)?,
        };
        let (mut down, down_events, stop_down) = sweep(&pr, &y0, &j0, -1.0, range, opts)?;
        let (up, up_events, stop_up) = sweep(&pr, &y0, &j0, 1.0, range, opts)?;
        // Lower end first: the decreasing sweep reversed, the start, the increasing sweep.
        let nd = down.len();
        down.reverse();
        let mut points = down;
        points.push(first);
        points.extend(up);
        let mut events: Vec<LensEvent> = down_events
            .into_iter()
            .map(|e| LensEvent {
                // point k of the sweep (k ≥ 1: 0 is the start) sits at nd − k
                index: nd + 1 - e.index,
                ..e
            })
            .collect();
        events.reverse();
        events.extend(up_events.into_iter().map(|e| LensEvent {
            index: nd + e.index,
            ..e
        }));
        Ok(LensBranch {
            parameter: lens.name(),
            unit: lens.unit(),
            u: start.u,
            start_value: p0,
            start_index: nd,
            points,
            events,
            stops: [stop_down, stop_up],
        })
    }
}

impl Section {
    /// The orbit at `u` [m/s] on the first branch of `set` (this section's branches in U)
    /// that has one there — stable orbits first, then unstable — continued in `lens` over
    /// `range` ([`Section::continue_in`]): what `aeroform branch --parameter` and Python's
    /// `branch(parameter=…)` run.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `at_speed` when no branch has an orbit at `u`
    /// (the message gives each branch's speed span); the errors of
    /// [`Section::continue_in`].
    pub fn continue_set_in(
        &self,
        set: &BranchSet,
        lens: &dyn Lens,
        range: [f64; 2],
        u: f64,
        opts: &BranchOptions,
    ) -> Result<LensBranch> {
        let found = [true, false].into_iter().find_map(|stable| {
            set.branches.iter().find_map(|b| {
                self.orbit_on_branch(b, u, stable, opts)
                    .ok()
                    .map(|p| (b, p))
            })
        });
        let Some((b, p)) = found else {
            let spans: Vec<String> = set
                .branches
                .iter()
                .map(|b| {
                    let (lo, hi) = b
                        .points
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                            (l.min(p.u), h.max(p.u))
                        });
                    format!("{lo:.4}…{hi:.4}")
                })
                .collect();
            return Err(Error::param(
                "at_speed",
                u,
                format!(
                    "no branch has an orbit at U = {u} m/s (the branches span U = {} m/s)",
                    spans.join(", ")
                ),
            ));
        };
        self.continue_in(lens, &b.hopf, &p, range, opts)
    }
}

/// One direction (`sign` ±1 in p) of the continuation from the converged `y0`: the points
/// after the start, the events (index k: between sweep points k − 1 and k, the start being
/// point 0) and the end.
fn sweep(
    pr: &LensProblem<'_>,
    y0: &DVector<f64>,
    j0: &DMatrix<f64>,
    sign: f64,
    range: [f64; 2],
    opts: &BranchOptions,
) -> Result<(Vec<LensPoint>, Vec<LensEvent>, LensEnd)> {
    let m = pr.m;
    let mut e = DVector::zeros(m);
    e[m - 1] = sign;
    let (mut t, mut chord) = tangent(j0, &e, None)?;
    let mut yk = y0.clone();
    let mut prev = pr.point(y0, j0)?;
    let mut vals = vec![pr.value(y0)];
    let mut arc = vec![0.0];
    let mut ts = vec![t.clone()];
    let mut points: Vec<LensPoint> = Vec::new();
    let mut events = Vec::new();
    let mut ds = opts.ds;
    let stop = loop {
        if points.len() + 1 >= opts.max_points {
            break LensEnd::MaxPoints;
        }
        let pred = &yk + &t * ds;
        let c = Closure::Arclength(&yk, &t, ds);
        let chord_here = pr.jacobian_at_solution().then_some(&chord);
        let res = newton(pr, pred, &c, chord_here, opts.newton_tol, opts.max_newton).and_then(
            |(y, j, it, lu)| {
                let (tn, lu) = tangent(&j, &t, lu)?;
                Ok((y, j, it, tn, lu))
            },
        );
        let (y, j, it, tn, lu) = match res {
            Ok(r) if r.3.dot(&t) > 0.8 => r,
            other => {
                ds *= 0.5;
                if ds < opts.ds_min {
                    let message = match other {
                        Err(e) => e.to_string(),
                        Ok(_) => "the tangent turns too sharply even at the smallest step".into(),
                    };
                    break LensEnd::NotConverged {
                        value: *vals.last().expect("start value"),
                        message,
                    };
                }
                continue;
            }
        };
        let value = pr.value(&y);
        let orbit = pr.point(&y, &j)?;
        if value < range[0] || value > range[1] {
            break LensEnd::Range { value };
        }
        if orbit.amplitude_alpha > opts.max_amplitude_alpha {
            break LensEnd::Amplitude {
                amplitude_alpha: orbit.amplitude_alpha,
            };
        }
        if orbit.amplitude_alpha < 0.5 * opts.start_amplitude {
            break LensEnd::Equilibrium { value };
        }
        arc.push(arc.last().copied().unwrap_or(0.0) + (&y - &yk).norm());
        vals.push(value);
        ts.push(tn.clone());
        let k = vals.len() - 1;
        if ts[k - 1][m - 1] * ts[k][m - 1] < 0.0 && k >= 2 {
            let s3 = [arc[k - 2], arc[k - 1], arc[k]];
            let v3 = [vals[k - 2], vals[k - 1], vals[k]];
            let at_vertex = parabola_vertex(s3, v3).filter(|(s, _)| *s >= s3[0] && *s <= s3[2]);
            events.push(LensEvent {
                kind: EventKind::Fold,
                value: at_vertex.map_or(vals[k - 1], |(_, v)| v),
                // the turning point lies next to point k − 1 (`prev`)
                amplitude_alpha: prev.amplitude_alpha,
                index: k,
            });
        } else if let Some(kind) = crossing(&prev, &orbit) {
            events.push(LensEvent {
                kind,
                value,
                amplitude_alpha: orbit.amplitude_alpha,
                index: k,
            });
        }
        prev = orbit.clone();
        points.push(LensPoint { value, orbit });
        yk = y;
        chord = lu;
        t = tn;
        if it <= 3 {
            ds = (ds * 1.5).min(opts.ds_max);
        }
    };
    Ok((points, events, stop))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::hp1_cubic_pitch;

    fn no_obs(_: super::super::BranchProgress) {}

    /// The HP-1 section with a cubic pitch spring and linear (Theodorsen) aerodynamics,
    /// its branch in U and the stable orbit at 1.2 U_F.
    fn start() -> (Section, super::super::Branch, BranchPoint) {
        let s = hp1_cubic_pitch();
        let opts = BranchOptions::default();
        let set = s.lco_branches(1.5, 3.0, &opts, &no_obs).unwrap();
        let b = set.branches[0].clone();
        let p = s.orbit_on_branch(&b, 1.2 * b.hopf.u, true, &opts).unwrap();
        (s, b, p)
    }

    /// With every other term linear, scaling the cubic coefficient by λ scales the orbit
    /// by 1/√λ exactly (x ↦ x/√λ maps the solutions onto each other) and keeps its period
    /// and multipliers: the branch in the cubic's coefficient must show A √k₃ constant.
    #[test]
    fn amplitude_scales_as_the_inverse_square_root_of_the_cubic() {
        let (s, b, p) = start();
        let lens = SectionParameter::parse("pitch_stiffness[3]").unwrap();
        let k3 = lens.get(&s);
        let opts = BranchOptions::default();
        let lb = s
            .continue_in(&lens, &b.hopf, &p, [0.5 * k3, 4.0 * k3], &opts)
            .unwrap();
        assert_eq!(lb.parameter, "structure.pitch_stiffness[3]");
        assert!(lb.points.len() > 5, "{} points", lb.points.len());
        let lo = lb.points.first().unwrap().value;
        let hi = lb.points.last().unwrap().value;
        assert!(
            lo < 0.6 * k3 && hi > 3.5 * k3,
            "covered {lo} … {hi} of k3 = {k3}"
        );
        assert!(
            matches!(lb.stops[0], LensEnd::Range { .. })
                && matches!(lb.stops[1], LensEnd::Range { .. }),
            "{:?}",
            lb.stops
        );
        let c0 = p.amplitude_alpha * k3.sqrt();
        let mut worst: f64 = 0.0;
        for q in &lb.points {
            let c = q.orbit.amplitude_alpha * q.value.sqrt();
            worst = worst.max((c / c0 - 1.0).abs());
            assert!((q.orbit.period / p.period - 1.0).abs() < 1e-6, "{q:?}");
            assert!(q.orbit.stable);
        }
        println!(
            "A √k3 constant to {worst:.2e} over {} points",
            lb.points.len()
        );
        assert!(worst < 1e-5, "A √k3 varies by {worst:.2e}");
        assert!(lb.events.is_empty(), "{:?}", lb.events);
    }

    /// A point of the branch in k_α is the orbit the U-branch of the section built with
    /// that k_α has at the same speed.
    #[test]
    fn a_point_in_pitch_stiffness_is_the_orbit_of_that_section() {
        let (s, b, p) = start();
        let lens = SectionParameter::KAlpha;
        let k = lens.get(&s);
        let opts = BranchOptions::default();
        let lb = s
            .continue_in(&lens, &b.hopf, &p, [0.97 * k, 1.03 * k], &opts)
            .unwrap();
        let q = lb
            .points
            .iter()
            .filter(|q| (q.value / k - 1.0).abs() > 0.01)
            .max_by(|a, b| (a.value - k).abs().total_cmp(&(b.value - k).abs()))
            .expect("a point away from the start");
        let s2 = lens.set(&s, q.value).unwrap();
        let set = s2.lco_branches(1.5, 3.0, &opts, &no_obs).unwrap();
        let other = s2
            .orbit_on_branch(&set.branches[0], p.u, true, &opts)
            .unwrap();
        let rel = (other.amplitude_alpha / q.orbit.amplitude_alpha - 1.0).abs();
        println!(
            "k_alpha {:.5} (start {k:.5}): lens {:.6e} rad, U-branch {:.6e} rad ({rel:.1e})",
            q.value, q.orbit.amplitude_alpha, other.amplitude_alpha
        );
        assert!(rel < 1e-4, "{rel:.2e}");
        assert!((other.period / q.orbit.period - 1.0).abs() < 1e-4);
        assert!((q.orbit.amplitude_alpha / p.amplitude_alpha - 1.0).abs() > 1e-3);
    }

    /// A fold in the parameter is where the section's fold in U sits at the branch's
    /// speed: continue the stable orbit of the softening–hardening HP-1 section (a fold
    /// below U_F) in its cubic; at the fold value found, the U-branch of the section built
    /// with it must turn at the same speed.
    #[test]
    fn a_fold_in_the_cubic_is_the_fold_in_u_of_that_section() {
        let s = super::super::tests::hp1_soft_hard();
        let opts = BranchOptions::default();
        let set = s.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
        let b = &set.branches[0];
        let fold_u = b
            .events
            .iter()
            .find(|e| e.kind == EventKind::Fold)
            .expect("a fold")
            .u;
        // between the fold and the Hopf point: the stable large orbit
        let u = fold_u + 0.3 * (b.hopf.u - fold_u);
        let p = s.orbit_on_branch(b, u, true, &opts).unwrap();
        let lens = SectionParameter::PitchStiffness(3);
        let c3 = lens.get(&s);
        assert!(c3 < 0.0);
        let lb = s
            .continue_in(&lens, &b.hopf, &p, [3.0 * c3, 0.0], &opts)
            .unwrap();
        let folds: Vec<_> = lb
            .events
            .iter()
            .filter(|e| e.kind == EventKind::Fold)
            .collect();
        assert_eq!(folds.len(), 1, "{:?} {:?}", lb.events, lb.stops);
        let c_fold = folds[0].value;
        assert!(
            c_fold > c3,
            "less softening moves the fold up to U: {c_fold} vs {c3}"
        );
        let s2 = lens.set(&s, c_fold).unwrap();
        let set2 = s2.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
        let fold2 = set2.branches[0]
            .events
            .iter()
            .find(|e| e.kind == EventKind::Fold)
            .expect("a fold of the new section")
            .u;
        println!(
            "cubic {c3:.5} → fold at {c_fold:.5}; that section's fold in U {fold2:.6} vs U {u:.6}"
        );
        assert!((fold2 / u - 1.0).abs() < 2e-3, "{fold2} vs {u}");
        // the stable side and the unstable side of the fold
        let i = folds[0].index;
        assert_ne!(lb.points[i - 2].orbit.stable, lb.points[i + 1].orbit.stable);
    }

    #[test]
    fn names_parse_and_bad_ones_are_refused_by_field() {
        assert_eq!(
            SectionParameter::parse("structure.k_alpha").unwrap(),
            SectionParameter::KAlpha
        );
        assert_eq!(
            SectionParameter::parse("pitch_damping[3]").unwrap(),
            SectionParameter::PitchDamping(3)
        );
        for bad in [
            "k_beta",
            "pitch_stiffness[1]",
            "pitch_stiffness[x]",
            "pitch[3]",
        ] {
            let e = SectionParameter::parse(bad).unwrap_err();
            assert!(e.to_string().contains("parameter"), "{bad}: {e}");
        }
        let (s, b, p) = start();
        let e = s
            .continue_in(
                &SectionParameter::KAlpha,
                &b.hopf,
                &p,
                [1.0, 2.0],
                &BranchOptions::default(),
            )
            .unwrap_err();
        assert!(e.to_string().contains("range"), "{e}");
    }
}
