//! The whole identification of a data set, and the `identification.json` result.
//!
//! [`identify`] runs, per case (in parallel, `rayon`, sequential linear algebra inside):
//! library evaluation, one QR factorisation of the column-normalised library with both
//! targets, identifiability (rank, dependencies, canonical basis), candidate tones and the
//! least-squares harmonic projection of the targets and of every library column at the key
//! frequencies. Then per group and target (in parallel): the δ path of (group) STLSQ on the
//! group basis and the selection of the sparsest support under the loss limit. Results are
//! deterministic, independent of the thread count and of the case order (groups sorted by
//! name, cases by id inside a group); cases are reported in input order.
//!
//! The two stages are public: [`prepare`] does the per-case work once and
//! [`Prepared::identify`] runs the group stage on any subset of the prepared cases (a
//! cross-validation's folds, a leave-one-out), with the result [`identify`] gives on that
//! subset alone.

use std::collections::BTreeMap;

use rayon::prelude::*;

use num_complex::Complex64;

use crate::eq19::{Eq19Values, LiftEq19, MomentEq19, EQ19_TERMS};
use crate::identifiability::{self, BasisMode, CaseIdentifiability, RankOptions};
use crate::library::Library;
use crate::metrics::{self, HarmonicProjector};
use crate::record::{CaseMeta, NondimCase};
use crate::regress::path::{DeltaPath, KeyProjection, PathOptions};
use crate::regress::plugin::{run_path, CaseData, CaseInput, GroupInput, Options, Regressor};
use crate::regress::plugins;
use crate::regress::{self, bools_to_mask, CaseFactor, CaseProblem, Mask};
use crate::{Error, Result};

mod result;
mod settings;

pub use result::*;
pub use settings::*;

/// What the later stages read of a case's identifiability (the whole analysis, with its
/// singular values and dependencies as term lists, is several times larger).
struct IdentSummary {
    /// Numerical rank.
    rank: usize,
    /// The canonical basis as a column mask.
    in_basis: Mask,
    /// [`CaseIdentifiability::dependency_strings`].
    dependencies: Vec<String>,
}

impl IdentSummary {
    fn of(ident: &CaseIdentifiability) -> Self {
        IdentSummary {
            rank: ident.rank,
            in_basis: bools_to_mask(&ident.in_basis),
            dependencies: ident.dependency_strings(),
        }
    }
}

/// Per-case preparation result.
struct CaseWork {
    factor: CaseFactor,
    ident: IdentSummary,
    /// Key projections of (moment, lift); `None` without candidate tones.
    keys: [Option<KeyProjection>; 2],
    key_freqs: [Vec<f64>; 2],
    /// The regressor's per-case data ([`Regressor::prepare_case`]).
    data: Option<CaseData>,
    /// Centring about a mean pitch, when applied.
    centring: Option<Centring>,
}

/// A case regressed about its mean pitch: ᾱ, the library's column means (on α − ᾱ) and the
/// means of (moment, lift).
struct Centring {
    mean_pitch: f64,
    columns: Vec<f64>,
    targets: [f64; 2],
}

impl Centring {
    /// The constant of the uncentred fit: ȳ − Σ ξ_j θ̄_j.
    fn constant(&self, target: usize, raw: &[f64]) -> f64 {
        self.targets[target]
            - raw
                .iter()
                .zip(&self.columns)
                .map(|(a, b)| a * b)
                .sum::<f64>()
    }
}

/// Mean of every library column over the samples `x` (block by block).
fn column_means(lib: &Library, x: &[Vec<f64>; 4]) -> Vec<f64> {
    let n = x[0].len();
    let p = lib.len();
    let mut sums = vec![0.0; p];
    let mut block =
        crate::numerics::mat::Mat::<f64>::zeros(crate::library::EVAL_BLOCK.min(n.max(1)), p);
    let mut r0 = 0;
    while r0 < n {
        let rows = crate::library::EVAL_BLOCK.min(n - r0);
        let mut b = block.as_mut().subrows_mut(0, rows);
        lib.evaluate_rows(x, r0, b.as_mut());
        for (j, s) in sums.iter_mut().enumerate() {
            *s += b.as_ref().col(j).iter().sum::<f64>();
        }
        r0 += rows;
    }
    sums.iter().map(|s| s / n.max(1) as f64).collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn check_case(case: &NondimCase) -> Result<()> {
    let bad = |field: &str, message: String| Error::InvalidData {
        case: case.meta.id.clone(),
        field: field.to_string(),
        message,
    };
    let n = case.c_lift.len();
    if case.c_moment.len() != n || case.x.iter().any(|v| v.len() != n) {
        return Err(bad(
            "samples",
            format!(
                "series of unequal lengths (x: {:?}, c_moment: {}, c_lift: {n})",
                case.x.iter().map(Vec::len).collect::<Vec<_>>(),
                case.c_moment.len()
            ),
        ));
    }
    if !(case.dt.is_finite() && case.dt > 0.0) {
        return Err(bad("dt", format!("{} s must be > 0", case.dt)));
    }
    for (name, v) in [
        ("alpha", &case.x[0]),
        ("alpha_dot", &case.x[1]),
        ("h", &case.x[2]),
        ("h_dot", &case.x[3]),
        ("c_moment", &case.c_moment),
        ("c_lift", &case.c_lift),
    ] {
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(bad(
                name,
                format!("non-finite value {} at sample {i}", v[i]),
            ));
        }
    }
    Ok(())
}

