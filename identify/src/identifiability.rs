//! Numerical rank of a case's library, named dependencies, canonical identifiable basis.
//!
//! Under two-frequency harmonic motion the polynomial library is rank deficient: with
//! α = A sin ω_α t one has (Bα̇/U)² = K_α²(A² − α²), so for instance
//! `alpha_dot^2*h = K_α² A² h − K_α² alpha^2*h`, and the four squares satisfy one linear
//! relation. A least-squares fit on such a library has no unique solution. This module
//!
//! 1. measures the numerical rank of each case's column-normalised library Θ_s (every
//!    column divided by its 2-norm) by the SVD of its triangular factor: rank = number of
//!    singular values σ_i > `tol`·σ_max (default [`DEFAULT_RANK_TOL`] = 1e-9, "exact"
//!    dependencies; rounding in a 10⁴-sample record is ~1e-13); singular values below
//!    `near_tol`·σ_max (default [`DEFAULT_NEAR_TOL`] = 1e-6) are "near" dependencies;
//! 2. chooses a canonical identifiable basis greedily in the fixed priority order of
//!    [`priority_order`]: a term enters when the residual of its normalised column after
//!    projection on the terms already in exceeds `tol`·σ_max (this residual is the
//!    diagonal entry of the QR factor of the columns in priority order);
//! 3. reports each rejected term as a dependency in term names, with coefficients in the
//!    unscaled library variables (terms whose contribution is below 1e-6 of the largest are
//!    dropped), e.g. `alpha_dot^2*h = 0.987*h - 0.987*alpha^2*h`.
//!
//! A group of cases is fitted on the terms that are in the basis of every case
//! ([`group_basis`]).

use crate::numerics::mat::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use crate::library::{Library, Term};
use crate::regress::factor::CaseFactor;
use crate::{Error, Result};

/// Default relative tolerance on singular values (and basis residuals) for an exact
/// dependency: σ < 1e-9·σ_max of the column-normalised library.
pub const DEFAULT_RANK_TOL: f64 = 1e-9;
/// Default relative tolerance below which a singular value (or basis residual) is reported
/// as a near dependency: σ < 1e-6·σ_max.
pub const DEFAULT_NEAR_TOL: f64 = 1e-6;
/// Coefficients of a dependency whose contribution (on normalised columns) is below this
/// fraction of the largest one are dropped from its description.
const NEGLIGIBLE: f64 = 1e-6;

/// Tolerances of the rank test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RankOptions {
    /// Relative tolerance for exact dependencies (σ < tol·σ_max).
    pub tol: f64,
    /// Relative tolerance for reported near dependencies (σ < near_tol·σ_max).
    pub near_tol: f64,
}

impl Default for RankOptions {
    fn default() -> Self {
        RankOptions {
            tol: DEFAULT_RANK_TOL,
            near_tol: DEFAULT_NEAR_TOL,
        }
    }
}

impl RankOptions {
    /// Checks the tolerances: 0 < tol ≤ near_tol < 1.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `rank_tol` or `near_tol`.
    pub fn validate(&self) -> Result<()> {
        if !(self.tol > 0.0 && self.tol < 1.0) {
            return Err(Error::InvalidOption {
                name: "rank_tol".to_string(),
                message: format!("{} must be in (0, 1)", self.tol),
            });
        }
        if !(self.near_tol >= self.tol && self.near_tol < 1.0) {
            return Err(Error::InvalidOption {
                name: "near_tol".to_string(),
                message: format!("{} must be in [rank_tol = {}, 1)", self.near_tol, self.tol),
            });
        }
        Ok(())
    }
}

/// How the regression basis is chosen.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum BasisMode {
    /// Drop dependent terms greedily in the priority order (the default).
    #[default]
    Canonical,
    /// Keep every term; any rank deficiency is an [`Error::RankDeficient`].
    Full,
}

/// Fixed priority order of the library columns for the canonical basis:
/// (1) the linear terms alpha, alpha_dot, h, h_dot; (2) the Eq. 19 nonlinear terms
/// `alpha*alpha_dot`, `alpha^3`, `alpha_dot^3`; (3) the rest by degree ascending (the
/// constant first), then by number of rate factors ascending (displacement-type before
/// rate-type), then library column order.
pub fn priority_order(lib: &Library) -> Vec<usize> {
    let eq19 = [[1u8, 1, 0, 0], [3, 0, 0, 0], [0, 3, 0, 0]];
    let class = |t: &Term| -> (u32, u32, u32, usize) {
        if t.degree() == 1 {
            let v = t.powers.iter().position(|&p| p == 1).unwrap_or(0);
            (0, 0, 0, v)
        } else if let Some(k) = eq19.iter().position(|p| *p == t.powers) {
            (1, 0, 0, k)
        } else {
            (2, t.degree(), t.n_rate_factors(), 0)
        }
    };
    let mut idx: Vec<usize> = (0..lib.len()).collect();
    idx.sort_by_key(|&j| {
        let c = class(&lib.terms()[j]);
        (c.0, c.1, c.2, c.3, j)
    });
    idx
}

