//! Candidate augmentations of the sim, fitted on training runs and scored on held-out
//! runs through the equation-error residual.
//!
//! Every candidate adds terms Φ(t)θ to the structural side of the equations of motion,
//! r_aug = r − Φθ, linear in its coefficients θ; nonlinear parameters (a freeplay half
//! gap, a friction smoothing scale, the form of an offset) are chosen on a fixed grid by
//! the training error. The fit minimises the same normalised energy the gap uses:
//! Σ_runs Σ_c mean_t((r_c − Φ_c θ)²)/norm_c², so every run and channel counts equally.
//! Because everything is quadratic in θ, each run is reduced once to its moments
//! (ΦᵀWΦ, ΦᵀWr, rᵀWr per channel) and every fold is a small solve.
//!
//! The generic forms (not the generator's):
//! * `added_mass`: ΔM q̈ with a general 2×2 ΔM (4 coefficients: mass error or spurious
//!   apparent mass of the identified law);
//! * `time_delay`: the aerodynamic force delayed by τ, to first order F(t−τ) ≈ F − τḞ
//!   (1 coefficient τ shared by both channels);
//! * `structural_cubic`: c_h h³ and c_α α³ springs (2);
//! * `freeplay`: a pitch dead band of half gap δ, k·clamp(α, −δ, δ) (the spring force
//!   missing inside the gap; δ on a grid 0.05°…3°, k fitted: 2 parameters);
//! * `friction`: F_c tanh(ḣ/ε_h), T_c tanh(α̇/ε_α), ε a fraction (grid 0.01, 0.03, 0.1)
//!   of the pooled rms velocity (3 parameters);
//! * `structural_polynomial`: k₂h² + k₃h³ and k₂α² + k₃α³ springs, even and odd (4);
//! * `structural_damping`: amplitude-dependent damping c₂h²ḣ, c₂α²α̇ (2);
//! * `static_offset`: a constant force and moment, either constant in U (structural zero
//!   offset) or ∝ ½ρU² (aerodynamic mean-angle offset), chosen by training error (3).

use identify::numerics::{cholesky_in_place, cholesky_solve_in_place, PivotFloor};

use crate::effect::Effect;

use super::residual::RunResidual;

/// One regressor column: its series per channel over the kept samples (empty = 0).
pub(crate) type Column = [Vec<f64>; 2];

/// A variant of a candidate: grid parameters and the columns of every run.
pub(crate) struct Variant {
    #[allow(dead_code)]
    pub grid: Vec<(String, f64)>,
    pub names: Vec<String>,
    /// `moments[run]`.
    pub moments: Vec<Moments>,
}

/// Moments of one run for one variant: per channel G_c = ΦᵀW_cΦ, g_c = ΦᵀW_c r,
/// e_c = rᵀW_c r with W_c = 1/(n norm_c²).
#[derive(Debug, Clone)]
pub(crate) struct Moments {
    pub g: [Vec<f64>; 2],
    pub b: [Vec<f64>; 2],
    pub e: [f64; 2],
}

fn moments(run: &RunResidual, cols: &[Column]) -> Moments {
    let p = cols.len();
    let n = run.len() as f64;
    let mut g = [vec![0.0; p * p], vec![0.0; p * p]];
    let mut b = [vec![0.0; p], vec![0.0; p]];
    let mut e = [0.0; 2];
    for c in 0..2 {
        let w = 1.0 / (n * run.norm[c].powi(2));
        let r = &run.r[c];
        e[c] = w * r.iter().map(|v| v * v).sum::<f64>();
        for a in 0..p {
            let xa = &cols[a][c];
            if xa.is_empty() {
                continue;
            }
            b[c][a] = w * xa.iter().zip(r).map(|(x, y)| x * y).sum::<f64>();
            for bb in 0..=a {
                let xb = &cols[bb][c];
                if xb.is_empty() {
                    continue;
                }
                let v = w * xa.iter().zip(xb).map(|(x, y)| x * y).sum::<f64>();
                g[c][a * p + bb] = v;
                g[c][bb * p + a] = v;
            }
        }
    }
    Moments { g, b, e }
}

