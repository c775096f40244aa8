//! The force law of one fold: per (configuration, wind speed) node a coefficient vector on
//! the configuration's identified support (shared by the node's amplitudes), plus
//! augmentation coefficients β shared by every node; and its held-out prediction with the
//! node coefficients interpolated over K_α.
//!
//! Fit: min Σ_nodes ‖y_n − X_n a_n − Z_n β‖² by block elimination: β from the stacked
//! projections (I − P_n) Z_n, (I − P_n) y_n (P_n the projector on the node's support
//! columns), then a_n by least squares on y_n − Z_n β.

use identify::library::Term;

use super::data::{CaseData, Node};
use super::linalg::{dot, solve_spd, Qr};

/// Relative tolerance of dropped (dependent) columns.
const QR_TOL: f64 = 1e-9;
/// Relative ridge of the shared-coefficient solve (a direction the projected data do not
/// determine gets β ≈ 0 instead of an arbitrary value).
pub(crate) const BETA_RIDGE: f64 = 1e-9;

/// Support of each configuration (lift, moment).
pub(crate) type Supports = std::collections::BTreeMap<String, [Vec<Term>; 2]>;

/// Cached factorisation of a training node: stacked support columns and targets.
#[derive(Debug, Clone)]
pub(crate) struct NodeFit {
    pub node: usize,
    pub qr: [Qr; 2],
    /// Stacked targets (cases of the node in order).
    pub y: [Vec<f64>; 2],
    /// Stacked noise weights 1/σ̂ per sample (for chi-square units).
    pub w: [Vec<f64>; 2],
}

/// Builds the node factorisations of the training nodes.
pub(crate) fn node_fits(
    cases: &[CaseData],
    nodes: &[Node],
    train: &[usize],
    supports: &Supports,
) -> Vec<NodeFit> {
    train
        .iter()
        .map(|&n| {
            let node = &nodes[n];
            let sup = &supports[&node.config];
            let qr = std::array::from_fn(|c| {
                let cols: Vec<Vec<f64>> = sup[c]
                    .iter()
                    .map(|t| {
                        node.cases
                            .iter()
                            .flat_map(|&i| cases[i].column(t))
                            .collect()
                    })
                    .collect();
                let refs: Vec<&[f64]> = cols.iter().map(|v| v.as_slice()).collect();
                Qr::new(&refs, QR_TOL)
            });
            let y = std::array::from_fn(|c| {
                node.cases
                    .iter()
                    .flat_map(|&i| cases[i].y[c].iter().copied())
                    .collect()
            });
            let w = std::array::from_fn(|c| {
                node.cases
                    .iter()
                    .flat_map(|&i| {
                        let s = cases[i].sigma[c].max(1e-300);
                        std::iter::repeat_n(1.0 / s, cases[i].n)
                    })
                    .collect()
            });
            NodeFit { node: n, qr, y, w }
        })
        .collect()
}

/// A fitted law of one channel.
#[derive(Debug, Clone)]
pub(crate) struct ChannelLaw {
    /// Shared augmentation coefficients.
    pub beta: Vec<f64>,
    /// (node index, K_α, coefficients on the configuration's support).
    pub nodes: Vec<(usize, f64, Vec<f64>)>,
    /// Training residual sum of squares in noise units Σ (r/σ̂)².
    #[allow(dead_code)]
    pub rss_w: f64,
}

/// Extra (augmentation) columns of case `i`, channel `c`.
pub(crate) type Extra<'a> = &'a (dyn Fn(usize, usize) -> Vec<Vec<f64>> + Sync);

