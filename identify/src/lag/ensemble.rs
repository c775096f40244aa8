//! Intervals of a lag-law fit by a residual block bootstrap (issue 41 item 2: "intervals by
//! the existing ensemble").
//!
//! The memoryless ensemble ([`crate::ensemble`]) resamples a case's rows in blocks of one
//! forcing period; the lag law cannot drop rows (its state runs through the record in order),
//! so the blocks are resampled in the *residual*: member m refits the law on
//! y* = ŷ + r*, ŷ the fitted law's prediction of each case and r* the case's residual
//! y − ŷ rebuilt from blocks of one forcing period (half the record without one) drawn with
//! replacement, both channels with the same blocks (their errors are correlated). Each member
//! is a full output-error fit ([`super::fit::fit_series`], the options of the fit); a member
//! the fit refuses (a constant on an open bound) is counted, not used. The intervals are
//! the percentile intervals of the members' constants ([`Interval::from_samples`]).
//!
//! Draws: member m of case c is seeded with SplitMix64 of (seed, c, m), as the memoryless
//! ensemble does, so a member does not depend on the number of members or on the thread
//! that ran it.

use super::fit::{fit_series, predict_series, LagFit, LagFitOptions, PARAMETERS};
pub use super::report::{LagEnsemble, LagParameterInterval};
use super::series::LagSeries;
use crate::ensemble::{EnsembleSettings, Interval};
use crate::Result;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Residual block-bootstrap ensemble of `fit` on `series` (module docs), `settings`'
/// members, seed and level (its block length is one forcing period here).
///
/// # Errors
/// [`crate::Error::InvalidOption`] for bad settings; the prediction errors of
/// [`predict_series`] for a case the fitted law cannot predict; [`crate::Error::Numerical`]
/// when every member is refused.
pub fn bootstrap(
    series: &[LagSeries],
    fit: &LagFit,
    opts: &LagFitOptions,
    settings: &EnsembleSettings,
) -> Result<LagEnsemble> {
    settings.validate()?;
    let predictions = series
        .iter()
        .map(|s| predict_series(&fit.law, s))
        .collect::<Result<Vec<_>>>()?;
    let members: Vec<Option<[f64; 4]>> = (0..settings.members)
        .into_par_iter()
        .map(|m| {
            let resampled: Vec<LagSeries> = series
                .iter()
                .zip(&predictions)
                .enumerate()
                .map(|(c, (s, p))| member_series(s, &p.c_lift, &p.c_moment, settings.seed, c, m))
                .collect();
            fit_series(&resampled, opts)
                .ok()
                .map(|f| [f.law.tau1, f.law.tau2, f.law.alpha_star, f.law.sharpness])
        })
        .collect();
    let ok: Vec<[f64; 4]> = members.iter().flatten().copied().collect();
    if ok.is_empty() {
        return Err(crate::Error::Numerical {
            context: "lag-law ensemble".into(),
            message: format!("all {} members were refused", settings.members),
        });
    }
    let parameters = PARAMETERS
        .iter()
        .enumerate()
        .filter_map(|(i, (name, _, unit))| {
            let v: Vec<f64> = ok.iter().map(|t| t[i]).collect();
            Interval::from_samples(&v, settings.level).map(|interval| LagParameterInterval {
                name: name.to_string(),
                unit: unit.to_string(),
                interval,
            })
        })
        .collect();
    Ok(LagEnsemble {
        members: settings.members,
        seed: settings.seed.to_string(),
        level: settings.level,
        refused: settings.members - ok.len(),
        parameters,
    })
}

/// Case `s` of member `member` (module docs): the predictions `cl`, `cm` plus the case's
/// residuals rebuilt from blocks drawn with replacement (case `case` of the draw).
fn member_series(
    s: &LagSeries,
    cl: &[f64],
    cm: &[f64],
    seed: u64,
    case: usize,
    member: usize,
) -> LagSeries {
    let n = s.len();
    let block = s
        .period_samples
        .map_or(n / 2, |p| p.round() as usize)
        .clamp(1, n.max(1));
    let z = crate::numerics::split_seed(
        crate::numerics::split_seed(crate::numerics::split_seed(seed, 0) ^ case as u64, 0)
            ^ member as u64,
        0,
    );
    let mut rng = ChaCha8Rng::seed_from_u64(z);
    let mut out = s.clone();
    let mut i = 0;
    while i < n {
        // a block starting anywhere in the record, wrapped around its end
        let start = rng.random_range(0..n);
        for k in 0..block.min(n - i) {
            let j = (start + k) % n;
            out.c_lift[i + k] = cl[i + k] + (s.c_lift[j] - cl[j]);
            out.c_moment[i + k] = cm[i + k] + (s.c_moment[j] - cm[j]);
        }
        i += block;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lag::fit::tests::{case_of, truth};

    /// Noise-free records of the law itself: every member is the fit (zero residual), so the
    /// intervals shrink onto the fitted constants; with noise the interval covers the truth
    /// and is reproducible from its seed.
    #[test]
    fn intervals_cover_the_truth_and_repeat_from_the_seed() {
        let law = truth();
        let mut cases: Vec<_> = [(0.05, "a"), (0.1, "b"), (0.2, "c")]
            .iter()
            .map(|&(k, id)| case_of(&law, id, k, 15f64.to_radians(), 8f64.to_radians()))
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for c in &mut cases {
            let sd = 0.02 * c.c_lift.iter().map(|v| v.abs()).fold(0.0, f64::max);
            for v in c.c_lift.iter_mut().chain(c.c_moment.iter_mut()) {
                *v += sd * (rng.random::<f64>() - 0.5) * 3.46;
            }
        }
        let series: Vec<LagSeries> = cases.iter().map(|c| LagSeries::new(c).unwrap()).collect();
        let opts = LagFitOptions::default();
        let fit = fit_series(&series, &opts).unwrap();
        let settings = EnsembleSettings::new(12, 2026);
        let e = bootstrap(&series, &fit, &opts, &settings).unwrap();
        assert_eq!(e.members, 12);
        assert!(e.refused < 6, "{e:?}");
        let tau1 = &e.parameters[0];
        assert_eq!(tau1.name, "tau1");
        assert!(tau1.interval.lower < tau1.interval.upper, "{e:?}");
        let a = &e.parameters[2].interval;
        let widen = 0.5 * (a.upper - a.lower);
        assert!(
            a.lower - widen <= law.alpha_star && law.alpha_star <= a.upper + widen,
            "α* {} outside {a:?}",
            law.alpha_star
        );
        assert_eq!(bootstrap(&series, &fit, &opts, &settings).unwrap(), e);
    }
}
