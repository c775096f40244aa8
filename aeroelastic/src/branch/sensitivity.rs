//! Sensitivities of a continued orbit with respect to parameters of the section
//! ([`Section::orbit_sensitivity`]): the periodic-orbit residual G(Y; p) = 0 closed by
//! one more equation (U fixed, or the pitch-amplitude unknown fixed) gives
//! dY/dp = −[G_Y; c]⁻¹ [G_p; 0] with one solve of the Jacobian Newton already factors, so
//! a fit over the section's parameters (the bifurcation-level diagnosis) takes the slope
//! of each measured point's predicted orbit from one corrected orbit instead of one more
//! whole diagram per parameter. Additions only: nothing here changes a continuation.

use nalgebra::{DMatrix, DVector};

use super::continuation::{newton, problem};
use super::options::BranchOptions;
use super::periodic::{Closure, PeriodicProblem};
use super::types::{Branch, OrbitValues};
use crate::section::Section;
use crate::{Error, Result};

/// Where on a branch an orbit's sensitivity is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensitivityAt {
    /// At speed `u` [m/s] on the segment from branch point `index` to `index + 1` (the
    /// initial guess interpolates their unknowns linearly in U), U held fixed: the
    /// derivative of a measured point's predicted orbit at its own speed.
    Speed {
        /// Index of the segment's first point.
        index: usize,
        /// Speed [m/s].
        u: f64,
    },
    /// At branch point `index`, its pitch-amplitude unknown (the first-harmonic cosine
    /// coefficient of α) held fixed, U free: how the orbit of that amplitude moves in U
    /// (the slope that pulls a fold back towards a speed it no longer covers).
    Amplitude {
        /// Index of the branch point.
        index: usize,
    },
}

/// An orbit and its derivatives with respect to the parameters of the section.
#[derive(Debug, Clone, PartialEq)]
pub struct OrbitSensitivity {
    /// The corrected orbit (at the closure's U or amplitude).
    pub orbit: OrbitValues,
    /// Per parameter p_k, d(orbit)/dp_k at the closure held fixed (units of the orbit's
    /// quantities per unit of p_k).
    pub derivatives: Vec<OrbitValues>,
}

impl Section {
    /// The orbit of `branch` (continued on this section with `opts`) at `at`, corrected by
    /// Newton, and its derivative with respect to each parameter p_k of the section:
    /// `perturbed[k]` is the section with p_k moved by `δ_k` (its second element, ≠ 0, in
    /// p_k's unit). With G(Y; p) = 0 the discretised periodic-orbit equations and c the
    /// closure (U or the pitch-amplitude unknown fixed),
    ///
    /// dY/dp_k = −[∂G/∂Y; c]⁻¹ [(G(Y; p + δ_k) − G(Y; p))/δ_k; 0],
    ///
    /// one solve with the Jacobian of the corrected orbit per parameter (no continuation
    /// of the perturbed sections). The perturbed sections must have the same structural
    /// terms (only coefficients changed) so that their discretisation has the same
    /// unknowns.
    ///
    /// # Errors
    /// [`Error::Numerical`] when `at` names no segment or point of the branch, its points
    /// carry no unknowns of this problem, Newton fails, a perturbed section's
    /// discretisation has other unknowns, or the closed Jacobian is singular; as
    /// [`Section::orbit_on_branch`] otherwise.
    pub fn orbit_sensitivity(
        &self,
        branch: &Branch,
        at: SensitivityAt,
        perturbed: &[(Section, f64)],
        opts: &BranchOptions,
    ) -> Result<OrbitSensitivity> {
        let sh = problem(self, opts, &branch.scales, &branch.hopf);
        let sh = sh.as_ref();
        let m = sh.unknowns();
        let (y0, closure) = start(sh, branch, at)?;
        let (y, _, _, _) = newton(sh, y0, &closure, None, opts.newton_tol, 3 * opts.max_newton)?;
        // ∂G/∂Y at the solution itself (Newton's may be its last refresh's)
        let g0 = sh.g(&y)?;
        let jg = sh.jac(&y, &g0)?;
        let mut row = DVector::zeros(m);
        match closure {
            Closure::Speed(_) => row[m - 1] = 1.0,
            _ => row[sh.amplitude_index()] = 1.0,
        }
        let mut a = DMatrix::zeros(m, m);
        a.rows_mut(0, m - 1).copy_from(&jg);
        a.set_row(m - 1, &row.transpose());
        let lu = a.lu();
        let base = values(sh, &y, &jg)?;
        let mut derivatives = Vec::with_capacity(perturbed.len());
        for (k, (s, delta)) in perturbed.iter().enumerate() {
            if !(delta.is_finite() && *delta != 0.0) {
                return Err(Error::numerical(
                    "orbit_sensitivity",
                    format!("parameter {k}: the step {delta} must be finite and non-zero"),
                ));
            }
            let pk = problem(s, opts, &branch.scales, &branch.hopf);
            if pk.unknowns() != m {
                return Err(Error::numerical(
                    "orbit_sensitivity",
                    format!(
                        "parameter {k}: the perturbed section's discretisation has {} unknowns, \
                         this one {m} (a structural term added or removed)",
                        pk.unknowns()
                    ),
                ));
            }
            let gk = pk.g(&y)?;
            let mut rhs = DVector::zeros(m);
            for i in 0..m - 1 {
                rhs[i] = -(gk[i] - g0[i]) / delta;
            }
            let dy = lu
                .solve(&rhs)
                .ok_or_else(|| Error::numerical("orbit_sensitivity", "singular closed Jacobian"))?;
            // The orbit's quantities are smooth functions of Y: their derivative along dY
            // by a small difference (relative step 1e-6 of Y).
            let nd = dy.amax();
            if !nd.is_finite() {
                return Err(Error::numerical(
                    "orbit_sensitivity",
                    format!("parameter {k}: non-finite dY/dp"),
                ));
            }
            if nd == 0.0 {
                derivatives.push(OrbitValues::default());
                continue;
            }
            let eps = 1e-6 * y.amax().max(1.0) / nd;
            let yk = &y + &dy * eps;
            derivatives.push(slope(values(sh, &yk, &jg)?, base, eps));
        }
        Ok(OrbitSensitivity {
            orbit: base,
            derivatives,
        })
    }

