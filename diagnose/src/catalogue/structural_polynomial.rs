//! `structural_polynomial`: a structural stiffness polynomial with even and odd terms,
//! k₂q² + k₃q³ per DOF (an asymmetric or softening–hardening spring: a subcritical Hopf
//! with a fold). It holds [`super::structural_cubic`]'s terms.
//!
//! * System level: k₂h² + k₃h³ and k₂α² + k₃α³ springs (4 coefficients; forms pitch,
//!   heave, both).
//! * Bifurcation level: pitch k₃α³ + k₂α², then to α⁵, with heave h³, and with heave
//!   h³ + h² (each extending the one before).
//! * Generator (drawn when asked by name): k_α(α + c₂α² + c₃α³), hardening |c₃| 0.5–200
//!   or softening 0.2–5, the signs from the set's seed.

use aeroelastic::effects::{Form, InjectedEffect};
use aeroelastic::section::Section;

use super::entry::{log_map, Draw, DrawContext, Entry};
use crate::bifurcation::candidates::{stiffness_param, BranchCandidate, Change, Dof, Scales};
use super::{Effect, Level};
use crate::system::candidates::{acc_term, Column, SystemTerm};
use crate::system::residual::RunResidual;

/// The `structural_polynomial` entry.
pub(crate) struct StructuralPolynomial;

impl Entry for StructuralPolynomial {
    fn name(&self) -> &'static str {
        "structural_polynomial"
    }
    fn short_label(&self) -> &'static str {
        "s.poly"
    }
    fn level(&self) -> Level {
        Level::Structural
    }
    fn extends(&self) -> Option<Effect> {
        Some(Effect::StructuralCubic)
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn bifurcation(&self, base: &Section, s: Scales) -> Vec<BranchCandidate> {
        let st = &base.structure;
        let (ka, kh) = (st.k_alpha, super::heave_stiffness_scale(base, s));
        let e = Effect::StructuralPolynomial;
        vec![
            BranchCandidate::new(
                e,
                "pitch",
                vec![
                    stiffness_param(Dof::Pitch, 3, ka, s.alpha),
                    stiffness_param(Dof::Pitch, 2, ka, s.alpha),
                ],
                Some((Effect::StructuralCubic, "pitch")),
                Change::PitchStiffness(&[3, 2]),
            ),
            BranchCandidate::new(
                e,
                "pitch to α⁵",
                vec![
                    stiffness_param(Dof::Pitch, 3, ka, s.alpha),
                    stiffness_param(Dof::Pitch, 2, ka, s.alpha),
                    stiffness_param(Dof::Pitch, 5, ka, s.alpha),
                ],
                Some((e, "pitch")),
                Change::PitchStiffness(&[3, 2, 5]),
            ),
            BranchCandidate::new(
                e,
                "pitch, heave h³",
                vec![
                    stiffness_param(Dof::Pitch, 3, ka, s.alpha),
                    stiffness_param(Dof::Pitch, 2, ka, s.alpha),
                    stiffness_param(Dof::Heave, 3, kh, s.h),
                ],
                Some((e, "pitch")),
                Change::PitchHeaveStiffness(&[3, 2], &[3]),
            ),
            BranchCandidate::new(
                e,
                "pitch+heave",
                vec![
                    stiffness_param(Dof::Pitch, 3, ka, s.alpha),
                    stiffness_param(Dof::Pitch, 2, ka, s.alpha),
                    stiffness_param(Dof::Heave, 3, kh, s.h),
                    stiffness_param(Dof::Heave, 2, kh, s.h),
                ],
                Some((e, "pitch, heave h³")),
                Change::PitchHeaveStiffness(&[3, 2], &[3, 2]),
            ),
        ]
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl SystemTerm for StructuralPolynomial {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &[
            "k2_heave_N_per_m2",
            "k3_heave_N_per_m3",
            "k2_pitch_Nm_per_rad2",
            "k3_pitch_Nm_per_rad3",
        ]
    }
    fn columns(&self, _grid: &[f64], run: &RunResidual, _rho: f64, _chord: f64) -> Vec<Column> {
        let p = |c: usize, k: i32| {
            acc_term(run, &run.q[c].iter().map(|v| v.powi(k)).collect::<Vec<_>>())
        };
        vec![
            [p(0, 2), Vec::new()],
            [p(0, 3), Vec::new()],
            [Vec::new(), p(1, 2)],
            [Vec::new(), p(1, 3)],
        ]
    }
    fn forms(&self) -> Vec<(&'static str, Vec<usize>)> {
        vec![
            ("pitch", vec![2, 3]),
            ("heave", vec![0, 1]),
            ("pitch+heave", vec![0, 1, 2, 3]),
        ]
    }
    fn report_sign(&self) -> f64 {
        -1.0
    }
    fn convention(&self) -> &'static str {
        "extra restoring force added to K q: heave k2_heave·h² + k3_heave·h³ [N/m], \
         pitch k2_pitch·α² + k3_pitch·α³ [N·m/m]; h positive down, α positive nose-up"
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
        [
            t[0] * q[0].powi(2) + t[1] * q[0].powi(3),
            t[2] * q[1].powi(2) + t[3] * q[1].powi(3),
        ]
    }
}

impl Draw for StructuralPolynomial {
    fn generated(&self) -> bool {
        false
    }
    fn writes_drawn(&self) -> bool {
        false
    }
    // |c₃| of k_α(α + c₂α² + c₃α³); the sign and c₂ are drawn with it ([`Draw::inject`]):
    // hardening 0.5…200, softening 0.2…5
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("|c3| [1/rad^2]", 0.5, 200.0)
    }
    fn inject(
        &self,
        p: f64,
        s: f64,
        _form: Form,
        cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        // signs of c₂ and c₃ from the set's seed; the spring's slope 1 + 2c₂α + 3c₃α²
        // stays positive (hardening: c₂² < 3c₃ · 0.5) or positive beyond 15° (softening)
        let bits = identify::numerics::split_seed(cx.seed, 41);
        let soft = bits & 1 == 1;
        let s2 = if bits & 2 == 2 { -1.0 } else { 1.0 };
        let (c3, c2) = if soft {
            (-log_map(s, 0.2, 5.0), s2 * log_map(s, 0.05, 1.0))
        } else {
            let c3 = p;
            (c3, s2 * log_map(s, 0.05, 8.0).min((1.5 * c3).sqrt()))
        };
        (
            InjectedEffect::StructuralPolynomial { c2, c3 },
            vec![("c2 [1/rad]".into(), c2), ("c3 [1/rad^2]".into(), c3)],
        )
    }
}