/// A linear dependency among library terms: `term = Σ c_k terms_k` in the unscaled
/// variables of the library, up to a relative residual.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Dependency {
    /// The dependent term.
    pub term: String,
    /// The combination (term name, coefficient), in priority order.
    pub combination: Vec<(String, f64)>,
    /// Norm of the residual of the normalised column after projection on the basis terms
    /// before it (0 for an exact relation, ≤ 1).
    pub residual: f64,
}

impl Dependency {
    /// Human-readable form, e.g. `alpha_dot^2*h = 0.987*h - 0.987*alpha^2*h`
    /// (`h = 0` for an identically zero column).
    pub fn describe(&self) -> String {
        let mut s = format!("{} =", self.term);
        if self.combination.is_empty() {
            s.push_str(" 0");
        }
        for (k, (name, c)) in self.combination.iter().enumerate() {
            let sign = if *c < 0.0 { "-" } else { "+" };
            if k == 0 {
                if *c < 0.0 {
                    s.push_str(" -");
                }
                s.push(' ');
            } else {
                s.push_str(&format!(" {sign} "));
            }
            s.push_str(&format!("{}*{name}", fmt_sig(c.abs(), 4)));
        }
        s
    }
}

/// Formats a positive number with `sig` significant digits, trailing zeros removed.
pub(crate) fn fmt_sig(x: f64, sig: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if (-3..5).contains(&e) {
        let decimals = (sig as i32 - 1 - e).max(0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.*e}", sig - 1)
    }
}

/// Identifiability of one case's library.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseIdentifiability {
    /// Case id (or group name).
    pub case: String,
    /// Number of library terms p.
    pub n_terms: usize,
    /// Numerical rank (σ_i > tol·σ_max).
    pub rank: usize,
    /// Singular values of the column-normalised library, descending.
    pub singular_values: Vec<f64>,
    /// Number of singular values below near_tol·σ_max but above tol·σ_max.
    pub n_near: usize,
    /// `in_basis[j]`: library column j is in the canonical basis.
    pub in_basis: Vec<bool>,
    /// Each term left out of the basis, as a combination of basis terms before it.
    pub dependencies: Vec<Dependency>,
    /// Basis terms whose residual is below near_tol: kept, but poorly determined.
    pub near_dependencies: Vec<Dependency>,
}

impl CaseIdentifiability {
    /// Number of terms in the canonical basis.
    pub fn basis_size(&self) -> usize {
        self.in_basis.iter().filter(|&&b| b).count()
    }

    /// Descriptions of the dependencies ([`Dependency::describe`]).
    pub fn dependency_strings(&self) -> Vec<String> {
        self.dependencies.iter().map(Dependency::describe).collect()
    }

    /// For [`BasisMode::Full`]: succeeds only when the library has full column rank.
    ///
    /// # Errors
    /// [`Error::RankDeficient`] with the case, rank, number of terms and every dependency
    /// in term names.
    pub fn require_full_rank(&self) -> Result<()> {
        if self.rank < self.n_terms || !self.dependencies.is_empty() {
            return Err(Error::RankDeficient {
                case: self.case.clone(),
                rank: self.rank.min(self.basis_size()),
                expected: self.n_terms,
                dependencies: self.dependency_strings(),
            });
        }
        Ok(())
    }
}

/// Analyses the library matrix `theta` (n × p, library column order) of case `case`.
///
/// # Errors
/// As [`CaseFactor::new`] (too few samples, non-finite values), and
/// [`Error::Numerical`] when the SVD does not converge.
pub fn analyse(
    case: &str,
    lib: &Library,
    theta: MatRef<'_, f64>,
    opts: &RankOptions,
) -> Result<CaseIdentifiability> {
    let order = priority_order(lib);
    let factor = CaseFactor::new(case, theta, &order, &[])?;
    analyse_factor(case, lib, &factor, opts)
}

