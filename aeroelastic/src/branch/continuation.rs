//! The continuation core: the factory of the periodic-orbit problem of each method
//! ([`problem`]; the trait every discretisation implements, [`PeriodicProblem`], and the
//! closing equation [`Closure`] are in `periodic.rs`, below the discretisations), the
//! shooting scales, the chord-Newton
//! corrector, the tangent, the pseudo-arclength predictor–corrector of
//! [`Section::continue_branch`], and the location of folds and multiplier crossings between
//! consecutive branch points.

use identify::numerics::interp::lagrange;
use nalgebra::{DMatrix, DVector, Dyn};

use super::options::{BranchMethod, BranchOptions};
use super::periodic::{Closure, PeriodicProblem};
use super::shooting::Shooting;
use super::types::{
    Branch, BranchEnd, BranchEvent, BranchPoint, BranchProgress, EventKind, HopfPoint,
};
use super::{condensed, harmonic};
use crate::section::Section;
use crate::{Error, Result};

/// Scales of the shooting unknowns (z₀, T, U) of the branch from `hopf`: each state
/// component `amplitude_scale` \[rad\] times its Hopf-eigenvector magnitude (at least 1e-3
/// of the largest), T by 0.1 T_Hopf, U by 0.1 U_Hopf.
pub(super) fn branch_scales(hopf: &HopfPoint, amplitude_scale: f64) -> Vec<f64> {
    let vmax = hopf
        .eigenvector
        .iter()
        .map(|c| c.norm())
        .fold(0.0, f64::max);
    let mut scales: Vec<f64> = hopf
        .eigenvector
        .iter()
        .map(|c| amplitude_scale * c.norm().max(1e-3 * vmax))
        .collect();
    scales.push(0.1 * std::f64::consts::TAU / hopf.omega);
    scales.push(0.1 * hopf.u);
    scales
}

/// The problem of `opts.method` for `section` with the scales of `scales` (state
/// components, T, U: the shooting unknowns' scales).
pub(super) fn problem<'a>(
    section: &'a Section,
    opts: &BranchOptions,
    scales: &[f64],
    hopf: &HopfPoint,
) -> Box<dyn PeriodicProblem + 'a> {
    let n = section.n_states();
    match opts.method {
        BranchMethod::Shooting => Box::new(Shooting::new(
            section,
            opts.steps_per_period,
            scales.to_vec(),
        )),
        BranchMethod::HarmonicBalance if condensed::applies(section) => {
            Box::new(condensed::CondensedBalance::new(
                section,
                opts.harmonics,
                opts.steps_per_period,
                scales,
                hopf,
            ))
        }
        BranchMethod::HarmonicBalance => Box::new(harmonic::HarmonicBalance::new(
            section,
            opts.harmonics,
            opts.steps_per_period,
            &scales[..n],
            0.1 * hopf.omega,
            scales[n + 1],
            hopf.omega,
        )),
    }
}

fn closure_row(p: &dyn PeriodicProblem, c: &Closure, y: &DVector<f64>) -> (DVector<f64>, f64) {
    let m = p.unknowns();
    match c {
        Closure::Alpha(a) => {
            let i = p.amplitude_index();
            let mut r = DVector::zeros(m);
            r[i] = 1.0;
            (r, y[i] - a)
        }
        Closure::Arclength(yk, tk, ds) => ((*tk).clone(), (y - *yk).dot(tk) - ds),
        Closure::Speed(us) => {
            let mut r = DVector::zeros(m);
            r[m - 1] = 1.0;
            (r, y[m - 1] - us)
        }
    }
}

/// The Jacobian of G with one more row, LU-factored.
fn augmented(jg: &DMatrix<f64>, row: &DVector<f64>) -> nalgebra::LU<f64, Dyn, Dyn> {
    let m = jg.ncols();
    let mut a = DMatrix::zeros(m, m);
    a.rows_mut(0, m - 1).copy_from(jg);
    a.set_row(m - 1, &row.transpose());
    a.lu()
}

