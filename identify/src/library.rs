//! Polynomial candidate libraries in the four regression variables (DESIGN.md §3).
//!
//! The variables are, in this order, `alpha` = α, `alpha_dot` = Bα̇/U, `h` = h/B and
//! `h_dot` = ḣ/U (all nondimensional, see [`crate::record::NondimCase`]). A term is a
//! monomial of total degree 1 to 3 (or the constant `1`, degree 0). Its name joins the
//! factors with `*`, powers as `^2`, `^3`, variables in the order alpha, alpha_dot, h,
//! h_dot (DATA_FORMAT.md), e.g. `alpha^2*h` or `alpha*h*h_dot`.
//!
//! Column order of a library: the constant (when asked for), then degree 1, 2, 3; inside a
//! degree, lexicographic in the variable order (the order of
//! `itertools::combinations_with_replacement`): `alpha^2, alpha*alpha_dot, alpha*h, …`.

use crate::numerics::mat::{Mat, MatMut};
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// Rows per block of [`Library::evaluate`] (4096 rows × 35 terms × 8 B ≈ 1.1 MB).
pub const EVAL_BLOCK: usize = 4096;

/// Names of the four regression variables, in library order.
pub const VARIABLES: [&str; 4] = ["alpha", "alpha_dot", "h", "h_dot"];

/// Which polynomial library to use.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum LibraryKind {
    /// Every monomial of degree 1–3 in the four variables: 4 + 10 + 20 = 34 terms.
    Full34,
    /// The paper's 30-term library: [`LibraryKind::Full34`] without `alpha*alpha_dot^2`,
    /// `alpha^2*alpha_dot`, `h*h_dot^2`, `h^2*h_dot`.
    #[default]
    Paper30,
}

impl LibraryKind {
    /// Number of polynomial terms (without the optional constant).
    pub fn n_terms(self) -> usize {
        match self {
            LibraryKind::Full34 => 34,
            LibraryKind::Paper30 => 30,
        }
    }
}

/// One monomial term: `powers[v]` is the exponent of variable `v` (order of [`VARIABLES`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Term {
    /// Exponents of (alpha, alpha_dot, h, h_dot).
    pub powers: [u8; 4],
}

impl Term {
    /// The constant term `1`.
    pub const ONE: Term = Term { powers: [0; 4] };

    /// Term with the given exponents of (alpha, alpha_dot, h, h_dot).
    pub const fn new(powers: [u8; 4]) -> Self {
        Term { powers }
    }

    /// The linear term of variable `v` (0 = alpha, 1 = alpha_dot, 2 = h, 3 = h_dot).
    ///
    /// # Panics
    /// When `v > 3` (a programming error).
    #[track_caller]
    pub fn linear(v: usize) -> Self {
        assert!(v < 4, "variable index {v} out of range");
        let mut powers = [0; 4];
        powers[v] = 1;
        Term { powers }
    }

    /// Total degree Σ powers.
    pub fn degree(&self) -> u32 {
        self.powers.iter().map(|&p| p as u32).sum()
    }

    /// Number of rate factors: the exponent of alpha_dot plus that of h_dot.
    pub fn n_rate_factors(&self) -> u32 {
        self.powers[1] as u32 + self.powers[3] as u32
    }

    /// Canonical name (`1` for the constant), e.g. `alpha^2*h`.
    pub fn name(&self) -> String {
        if self.degree() == 0 {
            return "1".to_string();
        }
        let mut parts = Vec::with_capacity(4);
        for (v, &p) in self.powers.iter().enumerate() {
            match p {
                0 => {}
                1 => parts.push(VARIABLES[v].to_string()),
                _ => parts.push(format!("{}^{p}", VARIABLES[v])),
            }
        }
        parts.join("*")
    }

