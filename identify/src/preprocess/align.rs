//! Wind–no-wind alignment and subtraction.
//!
//! The still-air run holds the model's inertial forces for the same prescribed motion,
//! recorded with an unknown time offset. The two runs are aligned on their motion signals:
//! a normalised cross-correlation (FFT, energies over the overlap) gives the integer lag, a
//! parabola through the three values around its peak gives a sub-sample estimate, and a
//! golden-section search maximises a symmetric correlation of the two motions, each
//! interpolated (4-point cubic Lagrange) by half the fractional shift. A correlation (not
//! the squared difference) is maximised because interpolation smooths noise by an amount
//! that depends on the fractional shift, which pulls a squared-difference criterion
//! towards half samples; independent noise has no cross term in a correlation. The
//! symmetric half shifts remove the window-edge bias of a one-sided shift.

use std::ops::Range;

use super::harmonic::noise_sigma;
use crate::numerics::interp::uniform_cubic as interpolate_cubic;
use crate::record::Record;
use crate::{Error, Result};

/// Signal centred on its mean and scaled to unit standard deviation (None if constant).
fn normalised(x: &[f64]) -> Option<Vec<f64>> {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let sd = (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n).sqrt();
    (sd > 0.0 && sd.is_finite()).then(|| x.iter().map(|v| (v - m) / sd).collect())
}

/// Integer-plus-parabola lag (in samples of `b` against `a`) maximising the summed
/// cross-correlation `c(k) = Σᵢ a(i) b(i+k)` of the normalised pairs.
fn coarse_lag(pairs: &[(Vec<f64>, Vec<f64>)]) -> Option<f64> {
    let na = pairs[0].0.len();
    let nb = pairs[0].1.len();
    let len = (na + nb).next_power_of_two();
    let (fwd, inv) = fft::forward_and_inverse(len);
    let mut acc = fwd.make_output_vec();
    let mut buf = vec![0.0; len];
    let mut sa = fwd.make_output_vec();
    let mut sb = fwd.make_output_vec();
    for (a, b) in pairs {
        buf.iter_mut().for_each(|v| *v = 0.0);
        buf[..na].copy_from_slice(a);
        fwd.process(&mut buf, &mut sa).ok()?;
        buf.iter_mut().for_each(|v| *v = 0.0);
        buf[..nb].copy_from_slice(b);
        fwd.process(&mut buf, &mut sb).ok()?;
        for ((c, x), y) in acc.iter_mut().zip(&sa).zip(&sb) {
            *c += x.conj() * y;
        }
    }
    // The inverse of a real signal's spectrum needs real DC and Nyquist bins.
    acc[0].im = 0.0;
    if let Some(last) = acc.last_mut() {
        last.im = 0.0;
    }
    let mut c = vec![0.0; len];
    inv.process(&mut acc, &mut c).ok()?;
    // c[k] for lag k ≥ 0 (k < nb); c[len − k] for lag −k (k < na).
    let at = |k: i64| -> f64 {
        if k >= 0 {
            c[k as usize]
        } else {
            c[(len as i64 + k) as usize]
        }
    };
    // Normalised cross-correlation: c(k) / √(E_a(k) E_b(k)) with the energies over the
    // overlap, from prefix sums; lags with less than half the shorter record are skipped.
    let prefix = |second: bool, n: usize| -> Vec<f64> {
        let mut p = vec![0.0; n + 1];
        for pair in pairs {
            let x = if second { &pair.1 } else { &pair.0 };
            let mut acc = 0.0;
            for i in 0..n {
                acc += x[i] * x[i];
                p[i + 1] += acc;
            }
        }
        p
    };
    let pa = prefix(false, na);
    let pb = prefix(true, nb);
    let min_overlap = (na.min(nb) / 2).max(4) as i64;
    let ncc = |k: i64| -> Option<(f64, i64)> {
        let i0 = (-k).max(0);
        let i1 = (na as i64).min(nb as i64 - k);
        if i1 - i0 < min_overlap {
            return None;
        }
        let ea = pa[i1 as usize] - pa[i0 as usize];
        let eb = pb[(i1 + k) as usize] - pb[(i0 + k) as usize];
        let den = (ea * eb).sqrt();
        (den > 0.0).then(|| (at(k) / den, i1 - i0))
    };
    let lo = -(na as i64 - 1);
    let hi = nb as i64 - 1;
    let mut best = (0i64, f64::NEG_INFINITY, 0i64);
    for k in lo..=hi {
        if let Some((v, ov)) = ncc(k) {
            if v > best.1 {
                best = (k, v, ov);
            }
        }
    }
    if best.1 == f64::NEG_INFINITY {
        return None;
    }
    // Periodic motion matches equally well at several lags: take the largest overlap
    // among the (numerically) equal best matches.
    let top = best.1;
    for k in lo..=hi {
        if let Some((v, ov)) = ncc(k) {
            if v >= top - 1e-6 && ov > best.2 {
                best = (k, v, ov);
            }
        }
    }
    let k = best.0;
    let mut off = 0.0;
    if let (Some((y0, _)), Some((y2, _))) = (ncc(k - 1), ncc(k + 1)) {
        let y1 = best.1;
        let den = y0 - 2.0 * y1 + y2;
        if den < 0.0 {
            off = (0.5 * (y0 - y2) / den).clamp(-0.5, 0.5);
        }
    }
    Some(k as f64 + off)
}