/// Nuisance columns of one run (issue 29), two pooled groups of apparent-mass terms
/// ΔM q̈, each as q̈_d in the heave and in the pitch equation for the DOFs d of the group:
/// * group 0, the extrapolation: the motion whose response K leaves its forced range
///   (the part of the law a campaign forced below the free runs' K cannot know: the K²
///   apparent-mass terms of H₄*, A₃*…, beyond the Theodorsen-shaped tails the sim
///   already continues with);
/// * group 1, still air: both DOFs of the runs at U = 0 (the air's apparent mass, which
///   no identified law predicts at U = 0).
///
/// `flags[g][d]`: the run has group g's term for DOF d (else its column is empty on this
/// run); `dofs[g][d]`: some run has it (the column exists).
pub(crate) fn nuisance_columns(
    run: &RunResidual,
    flags: [[bool; 2]; 2],
    dofs: [[bool; 2]; 2],
) -> Vec<Column> {
    let mut v = Vec::new();
    for g in 0..2 {
        for d in (0..2).filter(|&d| dofs[g][d]) {
            let x = if flags[g][d] {
                kept(run, &run.qdd[d])
            } else {
                Vec::new()
            };
            v.push([x.clone(), Vec::new()]);
            v.push([Vec::new(), x]);
        }
    }
    v
}

impl Variant {
    /// The variant restricted to the coefficients `idx` (a form of the candidate: pitch
    /// terms only, heave terms only…): principal sub-blocks of every run's moments.
    pub(crate) fn select(&self, idx: &[usize]) -> Variant {
        let p = self.names.len();
        Variant {
            grid: self.grid.clone(),
            names: idx.iter().map(|&i| self.names[i].clone()).collect(),
            moments: self
                .moments
                .iter()
                .map(|m| Moments {
                    g: [0, 1].map(|c| {
                        idx.iter()
                            .flat_map(|&a| idx.iter().map(move |&b| (a, b)))
                            .map(|(a, b)| m.g[c][a * p + b])
                            .collect()
                    }),
                    b: [0, 1].map(|c| idx.iter().map(|&a| m.b[c][a]).collect()),
                    e: m.e,
                })
                .collect(),
        }
    }
}

/// Solves (G + λ diag G) θ = b by Cholesky (tiny ridge for conditioning); `None` when
/// singular.
pub(crate) fn solve(g: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let p = b.len();
    let mut a = g.to_vec();
    let scale = (0..p).map(|i| a[i * p + i]).fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    let mut y = b.to_vec();
    for i in 0..p {
        if a[i * p + i] == 0.0 {
            // a column empty on every training run (a nuisance term of a held-out run
            // only): its coefficient is 0
            a[i * p + i] = scale;
            y[i] = 0.0;
        }
        a[i * p + i] += 1e-10 * a[i * p + i].abs();
    }
    cholesky_in_place(&mut a, p, PivotFloor::Absolute(1e-13 * scale)).ok()?;
    cholesky_solve_in_place(&a, p, &mut y);
    Some(y)
}

/// Energy after θ of a run's moments, per channel: e − 2θᵀb + θᵀGθ.
pub(crate) fn energy_after(m: &Moments, theta: &[f64]) -> [f64; 2] {
    let p = theta.len();
    [0, 1].map(|c| {
        let mut v = m.e[c];
        for a in 0..p {
            v -= 2.0 * theta[a] * m.b[c][a];
            for bb in 0..p {
                v += theta[a] * m.g[c][a * p + bb] * theta[bb];
            }
        }
        v.max(0.0)
    })
}

/// Sum of moments over `runs` (both channels together): (G, b, e).
pub(crate) fn pooled(v: &Variant, runs: &[usize]) -> (Vec<f64>, Vec<f64>, f64) {
    let p = v.names.len();
    let mut g = vec![0.0; p * p];
    let mut b = vec![0.0; p];
    let mut e = 0.0;
    for &j in runs {
        let m = &v.moments[j];
        for c in 0..2 {
            for (x, y) in g.iter_mut().zip(&m.g[c]) {
                *x += y;
            }
            for (x, y) in b.iter_mut().zip(&m.b[c]) {
                *x += y;
            }
            e += m.e[c];
        }
    }
    (g, b, e)
}

/// The fitted variant on `runs`: (variant index, θ, training energy after).
pub(crate) fn fit(variants: &[Variant], runs: &[usize]) -> Option<(usize, Vec<f64>, f64)> {
    let mut best: Option<(usize, Vec<f64>, f64)> = None;
    for (k, v) in variants.iter().enumerate() {
        let (g, b, e) = pooled(v, runs);
        let Some(theta) = solve(&g, &b) else { continue };
        let after = e - theta.iter().zip(&b).map(|(t, y)| t * y).sum::<f64>();
        if best.as_ref().is_none_or(|x| after < x.2) {
            best = Some((k, theta, after));
        }
    }
    best
}

