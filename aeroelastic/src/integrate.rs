//! The one time-integration layer of the workspace: an adaptive Dop853 driver (ode_solvers
//! 0.6, sparse output: the observer sees every accepted step) for open-ended runs (LCO),
//! and one fixed-step classical Runge–Kutta (RK4) stepper and driver for uniformly sampled
//! records (trajectories, free-response records, forced-motion lag states, the diagnosis'
//! re-simulation). Both integrate any [`OdeSystem`]; [`crate::dynamics::SectionDynamics`]
//! is the section's.
//!
//! Every run returns an [`IntegrationRun`] with a typed [`StopReason`] and honest counts
//! (accepted steps and right-hand-side evaluations are counted here, so a run that the
//! solver aborts still reports the work done).
//!
//! Why Sparse output: ode_solvers 0.6's Dense output passes a stale state to `solout` and
//! extrapolates the final point; consumers that need values between steps interpolate
//! themselves (the LCO cycle detector uses a quintic Hermite interpolant on z, ż, z̈).

use std::cell::Cell;

use nalgebra::SVector;
use ode_solvers::dop853::Dop853;
use ode_solvers::dop_shared::{IntegrationError, OutputType, System};
use serde::{Deserialize, Serialize};

use crate::dynamics::SectionDynamics;
use crate::{Error, Result};

/// A first-order system ż = f(t, z).
pub trait OdeSystem {
    /// Number of states.
    fn dim(&self) -> usize;
    /// Writes ż = f(t, z) into `dz` (both of length [`OdeSystem::dim`]).
    fn rate(&self, t: f64, z: &[f64], dz: &mut [f64]);
}

impl OdeSystem for SectionDynamics<'_> {
    fn dim(&self) -> usize {
        SectionDynamics::dim(self)
    }
    #[inline]
    fn rate(&self, _t: f64, z: &[f64], dz: &mut [f64]) {
        SectionDynamics::rate(self, z, dz);
    }
}

/// What an observer concluded about the response: the run stops there. Every observer of
/// the workspace (LCO classification, the free-response bound, the diagnosis's
/// re-simulation) returns one of these through [`Control::Stop`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ObserverVerdict {
    /// A converged response (e.g. a steady limit cycle).
    Converged,
    /// The response decayed to the equilibrium.
    Decayed,
    /// Unbounded growth established before the bound was reached.
    Diverged,
    /// |h| or |α| left the bound ([`Bound`], or the observer's own).
    LeftBound,
}

/// Why a solver stopped on its own, without an observer's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SolverStop {
    /// The largest number of steps (accepted + rejected for Dop853) was reached.
    StepCap,
    /// The end time was reached without the observer stopping the run.
    TimeCap,
    /// Dop853's step size fell below the rounding of t.
    StepSizeUnderflow,
    /// Dop853's stiffness detector aborted the run (h·λ > 6.1 at 15 successive tests).
    Stiffness,
    /// A state value became NaN or infinite.
    NonFinite,
}

/// Why an integration ended: an observer's verdict or a solver stop. Written by its flat
/// [`StopReason::name`] (`converged`, `step_cap`, …) in lco.json and CSV files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StopReason {
    /// The observer (or the bound) stopped the run.
    Observer(ObserverVerdict),
    /// The solver stopped on its own.
    Solver(SolverStop),
}

impl StopReason {
    /// Every stop reason, observer verdicts first.
    pub const ALL: [StopReason; 9] = [
        StopReason::Observer(ObserverVerdict::Converged),
        StopReason::Observer(ObserverVerdict::Decayed),
        StopReason::Observer(ObserverVerdict::Diverged),
        StopReason::Observer(ObserverVerdict::LeftBound),
        StopReason::Solver(SolverStop::StepCap),
        StopReason::Solver(SolverStop::TimeCap),
        StopReason::Solver(SolverStop::StepSizeUnderflow),
        StopReason::Solver(SolverStop::Stiffness),
        StopReason::Solver(SolverStop::NonFinite),
    ];