/// Sub-sample refinement: maximise the symmetric covariance
/// `J(D) = Σ_pairs covᵢ(ã(tᵢ − δ/2), b̃(tᵢ + d0 + δ/2))`, `δ = D − d0`, within ±1 sample,
/// on a fixed set of `i` kept inside both records for the whole search (ã, b̃: 4-point
/// cubic interpolants). Shifting both signals by half the step makes `dJ/dD = 0` exactly at
/// the true lag for any window (a one-sided shift leaves a bias `Σ a a′ ≠ 0` from the window
/// edges), independent noise has no cross term, and the covariance (not the raw product)
/// is blind to an offset between the runs, so none of these biases the lag.
fn refine_lag(pairs: &[(Vec<f64>, Vec<f64>)], dt_a: f64, dt_b: f64, d0: f64) -> f64 {
    let na = pairs[0].0.len();
    let nb = pairs[0].1.len();
    let margin = 2.0 * dt_b.max(dt_a);
    let r = overlap_range(na, dt_a, nb, dt_b, d0, margin);
    let range = r.start.max(2)..r.end.min(na.saturating_sub(2));
    if range.len() < 4 {
        return d0;
    }
    let m = range.len() as f64;
    let obj = |delta: f64| -> f64 {
        let mut s = 0.0;
        for (a, b) in pairs {
            let (mut sab, mut sa, mut sb) = (0.0, 0.0, 0.0);
            for i in range.clone() {
                let t = i as f64 * dt_a;
                let x = interpolate_cubic(a, (t - 0.5 * delta) / dt_a);
                let y = interpolate_cubic(b, (t + d0 + 0.5 * delta) / dt_b);
                sab += x * y;
                sa += x;
                sb += y;
            }
            s += sab - sa * sb / m;
        }
        s
    };
    d0 + crate::numerics::golden_section_max(-dt_b, dt_b, 1e-7 * dt_b, obj)
}

/// Indices `i` of the wind-on record (`n_a` samples every `dt_a` s) whose time
/// `i·dt_a + lag` falls inside the still-air record (`n_b` samples every `dt_b` s), at least
/// `margin` seconds from either end.
fn overlap_range(
    n_a: usize,
    dt_a: f64,
    n_b: usize,
    dt_b: f64,
    lag: f64,
    margin: f64,
) -> Range<usize> {
    let eps = 1e-9 * dt_a;
    let first = ((margin - lag - eps) / dt_a).ceil().max(0.0);
    let last = (((n_b - 1) as f64 * dt_b - margin - lag + eps) / dt_a).floor();
    if last.is_nan() || last < first {
        return 0..0;
    }
    let first = first as usize;
    let end = ((last as usize) + 1).min(n_a);
    first.min(end)..end
}

/// Samples of the wind-on record (`wind_len` samples every `wind_dt` s) that overlap the
/// still-air record after shifting it by `lag` \[s\] (as returned by [`subtract_nowind`]):
/// the indices whose forces [`subtract_nowind`] returns.
pub fn nowind_overlap(
    wind_len: usize,
    wind_dt: f64,
    still_len: usize,
    still_dt: f64,
    lag: f64,
) -> Range<usize> {
    overlap_range(wind_len, wind_dt, still_len, still_dt, lag, 0.0)
}

