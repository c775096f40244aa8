//! Compact per-case series for figures: measured and identified-model C_L, C_M over a time
//! window, their amplitude spectra and the key frequencies — what the time-series and
//! spectrum figures need, saved next to `identification.json` so that figures can be
//! redrawn without the data set.

use serde::{Deserialize, Serialize};

use crate::library::Term;
use crate::pipeline::{CaseResult, TermMap};
use crate::record::NondimCase;
use crate::{Error, Result};

/// Format tag of a saved [`CaseSeries`].
pub const FORMAT: &str = "aeroform-case-series/1";

/// Measured and model series of one case (SI time, degrees and millimetres for the motion,
/// nondimensional forces C_L = L/(½ρU²B) positive down, C_M = M/(½ρU²B²) positive nose-up).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseSeries {
    /// Format tag ([`FORMAT`]).
    pub format: String,
    /// Case id.
    pub id: String,
    /// Wind speed U \[m/s\].
    pub wind_speed: f64,
    /// Motion configuration label.
    pub config: Option<String>,
    /// Pitch amplitude \[deg\].
    pub amplitude_deg: Option<f64>,
    /// Forcing frequencies (pitch, heave) \[Hz\].
    pub forcing_hz: [Option<f64>; 2],
    /// Time of the window \[s\] (from the first sample of the record).
    pub t: Vec<f64>,
    /// Pitch α \[deg\].
    pub alpha_deg: Vec<f64>,
    /// Heave h \[mm\] (positive down).
    pub h_mm: Vec<f64>,
    /// Measured C_L.
    pub c_lift: Vec<f64>,
    /// Identified-model C_L (Σ ξ θ over the library terms).
    pub c_lift_model: Vec<f64>,
    /// Measured C_M.
    pub c_moment: Vec<f64>,
    /// Identified-model C_M.
    pub c_moment_model: Vec<f64>,
    /// Frequencies of the spectra \[Hz\].
    pub freq: Vec<f64>,
    /// Amplitude spectrum of measured C_L (Hann window, amplitude-corrected).
    pub lift_spectrum: Vec<f64>,
    /// Amplitude spectrum of model C_L.
    pub lift_model_spectrum: Vec<f64>,
    /// Amplitude spectrum of measured C_M.
    pub moment_spectrum: Vec<f64>,
    /// Amplitude spectrum of model C_M.
    pub moment_model_spectrum: Vec<f64>,
    /// Key frequencies of the lift identification \[Hz\].
    pub lift_key_frequencies: Vec<f64>,
    /// Key frequencies of the moment identification \[Hz\].
    pub moment_key_frequencies: Vec<f64>,
}

/// Options of [`case_series`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeriesOptions {
    /// Length of the time window kept \[s\] (from the start of the record).
    pub window: f64,
    /// Highest frequency kept in the spectra \[Hz\].
    pub f_max: f64,
}

impl Default for SeriesOptions {
    fn default() -> Self {
        SeriesOptions {
            window: 3.0,
            f_max: 12.0,
        }
    }
}

/// Model output Σ ξ_j θ_j(x) of a term map on the samples of `case` (terms with a `null`
/// coefficient contribute nothing).
///
/// # Errors
/// [`Error::InvalidOption`] naming a term name that does not parse.
pub fn predict(case: &NondimCase, terms: &TermMap) -> Result<Vec<f64>> {
    let parsed: Vec<(Term, f64)> = terms
        .0
        .iter()
        .filter_map(|(n, v)| v.map(|v| (n, v)))
        .filter(|(_, v)| *v != 0.0)
        .map(|(n, v)| Term::parse(n).map(|t| (t, v)))
        .collect::<Result<_>>()?;
    let n = case.len();
    Ok((0..n)
        .map(|i| {
            let x = [case.x[0][i], case.x[1][i], case.x[2][i], case.x[3][i]];
            parsed.iter().map(|(t, c)| c * t.eval_at(x)).sum()
        })
        .collect())
}

/// One-sided amplitude spectrum of `y` sampled at `dt` with a Hann window (mean removed),
/// scaled so that a sinusoid of amplitude A on a bin shows A. Returns (f \[Hz\], amplitude)
/// up to `f_max`.
///
/// # Errors
/// [`Error::InvalidData`] for fewer than 4 samples or a non-positive `dt`.
pub fn amplitude_spectrum(y: &[f64], dt: f64, f_max: f64) -> Result<(Vec<f64>, Vec<f64>)> {
    let n = y.len();
    if n < 4 || !(dt.is_finite() && dt > 0.0) {
        return Err(Error::InvalidData {
            case: "-".into(),
            field: "spectrum".into(),
            message: format!("{n} samples at dt = {dt} s: need ≥ 4 samples and dt > 0"),
        });
    }
    let mean = y.iter().sum::<f64>() / n as f64;
    let w: Vec<f64> = (0..n)
        .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos())
        .collect();
    let wsum: f64 = w.iter().sum();
    let mut input: Vec<f64> = y.iter().zip(&w).map(|(v, w)| (v - mean) * w).collect();
    let fft = fft::forward(n);
    let mut out = fft.make_output_vec();
    fft.process(&mut input, &mut out)
        .map_err(|e| Error::Numerical {
            context: "amplitude spectrum".into(),
            message: e.to_string(),
        })?;
    let df = 1.0 / (n as f64 * dt);
    let mut f = Vec::new();
    let mut a = Vec::new();
    for (k, z) in out.iter().enumerate() {
        let fk = k as f64 * df;
        if fk > f_max {
            break;
        }
        f.push(fk);
        a.push(2.0 * z.norm() / wsum);
    }
    Ok((f, a))
}

