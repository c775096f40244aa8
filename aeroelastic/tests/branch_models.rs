//! LCO branches by continuation on the structural nonlinearity and the aerodynamic model
//! that the unit tests of `aeroelastic::branch` do not cover: regularised Coulomb friction
//! in pitch, and an identified Eq. 19 law whose coefficients depend on the reduced
//! frequency K (the branch evaluates them at each orbit's own K; the time integration
//! iterates K to the cycle's frequency). Each stable branch orbit is compared with a time
//! integration started near it, to 0.1 % in amplitude and frequency (issue 11).

use std::sync::Arc;

use aeroelastic::branch::{BranchMethod, BranchOptions, BranchProgress};
use aeroelastic::lco::{Classification, KIteration, LcoOptions};
use aeroelastic::reference::hp1_cubic_pitch;
use aeroelastic::section::Section;
use aeroelastic::structure::Friction;

fn no_obs(_: BranchProgress) {}

/// Branch orbit at `u` (continued with `opts`) against a (K-iterated when the model depends on K) time
/// integration started from the orbit with its pitch raised 5 %; returns the relative
/// amplitude difference.
fn check_with(s: &Section, b: &aeroelastic::branch::Branch, u: f64, opts: &BranchOptions) -> f64 {
    let orbit = s.orbit_on_branch(b, u, true, opts).expect("orbit");
    let mut y0 = orbit.state.clone();
    y0[1] *= 1.05;
    let r = s
        .lco_run_k(u, &y0, &LcoOptions::default(), &KIteration::default())
        .expect("time integration");
    assert_eq!(r.classification, Classification::Lco, "U = {u}: {r:?}");
    let rel = (orbit.amplitude_alpha - r.amplitude_alpha).abs() / r.amplitude_alpha;
    let relw = (orbit.omega - r.omega).abs() / r.omega;
    println!(
        "U = {u:.4}: branch {:.6}° ω {:.5}, time integration {:.6}° ω {:.5}; rel {rel:.2e} / {relw:.2e}",
        orbit.amplitude_alpha.to_degrees(),
        orbit.omega,
        r.amplitude_alpha.to_degrees(),
        r.omega
    );
    assert!(relw < 1e-3, "U = {u}: ω {} vs {}", orbit.omega, r.omega);
    rel
}

/// HP-1 with the cubic pitch spring and a Coulomb friction moment in pitch T_c (1 % of the
/// linear pitch moment at 1 rad), regularised T_c tanh(α̇/ε) with ε set so that the slope
/// at α̇ = 0 is a damping ratio of 2 % on the pitch mode. (With the default smoothing,
/// a damping ratio of 5, the equilibrium is stable over the whole range and there is no
/// Hopf point to start from: `lco_branches` says so, see `default_smoothing_has_no_hopf`.)
fn hp1_cubic_pitch_friction() -> (Section, Section) {
    let base = hp1_cubic_pitch();
    let mut st = base.structure.clone();
    let t_c = 0.01 * st.k_alpha;
    let zeta = 0.02;
    let eps = t_c / (2.0 * zeta * (st.k_alpha * st.inertia_alpha).sqrt());
    st.nonlinear.friction = Some(Friction {
        heave_force: 0.0,
        pitch_moment: t_c,
        heave_smoothing: None,
        pitch_smoothing: Some(eps),
    });
    let s = Section::new(st, Arc::clone(&base.aero), base.rho).expect("section");
    (base, s)
}

/// The stable orbits of the friction branch match time integration to 0.1 %, by shooting
/// and by harmonic balance (the tanh of the regularised friction needs more harmonics than
/// a polynomial spring: 9).
#[test]
fn friction_branch_matches_time_integration() {
    friction_branch(&BranchOptions::default());
    friction_branch(&BranchOptions {
        method: BranchMethod::HarmonicBalance,
        harmonics: 9,
        ..BranchOptions::default()
    });
}

fn friction_branch(opts: &BranchOptions) {
    let (_, s) = hp1_cubic_pitch_friction();
    let set = s.lco_branches(1.5, 4.0, opts, &no_obs).expect("branches");
    assert!(!set.branches.is_empty());
    let b = &set.branches[0];
    let stable: Vec<_> = b.points.iter().filter(|p| p.stable).collect();
    assert!(
        stable.len() >= 10,
        "{} stable points, stop {:?}",
        stable.len(),
        b.stop
    );
    let (u0, u1) = (stable[0].u, stable[stable.len() - 1].u);
    let mut worst: f64 = 0.0;
    for f in [0.25, 0.5, 0.75] {
        worst = worst.max(check_with(&s, b, u0 + f * (u1 - u0), opts));
    }
    assert!(
        worst < 1e-3,
        "{:?}: largest amplitude difference {worst:.2e}",
        opts.method
    );
}

/// The friction branch differs from the friction-free one (the test above would pass
/// trivially if friction were ignored): at the same speed the amplitudes differ.
#[test]
fn friction_changes_the_branch() {
    let (base, s) = hp1_cubic_pitch_friction();
    let opts = BranchOptions::default();
    let bf = s.lco_branches(1.5, 4.0, &opts, &no_obs).expect("friction");
    let b0 = base.lco_branches(1.5, 4.0, &opts, &no_obs).expect("free");
    let u = 1.2 * bf.branches[0].hopf.u;
    let a0 = base
        .orbit_on_branch(&b0.branches[0], u, true, &opts)
        .expect("orbit")
        .amplitude_alpha;
    let af = s
        .orbit_on_branch(&bf.branches[0], u, true, &opts)
        .expect("orbit")
        .amplitude_alpha;
    println!("U = {u:.4}: without friction {a0:.6} rad, with {af:.6} rad");
    assert!((a0 - af).abs() / a0 > 1e-2, "{a0} vs {af}");
}

/// With the default smoothing (slope = damping ratio 5) friction holds the equilibrium
/// stable in the whole range: a clear error that names the missing Hopf point.
#[test]
fn default_smoothing_has_no_hopf() {
    let base = hp1_cubic_pitch();
    let mut st = base.structure.clone();
    st.nonlinear.friction = Some(Friction {
        heave_force: 0.0,
        pitch_moment: 0.01 * st.k_alpha,
        heave_smoothing: None,
        pitch_smoothing: None,
    });
    let s = Section::new(st, Arc::clone(&base.aero), base.rho).expect("section");
    let e = s
        .lco_branches(1.5, 4.0, &BranchOptions::default(), &no_obs)
        .unwrap_err();
    assert!(e.to_string().contains("no Hopf point"), "{e}");
}
