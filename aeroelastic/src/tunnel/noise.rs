//! Sensor noise of the rig: the force balance (absolute, [`BalanceNoise`], or relative to
//! each record's peak force) quantised to its resolution, and the lasers ([`SensorNoise`]).

use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::error::{non_negative, positive};
use crate::Result;

/// Absolute noise of a two-component force balance: σ = `fraction` × full range per
/// channel (independent of the load, as a real balance), then every reading quantised to
/// the balance's resolution. Ranges and resolutions are totals over the span [N, N·m], as a
/// balance reads them; records per unit span get σ/span and resolution/span.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BalanceNoise {
    /// Full range of the lift channel ±R_L \[N\] (the paper's balance: 65 N).
    pub lift_range: f64,
    /// Full range of the moment channel ±R_M [N·m] (the paper's balance: 5 N·m).
    pub moment_range: f64,
    /// σ as a fraction of the full range (0.1 % → 1e-3).
    pub fraction: f64,
    /// Resolution of the lift reading \[N\] (0: no quantisation).
    pub lift_resolution: f64,
    /// Resolution of the moment reading [N·m] (0: no quantisation).
    pub moment_resolution: f64,
}

impl BalanceNoise {
    /// The paper's balance: ±65 N, ±5 N·m, σ = 0.1 % of range (0.065 N, 0.005 N·m), read by
    /// a 16-bit converter over the full span 2R (resolution 2R/2¹⁶: 1.98e-3 N, 1.53e-4 N·m;
    /// the converter's word length is aeroform's assumption, the paper does not give it).
    pub fn paper() -> Self {
        BalanceNoise {
            lift_range: 65.0,
            moment_range: 5.0,
            fraction: 1e-3,
            lift_resolution: 130.0 / 65536.0,
            moment_resolution: 10.0 / 65536.0,
        }
    }

    /// σ of (lift, moment) per unit span [N/m, N·m/m] for a model of span `span` \[m\].
    pub fn sd_per_span(&self, span: f64) -> (f64, f64) {
        (
            self.fraction * self.lift_range / span,
            self.fraction * self.moment_range / span,
        )
    }

    fn check(&self) -> Result<()> {
        non_negative("noise.balance_absolute.lift_range", self.lift_range)?;
        non_negative("noise.balance_absolute.moment_range", self.moment_range)?;
        non_negative("noise.balance_absolute.fraction", self.fraction)?;
        non_negative(
            "noise.balance_absolute.lift_resolution",
            self.lift_resolution,
        )?;
        non_negative(
            "noise.balance_absolute.moment_resolution",
            self.moment_resolution,
        )
    }
}

/// Sensor noise of the rig (see the module docs). Zero values switch a channel off.
///
/// The balance is either absolute ([`BalanceNoise`], `balance_absolute = Some`, the
/// physical model and [`SensorNoise::paper`]) or relative to each record's peak force
/// (`balance` fraction, used only when `balance_absolute` is `None`;
/// [`SensorNoise::paper_relative`], aeroform's earlier model).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SensorNoise {
    /// Relative balance noise: σ as a fraction of the record's peak |force| per channel
    /// (0.1 % → 1e-3); ignored when `balance_absolute` is set.
    pub balance: f64,
    /// Absolute balance noise (range × fraction, quantised to a resolution).
    #[serde(default)]
    pub balance_absolute: Option<BalanceNoise>,
    /// Heave noise σ_h \[m\] (8 µm).
    pub laser: f64,
    /// Distance s between the two lasers \[m\]; σ_α = 2σ_h/s. `None`: the chord.
    pub laser_spacing: Option<f64>,
}

impl SensorNoise {
    /// The paper's rig: absolute balance noise ([`BalanceNoise::paper`]), laser 8 µm,
    /// lasers one chord apart.
    pub fn paper() -> Self {
        SensorNoise {
            balance: 0.0,
            balance_absolute: Some(BalanceNoise::paper()),
            laser: 8e-6,
            laser_spacing: None,
        }
    }

    /// aeroform's earlier relative model: balance σ = 0.1 % of each record's peak force,
    /// laser 8 µm, lasers one chord apart.
    pub fn paper_relative() -> Self {
        SensorNoise {
            balance: 1e-3,
            balance_absolute: None,
            laser: 8e-6,
            laser_spacing: None,
        }
    }

    /// No noise at all.
    pub fn none() -> Self {
        SensorNoise {
            balance: 0.0,
            balance_absolute: None,
            laser: 0.0,
            laser_spacing: None,
        }
    }

