//! Per-case data of the force level: nondimensional regressors and targets, scales back to
//! forces, noise estimates, a harmonic representation of the motion (for shifted and
//! differentiated regressors), and the (configuration, wind speed) nodes.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use identify::dataset::Dataset;
use identify::library::Term;
use identify::preprocess::{harmonic_fit, HarmonicFit, PreprocessOptions};
use identify::record::NondimCase;
use identify::workflow::prepare_dataset;

use crate::numerics::white_noise_sigma;
use crate::{Error, Result};

/// Channel names in index order.
pub(crate) const CHANNELS: [&str; 2] = ["lift", "moment"];

/// One forced case ready for the force level.
#[derive(Debug, Clone)]
pub(crate) struct CaseData {
    pub nd: NondimCase,
    pub config: String,
    pub u: f64,
    pub amp_deg: f64,
    pub n: usize,
    pub dt: f64,
    /// C_L, C_M.
    pub y: [Vec<f64>; 2],
    /// C → force per unit span: qB (lift), qB² (moment).
    pub scale: [f64; 2],
    /// Sensor-noise σ̂ of C_L, C_M (`numerics::white_noise_sigma`: the white floor of the
    /// third difference's spectrum, which a shedding line does not inflate).
    pub sigma: [f64; 2],
    /// Pitch / heave forcing frequency \[Hz\].
    pub f_alpha: f64,
    pub f_h: Option<f64>,
    /// K_α = Bω_α/U.
    pub k_alpha: f64,
    /// Harmonic fits of the four regression variables at the forcing frequencies (None
    /// when a fit fails: the shifted and differentiated regressors then fall back to finite
    /// differences and interpolation).
    pub rep: [Option<HarmonicFit>; 4],
    /// Node index (configuration, wind speed).
    pub node: usize,
    /// Mean pitch ᾱ \[rad\] about which the baseline identification regresses this case
    /// (identify's `centre_mean_angle`: the case's declared `mean_pitch`), 0 otherwise. The
    /// configuration's supports then get the constant term (the identification reports the
    /// mean force in one). Linear columns are evaluated on α − ᾱ (the node's constant is
    /// then the force at ᾱ, and a zero-mean augmentation such as an acceleration projects
    /// on it with nothing); nonlinear ones on the absolute α, since the section's nonlinear
    /// law, shared by configurations of different mean angles, is one law of the absolute
    /// angle (a cubic of α − ᾱ would need a quadratic per ᾱ).
    pub alpha_shift: f64,
    /// Monomial columns evaluated so far (filled on demand, shared by every fold and
    /// candidate; a clone starts empty, since clones are made to change the regressors).
    pub cols: ColumnCache,
}

/// Memo of a case's monomial columns.
#[derive(Debug, Default)]
pub(crate) struct ColumnCache(Mutex<HashMap<Term, Arc<Vec<f64>>>>);

impl Clone for ColumnCache {
    fn clone(&self) -> Self {
        ColumnCache::default()
    }
}

impl CaseData {
    /// Column of a monomial on this case's samples (evaluated once, then shared).
    pub fn column(&self, t: &Term) -> Arc<Vec<f64>> {
        if let Some(v) = self.cols.0.lock().ok().and_then(|m| m.get(t).cloned()) {
            return v;
        }
        let shift = if t.degree() <= 1 {
            self.alpha_shift
        } else {
            0.0
        };
        let v = Arc::new(column_of(&self.nd.x, shift, t));
        if let Ok(mut m) = self.cols.0.lock() {
            m.entry(*t).or_insert_with(|| v.clone());
        }
        v
    }

    /// Nondimensional accelerations (B²α̈/U², Bḧ/U²) = (B/U)·d/dt(Bα̇/U, ḣ/U).
    pub fn accelerations(&self) -> [Vec<f64>; 2] {
        let c = self.nd.chord / self.u;
        [1, 3].map(|k| match &self.rep[k] {
            Some(f) => (0..self.n)
                .map(|i| c * f.derivative(i as f64 * self.dt))
                .collect(),
            None => central_difference(&self.nd.x[k], self.dt)
                .into_iter()
                .map(|v| c * v)
                .collect(),
        })
    }
}

