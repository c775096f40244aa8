//! `friction`: dry (Coulomb) friction in the supports: a linear, not exponential,
//! amplitude decay.
//!
//! * System level: F_c tanh(ḣ/ε_h), T_c tanh(α̇/ε_α), ε a fraction (grid 0.01, 0.03, 0.1)
//!   of the pooled rms velocity (3 parameters); a friction that does not oppose the
//!   motion is no such effect.
//! * Bifurcation level: a Coulomb moment T_c tanh(α̇/ε) in pitch, ε fixed at 5 % of the
//!   largest measured orbit's peak pitch velocity, then with ε fitted.
//! * Generator: T_c 1e-5–3e-3 N·m/m.

use aeroelastic::effects::{Form, InjectedEffect};
use aeroelastic::section::Section;

use super::entry::{Draw, DrawContext, Entry};
use crate::bifurcation::candidates::{param, BranchCandidate, Change, Scales};
use super::{Effect, Level};
use crate::system::candidates::{acc_term, Column, Grid, SystemTerm};
use crate::system::residual::RunResidual;

/// Smoothing grid of the system-level fit (fractions of the pooled rms velocity).
pub(crate) const GRID: [f64; 3] = [0.01, 0.03, 0.1];

/// The `friction` entry.
pub(crate) struct Friction;

impl Entry for Friction {
    fn name(&self) -> &'static str {
        "friction"
    }
    fn short_label(&self) -> &'static str {
        "frict"
    }
    fn level(&self) -> Level {
        Level::Structural
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn bifurcation(&self, base: &Section, s: Scales) -> Vec<BranchCandidate> {
        let st = &base.structure;
        let ka = st.k_alpha;
        vec![
            BranchCandidate::new(
                Effect::Friction,
                "pitch",
                vec![param(
                    "friction_pitch",
                    "N m",
                    "Coulomb moment T_c·tanh(α̇/ε) opposing α̇ (T_c = |θ|·scale ≥ 0; ε = 5 % \
                     of the largest measured orbit's peak pitch velocity)",
                    0.02 * ka * s.alpha,
                )],
                None,
                Change::PitchFriction,
            )
            .with_reference_alpha(s.alpha),
            BranchCandidate::new(
                Effect::Friction,
                "pitch, ε fitted",
                vec![
                    param(
                        "friction_pitch",
                        "N m",
                        "Coulomb moment T_c·tanh(α̇/ε) opposing α̇ (T_c = |θ|·scale ≥ 0)",
                        0.02 * ka * s.alpha,
                    ),
                    param(
                        "friction_smoothing_pitch",
                        "rad/s",
                        "velocity ε of the regularisation tanh(α̇/ε), scale·10^(θ/2) with θ \
                         in [−4, 4] (below it the friction acts as a viscous damping T_c/ε: \
                         pre-sliding, which sets the Hopf point)",
                        0.05 * st.omega_alpha() * s.alpha,
                    ),
                ],
                Some((Effect::Friction, "pitch")),
                Change::PitchFrictionSmoothing,
            )
            .with_reference_alpha(s.alpha),
        ]
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl SystemTerm for Friction {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &["friction_heave_N_per_m", "friction_pitch_Nm_per_m"]
    }
    fn grids(&self, runs: &[RunResidual]) -> Grid {
        let rms = |c: usize| {
            let (s, n) = runs.iter().fold((0.0, 0usize), |(s, n), r| {
                (
                    s + r.qd[c][r.i0..r.i1].iter().map(|v| v * v).sum::<f64>(),
                    n + r.len(),
                )
            });
            (s / n.max(1) as f64).sqrt().max(1e-12)
        };
        let (vh, va) = (rms(0), rms(1));
        GRID.iter()
            .map(|f| {
                (
                    vec![
                        ("smoothing_heave_m_per_s".into(), f * vh),
                        ("smoothing_pitch_rad_per_s".into(), f * va),
                    ],
                    vec![f * vh, f * va],
                )
            })
            .collect()
    }
    fn n_grid_params(&self) -> usize {
        1
    }
    fn columns(&self, grid: &[f64], run: &RunResidual, _rho: f64, _chord: f64) -> Vec<Column> {
        let (eh, ea) = (grid[0], grid[1]);
        let xh: Vec<f64> = run.qd[0].iter().map(|v| (v / eh).tanh()).collect();
        let xa: Vec<f64> = run.qd[1].iter().map(|v| (v / ea).tanh()).collect();
        vec![
            [acc_term(run, &xh), Vec::new()],
            [Vec::new(), acc_term(run, &xa)],
        ]
    }
    fn forms(&self) -> Vec<(&'static str, Vec<usize>)> {
        super::dof_forms()
    }
    fn report_sign(&self) -> f64 {
        -1.0
    }
    fn sign_bound(&self) -> bool {
        true
    }
    fn convention(&self) -> &'static str {
        "extra dissipative force added to C q̇: friction·tanh(q̇/smoothing) (heave N/m, \
         pitch N·m/m); > 0 opposes the motion"
    }
    fn force(
        &self,
        grid: &[f64],
        t: &[f64],
        _q: [f64; 2],
        qd: [f64; 2],
        _q_dyn: f64,
        _chord: f64,
    ) -> [f64; 2] {
        [
            t[0] * (qd[0] / grid[0]).tanh(),
            t[1] * (qd[1] / grid[1]).tanh(),
        ]
    }
}

impl Draw for Friction {
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("T_c [N*m/m]", 1e-5, 3e-3)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        _cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::Friction { moment: p },
            Vec::new(),
        )
    }
}
