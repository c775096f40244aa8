//! Writing data sets: the units of the written files ([`paper_units`]), manifest descriptors
//! rounded for writing, the manifest's `[extra]` entries of a tunnel run, the case-id check
//! and the atomic write of case files and manifest ([`write`]).

use std::path::Path;

use identify::dataset::{AngleUnit, ForceUnit, LengthUnit, Manifest, MomentUnit, Units};
use identify::record::Record;

use super::SensorNoise;
use crate::{Error, Result};

/// Units mm / deg / N / N·m (totals over the span), as the paper's rig.
pub fn paper_units() -> Units {
    Units {
        heave: LengthUnit::Mm,
        pitch: AngleUnit::Deg,
        lift: ForceUnit::N,
        moment: MomentUnit::Nm,
    }
}

/// A descriptor converted from SI for the manifest, rounded to 12 significant digits so that
/// a value given in degrees comes back as written (6, not 6.000000000000001, after rad → deg).
pub(super) fn tidy(x: f64) -> f64 {
    format!("{x:.11e}").parse().unwrap_or(x)
}

pub(super) fn manifest_extra(
    kind: &str,
    model: &str,
    seed: u64,
    noise: &SensorNoise,
    chord: f64,
) -> toml::Table {
    let mut extra = toml::Table::new();
    extra.insert(
        "generator".into(),
        format!("aeroelastic::tunnel ({kind})").into(),
    );
    extra.insert("model".into(), model.into());
    extra.insert("seed".into(), seed.to_string().into());
    extra.insert(
        "seed_rule".into(),
        "case seed = aeroelastic::tunnel::case_seed(seed, case index from 0)".into(),
    );
    match &noise.balance_absolute {
        Some(b) => {
            extra.insert("noise_balance_model".into(), "absolute".into());
            extra.insert("noise_balance_lift_range_n".into(), b.lift_range.into());
            extra.insert(
                "noise_balance_moment_range_nm".into(),
                b.moment_range.into(),
            );
            extra.insert("noise_balance_fraction".into(), b.fraction.into());
            extra.insert(
                "noise_balance_lift_resolution_n".into(),
                b.lift_resolution.into(),
            );
            extra.insert(
                "noise_balance_moment_resolution_nm".into(),
                b.moment_resolution.into(),
            );
        }
        None => {
            extra.insert("noise_balance_model".into(), "relative_to_peak".into());
            extra.insert("noise_balance_fraction".into(), noise.balance.into());
        }
    }
    extra.insert("noise_heave_m".into(), noise.laser.into());
    extra.insert("noise_pitch_rad".into(), noise.pitch_sd(chord).into());
    extra
}

pub(super) fn check_ids<'a>(ids: impl Iterator<Item = &'a str>) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    let mut n = 0;
    for id in ids {
        n += 1;
        if !identify::dataset::is_valid_case_id(id) {
            return Err(Error::param(
                format!("case id `{id}`"),
                f64::NAN,
                "must match [A-Za-z0-9._-]+",
            ));
        }
        if !seen.insert(id.to_string()) {
            return Err(Error::param(
                format!("case id `{id}`"),
                f64::NAN,
                "repeated",
            ));
        }
    }
    if n == 0 {
        return Err(Error::param("cases", 0.0, "no case"));
    }
    Ok(())
}

/// Writes a data set (case files first, manifest last, atomically).
///
/// # Errors
/// [`Error::Identify`] naming the folder and the underlying file/field.
pub fn write(dir: &Path, manifest: &Manifest, records: &[Record]) -> Result<()> {
    identify::dataset::write_dataset(dir, manifest, records).map_err(|e| Error::Identify {
        context: format!("writing data set {}", dir.display()),
        source: e,
    })
}

#[cfg(test)]
mod tests {
    /// Degrees that went through radians are written as given.
    #[test]
    fn descriptors_come_back_as_written() {
        for d in [3.0, 6.0, 0.1, 24.0, 1.5, 7.3] {
            let back = f64::to_degrees(f64::to_radians(d));
            assert_eq!(super::tidy(back), d, "{d} → {back}");
        }
        assert_eq!(super::tidy(1.0 / 3.0), 0.333333333333);
    }
}
