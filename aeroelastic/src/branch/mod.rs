//! Limit-cycle branches by numerical continuation: Hopf points of the equilibrium, periodic
//! orbits continued in the wind speed U by pseudo-arclength from each Hopf point (stable and
//! unstable), their stability by Floquet multipliers, folds (saddle-node of cycles),
//! period-doubling and Neimark–Sacker points.
//!
//! Method (DECISIONS.md, "LCO branches by continuation"): single shooting. The unknowns
//! are the initial state z₀ (h, α, ḣ, α̇, lag states), the period T and U; the equations
//! are φ_T(z₀; U) − z₀ = 0 (periodicity, φ the flow of
//! [`SectionDynamics`](crate::dynamics::SectionDynamics) over one period by N fixed
//! classical RK4 steps), the phase condition α̇(0) = 0 (the orbit starts at a pitch
//! extremum) and the pseudo-arclength condition ⟨X − X_k, t_k⟩ = Δs in scaled
//! variables. Newton's Jacobian is built from finite-difference columns; its z₀ block is
//! the monodromy matrix, whose eigenvalues are the Floquet multipliers (one is the trivial
//! multiplier 1, removed as the one closest to 1).
//!
//! The equilibrium is the origin (every restoring and aerodynamic term of the section
//! vanishes there). Hopf points are the speeds where a complex pair of eigenvalues of the
//! Jacobian of [`SectionDynamics::rate`](crate::dynamics::SectionDynamics::rate) at the
//! origin crosses the imaginary axis; the branch starts from the Hopf eigenvector at a small
//! pitch amplitude.
//!
//! Models whose coefficients depend on the reduced frequency K = Bω/U (identified Eq. 19
//! law, [`crate::aero::NonlinearAero`]) are evaluated at the orbit's own K = B(2π/T)/U at
//! every Newton iterate ([`crate::aero::AeroModel::with_reduced_frequency`]); their Floquet multipliers
//! are those of the system with K frozen at the orbit's value.
//!
//! Units: U [m/s], T \[s\], ω [rad/s], h \[m\] positive down, α \[rad\] positive nose-up.
//!
//! Files: this one holds the results (Hopf points, branch points, events, branches) and the
//! driver ([`Section::lco_branches`], [`Section::orbit_on_branch`]); `options.rs` the
//! settings, `hopf.rs` the Hopf scan, `continuation.rs` the predictor–corrector,
//! `shooting.rs`, `harmonic.rs` and `condensed.rs` the orbit discretisations, `orbit.rs` and
//! `floquet.rs` an orbit's amplitudes and multipliers, `measured.rs` measured diagrams,
//! `lens.rs` the continuation in a parameter other than U ([`Section::continue_in`]),
//! `sensitivity.rs` an orbit's derivatives with respect to the section's parameters
//! ([`Section::orbit_sensitivity`]).

use crate::section::Section;
use crate::{Error, Result};

mod condensed;
mod continuation;
mod floquet;
mod harmonic;
mod hopf;
mod lens;
mod measured;
mod options;
mod orbit;
mod periodic;
mod sensitivity;
mod shooting;
mod types;

use continuation::{newton, problem};
pub use lens::{Lens, LensBranch, LensEnd, LensEvent, LensPoint, SectionParameter};
pub use measured::{
    covering_segment, measured_distance, measured_distances, parse_absence_arg,
    parse_measured_amplitudes, parse_measured_diagram, parse_onset_arg, predicted_at,
    read_measured_amplitudes, read_measured_diagram, Criticality, MeasuredAbsence,
    MeasuredAmplitude, MeasuredDiagram, MeasuredDistance, MeasuredOnset,
};
pub use options::{BranchMethod, BranchOptions};
use periodic::Closure;
pub use sensitivity::{OrbitSensitivity, SensitivityAt};
pub use types::{
    Branch, BranchEnd, BranchEvent, BranchPoint, BranchProgress, BranchSet, EventKind, HopfPoint,
    OrbitValues,
};

/// Largest number of harmonics of the harmonic balance (the limits table's entry).
pub use identify::limits::MAX_HARMONICS;

