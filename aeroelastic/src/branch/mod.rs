//! Limit-cycle branches by numerical continuation: Hopf points of the equilibrium, periodic
//! orbits continued in the wind speed U by pseudo-arclength from each Hopf point (stable and
//! unstable), their stability by Floquet multipliers, folds (saddle-node of cycles),
//! period-doubling and Neimark–Sacker points.
//!
//! Method (DECISIONS.md, "LCO branches by continuation"): single shooting. The unknowns
//! are the initial state z₀ (h, α, ḣ, α̇, lag states), the period T and U; the equations
//! are φ_T(z₀; U) − z₀ = 0 (periodicity, φ the flow of [`SectionDynamics`] over one period
//! by N fixed classical RK4 steps), the phase condition α̇(0) = 0 (the orbit starts at a
//! pitch extremum) and the pseudo-arclength condition ⟨X − X_k, t_k⟩ = Δs in scaled
//! variables. Newton's Jacobian is built from finite-difference columns; its z₀ block is
//! the monodromy matrix, whose eigenvalues are the Floquet multipliers (one is the trivial
//! multiplier 1, removed as the one closest to 1).
//!
//! The equilibrium is the origin (every restoring and aerodynamic term of the section
//! vanishes there). Hopf points are the speeds where a complex pair of eigenvalues of the
//! Jacobian of [`SectionDynamics::rate`] at the origin crosses the imaginary axis; the
//! branch starts from the Hopf eigenvector at a small pitch amplitude.
//!
//! Models whose coefficients depend on the reduced frequency K = Bω/U (identified Eq. 19
//! law, [`crate::aero::NonlinearAero`]) are evaluated at the orbit's own K = B(2π/T)/U at
//! every Newton iterate ([`crate::aero::AeroModel::with_reduced_frequency`]); their Floquet multipliers
//! are those of the system with K frozen at the orbit's value.
//!
//! Units: U [m/s], T \[s\], ω [rad/s], h \[m\] positive down, α \[rad\] positive nose-up.

use identify::numerics::interp::lagrange;
use nalgebra::{DMatrix, DVector, Dyn};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::dynamics::SectionDynamics;
use crate::flutter::{eigenvalues, eigenvector};
use crate::integrate::Rk4;
use crate::section::Section;
use crate::{Error, Result};

mod condensed;
mod harmonic;

/// Settings of the continuation. Scaled variables: the state is divided by
/// `amplitude_scale` times the Hopf eigenvector's magnitude of each component (pitch
/// normalised to 1), T by 0.1 T_Hopf, U by 0.1 U_Hopf; Δs is measured in these units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchOptions {
    /// How each periodic orbit is discretised (DECISIONS.md: harmonic balance is the
    /// faster, shooting the reference).
    #[serde(default)]
    pub method: BranchMethod,
    /// Harmonics H of the harmonic-balance series (ignored by shooting).
    #[serde(default = "default_harmonics")]
    pub harmonics: usize,
    /// Fixed steps per period: RK4 steps of the shooting integration, or the steps of the
    /// variational equation that gives harmonic balance its Floquet multipliers (RK4, or
    /// the exponential trapezoidal rule of the condensed form for linear aerodynamics).
    pub steps_per_period: usize,
    /// Largest number of branch points per Hopf point.
    pub max_points: usize,
    /// Initial arclength step (scaled).
    pub ds: f64,
    /// Smallest arclength step before the branch is declared not converging.
    pub ds_min: f64,
    /// Largest arclength step.
    pub ds_max: f64,
    /// Newton tolerance on the scaled residual (max norm).
    pub newton_tol: f64,
    /// Newton iterations per point before the step is halved.
    pub max_newton: usize,
    /// Pitch amplitude of the first orbit, started from the Hopf eigenvector \[rad\].
    pub start_amplitude: f64,
    /// Reference pitch amplitude of the scaling \[rad\].
    pub amplitude_scale: f64,
    /// The branch stops when the pitch amplitude exceeds this \[rad\].
    pub max_amplitude_alpha: f64,
    /// Speeds of the Hopf scan over the range (sign of det(2A⊙I); each bracket then solved
    /// by regula falsi).
    pub n_scan: usize,
}

/// Discretisation of the periodic orbits of a branch.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum BranchMethod {
    /// Single shooting: the flow over one period by fixed RK4 steps; multipliers from the
    /// finite-difference monodromy matrix.
    #[default]
    Shooting,
    /// Harmonic balance (AFT) with `harmonics` harmonics; multipliers from the variational
    /// equation along the series. With linear aerodynamics independent of K it is condensed
    /// onto heave and pitch (DECISIONS.md).
    HarmonicBalance,
}

impl std::str::FromStr for BranchMethod {
    type Err = Error;

    /// A method by its serde name, `shooting` or `harmonic_balance` (`-` read as `_`).
    ///
    /// # Errors
    /// [`Error::Toml`] (source `method`) naming the unknown value and the known ones.
    fn from_str(s: &str) -> Result<Self> {
        use serde::de::IntoDeserializer;
        let name = s.replace('-', "_");
        let d: serde::de::value::StrDeserializer<serde::de::value::Error> =
            name.as_str().into_deserializer();
        Self::deserialize(d).map_err(|e| Error::Toml {
            source_name: "method".into(),
            message: e.to_string(),
        })
    }
}

/// Largest number of harmonics of the harmonic balance (the limits table's entry).
pub use identify::limits::MAX_HARMONICS;

fn default_harmonics() -> usize {
    5
}

impl Default for BranchOptions {
    fn default() -> Self {
        BranchOptions {
            method: BranchMethod::default(),
            harmonics: default_harmonics(),
            steps_per_period: 128,
            max_points: 200,
            ds: 0.05,
            ds_min: 1e-5,
            ds_max: 0.5,
            newton_tol: 1e-9,
            max_newton: 8,
            start_amplitude: 1e-3,
            amplitude_scale: 0.05,
            max_amplitude_alpha: 0.6,
            n_scan: 200,
        }
    }
}

