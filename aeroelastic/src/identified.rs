//! The identified Eq. 19 law built directly from an `identification.json`
//! ([`identify::pipeline::Identification`]).
//!
//! **Linear part.** Under two-frequency forced motion the α-derivatives (A2*, A3*, H2*, H3*)
//! are identified at K_α = Bω_α/U and the h-derivatives (A1*, A4*, H1*, H4*) at K_h =
//! Bω_h/U, so each derivative is tabulated over its *own* K. Cases at the same K (equal
//! within `k_merge_tol`, e.g. different amplitudes at one wind speed) are aggregated by the
//! median, and the spread (min, max, 1.4826·MAD) is reported. The eight tables are then
//! resampled onto the union of their K values to build one [`DerivativeTable`] (p-k
//! flutter exactly in the frequency domain; Roger RFA in the time domain): each derivative
//! d is interpolated as its Q-matrix entry K²d (smooth in K, unlike d) by a natural cubic
//! spline over its own K, and extrapolated linearly through its two end nodes where the
//! union grid leaves its range (K²H1* ≈ −2πFK is close to linear at low K). Outside the
//! union range [`DerivativeTable`] holds the end values. A derivative that is `null` (not
//! identifiable) is an [`Error::NotIdentifiable`] naming it, unless a
//! [`MissingDerivative`] fallback is chosen.
//!
//! **Nonlinear part.** N1*..N3* of moment and lift, over K_α, aggregated by the median per
//! K, become [`Coefficient::OverK`] terms on α·(Bα̇/U) (k_power 3), α³ (6) and (Bα̇/U)³ (3).
//! Terms that are zero in every case (not in the selected support) are omitted.
//!
//! **Evaluation away from the identified K.** A nonlinear coefficient is identified at the
//! forcing frequency K_α of each case. In a free response (LCO) it is evaluated at the
//! response's own reduced frequency K = Bω/U ([`crate::section::Section::lco_run_k`] iterates
//! K to the limit cycle's frequency); between identified K the effective coefficient
//! ξ = K^p N* is interpolated linearly, outside the identified K_α range it is held at
//! the nearest end (never extrapolated) — see [`Coefficient::OverK`]. In a forced run the
//! model is evaluated at the forcing K_α ([`AeroModel::with_reduced_frequency`]).
//!
//! **Cases forced about a mean pitch.** A case regressed about ᾱ (`CaseResult::mean_pitch`,
//! its variable `alpha` is α − ᾱ) is re-expanded about α = 0 before aggregation: each
//! coefficient becomes Σ_{p ≥ j} c_p·C(p, j)·(−ᾱ)^(p−j) over the monomials that share its α̇,
//! h, ḣ powers, each Eq. 19 value scaled with its raw coefficient. The law is evaluated
//! about α = 0; without this a cubic identified about 3° adds an even term and α·α̇ adds
//! ᾱ·N1 to the α̇ derivative.
//!
//! **Terms outside Eq. 19** (e.g. `alpha^2*h` if the regression selected it) are plain
//! nondimensional coefficients without a K scaling. A term is *included* as a
//! [`Coefficient::Constant`] (the median over the cases) when it has one sign in every case
//! where it is non-zero, is non-zero in at least half of the cases, and its robust relative
//! spread 1.4826·MAD/|median| is at most `outside_max_spread` (default 0.5); otherwise it is
//! *excluded* and a warning says why. A constant term `1` (static offset) and linear terms
//! are always excluded with a warning (an offset moves the equilibrium, which the flutter and
//! LCO analyses about the origin do not model). Rationale: a term that the sparse regression
//! selects with a consistent value is part of the law, one that flips sign or scatters over
//! the cases is fitting noise or an unmodelled effect, and adding it to a time integration
//! can only make the prediction worse.

use std::path::Path;
use std::sync::Arc;

use identify::pipeline::{CaseResult, Identification};
use serde::{Deserialize, Serialize};

use crate::aero::{
    term_name, AeroModel, Channel, Coefficient, DerivativeTable, NonlinearAero, NonlinearTerm,
    RfaFit,
};
use crate::theodorsen::{flat_plate_derivatives, Derivative, Derivatives};
use crate::{Error, Result};
use identify::numerics::interp::Spline;

/// What to do with a derivative that is `null` (not identifiable) in a case.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum MissingDerivative {
    /// Any `null` derivative is an [`Error::NotIdentifiable`] naming it (default).
    #[default]
    Error,
    /// Ignore the cases where it is `null` (an error if no case has a value).
    Skip,
    /// Use the flat-plate closed form (exact Theodorsen) at the case's K.
    FlatPlate,
    /// Use 0.
    Zero,
}

/// Options of [`IdentifiedLaw::from_identification`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct IdentifiedOptions {
    /// Chord B \[m\] (`identification.json` does not hold it).
    pub chord: f64,
    /// Use only the cases of these groups (`None`: every case).
    pub groups: Option<Vec<String>>,
    /// Fallback for `null` derivatives.
    pub missing: MissingDerivative,
    /// Two K are the same table point when they differ by less than this, relative.
    pub k_merge_tol: f64,
    /// Lag roots of the Roger RFA (time domain).
    pub rfa_lags: usize,
    /// Largest robust relative spread 1.4826·MAD/|median| of a term outside Eq. 19 that is
    /// still included as a constant.
    pub outside_max_spread: f64,
    /// How each derivative continues outside the K range its cases identified.
    #[serde(default)]
    pub extrapolation: Extrapolation,
}

/// Continuation of an identified derivative outside the K range of its cases (the tails).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Extrapolation {
    /// Q entry K²d continued by the straight line through its two end nodes up to the
    /// union K grid, held at the grid's end values beyond (the default).
    #[default]
    Linear,
    /// Theodorsen-shaped tails fitted to the identified range: beyond an end node K_e the
    /// Q entry follows flat-plate entries (d_fp = [`flat_plate_derivatives`]), shifted to
    /// match there, K²d(K) = K_e²d(K_e) + Σ c_b (K²d_b(K) − K_e²d_b(K_e)), the weights c_b
    /// fitted to the derivative's nodes (H_j: the plate's H_j scaled; A_j: the plate's A_j
    /// and H_j, which reproduces a plate about any elastic axis); and the table grid is
    /// extended to 4 × its highest K so the tail, not a held value, is what the model sees
    /// up there. A physically consistent alternative to the straight line, used by the
    /// diagnosis to ask whether a gap comes from extrapolating the tables.
    Theodorsen,
}

