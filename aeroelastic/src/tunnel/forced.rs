//! Forced-motion records: the options ([`ForcedOptions`]) with the still-air runs and the
//! rig's mass ([`StillAir`], [`RigMass`]), the aerodynamic forces along a prescribed motion
//! with the lag states on their periodic solution ([`forced_forces`]), one record
//! ([`forced_record`]) and a whole data set in parallel ([`forced_dataset`]).

use std::sync::atomic::{AtomicUsize, Ordering};

use identify::dataset::{CaseSpec, Manifest, Units};
use identify::record::{CaseKind, Record, SectionGeometry};
use nalgebra::{DMatrix, DVector, Matrix2};
use num_complex::Complex64;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::noise::{add_noise, peak};
use super::write::{check_ids, manifest_extra, tidy};
use super::{case_seed, paper_units, ForcedCase, Motion, SensorNoise, TunnelProgress};
use crate::aero::{linearize, AeroModel, Flow};
use crate::error::{non_negative, positive};
use crate::integrate::{OdeSystem, Rk4};
use crate::{Error, Result};

/// Mass properties of the moving model per unit span (inertial balance forces).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RigMass {
    /// Mass m \[kg/m\].
    pub mass: f64,
    /// Pitch inertia about the elastic axis I \[kg·m²/m\].
    pub inertia: f64,
    /// Static unbalance S \[kg·m/m\], + when the mass centre is aft of the elastic axis.
    pub static_unbalance: f64,
}

impl RigMass {
    /// A uniform plate of total mass `mass_total` \[kg\] over `span` \[m\], chord `chord` \[m\],
    /// elastic axis at mid-chord: m = mass/span, I = m B²/12, S = 0 (the paper's 0.82 kg,
    /// 0.75 m, 0.25 m plate: m = 1.0933 kg/m, I = 5.694e-3 kg·m²/m).
    pub fn uniform_plate(mass_total: f64, span: f64, chord: f64) -> Self {
        let m = mass_total / span;
        RigMass {
            mass: m,
            inertia: m * chord * chord / 12.0,
            static_unbalance: 0.0,
        }
    }

    fn matrix(&self) -> Matrix2<f64> {
        Matrix2::new(
            self.mass,
            self.static_unbalance,
            self.static_unbalance,
            self.inertia,
        )
    }
}

/// Still-air runs (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct StillAir {
    /// Mass properties of the moving model.
    pub rig: RigMass,
    /// Add the model's U-independent apparent-mass forces M_a q̈ to the still-air run (as
    /// physics does); off by default.
    pub apparent_mass: bool,
    /// Half the largest random time offset of the still-air run \[s\].
    pub max_offset: f64,
}

/// Options of forced-motion records.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ForcedOptions {
    /// Data-set name.
    pub name: String,
    /// Section geometry and air (chord must equal the model's).
    pub section: SectionGeometry,
    /// Sampling rate \[Hz\].
    pub rate: f64,
    /// Record duration \[s\].
    pub duration: f64,
    /// Sensor noise.
    pub noise: SensorNoise,
    /// Still-air runs, if any.
    pub still_air: Option<StillAir>,
    /// Extra integration before recording \[s\] (0: start on the periodic solution).
    pub pre_roll: f64,
    /// Master seed.
    pub seed: u64,
    /// Units of the written CSV files.
    pub units: Units,
}

impl ForcedOptions {
    /// The paper's rig: B = 0.25 m, span 0.75 m, ρ = 1.225, 512 Hz, 10 s, paper noise, no
    /// still-air runs, units mm / deg / N / N·m (totals over the span).
    pub fn paper(seed: u64) -> Self {
        ForcedOptions {
            name: "virtual wind tunnel: forced motion".into(),
            section: SectionGeometry {
                chord: 0.25,
                span: 0.75,
                air_density: 1.225,
            },
            rate: 512.0,
            duration: 10.0,
            noise: SensorNoise::paper(),
            still_air: None,
            pre_roll: 0.0,
            seed,
            units: paper_units(),
        }
    }

