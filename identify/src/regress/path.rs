//! The δ path (paper Alg. 3) and the selection of the sparsest adequate support.
//!
//! δ runs over a logarithmic grid (default 50 values from 1e-4 to 1 for the contribution
//! measure, from 1e-3 to 10 for the raw-coefficient measure). For each δ a regressor's
//! support and coefficients are computed from the whole identifiable basis (each plug-in
//! walks its own path parameter, [`super::plugin::Regressor::fit_path`]); the path's
//! distinct supports are scored by their key-frequency loss (Eq. 14, mean over the cases of
//! the group). The selected support is the sparsest one whose loss is under the limit
//!
//! loss ≤ loss_dense·(1 + rel) + abs + c·loss_noise   (defaults rel = 0.1, abs = 1e-4, c = 3),
//!
//! loss_dense being the loss of the densest support on the path; ties in size go to the
//! lower loss. loss_noise is the loss that measurement noise alone gives a correct model:
//! the least-squares amplitude of a tone in white noise of variance σ² over n samples has
//! E|ΔA|² = 4σ²/n, so loss_noise = k·4σ̂²/(n Σ|A_i|²) with σ̂² = RSS_dense/(n − p_dense)
//! (mean over the cases of the group). The Eq. 14 loss of a correct model is then ≈
//! loss_noise·χ²₂ₖ/2k, and c = 3 leaves it out with probability ~3·10⁻⁴ for k = 6.
//! Under two-frequency harmonic motion the dense loss is ~0 (the library spans every tone
//! up to order 3, so the dense fit reproduces the measured key amplitudes, noise included),
//! which is why the limit needs the absolute and noise terms and not only the relative one.
//! A case without key frequencies (no forcing frequency known) is scored by its normalised
//! residual 1 − R² instead (noise term 0).

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::{mask_to_vec, CaseProblem, Mask, Measure};
use crate::{Error, Result};

/// Options of the δ path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PathOptions {
    /// Number of δ values (log grid).
    pub n_delta: usize,
    /// Smallest δ.
    pub delta_min: f64,
    /// Largest δ.
    pub delta_max: f64,
    /// Relative slack of the loss limit.
    pub loss_rel: f64,
    /// Absolute slack of the loss limit.
    pub loss_abs: f64,
    /// Multiple c of the noise loss added to the limit.
    pub loss_noise: f64,
}

/// Largest number of δ values on a path: the limits table's entry.
pub use crate::limits::MAX_N_DELTA;
/// Default number of δ values.
pub const DEFAULT_N_DELTA: usize = 50;
/// Default relative slack of the loss limit.
pub const DEFAULT_LOSS_REL: f64 = 0.1;
/// Default absolute slack of the loss limit.
pub const DEFAULT_LOSS_ABS: f64 = 1e-4;
/// Default multiple of the noise loss in the limit.
pub const DEFAULT_LOSS_NOISE: f64 = 3.0;

impl PathOptions {
    /// Defaults for a measure: 50 values over [1e-4, 1] (contribution) or [1e-3, 10]
    /// (raw coefficient), loss limit slack rel = 0.1, abs = 1e-4, noise multiple 3.
    pub fn for_measure(measure: Measure) -> Self {
        let (delta_min, delta_max) = default_range(measure);
        PathOptions {
            n_delta: DEFAULT_N_DELTA,
            delta_min,
            delta_max,
            loss_rel: DEFAULT_LOSS_REL,
            loss_abs: DEFAULT_LOSS_ABS,
            loss_noise: DEFAULT_LOSS_NOISE,
        }
    }