impl BranchOptions {
    /// Checks the options.
    ///
    /// Counts are capped by the limits table (`identify::limits`: steps per period, points,
    /// scan speeds, Newton iterations, harmonics) so that no request allocates without bound.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad option and its allowed range.
    pub fn check(&self) -> Result<()> {
        use crate::error::positive;
        positive("branch.ds", self.ds)?;
        positive("branch.ds_min", self.ds_min)?;
        positive("branch.ds_max", self.ds_max)?;
        positive("branch.newton_tol", self.newton_tol)?;
        positive("branch.start_amplitude", self.start_amplitude)?;
        positive("branch.amplitude_scale", self.amplitude_scale)?;
        positive("branch.max_amplitude_alpha", self.max_amplitude_alpha)?;
        if self.ds_min > self.ds || self.ds > self.ds_max {
            return Err(Error::param(
                "branch.ds",
                self.ds,
                format!(
                    "must lie in [ds_min, ds_max] = [{}, {}]",
                    self.ds_min, self.ds_max
                ),
            ));
        }
        use identify::limits as l;
        for (name, v, min, max) in [
            (
                "branch.steps_per_period",
                self.steps_per_period,
                16,
                l::MAX_STEPS_PER_PERIOD,
            ),
            (
                "branch.max_points",
                self.max_points,
                2,
                l::MAX_BRANCH_POINTS,
            ),
            (
                "branch.max_newton",
                self.max_newton,
                2,
                l::MAX_NEWTON_ITERATIONS,
            ),
            ("branch.n_scan", self.n_scan, 2, l::MAX_SCAN_SPEEDS),
            ("branch.harmonics", self.harmonics, 1, MAX_HARMONICS),
        ] {
            if v < min || v > max {
                return Err(Error::param(
                    name,
                    v as f64,
                    format!("must lie in {min} … {max}"),
                ));
            }
        }
        Ok(())
    }
}

/// A Hopf point of the equilibrium: a complex pair λ = σ ± iω crosses σ = 0 at U.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HopfPoint {
    /// Wind speed [m/s].
    pub u: f64,
    /// Frequency of the crossing pair [rad/s].
    pub omega: f64,
    /// dσ/dU at the crossing [1/m]: > 0 when the equilibrium loses stability with
    /// increasing U (flutter onset), < 0 when it regains it.
    pub dsigma_du: f64,
    /// Hopf eigenvector, pitch component normalised to 1: (re, im) of each state.
    #[serde(skip)]
    pub eigenvector: Vec<Complex64>,
}

/// Kind of a bifurcation of the periodic orbits found on a branch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// Turning point in U (saddle-node of cycles): a Floquet multiplier crosses +1.
    Fold,
    /// A real Floquet multiplier crosses −1.
    PeriodDoubling,
    /// A complex pair of Floquet multipliers crosses the unit circle (torus).
    NeimarkSacker,
    /// A real multiplier crosses +1 without a turning point (branch point of cycles).
    BranchPoint,
}

/// A bifurcation located between two consecutive branch points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchEvent {
    /// Kind.
    pub kind: EventKind,
    /// Speed [m/s] (folds: vertex of the parabola U(s) through three points; others: the
    /// point after the crossing).
    pub u: f64,
    /// Pitch amplitude (half peak-to-peak) there \[rad\].
    pub amplitude_alpha: f64,
    /// Heave amplitude (half peak-to-peak) there \[m\].
    pub amplitude_h: f64,
    /// Index of the branch point after the crossing.
    pub index: usize,
}

/// One periodic orbit on a branch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchPoint {
    /// Wind speed [m/s].
    pub u: f64,
    /// Period T \[s\].
    pub period: f64,
    /// Frequency ω = 2π/T [rad/s].
    pub omega: f64,
    /// Pitch amplitude, half peak-to-peak \[rad\] (as the time-integration LCO runs report).
    pub amplitude_alpha: f64,
    /// Heave amplitude, half peak-to-peak \[m\].
    pub amplitude_h: f64,
    /// First-harmonic pitch amplitude \[rad\] (as the measured tables report).
    pub amplitude1_alpha: f64,
    /// First-harmonic heave amplitude \[m\].
    pub amplitude1_h: f64,
    /// Largest modulus of the non-trivial Floquet multipliers.
    pub max_floquet: f64,
    /// Stable orbit (every non-trivial multiplier inside the unit circle).
    pub stable: bool,
    /// Non-trivial Floquet multipliers (re, im).
    pub multipliers: Vec<[f64; 2]>,
    /// A state on the orbit: z₀ at t = 0 (shooting: α̇ = 0, a pitch extremum; harmonic
    /// balance: the phase where the first pitch harmonic is a cosine).
    pub state: Vec<f64>,
    /// The continuation's scaled unknowns of this orbit (method-specific; not written).
    #[serde(skip)]
    #[schemars(skip)]
    pub unknowns: Vec<f64>,
}

/// Why a branch ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum StopReason {
    /// U left the requested range.
    SpeedRange {
        /// Speed of the first point outside [m/s].
        u: f64,
    },
    /// The pitch amplitude exceeded `max_amplitude_alpha`.
    Amplitude {
        /// Amplitude reached \[rad\].
        amplitude_alpha: f64,
    },
    /// The branch came back to the equilibrium (another Hopf point).
    Equilibrium {
        /// Speed [m/s].
        u: f64,
    },
    /// `max_points` reached.
    MaxPoints,
    /// Newton did not converge even with the smallest step.
    NotConverged {
        /// Speed of the last converged point [m/s].
        u: f64,
        /// Its pitch amplitude \[rad\].
        amplitude_alpha: f64,
        /// What failed.
        message: String,
    },
}

/// A continued branch of periodic orbits from one Hopf point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Branch {
    /// The Hopf point it starts from.
    pub hopf: HopfPoint,
    /// Orbits in continuation order.
    pub points: Vec<BranchPoint>,
    /// Folds, period doublings, Neimark–Sacker points.
    pub events: Vec<BranchEvent>,
    /// Why it ended.
    pub stop: StopReason,
    /// `supercritical` (stable cycles born towards U where the equilibrium is unstable)
    /// or `subcritical`, from the first continued orbits.
    pub criticality: String,
    /// Scale of each unknown (state, T, U) used by the continuation.
    pub scales: Vec<f64>,
}

/// All branches of a speed range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BranchSet {
    /// Hopf points in the range, increasing U.
    pub hopf_points: Vec<HopfPoint>,
    /// One branch per Hopf point.
    pub branches: Vec<Branch>,
    /// Settings.
    pub options: BranchOptions,
    /// Speed range [m/s].
    pub u_range: [f64; 2],
}

/// Progress report after each branch point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchProgress {
    /// Branch index.
    pub branch: usize,
    /// Points so far on this branch.
    pub points: usize,
    /// Speed of the last point [m/s].
    pub u: f64,
    /// Its pitch amplitude \[rad\].
    pub amplitude_alpha: f64,
}

/// Which extra equation closes the periodic-orbit system.
enum Closure<'a> {
    /// The pitch-amplitude unknown ([`PeriodicProblem::amplitude_index`]) equals the
    /// value (start from the Hopf point).
    Alpha(f64),
    /// Pseudo-arclength ⟨Y − Y_k, t_k⟩ = Δs.
    Arclength(&'a DVector<f64>, &'a DVector<f64>, f64),
    /// U fixed (scaled).
    Speed(f64),
}