impl Section {
    /// Checks that the vector field is smooth enough for continuation: a sharp pitch
    /// freeplay is refused (Coulomb friction is always regularised, F_c tanh(v/ε)).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `structure.pitch_freeplay`.
    pub fn check_smooth(&self) -> Result<()> {
        if self.structure.nonlinear.pitch_freeplay > 0.0 {
            return Err(Error::param(
                "structure.pitch_freeplay",
                self.structure.nonlinear.pitch_freeplay,
                "a sharp freeplay gap is not differentiable: continuation of periodic orbits \
                 needs a smooth vector field; replace it by a smooth stiffness polynomial \
                 (e.g. the hardening terms of a fitted smoothed gap) or use time integration \
                 (`aeroform lco`)",
            ));
        }
        Ok(())
    }

    /// Hopf points in [`u_min`, `u_max`] and the branch of periodic orbits of each.
    ///
    /// # Errors
    /// [`Error::Numerical`] when there is no Hopf point in the range (the message gives
    /// the growth rate at both ends); otherwise as [`Section::continue_branch`].
    pub fn lco_branches(
        &self,
        u_min: f64,
        u_max: f64,
        opts: &BranchOptions,
        observer: &dyn Fn(BranchProgress),
    ) -> Result<BranchSet> {
        self.lco_branches_within(u_min, u_max, f64::INFINITY, opts, observer)
    }

    /// [`Section::lco_branches`] whose branches also stop where they pass `u_reach` [m/s]
    /// with increasing speed ([`Section::continue_branch_within`]); the Hopf points are
    /// searched in [`u_min`, `u_max`] as there. `u_reach = ∞` is [`Section::lco_branches`].
    ///
    /// # Errors
    /// As [`Section::lco_branches`].
    pub fn lco_branches_within(
        &self,
        u_min: f64,
        u_max: f64,
        u_reach: f64,
        opts: &BranchOptions,
        observer: &dyn Fn(BranchProgress),
    ) -> Result<BranchSet> {
        opts.check()?;
        self.check_smooth()?;
        let hopf_points = self.hopf_points(u_min, u_max, opts.n_scan)?;
        if hopf_points.is_empty() {
            let g0 = self.oscillatory_growth(u_min)?.0;
            let g1 = self.oscillatory_growth(u_max)?.0;
            return Err(Error::numerical(
                "branch",
                format!(
                    "no Hopf point in U = {u_min}…{u_max} m/s: the largest oscillatory growth \
                     rate is {g0:.4e} 1/s at {u_min} and {g1:.4e} 1/s at {u_max} (no sign \
                     change); widen the speed range"
                ),
            ));
        }
        let mut branches = Vec::new();
        for (i, h) in hopf_points.iter().enumerate() {
            let obs = |p: BranchProgress| observer(BranchProgress { branch: i, ..p });
            branches.push(self.continue_branch_within(h, u_min, u_max, u_reach, opts, &obs)?);
        }
        Ok(BranchSet {
            hopf_points,
            branches,
            options: *opts,
            u_range: [u_min, u_max],
        })
    }

