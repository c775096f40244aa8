//! Simulation of the sim (optionally augmented by a fitted candidate) from a run's
//! measured state, and the observables of a response: dominant pitch frequency, decay or
//! growth rate of the pitch amplitude, final (LCO) amplitude.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use aeroelastic::aero::{AeroModel, Flow};
use aeroelastic::dynamics::{ExtraTerms, SectionDynamics};
use aeroelastic::integrate::{Control, ObserverVerdict};
use aeroelastic::section::Section;
use nalgebra::Matrix2;

use super::candidates::SystemTerm;
use crate::structure::line_fit;

use aeroelastic::structure::Structure;

use super::residual::{dominant_frequency, RunResidual};

/// A fitted augmentation used in a simulation: the effect's terms, grid values,
/// coefficients.
#[derive(Clone)]
pub(crate) struct Augment {
    pub term: &'static dyn SystemTerm,
    pub grid: Vec<f64>,
    pub theta: Vec<f64>,
}

impl std::fmt::Debug for Augment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Augment")
            .field("coefficients", &self.term.coefficient_names())
            .field("grid", &self.grid)
            .field("theta", &self.theta)
            .finish()
    }
}

impl Augment {
    /// Extra force Φ(q, q̇)θ (not the added-mass or delay parts).
    fn force(&self, q: [f64; 2], qd: [f64; 2], q_dyn: f64, chord: f64) -> [f64; 2] {
        self.term
            .force(&self.grid, &self.theta, q, qd, q_dyn, chord)
    }

    fn added_mass(&self) -> [[f64; 2]; 2] {
        self.term.mass(&self.theta)
    }

    fn delay(&self) -> f64 {
        self.term.delay(&self.theta)
    }
}

/// Simulated pitch and heave from sample `run.i0` to the end of the run, RK4
/// ([`aeroelastic::integrate::rk4`]) with `substeps` steps per sample, from the measured
/// state at `i0` (SG velocities) and the lag states integrated along the measured motion
/// up to `i0`. The equations are the section's ([`SectionDynamics`]) with the fitted
/// augmentation as [`ExtraTerms`]. The run stops early when |α| > 1.5 rad; it is empty
/// when the section or its total mass is invalid.
pub(crate) fn simulate(
    model: &Arc<dyn AeroModel>,
    rho: f64,
    st: &Structure,
    run: &RunResidual,
    aug: Option<&Augment>,
    substeps: usize,
) -> [Vec<f64>; 2] {
    let model = super::residual::run_model(model, run.u, run.k);
    let chord = model.chord();
    let q_dyn = Flow { rho, u: run.u }.q_dyn();
    let Ok(section) = Section::new(st.clone(), model, rho) else {
        return [Vec::new(), Vec::new()];
    };
    let terms = Fitted {
        aug,
        dm: aug.map(|a| a.added_mass()).unwrap_or([[0.0; 2]; 2]),
        tau: aug.map(|a| a.delay()).unwrap_or(0.0),
        q_dyn,
        chord,
        fdot: Default::default(),
    };
    let Ok(sys) = SectionDynamics::with_extra(&section, run.u, &terms) else {
        return [Vec::new(), Vec::new()];
    };
    let nz = sys.dim();
    let n_out = run.q[0].len() - run.i0;
    let dt = run.dt;
    let h = dt / substeps as f64;
    let mut y = vec![0.0; nz];
    y[0] = run.q[0][run.i0];
    y[1] = run.q[1][run.i0];
    y[2] = run.qd[0][run.i0];
    y[3] = run.qd[1][run.i0];
    y[4..].copy_from_slice(&run.lag0);
    let mut out = [Vec::with_capacity(n_out), Vec::with_capacity(n_out)];
    if n_out == 0 {
        return out;
    }
    out[0].push(y[0]);
    out[1].push(y[1]);
    // Delay: F(t − τ) ≈ F − τ Ḟ with Ḟ = (F(y_s) − F(y_{s−1}))/h, from the two previous
    // step starts (explicit, held over the step; 0 on the first step).
    let mut f_prev = sys.aero_forces(&y);
    let _ = aeroelastic::integrate::rk4(
        &sys,
        0.0,
        &mut y,
        h,
        (n_out - 1) * substeps,
        None,
        &mut |s, _t, y| {
            if y[1].abs() >= 1.5 {
                return Control::Stop(ObserverVerdict::LeftBound);
            }
            let f = sys.aero_forces(y);
            terms.set_fdot([(f[0] - f_prev[0]) / h, (f[1] - f_prev[1]) / h]);
            f_prev = f;
            if s % substeps == 0 {
                out[0].push(y[0]);
                out[1].push(y[1]);
            }
            Control::Continue
        },
    );
    out
}

