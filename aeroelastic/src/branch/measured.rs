//! Measured bifurcation diagrams: measured branch points read from CSV
//! ([`read_measured_amplitudes`]) and their distances to the predicted branches
//! ([`measured_distances`]).

use serde::{Deserialize, Serialize};

use super::types::BranchSet;
use crate::{Error, Result};

/// One measured point of a bifurcation diagram (a row of a table like
/// `bristol-spring1-lco-amplitudes.csv`, or a point extracted from an LCO record):
/// first-harmonic amplitudes and frequency of a periodic orbit at one speed. Any of the
/// amplitudes and the frequency may be missing (e.g. a heave-only table), not both
/// amplitudes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MeasuredAmplitude {
    /// Line in the file (1-based; 0 for a point extracted from a record).
    pub line: usize,
    /// Branch the point was measured on (`stable` / `unstable`).
    pub stable: bool,
    /// Wind speed [m/s].
    pub u: f64,
    /// First-harmonic heave amplitude \[m\] (peak), if measured.
    pub amplitude_h: Option<f64>,
    /// First-harmonic pitch amplitude \[rad\] (peak), if measured.
    pub amplitude_alpha: Option<f64>,
    /// Frequency of the orbit \[Hz\], if measured.
    #[serde(default)]
    pub frequency_hz: Option<f64>,
}

