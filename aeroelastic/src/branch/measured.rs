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

/// The measured criticality of a flutter onset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Criticality {
    /// Limit cycles exist below the onset speed (a jump to a finite-amplitude cycle at the
    /// onset, hysteresis on the way back).
    Subcritical,
    /// Limit cycles are born at the onset with zero amplitude and grow above it.
    Supercritical,
}

impl Criticality {
    /// `subcritical` / `supercritical` (as a continued branch's `criticality`).
    pub fn name(self) -> &'static str {
        match self {
            Criticality::Subcritical => "subcritical",
            Criticality::Supercritical => "supercritical",
        }
    }

    fn parse(s: &str) -> Option<Criticality> {
        match s {
            "subcritical" | "sub" => Some(Criticality::Subcritical),
            "supercritical" | "super" => Some(Criticality::Supercritical),
            _ => None,
        }
    }
}

/// A measured flutter onset (Hopf point): the wind speed at which the rig's equilibrium
/// lost stability (a row `onset` of a measured diagram, or `diagnose --onset`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MeasuredOnset {
    /// Line in the file (1-based; 0 for a command-line onset).
    pub line: usize,
    /// Onset (Hopf) speed [m/s].
    pub u: f64,
    /// Its standard uncertainty [m/s], if stated (`wind_speed_sd_m_s`).
    #[serde(default)]
    pub u_sd: Option<f64>,
    /// Frequency of the oscillation at onset \[Hz\], if measured.
    #[serde(default)]
    pub frequency_hz: Option<f64>,
    /// Its standard uncertainty \[Hz\], if stated (`freq_sd_hz`).
    #[serde(default)]
    pub frequency_sd_hz: Option<f64>,
    /// Sub- or supercritical, if known.
    #[serde(default)]
    pub criticality: Option<Criticality>,
}

/// "No LCO observed at U": the rig was perturbed at speed `u` (up to the largest
/// perturbation tried, when known) and always returned to rest (a row `none` of a measured
/// diagram, or `diagnose --no-lco`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MeasuredAbsence {
    /// Line in the file (1-based; 0 for a command-line row).
    pub line: usize,
    /// Wind speed [m/s].
    pub u: f64,
    /// Largest pitch perturbation tried \[rad\] (peak), if known.
    #[serde(default)]
    pub max_perturbation_alpha: Option<f64>,
    /// Largest heave perturbation tried \[m\] (peak, positive down), if known.
    #[serde(default)]
    pub max_perturbation_h: Option<f64>,
}

/// A measured bifurcation diagram: LCO amplitude points, measured onsets and speeds
/// where no LCO was observed.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MeasuredDiagram {
    /// Rows `stable` / `unstable`.
    pub points: Vec<MeasuredAmplitude>,
    /// Rows `onset`.
    pub onsets: Vec<MeasuredOnset>,
    /// Rows `none`.
    pub absences: Vec<MeasuredAbsence>,
}

fn read_table_text(path: &std::path::Path) -> Result<String> {
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
    })
}