/// Kept-sample slice of a whole-run series.
fn kept(run: &RunResidual, x: &[f64]) -> Vec<f64> {
    x[run.i0..run.i1].to_vec()
}

/// A non-smooth structural force series (whole run) as the residual sees it
/// ([`RunResidual::as_acceleration_term`]); the raw kept samples if that fails.
fn acc_term(run: &RunResidual, x: &[f64]) -> Vec<f64> {
    run.as_acceleration_term(x)
        .unwrap_or_else(|| x[run.i0..run.i1].to_vec())
}

/// Columns of one candidate variant for one run.
fn columns(effect: Effect, grid: &[f64], run: &RunResidual, rho: f64, chord: f64) -> Vec<Column> {
    let z = Vec::new;
    match effect {
        Effect::AddedMass => {
            let (hdd, add) = (kept(run, &run.qdd[0]), kept(run, &run.qdd[1]));
            vec![
                [hdd.clone(), z()],
                [add.clone(), z()],
                [z(), hdd],
                [z(), add],
            ]
        }
        Effect::TimeDelay => {
            let d = |f: &[f64]| -> Vec<f64> {
                (run.i0..run.i1)
                    .map(|i| -(f[i + 1] - f[i - 1]) / (2.0 * run.dt))
                    .collect()
            };
            vec![[d(&run.force[0]), d(&run.force[1])]]
        }
        // restoring terms through the same smoothing as the residual's structural force
        // (their harmonics at 2f, 3f are attenuated by the differentiator as the
        // measured acceleration's are)
        Effect::StructuralCubic => {
            let p =
                |c: usize| acc_term(run, &run.q[c].iter().map(|v| v.powi(3)).collect::<Vec<_>>());
            vec![[p(0), z()], [z(), p(1)]]
        }
        Effect::Freeplay => {
            let d = grid[0];
            let x: Vec<f64> = run.q[1].iter().map(|a| a.clamp(-d, d)).collect();
            vec![[z(), acc_term(run, &x)]]
        }
        Effect::StructuralPolynomial => {
            let p = |c: usize, k: i32| {
                acc_term(run, &run.q[c].iter().map(|v| v.powi(k)).collect::<Vec<_>>())
            };
            vec![
                [p(0, 2), z()],
                [p(0, 3), z()],
                [z(), p(1, 2)],
                [z(), p(1, 3)],
            ]
        }
        Effect::StructuralDamping => {
            let p = |c: usize| -> Vec<f64> {
                let x: Vec<f64> = run.q[c]
                    .iter()
                    .zip(&run.qd[c])
                    .map(|(q, v)| q * q * v)
                    .collect();
                acc_term(run, &x)
            };
            vec![[p(0), z()], [z(), p(1)]]
        }
        Effect::Friction => {
            let (eh, ea) = (grid[0], grid[1]);
            let xh: Vec<f64> = run.qd[0].iter().map(|v| (v / eh).tanh()).collect();
            let xa: Vec<f64> = run.qd[1].iter().map(|v| (v / ea).tanh()).collect();
            vec![[acc_term(run, &xh), z()], [z(), acc_term(run, &xa)]]
        }
        Effect::StaticOffset => {
            let s = if grid[0] > 0.5 {
                0.5 * rho * run.u * run.u
            } else {
                1.0
            };
            let n = run.len();
            vec![[vec![s * chord; n], z()], [z(), vec![s * chord * chord; n]]]
        }
        _ => Vec::new(),
    }
}

/// Names of the coefficients of a candidate.
pub(crate) fn coefficient_names(effect: Effect) -> Vec<String> {
    let v: &[&str] = match effect {
        Effect::AddedMass => &["dM_hh_kg_per_m", "dM_ha_kg", "dM_ah_kg", "dM_aa_kg_m"],
        Effect::TimeDelay => &["tau_s"],
        Effect::StructuralCubic => &["k3_heave_N_per_m3", "k3_pitch_Nm_per_rad3"],
        Effect::Freeplay => &["gap_stiffness_Nm_per_rad"],
        Effect::Friction => &["friction_heave_N_per_m", "friction_pitch_Nm_per_m"],
        Effect::StaticOffset => &["offset_coefficient_lift", "offset_coefficient_moment"],
        Effect::StructuralPolynomial => &[
            "k2_heave_N_per_m2",
            "k3_heave_N_per_m3",
            "k2_pitch_Nm_per_rad2",
            "k3_pitch_Nm_per_rad3",
        ],
        Effect::StructuralDamping => &["c2_heave_Ns_per_m3", "c2_pitch_Nms_per_rad3"],
        _ => &[],
    };
    v.iter().map(|s| s.to_string()).collect()
}

