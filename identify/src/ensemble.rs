//! Uncertainty of an identification: a moving-block bootstrap of whole forcing periods
//! within each case, with the selected supports held fixed.
//!
//! **What is resampled.** Each case's record (after preprocessing, which is done once) is cut
//! into `n_b` contiguous blocks of `block_periods` periods of its slowest forcing frequency
//! (the last block takes the remainder; without forcing frequencies, 20 equal blocks). A
//! member draws `n_b` blocks with replacement, independently per case and the same draw for
//! lift and moment (their noises stay paired). Blocks of whole periods keep the noise's
//! correlation inside a block and keep every block's regressors a full cycle of the motion,
//! so the resampled problem stays identifiable. Cases are not resampled: each case is one
//! reduced frequency of the derivative tables, and dropping or repeating cases would move
//! table nodes rather than measure the noise on them.
//!
//! **What is re-fitted.** The group's selected support of each force (from the full-data
//! identification) is re-fitted by least squares on the resampled record. Selection is not
//! repeated: the intervals are conditional on the selected support (a term the selection
//! dropped contributes no spread; see `docs/DECISIONS.md`).
//!
//! **Cost.** Per case and force, each block's column-normalised support columns and target
//! are reduced once to a triangle R_b and Q_bᵀy_b (q × q and q numbers). Repeating a block c
//! times multiplies its normal-equation contribution by c, so a member's fit is the
//! least-squares solve of the stack of √c_b·[R_b | Q_bᵀy_b] over the drawn blocks — a
//! (n_b q) × q problem, independent of the record length.
//!
//! **Finite-block correction.** The bootstrap variance of a sum of n_b blocks is
//! (n_b − 1)/n_b of the sampling variance, and it is itself an estimate with only n_b − 1
//! degrees of freedom (13 blocks for 10 s at 1.3 Hz), so a percentile interval of level ℓ
//! covers like a normal interval with an estimated variance: P(|t_{n_b−1}| < z_{(1+ℓ)/2})
//! ≈ 87.5 % for ℓ = 90 %, n_b = 13 (measured: 87.2 %). With `variance_correction` each member
//! is moved to θ̂ + c·(θ* − θ̂) (θ̂ the full-data fit) with
//! c = √(n_b/(n_b − 1))·t_{n_b−1}((1+ℓ)/2)/z((1+ℓ)/2), the usual Student correction of an
//! interval whose variance comes from n_b − 1 degrees of freedom. The factor depends on the
//! level, so the stored members are those of the stored level.
//!
//! **Intervals.** Percentile intervals: for level ℓ the empirical quantiles (1 − ℓ)/2 and
//! (1 + ℓ)/2 of the members (linear interpolation between order statistics), and the median.

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::eq19::{Eq19Values, LiftEq19, MomentEq19, EQ19_TERMS};
use crate::library::Library;
use crate::numerics::qr;
use crate::pipeline::{Identification, TermMap};
use crate::record::NondimCase;
use crate::regress::plugins;
use crate::{Error, Result};

pub(crate) mod types;
pub use types::{
    quantile_sorted, CaseEnsemble, Ensemble, EnsembleSettings, ForceEnsemble, Interval,
    DEFAULT_LEVEL,
};

/// Blocks used for a case without forcing frequencies.
const BLOCKS_WITHOUT_FORCING: usize = 20;

/// Per-case, per-force data of a bootstrap: each block's reduced triangle.
struct ForceBlocks {
    /// Library columns of the support.
    cols: Vec<usize>,
    /// Column scales (2-norm over the whole record).
    scales: Vec<f64>,
    /// Per block: column-major (q + 1) × q… stored as q × (q + 1) column-major [R_b | z_b].
    tri: Vec<Vec<f64>>,
}

/// SplitMix64 step ([`crate::numerics::split_seed`] of stream 0): decorrelates (seed, case,
/// member) into one RNG seed.
fn mix(z: u64) -> u64 {
    crate::numerics::split_seed(z, 0)
}

/// Block counts of member `m` of case `case_index` (n_b draws with replacement).
fn draw_counts(seed: u64, case_index: usize, member: usize, n_blocks: usize) -> Vec<u32> {
    let s = mix(mix(mix(seed) ^ case_index as u64) ^ member as u64);
    let mut rng = ChaCha8Rng::seed_from_u64(s);
    let mut c = vec![0u32; n_blocks];
    for _ in 0..n_blocks {
        c[rng.random_range(0..n_blocks)] += 1;
    }
    c
}