    /// Parses a term name; factors may come in any order and repeat (`h*alpha*alpha`
    /// = `alpha^2*h`); whitespace around factors is ignored; `1` is the constant.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] (option `term`) naming the term when a factor is not one of
    /// the four variables, a power is not a positive integer, or the degree exceeds 3.
    pub fn parse(name: &str) -> Result<Term> {
        let bad = |message: String| Error::InvalidOption {
            name: "term".to_string(),
            message: format!("`{name}`: {message}"),
        };
        let trimmed = name.trim();
        if trimmed == "1" {
            return Ok(Term::ONE);
        }
        if trimmed.is_empty() {
            return Err(bad("empty term name".to_string()));
        }
        let mut powers = [0u32; 4];
        for factor in trimmed.split('*') {
            let factor = factor.trim();
            let (var, pow) = match factor.split_once('^') {
                Some((v, p)) => {
                    let p: u32 = p.trim().parse().map_err(|_| {
                        bad(format!("power `{}` is not a positive integer", p.trim()))
                    })?;
                    if p == 0 {
                        return Err(bad("power 0 is not allowed".to_string()));
                    }
                    (v.trim(), p)
                }
                None => (factor, 1),
            };
            let v = VARIABLES.iter().position(|&n| n == var).ok_or_else(|| {
                bad(format!(
                    "unknown factor `{var}` (expected one of alpha, alpha_dot, h, h_dot)"
                ))
            })?;
            powers[v] += pow;
        }
        let degree: u32 = powers.iter().sum();
        if degree > 3 {
            return Err(bad(format!("degree {degree} exceeds 3")));
        }
        Ok(Term {
            powers: powers.map(|p| p as u8),
        })
    }

    /// A column name safe for CSV readers that mangle `^` and `*` (numpy `genfromtxt`,
    /// MATLAB `readtable`): letters, digits and `_` only, the variables in the order of
    /// [`VARIABLES`] joined by `_`, a power above 1 appended as a digit (`alpha^2*h` →
    /// `alpha2_h`, `alpha_dot^3` → `alpha_dot3`, `alpha*h_dot` → `alpha_h_dot`), the
    /// constant `const`. One-to-one over the library (unit test).
    pub fn safe_name(&self) -> String {
        let parts: Vec<String> = self
            .powers
            .iter()
            .enumerate()
            .filter(|(_, p)| **p > 0)
            .map(|(v, &p)| {
                if p == 1 {
                    VARIABLES[v].to_string()
                } else {
                    format!("{}{p}", VARIABLES[v])
                }
            })
            .collect();
        if parts.is_empty() {
            "const".into()
        } else {
            parts.join("_")
        }
    }

    /// Value of the term at one sample `x = (α, Bα̇/U, h/B, ḣ/U)`.
    pub fn eval_at(&self, x: [f64; 4]) -> f64 {
        let mut v = 1.0;
        for (k, &p) in self.powers.iter().enumerate() {
            for _ in 0..p {
                v *= x[k];
            }
        }
        v
    }
}

impl std::fmt::Display for Term {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

/// An ordered set of candidate terms: the columns of the regression matrix Θ.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Library {
    kind: LibraryKind,
    constant: bool,
    terms: Vec<Term>,
}

/// The four terms the paper's 30-term library leaves out of the 34.
const PAPER_REMOVED: [[u8; 4]; 4] = [[1, 2, 0, 0], [2, 1, 0, 0], [0, 0, 1, 2], [0, 0, 2, 1]];

impl Library {
    /// Builds a library; `constant` adds the term `1` as the first column.
    pub fn new(kind: LibraryKind, constant: bool) -> Self {
        let mut terms = Vec::with_capacity(35);
        if constant {
            terms.push(Term::ONE);
        }
        // combinations with replacement of the variable indices, non-decreasing, which is
        // lexicographic order in the variable order
        let mut combos: Vec<Vec<usize>> = Vec::with_capacity(34);
        for a in 0..4 {
            combos.push(vec![a]);
        }
        for a in 0..4 {
            for b in a..4 {
                combos.push(vec![a, b]);
            }
        }
        for a in 0..4 {
            for b in a..4 {
                for c in b..4 {
                    combos.push(vec![a, b, c]);
                }
            }
        }
        for idx in combos {
            let mut powers = [0u8; 4];
            for v in idx {
                powers[v] += 1;
            }
            if kind == LibraryKind::Full34 || !PAPER_REMOVED.contains(&powers) {
                terms.push(Term { powers });
            }
        }
        Library {
            kind,
            constant,
            terms,
        }
    }