/// The chosen regressor and its resolved options.
#[derive(Clone, Copy)]
struct Chosen<'a> {
    reg: &'static dyn Regressor,
    options: &'a Options,
}

/// Records up to this many rows have their library matrix evaluated once per case and
/// held while the case is prepared ([`prepare_case`]); longer ones are evaluated block by
/// block on each pass (bounded memory).
const HOLD_THETA_ROWS: usize = 4 * crate::library::EVAL_BLOCK;

fn prepare_case(
    case: &NondimCase,
    lib: &Library,
    order: &[usize],
    s: &IdentifySettings,
    deltas: &[f64],
    chosen: Chosen<'_>,
) -> Result<CaseWork> {
    check_case(case)?;
    let id = &case.meta.id;
    // Θ is read three times: twice for the factorisation, once for the key-frequency
    // projection (held for short records, else evaluated block by block: below).
    let n = case.len();
    let p = lib.len();
    let shifted;
    let mut centred_targets = None;
    let (x, centring): (&[Vec<f64>; 4], Option<Centring>) = match case.meta.mean_pitch {
        Some(m) if s.centre_mean_angle && m != 0.0 && m.is_finite() => {
            let mut xs = case.x.clone();
            xs[0].iter_mut().for_each(|a| *a -= m);
            shifted = xs;
            let targets = [mean(&case.c_moment), mean(&case.c_lift)];
            centred_targets = Some([
                case.c_moment
                    .iter()
                    .map(|v| v - targets[0])
                    .collect::<Vec<f64>>(),
                case.c_lift
                    .iter()
                    .map(|v| v - targets[1])
                    .collect::<Vec<f64>>(),
            ]);
            let columns = column_means(lib, &shifted);
            (
                &shifted,
                Some(Centring {
                    mean_pitch: m,
                    columns,
                    targets,
                }),
            )
        }
        _ => (&case.x, None),
    };
    let col_means = centring.as_ref().map(|c| c.columns.as_slice());
    let evaluate = |r0: usize, mut out: crate::numerics::mat::MatMut<'_, f64>| {
        lib.evaluate_rows(x, r0, out.as_mut());
        if let Some(m) = col_means {
            for (j, mj) in m.iter().enumerate() {
                out.as_mut().col_mut(j).iter_mut().for_each(|v| *v -= mj);
            }
        }
    };
    // Θ is read three times (column norms, factorisation, key projections): a record of
    // at most HOLD_THETA_ROWS rows has it evaluated once and held (≤ 4 MB at p = 30), a
    // longer one evaluated block by block each time. Every entry is a function of its
    // own row, so both give the same numbers.
    let held = (n <= HOLD_THETA_ROWS).then(|| {
        // `evaluate` writes every value
        let mut t = crate::numerics::scratch::Scratch::overwritten(n * p);
        evaluate(
            0,
            crate::numerics::mat::MatMut::from_column_major_slice_mut(&mut t, n, p),
        );
        t
    });
    let eval = |r0: usize, mut out: crate::numerics::mat::MatMut<'_, f64>| match &held {
        Some(t) => {
            let rows = out.nrows();
            for j in 0..p {
                let src = &t[j * n + r0..j * n + r0 + rows];
                out.as_mut()
                    .col_mut(j)
                    .iter_mut()
                    .zip(src)
                    .for_each(|(o, v)| *o = *v);
            }
        }
        None => evaluate(r0, out),
    };
    let (y_m, y_l): (&[f64], &[f64]) = match &centred_targets {
        Some([a, b]) => (a, b),
        None => (&case.c_moment, &case.c_lift),
    };
    let factor = match &held {
        Some(t) => CaseFactor::from_columns(id, t, n, p, order, &[y_m, y_l])?,
        None => CaseFactor::from_row_blocks(id, n, p, order, &[y_m, y_l], eval)?,
    };
    let ident = identifiability::analyse_factor(
        id,
        lib,
        &factor,
        &RankOptions {
            tol: s.rank_tol,
            near_tol: s.near_tol,
        },
    )?;
    if s.basis == BasisMode::Full {
        ident.require_full_rank()?;
    }
    let duration = n as f64 * case.dt;
    let tones = metrics::candidate_tones(&case.forcing, s.max_harmonic_order, duration, case.dt);
    let mut keys = [None, None];
    let mut key_freqs = [Vec::new(), Vec::new()];
    if !tones.is_empty() {
        let freqs: Vec<f64> = tones.iter().map(|t| t.freq).collect();
        let fit = HarmonicProjector::new(&freqs, n, case.dt).map_err(|e| Error::Numerical {
            context: format!("case `{id}`: key frequencies"),
            message: e.to_string(),
        })?;
        // one pass: the basis of each block serves both targets and every column
        let (targets, cols) = fit.amplitudes_and_columns_with(&[y_m, y_l], p, eval);
        let selected =
            [0, 1].map(|t| metrics::select_key_frequencies(&tones, &targets[t].1, s.k_key));
        // the column amplitudes at the union of both targets' key tones, held once
        let mut union: Vec<usize> = selected.iter().flat_map(|k| k.index.clone()).collect();
        union.sort_unstable();
        union.dedup();
        let shared: std::sync::Arc<[Complex64]> = cols
            .iter()
            .flat_map(|c| union.iter().map(|&i| c[i]))
            .collect();
        for (t, key) in selected.into_iter().enumerate() {
            key_freqs[t] = key.tones.iter().map(|t| t.freq).collect();
            let at = key
                .index
                .iter()
                .map(|i| union.binary_search(i).unwrap_or(0))
                .collect();
            keys[t] = Some(KeyProjection::new(key.amplitudes, shared.clone(), p, at));
        }
    }
    let basis: Vec<usize> = (0..lib.len()).filter(|&j| ident.in_basis[j]).collect();
    let data = chosen.reg.prepare_case(&CaseInput {
        id,
        library: lib,
        x,
        measured: [&case.c_moment, &case.c_lift],
        basis: &basis,
        grid: deltas,
        options: chosen.options,
    })?;
    Ok(CaseWork {
        factor,
        ident: IdentSummary::of(&ident),
        keys,
        key_freqs,
        data,
        centring,
    })
}

