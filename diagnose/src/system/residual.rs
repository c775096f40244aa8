//! Equation-error residual of the sim along measured free-response runs.
//!
//! For a run with measured motion q = (h, α) the velocities and accelerations come from a
//! Savitzky–Golay smoothing differentiator (q̇ = D q, q̈ = D D q); the sim's aerodynamic
//! forces F(t) = M_a q̈ + f(q, q̇, x) are evaluated along the measured motion, with the
//! model's lag states x integrated along it (RK4, one step per sample, q̇ linearly
//! interpolated; x(0) = 0, i.e. a release from rest) and the nonlinear N* coefficients
//! evaluated at the run's reduced frequency K = Bω/U (ω: dominant pitch frequency of
//! the run). The residual per degree of freedom c (heave, pitch) is
//!
//! r_c(t) = (M_s q̈ + S(C_s q̇ + K_s q − F))_c,
//!
//! with S = D D I I the smoothing the differentiator applies to a true acceleration (every
//! term seen through the same filter; see [`smooth_as_acceleration`]),
//! normalised by the rms of the structural inertial + restoring force
//! (M_s q̈ + C_s q̇ + K_s q)_c of the run over the kept samples (what the aerodynamic force
//! must balance: the metric is the relative equation error). The first `warmup` seconds (lag states) and the Savitzky–Golay edges
//! (2·half-window samples each side, where the asymmetric end windows are less
//! accurate) are trimmed.

use std::sync::{Arc, Mutex};

use aeroelastic::aero::{linearize, AeroModel, Flow};
use aeroelastic::structure::Structure;
use identify::preprocess::{noise_sigma, savitzky_golay_derivative, spectral_peak, PeakSearch};
use identify::record::Record;
use nalgebra::Matrix2;
use num_complex::Complex64;

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// The aerodynamic model of a still-air run (U = 0): no aerodynamic force at all. Any
/// apparent mass of the air is part of the structure a still-air decay measures, so a
/// still-air run tests the structure alone, before any aerodynamics is blamed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StillAir {
    /// Chord B \[m\] (of the model it stands in for).
    pub chord: f64,
}

impl AeroModel for StillAir {
    fn name(&self) -> String {
        "still air".into()
    }
    fn chord(&self) -> f64 {
        self.chord
    }
    fn n_lag(&self) -> usize {
        0
    }
    fn apparent_mass(&self, _flow: &Flow) -> Matrix2<f64> {
        Matrix2::zeros()
    }
    fn forces(&self, _flow: &Flow, _q: [f64; 2], _qd: [f64; 2], _lag: &[f64]) -> [f64; 2] {
        [0.0; 2]
    }
    fn lag_rates(&self, _f: &Flow, _q: [f64; 2], _qd: [f64; 2], _lag: &[f64], _o: &mut [f64]) {}
    fn frequency_response(&self, _flow: &Flow, _omega: f64) -> Matrix2<Complex64> {
        Matrix2::zeros()
    }
}

/// The aerodynamic model of one run: [`StillAir`] at U = 0, else `model` at the run's
/// reduced frequency (or `model` itself when nothing in it depends on K).
pub fn run_model(model: &Arc<dyn AeroModel>, u: f64, k: f64) -> Arc<dyn AeroModel> {
    if u == 0.0 || !k.is_finite() {
        return Arc::new(StillAir {
            chord: model.chord(),
        });
    }
    model
        .with_reduced_frequency(k)
        .unwrap_or_else(|| model.clone())
}

/// Settings of the residual computation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidualSettings {
    /// Savitzky–Golay half window \[samples\].
    pub half_window: usize,
    /// Savitzky–Golay polynomial degree.
    pub order: usize,
    /// Seconds trimmed at the start (aerodynamic start-up transient) besides the SG edges.
    pub warmup: f64,
    /// Seconds of padding of the frequency-domain force evaluation (≥ the memory of the
    /// aerodynamic law).
    pub pad: f64,
}

