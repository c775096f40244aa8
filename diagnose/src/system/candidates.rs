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
//! Each effect's generic form (not the generator's) is its [`SystemTerm`], in its file of
//! `crate::catalogue` (e.g. `added_mass`: ΔM q̈ with a general 2×2 ΔM; `freeplay`:
//! k·clamp(α, −δ, δ) with δ on a grid).

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

pub(crate) fn moments(run: &RunResidual, cols: &[Column]) -> Moments {
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

/// Nuisance columns of one run: two pooled groups of apparent-mass terms ΔM q̈ (issue 29),
/// each as q̈_d in the heave and in the pitch equation for the DOFs d of the group, and a
/// group of linear stiffness terms:
/// * group 0, the extrapolation: the motion whose response K leaves its forced range
///   (the part of the law a campaign forced below the free runs' K cannot know: the K²
///   apparent-mass terms of H₄*, A₃*…, beyond the Theodorsen-shaped tails the sim
///   already continues with);
/// * group 1, still air: both DOFs of the runs at U = 0 (the air's apparent mass, which
///   no identified law predicts at U = 0);
/// * group 2, the linear structure (issue 42 item 5, round 30): a stiffness correction
///   Δk_d q_d in DOF d's own equation, pooled over the runs in the wind (in still air the
///   free apparent mass of group 1 and a stiffness together would follow any backbone:
///   Δk − ΔM ω(t)² tracks a cubic's A(t)² along a decay), for the DOFs whose still-air
///   mode the decays read off the given structure (see [`super`]'s `rest_check`): what a
///   nonlinear structural candidate removes beyond it is amplitude dependence, not the
///   given structure's linear error. One column per DOF, through the residual's smoothing
///   ([`acc_term`], as the structure's own K q).
///
/// `flags[g][d]`: the run has group g's term for DOF d (else its column is empty on this
/// run); `dofs[g][d]`: some run has it (the column exists).
pub(crate) fn nuisance_columns(run: &RunResidual, flags: Flags, dofs: Flags) -> Vec<Column> {
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
    for d in (0..2).filter(|&d| dofs[2][d]) {
        let x = if flags[2][d] {
            acc_term(run, &run.q[d])
        } else {
            Vec::new()
        };
        let mut col: Column = [Vec::new(), Vec::new()];
        col[d] = x;
        v.push(col);
    }
    v
}

/// Per-run nuisance flags `[group][dof]` of [`nuisance_columns`] (groups: extrapolation,
/// still air, linear stiffness).
pub(crate) type Flags = [[bool; 2]; 3];

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

/// Solves (G + λ diag G) θ = b for the flat p × p moments `g`, λ = 1e-10
/// ([`crate::numerics::ridge_solve`]: a coefficient of a column empty on every training
/// run, a nuisance term of a held-out run only, is 0); `None` when singular.
pub(crate) fn solve(g: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let p = b.len();
    crate::numerics::ridge_solve(|i, j| g[i * p + j], b, 1e-10)
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
pub(crate) fn kept(run: &RunResidual, x: &[f64]) -> Vec<f64> {
    x[run.i0..run.i1].to_vec()
}

/// A non-smooth structural force series (whole run) as the residual sees it
/// ([`RunResidual::as_acceleration_term`]); the raw kept samples if that fails.
pub(crate) fn acc_term(run: &RunResidual, x: &[f64]) -> Vec<f64> {
    run.as_acceleration_term(x)
        .unwrap_or_else(|| x[run.i0..run.i1].to_vec())
}

/// Grid variants of a candidate: (named grid values in SI units, the values).
pub(crate) type Grid = Vec<(Vec<(String, f64)>, Vec<f64>)>;

/// An effect's terms at the system level: the columns Φ of the equation-error fit, linear
/// in the coefficients θ (r_aug = r − Φθ), nonlinear parameters on a grid, and the same
/// terms in the augmented simulation ([`super::simulate`]).
pub(crate) trait SystemTerm: Sync {
    /// Names of the coefficients θ, with their SI unit.
    fn coefficient_names(&self) -> &'static [&'static str];

    /// The grid variants over `runs` (default: one variant without grid parameters).
    fn grids(&self, runs: &[RunResidual]) -> Grid {
        let _ = runs;
        vec![(Vec::new(), Vec::new())]
    }

    /// Number of grid parameters (fitted on a grid, not by least squares).
    fn n_grid_params(&self) -> usize {
        0
    }

    /// The columns of `run` at grid values `grid` (ρ \[kg/m³\], chord B \[m\]).
    fn columns(&self, grid: &[f64], run: &RunResidual, rho: f64, chord: f64) -> Vec<Column>;

    /// The forms of the candidate, simplest first: (label, coefficient indices).
    /// Structural terms come as pitch only, heave only, and both DOFs; the choice among
    /// them follows the one-standard-error rule of [`super`] (DECISIONS, "The simplest
    /// sufficient effect"). Default: one form with every coefficient.
    fn forms(&self) -> Vec<(&'static str, Vec<usize>)> {
        vec![("all", (0..self.coefficient_names().len()).collect())]
    }

    /// Sign that turns a fitted coefficient θ into the reported one. The fit writes the
    /// augmentation like an aerodynamic force on the right of M q̈ + C q̇ + K q = F
    /// (r_aug = r − Φθ); structural springs, dampers and friction are reported as the
    /// extra restoring or dissipative force on the left, added to C q̇ + K q, so their
    /// sign flips (−1).
    fn report_sign(&self) -> f64 {
        1.0
    }

    /// Whether a negative reported coefficient is no such effect (a dead band removes
    /// stiffness, friction opposes the motion: the other sign would only mimic a
    /// hardening spring or a negative damping).
    fn sign_bound(&self) -> bool {
        false
    }

    /// The sign convention of the reported parameters (written in diagnosis.json).
    fn convention(&self) -> &'static str;

    /// The term's force in the augmented simulation at grid values `grid` and
    /// coefficients `theta`: Φ(q, q̇)θ on the right of the equations of motion, like an
    /// aerodynamic force \[N/m, N·m/m\] (q_dyn = ½ρU² \[Pa\], chord B \[m\]).
    fn force(
        &self,
        grid: &[f64],
        theta: &[f64],
        q: [f64; 2],
        qd: [f64; 2],
        q_dyn: f64,
        chord: f64,
    ) -> [f64; 2] {
        let _ = (grid, theta, q, qd, q_dyn, chord);
        [0.0; 2]
    }

    /// The mass ΔM the fitted term adds on the right, ΔM q̈ (the structure carries
    /// M_s − ΔM), rows \[kg/m, kg; kg, kg·m\].
    fn mass(&self, theta: &[f64]) -> [[f64; 2]; 2] {
        let _ = theta;
        [[0.0; 2]; 2]
    }

    /// The delay τ \[s\] of the aerodynamic force, F(t − τ) ≈ F − τḞ.
    fn delay(&self, theta: &[f64]) -> f64 {
        let _ = theta;
        0.0
    }
}

/// All variants of a candidate over the runs, its columns followed by the nuisance
/// columns ([`nuisance_columns`]; `flags[j]`: run j's nuisance terms; no nuisance column
/// that no run has) and, when some run has a raw control signal, the control's gain and
/// offset columns ([`control_columns`]).
pub(crate) fn variants(
    term: &dyn SystemTerm,
    runs: &[RunResidual],
    rho: f64,
    chord: f64,
    flags: &[Flags],
) -> Vec<Variant> {
    let dofs = [0, 1, 2].map(|g| [0, 1].map(|d| flags.iter().any(|f| f[g][d])));
    let mut names: Vec<String> = term
        .coefficient_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    for g in 0..2 {
        for d in (0..2).filter(|&d| dofs[g][d]) {
            let (group, q) = (["extrapolation", "still_air"][g], ["h", "alpha"][d]);
            names.push(format!("nuisance_{group}_dM_heave_{q}"));
            names.push(format!("nuisance_{group}_dM_pitch_{q}"));
        }
    }
    for d in (0..2).filter(|&d| dofs[2][d]) {
        names.push(format!("nuisance_structure_dk_{}", ["h", "alpha"][d]));
    }
    // a raw control signal: its gain and offset are fitted with every candidate
    let control = runs.iter().any(raw_control);
    if control {
        names.extend(CONTROL_NAMES.iter().map(|s| s.to_string()));
    }
    term.grids(runs)
        .into_iter()
        .map(|(grid, g)| Variant {
            grid,
            names: names.clone(),
            moments: runs
                .iter()
                .enumerate()
                .map(|(j, r)| {
                    let mut cols = term.columns(&g, r, rho, chord);
                    let f = flags.get(j).copied().unwrap_or([[false; 2]; 3]);
                    cols.extend(nuisance_columns(r, f, dofs));
                    if control {
                        cols.extend(control_columns(r));
                    }
                    moments(r, &cols)
                })
                .collect(),
        })
        .collect()
}

/// The candidate's extra residual columns for one run at fitted grid values, for
/// re-evaluating the augmented residual sample by sample (where/spectra).
pub(crate) fn run_columns(
    term: &dyn SystemTerm,
    grid: &[(String, f64)],
    run: &RunResidual,
    rho: f64,
    chord: f64,
) -> Vec<Column> {
    let g: Vec<f64> = grid.iter().map(|x| x.1).collect();
    term.columns(&g, run, rho, chord)
}

/// Whether run `r` has a raw (fitted) control signal.
pub(crate) fn raw_control(r: &RunResidual) -> bool {
    r.control.as_ref().is_some_and(|c| !c.calibrated)
}

/// Names of the control columns appended to every candidate when some run has a raw
/// control signal ([`control_columns`]).
pub(crate) const CONTROL_NAMES: [&str; 2] = ["control_gain_heave", "control_offset_heave"];

/// The control columns of one run on DOF `dof` (0 heave, 1 pitch): S(u) and a constant,
/// empty on a run without a raw signal.
pub(crate) fn control_columns_on(r: &RunResidual, dof: usize) -> Vec<Column> {
    let mut out = vec![[Vec::new(), Vec::new()], [Vec::new(), Vec::new()]];
    if let Some(c) = r.control.as_ref().filter(|c| !c.calibrated) {
        out[0][dof] = c.column.clone();
        out[1][dof] = vec![1.0; c.column.len()];
    }
    out
}

/// The control columns of one run on the heave DOF ([`CONTROL_NAMES`]): S(u) and a constant on
/// a run with a raw signal, empty otherwise.
pub(crate) fn control_columns(r: &RunResidual) -> Vec<Column> {
    control_columns_on(r, 0)
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
