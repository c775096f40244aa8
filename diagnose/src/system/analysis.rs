//! Where the system-level gap lies (shares of the excess residual energy) and residual
//! spectra before/after the best candidate.

use crate::effect::Level;
use crate::report::{Channel, Harmonic, ResidualSpectrum, Split, WhereShare};

use super::candidates::{self, SystemTerm};
use super::residual::RunResidual;

/// The best candidate: effect, grid parameters, coefficients.
pub(crate) type Best = (&'static dyn SystemTerm, Vec<(String, f64)>, Vec<f64>);

/// Shares of the excess normalised residual energy (energy minus its noise expectation,
/// clipped at 0; raw energy when nothing exceeds the noise) by channel, by response
/// amplitude band (|α| below/above half the run's largest |α|), by wind speed (one cell
/// per run) and by state-space region (|α| small/large × sign of α̇). Each split sums to 1.
pub(crate) fn where_shares(runs: &[RunResidual], noise: &[[f64; 2]]) -> Vec<WhereShare> {
    let u_min = runs.iter().map(|r| r.u).fold(f64::INFINITY, f64::min);
    let u_max = runs.iter().map(|r| r.u).fold(0.0, f64::max);
    // Accumulators: (energy, noise energy) per cell.
    let mut chan = [[0.0; 2]; 2];
    let mut band = [[0.0; 2]; 2];
    let mut state = [[0.0; 2]; 4];
    let mut per_run = vec![[0.0; 2]; runs.len()];
    let mut amp_max: f64 = 0.0;
    for (j, r) in runs.iter().enumerate() {
        let n = r.len() as f64;
        let a_max = r.q[1][r.i0..r.i1]
            .iter()
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        amp_max = amp_max.max(a_max);
        for k in 0..r.len() {
            let i = r.i0 + k;
            let big = r.q[1][i].abs() > 0.5 * a_max;
            let up = r.qd[1][i] > 0.0;
            for c in 0..2 {
                let e = (r.r[c][k] / r.norm[c]).powi(2) / (2.0 * n * runs.len() as f64);
                let nz = noise[j][c] / (2.0 * n * runs.len() as f64);
                for acc in [
                    &mut chan[c],
                    &mut band[big as usize],
                    &mut state[2 * big as usize + up as usize],
                    &mut per_run[j],
                ] {
                    acc[0] += e;
                    acc[1] += nz;
                }
            }
        }
    }
    let shares = |cells: &[[f64; 2]]| -> Vec<f64> {
        let ex: Vec<f64> = cells.iter().map(|c| (c[0] - c[1]).max(0.0)).collect();
        let tot: f64 = ex.iter().sum();
        if tot > 0.0 {
            ex.iter().map(|v| v / tot).collect()
        } else {
            let raw: f64 = cells.iter().map(|c| c[0]).sum();
            cells
                .iter()
                .map(|c| {
                    if raw > 0.0 {
                        c[0] / raw
                    } else {
                        1.0 / cells.len() as f64
                    }
                })
                .collect()
        }
    };
    let amp_deg = amp_max.to_degrees();
    let cell =
        |split: Split, channel: Channel, u: [f64; 2], a: [f64; 2], st: Option<String>, share| {
            WhereShare {
                split,
                level: Level::Structural,
                channel,
                harmonic: Harmonic::All,
                wind_speed: u,
                amplitude: a,
                config: None,
                state: st,
                share,
            }
        };
    let mut out = Vec::new();
    for (c, sh) in shares(&chan).into_iter().enumerate() {
        out.push(cell(
            Split::Channel,
            Channel::MOTIONS[c],
            [u_min, u_max],
            [0.0, amp_deg],
            None,
            sh,
        ));
    }
    for (b, sh) in shares(&band).into_iter().enumerate() {
        let a = if b == 0 {
            [0.0, 0.5 * amp_deg]
        } else {
            [0.5 * amp_deg, amp_deg]
        };
        let mut w = cell(Split::Amplitude, Channel::All, [u_min, u_max], a, None, sh);
        w.state = Some(if b == 0 {
            "|alpha| <= 0.5 max|alpha| of the run".into()
        } else {
            "|alpha| > 0.5 max|alpha| of the run".into()
        });
        out.push(w);
    }
    for (j, sh) in shares(&per_run).into_iter().enumerate() {
        out.push(cell(
            Split::Region,
            Channel::All,
            [runs[j].u, runs[j].u],
            [0.0, amp_deg],
            None,
            sh,
        ));
    }
    let names = [
        "|alpha| small, alpha_dot < 0",
        "|alpha| small, alpha_dot > 0",
        "|alpha| large, alpha_dot < 0",
        "|alpha| large, alpha_dot > 0",
    ];
    for (k, sh) in shares(&state).into_iter().enumerate() {
        out.push(cell(
            Split::State,
            Channel::All,
            [u_min, u_max],
            [0.0, amp_deg],
            Some(names[k].into()),
            sh,
        ));
    }
    out
}

/// Mean residual amplitude spectrum per channel over the runs (each run's residual
/// normalised by its normaliser, mean removed, rectangular window, amplitude per bin
/// 2|X|/n), on 0–20 Hz in 0.1 Hz bins, before and after the best candidate (`best`:
/// effect, grid, coefficients fitted on all runs).
pub(crate) fn spectra(
    runs: &[RunResidual],
    best: Option<&Best>,
    rho: f64,
    chord: f64,
) -> Vec<ResidualSpectrum> {
    let df = 0.1;
    let nb = 201;
    let freq: Vec<f64> = (0..nb).map(|k| k as f64 * df).collect();
    let mut before = [vec![0.0; nb], vec![0.0; nb]];
    let mut after = [vec![0.0; nb], vec![0.0; nb]];
    for r in runs {
        let cols = best.map(|(e, g, _)| candidates::run_columns(*e, g, r, rho, chord));
        for c in 0..2 {
            let base: Vec<f64> = r.r[c].iter().map(|v| v / r.norm[c]).collect();
            let aug: Vec<f64> = match (&cols, best) {
                (Some(cols), Some((_, _, theta))) => (0..base.len())
                    .map(|k| {
                        let mut v = r.r[c][k];
                        for (col, t) in cols.iter().zip(theta) {
                            if !col[c].is_empty() {
                                v -= t * col[c][k];
                            }
                        }
                        v / r.norm[c]
                    })
                    .collect(),
                _ => base.clone(),
            };
            for (x, acc) in [(&base, &mut before[c]), (&aug, &mut after[c])] {
                let n = x.len();
                let fft = fft::forward(n);
                let mean = x.iter().sum::<f64>() / n as f64;
                let mut buf: Vec<f64> = x.iter().map(|v| v - mean).collect();
                let mut sp = fft.make_output_vec();
                if fft.process(&mut buf, &mut sp).is_err() {
                    continue;
                }
                let res = 1.0 / (n as f64 * r.dt);
                for (k, f) in freq.iter().enumerate() {
                    let b = (f / res).round() as usize;
                    if b < sp.len() {
                        acc[k] += 2.0 * sp[b].norm() / n as f64 / runs.len() as f64;
                    }
                }
            }
        }
    }
    (0..2)
        .map(|c| ResidualSpectrum {
            level: Level::Structural,
            channel: Channel::MOTIONS[c],
            frequency_unit: "Hz".into(),
            frequency: freq.clone(),
            before: before[c].clone(),
            after: after[c].clone(),
        })
        .collect()
}