fn group_name(case: &CaseSummary, by: GroupBy) -> String {
    match by {
        GroupBy::Config => case.meta.config.clone().unwrap_or_else(|| "-".to_string()),
        GroupBy::WindSpeed => format!("U={}", case.meta.wind_speed),
        GroupBy::Amplitude => match case.meta.amplitude {
            Some(a) => format!("amplitude={}", (a.to_degrees() * 1e6).round() / 1e6),
            None => "amplitude=-".to_string(),
        },
        GroupBy::None => case.meta.id.clone(),
    }
}

/// What the group stage needs of a case besides its [`CaseWork`]: the manifest descriptors
/// (id, group keys, wind speed) and the reduced frequencies, O(1) per case (the samples
/// are not kept: [`Prepared::push`]).
#[derive(Debug, Clone)]
struct CaseSummary {
    meta: CaseMeta,
    k_alpha: Option<f64>,
    k_h: Option<f64>,
}

impl CaseSummary {
    fn of(case: &NondimCase) -> Self {
        Self {
            meta: case.meta.clone(),
            k_alpha: case.k_alpha(),
            k_h: case.k_h(),
        }
    }
}

/// Result of one group and target.
struct GroupOutcome {
    path: DeltaPath,
    /// Per case of the group (in group order), raw coefficients over the library.
    coefficients: Vec<Vec<f64>>,
}