/// Analyses a case from its factor (built with the columns in [`priority_order`]).
///
/// # Errors
/// [`Error::Numerical`] when the SVD does not converge.
pub fn analyse_factor(
    case: &str,
    lib: &Library,
    factor: &CaseFactor,
    opts: &RankOptions,
) -> Result<CaseIdentifiability> {
    let p = factor.n_columns();
    assert_eq!(p, lib.len(), "factor and library sizes differ");
    let sv = singular_values(factor.r.to_mat().as_ref()).map_err(|message| Error::Numerical {
        context: format!("case `{case}`: SVD of the library"),
        message,
    })?;
    let smax = sv.first().copied().unwrap_or(0.0);
    let rank = sv.iter().filter(|&&s| s > opts.tol * smax).count();
    let n_near = sv
        .iter()
        .filter(|&&s| s <= opts.near_tol * smax && s > opts.tol * smax)
        .count();
    let mut in_basis = vec![false; p];
    let mut basis_pos: Vec<usize> = Vec::with_capacity(p); // priority positions in basis
    let mut dependencies = Vec::new();
    let mut near_dependencies = Vec::new();
    for k in 0..p {
        let j = factor.order[k];
        let resid = if factor.zero_column[j] {
            0.0
        } else {
            factor.r[(k, k)].abs()
        };
        let independent = smax > 0.0 && resid > opts.tol * smax;
        if !independent || resid <= opts.near_tol * smax {
            let dep = describe_dependency(lib, factor, k, &basis_pos, resid);
            if independent {
                near_dependencies.push(dep);
            } else {
                dependencies.push(dep);
            }
        }
        if independent {
            in_basis[j] = true;
            basis_pos.push(k);
        }
    }
    Ok(CaseIdentifiability {
        case: case.to_string(),
        n_terms: p,
        rank,
        singular_values: sv,
        n_near,
        in_basis,
        dependencies,
        near_dependencies,
    })
}

/// Expresses the column at priority position `k` through the basis columns before it.
fn describe_dependency(
    lib: &Library,
    f: &CaseFactor,
    k: usize,
    basis_pos: &[usize],
    resid: f64,
) -> Dependency {
    let j = f.order[k];
    let term = lib.terms()[j].name();
    if f.zero_column[j] || basis_pos.is_empty() {
        return Dependency {
            term,
            combination: Vec::new(),
            residual: resid,
        };
    }
    let m = k + 1;
    let q = basis_pos.len();
    let mut a = vec![0.0; m * q];
    for (c, &kb) in basis_pos.iter().enumerate() {
        for i in 0..=kb {
            a[c * m + i] = f.r[(i, kb)];
        }
    }
    let b: Vec<f64> = (0..m).map(|i| f.r[(i, k)]).collect();
    let (x, _) = crate::numerics::qr::lstsq(&a, m, q, &b, 0.0);
    let big = x.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
    let combination = basis_pos
        .iter()
        .zip(&x)
        .filter(|(_, c)| c.abs() > NEGLIGIBLE * big)
        .map(|(&kb, &c)| {
            let jb = f.order[kb];
            // θ_j/d_j = Σ c θ_b/d_b  ⇒  θ_j = Σ (c d_j/d_b) θ_b
            (lib.terms()[jb].name(), c * f.scales[j] / f.scales[jb])
        })
        .collect();
    Dependency {
        term,
        combination,
        residual: resid,
    }
}

/// Singular values (descending) of a small square matrix.
fn singular_values(a: MatRef<'_, f64>) -> std::result::Result<Vec<f64>, String> {
    crate::numerics::mat::singular_values(a)
}

/// Group basis: the terms in the basis of every case, as a mask in library order.
///
/// # Panics
/// When the cases have libraries of different sizes (a programming error).
pub fn group_basis(cases: &[&CaseIdentifiability]) -> Vec<bool> {
    let Some(first) = cases.first() else {
        return Vec::new();
    };
    let mut mask = first.in_basis.clone();
    for c in &cases[1..] {
        assert_eq!(c.in_basis.len(), mask.len(), "library sizes differ");
        for (m, &b) in mask.iter_mut().zip(&c.in_basis) {
            *m = *m && b;
        }
    }
    mask
}