    /// The orbit of `branch` (continued on this section with `opts`) at `at`, corrected by
    /// Newton: the smooth prediction of a measured point (at its own speed, or at a branch
    /// point's pitch amplitude with U free), where [`predicted_at`](super::predicted_at)
    /// interpolates linearly between continuation points. The orbit
    /// [`Section::orbit_sensitivity`] differentiates, without the derivatives.
    ///
    /// # Errors
    /// As [`Section::orbit_sensitivity`] for the closure and Newton.
    pub fn orbit_at(
        &self,
        branch: &Branch,
        at: SensitivityAt,
        opts: &BranchOptions,
    ) -> Result<OrbitValues> {
        let sh = problem(self, opts, &branch.scales, &branch.hopf);
        let sh = sh.as_ref();
        let (y0, closure) = start(sh, branch, at)?;
        let (y, jg, _, _) = newton(sh, y0, &closure, None, opts.newton_tol, 3 * opts.max_newton)?;
        values(sh, &y, &jg)
    }
}

/// The initial guess and closure of the orbit `at` names on `branch` (module
/// documentation of [`SensitivityAt`]).
fn start(
    sh: &dyn PeriodicProblem,
    branch: &Branch,
    at: SensitivityAt,
) -> Result<(DVector<f64>, Closure<'static>)> {
    let m = sh.unknowns();
    let missing = || {
        Error::numerical(
            "orbit_sensitivity",
            format!(
                "{at:?} names no segment or point of the branch from the Hopf point at \
                     {:.4} m/s ({} points)",
                branch.hopf.u,
                branch.points.len()
            ),
        )
    };
    Ok(match at {
        SensitivityAt::Speed { index, u } => {
            let (a, b) = (
                branch.points.get(index).ok_or_else(missing)?,
                branch.points.get(index + 1).ok_or_else(missing)?,
            );
            let f = if a.u == b.u {
                0.0
            } else {
                (u - a.u) / (b.u - a.u)
            };
            let y = sh.scaled(a)? * (1.0 - f) + sh.scaled(b)? * f;
            (y, Closure::Speed(u / sh.scales()[m - 1]))
        }
        SensitivityAt::Amplitude { index } => {
            let p = branch.points.get(index).ok_or_else(missing)?;
            let y = sh.scaled(p)?;
            let a = y[sh.amplitude_index()];
            (y, Closure::Alpha(a))
        }
    })
}