    /// Still-air runs with the paper's plate (0.82 kg uniform plate over the span) and
    /// offsets up to 1 s.
    pub fn with_paper_still_air(mut self) -> Self {
        self.still_air = Some(StillAir {
            rig: RigMass::uniform_plate(0.82, self.section.span, self.section.chord),
            apparent_mass: false,
            max_offset: 0.5,
        });
        self
    }

    fn check(&self, model_chord: f64) -> Result<()> {
        positive("section.chord", self.section.chord)?;
        positive("section.span", self.section.span)?;
        positive("section.air_density", self.section.air_density)?;
        positive("rate", self.rate)?;
        positive("duration", self.duration)?;
        non_negative("pre_roll", self.pre_roll)?;
        self.noise.check()?;
        if (model_chord - self.section.chord).abs() > 1e-9 * self.section.chord {
            return Err(Error::param(
                "section.chord",
                self.section.chord,
                format!("differs from the model's chord {model_chord}"),
            ));
        }
        if let Some(s) = &self.still_air {
            positive("still_air.rig.mass", s.rig.mass)?;
            positive("still_air.rig.inertia", s.rig.inertia)?;
            crate::error::finite("still_air.rig.static_unbalance", s.rig.static_unbalance)?;
            non_negative("still_air.max_offset", s.max_offset)?;
        }
        Ok(())
    }
}

/// Lag state on the periodic solution of the linearised lag dynamics at time t.
fn periodic_lag_state(
    model: &dyn AeroModel,
    flow: &Flow,
    motion: &Motion,
    t: f64,
    case: &str,
) -> Result<Vec<f64>> {
    let n = model.n_lag();
    let mut x = vec![0.0; n];
    if n == 0 {
        return Ok(x);
    }
    let lin = linearize(model, flow);
    let sing = || Error::numerical(format!("case {case}"), "singular lag dynamics (iωI − G)");
    for (j, comps) in [&motion.heave, &motion.pitch].into_iter().enumerate() {
        for s in comps {
            let w = 2.0 * std::f64::consts::PI * s.freq;
            let iw = Complex64::new(0.0, w);
            let mut a = DMatrix::<Complex64>::zeros(n, n);
            let mut rhs = DVector::<Complex64>::zeros(n);
            let amp = Complex64::from_polar(s.amplitude, s.phase);
            for r in 0..n {
                for c in 0..n {
                    a[(r, c)] = Complex64::new(-lin.g[(r, c)], 0.0);
                }
                a[(r, r)] += iw;
                rhs[r] = (lin.e[(r, j)] + iw * lin.f[(r, j)]) * amp;
            }
            let xh = a.lu().solve(&rhs).ok_or_else(sing)?;
            let e = Complex64::from_polar(1.0, w * t);
            for r in 0..n {
                x[r] += (xh[r] * e).im;
            }
        }
    }
    if motion.mean_pitch != 0.0 {
        let g = lin.g.clone();
        let rhs = -lin.e.column(1) * motion.mean_pitch;
        let xs = g.lu().solve(&rhs).ok_or_else(sing)?;
        for r in 0..n {
            x[r] += xs[r];
        }
    }
    Ok(x)
}

/// Infinity norm of the linearised lag matrix G (bounds its eigenvalues).
fn lag_rate_bound(model: &dyn AeroModel, flow: &Flow) -> f64 {
    if model.n_lag() == 0 {
        return 0.0;
    }
    let lin = linearize(model, flow);
    (0..lin.g.nrows())
        .map(|r| lin.g.row(r).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// The model's lag dynamics ẋ = g(q(t), q̇(t), x) along a prescribed motion.
struct PrescribedLag<'a> {
    model: &'a dyn AeroModel,
    flow: &'a Flow,
    motion: &'a Motion,
    n: usize,
}

impl OdeSystem for PrescribedLag<'_> {
    fn dim(&self) -> usize {
        self.n
    }
    fn rate(&self, t: f64, x: &[f64], dx: &mut [f64]) {
        let (q, qd, _) = self.motion.eval(t);
        self.model.lag_rates(self.flow, q, qd, x, dx);
    }
}