/// Delay \[s\] of `b` relative to `a` (both sampled every `dt` s, from their own first
/// sample): if `b(t) = a(t − D)` the result is `D`, sub-sample. Found by FFT
/// cross-correlation of the normalised signals, a parabolic interpolation of its peak, and
/// a golden-section maximisation of the correlation with `b` interpolated by 4-point cubic
/// Lagrange at fractional shifts (see the module documentation).
///
/// For a periodic signal the lag is only defined up to a whole number of periods; the
/// largest overlap wins. Returns NaN when either signal is shorter than 4 samples,
/// constant or not finite, or `dt` is not finite and positive.
pub fn align_lag(a: &[f64], b: &[f64], dt: f64) -> f64 {
    if !(dt.is_finite() && dt > 0.0)
        || a.len() < 4
        || b.len() < 4
        || a.iter().chain(b).any(|v| !v.is_finite())
    {
        return f64::NAN;
    }
    match (normalised(a), normalised(b)) {
        (Some(a), Some(b)) => align_pairs(&[(a, b)], dt, dt).unwrap_or(f64::NAN),
        _ => f64::NAN,
    }
}

fn align_pairs(pairs: &[(Vec<f64>, Vec<f64>)], dt_a: f64, dt_b: f64) -> Option<f64> {
    let k = coarse_lag(pairs)?;
    Some(refine_lag(pairs, dt_a, dt_b, k * dt_b))
}

fn bad(case: &str, field: &str, message: String) -> Error {
    Error::InvalidData {
        case: case.to_string(),
        field: field.to_string(),
        message,
    }
}

