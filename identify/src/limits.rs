//! The limits table: every count, size, duration and physical bound that a user can set in
//! any command-line flag, study key, sweep specification, data-set manifest, structure or
//! model file, or Python argument, with one value per quantity. Each is checked where the
//! input is parsed, before anything is allocated or written, and refused with a message that
//! names the flag, key, line or argument (exit code 2 from the binary). The bounds are far
//! outside any wind-tunnel section and the caps far above every shipped scenario, so that
//! only typos and absurd requests hit them. [`TABLE`] lists them all; docs/DATA_FORMAT.md
//! ("Limits") prints it (a test keeps the two equal) and `tests/limits.rs` walks every entry
//! point with each limit exceeded.

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
/// Largest damping ratio ζ of a structural mode \[-\]: critical damping (an overdamped mode
/// does not oscillate, so it can neither flutter nor be identified from a decay).
pub const MAX_DAMPING_RATIO: f64 = 1.0;
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

/// Largest number of wind speeds of a scan, sweep, speed list or free-response campaign
/// (the densest shipped flutter scan has 96).
pub const MAX_SPEEDS: usize = 10_000;
/// Largest number of generated data sets of a withheld-effect benchmark (`diagnose
/// --blind`, a sweep specification's `blind` kind; ≈ 4 s each on 2 cores).
pub const MAX_BLIND_SETS: usize = 10_000;
/// Largest number of cases a study may generate (configurations × amplitudes × speeds,
/// or Table IV repeats). `run` holds every case of its campaign (samples, per-case work,
/// results): 10,000 cases of 240 samples took 690 MiB with `group_by = "none"` and
/// 458 MiB with one group, 20,000 cases 750 MiB before failing; 8,000 holds the 1-GB bound
/// with a margin (docs/DECISIONS.md, round 29; 100,000 before).
pub const MAX_CASES: usize = 8_000;
/// Largest number of samples a command may generate and hold (all cases and records
/// together, still-air runs included): 25 M samples ≈ 1 GB of five f64 channels (the
/// paper campaign holds 448 × 10 s × 512 Hz = 2.3 M).
pub const MAX_SAMPLES: f64 = 2.5e7;
/// Largest record duration \[s\] (≈ 11.6 days).
pub const MAX_DURATION: f64 = 1e6;
/// Largest sampling rate \[Hz\].
pub const MAX_RATE: f64 = 1e6;
/// Largest length of an LCO run \[pitch periods\].
pub const MAX_PERIODS: f64 = 1e5;
/// Largest phase-portrait length \[pitch periods\] (400 points each).
pub const MAX_PHASE_PERIODS: f64 = 1000.0;
/// Largest number of bootstrap members of an identification ensemble (each member is one
/// identification, ≈ the nominal one's cost).
pub const MAX_ENSEMBLE: usize = 10_000;
/// Largest number of bootstrap members × cases of an identification ensemble: every
/// member's coefficients of every case are held until the result is written (≈ 0.4 kB per
/// member and case in `identify`, ≈ 2.4 kB in a study's `run`). `identify --ensemble 20`
/// on 40,000 cases took 1.08 GB (docs/DECISIONS.md, round 29).
pub const MAX_ENSEMBLE_FITS: usize = 50_000;
/// Largest number of points of a sweep specification's flutter map (μ × σ × x_α × r²,
/// multiplied with overflow checks).
pub const MAX_GRID_POINTS: usize = 100_000;
/// Largest number of harmonics of the harmonic balance: the full form's Jacobian has
/// (n(2H + 1) + 2)² entries (H = 100 and 6 states: 15 MB), far beyond what a limit cycle of
/// a smooth section needs (5 by default).
pub const MAX_HARMONICS: usize = 100;
/// Largest number of integration steps per period of a shooting continuation (128 by
/// default).
pub const MAX_STEPS_PER_PERIOD: usize = 100_000;
/// Largest number of continuation points of one LCO branch (200 by default).
pub const MAX_BRANCH_POINTS: usize = 100_000;
/// Largest number of speeds of the Hopf scan before a continuation (200 by default).
pub const MAX_SCAN_SPEEDS: usize = 100_000;
/// Largest number of Newton iterations of one continuation step (8 by default).
pub const MAX_NEWTON_ITERATIONS: usize = 1_000;
/// Largest number of δ values of a regularisation path (each one sparse fit per case; 50
/// by default).
pub const MAX_N_DELTA: usize = 100_000;

