//! Assembling the [`LevelResult`] of the force level: gap, gap test, candidate ranking,
//! where the gap lies, signatures and spectra.
//!
//! **Where.** Every split distributes the *excess* held-out residual energy (forces per
//! unit span, Σ r² − Σ n σ̂² per cell, clamped at 0) over its cells and normalises to 1:
//! `channel` (lift, moment), `region` (configuration × U × amplitude cells = cases),
//! `state` (|α| < ½A, ½A ≤ |α| < 0.85A, |α| ≥ 0.85A, each split by the sign of α̇) and
//! `harmonic` (periodogram bins of the residual assigned to the nearest forcing tone
//! m·f_α + n·f_h of order ≤ 9 within 1.5/T — labels `DC`, `n*f_alpha`, `n*f_h`,
//! `m*f_alpha±n*f_h` —, to `off-harmonic line` when the bin is above 20× the median bin
//! power of the case, else to `broadband`, from which the noise energy is removed).

use std::collections::BTreeMap;

use crate::effect::{Effect, Level};
use crate::report::{
    CandidateScore, CaseGap, Channel, Harmonic, LevelResult, ObservableGap, ResidualSpectrum,
    SignatureTest, Split, WhereShare,
};
use crate::stats::excess_shrink;

use super::candidates::{significance, Scored};
use super::data::{CaseData, Node, CHANNELS};

/// The thresholds of the force level's tests (`ForceOptions`' fields of the same names).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Thresholds {
    /// Threshold of the gap statistic held-out gap / noise level.
    pub gap_threshold: f64,
    /// Significance threshold of a candidate's held-out improvement.
    pub significance: f64,
    /// Minimum share of the excess residual energy a candidate must remove.
    pub min_shrink: f64,
}
use super::data::{gaps, gaps_of, noise_gaps, noise_of};
use crate::numerics::periodogram_full;

use super::candidates::noise_energy as energy_w;

/// The gap statistic of held-out residuals `before`: their gap over the noise level
/// ([`LevelResult::gap_statistic`]; infinite without noise).
pub(crate) fn gap_statistic(cases: &[CaseData], before: &[[Vec<f64>; 2]]) -> f64 {
    let noise = noise_gaps(cases);
    if noise.combined > 0.0 {
        gaps(cases, before).combined / noise.combined
    } else {
        f64::INFINITY
    }
}