/// One measured run prepared for the equation-error residual.
#[derive(Debug, Clone)]
pub struct RunResidual {
    /// Case id.
    pub id: String,
    /// Wind speed \[m/s\].
    pub u: f64,
    /// Sample interval \[s\].
    pub dt: f64,
    /// First kept sample.
    pub i0: usize,
    /// One past the last kept sample.
    pub i1: usize,
    /// Measured displacement (h \[m\], α \[rad\]), whole run.
    pub q: [Vec<f64>; 2],
    /// SG velocity, whole run.
    pub qd: [Vec<f64>; 2],
    /// SG acceleration, whole run.
    pub qdd: [Vec<f64>; 2],
    /// Sim aerodynamic forces (L \[N/m\], M \[N·m/m\]) along the measured motion.
    pub force: [Vec<f64>; 2],
    /// Lag states of the sim at sample `i0` (integrated along the measured motion).
    pub lag0: Vec<f64>,
    /// Residual per DOF (kept samples only, index k ↔ sample i0 + k).
    pub r: [Vec<f64>; 2],
    /// Normaliser per DOF: rms of the structural force (M_s q̈ + C_s q̇ + K_s q)_c over
    /// the kept samples.
    pub norm: [f64; 2],
    /// Dominant pitch frequency \[Hz\].
    pub freq: f64,
    /// Reduced frequency K = B·2πf/U the nonlinear terms were evaluated at.
    pub k: f64,
    /// Displacement noise estimates σ̂ (h \[m\], α \[rad\]).
    pub sigma: [f64; 2],
    /// Expected normalised residual energy per sample due to displacement noise, per DOF
    /// (noise level² of the metric).
    pub noise_energy: [f64; 2],
    /// Savitzky–Golay half window \[samples\] and degree of the derivatives.
    pub sg: (usize, usize),
    /// The controller's signal of a controlled record ([`super::control`]); a calibrated
    /// force is already in `r`, a raw one is fitted by the level.
    pub control: Option<RunControl>,
}

impl RunResidual {
    /// Number of kept samples.
    pub fn len(&self) -> usize {
        self.i1 - self.i0
    }

    /// True when no sample is kept.
    pub fn is_empty(&self) -> bool {
        self.i1 <= self.i0
    }

    /// A force series `x` (whole run) as it appears in the residual when it acts on the
    /// structure: through the Savitzky–Golay acceleration q̈ = D D q, i.e. smoothed by
    /// S = D D I I (I: cumulative trapezoidal integral). Smooth series pass unchanged;
    /// a friction step is spread over the differentiator's window, as in the residual.
    /// Returns the kept samples; `None` when the differentiator fails (too short a run).
    pub fn as_acceleration_term(&self, x: &[f64]) -> Option<Vec<f64>> {
        let s = smooth_as_acceleration(x, self.dt, self.sg.0, self.sg.1).ok()?;
        Some(s[self.i0..self.i1].to_vec())
    }

    /// Normalised residual energy per sample, per DOF: mean((r_c/norm_c)²).
    pub fn energy(&self) -> [f64; 2] {
        let n = self.len().max(1) as f64;
        [0, 1].map(|c| self.r[c].iter().map(|v| v * v).sum::<f64>() / (n * self.norm[c].powi(2)))
    }
}

/// The smoothing S = D D I I that the Savitzky–Golay acceleration q̈ = D D q applies to
/// the true acceleration (I: cumulative trapezoidal integral, D: the Savitzky–Golay first
/// derivative with `half_window` samples each side and degree `order`), applied to a
/// whole series `x`. Polynomials up to degree 2 pass unchanged (D is exact on them); a
/// harmonic at ω is scaled by D(ω)²/(iω)², the same factor D D gives a harmonic of q̈.
///
/// # Errors
/// The differentiator's errors (too short a series, a non-finite value, bad settings).
pub fn smooth_as_acceleration(
    x: &[f64],
    dt: f64,
    half_window: usize,
    order: usize,
) -> identify::Result<Vec<f64>> {
    let integ = |v: &[f64]| -> Vec<f64> {
        let mut out = Vec::with_capacity(v.len());
        let mut acc = 0.0;
        out.push(0.0);
        for w in v.windows(2) {
            acc += 0.5 * (w[0] + w[1]) * dt;
            out.push(acc);
        }
        out
    };
    let ii = integ(&integ(x));
    let d1 = savitzky_golay_derivative(&ii, dt, half_window, order)?;
    savitzky_golay_derivative(&d1, dt, half_window, order)
}

