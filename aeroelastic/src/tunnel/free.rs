//! Free-response records: the section on springs in the flow from an initial perturbation
//! ([`FreeOptions`]), one record at one speed ([`free_record`]) and a data set over a list of
//! speeds with the manifest's `[structure]` ([`free_dataset`]).

use std::sync::atomic::{AtomicUsize, Ordering};

use identify::dataset::{CaseSpec, Manifest, Units};
use identify::record::{CaseKind, CaseMeta, Record, SectionGeometry};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::motion::num_label;
use super::noise::{add_noise, peak};
use super::write::{check_ids, manifest_extra};
use super::{case_seed, paper_units, SensorNoise, TunnelProgress};
use crate::dynamics::SectionDynamics;
use crate::error::positive;
use crate::integrate::{rk4, Bound, Control, ObserverVerdict, SolverStop, StopReason};
use crate::section::Section;
use crate::{Error, Result};

/// Options of free-response records.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FreeOptions {
    /// Data-set name.
    pub name: String,
    /// Span \[m\] of the written totals (chord and density come from the section).
    pub span: f64,
    /// Sampling rate \[Hz\].
    pub rate: f64,
    /// Record duration \[s\].
    pub duration: f64,
    /// Initial state (h, α, ḣ, α̇) [m, rad, m/s, rad/s]; lag states start at 0.
    pub initial: [f64; 4],
    /// RK4 steps per sample.
    pub substeps: usize,
    /// Record L and M too.
    pub record_forces: bool,
    /// Sensor noise.
    pub noise: SensorNoise,
    /// |α| bound \[rad\]: a run leaving it is truncated there.
    pub bound_alpha: f64,
    /// |h| bound in chords.
    pub bound_h: f64,
    /// Master seed.
    pub seed: u64,
    /// Units of the written CSV files.
    pub units: Units,
}

impl FreeOptions {
    /// 512 Hz, 20 s, α₀ = 2°, 8 RK4 steps per sample, forces recorded, paper noise, bound
    /// 1.5 rad / 5 chords, paper units, span 0.75 m.
    pub fn new(seed: u64) -> Self {
        FreeOptions {
            name: "virtual wind tunnel: free response".into(),
            span: 0.75,
            rate: 512.0,
            duration: 20.0,
            initial: [0.0, 2f64.to_radians(), 0.0, 0.0],
            substeps: 8,
            record_forces: true,
            noise: SensorNoise::paper(),
            bound_alpha: 1.5,
            bound_h: 5.0,
            seed,
            units: paper_units(),
        }
    }

    fn check(&self) -> Result<()> {
        positive("span", self.span)?;
        positive("rate", self.rate)?;
        positive("duration", self.duration)?;
        positive("bound_alpha", self.bound_alpha)?;
        positive("bound_h", self.bound_h)?;
        if self.substeps == 0 {
            return Err(Error::param("substeps", 0.0, "must be > 0"));
        }
        for (i, v) in self.initial.iter().enumerate() {
            crate::error::finite(&format!("initial[{i}]"), *v)?;
        }
        self.noise.check()
    }
}

/// Result of one free run besides the record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FreeRun {
    /// Wind speed \[m/s\].
    pub u: f64,
    /// Time the state left the bound \[s\], if it did (the record ends there).
    pub left_bound_at: Option<f64>,
}