    /// Short snake_case name, as written in lco.json and CSV files.
    pub fn name(&self) -> &'static str {
        match self {
            StopReason::Observer(v) => match v {
                ObserverVerdict::Converged => "converged",
                ObserverVerdict::Decayed => "decayed",
                ObserverVerdict::Diverged => "diverged",
                ObserverVerdict::LeftBound => "left_bound",
            },
            StopReason::Solver(s) => match s {
                SolverStop::StepCap => "step_cap",
                SolverStop::TimeCap => "time_cap",
                SolverStop::StepSizeUnderflow => "step_size_underflow",
                SolverStop::Stiffness => "stiffness",
                SolverStop::NonFinite => "non_finite",
            },
        }
    }

    /// What the stop means, in one sentence (the schema's description of its name).
    pub fn description(&self) -> &'static str {
        match self {
            StopReason::Observer(v) => match v {
                ObserverVerdict::Converged => {
                    "The observer found a converged response (e.g. a steady limit cycle)."
                }
                ObserverVerdict::Decayed => "The observer found the response decayed to the equilibrium.",
                ObserverVerdict::Diverged => {
                    "The observer found unbounded growth established before the bound was reached."
                }
                ObserverVerdict::LeftBound => "|h| or |α| left the bound.",
            },
            StopReason::Solver(s) => match s {
                SolverStop::StepCap => {
                    "The largest number of steps (accepted + rejected for Dop853) was reached."
                }
                SolverStop::TimeCap => "The end time was reached without the observer stopping the run.",
                SolverStop::StepSizeUnderflow => "Dop853's step size fell below the rounding of t.",
                SolverStop::Stiffness => {
                    "Dop853's stiffness detector aborted the run (h·λ > 6.1 at 15 successive tests)."
                }
                SolverStop::NonFinite => "A state value became NaN or infinite.",
            },
        }
    }

    /// The stop reason of a [`StopReason::name`], if any.
    pub fn from_name(name: &str) -> Option<Self> {
        StopReason::ALL.into_iter().find(|r| r.name() == name)
    }
}

impl From<ObserverVerdict> for StopReason {
    fn from(v: ObserverVerdict) -> Self {
        StopReason::Observer(v)
    }
}

impl From<SolverStop> for StopReason {
    fn from(s: SolverStop) -> Self {
        StopReason::Solver(s)
    }
}

/// Written as its [`StopReason::name`].
impl Serialize for StopReason {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// Read from its [`StopReason::name`]; any other string is an error naming it.
impl<'de> Deserialize<'de> for StopReason {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        StopReason::from_name(&s).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "stop reason `{s}`: expected one of {}",
                StopReason::ALL.map(|r| r.name()).join(", ")
            ))
        })
    }
}

/// One string constant per [`StopReason::name`], with its description.
impl schemars::JsonSchema for StopReason {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "StopReason".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let one_of: Vec<serde_json::Value> = StopReason::ALL
            .iter()
            .map(|r| {
                serde_json::json!({
                    "const": r.name(),
                    "description": r.description(),
                    "type": "string",
                })
            })
            .collect();
        schemars::json_schema!({
            "description": "Why an integration ended: an observer's verdict (`converged`, \
                `decayed`, `diverged`, `left_bound`) or a solver stop (`step_cap`, \
                `time_cap`, `step_size_underflow`, `stiffness`, `non_finite`).",
            "oneOf": one_of,
        })
    }
}

/// What an observer tells the driver after a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Go on.
    Continue,
    /// Stop now, with this verdict.
    Stop(ObserverVerdict),
}

/// Observer of an adaptive run: called with (t, z, ż) after every accepted step.
pub type StepObserver<'a> = dyn FnMut(f64, &[f64], &[f64]) -> Control + 'a;

/// Bound on the section's displacements: the run stops with [`ObserverVerdict::LeftBound`]
/// when |z₀| = |h| > `h` \[m\] or |z₁| = |α| > `alpha` \[rad\] after a step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Bound {
    /// Largest |h| \[m\].
    pub h: f64,
    /// Largest |α| \[rad\].
    pub alpha: f64,
}

impl Bound {
    /// Bound on |α| only.
    pub fn alpha(alpha: f64) -> Self {
        Bound {
            h: f64::INFINITY,
            alpha,
        }
    }

    /// Whether state `z` (h, α first) is outside the bound (a NaN counts as outside).
    pub fn left(&self, z: &[f64]) -> bool {
        !(z[0].abs() <= self.h && z[1].abs() <= self.alpha)
    }
}