/// A discretisation of the periodic orbits of a section: scaled unknowns Y whose last
/// component is U, and m − 1 equations G(Y) = 0 (periodicity and phase). The continuation
/// adds the m-th equation ([`Closure`]).
trait PeriodicProblem {
    /// Number of unknowns m (U last).
    fn unknowns(&self) -> usize;
    /// Index of the unknown fixed by [`Closure::Alpha`] (a pitch amplitude).
    fn amplitude_index(&self) -> usize;
    /// Scale of each unknown.
    fn scales(&self) -> &[f64];
    /// G(Y), m − 1 values.
    fn g(&self, y: &DVector<f64>) -> Result<DVector<f64>>;
    /// ∂G/∂Y at `y` given G(y), (m − 1) × m.
    fn jac(&self, y: &DVector<f64>, g0: &DVector<f64>) -> Result<DMatrix<f64>>;
    /// The converged orbit at `y` with its multipliers.
    fn point(&self, y: &DVector<f64>, jg: &DMatrix<f64>) -> Result<BranchPoint>;
    /// Whether [`PeriodicProblem::point`] needs ∂G/∂Y at the solution itself (shooting: its
    /// block is the monodromy matrix). When not, Newton hands on the Jacobian of its last
    /// refresh, within the Newton tolerance of the solution, for the tangent.
    fn jacobian_at_solution(&self) -> bool {
        true
    }
    /// Initial guess at pitch amplitude `a` \[rad\] from the Hopf eigenvector.
    fn start(&self, hopf: &HopfPoint, a: f64) -> DVector<f64>;
    /// Scaled unknowns of a point of a branch of this problem.
    fn scaled(&self, p: &BranchPoint) -> Result<DVector<f64>>;
}

/// The scaled unknowns a harmonic-balance point stored, when they belong to a problem of `m`
/// unknowns.
///
/// # Errors
/// [`Error::Numerical`] when they do not (a branch read back from `branch.json`, whose
/// points keep no coefficients, or one of another method).
fn stored_unknowns(p: &BranchPoint, m: usize) -> Result<DVector<f64>> {
    if p.unknowns.len() != m {
        return Err(Error::numerical(
            "orbit_on_branch",
            "the branch points carry no harmonic-balance coefficients of this problem (a \
             branch read back from branch.json, or of another method): continue the branch \
             again",
        ));
    }
    Ok(DVector::from_column_slice(&p.unknowns))
}