/// The fitted augmentation as terms of the section's equations of motion: its mass ΔM,
/// and on the applied force F − τḞ + Φ(q, q̇)θ (r_aug = r − Φθ: the augmentation acts
/// like an aerodynamic force).
#[derive(Debug)]
struct Fitted<'a> {
    aug: Option<&'a Augment>,
    dm: [[f64; 2]; 2],
    tau: f64,
    q_dyn: f64,
    chord: f64,
    /// Ḟ used by the delay term over the current step (bits of two f64).
    fdot: [AtomicU64; 2],
}

impl Fitted<'_> {
    fn set_fdot(&self, v: [f64; 2]) {
        for (a, v) in self.fdot.iter().zip(v) {
            a.store(v.to_bits(), Ordering::Relaxed);
        }
    }
}

impl ExtraTerms for Fitted<'_> {
    fn mass(&self) -> Matrix2<f64> {
        let m = &self.dm;
        Matrix2::new(m[0][0], m[0][1], m[1][0], m[1][1])
    }

    fn applied(&self, q: [f64; 2], qd: [f64; 2], f: [f64; 2]) -> [f64; 2] {
        let extra = self
            .aug
            .map(|a| a.force(q, qd, self.q_dyn, self.chord))
            .unwrap_or([0.0; 2]);
        let fdot = self
            .fdot
            .each_ref()
            .map(|a| f64::from_bits(a.load(Ordering::Relaxed)));
        [0, 1].map(|c| f[c] - self.tau * fdot[c] + extra[c])
    }
}

/// Observables of a pitch response sampled every `dt`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Observables {
    /// Dominant pitch frequency \[Hz\].
    pub freq: f64,
    /// Exponential growth rate of the pitch amplitude σ \[1/s\] (< 0: decay), from a
    /// least-squares line through ln A(t) of the per-period amplitudes above the noise.
    pub rate: f64,
    /// Pitch amplitude over the last 2 s (half peak-to-peak) \[deg\].
    pub final_amp_deg: f64,
    /// Linear decay rate of the amplitude dA/dt \[rad/s\] (least-squares line through A(t)).
    pub linear_slope: f64,
    /// Relative misfit of the exponential envelope over that of the linear envelope
    /// (> 1: the decay is closer to linear, as Coulomb friction makes it).
    pub exp_over_lin: f64,
    /// Relative frequency change between the large- and small-amplitude halves of the
    /// record, (f_large − f_small)/f (amplitude-dependent frequency).
    pub freq_shift: f64,
    /// Mean α over the last half of the record \[rad\].
    pub mean_late: f64,
}

/// Per-period amplitude windows of `a`: (centre time \[s\], half peak-to-peak, mean,
/// zero-crossing frequency \[Hz\]).
fn windows(a: &[f64], dt: f64, f: f64) -> Vec<(f64, f64, f64, f64)> {
    if f.is_nan() || f <= 0.0 {
        return Vec::new();
    }
    let w = ((1.0 / f) / dt).round().max(4.0) as usize;
    let mut out = Vec::new();
    let mut s = 0;
    while s + w <= a.len() {
        let seg = &a[s..s + w];
        let (mn, mx) = seg
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let mean = seg.iter().sum::<f64>() / w as f64;
        out.push(((s as f64 + 0.5 * w as f64) * dt, 0.5 * (mx - mn), mean, f));
        s += w;
    }
    out
}