/// Dominant frequency \[Hz\] of a free response `x` ([`identify::preprocess::spectral_peak`]
/// with [`PeakSearch::FREE`]: mean removed, rectangular window, bins below two cycles per
/// record ignored); 0 when flat or shorter than 4 samples.
pub fn dominant_frequency(x: &[f64], dt: f64) -> f64 {
    spectral_peak(x, dt, PeakSearch::FREE).unwrap_or(0.0)
}

/// Pass band \[Hz\] of the frequency-domain force evaluation: full up to
/// [`LOWPASS_HZ`].0, cosine taper to zero at [`LOWPASS_HZ`].1.
pub const LOWPASS_HZ: (f64, f64) = (20.0, 30.0);

/// Weight of the low-pass at frequency `f` \[Hz\] (see [`LOWPASS_HZ`]).
fn lowpass(f: f64) -> f64 {
    let (a, b) = LOWPASS_HZ;
    if f <= a {
        1.0
    } else if f >= b {
        0.0
    } else {
        0.5 + 0.5 * (std::f64::consts::PI * (f - a) / (b - a)).cos()
    }
}

/// Forces of `model` along a measured motion (see the module docs): the linear part
/// from the model's *frequency response* H(ω) (the identified derivative table itself,
/// not its time-domain rational approximation, whose fitted lag roots can be stiff and
/// whose coefficients can cancel by orders of magnitude), applied by FFT to the motion
/// extended by `pad` samples of rest (q = 0) before — the wake starts at release, as with
/// lag states x(0) = 0; a held pre-release position would put a large low-frequency
/// component into the padding, where an identified table's H(ω) is extrapolated — and by
/// its tapered even reflection after; plus the
/// nonlinear remainder f(q, q̇, 0) − K_q q − C_q q̇ in the time domain (exact for a
/// linear model plus polynomial terms, which is what an identified law is). The linear
/// part is low-passed ([`LOWPASS_HZ`], far above the rig's modes and their first
/// harmonics): H(ω) of a law with apparent mass grows like ω², and applied to raw
/// displacements it would turn sensor noise near the Nyquist frequency into a residual
/// far above the signal.
pub fn forces_along(
    model: &dyn AeroModel,
    flow: &Flow,
    q: &[Vec<f64>; 2],
    qd: &[Vec<f64>; 2],
    dt: f64,
    pad: usize,
) -> [Vec<f64>; 2] {
    let n = q[0].len();
    let nfft = (n + 2 * pad).next_power_of_two();
    // planned once per process and length and shared (`forces_along` runs a few hundred
    // times per diagnosis on a few lengths; planning was a quarter of its time, DECISIONS
    // round 32): the plan a fresh planner makes, bit for bit
    let (fwd, inv) = fft::forward_and_inverse(nfft);
    let mut spec: [Vec<Complex64>; 2] = [fwd.make_output_vec(), fwd.make_output_vec()];
    for j in 0..2 {
        let mut buf = fwd.make_input_vec();
        // After the run: its even reflection about the last sample, tapered to zero over
        // at most `pad` samples (an oscillation under a slow taper has little
        // low-frequency content; the table's H(ω) at ω → 0 is the least reliable part).
        let m = (nfft - pad - n).min(pad).min(n - 1).max(1);
        for (k, v) in buf.iter_mut().enumerate() {
            *v = if k < pad {
                0.0
            } else if k < pad + n {
                q[j][k - pad]
            } else if k - pad - n < m {
                let s = k - pad - n + 1;
                let w = 0.5 + 0.5 * (std::f64::consts::PI * s as f64 / m as f64).cos();
                q[j][n - 1 - s] * w
            } else {
                0.0
            };
        }
        // The FFT only fails on a length mismatch (a bug).
        fwd.process(&mut buf, &mut spec[j]).expect("FFT length");
    }
    let nb = spec[0].len();
    let mut out_spec = [fwd.make_output_vec(), fwd.make_output_vec()];
    for m in 0..nb {
        let f = m as f64 / (nfft as f64 * dt);
        let lp = lowpass(f);
        if lp == 0.0 {
            for o in out_spec.iter_mut() {
                o[m] = Complex64::new(0.0, 0.0);
            }
            continue;
        }
        let w = 2.0 * std::f64::consts::PI * f;
        let h = model.frequency_response(flow, w);
        for c in 0..2 {
            let mut v = (h[(c, 0)] * spec[0][m] + h[(c, 1)] * spec[1][m]) * lp;
            if m == 0 || m + 1 == nb {
                v = Complex64::new(v.re, 0.0);
            }
            out_spec[c][m] = v;
        }
    }
    let lin = linearize(model, flow);
    let zeros = vec![0.0; model.n_lag()];
    let mut out = [vec![0.0; n], vec![0.0; n]];
    for c in 0..2 {
        let mut buf = inv.make_output_vec();
        inv.process(&mut out_spec[c], &mut buf).expect("FFT length");
        for i in 0..n {
            out[c][i] = buf[pad + i] / nfft as f64;
        }
    }
    for i in 0..n {
        let qi = [q[0][i], q[1][i]];
        let qdi = [qd[0][i], qd[1][i]];
        let f = model.forces(flow, qi, qdi, &zeros);
        for c in 0..2 {
            let l = lin.k_q[(c, 0)] * qi[0]
                + lin.k_q[(c, 1)] * qi[1]
                + lin.c_q[(c, 0)] * qdi[0]
                + lin.c_q[(c, 1)] * qdi[1];
            out[c][i] += f[c] - l;
        }
    }
    out
}