    /// The periodic orbit at speed `u` [m/s] on `branch`, of the given stability: the
    /// first branch segment of that stability whose speeds bracket `u` gives the initial
    /// guess (linear interpolation), Newton at fixed U corrects it.
    ///
    /// # Errors
    /// [`Error::Numerical`] when no such segment brackets `u` or Newton fails.
    pub fn orbit_on_branch(
        &self,
        branch: &Branch,
        u: f64,
        stable: bool,
        opts: &BranchOptions,
    ) -> Result<BranchPoint> {
        let sh = problem(self, opts, &branch.scales, &branch.hopf);
        let sh = sh.as_ref();
        let seg = branch.points.windows(2).find(|w| {
            w[0].stable == stable
                && w[1].stable == stable
                && (w[0].u - u) * (w[1].u - u) <= 0.0
                && w[0].u != w[1].u
        });
        let w = seg.ok_or_else(|| {
            Error::numerical(
                "orbit_on_branch",
                format!(
                    "no {} segment of the branch from the Hopf point at {:.4} m/s covers U = {u} m/s",
                    if stable { "stable" } else { "unstable" },
                    branch.hopf.u
                ),
            )
        })?;
        let f = (u - w[0].u) / (w[1].u - w[0].u);
        let y = sh.scaled(&w[0])? * (1.0 - f) + sh.scaled(&w[1])? * f;
        let m = sh.unknowns();
        let c = Closure::Speed(u / sh.scales()[m - 1]);
        let (y, j, _, _) = newton(sh, y, &c, None, opts.newton_tol, 3 * opts.max_newton)?;
        sh.point(&y, &j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lco::LcoOptions;
    use crate::reference::{hp1_cubic_pitch, hp1_structure};
    use crate::structure::PolyTerm;

    fn no_obs(_: BranchProgress) {}

    #[test]
    fn freeplay_is_refused_with_the_field_name() {
        let mut s = hp1_cubic_pitch();
        s.structure.nonlinear.pitch_freeplay = 0.01;
        let e = s
            .lco_branches(1.0, 3.0, &BranchOptions::default(), &no_obs)
            .unwrap_err();
        assert!(e.to_string().contains("pitch_freeplay"), "{e}");
    }

    #[test]
    fn no_hopf_point_in_range_is_an_error() {
        let s = hp1_cubic_pitch();
        let e = s
            .lco_branches(0.5, 1.5, &BranchOptions::default(), &no_obs)
            .unwrap_err();
        assert!(e.to_string().contains("no Hopf point"), "{e}");
    }

    /// Supercritical reference: the cubic-pitch-spring HP-1 section of the LCO benchmark.
    /// Stable amplitudes equal long Dop853 time integration (rtol 1e-10) to 0.1 %, and
    /// the onset follows U − U_F ∝ A² (log-log slope 2 over the first orbits).
    #[test]
    fn supercritical_branch_matches_time_integration() {
        supercritical(&BranchOptions::default());
    }

    /// The same reference by harmonic balance (5 harmonics).
    #[test]
    fn supercritical_branch_by_harmonic_balance_matches_time_integration() {
        supercritical(&BranchOptions {
            method: BranchMethod::HarmonicBalance,
            ..BranchOptions::default()
        });
    }

    fn supercritical(opts: &BranchOptions) {
        let opts = *opts;
        let s = hp1_cubic_pitch();
        let set = s.lco_branches(1.5, 3.0, &opts, &no_obs).unwrap();
        let b = &set.branches[0];
        assert_eq!(b.criticality, "supercritical");
        assert!(b.events.is_empty(), "{:?}", b.events);
        assert!(b.points.iter().all(|p| p.stable && p.u >= b.hopf.u));
        // √(U − U_F) onset.
        let uf = b.hopf.u;
        let (p0, p1) = (&b.points[0], &b.points[1]);
        let slope =
            ((p1.u - uf) / (p0.u - uf)).ln() / (p1.amplitude_alpha / p0.amplitude_alpha).ln();
        println!("supercritical onset: log-log slope of U − U_F vs A = {slope:.4}");
        assert!((slope - 2.0).abs() < 0.02, "slope {slope}");
        let lo = LcoOptions::default();
        for f in [1.1, 1.3] {
            let u = f * uf;
            let orbit = s.orbit_on_branch(b, u, true, &opts).unwrap();
            let mut y0 = orbit.state.clone();
            y0[1] *= 1.05;
            let r = s.lco_run(u, &y0, &lo).unwrap();
            assert_eq!(r.classification, crate::lco::Classification::Lco);
            let rel = (orbit.amplitude_alpha - r.amplitude_alpha).abs() / r.amplitude_alpha;
            println!(
                "supercritical U = {u:.5}: branch {:.7} time integration {:.7} rad, rel {rel:.2e}",
                orbit.amplitude_alpha, r.amplitude_alpha
            );
            assert!(
                rel < 1e-3,
                "U = {u}: branch {} vs time integration {} ({rel:.2e})",
                orbit.amplitude_alpha,
                r.amplitude_alpha
            );
            let relw = (orbit.omega - r.omega).abs() / r.omega;
            assert!(relw < 1e-3, "ω {} vs {}", orbit.omega, r.omega);
        }
    }

    /// HP-1 with the softening–hardening pitch spring k_α(α − 3α³ + 20α⁵).
    pub(crate) fn hp1_soft_hard() -> Section {
        let mut s = hp1_cubic_pitch();
        let k = hp1_structure().k_alpha;
        s.structure.nonlinear.pitch_stiffness_terms = vec![
            PolyTerm {
                power: 3,
                coefficient: -3.0 * k,
            },
            PolyTerm {
                power: 5,
                coefficient: 20.0 * k,
            },
        ];
        s
    }

    /// Subcritical reference: a fold below the flutter speed, the unstable branch leaves
    /// the Hopf point, the stable branch above the fold matches a downward time-integration
    /// sweep to 0.1 %.
    #[test]
    fn subcritical_branch_has_a_fold_and_matches_down_sweep() {
        subcritical(&BranchOptions::default());
    }

    /// The same reference by harmonic balance (5 harmonics).
    #[test]
    fn subcritical_branch_by_harmonic_balance_has_a_fold_and_matches_down_sweep() {
        subcritical(&BranchOptions {
            method: BranchMethod::HarmonicBalance,
            ..BranchOptions::default()
        });
    }

    /// A branch stopped at a reach is the whole branch up to it, orbit for orbit (bit for
    /// bit), ending where it first passes the reach with increasing speed: on the
    /// subcritical reference, whose stable branch turns up at its fold and runs past the
    /// Hopf speed.
    #[test]
    fn a_branch_stopped_at_its_reach_is_the_whole_branch_up_to_it() {
        let opts = BranchOptions {
            method: BranchMethod::HarmonicBalance,
            ..BranchOptions::default()
        };
        let s = hp1_soft_hard();
        let whole = s.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
        let b = &whole.branches[0];
        let reach = b.hopf.u * 1.05;
        let cut = s
            .lco_branches_within(1.0, 3.0, reach, &opts, &no_obs)
            .unwrap();
        let c = &cut.branches[0];
        let n = c.points.len();
        assert!(n >= 5 && n < b.points.len(), "{n} of {}", b.points.len());
        for (p, q) in c.points.iter().zip(&b.points) {
            assert_eq!(p.unknowns, q.unknowns);
            assert_eq!(p.multipliers, q.multipliers);
        }
        // the whole branch's next orbit is the first beyond the reach, moving up
        let next = &b.points[n];
        assert!(next.u > reach && next.u > b.points[n - 1].u, "{next:?}");
        assert!(c.points.iter().all(|p| p.u <= reach));
        match c.stop {
            BranchEnd::SpeedRange { u } => assert!((u - next.u).abs() < 1e-9 * u, "{u}"),
            ref e => panic!("{e:?}"),
        }
        assert_eq!(c.events, b.events[..c.events.len()]);
        // an infinite reach is the whole branch
        let all = s
            .lco_branches_within(1.0, 3.0, f64::INFINITY, &opts, &no_obs)
            .unwrap();
        assert_eq!(all.branches[0].points.len(), b.points.len());
    }

    fn subcritical(opts: &BranchOptions) {
        let opts = *opts;
        let s = hp1_soft_hard();
        let set = s.lco_branches(1.0, 3.0, &opts, &no_obs).unwrap();
        let b = &set.branches[0];
        assert_eq!(b.criticality, "subcritical");
        let uf = b.hopf.u;
        // The unstable branch joins the Hopf point.
        let p0 = &b.points[0];
        assert!(!p0.stable && p0.u < uf && uf - p0.u < 1e-3 * uf, "{p0:?}");
        assert!(p0.amplitude_alpha < 1.1e-3);
        let folds: Vec<_> = b
            .events
            .iter()
            .filter(|e| e.kind == EventKind::Fold)
            .collect();
        assert_eq!(folds.len(), 1, "{:?}", b.events);
        let fold = folds[0];
        assert!(fold.u < uf, "fold {} vs Hopf {uf}", fold.u);
        // Stability changes at the fold.
        assert!(!b.points[fold.index - 1].stable || !b.points[fold.index - 2].stable);
        assert!(
            b.points[fold.index + 1].stable,
            "{:?}",
            b.points[fold.index + 1]
        );
        // Downward sweep of time integration from a large perturbation above U_F.
        let u_test = [uf * 1.02, 0.5 * (fold.u + uf), fold.u + 0.2 * (uf - fold.u)];
        let h = s
            .lco_sweep(
                &u_test,
                crate::lco::SweepDirection::Down,
                &s.perturbation(0.3),
                &LcoOptions::default(),
                &crate::lco::KIteration::default(),
                &|_| {},
            )
            .unwrap();
        for r in &h {
            if r.u > uf {
                continue;
            }
            assert_eq!(r.classification, crate::lco::Classification::Lco, "{r:?}");
            let orbit = s.orbit_on_branch(b, r.u, true, &opts).unwrap();
            let rel = (orbit.amplitude_alpha - r.amplitude_alpha).abs() / r.amplitude_alpha;
            println!(
                "subcritical U = {:.5} (fold {:.5}, Hopf {uf:.5}): branch {:.7} down-sweep {:.7} rad, rel {rel:.2e}",
                r.u, fold.u, orbit.amplitude_alpha, r.amplitude_alpha
            );
            assert!(
                rel < 1e-3,
                "U = {}: branch {} vs down-sweep {} ({rel:.2e})",
                r.u,
                orbit.amplitude_alpha,
                r.amplitude_alpha
            );
        }
    }
}
