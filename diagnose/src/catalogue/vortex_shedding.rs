//! `vortex_shedding`: narrow-band forcing at a Strouhal frequency f = St·U/D that moves
//! with U and is not a combination tone of the motion.
//!
//! * Force level: a band at f = S·U/B ([`vortex`]). S is fitted on the training
//!   residuals (sum over training cases of the power at S·U/B, forcing tones masked); on
//!   each held-out case the band's amplitude and phase are fitted on its residual
//!   (nuisance parameters, 2 per bin and channel, counted in the penalty).
//! * Generator: lift coefficient C_L,vs 0.001–0.1 at the form's Strouhal number.

use std::collections::HashMap;
use std::sync::Arc;

use aeroelastic::effects::{self, Form, InjectedEffect};

use super::entry::{Draw, DrawContext, Entry};
use super::Level;
use crate::force::candidates::{Context, ForceFit, Scored};
use crate::force::data::{CaseData, Node};
use crate::force::folds::Fold;
use crate::force::law::{self, Aug};
use crate::numerics::periodogram_full;

/// The `vortex_shedding` entry.
pub(crate) struct VortexShedding;

impl Entry for VortexShedding {
    fn name(&self) -> &'static str {
        "vortex_shedding"
    }
    fn short_label(&self) -> &'static str {
        "shed"
    }
    fn level(&self) -> Level {
        Level::Aerodynamic
    }
    fn force(&self) -> Option<&dyn ForceFit> {
        Some(self)
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

impl ForceFit for VortexShedding {
    fn fit(&self, cx: &Context<'_>) -> Scored {
        vortex(cx.cases, cx.nodes, cx.folds, cx.before)
    }
}

impl Draw for VortexShedding {
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("C_L,vs [-]", 0.001, 0.1)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        form: Form,
        cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::VortexShedding {
                c_lift: p,
                depth: cx.depth,
            },
            vec![
                ("depth D [m]".into(), cx.depth),
                (
                    "Strouhal [-]".into(),
                    effects::shedding_frequency(1.0, 1.0, form),
                ),
            ],
        )
    }
}

/// (case, lift and moment factorisations of its node, hash of the shared nonlinear
/// coefficients) naming a training residual.
type SpecKey = (usize, *const law::NodeChan, *const law::NodeChan, u64);

/// (case, 4×-padded periodogram, its bin width \[Hz\], unpadded periodogram) of a training
/// residual, both channels summed.
type Spectra = (usize, Vec<f64>, f64, Vec<f64>);

/// Sine/cosine least-squares fit at frequency f removed from r; returns the new residual.
fn remove_line(r: &[f64], dt: f64, f: f64) -> Vec<f64> {
    let w = 2.0 * std::f64::consts::PI * f * dt;
    let (mut cc, mut ss, mut cs, mut rc, mut rs) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (i, &v) in r.iter().enumerate() {
        let (s, c) = (w * i as f64).sin_cos();
        cc += c * c;
        ss += s * s;
        cs += c * s;
        rc += v * c;
        rs += v * s;
    }
    let det = cc * ss - cs * cs;
    if det.abs() < 1e-12 * (cc * ss).max(1e-300) {
        return r.to_vec();
    }
    let a = (rc * ss - rs * cs) / det;
    let b = (rs * cc - rc * cs) / det;
    r.iter()
        .enumerate()
        .map(|(i, &v)| {
            let (s, c) = (w * i as f64).sin_cos();
            v - a * c - b * s
        })
        .collect()
}

/// |DFT|²·2/n of x zero-padded to m points (≈ the energy a least-squares line at a bin
/// frequency removes).
fn periodogram(x: &[f64], m: usize) -> Vec<f64> {
    let n = x.len() as f64;
    let mut p = periodogram_full(x, m);
    p.iter_mut().for_each(|v| *v = 2.0 * *v / n);
    p
}