/// Observables of the pitch series `a` (rad) sampled every `dt`; `floor` is the
/// amplitude \[rad\] below which windows are ignored (noise).
pub(crate) fn observables(a: &[f64], dt: f64, floor: f64) -> Observables {
    let freq = dominant_frequency(a, dt);
    let win = windows(a, dt, freq);
    let good: Vec<&(f64, f64, f64, f64)> = win.iter().filter(|w| w.1 > floor).collect();
    let t: Vec<f64> = good.iter().map(|w| w.0).collect();
    let amp: Vec<f64> = good.iter().map(|w| w.1).collect();
    let lnamp: Vec<f64> = amp.iter().map(|v| v.ln()).collect();
    let (rate, c_exp, _) = line_fit(&t, &lnamp);
    let (lin_slope, lin_icpt, sse_lin) = line_fit(&t, &amp);
    let sse_exp: f64 = t
        .iter()
        .zip(&amp)
        .map(|(ti, ai)| (ai - (c_exp + rate * ti).exp()).powi(2))
        .sum();
    let _ = lin_icpt;
    let exp_over_lin = if sse_lin > 0.0 {
        sse_exp / sse_lin
    } else {
        1.0
    };
    let n = a.len();
    let tail = ((2.0 / dt) as usize).min(n);
    let final_amp = if tail > 0 {
        let seg = &a[n - tail..];
        let (mn, mx) = seg
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        0.5 * (mx - mn)
    } else {
        0.0
    };
    // Amplitude-dependent frequency: dominant frequency of the large- vs small-amplitude
    // halves (split at the median window amplitude), by zero-crossing counts.
    let freq_shift = {
        let mut amps: Vec<f64> = good.iter().map(|w| w.1).collect();
        if amps.len() >= 6 {
            amps.sort_by(f64::total_cmp);
            let med = amps[amps.len() / 2];
            let zc = |big: bool| -> f64 {
                let mut crossings = 0usize;
                let mut span = 0.0;
                let w = ((1.0 / freq) / dt).round().max(4.0) as usize;
                for (k, wd) in win.iter().enumerate() {
                    if wd.1 <= floor || (wd.1 > med) != big {
                        continue;
                    }
                    let seg = &a[k * w..((k + 1) * w + 1).min(n)];
                    let m = wd.2;
                    crossings += seg
                        .windows(2)
                        .filter(|p| (p[0] - m) * (p[1] - m) < 0.0)
                        .count();
                    span += (seg.len() - 1) as f64 * dt;
                }
                if span > 0.0 {
                    crossings as f64 / (2.0 * span)
                } else {
                    0.0
                }
            };
            let (fl, fs) = (zc(true), zc(false));
            if fl > 0.0 && fs > 0.0 && freq > 0.0 {
                (fl - fs) / freq
            } else {
                0.0
            }
        } else {
            0.0
        }
    };
    let late = &a[n / 2..];
    let mean_late = late.iter().sum::<f64>() / late.len().max(1) as f64;
    Observables {
        freq,
        rate,
        final_amp_deg: final_amp.to_degrees(),
        linear_slope: lin_slope,
        exp_over_lin,
        freq_shift,
        mean_late,
    }
}

/// Flutter speed from growth rates over U: the first sign change from decay to growth
/// (sorted by U), linearly interpolated; `None` when the runs do not bracket it.
pub(crate) fn flutter_speed(points: &[(f64, f64)]) -> Option<f64> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p.windows(2).find_map(|w| {
        let ((u0, s0), (u1, s1)) = (w[0], w[1]);
        (s0 < 0.0 && s1 >= 0.0 && u1 > u0).then(|| u0 + (u1 - u0) * (-s0) / (s1 - s0))
    })
}

