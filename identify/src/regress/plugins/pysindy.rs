//! The pysindy plug-in: pysindy 2.1 STLSQ per case on the raw columns of the case's
//! identifiable basis ([`crate::regress::adapter`]), walking pysindy's `threshold` on raw
//! coefficients. The group support of a threshold is the union of the case supports; kept
//! terms do not apply (pysindy has none).
//!
//! The whole path of every case is computed once, when the case is prepared (the raw
//! library matrix is evaluated there and not kept).

use crate::regress::adapter::{self, PysindyOptions};
use crate::regress::plugin::{
    CaseData, CaseInput, FitSettings, GroupInput, OptionKind, OptionSpec, OptionValue,
    Options, PathFits, PathGrid, PathParameter, Regressor,
};
use crate::regress::{Mask, Measure};
use crate::Result;

/// pysindy-compatible STLSQ (`--regressor pysindy`).
#[derive(Debug, Clone, Copy)]
pub struct Pysindy;

/// The per-case data: per target (moment, lift), per threshold, raw coefficients.
struct CasePaths([Vec<Vec<f64>>; 2]);

const OPTIONS: &[OptionSpec] = &[
    OptionSpec {
        name: "alpha",
        kind: OptionKind::Float {
            min: 0.0,
            max: f64::INFINITY,
        },
        default: OptionValue::Float(0.05),
        doc: "ridge parameter on raw columns (pysindy default 0.05)",
    },
    OptionSpec {
        name: "max_iter",
        kind: OptionKind::Count {
            min: 1,
            max: 1_000_000,
        },
        default: OptionValue::Count(20),
        doc: "maximum iterations (pysindy default 20)",
    },
    OptionSpec {
        name: "unbias",
        kind: OptionKind::Flag,
        default: OptionValue::Flag(true),
        doc: "least-squares refit on the final support (pysindy default true)",
    },
];

fn options(o: &Options) -> PysindyOptions {
    PysindyOptions {
        alpha: o.float("alpha"),
        max_iter: o.count("max_iter") as usize,
        unbias: o.flag("unbias"),
    }
}

impl Regressor for Pysindy {
    fn name(&self) -> &'static str {
        "pysindy"
    }
    fn doc(&self) -> &'static str {
        "pysindy 2.1 STLSQ per case on raw columns (comparison mode; the group support is \
         the union of the case supports)."
    }
    fn options(&self) -> &'static [OptionSpec] {
        OPTIONS
    }
    fn path_parameter(&self, _shared: &FitSettings) -> PathParameter {
        PathParameter {
            name: "threshold",
            unit: "raw coefficient |xi_j| on raw columns",
            grid: PathGrid::Log {
                measure: Measure::Coefficient,
            },
        }
    }
    fn refits_by_least_squares(&self) -> bool {
        false
    }
    fn prepare_case(&self, case: &CaseInput<'_>) -> Result<Option<CaseData>> {
        let o = options(case.options);
        // comparison mode: pysindy works on the whole matrix
        let theta = case.library.evaluate(case.x);
        let paths = case
            .measured
            .map(|y| adapter::path_case(theta.as_ref(), case.basis, y, case.grid, &o));
        Ok(Some(Box::new(CasePaths(paths))))
    }
    fn fit_path(&self, group: &GroupInput<'_>, grid: &[f64]) -> PathFits {
        (0..grid.len()).map(|d| point(group, d)).collect()
    }
    fn walk_path(
        &self,
        group: &GroupInput<'_>,
        grid: &[f64],
        sink: &mut dyn FnMut(Mask, &[Vec<f64>]),
    ) {
        for d in 0..grid.len() {
            let (mask, coefs) = point(group, d);
            sink(mask, &coefs);
        }
    }
    /// The per-case paths are prepared once: the point is read from them.
    fn coefficients_at(
        &self,
        group: &GroupInput<'_>,
        _grid: &[f64],
        index: usize,
        _mask: Mask,
    ) -> Vec<Vec<f64>> {
        point(group, index).1
    }
}

/// Path point `d` of a group: the union of the case supports and, per case, its raw
/// coefficients (from the per-case paths of [`Regressor::prepare_case`]).
fn point(group: &GroupInput<'_>, d: usize) -> (Mask, Vec<Vec<f64>>) {
    let coefs: Vec<Vec<f64>> = group
        .data
        .iter()
        .map(|w| {
            w.and_then(|p| p.downcast_ref::<CasePaths>())
                .map(|p| p.0[group.target][d].clone())
                .unwrap_or_default()
        })
        .collect();
    let mask: Mask = coefs.iter().fold(0u64, |m, c| {
        m | c
            .iter()
            .enumerate()
            .fold(0u64, |a, (j, &x)| if x != 0.0 { a | 1 << j } else { a })
    });
    (mask, coefs)
}