/// Builds the level result.
pub(crate) fn assemble(
    cases: &[CaseData],
    nodes: &[Node],
    fold_of: &[usize],
    before: &[[Vec<f64>; 2]],
    scored: Vec<(Effect, Scored)>,
    opts: &Thresholds,
) -> LevelResult {
    let g = gaps(cases, before);
    let noise = noise_gaps(cases);
    let stat = gap_statistic(cases, before);
    // The held-out cases whose K lies inside the K range their fold was trained on (same
    // configuration): their prediction interpolates; the others extrapolate only because
    // cross-validation held their wind speed out (the law of every case covers them).
    let inside: Vec<bool> = cases
        .iter()
        .map(|c| {
            let f = fold_of[c.node];
            let (lo, hi) = nodes
                .iter()
                .enumerate()
                .filter(|(n, nd)| fold_of[*n] != f && nd.config == c.config)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, nd)| {
                    (lo.min(nd.k_alpha), hi.max(nd.k_alpha))
                });
            let k = nodes[c.node].k_alpha;
            k >= lo * (1.0 - 1e-9) && k <= hi * (1.0 + 1e-9)
        })
        .collect();
    let inside_cases = || {
        cases
            .iter()
            .zip(before)
            .zip(&inside)
            .filter(|(_, &k)| k)
            .map(|(pair, _)| pair)
    };
    let inside_noise = noise_of(inside_cases().map(|(c, _)| c)).combined;
    let inside_stat = (inside_noise > 0.0).then(|| gaps_of(inside_cases()).combined / inside_noise);
    let n_samples: f64 = cases.iter().map(|c| 2.0 * c.n as f64).sum();
    let e_before = energy_w(cases, before);
    let mut cands: Vec<(CandidateScore, usize)> = scored
        .iter()
        .enumerate()
        .map(|(k, (effect, s))| {
            let e_after = energy_w(cases, &s.residuals);
            let (z, thr, sig, _share, score) = significance(
                e_before,
                e_after,
                n_samples,
                s.n_params,
                s.n_nuisance,
                opts.significance,
                opts.min_shrink,
            );
            let after = gaps(cases, &s.residuals).combined;
            (
                CandidateScore {
                    effect: *effect,
                    level: Level::Aerodynamic,
                    before: g.combined,
                    after,
                    shrink: excess_shrink(g.combined, after, noise.combined),
                    n_params: s.n_params + s.n_nuisance,
                    statistic: z,
                    threshold: thr,
                    significant: sig,
                    score,
                    parameters: s.parameters.clone(),
                    failure: s.failure.clone(),
                    convention: None,
                    note: None,
                    held_out_runs: vec![],
                },
                k,
            )
        })
        .collect();
    cands.sort_by(|a, b| {
        b.0.significant
            .cmp(&a.0.significant)
            .then(a.0.score.total_cmp(&b.0.score))
    });
    let best = cands.first().map(|(_, k)| &scored[*k].1.residuals);
    let after_res: &[[Vec<f64>; 2]] = best.map_or(before, |v| v.as_slice());
    let case_gaps = cases
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let one = std::slice::from_ref(c);
            CaseGap {
                id: c.nd.meta.id.clone(),
                level: Level::Aerodynamic,
                config: Some(c.config.clone()),
                wind_speed: c.u,
                amplitude: c.amp_deg,
                fold: fold_of[c.node],
                before: gaps(one, std::slice::from_ref(&before[i])).combined,
                after: gaps(one, std::slice::from_ref(&after_res[i])).combined,
                noise_level: noise_gaps(one).combined,
            }
        })
        .collect();
    let ga = gaps(cases, after_res);
    let observables = (0..2)
        .map(|k| ObservableGap {
            name: format!("force residual ({})", CHANNELS[k]),
            level: Level::Aerodynamic,
            unit: "-".into(),
            before: g.channel[k],
            after: ga.channel[k],
            shrink: if g.channel[k] > 0.0 {
                1.0 - ga.channel[k].abs() / g.channel[k]
            } else {
                0.0
            },
        })
        .collect();
    let (where_, signatures, spectra) = locate(cases, before, after_res, stat, opts);
    LevelResult {
        level: Level::Aerodynamic,
        metric: "held-out normalised force residual sqrt(Σr²/ΣF²), rms of lift and moment".into(),
        before: g.combined,
        noise_level: noise.combined,
        significant_gap: stat > opts.gap_threshold,
        gap_statistic: stat,
        gap_threshold: opts.gap_threshold,
        interpolated_gap_statistic: inside_stat,
        model_level: None,
        held_out_cases: cases.iter().map(|c| c.nd.meta.id.clone()).collect(),
        candidates: cands.into_iter().map(|(c, _)| c).collect(),
        where_,
        cases: case_gaps,
        spectra,
        signatures,
        observables,
        bifurcation: None,
        fold_scheme: None,
        coverage: None,
        structure: None,
        control: None,
    }
}

fn share(
    split: Split,
    channel: Channel,
    harmonic: Harmonic,
    w: [f64; 2],
    a: [f64; 2],
) -> WhereShare {
    WhereShare {
        split,
        level: Level::Aerodynamic,
        channel,
        harmonic,
        wind_speed: w,
        amplitude: a,
        config: None,
        state: None,
        share: 0.0,
    }
}

fn normalise(v: &mut [WhereShare], e: &[f64]) {
    let tot: f64 = e.iter().map(|x| x.max(0.0)).sum();
    for (s, x) in v.iter_mut().zip(e) {
        s.share = if tot > 0.0 {
            x.max(0.0) / tot
        } else {
            1.0 / e.len() as f64
        };
    }
}