fn sg(x: &[f64], dt: f64, s: &ResidualSettings, id: &str, what: &str) -> Result<Vec<f64>> {
    savitzky_golay_derivative(x, dt, s.half_window, s.order)
        .map_err(|e| Error::identify(format!("free run `{id}`: derivative of {what}"), e))
}

/// Structural residual per DOF over a whole run, with every term seen through the same
/// differentiator:
///
/// r = M_s q̈ + S(C_s q̇ + K_s q − F),  q̈ = D D q,
///
/// where S = D D I I ([`smooth_as_acceleration`]) is what D D does to a true
/// acceleration. The equation of motion M_s q̈ + C_s q̇ + K_s q = F holds for the true
/// motion; seen through S it holds for the measured one, so what the differentiator
/// attenuates (with the default 0.05-s window at 512 Hz: 0.02 % at 1.5 Hz, 1.5 % at
/// 4.5 Hz, a limit cycle's third harmonic) is attenuated in every term alike and an exact
/// model leaves no residual beyond the noise. Evaluating the terms other than M_s q̈
/// unsmoothed leaves M_s (D D − 1) q̈, which on a large limit cycle (small noise next to
/// the motion) is several times the noise level: 7.0× → 1.35× on an 8° cycle of the
/// exact model (DECISIONS, "A residual consistent with its differentiator").
fn residual_series(
    st: &Structure,
    q: &[Vec<f64>; 2],
    qd: &[Vec<f64>; 2],
    qdd: &[Vec<f64>; 2],
    f: &[Vec<f64>; 2],
    dt: f64,
    s: &ResidualSettings,
) -> identify::Result<[Vec<f64>; 2]> {
    let (ms, cs, ks) = (st.mass_matrix(), st.damping_matrix(), st.stiffness_matrix());
    let n = q[0].len();
    let mut out = [vec![0.0; n], vec![0.0; n]];
    for (c, o) in out.iter_mut().enumerate() {
        let rest: Vec<f64> = (0..n)
            .map(|i| {
                (0..2)
                    .map(|j| cs[(c, j)] * qd[j][i] + ks[(c, j)] * q[j][i])
                    .sum::<f64>()
                    - f[c][i]
            })
            .collect();
        let smooth = smooth_as_acceleration(&rest, dt, s.half_window, s.order)?;
        for (i, v) in o.iter_mut().enumerate() {
            *v = ms[(c, 0)] * qdd[0][i] + ms[(c, 1)] * qdd[1][i] + smooth[i];
        }
    }
    Ok(out)
}

/// Prepares one free run: derivatives, sim forces, residual, normalisers, noise level.
///
/// # Errors
/// [`Error::Data`] naming the data set and run when the run is too short for the
/// trimming, has (nearly) no motion, or has unequal h and α lengths; wrapped identify
/// errors from the differentiator.
pub fn prepare_run(
    dataset: &str,
    rec: &Record,
    model: &Arc<dyn AeroModel>,
    rho: f64,
    st: &Structure,
    s: &ResidualSettings,
) -> Result<RunResidual> {
    prepare_run_with(dataset, rec, model, rho, st, s, None)
}