/// Block boundaries of a case: n_b = round(n / L) nearly equal contiguous blocks covering
/// 0..n, L = `block_periods` slowest forcing periods in samples (at least `min_rows`).
fn blocks_of(case: &NondimCase, block_periods: f64, min_rows: usize) -> Vec<(usize, usize)> {
    let n = case.len();
    let f_min = [case.forcing.pitch, case.forcing.heave]
        .into_iter()
        .flatten()
        .filter(|f| f.is_finite() && *f > 0.0)
        .fold(f64::INFINITY, f64::min);
    let mut len = if f_min.is_finite() {
        (block_periods / (f_min * case.dt)).round() as usize
    } else {
        n / BLOCKS_WITHOUT_FORCING
    };
    len = len.max(min_rows).max(1);
    let nb = ((n as f64 / len as f64).round() as usize).clamp(1, (n / min_rows.max(1)).max(1));
    (0..nb).map(|b| (b * n / nb, (b + 1) * n / nb)).collect()
}

impl ForceBlocks {
    fn new(
        theta: crate::numerics::mat::MatRef<'_, f64>,
        cols: Vec<usize>,
        y: &[f64],
        blocks: &[(usize, usize)],
    ) -> Self {
        let q = cols.len();
        let scales: Vec<f64> = cols
            .iter()
            .map(|&j| {
                let s = (0..theta.nrows())
                    .map(|i| theta[(i, j)] * theta[(i, j)])
                    .sum::<f64>()
                    .sqrt();
                if s > 0.0 {
                    s
                } else {
                    1.0
                }
            })
            .collect();
        let tri = blocks
            .iter()
            .map(|&(r0, r1)| {
                let m = r1 - r0;
                let mut a = vec![0.0; m * (q + 1)];
                for (k, &j) in cols.iter().enumerate() {
                    for i in 0..m {
                        a[k * m + i] = theta[(r0 + i, j)] / scales[k];
                    }
                }
                a[q * m..].copy_from_slice(&y[r0..r1]);
                let nref = q.min(m);
                let diag = qr::householder_qr(&mut a, m, q + 1, nref);
                // [R_b | z_b], q × (q + 1) column-major
                let mut t = vec![0.0; q * (q + 1)];
                for c in 0..=q {
                    for i in 0..q.min(m) {
                        t[c * q + i] = if c < q && i == c {
                            diag[i]
                        } else if i < c || c == q {
                            a[c * m + i]
                        } else {
                            0.0
                        };
                    }
                }
                t
            })
            .collect();
        ForceBlocks { cols, scales, tri }
    }

    /// Raw coefficients (support order) of the fit with block counts `counts`.
    fn fit(&self, counts: &[u32]) -> Vec<f64> {
        let q = self.cols.len();
        if q == 0 {
            return Vec::new();
        }
        let used: Vec<(usize, f64)> = counts
            .iter()
            .enumerate()
            .filter(|(_, &c)| c > 0)
            .map(|(b, &c)| (b, f64::from(c).sqrt()))
            .collect();
        let m = used.len() * q;
        let mut a = vec![0.0; m * q];
        let mut rhs = vec![0.0; m];
        for (u, &(b, w)) in used.iter().enumerate() {
            let t = &self.tri[b];
            for c in 0..q {
                for i in 0..q {
                    a[c * m + u * q + i] = w * t[c * q + i];
                }
            }
            for i in 0..q {
                rhs[u * q + i] = w * t[q * q + i];
            }
        }
        let (x, _) = qr::lstsq(&a, m, q, &rhs, 0.0);
        x.iter().zip(&self.scales).map(|(v, s)| v / s).collect()
    }
}

/// Standard normal quantile (Acklam's rational approximation, relative error < 1.2e-9).
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p <= 0.0 {
        f64::NEG_INFINITY
    } else if p >= 1.0 {
        f64::INFINITY
    } else if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// Student-t quantile with ν degrees of freedom from the normal quantile z by the
/// Cornish–Fisher expansion to ν⁻⁴ (Abramowitz & Stegun 26.7.5; error < 1e-3 for ν ≥ 5 at
/// the 95 % point, exact as ν → ∞).
pub fn student_quantile(p: f64, nu: f64) -> f64 {
    let z = normal_quantile(p);
    let z2 = z * z;
    let g1 = (z2 + 1.0) * z / 4.0;
    let g2 = ((5.0 * z2 + 16.0) * z2 + 3.0) * z / 96.0;
    let g3 = (((3.0 * z2 + 19.0) * z2 + 17.0) * z2 - 15.0) * z / 384.0;
    let g4 = ((((79.0 * z2 + 776.0) * z2 + 1482.0) * z2 - 1920.0) * z2 - 945.0) * z / 92160.0;
    z + g1 / nu + g2 / nu.powi(2) + g3 / nu.powi(3) + g4 / nu.powi(4)
}