    /// Checks the options.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `n_delta`, `delta_range`, `loss_rel` or `loss_abs`.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, message: String| Error::InvalidOption {
            name: name.to_string(),
            message,
        };
        if self.n_delta == 0 || self.n_delta > MAX_N_DELTA {
            return Err(bad(
                "n_delta",
                format!("{} must be in 1..={MAX_N_DELTA}", self.n_delta),
            ));
        }
        if !(self.delta_min > 0.0 && self.delta_max >= self.delta_min && self.delta_max.is_finite())
        {
            return Err(bad(
                "delta_range",
                format!(
                    "[{}, {}] must satisfy 0 < min ≤ max < ∞",
                    self.delta_min, self.delta_max
                ),
            ));
        }
        if !(self.loss_rel >= 0.0 && self.loss_rel.is_finite()) {
            return Err(bad(
                "loss_rel",
                format!("{} must be finite and ≥ 0", self.loss_rel),
            ));
        }
        if !(self.loss_abs >= 0.0 && self.loss_abs.is_finite()) {
            return Err(bad(
                "loss_abs",
                format!("{} must be finite and ≥ 0", self.loss_abs),
            ));
        }
        if !(self.loss_noise >= 0.0 && self.loss_noise.is_finite()) {
            return Err(bad(
                "loss_noise",
                format!("{} must be finite and ≥ 0", self.loss_noise),
            ));
        }
        Ok(())
    }

    /// The δ grid, ascending, log-spaced (a single value `delta_min` when n_delta = 1).
    pub fn grid(&self) -> Vec<f64> {
        if self.n_delta == 1 {
            return vec![self.delta_min];
        }
        let (a, b) = (self.delta_min.ln(), self.delta_max.ln());
        (0..self.n_delta)
            .map(|i| (a + (b - a) * i as f64 / (self.n_delta - 1) as f64).exp())
            .collect()
    }
}

/// Default δ range of a measure.
pub fn default_range(measure: Measure) -> (f64, f64) {
    match measure {
        Measure::Contribution => (1e-4, 1.0),
        Measure::Coefficient => (1e-3, 10.0),
    }
}

/// Key-frequency data of one case and target: measured amplitudes and the amplitude of
/// every (raw) library column at the key tones.
///
/// The column amplitudes are held once per case for the union of both targets' key tones
/// (`columns`, shared between the moment's and the lift's projection) and each target
/// reads its own tones through `tones`: p × u complex numbers per case instead of
/// 2 × p × k in vectors per column.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyProjection {
    /// Measured complex amplitudes A_i (k values).
    pub measured: Vec<Complex64>,
    /// Column amplitudes at u tones, column j at `j·u .. (j + 1)·u`.
    columns: std::sync::Arc<[Complex64]>,
    /// Number of library columns p.
    n_columns: usize,
    /// Per key tone i, its position among the u tones of `columns`.
    tones: Vec<usize>,
}

impl KeyProjection {
    /// The projection of a target with measured amplitudes `measured` at its key tones,
    /// whose column amplitudes are `columns` (p columns × u tones, column j at
    /// `j·u .. (j + 1)·u`) at positions `tones` (one per measured amplitude).
    ///
    /// # Panics
    /// When `columns` does not hold p × u numbers, `tones` and `measured` differ in length
    /// or a position is ≥ u (programming errors).
    #[track_caller]
    pub fn new(
        measured: Vec<Complex64>,
        columns: std::sync::Arc<[Complex64]>,
        n_columns: usize,
        tones: Vec<usize>,
    ) -> Self {
        let u = columns.len().checked_div(n_columns).unwrap_or(0);
        assert_eq!(columns.len(), u * n_columns, "p × u column amplitudes");
        assert_eq!(
            tones.len(),
            measured.len(),
            "one tone per measured amplitude"
        );
        assert!(tones.iter().all(|&t| t < u), "tone position out of range");
        KeyProjection {
            measured,
            columns,
            n_columns,
            tones,
        }
    }

    /// Number of library columns p.
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Amplitudes of library column j at the key tones (k values).
    ///
    /// # Panics
    /// When j ≥ p (a programming error).
    #[track_caller]
    pub fn column(&self, j: usize) -> Vec<Complex64> {
        assert!(j < self.n_columns, "column {j} out of range");
        let row = self.row(j);
        self.tones.iter().map(|&t| row[t]).collect()
    }