/// Subtracts the still-air run from the wind-on run: the aerodynamic forces
/// `L_aero(tᵢ) = L_wind(tᵢ) − L_still(tᵢ + D)` (same for M) on the wind-on samples that
/// overlap the shifted still-air run ([`nowind_overlap`]), and the lag `D` \[s\] (delay of the
/// still-air motion relative to the wind-on motion, [`align_lag`] convention).
///
/// The runs are aligned on α and h together: each degree of freedom whose wind-on motion is
/// well above its noise (standard deviation > 10 × [`super::noise_sigma`]) enters the
/// cross-correlation normalised to unit variance; the still-air forces are interpolated
/// onto the wind-on time base by 4-point cubic Lagrange interpolation. Forces in the units
/// of the records (SI per unit span for records from [`crate::dataset`]).
///
/// # Errors
/// [`Error::InvalidData`] naming the case (`wind.meta.id`) and field when either run lacks
/// `lift` or `moment`, holds a non-finite value, the sample intervals differ by more than
/// 0.1 %, neither α nor h moves, or the runs overlap on fewer than 3 samples.
pub fn subtract_nowind(wind: &Record, still: &Record) -> Result<(Vec<f64>, Vec<f64>, f64)> {
    let id = wind.meta.id.as_str();
    // the column and its name travel together: (field, name) pairs, no name dispatch
    let get = |col: &Option<Vec<f64>>, name: &str, which: &str| -> Result<Vec<f64>> {
        col.clone().ok_or_else(|| {
            bad(
                id,
                &format!("{which}{name}"),
                format!("wind–no-wind subtraction needs `{name}`"),
            )
        })
    };
    let (lw, mw) = (
        get(&wind.lift, "lift", "")?,
        get(&wind.moment, "moment", "")?,
    );
    let (ls, ms) = (
        get(&still.lift, "lift", "nowind.")?,
        get(&still.moment, "moment", "nowind.")?,
    );
    for (name, v) in [
        ("alpha", &wind.alpha),
        ("h", &wind.h),
        ("lift", &lw),
        ("moment", &mw),
        ("nowind.alpha", &still.alpha),
        ("nowind.h", &still.h),
        ("nowind.lift", &ls),
        ("nowind.moment", &ms),
    ] {
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(bad(
                id,
                name,
                format!("non-finite value {} at sample {i}", v[i]),
            ));
        }
    }
    if wind.len() < 4 || still.len() < 4 {
        return Err(bad(
            id,
            "nowind",
            format!(
                "records of {} and {} samples: alignment needs at least 4 each",
                wind.len(),
                still.len()
            ),
        ));
    }
    let (dtw, dts) = (wind.dt, still.dt);
    if !(dtw > 0.0 && dts > 0.0 && (dtw - dts).abs() <= 1e-3 * dtw) {
        return Err(bad(
            id,
            "nowind.dt",
            format!("sample intervals differ: wind-on {dtw} s, still-air {dts} s"),
        ));
    }
    let mut pairs = Vec::with_capacity(2);
    for (a, b) in [(&wind.alpha, &still.alpha), (&wind.h, &still.h)] {
        let m = a.iter().sum::<f64>() / a.len() as f64;
        let sd = (a.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / a.len() as f64).sqrt();
        if sd > 10.0 * noise_sigma(a) {
            if let (Some(x), Some(y)) = (normalised(a), normalised(b)) {
                pairs.push((x, y));
            }
        }
    }
    if pairs.is_empty() {
        return Err(bad(
            id,
            "alpha",
            "neither alpha nor h moves above its noise: the runs cannot be aligned".into(),
        ));
    }
    let lag = align_pairs(&pairs, dtw, dts).ok_or_else(|| Error::Numerical {
        context: format!("case `{id}`: wind–no-wind alignment"),
        message: "FFT failed".into(),
    })?;
    let range = nowind_overlap(wind.len(), dtw, still.len(), dts, lag);
    if range.len() < 3 {
        return Err(bad(
            id,
            "nowind",
            format!(
                "after alignment (lag {lag} s) the runs overlap on {} samples",
                range.len()
            ),
        ));
    }
    let mut lift = Vec::with_capacity(range.len());
    let mut moment = Vec::with_capacity(range.len());
    for i in range {
        let u = (i as f64 * dtw + lag) / dts;
        lift.push(lw[i] - interpolate_cubic(&ls, u));
        moment.push(mw[i] - interpolate_cubic(&ms, u));
    }
    Ok((lift, moment, lag))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::{CaseKind, CaseMeta};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};
    use std::f64::consts::PI;

    #[test]
    fn cubic_interpolation_is_exact_for_cubics_and_accurate_for_sines() {
        let x: Vec<f64> = (0..10)
            .map(|i| {
                let t = i as f64;
                1.0 + t - 0.5 * t * t + 0.1 * t * t * t
            })
            .collect();
        for u in [0.0, 0.3, 4.5, 8.7, 9.0] {
            let e = 1.0 + u - 0.5 * u * u + 0.1 * u * u * u;
            assert!((interpolate_cubic(&x, u) - e).abs() < 1e-12, "{u}");
        }
        let wdt = 0.1;
        let s: Vec<f64> = (0..200).map(|i| (wdt * i as f64).sin()).collect();
        let max_err = (0..1000)
            .map(|k| {
                let u = 1.0 + k as f64 * 0.19;
                (interpolate_cubic(&s, u) - (wdt * u).sin()).abs()
            })
            .fold(0.0, f64::max);
        assert!(max_err <= 0.0234 * wdt.powi(4) * 1.01, "{max_err}");
    }

    #[test]
    fn align_lag_recovers_fractional_delay_of_a_chirp() {
        let dt = 0.01;
        let f = |t: f64| {
            (2.0 * PI * (0.5 * t + 0.05 * t * t)).sin() * (-0.01 * (t - 10.0).powi(2)).exp()
        };
        let d = 0.3737;
        let a: Vec<f64> = (0..2000).map(|i| f(i as f64 * dt)).collect();
        let b: Vec<f64> = (0..1500).map(|i| f(i as f64 * dt - d)).collect();
        // Coarse sampling (≥ 15 samples per period, ω·dt ≤ 0.16): the cubic interpolant's
        // error 0.0234 (ω dt)⁴ divided by the slope ω dt bounds the lag error at about
        // 0.0234 (ω dt)³ ≈ 1e-4 samples; allow 1e-3.
        let lag = align_lag(&a, &b, dt);
        assert!((lag - d).abs() < 1e-3 * dt, "lag {lag} vs {d}");
        let lag = align_lag(&b, &a, dt);
        assert!((lag + d).abs() < 1e-3 * dt, "lag {lag} vs {}", -d);
        // Offsets between the runs do not matter.
        let b2: Vec<f64> = b.iter().map(|v| 3.0 * v + 0.7).collect();
        let lag = align_lag(&a, &b2, dt);
        assert!((lag - d).abs() < 1e-3 * dt, "lag {lag} vs {d}");
        assert!(align_lag(&[1.0; 10], &a, dt).is_nan());
    }

    /// Forced two-frequency motion with a start-up ramp; the still-air run is the wind-on
    /// run's inertial part, delayed by a random non-integer number of samples and of a
    /// different length. Subtraction recovers the aerodynamic force to < 1e-3 of its
    /// amplitude, and the lag to a small fraction of a sample.
    #[test]
    fn nowind_subtraction_recovers_aerodynamic_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(2024);
        let dt = 1.0 / 512.0;
        let (fa, fh) = (2.0, 1.3);
        let (wa, wh) = (2.0 * PI * fa, 2.0 * PI * fh);
        let ramp = |t: f64| {
            if t < 2.0 {
                0.5 - 0.5 * (PI * t / 2.0).cos()
            } else {
                1.0
            }
        };
        let alpha = |t: f64| 0.1 * ramp(t) * (wa * t).sin();
        let h = |t: f64| 0.01 * ramp(t) * (wh * t).sin();
        // Inertial forces (from the exact second derivatives away from the ramp; inside
        // the ramp a smooth function of the motion is all that matters).
        let inertial_l = |t: f64| 0.8 * 0.01 * wh * wh * ramp(t) * (wh * t).sin() + 0.05 * alpha(t);
        let inertial_m = |t: f64| 0.004 * 0.1 * wa * wa * ramp(t) * (wa * t).sin() - 0.2 * h(t);
        let aero_l = |t: f64| 3.0 * alpha(t) + 0.4 * (wa * t).cos() * ramp(t);
        let aero_m = |t: f64| 0.3 * alpha(t) - 0.05 * (wh * t + 0.3).sin() * ramp(t);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let n_w = 12 * 512;
        let n_s = 10 * 512 + 77;
        let delay_samples = rng.random_range(100.0..400.0);
        let d_true = delay_samples * dt;
        let mk = |n: usize, shift: f64, aero: bool, rng: &mut ChaCha8Rng| -> Record {
            let ts: Vec<f64> = (0..n).map(|i| i as f64 * dt - shift).collect();
            let sig = 1e-6;
            Record {
                kind: CaseKind::Forced,
                meta: CaseMeta {
                    id: "case-1".into(),
                    ..Default::default()
                },
                t0: 0.0,
                dt,
                alpha: ts
                    .iter()
                    .map(|&t| alpha(t) + sig * noise.sample(rng))
                    .collect(),
                h: ts
                    .iter()
                    .map(|&t| h(t) + 0.1 * sig * noise.sample(rng))
                    .collect(),
                lift: Some(
                    ts.iter()
                        .map(|&t| inertial_l(t) + if aero { aero_l(t) } else { 0.0 })
                        .collect(),
                ),
                moment: Some(
                    ts.iter()
                        .map(|&t| inertial_m(t) + if aero { aero_m(t) } else { 0.0 })
                        .collect(),
                ),
                nowind: None,
                control: None,
            }
        };
        let wind = mk(n_w, 0.0, true, &mut rng);
        // Still-air sample j is at motion time j·dt − d_true: b(t) = a(t − D).
        let still = mk(n_s, d_true, false, &mut rng);
        let (l, m, lag) = subtract_nowind(&wind, &still).unwrap();
        assert!(
            (lag - d_true).abs() < 1e-3 * dt,
            "lag {lag} vs {d_true} ({} samples off)",
            (lag - d_true) / dt
        );
        let range = nowind_overlap(n_w, dt, n_s, dt, lag);
        assert_eq!(range.len(), l.len());
        // The still-air run starts D before the wind-on run: the overlap is its first
        // n_s − D/dt samples.
        let expected = n_s as f64 - delay_samples;
        assert!(
            (range.len() as f64 - expected).abs() <= 1.0,
            "{} vs {expected}",
            range.len()
        );
        let (mut el, mut em) = (0.0f64, 0.0f64);
        for (k, i) in range.enumerate() {
            let t = i as f64 * dt;
            el = el.max((l[k] - aero_l(t)).abs());
            em = em.max((m[k] - aero_m(t)).abs());
        }
        eprintln!(
            "nowind: lag error {:e} samples, max lift error {el:e}, max moment error {em:e}",
            (lag - d_true) / dt
        );
        let amp_l = 3.0 * 0.1 + 0.4;
        let amp_m = 0.3 * 0.1 + 0.05;
        assert!(el < 1e-3 * amp_l, "lift error {el}");
        assert!(em < 1e-3 * amp_m, "moment error {em}");
    }

    #[test]
    fn subtraction_errors_name_the_field() {
        let r = Record {
            kind: CaseKind::Forced,
            meta: CaseMeta {
                id: "c7".into(),
                ..Default::default()
            },
            t0: 0.0,
            dt: 0.01,
            alpha: (0..100).map(|i| (i as f64 * 0.3).sin()).collect(),
            h: vec![0.0; 100],
            lift: Some(vec![0.0; 100]),
            moment: None,
            nowind: None,
            control: None,
        };
        let e = subtract_nowind(&r, &r).unwrap_err();
        assert!(
            matches!(&e, Error::InvalidData { case, field, .. } if case == "c7" && field == "moment"),
            "{e:?}"
        );
        let mut s = r.clone();
        s.moment = Some(vec![0.0; 100]);
        let mut still = s.clone();
        still.dt = 0.011;
        let e = subtract_nowind(&s, &still).unwrap_err();
        assert!(
            matches!(&e, Error::InvalidData { field, .. } if field == "nowind.dt"),
            "{e:?}"
        );
    }
}
