//! The least-squares plug-in: plain least squares on the whole identifiable basis, no path
//! (one point, reported as δ = 0).

use crate::regress::plugin::{
    FitSettings, GroupInput, PathFits, PathGrid, PathParameter, Regressor,
};
use crate::regress::{self, FitCache, Mask};

/// Plain least squares (`--regressor least_squares`, alias `lsq`).
#[derive(Debug, Clone, Copy)]
pub struct LeastSquares;

impl Regressor for LeastSquares {
    fn name(&self) -> &'static str {
        "least_squares"
    }
    fn aliases(&self) -> &'static [&'static str] {
        &["lsq"]
    }
    fn doc(&self) -> &'static str {
        "plain least squares on the whole identifiable basis (no path)."
    }
    fn path_parameter(&self, _shared: &FitSettings) -> PathParameter {
        PathParameter {
            name: "none",
            unit: "-",
            grid: PathGrid::Fixed(&[0.0]),
        }
    }
    fn refits_by_least_squares(&self) -> bool {
        true
    }
    fn fit_path(&self, group: &GroupInput<'_>, grid: &[f64]) -> PathFits {
        let mut cache = FitCache::default();
        let fit = regress::fit_group(
            group.cases,
            &regress::LeastSquares,
            group.basis,
            group.basis,
            &mut cache,
        );
        grid.iter()
            .map(|_| (group.basis, fit.coefficients.clone()))
            .collect()
    }
    /// Every point is the least-squares fit on the whole basis (`mask`): one QR solve per
    /// case, the numbers of the path.
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