/// Scales of the shooting unknowns (z₀, T, U) of the branch from `hopf`: each state
/// component `amplitude_scale` \[rad\] times its Hopf-eigenvector magnitude (at least 1e-3
/// of the largest), T by 0.1 T_Hopf, U by 0.1 U_Hopf.
fn branch_scales(hopf: &HopfPoint, amplitude_scale: f64) -> Vec<f64> {
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
fn problem<'a>(
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
fn newton(
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
fn tangent(
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

/// One orbit of either discretisation as a [`BranchPoint`]: speed `u` [m/s], frequency
/// `omega` [rad/s], one period of (h, α) samples (half peak-to-peak amplitudes), the
/// first-harmonic amplitudes (h, α), the monodromy matrix, a state on the orbit and the
/// scaled unknowns.
fn orbit_point(
    u: f64,
    omega: f64,
    samples: &[[f64; 2]],
    first_harmonic: [f64; 2],
    monodromy: DMatrix<f64>,
    state: Vec<f64>,
    y: &DVector<f64>,
) -> Result<BranchPoint> {
    let (mu, max_floquet) = floquet(monodromy)?;
    Ok(BranchPoint {
        u,
        period: std::f64::consts::TAU / omega,
        omega,
        amplitude_alpha: half_peak_to_peak(samples, 1),
        amplitude_h: half_peak_to_peak(samples, 0),
        amplitude1_alpha: first_harmonic[1],
        amplitude1_h: first_harmonic[0],
        max_floquet,
        stable: max_floquet < 1.0,
        multipliers: mu.iter().map(|m| [m.re, m.im]).collect(),
        state,
        unknowns: y.iter().copied().collect(),
    })
}

/// The equilibrium Jacobian A(U) (row-major, [`Section::equilibrium_jacobian`]) as the
/// quadratic A₀ + U A₁ + U² A₂ through its values at `nodes`, when it is one: checked at a
/// fourth speed to 1e-8 of A's largest entry, and the total mass M_s − M_a the same at all
/// four (then (M_s − M_a)⁻¹ is constant too). Linear aerodynamic models in dimensional form
/// (Theodorsen, Theodorsen–Jones, RFA tables, quasi-steady) are exactly quadratic in U:
/// stiffness ∝ U², damping and lag rates ∝ U, apparent mass constant. `None` otherwise.
pub(crate) struct QuadraticJacobian {
    n: usize,
    coef: [Vec<f64>; 3],
}

impl QuadraticJacobian {
    pub(crate) fn fit(section: &Section, nodes: [f64; 3], check: f64) -> Result<Option<Self>> {
        let n = section.n_states();
        let jac = |u: f64| -> Result<Vec<f64>> {
            let mut a = vec![0.0; n * n];
            SectionDynamics::new(section, u)?.jacobian(
                &vec![0.0; n],
                &mut a,
                &mut vec![0.0; 3 * n],
            );
            Ok(a)
        };
        let m0 = section.total_mass(nodes[0]);
        for u in [nodes[1], nodes[2], check] {
            if (section.total_mass(u) - m0).amax() > 1e-12 * m0.amax() {
                return Ok(None);
            }
        }
        let vals = [jac(nodes[0])?, jac(nodes[1])?, jac(nodes[2])?];
        // Lagrange → monomial coefficients per entry.
        let [u0, u1, u2] = nodes;
        let d0 = (u0 - u1) * (u0 - u2);
        let d1 = (u1 - u0) * (u1 - u2);
        let d2 = (u2 - u0) * (u2 - u1);
        let mut coef = [vec![0.0; n * n], vec![0.0; n * n], vec![0.0; n * n]];
        for i in 0..n * n {
            let (y0, y1, y2) = (vals[0][i] / d0, vals[1][i] / d1, vals[2][i] / d2);
            coef[2][i] = y0 + y1 + y2;
            coef[1][i] = -(y0 * (u1 + u2) + y1 * (u0 + u2) + y2 * (u0 + u1));
            coef[0][i] = y0 * u1 * u2 + y1 * u0 * u2 + y2 * u0 * u1;
        }
        let q = QuadraticJacobian { n, coef };
        let direct = jac(check)?;
        let scale = direct.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut fitted = vec![0.0; n * n];
        q.at(check, &mut fitted);
        let exact = direct
            .iter()
            .zip(&fitted)
            .all(|(a, b)| (a - b).abs() <= 1e-8 * scale);
        Ok(exact.then_some(q))
    }

    /// dA/dU = A₁ + 2U A₂ into `a` (n × n row-major).
    pub(crate) fn derivative_at(&self, u: f64, a: &mut [f64]) {
        for (i, v) in a.iter_mut().enumerate().take(self.n * self.n) {
            *v = self.coef[1][i] + 2.0 * u * self.coef[2][i];
        }
    }

    /// A(U) into `a` (n × n row-major).
    pub(crate) fn at(&self, u: f64, a: &mut [f64]) {
        for (i, v) in a.iter_mut().enumerate().take(self.n * self.n) {
            *v = self.coef[0][i] + u * (self.coef[1][i] + u * self.coef[2][i]);
        }
    }
}

/// The bialternate product 2A⊙I of an n × n matrix with the identity, as the list of its
/// non-zero entries: eigenvalues λ_i + λ_j (i < j), so det(2A⊙I) vanishes where a complex
/// pair of A crosses the imaginary axis (Hopf) and not where a real eigenvalue crosses zero
/// (Govaerts 2000, Kuznetsov §10.2). Rows and columns are the pairs (p, q), p > q.
struct Bialternate {
    /// Order m = n(n − 1)/2.
    m: usize,
    /// (row · m + column, sign, first entry of A, second entry of A or usize::MAX).
    entries: Vec<(usize, f64, usize, usize)>,
}

impl Bialternate {
    fn new(n: usize) -> Self {
        let pairs: Vec<(usize, usize)> = (1..n).flat_map(|p| (0..p).map(move |q| (p, q))).collect();
        let m = pairs.len();
        let at = |r: usize, c: usize| r * n + c;
        let mut entries = Vec::new();
        for (i, &(p, q)) in pairs.iter().enumerate() {
            for (j, &(r, s)) in pairs.iter().enumerate() {
                let e = if r == q {
                    Some((-1.0, at(p, s), usize::MAX))
                } else if r != p && s == q {
                    Some((1.0, at(p, r), usize::MAX))
                } else if r == p && s == q {
                    Some((1.0, at(p, p), at(q, q)))
                } else if r == p && s != q {
                    Some((1.0, at(q, s), usize::MAX))
                } else if s == p {
                    Some((-1.0, at(q, r), usize::MAX))
                } else {
                    None
                };
                if let Some((sign, a1, a2)) = e {
                    entries.push((i * m + j, sign, a1, a2));
                }
            }
        }
        Bialternate { m, entries }
    }

    /// det(2A⊙I) for `a` (row-major) by Gaussian elimination with partial pivoting in
    /// `work` (m × m).
    fn determinant(&self, a: &[f64], work: &mut Vec<f64>) -> f64 {
        let m = self.m;
        work.clear();
        work.resize(m * m, 0.0);
        for &(k, sign, a1, a2) in &self.entries {
            work[k] = sign * a[a1] + if a2 == usize::MAX { 0.0 } else { a[a2] };
        }
        let b = work;
        let mut det = 1.0;
        for k in 0..m {
            let mut piv = k;
            for i in k + 1..m {
                if b[i * m + k].abs() > b[piv * m + k].abs() {
                    piv = i;
                }
            }
            if b[piv * m + k] == 0.0 {
                return 0.0;
            }
            if piv != k {
                for c in 0..m {
                    b.swap(k * m + c, piv * m + c);
                }
                det = -det;
            }
            let d = b[k * m + k];
            det *= d;
            let (top, rest) = b.split_at_mut((k + 1) * m);
            let pivot_row = &top[k * m + k + 1..(k + 1) * m];
            for row in rest.chunks_exact_mut(m) {
                let f = row[k] / d;
                if f != 0.0 {
                    for (x, p) in row[k + 1..].iter_mut().zip(pivot_row) {
                        *x -= f * p;
                    }
                }
            }
        }
        det
    }
}

/// Non-trivial Floquet multipliers of a monodromy matrix (the trivial multiplier 1 removed
/// as the eigenvalue closest to 1) and their largest modulus.
fn floquet(mono: DMatrix<f64>) -> Result<(Vec<Complex64>, f64)> {
    let mut mu = match mono.nrows() {
        6 => eigenvalues6(&mono)?,
        _ => eigenvalues(&mono)?,
    };
    if let Some((k, _)) = mu
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1 - 1.0).norm().total_cmp(&(b.1 - 1.0).norm()))
    {
        mu.remove(k);
    }
    let max_floquet = mu.iter().map(|m| m.norm()).fold(0.0, f64::max);
    Ok((mu, max_floquet))
}

/// Eigenvalues of a 6 × 6 matrix (two DOFs and two lag states, the common case) by the
/// fixed-size Schur decomposition: no allocation, the same algorithm as [`eigenvalues`].
fn eigenvalues6(a: &DMatrix<f64>) -> Result<Vec<Complex64>> {
    if a.iter().any(|v| !v.is_finite()) {
        return Err(Error::numerical(
            "eigenvalues",
            "non-finite monodromy matrix",
        ));
    }
    let m = nalgebra::Matrix6::<f64>::from_fn(|r, c| a[(r, c)]);
    let s = nalgebra::Schur::try_new(m, f64::EPSILON, 100_000)
        .ok_or_else(|| Error::numerical("eigenvalues", "Schur decomposition did not converge"))?;
    Ok(s.complex_eigenvalues().iter().copied().collect())
}

/// The shooting problem of one section in scaled unknowns Y = (z₀, T, U) / scales.
struct Shooting<'a> {
    section: &'a Section,
    n: usize,
    steps: usize,
    scales: Vec<f64>,
}

/// Result of one flow evaluation.
struct Flow {
    end: Vec<f64>,
    samples: Option<Vec<[f64; 2]>>,
}

impl<'a> Shooting<'a> {
    fn new(section: &'a Section, steps: usize, scales: Vec<f64>) -> Self {
        Shooting {
            section,
            n: section.n_states(),
            steps,
            scales,
        }
    }

    fn unscale(&self, y: &DVector<f64>) -> (Vec<f64>, f64, f64) {
        let n = self.n;
        let z = (0..n).map(|i| y[i] * self.scales[i]).collect();
        (z, y[n] * self.scales[n], y[n + 1] * self.scales[n + 1])
    }

    /// φ_T(z₀; U) by `steps` RK4 steps; with `record`, (h, α) at every step.
    fn flow(&self, z0: &[f64], t: f64, u: f64, record: bool) -> Result<Flow> {
        if !(t.is_finite() && t > 0.0 && u.is_finite() && u > 0.0) {
            return Err(Error::numerical(
                "shooting",
                format!("non-physical iterate T = {t} s, U = {u} m/s"),
            ));
        }
        // K-dependent models at the orbit's own K = B(2π/T)/U
        let k = self.section.aero.chord() * (std::f64::consts::TAU / t) / u;
        let rebuilt = self.section.at_reduced_frequency(k)?;
        let dynamics = SectionDynamics::new(rebuilt.as_ref().unwrap_or(self.section), u)?;
        let dt = t / self.steps as f64;
        let mut z = z0.to_vec();
        let mut work = Rk4::new(self.n);
        let mut samples = record.then(|| Vec::with_capacity(self.steps + 1));
        for _ in 0..self.steps {
            if let Some(s) = samples.as_mut() {
                s.push([z[0], z[1]]);
            }
            work.step(&dynamics, 0.0, dt, &mut z);
        }
        if z.iter().any(|v| !v.is_finite()) {
            return Err(Error::numerical(
                "shooting",
                format!("orbit integration overflowed at U = {u} m/s"),
            ));
        }
        Ok(Flow { end: z, samples })
    }
}