fn run_group(
    work: &[&CaseWork],
    target: usize,
    s: &IdentifySettings,
    chosen: Chosen<'_>,
    basis: Mask,
    kept: Mask,
    opts: &PathOptions,
) -> GroupOutcome {
    let cases: Vec<CaseProblem<'_>> = work
        .iter()
        .map(|w| CaseProblem {
            factor: &w.factor,
            target,
        })
        .collect();
    let keys: Vec<Option<&KeyProjection>> = work.iter().map(|w| w.keys[target].as_ref()).collect();
    let data: Vec<Option<&(dyn std::any::Any + Send + Sync)>> =
        work.iter().map(|w| w.data.as_deref()).collect();
    let group = GroupInput {
        cases: &cases,
        keys: &keys,
        data: &data,
        target,
        basis,
        kept,
        shared: s.fit_settings(),
        options: chosen.options,
    };
    let (path, coefficients) = run_path(chosen.reg, &group, opts);
    GroupOutcome { path, coefficients }
}

fn group_force(path: &DeltaPath, names: &[String]) -> GroupForce {
    let sel = path.selected_support();
    let range = |d: &[f64]| {
        [
            d.iter().cloned().fold(f64::INFINITY, f64::min),
            d.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        ]
    };
    GroupForce {
        support: sel.support.iter().map(|&j| names[j].clone()).collect(),
        selected_delta: range(&sel.deltas)[0],
        delta_range: range(&sel.deltas),
        loss: sel.loss,
        loss_dense: path.loss_dense,
        loss_noise: path.loss_noise,
        loss_limit: path.limit,
        path: path
            .supports
            .iter()
            .map(|p| PathEntry {
                n_terms: p.support.len(),
                loss: p.loss,
                delta: range(&p.deltas),
                support: p.support.iter().map(|&j| names[j].clone()).collect(),
            })
            .collect(),
    }
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Per-case result of one force.
fn force_result<E: From<Eq19Values>>(
    lib: &Library,
    case: &CaseSummary,
    w: &CaseWork,
    target: usize,
    basis: Mask,
    raw: &[f64],
) -> ForceResult<E> {
    let names = lib.names();
    let terms = TermMap(
        names
            .iter()
            .enumerate()
            .map(|(j, n)| (n.clone(), (basis >> j & 1 == 1).then_some(raw[j])))
            .collect(),
    );
    let xi: [Option<f64>; 7] = EQ19_TERMS.map(|t| {
        lib.index_of(t)
            .ok()
            .and_then(|j| (basis >> j & 1 == 1).then_some(raw[j]))
    });
    let eq19 = Eq19Values::from_coefficients(xi, case.k_alpha, case.k_h);
    let support: Vec<usize> = (0..raw.len()).filter(|&j| raw[j] != 0.0).collect();
    let scaled: Vec<f64> = support
        .iter()
        .map(|&j| raw[j] * w.factor.scales[j])
        .collect();
    let rss = w.factor.rss_of(target, &support, &scaled);
    let r2 = metrics::r_squared_from_sums(rss, w.factor.targets[target].ss_tot());
    let (mfwa, mfwa_phase, loss) = match &w.keys[target] {
        Some(k) if !k.measured.is_empty() => {
            let model = k.model(raw);
            (
                finite(metrics::mfwa(&k.measured, &model)),
                finite(metrics::mfwa_phase(&k.measured, &model)),
                finite(metrics::key_frequency_loss(&k.measured, &model)),
            )
        }
        _ => (None, None, None),
    };
    ForceResult {
        terms,
        eq19: E::from(eq19),
        r2: finite(r2),
        mfwa,
        mfwa_phase,
        key_frequency_loss: loss,
        key_frequencies: w.key_freqs[target].clone(),
        constant: w.centring.as_ref().map(|c| c.constant(target, raw)),
    }
}

/// Identifies the force laws of `cases` (see the module documentation): [`prepare`] then
/// [`Prepared::identify_all`].
///
/// `observer` receives [`Progress`] on the calling thread between parallel batches.
///
/// # Errors
/// As [`prepare`] and [`Prepared::identify`].
pub fn identify(
    cases: &[NondimCase],
    settings: &IdentifySettings,
    dataset_name: &str,
    observer: &dyn Fn(Progress),
) -> Result<Identification> {
    prepare(cases, settings, observer)?.identify_all(dataset_name, observer)
}

/// The first stage of an identification: every case prepared once (library factorisation
/// with both targets, identifiability, key-frequency projections), ready to identify any
/// subset of the cases with [`Prepared::identify`]. Preparing a case does not depend on
/// the other cases, so identifying a subset gives exactly what [`identify`] gives on those
/// cases alone, at the cost of the group stage only (a cross-validation's folds prepare
/// once).
pub struct Prepared<'c> {
    cases: &'c [NondimCase],
    settings: IdentifySettings,
    regressor: &'static dyn Regressor,
    regressor_options: Options,
    lib: Library,
    order: Vec<usize>,
    opts: PathOptions,
    kept: Mask,
    deltas: Vec<f64>,
    work: Vec<CaseWork>,
    summaries: Vec<CaseSummary>,
    ids: std::collections::HashSet<String>,
}