/// The system-level candidates, in catalogue order.
pub(crate) const CANDIDATES: [Effect; 8] = [
    Effect::StaticOffset,
    Effect::AddedMass,
    Effect::TimeDelay,
    Effect::StructuralCubic,
    Effect::Freeplay,
    Effect::Friction,
    Effect::StructuralPolynomial,
    Effect::StructuralDamping,
];

/// Freeplay half-gap grid \[deg\].
pub(crate) const FREEPLAY_GRID_DEG: [f64; 14] = [
    0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0, 1.4, 2.0, 2.5, 3.0,
];
/// Friction smoothing grid (fractions of the pooled rms velocity).
pub(crate) const FRICTION_GRID: [f64; 3] = [0.01, 0.03, 0.1];

/// Grid parameters of every variant of a candidate (names and SI values).
pub(crate) fn variants_grid(effect: Effect, runs: &[RunResidual]) -> Vec<Vec<(String, f64)>> {
    grids(effect, runs).into_iter().map(|g| g.0).collect()
}

type Grid = Vec<(Vec<(String, f64)>, Vec<f64>)>;

fn grids(effect: Effect, runs: &[RunResidual]) -> Grid {
    match effect {
        Effect::Freeplay => FREEPLAY_GRID_DEG
            .iter()
            .map(|d| {
                (
                    vec![("half_gap_rad".into(), d.to_radians())],
                    vec![d.to_radians()],
                )
            })
            .collect(),
        Effect::Friction => {
            let rms = |c: usize| {
                let (s, n) = runs.iter().fold((0.0, 0usize), |(s, n), r| {
                    (
                        s + r.qd[c][r.i0..r.i1].iter().map(|v| v * v).sum::<f64>(),
                        n + r.len(),
                    )
                });
                (s / n.max(1) as f64).sqrt().max(1e-12)
            };
            let (vh, va) = (rms(0), rms(1));
            FRICTION_GRID
                .iter()
                .map(|f| {
                    (
                        vec![
                            ("smoothing_heave_m_per_s".into(), f * vh),
                            ("smoothing_pitch_rad_per_s".into(), f * va),
                        ],
                        vec![f * vh, f * va],
                    )
                })
                .collect()
        }
        Effect::StaticOffset => vec![
            (vec![("proportional_to_q_dyn".into(), 0.0)], vec![0.0]),
            (vec![("proportional_to_q_dyn".into(), 1.0)], vec![1.0]),
        ],
        _ => vec![(Vec::new(), Vec::new())],
    }
}

/// All variants of a candidate over the runs, its columns followed by the nuisance
/// columns ([`nuisance_columns`]; `flags[j]`: run j's nuisance terms; no nuisance column
/// that no run has).
pub(crate) fn variants(
    effect: Effect,
    runs: &[RunResidual],
    rho: f64,
    chord: f64,
    flags: &[[[bool; 2]; 2]],
) -> Vec<Variant> {
    let dofs = [0, 1].map(|g| [0, 1].map(|d| flags.iter().any(|f| f[g][d])));
    let mut names = coefficient_names(effect);
    for g in 0..2 {
        for d in (0..2).filter(|&d| dofs[g][d]) {
            let (group, q) = (["extrapolation", "still_air"][g], ["h", "alpha"][d]);
            names.push(format!("nuisance_{group}_dM_heave_{q}"));
            names.push(format!("nuisance_{group}_dM_pitch_{q}"));
        }
    }
    grids(effect, runs)
        .into_iter()
        .map(|(grid, g)| Variant {
            grid,
            names: names.clone(),
            moments: runs
                .iter()
                .enumerate()
                .map(|(j, r)| {
                    let mut cols = columns(effect, &g, r, rho, chord);
                    let f = flags.get(j).copied().unwrap_or([[false; 2]; 2]);
                    cols.extend(nuisance_columns(r, f, dofs));
                    moments(r, &cols)
                })
                .collect(),
        })
        .collect()
}