impl PeriodicProblem for Shooting<'_> {
    fn unknowns(&self) -> usize {
        self.n + 2
    }

    fn amplitude_index(&self) -> usize {
        1
    }

    fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// Periodicity and phase residuals (n + 1 values, scaled).
    fn g(&self, y: &DVector<f64>) -> Result<DVector<f64>> {
        let (z, t, u) = self.unscale(y);
        let f = self.flow(&z, t, u, false)?;
        let n = self.n;
        let mut g = DVector::zeros(n + 1);
        for i in 0..n {
            g[i] = (f.end[i] - z[i]) / self.scales[i];
        }
        g[n] = y[3];
        Ok(g)
    }

    /// Forward-difference Jacobian of G at `y` given G(y).
    fn jac(&self, y: &DVector<f64>, g0: &DVector<f64>) -> Result<DMatrix<f64>> {
        let m = self.n + 2;
        let mut j = DMatrix::zeros(self.n + 1, m);
        for c in 0..m {
            let d = 1e-7 * (1.0 + y[c].abs());
            let mut yp = y.clone();
            yp[c] += d;
            let gp = self.g(&yp)?;
            j.set_column(c, &((gp - g0) / d));
        }
        Ok(j)
    }

    /// The orbit at `y` (converged) with its multipliers from the Jacobian `jg`.
    fn point(&self, y: &DVector<f64>, jg: &DMatrix<f64>) -> Result<BranchPoint> {
        let (z, t, u) = self.unscale(y);
        let f = self.flow(&z, t, u, true)?;
        let s = f.samples.unwrap_or_default();
        // Monodromy in scaled variables: M_s = S⁻¹ (∂φ/∂z₀) S = J_zz + I (same spectrum).
        let n = self.n;
        let mut mono = jg.view((0, 0), (n, n)).into_owned();
        for i in 0..n {
            mono[(i, i)] += 1.0;
        }
        let a1 = [first_harmonic(&s, 0), first_harmonic(&s, 1)];
        orbit_point(u, std::f64::consts::TAU / t, &s, a1, mono, z, y)
    }

    fn start(&self, hopf: &HopfPoint, a: f64) -> DVector<f64> {
        let n = self.n;
        let mut y = DVector::zeros(n + 2);
        for i in 0..n {
            y[i] = a * hopf.eigenvector[i].re / self.scales[i];
        }
        y[3] = 0.0;
        y[n] = std::f64::consts::TAU / hopf.omega / self.scales[n];
        y[n + 1] = hopf.u / self.scales[n + 1];
        y
    }

    fn scaled(&self, p: &BranchPoint) -> Result<DVector<f64>> {
        let n = self.n;
        let mut y = DVector::zeros(n + 2);
        for i in 0..n {
            y[i] = p.state[i] / self.scales[i];
        }
        y[n] = p.period / self.scales[n];
        y[n + 1] = p.u / self.scales[n + 1];
        Ok(y)
    }
}

/// Half peak-to-peak of channel `c` of one period of samples, each extremum refined by the
/// parabola through the extreme sample and its two (periodic) neighbours.
fn half_peak_to_peak(s: &[[f64; 2]], c: usize) -> f64 {
    let n = s.len();
    if n < 3 {
        return 0.0;
    }
    let refine = |k: usize| {
        let (a, b, d) = (s[(k + n - 1) % n][c], s[k][c], s[(k + 1) % n][c]);
        let den = a - 2.0 * b + d;
        if den.abs() < 1e-300 {
            b
        } else {
            b - 0.125 * (d - a) * (d - a) / den
        }
    };
    let (mut kmax, mut kmin) = (0, 0);
    for k in 0..n {
        if s[k][c] > s[kmax][c] {
            kmax = k;
        }
        if s[k][c] < s[kmin][c] {
            kmin = k;
        }
    }
    0.5 * (refine(kmax) - refine(kmin))
}

/// First-harmonic amplitude |c₁| of channel `c` over one period of uniform samples:
/// (2/N)|Σ x_k e^{−2πik/N}| (exact for periodic signals up to aliasing).
fn first_harmonic(s: &[[f64; 2]], c: usize) -> f64 {
    let n = s.len() as f64;
    let (mut re, mut im) = (0.0, 0.0);
    for (k, v) in s.iter().enumerate() {
        let th = std::f64::consts::TAU * k as f64 / n;
        re += v[c] * th.cos();
        im -= v[c] * th.sin();
    }
    2.0 / n * (re * re + im * im).sqrt()
}

