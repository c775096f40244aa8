//! Data behind the seed paper's results-section figures that the other result files do not
//! hold (`paper_figures.json`): the wind-on / still-air / aerodynamic force decomposition of
//! the shown cases (paper Figs. 4/5), the fits of one case at a high, the selected and a low
//! δ of the path (Figs. 7/8, Table III), and the force loops of one configuration across wind
//! speed and across amplitude (Figs. 14/15). Everything is computed from the records and the
//! identification; the figures are drawn from this file so `aeroform plot` can redraw them.

use aeroelastic::aero::Channel;
use identify::dataset::Dataset;
use identify::library::Term;
use identify::pipeline::{GroupForce, Identification};
use identify::record::NondimCase;
use serde::{Deserialize, Serialize};

/// Seconds of record kept for the time-series figures (from the start of the record).
pub const WINDOW_S: f64 = 3.0;
/// Forcing periods kept for a force loop (the last ones of the record).
pub const LOOP_PERIODS: f64 = 2.0;
/// Loops per figure (evenly spaced over the available wind speeds or amplitudes).
const MAX_LOOPS: usize = 4;

/// Balance forces of one forced case, wind on and still air, over the first seconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForceDecomposition {
    /// Case id.
    pub id: String,
    /// Wind speed U [m/s].
    pub wind_speed: f64,
    /// Time from the first sample \[s\].
    pub t: Vec<f64>,
    /// Lift per unit span with wind \[N/m\], positive down.
    pub lift_wind_on: Vec<f64>,
    /// Lift per unit span of the still-air run of the same motion \[N/m\].
    pub lift_still_air: Vec<f64>,
    /// Moment per unit span with wind \[N·m/m\], positive nose-up.
    pub moment_wind_on: Vec<f64>,
    /// Moment per unit span of the still-air run \[N·m/m\].
    pub moment_still_air: Vec<f64>,
}

/// The wind-on and still-air forces of the cases `ids` that have a still-air run with the
/// same sampling (others are skipped): the first [`WINDOW_S`] seconds. The aerodynamic
/// force is their difference (the subtraction preprocessing performs before filtering).
pub fn force_decompositions(dataset: &Dataset, ids: &[String]) -> Vec<ForceDecomposition> {
    ids.iter()
        .filter_map(|id| {
            let r = dataset.record(id)?;
            let s = r.nowind.as_deref()?;
            let (l, m) = (r.lift.as_ref()?, r.moment.as_ref()?);
            let (ls, ms) = (s.lift.as_ref()?, s.moment.as_ref()?);
            if (s.dt - r.dt).abs() > 1e-9 * r.dt {
                return None;
            }
            let n = [l.len(), m.len(), ls.len(), ms.len()]
                .into_iter()
                .min()?
                .min((WINDOW_S / r.dt).ceil() as usize);
            Some(ForceDecomposition {
                id: id.clone(),
                wind_speed: r.meta.wind_speed,
                t: (0..n).map(|i| i as f64 * r.dt).collect(),
                lift_wind_on: l[..n].to_vec(),
                lift_still_air: ls[..n].to_vec(),
                moment_wind_on: m[..n].to_vec(),
                moment_still_air: ms[..n].to_vec(),
            })
        })
        .collect()
}

/// One support of the δ path refitted on one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeltaFit {
    /// `"high δ"`, `"selected δ"` or `"low δ"`.
    pub label: String,
    /// δ interval of the path giving this support.
    pub delta: [f64; 2],
    /// Terms (library names) and their least-squares coefficients on this case.
    pub coefficients: Vec<(String, f64)>,
    /// R² of the fit on the whole record.
    pub r2: f64,
    /// Model output over the window.
    pub model: Vec<f64>,
}

/// Fits of one case at three points of its group's δ path (paper Figs. 7/8, Table III).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeltaFits {
    /// Group name.
    pub group: String,
    /// Case id.
    pub case: String,
    /// The force (written `"lift"` or `"moment"`).
    #[serde(with = "aeroelastic::aero::channel_name")]
    pub force: Channel,
    /// Time from the first sample \[s\].
    pub t: Vec<f64>,
    /// Measured coefficient (C_L positive down or C_M nose-up) over the window.
    pub measured: Vec<f64>,
    /// High δ (sparsest non-empty support), the selected support, low δ (densest).
    pub fits: Vec<DeltaFit>,
}

/// A force-coefficient loop of one case: the last [`LOOP_PERIODS`] pitch periods.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForceLoop {
    /// Legend label (`U = 6 m/s` or `A = 12°`).
    pub label: String,
    /// Case id.
    pub case: String,
    /// Pitch α \[deg\].
    pub alpha_deg: Vec<f64>,
    /// C_L (positive down).
    pub c_lift: Vec<f64>,
    /// C_M (nose-up).
    pub c_moment: Vec<f64>,
}