    fn row(&self, j: usize) -> &[Complex64] {
        let u = self.columns.len() / self.n_columns.max(1);
        &self.columns[j * u..(j + 1) * u]
    }

    /// Model amplitudes Â_i = Σ_j ξ_j G_ji for raw coefficients over the library.
    ///
    /// # Panics
    /// When `raw.len()` differs from the number of library columns (a programming error).
    #[track_caller]
    pub fn model(&self, raw: &[f64]) -> Vec<Complex64> {
        assert_eq!(
            raw.len(),
            self.n_columns,
            "one coefficient per library column"
        );
        let mut out = vec![Complex64::new(0.0, 0.0); self.measured.len()];
        for (j, x) in raw.iter().enumerate() {
            if *x != 0.0 {
                let row = self.row(j);
                for (o, &t) in out.iter_mut().zip(&self.tones) {
                    *o += row[t] * x;
                }
            }
        }
        out
    }

    /// Eq. 14 loss of raw coefficients ([`crate::metrics::key_frequency_loss`]).
    pub fn loss(&self, raw: &[f64]) -> f64 {
        crate::metrics::key_frequency_loss(&self.measured, &self.model(raw))
    }
}

/// One distinct support on the path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PathSupport {
    /// Library columns, ascending.
    pub support: Vec<usize>,
    /// The δ values of the grid that gave this support.
    pub deltas: Vec<f64>,
    /// Group loss: mean over cases of the per-case loss.
    pub loss: f64,
    /// Per-case loss.
    pub case_losses: Vec<f64>,
    /// Index in the grid of the first δ that gave this support (its coefficients are the
    /// fits there: [`super::plugin::Regressor::coefficients_at`]).
    pub first: usize,
}

/// A whole δ path of one group and target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DeltaPath {
    /// The δ grid.
    pub deltas: Vec<f64>,
    /// For each δ, the index of its support in `supports`.
    pub support_of: Vec<usize>,
    /// Distinct supports, in order of first appearance along increasing δ.
    pub supports: Vec<PathSupport>,
    /// Loss of the densest support.
    pub loss_dense: f64,
    /// Noise loss (mean over cases) k·4σ̂²/(n Σ|A|²).
    pub loss_noise: f64,
    /// Loss limit loss_dense·(1 + rel) + abs + c·loss_noise.
    pub limit: f64,
    /// Index of the selected support.
    pub selected: usize,
}

impl DeltaPath {
    /// The selected support.
    pub fn selected_support(&self) -> &PathSupport {
        &self.supports[self.selected]
    }
}

/// Loss of one case for raw coefficients (key-frequency loss, or 1 − R² without keys).
fn case_loss(case: &CaseProblem<'_>, key: Option<&KeyProjection>, raw: &[f64]) -> f64 {
    match key {
        Some(k) if !k.measured.is_empty() => k.loss(raw),
        _ => {
            let f = case.factor;
            let support: Vec<usize> = (0..raw.len()).filter(|&j| raw[j] != 0.0).collect();
            let scaled: Vec<f64> = support.iter().map(|&j| raw[j] * f.scales[j]).collect();
            let rss = f.rss_of(case.target, &support, &scaled);
            let tot = f.targets[case.target].ss_tot();
            if tot > 0.0 {
                rss / tot
            } else {
                0.0
            }
        }
    }
}

/// The δ path built one grid point at a time (Alg. 3 in bounded memory): each point's
/// per-case coefficients are scored when they arrive ([`PathBuilder::push`]) and dropped;
/// what is kept is, per distinct support, its δ values, its per-case losses (8 B per case)
/// and the grid index of its first appearance, and for the densest support so far the
/// mean noise loss. [`PathBuilder::finish`] selects. The result equals that of scoring
/// every point at once ([`summarise`]), bit for bit: the same per-case losses summed in
/// the same order.
pub struct PathBuilder<'g> {
    deltas: &'g [f64],
    cases: &'g [CaseProblem<'g>],
    keys: &'g [Option<&'g KeyProjection>],
    supports: Vec<PathSupport>,
    masks: Vec<Mask>,
    support_of: Vec<usize>,
    /// (index in `supports`, number of terms, mean noise loss) of the densest support so
    /// far: most terms, first along the path on ties.
    dense: Option<(usize, usize, f64)>,
}

