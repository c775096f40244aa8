//! `time_delay`: forces lag the motion by a delay τ (balance or flow latency): a phase ωτ
//! absorbed by derivatives at the forcing frequency, visible across frequencies and in
//! free response.
//!
//! * Force level: no extra column: the law is identified on the motion delayed by τ
//!   (forces lagging the motion by τ), τ chosen per fold on the training nodes by the
//!   consistency of the linear transfers across configurations ([`time_delay`]).
//! * System level: the aerodynamic force delayed by τ, to first order F(t−τ) ≈ F − τḞ
//!   (1 coefficient τ shared by both channels).
//! * Not at the bifurcation level (the section model has no delay states).
//! * Generator: τ 0.1–20 ms.

use std::sync::Arc;

use aeroelastic::effects::{Form, InjectedEffect};

use super::entry::{Draw, DrawContext, Entry};
use super::Level;
use crate::force::candidates::{Context, ForceFit, Scored};
use crate::force::data::{CaseData, Node};
use crate::force::folds::{fold_residuals, Fold};
use crate::force::law::{self, Aug, NodeCache};
use crate::numerics::dot;
use crate::system::candidates::{Column, SystemTerm};
use crate::system::residual::RunResidual;

/// The `time_delay` entry.
pub(crate) struct TimeDelay;

impl Entry for TimeDelay {
    fn name(&self) -> &'static str {
        "time_delay"
    }
    fn short_label(&self) -> &'static str {
        "delay"
    }
    fn level(&self) -> Level {
        Level::Aerodynamic
    }
    fn force(&self) -> Option<&dyn ForceFit> {
        Some(self)
    }
    fn system(&self) -> Option<&dyn SystemTerm> {
        Some(self)
    }
    fn not_at_bifurcation(&self) -> Option<&'static str> {
        Some("time_delay: the section model has no delay states")
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl ForceFit for TimeDelay {
    fn fit(&self, cx: &Context<'_>) -> Scored {
        time_delay(cx)
    }
}

impl SystemTerm for TimeDelay {
    fn coefficient_names(&self) -> &'static [&'static str] {
        &["tau_s"]
    }
    fn columns(&self, _grid: &[f64], run: &RunResidual, _rho: f64, _chord: f64) -> Vec<Column> {
        let d = |f: &[f64]| -> Vec<f64> {
            (run.i0..run.i1)
                .map(|i| -(f[i + 1] - f[i - 1]) / (2.0 * run.dt))
                .collect()
        };
        vec![[d(&run.force[0]), d(&run.force[1])]]
    }
    fn convention(&self) -> &'static str {
        "aerodynamic force F(t − τ), τ > 0 a lag [s]"
    }
    fn delay(&self, theta: &[f64]) -> f64 {
        theta[0]
    }
}

impl Draw for TimeDelay {
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("tau [s]", 1e-4, 0.02)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        _cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::TimeDelay { tau: p },
            Vec::new(),
        )
    }
}

/// Copy of the cases whose regressors are the motion delayed by `tau` [s]: each variable's
/// harmonic part (its fit at the forcing frequencies) is replaced by the same harmonics
/// shifted by τ, x'(t) = x(t) + x̂(t − τ) − x̂(t), so noise and the non-harmonic remainder
/// are those of the baseline and τ = 0 reproduces it exactly. Without a harmonic fit the
/// series is shifted by linear interpolation (held at the start).
fn delayed_cases(cases: &[CaseData], tau: f64) -> Vec<CaseData> {
    cases
        .iter()
        .map(|c| {
            let mut d = c.clone();
            if tau == 0.0 {
                return d;
            }
            for k in 0..4 {
                match &c.rep[k] {
                    Some(h) => {
                        let mut diff = h.clone();
                        diff.mean = 0.0;
                        for j in 0..h.freqs.len() {
                            let (s, co) = (2.0 * std::f64::consts::PI * h.freqs[j] * tau).sin_cos();
                            let (a, b) = (h.cos[j], h.sin[j]);
                            diff.cos[j] = a * co - b * s - a;
                            diff.sin[j] = a * s + b * co - b;
                        }
                        let v = diff.values(c.n, c.dt);
                        d.nd.x[k].iter_mut().zip(&v).for_each(|(x, v)| *x += v);
                    }
                    None => {
                        let x = &c.nd.x[k];
                        let n = x.len();
                        d.nd.x[k] = (0..n)
                            .map(|i| {
                                let p = (i as f64 - tau / c.dt).max(0.0);
                                let j = (p.floor() as usize).min(n.saturating_sub(2));
                                let w = p - j as f64;
                                x[j] * (1.0 - w) + x[(j + 1).min(n - 1)] * w
                            })
                            .collect();
                    }
                }
            }
            d
        })
        .collect()
}