/// What [`prepare_run`] computes from the measured motion alone, whatever the model: the
/// Savitzky–Golay velocity and acceleration (whole run), the dominant pitch frequency
/// \[Hz\] of the kept samples and the displacement noise estimates σ̂ (h \[m\], α \[rad\]).
#[derive(Debug)]
pub(crate) struct RunKinematics {
    qd: [Vec<f64>; 2],
    qdd: [Vec<f64>; 2],
    freq: f64,
    sigma: [f64; 2],
}

/// What a [`RunKinematics`] was computed with: (half window, degree, i0, i1, dt bits).
type KinematicsKey = (usize, usize, usize, usize, u64);

/// One free run's [`RunKinematics`], computed by the first preparation of the run that
/// needs them and shared by every later one with the same settings (one free-response
/// diagnosis prepares each run once per aerodynamic model: the sim's law with two table
/// extrapolations and each of their jackknife laws, twelve times on issue 43's job,
/// DECISIONS round 32). The values are those a fresh computation gives, bit for bit.
#[derive(Debug, Default)]
pub(crate) struct KinematicsSlot(Mutex<Option<(KinematicsKey, Arc<RunKinematics>)>>);

impl KinematicsSlot {
    /// The kinematics for `key`: the stored ones when computed with the same key, else
    /// `compute()` (stored on success; the slot's lock is held meanwhile, so a preparation
    /// of the same run on another thread waits for them instead of computing them again).
    fn get_or_compute(
        &self,
        key: KinematicsKey,
        compute: impl FnOnce() -> Result<RunKinematics>,
    ) -> Result<Arc<RunKinematics>> {
        let Ok(mut slot) = self.0.lock() else {
            return compute().map(Arc::new);
        };
        if let Some((k, kin)) = slot.as_ref() {
            if *k == key {
                return Ok(kin.clone());
            }
        }
        let kin = Arc::new(compute()?);
        *slot = Some((key, kin.clone()));
        Ok(kin)
    }
}