    /// Pitch noise σ_α \[rad\] for chord `chord`.
    pub fn pitch_sd(&self, chord: f64) -> f64 {
        2.0 * self.laser / self.laser_spacing.unwrap_or(chord)
    }

    /// Balance σ of (lift, moment) per unit span [N/m, N·m/m] for records of peak |force|
    /// `peaks` (per unit span) on a model of span `span` \[m\].
    pub fn balance_sd(&self, peaks: (f64, f64), span: f64) -> (f64, f64) {
        match &self.balance_absolute {
            Some(b) => b.sd_per_span(span),
            None => (self.balance * peaks.0, self.balance * peaks.1),
        }
    }

    /// Adds balance noise to (lift, moment) per unit span and quantises them to the
    /// balance's resolution; `sd` from [`SensorNoise::balance_sd`].
    pub(super) fn apply_balance(
        &self,
        rng: &mut ChaCha8Rng,
        lift: &mut [f64],
        moment: &mut [f64],
        sd: (f64, f64),
        span: f64,
    ) {
        add_noise(rng, lift, sd.0);
        add_noise(rng, moment, sd.1);
        if let Some(b) = &self.balance_absolute {
            quantise(lift, b.lift_resolution / span);
            quantise(moment, b.moment_resolution / span);
        }
    }

    pub(super) fn check(&self) -> Result<()> {
        non_negative("noise.balance", self.balance)?;
        if let Some(b) = &self.balance_absolute {
            b.check()?;
        }
        non_negative("noise.laser", self.laser)?;
        if let Some(s) = self.laser_spacing {
            positive("noise.laser_spacing", s)?;
        }
        Ok(())
    }
}

fn quantise(v: &mut [f64], step: f64) {
    if step > 0.0 && step.is_finite() {
        for x in v.iter_mut() {
            *x = (*x / step).round() * step;
        }
    }
}

/// Adds independent normal noise of standard deviation `sd` to every value of `v`, drawn
/// from `rng` (nothing for `sd` ≤ 0 or not finite).
pub fn add_noise(rng: &mut ChaCha8Rng, v: &mut [f64], sd: f64) {
    if sd > 0.0 && sd.is_finite() {
        if let Ok(n) = Normal::new(0.0, sd) {
            for x in v.iter_mut() {
                *x += n.sample(rng);
            }
        }
    }
}

/// Largest |value| of `v` (0 for an empty slice).
pub fn peak(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::TheodorsenAero;
    use crate::tunnel::{forced_record, ForcedCase, ForcedOptions, Motion};

    #[test]
    fn absolute_balance_noise_is_range_times_fraction_and_quantised() {
        // Zero aerodynamic force (U tiny, tiny motion): the balance still reads noise of
        // σ = 0.1 % of range / span, on the resolution grid.
        let m = TheodorsenAero::new(0.25, 0.0).unwrap();
        let mut opts = ForcedOptions::paper(11);
        opts.duration = 8.0;
        opts.noise.laser = 0.0;
        let case = ForcedCase {
            id: "quiet".into(),
            wind_speed: 1e-6,
            motion: Motion::two_frequency(1.3, 2.0, 1e-9, 1e-12),
            config: None,
            amplitude_ratio: None,
        };
        let (r, _) = forced_record(&m, &case, &opts, 5).unwrap();
        let span = opts.section.span;
        let b = BalanceNoise::paper();
        for (v, range, res) in [
            (r.lift.as_ref().unwrap(), b.lift_range, b.lift_resolution),
            (
                r.moment.as_ref().unwrap(),
                b.moment_range,
                b.moment_resolution,
            ),
        ] {
            let sd = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt() * span;
            let want = 1e-3 * range;
            assert!((sd / want - 1.0).abs() < 0.03, "σ {sd} vs {want}");
            for x in v.iter().take(50) {
                let k = x * span / res;
                assert!((k - k.round()).abs() < 1e-6, "{x} off the grid {res}");
            }
        }
        // the relative model stays available and scales with the record
        let mut rel = opts.clone();
        rel.noise = SensorNoise::paper_relative();
        rel.noise.laser = 0.0;
        let (r2, _) = forced_record(&m, &case, &rel, 5).unwrap();
        let sd2 = r2.lift.unwrap().iter().map(|x| x.abs()).fold(0.0, f64::max);
        assert!(sd2 < 1e-9, "relative noise of a zero force {sd2}");
    }
}