/// Builds the [`CaseSeries`] of a case from its data and its identification result.
///
/// # Errors
/// [`Error::InvalidData`] when `result` is not the result of `case` (ids differ) or the case
/// is too short; errors of [`predict`] and [`amplitude_spectrum`].
pub fn case_series(
    case: &NondimCase,
    result: &CaseResult,
    opts: &SeriesOptions,
) -> Result<CaseSeries> {
    if case.meta.id != result.id {
        return Err(Error::InvalidData {
            case: case.meta.id.clone(),
            field: "id".into(),
            message: format!("result is for case `{}`", result.id),
        });
    }
    let lift_model = predict(case, &result.lift.terms)?;
    let moment_model = predict(case, &result.moment.terms)?;
    let (freq, ls) = amplitude_spectrum(&case.c_lift, case.dt, opts.f_max)?;
    let (_, lms) = amplitude_spectrum(&lift_model, case.dt, opts.f_max)?;
    let (_, ms) = amplitude_spectrum(&case.c_moment, case.dt, opts.f_max)?;
    let (_, mms) = amplitude_spectrum(&moment_model, case.dt, opts.f_max)?;
    let n_win = ((opts.window / case.dt).round() as usize).clamp(1, case.len());
    let b = case.chord;
    Ok(CaseSeries {
        format: FORMAT.into(),
        id: case.meta.id.clone(),
        wind_speed: case.meta.wind_speed,
        config: case.meta.config.clone(),
        amplitude_deg: case.meta.amplitude.map(f64::to_degrees),
        forcing_hz: [case.forcing.pitch, case.forcing.heave],
        t: (0..n_win).map(|i| i as f64 * case.dt).collect(),
        alpha_deg: case.x[0][..n_win].iter().map(|a| a.to_degrees()).collect(),
        h_mm: case.x[2][..n_win].iter().map(|h| h * b * 1e3).collect(),
        c_lift: case.c_lift[..n_win].to_vec(),
        c_lift_model: lift_model[..n_win].to_vec(),
        c_moment: case.c_moment[..n_win].to_vec(),
        c_moment_model: moment_model[..n_win].to_vec(),
        freq,
        lift_spectrum: ls,
        lift_model_spectrum: lms,
        moment_spectrum: ms,
        moment_model_spectrum: mms,
        lift_key_frequencies: result.lift.key_frequencies.clone(),
        moment_key_frequencies: result.moment.key_frequencies.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::{CaseMeta, Forcing};

    #[test]
    fn spectrum_of_a_sinusoid_on_a_bin_shows_its_amplitude() {
        let dt = 1.0 / 512.0;
        let y: Vec<f64> = (0..5120)
            .map(|i| 1.0 + 0.7 * (std::f64::consts::TAU * 2.0 * i as f64 * dt).sin())
            .collect();
        let (f, a) = amplitude_spectrum(&y, dt, 10.0).unwrap();
        let k = a
            .iter()
            .enumerate()
            .max_by(|x, y| x.1.total_cmp(y.1))
            .unwrap()
            .0;
        assert!((f[k] - 2.0).abs() < 1e-12, "peak at {}", f[k]);
        assert!((a[k] - 0.7).abs() < 1e-9, "amplitude {}", a[k]);
        assert!(*f.last().unwrap() <= 10.0);
        assert!(amplitude_spectrum(&y[..3], dt, 10.0).is_err());
    }

    #[test]
    fn predict_sums_term_contributions_and_skips_nulls() {
        let case = NondimCase {
            meta: CaseMeta {
                id: "c".into(),
                wind_speed: 1.0,
                ..CaseMeta::default()
            },
            dt: 0.1,
            chord: 1.0,
            x: [
                vec![1.0, 2.0],
                vec![3.0, 0.5],
                vec![0.0, 1.0],
                vec![1.0, 1.0],
            ],
            c_lift: vec![0.0; 2],
            c_moment: vec![0.0; 2],
            forcing: Forcing::default(),
        };
        let terms = TermMap(vec![
            ("alpha".into(), Some(2.0)),
            ("alpha^2*h".into(), Some(-1.0)),
            ("h_dot".into(), None),
        ]);
        let y = predict(&case, &terms).unwrap();
        // 2·α − α²h: sample 0: 2·1 − 0 = 2; sample 1: 2·2 − 4·1 = 0
        assert_eq!(y, vec![2.0, 0.0]);
        let bad = TermMap(vec![("beta".into(), Some(1.0))]);
        assert!(predict(&case, &bad).is_err());
    }
}