    /// Library kind.
    pub fn kind(&self) -> LibraryKind {
        self.kind
    }

    /// Whether the constant term `1` is the first column.
    pub fn has_constant(&self) -> bool {
        self.constant
    }

    /// The terms in column order.
    pub fn terms(&self) -> &[Term] {
        &self.terms
    }

    /// Number of terms (columns).
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// True for a library without a term (never produced by [`Library::new`]).
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Term names in column order.
    pub fn names(&self) -> Vec<String> {
        self.terms.iter().map(Term::name).collect()
    }

    /// Column index of a term.
    pub fn index_of_term(&self, term: &Term) -> Option<usize> {
        self.terms.iter().position(|t| t == term)
    }

    /// Column index of a term given by name (any factor order, see [`Term::parse`]).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming the term when the name does not parse or the term
    /// is not in this library.
    pub fn index_of(&self, name: &str) -> Result<usize> {
        let term = self.parse_term(name)?;
        self.index_of_term(&term)
            .ok_or_else(|| Error::InvalidOption {
                name: "term".to_string(),
                message: format!(
                    "`{name}` (= `{}`) is not in the {:?} library{}",
                    term.name(),
                    self.kind,
                    if self.constant { " with constant" } else { "" }
                ),
            })
    }

    /// Parses a term name and normalises it (see [`Term::parse`]).
    ///
    /// # Errors
    /// As [`Term::parse`].
    pub fn parse_term(&self, name: &str) -> Result<Term> {
        Term::parse(name)
    }

    /// Evaluates every term on the samples `x = [α, Bα̇/U, h/B, ḣ/U]`: the n × p matrix Θ
    /// (column-major, one column per term in library order).
    ///
    /// Holds the whole n × p matrix (8·n·p bytes); [`Library::evaluate_rows`] evaluates a
    /// block of rows for callers that can work block by block.
    ///
    /// # Panics
    /// When the four series do not have the same length (a programming error).
    #[track_caller]
    pub fn evaluate(&self, x: &[Vec<f64>; 4]) -> Mat<f64> {
        let n = x[0].len();
        assert!(
            x.iter().all(|v| v.len() == n),
            "regression variables of unequal lengths"
        );
        let mut theta = Mat::<f64>::zeros(n, self.terms.len());
        let mut r0 = 0;
        while r0 < n {
            let rows = EVAL_BLOCK.min(n - r0);
            self.evaluate_rows(x, r0, theta.as_mut().subrows_mut(r0, rows));
            r0 += rows;
        }
        theta
    }