/// Aerodynamic forces (L, M) [N/m, N·m/m] of `model` along prescribed `motion` at the
/// sample times t_i = t_start + i·dt (i < n), lag states started on the periodic solution
/// at t_start − pre_roll. Returns (lift, moment).
///
/// # Errors
/// [`Error::Numerical`] when the lag dynamics are singular at a forcing frequency.
#[allow(clippy::too_many_arguments)]
pub fn forced_forces(
    model: &dyn AeroModel,
    flow: &Flow,
    motion: &Motion,
    t_start: f64,
    dt: f64,
    n: usize,
    pre_roll: f64,
    case: &str,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let nl = model.n_lag();
    let t0 = t_start - pre_roll;
    let mut x = periodic_lag_state(model, flow, motion, t0, case)?;
    let w_max = motion
        .pitch
        .iter()
        .chain(&motion.heave)
        .map(|s| 2.0 * std::f64::consts::PI * s.freq)
        .fold(0.0, f64::max);
    let rate = lag_rate_bound(model, flow).max(w_max);
    let n_sub = ((dt * rate / 0.05).ceil() as usize).max(2);
    let h = dt / n_sub as f64;
    let lag = PrescribedLag {
        model,
        flow,
        motion,
        n: nl,
    };
    let mut rk = Rk4::new(nl);
    let mut step = |x: &mut Vec<f64>, t: f64| {
        if nl > 0 {
            rk.step(&lag, t, h, x);
        }
    };
    let n_pre = (pre_roll / h).round() as usize;
    let mut t = t0;
    for _ in 0..n_pre {
        step(&mut x, t);
        t += h;
    }
    let ma = model.apparent_mass(flow);
    let mut lift = Vec::with_capacity(n);
    let mut moment = Vec::with_capacity(n);
    for i in 0..n {
        let ti = t_start + i as f64 * dt;
        let (q, qd, qdd) = motion.eval(ti);
        let f = model.forces(flow, q, qd, &x);
        lift.push(f[0] + ma[(0, 0)] * qdd[0] + ma[(0, 1)] * qdd[1]);
        moment.push(f[1] + ma[(1, 0)] * qdd[0] + ma[(1, 1)] * qdd[1]);
        if i + 1 < n {
            for s in 0..n_sub {
                step(&mut x, ti + s as f64 * h);
            }
        }
    }
    Ok((lift, moment))
}

/// Refuses aerodynamic forces (L, M) [N/m, N·m/m], sampled every `dt` \[s\] from t = 0,
/// whose coefficients C_L = L/(½ρU²B), C_M = M/(½ρU²B²) (`chord` B \[m\]) are not finite or
/// exceed [`identify::limits::MAX_FORCE_COEFFICIENT`] in magnitude: a model whose
/// nonlinear terms blow up along the motion would otherwise write forces that no reader
/// accepts (issue 27, row 15).
///
/// # Errors
/// [`Error::InvalidParameter`] naming `case.lift` or `case.moment` with the first offending
/// coefficient and its time.
fn check_force_coefficients(
    case: &str,
    flow: &Flow,
    chord: f64,
    dt: f64,
    lift: &[f64],
    moment: &[f64],
) -> Result<()> {
    use identify::limits::{show, MAX_FORCE_COEFFICIENT as MAX};
    let q = 0.5 * flow.rho * flow.u * flow.u;
    let channels = [
        ("lift", "C_L", lift, q * chord),
        ("moment", "C_M", moment, q * chord * chord),
    ];
    for (channel, symbol, forces, scale) in channels {
        let bad = forces.iter().enumerate().find(|(_, &f)| {
            let c = f / scale;
            !(c.is_finite() && c.abs() <= MAX)
        });
        if let Some((i, &f)) = bad {
            return Err(Error::param(
                format!("{case}.{channel}"),
                f / scale,
                format!(
                    "case `{case}`, {channel} at t = {} s: |{symbol}| must be finite and ≤ {} \
                     (identify::limits::MAX_FORCE_COEFFICIENT); the model's forces blow up \
                     along this motion (check its nonlinear terms), nothing was written",
                    show(i as f64 * dt),
                    show(MAX)
                ),
            ));
        }
    }
    Ok(())
}