/// Prepares every case of `cases` for identification with `settings` (the first stage of
/// [`identify`]). `observer` receives [`Progress::Cases`] on the calling thread.
///
/// # Errors
/// [`Error::InvalidOption`] for invalid settings (an unknown kept term names it);
/// [`Error::InvalidData`] naming the case for an empty input, duplicate ids, series of
/// unequal length, non-positive dt, non-finite values or too few samples;
/// [`Error::RankDeficient`] naming the case and its dependencies when `basis = Full` and a
/// library is rank deficient; [`Error::Numerical`] when an SVD or a harmonic fit fails.
pub fn prepare<'c>(
    cases: &'c [NondimCase],
    settings: &IdentifySettings,
    observer: &dyn Fn(Progress),
) -> Result<Prepared<'c>> {
    prepare_in(cases, settings, plugins::registry(), observer)
}

/// [`prepare`] with the regressor looked up in `registry` instead of the registered ones
/// ([`plugins::registry`]; a test registers its own this way). The prepared settings hold
/// the canonical regressor choice (its registered name and every option's value).
///
/// # Errors
/// As [`prepare`].
pub fn prepare_in<'c>(
    cases: &'c [NondimCase],
    settings: &IdentifySettings,
    registry: &[&'static dyn Regressor],
    observer: &dyn Fn(Progress),
) -> Result<Prepared<'c>> {
    let mut prepared = Prepared::start_in(settings, registry)?;
    if cases.is_empty() {
        return Err(Error::InvalidData {
            case: "-".to_string(),
            field: "cases".to_string(),
            message: "no case to identify".to_string(),
        });
    }
    prepared.check_ids(cases)?;
    // per case, in batches so that progress is reported on this thread
    let total = cases.len();
    for chunk in cases.chunks(batch_size()) {
        prepared.push(chunk)?;
        observer(Progress::Cases {
            done: prepared.len(),
            total,
        });
    }
    prepared.cases = cases;
    Ok(prepared)
}

/// Parallel batch size: enough tasks per batch to keep every thread busy, few enough
/// batches that progress moves.
pub fn batch_size() -> usize {
    (4 * rayon::current_num_threads()).max(8)
}

impl Prepared<'static> {
    /// An empty preparation with `settings`, to which cases are added batch by batch with
    /// [`Prepared::push`] (the streaming form of [`prepare`]: the caller may drop each
    /// batch's samples once pushed). [`Prepared::cases`] stays empty.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] for invalid settings (an unknown kept term or regressor
    /// names it).
    pub fn start(settings: &IdentifySettings) -> Result<Self> {
        Self::start_in(settings, plugins::registry())
    }

    /// [`Prepared::start`] with the regressor looked up in `registry` ([`prepare_in`]).
    ///
    /// # Errors
    /// As [`Prepared::start`].
    pub fn start_in(
        settings: &IdentifySettings,
        registry: &[&'static dyn Regressor],
    ) -> Result<Self> {
        settings.validate_in(registry)?;
        let (regressor, regressor_options, canonical) = settings.regressor_in(registry)?;
        let settings = IdentifySettings {
            regressor: canonical,
            ..settings.clone()
        };
        let lib = Library::new(settings.library, settings.constant);
        let order = identifiability::priority_order(&lib);
        let opts = settings.path_options_in(registry);
        let deltas = regressor
            .path_parameter(&settings.fit_settings())
            .values(&opts);
        let mut kept_cols = vec![false; lib.len()];
        for t in &settings.kept_terms {
            kept_cols[lib.index_of(t)?] = true;
        }
        let kept = bools_to_mask(&kept_cols);
        Ok(Prepared {
            cases: &[],
            settings,
            regressor,
            regressor_options,
            lib,
            order,
            opts,
            kept,
            deltas,
            work: Vec::new(),
            summaries: Vec::new(),
            ids: std::collections::HashSet::new(),
        })
    }
}