/// Chord Newton for G(Y) = 0 plus the closure, from `y`. `chord` is a factored
/// approximation of the full Jacobian (the previous point's Jacobian with the previous
/// tangent as last row); without it, or when convergence is slow, the Jacobian is
/// computed once at the current iterate. Returns the solution, ∂G/∂Y there, the
/// iterations used and, when that ∂G/∂Y is the last refresh's
/// ([`PeriodicProblem::jacobian_at_solution`] false), its factored [∂G/∂Y; closure row].
pub(super) fn newton(
    p: &dyn PeriodicProblem,
    mut y: DVector<f64>,
    closure: &Closure,
    chord: Option<&nalgebra::LU<f64, Dyn, Dyn>>,
    tol: f64,
    max_iter: usize,
) -> Result<Solved> {
    let m = p.unknowns();
    let mut own = None;
    let mut own_raw = None;
    let mut refreshed = false;
    let mut last = f64::INFINITY;
    for it in 0..max_iter {
        let g = p.g(&y)?;
        let (row, c) = closure_row(p, closure, &y);
        let mut r = DVector::zeros(m);
        r.rows_mut(0, m - 1).copy_from(&g);
        r[m - 1] = c;
        let norm = r.amax();
        if !norm.is_finite() {
            return Err(Error::numerical("newton", "non-finite residual"));
        }
        if norm < tol {
            return Ok(match own_raw {
                Some(j) if !p.jacobian_at_solution() => (y, j, it, own),
                _ => {
                    let j = p.jac(&y, &g)?;
                    (y, j, it, None)
                }
            });
        }
        let slow = norm > 0.5 * last || it == 3;
        if (chord.is_none() && own.is_none()) || (slow && !refreshed) {
            let j = p.jac(&y, &g)?;
            own = Some(augmented(&j, &row));
            own_raw = Some(j);
            refreshed = true;
        } else if norm > 2.0 * last && refreshed {
            return Err(Error::numerical(
                "newton",
                format!("residual grows ({last:.3e} → {norm:.3e})"),
            ));
        }
        last = norm;
        let lu = own.as_ref().or(chord).expect("a factored Jacobian");
        let dy = lu
            .solve(&(-r))
            .ok_or_else(|| Error::numerical("newton", "singular Jacobian"))?;
        y += dy;
    }
    Err(Error::numerical(
        "newton",
        format!("no convergence in {max_iter} iterations (residual {last:.3e})"),
    ))
}

/// Newton's result: the solution, ∂G/∂Y, iterations, and the factored [∂G/∂Y; row] when
/// ∂G/∂Y is the last refresh's.
type Solved = (
    DVector<f64>,
    DMatrix<f64>,
    usize,
    Option<nalgebra::LU<f64, Dyn, Dyn>>,
);

/// Tangent of the solution curve: null vector of the Jacobian of G, oriented along
/// `prev`; also returns the factored [∂G/∂Y; prevᵀ] (the next point's chord matrix).
/// `factored` is that matrix when already at hand.
pub(super) fn tangent(
    jg: &DMatrix<f64>,
    prev: &DVector<f64>,
    factored: Option<nalgebra::LU<f64, Dyn, Dyn>>,
) -> Result<(DVector<f64>, nalgebra::LU<f64, Dyn, Dyn>)> {
    let m = jg.ncols();
    let lu = factored.unwrap_or_else(|| augmented(jg, prev));
    let mut rhs = DVector::zeros(m);
    rhs[m - 1] = 1.0;
    let t = lu
        .solve(&rhs)
        .ok_or_else(|| Error::numerical("tangent", "singular extended Jacobian"))?;
    let nrm = t.norm();
    if !(nrm.is_finite() && nrm > 0.0) {
        return Err(Error::numerical("tangent", "degenerate tangent"));
    }
    Ok((t / nrm, lu))
}