/// The forms of a candidate, simplest first: (label, coefficient indices). Structural
/// terms come as pitch only, heave only, and both DOFs; the choice among them follows the
/// one-standard-error rule of [`super`] (DECISIONS, "The simplest sufficient effect").
pub(crate) fn forms(effect: Effect) -> Vec<(&'static str, Vec<usize>)> {
    match effect {
        Effect::StructuralCubic | Effect::StructuralDamping | Effect::Friction => vec![
            ("pitch", vec![1]),
            ("heave", vec![0]),
            ("pitch+heave", vec![0, 1]),
        ],
        Effect::StructuralPolynomial => vec![
            ("pitch", vec![2, 3]),
            ("heave", vec![0, 1]),
            ("pitch+heave", vec![0, 1, 2, 3]),
        ],
        _ => {
            let n = coefficient_names(effect).len();
            vec![("all", (0..n).collect())]
        }
    }
}

/// Number of grid parameters of a candidate (fitted on a grid, not by least squares).
pub(crate) fn n_grid_params(effect: Effect) -> usize {
    match effect {
        Effect::Freeplay | Effect::Friction | Effect::StaticOffset => 1,
        _ => 0,
    }
}

/// Sign that turns a fitted coefficient θ into the reported one. The fit writes the
/// augmentation like an aerodynamic force on the right of M q̈ + C q̇ + K q = F
/// (r_aug = r − Φθ); structural springs, dampers and friction are reported as the extra
/// restoring or dissipative force on the left, added to C q̇ + K q, so their sign flips.
pub(crate) fn report_sign(effect: Effect) -> f64 {
    match effect {
        Effect::StructuralCubic
        | Effect::StructuralPolynomial
        | Effect::StructuralDamping
        | Effect::Friction => -1.0,
        _ => 1.0,
    }
}

/// The sign convention of a candidate's reported parameters (written in diagnosis.json).
pub(crate) fn convention(effect: Effect) -> &'static str {
    match effect {
        Effect::StructuralCubic => {
            "extra restoring force added to K q: heave k3_heave·h³ [N/m], pitch \
             k3_pitch·α³ [N·m/m]; h positive down, α positive nose-up; k3 > 0 hardening"
        }
        Effect::StructuralPolynomial => {
            "extra restoring force added to K q: heave k2_heave·h² + k3_heave·h³ [N/m], \
             pitch k2_pitch·α² + k3_pitch·α³ [N·m/m]; h positive down, α positive nose-up"
        }
        Effect::StructuralDamping => {
            "extra damping force added to C q̇: c2_heave·h²ḣ [N/m], c2_pitch·α²α̇ [N·m/m]; \
             c2 > 0 damping that grows with amplitude"
        }
        Effect::Friction => {
            "extra dissipative force added to C q̇: friction·tanh(q̇/smoothing) (heave N/m, \
             pitch N·m/m); > 0 opposes the motion"
        }
        Effect::Freeplay => {
            "pitch restoring moment lost inside the gap: gap_stiffness·clamp(α, −half_gap, \
             half_gap) [N·m/m] (gap_stiffness ≈ k_α for a true dead band)"
        }
        Effect::AddedMass => {
            "extra force dM·q̈ on the right of M q̈ + C q̇ + K q = F: dM < 0 is mass the \
             sim lacks (e.g. apparent mass), dM > 0 mass it has too much of"
        }
        Effect::TimeDelay => "aerodynamic force F(t − τ), τ > 0 a lag [s]",
        Effect::StaticOffset => {
            "constant lift (positive down) and moment (positive nose-up) coefficients, × ½ρU² \
             when proportional_to_q_dyn = 1"
        }
        _ => "",
    }
}

/// The candidate's extra residual columns for one run at fitted grid values, for
/// re-evaluating the augmented residual sample by sample (where/spectra).
pub(crate) fn run_columns(
    effect: Effect,
    grid: &[(String, f64)],
    run: &RunResidual,
    rho: f64,
    chord: f64,
) -> Vec<Column> {
    let g: Vec<f64> = grid.iter().map(|x| x.1).collect();
    columns(effect, &g, run, rho, chord)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_a_small_system() {
        let g = [4.0, 1.0, 1.0, 3.0];
        let b = [1.0, 2.0];
        let x = solve(&g, &b).unwrap();
        assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-8);
        assert!((x[0] + 3.0 * x[1] - 2.0).abs() < 1e-8);
        assert!(solve(&[0.0, 0.0, 0.0, 0.0], &[1.0, 1.0]).is_none());
    }
}
