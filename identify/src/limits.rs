//! Physical plausibility bounds shared by every reader and command of the workspace (the
//! data-set manifest, structure and model files, command-line flags, study keys, sweep
//! specifications): one value per quantity, far outside any wind-tunnel section, so that
//! only typos and absurd inputs hit them (docs/DATA_FORMAT.md, "Limits"). The counts and
//! sizes a command may ask for are in `study::limits` and `diagnose::sweep`.

/// Largest wind speed \[m/s\] (or reduced speed in a nondimensional study).
pub const MAX_SPEED: f64 = 1000.0;
/// Largest chord \[m\].
pub const MAX_CHORD: f64 = 100.0;
/// Largest span \[m\].
pub const MAX_SPAN: f64 = 1000.0;
/// Largest air density \[kg/m³\].
pub const MAX_AIR_DENSITY: f64 = 2000.0;
/// Largest |elastic axis position| a \[semi-chords from mid-chord\].
pub const MAX_ELASTIC_AXIS: f64 = 10.0;
/// Largest |pitch angle| of an initial condition, offset or amplitude \[deg\].
pub const MAX_PITCH_DEG: f64 = 90.0;
/// Largest |constant nondimensional coefficient| of a model file's `[[nonlinear]]` term
/// (and |K^p N*| of an Eq. 19 table entry) \[-\]. Identified coefficients of high powers
/// of Bα̇/U (≈ 0.01–0.1 in a wind tunnel) reach 1e5; 1e9 leaves four decades above that
/// and refuses typos such as 1e300, whose forces overflow (issue 27, row 15).
pub const MAX_NONLINEAR_COEFFICIENT: f64 = 1e9;
/// Largest |C_L| or |C_M| (C_L = L/(½ρU²B), C_M = M/(½ρU²B²)) of a force the virtual wind
/// tunnel records \[-\]. A flat plate's circulatory lift stays below 2π·(π/2) ≈ 10 and its
/// noncirculatory terms below some tens at the campaigns' reduced frequencies; 1e4 is
/// three decades above any physical section, so only a model whose forces blow up along
/// the prescribed motion reaches it (issue 27, row 15).
pub const MAX_FORCE_COEFFICIENT: f64 = 1e4;

/// A number for a message: exponent form outside [1e-4, 1e16) so that 1e300 stays short.
pub fn show(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e16).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// `0 < x ≤ max`, finite: `x`, or what is wrong (value and bound, in `unit`).
///
/// # Errors
/// The message, for the caller to name its field (flag, key or file line).
pub fn positive_at_most(x: f64, max: f64, unit: &str) -> Result<f64, String> {
    if x.is_finite() && x > 0.0 && x <= max {
        Ok(x)
    } else {
        Err(format!(
            "{} {unit} must be finite, > 0 and ≤ {} {unit}",
            show(x),
            show(max)
        ))
    }
}

/// `|x| ≤ max`, finite: `x`, or what is wrong (value and bound, in `unit`).
///
/// # Errors
/// The message, for the caller to name its field (flag, key or file line).
pub fn abs_at_most(x: f64, max: f64, unit: &str) -> Result<f64, String> {
    if x.is_finite() && x.abs() <= max {
        Ok(x)
    } else {
        Err(format!(
            "{} {unit} must be finite with |value| ≤ {} {unit}",
            show(x),
            show(max)
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_accept_the_limit_and_refuse_beyond_it() {
        assert_eq!(positive_at_most(MAX_CHORD, MAX_CHORD, "m"), Ok(MAX_CHORD));
        assert!(positive_at_most(MAX_CHORD * 1.000001, MAX_CHORD, "m").is_err());
        assert!(positive_at_most(0.0, MAX_CHORD, "m").is_err());
        assert!(abs_at_most(-MAX_ELASTIC_AXIS, MAX_ELASTIC_AXIS, "").is_ok());
        assert!(abs_at_most(f64::NAN, MAX_ELASTIC_AXIS, "").is_err());
        assert_eq!(
            positive_at_most(1e300, MAX_CHORD, "m").unwrap_err(),
            "1e300 m must be finite, > 0 and ≤ 100 m"
        );
    }
}