/// [`prepare_run`] with the run's model-independent part taken from (or stored in) `kin`
/// when given (see [`KinematicsSlot`]); the result is the same with or without it.
///
/// # Errors
/// As [`prepare_run`].
pub(crate) fn prepare_run_with(
    dataset: &str,
    rec: &Record,
    model: &Arc<dyn AeroModel>,
    rho: f64,
    st: &Structure,
    s: &ResidualSettings,
    kin: Option<&KinematicsSlot>,
) -> Result<RunResidual> {
    let id = rec.meta.id.as_str();
    let n = rec.len();
    let dt = rec.dt;
    if rec.h.len() != n {
        return Err(Error::data(
            dataset,
            format!("free run `{id}`: h has {} samples, alpha {n}", rec.h.len()),
        ));
    }
    let edge = 2 * s.half_window;
    let i0 = edge.max((s.warmup / dt).ceil() as usize);
    let min_kept = 4 * (2 * s.half_window + 1);
    if n < i0 + edge + min_kept {
        return Err(Error::data(
            dataset,
            format!(
                "free run `{id}` is too short: {n} samples ({:.3} s); the residual needs at \
                 least {} (warm-up {i0}, edge {edge}, {min_kept} kept)",
                n as f64 * dt,
                i0 + edge + min_kept
            ),
        ));
    }
    let i1 = n - edge;
    let u = rec.meta.wind_speed;
    if !(u.is_finite() && u >= 0.0) {
        return Err(Error::data(
            dataset,
            format!("free run `{id}`: wind speed {u} m/s must be >= 0"),
        ));
    }
    let q = [rec.h.clone(), rec.alpha.clone()];
    let compute = || -> Result<RunKinematics> {
        let qd = [sg(&q[0], dt, s, id, "h")?, sg(&q[1], dt, s, id, "alpha")?];
        let qdd = [
            sg(&qd[0], dt, s, id, "h_dot")?,
            sg(&qd[1], dt, s, id, "alpha_dot")?,
        ];
        Ok(RunKinematics {
            freq: dominant_frequency(&q[1][i0..i1], dt),
            sigma: [noise_sigma(&q[0]), noise_sigma(&q[1])],
            qd,
            qdd,
        })
    };
    let kin = match kin {
        Some(slot) => {
            slot.get_or_compute((s.half_window, s.order, i0, i1, dt.to_bits()), compute)?
        }
        None => Arc::new(compute()?),
    };
    let (qd, qdd, freq) = (kin.qd.clone(), kin.qdd.clone(), kin.freq);
    let b = model.chord();
    // still air (U = 0): K = Bω/U is infinite and the run has no aerodynamic force
    let k = if u == 0.0 {
        f64::INFINITY
    } else if freq > 0.0 {
        b * 2.0 * std::f64::consts::PI * freq / u
    } else {
        1.0
    };
    let run_model = run_model(model, u, k);
    let flow = Flow { rho, u };
    let pad = (s.pad / dt).ceil() as usize;
    let force = forces_along(run_model.as_ref(), &flow, &q, &qd, dt, pad);
    let lag0 = vec![0.0; run_model.n_lag()];
    let control = run_control(dataset, rec, &q, dt, s, (i0, i1))?;
    // a calibrated control force acts on the heave DOF like the lift
    let mut applied = force.clone();
    if let Some(c) = rec.control.as_ref().filter(|c| c.calibrated) {
        for (f, u) in applied[0].iter_mut().zip(&c.values) {
            *f += u;
        }
    }
    let whole = residual_series(st, &q, &qd, &qdd, &applied, dt, s)
        .map_err(|e| Error::identify(format!("free run `{id}`: residual smoothing"), e))?;
    let r = whole.map(|w| w[i0..i1].to_vec());
    let mut ss = [0.0; 2];
    let (ms, cs, ks) = (st.mass_matrix(), st.damping_matrix(), st.stiffness_matrix());
    for i in i0..i1 {
        for (c, sc) in ss.iter_mut().enumerate() {
            // in still air the structural force *is* the residual (no aerodynamic force
            // balances it), so the run is normalised by its elastic force K_s q instead:
            // the force the inertia must balance
            let sf = (0..2)
                .map(|j| {
                    let elastic = ks[(c, j)] * q[j][i];
                    if u == 0.0 {
                        elastic
                    } else {
                        ms[(c, j)] * qdd[j][i] + cs[(c, j)] * qd[j][i] + elastic
                    }
                })
                .sum::<f64>();
            *sc += sf * sf;
        }
    }
    let norm = ss.map(|v| (v / (i1 - i0) as f64).sqrt());
    for (c, name) in ["heave", "pitch"].iter().enumerate() {
        if !(norm[c] > 0.0 && norm[c].is_finite()) {
            return Err(Error::data(
                dataset,
                format!(
                    "free run `{id}`: no {name} motion (rms structural force {})",
                    norm[c]
                ),
            ));
        }
    }
    let sigma = kin.sigma;
    let kernels = noise_kernels(run_model.as_ref(), &flow, st, s, dt, id)?;
    let noise_energy = [0, 1].map(|c| {
        (sigma[0].powi(2) * kernels[c][0] + sigma[1].powi(2) * kernels[c][1]) / norm[c].powi(2)
    });
    Ok(RunResidual {
        id: id.to_string(),
        u,
        dt,
        i0,
        i1,
        q,
        qd,
        qdd,
        force,
        lag0,
        r,
        norm,
        freq,
        k,
        sigma,
        noise_energy,
        sg: (s.half_window, s.order),
        control,
    })
}