/// Reads a measured bifurcation diagram: CSV with a header naming `branch` (`stable` or
/// `unstable`), `wind_speed_m_s` and at least one of `heave_amp_m` \[m\] and `pitch_amp_rad`
/// \[rad\] (first-harmonic peak amplitudes), optionally `freq_hz` \[Hz\]; other columns are
/// ignored (the last column may contain commas); lines starting with `#` are comments. A
/// missing value is an empty field, `nan` or `-`; every row needs a speed and at least one
/// amplitude (docs/DATA_FORMAT.md, "Measured bifurcation diagram").
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::InvalidTable`] naming the file,
/// the line and the column for a missing column, a bad or negative number, a row without
/// any amplitude or an unknown branch name, or a table without data rows.
pub fn read_measured_amplitudes(path: &std::path::Path) -> Result<Vec<MeasuredAmplitude>> {
    let text =
        identify::io::read_text(path).map_err(|e| match identify::io::is_input_error(&e) {
            // refused by the reader (missing, not a regular file, too large, not UTF-8): an input error
            true => Error::InvalidTable {
                table: path.display().to_string(),
                message: e.to_string(),
            },
            false => Error::Io {
                path: path.display().to_string(),
                message: e.to_string(),
            },
        })?;
    parse_measured_amplitudes(&text, &path.display().to_string())
}

/// [`read_measured_amplitudes`] on the text of a file named `source` (for messages).
///
/// # Errors
/// As [`read_measured_amplitudes`].
pub fn parse_measured_amplitudes(text: &str, source: &str) -> Result<Vec<MeasuredAmplitude>> {
    let bad = |line: usize, msg: String| Error::InvalidTable {
        table: source.to_string(),
        message: format!("line {line}: {msg}"),
    };
    // (branch, speed) required; heave, pitch, frequency optional columns.
    const NAMES: [&str; 5] = [
        "branch",
        "wind_speed_m_s",
        "heave_amp_m",
        "pitch_amp_rad",
        "freq_hz",
    ];
    let mut header: Option<(usize, [Option<usize>; 5])> = None;
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let Some((width, cols)) = header else {
            let h = identify::csv_fields::split_line(l);
            let cols = NAMES.map(|name| h.iter().position(|c| c == name));
            for k in 0..2 {
                if cols[k].is_none() {
                    return Err(bad(
                        line,
                        format!(
                            "header has no column `{}` (columns: {})",
                            NAMES[k],
                            h.join(", ")
                        ),
                    ));
                }
            }
            if cols[2].is_none() && cols[3].is_none() {
                return Err(bad(
                    line,
                    format!(
                        "header has neither `heave_amp_m` nor `pitch_amp_rad` (columns: {})",
                        h.join(", ")
                    ),
                ));
            }
            header = Some((h.len(), cols));
            continue;
        };
        if out.len() >= identify::limits::MAX_MEASURED_POINTS {
            return Err(bad(
                line,
                format!(
                    "more than {} data rows (the limits table's MAX_MEASURED_POINTS)",
                    identify::limits::MAX_MEASURED_POINTS
                ),
            ));
        }
        let f = identify::csv_fields::split_line(l);
        if f.len() < width {
            return Err(bad(
                line,
                format!("{} fields, the header has {width}", f.len()),
            ));
        }
        let num = |k: usize| -> Result<Option<f64>> {
            let Some(c) = cols[k] else { return Ok(None) };
            let s = f[c].as_str();
            if s.is_empty() || s == "-" || s.eq_ignore_ascii_case("nan") {
                return Ok(None);
            }
            let v: f64 = s.parse().map_err(|_| {
                bad(
                    line,
                    format!("column `{}`: `{s}` is not a number", NAMES[k]),
                )
            })?;
            if !v.is_finite() || v < 0.0 {
                return Err(bad(
                    line,
                    format!("column `{}`: {v} must be finite and ≥ 0", NAMES[k]),
                ));
            }
            // the limits table's bounds, so that one absurd row cannot decide the
            // diagnosis silently (issue 39, row 6: a speed of 1e308 or 0 gave "Hopf none")
            use identify::limits as lim;
            let (max, unit, positive) = match k {
                1 => (lim::MAX_SPEED, "m/s", true),
                2 => (lim::MAX_CHORD, "m", false),
                3 => (lim::MAX_PITCH_DEG.to_radians(), "rad", false),
                _ => (lim::MAX_RATE, "Hz", false),
            };
            if v > max || (positive && v == 0.0) {
                return Err(bad(
                    line,
                    format!(
                        "column `{}`: {} {unit} is outside {} value ≤ {} {unit} (the limits table)",
                        NAMES[k],
                        lim::show(v),
                        if positive { "0 <" } else { "0 ≤" },
                        lim::show(max)
                    ),
                ));
            }
            Ok(Some(v))
        };
        let stable = match f[cols[0].expect("checked")].as_str() {
            "stable" => true,
            "unstable" => false,
            other => {
                return Err(bad(
                    line,
                    format!("column `branch`: `{other}` is neither `stable` nor `unstable`"),
                ))
            }
        };
        let u = num(1)?.ok_or_else(|| bad(line, "column `wind_speed_m_s`: no value".into()))?;
        let (amplitude_h, amplitude_alpha) = (num(2)?, num(3)?);
        if amplitude_h.is_none() && amplitude_alpha.is_none() {
            return Err(bad(
                line,
                "neither `heave_amp_m` nor `pitch_amp_rad` has a value".into(),
            ));
        }
        out.push(MeasuredAmplitude {
            line,
            stable,
            u,
            amplitude_h,
            amplitude_alpha,
            frequency_hz: num(4)?.filter(|&v| v > 0.0),
        });
    }
    if out.is_empty() {
        return Err(Error::InvalidTable {
            table: source.to_string(),
            message: "no data rows".into(),
        });
    }
    Ok(out)
}

/// Distance of one measured point to the predicted branch of the same stability.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MeasuredDistance {
    /// The measured point.
    pub measured: MeasuredAmplitude,
    /// Predicted first-harmonic pitch amplitude at the measured speed on the branch of the
    /// same stability \[rad\] (the segment closest in amplitude when several cover the
    /// speed); `None` when no such segment covers the speed.
    pub predicted_alpha: Option<f64>,
    /// Predicted first-harmonic heave amplitude there \[m\].
    pub predicted_h: Option<f64>,
    /// Predicted frequency there \[Hz\].
    #[serde(default)]
    pub predicted_frequency_hz: Option<f64>,
    /// Predicted − measured pitch amplitude \[rad\] (`None` when either is missing).
    pub d_alpha: Option<f64>,
    /// Predicted − measured heave amplitude \[m\] (`None` when either is missing).
    pub d_h: Option<f64>,
    /// Distance in speed to the nearest predicted orbit of the same stability \[m/s\]
    /// (0 when a segment covers the speed); `None` (`null`) when no predicted orbit has
    /// that stability (it was written `null` before, as the non-finite distance).
    pub speed_gap: Option<f64>,
}

/// The predicted orbit at a measured point's speed on the branches of `set`: the
/// segment of the same stability that covers `m.u` and whose first-harmonic amplitude is
/// closest to the measured one (pitch when measured, else heave), linearly interpolated
/// in U. Returns (pitch \[rad\], heave \[m\], frequency \[Hz\]).
pub fn predicted_at(set: &BranchSet, m: &MeasuredAmplitude) -> Option<(f64, f64, f64)> {
    let mut best: Option<(f64, (f64, f64, f64))> = None;
    for b in &set.branches {
        for w in b.points.windows(2) {
            if w[0].stable != m.stable || w[1].stable != m.stable {
                continue;
            }
            if (w[0].u - m.u) * (w[1].u - m.u) > 0.0 || w[0].u == w[1].u {
                continue;
            }
            let f = (m.u - w[0].u) / (w[1].u - w[0].u);
            let lerp = |a: f64, b: f64| a * (1.0 - f) + b * f;
            let a = lerp(w[0].amplitude1_alpha, w[1].amplitude1_alpha);
            let h = lerp(w[0].amplitude1_h, w[1].amplitude1_h);
            let hz = lerp(w[0].omega, w[1].omega) / std::f64::consts::TAU;
            let miss = match (m.amplitude_alpha, m.amplitude_h) {
                (Some(ma), _) => (a - ma).abs(),
                (None, Some(mh)) => (h - mh).abs(),
                (None, None) => 0.0,
            };
            if best.is_none_or(|(bm, _)| miss < bm) {
                best = Some((miss, (a, h, hz)));
            }
        }
    }
    best.map(|b| b.1)
}

/// Distances of measured points to the predicted branches of the same stability
/// (first-harmonic amplitudes, linear interpolation in U between branch points;
/// [`predicted_at`]).
pub fn measured_distances(
    set: &BranchSet,
    measured: &[MeasuredAmplitude],
) -> Vec<MeasuredDistance> {
    measured
        .iter()
        .map(|m| {
            let gap = set
                .branches
                .iter()
                .flat_map(|b| b.points.iter())
                .filter(|p| p.stable == m.stable)
                .map(|p| (p.u - m.u).abs())
                .fold(f64::INFINITY, f64::min);
            let best = predicted_at(set, m);
            let diff = |p: Option<f64>, q: Option<f64>| Some(p? - q?);
            MeasuredDistance {
                measured: m.clone(),
                predicted_alpha: best.map(|b| b.0),
                predicted_h: best.map(|b| b.1),
                predicted_frequency_hz: best.map(|b| b.2),
                d_alpha: diff(best.map(|b| b.0), m.amplitude_alpha),
                d_h: diff(best.map(|b| b.1), m.amplitude_h),
                speed_gap: if best.is_some() {
                    Some(0.0)
                } else {
                    Some(gap).filter(|g| g.is_finite())
                },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Missing values (empty, `nan`, `-`), a heave-only header and the optional frequency
    /// are read; a row without any amplitude, a missing speed column and a bad number are
    /// refused with file, line and column.
    #[test]
    fn measured_tables_with_missing_values() {
        let t = "# c\nbranch,wind_speed_m_s,heave_amp_m,pitch_amp_rad,freq_hz,source\n\
                 stable,15,0.02,,2.4,a, b\nunstable,16,-,0.03,nan,x\n";
        let m = parse_measured_amplitudes(t, "t.csv").unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!((m[0].amplitude_alpha, m[0].frequency_hz), (None, Some(2.4)));
        assert_eq!((m[1].amplitude_h, m[1].amplitude_alpha), (None, Some(0.03)));
        assert_eq!(m[1].frequency_hz, None);
        let heave =
            parse_measured_amplitudes("branch,wind_speed_m_s,heave_amp_m\nstable,15,0.02\n", "h")
                .unwrap();
        assert_eq!(heave[0].amplitude_alpha, None);
        for (text, needle) in [
            (
                "branch,wind_speed_m_s,heave_amp_m,pitch_amp_rad\nstable,15,,nan\n",
                "line 2",
            ),
            ("branch,heave_amp_m\nstable,0.1\n", "wind_speed_m_s"),
            (
                "branch,wind_speed_m_s,pitch_amp_rad\nstable,15,abc\n",
                "pitch_amp_rad",
            ),
            ("branch,wind_speed_m_s,freq_hz\nstable,15,2\n", "neither"),
        ] {
            let e = parse_measured_amplitudes(text, "bad.csv")
                .unwrap_err()
                .to_string();
            assert!(e.contains(needle) && e.contains("bad.csv"), "{e}");
        }
    }
}