/// Finite-block factor c = √(n_b/(n_b − 1))·t_{n_b−1}((1+ℓ)/2)/z((1+ℓ)/2) (module docs).
pub fn finite_block_factor(n_blocks: usize, level: f64) -> f64 {
    let nu = n_blocks as f64 - 1.0;
    let p = (1.0 + level) / 2.0;
    (n_blocks as f64 / nu).sqrt() * student_quantile(p, nu) / normal_quantile(p)
}

/// Eq. 19 names of a force, in [`EQ19_TERMS`] order.
fn eq19_names(moment: bool) -> [&'static str; 7] {
    if moment {
        crate::eq19::MOMENT_NAMES
    } else {
        crate::eq19::LIFT_NAMES
    }
}

/// Eq. 19 values of a force from raw coefficients `support`/`values`, the terms that are
/// in the basis taken from `base` (a term in the basis but not in the support is 0).
fn eq19_of(
    base: &TermMap,
    support: &[String],
    values: &[f64],
    k_alpha: Option<f64>,
    k_h: Option<f64>,
) -> Eq19Values {
    let xi = EQ19_TERMS.map(|t| {
        base.0.iter().find(|(n, _)| n == t).and_then(|(_, v)| {
            v.map(|_| {
                support
                    .iter()
                    .position(|s| s == t)
                    .map_or(0.0, |k| values[k])
            })
        })
    });
    Eq19Values::from_coefficients(xi, k_alpha, k_h)
}

/// Runs the block bootstrap of `id` (module docs) on the prepared `cases` it was identified
/// from (matched by id; the same cases, in any order).
///
/// Deterministic: the draws of member m of case i come from a ChaCha8 stream seeded by
/// (seed, i, m), so the result depends neither on the thread count nor on the order of work.
///
/// # Errors
/// [`Error::InvalidOption`] for invalid settings, an unregistered regressor, or when the
/// identification used ridge or a regressor whose coefficients are not plain least squares
/// on the support ([`crate::regress::plugin::Regressor::refits_by_least_squares`]: the
/// re-fit is plain least squares); [`Error::InvalidData`] naming
/// the case when a case of `id` is missing from `cases`, or a support term is unknown to
/// the library.
pub fn bootstrap(
    cases: &[NondimCase],
    id: &Identification,
    settings: &EnsembleSettings,
) -> Result<Ensemble> {
    settings.validate()?;
    check_refits(id)?;
    let lib = Library::new(id.settings.library, id.settings.constant);
    let work: Vec<(usize, &NondimCase)> = id
        .cases
        .iter()
        .enumerate()
        .map(|(i, c)| {
            cases
                .iter()
                .find(|x| x.meta.id == c.id)
                .map(|x| (i, x))
                .ok_or_else(|| Error::InvalidData {
                    case: c.id.clone(),
                    field: "id".to_string(),
                    message: "case of the identification not among the prepared cases".to_string(),
                })
        })
        .collect::<Result<_>>()?;
    let out: Vec<Result<CaseEnsemble>> = work
        .par_iter()
        .map(|&(i, case)| case_ensemble(&lib, id, i, case, settings))
        .collect();
    Ok(Ensemble {
        method: "block_bootstrap".to_string(),
        settings: settings.clone(),
        cases: out.into_iter().collect::<Result<_>>()?,
    })
}

/// Refuses an identification whose coefficients the bootstrap's least-squares re-fit
/// would not reproduce: ridge, or a regressor that does not re-fit by least squares.
fn check_refits(id: &Identification) -> Result<()> {
    check_settings(&id.settings)
}

/// Whether an identification under `settings` can have an ensemble: the bootstrap re-fits
/// by least squares, so the regressor must re-fit by least squares on its support
/// ([`crate::regress::plugin::Regressor::refits_by_least_squares`]) and the ridge must be
/// 0. Callers check this before reading any data, so that `--ensemble` with `--regressor
/// pysindy` is refused at once, not after the whole identification (issue 39, round 29).
///
/// # Errors
/// [`Error::InvalidOption`] naming `ensemble` and the regressors that qualify; an unknown
/// regressor as [`plugins::find`].
pub fn check_settings(settings: &crate::pipeline::IdentifySettings) -> Result<()> {
    let refits = plugins::find(&settings.regressor.kind)?.refits_by_least_squares();
    if !refits || settings.ridge != 0.0 {
        let fit: Vec<&str> = plugins::registry()
            .iter()
            .filter(|r| r.refits_by_least_squares())
            .map(|r| r.name())
            .collect();
        return Err(Error::InvalidOption {
            name: "ensemble".to_string(),
            message: format!(
                "the bootstrap re-fits by least squares: use the {} regressor with ridge = 0",
                fit.join(" or ")
            ),
        });
    }
    Ok(())
}

