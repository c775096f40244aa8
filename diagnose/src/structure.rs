//! The still-air decays' structure (DESIGN §5, "structure first"), below every level:
//! per record at U = 0 and DOF, the frequency and damping ratio of its dominant mode in
//! windows of four periods, their trend with amplitude (the backbone curve and damping
//! against amplitude), and the shape of the envelope (exponential for viscous damping,
//! linear for dry friction), against the modes of the given structure in still air. The
//! system level reports it for the free runs it scores, the bifurcation level for the
//! decays it is given.

use std::f64::consts::TAU;

use aeroelastic::section::Section;
use identify::dataset::Dataset;
use identify::preprocess::{dominant_frequency, harmonic_fit, refine_frequency};
use nalgebra::{DMatrix, Matrix2};
use serde::{Deserialize, Serialize};

/// Fewest periods a record must hold to give a bifurcation point or a decay analysis.
pub const MIN_PERIODS: f64 = 8.0;

/// First-harmonic amplitude of `x` (sampled every `dt` s) at `f` Hz, by least squares.
pub(crate) fn first_harmonic(x: &[f64], dt: f64, f: f64) -> Option<f64> {
    harmonic_fit(x, dt, &[f]).ok().map(|fit| fit.amplitude(0))
}

/// Least-squares line y = icpt + slope·x: (slope, icpt, sum of squared residuals); a
/// single point gives slope 0.
pub(crate) fn line_fit(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    if x.len() < 2 {
        return (0.0, y.first().copied().unwrap_or(0.0), 0.0);
    }
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let icpt = my - slope * mx;
    let sse: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (b - icpt - slope * a).powi(2))
        .sum();
    (slope, icpt, sse)
}

/// One mode of the still-air decay against the given structure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ModeCheck {
    /// Record (case id).
    pub case: String,
    /// DOF whose record was analysed (`heave` / `pitch`).
    pub dof: String,
    /// Measured frequency at the smallest analysed amplitude \[Hz\].
    pub measured_hz: f64,
    /// Frequency of the given structure's still-air mode closest to it \[Hz\].
    pub given_hz: f64,
    /// (measured − given) / given.
    pub frequency_error: f64,
    /// Measured damping ratio at the smallest analysed amplitudes.
    pub measured_zeta: f64,
    /// Damping ratio of that mode of the given structure.
    pub given_zeta: f64,
    /// Analysed amplitude range (first-harmonic, record units: m or rad).
    pub amplitude_range: [f64; 2],
    /// Relative frequency change from the smallest to the largest analysed amplitude
    /// (> 0 hardening, < 0 softening: the backbone).
    pub backbone_change: f64,
    /// Damping ratio at the largest analysed amplitudes minus that at the smallest.
    pub damping_change: f64,
    /// Residual of an exponential envelope over that of a linear one (> 1: the envelope
    /// is closer to linear, the dry-friction signature).
    pub exp_over_linear: f64,
    /// What the decay says, in words.
    pub signature: String,
}

/// The still-air decays against the given structure (DESIGN §5, "structure first").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct StructureCheck {
    /// One row per analysed record and DOF.
    pub modes: Vec<ModeCheck>,
    /// Largest |frequency error| of the modes.
    pub worst_frequency_error: f64,
    /// Summary in words.
    pub summary: String,
}

/// The given structure's still-air modes (structure plus the aerodynamic apparent mass at
/// U = 0): (frequency \[Hz\], damping ratio), increasing frequency.
fn still_air_modes(section: &Section) -> Vec<(f64, f64)> {
    let s = &section.structure;
    modes_of(
        &section.total_mass(0.0),
        &s.stiffness_matrix(),
        &s.damping_matrix(),
    )
}

/// Modes (frequency \[Hz\], damping ratio) of M q̈ + C q̇ + K q = 0, increasing frequency;
/// empty when M is singular.
fn modes_of(m: &Matrix2<f64>, k: &Matrix2<f64>, c: &Matrix2<f64>) -> Vec<(f64, f64)> {
    let Some(mi) = m.try_inverse() else {
        return Vec::new();
    };
    let k = mi * k;
    let c = mi * c;
    let mut a = DMatrix::<f64>::zeros(4, 4);
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    for i in 0..2 {
        for j in 0..2 {
            a[(2 + i, j)] = -k[(i, j)];
            a[(2 + i, 2 + j)] = -c[(i, j)];
        }
    }
    let mut out: Vec<(f64, f64)> = a
        .complex_eigenvalues()
        .iter()
        .filter(|l| l.im > 0.0)
        .map(|l| (l.norm() / TAU, -l.re / l.norm()))
        .collect();
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    out
}

