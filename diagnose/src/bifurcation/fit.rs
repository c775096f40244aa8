//! Fitting a candidate with continuation inside the fit, and scoring it by
//! leave-one-speed-out.
//!
//! Every evaluation continues the periodic orbits of the changed section from its Hopf
//! points ([`Section::lco_branches`], condensed harmonic balance where it applies) and
//! compares them with the measured points. The fit minimises, by Levenberg–Marquardt with
//! forward-difference Jacobians from the best point of a coarse start grid, the residuals
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
//! The score that decides is the plain one at the measured speed (a point the model
//! leaves uncovered counts with predicted amplitude 0), on held-out speeds only.

use aeroelastic::branch::{BranchOptions, BranchSet, MeasuredAmplitude};
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
        .lco_branches(s.range[0], s.range[1], s.branch, &|_| {})
        .ok()
}

/// Residuals of the measured points `pts` against `set` (layout per point: pitch if
/// measured, heave if measured, frequency if measured, speed).
pub(crate) fn residuals(
    set: Option<&BranchSet>,
    pts: &[&MeasuredAmplitude],
    s: &Setting,
) -> Vec<f64> {
    let mut r = Vec::with_capacity(3 * pts.len());
    for m in pts {
        let covered = set.and_then(|set| aeroelastic::branch::predicted_at(set, m));
        let (pa, ph, pf, du) = match covered {
            Some((a, h, f)) => (a, h, f, 0.0),
            None => {
                // nearest orbit of the same stability in the scaled plane
                let mut best: Option<(f64, (f64, f64, f64, f64))> = None;
                for b in set.iter().flat_map(|s| s.branches.iter()) {
                    for p in b.points.iter().filter(|p| p.stable == m.stable) {
                        let mut d = ((p.u - m.u) / s.s_u).powi(2);
                        if let Some(a) = m.amplitude_alpha {
                            d += ((p.amplitude1_alpha - a) / s.n_alpha(a)).powi(2);
                        }
                        if let Some(h) = m.amplitude_h {
                            d += ((p.amplitude1_h - h) / s.n_h(h)).powi(2);
                        }
                        if best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((
                                d,
                                (
                                    p.amplitude1_alpha,
                                    p.amplitude1_h,
                                    p.omega / std::f64::consts::TAU,
                                    p.u - m.u,
                                ),
                            ));
                        }
                    }
                }
                match best {
                    Some((_, v)) => v,
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

/// Result of one fit.
#[derive(Debug, Clone)]
pub(crate) struct FitResult {
    /// Scaled parameters.
    pub theta: Vec<f64>,
    /// Sum of squared residuals at `theta`.
    pub cost: f64,
}

/// Levenberg–Marquardt on `f` from `x0` (forward differences, step 1e-2 in θ).
pub(crate) fn levenberg_marquardt(
    f: &dyn Fn(&[f64]) -> Vec<f64>,
    x0: &[f64],
    max_iter: usize,
) -> FitResult {
    let n = x0.len();
    let mut x = x0.to_vec();
    let mut r = f(&x);
    let mut c = cost(&r);
    let mut lambda = 1e-2;
    let h = 1e-2;
    for _ in 0..max_iter {
        let m = r.len();
        let mut j = DMatrix::<f64>::zeros(m, n);
        for k in 0..n {
            let mut xp = x.clone();
            xp[k] += h;
            let rp = f(&xp);
            for i in 0..m {
                j[(i, k)] = (rp[i] - r[i]) / h;
            }
        }
        let rv = DVector::from_column_slice(&r);
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &rv;
        let mut improved = false;
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
            let rn = f(&xn);
            let cn = cost(&rn);
            if cn.is_finite() && cn < c {
                let rel = (c - cn) / c.max(1e-300);
                x = xn;
                r = rn;
                c = cn;
                lambda = (lambda / 3.0).max(1e-7);
                improved = rel > 1e-6;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    FitResult { theta: x, cost: c }
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
