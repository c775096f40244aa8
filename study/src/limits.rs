//! The checks of the limits table (`identify::limits::TABLE`, the one place the values
//! live) for command-line flags and study keys. Each runs before anything is allocated or
//! written and fails with a [`LimitError`] naming the flag or the dotted study key; the
//! binary exits with code 2 on it.

pub use identify::limits::{
    MAX_BLIND_SETS, MAX_CASES, MAX_DURATION, MAX_ENSEMBLE, MAX_ENSEMBLE_FITS, MAX_PERIODS,
    MAX_PHASE_PERIODS, MAX_PITCH_DEG, MAX_RATE, MAX_SAMPLES, MAX_SPEED, MAX_SPEEDS,
};

/// A request beyond a cap or a physically implausible number: the flag or dotted key, and
/// what is wrong with the numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct LimitError {
    /// Flag (`--speeds`) or dotted study key (`data.synthetic.duration`).
    pub field: String,
    /// What is wrong, with the value and the bound.
    pub message: String,
}

impl std::fmt::Display for LimitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "`{}`: {}", self.field, self.message)
    }
}

impl std::error::Error for LimitError {}

use identify::limits::show;

fn err<T>(field: &str, message: String) -> Result<T, LimitError> {
    Err(LimitError {
        field: field.to_string(),
        message,
    })
}

/// `0 < x ≤ max`, finite.
///
/// # Errors
/// [`LimitError`] naming `field` with the value and the bound.
pub fn positive_at_most(field: &str, x: f64, max: f64, unit: &str) -> Result<f64, LimitError> {
    identify::limits::positive_at_most(x, max, unit).or_else(|m| err(field, m))
}

/// `|x| ≤ max`, finite.
///
/// # Errors
/// [`LimitError`] naming `field` with the value and the bound.
pub fn abs_at_most(field: &str, x: f64, max: f64, unit: &str) -> Result<f64, LimitError> {
    identify::limits::abs_at_most(x, max, unit).or_else(|m| err(field, m))
}

/// `1 ≤ n ≤ max` for a count.
///
/// # Errors
/// [`LimitError`] naming `field` with the count and the bound.
pub fn count(field: &str, n: u128, max: usize) -> Result<usize, LimitError> {
    identify::limits::count_at_most(n, max).or_else(|m| err(field, m))
}

/// Members × cases of an identification ensemble ([`MAX_ENSEMBLE_FITS`]):
/// `identify::limits::ensemble_fits` naming `field`.
///
/// # Errors
/// [`LimitError`] naming `field` with the members, the cases, their product and the cap.
pub fn ensemble_fits(field: &str, members: usize, cases: u128) -> Result<(), LimitError> {
    identify::limits::ensemble_fits(members, cases).or_else(|m| err(field, m))
}

/// Samples of a generated campaign, `records × duration × rate` (still-air runs count as
/// records), checked against [`MAX_SAMPLES`] after `duration` against [`MAX_DURATION`]
/// and `rate` against [`MAX_RATE`]. Computed in floating point, so no count can overflow.
///
/// # Errors
/// [`LimitError`] naming `duration_field` or `rate_field` for a bad value, or
/// `duration_field` with the estimate (samples and memory) when it exceeds the cap.
pub fn samples(
    duration_field: &str,
    rate_field: &str,
    records: usize,
    duration: f64,
    rate: f64,
) -> Result<f64, LimitError> {
    positive_at_most(duration_field, duration, MAX_DURATION, "s")?;
    positive_at_most(rate_field, rate, MAX_RATE, "Hz")?;
    let n = records as f64 * (duration * rate).ceil();
    if n > MAX_SAMPLES {
        return err(
            duration_field,
            format!(
                "{records} record(s) × {} s × {} Hz = {} samples \
                 (≈ {:.1} GB) exceed the cap of {} samples (MAX_SAMPLES); shorten the \
                 records or use fewer cases",
                show(duration),
                show(rate),
                show(n),
                n * 5.0 * 8.0 / 1e9,
                show(MAX_SAMPLES)
            ),
        );
    }
    Ok(n)
}

/// Parses a speed list `a:b:n` (n ≥ 1 speeds from a to b, n ≤ [`MAX_SPEEDS`], checked
/// before anything is allocated) or a comma list `3,4,5.5`; every speed finite, > 0 and
/// ≤ [`MAX_SPEED`]. `field` names the flag in errors (`--speeds`, `--sweep`).
///
/// # Errors
/// [`LimitError`] naming `field`: syntax, count or a speed out of range.
pub fn parse_speeds(field: &str, s: &str) -> Result<Vec<f64>, LimitError> {
    let bad = || LimitError {
        field: field.to_string(),
        message: format!("`{s}`: expected `a:b:n` or a comma list like `3,4,5`"),
    };
    let v: Vec<f64> = if let Some((a, rest)) = s.split_once(':') {
        let (b, n) = rest.split_once(':').ok_or_else(bad)?;
        let a: f64 = a.trim().parse().map_err(|_| bad())?;
        let b: f64 = b.trim().parse().map_err(|_| bad())?;
        let n: u128 = n.trim().parse().map_err(|_| bad())?;
        let n = count(&format!("{field} (count n of a:b:n)"), n, MAX_SPEEDS)?;
        positive_at_most(field, a, MAX_SPEED, "m/s")?;
        positive_at_most(field, b, MAX_SPEED, "m/s")?;
        match n {
            1 => vec![a],
            _ => (0..n)
                .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
                .collect(),
        }
    } else {
        if s.split(',').count() > MAX_SPEEDS {
            return err(field, format!("more than {MAX_SPEEDS} speeds"));
        }
        s.split(',')
            .map(|x| x.trim().parse::<f64>().map_err(|_| bad()))
            .collect::<Result<_, _>>()?
    };
    for u in &v {
        positive_at_most(field, *u, MAX_SPEED, "m/s")?;
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_lists_are_bounded_before_allocation() {
        assert_eq!(
            parse_speeds("--speeds", "1:3:3").unwrap(),
            vec![1.0, 2.0, 3.0]
        );
        assert_eq!(parse_speeds("--speeds", "2, 4").unwrap(), vec![2.0, 4.0]);
        for s in [
            "1:20:18446744073709551615",
            "1:20:1000000000",
            "1:20:0",
            "1:1e308:5",
            "0:5:5",
            "nan,2",
            "1e9",
            "1:2",
        ] {
            let e = parse_speeds("--speeds", s).unwrap_err();
            assert!(e.field.starts_with("--speeds"), "{s}: {e}");
        }
    }

    #[test]
    fn sample_estimates_are_capped() {
        assert!(samples("d", "r", 448, 10.0, 512.0).is_ok());
        let e = samples("d", "r", 448, 1e300, 512.0).unwrap_err();
        assert_eq!(e.field, "d");
        let e = samples("d", "r", 1, 10.0, 1e12).unwrap_err();
        assert_eq!(e.field, "r");
        let e = samples("d", "r", 448, 1e5, 512.0).unwrap_err();
        assert!(e.message.contains("exceed the cap"), "{e}");
        assert!(samples("d", "r", 1, f64::NAN, 512.0).is_err());
    }
}
