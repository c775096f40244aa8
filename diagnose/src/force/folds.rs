//! The folds of the force level: which nodes each fold trains on and holds out, the
//! supports and factorisations of its training nodes, and the held-out residuals of a
//! law (optionally augmented) fitted on them.

use identify::library::Term;

use super::data::{CaseData, Node};
use super::law::{self, Aug, NodeFit, Supports};

/// One fold: its training and held-out nodes, the supports identified on its training
/// cases and the training nodes' factorisations.
pub(crate) struct Fold {
    pub index: usize,
    pub train: Vec<usize>,
    pub test: Vec<usize>,
    /// Linear support of each configuration (terms of degree ≤ 1, with the constant of a
    /// centred configuration): coefficients per node.
    pub supports: Supports,
    /// The section's nonlinear terms (lift, moment): one coefficient each, shared by every
    /// node.
    pub shared: [Vec<Term>; 2],
    pub fits: Vec<NodeFit>,
}

/// Held-out residuals r = measured − predicted, `[case][channel]` in C units, for the
/// augmentation `aug` ([`Aug::NONE`]: none).
pub(crate) fn held_out_residuals(
    cases: &[CaseData],
    nodes: &[Node],
    folds: &[Fold],
    aug: Aug<'_>,
) -> Vec<[Vec<f64>; 2]> {
    let mut out: Vec<[Vec<f64>; 2]> = vec![[Vec::new(), Vec::new()]; cases.len()];
    for f in folds {
        for c in 0..2 {
            fold_residuals(cases, nodes, f, c, aug, &mut out);
        }
    }
    out
}

/// Held-out residuals of one fold and channel into `out`; returns the fitted law.
pub(crate) fn fold_residuals(
    cases: &[CaseData],
    nodes: &[Node],
    f: &Fold,
    c: usize,
    aug: Aug<'_>,
    out: &mut [[Vec<f64>; 2]],
) -> law::ChannelLaw {
    let lawc = law::fit_channel(cases, nodes, &f.fits, &f.shared[c], c, aug);
    for &n in &f.test {
        for &i in &nodes[n].cases {
            let z = aug.columns(i, c);
            let p = law::predict(cases, nodes, &f.supports, &f.shared[c], &lawc, i, c, &z);
            out[i][c] = cases[i].y[c].iter().zip(&p).map(|(y, p)| y - p).collect();
        }
    }
    lawc
}