/// The control signal of a controlled record prepared for the residual: S(u) over the
/// kept samples `keep` and, with a heave target, the PD law reconstructed from it
/// ([`pd_law`]).
///
/// # Errors
/// [`Error::Data`] naming the data set and run when the signal or the target has another
/// length than the record; wrapped identify errors from the differentiator.
fn run_control(
    dataset: &str,
    rec: &Record,
    q: &[Vec<f64>; 2],
    dt: f64,
    s: &ResidualSettings,
    keep: (usize, usize),
) -> Result<Option<RunControl>> {
    let Some(c) = &rec.control else {
        return Ok(None);
    };
    let id = rec.meta.id.as_str();
    let n = q[0].len();
    let (i0, i1) = keep;
    for (what, len) in [
        ("control signal", Some(c.values.len())),
        ("h_target", c.h_target.as_ref().map(Vec::len)),
    ] {
        if let Some(len) = len.filter(|&l| l != n) {
            return Err(Error::data(
                dataset,
                format!("free run `{id}`: the {what} has {len} samples, the motion {n}"),
            ));
        }
    }
    let su = smooth_as_acceleration(&c.values, dt, s.half_window, s.order)
        .map_err(|e| Error::identify(format!("free run `{id}`: control signal smoothing"), e))?;
    let pd = match &c.h_target {
        Some(t) => {
            let e: Vec<f64> = t.iter().zip(&q[0]).map(|(a, b)| a - b).collect();
            let ed = sg(&e, dt, s, id, "h_target - h")?;
            pd_law(&c.values[i0..i1], &e[i0..i1], &ed[i0..i1])
        }
        None => None,
    };
    Ok(Some(RunControl {
        calibrated: c.calibrated,
        column: su[i0..i1].to_vec(),
        pd,
    }))
}

/// Squared ℓ² norms ‖k_cj‖² of the residual operator's impulse responses from white
/// displacement noise on DOF j to the residual of DOF c (interior of a run): the expected
/// residual energy per sample is Σ_j σ_j² ‖k_cj‖². Computed by passing an impulse of
/// 1e-7 (m or rad; small enough that nonlinear terms do not matter) through the same
/// differentiator, lag integration and residual.
fn noise_kernels(
    model: &dyn AeroModel,
    flow: &Flow,
    st: &Structure,
    s: &ResidualSettings,
    dt: f64,
    id: &str,
) -> Result<[[f64; 2]; 2]> {
    let m = s.half_window;
    // Lag memory: the impulse's lag response decays within ~2 s for any sensible law;
    // its energy is small next to the q̈ term anyway.
    let tail = (2.0 / dt).ceil() as usize;
    let n = 8 * m + 4 + tail;
    let at = 4 * m + 2;
    let eps = 1e-7;
    let mut out = [[0.0; 2]; 2];
    for j in 0..2 {
        let mut q = [vec![0.0; n], vec![0.0; n]];
        q[j][at] = eps;
        let qd = [
            sg(&q[0], dt, s, id, "noise kernel")?,
            sg(&q[1], dt, s, id, "noise kernel")?,
        ];
        let qdd = [
            sg(&qd[0], dt, s, id, "noise kernel")?,
            sg(&qd[1], dt, s, id, "noise kernel")?,
        ];
        let f = forces_along(model, flow, &q, &qd, dt, (s.pad / dt).ceil() as usize);
        let r = residual_series(st, &q, &qd, &qdd, &f, dt, s)
            .map_err(|e| Error::identify(format!("free run `{id}`: noise kernel"), e))?;
        for (o, rc) in out.iter_mut().zip(&r) {
            o[j] += rc[2 * m..n - 2 * m]
                .iter()
                .map(|v| (v / eps).powi(2))
                .sum::<f64>();
        }
    }
    Ok(out)
}

/// The control signal of one prepared run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunControl {
    /// `true`: a calibrated force (already in the residual); `false`: a raw signal whose
    /// gain and offset the level fits.
    pub calibrated: bool,
    /// The signal as it enters the residual, S(u) over the kept samples (raw units, or N/m
    /// when calibrated).
    pub column: Vec<f64>,
    /// The feedback law reconstructed from the heave target, when the record has one.
    pub pd: Option<PdLaw>,
}

/// A proportional-derivative law reconstructed from a controlled record:
/// u = k_p·(h_target − h) + k_d·(ḣ_target − ḣ) + c, least squares over the kept samples
/// (derivatives by the run's Savitzky–Golay differentiator).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PdLaw {
    /// Proportional gain \[signal units per m\].
    pub kp: f64,
    /// Derivative gain \[signal units per m/s\].
    pub kd: f64,
    /// Constant \[signal units\].
    pub offset: f64,
    /// Share of the signal's variance the law reproduces, 1 − SSR/SST.
    pub r2: f64,
}