fn tone(m: i32, n: i32) -> Harmonic {
    if m == 0 && n == 0 {
        Harmonic::Dc
    } else {
        Harmonic::Tone { m, n }
    }
}

type Located = (Vec<WhereShare>, Vec<SignatureTest>, Vec<ResidualSpectrum>);

fn locate(
    cases: &[CaseData],
    before: &[[Vec<f64>; 2]],
    after: &[[Vec<f64>; 2]],
    stat: f64,
    opts: &Thresholds,
) -> Located {
    let u_rng = [
        cases.iter().map(|c| c.u).fold(f64::INFINITY, f64::min),
        cases.iter().map(|c| c.u).fold(0.0, f64::max),
    ];
    let a_rng = [
        cases
            .iter()
            .map(|c| c.amp_deg)
            .fold(f64::INFINITY, f64::min),
        cases.iter().map(|c| c.amp_deg).fold(0.0, f64::max),
    ];
    let mut out = Vec::new();
    // channel
    let mut e_ch = [0.0; 2];
    for (c, r) in cases.iter().zip(before) {
        for k in 0..2 {
            let s2 = c.scale[k] * c.scale[k];
            e_ch[k] += s2
                * (r[k].iter().map(|v| v * v).sum::<f64>() - c.n as f64 * c.sigma[k] * c.sigma[k]);
        }
    }
    let mut v: Vec<WhereShare> = (0..2)
        .map(|k| {
            share(
                Split::Channel,
                Channel::FORCES[k],
                Harmonic::All,
                u_rng,
                a_rng,
            )
        })
        .collect();
    normalise(&mut v, &e_ch);
    out.extend(v);
    // region (cases)
    let e_case: Vec<f64> = cases
        .iter()
        .zip(before)
        .map(|(c, r)| {
            (0..2)
                .map(|k| {
                    c.scale[k].powi(2)
                        * (r[k].iter().map(|v| v * v).sum::<f64>()
                            - c.n as f64 * c.sigma[k].powi(2))
                })
                .sum()
        })
        .collect();
    let mut v: Vec<WhereShare> = cases
        .iter()
        .map(|c| {
            let mut s = share(
                Split::Region,
                Channel::All,
                Harmonic::All,
                [c.u, c.u],
                [c.amp_deg, c.amp_deg],
            );
            s.config = Some(c.config.clone());
            s
        })
        .collect();
    normalise(&mut v, &e_case);
    out.extend(v);
    // state
    let labels = [
        "|alpha| < 0.5 A",
        "0.5 A <= |alpha| < 0.85 A",
        "|alpha| >= 0.85 A",
    ];
    let mut e_state = [0.0; 6];
    for (c, r) in cases.iter().zip(before) {
        // pitch about the mean the case was regressed about (a mean angle is not amplitude)
        let amp = c.nd.x[0]
            .iter()
            .fold(0.0f64, |m, v| m.max((v - c.alpha_shift).abs()))
            .max(1e-12);
        #[allow(clippy::needless_range_loop)]
        for i in 0..c.n {
            let a = (c.nd.x[0][i] - c.alpha_shift).abs() / amp;
            let band = if a < 0.5 {
                0
            } else if a < 0.85 {
                1
            } else {
                2
            };
            let up = usize::from(c.nd.x[1][i] <= 0.0);
            for k in 0..2 {
                e_state[2 * band + up] +=
                    c.scale[k].powi(2) * (r[k][i] * r[k][i] - c.sigma[k] * c.sigma[k]);
            }
        }
    }
    let mut v: Vec<WhereShare> = (0..6)
        .map(|j| {
            let mut s = share(Split::State, Channel::All, Harmonic::All, u_rng, a_rng);
            s.state = Some(format!(
                "{}, {}",
                labels[j / 2],
                if j % 2 == 0 {
                    "alpha_dot > 0"
                } else {
                    "alpha_dot <= 0"
                }
            ));
            s
        })
        .collect();
    normalise(&mut v, &e_state);
    out.extend(v);
    // harmonic
    // keyed by label: cells in the label order
    let mut e_h: BTreeMap<String, (Harmonic, f64)> = BTreeMap::new();
    let mut amp_hi_lo = [0.0f64; 2];
    let mut n_hi_lo = [0usize; 2];
    let (a_min, a_max) = (a_rng[0], a_rng[1]);
    for (c, r) in cases.iter().zip(before) {
        let m = c.n.next_power_of_two();
        let df = 1.0 / (m as f64 * c.dt);
        let tol = 1.5 / (c.n as f64 * c.dt);
        let fh = c.f_h.unwrap_or(0.0);
        for k in 0..2 {
            let s2 = c.scale[k].powi(2);
            let p = periodogram_full(&r[k], m);
            let mut sorted = p.clone();
            sorted.sort_by(f64::total_cmp);
            let med = sorted[sorted.len() / 2];
            let tot_p: f64 = p.iter().sum();
            let e_tot: f64 = r[k].iter().map(|v| v * v).sum();
            let scale = if tot_p > 0.0 { e_tot / tot_p } else { 0.0 };
            let noise_e = c.n as f64 * c.sigma[k].powi(2);
            for (b, &pb) in p.iter().enumerate() {
                let f = b as f64 * df;
                let mut label = None;
                'outer: for order in 0..=9i32 {
                    for mm in 0..=order {
                        let nn_abs = order - mm;
                        for nn in [nn_abs, -nn_abs] {
                            if c.f_h.is_none() && nn != 0 {
                                continue;
                            }
                            if mm == 0 && nn < 0 {
                                continue;
                            }
                            let t = (mm as f64 * c.f_alpha + nn as f64 * fh).abs();
                            if (t - f).abs() < tol {
                                label = Some(tone(mm, nn));
                                break 'outer;
                            }
                        }
                    }
                }
                let key = label.unwrap_or(if pb > 20.0 * med {
                    Harmonic::OffHarmonicLine
                } else {
                    Harmonic::Broadband
                });
                e_h.entry(key.label()).or_insert((key, 0.0)).1 += s2 * pb * scale;
            }
            let b = Harmonic::Broadband;
            e_h.entry(b.label()).or_insert((b, 0.0)).1 -= s2 * noise_e;
            let band = if c.amp_deg >= a_max - 1e-9 {
                Some(0)
            } else if c.amp_deg <= a_min + 1e-9 {
                Some(1)
            } else {
                None
            };
            if let Some(bi) = band {
                amp_hi_lo[bi] += (e_tot - noise_e).max(0.0)
                    / (c.n as f64 * c.y[k].iter().map(|v| v * v).sum::<f64>() / c.n as f64)
                        .max(1e-300);
                n_hi_lo[bi] += 1;
            }
        }
    }
    let vals: Vec<f64> = e_h.values().map(|v| v.1).collect();
    let mut v: Vec<WhereShare> = e_h
        .values()
        .map(|&(h, _)| share(Split::Harmonic, Channel::All, h, u_rng, a_rng))
        .collect();
    normalise(&mut v, &vals);
    let hshare = |pred: &dyn Fn(Harmonic) -> bool| -> f64 {
        v.iter().filter(|s| pred(s.harmonic)).map(|s| s.share).sum()
    };
    let dc = hshare(&|h| h == Harmonic::Dc);
    let odd = hshare(&|h| h.net().is_some_and(|k| k % 2 == 1 && k >= 3));
    let even = hshare(&|h| h.net().is_some_and(|k| k % 2 == 0));
    let off = hshare(&|h| h == Harmonic::OffHarmonicLine);
    let broad = hshare(&|h| h == Harmonic::Broadband);
    out.extend(v);
    // signatures
    let sig = |name: &str, s: f64, t: f64, d: String| SignatureTest {
        name: name.into(),
        level: Level::Aerodynamic,
        statistic: s,
        threshold: t,
        detected: s > t,
        detail: d,
    };
    let ratio_amp = if n_hi_lo[0] > 0 && n_hi_lo[1] > 0 {
        (amp_hi_lo[0] / n_hi_lo[0] as f64) / (amp_hi_lo[1] / n_hi_lo[1] as f64).max(1e-12)
    } else {
        1.0
    };
    // U dependence: slope of log excess (C units) against log U over cases
    let pts: Vec<(f64, f64)> = cases
        .iter()
        .zip(before)
        .filter_map(|(c, r)| {
            let e: f64 = (0..2)
                .map(|k| {
                    (r[k].iter().map(|v| v * v).sum::<f64>() / c.n as f64 - c.sigma[k].powi(2))
                        .max(0.0)
                })
                .sum();
            (e > 0.0).then(|| (c.u.ln(), e.ln()))
        })
        .collect();
    let slope = if pts.len() >= 3 {
        let mx = pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64;
        let my = pts.iter().map(|p| p.1).sum::<f64>() / pts.len() as f64;
        let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        if sxx > 0.0 {
            sxy / sxx
        } else {
            0.0
        }
    } else {
        0.0
    };
    let signatures = vec![
        sig("whiteness", stat, opts.gap_threshold, format!("held-out gap / noise level = {stat:.3} (1 for a white residual at the sensor-noise level)")),
        sig("dc", dc, 0.3, format!("share of the excess residual energy at DC = {dc:.3}")),
        sig("odd_harmonics", odd, 0.3, format!("share at odd tones of order ≥ 3 = {odd:.3}")),
        sig("even_harmonics", even, 0.3, format!("share at even tones (order ≥ 2) = {even:.3}")),
        sig("off_harmonic_line", off, 0.3, format!("share in narrow lines off every forcing tone = {off:.3}")),
        sig("broadband", broad, 0.5, format!("share in the broadband floor above noise = {broad:.3}")),
        sig("amplitude_threshold", ratio_amp, 30.0, format!("excess residual/force energy ratio, largest vs smallest amplitude = {ratio_amp:.3}")),
        sig("u_dependence", slope, 1.0, format!("slope of log excess C² residual vs log U = {slope:.3} (0: force ∝ U²)")),
    ];
    // spectra (mean over cases, f/f_alpha axis, normalised by rms of the measured channel)
    let nb = 200;
    let fmax = 10.0;
    let spectra = (0..2)
        .map(|k| {
            let mut sb = vec![0.0; nb];
            let mut sa = vec![0.0; nb];
            for (i, c) in cases.iter().enumerate() {
                let rms = (c.y[k].iter().map(|v| v * v).sum::<f64>() / c.n as f64)
                    .sqrt()
                    .max(1e-300);
                let m = c.n.next_power_of_two();
                let df = 1.0 / (m as f64 * c.dt);
                for (dst, r) in [(&mut sb, &before[i][k]), (&mut sa, &after[i][k])] {
                    let p = periodogram_full(r, m);
                    for (b, pb) in p.iter().enumerate() {
                        let x = b as f64 * df / c.f_alpha;
                        let j = (x / fmax * nb as f64) as usize;
                        if j < nb {
                            dst[j] = f64::max(
                                dst[j],
                                (2.0 * pb / c.n as f64).sqrt() / rms / cases.len() as f64 + 0.0,
                            );
                        }
                    }
                }
            }
            ResidualSpectrum {
                level: Level::Aerodynamic,
                channel: Channel::FORCES[k],
                frequency_unit: "f/f_alpha".into(),
                frequency: (0..nb)
                    .map(|j| (j as f64 + 0.5) * fmax / nb as f64)
                    .collect(),
                before: sb,
                after: sa,
            }
        })
        .collect();
    (out, signatures, spectra)
}