/// Outcome of one integration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct IntegrationRun {
    /// Why it stopped.
    pub stop: StopReason,
    /// Time reached \[s\] (the last accepted step).
    pub t_end: f64,
    /// Accepted steps.
    pub steps: u64,
    /// Right-hand-side evaluations (including rejected steps' and the initial-step guess).
    pub rhs_evals: u64,
}

/// Options of the adaptive Dop853 driver.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct AdaptiveOptions {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (in the state's units).
    pub atol: f64,
    /// Largest number of steps, accepted + rejected.
    pub max_steps: u32,
    /// Run ode_solvers' stiffness detector (aborts with [`SolverStop::Stiffness`]). Off by
    /// default: the error control keeps an explicit run accurate on a stiff problem, only
    /// slower (see DECISIONS.md, "Stiffness detector").
    pub stiffness_test: bool,
    /// Optional bound on |h|, |α|.
    pub bound: Option<Bound>,
}

impl AdaptiveOptions {
    fn check(&self) -> Result<()> {
        crate::error::positive("rtol", self.rtol)?;
        crate::error::positive("atol", self.atol)?;
        if self.max_steps == 0 {
            return Err(Error::param("max_steps", 0.0, "must be > 0"));
        }
        Ok(())
    }
}

/// Adapter of an [`OdeSystem`] + observer to ode_solvers' `System`, counting evaluations
/// and recording the stop reason decided in `solout`.
struct Adapter<'a> {
    sys: &'a dyn OdeSystem,
    evals: Cell<u64>,
    steps: u64,
    t_last: f64,
    bound: Option<Bound>,
    stop: Option<StopReason>,
    observer: &'a mut StepObserver<'a>,
}

impl<const N: usize> System<f64, SVector<f64, N>> for &mut Adapter<'_> {
    #[inline]
    fn system(&self, t: f64, y: &SVector<f64, N>, dy: &mut SVector<f64, N>) {
        self.evals.set(self.evals.get() + 1);
        self.sys.rate(t, y.as_slice(), dy.as_mut_slice());
    }

    fn solout(&mut self, t: f64, y: &SVector<f64, N>, dy: &SVector<f64, N>) -> bool {
        self.steps += 1;
        self.t_last = t;
        let z = y.as_slice();
        if z.iter().any(|v| !v.is_finite()) {
            self.stop = Some(SolverStop::NonFinite.into());
            return true;
        }
        if self.bound.is_some_and(|b| b.left(z)) {
            self.stop = Some(ObserverVerdict::LeftBound.into());
            // the observer still sees the state that left the bound
            let _ = (self.observer)(t, z, dy.as_slice());
            return true;
        }
        match (self.observer)(t, z, dy.as_slice()) {
            Control::Continue => false,
            Control::Stop(r) => {
                self.stop = Some(r.into());
                true
            }
        }
    }
}

fn dop853_fixed<const N: usize>(
    adapter: &mut Adapter<'_>,
    t0: f64,
    t_end: f64,
    z0: &[f64],
    opts: &AdaptiveOptions,
) -> Option<StopReason> {
    let y = SVector::<f64, N>::from_column_slice(z0);
    // n_stiff = u32::MAX: the test runs when accepted_steps is a multiple of n_stiff,
    // which never happens, so the detector is off.
    let n_stiff = if opts.stiffness_test { 1000 } else { u32::MAX };
    let mut solver = Dop853::from_param(
        &mut *adapter,
        t0,
        t_end,
        0.0,
        y,
        opts.rtol,
        opts.atol,
        0.9,
        0.0,
        0.333,
        6.0,
        t_end - t0,
        0.0,
        opts.max_steps,
        n_stiff,
        OutputType::Sparse,
    );
    match solver.integrate() {
        Ok(_) => None,
        Err(IntegrationError::MaxNumStepReached { .. }) => Some(SolverStop::StepCap.into()),
        Err(IntegrationError::StepSizeUnderflow { .. }) => {
            Some(SolverStop::StepSizeUnderflow.into())
        }
        Err(IntegrationError::StiffnessDetected { .. }) => Some(SolverStop::Stiffness.into()),
    }
}

