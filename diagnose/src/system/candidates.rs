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

/// Solves (G + λ diag G) θ = b by Cholesky (tiny ridge for conditioning); `None` when
/// singular.
pub(crate) fn solve(g: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let p = b.len();
    let mut a = g.to_vec();
    let scale = (0..p).map(|i| a[i * p + i]).fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    for i in 0..p {
        a[i * p + i] += 1e-10 * a[i * p + i].abs();
    }
    cholesky_in_place(&mut a, p, PivotFloor::Absolute(1e-13 * scale)).ok()?;
    let mut y = b.to_vec();
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
        Effect::StructuralCubic => vec![
            [
                kept(run, &run.q[0]).iter().map(|v| v.powi(3)).collect(),
                z(),
            ],
            [
                z(),
                kept(run, &run.q[1]).iter().map(|v| v.powi(3)).collect(),
            ],
        ],
        Effect::Freeplay => {
            let d = grid[0];
            let x: Vec<f64> = run.q[1].iter().map(|a| a.clamp(-d, d)).collect();
            vec![[z(), acc_term(run, &x)]]
        }
        Effect::StructuralPolynomial => {
            let p = |c: usize, k: i32| kept(run, &run.q[c]).iter().map(|v| v.powi(k)).collect();
            vec![
                [p(0, 2), z()],
                [p(0, 3), z()],
                [z(), p(1, 2)],
                [z(), p(1, 3)],
            ]
        }
        Effect::StructuralDamping => {
            let p = |c: usize| -> Vec<f64> {
                (run.i0..run.i1)
                    .map(|i| run.q[c][i].powi(2) * run.qd[c][i])
                    .collect()
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

/// Number of parameters a candidate adds (coefficients + grid parameters).
pub(crate) fn n_params(effect: Effect) -> usize {
    match effect {
        Effect::AddedMass => 4,
        Effect::TimeDelay => 1,
        Effect::StructuralCubic => 2,
        Effect::Freeplay => 2,
        Effect::Friction => 3,
        Effect::StaticOffset => 3,
        Effect::StructuralPolynomial => 4,
        Effect::StructuralDamping => 2,
        _ => 0,
    }
}

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

/// All variants of a candidate over the runs.
pub(crate) fn variants(effect: Effect, runs: &[RunResidual], rho: f64, chord: f64) -> Vec<Variant> {
    grids(effect, runs)
        .into_iter()
        .map(|(grid, g)| Variant {
            grid,
            names: coefficient_names(effect),
            moments: runs
                .iter()
                .map(|r| moments(r, &columns(effect, &g, r, rho, chord)))
                .collect(),
        })
        .collect()
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