/// RK4 substeps per sample that keep the sim's lag states stable: h·ρ ≤ 2.5 with ρ the
/// Gershgorin bound of ∂ẋ/∂x of the linearised law at the run's speed; `None` when more
/// than `max` would be needed (a stiff identified lag root: no simulation).
pub(crate) fn stable_substeps(
    model: &dyn AeroModel,
    rho: f64,
    u: f64,
    dt: f64,
    max: usize,
) -> Option<usize> {
    let lin = aeroelastic::aero::linearize(model, &Flow { rho, u });
    let g = &lin.g;
    let mut bound: f64 = 0.0;
    for i in 0..g.nrows() {
        let row: f64 = (0..g.ncols()).map(|j| g[(i, j)].abs()).sum();
        bound = bound.max(row);
    }
    // Structural modes (a few Hz) need no more than 4 steps per sample at 512 Hz.
    let need = ((bound * dt / 2.5).ceil() as usize).max(4);
    (need <= max).then_some(need)
}

/// Observables of every run, measured and simulated (before/after the best
/// augmentation), the bifurcation diagram, and the simulated response gap.
pub(crate) struct SimResult {
    pub observables: Vec<crate::report::ObservableGap>,
    pub bifurcation: crate::report::Bifurcation,
}

fn point(u: f64, o: &Observables) -> crate::report::BifurcationPoint {
    crate::report::BifurcationPoint {
        wind_speed: u,
        amplitude: o.final_amp_deg,
        frequency: o.freq,
    }
}