/// Integrates `sys` from `z0` at `t0` to at most `t_end` with Dop853 (8th order, error
/// control on |δz_i| ≤ atol + rtol·|z_i|), calling `observer(t, z, ż)` after every
/// accepted step (never at t0). Stops at the first of: the observer's
/// [`Control::Stop`], a non-finite state, leaving `opts.bound`, `t_end`
/// ([`SolverStop::TimeCap`]), the step cap, step-size underflow or (when enabled) the
/// stiffness detector.
///
/// # Errors
/// [`Error::InvalidParameter`] for bad tolerances, a zero step cap, `t_end ≤ t0`, or a
/// `z0` whose length differs from `sys.dim()` or is not finite; [`Error::Numerical`] for
/// a dimension outside 1…12 (the solver's states are fixed-size vectors).
///
/// `sys` is a trait object: the solver is compiled once per state size (twelve), not once
/// per size and per system type; every system of the unit tests had compiled twelve more
/// (docs/DECISIONS.md, "Staged starts for the difference fits, a stacked column in one
/// piece, Dop853 once per size", round 42).
pub fn dop853(
    sys: &dyn OdeSystem,
    t0: f64,
    t_end: f64,
    z0: &[f64],
    opts: &AdaptiveOptions,
    observer: &mut StepObserver<'_>,
) -> Result<IntegrationRun> {
    opts.check()?;
    check_start(sys, t0, z0)?;
    if t_end.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater) || !t_end.is_finite() {
        return Err(Error::param("t_end", t_end, "must be finite and > t0"));
    }
    let n = sys.dim();
    let mut a = Adapter {
        sys,
        evals: Cell::new(0),
        steps: 0,
        t_last: t0,
        bound: opts.bound,
        stop: None,
        observer,
    };
    macro_rules! dispatch {
        ($($k:literal),*) => {
            match n {
                $( $k => dop853_fixed::<$k>(&mut a, t0, t_end, z0, opts), )*
                _ => {
                    return Err(Error::numerical(
                        "dop853",
                        format!("state dimension {n} not supported (1..=12)"),
                    ))
                }
            }
        };
    }
    let solver_stop = dispatch!(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12);
    let stop = a.stop.or(solver_stop).unwrap_or(SolverStop::TimeCap.into());
    Ok(IntegrationRun {
        stop,
        t_end: a.t_last,
        steps: a.steps,
        rhs_evals: a.evals.get(),
    })
}

fn check_start<S: OdeSystem + ?Sized>(sys: &S, t0: f64, z0: &[f64]) -> Result<()> {
    if !t0.is_finite() {
        return Err(Error::param("t0", t0, "must be finite"));
    }
    let n = sys.dim();
    if z0.len() != n || z0.iter().any(|v| !v.is_finite()) {
        return Err(Error::param(
            "y0",
            z0.len() as f64,
            format!("must hold {n} finite values"),
        ));
    }
    Ok(())
}

/// Work space of the classical fourth-order Runge–Kutta step (one allocation per run).
#[derive(Debug, Clone)]
pub struct Rk4 {
    k: [Vec<f64>; 4],
    tmp: Vec<f64>,
}

impl Rk4 {
    /// Work space for `n` states.
    pub fn new(n: usize) -> Self {
        Rk4 {
            k: std::array::from_fn(|_| vec![0.0; n]),
            tmp: vec![0.0; n],
        }
    }

    /// One RK4 step of length `h` from (t, z), in place:
    /// z ← z + h/6 (k₁ + 2k₂ + 2k₃ + k₄), k₁ = f(t, z), k₂ = f(t + h/2, z + h/2 k₁),
    /// k₃ = f(t + h/2, z + h/2 k₂), k₄ = f(t + h, z + h k₃). Local error O(h⁵).
    /// Returns k₁ = ż at the start of the step. `z` must hold as many values as the
    /// work space (a mismatch is a bug and panics).
    pub fn step<S: OdeSystem + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        h: f64,
        z: &mut [f64],
    ) -> &[f64] {
        let n = z.len();
        let [k1, k2, k3, k4] = &mut self.k;
        let tmp = &mut self.tmp;
        sys.rate(t, z, k1);
        for i in 0..n {
            tmp[i] = z[i] + 0.5 * h * k1[i];
        }
        sys.rate(t + 0.5 * h, tmp, k2);
        for i in 0..n {
            tmp[i] = z[i] + 0.5 * h * k2[i];
        }
        sys.rate(t + 0.5 * h, tmp, k3);
        for i in 0..n {
            tmp[i] = z[i] + h * k3[i];
        }
        sys.rate(t + h, tmp, k4);
        for i in 0..n {
            z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        k1
    }
}