/// Reads the LCO amplitude rows of a measured bifurcation diagram: CSV with a header naming
/// `branch` (`stable` or `unstable`), `wind_speed_m_s` and at least one of `heave_amp_m`
/// \[m\] and `pitch_amp_rad` \[rad\] (first-harmonic peak amplitudes), optionally `freq_hz`
/// \[Hz\]; other columns are ignored (the last column may contain commas); lines starting
/// with `#` are comments. A missing value is an empty field, `nan` or `-`; every row needs a
/// speed and at least one amplitude (docs/DATA_FORMAT.md, "Measured bifurcation diagram").
/// Rows `onset` and `none` are checked and left out ([`read_measured_diagram`] reads them).
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::InvalidTable`] naming the file,
/// the line and the column for a missing column, a bad or negative number, a row without
/// any amplitude or an unknown branch name, or a table without amplitude rows.
pub fn read_measured_amplitudes(path: &std::path::Path) -> Result<Vec<MeasuredAmplitude>> {
    parse_measured_amplitudes(&read_table_text(path)?, &path.display().to_string())
}

/// [`read_measured_amplitudes`] on the text of a file named `source` (for messages).
///
/// # Errors
/// As [`read_measured_amplitudes`].
pub fn parse_measured_amplitudes(text: &str, source: &str) -> Result<Vec<MeasuredAmplitude>> {
    let d = parse_measured_diagram(text, source)?;
    if d.points.is_empty() {
        return Err(Error::InvalidTable {
            table: source.to_string(),
            message: "no LCO amplitude rows (`stable` / `unstable`)".into(),
        });
    }
    Ok(d.points)
}

/// Reads a measured bifurcation diagram with its onset and absence rows: the table of
/// [`read_measured_amplitudes`] whose `branch` may also be
///
/// - `onset`: a measured flutter onset (Hopf point) at `wind_speed_m_s`, with optional
///   `freq_hz` \[Hz\], `criticality` (`subcritical` / `supercritical`) and the standard
///   uncertainties `wind_speed_sd_m_s` [m/s] and `freq_sd_hz` \[Hz\] (both > 0); no
///   amplitude;
/// - `none`: no LCO observed at `wind_speed_m_s`, with the largest perturbation tried in
///   the optional columns `max_perturbation_pitch_rad` \[rad\] and
///   `max_perturbation_heave_m` \[m\] (peak); no amplitude, frequency or criticality.
///
/// The amplitude columns are needed only when the table has `stable`/`unstable` rows.
/// Every file valid before these rows existed reads unchanged.
///
/// # Errors
/// As [`read_measured_amplitudes`]; [`Error::InvalidTable`] naming the file, line and
/// column also for a value in a column the row's kind does not take, an unknown
/// criticality, a zero uncertainty, or a table without any data row.
pub fn read_measured_diagram(path: &std::path::Path) -> Result<MeasuredDiagram> {
    parse_measured_diagram(&read_table_text(path)?, &path.display().to_string())
}

/// The columns of a measured diagram, in index order of [`parse_measured_diagram`].
const NAMES: [&str; 10] = [
    "branch",
    "wind_speed_m_s",
    "heave_amp_m",
    "pitch_amp_rad",
    "freq_hz",
    "criticality",
    "max_perturbation_pitch_rad",
    "max_perturbation_heave_m",
    "wind_speed_sd_m_s",
    "freq_sd_hz",
];

/// One checked number of column `k` (`None` when missing), with the limits table's bounds.
fn number(s: &str, k: usize) -> std::result::Result<Option<f64>, String> {
    if s.is_empty() || s == "-" || s.eq_ignore_ascii_case("nan") {
        return Ok(None);
    }
    let v: f64 = s
        .parse()
        .map_err(|_| format!("column `{}`: `{s}` is not a number", NAMES[k]))?;
    if !v.is_finite() || v < 0.0 {
        return Err(format!("column `{}`: {v} must be finite and ≥ 0", NAMES[k]));
    }
    // the limits table's bounds, so that one absurd row cannot decide the
    // diagnosis silently (issue 39, row 6: a speed of 1e308 or 0 gave "Hopf none")
    use identify::limits as lim;
    let (max, unit, positive) = match k {
        1 => (lim::MAX_SPEED, "m/s", true),
        2 | 7 => (lim::MAX_CHORD, "m", false),
        3 | 6 => (lim::MAX_PITCH_DEG.to_radians(), "rad", false),
        8 => (lim::MAX_SPEED, "m/s", true),
        9 => (lim::MAX_RATE, "Hz", true),
        _ => (lim::MAX_RATE, "Hz", false),
    };
    if v > max || (positive && v == 0.0) {
        return Err(format!(
            "column `{}`: {} {unit} is outside {} value ≤ {} {unit} (the limits table)",
            NAMES[k],
            lim::show(v),
            if positive { "0 <" } else { "0 ≤" },
            lim::show(max)
        ));
    }
    Ok(Some(v))
}

/// [`read_measured_diagram`] on the text of a file named `source` (for messages).
///
/// # Errors
/// As [`read_measured_diagram`].
pub fn parse_measured_diagram(text: &str, source: &str) -> Result<MeasuredDiagram> {
    let bad = |line: usize, msg: String| Error::InvalidTable {
        table: source.to_string(),
        message: format!("line {line}: {msg}"),
    };
    let mut header: Option<(usize, [Option<usize>; NAMES.len()], Vec<String>)> = None;
    let mut out = MeasuredDiagram::default();
    let mut rows = 0usize;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let Some((width, cols, names)) = &header else {
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
            header = Some((h.len(), cols, h));
            continue;
        };
        let (width, cols) = (*width, *cols);
        if rows >= identify::limits::MAX_MEASURED_POINTS {
            return Err(bad(
                line,
                format!(
                    "more than {} data rows (the limits table's MAX_MEASURED_POINTS)",
                    identify::limits::MAX_MEASURED_POINTS
                ),
            ));
        }
        rows += 1;
        let f = identify::csv_fields::split_line(l);
        if f.len() < width {
            return Err(bad(
                line,
                format!("{} fields, the header has {width}", f.len()),
            ));
        }
        let text_of = |k: usize| -> &str { cols[k].map_or("", |c| f[c].as_str()) };
        let num =
            |k: usize| -> Result<Option<f64>> { number(text_of(k), k).map_err(|m| bad(line, m)) };
        let kind = text_of(0);
        // a column this row's kind does not take must be empty
        let empty = |ks: &[usize]| -> Result<()> {
            for &k in ks {
                let s = text_of(k);
                if !(s.is_empty() || s == "-" || s.eq_ignore_ascii_case("nan")) {
                    return Err(bad(
                        line,
                        format!(
                            "column `{}`: a `{kind}` row takes no value (`{s}`)",
                            NAMES[k]
                        ),
                    ));
                }
            }
            Ok(())
        };
        let u = || -> Result<f64> {
            num(1)?.ok_or_else(|| bad(line, "column `wind_speed_m_s`: no value".into()))
        };
        match kind {
            "stable" | "unstable" => {
                if cols[2].is_none() && cols[3].is_none() {
                    return Err(bad(
                        line,
                        format!(
                            "a `{kind}` row needs an amplitude, but the header has neither \
                             `heave_amp_m` nor `pitch_amp_rad` (columns: {})",
                            names.join(", ")
                        ),
                    ));
                }
                empty(&[5, 6, 7, 8, 9])?;
                let u = u()?;
                let (amplitude_h, amplitude_alpha) = (num(2)?, num(3)?);
                if amplitude_h.is_none() && amplitude_alpha.is_none() {
                    return Err(bad(
                        line,
                        "neither `heave_amp_m` nor `pitch_amp_rad` has a value".into(),
                    ));
                }
                out.points.push(MeasuredAmplitude {
                    line,
                    stable: kind == "stable",
                    u,
                    amplitude_h,
                    amplitude_alpha,
                    frequency_hz: num(4)?.filter(|&v| v > 0.0),
                });
            }
            "onset" => {
                empty(&[2, 3, 6, 7])?;
                let crit = text_of(5);
                let criticality = match crit {
                    "" | "-" => None,
                    s => Some(Criticality::parse(s).ok_or_else(|| {
                        bad(
                            line,
                            format!(
                                "column `criticality`: `{s}` is neither `subcritical` nor \
                                 `supercritical` (or empty: unknown)"
                            ),
                        )
                    })?),
                };
                let frequency_hz = num(4)?.filter(|&v| v > 0.0);
                let frequency_sd_hz = num(9)?;
                if frequency_sd_hz.is_some() && frequency_hz.is_none() {
                    return Err(bad(
                        line,
                        "column `freq_sd_hz`: an uncertainty without a frequency".into(),
                    ));
                }
                out.onsets.push(MeasuredOnset {
                    line,
                    u: u()?,
                    u_sd: num(8)?,
                    frequency_hz,
                    frequency_sd_hz,
                    criticality,
                });
            }
            "none" => {
                empty(&[2, 3, 4, 5, 8, 9])?;
                out.absences.push(MeasuredAbsence {
                    line,
                    u: u()?,
                    max_perturbation_alpha: num(6)?,
                    max_perturbation_h: num(7)?,
                });
            }
            other => {
                return Err(bad(
                    line,
                    format!(
                        "column `branch`: `{other}` is none of `stable`, `unstable`, `onset` \
                         (a measured flutter onset) and `none` (no LCO observed)"
                    ),
                ))
            }
        }
    }
    if rows == 0 {
        return Err(Error::InvalidTable {
            table: source.to_string(),
            message: "no data rows".into(),
        });
    }
    Ok(out)
}

/// A measured onset from the command line: `U[:F][:sub|super][:sd=SD]` — speed [m/s],
/// then in any order a frequency \[Hz\], a criticality (`sub`, `subcritical`, `super`,
/// `supercritical`) and the speed's standard uncertainty `sd=SD` [m/s].
///
/// # Errors
/// [`Error::InvalidTable`] (table `--onset`) naming the part that is not a number, out of
/// the limits table's bounds, or given twice.
pub fn parse_onset_arg(s: &str) -> Result<MeasuredOnset> {
    let bad = |m: String| Error::InvalidTable {
        table: "--onset".into(),
        message: format!("`{s}`: {m}"),
    };
    let mut parts = s.split(':').map(str::trim);
    let u = number(parts.next().unwrap_or(""), 1)
        .map_err(bad)?
        .ok_or_else(|| bad("no speed (`U[:F][:sub|super][:sd=SD]`)".into()))?;
    let mut o = MeasuredOnset {
        line: 0,
        u,
        u_sd: None,
        frequency_hz: None,
        frequency_sd_hz: None,
        criticality: None,
    };
    for p in parts {
        if let Some(c) = Criticality::parse(p) {
            if o.criticality.replace(c).is_some() {
                return Err(bad("criticality given twice".into()));
            }
        } else if let Some(v) = p.strip_prefix("sd=") {
            let v = number(v, 8).map_err(bad)?;
            if v.is_none() || o.u_sd.replace(v.unwrap_or(0.0)).is_some() {
                return Err(bad("`sd=` needs one value, once".into()));
            }
        } else {
            let v = number(p, 4)
                .map_err(|_| {
                    bad(format!(
                        "`{p}` is neither a frequency [Hz], `sub`/`super` nor `sd=SD`"
                    ))
                })?
                .filter(|&v| v > 0.0)
                .ok_or_else(|| bad(format!("`{p}`: the frequency must be > 0")))?;
            if o.frequency_hz.replace(v).is_some() {
                return Err(bad("frequency given twice".into()));
            }
        }
    }
    Ok(o)
}

/// "No LCO observed" from the command line: `U[:PITCH_RAD[:HEAVE_M]]` — speed [m/s] and
/// the largest pitch \[rad\] and heave \[m\] perturbation tried (peak; `-` or empty for
/// unknown).
///
/// # Errors
/// [`Error::InvalidTable`] (table `--no-lco`) naming the part that is not a number or out
/// of the limits table's bounds, or more than three parts.
pub fn parse_absence_arg(s: &str) -> Result<MeasuredAbsence> {
    let bad = |m: String| Error::InvalidTable {
        table: "--no-lco".into(),
        message: format!("`{s}`: {m}"),
    };
    let parts: Vec<&str> = s.split(':').map(str::trim).collect();
    if parts.len() > 3 {
        return Err(bad(
            "more than three parts (`U[:PITCH_RAD[:HEAVE_M]]`)".into()
        ));
    }
    let get = |i: usize, k: usize| -> Result<Option<f64>> {
        parts.get(i).map_or(Ok(None), |p| number(p, k).map_err(bad))
    };
    Ok(MeasuredAbsence {
        line: 0,
        u: get(0, 1)?.ok_or_else(|| bad("no speed".into()))?,
        max_perturbation_alpha: get(1, 6)?,
        max_perturbation_h: get(2, 7)?,
    })
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
    /// For a point no segment covers, set by the bifurcation-level diagnosis: the nearest
    /// predicted orbit of the same stability in its scaled plane of speed and amplitudes,
    /// `[u` [m/s], first-harmonic pitch \[rad\], heave \[m\]`]` (the orbit its score
    /// compares the point with); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nearest: Option<[f64; 3]>,
}

/// The segment of `set` that [`predicted_at`] interpolates for the measured point `m`:
/// (branch index, index of the segment's first point). Among the segments of the same
/// stability that cover `m.u`, the one whose interpolated first-harmonic amplitude is
/// closest to the measured one (pitch when measured, else heave); the first on a tie.
/// `None` when no segment covers `m.u`.
pub fn covering_segment(set: &BranchSet, m: &MeasuredAmplitude) -> Option<(usize, usize)> {
    let mut best: Option<(f64, (usize, usize))> = None;
    for (bi, b) in set.branches.iter().enumerate() {
        for (i, w) in b.points.windows(2).enumerate() {
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
            let miss = match (m.amplitude_alpha, m.amplitude_h) {
                (Some(ma), _) => (a - ma).abs(),
                (None, Some(mh)) => (h - mh).abs(),
                (None, None) => 0.0,
            };
            if best.is_none_or(|(bm, _)| miss < bm) {
                best = Some((miss, (bi, i)));
            }
        }
    }
    best.map(|b| b.1)
}

/// The predicted orbit at a measured point's speed on the branches of `set`: the
/// segment of the same stability that covers `m.u` and whose first-harmonic amplitude is
/// closest to the measured one (pitch when measured, else heave; [`covering_segment`]),
/// linearly interpolated in U. Returns (pitch \[rad\], heave \[m\], frequency \[Hz\]).
pub fn predicted_at(set: &BranchSet, m: &MeasuredAmplitude) -> Option<(f64, f64, f64)> {
    let (bi, i) = covering_segment(set, m)?;
    let w = &set.branches[bi].points[i..i + 2];
    let f = (m.u - w[0].u) / (w[1].u - w[0].u);
    let lerp = |a: f64, b: f64| a * (1.0 - f) + b * f;
    Some((
        lerp(w[0].amplitude1_alpha, w[1].amplitude1_alpha),
        lerp(w[0].amplitude1_h, w[1].amplitude1_h),
        lerp(w[0].omega, w[1].omega) / std::f64::consts::TAU,
    ))
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
        .map(|m| measured_distance(set, m, predicted_at(set, m)))
        .collect()
}

/// The distance of measured point `m` to the branches of `set` given its predicted orbit
/// `best` (first-harmonic pitch \[rad\], heave \[m\], frequency \[Hz\]; `None`: no segment
/// of its stability covers its speed, and `speed_gap` is then the distance in speed to the
/// nearest orbit of that stability). [`measured_distances`] takes `best` from
/// [`predicted_at`]; a caller that corrects the orbit at the measured speed passes its own.
pub fn measured_distance(
    set: &BranchSet,
    m: &MeasuredAmplitude,
    best: Option<(f64, f64, f64)>,
) -> MeasuredDistance {
    let gap = set
        .branches
        .iter()
        .flat_map(|b| b.points.iter())
        .filter(|p| p.stable == m.stable)
        .map(|p| (p.u - m.u).abs())
        .fold(f64::INFINITY, f64::min);
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
        nearest: None,
    }
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

    /// Onset and absence rows: read with their optional columns beside amplitude rows; an
    /// old table reads unchanged; a table of onsets alone needs no amplitude column.
    #[test]
    fn onset_and_absence_rows() {
        let t = "branch,wind_speed_m_s,heave_amp_m,pitch_amp_rad,freq_hz,criticality,\
                 max_perturbation_pitch_rad,wind_speed_sd_m_s,source\n\
                 stable,15,0.02,0.05,2.4,,,,a, b\n\
                 onset,17.93,,,2.46,subcritical,,0.05,estimate\n\
                 onset,18.1,-,nan,,,,,second\n\
                 none,12,,,,,0.1,,kicked\n";
        let d = parse_measured_diagram(t, "t.csv").unwrap();
        assert_eq!(d.points.len(), 1);
        assert_eq!(d.onsets.len(), 2);
        assert_eq!(d.onsets[0].u, 17.93);
        assert_eq!(d.onsets[0].u_sd, Some(0.05));
        assert_eq!(d.onsets[0].frequency_hz, Some(2.46));
        assert_eq!(d.onsets[0].criticality, Some(Criticality::Subcritical));
        assert_eq!(d.onsets[1].criticality, None);
        assert_eq!(d.onsets[1].line, 4);
        assert_eq!(d.absences.len(), 1);
        assert_eq!(d.absences[0].max_perturbation_alpha, Some(0.1));
        assert_eq!(d.absences[0].max_perturbation_h, None);
        // the amplitude rows alone, as before
        assert_eq!(parse_measured_amplitudes(t, "t.csv").unwrap(), d.points);
        let only =
            parse_measured_diagram("branch,wind_speed_m_s\nonset,17.9\nnone,10\n", "o").unwrap();
        assert_eq!(
            (only.points.len(), only.onsets.len(), only.absences.len()),
            (0, 1, 1)
        );
        let e = parse_measured_amplitudes("branch,wind_speed_m_s\nonset,17.9\n", "o.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no LCO amplitude rows") && e.contains("o.csv"),
            "{e}"
        );
        // an old table: the same points as the old reader gave
        let old = "branch,wind_speed_m_s,heave_amp_m,pitch_amp_rad,freq_hz,source\n\
                   stable,14.9,0.0191,0.0462,2.449,record 1\nunstable,15.7,,0.0321,nan,x\n";
        let o = parse_measured_diagram(old, "old").unwrap();
        assert_eq!(o.points.len(), 2);
        assert!(o.onsets.is_empty() && o.absences.is_empty());
    }

    /// Malformed onset and absence rows are refused naming file, line and column.
    #[test]
    fn malformed_onset_and_absence_rows_are_refused() {
        let head = "branch,wind_speed_m_s,pitch_amp_rad,freq_hz,criticality,\
                    max_perturbation_pitch_rad,wind_speed_sd_m_s,freq_sd_hz\n";
        for (row, needle) in [
            ("onset,17.9,0.02,,,,,", "pitch_amp_rad"),
            ("onset,17.9,,,hyper,,,", "criticality"),
            ("onset,17.9,,,,0.1,,", "max_perturbation_pitch_rad"),
            ("onset,17.9,,,,,0,", "wind_speed_sd_m_s"),
            ("onset,17.9,,,,,,0.1", "freq_sd_hz"),
            ("onset,,,,,,,", "wind_speed_m_s"),
            ("none,12,,2.4,,,,", "freq_hz"),
            ("none,12,,,subcritical,,,", "criticality"),
            ("none,12,,,,-0.1,,", "max_perturbation_pitch_rad"),
            ("stable,12,0.1,,subcritical,,,", "criticality"),
            ("flutter,12,,,,,,", "`flutter`"),
        ] {
            let e = parse_measured_diagram(&format!("{head}{row}\n"), "bad.csv")
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(needle) && e.contains("bad.csv") && e.contains("line 2"),
                "{row}: {e}"
            );
        }
    }

    /// Command-line onsets and absences: parts in any order, refusals name the flag.
    #[test]
    fn onset_and_absence_arguments() {
        let o = parse_onset_arg("17.93:2.46:sub:sd=0.05").unwrap();
        assert_eq!(
            (o.u, o.frequency_hz, o.criticality, o.u_sd),
            (
                17.93,
                Some(2.46),
                Some(Criticality::Subcritical),
                Some(0.05)
            )
        );
        let o = parse_onset_arg("18:supercritical").unwrap();
        assert_eq!(
            (o.frequency_hz, o.criticality),
            (None, Some(Criticality::Supercritical))
        );
        let a = parse_absence_arg("12:0.1").unwrap();
        assert_eq!(
            (a.u, a.max_perturbation_alpha, a.max_perturbation_h),
            (12.0, Some(0.1), None)
        );
        let a = parse_absence_arg("12:-:0.01").unwrap();
        assert_eq!(
            (a.max_perturbation_alpha, a.max_perturbation_h),
            (None, Some(0.01))
        );
        for (s, flag) in [
            ("x", "--onset"),
            ("17:2:3", "--onset"),
            ("17:sub:super", "--onset"),
            ("0", "--onset"),
            ("17:sd=0", "--onset"),
        ] {
            let e = parse_onset_arg(s).unwrap_err().to_string();
            assert!(e.contains(flag) && e.contains(s), "{s}: {e}");
        }
        for s in ["", "12:a", "12:0.1:0.1:1", "-3"] {
            let e = parse_absence_arg(s).unwrap_err().to_string();
            assert!(e.contains("--no-lco"), "{s}: {e}");
        }
    }
}