/// Column of a monomial (any degree) on four variable series, pitch taken about
/// `alpha_shift` (α − ᾱ; 0 for none).
pub(crate) fn column_of(x: &[Vec<f64>; 4], alpha_shift: f64, t: &Term) -> Vec<f64> {
    let n = x[0].len();
    (0..n)
        .map(|i| t.eval_at([x[0][i] - alpha_shift, x[1][i], x[2][i], x[3][i]]))
        .collect()
}

fn central_difference(x: &[f64], dt: f64) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (x[b] - x[a]) / ((b - a).max(1) as f64 * dt)
        })
        .collect()
}

/// A (configuration, wind speed) node: one fold group.
#[derive(Debug, Clone)]
pub(crate) struct Node {
    pub config: String,
    pub u: f64,
    /// Mean K_α of its cases.
    pub k_alpha: f64,
    pub cases: Vec<usize>,
}

/// Label of the configuration every case gets when configurations are pooled.
pub(crate) const POOLED: &str = "pooled";

/// Prepares the forced cases of a data set (identify's preprocessing) and groups them into
/// nodes (sorted by configuration then wind speed). Pitch-only and heave-only forcing are
/// both accepted: the node's reduced frequency `k_alpha` is then that of the one forcing
/// frequency. When a configuration has forced cases at a single wind speed while the data
/// set has at least two (configuration, wind speed) groups, every configuration is pooled
/// into one (`POOLED`; its held-out node could not be predicted from its own configuration
/// otherwise); the third value says so.
pub(crate) fn prepare(forced: &Dataset) -> Result<(Vec<CaseData>, Vec<Node>, Option<String>)> {
    let name = forced.manifest.name.clone();
    let prepared = prepare_dataset(forced, &PreprocessOptions::default())
        .map_err(|e| Error::identify(format!("data set `{name}`: preprocessing"), e))?;
    if prepared.cases.is_empty() {
        return Err(Error::data(&name, "no forced case"));
    }
    let section = forced.manifest.section;
    let mut cases = Vec::with_capacity(prepared.cases.len());
    for nd in prepared.cases {
        let id = nd.meta.id.clone();
        let u = nd.meta.wind_speed;
        // pitch-only or heave-only forcing: the one forcing frequency sets the node's K
        let Some(f_alpha) = nd.forcing.pitch.or(nd.forcing.heave) else {
            return Err(Error::data(
                &name,
                format!(
                    "case `{id}`: no forcing frequency (neither pitch nor heave moves \
                     periodically; give `freq_pitch` or `freq_heave` in the manifest)"
                ),
            ));
        };
        let q = 0.5 * section.air_density * u * u;
        let b = section.chord;
        let scale = [q * b, q * b * b];
        let y = [nd.c_lift.clone(), nd.c_moment.clone()];
        let sigma = [white_noise_sigma(&y[0]), white_noise_sigma(&y[1])];
        let freqs = nd.forcing.frequencies();
        let rep = std::array::from_fn(|k| harmonic_fit(&nd.x[k], nd.dt, &freqs).ok());
        let amp_deg = match nd.meta.amplitude {
            Some(a) => a.to_degrees(),
            None => {
                let (lo, hi) = nd.x[0]
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                        (l.min(v), h.max(v))
                    });
                0.5 * (hi - lo).to_degrees()
            }
        };
        cases.push(CaseData {
            config: nd.meta.config.clone().unwrap_or_else(|| "-".to_string()),
            u,
            amp_deg,
            n: nd.len(),
            dt: nd.dt,
            y,
            scale,
            sigma,
            f_alpha,
            f_h: nd.forcing.heave,
            k_alpha: b * 2.0 * std::f64::consts::PI * f_alpha / u,
            rep,
            node: 0,
            alpha_shift: nd
                .meta
                .mean_pitch
                .filter(|m| *m != 0.0 && m.is_finite())
                .unwrap_or(0.0),
            cols: ColumnCache::default(),
            nd,
        });
    }
    let pooled = pool_single_speed_configs(&mut cases);
    let mut keys: Vec<(String, f64)> = cases.iter().map(|c| (c.config.clone(), c.u)).collect();
    keys.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    keys.dedup_by(|a, b| a.0 == b.0 && (a.1 - b.1).abs() <= 1e-9 * b.1.abs().max(1.0));
    let mut nodes: Vec<Node> = keys
        .iter()
        .map(|(c, u)| Node {
            config: c.clone(),
            u: *u,
            k_alpha: 0.0,
            cases: Vec::new(),
        })
        .collect();
    for (i, c) in cases.iter_mut().enumerate() {
        let j = nodes
            .iter()
            .position(|nd| nd.config == c.config && (nd.u - c.u).abs() <= 1e-9 * c.u.max(1.0))
            .unwrap_or(0);
        c.node = j;
        nodes[j].cases.push(i);
    }
    for nd in &mut nodes {
        nd.k_alpha =
            nd.cases.iter().map(|&i| cases[i].k_alpha).sum::<f64>() / nd.cases.len() as f64;
    }
    Ok((cases, nodes, pooled))
}