/// Leave-one-node-out energy (noise units) on a fold's training nodes of the law
/// identified on the motion delayed by τ: each training node's coefficients are predicted
/// from the other training nodes by the held-out rule ([`law::node_coefficients`]) and its
/// residual energy is ‖r_n‖² + ‖R_n(â_n − a_n)‖² (a_n the node's own least-squares fit,
/// X_n = Q_n R_n; dependent columns ignored), weighted by the node's mean 1/σ̂².
fn delay_criterion(sh: &[CaseData], nodes: &[Node], f: &Fold, tau: f64, cache: &NodeCache) -> f64 {
    let fits = law::node_fits(sh, nodes, &f.train, &f.supports, cache, tau.to_bits());
    let mut e = 0.0;
    for c in 0..2 {
        let full = law::fit_channel(sh, nodes, &fits, &f.shared[c], c, Aug::NONE);
        for (j, nf) in fits.iter().enumerate() {
            let mut loo = full.clone();
            loo.nodes.remove(j);
            let Some(&i0) = nodes[nf.node].cases.first() else {
                continue;
            };
            let ahat = law::node_coefficients(sh, nodes, &f.supports, &loo, i0, c);
            let a = &full.nodes[j].2;
            if ahat.len() != a.len() {
                // no other training node of this configuration (leave-one-group-out on
                // a configuration with two wind speeds): nothing to predict it from
                continue;
            }
            let qr = &nf.ch[c].qr;
            // the node's residual off its support after the shared nonlinear part
            let node = &nodes[nf.node];
            let mut y: Vec<f64> = node
                .cases
                .iter()
                .flat_map(|&i| sh[i].y[c].iter().copied())
                .collect();
            for (t, g) in f.shared[c].iter().zip(&full.shared) {
                let z = law::stacked_column(sh, node, t);
                y.iter_mut().zip(z).for_each(|(v, z)| *v -= g * z);
            }
            let r = &qr.residual(&y);
            let d: Vec<f64> = ahat.iter().zip(a).map(|(x, y)| x - y).collect();
            let rd = qr.r_times(&d);
            let en = dot(r, r) + dot(&rd, &rd);
            let w = nf.ch[c].w_mean;
            e += w * w * en;
        }
    }
    e
}

/// The cases delayed by one τ with their node factorisations: τ = 0 is the measured
/// motion itself (the run's cases and shared cache, version 0 = `0.0f64.to_bits()`), any
/// other τ a delayed copy ([`delayed_cases`]) with a cache of its own, dropped with it.
struct Shifted<'a> {
    tau: f64,
    cases: std::borrow::Cow<'a, [CaseData]>,
    own: NodeCache,
}

impl<'a> Shifted<'a> {
    fn new(cases: &'a [CaseData], tau: f64) -> Self {
        Shifted {
            tau,
            cases: if tau == 0.0 {
                std::borrow::Cow::Borrowed(cases)
            } else {
                std::borrow::Cow::Owned(delayed_cases(cases, tau))
            },
            own: NodeCache::default(),
        }
    }

    /// The node factorisations' cache: the run's for τ = 0, else this copy's own.
    fn cache<'b>(&'b self, run: &'b NodeCache) -> &'b NodeCache {
        if self.tau == 0.0 {
            run
        } else {
            &self.own
        }
    }
}

/// A held-out residual series: (case, channel, measured − predicted).
type HeldOut = (usize, usize, Vec<f64>);

/// Delays tried by the `time_delay` search \[s\] (coarse; refined by one parabola through
/// the best one and its neighbours).
pub const DELAY_GRID: [f64; 6] = [0.0, 1e-3, 3e-3, 8e-3, 0.02, 0.05];