    /// Evaluates every term on the rows `r0 .. r0 + out.nrows()` of the samples `x` (as
    /// [`Library::evaluate`]) into `out` (`out.nrows()` × p, library column order). Every
    /// entry is computed by the same floating-point operations as in
    /// [`Library::evaluate`] (`v²  = v·v`, `v³ = v·v²`, factors multiplied left to right in
    /// the variable order), so block-wise and whole-matrix evaluation agree bit for bit.
    /// Scratch memory: 12 × 8 bytes per row of the block.
    ///
    /// # Panics
    /// When the four series differ in length, the rows run past their end, or `out` does
    /// not have one column per term (programming errors).
    #[track_caller]
    pub fn evaluate_rows(&self, x: &[Vec<f64>; 4], r0: usize, mut out: MatMut<'_, f64>) {
        let n = x[0].len();
        let rows = out.nrows();
        assert!(
            x.iter().all(|v| v.len() == n),
            "regression variables of unequal lengths"
        );
        assert!(
            r0 + rows <= n,
            "rows {r0}..{} past the {n} samples",
            r0 + rows
        );
        assert_eq!(out.ncols(), self.terms.len(), "one output column per term");
        // powers 1..3 of each variable on the block: pw[(3·v + p − 1)·rows + i]
        // every power is written before it is read
        let mut pw = crate::numerics::scratch::Scratch::overwritten(12 * rows);
        for (v, xv) in x.iter().enumerate() {
            let src = &xv[r0..r0 + rows];
            let (p1, rest) = pw[3 * v * rows..(3 * v + 3) * rows].split_at_mut(rows);
            let (p2, p3) = rest.split_at_mut(rows);
            p1.copy_from_slice(src);
            for (b, a) in p2.iter_mut().zip(src) {
                *b = a * a;
            }
            for ((c, a), b) in p3.iter_mut().zip(src).zip(p2.iter()) {
                *c = a * b;
            }
        }
        let power = |v: usize, p: u8| &pw[(3 * v + p as usize - 1) * rows..][..rows];
        for (j, term) in self.terms.iter().enumerate() {
            let col = out.as_mut().col_mut(j);
            let factors: Vec<&[f64]> = term
                .powers
                .iter()
                .enumerate()
                .filter(|(_, &p)| p > 0)
                .map(|(v, &p)| power(v, p))
                .collect();
            match factors.len() {
                0 => {
                    for c in col.iter_mut() {
                        *c = 1.0;
                    }
                }
                1 => {
                    for (i, c) in col.iter_mut().enumerate() {
                        *c = factors[0][i];
                    }
                }
                2 => {
                    for (i, c) in col.iter_mut().enumerate() {
                        *c = factors[0][i] * factors[1][i];
                    }
                }
                _ => {
                    for (i, c) in col.iter_mut().enumerate() {
                        *c = factors[0][i] * factors[1][i] * factors[2][i];
                    }
                }
            }
        }
    }
}

/// The signals a term set is evaluated on: the four regression variables and any named
/// internal states of the case (e.g. the lag law's separation state `x`), each one value per
/// sample.
#[derive(Debug, Clone, Copy)]
pub struct Signals<'a> {
    /// (α, Bα̇/U, h/B, ḣ/U), nondimensional.
    pub x: &'a [Vec<f64>; 4],
    /// Named states, (name, series); nondimensional.
    pub states: &'a [(&'a str, &'a [f64])],
}

impl<'a> Signals<'a> {
    /// The state `name`.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] (option `library`) naming the state when the signals lack it.
    pub fn state(&self, name: &str) -> Result<&'a [f64]> {
        self.states
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| Error::InvalidOption {
                name: "library".to_string(),
                message: format!("the state `{name}` its terms need is not among the signals"),
            })
    }
}

/// A set of candidate terms: names and values on [`Signals`]. [`Library`] (the Eq. 19
/// polynomial library) is one; [`StateTerms`] (a state's terms) another; [`Composite`]
/// joins several into one library.
pub trait TermSet: Send + Sync {
    /// Short name of the set (in error messages): `paper30`, `state x`.
    fn set_name(&self) -> String;
    /// Term names in column order.
    fn term_names(&self) -> Vec<String>;
    /// Values of every term on the rows `r0 .. r0 + out.nrows()` into `out` (one column per
    /// term).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] when a signal the terms need is missing.
    fn evaluate_set(&self, signals: &Signals<'_>, r0: usize, out: MatMut<'_, f64>) -> Result<()>;
}

impl TermSet for Library {
    fn set_name(&self) -> String {
        format!("{:?}", self.kind).to_lowercase()
    }
    fn term_names(&self) -> Vec<String> {
        self.names()
    }
    fn evaluate_set(&self, signals: &Signals<'_>, r0: usize, out: MatMut<'_, f64>) -> Result<()> {
        self.evaluate_rows(signals.x, r0, out);
        Ok(())
    }
}