/// Vertex of the parabola through three points (s_i, u_i); returns (s*, u*).
pub(super) fn parabola_vertex(s: [f64; 3], u: [f64; 3]) -> Option<(f64, f64)> {
    let d1 = (u[1] - u[0]) / (s[1] - s[0]);
    let d2 = (u[2] - u[1]) / (s[2] - s[1]);
    let a = (d2 - d1) / (s[2] - s[0]);
    if a.abs() < 1e-300 || !a.is_finite() {
        return None;
    }
    let b = d1 - a * (s[0] + s[1]);
    let sv = -b / (2.0 * a);
    let uv = u[0] + d1 * (sv - s[0]) + a * (sv - s[0]) * (sv - s[1]);
    Some((sv, uv))
}

impl Section {
    /// Continues the periodic orbits born at `hopf` within [`u_min`, `u_max`] [m/s].
    /// `observer` receives a report after each point.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for bad options or a non-smooth structure
    /// ([`Section::check_smooth`]); [`Error::Numerical`] when not even the first orbits
    /// near the Hopf point converge (the message names the speed and amplitude). A branch
    /// that stops converging later ends with [`BranchEnd::NotConverged`] and keeps its
    /// points.
    pub fn continue_branch(
        &self,
        hopf: &HopfPoint,
        u_min: f64,
        u_max: f64,
        opts: &BranchOptions,
        observer: &dyn Fn(BranchProgress),
    ) -> Result<Branch> {
        self.continue_branch_within(hopf, u_min, u_max, f64::INFINITY, opts, observer)
    }