impl<'c> Prepared<'c> {
    /// Refuses a case id given twice in `cases` or already pushed.
    fn check_ids(&self, cases: &[NondimCase]) -> Result<()> {
        let mut seen = std::collections::HashSet::new();
        for c in cases {
            if self.ids.contains(&c.meta.id) || !seen.insert(c.meta.id.as_str()) {
                return Err(Error::InvalidData {
                    case: c.meta.id.clone(),
                    field: "id".to_string(),
                    message: "duplicate case id".to_string(),
                });
            }
        }
        Ok(())
    }

    /// Prepares the cases of `batch` (in parallel) and appends them, in order, after the
    /// cases prepared so far; only their O(p²) summaries are kept, so the caller may drop
    /// the samples. The result of [`Prepared::identify`] does not depend on how the cases
    /// were split into batches.
    ///
    /// # Errors
    /// As [`prepare`], for the first failing case of the batch in order (nothing of the
    /// batch is appended then).
    pub fn push(&mut self, batch: &[NondimCase]) -> Result<()> {
        self.check_ids(batch)?;
        let (lib, order, settings, deltas) = (&self.lib, &self.order, &self.settings, &self.deltas);
        let chosen = Chosen {
            reg: self.regressor,
            options: &self.regressor_options,
        };
        let done: Vec<Result<CaseWork>> = batch
            .par_iter()
            .map(|c| prepare_case(c, lib, order, settings, deltas, chosen))
            .collect();
        let done = done.into_iter().collect::<Result<Vec<CaseWork>>>()?;
        self.work.extend(done);
        for c in batch {
            self.ids.insert(c.meta.id.clone());
            self.summaries.push(CaseSummary::of(c));
        }
        Ok(())
    }

    /// Forgets every prepared case and frees its work (factors, projections: ≈ 12 kB a
    /// case): the preparation is then as [`Prepared::start`] left it. For a caller done
    /// with the group stage that still holds the preparation (e.g. while it writes the
    /// result).
    pub fn clear(&mut self) {
        self.cases = &[];
        self.work = Vec::new();
        self.summaries = Vec::new();
        self.ids = std::collections::HashSet::new();
    }

    /// Number of cases prepared.
    pub fn len(&self) -> usize {
        self.summaries.len()
    }

    /// True when no case is prepared.
    pub fn is_empty(&self) -> bool {
        self.summaries.is_empty()
    }

    /// The manifest descriptors of the prepared cases, in order (the indices
    /// [`Prepared::identify`] takes).
    pub fn metas(&self) -> impl ExactSizeIterator<Item = &CaseMeta> {
        self.summaries.iter().map(|s| &s.meta)
    }