/// The forcing tones |m f_α + n f_h| of order ≤ 9 (pitch only: m f_α), sorted (see
/// [`near_tone`]).
fn tone_list(f_alpha: f64, f_h: Option<f64>) -> Vec<f64> {
    let fh = f_h.unwrap_or(0.0);
    let mut v = Vec::new();
    for m in 0..=9i32 {
        for n in -9..=9i32 {
            if m.abs() + n.abs() > 9 || (f_h.is_none() && n != 0) {
                continue;
            }
            v.push((m as f64 * f_alpha + n as f64 * fh).abs());
        }
    }
    v.sort_by(f64::total_cmp);
    v
}

/// True when f < tol or f is within tol of one of the sorted `tones` (bisection): the
/// answer of [`near_tone`] with tol = 1.5/T.
fn near_tone_sorted(tol: f64, tones: &[f64], f: f64) -> bool {
    if f < tol {
        return true;
    }
    let k = tones.partition_point(|&t| t < f);
    (k < tones.len() && (tones[k] - f).abs() < tol) || (k > 0 && (tones[k - 1] - f).abs() < tol)
}

/// True when f is within 1.5/T of a forcing tone |m f_α + n f_h| of order ≤ 9 (or DC).
fn near_tone(c: &CaseData, f: f64) -> bool {
    let tol = 1.5 / (c.n as f64 * c.dt);
    if f < tol {
        return true;
    }
    let fh = c.f_h.unwrap_or(0.0);
    for m in 0..=9i32 {
        for n in -9..=9i32 {
            if m.abs() + n.abs() > 9 || (c.f_h.is_none() && n != 0) {
                continue;
            }
            let t = (m as f64 * c.f_alpha + n as f64 * fh).abs();
            if (t - f).abs() < tol {
                return true;
            }
        }
    }
    false
}

/// Relative half-widths of the `vortex_shedding` band (around f = S·U/B) tried on the
/// training residuals.
pub const SHEDDING_BANDS: [f64; 6] = [0.0, 0.005, 0.01, 0.02, 0.04, 0.08];

/// DFT bins of an n-sample record within the band f(1 ± b) (at least the two bins around
/// f), excluding DC, Nyquist and bins near a forcing tone.
fn band_bins(c: &CaseData, f: f64, b: f64) -> Vec<usize> {
    let t = c.n as f64 * c.dt;
    let lo = ((f * (1.0 - b)) * t).floor().min((f * t).floor()) as usize;
    let hi = ((f * (1.0 + b)) * t).ceil().max((f * t).ceil()) as usize;
    (lo.max(1)..=hi.min(c.n / 2 - 1))
        .filter(|&k| !near_tone(c, k as f64 / t))
        .collect()
}

/// Removes the content of DFT bins `bins` from r (least-squares projection on those
/// sinusoids: they are orthogonal on the record).
fn remove_bins(r: &[f64], bins: &[usize]) -> Vec<f64> {
    let n = r.len();
    let (fwd, inv) = fft::forward_and_inverse(n);
    let mut input = r.to_vec();
    let mut spec = fwd.make_output_vec();
    if fwd.process(&mut input, &mut spec).is_err() {
        return r.to_vec();
    }
    for &k in bins {
        if k < spec.len() {
            spec[k] = num_complex::Complex64::new(0.0, 0.0);
        }
    }
    let mut out = inv.make_output_vec();
    if inv.process(&mut spec, &mut out).is_err() {
        return r.to_vec();
    }
    out.iter().map(|v| v / n as f64).collect()
}