/// Largest text file read whole \[bytes\]: a manifest, study, model or structure file, a
/// sweep specification, a part or result document, a measured bifurcation table (64 MiB;
/// the largest shipped one is 30 kB). Beyond it a file is refused before it is read, so a
/// link to `/dev/zero` or a sparse file cannot exhaust memory (issue 39, row 5).
pub const MAX_TEXT_FILE_BYTES: f64 = 67_108_864.0;
/// Largest `identification.json` read back \[bytes\] (a study's report stage, `plot`,
/// `--model identification.json` of `flutter`/`lco`/`branch`/`tunnel`): aeroform's own
/// result document outgrows [`MAX_TEXT_FILE_BYTES`] in large campaigns (≈ 185 MB for the
/// 8,000-case study cap with `group_by = "none"`, 130–200 MB for 40,000 data-set cases), so
/// a study would fail after its identification, reading back what it wrote (round 29). 256
/// MiB; a larger file is refused before it is read.
pub const MAX_RESULT_FILE_BYTES: f64 = 268_435_456.0;
/// Largest line of a case CSV \[bytes\] (a row of five numbers is under 120 bytes): a
/// file without line breaks is refused at this length, not held whole.
pub const MAX_CSV_LINE_BYTES: usize = 1 << 20;
/// Largest number of `[[case]]` entries of a data set: `identify` keeps ≈ 19 kB per case
/// (50,000 distinct files measured at 0.91–0.95 GB peak, docs/DECISIONS.md round 28), so
/// 40,000 holds the 1-GB bound for any data set with a margin (≈ 0.78 GB).
pub const MAX_DATASET_CASES: usize = 40_000;
/// Largest number of rows (points) of a measured bifurcation table.
pub const MAX_MEASURED_POINTS: usize = 100_000;

/// Largest label \[characters\]: a manifest's `name`, a case's `id` and `config`. Labels
/// are drawn in figures and reports; a 20,000-character `config` made `diagnose` take
/// minutes (issue 39, row 5).
pub const MAX_LABEL_CHARS: usize = 256;

/// One row of the limits table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// The constant's name in this module (`MAX_SPEED`).
    pub name: &'static str,
    /// The bound: largest allowed value (of |x| for signed quantities).
    pub max: f64,
    /// Unit of `max` (`m/s`, `deg`, `-` for counts and coefficients).
    pub unit: &'static str,
    /// Where a user sets it: flags, study keys, sweep fields, file fields, Python arguments.
    pub set_by: &'static str,
}

