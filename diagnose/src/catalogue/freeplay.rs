//! `freeplay`: a pitch dead band of the spring: the frequency falls at small amplitude.
//!
//! * System level: k·clamp(α, −δ, δ), the spring force missing inside a gap of half width
//!   δ (δ on a grid 0.05°…3°, k fitted: 2 parameters); a negative k is no dead band.
//! * Not at the bifurcation level (a sharp gap is not a smooth vector field).
//! * Generator: half gap 0.001°–1°.

use aeroelastic::effects::{Form, InjectedEffect};

use super::entry::{Draw, DrawContext, Entry};
use super::Level;
use crate::system::candidates::{acc_term, Column, Grid, SystemTerm};
use crate::system::residual::RunResidual;

/// Half-gap grid of the system-level fit \[deg\].
pub(crate) const GRID_DEG: [f64; 14] = [
    0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0, 1.4, 2.0, 2.5, 3.0,
];

/// The `freeplay` entry.
pub(crate) struct Freeplay;

impl Entry for Freeplay {
    fn name(&self) -> &'static str {
        "freeplay"
    }
    fn short_label(&self) -> &'static str {
        "freepl"
    }
    fn level(&self) -> Level {
        Level::Structural
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn not_at_bifurcation(&self) -> Option<&'static str> {
        Some(
            "freeplay: a sharp gap is not a smooth vector field; continuation of periodic \
             orbits refuses it (use `aeroform lco` time integration)",
        )
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl SystemTerm for Freeplay {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &["gap_stiffness_Nm_per_rad"]
    }
    fn grids(&self, _runs: &[RunResidual]) -> Grid {
        GRID_DEG
            .iter()
            .map(|d| {
                (
                    vec![("half_gap_rad".into(), d.to_radians())],
                    vec![d.to_radians()],
                )
            })
            .collect()
    }
    fn n_grid_params(&self) -> usize {
        1
    }
    fn columns(&self, grid: &[f64], run: &RunResidual, _rho: f64, _chord: f64) -> Vec<Column> {
        let d = grid[0];
        let x: Vec<f64> = run.q[1].iter().map(|a| a.clamp(-d, d)).collect();
        vec![[Vec::new(), acc_term(run, &x)]]
    }
    fn sign_bound(&self) -> bool {
        true
    }
    fn convention(&self) -> &'static str {
        "pitch restoring moment lost inside the gap: gap_stiffness·clamp(α, −half_gap, \
         half_gap) [N·m/m] (gap_stiffness ≈ k_α for a true dead band)"
    }
    fn force(
        &self,
        grid: &[f64],
        t: &[f64],
        q: [f64; 2],
        _qd: [f64; 2],
        _q_dyn: f64,
        _chord: f64,
    ) -> [f64; 2] {
        let d = grid[0];
        [0.0, t[0] * q[1].clamp(-d, d)]
    }
}

impl Draw for Freeplay {
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("half gap [deg]", 0.001, 1.0)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        _cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::Freeplay {
                half_gap: p.to_radians(),
            },
            Vec::new(),
        )
    }
}