/// The Θ matrix of a case restricted to a mask of columns (helper for tests and tools).
pub fn select_columns(theta: MatRef<'_, f64>, mask: &[bool]) -> Mat<f64> {
    let cols: Vec<usize> = (0..mask.len()).filter(|&j| mask[j]).collect();
    Mat::from_fn(theta.nrows(), cols.len(), |i, c| theta[(i, cols[c])])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library::LibraryKind;

    fn harmonic(n: usize, dt: f64, fa: f64, fh: f64) -> [Vec<f64>; 4] {
        let (wa, wh) = (
            2.0 * std::f64::consts::PI * fa,
            2.0 * std::f64::consts::PI * fh,
        );
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        [
            t.iter().map(|t| 0.2 * (wa * t).sin()).collect(),
            t.iter().map(|t| 0.2 * wa * 0.1 * (wa * t).cos()).collect(),
            t.iter().map(|t| 0.3 * (wh * t + 0.4).sin()).collect(),
            t.iter()
                .map(|t| 0.3 * wh * 0.1 * (wh * t + 0.4).cos())
                .collect(),
        ]
    }

    #[test]
    fn priority_order_puts_linear_then_eq19_first() {
        let lib = Library::new(LibraryKind::Paper30, false);
        let names = lib.names();
        let order: Vec<&str> = priority_order(&lib)
            .iter()
            .map(|&j| names[j].as_str())
            .collect();
        assert_eq!(
            &order[..7],
            &[
                "alpha",
                "alpha_dot",
                "h",
                "h_dot",
                "alpha*alpha_dot",
                "alpha^3",
                "alpha_dot^3"
            ]
        );
        // degree 2 displacement-type before rate-type
        assert_eq!(&order[7..10], &["alpha^2", "alpha*h", "h^2"]);
        assert_eq!(*order.last().unwrap(), "h_dot^3");
    }

    #[test]
    fn harmonic_motion_drops_the_expected_terms() {
        let x = harmonic(2000, 1.0 / 256.0, 1.7, 0.9);
        let lib = Library::new(LibraryKind::Paper30, false);
        let theta = lib.evaluate(&x);
        let id = analyse("c", &lib, theta.as_ref(), &RankOptions::default()).unwrap();
        assert_eq!(id.rank, 25);
        assert_eq!(id.basis_size(), 25);
        let mut dropped: Vec<&str> = id.dependencies.iter().map(|d| d.term.as_str()).collect();
        dropped.sort();
        assert_eq!(
            dropped,
            [
                "alpha*h_dot^2",
                "alpha_dot*h_dot^2",
                "alpha_dot^2*h",
                "alpha_dot^2*h_dot",
                "h_dot^2"
            ]
        );
        // α̇'² = K²(A² − α²) with K = 0.1·ω (nondim rate = 0.1 × physical rate here)
        let k2 = (0.1 * 2.0 * std::f64::consts::PI * 1.7f64).powi(2);
        let d = id
            .dependencies
            .iter()
            .find(|d| d.term == "alpha_dot^2*h")
            .unwrap();
        let get = |n: &str| d.combination.iter().find(|c| c.0 == n).map(|c| c.1);
        assert!(
            (get("h").unwrap() - k2 * 0.04).abs() < 1e-8 * k2,
            "{}",
            d.describe()
        );
        assert!(
            (get("alpha^2*h").unwrap() + k2).abs() < 1e-8 * k2,
            "{}",
            d.describe()
        );
        assert_eq!(d.combination.len(), 2, "{}", d.describe());
        assert!(id.require_full_rank().is_err());
    }

    #[test]
    fn zero_heave_makes_h_terms_unidentifiable() {
        let mut x = harmonic(1000, 1.0 / 256.0, 1.7, 0.9);
        x[2] = vec![0.0; 1000];
        x[3] = vec![0.0; 1000];
        let lib = Library::new(LibraryKind::Paper30, false);
        let theta = lib.evaluate(&x);
        let id = analyse("p", &lib, theta.as_ref(), &RankOptions::default()).unwrap();
        assert!(!id.in_basis[lib.index_of("h").unwrap()]);
        assert!(!id.in_basis[lib.index_of("h_dot").unwrap()]);
        assert!(id.in_basis[lib.index_of("alpha").unwrap()]);
        let h = id.dependencies.iter().find(|d| d.term == "h").unwrap();
        assert_eq!(h.describe(), "h = 0");
    }

    #[test]
    fn formats_significant_digits() {
        assert_eq!(fmt_sig(0.98696, 3), "0.987");
        assert_eq!(fmt_sig(12.5, 4), "12.5");
        assert_eq!(fmt_sig(1.0e-7, 3), "1.00e-7");
    }
}
