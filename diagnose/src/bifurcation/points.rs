//! Measured bifurcation points from LCO records, and the still-air decays' structure.
//!
//! A free-response record at U > 0 that holds a periodic orbit gives one point of the
//! measured bifurcation diagram: its frequency (the largest spectral peak of pitch, or of
//! heave when pitch is flat, refined by least squares) and the first-harmonic amplitude of
//! each DOF at that frequency over the whole record. Its branch is the `branch` entry of
//! the case's `[case.extra]` (`stable` / `unstable`, as control-based continuation records
//! carry it); without one, a record whose first-harmonic amplitude changes by less than
//! [`STEADY_CHANGE`] between its halves is a stable orbit (an uncontrolled rig holds only
//! stable cycles), and any other record is a transient and gives no point.
//!
//! A record at U = 0 (still-air decay) identifies the structure instead
//! ([`structure_check`]): per DOF, the frequency and damping ratio of its dominant mode
//! in windows of four periods, their trend with amplitude (backbone), and the shape of the
//! envelope (exponential for viscous damping, linear for dry friction), against the modes
//! of the given structure in still air.

use aeroelastic::branch::MeasuredAmplitude;
use identify::dataset::Dataset;
use identify::preprocess::{dominant_frequency, refine_frequency};
use serde::{Deserialize, Serialize};

use crate::structure::first_harmonic;
pub use crate::structure::{structure_check, ModeCheck, StructureCheck, MIN_PERIODS};
use crate::{Error, Result};

/// Largest relative change of a record's first-harmonic amplitude between its halves for
/// it to count as a steady (stable) orbit when its case does not name its branch.
pub const STEADY_CHANGE: f64 = 0.10;

/// What became of one free-response record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RecordUse {
    /// Case id.
    pub case: String,
    /// Wind speed [m/s].
    pub wind_speed: f64,
    /// `point` (a measured branch point), `decay` (still air: structure) or `skipped`.
    pub used_as: RecordRole,
    /// Why, in words (the branch source, or the reason it was skipped).
    pub note: String,
}

/// The role a free-response record plays at the bifurcation level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RecordRole {
    /// A measured branch point.
    Point,
    /// A still-air decay (structure identification).
    Decay,
    /// Not used (transient, too short, flat).
    Skipped,
}

/// First-harmonic amplitude of `x` at `f` \[Hz\] (mean fitted too).
fn std_dev(x: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n).sqrt()
}

/// The measured branch points of the LCO records (U > 0) of `set`, and what became of
/// every record (decays and skipped records included).
///
/// # Errors
/// [`Error::Data`] naming the data set when no record gives a point (the message lists
/// why each was skipped).
pub fn points_from_records(set: &Dataset) -> Result<(Vec<MeasuredAmplitude>, Vec<RecordUse>)> {
    let mut points = Vec::new();
    let mut uses = Vec::new();
    for (spec, rec) in set.manifest.cases.iter().zip(&set.records) {
        let u = rec.meta.wind_speed;
        let mut use_ = |role: RecordRole, note: String| {
            uses.push(RecordUse {
                case: spec.id.clone(),
                wind_speed: u,
                used_as: role,
                note,
            })
        };
        if u <= 0.0 {
            use_(
                RecordRole::Decay,
                "still air: structure identification".into(),
            );
            continue;
        }
        let dt = rec.dt;
        let (sa, sh) = (std_dev(&rec.alpha), std_dev(&rec.h));
        let main: &[f64] = if sa > 0.0 { &rec.alpha } else { &rec.h };
        let Some(f0) = dominant_frequency(main, dt) else {
            use_(RecordRole::Skipped, "flat record: no spectral peak".into());
            continue;
        };
        let f = refine_frequency(main, dt, f0);
        let periods = rec.len() as f64 * dt * f;
        if periods < MIN_PERIODS {
            use_(
                RecordRole::Skipped,
                format!("{periods:.1} periods of {f:.3} Hz, fewer than {MIN_PERIODS}"),
            );
            continue;
        }
        let a1 = (sa > 0.0)
            .then(|| first_harmonic(&rec.alpha, dt, f))
            .flatten();
        let h1 = (sh > 0.0).then(|| first_harmonic(&rec.h, dt, f)).flatten();
        let extra = spec
            .extra
            .as_ref()
            .and_then(|e| e.get("branch"))
            .and_then(|v| v.as_str());
        let stable = match extra {
            Some("stable") => Some((true, "branch from [case.extra]".to_string())),
            Some("unstable") => Some((false, "branch from [case.extra]".to_string())),
            _ => {
                let n = main.len() / 2;
                let first = first_harmonic(&main[..n], dt, f).unwrap_or(0.0);
                let second = first_harmonic(&main[n..], dt, f).unwrap_or(0.0);
                let change = (second - first).abs() / first.max(second).max(f64::MIN_POSITIVE);
                if change < STEADY_CHANGE {
                    Some((
                        true,
                        format!(
                            "steady orbit (amplitude changes {:.1} % between halves): stable",
                            100.0 * change
                        ),
                    ))
                } else {
                    use_(
                        RecordRole::Skipped,
                        format!(
                            "transient: amplitude changes {:.1} % between halves and the case \
                             names no branch",
                            100.0 * change
                        ),
                    );
                    None
                }
            }
        };
        let Some((stable, note)) = stable else {
            continue;
        };
        points.push(MeasuredAmplitude {
            line: 0,
            stable,
            u,
            amplitude_h: h1,
            amplitude_alpha: a1,
            frequency_hz: Some(f),
        });
        use_(RecordRole::Point, note);
    }
    if points.is_empty() {
        let why: Vec<String> = uses
            .iter()
            .map(|u| format!("{} ({})", u.case, u.note))
            .collect();
        return Err(Error::data(
            &set.manifest.name,
            format!(
                "no record gives a branch point: {}",
                if why.is_empty() {
                    "no free-response case".to_string()
                } else {
                    why.join("; ")
                }
            ),
        ));
    }
    Ok((points, uses))
}