fn same_speed(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

/// Pools every configuration into [`POOLED`] when one configuration has a single wind
/// speed but the cases span at least two (configuration, wind speed) groups; returns a
/// note naming the single-speed configurations, or `None` when nothing changed.
pub(crate) fn pool_single_speed_configs(cases: &mut [CaseData]) -> Option<String> {
    let mut speeds: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    for c in cases.iter() {
        let v = speeds.entry(c.config.clone()).or_default();
        if !v.iter().any(|&u| same_speed(u, c.u)) {
            v.push(c.u);
        }
    }
    let groups: usize = speeds.values().map(Vec::len).sum();
    let single: Vec<&str> = speeds
        .iter()
        .filter(|(_, v)| v.len() < 2)
        .map(|(k, _)| k.as_str())
        .collect();
    if single.is_empty() || groups < 2 || speeds.len() < 2 {
        return None;
    }
    let note = format!(
        "configuration(s) {} at a single wind speed: all configurations pooled into one law over K",
        single.join(", ")
    );
    for c in cases.iter_mut() {
        c.config = POOLED.to_string();
        c.nd.meta.config = Some(POOLED.to_string());
    }
    Some(note)
}

/// Held-out gap metrics of a set of residuals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gaps {
    /// sqrt(Σr²/ΣF²) of lift, moment (forces per unit span).
    pub channel: [f64; 2],
    /// rms of the two channels.
    pub combined: f64,
}

/// Gap of residuals `res[case][channel]` (C units) in forces: Σ(r·scale)²/Σ(F)².
pub(crate) fn gaps(cases: &[CaseData], res: &[[Vec<f64>; 2]]) -> Gaps {
    gaps_of(cases.iter().zip(res))
}

/// Noise level of the gap of some cases ([`noise_gaps`]).
pub(crate) fn noise_of<'a>(cases: impl Iterator<Item = &'a CaseData>) -> Gaps {
    let cases: Vec<&CaseData> = cases.collect();
    let res: Vec<[Vec<f64>; 2]> = cases
        .iter()
        .map(|c| [0, 1].map(|k| vec![c.sigma[k]; c.n]))
        .collect();
    gaps_of(cases.into_iter().zip(&res))
}

/// [`gaps`] of (case, residuals) pairs.
pub(crate) fn gaps_of<'a>(pairs: impl Iterator<Item = (&'a CaseData, &'a [Vec<f64>; 2])>) -> Gaps {
    let mut num = [0.0; 2];
    let mut den = [0.0; 2];
    for (case, r) in pairs {
        for c in 0..2 {
            let s2 = case.scale[c] * case.scale[c];
            num[c] += s2 * r[c].iter().map(|v| v * v).sum::<f64>();
            den[c] += s2 * case.y[c].iter().map(|v| v * v).sum::<f64>();
        }
    }
    let channel = [0, 1].map(|c| {
        if den[c] > 0.0 {
            (num[c] / den[c]).sqrt()
        } else {
            0.0
        }
    });
    Gaps {
        channel,
        combined: ((channel[0].powi(2) + channel[1].powi(2)) / 2.0).sqrt(),
    }
}

/// Noise level of the gap: Σr² replaced by Σ n σ̂².
pub(crate) fn noise_gaps(cases: &[CaseData]) -> Gaps {
    noise_of(cases.iter())
}