/// A state's terms: each the state raised to a power times a monomial of the regression
/// variables, named `<state>` (power 1, monomial 1), `<state>^p`, `<state>*<monomial>`
/// (e.g. `x`, `x^2`, `x*alpha`): the terms a law with an internal state adds to the
/// Eq. 19 library.
#[derive(Debug, Clone, PartialEq)]
pub struct StateTerms {
    state: String,
    terms: Vec<(u8, Term)>,
}

impl StateTerms {
    /// The terms `state^power · monomial` of the list.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] (option `library`) for an empty or non-identifier state
    /// name, a power 0 or above 3.
    pub fn new(state: &str, terms: &[(u8, Term)]) -> Result<StateTerms> {
        let bad = |message: String| Error::InvalidOption {
            name: "library".to_string(),
            message,
        };
        if state.is_empty()
            || !state.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            || VARIABLES.contains(&state)
        {
            return Err(bad(format!(
                "state name `{state}` must be an identifier other than the four variables"
            )));
        }
        if let Some((p, t)) = terms.iter().find(|(p, _)| *p == 0 || *p > 3) {
            return Err(bad(format!(
                "term `{state}^{p}*{t}`: the state's power must be 1, 2 or 3"
            )));
        }
        Ok(StateTerms {
            state: state.to_string(),
            terms: terms.to_vec(),
        })
    }
}

impl TermSet for StateTerms {
    fn set_name(&self) -> String {
        format!("state {}", self.state)
    }
    fn term_names(&self) -> Vec<String> {
        self.terms
            .iter()
            .map(|(p, t)| {
                let s = if *p == 1 {
                    self.state.clone()
                } else {
                    format!("{}^{p}", self.state)
                };
                if t.degree() == 0 {
                    s
                } else {
                    format!("{s}*{}", t.name())
                }
            })
            .collect()
    }
    fn evaluate_set(
        &self,
        signals: &Signals<'_>,
        r0: usize,
        mut out: MatMut<'_, f64>,
    ) -> Result<()> {
        let z = signals.state(&self.state)?;
        for (j, (p, t)) in self.terms.iter().enumerate() {
            for (i, c) in out.as_mut().col_mut(j).iter_mut().enumerate() {
                let r = r0 + i;
                let x = [
                    signals.x[0][r],
                    signals.x[1][r],
                    signals.x[2][r],
                    signals.x[3][r],
                ];
                *c = z[r].powi(*p as i32) * t.eval_at(x);
            }
        }
        Ok(())
    }
}

/// Several term sets as one library (columns in set order), names unique across the sets.
pub struct Composite {
    sets: Vec<Box<dyn TermSet>>,
    names: Vec<String>,
    offsets: Vec<usize>,
}

impl std::fmt::Debug for Composite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Composite")
            .field("names", &self.names)
            .finish()
    }
}

impl Composite {
    /// Joins `sets` (e.g. the Eq. 19 library and a state's terms).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] (option `library`) naming the term and the two sets when a
    /// term name appears twice, or when no set has a term.
    pub fn new(sets: Vec<Box<dyn TermSet>>) -> Result<Composite> {
        let mut names: Vec<String> = Vec::new();
        let mut owner: Vec<usize> = Vec::new();
        let mut offsets = Vec::with_capacity(sets.len());
        for (k, s) in sets.iter().enumerate() {
            offsets.push(names.len());
            for n in s.term_names() {
                if let Some(i) = names.iter().position(|m| *m == n) {
                    return Err(Error::InvalidOption {
                        name: "library".to_string(),
                        message: format!(
                            "term `{n}` is in both `{}` and `{}`: names must be unique",
                            sets[owner[i]].set_name(),
                            s.set_name()
                        ),
                    });
                }
                names.push(n);
                owner.push(k);
            }
        }
        if names.is_empty() {
            return Err(Error::InvalidOption {
                name: "library".to_string(),
                message: "no term".to_string(),
            });
        }
        Ok(Composite {
            sets,
            names,
            offsets,
        })
    }

