//! The force level's fitting machinery for the candidate augmentations of the catalogue.
//! Each effect's fit is a generic form (not the virtual generator's), written in its own
//! file of [`crate::catalogue`] on top of this machinery, fitted on the training folds
//! and scored on the held-out folds.
//!
//! **Fitting.** An augmentation adds columns Z (nondimensional regressors) to every case
//! with coefficients β *shared by all nodes* (so they carry across wind speeds,
//! amplitudes and configurations), fitted jointly with the per-node law
//! ([`super::law::fit_channel`]): [`shared`] for fixed columns, [`sparse`] for a forward
//! selection from a pool of columns. Hyperparameters (critical angle, lag, Strouhal
//! number, sparse term choice) are chosen per fold on the training nodes only, by the
//! training residual in noise units.
//!
//! **Score and significance.** E = Σ (r/σ̂)² over held-out samples and channels (noise
//! units). With p shared parameters (β and hyperparameters) and q nuisance parameters:
//! * score (ranking, lower is better) = (E_after + 2(p + q)) / N, N the number of samples
//!   (an AIC-like parsimony penalty in noise units);
//! * statistic z = (E_before − E_after − q) / √(2(p + q)) (see [`significance`]): the
//!   improvement beyond what q fitted nuisance parameters give on pure noise, in standard
//!   deviations of that null improvement (√(2q) for χ²_q), with 2p added for the shared
//!   parameters;
//! * significant ⇔ z > `opts.significance` **and** the candidate removes at least
//!   `opts.min_shrink` of the excess energy E_before − N (the baseline's own interpolation
//!   error is systematic, so a test in noise units alone would call tiny improvements
//!   significant).

use identify::library::Term;

use super::data::{CaseData, Node};
use super::folds::{fold_residuals, Fold};
use super::law::{self, Aug, NodeCache, NodeFit};
use crate::numerics::{dot, ridge_solve};

/// Default significance threshold (z, standard deviations of the null improvement).
pub const DEFAULT_SIGNIFICANCE: f64 = 4.0;
/// Default minimum share of the excess residual energy a significant candidate removes.
pub const DEFAULT_MIN_SHRINK: f64 = 0.3;
/// Minimum training improvement (noise units) of a forward-selection step.
pub const STEP_GAIN: f64 = 50.0;

/// What an effect's force-level fit sees: the prepared cases and nodes, the folds, the
/// baseline's held-out residuals and the node factorisations' cache.
pub(crate) struct Context<'a> {
    pub cases: &'a [CaseData],
    pub nodes: &'a [Node],
    pub folds: &'a [Fold],
    /// Held-out residuals of the baseline law, `[case][channel]`.
    pub before: &'a [[Vec<f64>; 2]],
    pub cache: &'a NodeCache,
    /// Cache key of the effect's columns (unique within a run).
    pub key: &'a str,
}

/// One fold's split of the nodes: its index, training and held-out nodes (indices into
/// the level's nodes), what a form fitted without the folds' factorisations needs.
pub(crate) struct Split {
    pub index: usize,
    pub train: Vec<usize>,
    pub test: Vec<usize>,
}

/// What an effect's early form sees ([`ForceFit::early`]): the prepared cases and nodes
/// and the folds' splits, known before any fold is identified.
pub(crate) struct EarlyContext<'a> {
    pub cases: &'a [CaseData],
    pub nodes: &'a [Node],
    pub splits: &'a [Split],
}

/// An effect's early form: its scored held-out result, or the reason it was refused.
pub(crate) type Early = Result<Scored, String>;