/// Fits channel `c` with shared columns `extra` on the training nodes. `targets` replaces
/// the measured targets when given (per node fit, stacked), e.g. for shifted data.
pub(crate) fn fit_channel(
    _cases: &[CaseData],
    nodes: &[Node],
    fits: &[NodeFit],
    c: usize,
    extra: Extra<'_>,
) -> ChannelLaw {
    // stacked extra columns per node
    let z: Vec<Vec<Vec<f64>>> = fits
        .iter()
        .map(|f| {
            let per_case: Vec<Vec<Vec<f64>>> =
                nodes[f.node].cases.iter().map(|&i| extra(i, c)).collect();
            let m = per_case.first().map_or(0, |v| v.len());
            (0..m)
                .map(|j| per_case.iter().flat_map(|v| v[j].iter().copied()).collect())
                .collect()
        })
        .collect();
    let m = z.first().map_or(0, |v| v.len());
    let mut beta = vec![0.0; m];
    if m > 0 {
        let mut g = vec![vec![0.0; m]; m];
        let mut b = vec![0.0; m];
        for (f, zn) in fits.iter().zip(&z) {
            // weighted by the node's noise level so that quiet and noisy nodes count alike
            let wn = mean(&f.w[c]);
            let w2 = wn * wn;
            // a column the node's support spans (projection below 1e-6 of its norm) is
            // absorbed by the node coefficients: it gets no weight (β = 0 by the ridge)
            let zt: Vec<Vec<f64>> = zn
                .iter()
                .map(|col| {
                    let r = f.qr[c].residual(col);
                    if dot(&r, &r) <= 1e-12 * dot(col, col) {
                        vec![0.0; r.len()]
                    } else {
                        r
                    }
                })
                .collect();
            let yt = f.qr[c].residual(&f.y[c]);
            for j in 0..m {
                b[j] += w2 * dot(&zt[j], &yt);
                for k in j..m {
                    let v = w2 * dot(&zt[j], &zt[k]);
                    g[j][k] += v;
                    if k != j {
                        g[k][j] += v;
                    }
                }
            }
        }
        beta = solve_spd(&g, &b, BETA_RIDGE).unwrap_or(beta);
    }
    let mut out = Vec::with_capacity(fits.len());
    let mut rss_w = 0.0;
    for (f, zn) in fits.iter().zip(&z) {
        let mut t = f.y[c].clone();
        for (j, col) in zn.iter().enumerate() {
            t.iter_mut().zip(col).for_each(|(a, b)| *a -= beta[j] * b);
        }
        let a = f.qr[c].solve(&t);
        let r = f.qr[c].residual(&t);
        rss_w += r
            .iter()
            .zip(&f.w[c])
            .map(|(r, w)| (r * w) * (r * w))
            .sum::<f64>();
        out.push((f.node, nodes[f.node].k_alpha, a));
    }
    ChannelLaw {
        beta,
        nodes: out,
        rss_w,
    }
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Interpolates node coefficient vectors over K_α (see [`interpolate_scalar`]).
pub(crate) fn interpolate(points: &[(f64, &[f64])], k: f64) -> Vec<f64> {
    let p = points.first().map_or(0, |x| x.1.len());
    let mut pts: Vec<(f64, &[f64])> = points.to_vec();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    (0..p)
        .map(|j| {
            let xy: Vec<(f64, f64)> = pts.iter().map(|(x, v)| (*x, v[j])).collect();
            interpolate_scalar(&xy, k)
        })
        .collect()
}

/// The interpolation rule of the held-out prediction, on nodes sorted by K: inside the
/// node range a quadratic through the three nearest nodes (linear with two nodes); outside
/// it a line through the two end nodes, evaluated at most one end spacing beyond the end
/// node and held constant further out (never a runaway extrapolation); one node: constant.
pub(crate) fn interpolate_scalar(xy: &[(f64, f64)], x: f64) -> f64 {
    let n = xy.len();
    match n {
        0 => 0.0,
        1 => xy[0].1,
        _ => {
            let (x0, xl) = (xy[0].0, xy[n - 1].0);
            if x < x0 || x > xl {
                let (a, b) = if x < x0 {
                    (xy[0], xy[1])
                } else {
                    (xy[n - 1], xy[n - 2])
                };
                let span = (b.0 - a.0).abs();
                let d = (x - a.0).clamp(-span, span);
                let slope = (b.1 - a.1) / (b.0 - a.0);
                return a.1 + slope * d;
            }
            if n == 2 {
                let w = (x - x0) / (xl - x0);
                return xy[0].1 * (1.0 - w) + xy[1].1 * w;
            }
            // three nearest nodes
            let mut idx: Vec<usize> = (0..n).collect();
            idx.sort_by(|&i, &j| (xy[i].0 - x).abs().total_cmp(&(xy[j].0 - x).abs()));
            let mut three = [idx[0], idx[1], idx[2]];
            three.sort();
            let (p0, p1, p2) = (xy[three[0]], xy[three[1]], xy[three[2]]);
            let l0 = (x - p1.0) * (x - p2.0) / ((p0.0 - p1.0) * (p0.0 - p2.0));
            let l1 = (x - p0.0) * (x - p2.0) / ((p1.0 - p0.0) * (p1.0 - p2.0));
            let l2 = (x - p0.0) * (x - p1.0) / ((p2.0 - p0.0) * (p2.0 - p1.0));
            p0.1 * l0 + p1.1 * l1 + p2.1 * l2
        }
    }
}

/// Lag poles of the rational function of the linear terms, in units of K (generic, not
/// the truth's: a Jones approximation of Theodorsen's function has 0.091 and 0.6).
pub(crate) const RFA_POLES: [f64; 3] = [0.08, 0.3, 1.0];

/// Complex basis of the transfer of a linear term pair (displacement d, rate d′) at reduced
/// frequency K: T(K) = ξ_d + iK ξ_d′ ≈ c₀ + c₁ iK + c₂ (iK)² + Σⱼ dⱼ iK/(iK + bⱼ) (Roger's
/// rational-function form; real coefficients, so T is realisable in time).
fn rfa_basis(k: f64) -> Vec<(f64, f64)> {
    let mut v = vec![(1.0, 0.0), (0.0, k), (-k * k, 0.0)];
    for b in RFA_POLES {
        // iK/(iK + b) = (K² + i K b)/(K² + b²)
        let d = k * k + b * b;
        v.push((k * k / d, k * b / d));
    }
    v
}

/// Fits the rational form of [`rfa_basis`] to (K, ξ_d, ξ_d′) nodes (least squares on real
/// and imaginary parts, a small relative ridge) and evaluates ξ_d, ξ_d′ at `k`. Falls back
/// to the per-configuration interpolation (None) with fewer than 4 nodes.
pub(crate) fn rfa_predict(nodes: &[(f64, f64, f64)], k: f64) -> Option<(f64, f64)> {
    if nodes.len() < 4 {
        return None;
    }
    let m = 3 + RFA_POLES.len();
    let mut g = vec![vec![0.0; m]; m];
    let mut b = vec![0.0; m];
    for &(kn, xd, xr) in nodes {
        let phi = rfa_basis(kn);
        let (re, im) = (xd, kn * xr);
        for j in 0..m {
            b[j] += phi[j].0 * re + phi[j].1 * im;
            for l in 0..m {
                g[j][l] += phi[j].0 * phi[l].0 + phi[j].1 * phi[l].1;
            }
        }
    }
    let c = solve_spd(&g, &b, 1e-10)?;
    let phi = rfa_basis(k);
    let re: f64 = phi.iter().zip(&c).map(|(p, c)| p.0 * c).sum();
    let im: f64 = phi.iter().zip(&c).map(|(p, c)| p.1 * c).sum();
    Some((re, im / k))
}

/// Node coefficient vector of case `i`'s node for channel `c`, predicted from the training
/// nodes: the linear terms (α, Bα̇/U) over K_α and (h/B, ḣ/U) over K_h by the rational
/// form [`rfa_predict`] pooled over every configuration (a linear law's transfer depends on
/// its own reduced frequency only); every other term over K_α inside its configuration
/// ([`interpolate`]).
pub(crate) fn node_coefficients(
    cases: &[CaseData],
    nodes: &[Node],
    supports: &Supports,
    law: &ChannelLaw,
    i: usize,
    c: usize,
) -> Vec<f64> {
    let case = &cases[i];
    let cfg = &nodes[case.node].config;
    let pts: Vec<(f64, &[f64])> = law
        .nodes
        .iter()
        .filter(|(n, _, _)| &nodes[*n].config == cfg)
        .map(|(_, k, a)| (*k, a.as_slice()))
        .collect();
    let mut a = interpolate(&pts, nodes[case.node].k_alpha);
    let sup = &supports[cfg][c];
    for (d, r) in [(0usize, 1usize), (2, 3)] {
        let td = Term::linear(d);
        let tr = Term::linear(r);
        let (Some(jd), Some(jr)) = (
            sup.iter().position(|t| *t == td),
            sup.iter().position(|t| *t == tr),
        ) else {
            continue;
        };
        let kf = |n: usize| -> Option<f64> {
            let nd = &nodes[n];
            let ci = nd.cases.first()?;
            if d == 0 {
                Some(nd.k_alpha)
            } else {
                let cs = &cases[*ci];
                cs.f_h
                    .map(|f| cs.nd.chord * 2.0 * std::f64::consts::PI * f / cs.u)
            }
        };
        let Some(k_here) = kf(case.node) else {
            continue;
        };
        let pts: Vec<(f64, f64, f64)> = law
            .nodes
            .iter()
            .filter_map(|(n, _, a)| {
                let s = &supports[&nodes[*n].config][c];
                let pd = s.iter().position(|t| *t == td)?;
                let pr = s.iter().position(|t| *t == tr)?;
                Some((kf(*n)?, a[pd], a[pr]))
            })
            .collect();
        if let Some((xd, xr)) = rfa_predict(&pts, k_here) {
            a[jd] = xd;
            a[jr] = xr;
        }
    }
    a
}

/// Held-out prediction of case `i`, channel `c`: support columns × node coefficients
/// predicted by [`node_coefficients`], plus the shared augmentation columns × β.
pub(crate) fn predict(
    cases: &[CaseData],
    nodes: &[Node],
    supports: &Supports,
    law: &ChannelLaw,
    i: usize,
    c: usize,
    extra_cols: &[Vec<f64>],
) -> Vec<f64> {
    let case = &cases[i];
    let cfg = &nodes[case.node].config;
    let a = node_coefficients(cases, nodes, supports, law, i, c);
    let mut out = vec![0.0; case.n];
    for (t, &aj) in supports[cfg][c].iter().zip(&a) {
        if aj != 0.0 {
            let col = case.column(t);
            out.iter_mut().zip(&col).for_each(|(o, v)| *o += aj * v);
        }
    }
    for (col, &b) in extra_cols.iter().zip(&law.beta) {
        out.iter_mut().zip(col).for_each(|(o, v)| *o += b * v);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_exact_for_quadratics_and_bounded_outside() {
        let f = |x: f64| 1.0 + 2.0 * x - 3.0 * x * x;
        let xy: Vec<(f64, f64)> = [0.2, 0.3, 0.45, 0.6].iter().map(|&x| (x, f(x))).collect();
        for x in [0.25, 0.4, 0.5, 0.55] {
            assert!((interpolate_scalar(&xy, x) - f(x)).abs() < 1e-12);
        }
        // outside: a line through the end nodes, held beyond one spacing
        let line = |x: f64| f(0.6) + (f(0.6) - f(0.45)) / 0.15 * (x - 0.6);
        assert!((interpolate_scalar(&xy, 0.65) - line(0.65)).abs() < 1e-12);
        assert!((interpolate_scalar(&xy, 5.0) - line(0.75)).abs() < 1e-12);
        assert_eq!(interpolate_scalar(&xy[..1], 9.0), f(0.2));
    }
}