/// The ensemble entries of the cases of `id` whose samples are `cases` (a part of the
/// identification's cases, e.g. one batch re-read from disk by a streaming caller), in the
/// order of `cases`: each entry is exactly the one [`bootstrap`] gives that case (its draws
/// depend on the seed and the case's index in `id`, not on the other cases).
///
/// # Errors
/// As [`bootstrap`].
pub fn bootstrap_subset(
    cases: &[NondimCase],
    id: &Identification,
    settings: &EnsembleSettings,
) -> Result<Vec<CaseEnsemble>> {
    settings.validate()?;
    check_refits(id)?;
    let lib = Library::new(id.settings.library, id.settings.constant);
    let index: std::collections::HashMap<&str, usize> = id
        .cases
        .iter()
        .enumerate()
        .map(|(i, c)| (c.id.as_str(), i))
        .collect();
    let work: Vec<(usize, &NondimCase)> = cases
        .iter()
        .map(|x| {
            index
                .get(x.meta.id.as_str())
                .map(|&i| (i, x))
                .ok_or_else(|| Error::InvalidData {
                    case: x.meta.id.clone(),
                    field: "id".to_string(),
                    message: "case not among the identification's cases".to_string(),
                })
        })
        .collect::<Result<_>>()?;
    work.par_iter()
        .map(|&(i, case)| case_ensemble(&lib, id, i, case, settings))
        .collect()
}

fn case_ensemble(
    lib: &Library,
    id: &Identification,
    index: usize,
    case: &NondimCase,
    s: &EnsembleSettings,
) -> Result<CaseEnsemble> {
    let cr = &id.cases[index];
    let group = id
        .groups
        .iter()
        .find(|g| g.name == cr.group)
        .ok_or_else(|| Error::InvalidData {
            case: cr.id.clone(),
            field: "group".to_string(),
            message: format!("group `{}` not in the identification", cr.group),
        })?;
    let cols_of = |support: &[String]| -> Result<Vec<usize>> {
        support
            .iter()
            .map(|t| {
                lib.index_of(t).map_err(|e| Error::InvalidData {
                    case: cr.id.clone(),
                    field: "support".to_string(),
                    message: e.to_string(),
                })
            })
            .collect()
    };
    let cm = cols_of(&group.moment.support)?;
    let cl = cols_of(&group.lift.support)?;
    let q_max = cm.len().max(cl.len());
    let blocks = blocks_of(case, s.block_periods, 2 * q_max + 2);
    let theta = lib.evaluate(&case.x);
    let fb = [
        ForceBlocks::new(theta.as_ref(), cm, &case.c_moment, &blocks),
        ForceBlocks::new(theta.as_ref(), cl, &case.c_lift, &blocks),
    ];
    drop(theta);
    let nb = blocks.len();
    let ones = vec![1u32; nb];
    let centre = [fb[0].fit(&ones), fb[1].fit(&ones)];
    let scale = if s.variance_correction && nb > 1 {
        finite_block_factor(nb, s.level)
    } else {
        1.0
    };
    let mut samples: [Vec<Vec<f64>>; 2] = [Vec::new(), Vec::new()];
    for m in 0..s.members {
        let counts = draw_counts(s.seed, index, m, nb);
        for t in 0..2 {
            let x = fb[t].fit(&counts);
            samples[t].push(
                x.iter()
                    .zip(&centre[t])
                    .map(|(v, c)| c + scale * (v - c))
                    .collect(),
            );
        }
    }
    let [sm, sl] = samples;
    let force = |t: usize, support: &[String], base: &TermMap, samples: Vec<Vec<f64>>| {
        let mut terms = BTreeMap::new();
        for (k, name) in support.iter().enumerate() {
            let v: Vec<f64> = samples.iter().map(|x| x[k]).collect();
            if let Some(iv) = Interval::from_samples(&v, s.level) {
                terms.insert(name.clone(), iv);
            }
        }
        let eq: Vec<Eq19Values> = samples
            .iter()
            .map(|x| eq19_of(base, support, x, cr.k_alpha, cr.k_h))
            .collect();
        let mut eq19 = BTreeMap::new();
        for (j, name) in eq19_names(t == 0).iter().enumerate() {
            if !support.iter().any(|x| x == EQ19_TERMS[j]) {
                continue; // not in the model: 0 with no spread, not an interval
            }
            let v: Vec<f64> = eq.iter().filter_map(|e| e.0[j]).collect();
            if let Some(iv) = Interval::from_samples(&v, s.level) {
                eq19.insert(name.to_string(), iv);
            }
        }
        ForceEnsemble {
            support: support.to_vec(),
            terms,
            eq19,
            samples,
        }
    };
    Ok(CaseEnsemble {
        id: cr.id.clone(),
        blocks: nb,
        block_samples: blocks[0].1 - blocks[0].0,
        moment: force(0, &group.moment.support, &cr.moment.terms, sm),
        lift: force(1, &group.lift.support, &cr.lift.terms, sl),
    })
}

