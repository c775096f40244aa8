//! The STLSQ plug-in: (group) STLSQ (paper Alg. 1, Alg. 2) on the column-normalised basis,
//! walking the threshold δ on the settings' measure ([`crate::regress::Measure`]).
//!
//! Each δ of the grid runs [`crate::regress::fit_group`] with
//! `Stlsq { threshold: δ, .. }` from the whole basis, never removing the kept terms; one
//! memo of support fits serves the whole path.

use crate::regress::plugin::{
    FitSettings, GroupInput, PathFits, PathGrid, PathParameter, Regressor,
};
use crate::regress::{self, vec_to_mask, CaseProblem, FitCache, GroupFit, Mask};

/// STLSQ (the default regressor); its options are the settings' `measure`, `group_rule`,
/// `ridge` and `max_iter` ([`FitSettings`]).
#[derive(Debug, Clone, Copy)]
pub struct Stlsq;

impl Regressor for Stlsq {
    fn name(&self) -> &'static str {
        "stlsq"
    }
    fn doc(&self) -> &'static str {
        "(group) STLSQ on the column-normalised basis (paper Alg. 1-2); uses the settings' \
         measure, group_rule, ridge and max_iter."
    }
    fn path_parameter(&self, shared: &FitSettings) -> PathParameter {
        PathParameter {
            name: "delta",
            unit: match shared.measure {
                regress::Measure::Contribution => "contribution |xi_j theta_j|/|y|",
                regress::Measure::Coefficient => "raw coefficient |xi_j|",
            },
            grid: PathGrid::Log {
                measure: shared.measure,
            },
        }
    }
    fn refits_by_least_squares(&self) -> bool {
        true
    }
    fn fit_path(&self, group: &GroupInput<'_>, grid: &[f64]) -> PathFits {
        let mut out = Vec::with_capacity(grid.len());
        self.walk_path(group, grid, &mut |mask, coefs| out.push((mask, coefs.to_vec())));
        out
    }
    fn walk_path(
        &self,
        group: &GroupInput<'_>,
        grid: &[f64],
        sink: &mut dyn FnMut(Mask, &[Vec<f64>]),
    ) {
        let template = template(&group.shared);
        let mut cache = FitCache::default();
        for &d in grid {
            let f = fit_at(group.cases, &template, d, group.basis, group.kept, &mut cache);
            sink(vec_to_mask(&f.support), &f.coefficients);
        }
    }
    /// The fit of a point is the least-squares refit on its final support (STLSQ
    /// unbiases; [`regress::fit_group`]'s last step), a function of the support alone: one
    /// QR solve per case on `mask`, the numbers of the path.
    fn coefficients_at(
        &self,
        group: &GroupInput<'_>,
        _grid: &[f64],
        _index: usize,
        mask: Mask,
    ) -> Vec<Vec<f64>> {
        regress::exact_fit_over_library(group.cases, mask)
    }
}

/// The STLSQ optimiser of the shared settings (threshold 0: set per δ).
fn template(s: &FitSettings) -> regress::Stlsq {
    regress::Stlsq {
        threshold: 0.0,
        measure: s.measure,
        group_rule: s.group_rule,
        ridge: s.ridge,
        max_iter: s.max_iter,
    }
}

fn fit_at(
    cases: &[CaseProblem<'_>],
    template: &regress::Stlsq,
    delta: f64,
    basis: Mask,
    kept: Mask,
    cache: &mut FitCache,
) -> GroupFit {
    let reg = regress::Stlsq {
        threshold: delta,
        ..*template
    };
    regress::fit_group(cases, &reg, basis, kept & basis, cache)
}