/// Windows of four periods (half overlap) of `x`: (centre time, first-harmonic
/// amplitude, frequency refined in the window).
fn decay_windows(x: &[f64], dt: f64, f: f64) -> Vec<(f64, f64, f64)> {
    let w = ((4.0 / f) / dt).round() as usize;
    let mut out = Vec::new();
    if w < 8 {
        return out;
    }
    let mut s = 0;
    while s + w <= x.len() {
        let seg = &x[s..s + w];
        let fw = refine_frequency(seg, dt, f);
        let fw = if (fw - f).abs() < 0.25 * f { fw } else { f };
        if let Some(a) = first_harmonic(seg, dt, fw) {
            out.push(((s as f64 + 0.5 * w as f64) * dt, a, fw));
        }
        s += w / 2;
    }
    out
}

/// Analyses the still-air records (U = 0) of `sets` against `section`'s structure; `None`
/// when there is none.
pub fn structure_check(sets: &[&Dataset], section: &Section) -> Option<StructureCheck> {
    check_against(sets, &still_air_modes(section))
}

/// As [`structure_check`], against the modes of M q̈ + C q̇ + K q = 0 (mass, damping and
/// stiffness matrices per unit span: the nominal structure, with the air's mass where it
/// is known).
pub fn structure_check_matrices(
    sets: &[&Dataset],
    m: &Matrix2<f64>,
    k: &Matrix2<f64>,
    c: &Matrix2<f64>,
) -> Option<StructureCheck> {
    check_against(sets, &modes_of(m, k, c))
}