/// Manifest case of a forced case (descriptors in the manifest's units).
fn forced_spec(case: &ForcedCase, units: &Units, still: bool) -> CaseSpec {
    let mut spec = CaseSpec::forced(&case.id, format!("cases/{}.csv", case.id), case.wind_speed);
    spec.config = case.config.clone();
    spec.amplitude_ratio = case.amplitude_ratio;
    if case.motion.pitch.len() == 1 {
        spec.freq_pitch = Some(case.motion.pitch[0].freq);
        spec.amplitude = Some(tidy(
            units.pitch.from_si(case.motion.pitch[0].amplitude.abs()),
        ));
    }
    if case.motion.heave.len() == 1 {
        spec.freq_heave = Some(case.motion.heave[0].freq);
    }
    if case.motion.mean_pitch != 0.0 {
        spec.mean_pitch = Some(tidy(units.pitch.from_si(case.motion.mean_pitch)));
    }
    if still {
        spec.nowind_file = Some(format!("cases/{}.still.csv", case.id).into());
    }
    spec
}

/// One forced-motion record (and its still-air run when `opts.still_air` is set), SI per
/// unit span, with the case's `[extra]` entries (seed, still-air offset).
///
/// # Errors
/// [`Error::InvalidParameter`] for bad options or case (wind speed ≤ 0, bad motion, model
/// chord ≠ section chord) and, naming `CASE.lift` or `CASE.moment` and the time, for a
/// force coefficient that is not finite or exceeds
/// [`identify::limits::MAX_FORCE_COEFFICIENT`]; [`Error::Numerical`] from the lag
/// initialisation.
pub fn forced_record(
    model: &dyn AeroModel,
    case: &ForcedCase,
    opts: &ForcedOptions,
    seed: u64,
) -> Result<(Record, toml::Table)> {
    opts.check(model.chord())?;
    positive(&format!("{}.wind_speed", case.id), case.wind_speed)?;
    case.motion.check(&case.id)?;
    let flow = Flow {
        rho: opts.section.air_density,
        u: case.wind_speed,
    };
    let b = opts.section.chord;
    let k_model = case.motion.dominant_pitch().and_then(|s| {
        model.with_reduced_frequency(b * 2.0 * std::f64::consts::PI * s.freq / flow.u)
    });
    let m: &dyn AeroModel = k_model.as_deref().unwrap_or(model);
    let n = (opts.rate * opts.duration).round() as usize;
    let dt = 1.0 / opts.rate;
    let pre_roll = opts.pre_roll.max(m.settle_time(&flow));
    let (mut lift, mut moment) =
        forced_forces(m, &flow, &case.motion, 0.0, dt, n, pre_roll, &case.id)?;
    check_force_coefficients(&case.id, &flow, b, dt, &lift, &moment)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut extra = toml::Table::new();
    extra.insert("seed".into(), seed.to_string().into());
    let motion_of = |t0: f64, len: usize| -> (Vec<f64>, Vec<f64>, Vec<[f64; 2]>) {
        let mut h = Vec::with_capacity(len);
        let mut a = Vec::with_capacity(len);
        let mut acc = Vec::with_capacity(len);
        for i in 0..len {
            let (q, _, qdd) = case.motion.eval(t0 + i as f64 * dt);
            h.push(q[0]);
            a.push(q[1]);
            acc.push(qdd);
        }
        (h, a, acc)
    };
    let (mut h, mut alpha, acc) = motion_of(0.0, n);
    let mut nowind = None;
    let sd_h = opts.noise.laser;
    let sd_a = opts.noise.pitch_sd(b);
    if let Some(st) = &opts.still_air {
        let tau = if st.max_offset > 0.0 {
            rng.random_range(0.0..2.0 * st.max_offset)
        } else {
            0.0
        };
        extra.insert("still_air_offset_s".into(), tau.into());
        let ms = st.rig.matrix();
        for i in 0..n {
            let f = ms * nalgebra::Vector2::new(acc[i][0], acc[i][1]);
            lift[i] += f[0];
            moment[i] += f[1];
        }
        let n_still = n + (2.0 * st.max_offset / dt).ceil() as usize;
        let (mut hs, mut als, accs) = motion_of(-tau, n_still);
        let mut m_still = ms;
        if st.apparent_mass {
            m_still += m.apparent_mass(&Flow {
                rho: flow.rho,
                u: 0.0,
            });
        }
        let mut ls = Vec::with_capacity(n_still);
        let mut mss = Vec::with_capacity(n_still);
        for a in &accs {
            let f = m_still * nalgebra::Vector2::new(a[0], a[1]);
            ls.push(f[0]);
            mss.push(f[1]);
        }
        // One balance: the same σ for both runs of a case.
        let sd = opts.noise.balance_sd(
            (peak(&lift).max(peak(&ls)), peak(&moment).max(peak(&mss))),
            opts.section.span,
        );
        let span = opts.section.span;
        opts.noise
            .apply_balance(&mut rng, &mut lift, &mut moment, sd, span);
        opts.noise
            .apply_balance(&mut rng, &mut ls, &mut mss, sd, span);
        add_noise(&mut rng, &mut hs, sd_h);
        add_noise(&mut rng, &mut als, sd_a);
        nowind = Some((hs, als, ls, mss));
    } else {
        let span = opts.section.span;
        let sd = opts.noise.balance_sd((peak(&lift), peak(&moment)), span);
        opts.noise
            .apply_balance(&mut rng, &mut lift, &mut moment, sd, span);
    }
    add_noise(&mut rng, &mut h, sd_h);
    add_noise(&mut rng, &mut alpha, sd_a);
    let spec = forced_spec(case, &opts.units, opts.still_air.is_some());
    let manifest_stub = Manifest {
        name: String::new(),
        description: None,
        section: opts.section,
        structure: None,
        units: opts.units,
        convention: Default::default(),
        cases: vec![],
        extra: None,
    };
    let meta = manifest_stub.case_meta(&spec);
    let still = nowind.map(|(hs, als, ls, mss)| {
        Box::new(Record {
            kind: CaseKind::Forced,
            meta: meta.clone(),
            t0: 0.0,
            dt,
            h: hs,
            alpha: als,
            lift: Some(ls),
            moment: Some(mss),
            nowind: None,
            control: None,
        })
    });
    Ok((
        Record {
            kind: CaseKind::Forced,
            meta,
            t0: 0.0,
            dt,
            h,
            alpha,
            lift: Some(lift),
            moment: Some(moment),
            nowind: still,
            control: None,
        },
        extra,
    ))
}