impl IdentifiedOptions {
    /// Defaults for chord `chord`: all cases, strict on `null`, K merged within 1e-3,
    /// 3 RFA lags, outside terms included up to a relative spread of 0.5.
    pub fn new(chord: f64) -> Self {
        IdentifiedOptions {
            chord,
            groups: None,
            missing: MissingDerivative::Error,
            k_merge_tol: 1e-3,
            rfa_lags: 3,
            outside_max_spread: 0.5,
            extrapolation: Extrapolation::Linear,
        }
    }
}

pub use identify::eq19::ReducedFrequency;
use identify::eq19::EQ19;

/// One aggregated table point: the median over the cases at one K, and its spread.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct TablePoint {
    /// Reduced frequency (mean of the merged K).
    pub k: f64,
    /// Median of the values.
    pub value: f64,
    /// Number of values.
    pub n: usize,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Robust standard deviation 1.4826·MAD (0 for one value).
    pub spread: f64,
    /// How many of the values came from the fallback.
    pub filled: usize,
}

/// A derivative (H1*..H4*, A1*..A4*) or N* tabulated over its own K.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct TableSeries {
    /// Name: `H1`..`H4`, `A1`..`A4`, or `lift N1`.. `moment N3`.
    pub name: String,
    /// The library term it multiplies (`h_dot`, `alpha*alpha_dot`…).
    pub term: String,
    /// The K it is tabulated over.
    pub over: ReducedFrequency,
    /// Points by increasing K.
    pub points: Vec<TablePoint>,
}

/// A term outside Eq. 19 selected by the identification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct OutsideTerm {
    /// Force channel.
    pub channel: Channel,
    /// Term name.
    pub term: String,
    /// Median over the cases where it is non-zero.
    pub median: f64,
    /// Robust relative spread 1.4826·MAD/|median|.
    pub relative_spread: f64,
    /// Cases where it is non-zero.
    pub n_nonzero: usize,
    /// Cases used.
    pub n_cases: usize,
    /// Whether it is part of the model (as a constant).
    pub included: bool,
}

/// The serialisable description of an identified law (what was built and from what).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct IdentifiedTables {
    /// Data-set name of the identification.
    pub dataset: String,
    /// Chord B \[m\].
    pub chord: f64,
    /// Case ids used.
    pub cases: Vec<String>,
    /// H1*..H4*, A1*..A4* over their own K.
    pub derivatives: Vec<TableSeries>,
    /// N* terms (non-zero somewhere) over K_α.
    pub nonlinear: Vec<TableSeries>,
    /// Terms outside Eq. 19.
    pub outside: Vec<OutsideTerm>,
    /// Range of K_α of the cases.
    pub k_alpha_range: [f64; 2],
    /// Range of K_h of the cases.
    pub k_h_range: [f64; 2],
    /// The RFA of the resampled table (time domain) with its fit error.
    pub rfa: RfaFit,
    /// Everything that was dropped or filled in.
    pub warnings: Vec<String>,
    /// The Theodorsen-shaped tails' fitted weights ([`Extrapolation::Theodorsen`]; empty
    /// with straight-line continuation).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tails: Vec<TailWeights>,
}

/// The fitted weights of one derivative's Theodorsen-shaped tail: beyond an end node K_e,
/// K²d(K) = K_e²d(K_e) + Σ_b c_b (K²d_b(K) − K_e²d_b(K_e)), d_b the mid-chord flat plate's
/// derivatives ([`flat_plate_derivatives`]) named in `basis`. A weight of 1 on the own
/// entry alone is the flat plate itself; for H4 (whose growth at high K is the apparent
/// mass) the weight is the apparent heave mass the tail implies over the plate's πρb².
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct TailWeights {
    /// The derivative (`H1` … `A4`).
    pub derivative: String,
    /// The plate derivatives of the basis, own entry first.
    pub basis: Vec<String>,
    /// Their fitted weights c_b (nondimensional), in `basis` order.
    pub weights: Vec<f64>,
}

/// An identified Eq. 19 law: derivative table (linear) + N* and outside terms
/// (nonlinear), usable as an [`AeroModel`] through [`IdentifiedLaw::model`].
#[derive(Debug, Clone)]
pub struct IdentifiedLaw {
    /// What was built.
    pub tables: IdentifiedTables,
    table: Arc<DerivativeTable>,
    model: NonlinearAero,
}

const LIFT_NAMES: [Derivative; 4] = [
    Derivative::H1,
    Derivative::H2,
    Derivative::H3,
    Derivative::H4,
];
const MOMENT_NAMES: [Derivative; 4] = [
    Derivative::A1,
    Derivative::A2,
    Derivative::A3,
    Derivative::A4,
];

/// Robust standard deviation 1.4826·MAD around `med`.
fn robust_sd(v: &[f64], med: f64) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    1.4826 * identify::numerics::mad(v, med)
}

/// A case regressed about a mean pitch ᾱ (its `alpha` is α − ᾱ) re-expanded about α = 0
/// ([`about_zero_pitch`] for every non-zero raw coefficient; each Eq. 19 value scaled with
/// its raw coefficient ξ, value = ξ/K^p); other cases unchanged. The law is evaluated
/// about α = 0 (flutter, LCO, free responses), where the centred coefficients are off by
/// the expansion: e.g. α·α̇ about ᾱ adds ᾱ·N1 to the α̇ derivative, a cubic adds an even
/// term 3ᾱN·a² (DECISIONS "Laws identified about a mean pitch"). The constant (the force
/// at ᾱ) is left as identified.
fn about_zero_pitch_case(c: &CaseResult) -> CaseResult {
    let mut out = c.clone();
    if !c.mean_pitch.is_some_and(|a| a != 0.0 && a.is_finite()) {
        return out;
    }
    fn force<E: Copy + Into<identify::eq19::Eq19Values> + From<identify::eq19::Eq19Values>>(
        f: &mut identify::pipeline::ForceResult<E>,
        mean_pitch: Option<f64>,
    ) {
        let old = f.terms.clone();
        for (n, v) in f.terms.0.iter_mut() {
            if let Some(x) = v.filter(|x| *x != 0.0) {
                *v = Some(about_zero_pitch(&old, n, mean_pitch).unwrap_or(x));
            }
        }
        let mut e: identify::eq19::Eq19Values = f.eq19.into();
        for (i, t) in identify::eq19::EQ19.iter().enumerate() {
            if let (Some(d), Some(x0), Some(x1)) = (e.0[i], old.get(t.name), f.terms.get(t.name)) {
                if x0 != 0.0 {
                    e.0[i] = Some(d * x1 / x0);
                }
            }
        }
        f.eq19 = E::from(e);
    }
    force(&mut out.lift, c.mean_pitch);
    force(&mut out.moment, c.mean_pitch);
    out.mean_pitch = None;
    out
}