/// Vertex of the parabola through three points (s_i, u_i); returns (s*, u*).
fn parabola_vertex(s: [f64; 3], u: [f64; 3]) -> Option<(f64, f64)> {
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

    /// Jacobian of [`SectionDynamics::rate`] at the origin at speed `u` (central
    /// differences; consistent with the nonlinear rate, including regularised friction).
    ///
    /// # Errors
    /// As [`SectionDynamics::new`].
    pub fn equilibrium_jacobian(&self, u: f64) -> Result<DMatrix<f64>> {
        let d = SectionDynamics::new(self, u)?;
        let n = d.dim();
        let mut j = vec![0.0; n * n];
        d.jacobian(&vec![0.0; n], &mut j, &mut vec![0.0; 3 * n]);
        Ok(DMatrix::from_row_slice(n, n, &j))
    }

    /// Largest real part of the oscillatory eigenvalues (|Im| > 1e-6 ω_α) of the
    /// equilibrium at `u`, and the eigenvalue.
    fn oscillatory_growth(&self, u: f64) -> Result<(f64, Complex64)> {
        let jac = self.equilibrium_jacobian(u)?;
        let ev = match jac.nrows() {
            6 => eigenvalues6(&jac)?,
            _ => eigenvalues(&jac)?,
        };
        let floor = 1e-6 * self.structure.omega_alpha();
        ev.into_iter()
            .filter(|l| l.im > floor)
            .map(|l| (l.re, l))
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .ok_or_else(|| Error::numerical("hopf", format!("no oscillatory mode at U = {u}")))
    }

    /// The speed in [a, b] where the growth rate, of opposite signs `ga` and `gb` at the
    /// ends, vanishes: regula falsi with the Illinois modification (superlinear on the
    /// smooth growth rate, the bracket kept), to a bracket of 1e-12 U or a growth rate
    /// below 1e-15 ω_α.
    fn growth_root(&self, mut a: f64, mut ga: f64, mut b: f64, mut gb: f64) -> Result<f64> {
        let tiny = 1e-15 * self.structure.omega_alpha();
        let mut side = 0;
        for _ in 0..200 {
            if b - a <= 1e-12 * b {
                break;
            }
            let mut m = (a * gb - b * ga) / (gb - ga);
            if !(m > a && m < b) {
                m = 0.5 * (a + b);
            }
            let gm = self.oscillatory_growth(m)?.0;
            if gm.abs() <= tiny {
                return Ok(m);
            }
            if (gm < 0.0) == (ga < 0.0) {
                (a, ga) = (m, gm);
                if side == -1 {
                    gb *= 0.5;
                }
                side = -1;
            } else {
                (b, gb) = (m, gm);
                if side == 1 {
                    ga *= 0.5;
                }
                side = 1;
            }
        }
        Ok(if ga.abs() < gb.abs() { a } else { b })
    }

    /// Hopf points of the equilibrium in [`u_min`, `u_max`] [m/s]: the largest real part
    /// of the oscillatory eigenvalues of [`Section::equilibrium_jacobian`] is scanned at
    /// `n_scan` speeds and each sign change solved to 1e-12 U (Illinois regula falsi).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a bad range; as [`Section::equilibrium_jacobian`].
    pub fn hopf_points(&self, u_min: f64, u_max: f64, n_scan: usize) -> Result<Vec<HopfPoint>> {
        crate::error::positive("u_min", u_min)?;
        if !(u_max.is_finite() && u_max > u_min) {
            return Err(Error::param(
                "u_max",
                u_max,
                format!("must be > u_min = {u_min}"),
            ));
        }
        let n_scan = n_scan.max(2);
        let us: Vec<f64> = (0..n_scan)
            .map(|i| u_min + (u_max - u_min) * i as f64 / (n_scan - 1) as f64)
            .collect();
        // Scan the sign of det(2A⊙I) = Π_{i<j}(λ_i + λ_j), which changes where a complex
        // pair crosses the imaginary axis; the growth rate (eigenvalues) only at the ends of
        // brackets where it does. Its n(n − 1)/2 rows outgrow an eigenvalue problem beyond
        // n = 8 states: there the growth rate itself is scanned.
        let n = self.n_states();
        let (mut a, mut work, origin) = (vec![0.0; n * n], vec![0.0; 3 * n], vec![0.0; n]);
        let mut b = Vec::new();
        let bialternate = Bialternate::new(n);
        let mut psi = Vec::with_capacity(n_scan);
        let quadratic = if n <= 8 {
            QuadraticJacobian::fit(
                self,
                [u_min, 0.5 * (u_min + u_max), u_max],
                0.3 * u_min + 0.7 * u_max,
            )?
        } else {
            None
        };
        for &u in &us {
            psi.push(if n <= 8 {
                match &quadratic {
                    Some(q) => q.at(u, &mut a),
                    None => SectionDynamics::new(self, u)?.jacobian(&origin, &mut a, &mut work),
                }
                bialternate.determinant(&a, &mut b)
            } else {
                self.oscillatory_growth(u)?.0
            });
        }
        let mut out = Vec::new();
        for i in 1..n_scan {
            if (psi[i - 1] < 0.0) == (psi[i] < 0.0) && psi[i - 1] != 0.0 {
                continue;
            }
            let g = [
                self.oscillatory_growth(us[i - 1])?.0,
                self.oscillatory_growth(us[i])?.0,
            ];
            if (g[0] < 0.0) == (g[1] < 0.0) {
                continue;
            }
            let u = self.growth_root(us[i - 1], g[0], us[i], g[1])?;
            let (_, lam) = self.oscillatory_growth(u)?;
            let jac = self.equilibrium_jacobian(u)?;
            let v = eigenvector(&jac, lam);
            if v[1].norm() < 1e-8 * v.norm() {
                return Err(Error::numerical(
                    "hopf",
                    format!("Hopf mode at U = {u} m/s has no pitch motion"),
                ));
            }
            let v1 = v[1];
            let du = 1e-6 * u;
            let dsig = (self.oscillatory_growth(u + du)?.0 - self.oscillatory_growth(u - du)?.0)
                / (2.0 * du);
            out.push(HopfPoint {
                u,
                omega: lam.im,
                dsigma_du: dsig,
                eigenvector: v.iter().map(|c| c / v1).collect(),
            });
        }
        Ok(out)
    }

    /// Continues the periodic orbits born at `hopf` within [`u_min`, `u_max`] [m/s].
    /// `observer` receives a report after each point.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for bad options or a non-smooth structure
    /// ([`Section::check_smooth`]); [`Error::Numerical`] when not even the first orbits
    /// near the Hopf point converge (the message names the speed and amplitude). A branch
    /// that stops converging later ends with [`StopReason::NotConverged`] and keeps its
    /// points.
    pub fn continue_branch(
        &self,
        hopf: &HopfPoint,
        u_min: f64,
        u_max: f64,
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
                stop = StopReason::MaxPoints;
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
                        stop = StopReason::NotConverged {
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
                    stop = StopReason::NotConverged {
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
            let p = sh.point(&y, &j)?;
            if p.u < u_min || p.u > u_max {
                stop = StopReason::SpeedRange { u: p.u };
                break;
            }
            if p.amplitude_alpha > opts.max_amplitude_alpha {
                stop = StopReason::Amplitude {
                    amplitude_alpha: p.amplitude_alpha,
                };
                break;
            }
            if points.len() > 4 && p.amplitude_alpha < 0.5 * opts.start_amplitude {
                stop = StopReason::Equilibrium { u: p.u };
                break;
            }
            arc.push(arc.last().copied().unwrap_or(0.0) + (&y - &yk).norm());
            let prev = points.last().expect("two start points").clone();
            let k = points.len();
            points.push(p);
            ts.push(tn.clone());
            // Events between k−1 and k.
            let ui = sh.unknowns() - 1;
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
            branches.push(self.continue_branch(h, u_min, u_max, opts, &obs)?);
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

/// One measured point of a bifurcation diagram (a row of a table like
/// `bristol-spring1-lco-amplitudes.csv`, or a point extracted from an LCO record):
/// first-harmonic amplitudes and frequency of a periodic orbit at one speed. Any of the
/// amplitudes and the frequency may be missing (e.g. a heave-only table), not both
/// amplitudes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MeasuredAmplitude {
    /// Line in the file (1-based; 0 for a point extracted from a record).
    pub line: usize,
    /// Branch the point was measured on (`stable` / `unstable`).
    pub stable: bool,
    /// Wind speed [m/s].
    pub u: f64,
    /// First-harmonic heave amplitude \[m\] (peak), if measured.
    pub amplitude_h: Option<f64>,
    /// First-harmonic pitch amplitude \[rad\] (peak), if measured.
    pub amplitude_alpha: Option<f64>,
    /// Frequency of the orbit \[Hz\], if measured.
    #[serde(default)]
    pub frequency_hz: Option<f64>,
}

/// Reads a measured bifurcation diagram: CSV with a header naming `branch` (`stable` or
/// `unstable`), `wind_speed_m_s` and at least one of `heave_amp_m` \[m\] and `pitch_amp_rad`
/// \[rad\] (first-harmonic peak amplitudes), optionally `freq_hz` \[Hz\]; other columns are
/// ignored (the last column may contain commas); lines starting with `#` are comments. A
/// missing value is an empty field, `nan` or `-`; every row needs a speed and at least one
/// amplitude (docs/DATA_FORMAT.md, "Measured bifurcation diagram").
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::InvalidTable`] naming the file,
/// the line and the column for a missing column, a bad or negative number, a row without
/// any amplitude or an unknown branch name, or a table without data rows.
pub fn read_measured_amplitudes(path: &std::path::Path) -> Result<Vec<MeasuredAmplitude>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    parse_measured_amplitudes(&text, &path.display().to_string())
}

/// [`read_measured_amplitudes`] on the text of a file named `source` (for messages).
///
/// # Errors
/// As [`read_measured_amplitudes`].
pub fn parse_measured_amplitudes(text: &str, source: &str) -> Result<Vec<MeasuredAmplitude>> {
    let bad = |line: usize, msg: String| Error::InvalidTable {
        table: source.to_string(),
        message: format!("line {line}: {msg}"),
    };
    // (branch, speed) required; heave, pitch, frequency optional columns.
    const NAMES: [&str; 5] = [
        "branch",
        "wind_speed_m_s",
        "heave_amp_m",
        "pitch_amp_rad",
        "freq_hz",
    ];
    let mut header: Option<(usize, [Option<usize>; 5])> = None;
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let Some((width, cols)) = header else {
            let h: Vec<&str> = l.split(',').map(str::trim).collect();
            let cols = NAMES.map(|name| h.iter().position(|c| *c == name));
            for k in 0..2 {
                if cols[k].is_none() {
                    return Err(bad(
                        line,
                        format!(
                            "header has no column `{}` (columns: {})",
                            NAMES[k],
                            h.join(", ")
                        ),
                    ));
                }
            }
            if cols[2].is_none() && cols[3].is_none() {
                return Err(bad(
                    line,
                    format!(
                        "header has neither `heave_amp_m` nor `pitch_amp_rad` (columns: {})",
                        h.join(", ")
                    ),
                ));
            }
            header = Some((h.len(), cols));
            continue;
        };
        let f: Vec<&str> = l.splitn(width, ',').map(str::trim).collect();
        if f.len() < width {
            return Err(bad(
                line,
                format!("{} fields, the header has {width}", f.len()),
            ));
        }
        let num = |k: usize| -> Result<Option<f64>> {
            let Some(c) = cols[k] else { return Ok(None) };
            let s = f[c];
            if s.is_empty() || s == "-" || s.eq_ignore_ascii_case("nan") {
                return Ok(None);
            }
            let v: f64 = s.parse().map_err(|_| {
                bad(
                    line,
                    format!("column `{}`: `{s}` is not a number", NAMES[k]),
                )
            })?;
            if !v.is_finite() || v < 0.0 {
                return Err(bad(
                    line,
                    format!("column `{}`: {v} must be finite and ≥ 0", NAMES[k]),
                ));
            }
            Ok(Some(v))
        };
        let stable = match f[cols[0].expect("checked")] {
            "stable" => true,
            "unstable" => false,
            other => {
                return Err(bad(
                    line,
                    format!("column `branch`: `{other}` is neither `stable` nor `unstable`"),
                ))
            }
        };
        let u = num(1)?.ok_or_else(|| bad(line, "column `wind_speed_m_s`: no value".into()))?;
        let (amplitude_h, amplitude_alpha) = (num(2)?, num(3)?);
        if amplitude_h.is_none() && amplitude_alpha.is_none() {
            return Err(bad(
                line,
                "neither `heave_amp_m` nor `pitch_amp_rad` has a value".into(),
            ));
        }
        out.push(MeasuredAmplitude {
            line,
            stable,
            u,
            amplitude_h,
            amplitude_alpha,
            frequency_hz: num(4)?.filter(|&v| v > 0.0),
        });
    }
    if out.is_empty() {
        return Err(Error::InvalidTable {
            table: source.to_string(),
            message: "no data rows".into(),
        });
    }
    Ok(out)
}

/// Distance of one measured point to the predicted branch of the same stability.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MeasuredDistance {
    /// The measured point.
    pub measured: MeasuredAmplitude,
    /// Predicted first-harmonic pitch amplitude at the measured speed on the branch of the
    /// same stability \[rad\] (the segment closest in amplitude when several cover the
    /// speed); `None` when no such segment covers the speed.
    pub predicted_alpha: Option<f64>,
    /// Predicted first-harmonic heave amplitude there \[m\].
    pub predicted_h: Option<f64>,
    /// Predicted frequency there \[Hz\].
    #[serde(default)]
    pub predicted_frequency_hz: Option<f64>,
    /// Predicted − measured pitch amplitude \[rad\] (`None` when either is missing).
    pub d_alpha: Option<f64>,
    /// Predicted − measured heave amplitude \[m\] (`None` when either is missing).
    pub d_h: Option<f64>,
    /// Distance in speed to the nearest predicted orbit of the same stability \[m/s\]
    /// (0 when a segment covers the speed); `None` (`null`) when no predicted orbit has
    /// that stability (it was written `null` before, as the non-finite distance).
    pub speed_gap: Option<f64>,
}

/// The predicted orbit at a measured point's speed on the branches of `set`: the
/// segment of the same stability that covers `m.u` and whose first-harmonic amplitude is
/// closest to the measured one (pitch when measured, else heave), linearly interpolated
/// in U. Returns (pitch \[rad\], heave \[m\], frequency \[Hz\]).
pub fn predicted_at(set: &BranchSet, m: &MeasuredAmplitude) -> Option<(f64, f64, f64)> {
    let mut best: Option<(f64, (f64, f64, f64))> = None;
    for b in &set.branches {
        for w in b.points.windows(2) {
            if w[0].stable != m.stable || w[1].stable != m.stable {
                continue;
            }
            if (w[0].u - m.u) * (w[1].u - m.u) > 0.0 || w[0].u == w[1].u {
                continue;
            }
            let f = (m.u - w[0].u) / (w[1].u - w[0].u);
            let lerp = |a: f64, b: f64| a * (1.0 - f) + b * f;
            let a = lerp(w[0].amplitude1_alpha, w[1].amplitude1_alpha);
            let h = lerp(w[0].amplitude1_h, w[1].amplitude1_h);
            let hz = lerp(w[0].omega, w[1].omega) / std::f64::consts::TAU;
            let miss = match (m.amplitude_alpha, m.amplitude_h) {
                (Some(ma), _) => (a - ma).abs(),
                (None, Some(mh)) => (h - mh).abs(),
                (None, None) => 0.0,
            };
            if best.is_none_or(|(bm, _)| miss < bm) {
                best = Some((miss, (a, h, hz)));
            }
        }
    }
    best.map(|b| b.1)
}

/// Distances of measured points to the predicted branches of the same stability
/// (first-harmonic amplitudes, linear interpolation in U between branch points;
/// [`predicted_at`]).
pub fn measured_distances(
    set: &BranchSet,
    measured: &[MeasuredAmplitude],
) -> Vec<MeasuredDistance> {
    measured
        .iter()
        .map(|m| {
            let gap = set
                .branches
                .iter()
                .flat_map(|b| b.points.iter())
                .filter(|p| p.stable == m.stable)
                .map(|p| (p.u - m.u).abs())
                .fold(f64::INFINITY, f64::min);
            let best = predicted_at(set, m);
            let diff = |p: Option<f64>, q: Option<f64>| Some(p? - q?);
            MeasuredDistance {
                measured: m.clone(),
                predicted_alpha: best.map(|b| b.0),
                predicted_h: best.map(|b| b.1),
                predicted_frequency_hz: best.map(|b| b.2),
                d_alpha: diff(best.map(|b| b.0), m.amplitude_alpha),
                d_h: diff(best.map(|b| b.1), m.amplitude_h),
                speed_gap: if best.is_some() {
                    Some(0.0)
                } else {
                    Some(gap).filter(|g| g.is_finite())
                },
            }
        })
        .collect()
}

/// The parabola through (s_i, v_i), i = 0‥2, at `x`.
fn quadratic(s: [f64; 3], v: [f64; 3], x: f64) -> f64 {
    lagrange(&[(s[0], v[0]), (s[1], v[1]), (s[2], v[2])], x)
}

/// Kind of multiplier crossing between two points without a turning point, if the number
/// of multipliers outside the unit circle changed.
fn crossing(a: &BranchPoint, b: &BranchPoint) -> Option<EventKind> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flutter::{FlutterMethod, FlutterOptions};
    use crate::lco::LcoOptions;
    use crate::reference::{hp1_cubic_pitch, hp1_structure};
    use crate::structure::PolyTerm;

    fn no_obs(_: BranchProgress) {}

    /// Missing values (empty, `nan`, `-`), a heave-only header and the optional frequency
    /// are read; a row without any amplitude, a missing speed column and a bad number are
    /// refused with file, line and column.
    #[test]
    fn measured_tables_with_missing_values() {
        let t = "# c\nbranch,wind_speed_m_s,heave_amp_m,pitch_amp_rad,freq_hz,source\n\
                 stable,15,0.02,,2.4,a, b\nunstable,16,-,0.03,nan,x\n";
        let m = parse_measured_amplitudes(t, "t.csv").unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!((m[0].amplitude_alpha, m[0].frequency_hz), (None, Some(2.4)));
        assert_eq!((m[1].amplitude_h, m[1].amplitude_alpha), (None, Some(0.03)));
        assert_eq!(m[1].frequency_hz, None);
        let heave =
            parse_measured_amplitudes("branch,wind_speed_m_s,heave_amp_m\nstable,15,0.02\n", "h")
                .unwrap();
        assert_eq!(heave[0].amplitude_alpha, None);
        for (text, needle) in [
            (
                "branch,wind_speed_m_s,heave_amp_m,pitch_amp_rad\nstable,15,,nan\n",
                "line 2",
            ),
            ("branch,heave_amp_m\nstable,0.1\n", "wind_speed_m_s"),
            (
                "branch,wind_speed_m_s,pitch_amp_rad\nstable,15,abc\n",
                "pitch_amp_rad",
            ),
            ("branch,wind_speed_m_s,freq_hz\nstable,15,2\n", "neither"),
        ] {
            let e = parse_measured_amplitudes(text, "bad.csv")
                .unwrap_err()
                .to_string();
            assert!(e.contains(needle) && e.contains("bad.csv"), "{e}");
        }
    }

    /// det(2A⊙I) = Π_{i<j}(λ_i + λ_j) on a non-symmetric matrix with complex eigenvalues.
    #[test]
    fn bialternate_determinant_is_the_product_of_eigenvalue_pair_sums() {
        let a = DMatrix::from_fn(6, 6, |i, j| {
            ((i * 7 + j * 3) % 11) as f64 * 0.3 - 1.1 + (i == j) as u8 as f64 * 0.2 * i as f64
        });
        let ev = eigenvalues(&a).unwrap();
        let mut prod = Complex64::new(1.0, 0.0);
        for i in 0..6 {
            for j in 0..i {
                prod *= ev[i] + ev[j];
            }
        }
        let d = Bialternate::new(6).determinant(a.transpose().as_slice(), &mut Vec::new());
        assert!(prod.im.abs() < 1e-9 * prod.norm(), "{prod}");
        assert!((d - prod.re).abs() < 1e-9 * prod.norm(), "{d} vs {prod}");
        assert!(ev.iter().any(|l| l.im.abs() > 1e-3), "{ev:?}");
    }

    /// Theodorsen's A(U) is exactly quadratic in U: the fit reproduces the central-difference
    /// Jacobian at other speeds; a K-dependent law is not, and gets no fit.
    #[test]
    fn linear_models_have_a_quadratic_equilibrium_jacobian() {
        let s = hp1_cubic_pitch();
        let q = QuadraticJacobian::fit(&s, [1.0, 2.0, 3.0], 2.4)
            .unwrap()
            .expect("Theodorsen is quadratic in U");
        let n = s.n_states();
        let mut a = vec![0.0; n * n];
        for u in [0.7, 1.7, 3.9] {
            q.at(u, &mut a);
            let direct = s.equilibrium_jacobian(u).unwrap();
            let scale = direct.amax();
            for r in 0..n {
                for c in 0..n {
                    assert!(
                        (a[r * n + c] - direct[(r, c)]).abs() < 1e-8 * scale,
                        "U {u}: A[{r}][{c}] {} vs {}",
                        a[r * n + c],
                        direct[(r, c)]
                    );
                }
            }
        }
    }

    #[test]
    fn hopf_point_is_the_linear_flutter_speed() {
        let s = hp1_cubic_pitch();
        let h = s.hopf_points(1.0, 3.0, 50).unwrap();
        let fo = FlutterOptions {
            u_min: 0.05,
            u_max: 4.0,
            n_speeds: 80,
            tol_rel: 1e-10,
        };
        let f = s.flutter(FlutterMethod::P, &fo).unwrap().flutter.unwrap();
        assert_eq!(h.len(), 1, "{h:?}");
        assert!((h[0].u - f.u).abs() < 1e-6 * f.u, "{} vs {}", h[0].u, f.u);
        assert!((h[0].omega - f.omega).abs() < 1e-5 * f.omega);
        assert!(h[0].dsigma_du > 0.0);
    }

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
