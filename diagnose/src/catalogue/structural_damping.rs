//! `structural_damping`: amplitude-dependent structural damping, c₂q²q̇ per DOF (damping
//! that grows with amplitude, the opposite trend of dry friction).
//!
//! * System level: c₂h²ḣ, c₂α²α̇ (2 coefficients; forms pitch, heave, both).
//! * Bifurcation level: c₂α²α̇ in pitch, then in pitch and heave.
//! * Generator (drawn when asked by name): d 10–5000 rad⁻².

use aeroelastic::effects::{Form, InjectedEffect};
use aeroelastic::section::Section;

use super::entry::{Draw, DrawContext, Entry};
use crate::bifurcation::candidates::{param, BranchCandidate, Change, Scales};
use super::{Effect, Level};
use crate::system::candidates::{acc_term, Column, SystemTerm};
use crate::system::residual::RunResidual;

/// The `structural_damping` entry.
pub(crate) struct StructuralDamping;

impl Entry for StructuralDamping {
    fn name(&self) -> &'static str {
        "structural_damping"
    }
    fn short_label(&self) -> &'static str {
        "s.damp"
    }
    fn level(&self) -> Level {
        Level::Structural
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn bifurcation(&self, base: &Section, s: Scales) -> Vec<BranchCandidate> {
        let st = &base.structure;
        let kh = super::heave_stiffness_scale(base, s);
        // A damping scale of a 5 % damping ratio on the uncoupled mode at the reference
        // amplitude (the nominal c may be zero).
        let ca = 0.1 * (st.k_alpha * st.inertia_alpha).sqrt();
        let ch = 0.1 * (kh * st.mass).sqrt();
        let pitch = || {
            param(
                "c2_pitch",
                "N m s/rad^3",
                "extra pitch damping moment c2·α²·α̇ (c2 > 0 dissipates)",
                ca / (s.alpha * s.alpha),
            )
        };
        let e = Effect::StructuralDamping;
        vec![
            BranchCandidate::new(e, "pitch", vec![pitch()], None, Change::PitchDamping),
            BranchCandidate::new(
                e,
                "pitch+heave",
                vec![
                    pitch(),
                    param(
                        "c2_heave",
                        "N s/m^3",
                        "extra heave damping force c2·h²·ḣ (c2 > 0 dissipates)",
                        ch / (s.h * s.h),
                    ),
                ],
                Some((e, "pitch")),
                Change::PitchHeaveDamping,
            ),
        ]
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl SystemTerm for StructuralDamping {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &["c2_heave_Ns_per_m3", "c2_pitch_Nms_per_rad3"]
    }
    fn columns(&self, _grid: &[f64], run: &RunResidual, _rho: f64, _chord: f64) -> Vec<Column> {
        let p = |c: usize| -> Vec<f64> {
            let x: Vec<f64> = run.q[c]
                .iter()
                .zip(&run.qd[c])
                .map(|(q, v)| q * q * v)
                .collect();
            acc_term(run, &x)
        };
        vec![[p(0), Vec::new()], [Vec::new(), p(1)]]
    }
    fn forms(&self) -> Vec<(&'static str, Vec<usize>)> {
        super::dof_forms()
    }
    fn report_sign(&self) -> f64 {
        -1.0
    }
    fn convention(&self) -> &'static str {
        "extra damping force added to C q̇: c2_heave·h²ḣ [N/m], c2_pitch·α²α̇ [N·m/m]; \
         c2 > 0 damping that grows with amplitude"
    }
    fn force(
        &self,
        _grid: &[f64],
        t: &[f64],
        q: [f64; 2],
        qd: [f64; 2],
        _q_dyn: f64,
        _chord: f64,
    ) -> [f64; 2] {
        [t[0] * q[0].powi(2) * qd[0], t[1] * q[1].powi(2) * qd[1]]
    }
}

impl Draw for StructuralDamping {
    fn generated(&self) -> bool {
        false
    }
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("d [1/rad^2]", 10.0, 5000.0)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        _cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::StructuralDamping { d: p },
            Vec::new(),
        )
    }
}