/// Fixed-step RK4 driver: `n_steps` steps of length `h` from (t0, z), in place, calling
/// `observer(i, t_i, z_i)` after step i (1-based, t_i = t0 + i·h). Stops at the first
/// of: a non-finite state ([`SolverStop::NonFinite`]), leaving `bound`
/// ([`ObserverVerdict::LeftBound`]; the observer is not called for that state), the
/// observer's [`Control::Stop`], or after the last step ([`SolverStop::TimeCap`]).
///
/// # Errors
/// [`Error::InvalidParameter`] for a non-positive or non-finite `h`, or a `z` whose
/// length differs from `sys.dim()` or is not finite.
pub fn rk4<S: OdeSystem + ?Sized>(
    sys: &S,
    t0: f64,
    z: &mut [f64],
    h: f64,
    n_steps: usize,
    bound: Option<Bound>,
    observer: &mut dyn FnMut(usize, f64, &[f64]) -> Control,
) -> Result<IntegrationRun> {
    crate::error::positive("h", h)?;
    check_start(sys, t0, z)?;
    let mut w = Rk4::new(z.len());
    let mut run = IntegrationRun {
        stop: SolverStop::TimeCap.into(),
        t_end: t0,
        steps: 0,
        rhs_evals: 0,
    };
    for i in 1..=n_steps {
        let t = t0 + (i - 1) as f64 * h;
        w.step(sys, t, h, z);
        run.steps += 1;
        run.rhs_evals += 4;
        run.t_end = t0 + i as f64 * h;
        if z.iter().any(|v| !v.is_finite()) {
            run.stop = SolverStop::NonFinite.into();
            return Ok(run);
        }
        if bound.is_some_and(|b| b.left(z)) {
            run.stop = ObserverVerdict::LeftBound.into();
            return Ok(run);
        }
        if let Control::Stop(r) = observer(i, run.t_end, z) {
            run.stop = r.into();
            return Ok(run);
        }
    }
    Ok(run)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ż = A z for the undamped oscillator ẍ = −ω² x (x, ẋ; padded with h = 0).
    struct Osc {
        w: f64,
    }
    impl OdeSystem for Osc {
        fn dim(&self) -> usize {
            4
        }
        fn rate(&self, _t: f64, z: &[f64], dz: &mut [f64]) {
            dz[0] = 0.0;
            dz[1] = z[3];
            dz[2] = 0.0;
            dz[3] = -self.w * self.w * z[1];
        }
    }

    /// ż = λ z: exponential growth, for the bound and non-finite checks.
    struct Exp(f64);
    impl OdeSystem for Exp {
        fn dim(&self) -> usize {
            2
        }
        fn rate(&self, _t: f64, z: &[f64], dz: &mut [f64]) {
            dz[0] = self.0 * z[0];
            dz[1] = self.0 * z[1];
        }
    }

    fn opts() -> AdaptiveOptions {
        AdaptiveOptions {
            rtol: 1e-10,
            atol: 1e-12,
            max_steps: 100_000,
            stiffness_test: false,
            bound: None,
        }
    }

    #[test]
    fn dop853_reaches_the_end_time_with_the_exact_oscillator_state() {
        let sys = Osc { w: 2.0 };
        let mut last = vec![];
        let mut obs = |_t: f64, z: &[f64], _dz: &[f64]| {
            last = z.to_vec();
            Control::Continue
        };
        let t_end = 3.0;
        let r = dop853(&sys, 0.0, t_end, &[0.0, 0.1, 0.0, 0.0], &opts(), &mut obs).unwrap();
        assert_eq!(r.stop, StopReason::Solver(SolverStop::TimeCap));
        assert!((r.t_end - t_end).abs() < 1e-12);
        assert!(
            (last[1] - 0.1 * (2.0 * t_end).cos()).abs() < 1e-9,
            "{last:?}"
        );
        assert!(r.steps > 0 && r.rhs_evals >= 12 * r.steps);
    }

    #[test]
    fn every_stop_reason_of_the_drivers_is_reported() {
        let mut cont = |_t: f64, _z: &[f64], _d: &[f64]| Control::Continue;
        // step cap: counts survive the solver's error
        let o = AdaptiveOptions {
            max_steps: 5,
            ..opts()
        };
        let r = dop853(
            &Osc { w: 2.0 },
            0.0,
            100.0,
            &[0.0, 0.1, 0.0, 0.0],
            &o,
            &mut cont,
        )
        .unwrap();
        assert_eq!(r.stop, StopReason::Solver(SolverStop::StepCap));
        assert!(r.steps > 0 && r.rhs_evals > 0, "{r:?}");
        // bound
        let o = AdaptiveOptions {
            bound: Some(Bound::alpha(1.0)),
            ..opts()
        };
        let r = dop853(&Exp(1.0), 0.0, 100.0, &[0.0, 0.01], &o, &mut cont).unwrap();
        assert_eq!(r.stop, StopReason::Observer(ObserverVerdict::LeftBound));
        assert!(r.t_end > 4.0 && r.t_end < 5.0, "{}", r.t_end);
        // observer decision
        let mut stop_at_1 = |t: f64, _z: &[f64], _d: &[f64]| {
            if t > 1.0 {
                Control::Stop(ObserverVerdict::Converged)
            } else {
                Control::Continue
            }
        };
        let r = dop853(
            &Osc { w: 2.0 },
            0.0,
            10.0,
            &[0.0, 0.1, 0.0, 0.0],
            &opts(),
            &mut stop_at_1,
        )
        .unwrap();
        assert_eq!(r.stop, StopReason::Observer(ObserverVerdict::Converged));
        // stiffness: ż = −1e6 z with loose tolerance, detector on
        let o = AdaptiveOptions {
            rtol: 1e-3,
            atol: 1e-3,
            stiffness_test: true,
            max_steps: 1_000_000,
            ..opts()
        };
        let r = dop853(&Exp(-1e6), 0.0, 0.01, &[1.0, 1.0], &o, &mut cont).unwrap();
        assert_eq!(r.stop, StopReason::Solver(SolverStop::Stiffness), "{r:?}");
        // the same run with the detector off finishes, accurately
        let o = AdaptiveOptions {
            stiffness_test: false,
            ..o
        };
        let r = dop853(&Exp(-1e6), 0.0, 0.01, &[1.0, 1.0], &o, &mut cont).unwrap();
        assert_eq!(r.stop, StopReason::Solver(SolverStop::TimeCap), "{r:?}");
        // rk4: bound, non-finite and time cap
        let mut none = |_i: usize, _t: f64, _z: &[f64]| Control::Continue;
        let mut z = [0.0, 0.01];
        let r = rk4(
            &Exp(1.0),
            0.0,
            &mut z,
            0.01,
            1000,
            Some(Bound::alpha(1.0)),
            &mut none,
        )
        .unwrap();
        assert_eq!(r.stop, StopReason::Observer(ObserverVerdict::LeftBound));
        let mut z = [1.0, 1.0];
        let r = rk4(&Exp(1e3), 0.0, &mut z, 1.0, 1000, None, &mut none).unwrap();
        assert_eq!(r.stop, StopReason::Solver(SolverStop::NonFinite));
        let mut z = [1.0, 1.0];
        let r = rk4(&Exp(-1.0), 0.0, &mut z, 0.01, 100, None, &mut none).unwrap();
        assert_eq!(
            (r.stop, r.steps, r.rhs_evals),
            (StopReason::Solver(SolverStop::TimeCap), 100, 400)
        );
        assert!((z[0] - (-1.0f64).exp()).abs() < 1e-9);
        // bad input is an error naming the field
        let e = rk4(&Exp(1.0), 0.0, &mut [1.0], 0.1, 1, None, &mut none).unwrap_err();
        assert!(e.to_string().contains("y0"), "{e}");
        let e = dop853(&Exp(1.0), 0.0, -1.0, &[1.0, 1.0], &opts(), &mut cont).unwrap_err();
        assert!(e.to_string().contains("t_end"), "{e}");
    }
}