/// Every limit, in the order docs/DATA_FORMAT.md prints them.
pub const TABLE: &[Limit] = &[
    Limit { name: "MAX_SPEED", max: MAX_SPEED, unit: "m/s", set_by: "`--speeds`, `--speed`, `--sweep`; manifest `wind_speed`; study speed lists; sweep `lco_speeds`, `speeds`; Python `speeds`, `speed`, `sweep`, `u_min`, `u_max`" },
    Limit { name: "MAX_CHORD", max: MAX_CHORD, unit: "m", set_by: "`--chord`; manifest and structure `chord`; Python `chord`" },
    Limit { name: "MAX_SPAN", max: MAX_SPAN, unit: "m", set_by: "manifest `span`" },
    Limit { name: "MAX_AIR_DENSITY", max: MAX_AIR_DENSITY, unit: "kg/m³", set_by: "manifest and structure `air_density`" },
    Limit { name: "MAX_ELASTIC_AXIS", max: MAX_ELASTIC_AXIS, unit: "semi-chords", set_by: "model `elastic_axis`" },
    Limit { name: "MAX_DAMPING_RATIO", max: MAX_DAMPING_RATIO, unit: "-", set_by: "structure `damping_heave`, `damping_pitch`; Python structure dict" },
    Limit { name: "MAX_PITCH_DEG", max: MAX_PITCH_DEG, unit: "deg", set_by: "`--alpha0`, `--alpha0-down`; study `[lco] perturbation_deg`; sweep `alpha0`; Python `alpha0`, `alpha0_down`; manifest `amplitude`, `mean_pitch`" },
    Limit { name: "MAX_NONLINEAR_COEFFICIENT", max: MAX_NONLINEAR_COEFFICIENT, unit: "-", set_by: "model `[[nonlinear]] coefficient`; study `[aero]` terms" },
    Limit { name: "MAX_FORCE_COEFFICIENT", max: MAX_FORCE_COEFFICIENT, unit: "-", set_by: "reached through a model (`tunnel forced`)" },
    Limit { name: "MAX_SPEEDS", max: MAX_SPEEDS as f64, unit: "-", set_by: "`--speeds`, `--sweep` (n of a:b:n or list length); study `n_speeds`, `speeds`; sweep speed lists; Python `speeds`, `sweep`" },
    Limit { name: "MAX_BLIND_SETS", max: MAX_BLIND_SETS as f64, unit: "-", set_by: "`diagnose --blind`; sweep `blind` `n`" },
    Limit { name: "MAX_CASES", max: MAX_CASES as f64, unit: "-", set_by: "study campaign (configurations × amplitudes × speeds; Table IV `repeats`)" },
    Limit { name: "MAX_SAMPLES", max: MAX_SAMPLES, unit: "-", set_by: "`tunnel --duration` × rate × records; study `duration` × `rate` × cases" },
    Limit { name: "MAX_DURATION", max: MAX_DURATION, unit: "s", set_by: "`tunnel --duration`; study `duration`" },
    Limit { name: "MAX_RATE", max: MAX_RATE, unit: "Hz", set_by: "study `rate`" },
    Limit { name: "MAX_PERIODS", max: MAX_PERIODS, unit: "pitch periods", set_by: "study `[lco] max_periods`" },
    Limit { name: "MAX_PHASE_PERIODS", max: MAX_PHASE_PERIODS, unit: "pitch periods", set_by: "study `[lco] phase_periods`" },
    Limit { name: "MAX_ENSEMBLE", max: MAX_ENSEMBLE as f64, unit: "-", set_by: "`identify --ensemble`; study `[identify] ensemble`; Python `ensemble`" },
    Limit { name: "MAX_ENSEMBLE_FITS", max: MAX_ENSEMBLE_FITS as f64, unit: "-", set_by: "`identify --ensemble` × the manifest's `[[case]]` entries; study `[identify] ensemble` × campaign cases; Python `identify(ensemble=)` × cases" },
    Limit { name: "MAX_GRID_POINTS", max: MAX_GRID_POINTS as f64, unit: "-", set_by: "sweep `flutter_map` grid" },
    Limit { name: "MAX_HARMONICS", max: MAX_HARMONICS as f64, unit: "-", set_by: "`branch --harmonics`; study `[branch] harmonics`; Python `harmonics`" },
    Limit { name: "MAX_STEPS_PER_PERIOD", max: MAX_STEPS_PER_PERIOD as f64, unit: "-", set_by: "`branch --steps-per-period`; study `[branch] steps_per_period`; Python `steps_per_period`" },
    Limit { name: "MAX_BRANCH_POINTS", max: MAX_BRANCH_POINTS as f64, unit: "-", set_by: "`branch --max-points`; study `[branch] max_points`; Python `max_points`" },
    Limit { name: "MAX_SCAN_SPEEDS", max: MAX_SCAN_SPEEDS as f64, unit: "-", set_by: "Rust API `BranchOptions::n_scan`" },
    Limit { name: "MAX_NEWTON_ITERATIONS", max: MAX_NEWTON_ITERATIONS as f64, unit: "-", set_by: "Rust API `BranchOptions::max_newton`" },
    Limit { name: "MAX_N_DELTA", max: MAX_N_DELTA as f64, unit: "-", set_by: "`identify --n-delta`; study `[identify] n_delta`; Python `n_delta`" },
    Limit { name: "MAX_TEXT_FILE_BYTES", max: MAX_TEXT_FILE_BYTES, unit: "bytes", set_by: "the size of a manifest, study, model, structure, sweep, part or result document, measured table" },
    Limit { name: "MAX_RESULT_FILE_BYTES", max: MAX_RESULT_FILE_BYTES, unit: "bytes", set_by: "the size of an identification.json read back (study report, `plot`, `--model`)" },
    Limit { name: "MAX_CSV_LINE_BYTES", max: MAX_CSV_LINE_BYTES as f64, unit: "bytes", set_by: "a line of a case CSV" },
    Limit { name: "MAX_DATASET_CASES", max: MAX_DATASET_CASES as f64, unit: "-", set_by: "manifest `[[case]]` entries" },
    Limit { name: "MAX_LABEL_CHARS", max: MAX_LABEL_CHARS as f64, unit: "characters", set_by: "manifest `name`, case `id` and `config`" },
    Limit { name: "MAX_MEASURED_POINTS", max: MAX_MEASURED_POINTS as f64, unit: "-", set_by: "rows of a measured bifurcation table (`--measured`, `--measured-branch`)" },
];