/// Simulates every run from its measured state at `i0` with the sim (and with `aug`),
/// and compares observables with the measured ones: pitch frequency \[Hz\], growth rate
/// \[1/s\], final (LCO) amplitude \[deg\] — each as the rms over runs of sim − measured —
/// the response gap rms(α_sim − α_meas)/rms(α_meas) \[-\] (rms over runs), and — when the
/// measured growth rates change sign over U — |flutter speed sim − measured| \[m/s\]
/// ([`flutter_speed`]). Runs whose simulation is not possible (stiff law) or stops early
/// (divergence) are left out of the comparison, and so are controlled records
/// ([`super::control`]: only their measured point is kept); an observable no run (or no bracketing
/// of the flutter speed) supports is left out of the list.
pub(crate) fn compare(
    model: &Arc<dyn AeroModel>,
    rho: f64,
    st: &Structure,
    runs: &[RunResidual],
    aug: Option<&Augment>,
) -> SimResult {
    let mut meas_pts = Vec::new();
    let mut before_pts = Vec::new();
    let mut after_pts = Vec::new();
    // (sum of squares before, after, count before, count after) per observable.
    let mut acc = [[0.0; 4]; 4];
    // (U, growth rate): measured, sim before, sim after.
    let mut rates: [Vec<(f64, f64)>; 3] = Default::default();
    for r in runs {
        let a = &r.q[1][r.i0..];
        let floor = 3.0 * r.sigma[1];
        let om = observables(a, r.dt, floor);
        meas_pts.push(point(r.u, &om));
        // a controlled record is not a free response: its measured point is kept, but it
        // is neither simulated as if free nor part of the measured growth rates
        // (super::control: the feedback law could not be rebuilt)
        if r.control.is_some() {
            continue;
        }
        rates[0].push((r.u, om.rate));
        let run_model = super::residual::run_model(model, r.u, r.k);
        let Some(sub) = stable_substeps(run_model.as_ref(), rho, r.u, r.dt, 64) else {
            continue;
        };
        let rms_meas = (a.iter().map(|v| v * v).sum::<f64>() / a.len().max(1) as f64).sqrt();
        let mut one = |which: usize, aug: Option<&Augment>, pts: &mut Vec<_>| {
            let sim = simulate(model, rho, st, r, aug, sub);
            if sim[1].len() < a.len() {
                return;
            }
            let os = observables(&sim[1], r.dt, floor);
            pts.push(point(r.u, &os));
            rates[1 + which].push((r.u, os.rate));
            let resp = (sim[1]
                .iter()
                .zip(a)
                .map(|(x, y)| (x - y).powi(2))
                .sum::<f64>()
                / a.len() as f64)
                .sqrt()
                / rms_meas.max(f64::MIN_POSITIVE);
            for (k, d) in [
                os.freq - om.freq,
                os.rate - om.rate,
                os.final_amp_deg - om.final_amp_deg,
                resp,
            ]
            .into_iter()
            .enumerate()
            {
                if d.is_finite() {
                    acc[k][which] += d * d;
                    acc[k][2 + which] += 1.0;
                }
            }
        };
        one(0, None, &mut before_pts);
        if aug.is_some() {
            one(1, aug, &mut after_pts);
        }
    }
    let names = [
        ("pitch frequency", "Hz"),
        ("pitch growth rate", "1/s"),
        ("final pitch amplitude", "deg"),
        ("simulated pitch response gap", "-"),
    ];
    let mut observables: Vec<crate::report::ObservableGap> = names
        .iter()
        .zip(acc)
        .map(|(&(name, unit), a)| {
            let rms = |s: f64, n: f64| if n > 0.0 { (s / n).sqrt() } else { f64::NAN };
            let before = rms(a[0], a[2]);
            let after = if aug.is_some() {
                rms(a[1], a[3])
            } else {
                before
            };
            crate::report::ObservableGap {
                name: name.into(),
                level: crate::effect::Level::Structural,
                unit: unit.into(),
                before,
                after,
                shrink: if before > 0.0 && after.is_finite() {
                    1.0 - after.abs() / before.abs()
                } else {
                    0.0
                },
            }
        })
        .collect();
    // Flutter speed: where the growth rate changes sign over U (measured vs sim).
    if let Some(fm) = flutter_speed(&rates[0]) {
        let gap = |k: usize| flutter_speed(&rates[k]).map_or(f64::NAN, |f| (f - fm).abs());
        let before = gap(1);
        let after = if aug.is_some() { gap(2) } else { before };
        observables.push(crate::report::ObservableGap {
            name: "flutter speed".into(),
            level: crate::effect::Level::Structural,
            unit: "m/s".into(),
            before,
            after,
            shrink: if before > 0.0 && after.is_finite() {
                1.0 - after / before
            } else {
                0.0
            },
        });
    }
    // JSON has no NaN: an observable the sims could not give is left out.
    observables.retain(|o| o.before.is_finite() && o.after.is_finite());
    SimResult {
        observables,
        bifurcation: crate::report::Bifurcation {
            measured: meas_pts,
            predicted_before: before_pts,
            predicted_after: after_pts,
        },
    }
}