/// The coefficient of term `name` in the polynomial about α = 0, for a case regressed
/// about a mean pitch ᾱ (`mean_pitch`; its variable `alpha` is α − ᾱ): with the case's raw
/// coefficients c_p of the monomials (α − ᾱ)^p·R that share the rest R (α̇, h, ḣ powers) of
/// `name` = α^j·R, the coefficient is Σ_{p ≥ j} c_p·C(p, j)·(−ᾱ)^(p−j). A configuration
/// forced about ᾱ = 3° turns a cubic c₃α³ into c₃(a³ + 3ᾱa² + …): the a² term it selects is
/// that expansion, not an even term of the section, and vanishes here (DECISIONS
/// "Laws identified about a mean pitch"). `None` for a case regressed on α itself, or a
/// name that does not parse.
fn about_zero_pitch(
    terms: &identify::pipeline::TermMap,
    name: &str,
    mean_pitch: Option<f64>,
) -> Option<f64> {
    let ab = mean_pitch.filter(|a| *a != 0.0 && a.is_finite())?;
    let pw = NonlinearTerm::powers_of(name).ok()?;
    let j = pw[0];
    let mut sum = 0.0;
    for (n, v) in &terms.0 {
        let (Some(x), Ok(q)) = (v, NonlinearTerm::powers_of(n)) else {
            continue;
        };
        if q[1..] == pw[1..] && q[0] >= j {
            let mut binom = 1.0;
            for i in 0..(q[0] - j) {
                binom *= f64::from(q[0] - i) / f64::from(i + 1);
            }
            sum += x * binom * (-ab).powi((q[0] - j) as i32);
        }
    }
    Some(sum)
}

/// Groups (K, value, filled) by K within `tol` (relative) and aggregates each group.
fn aggregate(mut pts: Vec<(f64, f64, bool)>, tol: f64) -> Vec<TablePoint> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = Vec::new();
    let mut i = 0;
    while i < pts.len() {
        let mut j = i + 1;
        while j < pts.len() && (pts[j].0 - pts[i].0) <= tol * pts[i].0 {
            j += 1;
        }
        let grp = &pts[i..j];
        let mut vals: Vec<f64> = grp.iter().map(|p| p.1).collect();
        let med = identify::numerics::median(&mut vals);
        out.push(TablePoint {
            k: grp.iter().map(|p| p.0).sum::<f64>() / grp.len() as f64,
            value: med,
            n: grp.len(),
            min: vals[0],
            max: vals[vals.len() - 1],
            spread: robust_sd(&vals, med),
            filled: grp.iter().filter(|p| p.2).count(),
        });
        i = j;
    }
    out
}

/// Q-entry K²d of a series as a function of K: natural cubic spline inside, linear
/// through the end nodes outside.
struct QEntry {
    ks: Vec<f64>,
    gs: Vec<f64>,
    spline: Option<Spline>,
    /// Theodorsen-shaped tails: flat-plate Q entries and their fitted weights.
    tail: Option<Tail>,
}

/// A Theodorsen-shaped tail: beyond an end node K_e, K²d(K) = K_e²d(K_e) + Σ c_b (f_b(K) −
/// f_b(K_e)) with f_b flat-plate Q entries.
struct Tail {
    basis: Vec<fn(f64) -> f64>,
    c: Vec<f64>,
}

/// K²d_fp(K) of derivative `i` (0..8 = H1..H4, A1..A4) of the flat plate (mid-chord axis).
fn flat_plate_q(i: usize) -> fn(f64) -> f64 {
    const F: [fn(f64) -> f64; 8] = [
        |k| k * k * flat_plate_derivatives(k).h1,
        |k| k * k * flat_plate_derivatives(k).h2,
        |k| k * k * flat_plate_derivatives(k).h3,
        |k| k * k * flat_plate_derivatives(k).h4,
        |k| k * k * flat_plate_derivatives(k).a1,
        |k| k * k * flat_plate_derivatives(k).a2,
        |k| k * k * flat_plate_derivatives(k).a3,
        |k| k * k * flat_plate_derivatives(k).a4,
    ];
    F[i]
}

impl Tail {
    /// Plate entries (0..8 = H1..H4, A1..A4) of each derivative's tail, own entry first.
    const BASIS: [&'static [usize]; 8] = [
        &[0],
        &[1, 0],
        &[2, 3],
        &[3],
        &[4, 0],
        &[5, 4, 1, 0],
        &[6, 7, 2, 3],
        &[7, 3],
    ];

    /// The tail of derivative `i` fitted to the entry's nodes (`ks`, `gs`). Moving the
    /// elastic axis by x transforms the aerodynamic matrix as Q' = TᵀQT, T = [[1, x], [0, 1]]
    /// (Q_hh = K²(H4 + iH1), Q_hα = K²(H3 + iH2), Q_αh = K²(A4 + iA1), Q_αα = K²(A3 +
    /// iA2)), so each entry of a plate about any axis is a fixed combination of the
    /// mid-chord plate's entries of the same real/imaginary part: H1: {H1}; H4: {H4}; H2:
    /// {H2, H1}; H3: {H3, H4}; A1: {A1, H1}; A4: {A4, H4}; A2: {A2, A1, H2, H1}; A3: {A3,
    /// A4, H3, H4}. The weights are fitted by least squares with an intercept over the
    /// nodes, with as many of these functions (own entry first) as the nodes allow (nodes −
    /// 2); with none, or a singular fit, the plain flat-plate shape of its own entry.
    fn fit(i: usize, ks: &[f64], gs: &[f64]) -> Tail {
        const BASIS: [&[usize]; 8] = Tail::BASIS;
        let m = BASIS[i].len().min(ks.len().saturating_sub(2)).max(1);
        let basis: Vec<fn(f64) -> f64> = BASIS[i][..m].iter().map(|&j| flat_plate_q(j)).collect();
        let nb = basis.len();
        let plain = {
            let mut c = vec![0.0; nb];
            c[0] = 1.0;
            c
        };
        if ks.len() < nb + 2 {
            return Tail { basis, c: plain };
        }
        // g ≈ c₀ + Σ c_b f_b(K) by a rank-revealing SVD on unit-norm columns (entries of
        // the plate are collinear in places, e.g. A1 = −H1/4 at mid-chord: the minimum-norm
        // solution then gives the one combination the data determine)
        let n = nb + 1;
        let mut a = nalgebra::DMatrix::<f64>::zeros(ks.len(), n);
        for (r, &k) in ks.iter().enumerate() {
            a[(r, 0)] = 1.0;
            for (c, f) in basis.iter().enumerate() {
                a[(r, c + 1)] = f(k);
            }
        }
        let scale: Vec<f64> = (0..n)
            .map(|c| a.column(c).norm().max(f64::MIN_POSITIVE))
            .collect();
        for (c, sc) in scale.iter().enumerate() {
            a.column_mut(c).unscale_mut(*sc);
        }
        let rhs = nalgebra::DVector::from_column_slice(gs);
        let svd = a.svd(true, true);
        let tol = 1e-9 * svd.singular_values.max();
        match svd.solve(&rhs, tol) {
            Ok(x) if x.iter().all(|v| v.is_finite()) => Tail {
                basis,
                c: (1..n).map(|c| x[c] / scale[c]).collect(),
            },
            _ => Tail { basis, c: plain },
        }
    }