/// One free-response record of `section` at wind speed `u` (SI per unit span; `u = 0` is a
/// still-air decay).
///
/// # Errors
/// [`Error::InvalidParameter`] for bad options or `u < 0`; [`Error::Numerical`] when
/// M_s − M_a is singular.
pub fn free_record(
    section: &Section,
    u: f64,
    id: &str,
    opts: &FreeOptions,
    seed: u64,
) -> Result<(Record, FreeRun)> {
    opts.check()?;
    if !(u.is_finite() && u >= 0.0) {
        return Err(Error::param("wind_speed", u, "must be finite and ≥ 0"));
    }
    let b = section.aero.chord();
    // Still air (U = 0): the model's zero-speed forces (apparent mass), no K to evaluate at.
    let k_model = if u > 0.0 {
        section
            .aero
            .with_reduced_frequency(b * section.structure.omega_alpha() / u)
    } else {
        None
    };
    // The section at the pitch frequency's K when the model's coefficients depend on K.
    let k_section;
    let sec = match k_model {
        Some(m) => {
            k_section = Section::new(section.structure.clone(), m, section.rho)?;
            &k_section
        }
        None => section,
    };
    let dynamics = SectionDynamics::new(sec, u)?;
    let ma = sec.aero.apparent_mass(&sec.flow(u));
    let n = (opts.rate * opts.duration).round() as usize;
    let dt = 1.0 / opts.rate;
    let hstep = dt / opts.substeps as f64;
    let mut y = vec![0.0; dynamics.dim()];
    y[..4].copy_from_slice(&opts.initial);
    let (mut h, mut alpha, mut lift, mut moment) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::new(),
        Vec::new(),
    );
    let mut dy = vec![0.0; dynamics.dim()];
    let bound = Bound {
        h: opts.bound_h * b,
        alpha: opts.bound_alpha,
    };
    // Sample i (state at i·dt): the bound is checked at the samples only; the record
    // ends before the first sample outside it.
    let mut record = |y: &[f64]| -> bool {
        if bound.left(y) || !y.iter().all(|v| v.is_finite()) {
            return false;
        }
        h.push(y[0]);
        alpha.push(y[1]);
        if opts.record_forces {
            // Full forces include the apparent-mass part M_a q̈.
            let f = dynamics.aero_forces(y);
            dynamics.rate(y, &mut dy);
            lift.push(f[0] + ma[(0, 0)] * dy[2] + ma[(0, 1)] * dy[3]);
            moment.push(f[1] + ma[(1, 0)] * dy[2] + ma[(1, 1)] * dy[3]);
        }
        true
    };
    let mut left = None;
    if n > 0 && !record(&y) {
        left = Some(0.0);
    } else if n > 1 {
        let run = rk4(
            &dynamics,
            0.0,
            &mut y,
            hstep,
            (n - 1) * opts.substeps,
            None,
            &mut |s, _t, y| {
                if s % opts.substeps != 0 {
                    return Control::Continue;
                }
                if record(y) {
                    Control::Continue
                } else {
                    Control::Stop(ObserverVerdict::LeftBound)
                }
            },
        )?;
        if run.stop != StopReason::Solver(SolverStop::TimeCap) {
            // left the bound (or overflowed) before the next sample
            left = Some(h.len() as f64 * dt);
        }
    }
    if h.len() < 3 {
        return Err(Error::numerical(
            format!("free case {id}"),
            format!("left the bound after {} samples (need ≥ 3)", h.len()),
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    add_noise(&mut rng, &mut h, opts.noise.laser);
    add_noise(&mut rng, &mut alpha, opts.noise.pitch_sd(b));
    let (lift, moment) = if opts.record_forces {
        let sd = opts
            .noise
            .balance_sd((peak(&lift), peak(&moment)), opts.span);
        opts.noise
            .apply_balance(&mut rng, &mut lift, &mut moment, sd, opts.span);
        (Some(lift), Some(moment))
    } else {
        (None, None)
    };
    Ok((
        Record {
            kind: CaseKind::Free,
            meta: CaseMeta {
                id: id.to_string(),
                wind_speed: u,
                ..Default::default()
            },
            t0: 0.0,
            dt,
            h,
            alpha,
            lift,
            moment,
            nowind: None,
            control: None,
        },
        FreeRun {
            u,
            left_bound_at: left,
        },
    ))
}

/// Free-response records of `section` at every speed (case id `free-U{U}`), in parallel,
/// and their manifest (with `[structure]`; the full structure, including nonlinear terms,
/// under `[extra] structure`).
///
/// # Errors
/// As [`free_record`] and [`crate::structure::Structure::modal`]; [`Error::InvalidParameter`] for an empty or
/// repeated speed list.
pub fn free_dataset(
    section: &Section,
    speeds: &[f64],
    opts: &FreeOptions,
    observer: &(dyn Fn(TunnelProgress) + Sync),
) -> Result<(Manifest, Vec<Record>, Vec<FreeRun>)> {
    let ids: Vec<String> = speeds
        .iter()
        .map(|u| format!("free-U{}", num_label(*u)))
        .collect();
    check_ids(ids.iter().map(String::as_str))?;
    let spec = section.structure.modal()?;
    let done = AtomicUsize::new(0);
    let results: Vec<Result<(Record, FreeRun)>> = speeds
        .par_iter()
        .zip(&ids)
        .enumerate()
        .map(|(i, (&u, id))| {
            let r = free_record(section, u, id, opts, case_seed(opts.seed, i));
            observer(TunnelProgress {
                done: done.fetch_add(1, Ordering::Relaxed) + 1,
                total: speeds.len(),
                id: id.clone(),
            });
            r
        })
        .collect();
    let mut records = Vec::new();
    let mut runs = Vec::new();
    let mut cases = Vec::new();
    for (i, (r, id)) in results.into_iter().zip(&ids).enumerate() {
        let (rec, run) = r?;
        let mut c = CaseSpec::forced(id, format!("cases/{id}.csv"), run.u);
        c.kind = CaseKind::Free;
        let mut extra = toml::Table::new();
        extra.insert("seed".into(), case_seed(opts.seed, i).to_string().into());
        if let Some(t) = run.left_bound_at {
            extra.insert("left_bound_at_s".into(), t.into());
        }
        c.extra = Some(extra);
        cases.push(c);
        records.push(rec);
        runs.push(run);
    }
    let b = section.aero.chord();
    let mut extra = manifest_extra("free", &section.aero.name(), opts.seed, &opts.noise, b);
    extra.insert(
        "initial_state".into(),
        toml::Value::Array(opts.initial.iter().map(|v| (*v).into()).collect()),
    );
    if let Ok(t) = toml::Table::try_from(&section.structure) {
        extra.insert("structure".into(), toml::Value::Table(t));
    }
    let manifest = Manifest {
        name: opts.name.clone(),
        description: Some(format!(
            "Virtual wind tunnel, free response on springs, model `{}`, {} Hz, {} s.",
            section.aero.name(),
            opts.rate,
            opts.duration
        )),
        section: SectionGeometry {
            chord: b,
            span: opts.span,
            air_density: section.rho,
        },
        structure: Some(spec),
        units: opts.units,
        convention: Default::default(),
        cases,
        extra: Some(extra),
    };
    Ok((manifest, records, runs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tunnel::write;

    fn no_obs(_: TunnelProgress) {}

    #[test]
    fn free_records_decay_below_and_grow_above_flutter_and_write_structure() {
        let s = crate::reference::hp1_theodorsen();
        let opts_fl = crate::flutter::FlutterOptions {
            u_min: 0.1,
            u_max: 4.0,
            n_speeds: 60,
            tol_rel: 1e-10,
        };
        let uf = s
            .flutter(crate::flutter::FlutterMethod::P, &opts_fl)
            .unwrap()
            .flutter
            .unwrap()
            .u;
        let mut o = FreeOptions::new(3);
        o.noise = SensorNoise::none();
        o.rate = 64.0;
        o.duration = 60.0;
        o.initial = [0.0, 0.05, 0.0, 0.0];
        let (man, recs, runs) = free_dataset(&s, &[0.9 * uf, 1.1 * uf], &o, &no_obs).unwrap();
        let amp =
            |v: &[f64], a: usize, b: usize| v[a..b].iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let n = recs[0].alpha.len();
        assert!(amp(&recs[0].alpha, n - 200, n) < 0.5 * amp(&recs[0].alpha, 0, 200));
        let n1 = recs[1].alpha.len();
        assert!(runs[1].left_bound_at.is_some() || amp(&recs[1].alpha, n1 - 200, n1) > 2.0 * 0.05);
        let st = man.structure.unwrap();
        assert!(
            (st.freq_pitch * 2.0 * std::f64::consts::PI - s.structure.omega_alpha()).abs() < 1e-9
        );
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &man, &recs).unwrap();
        let ds = identify::dataset::read_dataset(dir.path()).unwrap();
        assert_eq!(ds.records[1].kind, CaseKind::Free);
    }
}