    /// Term names in column order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of terms.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Never true ([`Composite::new`] refuses an empty library).
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Column of the term `name` (exact name).
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Values of every term on rows `r0 .. r0 + out.nrows()` (as [`TermSet::evaluate_set`]).
    ///
    /// # Errors
    /// As [`TermSet::evaluate_set`].
    ///
    /// # Panics
    /// When `out` does not have one column per term (a programming error).
    #[track_caller]
    pub fn evaluate_rows(
        &self,
        signals: &Signals<'_>,
        r0: usize,
        mut out: MatMut<'_, f64>,
    ) -> Result<()> {
        assert_eq!(out.ncols(), self.len(), "one output column per term");
        for (k, s) in self.sets.iter().enumerate() {
            let end = self.offsets.get(k + 1).copied().unwrap_or(self.len());
            let cols = out
                .as_mut()
                .subcols_mut(self.offsets[k], end - self.offsets[k]);
            s.evaluate_set(signals, r0, cols)?;
        }
        Ok(())
    }

    /// The n × p matrix of every term on all samples.
    ///
    /// # Errors
    /// As [`TermSet::evaluate_set`].
    pub fn evaluate(&self, signals: &Signals<'_>) -> Result<Mat<f64>> {
        let n = signals.x[0].len();
        let mut theta = Mat::<f64>::zeros(n, self.len());
        self.evaluate_rows(signals, 0, theta.as_mut())?;
        Ok(theta)
    }
}

#[cfg(test)]
mod tests {

    #[test]
    fn safe_names_are_plain_and_one_to_one_over_every_term() {
        let mut names = std::collections::BTreeSet::new();
        let mut n = 0;
        for a in 0..=3u8 {
            for b in 0..=3 - a {
                for c in 0..=3 - a - b {
                    for d in 0..=3 - a - b - c {
                        let t = Term {
                            powers: [a, b, c, d],
                        };
                        let s = t.safe_name();
                        assert!(
                            s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'),
                            "{s}"
                        );
                        names.insert(s);
                        n += 1;
                    }
                }
            }
        }
        assert_eq!(names.len(), n, "two terms share a safe name");
        assert_eq!(Term::parse("alpha^2*h").unwrap().safe_name(), "alpha2_h");
        assert_eq!(
            Term::parse("alpha_dot^3").unwrap().safe_name(),
            "alpha_dot3"
        );
        assert_eq!(
            Term::parse("h_dot*alpha").unwrap().safe_name(),
            "alpha_h_dot"
        );
        assert_eq!(Term::parse("1").unwrap().safe_name(), "const");
    }

    use super::*;

    #[test]
    fn sizes_and_order() {
        let full = Library::new(LibraryKind::Full34, false);
        assert_eq!(full.len(), 34);
        let paper = Library::new(LibraryKind::Paper30, false);
        assert_eq!(paper.len(), 30);
        let with_one = Library::new(LibraryKind::Paper30, true);
        assert_eq!(with_one.len(), 31);
        assert_eq!(with_one.names()[0], "1");
        let names = full.names();
        assert_eq!(&names[..4], &["alpha", "alpha_dot", "h", "h_dot"]);
        assert_eq!(
            &names[4..8],
            &["alpha^2", "alpha*alpha_dot", "alpha*h", "alpha*h_dot"]
        );
        assert_eq!(names[13], "h_dot^2");
        assert_eq!(names[14], "alpha^3");
        assert_eq!(names[15], "alpha^2*alpha_dot");
        assert_eq!(names[33], "h_dot^3");
        for removed in [
            "alpha*alpha_dot^2",
            "alpha^2*alpha_dot",
            "h*h_dot^2",
            "h^2*h_dot",
        ] {
            assert!(full.index_of(removed).is_ok());
            assert!(paper.index_of(removed).is_err(), "{removed}");
        }
        // degrees non-decreasing, names unique
        let mut seen = std::collections::HashSet::new();
        let mut last = 0;
        for t in full.terms() {
            assert!(t.degree() >= last);
            last = t.degree();
            assert!(seen.insert(t.name()));
        }
    }