/// Forced-motion records of every case of `cases` (in parallel over cases; the result does
/// not depend on the thread count) and their manifest.
///
/// # Errors
/// As [`forced_record`] (the first failing case in order); [`Error::InvalidParameter`] for
/// an empty case list or a repeated id.
pub fn forced_dataset(
    model: &dyn AeroModel,
    cases: &[ForcedCase],
    opts: &ForcedOptions,
    observer: &(dyn Fn(TunnelProgress) + Sync),
) -> Result<(Manifest, Vec<Record>)> {
    check_ids(cases.iter().map(|c| c.id.as_str()))?;
    opts.check(model.chord())?;
    let done = AtomicUsize::new(0);
    let results: Vec<Result<(Record, toml::Table)>> = cases
        .par_iter()
        .enumerate()
        .map(|(i, c)| {
            let r = forced_record(model, c, opts, case_seed(opts.seed, i));
            observer(TunnelProgress {
                done: done.fetch_add(1, Ordering::Relaxed) + 1,
                total: cases.len(),
                id: c.id.clone(),
            });
            r
        })
        .collect();
    let mut records = Vec::with_capacity(cases.len());
    let mut specs = Vec::with_capacity(cases.len());
    for (c, r) in cases.iter().zip(results) {
        let (rec, extra) = r?;
        let mut spec = forced_spec(c, &opts.units, opts.still_air.is_some());
        spec.extra = Some(extra);
        specs.push(spec);
        records.push(rec);
    }
    let mut extra = manifest_extra(
        "forced",
        &model.name(),
        opts.seed,
        &opts.noise,
        opts.section.chord,
    );
    if let Some(st) = &opts.still_air {
        extra.insert("still_air_rig_mass".into(), st.rig.mass.into());
        extra.insert("still_air_rig_inertia".into(), st.rig.inertia.into());
        extra.insert(
            "still_air_rig_static_unbalance".into(),
            st.rig.static_unbalance.into(),
        );
        extra.insert("still_air_apparent_mass".into(), st.apparent_mass.into());
    }
    let manifest = Manifest {
        name: opts.name.clone(),
        description: Some(format!(
            "Virtual wind tunnel, forced motion, model `{}`, {} Hz, {} s{}.",
            model.name(),
            opts.rate,
            opts.duration,
            if opts.still_air.is_some() {
                "; wind-on files hold aerodynamic + inertial forces, still-air runs in nowind_file"
            } else {
                ""
            }
        )),
        section: opts.section,
        structure: None,
        units: opts.units,
        convention: Default::default(),
        cases: specs,
        extra: Some(extra),
    };
    Ok((manifest, records))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::aero::{state_space_response, TheodorsenAero};
    use crate::tunnel::{write, Campaign};

    fn no_obs(_: TunnelProgress) {}

    /// Issue 27 row 15: a model whose nonlinear term blows up along the motion (an α² lift
    /// coefficient at the model files' limit, 1e9: C_L ≈ 1e6 at 3°) is refused naming the
    /// case, the channel and the time, before any record exists; a plausible one passes.
    #[test]
    fn forces_beyond_the_coefficient_bound_are_refused_naming_case_channel_and_time() {
        let model = |c: f64| {
            crate::files::LoadedModel::parse(
                &format!(
                    "kind = \"theodorsen\"\nchord = 0.25\nelastic_axis = -0.3\n\
                     [[nonlinear]]\nterm = \"alpha^2\"\nchannel = \"lift\"\n\
                     coefficient = {c:e}\n"
                ),
                "m.toml",
                Path::new("."),
                None,
            )
            .unwrap()
            .model
        };
        let mut opts = ForcedOptions::paper(1);
        opts.duration = 1.0;
        let cases = Campaign::paper_config("D").unwrap().cases();
        let e = forced_dataset(model(1e9).as_ref(), &cases, &opts, &no_obs).unwrap_err();
        let m = e.to_string();
        let first = &cases[0].id;
        assert!(
            m.contains(&format!("field `{first}.lift`"))
                && m.contains(&format!("case `{first}`, lift at t = "))
                && m.contains("|C_L| must be finite and ≤ 10000"),
            "{m}"
        );
        forced_dataset(model(-100.0).as_ref(), &cases[..2], &opts, &no_obs).unwrap();
        // a non-finite moment names the moment channel and the sample's time
        let flow = Flow { rho: 1.2, u: 10.0 };
        let e = check_force_coefficients("c", &flow, 0.25, 0.5, &[1.0; 3], &[0.0, 0.0, f64::NAN])
            .unwrap_err();
        assert!(e.to_string().contains("case `c`, moment at t = 1 s"), "{e}");
    }

    #[test]
    fn forced_forces_equal_the_time_domain_harmonic_response() {
        // Theodorsen with Jones' lags on the periodic solution: the recorded forces are
        // Re/Im of H_ss(ω) q̂ at each frequency, to RK4 accuracy.
        let m = TheodorsenAero::new(0.25, 0.0).unwrap();
        let flow = Flow { rho: 1.225, u: 4.0 };
        let motion = Motion::two_frequency(2.0, 1.3, 0.2, 0.018);
        let (l, mo) = forced_forces(&m, &flow, &motion, 3.0, 1.0 / 512.0, 2048, 0.0, "t").unwrap();
        let mut want_l = vec![0.0; l.len()];
        let mut want_m = vec![0.0; l.len()];
        for (j, s) in [(0, motion.heave[0]), (1, motion.pitch[0])] {
            let w = 2.0 * std::f64::consts::PI * s.freq;
            let hm = state_space_response(&m, &flow, w).unwrap();
            for i in 0..l.len() {
                let e = Complex64::from_polar(s.amplitude, w * (3.0 + i as f64 / 512.0));
                want_l[i] += (hm[(0, j)] * e).im;
                want_m[i] += (hm[(1, j)] * e).im;
            }
        }
        let (pl, pm) = (peak(&want_l), peak(&want_m));
        let el = l
            .iter()
            .zip(&want_l)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let em = mo
            .iter()
            .zip(&want_m)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            el < 1e-7 * pl && em < 1e-7 * pm,
            "errors {} {}",
            el / pl,
            em / pm
        );
    }

    #[test]
    fn still_air_dataset_round_trips_and_subtraction_recovers_aero_forces() {
        let m = TheodorsenAero::new(0.25, 0.0).unwrap();
        let mut opts = ForcedOptions::paper(7).with_paper_still_air();
        opts.duration = 4.0;
        let mut cases = Campaign::paper_config("D").unwrap().cases();
        cases.retain(|c| c.id == "D-U6-A12" || c.id == "D-U10-A24");
        let (man, recs) = forced_dataset(&m, &cases, &opts, &no_obs).unwrap();
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &man, &recs).unwrap();
        let ds = identify::dataset::read_dataset(dir.path()).unwrap();
        assert_eq!(ds.records.len(), 2);
        let extra = ds.manifest.extra.as_ref().unwrap();
        assert_eq!(extra["seed"].as_str(), Some("7"));
        let r = &ds.records[0];
        assert!(r.nowind.is_some());
        // Aligned subtraction gives back the noiseless aerodynamic force to noise level.
        let (l_aero, _m_aero, lag) =
            identify::preprocess::subtract_nowind(r, r.nowind.as_ref().unwrap()).unwrap();
        let tau = ds.manifest.cases[0].extra.as_ref().unwrap()["still_air_offset_s"]
            .as_float()
            .unwrap();
        assert!((lag.abs() - tau).abs() < 1e-3, "lag {lag} vs offset {tau}");
        let flow = Flow { rho: 1.225, u: 6.0 };
        let (lt, _) = forced_forces(
            &m,
            &flow,
            &cases[0].motion,
            0.0,
            1.0 / 512.0,
            r.len(),
            0.0,
            "x",
        )
        .unwrap();
        let rng = identify::preprocess::nowind_overlap(
            r.len(),
            r.dt,
            r.nowind.as_ref().unwrap().len(),
            r.dt,
            lag,
        );
        assert_eq!(rng.len(), l_aero.len());
        let err: f64 = rng
            .clone()
            .zip(&l_aero)
            .map(|(i, v)| (v - lt[i]).powi(2))
            .sum::<f64>()
            / l_aero.len() as f64;
        // Absolute balance σ (0.1 % of 65 N over 0.75 m) in each of two runs → √2 σ; the
        // interpolation of the still-air run smooths its noise a little, so rms ≤ √2 σ.
        let (sd_l, _) = opts.noise.balance_sd((0.0, 0.0), opts.section.span);
        assert!(
            err.sqrt() < 1.1 * 2f64.sqrt() * sd_l && err.sqrt() > 0.8 * sd_l,
            "rms {} vs σ {}",
            err.sqrt(),
            sd_l
        );
    }
}