/// `time_delay`: the law of every node is identified on the motion delayed by τ
/// ([`delayed_cases`]), τ ∈ [0, 50 ms] chosen per fold on the training nodes ([`DELAY_GRID`], parabolic refinement) by
/// the cross-configuration consistency of the linear transfers ([`delay_criterion`]: a
/// delay is a phase ωτ that depends on U as well as K, which the pooled prediction over K
/// cannot absorb), then scored on the held-out nodes. One shared parameter (τ).
fn time_delay(cx: &Context<'_>) -> Scored {
    use rayon::prelude::*;
    let (cases, nodes, folds) = (cx.cases, cx.nodes, cx.folds);
    // the grid is the same in every fold: one delayed copy per grid delay, its criterion in
    // every fold, then the copy dropped unless it is a fold's best so far (the copies and
    // their node factorisations are most of this candidate's memory)
    let mut vals = vec![Vec::with_capacity(DELAY_GRID.len()); folds.len()];
    let mut best: Vec<usize> = vec![0; folds.len()];
    let mut kept: Vec<Option<Arc<Shifted<'_>>>> = DELAY_GRID.iter().map(|_| None).collect();
    for (g, &t) in DELAY_GRID.iter().enumerate() {
        let sh = Arc::new(Shifted::new(cases, t));
        // fold after fold: the first fold fills the copy's node factorisations for the
        // next (folds in parallel would build the same nodes twice)
        let v: Vec<f64> = folds
            .iter()
            .map(|f| delay_criterion(&sh.cases, nodes, f, t, sh.cache(cx.cache)))
            .collect();
        for (fi, v) in v.into_iter().enumerate() {
            // the first of equal minima, as `min_by` over the grid
            if g == 0 || v < vals[fi][best[fi]] {
                best[fi] = g;
            }
            vals[fi].push(v);
        }
        kept[g] = Some(sh);
        for (k, slot) in kept.iter_mut().enumerate() {
            if !best.contains(&k) {
                *slot = None;
            }
        }
    }
    let per_fold: Vec<(f64, Vec<HeldOut>)> = folds
        .par_iter()
        .zip(&vals)
        .zip(&best)
        .map(|((f, vals), &kb)| {
            let (mut tau, best) = (DELAY_GRID[kb], vals[kb]);
            let mut sh = kept[kb].clone();
            // one parabola through the best grid point and its neighbours (unequal spacing)
            if kb > 0 && kb + 1 < DELAY_GRID.len() {
                let (x0, x1, x2) = (DELAY_GRID[kb - 1], DELAY_GRID[kb], DELAY_GRID[kb + 1]);
                let (y0, y1, y2) = (vals[kb - 1], vals[kb], vals[kb + 1]);
                let num = (x1 - x0).powi(2) * (y1 - y2) - (x1 - x2).powi(2) * (y1 - y0);
                let den = (x1 - x0) * (y1 - y2) - (x1 - x2) * (y1 - y0);
                if den.abs() > 0.0 {
                    let xv = x1 - 0.5 * num / den;
                    if xv > x0 && xv < x2 {
                        let refined = Arc::new(Shifted::new(cases, xv));
                        let v =
                            delay_criterion(&refined.cases, nodes, f, xv, refined.cache(cx.cache));
                        if v < best {
                            tau = xv;
                            sh = Some(refined);
                        }
                    }
                }
            }
            let sh = sh.unwrap_or_else(|| Arc::new(Shifted::new(cases, tau)));
            let fold = Fold {
                index: f.index,
                train: f.train.clone(),
                test: f.test.clone(),
                supports: f.supports.clone(),
                shared: f.shared.clone(),
                fits: law::node_fits(
                    &sh.cases,
                    nodes,
                    &f.train,
                    &f.supports,
                    sh.cache(cx.cache),
                    tau.to_bits(),
                ),
            };
            let mut res = vec![[Vec::new(), Vec::new()]; cases.len()];
            let mut out = Vec::new();
            for c in 0..2 {
                fold_residuals(&sh.cases, nodes, &fold, c, Aug::NONE, &mut res);
                for &n in &f.test {
                    for &i in &nodes[n].cases {
                        out.push((i, c, std::mem::take(&mut res[i][c])));
                    }
                }
            }
            (tau, out)
        })
        .collect();
    drop(kept);
    let mut res = vec![[Vec::new(), Vec::new()]; cases.len()];
    let mut taus = Vec::new();
    for (tau, out) in per_fold {
        taus.push(tau);
        for (i, c, r) in out {
            res[i][c] = r;
        }
    }
    let tau = taus.iter().sum::<f64>() / taus.len().max(1) as f64;
    let mut parameters = vec![("tau_s".into(), tau)];
    for (k, t) in taus.iter().enumerate() {
        parameters.push((format!("fold{k}_tau_s"), *t));
    }
    Scored {
        residuals: res,
        n_params: 1,
        n_nuisance: 0,
        parameters,
        failure: None,
    }
}