    #[test]
    fn parse_normalises_and_rejects() {
        let t = Term::parse("h * alpha*alpha").unwrap();
        assert_eq!(t.name(), "alpha^2*h");
        assert_eq!(
            Term::parse("h_dot*h*alpha").unwrap().name(),
            "alpha*h*h_dot"
        );
        assert_eq!(Term::parse("alpha_dot^3").unwrap().n_rate_factors(), 3);
        let e = Term::parse("alpha*beta").unwrap_err().to_string();
        assert!(e.contains("beta") && e.contains("alpha*beta"), "{e}");
        assert!(Term::parse("alpha^4").is_err());
        assert!(Term::parse("alpha^2*h^2").is_err());
        assert!(Term::parse("alpha^x").is_err());
        for t in Library::new(LibraryKind::Full34, true).terms() {
            assert_eq!(Term::parse(&t.name()).unwrap(), *t);
        }
    }

    #[test]
    fn evaluate_matches_pointwise() {
        let x = [
            vec![0.1, -0.2, 0.3],
            vec![1.0, 2.0, -1.5],
            vec![-0.5, 0.25, 0.7],
            vec![0.3, -0.9, 1.1],
        ];
        let lib = Library::new(LibraryKind::Full34, true);
        let theta = lib.evaluate(&x);
        for i in 0..3 {
            let xi = [x[0][i], x[1][i], x[2][i], x[3][i]];
            for (j, t) in lib.terms().iter().enumerate() {
                let manual: f64 = (0..4).map(|v| xi[v].powi(t.powers[v] as i32)).product();
                assert!((theta[(i, j)] - manual).abs() < 1e-14);
            }
        }
        let j = lib.index_of("alpha*h*h_dot").unwrap();
        assert!((theta[(1, j)] - (-0.2 * 0.25 * -0.9)).abs() < 1e-15);
    }

    /// Row blocks at any offset (and the blocked whole-matrix evaluation over more than
    /// one [`EVAL_BLOCK`]) equal the pointwise products, and blocks agree bit for bit with
    /// the whole matrix.
    #[test]
    fn evaluate_rows_matches_whole_matrix_and_pointwise() {
        let n = EVAL_BLOCK + 1234;
        let x: [Vec<f64>; 4] = std::array::from_fn(|v| {
            (0..n)
                .map(|i| ((i * (v + 3)) as f64 * 0.013).sin() * (1.0 + v as f64))
                .collect()
        });
        let lib = Library::new(LibraryKind::Full34, true);
        let theta = lib.evaluate(&x);
        for (r0, rows) in [(0, 1), (17, 300), (EVAL_BLOCK - 5, 1000), (n - 3, 3)] {
            let mut out = Mat::<f64>::zeros(rows, lib.len());
            lib.evaluate_rows(&x, r0, out.as_mut());
            for i in 0..rows {
                let xi = [x[0][r0 + i], x[1][r0 + i], x[2][r0 + i], x[3][r0 + i]];
                for (j, t) in lib.terms().iter().enumerate() {
                    assert_eq!(out[(i, j)].to_bits(), theta[(r0 + i, j)].to_bits());
                    let manual: f64 = (0..4).map(|v| xi[v].powi(t.powers[v] as i32)).product();
                    assert!(
                        (out[(i, j)] - manual).abs() <= 1e-14 * manual.abs().max(1e-300),
                        "row {} term {}",
                        r0 + i,
                        t.name()
                    );
                }
            }
        }
    }

