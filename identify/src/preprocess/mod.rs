//! Preprocessing: from a [`Record`] (SI per unit span) to a [`PreparedCase`] ready for
//! regression (DESIGN.md §3).
//!
//! Steps of [`prepare`]:
//! 1. checks: finite samples, forces present, at least 3 samples;
//! 2. wind–no-wind subtraction when the record carries a still-air run
//!    ([`subtract_nowind`]; only the overlap of the two runs is kept);
//! 3. forcing frequencies (forced cases): from the manifest when given, else from the
//!    largest spectral peak of α and of h ([`dominant_frequency`]), each refined by
//!    maximising the power of a least-squares sinusoid fit ([`refine_frequency`]), then
//!    refined jointly for α and h together. A degree of freedom that does not move
//!    (amplitude below [`PreprocessOptions::min_pitch_amplitude`] /
//!    [`PreprocessOptions::min_heave_amplitude`], or a spectral peak holding less than
//!    [`PreprocessOptions::min_peak_share`] of its variance) has no forcing frequency;
//! 4. length check: at least [`PreprocessOptions::min_periods`] periods of the lowest
//!    forcing frequency;
//! 5. velocities ([`VelocityMethod`]). A harmonic fit of a degree of freedom starts at all
//!    forcing frequencies and keeps only its significant components
//!    ([`significant_harmonic_fit`] with [`PreprocessOptions::component_significance`] and
//!    [`PreprocessOptions::component_floor`]): in a two-frequency test where α is driven at
//!    f_α only, the fitted α then has no f_h component at all, so the identities of
//!    single-frequency motion (α̇² = ω²(A² − (α − ᾱ)²)) hold to rounding and the
//!    identifiability analysis sees the exact dependencies.

mod align;
mod harmonic;
mod sg;

pub use self::align::{align_lag, nowind_overlap, subtract_nowind};
pub(crate) use self::harmonic::sinusoid_share as harmonic_share;
pub use self::harmonic::{
    dominant_frequency, harmonic_fit, noise_sigma, refine_frequency, significant_harmonic_fit,
    spectral_peak, HarmonicComponent, HarmonicFit, PeakSearch, Window,
};
pub use self::sg::savitzky_golay_derivative;

use crate::record::{CaseKind, Forcing, PreparedCase, Record};
use crate::{Error, Result};

/// Default Savitzky–Golay half-window \[samples\] of [`VelocityMethod::Auto`]'s fallback.
///
/// Chosen with order 4 on noisy multi-sines sampled at 512 Hz (the paper's rate) with
/// content up to 6 Hz: rms derivative error 0.7–2.9 % of the rms velocity (noise 0.5–2 %),
/// see the ignored test `sg_parameter_sweep`. For other sampling rates scale it to about
/// 0.1–0.2 × the samples per period of the highest frequency of interest.
pub const DEFAULT_SG_HALF_WINDOW: usize = 25;
/// Default Savitzky–Golay polynomial order of [`VelocityMethod::Auto`]'s fallback.
pub const DEFAULT_SG_ORDER: usize = 4;
/// Default acceptance fraction of the harmonic fit (rms residual / rms motion).
///
/// Evidence (ignored test `harmonic_acceptance_sweep`, 2 Hz pitch over 20.3 s at 512 Hz
/// plus an unmodelled 3.3 Hz component): an accepted fit carries the unmodelled share
/// into the velocity almost in full (1 % extra amplitude → 1.6 % velocity error), while the
/// Savitzky–Golay fallback gives 0.2 % (noise 0.05 %) to 1.6 % (noise 0.5 %). At 2 % the
/// fit was accepted with 3.2 % velocity error where the fallback gave 0.2 %; 1 % keeps the
/// accepted error at the level of the fallback's. At high noise the noise term of the
/// rule dominates and accepting is right (2 % noise: fit 4.8 %, fallback 6.3 %).
pub const DEFAULT_HARMONIC_TOLERANCE: f64 = 0.01;
/// Default multiple of the sensor-noise estimate allowed in the harmonic-fit residual.
pub const DEFAULT_NOISE_FACTOR: f64 = 1.5;
/// Default number of standard errors a harmonic component's amplitude must exceed to be
/// kept ([`significant_harmonic_fit`]). A pure-noise component exceeds 5 with probability
/// `exp(−12.5) ≈ 4·10⁻⁶` (its amplitude over its standard error is Rayleigh distributed).
pub const DEFAULT_COMPONENT_SIGNIFICANCE: f64 = 5.0;
/// Default relative floor of a kept harmonic component: its amplitude must be at least this
/// fraction of the largest component of the same degree of freedom. Dropping a component
/// of relative amplitude r < 1e-3 at frequency f changes the velocity by about r·f/f₁ of
/// its peak (f₁ the frequency of the largest component; < 1.6·10⁻³ for the paper's 2 Hz
/// and 1.3 Hz), well inside the 1 % acceptance tolerance, while such components (rig
/// cross-talk, noise fitted at the other DOF's frequency) break the exact identities of
/// single-frequency motion. A degree of freedom with no kept component is fitted by its
/// mean (velocity exactly 0).
pub const DEFAULT_COMPONENT_FLOOR: f64 = 1e-3;