    fn eval(&self, k: f64, edge_k: f64, edge_g: f64) -> f64 {
        edge_g
            + self
                .basis
                .iter()
                .zip(&self.c)
                .map(|(f, c)| c * (f(k) - f(edge_k)))
                .sum::<f64>()
    }
}

impl QEntry {
    fn new(points: &[TablePoint], tail: Option<usize>) -> Self {
        let ks: Vec<f64> = points.iter().map(|p| p.k).collect();
        let gs: Vec<f64> = points.iter().map(|p| p.k * p.k * p.value).collect();
        let spline = (ks.len() >= 2).then(|| Spline::new(&ks, &gs));
        let tail = tail.map(|i| Tail::fit(i, &ks, &gs));
        QEntry {
            ks,
            gs,
            spline,
            tail,
        }
    }

    fn eval(&self, k: f64) -> f64 {
        let n = self.ks.len();
        if let Some(tail) = &self.tail {
            let edge = if k < self.ks[0] {
                Some(0)
            } else if k > self.ks[n - 1] {
                Some(n - 1)
            } else {
                None
            };
            if let Some(e) = edge {
                return tail.eval(k, self.ks[e], self.gs[e]);
            }
        }
        let Some(s) = &self.spline else {
            return self.gs[0];
        };
        let line = |i: usize, j: usize| {
            self.gs[i] + (k - self.ks[i]) * (self.gs[j] - self.gs[i]) / (self.ks[j] - self.ks[i])
        };
        if k < self.ks[0] {
            line(0, 1)
        } else if k > self.ks[n - 1] {
            line(n - 2, n - 1)
        } else {
            s.eval(k)
        }
    }
}

fn k_of(c: &CaseResult, over: ReducedFrequency) -> Option<f64> {
    match over {
        ReducedFrequency::KAlpha => c.k_alpha,
        ReducedFrequency::KH => c.k_h,
    }
}

/// The four linear derivatives then N1..N3 of one force of one case.
fn eq19_of(c: &CaseResult, channel: Channel) -> [Option<f64>; 7] {
    match channel {
        Channel::Lift => {
            let e = &c.lift.eq19;
            [e.H1, e.H2, e.H3, e.H4, e.N1, e.N2, e.N3]
        }
        Channel::Moment => {
            let e = &c.moment.eq19;
            [e.A1, e.A2, e.A3, e.A4, e.N1, e.N2, e.N3]
        }
    }
}

impl IdentifiedLaw {
    /// Reads `identification.json` at `path` and builds the law.
    ///
    /// # Errors
    /// [`Error::Identify`] naming the file when it cannot be read or parsed; otherwise as
    /// [`IdentifiedLaw::from_identification`].
    pub fn read(path: &Path, opts: &IdentifiedOptions) -> Result<Self> {
        let id = Identification::read(path).map_err(|e| Error::Identify {
            context: format!("reading {}", path.display()),
            source: e,
        })?;
        Self::from_identification(&id, opts)
    }