/// Loops of one configuration with one descriptor fixed and the other varied
/// (paper Figs. 14/15).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopSet {
    /// Configuration.
    pub config: String,
    /// What is held fixed, e.g. `amplitude 24°`.
    pub fixed: String,
    /// What varies: `wind speed` or `amplitude`.
    pub varied: String,
    /// One loop per value of the varied descriptor, increasing.
    pub loops: Vec<ForceLoop>,
}

/// The content of `paper_figures.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PaperFigures {
    /// Wind-on / still-air forces of the shown cases.
    pub forces: Vec<ForceDecomposition>,
    /// Fits along the δ path.
    pub delta_fits: Vec<DeltaFits>,
    /// Force loops across wind speed and across amplitude.
    pub loops: Vec<LoopSet>,
}

impl PaperFigures {
    /// True when no figure has data.
    pub fn is_empty(&self) -> bool {
        self.forces.is_empty() && self.delta_fits.is_empty() && self.loops.is_empty()
    }
}

/// The regression variables of `case` as the identification used them: pitch about the
/// case's mean when it was regressed about it.
fn variables(case: &NondimCase, mean_pitch: Option<f64>) -> [Vec<f64>; 4] {
    let mut x = case.x.clone();
    if let Some(m) = mean_pitch {
        x[0].iter_mut().for_each(|a| *a -= m);
    }
    x
}

/// Least squares of `y` on the columns of `terms` evaluated on `x`; (coefficients, R²,
/// model). `None` when a term does not parse.
fn fit(x: &[Vec<f64>; 4], y: &[f64], terms: &[String]) -> Option<(Vec<f64>, f64, Vec<f64>)> {
    let parsed: Vec<Term> = terms
        .iter()
        .map(|t| Term::parse(t).ok())
        .collect::<Option<_>>()?;
    let n = y.len();
    let q = parsed.len();
    let mut a = vec![0.0; n * q];
    for (j, t) in parsed.iter().enumerate() {
        for i in 0..n {
            a[j * n + i] = t.eval_at([x[0][i], x[1][i], x[2][i], x[3][i]]);
        }
    }
    let (c, rss) = identify::numerics::qr::lstsq(&a, n, q, y, 0.0);
    let mean = y.iter().sum::<f64>() / n as f64;
    let tss: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    let model = (0..n)
        .map(|i| (0..q).map(|j| c[j] * a[j * n + i]).sum())
        .collect();
    Some((c, 1.0 - rss / tss, model))
}

/// Fits of `case_id` (of group `group`) at the high, selected and low δ of its group's path,
/// for both forces.
pub fn delta_fits(
    id: &Identification,
    cases: &[NondimCase],
    group: &str,
    case_id: &str,
) -> Vec<DeltaFits> {
    let (Some(g), Some(ci)) = (
        id.groups.iter().find(|g| g.name == group),
        id.cases.iter().position(|c| c.id == case_id),
    ) else {
        return vec![];
    };
    let Some(case) = cases.iter().find(|c| c.meta.id == case_id) else {
        return vec![];
    };
    let x = variables(case, id.cases[ci].mean_pitch);
    let n_win = ((WINDOW_S / case.dt).ceil() as usize).min(case.len());
    let t: Vec<f64> = (0..n_win).map(|i| i as f64 * case.dt).collect();
    [
        (Channel::Lift, &g.lift, &case.c_lift),
        (Channel::Moment, &g.moment, &case.c_moment),
    ]
    .into_iter()
    .filter_map(|(force, gf, y): (Channel, &GroupForce, &Vec<f64>)| {
        let sparsest = gf.path.iter().rev().find(|p| p.n_terms > 0)?;
        let densest = gf.path.first()?;
        let picks = [
            ("high δ", sparsest.delta, &sparsest.support),
            ("selected δ", gf.delta_range, &gf.support),
            ("low δ", densest.delta, &densest.support),
        ];
        let fits = picks
            .into_iter()
            .filter_map(|(label, delta, support)| {
                let (c, r2, model) = fit(&x, y, support)?;
                Some(DeltaFit {
                    label: label.into(),
                    delta,
                    coefficients: support.iter().cloned().zip(c).collect(),
                    r2,
                    model: model[..n_win].to_vec(),
                })
            })
            .collect::<Vec<_>>();
        (fits.len() == 3).then(|| DeltaFits {
            group: group.into(),
            case: case_id.into(),
            force,
            t: t.clone(),
            measured: y[..n_win].to_vec(),
            fits,
        })
    })
    .collect()
}