/// How α̇ and ḣ are obtained from the measured motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VelocityMethod {
    /// Forced case whose motion a harmonic fit at the forcing frequencies explains
    /// (per degree of freedom: residual within tolerance, see
    /// [`PreprocessOptions::harmonic_tolerance`]) → the motion is replaced by the fit and
    /// the velocity is its analytic derivative (exact and denoising). Otherwise (free
    /// response, multi-sine, random motion, poor fit) → Savitzky–Golay with
    /// [`PreprocessOptions::sg_half_window`] and [`PreprocessOptions::sg_order`]; the
    /// measured motion is kept.
    Auto,
    /// Always the harmonic fit; an error when it does not explain the motion.
    Harmonic,
    /// Always a Savitzky–Golay smoothing differentiator with these parameters
    /// (window `2·half_window + 1` samples, polynomial degree `order`); motion kept.
    SavitzkyGolay {
        /// Half-width of the window \[samples\].
        half_window: usize,
        /// Polynomial degree.
        order: usize,
    },
}

/// Options of [`prepare`]. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct PreprocessOptions {
    /// Velocity method (default [`VelocityMethod::Auto`]).
    pub velocity: VelocityMethod,
    /// Subtract the still-air run when the record has one (default true).
    pub subtract_nowind: bool,
    /// Minimum record length in periods of the lowest forcing frequency (default 1.0).
    pub min_periods: f64,
    /// Harmonic-fit acceptance: the fit of a degree of freedom is accepted when
    /// `rms_residual² ≤ (harmonic_tolerance · rms_motion)² + (noise_factor · σ̂)²` with
    /// `rms_motion` the rms of the signal about its mean and `σ̂` the sensor-noise
    /// estimate [`noise_sigma`] (default 0.01, see [`DEFAULT_HARMONIC_TOLERANCE`]).
    pub harmonic_tolerance: f64,
    /// Multiple of the noise estimate allowed in the residual (default 1.5).
    pub noise_factor: f64,
    /// A harmonic component is kept only when its amplitude exceeds this many standard
    /// errors (default 5, [`DEFAULT_COMPONENT_SIGNIFICANCE`]; see
    /// [`significant_harmonic_fit`]). 0 with `component_floor = 0` keeps every component.
    pub component_significance: f64,
    /// … and is at least this fraction of the largest component of the same degree of
    /// freedom (default 1e-3, [`DEFAULT_COMPONENT_FLOOR`]).
    pub component_floor: f64,
    /// Savitzky–Golay half-window of the `Auto` fallback \[samples\] (default 25).
    pub sg_half_window: usize,
    /// Savitzky–Golay order of the `Auto` fallback (default 4).
    pub sg_order: usize,
    /// Pitch amplitude \[rad\] below which pitch counts as not forced (default 1e-4).
    pub min_pitch_amplitude: f64,
    /// Heave amplitude \[m\] below which heave counts as not forced (default 1e-5).
    pub min_heave_amplitude: f64,
    /// Minimum share of a signal's variance held by its largest spectral peak for that
    /// peak to count as a forcing frequency when the manifest gives none (default 0.1).
    pub min_peak_share: f64,
}