/// (a − b)/over, quantity by quantity.
fn slope(a: OrbitValues, b: OrbitValues, over: f64) -> OrbitValues {
    OrbitValues {
        u: (a.u - b.u) / over,
        amplitude1_alpha: (a.amplitude1_alpha - b.amplitude1_alpha) / over,
        amplitude1_h: (a.amplitude1_h - b.amplitude1_h) / over,
        frequency_hz: (a.frequency_hz - b.frequency_hz) / over,
    }
}

/// The compared quantities of the orbit at scaled unknowns `y`.
fn values(sh: &dyn PeriodicProblem, y: &DVector<f64>, jg: &DMatrix<f64>) -> Result<OrbitValues> {
    match sh.first_harmonics(y) {
        Some(v) => Ok(v),
        None => sh.point(y, jg).map(|p| OrbitValues {
            u: p.u,
            amplitude1_alpha: p.amplitude1_alpha,
            amplitude1_h: p.amplitude1_h,
            frequency_hz: p.omega / std::f64::consts::TAU,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::branch::BranchMethod;
    use crate::reference::hp1_structure;
    use crate::structure::add_poly_term;

    fn no_obs(_: super::super::BranchProgress) {}

    /// The soft–hard HP-1 section (subcritical, one fold) with its quintic scaled.
    fn section(k5: f64) -> Section {
        let mut s = super::super::tests::hp1_soft_hard();
        let k = hp1_structure().k_alpha;
        add_poly_term(
            &mut s.structure.nonlinear.pitch_stiffness_terms,
            5,
            k5 * k - 20.0 * k,
        );
        s
    }

    /// The orbit a measured point is compared with under the smooth objective: corrected
    /// at the point's own speed, it is the orbit `orbit_on_branch` finds there and the one
    /// `orbit_sensitivity` differentiates, where the linear interpolation between the two
    /// continuation points misses it.
    #[test]
    fn orbit_at_is_the_corrected_orbit_not_the_interpolation() {
        let opts = BranchOptions {
            method: BranchMethod::HarmonicBalance,
            ..BranchOptions::default()
        };
        let s0 = section(20.0);
        let set = s0.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
        let b = &set.branches[0];
        let i = b.events[0].index + 3;
        let u = 0.5 * (b.points[i].u + b.points[i + 1].u);
        let at = SensitivityAt::Speed { index: i, u };
        let v = s0.orbit_at(b, at, &opts).unwrap();
        let o = s0.orbit_on_branch(b, u, true, &opts).unwrap();
        let sens = s0.orbit_sensitivity(b, at, &[], &opts).unwrap();
        let lerp = 0.5 * (b.points[i].amplitude1_alpha + b.points[i + 1].amplitude1_alpha);
        let (e_at, e_lerp) = (
            (v.amplitude1_alpha - o.amplitude1_alpha).abs(),
            (lerp - o.amplitude1_alpha).abs(),
        );
        println!("|orbit_at − orbit_on_branch| {e_at:.3e}, |interpolation − it| {e_lerp:.3e}");
        assert_eq!(v.u, u);
        assert!(e_at < 1e-8 * o.amplitude1_alpha, "{v:?} vs {o:?}");
        assert!((v.frequency_hz - o.omega / std::f64::consts::TAU).abs() < 1e-8);
        assert_eq!(v, sens.orbit);
        assert!(e_lerp > 100.0 * e_at, "{e_lerp} vs {e_at}");
    }

    /// The derivative of the orbit at a fixed speed with respect to the quintic equals the
    /// central difference of the orbits of the two sections built with k₅ ± 0.1 % at that
    /// speed (each continued from scratch) to 1e-5 relative (measured 7e-7) and in frequency to
    /// 1e-4 (5e-6); at a fixed amplitude the speed's derivative equals theirs to 2e-3 (4e-4:
    /// their speed is interpolated linearly between branch points).
    #[test]
    fn sensitivities_match_differences_of_continued_orbits() {
        let opts = BranchOptions {
            method: BranchMethod::HarmonicBalance,
            ..BranchOptions::default()
        };
        let k = hp1_structure().k_alpha;
        let s0 = section(20.0);
        let set = s0.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
        let b = &set.branches[0];
        let fold = b.events[0].index;
        // a stable point above the fold: its segment and speed
        let i = fold + 3;
        let u = 0.5 * (b.points[i].u + b.points[i + 1].u);
        assert!(b.points[i].stable && b.points[i + 1].stable);
        let d = 0.001 * 20.0 * k;
        let plus = section(20.0 * 1.001);
        let sens = s0
            .orbit_sensitivity(
                b,
                SensitivityAt::Speed { index: i, u },
                &[(plus.clone(), d)],
                &opts,
            )
            .unwrap();
        let at = |s: &Section| {
            let set = s.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
            s.orbit_on_branch(&set.branches[0], u, true, &opts).unwrap()
        };
        let (op, om) = (at(&plus), at(&section(20.0 * 0.999)));
        let fd_a = (op.amplitude1_alpha - om.amplitude1_alpha) / (2.0 * d);
        let fd_h = (op.amplitude1_h - om.amplitude1_h) / (2.0 * d);
        let fd_f = (op.omega - om.omega) / std::f64::consts::TAU / (2.0 * d);
        let s = &sens.derivatives[0];
        println!(
            "dA/dk5: sensitivity {:.6e} central difference {fd_a:.6e}; dh {:.6e} {fd_h:.6e}; \
             df {:.6e} {fd_f:.6e}",
            s.amplitude1_alpha, s.amplitude1_h, s.frequency_hz
        );
        assert!(
            s.amplitude1_alpha < 0.0,
            "a harder quintic shrinks the cycle"
        );
        assert!(
            (s.amplitude1_alpha - fd_a).abs() < 1e-5 * fd_a.abs(),
            "{s:?} vs {fd_a}"
        );
        assert!(
            (s.amplitude1_h - fd_h).abs() < 1e-5 * fd_h.abs(),
            "{s:?} vs {fd_h}"
        );
        assert!(
            (s.frequency_hz - fd_f).abs() < 1e-4 * fd_f.abs(),
            "{s:?} vs {fd_f}"
        );
        assert_eq!(s.u, 0.0, "U held fixed");
        // fixed amplitude at the fold's neighbour: U moves, the amplitude does not
        let sa = s0
            .orbit_sensitivity(
                b,
                SensitivityAt::Amplitude { index: i },
                &[(plus, d)],
                &opts,
            )
            .unwrap();
        let du = sa.derivatives[0].u;
        // the same orbit amplitude's speed on the ±0.1 % sections: U where their stable
        // branch passes the amplitude of point i
        let speed_at = |s: &Section| {
            let set = s.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
            let a = sa.orbit.amplitude1_alpha;
            let w = set.branches[0]
                .points
                .windows(2)
                .find(|w| {
                    w[0].stable
                        && w[1].stable
                        && (w[0].amplitude1_alpha - a) * (w[1].amplitude1_alpha - a) <= 0.0
                })
                .unwrap()
                .to_vec();
            let f = (a - w[0].amplitude1_alpha) / (w[1].amplitude1_alpha - w[0].amplitude1_alpha);
            w[0].u + f * (w[1].u - w[0].u)
        };
        let fd_u =
            (speed_at(&section(20.0 * 1.001)) - speed_at(&section(20.0 * 0.999))) / (2.0 * d);
        println!("dU/dk5 at fixed amplitude: sensitivity {du:.6e} difference {fd_u:.6e}");
        assert!(
            du > 0.0,
            "a harder quintic needs more speed for the same cycle"
        );
        // the difference interpolates the branches linearly between points
        assert!((du - fd_u).abs() < 2e-3 * fd_u.abs(), "{du} vs {fd_u}");
    }

    /// A perturbed section with another set of terms (a different discretisation) is
    /// refused, naming the parameter; so is a zero step.
    #[test]
    fn a_perturbation_that_changes_the_unknowns_is_refused() {
        let opts = BranchOptions {
            method: BranchMethod::HarmonicBalance,
            ..BranchOptions::default()
        };
        let s0 = section(20.0);
        let set = s0.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
        let b = &set.branches[0];
        let mut even = s0.clone();
        add_poly_term(&mut even.structure.nonlinear.pitch_stiffness_terms, 2, 1.0);
        let at = SensitivityAt::Amplitude { index: 3 };
        let e = s0
            .orbit_sensitivity(b, at, &[(even, 1.0)], &opts)
            .unwrap_err();
        assert!(e.to_string().contains("unknowns"), "{e}");
        let e = s0
            .orbit_sensitivity(b, at, &[(s0.clone(), 0.0)], &opts)
            .unwrap_err();
        assert!(e.to_string().contains("non-zero"), "{e}");
        let e = s0
            .orbit_sensitivity(b, SensitivityAt::Amplitude { index: 10_000 }, &[], &opts)
            .unwrap_err();
        assert!(e.to_string().contains("names no"), "{e}");
    }
}