/// One loop: the last [`LOOP_PERIODS`] periods of the slowest forcing of `case`.
fn force_loop(case: &NondimCase, label: String) -> Option<ForceLoop> {
    let f = [case.meta.freq_pitch, case.meta.freq_heave]
        .into_iter()
        .flatten()
        .filter(|f| *f > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !f.is_finite() {
        return None;
    }
    let n = case.len();
    let k = ((LOOP_PERIODS / f / case.dt).ceil() as usize).min(n);
    let r = n - k..n;
    Some(ForceLoop {
        label,
        case: case.meta.id.clone(),
        alpha_deg: case.x[0][r.clone()]
            .iter()
            .map(|a| a.to_degrees())
            .collect(),
        c_lift: case.c_lift[r.clone()].to_vec(),
        c_moment: case.c_moment[r].to_vec(),
    })
}

/// At most [`MAX_LOOPS`] of `v`, evenly spaced, ends included (more overlap unreadably).
fn thin<T: Copy>(v: Vec<T>) -> Vec<T> {
    if v.len() <= MAX_LOOPS {
        return v;
    }
    let last = v.len() - 1;
    let mut idx: Vec<usize> = (0..MAX_LOOPS)
        .map(|i| (i * last + (MAX_LOOPS - 1) / 2) / (MAX_LOOPS - 1))
        .collect();
    idx.dedup();
    idx.into_iter().map(|i| v[i]).collect()
}

/// Loops of configuration `config`: across wind speed at its largest amplitude, and across
/// amplitude at its highest wind speed.
pub fn loop_sets(cases: &[NondimCase], config: &str) -> Vec<LoopSet> {
    let of: Vec<&NondimCase> = cases
        .iter()
        .filter(|c| c.meta.config.as_deref() == Some(config) && c.meta.amplitude.is_some())
        .collect();
    let amp = |c: &NondimCase| c.meta.amplitude.unwrap_or(0.0);
    let (Some(a_max), Some(u_max)) = (
        of.iter().map(|c| amp(c)).max_by(f64::total_cmp),
        of.iter().map(|c| c.meta.wind_speed).max_by(f64::total_cmp),
    ) else {
        return vec![];
    };
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
    let mut across_u: Vec<&NondimCase> =
        of.iter().copied().filter(|c| same(amp(c), a_max)).collect();
    across_u.sort_by(|a, b| a.meta.wind_speed.total_cmp(&b.meta.wind_speed));
    let mut across_a: Vec<&NondimCase> = of
        .iter()
        .copied()
        .filter(|c| same(c.meta.wind_speed, u_max))
        .collect();
    across_a.sort_by(|a, b| amp(a).total_cmp(&amp(b)));
    let (across_u, across_a) = (thin(across_u), thin(across_a));
    let fmt = |x: f64| format!("{}", (x * 1e6).round() / 1e6);
    let mut sets = vec![];
    if across_u.len() > 1 {
        sets.push(LoopSet {
            config: config.into(),
            fixed: format!("amplitude {}°", fmt(a_max.to_degrees())),
            varied: "wind speed".into(),
            loops: across_u
                .iter()
                .filter_map(|c| force_loop(c, format!("U = {} m/s", fmt(c.meta.wind_speed))))
                .collect(),
        });
    }
    if across_a.len() > 1 {
        sets.push(LoopSet {
            config: config.into(),
            fixed: format!("U = {} m/s", fmt(u_max)),
            varied: "amplitude".into(),
            loops: across_a
                .iter()
                .filter_map(|c| force_loop(c, format!("A = {}°", fmt(amp(c).to_degrees()))))
                .collect(),
        });
    }
    sets
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_both_ends_and_spaces_evenly() {
        assert_eq!(thin((0..8).collect()), vec![0, 2, 5, 7]);
        assert_eq!(thin((0..3).collect()), vec![0, 1, 2]);
        assert_eq!(thin((0..100).collect())[3], 99);
    }

    #[test]
    fn least_squares_recovers_a_two_term_law_and_its_r2() {
        let n = 400;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let a: Vec<f64> = t.iter().map(|t| 0.2 * (6.0 * t).sin()).collect();
        let ad: Vec<f64> = t.iter().map(|t| 0.3 * (6.0 * t).cos()).collect();
        let x = [a.clone(), ad.clone(), vec![0.0; n], vec![0.0; n]];
        let y: Vec<f64> = (0..n).map(|i| 2.0 * a[i] - 0.5 * a[i].powi(3)).collect();
        let (c, r2, model) = fit(&x, &y, &["alpha".into(), "alpha^3".into()]).unwrap();
        assert!(
            (c[0] - 2.0).abs() < 1e-10 && (c[1] + 0.5).abs() < 1e-9,
            "{c:?}"
        );
        assert!((r2 - 1.0).abs() < 1e-12);
        assert!((model[7] - y[7]).abs() < 1e-12);
        // a missing term leaves a misfit
        let (_, r2, _) = fit(&x, &y, &["alpha_dot".into()]).unwrap();
        assert!(r2 < 0.1, "{r2}");
        assert!(fit(&x, &y, &["nope".into()]).is_none());
    }
}