fn check_against(sets: &[&Dataset], modes_given: &[(f64, f64)]) -> Option<StructureCheck> {
    let modes_given = modes_given.to_vec();
    let mut rows = Vec::new();
    for set in sets {
        for (spec, rec) in set.manifest.cases.iter().zip(&set.records) {
            if rec.meta.wind_speed > 0.0 {
                continue;
            }
            for (dof, x) in [("pitch", &rec.alpha), ("heave", &rec.h)] {
                if let Some(row) = decay_row(&spec.id, dof, x, rec.dt, &modes_given) {
                    rows.push(row);
                }
            }
        }
    }
    if rows.is_empty() {
        return None;
    }
    let worst = rows
        .iter()
        .map(|r| r.frequency_error.abs())
        .fold(0.0, f64::max);
    let summary = rows
        .iter()
        .map(|r| {
            format!(
                "{} {}: {:.3} Hz measured vs {:.3} Hz given ({:+.1} %), ζ {:.4} vs {:.4}; {}",
                r.case,
                r.dof,
                r.measured_hz,
                r.given_hz,
                100.0 * r.frequency_error,
                r.measured_zeta,
                r.given_zeta,
                r.signature
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    Some(StructureCheck {
        modes: rows,
        worst_frequency_error: worst,
        summary,
    })
}

fn decay_row(
    case: &str,
    dof: &str,
    x: &[f64],
    dt: f64,
    modes_given: &[(f64, f64)],
) -> Option<ModeCheck> {
    let f0 = dominant_frequency(x, dt)?;
    let f = refine_frequency(x, dt, f0);
    if (x.len() as f64 * dt * f) < MIN_PERIODS {
        return None;
    }
    let win = decay_windows(x, dt, f);
    let peak = win.iter().map(|w| w.1).fold(0.0, f64::max);
    // Noise floor: the windows' amplitude at the end of a decay, or 5 % of the peak.
    let tail = win.last().map_or(0.0, |w| w.1);
    let floor = (2.0 * tail).max(0.05 * peak);
    let good: Vec<(f64, f64, f64)> = win.iter().copied().filter(|w| w.1 > floor).collect();
    if good.len() < 4 {
        return None;
    }
    let t: Vec<f64> = good.iter().map(|w| w.0).collect();
    let a: Vec<f64> = good.iter().map(|w| w.1).collect();
    let la: Vec<f64> = a.iter().map(|v| v.ln()).collect();
    let (_, _, sse_lin) = line_fit(&t, &a);
    let (rate, c, _) = line_fit(&t, &la);
    let sse_exp: f64 = t
        .iter()
        .zip(&a)
        .map(|(ti, ai)| (ai - (c + rate * ti).exp()).powi(2))
        .sum();
    let exp_over_linear = if sse_lin > 0.0 {
        sse_exp / sse_lin
    } else {
        1.0
    };
    // Small- and large-amplitude thirds (the windows are in time order, amplitude falling).
    let n3 = (good.len() / 3).max(2);
    let late = &good[good.len() - n3..];
    let early = &good[..n3];
    let mean = |v: &[(f64, f64, f64)], k: usize| {
        v.iter().map(|w| [w.0, w.1, w.2][k]).sum::<f64>() / v.len() as f64
    };
    let zeta = |v: &[(f64, f64, f64)]| {
        let tt: Vec<f64> = v.iter().map(|w| w.0).collect();
        let ll: Vec<f64> = v.iter().map(|w| w.1.ln()).collect();
        let (r, _, _) = line_fit(&tt, &ll);
        -r / (TAU * mean(v, 2))
    };
    let f_small = mean(late, 2);
    let f_large = mean(early, 2);
    let (z_small, z_large) = (zeta(late), zeta(early));
    let given = modes_given
        .iter()
        .min_by(|p, q| (p.0 - f_small).abs().total_cmp(&(q.0 - f_small).abs()))
        .copied()
        .unwrap_or((f64::NAN, f64::NAN));
    let backbone_change = (f_large - f_small) / f_small;
    let damping_change = z_large - z_small;
    let mut sig = Vec::new();
    if backbone_change > 0.005 {
        sig.push(format!(
            "hardening backbone ({:+.1} % over the decay)",
            100.0 * backbone_change
        ));
    } else if backbone_change < -0.005 {
        sig.push(format!(
            "softening backbone ({:+.1} % over the decay)",
            100.0 * backbone_change
        ));
    } else {
        sig.push("frequency independent of amplitude".into());
    }
    if exp_over_linear > 2.0 {
        sig.push(format!(
            "envelope closer to linear than exponential (misfit ratio {exp_over_linear:.1}: dry friction)"
        ));
    } else if damping_change > 0.3 * z_small.abs().max(1e-3) {
        sig.push("damping grows with amplitude".into());
    } else {
        sig.push("exponential envelope (viscous)".into());
    }
    Some(ModeCheck {
        case: case.to_string(),
        dof: dof.to_string(),
        measured_hz: f_small,
        given_hz: given.0,
        frequency_error: (f_small - given.0) / given.0,
        measured_zeta: z_small,
        given_zeta: given.1,
        amplitude_range: [mean(late, 1), mean(early, 1)],
        backbone_change,
        damping_change,
        exp_over_linear,
        signature: sig.join("; "),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decay_row_reads_frequency_damping_and_a_linear_envelope() {
        let dt = 1.0 / 250.0;
        let n = 4000;
        let f = 2.5;
        // Viscous decay, ζ = 0.01.
        let z = 0.01;
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                0.05 * (-z * TAU * f * t).exp() * (TAU * f * t).cos()
            })
            .collect();
        let r = decay_row("c", "pitch", &x, dt, &[(2.5, 0.01)]).unwrap();
        assert!((r.measured_hz - 2.5).abs() < 0.005, "{}", r.measured_hz);
        assert!(
            (r.measured_zeta - 0.01).abs() < 0.001,
            "{}",
            r.measured_zeta
        );
        assert!(r.exp_over_linear < 1.0, "{}", r.exp_over_linear);
        assert!(r.backbone_change.abs() < 0.005, "{}", r.backbone_change);
        // Dry friction: linear envelope.
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                (0.05 - 0.003 * t).max(0.0) * (TAU * f * t).cos()
            })
            .collect();
        let r = decay_row("c", "pitch", &y, dt, &[(2.5, 0.01)]).unwrap();
        assert!(r.exp_over_linear > 2.0, "{}", r.exp_over_linear);
        assert!(r.signature.contains("friction"), "{}", r.signature);
    }
}