impl Ensemble {
    /// Number of members.
    pub fn members(&self) -> usize {
        self.settings.members
    }

    /// Checks that the section matches `id` (one entry per case, same ids and order, one
    /// sample row per member of the support's length) — a hand-edited or truncated file.
    ///
    /// # Errors
    /// [`Error::InvalidData`] naming the case and the field.
    pub fn check(&self, id: &Identification) -> Result<()> {
        let bad = |case: &str, field: &str, message: String| Error::InvalidData {
            case: case.to_string(),
            field: format!("ensemble.{field}"),
            message,
        };
        if self.cases.len() != id.cases.len() {
            return Err(bad(
                "-",
                "cases",
                format!(
                    "{} entries for {} identified cases",
                    self.cases.len(),
                    id.cases.len()
                ),
            ));
        }
        for (e, c) in self.cases.iter().zip(&id.cases) {
            if e.id != c.id {
                return Err(bad(
                    &c.id,
                    "cases",
                    format!("entry `{}` out of order", e.id),
                ));
            }
            for (name, f, base) in [
                ("moment", &e.moment, &c.moment.terms),
                ("lift", &e.lift, &c.lift.terms),
            ] {
                if f.samples.len() != self.settings.members {
                    return Err(bad(
                        &c.id,
                        &format!("{name}.samples"),
                        format!(
                            "{} rows for {} members",
                            f.samples.len(),
                            self.settings.members
                        ),
                    ));
                }
                if let Some(r) = f.samples.iter().position(|r| r.len() != f.support.len()) {
                    return Err(bad(
                        &c.id,
                        &format!("{name}.samples[{r}]"),
                        format!(
                            "{} values for {} support terms",
                            f.samples[r].len(),
                            f.support.len()
                        ),
                    ));
                }
                if let Some(t) = f.support.iter().find(|t| base.get(t).is_none()) {
                    return Err(bad(
                        &c.id,
                        &format!("{name}.support"),
                        format!("term `{t}` has no identified coefficient"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The identification of member `m`: `base` with every case's support coefficients and
    /// Eq. 19 values replaced by the member's (terms outside the support keep their value,
    /// 0 or `null`); no `ensemble` section.
    ///
    /// # Errors
    /// As [`Ensemble::check`]; [`Error::InvalidOption`] naming `member` when m ≥ N.
    pub fn member(&self, base: &Identification, m: usize) -> Result<Identification> {
        self.check(base)?;
        if m >= self.settings.members {
            return Err(Error::InvalidOption {
                name: "member".to_string(),
                message: format!("{m} ≥ the {} members", self.settings.members),
            });
        }
        let mut out = Identification {
            format: base.format.clone(),
            dataset: base.dataset.clone(),
            settings: base.settings.clone(),
            library: base.library.clone(),
            cases: base.cases.clone(),
            groups: base.groups.clone(),
            ensemble: None,
        };
        for (c, e) in out.cases.iter_mut().zip(&self.cases) {
            let set = |terms: &mut TermMap, f: &ForceEnsemble| {
                for (name, v) in &mut terms.0 {
                    if let Some(k) = f.support.iter().position(|s| s == name) {
                        *v = Some(f.samples[m][k]);
                    }
                }
            };
            set(&mut c.moment.terms, &e.moment);
            set(&mut c.lift.terms, &e.lift);
            c.moment.eq19 = MomentEq19::from(eq19_of(
                &c.moment.terms,
                &e.moment.support,
                &e.moment.samples[m],
                c.k_alpha,
                c.k_h,
            ));
            c.lift.eq19 = LiftEq19::from(eq19_of(
                &c.lift.terms,
                &e.lift.support,
                &e.lift.samples[m],
                c.k_alpha,
                c.k_h,
            ));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests;