    /// [`Section::continue_branch`] that also stops where the branch passes `u_reach`
    /// [m/s] with increasing speed (ending with [`BranchEnd::SpeedRange`] at the speed of
    /// the first orbit beyond it, whose Floquet multipliers are not computed). For a fit
    /// to data measured below `u_reach`: the branch beyond it bears on those speeds only if
    /// it folds back, and the orbits there are the costliest of a diagram that starts at a
    /// Hopf point far above the data (docs/DECISIONS.md, "The fits' continuation reach").
    /// `u_reach = ∞` is [`Section::continue_branch`] exactly.
    ///
    /// # Errors
    /// As [`Section::continue_branch`].
    pub fn continue_branch_within(
        &self,
        hopf: &HopfPoint,
        u_min: f64,
        u_max: f64,
        u_reach: f64,
        opts: &BranchOptions,
        observer: &dyn Fn(BranchProgress),
    ) -> Result<Branch> {
        opts.check()?;
        self.check_smooth()?;
        let scales = branch_scales(hopf, opts.amplitude_scale);
        let sh = problem(self, opts, &scales, hopf);
        let sh = sh.as_ref();
        let ai = sh.amplitude_index();
        let start = |a: f64| -> Result<(DVector<f64>, DMatrix<f64>)> {
            let y = sh.start(hopf, a);
            let c = Closure::Alpha(a / sh.scales()[ai]);
            newton(sh, y, &c, None, opts.newton_tol, 3 * opts.max_newton)
                .map(|(y, j, _, _)| (y, j))
                .map_err(|e| {
                    Error::numerical(
                        "branch start",
                        format!(
                            "the orbit of pitch amplitude {a:.3e} rad next to the Hopf point \
                             U = {:.6} m/s did not converge: {e}",
                            hopf.u
                        ),
                    )
                })
        };
        let a0 = opts.start_amplitude;
        let (y0, j0) = start(a0)?;
        let (y1, j1) = start(2.0 * a0)?;
        let mut points = vec![sh.point(&y0, &j0)?, sh.point(&y1, &j1)?];
        for p in &points {
            observer(BranchProgress {
                branch: 0,
                points: 1,
                u: p.u,
                amplitude_alpha: p.amplitude_alpha,
            });
        }
        let sec = &y1 - &y0;
        let (mut t, mut chord) = tangent(&j1, &(&sec / sec.norm()), None)?;
        let mut ts = vec![sec.clone() / sec.norm(), t.clone()];
        let mut arc = vec![0.0, sec.norm()];
        // The two orbits before `yk` with their arclengths (for the parabolic predictor).
        let mut prev2: Option<(f64, DVector<f64>)> = None;
        let mut prev1: Option<(f64, DVector<f64>)> = Some((0.0, y0.clone()));
        let mut yk = y1;
        let mut ds = opts.ds;
        let mut events = Vec::new();
        let stop;
        loop {
            if points.len() >= opts.max_points {
                stop = BranchEnd::MaxPoints;
                break;
            }
            // Predictor: the tangent step; for a problem that takes a fresh Jacobian at the
            // predictor, the parabola through the last three orbits (error O(ds³) instead of
            // O(ds²), one Newton correction less), when there are three.
            let pred = match (&prev2, &prev1) {
                (Some((s2, y2)), Some((s1, y1))) if !sh.jacobian_at_solution() => {
                    let s0 = *arc.last().expect("two start points");
                    let x = s0 + ds;
                    let l2 = (x - s1) * (x - s0) / ((s2 - s1) * (s2 - s0));
                    let l1 = (x - s2) * (x - s0) / ((s1 - s2) * (s1 - s0));
                    let l0 = (x - s2) * (x - s1) / ((s0 - s2) * (s0 - s1));
                    y2 * l2 + y1 * l1 + &yk * l0
                }
                _ => &yk + &t * ds,
            };
            let c = Closure::Arclength(&yk, &t, ds);
            // A problem whose Jacobian is cheap (no exact one needed at the solution) takes
            // a fresh one at the predictor instead of the previous point's chord.
            let chord_here = sh.jacobian_at_solution().then_some(&chord);
            let res = newton(sh, pred, &c, chord_here, opts.newton_tol, opts.max_newton).and_then(
                |(y, j, it, lu)| {
                    // Newton's refresh factored [∂G/∂Y; tᵀ]: the same matrix.
                    let (tn, lu) = tangent(&j, &t, lu)?;
                    Ok((y, j, it, tn, lu))
                },
            );
            let accepted = match res {
                Ok((y, j, it, tn, lu)) if tn.dot(&t) > 0.8 => Some((y, j, it, tn, lu)),
                Ok(_) => None,
                Err(e) => {
                    if ds * 0.5 < opts.ds_min {
                        let last = points.last().expect("two start points");
                        stop = BranchEnd::NotConverged {
                            u: last.u,
                            amplitude_alpha: last.amplitude_alpha,
                            message: format!(
                                "after point {} (U = {:.6} m/s, pitch amplitude {:.4e} rad): {e}",
                                points.len() - 1,
                                last.u,
                                last.amplitude_alpha
                            ),
                        };
                        break;
                    }
                    None
                }
            };
            let Some((y, j, it, tn, lu)) = accepted else {
                ds *= 0.5;
                if ds < opts.ds_min {
                    let last = points.last().expect("two start points");
                    stop = BranchEnd::NotConverged {
                        u: last.u,
                        amplitude_alpha: last.amplitude_alpha,
                        message: format!(
                            "after point {} (U = {:.6} m/s): the tangent turns too sharply \
                             even at the smallest step",
                            points.len() - 1,
                            last.u
                        ),
                    };
                    break;
                }
                continue;
            };
            let ui = sh.unknowns() - 1;
            let u_here = y[ui] * sh.scales()[ui];
            if u_here > u_reach && tn[ui] > 0.0 {
                stop = BranchEnd::SpeedRange { u: u_here };
                break;
            }
            let p = sh.point(&y, &j)?;
            if p.u < u_min || p.u > u_max {
                stop = BranchEnd::SpeedRange { u: p.u };
                break;
            }
            if p.amplitude_alpha > opts.max_amplitude_alpha {
                stop = BranchEnd::Amplitude {
                    amplitude_alpha: p.amplitude_alpha,
                };
                break;
            }
            if points.len() > 4 && p.amplitude_alpha < 0.5 * opts.start_amplitude {
                stop = BranchEnd::Equilibrium { u: p.u };
                break;
            }
            arc.push(arc.last().copied().unwrap_or(0.0) + (&y - &yk).norm());
            let prev = points.last().expect("two start points").clone();
            let k = points.len();
            points.push(p);
            ts.push(tn.clone());
            // Events between k−1 and k.
            let fold = ts[k - 1][ui] * ts[k][ui] < 0.0;
            if fold {
                let s3 = [arc[k - 2], arc[k - 1], arc[k]];
                let u3 = [points[k - 2].u, points[k - 1].u, points[k].u];
                let a3 = [
                    points[k - 2].amplitude_alpha,
                    points[k - 1].amplitude_alpha,
                    points[k].amplitude_alpha,
                ];
                let h3 = [
                    points[k - 2].amplitude_h,
                    points[k - 1].amplitude_h,
                    points[k].amplitude_h,
                ];
                let (u_f, a_f, h_f) = match parabola_vertex(s3, u3) {
                    Some((sv, uv)) if sv >= s3[0] && sv <= s3[2] => {
                        (uv, quadratic(s3, a3, sv), quadratic(s3, h3, sv))
                    }
                    _ => (points[k - 1].u, a3[1], h3[1]),
                };
                events.push(BranchEvent {
                    kind: EventKind::Fold,
                    u: u_f,
                    amplitude_alpha: a_f,
                    amplitude_h: h_f,
                    index: k,
                });
            } else if let Some(kind) = crossing(&prev, &points[k]) {
                events.push(BranchEvent {
                    kind,
                    u: points[k].u,
                    amplitude_alpha: points[k].amplitude_alpha,
                    amplitude_h: points[k].amplitude_h,
                    index: k,
                });
            }
            observer(BranchProgress {
                branch: 0,
                points: points.len(),
                u: points[k].u,
                amplitude_alpha: points[k].amplitude_alpha,
            });
            prev2 = prev1.take();
            prev1 = Some((arc[arc.len() - 2], std::mem::replace(&mut yk, y)));
            chord = lu;
            t = tn;
            if it <= 3 {
                ds = (ds * 1.5).min(opts.ds_max);
            }
        }
        let criticality = {
            let q = points.get(2).unwrap_or(&points[1]);
            let towards_unstable = (q.u - hopf.u) * hopf.dsigma_du > 0.0;
            if towards_unstable {
                "supercritical"
            } else {
                "subcritical"
            }
        }
        .to_string();
        Ok(Branch {
            hopf: hopf.clone(),
            points,
            events,
            stop,
            criticality,
            scales,
        })
    }
}

/// The parabola through (s_i, v_i), i = 0‥2, at `x`.
fn quadratic(s: [f64; 3], v: [f64; 3], x: f64) -> f64 {
    lagrange(&[(s[0], v[0]), (s[1], v[1]), (s[2], v[2])], x)
}

/// Kind of multiplier crossing between two points without a turning point, if the number
/// of multipliers outside the unit circle changed.
pub(super) fn crossing(a: &BranchPoint, b: &BranchPoint) -> Option<EventKind> {
    let outside = |p: &BranchPoint| {
        p.multipliers
            .iter()
            .filter(|m| m[0].hypot(m[1]) > 1.0)
            .count()
    };
    if outside(a) == outside(b) {
        return None;
    }
    let m = b.multipliers.iter().min_by(|x, y| {
        (x[0].hypot(x[1]) - 1.0)
            .abs()
            .total_cmp(&(y[0].hypot(y[1]) - 1.0).abs())
    })?;
    Some(if m[1].abs() > 1e-6 {
        EventKind::NeimarkSacker
    } else if m[0] < 0.0 {
        EventKind::PeriodDoubling
    } else {
        EventKind::BranchPoint
    })
}