/// The row of [`TABLE`] named `name` (`MAX_SPEED`).
pub fn find(name: &str) -> Option<&'static Limit> {
    TABLE.iter().find(|l| l.name == name)
}

/// `1 ≤ n ≤ max` for a count given as any unsigned integer (so that a request of 1e20
/// cannot wrap): `n`, or what is wrong.
///
/// # Errors
/// The message, for the caller to name its field.
pub fn count_at_most(n: u128, max: usize) -> Result<usize, String> {
    if n >= 1 && n <= max as u128 {
        Ok(n as usize)
    } else {
        Err(format!("{n} must be in 1..={max}"))
    }
}

/// Members × cases of an identification ensemble within [`MAX_ENSEMBLE_FITS`] (every
/// member's coefficients of every case are held until the result is written): the one check
/// of `identify --ensemble`, a study's `[identify] ensemble` and Python's `ensemble`.
///
/// # Errors
/// The message (members, cases, their product and the cap), for the caller to name its
/// field.
pub fn ensemble_fits(members: usize, cases: u128) -> Result<(), String> {
    let n = members as u128 * cases;
    if n > MAX_ENSEMBLE_FITS as u128 {
        return Err(format!(
            "{members} members × {cases} cases = {n} member fits exceed the cap of \
             {MAX_ENSEMBLE_FITS} (the limits table's MAX_ENSEMBLE_FITS: every member's \
             coefficients of every case are held until the result is written)"
        ));
    }
    Ok(())
}

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

    /// docs/DATA_FORMAT.md prints the table: one row per entry, value and unit as here.
    #[test]
    fn the_data_format_prints_every_limit() {
        let doc = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../docs/DATA_FORMAT.md"
        ))
        .unwrap();
        let section = doc
            .split("\n## Limits")
            .nth(1)
            .expect("a `## Limits` section");
        let section = section.split("\n## ").next().unwrap();
        let rows: Vec<&str> = section
            .lines()
            .filter(|l| l.starts_with("| `MAX_"))
            .collect();
        assert_eq!(
            rows.len(),
            TABLE.len(),
            "one row per limit:\n{}",
            rows.join("\n")
        );
        for (l, row) in TABLE.iter().zip(&rows) {
            let want = format!("| `{}` | {} | {} |", l.name, show(l.max), l.unit);
            assert!(
                row.starts_with(&want),
                "row `{row}`, expected it to start `{want}`"
            );
        }
    }

    #[test]
    fn counts_refuse_zero_and_beyond_the_cap() {
        assert_eq!(count_at_most(3, 3), Ok(3));
        assert!(count_at_most(0, 3).is_err());
        assert!(count_at_most(4, 3).is_err());
        assert!(count_at_most(u128::MAX, MAX_SPEEDS).is_err());
        assert_eq!(find("MAX_HARMONICS").unwrap().max, 100.0);
    }

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