impl<'g> PathBuilder<'g> {
    /// An empty path over the grid `deltas` of the group `cases` (one key projection per
    /// case).
    ///
    /// # Panics
    /// When `cases` and `keys` differ in length (a programming error).
    #[track_caller]
    pub fn new(
        deltas: &'g [f64],
        cases: &'g [CaseProblem<'g>],
        keys: &'g [Option<&'g KeyProjection>],
    ) -> Self {
        assert_eq!(cases.len(), keys.len(), "one key projection per case");
        PathBuilder {
            deltas,
            cases,
            keys,
            supports: Vec::new(),
            masks: Vec::new(),
            support_of: Vec::with_capacity(deltas.len()),
            dense: None,
        }
    }

    /// Takes the fit at the next grid point: its support `mask` and, per case, the raw
    /// coefficients over the library (scored, then dropped).
    ///
    /// # Panics
    /// When more points are pushed than the grid has, or `coefs` does not hold one vector
    /// per case (programming errors).
    #[track_caller]
    pub fn push(&mut self, mask: Mask, coefs: &[Vec<f64>]) {
        let at = self.support_of.len();
        let d = self.deltas[at];
        if let Some(i) = self.masks.iter().position(|&m| m == mask) {
            self.supports[i].deltas.push(d);
            self.support_of.push(i);
            return;
        }
        assert_eq!(coefs.len(), self.cases.len(), "one fit per case");
        let case_losses: Vec<f64> = self
            .cases
            .iter()
            .zip(self.keys)
            .zip(coefs)
            .map(|((c, k), x)| case_loss(c, *k, x))
            .collect();
        let loss = case_losses.iter().sum::<f64>() / case_losses.len().max(1) as f64;
        let index = self.supports.len();
        let support = mask_to_vec(mask);
        let n_terms = support.len();
        if self.dense.is_none_or(|(_, n, _)| n_terms > n) {
            let v: Vec<f64> = self
                .cases
                .iter()
                .zip(self.keys)
                .zip(coefs)
                .map(|((c, k), x)| noise_loss(c, *k, x))
                .collect();
            let noise = v.iter().sum::<f64>() / v.len().max(1) as f64;
            self.dense = Some((index, n_terms, noise));
        }
        self.masks.push(mask);
        self.support_of.push(index);
        self.supports.push(PathSupport {
            support,
            deltas: vec![d],
            loss,
            case_losses,
            first: at,
        });
    }

    /// The path and its selection (see the module documentation).
    ///
    /// # Panics
    /// When fewer points were pushed than the grid has (a programming error).
    #[track_caller]
    pub fn finish(self, opts: &PathOptions) -> DeltaPath {
        assert_eq!(self.support_of.len(), self.deltas.len(), "one fit per δ");
        let supports = self.supports;
        let (dense, loss_noise) = self.dense.map_or((0, 0.0), |(i, _, v)| (i, v));
        let loss_dense = supports.get(dense).map(|s| s.loss).unwrap_or(0.0);
        let limit =
            loss_dense * (1.0 + opts.loss_rel) + opts.loss_abs + opts.loss_noise * loss_noise;
        let selected = (0..supports.len())
            .filter(|&i| supports[i].loss <= limit || i == dense)
            .min_by(|&a, &b| {
                supports[a]
                    .support
                    .len()
                    .cmp(&supports[b].support.len())
                    .then(supports[a].loss.total_cmp(&supports[b].loss))
                    .then(a.cmp(&b))
            })
            .unwrap_or(dense);
        DeltaPath {
            deltas: self.deltas.to_vec(),
            support_of: self.support_of,
            supports,
            loss_dense,
            loss_noise,
            limit,
            selected,
        }
    }
}