    /// Issue 40 item 2: the Eq. 19 library plus a state's terms as one library; duplicate
    /// names refused naming the term; the composite's columns regress like any library
    /// (the registered STLSQ recovers a law with a state term).
    #[test]
    fn eq19_library_and_state_terms_compose() {
        use crate::regress::plugin::{run_path, FitSettings, GroupInput, RegressorChoice};
        use crate::regress::{path::PathOptions, plugins, CaseFactor, CaseProblem, Measure};
        let n = 3000;
        let x: [Vec<f64>; 4] = std::array::from_fn(|v| {
            (0..n)
                .map(|i| ((i * (v + 2)) as f64 * 0.0107).sin() * (0.3 + 0.1 * v as f64))
                .collect()
        });
        let z: Vec<f64> = (0..n)
            .map(|i| 0.5 + 0.4 * (i as f64 * 0.0031).cos())
            .collect();
        let states = [("x", z.as_slice())];
        let signals = Signals {
            x: &x,
            states: &states,
        };
        let state =
            StateTerms::new("x", &[(1, Term::ONE), (1, Term::linear(0)), (2, Term::ONE)]).unwrap();
        assert_eq!(state.term_names(), ["x", "x*alpha", "x^2"]);
        let lib = Composite::new(vec![
            Box::new(Library::new(LibraryKind::Paper30, false)),
            Box::new(state.clone()),
        ])
        .unwrap();
        assert_eq!(lib.len(), 33);
        assert_eq!(lib.names()[30], "x");
        let theta = lib.evaluate(&signals).unwrap();
        let j = lib.index_of("x*alpha").unwrap();
        assert_eq!(theta[(7, j)], z[7] * x[0][7]);
        assert_eq!(theta[(7, 0)], x[0][7]);

        let e = Composite::new(vec![
            Box::new(Library::new(LibraryKind::Paper30, false)),
            Box::new(Library::new(LibraryKind::Full34, false)),
        ])
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("`alpha`") && e.contains("paper30") && e.contains("full34"),
            "{e}"
        );
        let e = Composite::new(vec![Box::new(state.clone()), Box::new(state)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("term `x`"), "{e}");
        assert!(StateTerms::new("alpha", &[]).is_err());
        let none: [(&str, &[f64]); 0] = [];
        let bare = Signals {
            x: &x,
            states: &none,
        };
        assert!(lib.evaluate(&bare).unwrap_err().to_string().contains("`x`"));

        // y = 1.5 α − 0.8 x·α + 0.3 x²: STLSQ on the composite finds exactly these terms
        let y: Vec<f64> = (0..n)
            .map(|i| 1.5 * x[0][i] - 0.8 * z[i] * x[0][i] + 0.3 * z[i] * z[i])
            .collect();
        let order: Vec<usize> = (0..lib.len()).collect();
        let f = CaseFactor::new("c", theta.as_ref(), &order, &[&y]).unwrap();
        let cases = [CaseProblem {
            factor: &f,
            target: 0,
        }];
        let shared = FitSettings {
            measure: Measure::Contribution,
            group_rule: crate::regress::GroupRule::Norm,
            ridge: 0.0,
            max_iter: 25,
        };
        let (reg, options, _) = RegressorChoice::new("stlsq")
            .resolve(plugins::registry(), &shared)
            .unwrap();
        let group = GroupInput {
            cases: &cases,
            keys: &[None],
            data: &[None],
            target: 0,
            basis: (1u64 << lib.len()) - 1,
            kept: 0,
            shared,
            options: &options,
        };
        let (path, coefs) = run_path(
            reg,
            &group,
            &PathOptions::for_measure(Measure::Contribution),
        );
        let sel: Vec<&str> = path
            .selected_support()
            .support
            .iter()
            .map(|&j| lib.names()[j].as_str())
            .collect();
        assert_eq!(sel, ["alpha", "x*alpha", "x^2"]);
        assert!((coefs[0][lib.index_of("x^2").unwrap()] - 0.3).abs() < 1e-9);
    }
}
