//! The gap statistics every level and the verdict share: the excess of a gap over the
//! noise, the plain and excess shrink of a candidate, and the paired one-standard-error
//! test of the simplest-sufficient rule.

/// Excess of a gap over the noise level: sqrt(max(gap² − noise², 0)).
pub fn excess(gap: f64, noise: f64) -> f64 {
    (gap * gap - noise * noise).max(0.0).sqrt()
}

/// 1 − after/before, 0 when before is not positive.
pub fn plain_shrink(before: f64, after: f64) -> f64 {
    if before > 0.0 && before.is_finite() && after.is_finite() {
        1.0 - after / before
    } else {
        0.0
    }
}

/// 1 − excess(after)/excess(before), 0 when there is no excess before.
pub fn excess_shrink(before: f64, after: f64, noise: f64) -> f64 {
    let eb = excess(before, noise);
    if eb > 0.0 && after.is_finite() {
        1.0 - excess(after, noise) / eb
    } else {
        0.0
    }
}

/// Paired one-standard-error test: whether the mean of the per-unit differences `d`
/// (simpler minus richer held-out energy) is at most their standard error, or at most
/// `allowance` (a parsimony allowance). An empty `d` passes.
pub(crate) fn paired_within_one_se(d: &[f64], allowance: f64) -> bool {
    if d.is_empty() {
        return true;
    }
    let m = d.len() as f64;
    let mean = d.iter().sum::<f64>() / m;
    let sd = if d.len() > 1 {
        (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt()
    } else {
        0.0
    };
    mean <= (sd / m.sqrt()).max(allowance)
}