    /// Builds the law from an identification result (see the module docs).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a bad chord, tolerance or RFA lag count, an unknown
    /// group or no case left; [`Error::NotIdentifiable`] for a `null` derivative without a
    /// fallback (or with [`MissingDerivative::Skip`] when no case has it);
    /// [`Error::InvalidTable`] when the cases span fewer reduced frequencies than the table
    /// needs (4 distinct K, and 3 + `rfa_lags`).
    pub fn from_identification(id: &Identification, opts: &IdentifiedOptions) -> Result<Self> {
        crate::error::positive("chord", opts.chord)?;
        identify::limits::positive_at_most(opts.chord, identify::limits::MAX_CHORD, "m")
            .map_err(|m| Error::param("chord", opts.chord, m))?;
        crate::error::positive("k_merge_tol", opts.k_merge_tol)?;
        crate::error::non_negative("outside_max_spread", opts.outside_max_spread)?;
        let cases: Vec<&CaseResult> = match &opts.groups {
            None => id.cases.iter().collect(),
            Some(gs) => {
                for g in gs {
                    if !id.groups.iter().any(|x| &x.name == g) {
                        return Err(Error::param(
                            format!("groups: `{g}`"),
                            f64::NAN,
                            format!(
                                "no such group (have: {})",
                                id.groups
                                    .iter()
                                    .map(|x| x.name.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        ));
                    }
                }
                id.cases.iter().filter(|c| gs.contains(&c.group)).collect()
            }
        };
        if cases.is_empty() {
            return Err(Error::param(
                "cases",
                0.0,
                "no identified case to build a law from",
            ));
        }
        // cases regressed about a mean pitch, re-expanded about α = 0
        let recentred: Vec<CaseResult> = cases.iter().map(|c| about_zero_pitch_case(c)).collect();
        let cases: Vec<&CaseResult> = recentred.iter().collect();
        let mut warnings = Vec::new();
        let range = |over| {
            let ks: Vec<f64> = cases.iter().filter_map(|c| k_of(c, over)).collect();
            if ks.is_empty() {
                [f64::NAN, f64::NAN]
            } else {
                [
                    ks.iter().copied().fold(f64::INFINITY, f64::min),
                    ks.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                ]
            }
        };

        // Linear derivatives, each over its own K.
        let mut derivatives = Vec::with_capacity(8);
        for (channel, names) in [(Channel::Lift, LIFT_NAMES), (Channel::Moment, MOMENT_NAMES)] {
            for (i, derivative) in names.into_iter().enumerate() {
                let name = derivative.name();
                let (term, over) = (EQ19[i].name, EQ19[i].over);
                let mut pts = Vec::new();
                let mut missing = Vec::new();
                for c in &cases {
                    let k = k_of(c, over);
                    match (eq19_of(c, channel)[i], k) {
                        (Some(v), Some(k)) if v.is_finite() && k > 0.0 => pts.push((k, v, false)),
                        (_, k) => missing.push((c.id.clone(), k)),
                    }
                }
                if !missing.is_empty() {
                    let ids: Vec<String> = missing.iter().map(|m| m.0.clone()).collect();
                    match opts.missing {
                        MissingDerivative::Error => {
                            return Err(Error::NotIdentifiable {
                                derivative: name.to_string(),
                                cases: ids,
                            })
                        }
                        MissingDerivative::Skip => {
                            if pts.is_empty() {
                                return Err(Error::NotIdentifiable {
                                    derivative: name.to_string(),
                                    cases: ids,
                                });
                            }
                            warnings
                                .push(format!("{name}: null in {} case(s), skipped", ids.len()));
                        }
                        MissingDerivative::FlatPlate | MissingDerivative::Zero => {
                            let mut n_no_k = 0;
                            for (_, k) in &missing {
                                match k {
                                    Some(k) if *k > 0.0 => {
                                        let v = if opts.missing == MissingDerivative::Zero {
                                            0.0
                                        } else {
                                            flat_plate_derivatives(*k).get(derivative)
                                        };
                                        pts.push((*k, v, true));
                                    }
                                    _ => n_no_k += 1,
                                }
                            }
                            warnings.push(format!(
                                "{name}: null in {} case(s), filled with {}{}",
                                ids.len(),
                                if opts.missing == MissingDerivative::Zero {
                                    "0"
                                } else {
                                    "the flat-plate value"
                                },
                                if n_no_k > 0 {
                                    format!(" ({n_no_k} without a reduced frequency skipped)")
                                } else {
                                    String::new()
                                }
                            ));
                            if pts.is_empty() {
                                return Err(Error::NotIdentifiable {
                                    derivative: name.to_string(),
                                    cases: ids,
                                });
                            }
                        }
                    }
                }
                derivatives.push(TableSeries {
                    name: name.to_string(),
                    term: term.to_string(),
                    over,
                    points: aggregate(pts, opts.k_merge_tol),
                });
            }
        }

        // Common K grid and the derivative table.
        let mut grid: Vec<f64> = derivatives
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.k))
            .collect();
        grid.sort_by(f64::total_cmp);
        let mut merged: Vec<f64> = Vec::new();
        for k in grid {
            if merged.last().is_none_or(|&l| k - l > opts.k_merge_tol * l) {
                merged.push(k);
            }
        }
        if opts.extrapolation == Extrapolation::Theodorsen {
            // the tails up to 4 × the highest K (geometric steps of 2^(1/4))
            if let Some(&top) = merged.last() {
                let mut k = top;
                for _ in 0..8 {
                    k *= 2f64.powf(0.25);
                    merged.push(k);
                }
            }
        }
        let q: Vec<QEntry> = derivatives
            .iter()
            .map(|s| {
                let index = LIFT_NAMES
                    .iter()
                    .chain(&MOMENT_NAMES)
                    .position(|d| d.name() == s.name);
                let tail = index.filter(|_| opts.extrapolation == Extrapolation::Theodorsen);
                QEntry::new(&s.points, tail)
            })
            .collect();
        let tails: Vec<TailWeights> = derivatives
            .iter()
            .zip(&q)
            .filter_map(|(s, e)| {
                let t = e.tail.as_ref()?;
                let i = LIFT_NAMES
                    .iter()
                    .chain(&MOMENT_NAMES)
                    .position(|d| d.name() == s.name)?;
                Some(TailWeights {
                    derivative: s.name.clone(),
                    basis: Tail::BASIS[i][..t.c.len()]
                        .iter()
                        .map(|&j| {
                            LIFT_NAMES
                                .iter()
                                .chain(&MOMENT_NAMES)
                                .nth(j)
                                .map_or("?", |d| d.name())
                                .to_string()
                        })
                        .collect(),
                    weights: t.c.clone(),
                })
            })
            .collect();
        let rows: Vec<Derivatives> = merged
            .iter()
            .map(|&k| {
                let d = |i: usize| q[i].eval(k) / (k * k);
                Derivatives {
                    k,
                    h1: d(0),
                    h2: d(1),
                    h3: d(2),
                    h4: d(3),
                    a1: d(4),
                    a2: d(5),
                    a3: d(6),
                    a4: d(7),
                }
            })
            .collect();
        let n_rows = rows.len();
        let table = DerivativeTable::new(opts.chord, rows, opts.rfa_lags).map_err(|e| match e {
            Error::InvalidTable { message, .. } => Error::InvalidTable {
                table: "identified derivatives".into(),
                message: format!("the cases span {n_rows} distinct reduced frequencies: {message}"),
            },
            other => other,
        })?;

        // N* terms over K_α.
        let mut nonlinear = Vec::new();
        let mut terms = Vec::new();
        for channel in [Channel::Lift, Channel::Moment] {
            for (j, t) in EQ19[4..].iter().enumerate() {
                let (term, powers, k_power) = (t.name, &t.powers, &t.k_power);
                let mut pts = Vec::new();
                let mut n_null = 0;
                for c in &cases {
                    match (eq19_of(c, channel)[4 + j], c.k_alpha) {
                        (Some(v), Some(k)) if v.is_finite() && k > 0.0 => pts.push((k, v, false)),
                        _ => n_null += 1,
                    }
                }
                let name = format!("{} N{}", channel.name(), j + 1);
                if pts.iter().all(|p| p.1 == 0.0) {
                    if n_null > 0 && !pts.is_empty() {
                        warnings.push(format!("{name}: null in {n_null} case(s), zero elsewhere"));
                    }
                    continue;
                }
                if n_null > 0 {
                    warnings.push(format!("{name}: null in {n_null} case(s), skipped"));
                }
                let points = aggregate(pts, opts.k_merge_tol);
                terms.push(NonlinearTerm {
                    channel,
                    powers: *powers,
                    coefficient: Coefficient::OverK {
                        k: points.iter().map(|p| p.k).collect(),
                        values: points.iter().map(|p| p.value).collect(),
                        k_power: *k_power,
                    },
                });
                nonlinear.push(TableSeries {
                    name,
                    term: term.to_string(),
                    over: ReducedFrequency::KAlpha,
                    points,
                });
            }
        }

        // Terms outside Eq. 19.
        let eq19: Vec<&str> = identify::eq19::EQ19_TERMS.to_vec();
        let mut outside = Vec::new();
        for channel in [Channel::Lift, Channel::Moment] {
            let mut names: Vec<String> = Vec::new();
            for c in &cases {
                let tm = match channel {
                    Channel::Lift => &c.lift.terms,
                    Channel::Moment => &c.moment.terms,
                };
                for (n, v) in &tm.0 {
                    if !eq19.contains(&n.as_str())
                        && v.is_some_and(|x| x != 0.0)
                        && !names.contains(n)
                    {
                        names.push(n.clone());
                    }
                }
            }
            for n in names {
                let mut vals: Vec<f64> = cases
                    .iter()
                    .filter_map(|c| match channel {
                        Channel::Lift => c.lift.terms.get(&n),
                        Channel::Moment => c.moment.terms.get(&n),
                    })
                    .filter(|v| *v != 0.0 && v.is_finite())
                    .collect();
                let n_nonzero = vals.len();
                let med = identify::numerics::median(&mut vals);
                let rel = robust_sd(&vals, med) / med.abs().max(f64::MIN_POSITIVE);
                let one_sign = vals.iter().all(|v| v.signum() == med.signum());
                let powers = NonlinearTerm::powers_of(&n).ok();
                let degree: u32 = powers.map(|p| p.iter().sum()).unwrap_or(0);
                let reason = if powers.is_none() {
                    Some("its name does not parse".to_string())
                } else if degree < 2 {
                    Some("a constant or linear term outside Eq. 19 is not modelled".to_string())
                } else if !one_sign {
                    Some("its sign changes between cases".to_string())
                } else if 2 * n_nonzero < cases.len() {
                    Some(format!(
                        "non-zero in only {n_nonzero} of {} cases",
                        cases.len()
                    ))
                } else if rel > opts.outside_max_spread {
                    Some(format!(
                        "relative spread {rel:.3} > {}",
                        opts.outside_max_spread
                    ))
                } else {
                    None
                };
                let included = reason.is_none();
                match reason {
                    Some(r) => warnings.push(format!(
                        "{} term `{n}` (median {med:.4e}) excluded: {r}",
                        channel.name()
                    )),
                    None => {
                        if let Some(p) = powers {
                            terms.push(NonlinearTerm {
                                channel,
                                powers: p,
                                coefficient: Coefficient::Constant(med),
                            });
                        }
                    }
                }
                outside.push(OutsideTerm {
                    channel,
                    term: powers.map(term_name).unwrap_or(n),
                    median: med,
                    relative_spread: rel,
                    n_nonzero,
                    n_cases: cases.len(),
                    included,
                });
            }
        }

        let k_alpha_range = range(ReducedFrequency::KAlpha);
        let k_eval = if k_alpha_range[0].is_finite() {
            (k_alpha_range[0] * k_alpha_range[1]).sqrt()
        } else {
            1.0
        };
        let table = Arc::new(table);
        let model = NonlinearAero::new(table.clone() as Arc<dyn AeroModel>, terms, k_eval)?;
        let tables = IdentifiedTables {
            dataset: id.dataset.clone(),
            chord: opts.chord,
            cases: cases.iter().map(|c| c.id.clone()).collect(),
            derivatives,
            nonlinear,
            outside,
            k_alpha_range,
            k_h_range: range(ReducedFrequency::KH),
            rfa: table.rfa().clone(),
            warnings,
            tails,
        };
        Ok(IdentifiedLaw {
            tables,
            table,
            model,
        })
    }

