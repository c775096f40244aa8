//! `static_offset`: a mean angle offset α₀ (the model sits at α + α₀ when the rig reads
//! α): DC forces and, through the nonlinear terms, even harmonics.
//!
//! * Force level: Z = [1, α², (Bα̇/U)², α·Bα̇/U] with β shared by every node (a DC force
//!   per dynamic pressure and the even terms an angle offset induces through odd
//!   nonlinear terms).
//! * System level: a constant force and moment, either constant in U (a structural zero
//!   offset) or ∝ ½ρU² (an aerodynamic mean-angle offset), chosen by training error (3
//!   parameters). Scored beyond the forced range too: its evidence is the runs' mean
//!   force (K = 0), which no error of the law's extrapolation in K can produce from the
//!   zero-mean response of an effect-free section (issue 29, DECISIONS "Static offsets
//!   scored beyond coverage").
//! * Generator: α₀ 0.02°–2°.

use aeroelastic::effects::{Form, InjectedEffect};

use super::entry::{Draw, DrawContext, Entry};
use super::Level;
use crate::force::candidates::{shared, Context, ForceFit, Scored};
use crate::force::data::CaseData;
use crate::system::candidates::{Column, Grid, SystemTerm};
use crate::system::residual::RunResidual;

/// The `static_offset` entry.
pub(crate) struct StaticOffset;

impl Entry for StaticOffset {
    fn name(&self) -> &'static str {
        "static_offset"
    }
    fn short_label(&self) -> &'static str {
        "offset"
    }
    fn level(&self) -> Level {
        Level::Aerodynamic
    }
    fn scored_beyond_coverage(&self) -> bool {
        true
    }
    fn force(&self) -> Option<&dyn ForceFit> {
        Some(self)
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

/// The force-level columns of a case: 1, α², (Bα̇/U)², α·Bα̇/U.
fn columns(c: &CaseData, _ch: usize) -> Vec<Vec<f64>> {
    let x = &c.nd.x;
    vec![
        vec![1.0; c.n],
        x[0].iter().map(|a| a * a).collect(),
        x[1].iter().map(|a| a * a).collect(),
        x[0].iter().zip(&x[1]).map(|(a, b)| a * b).collect(),
    ]
}

impl ForceFit for StaticOffset {
    fn fit(&self, cx: &Context<'_>) -> Scored {
        shared(cx, &columns)
    }
}

impl SystemTerm for StaticOffset {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &["offset_coefficient_lift", "offset_coefficient_moment"]
    }
    fn grids(&self, _runs: &[RunResidual]) -> Grid {
        vec![
            (vec![("proportional_to_q_dyn".into(), 0.0)], vec![0.0]),
            (vec![("proportional_to_q_dyn".into(), 1.0)], vec![1.0]),
        ]
    }
    fn n_grid_params(&self) -> usize {
        1
    }
    fn columns(&self, grid: &[f64], run: &RunResidual, rho: f64, chord: f64) -> Vec<Column> {
        let s = if grid[0] > 0.5 {
            0.5 * rho * run.u * run.u
        } else {
            1.0
        };
        let n = run.len();
        vec![
            [vec![s * chord; n], Vec::new()],
            [Vec::new(), vec![s * chord * chord; n]],
        ]
    }
    fn convention(&self) -> &'static str {
        "constant lift (positive down) and moment (positive nose-up) coefficients, × ½ρU² \
         when proportional_to_q_dyn = 1"
    }
    fn force(
        &self,
        grid: &[f64],
        t: &[f64],
        _q: [f64; 2],
        _qd: [f64; 2],
        q_dyn: f64,
        chord: f64,
    ) -> [f64; 2] {
        let s = if grid[0] > 0.5 { q_dyn } else { 1.0 };
        [t[0] * s * chord, t[1] * s * chord * chord]
    }
}

impl Draw for StaticOffset {
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("alpha0 [deg]", 0.02, 2.0)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        _cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::StaticOffset {
                alpha0: p.to_radians(),
            },
            Vec::new(),
        )
    }
}
