//! `structural_cubic`: cubic structural stiffness (hardening or softening): an
//! amplitude-dependent frequency in free response, forced residuals clean.
//!
//! * System level: c_h h³ and c_α α³ springs (2 coefficients; forms pitch, heave, both).
//! * Bifurcation level: an extra restoring moment k₃α³ in pitch.
//! * Generator: κ 0.5–200 rad⁻² (k_α(α + κα³)).

use aeroelastic::effects::{Form, InjectedEffect};
use aeroelastic::section::Section;

use super::entry::{Draw, DrawContext, Entry};
use crate::bifurcation::candidates::{stiffness_param, BranchCandidate, Change, Dof, Scales};
use super::{Effect, Level};
use crate::system::candidates::{acc_term, Column, SystemTerm};
use crate::system::residual::RunResidual;

/// The `structural_cubic` entry.
pub(crate) struct StructuralCubic;

impl Entry for StructuralCubic {
    fn name(&self) -> &'static str {
        "structural_cubic"
    }
    fn short_label(&self) -> &'static str {
        "s.cubic"
    }
    fn level(&self) -> Level {
        Level::Structural
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn bifurcation(&self, base: &Section, s: Scales) -> Vec<BranchCandidate> {
        vec![BranchCandidate::new(
            Effect::StructuralCubic,
            "pitch",
            vec![stiffness_param(Dof::Pitch, 3, base.structure.k_alpha, s.alpha)],
            None,
            Change::PitchStiffness(&[3]),
        )]
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl SystemTerm for StructuralCubic {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &["k3_heave_N_per_m3", "k3_pitch_Nm_per_rad3"]
    }
    // restoring terms through the same smoothing as the residual's structural force
    // (their harmonics at 2f, 3f are attenuated by the differentiator as the measured
    // acceleration's are)
    fn columns(&self, _grid: &[f64], run: &RunResidual, _rho: f64, _chord: f64) -> Vec<Column> {
        let p = |c: usize| acc_term(run, &run.q[c].iter().map(|v| v.powi(3)).collect::<Vec<_>>());
        vec![[p(0), Vec::new()], [Vec::new(), p(1)]]
    }
    fn forms(&self) -> Vec<(&'static str, Vec<usize>)> {
        super::dof_forms()
    }
    fn report_sign(&self) -> f64 {
        -1.0
    }
    fn convention(&self) -> &'static str {
        "extra restoring force added to K q: heave k3_heave·h³ [N/m], pitch \
         k3_pitch·α³ [N·m/m]; h positive down, α positive nose-up; k3 > 0 hardening"
    }
    fn force(
        &self,
        _grid: &[f64],
        t: &[f64],
        q: [f64; 2],
        _qd: [f64; 2],
        _q_dyn: f64,
        _chord: f64,
    ) -> [f64; 2] {
        [t[0] * q[0].powi(3), t[1] * q[1].powi(3)]
    }
}

impl Draw for StructuralCubic {
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("kappa [1/rad^2]", 0.5, 200.0)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        _cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::StructuralCubic { kappa: p },
            Vec::new(),
        )
    }
}