    /// The law as an aerodynamic model: derivative table (RFA in time) + nonlinear terms,
    /// the latter evaluated at the geometric mean of the K_α range until changed with
    /// [`NonlinearAero::with_k_eval`] (or by [`crate::section::Section::lco_run_k`]).
    pub fn model(&self) -> &NonlinearAero {
        &self.model
    }

    /// The linear part alone (resampled derivative table).
    pub fn table(&self) -> &Arc<DerivativeTable> {
        &self.table
    }

    /// The tabulated series of flutter derivative `d`, if the law has one.
    pub fn series(&self, d: Derivative) -> Option<&TableSeries> {
        self.tables.derivatives.iter().find(|s| s.name == d.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use identify::eq19::{LiftEq19, MomentEq19};
    use identify::pipeline::{ForceResult, TermMap};

    fn force<E>(eq19: E, terms: Vec<(&str, f64)>) -> ForceResult<E> {
        ForceResult {
            terms: TermMap(
                terms
                    .into_iter()
                    .map(|(n, v)| (n.to_string(), Some(v)))
                    .collect(),
            ),
            eq19,
            r2: Some(1.0),
            mfwa: None,
            mfwa_phase: None,
            key_frequency_loss: None,
            constant: None,
            key_frequencies: vec![],
        }
    }

    /// A case at wind speed u with flat-plate derivatives at K_α = 3.1416/u, K_h =
    /// 2.042/u, N3 = ξ/K_α³ with ξ = −2 + `noise`, and an outside term.
    fn case(u: f64, amp: f64, noise: f64, outside: f64) -> CaseResult {
        let (ka, kh) = (std::f64::consts::PI / u, 2.042 / u);
        let da = flat_plate_derivatives(ka);
        let dh = flat_plate_derivatives(kh);
        CaseResult {
            id: format!("D-U{u}-A{amp}"),
            group: "D".into(),
            wind_speed: u,
            k_alpha: Some(ka),
            k_h: Some(kh),
            rank: 25,
            dependencies: vec![],
            mean_pitch: None,
            moment: force(
                MomentEq19 {
                    A1: Some(dh.a1),
                    A2: Some(da.a2 + noise),
                    A3: Some(da.a3),
                    A4: Some(dh.a4),
                    N1: Some(0.0),
                    N2: Some(0.0),
                    N3: Some((-2.0 + noise) / ka.powi(3)),
                },
                vec![("alpha^2*h", outside), ("alpha_dot^3", -2.0 + noise)],
            ),
            lift: force(
                LiftEq19 {
                    H1: Some(dh.h1),
                    H2: Some(da.h2),
                    H3: Some(da.h3),
                    H4: Some(dh.h4),
                    N1: Some(0.0),
                    N2: Some(0.0),
                    N3: Some(0.0),
                },
                vec![],
            ),
        }
    }

    /// A case forced about ᾱ = 3° of the section M = 1.2α − 0.3α̇ + 0.5αα̇ − 2α³ (raw,
    /// nondimensional, α absolute) regressed on a = α − ᾱ has an even term −6ᾱa², an α̇
    /// coefficient −0.3 + 0.5ᾱ and an α coefficient 1.2 − 6ᾱ²: re-expanded about α = 0 the
    /// section's own coefficients come back, the Eq. 19 values with them.
    #[test]
    fn a_case_regressed_about_a_mean_pitch_is_reexpanded_about_zero() {
        let ab = 3f64.to_radians();
        let ka = 0.4;
        let mut c = case(8.0, 6.0, 0.0, 0.0);
        c.mean_pitch = Some(ab);
        c.k_alpha = Some(ka);
        let raw = [
            ("alpha", 1.2 - 6.0 * ab * ab),
            ("alpha_dot", -0.3 + 0.5 * ab),
            ("alpha^2", -6.0 * ab),
            ("alpha*alpha_dot", 0.5),
            ("alpha^3", -2.0),
        ];
        c.moment = force(
            MomentEq19 {
                A1: None,
                A2: Some(raw[1].1 / ka),
                A3: Some(raw[0].1 / (ka * ka)),
                A4: None,
                N1: Some(0.5 / ka.powi(3)),
                N2: Some(-2.0 / ka.powi(6)),
                N3: None,
            },
            raw.to_vec(),
        );
        let r = about_zero_pitch_case(&c);
        assert_eq!(r.mean_pitch, None);
        let t = &r.moment.terms;
        assert!(t.get("alpha^2").unwrap().abs() < 1e-15);
        assert!((t.get("alpha").unwrap() - 1.2).abs() < 1e-14);
        assert!((t.get("alpha_dot").unwrap() + 0.3).abs() < 1e-15);
        assert_eq!(t.get("alpha^3"), Some(-2.0));
        assert!((r.moment.eq19.A2.unwrap() + 0.3 / ka).abs() < 1e-14);
        assert!((r.moment.eq19.A3.unwrap() - 1.2 / (ka * ka)).abs() < 1e-12);
        assert_eq!(r.moment.eq19.N2, c.moment.eq19.N2);
        // a case regressed on α itself is left alone
        let plain = case(8.0, 6.0, 0.0, 0.0);
        assert_eq!(about_zero_pitch_case(&plain), plain);
    }

    fn identification(cases: Vec<CaseResult>) -> Identification {
        let text = r#"{"format":"aeroform-identification/1","dataset":"t","settings":{},
            "library":{"terms":[],"rank":25,"dependencies":[],"rank_case":null,"priority":[]},
            "cases":[],"groups":[]}"#;
        let mut id: Identification = serde_json::from_str(text).unwrap();
        id.cases = cases;
        id
    }

    fn grid_cases(outside: impl Fn(usize) -> f64) -> Vec<CaseResult> {
        let mut v = Vec::new();
        for (i, u) in (3..=10).enumerate() {
            for (j, (a, n)) in [(3.0, 0.3), (12.0, -0.01), (24.0, 0.02)].iter().enumerate() {
                v.push(case(u as f64, *a, *n, outside(3 * i + j)));
            }
        }
        v
    }

    /// Theodorsen-shaped tails continue a flat-plate table as the flat plate well beyond the
    /// identified K (the straight line/hold of the default does not), and leave the
    /// identified range untouched.
    #[test]
    fn theodorsen_tails_follow_the_flat_plate_beyond_the_range() {
        let id = identification(grid_cases(|_| 0.0));
        let lin = IdentifiedLaw::from_identification(&id, &IdentifiedOptions::new(0.25)).unwrap();
        let opts = IdentifiedOptions {
            extrapolation: Extrapolation::Theodorsen,
            ..IdentifiedOptions::new(0.25)
        };
        let tails = IdentifiedLaw::from_identification(&id, &opts).unwrap();
        // K_h spans 2.042/10 .. 2.042/3 = 0.68; K_α up to π/3 = 1.05: at K = 2.5 both are
        // outside their own range and the union grid
        let k = 2.5;
        let e = flat_plate_derivatives(k);
        let t = tails.table().derivatives(k);
        let l = lin.table().derivatives(k);
        for (name, got, held, want) in [
            ("H1", t.h1, l.h1, e.h1),
            ("H4", t.h4, l.h4, e.h4),
            ("A1", t.a1, l.a1, e.a1),
            // (A2 carries an artificial +0.02 offset in these cases: not a plate)
            ("A3", t.a3, l.a3, e.a3),
        ] {
            let err = (got - want).abs() / want.abs().max(0.05);
            assert!(err < 0.01, "{name}: tail {got} vs flat plate {want}");
            let err_lin = (held - want).abs() / want.abs().max(0.05);
            assert!(
                err_lin > 3.0 * err,
                "{name}: default {held} already as close"
            );
        }
        // inside the range the two agree to interpolation accuracy
        let k = 0.5;
        let (a, b) = (tails.table().derivatives(k), lin.table().derivatives(k));
        assert!(
            (a.a2 - b.a2).abs() < 1e-3 * b.a2.abs(),
            "{} vs {}",
            a.a2,
            b.a2
        );
        assert!(
            (a.h1 - b.h1).abs() < 1e-3 * b.h1.abs(),
            "{} vs {}",
            a.h1,
            b.h1
        );

        // a plate about another axis (a = −0.3 semi-chords): the fitted A_j + x·H_j tails
        // reproduce it, though the basis is the mid-chord plate
        let mut cases = grid_cases(|_| 0.0);
        for c in &mut cases {
            let ta = crate::aero::thin_plate_derivatives(c.k_alpha.unwrap(), -0.3);
            let th = crate::aero::thin_plate_derivatives(c.k_h.unwrap(), -0.3);
            let m = &mut c.moment.eq19;
            (m.A1, m.A2, m.A3, m.A4) = (Some(th.a1), Some(ta.a2), Some(ta.a3), Some(th.a4));
            let l = &mut c.lift.eq19;
            (l.H1, l.H2, l.H3, l.H4) = (Some(th.h1), Some(ta.h2), Some(ta.h3), Some(th.h4));
        }
        let tails = IdentifiedLaw::from_identification(&identification(cases), &opts).unwrap();
        let k = 2.5;
        let e = crate::aero::thin_plate_derivatives(k, -0.3);
        let t = tails.table().derivatives(k);
        for (name, got, want) in [
            ("H2", t.h2, e.h2),
            ("H3", t.h3, e.h3),
            ("A1", t.a1, e.a1),
            ("A2", t.a2, e.a2),
            ("A3", t.a3, e.a3),
            ("A4", t.a4, e.a4),
        ] {
            let err = (got - want).abs() / want.abs().max(0.05);
            assert!(
                err < 0.01,
                "{name} about a = −0.3: tail {got} vs plate {want}"
            );
        }
    }

    #[test]
    fn tables_reproduce_flat_plate_and_median_rejects_outlier() {
        let id = identification(grid_cases(|_| 0.1));
        let law = IdentifiedLaw::from_identification(&id, &IdentifiedOptions::new(0.25)).unwrap();
        // Each derivative over its own K: 8 points each, 3 cases per point.
        let a2 = law.series(Derivative::A2).unwrap();
        assert_eq!(a2.over, ReducedFrequency::KAlpha);
        assert_eq!(a2.points.len(), 8);
        assert!(a2.points.iter().all(|p| p.n == 3));
        // The median ignores the +0.3 outlier at 3° (noise −0.01, 0.02 → median 0.02).
        for p in &a2.points {
            let want = flat_plate_derivatives(p.k).a2 + 0.02;
            assert!((p.value - want).abs() < 1e-12, "{} vs {want}", p.value);
            assert!((p.max - p.min - 0.31).abs() < 1e-12);
        }
        let a1 = law.series(Derivative::A1).unwrap();
        assert_eq!(a1.over, ReducedFrequency::KH);
        assert!((a1.points[0].k - 2.042 / 10.0).abs() < 1e-12);
        // Resampled table: A1 at a K_α node (between K_h nodes) is the flat plate to
        // interpolation accuracy.
        let k = std::f64::consts::PI / 6.0;
        let d = law.table().derivatives(k);
        let e = flat_plate_derivatives(k);
        assert!(
            (d.a1 - e.a1).abs() < 2e-3 * e.a1.abs(),
            "{} vs {}",
            d.a1,
            e.a1
        );
        assert!(
            (d.h4 - e.h4).abs() < 2e-2 * e.h4.abs().max(0.1),
            "{} vs {}",
            d.h4,
            e.h4
        );
        // N3: ξ = −2 + median noise 0.02 at every K; the effective coefficient between
        // nodes is exactly that constant.
        let m = law.model();
        let t = m
            .terms()
            .iter()
            .find(|t| t.powers == [0, 3, 0, 0] && t.channel == Channel::Moment)
            .unwrap();
        assert!((t.coefficient.at(0.5) + 1.98).abs() < 1e-12);
        // N1, N2 are zero everywhere: omitted. Outside term consistent: included.
        assert_eq!(law.tables.nonlinear.len(), 1);
        assert_eq!(law.tables.outside.len(), 1);
        assert!(law.tables.outside[0].included);
        assert_eq!(m.terms().len(), 2);
    }

    #[test]
    fn scattered_outside_term_is_excluded_with_a_warning() {
        let id = identification(grid_cases(|i| if i % 2 == 0 { 0.1 } else { -0.1 }));
        let law = IdentifiedLaw::from_identification(&id, &IdentifiedOptions::new(0.25)).unwrap();
        assert!(!law.tables.outside[0].included);
        assert!(
            law.tables
                .warnings
                .iter()
                .any(|w| w.contains("alpha^2*h") && w.contains("sign")),
            "{:?}",
            law.tables.warnings
        );
        assert_eq!(law.model().terms().len(), 1);
    }

    #[test]
    fn null_derivative_is_an_error_naming_it_unless_a_fallback_is_given() {
        let mut cases = grid_cases(|_| 0.0);
        cases[4].moment.eq19.A4 = None;
        let id = identification(cases);
        let e = IdentifiedLaw::from_identification(&id, &IdentifiedOptions::new(0.25)).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("A4") && msg.contains("D-U4-A12"), "{msg}");
        let mut o = IdentifiedOptions::new(0.25);
        o.missing = MissingDerivative::FlatPlate;
        let law = IdentifiedLaw::from_identification(&id, &o).unwrap();
        let a4 = law.series(Derivative::A4).unwrap();
        assert_eq!(a4.points.iter().map(|p| p.filled).sum::<usize>(), 1);
        o.missing = MissingDerivative::Skip;
        let law = IdentifiedLaw::from_identification(&id, &o).unwrap();
        assert_eq!(
            law.series(Derivative::A4)
                .unwrap()
                .points
                .iter()
                .map(|p| p.n)
                .sum::<usize>(),
            23
        );
    }