/// Reconstructs u = k_p·e + k_d·ė + c with e = h_target − h over the kept samples of a run
/// (ė by the differentiator `d`); `None` when singular or flat.
pub(crate) fn pd_law(u: &[f64], e: &[f64], e_dot: &[f64]) -> Option<PdLaw> {
    let n = u.len();
    if n < 4 || e.len() != n || e_dot.len() != n {
        return None;
    }
    let x = |i: usize| [e[i], e_dot[i], 1.0];
    let mut g = [0.0; 9];
    let mut b = [0.0; 3];
    for (i, &ui) in u.iter().enumerate() {
        let xi = x(i);
        for a in 0..3 {
            b[a] += xi[a] * ui;
            for c in 0..3 {
                g[a * 3 + c] += xi[a] * xi[c];
            }
        }
    }
    let th = crate::numerics::ridge_solve(|i, j| g[i * 3 + j], &b, 1e-10)?;
    let mean = u.iter().sum::<f64>() / n as f64;
    let sst: f64 = u.iter().map(|v| (v - mean).powi(2)).sum();
    let ssr: f64 = (0..n)
        .map(|i| {
            let xi = x(i);
            (u[i] - th[0] * xi[0] - th[1] * xi[1] - th[2]).powi(2)
        })
        .sum();
    (sst > 0.0).then(|| PdLaw {
        kp: th[0],
        kd: th[1],
        offset: th[2],
        r2: 1.0 - ssr / sst,
    })
}

/// Each run's weight in the level's pooled energies (issue 42 item 5, round 29): 1 for a
/// run in the wind, 0 for a still-air run (U = 0) when some run is in the wind; 1 for
/// every run otherwise. Still-air decays are judged by the structure check
/// (`crate::structure`: frequencies, damping, backbone against the given structure) and
/// inform the structural candidates' fits, but stay out of the flow effects' gap test: a
/// decay sinks into its noise within the record, its normalised noise energy is about ten
/// times a limit cycle's, and pooled by a plain mean it set both the null and the gap
/// (null ×3.8, gap statistic 2.1 → 1.15 on the plate rig). Weighting every run by the
/// inverse of its own noise energy was tried and moved covered effects to
/// `extrapolation` on sets without any still-air run (docs/DECISIONS.md, round 29).
pub(crate) fn run_weights(runs: &[RunResidual]) -> Vec<f64> {
    let in_wind = runs.iter().any(|r| r.u > 0.0);
    runs.iter()
        .map(|r| if in_wind && r.u <= 0.0 { 0.0 } else { 1.0 })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Savitzky–Golay acceleration of a two-harmonic motion is biased (its third
    /// harmonic sits where the differentiator attenuates), but it equals the true
    /// acceleration seen through [`smooth_as_acceleration`]: the filter the residual puts on
    /// every other term.
    #[test]
    fn smoothing_matches_the_differentiators_acceleration() {
        let (dt, hw, order) = (1.0 / 512.0, 25, 4);
        let (w1, w3) = (
            2.0 * std::f64::consts::PI * 3.0,
            2.0 * std::f64::consts::PI * 9.0,
        );
        let n = 4096;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let q: Vec<f64> = t
            .iter()
            .map(|t| (w1 * t).sin() + 0.3 * (w3 * t).sin())
            .collect();
        let qdd_true: Vec<f64> = t
            .iter()
            .map(|t| -w1 * w1 * (w1 * t).sin() - 0.3 * w3 * w3 * (w3 * t).sin())
            .collect();
        let d1 = savitzky_golay_derivative(&q, dt, hw, order).unwrap();
        let dd = savitzky_golay_derivative(&d1, dt, hw, order).unwrap();
        let s = smooth_as_acceleration(&qdd_true, dt, hw, order).unwrap();
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        let inner = 4 * hw..n - 4 * hw;
        let bias: Vec<f64> = inner.clone().map(|i| dd[i] - qdd_true[i]).collect();
        let left: Vec<f64> = inner.clone().map(|i| dd[i] - s[i]).collect();
        let scale = rms(&qdd_true[inner]);
        // the differentiator's own bias: 17 % of the acceleration rms (the 9 Hz harmonic)
        assert!(rms(&bias) > 0.1 * scale, "bias {}", rms(&bias) / scale);
        // seen through the same filter it is gone, to the trapezoid rule's O((ω dt)²):
        // 0.9 % of the bias
        assert!(
            rms(&left) < 0.02 * rms(&bias),
            "left {}",
            rms(&left) / rms(&bias)
        );
    }
}