    /// The prepared cases, in input order (the indices [`Prepared::identify`] takes), as
    /// given to [`prepare`]; empty when the cases were pushed ([`Prepared::push`]), whose
    /// samples are not kept.
    pub fn cases(&self) -> &'c [NondimCase] {
        self.cases
    }

    /// The library the cases were prepared with.
    pub fn library(&self) -> &Library {
        &self.lib
    }

    /// Identifies all prepared cases: [`identify`]'s result.
    ///
    /// # Errors
    /// As [`Prepared::identify`].
    pub fn identify_all(
        &self,
        dataset_name: &str,
        observer: &dyn Fn(Progress),
    ) -> Result<Identification> {
        let all: Vec<usize> = (0..self.len()).collect();
        self.identify(&all, dataset_name, observer)
    }

    /// Identifies the cases `subset` (indices into [`Prepared::cases`]; the result lists
    /// them in this order): groups, δ paths and selected supports, as [`identify`] on
    /// those cases alone. `observer` receives [`Progress::Groups`] on the calling thread.
    ///
    /// # Errors
    /// [`Error::InvalidData`] (field `subset`) for an empty subset, an index out of range or
    /// an index given twice; [`Error::Numerical`] naming the group when a path result is
    /// missing.
    pub fn identify(
        &self,
        subset: &[usize],
        dataset_name: &str,
        observer: &dyn Fn(Progress),
    ) -> Result<Identification> {
        self.identify_keeping(subset, &[Vec::new(), Vec::new()], dataset_name, observer)
    }

    /// [`Prepared::identify`] with further terms kept per force, `keep` = (moment, lift)
    /// term names: the sparse regression never removes them where a group's identifiable
    /// basis holds them, beside the settings' `kept_terms` (which the result's `settings`
    /// record; these extra terms it does not). Used where the caller knows more than one
    /// group shows, e.g. that every configuration of a campaign is the same section.
    ///
    /// # Errors
    /// As [`Prepared::identify`]; [`Error::InvalidOption`] naming a term of `keep` that
    /// does not parse or is not in the library.
    pub fn identify_keeping(
        &self,
        subset: &[usize],
        keep: &[Vec<String>; 2],
        dataset_name: &str,
        observer: &dyn Fn(Progress),
    ) -> Result<Identification> {
        let mut kept = [self.kept; 2];
        for (target, names) in keep.iter().enumerate() {
            for t in names {
                kept[target] |= 1 << self.lib.index_of(t)?;
            }
        }
        let bad = |message: String| Error::InvalidData {
            case: "-".to_string(),
            field: "subset".to_string(),
            message,
        };
        if subset.is_empty() {
            return Err(bad("no case to identify".to_string()));
        }
        let mut seen = vec![false; self.len()];
        for &i in subset {
            match seen.get_mut(i) {
                None => {
                    return Err(bad(format!(
                        "case index {i} is out of range (0..{})",
                        self.len()
                    )))
                }
                Some(s) if *s => return Err(bad(format!("case index {i} is given twice"))),
                Some(s) => *s = true,
            }
        }
        let cases: Vec<&CaseSummary> = subset.iter().map(|&i| &self.summaries[i]).collect();
        let work: Vec<&CaseWork> = subset.iter().map(|&i| &self.work[i]).collect();
        self.identify_cases(&cases, work, kept, dataset_name, observer)
    }

    /// [`Prepared::identify_all`], freeing each case's work as soon as its result is made
    /// (the per-case work and the result are never both held whole); the preparation is
    /// then empty ([`Prepared::clear`]). For a caller that identifies once and writes the
    /// result (`aeroform identify`).
    ///
    /// # Errors
    /// As [`Prepared::identify`] (nothing is cleared then).
    pub fn identify_all_and_clear(
        &mut self,
        dataset_name: &str,
        observer: &dyn Fn(Progress),
    ) -> Result<Identification> {
        if self.is_empty() {
            return self.identify(&[], dataset_name, observer);
        }
        let work = std::mem::take(&mut self.work);
        let summaries = std::mem::take(&mut self.summaries);
        self.clear();
        let cases: Vec<&CaseSummary> = summaries.iter().collect();
        self.identify_cases(&cases, work, [self.kept; 2], dataset_name, observer)
    }

    /// The group stage and the result of `cases` with their work `work` (owned: each case's
    /// work is dropped once its result is made; or borrowed).
    fn identify_cases<W: std::borrow::Borrow<CaseWork>>(
        &self,
        cases: &[&CaseSummary],
        owned: Vec<W>,
        kept: [Mask; 2],
        dataset_name: &str,
        observer: &dyn Fn(Progress),
    ) -> Result<Identification> {
        let work: Vec<&CaseWork> = owned.iter().map(|w| w.borrow()).collect();
        let (settings, lib, opts) = (&self.settings, &self.lib, &self.opts);
        let chosen = Chosen {
            reg: self.regressor,
            options: &self.regressor_options,
        };
        let names = lib.names();
        let total = cases.len();
        let batch = batch_size();

        // groups: sorted by name, cases by id inside (positions in `subset`)
        let mut groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for (i, c) in cases.iter().enumerate() {
            groups
                .entry(group_name(c, settings.group_by))
                .or_default()
                .push(i);
        }
        for members in groups.values_mut() {
            members.sort_by(|&a, &b| cases[a].meta.id.cmp(&cases[b].meta.id));
        }
        let group_list: Vec<(String, Vec<usize>)> = groups.into_iter().collect();
        let tasks: Vec<(usize, usize)> = (0..group_list.len())
            .flat_map(|g| [(g, 0), (g, 1)])
            .collect();
        let bases: Vec<Mask> = group_list
            .iter()
            .map(|(_, m)| {
                // identifiability::group_basis on the masks: the columns in every case's basis
                m.iter().fold(Mask::MAX, |b, &i| b & work[i].ident.in_basis)
            })
            .collect();
        let mut outcomes: Vec<Option<GroupOutcome>> = (0..tasks.len()).map(|_| None).collect();
        let n_tasks = tasks.len();
        let mut done = 0;
        for chunk in (0..n_tasks).collect::<Vec<_>>().chunks(batch) {
            let res: Vec<GroupOutcome> = chunk
                .par_iter()
                .map(|&k| {
                    let (g, target) = tasks[k];
                    let members: Vec<&CaseWork> =
                        group_list[g].1.iter().map(|&i| work[i]).collect();
                    run_group(
                        &members,
                        target,
                        settings,
                        chosen,
                        bases[g],
                        kept[target],
                        opts,
                    )
                })
                .collect();
            for (&k, r) in chunk.iter().zip(res) {
                outcomes[k] = Some(r);
            }
            done += chunk.len();
            observer(Progress::Groups {
                done,
                total: n_tasks,
            });
        }

        // assemble
        let mut case_coefs: Vec<[Vec<f64>; 2]> = vec![[Vec::new(), Vec::new()]; total];
        let mut case_group: Vec<usize> = vec![0; total];
        let mut group_results = Vec::with_capacity(group_list.len());
        for (g, (name, members)) in group_list.iter().enumerate() {
            let mut forces = Vec::with_capacity(2);
            for target in 0..2 {
                let mut o = outcomes[2 * g + target]
                    .take()
                    .ok_or_else(|| Error::Numerical {
                        context: format!("group `{name}`"),
                        message: "missing path result".to_string(),
                    })?;
                for (k, &i) in members.iter().enumerate() {
                    case_coefs[i][target] = std::mem::take(&mut o.coefficients[k]);
                    case_group[i] = g;
                }
                forces.push(group_force(&o.path, &names));
            }
            let lift = forces.pop().ok_or_else(|| Error::Numerical {
                context: format!("group `{name}`"),
                message: "missing lift".to_string(),
            })?;
            let moment = forces.pop().ok_or_else(|| Error::Numerical {
                context: format!("group `{name}`"),
                message: "missing moment".to_string(),
            })?;
            group_results.push(GroupResult {
                name: name.clone(),
                cases: members.iter().map(|&i| cases[i].meta.id.clone()).collect(),
                basis: regress::mask_to_vec(bases[g])
                    .iter()
                    .map(|&j| names[j].clone())
                    .collect(),
                moment,
                lift,
            });
        }
        let min_case = (0..total)
            .min_by_key(|&i| (work[i].ident.rank, i))
            .unwrap_or(0);
        let library = LibraryInfo {
            terms: names.clone(),
            rank: work[min_case].ident.rank,
            dependencies: work[min_case].ident.dependencies.clone(),
            rank_case: Some(cases[min_case].meta.id.clone()),
            priority: self.order.iter().map(|&j| names[j].clone()).collect(),
        };
        drop(work);
        let case_results: Vec<CaseResult> = cases
            .iter()
            .zip(owned)
            .enumerate()
            .map(|(i, (c, w))| {
                let w: &CaseWork = w.borrow();
                let basis = bases[case_group[i]];
                CaseResult {
                    id: c.meta.id.clone(),
                    group: group_list[case_group[i]].0.clone(),
                    wind_speed: c.meta.wind_speed,
                    k_alpha: c.k_alpha,
                    k_h: c.k_h,
                    rank: w.ident.rank,
                    dependencies: w.ident.dependencies.clone(),
                    mean_pitch: w.centring.as_ref().map(|c| c.mean_pitch),
                    moment: force_result::<MomentEq19>(lib, c, w, 0, basis, &case_coefs[i][0]),
                    lift: force_result::<LiftEq19>(lib, c, w, 1, basis, &case_coefs[i][1]),
                }
            })
            .collect();
        Ok(Identification {
            format: FORMAT.to_string(),
            dataset: dataset_name.to_string(),
            settings: settings.clone(),
            library,
            cases: case_results,
            groups: group_results,
            ensemble: None,
        })
    }
}

#[cfg(test)]
mod fuzz_regressions {
    use super::*;

    /// Found by the `identification` fuzz target: a case whose `terms` object named a term
    /// twice (`"alpha^2": 0.0, …, "alpha^2": 4.03`) was accepted, and `TermMap::get` saw
    /// only the first value while iteration saw both (the law construction then took the
    /// median of an empty list). The reader now refuses a repeated term name.
    #[test]
    fn fuzz_regression_identification_duplicate_term_name() {
        let ok: TermMap = serde_json::from_str(r#"{"alpha": 1.0, "alpha^2": null}"#).unwrap();
        assert_eq!(ok.get("alpha"), Some(1.0));
        let e = serde_json::from_str::<TermMap>(r#"{"alpha^2": 0.0, "h": 1.0, "alpha^2": 4.0}"#)
            .unwrap_err();
        assert!(e.to_string().contains("duplicate term `alpha^2`"), "{e}");
    }
}