    #[test]
    fn unknown_group_and_too_few_frequencies_are_errors() {
        let id = identification(grid_cases(|_| 0.0));
        let mut o = IdentifiedOptions::new(0.25);
        o.groups = Some(vec!["Z".into()]);
        let e = IdentifiedLaw::from_identification(&id, &o).unwrap_err();
        assert!(e.to_string().contains("`Z`"), "{e}");
        let few = identification(vec![case(5.0, 3.0, 0.0, 0.0)]);
        let e =
            IdentifiedLaw::from_identification(&few, &IdentifiedOptions::new(0.25)).unwrap_err();
        assert!(
            e.to_string().contains("2 distinct reduced frequencies"),
            "{e}"
        );
    }
}

#[cfg(test)]
mod fuzz_regressions {
    use super::*;

    /// Found by the `identification` fuzz target (input
    /// fuzz/regressions/identification/duplicate-term-name.json): a term outside Eq. 19 that
    /// iteration sees as non-zero while `TermMap::get` finds no finite non-zero value (a
    /// repeated term name) left an empty list whose median underflowed an index. The reader
    /// now refuses repeated names; built in code, such a term is reported as not included.
    #[test]
    fn fuzz_regression_identification_outside_term_without_value() {
        let text = include_str!("../../fuzz/corpus/identification/cecfa55a89ef172c");
        let mut id: Identification = serde_json::from_str(text).unwrap();
        for c in &mut id.cases {
            c.lift.terms.0.insert(0, ("alpha^2*h".into(), Some(0.0)));
            c.lift.terms.0.push(("alpha^2*h".into(), Some(4.0)));
        }
        let mut o = IdentifiedOptions::new(0.25);
        o.missing = MissingDerivative::Zero;
        o.rfa_lags = 1;
        // no panic, and the term without a usable value is not part of the law
        let law = IdentifiedLaw::from_identification(&id, &o).unwrap();
        let t: Vec<_> = law
            .tables
            .outside
            .iter()
            .filter(|t| t.term == "alpha^2*h" && t.channel == Channel::Lift)
            .collect();
        assert_eq!(t.len(), 1, "{:?}", law.tables.outside);
        assert!(!t[0].included && t[0].n_nonzero == 0, "{:?}", t[0]);
        assert!(identify::numerics::median(&mut []).is_nan());
        assert_eq!(identify::numerics::median(&mut [3.0, 1.0, 2.0]), 2.0);
    }
}