/// `vortex_shedding`: a narrow band at f = S·U/B. Per fold on the training residuals: S
/// maximises the summed power at S·U/B (forcing tones masked), refined to a twentieth of
/// the resolution at the highest speed; the relative band half-width b ∈
/// [`SHEDDING_BANDS`] maximises the removed power minus 4 noise units per bin and channel
/// (2 for the fitted noise, 2 as a parsimony margin). On each held-out case the band's
/// content is removed (b = 0: one sinusoid at f, else the DFT bins in f(1 ± b)); its
/// amplitudes and phases are nuisance parameters (2 per bin and channel) in the penalty.
fn vortex(cases: &[CaseData], nodes: &[Node], folds: &[Fold], before: &[[Vec<f64>; 2]]) -> Scored {
    let mut res = before.to_vec();
    let mut ss = Vec::new();
    let mut bands = Vec::new();
    let mut q = 0usize;
    // periodograms of a training case's residual: they depend on its node's factorisation
    // only, so folds that train on the same node with the same support share them
    let mut spec_memo: HashMap<SpecKey, Arc<Spectra>> = HashMap::new();
    let tones: Vec<Vec<f64>> = cases.iter().map(|c| tone_list(c.f_alpha, c.f_h)).collect();
    for f in folds {
        // training residuals of the fold's baseline law (node supports and the section's
        // shared nonlinear terms), noise weighted, both channels
        let laws: [law::ChannelLaw; 2] = std::array::from_fn(|c| {
            law::fit_channel(cases, nodes, &f.fits, &f.shared[c], c, Aug::NONE)
        });
        let mut tag: u64 = 0xcbf2_9ce4_8422_2325;
        for v in laws.iter().flat_map(|l| l.shared.iter()) {
            tag = (tag ^ v.to_bits()).wrapping_mul(0x0000_0100_0000_01b3);
        }
        let mut train_res: Vec<(usize, [Vec<f64>; 2], SpecKey)> = Vec::new();
        for nf in &f.fits {
            let r: [Vec<f64>; 2] = std::array::from_fn(|c| {
                let mut r = nf.ch[c].res_y.clone();
                for (t, g) in f.shared[c].iter().zip(&laws[c].shared) {
                    let z = law::stacked_column(cases, &nodes[nf.node], t);
                    let zt = nf.ch[c].qr.residual(&z);
                    r.iter_mut().zip(&zt).for_each(|(v, z)| *v -= g * z);
                }
                r
            });
            let mut off = 0;
            for &i in &nodes[nf.node].cases {
                let n = cases[i].n;
                let rc = [0, 1].map(|c| {
                    r[c][off..off + n]
                        .iter()
                        .map(|v| v / cases[i].sigma[c].max(1e-300))
                        .collect::<Vec<f64>>()
                });
                off += n;
                let key = (i, Arc::as_ptr(&nf.ch[0]), Arc::as_ptr(&nf.ch[1]), tag);
                train_res.push((i, rc, key));
            }
        }
        // periodograms (4× zero padding, and unpadded) of every training residual, both
        // channels summed
        let spectra: Vec<Arc<Spectra>> = train_res
            .iter()
            .map(|(i, r, key)| {
                if let Some(v) = spec_memo.get(key) {
                    return v.clone();
                }
                let c = &cases[*i];
                let m = (4 * c.n).next_power_of_two();
                let mut p = vec![0.0; m / 2 + 1];
                let mut p1 = vec![0.0; c.n / 2 + 1];
                for ch in r.iter() {
                    for (k, v) in periodogram(ch, m).into_iter().enumerate() {
                        p[k] += v;
                    }
                    for (k, v) in periodogram(ch, c.n).into_iter().enumerate() {
                        p1[k] += v;
                    }
                }
                let v = Arc::new((*i, p, 1.0 / (m as f64 * c.dt), p1));
                spec_memo.insert(*key, v.clone());
                v
            })
            .collect();
        let total = |s: f64| -> f64 {
            spectra
                .iter()
                .map(|sp| {
                    let (i, p, df, _) = &**sp;
                    let c = &cases[*i];
                    let fq = s * c.u / c.nd.chord;
                    let k = (fq / df).round() as usize;
                    if fq >= 0.45 / c.dt
                        || k >= p.len()
                        || near_tone_sorted(1.5 / (c.n as f64 * c.dt), &tones[*i], fq)
                    {
                        0.0
                    } else {
                        p[k]
                    }
                })
                .sum()
        };
        let u_max = cases.iter().map(|c| c.u).fold(0.0, f64::max);
        let t_len = cases[0].n as f64 * cases[0].dt;
        let b = cases[0].nd.chord;
        // coarse: a quarter of the resolution at the highest speed, up to 0.45 f_s there
        let step = 0.25 * b / (t_len * u_max);
        let (s_min, s_max) = (0.02, 0.45 / cases[0].dt * b / u_max);
        let mut best = (0.0, s_min);
        let mut s = s_min;
        while s <= s_max {
            let p = total(s);
            if p > best.0 {
                best = (p, s);
            }
            s += step;
        }
        // refine around the best coarse value
        let mut s = best.1 - step;
        while s <= best.1 + step {
            let p = total(s);
            if p > best.0 {
                best = (p, s);
            }
            s += 0.1 * step;
        }
        let s_hat = best.1;
        ss.push(s_hat);
        // band half-width
        let mut best_b = (f64::NEG_INFINITY, 0.0);
        for &bw in &SHEDDING_BANDS {
            let g: f64 = spectra
                .iter()
                .map(|s| {
                    let (i, p4, df, p1) = &**s;
                    let c = &cases[*i];
                    let fq = s_hat * c.u / c.nd.chord;
                    if fq >= 0.45 / c.dt {
                        return 0.0;
                    }
                    if bw == 0.0 {
                        // one off-bin sinusoid ≈ the padded peak
                        let k = (fq / df).round() as usize;
                        return p4.get(k).copied().unwrap_or(0.0) - 8.0;
                    }
                    band_bins(c, fq, bw)
                        .iter()
                        .map(|&k| p1[k] - 8.0)
                        .sum::<f64>()
                })
                .sum();
            if g > best_b.0 {
                best_b = (g, bw);
            }
        }
        let bw = best_b.1;
        bands.push(bw);
        for &n in &f.test {
            for &i in &nodes[n].cases {
                let c = &cases[i];
                let fq = s_hat * c.u / c.nd.chord;
                if fq < 0.45 / c.dt {
                    if bw == 0.0 {
                        for ch in 0..2 {
                            res[i][ch] = remove_line(&before[i][ch], c.dt, fq);
                        }
                        q += 4;
                    } else {
                        let bins = band_bins(c, fq, bw);
                        for ch in 0..2 {
                            res[i][ch] = remove_bins(&before[i][ch], &bins);
                        }
                        q += 4 * bins.len();
                    }
                }
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    Scored {
        residuals: res,
        n_params: 2,
        n_nuisance: q,
        parameters: vec![
            ("strouhal_chord".into(), mean(&ss)),
            ("band_half_width".into(), mean(&bands)),
        ],
        failure: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorted_tone_test_matches_a_direct_scan() {
        for (fa, fh) in [(1.5, Some(0.7)), (2.0, Some(1.3)), (1.7, None)] {
            let tones = tone_list(fa, fh);
            let tol = 1.5 / 8.0;
            let mut hits = 0;
            for k in 0..40000 {
                let f = k as f64 * 0.00123;
                let direct = f < tol
                    || (0..=9i32).any(|m| {
                        (-9..=9i32).any(|n| {
                            m.abs() + n.abs() <= 9
                                && (fh.is_some() || n == 0)
                                && ((m as f64 * fa + n as f64 * fh.unwrap_or(0.0)).abs() - f).abs()
                                    < tol
                        })
                    });
                assert_eq!(direct, near_tone_sorted(tol, &tones, f), "f = {f}");
                hits += usize::from(direct);
            }
            // both outcomes occur
            assert!(hits > 100 && hits < 39000, "{hits}");
        }
    }
}