/// The function that fits an effect's early form ([`ForceFit::early`]).
pub(crate) type EarlyForm = fn(&EarlyContext<'_>) -> Early;

/// An effect's fit at the force level: its held-out residuals and fitted parameters.
pub(crate) trait ForceFit: Sync {
    /// Fits the augmentation per fold on the training nodes and returns the held-out
    /// residuals of every case (`Scored::residuals`), the parameter counts and the
    /// parameters (mean over folds, or per fold).
    fn fit(&self, cx: &Context<'_>) -> Scored;

    /// A second form of the effect that needs only the folds' splits of the nodes, not
    /// their identifications or factorisations: when the held-out gap is significant the
    /// force level starts it beside every [`ForceFit::fit`] (a long serial fit started last
    /// would leave a core idle at the end) and hands it with the effect's `fit` to
    /// [`ForceFit::choose`]; otherwise it is not fitted (the candidate's `note` says so).
    /// Returned as the function that fits it, so that whether an effect has the form is
    /// known without fitting it. `None` (the default): the effect has no such form.
    fn early(&self) -> Option<EarlyForm> {
        None
    }

    /// The effect's result from its [`ForceFit::fit`] (`fitted`) and its early form
    /// (`early`, when [`ForceFit::early`] gave one). Default: `fitted`.
    fn choose(&self, _cases: &[CaseData], fitted: Scored, _early: Early) -> Scored {
        fitted
    }
}

/// A scored candidate: its held-out residuals and fitted parameters.
#[derive(Debug, Clone)]
pub(crate) struct Scored {
    pub residuals: Vec<[Vec<f64>; 2]>,
    /// Shared parameters (β and hyperparameters, summed over channels, mean over folds).
    pub n_params: usize,
    /// Nuisance parameters fitted on held-out data.
    pub n_nuisance: usize,
    pub parameters: Vec<(String, f64)>,
    pub failure: Option<String>,
}

/// One column of a selection pool ([`sparse`]).
pub(crate) trait PoolColumn: Sync {
    /// Name written in the fitted parameters.
    fn name(&self) -> String;
    /// The column's series on case `c` (nondimensional, one value per sample).
    fn column(&self, c: &CaseData) -> Vec<f64>;
}

/// A candidate whose columns `cols(case, channel)` are fixed (no hyperparameter): β
/// fitted per fold and channel, reported as `lift_beta0`, … (mean over folds).
pub(crate) fn shared(
    cx: &Context<'_>,
    cols: &(dyn Fn(&CaseData, usize) -> Vec<Vec<f64>> + Sync),
) -> Scored {
    let (cases, nodes, folds) = (cx.cases, cx.nodes, cx.folds);
    let mut res = vec![[Vec::new(), Vec::new()]; cases.len()];
    let extra = |i: usize, c: usize| cols(&cases[i], c);
    let aug = Aug {
        key: cx.key,
        cols: &extra,
        subset: None,
        pick: None,
    };
    let mut betas: Vec<Vec<f64>> = vec![Vec::new(); 2];
    for f in folds {
        for c in 0..2 {
            let l = fold_residuals(cases, nodes, f, c, aug, &mut res);
            if betas[c].is_empty() {
                betas[c] = vec![0.0; l.beta.len()];
            }
            for (a, b) in betas[c].iter_mut().zip(&l.beta) {
                *a += b / folds.len() as f64;
            }
        }
    }
    let m = betas[0].len() + betas[1].len();
    let mut parameters = Vec::new();
    for (c, name) in ["lift", "moment"].iter().enumerate() {
        for (j, b) in betas[c].iter().enumerate() {
            parameters.push((format!("{name}_beta{j}"), *b));
        }
    }
    Scored {
        residuals: res,
        n_params: m,
        n_nuisance: 0,
        parameters,
        failure: None,
    }
}

/// Projected Gram statistics of a pool on one fold and channel (noise-weighted).
struct PoolStats {
    g: Vec<Vec<f64>>,
    b: Vec<f64>,
    /// Number of leading shared (nonlinear law) columns.
    shared: usize,
    /// bᵀ G⁻¹ b of the shared columns alone.
    base: f64,
}

/// Pool statistics with the section's `ms` shared nonlinear columns first: the gain of a
/// pool subset is measured on top of them.
fn pool_stats(
    cases: &[CaseData],
    nodes: &[Node],
    fits: &[NodeFit],
    shared: &[Term],
    c: usize,
    aug: Aug<'_>,
) -> PoolStats {
    let key = law::shared_key(shared, aug.key);
    let cols = law::with_shared(cases, shared, aug);
    let all = Aug {
        key: &key,
        cols: &cols,
        subset: None,
        pick: None,
    };
    let mut g: Vec<Vec<f64>> = Vec::new();
    let mut b: Vec<f64> = Vec::new();
    for f in fits {
        let w = f.ch[c].w_pool;
        let w2 = w * w;
        let gr = all.gram(nodes, f, c);
        let m = gr.b.len();
        if g.is_empty() {
            g = vec![vec![0.0; m]; m];
            b = vec![0.0; m];
        }
        for j in 0..m {
            if gr.absorbed[j] {
                continue;
            }
            b[j] += w2 * gr.b[j];
            for k in j..m {
                if gr.absorbed[k] {
                    continue;
                }
                let v = w2 * gr.g[j][k];
                g[j][k] += v;
                g[k][j] = g[j][k];
            }
        }
    }
    let mut ps = PoolStats {
        g,
        b,
        shared: shared.len(),
        base: 0.0,
    };
    ps.base = ps.quad(&(0..ps.shared).collect::<Vec<_>>());
    ps
}

/// Training improvement (noise units) of a pool subset on top of the shared columns:
/// bᵀ G⁻¹ b over (shared ∪ set) minus the same over the shared columns alone.
fn gain(ps: &PoolStats, set: &[usize]) -> f64 {
    let with: Vec<usize> = (0..ps.shared)
        .chain(set.iter().map(|j| j + ps.shared))
        .collect();
    ps.quad(&with) - ps.base
}

impl PoolStats {
    /// bᵀ G⁻¹ b over the columns `idx`.
    fn quad(&self, idx: &[usize]) -> f64 {
        if idx.is_empty() {
            return 0.0;
        }
        let g: Vec<Vec<f64>> = idx
            .iter()
            .map(|&i| idx.iter().map(|&j| self.g[i][j]).collect())
            .collect();
        let b: Vec<f64> = idx.iter().map(|&i| self.b[i]).collect();
        ridge_solve(|i, j| g[i][j], &b, law::BETA_RIDGE).map_or(0.0, |x| dot(&x, &b))
    }
}

/// Forward selection of up to `max_terms` columns from `pool` per fold and channel (each
/// step kept only when it lowers the training residual by more than [`STEP_GAIN`] noise
/// units), then held-out scoring. Each chosen column counts 1 + `hyper` parameters (its β
/// and the hyperparameters that picked it from the pool).
pub(crate) fn sparse<P: PoolColumn>(
    cx: &Context<'_>,
    pool: &[P],
    max_terms: usize,
    hyper: usize,
) -> Scored {
    let (cases, nodes, folds) = (cx.cases, cx.nodes, cx.folds);
    let mut res = vec![[Vec::new(), Vec::new()]; cases.len()];
    let mut n_params = 0usize;
    let mut chosen_names: Vec<(String, f64)> = Vec::new();
    // Pool columns are computed where a node's Gram or a selected column needs them, not
    // held for every case: holding them (126 stall columns a case) was 144.5 of the 331 MB
    // heap peak of the free-response job; each use cloned the held pool anyway, and the
    // CPU time stayed within run-to-run noise (docs/DECISIONS.md, "Where the free-response
    // diagnosis's memory goes").
    let all = |i: usize, _c: usize| pool.iter().map(|p| p.column(&cases[i])).collect();
    let pick =
        |i: usize, _c: usize, s: &[usize]| s.iter().map(|&j| pool[j].column(&cases[i])).collect();
    let pool_aug = Aug {
        key: cx.key,
        cols: &all,
        subset: None,
        pick: Some(&pick),
    };
    warm_grams(cases, nodes, folds, pool_aug);
    for f in folds {
        for c in 0..2 {
            let ps = pool_stats(cases, nodes, &f.fits, &f.shared[c], c, pool_aug);
            let mut set: Vec<usize> = Vec::new();
            let mut cur = 0.0;
            while set.len() < max_terms {
                let best = (0..pool.len())
                    .filter(|j| !set.contains(j))
                    .map(|j| {
                        let mut s = set.clone();
                        s.push(j);
                        (j, gain(&ps, &s))
                    })
                    .max_by(|a, b| a.1.total_cmp(&b.1));
                match best {
                    Some((j, gn)) if gn - cur > STEP_GAIN => {
                        set.push(j);
                        cur = gn;
                    }
                    _ => break,
                }
            }
            n_params += set.len() * (1 + hyper);
            let aug = Aug {
                subset: Some(&set),
                ..pool_aug
            };
            let l = fold_residuals(cases, nodes, f, c, aug, &mut res);
            for (&j, b) in set.iter().zip(&l.beta) {
                chosen_names.push((
                    format!(
                        "fold{}_{}_{}",
                        f.index,
                        super::data::CHANNELS[c],
                        pool[j].name()
                    ),
                    *b,
                ));
            }
        }
    }
    Scored {
        residuals: res,
        n_params: n_params.div_ceil(folds.len().max(1)),
        n_nuisance: 0,
        parameters: chosen_names,
        failure: None,
    }
}

/// Computes, in parallel and each once, the per-node statistics ([`law::NodeGram`]) of
/// `aug`'s whole set after each fold's shared columns, on every training node and channel
/// of every fold, into the node factorisations' caches: what [`pool_stats`] and the folds'
/// fits then read (they are the same values computed on first use, serially). A
/// (node factorisation, column set) pair that several folds share is computed once.
fn warm_grams(cases: &[CaseData], nodes: &[Node], folds: &[Fold], aug: Aug<'_>) {
    use rayon::prelude::*;
    let mut seen = std::collections::HashSet::new();
    let mut tasks: Vec<(usize, usize, usize)> = Vec::new();
    for (k, f) in folds.iter().enumerate() {
        for c in 0..2 {
            let key = law::shared_key(&f.shared[c], aug.key);
            for (m, fit) in f.fits.iter().enumerate() {
                if seen.insert((std::sync::Arc::as_ptr(&fit.ch[c]) as usize, key.clone())) {
                    tasks.push((k, c, m));
                }
            }
        }
    }
    tasks.par_iter().for_each(|&(k, c, m)| {
        let f = &folds[k];
        let key = law::shared_key(&f.shared[c], aug.key);
        let cols = law::with_shared(cases, &f.shared[c], aug);
        let all = Aug {
            key: &key,
            cols: &cols,
            subset: None,
            pick: None,
        };
        all.gram(nodes, &f.fits[m], c);
    });
}

/// Noise-unit energy Σ (r/σ̂)² of held-out residuals `res` (`[case][channel]`) over cases
/// and channels, σ̂ each case's channel noise.
pub(crate) fn noise_energy(cases: &[CaseData], res: &[[Vec<f64>; 2]]) -> f64 {
    cases
        .iter()
        .zip(res)
        .map(|(c, r)| {
            (0..2)
                .map(|k| {
                    let s = c.sigma[k].max(1e-300);
                    r[k].iter().map(|v| (v / s) * (v / s)).sum::<f64>()
                })
                .sum::<f64>()
        })
        .sum()
}

/// Significance of a candidate: (statistic z, threshold, significant, excess share removed,
/// score). `e_before`, `e_after` in noise units, `n` samples, `p` shared and `q` nuisance
/// parameters; significant when z > `threshold` and the share ≥ `min_shrink`.
pub(crate) fn significance(
    e_before: f64,
    e_after: f64,
    n: f64,
    p: usize,
    q: usize,
    threshold: f64,
    min_shrink: f64,
) -> (f64, f64, bool, f64, f64) {
    let (p, q) = (p as f64, q as f64);
    let z = (e_before - e_after - q) / (2.0 * (p + q)).max(1.0).sqrt();
    let excess = (e_before - n).max(1e-300);
    let share = (e_before - e_after - q) / excess;
    let sig = z > threshold && share >= min_shrink;
    let score = (e_after + 2.0 * (p + q)) / n;
    (z, threshold, sig, share, score)
}