/// Builds the path summary from the per-δ supports and coefficients, and selects
/// ([`PathBuilder`] fed every point in order).
///
/// # Panics
/// When the inputs are inconsistent in length (programming errors).
#[track_caller]
pub fn summarise(
    deltas: &[f64],
    per_delta: Vec<(Mask, Vec<Vec<f64>>)>,
    cases: &[CaseProblem<'_>],
    keys: &[Option<&KeyProjection>],
    opts: &PathOptions,
) -> DeltaPath {
    assert_eq!(deltas.len(), per_delta.len(), "one fit per δ");
    let mut b = PathBuilder::new(deltas, cases, keys);
    for (mask, coefs) in per_delta {
        b.push(mask, &coefs);
    }
    b.finish(opts)
}

/// Noise loss of one case for the dense coefficients `raw` (0 without key frequencies).
fn noise_loss(case: &CaseProblem<'_>, key: Option<&KeyProjection>, raw: &[f64]) -> f64 {
    let Some(k) = key.filter(|k| !k.measured.is_empty()) else {
        return 0.0;
    };
    let f = case.factor;
    let support: Vec<usize> = (0..raw.len()).filter(|&j| raw[j] != 0.0).collect();
    let scaled: Vec<f64> = support.iter().map(|&j| raw[j] * f.scales[j]).collect();
    let rss = f.rss_of(case.target, &support, &scaled);
    let dof = f.n.saturating_sub(support.len()).max(1) as f64;
    let sigma2 = rss / dof;
    let den: f64 = k.measured.iter().map(|a| a.norm_sqr()).sum();
    if den > 0.0 {
        k.measured.len() as f64 * 4.0 * sigma2 / (f.n as f64 * den)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two targets sharing the column amplitudes of the union of their tones: each
    /// target's model is Σ_j ξ_j G_ji over its own tones, and the shared block is held once.
    #[test]
    fn key_projections_share_the_union_of_tones() {
        let c = |re: f64, im: f64| Complex64::new(re, im);
        // p = 2 columns × u = 3 tones
        let cols: std::sync::Arc<[Complex64]> = vec![
            c(1.0, 0.0),
            c(0.0, 1.0),
            c(2.0, 2.0),
            c(-1.0, 0.5),
            c(3.0, 0.0),
            c(0.0, -4.0),
        ]
        .into();
        let m = KeyProjection::new(vec![c(1.0, 0.0), c(0.0, 1.0)], cols.clone(), 2, vec![2, 0]);
        let l = KeyProjection::new(vec![c(1.0, 1.0)], cols.clone(), 2, vec![1]);
        assert_eq!(m.column(1), vec![c(0.0, -4.0), c(-1.0, 0.5)]);
        assert_eq!(
            m.model(&[2.0, 0.5]),
            vec![c(4.0, 4.0) + c(0.0, -2.0), c(2.0, 0.0) + c(-0.5, 0.25)]
        );
        assert_eq!(l.model(&[0.0, -1.0]), vec![c(-3.0, 0.0)]);
        assert_eq!(std::sync::Arc::strong_count(&cols), 3);
        assert_eq!(m.n_columns(), 2);
    }

    #[test]
    fn grid_is_log_spaced_and_inclusive() {
        let o = PathOptions::for_measure(Measure::Contribution);
        let g = o.grid();
        assert_eq!(g.len(), 50);
        assert!((g[0] - 1e-4).abs() < 1e-18 && (g[49] - 1.0).abs() < 1e-12);
        let r = g[1] / g[0];
        assert!(g.windows(2).all(|w| (w[1] / w[0] - r).abs() < 1e-9));
        assert!(PathOptions { n_delta: 0, ..o }.validate().is_err());
        assert!(PathOptions {
            delta_min: 0.0,
            ..o
        }
        .validate()
        .is_err());
    }
}