impl Default for PreprocessOptions {
    fn default() -> Self {
        PreprocessOptions {
            velocity: VelocityMethod::Auto,
            subtract_nowind: true,
            min_periods: 1.0,
            harmonic_tolerance: DEFAULT_HARMONIC_TOLERANCE,
            noise_factor: DEFAULT_NOISE_FACTOR,
            component_significance: DEFAULT_COMPONENT_SIGNIFICANCE,
            component_floor: DEFAULT_COMPONENT_FLOOR,
            sg_half_window: DEFAULT_SG_HALF_WINDOW,
            sg_order: DEFAULT_SG_ORDER,
            min_pitch_amplitude: 1e-4,
            min_heave_amplitude: 1e-5,
            min_peak_share: 0.1,
        }
    }
}

impl PreprocessOptions {
    /// Validates the options.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming the option when a number is negative or not finite,
    /// `min_peak_share` or `component_floor` is outside [0, 1], or a Savitzky–Golay window
    /// is invalid (half-window ≥ 1, 1 ≤ order < 2·half-window + 1).
    pub fn check(&self) -> Result<()> {
        let opt = |name: &str, message: String| Error::InvalidOption {
            name: name.to_string(),
            message,
        };
        for (name, v) in [
            ("min_periods", self.min_periods),
            ("harmonic_tolerance", self.harmonic_tolerance),
            ("noise_factor", self.noise_factor),
            ("component_significance", self.component_significance),
            ("component_floor", self.component_floor),
            ("min_pitch_amplitude", self.min_pitch_amplitude),
            ("min_heave_amplitude", self.min_heave_amplitude),
            ("min_peak_share", self.min_peak_share),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(opt(name, format!("{v} must be finite and >= 0")));
            }
        }
        if self.component_floor > 1.0 {
            return Err(opt(
                "component_floor",
                format!("{} must be <= 1", self.component_floor),
            ));
        }
        if self.min_peak_share > 1.0 {
            return Err(opt(
                "min_peak_share",
                format!("{} must be <= 1", self.min_peak_share),
            ));
        }
        let mut windows = vec![("sg_half_window", self.sg_half_window, self.sg_order)];
        if let VelocityMethod::SavitzkyGolay { half_window, order } = self.velocity {
            windows.push(("velocity", half_window, order));
        }
        for (name, m, p) in windows {
            if m == 0 || p == 0 || p > 2 * m {
                return Err(opt(
                    name,
                    format!(
                        "Savitzky–Golay half-window {m}, order {p}: need half-window >= 1 \
                         and 1 <= order < 2*half-window + 1"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// How the velocity of one degree of freedom was obtained.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VelocitySource {
    /// Analytic derivative of the harmonic fit; the motion was replaced by the fit.
    Harmonic {
        /// Rms residual of the fit (signal units).
        rms_residual: f64,
    },
    /// Savitzky–Golay differentiator; the measured motion was kept.
    SavitzkyGolay {
        /// Half-window \[samples\].
        half_window: usize,
        /// Polynomial degree.
        order: usize,
    },
}

/// What [`prepare_with_report`] did, for reporting.
#[derive(Debug, Clone, PartialEq)]
pub struct PrepareReport {
    /// Lag of the still-air run \[s\] when it was subtracted.
    pub nowind_lag: Option<f64>,
    /// Index of the first wind-on sample kept (0 without subtraction).
    pub first_sample: usize,
    /// Source of α̇.
    pub pitch_velocity: VelocitySource,
    /// Source of ḣ.
    pub heave_velocity: VelocitySource,
    /// Sensor-noise estimates σ̂ of (α \[rad\], h \[m\]).
    pub noise: (f64, f64),
    /// Candidate components of the harmonic fit of α (one per forcing frequency, with
    /// amplitude \[rad\], standard error and whether it was kept); empty when no harmonic
    /// fit was attempted (free case, Savitzky–Golay requested, no forcing frequency).
    pub pitch_components: Vec<HarmonicComponent>,
    /// As `pitch_components`, for h \[m\].
    pub heave_components: Vec<HarmonicComponent>,
}

/// Prepares a record for regression; see the module documentation for the steps.
///
/// # Errors
/// [`Error::InvalidOption`] from [`PreprocessOptions::check`]; [`Error::InvalidData`]
/// naming the case and field for a non-finite sample, a missing `lift`/`moment`, fewer
/// than 3 samples, a failed still-air subtraction ([`subtract_nowind`]), or (with
/// [`VelocityMethod::Harmonic`]) a case without forcing frequencies or whose harmonic fit
/// leaves a residual above tolerance (the message gives the residual and the tolerance);
/// [`Error::TooShort`] when the record holds fewer than `min_periods` periods of its
/// lowest forcing frequency or is shorter than the Savitzky–Golay window.
pub fn prepare(record: &Record, opts: &PreprocessOptions) -> Result<PreparedCase> {
    prepare_with_report(record, opts).map(|(c, _)| c)
}

/// A harmonic fit's values, derivatives and rms residual.
type Fitted = (Vec<f64>, Vec<f64>, f64);

fn bad(case: &str, field: &str, message: String) -> Error {
    Error::InvalidData {
        case: case.to_string(),
        field: field.to_string(),
        message,
    }
}

/// As [`prepare`], also returning what was done (lag, velocity sources, noise levels).
///
/// # Errors
/// As [`prepare`].
pub fn prepare_with_report(
    record: &Record,
    opts: &PreprocessOptions,
) -> Result<(PreparedCase, PrepareReport)> {
    opts.check()?;
    let id = record.meta.id.as_str();
    let n = record.len();
    let dt = record.dt;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(bad(id, "dt", format!("sample interval {dt} s must be > 0")));
    }
    if record.h.len() != n {
        return Err(bad(
            id,
            "h",
            format!("{} samples but alpha has {n}", record.h.len()),
        ));
    }
    let lift = record.lift.as_ref().ok_or_else(|| {
        bad(
            id,
            "lift",
            format!("{:?} case has no `lift` column", record.kind),
        )
    })?;
    let moment = record.moment.as_ref().ok_or_else(|| {
        bad(
            id,
            "moment",
            format!("{:?} case has no `moment` column", record.kind),
        )
    })?;
    for (name, v) in [
        ("alpha", &record.alpha),
        ("h", &record.h),
        ("lift", lift),
        ("moment", moment),
    ] {
        if v.len() != n {
            return Err(bad(
                id,
                name,
                format!("{} samples but alpha has {n}", v.len()),
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(bad(
                id,
                name,
                format!("non-finite value {} at sample {i}", v[i]),
            ));
        }
    }
    if n < 3 {
        return Err(bad(
            id,
            "alpha",
            format!("{n} samples; at least 3 are needed"),
        ));
    }

    // Wind–no-wind subtraction.
    let (mut alpha, mut h, lift, moment, lag, first) = match (&record.nowind, opts.subtract_nowind)
    {
        (Some(still), true) => {
            let (l, m, lag) = subtract_nowind(record, still)?;
            let r = nowind_overlap(n, dt, still.len(), still.dt, lag);
            (
                record.alpha[r.clone()].to_vec(),
                record.h[r.clone()].to_vec(),
                l,
                m,
                Some(lag),
                r.start,
            )
        }
        _ => (
            record.alpha.clone(),
            record.h.clone(),
            lift.clone(),
            moment.clone(),
            None,
            0,
        ),
    };
    let n = alpha.len();
    let duration = n as f64 * dt;

    // Forcing frequencies.
    let forcing = if record.kind == CaseKind::Forced {
        forcing_frequencies(record, &alpha, &h, dt, opts)?
    } else {
        Forcing::default()
    };

    let noise = (noise_sigma(&alpha), noise_sigma(&h));

    // Velocities.
    let freqs = forcing.frequencies();
    let sg = |m: usize, p: usize| VelocitySource::SavitzkyGolay {
        half_window: m,
        order: p,
    };
    let mut fits: [Option<Fitted>; 2] = [None, None];
    let mut components: [Vec<HarmonicComponent>; 2] = [Vec::new(), Vec::new()];
    let use_harmonic = match opts.velocity {
        VelocityMethod::Auto => record.kind == CaseKind::Forced && !freqs.is_empty(),
        VelocityMethod::Harmonic => {
            if freqs.is_empty() {
                return Err(bad(
                    id,
                    "alpha",
                    "harmonic velocities need forcing frequencies, and this case has none".into(),
                ));
            }
            true
        }
        VelocityMethod::SavitzkyGolay { .. } => false,
    };
    if use_harmonic {
        for (k, (name, x, sigma)) in [("alpha", &alpha, noise.0), ("h", &h, noise.1)]
            .into_iter()
            .enumerate()
        {
            let (fit, comps) = significant_harmonic_fit(
                x,
                dt,
                &freqs,
                opts.component_significance,
                opts.component_floor,
            )
            .map_err(|e| {
                bad(
                    id,
                    name,
                    format!("harmonic fit at {freqs:?} Hz failed: {e}"),
                )
            })?;
            components[k] = comps;
            let m = x.iter().sum::<f64>() / n as f64;
            let rms = (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n as f64).sqrt();
            let allowed = (opts.harmonic_tolerance * rms).hypot(opts.noise_factor * sigma);
            if fit.rms_residual <= allowed {
                fits[k] = Some((fit.values(n, dt), fit.derivatives(n, dt), fit.rms_residual));
            } else if opts.velocity == VelocityMethod::Harmonic {
                return Err(bad(
                    id,
                    name,
                    format!(
                        "harmonic fit at {:?} Hz (of {freqs:?}) leaves an rms residual of {:e}, above \
                         the tolerance {allowed:e} ({} × rms motion {rms:e} ⊕ {} × noise \
                         {sigma:e})",
                        fit.freqs, fit.rms_residual, opts.harmonic_tolerance, opts.noise_factor
                    ),
                ));
            }
        }
    }
    let (m_sg, p_sg) = match opts.velocity {
        VelocityMethod::SavitzkyGolay { half_window, order } => (half_window, order),
        _ => (opts.sg_half_window, opts.sg_order),
    };
    let velocity = |x: &mut Vec<f64>, fit: Option<Fitted>, name: &str| match fit {
        Some((v, d, r)) => {
            *x = v;
            Ok((d, VelocitySource::Harmonic { rms_residual: r }))
        }
        None => {
            if n < 2 * m_sg + 1 {
                return Err(Error::TooShort {
                    case: id.to_string(),
                    duration,
                    needed: (2 * m_sg + 1) as f64 * dt,
                    reason: format!(
                        "the Savitzky–Golay window of {} samples for `{name}`",
                        2 * m_sg + 1
                    ),
                });
            }
            savitzky_golay_derivative(x, dt, m_sg, p_sg)
                .map(|d| (d, sg(m_sg, p_sg)))
                .map_err(|e| bad(id, name, e.to_string()))
        }
    };
    let [fa, fh] = fits;
    let [pc, hc] = components;
    let (alpha_dot, src_a) = velocity(&mut alpha, fa, "alpha")?;
    let (h_dot, src_h) = velocity(&mut h, fh, "h")?;

    Ok((
        PreparedCase {
            meta: record.meta.clone(),
            dt,
            alpha,
            alpha_dot,
            h,
            h_dot,
            lift,
            moment,
            forcing,
        },
        PrepareReport {
            nowind_lag: lag,
            first_sample: first,
            pitch_velocity: src_a,
            heave_velocity: src_h,
            noise,
            pitch_components: pc,
            heave_components: hc,
        },
    ))
}

/// Forcing frequencies of a forced case (see the module documentation), with the
/// `min_periods` check.
fn forcing_frequencies(
    record: &Record,
    alpha: &[f64],
    h: &[f64],
    dt: f64,
    opts: &PreprocessOptions,
) -> Result<Forcing> {
    let id = record.meta.id.as_str();
    let n = alpha.len();
    let duration = n as f64 * dt;
    let too_short = |f: f64, source: &str| Error::TooShort {
        case: id.to_string(),
        duration,
        needed: opts.min_periods / f,
        reason: format!(
            "{} period(s) of the {source} forcing frequency {f} Hz are needed",
            opts.min_periods
        ),
    };
    // Nominal frequency per DOF: manifest value, else the largest spectral peak.
    let mut nominal: [Option<(f64, bool)>; 2] = [None, None];
    for (k, (x, given)) in [(alpha, record.meta.freq_pitch), (h, record.meta.freq_heave)]
        .into_iter()
        .enumerate()
    {
        nominal[k] = match given {
            Some(f) => Some((f, true)),
            None => dominant_frequency(x, dt).map(|f| (f, false)),
        };
    }
    // Length check on the nominal values (refinement needs about a period).
    for (k, source) in [(0, "pitch"), (1, "heave")] {
        if let Some((f, given)) = nominal[k] {
            if given && duration * f < opts.min_periods {
                return Err(too_short(f, source));
            }
        }
    }
    let mins = [opts.min_pitch_amplitude, opts.min_heave_amplitude];
    let mut moving: [Option<f64>; 2] = [None, None];
    for (k, x) in [alpha, h].into_iter().enumerate() {
        let Some((f0, given)) = nominal[k] else {
            continue;
        };
        let f = if duration * f0 >= 0.5 {
            refine_frequency(x, dt, f0)
        } else {
            f0
        };
        let Some((share, amp)) = harmonic::sinusoid_share(x, dt, f) else {
            continue;
        };
        if amp >= mins[k] && (given || share >= opts.min_peak_share) {
            moving[k] = Some(f);
        }
    }
    // Joint refinement on α and h together.
    let mut freqs: Vec<f64> = Vec::new();
    let mut which = [usize::MAX; 2];
    let resolution = 1.0 / duration;
    for k in 0..2 {
        if let Some(f) = moving[k] {
            if let Some(j) = freqs.iter().position(|g| (g - f).abs() < resolution) {
                which[k] = j;
            } else {
                which[k] = freqs.len();
                freqs.push(f);
            }
        }
    }
    if !freqs.is_empty() && duration * freqs.iter().cloned().fold(f64::INFINITY, f64::min) >= 1.0 {
        let signals: Vec<&[f64]> = [alpha, h]
            .into_iter()
            .enumerate()
            .filter(|(k, _)| moving[*k].is_some())
            .map(|(_, x)| x)
            .collect();
        freqs = harmonic::refine_frequencies(&signals, dt, &freqs);
    }
    let forcing = Forcing {
        pitch: moving[0].map(|_| freqs[which[0]]),
        heave: moving[1].map(|_| freqs[which[1]]),
    };
    if let Some(fmin) = forcing.frequencies().into_iter().reduce(f64::min) {
        if duration * fmin < opts.min_periods {
            let source = if Some(fmin) == forcing.pitch {
                "pitch"
            } else {
                "heave"
            };
            return Err(too_short(fmin, source));
        }
    }
    Ok(forcing)
}

#[cfg(test)]
mod tests;