/// Signature tests on the measured runs (no simulation): amplitude-dependent
/// frequency (largest |relative change| of the FFT pitch frequency between the halves
/// of a run whose amplitude changes ≥ 1.5× between them, both above 20 σ̂_α; threshold
/// 2 %), linear decay (largest exponential-over-linear envelope misfit ratio among
/// decaying runs; threshold 2), mean shift (largest |mean α| of the last half of a run
/// that has decayed below 10 σ̂_α, in standard errors σ̂_α/√n; threshold 5), and
/// whiteness (held-out gap over
/// noise level; threshold: the gap test's).
pub(crate) fn signatures(
    runs: &[RunResidual],
    gap_statistic: f64,
    gap_threshold: f64,
) -> Vec<crate::report::SignatureTest> {
    let mut fshift: f64 = 0.0;
    let mut lin: f64 = 0.0;
    let mut mean_z: f64 = 0.0;
    for r in runs {
        let a = &r.q[1][r.i0..r.i1];
        let n = a.len();
        // Peak deviation from the segment's mean (an offset is not an oscillation).
        let peak = |x: &[f64]| {
            let m = x.iter().sum::<f64>() / x.len().max(1) as f64;
            x.iter().fold(0.0_f64, |p, v| p.max((v - m).abs()))
        };
        let clean = 20.0 * r.sigma[1];
        // Amplitude-dependent frequency: FFT frequency of the first vs the second half
        // of a run whose amplitude changes by ≥ 1.5× between them, both well above noise.
        let (h1, h2) = a.split_at(n / 2);
        let (p1, p2) = (peak(h1), peak(h2));
        if p1.min(p2) > clean && p1.max(p2) > 1.5 * p1.min(p2) {
            let (f1, f2) = (dominant_frequency(h1, r.dt), dominant_frequency(h2, r.dt));
            if f1 > 0.0 && f2 > 0.0 {
                let (fl, fs) = if p1 > p2 { (f1, f2) } else { (f2, f1) };
                let d = (fl - fs) / (0.5 * (fl + fs));
                if d.abs() > fshift.abs() {
                    fshift = d;
                }
            }
        }
        let o3 = observables(a, r.dt, 3.0 * r.sigma[1]);
        if o3.rate < 0.0 && o3.exp_over_lin.is_finite() {
            lin = lin.max(o3.exp_over_lin);
        }
        // Mean shift: runs that have decayed into the noise over their last half; the
        // mean of white noise has standard error σ̂/√n.
        if p2 < 10.0 * r.sigma[1] && r.sigma[1] > 0.0 {
            let mean = h2.iter().sum::<f64>() / h2.len().max(1) as f64;
            mean_z = mean_z.max(mean.abs() / (r.sigma[1] / (h2.len() as f64).sqrt()));
        }
    }
    let sig =
        |name: &str, statistic: f64, threshold: f64, detail: String| crate::report::SignatureTest {
            name: name.into(),
            level: crate::effect::Level::Structural,
            statistic,
            threshold,
            detected: statistic > threshold,
            detail,
        };
    vec![
        sig(
            "amplitude_dependent_frequency",
            fshift.abs(),
            0.02,
            format!("largest relative pitch-frequency change, large- vs small-amplitude half of a run: {fshift:+.4}"),
        ),
        sig(
            "linear_decay",
            lin,
            2.0,
            format!("largest exponential/linear envelope misfit ratio of a decaying run: {lin:.2}"),
        ),
        sig(
            "mean_shift",
            mean_z,
            5.0,
            format!("largest |mean pitch| of a decayed run's last half in standard errors: {mean_z:.1}"),
        ),
        sig(
            "whiteness",
            gap_statistic,
            gap_threshold,
            format!("held-out gap / noise level = {gap_statistic:.3} (1 for a residual at the noise level)"),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn observables_of_a_decaying_sine() {
        let dt = 1.0 / 512.0;
        let a: Vec<f64> = (0..6144)
            .map(|i| {
                let t = i as f64 * dt;
                0.07 * (-0.3 * t).exp() * (2.0 * std::f64::consts::PI * 3.0 * t).cos()
            })
            .collect();
        let o = observables(&a, dt, 1e-4);
        assert!((o.freq - 3.0).abs() < 0.01, "{}", o.freq);
        assert!((o.rate + 0.3).abs() < 0.02, "{}", o.rate);
        assert!(o.exp_over_lin < 0.2, "{}", o.exp_over_lin);
        assert!(o.freq_shift.abs() < 0.02, "{}", o.freq_shift);
        // Linear (friction-like) decay.
        let b: Vec<f64> = (0..6144)
            .map(|i| {
                let t = i as f64 * dt;
                (0.07 - 0.005 * t) * (2.0 * std::f64::consts::PI * 3.0 * t).cos()
            })
            .collect();
        assert!(observables(&b, dt, 1e-4).exp_over_lin > 2.0);
        assert_eq!(
            flutter_speed(&[(3.0, -1.0), (5.0, 1.0), (4.0, -0.5)]),
            Some(4.0 + 1.0 / 3.0)
        );
        assert_eq!(flutter_speed(&[(3.0, -1.0), (5.0, -1.0)]), None);
    }
}
