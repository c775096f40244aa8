//! The pysindy plug-in: pysindy 2.1 STLSQ per case on the raw columns of the case's
//! identifiable basis ([`crate::regress::adapter`]), walking pysindy's `threshold` on raw
//! coefficients. The group support of a threshold is the union of the case supports; kept
//! terms do not apply (pysindy has none).
//!
//! The whole path of every case is computed once, when the case is prepared (the raw
//! library matrix is evaluated there and not kept), and held compactly ([`crate::regress::plugins::pysindy::CompactPath`]:
//! each distinct fit once, its nonzero entries only, and per run of equal grid points the
//! index of its fit) for the group stage, which hands it out one point at a time
//! ([`crate::regress::plugin::Regressor::walk_path`]) and reads the selected point again
//! ([`crate::regress::plugin::Regressor::coefficients_at`]). Decoding gives the dense vectors bit for bit.

use crate::regress::adapter::{self, PysindyOptions};
use crate::regress::plugin::{
    CaseData, CaseInput, FitSettings, GroupInput, OptionKind, OptionSpec, OptionValue,
    Options, PathFits, PathGrid, PathParameter, Regressor,
};
use crate::regress::{Mask, Measure};
use crate::Result;

/// pysindy-compatible STLSQ (`--regressor pysindy`).
#[derive(Debug, Clone, Copy)]
pub struct Pysindy;

/// The per-case data: per target (moment, lift), the compact path of raw coefficients.
struct CasePaths([CompactPath; 2]);

/// One case's path of raw coefficient vectors over the library (length `p` ≤ 64), held
/// compactly: every distinct fit once (its entries whose bits are not all zero, in column
/// order: a `-0.0` or a NaN is kept as it is) and, per run of consecutive grid points with
/// the same fit, the run's first grid index and the fit's index.
///
/// pysindy's fit at a threshold depends on the final support only (the unbias refit, or the
/// ridge fit on a converged support), so a path of n_delta points holds a few distinct
/// fits of a few terms, against n_delta · p · 8 B (12 kB at 50 × 30) held dense before
/// round 29 (the 40,000-file set: 1.98 GB → 0.78 GB, stlsq's peak). Memory is at most the dense
/// path's plus 16 B per fit and 8 B per run (every point distinct and dense).
#[derive(Debug, Clone, PartialEq)]
pub struct CompactPath {
    /// Library size (length of a decoded vector).
    p: u8,
    /// Per distinct fit, the columns whose stored bits are not zero.
    masks: Vec<u64>,
    /// The stored entries of every fit, fit after fit, in column order.
    values: Vec<f64>,
    /// Per distinct fit, where its entries start in `values`.
    starts: Vec<u32>,
    /// Per run of equal points: (first grid index of the run, index of its fit), ascending.
    runs: Vec<(u32, u32)>,
    /// Number of grid points.
    len: u32,
}

impl CompactPath {
    /// The compact form of `dense` (one raw coefficient vector per grid point, each of the
    /// same length p ≤ 64).
    ///
    /// # Panics
    /// When the vectors differ in length, p > 64 or there are more than 2³² points (a
    /// programming error: the library has at most 64 columns, the grid at most
    /// [`crate::limits::MAX_N_DELTA`] points).
    pub fn new(dense: &[Vec<f64>]) -> Self {
        let p = dense.first().map_or(0, Vec::len);
        assert!(p <= 64, "at most 64 library columns");
        let mut c = CompactPath {
            p: p as u8,
            masks: Vec::new(),
            values: Vec::new(),
            starts: Vec::new(),
            runs: Vec::new(),
            len: u32::try_from(dense.len()).expect("grid of at most 2^32 points"),
        };
        let mut last: Option<u32> = None;
        for (d, v) in dense.iter().enumerate() {
            assert_eq!(v.len(), p, "one length for every point");
            let mask = v
                .iter()
                .enumerate()
                .fold(0u64, |m, (j, x)| if x.to_bits() != 0 { m | 1 << j } else { m });
            let same = |k: usize| {
                c.masks[k] == mask && {
                    let s = c.starts[k] as usize;
                    let n = mask.count_ones() as usize;
                    v.iter()
                        .filter(|x| x.to_bits() != 0)
                        .zip(&c.values[s..s + n])
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                }
            };
            let k = match (0..c.masks.len()).find(|&k| same(k)) {
                Some(k) => k as u32,
                None => {
                    c.masks.push(mask);
                    c.starts.push(c.values.len() as u32);
                    c.values.extend(v.iter().filter(|x| x.to_bits() != 0));
                    (c.masks.len() - 1) as u32
                }
            };
            if last != Some(k) {
                c.runs.push((d as u32, k));
                last = Some(k);
            }
        }
        c.masks.shrink_to_fit();
        c.values.shrink_to_fit();
        c.starts.shrink_to_fit();
        c.runs.shrink_to_fit();
        c
    }

    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the path has no point.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of distinct fits held.
    pub fn distinct(&self) -> usize {
        self.masks.len()
    }

    /// Bytes held on the heap (capacity of the four vectors), for the memory budget.
    pub fn heap_bytes(&self) -> usize {
        self.masks.capacity() * 8
            + self.values.capacity() * 8
            + self.starts.capacity() * 4
            + self.runs.capacity() * 8
    }

    /// The raw coefficients at grid index `d` (length p), bit for bit those given to
    /// [`CompactPath::new`]; an empty vector past the end.
    pub fn point(&self, d: usize) -> Vec<f64> {
        if d >= self.len() {
            return Vec::new();
        }
        let r = self.runs.partition_point(|&(s, _)| s as usize <= d) - 1;
        let k = self.runs[r].1 as usize;
        let mask = self.masks[k];
        let mut out = vec![0.0; self.p as usize];
        let mut next = self.starts[k] as usize;
        for (j, o) in out.iter_mut().enumerate() {
            if mask >> j & 1 == 1 {
                *o = self.values[next];
                next += 1;
            }
        }
        out
    }
}

const OPTIONS: &[OptionSpec] = &[
    OptionSpec {
        name: "alpha",
        kind: OptionKind::Float {
            min: 0.0,
            max: f64::INFINITY,
        },
        default: OptionValue::Float(0.05),
        doc: "ridge parameter on raw columns (pysindy default 0.05)",
    },
    OptionSpec {
        name: "max_iter",
        kind: OptionKind::Count {
            min: 1,
            max: 1_000_000,
        },
        default: OptionValue::Count(20),
        doc: "maximum iterations (pysindy default 20)",
    },
    OptionSpec {
        name: "unbias",
        kind: OptionKind::Flag,
        default: OptionValue::Flag(true),
        doc: "least-squares refit on the final support (pysindy default true)",
    },
];

fn options(o: &Options) -> PysindyOptions {
    PysindyOptions {
        alpha: o.float("alpha"),
        max_iter: o.count("max_iter") as usize,
        unbias: o.flag("unbias"),
    }
}

impl Regressor for Pysindy {
    fn name(&self) -> &'static str {
        "pysindy"
    }
    fn doc(&self) -> &'static str {
        "pysindy 2.1 STLSQ per case on raw columns (comparison mode; the group support is \
         the union of the case supports)."
    }
    fn options(&self) -> &'static [OptionSpec] {
        OPTIONS
    }
    fn path_parameter(&self, _shared: &FitSettings) -> PathParameter {
        PathParameter {
            name: "threshold",
            unit: "raw coefficient |xi_j| on raw columns",
            grid: PathGrid::Log {
                measure: Measure::Coefficient,
            },
        }
    }
    fn refits_by_least_squares(&self) -> bool {
        false
    }
    fn prepare_case(&self, case: &CaseInput<'_>) -> Result<Option<CaseData>> {
        let o = options(case.options);
        // comparison mode: pysindy works on the whole matrix
        let theta = case.library.evaluate(case.x);
        let paths = case.measured.map(|y| {
            CompactPath::new(&adapter::path_case(
                theta.as_ref(),
                case.basis,
                y,
                case.grid,
                &o,
            ))
        });
        Ok(Some(Box::new(CasePaths(paths))))
    }
    fn fit_path(&self, group: &GroupInput<'_>, grid: &[f64]) -> PathFits {
        (0..grid.len()).map(|d| point(group, d)).collect()
    }
    fn walk_path(
        &self,
        group: &GroupInput<'_>,
        grid: &[f64],
        sink: &mut dyn FnMut(Mask, &[Vec<f64>]),
    ) {
        for d in 0..grid.len() {
            let (mask, coefs) = point(group, d);
            sink(mask, &coefs);
        }
    }
    /// The per-case paths are prepared once: the point is decoded from them.
    fn coefficients_at(
        &self,
        group: &GroupInput<'_>,
        _grid: &[f64],
        index: usize,
        _mask: Mask,
    ) -> Vec<Vec<f64>> {
        point(group, index).1
    }
}

/// Path point `d` of a group: the union of the case supports and, per case, its raw
/// coefficients (from the per-case paths of [`Regressor::prepare_case`]).
fn point(group: &GroupInput<'_>, d: usize) -> (Mask, Vec<Vec<f64>>) {
    let coefs: Vec<Vec<f64>> = group
        .data
        .iter()
        .map(|w| {
            w.and_then(|p| p.downcast_ref::<CasePaths>())
                .map(|p| p.0[group.target].point(d))
                .unwrap_or_default()
        })
        .collect();
    let mask: Mask = coefs.iter().fold(0u64, |m, c| {
        m | c
            .iter()
            .enumerate()
            .fold(0u64, |a, (j, &x)| if x != 0.0 { a | 1 << j } else { a })
    });
    (mask, coefs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A real pysindy path (random raw library, sparse law, seed 29) and hand-made paths
    /// with signed zeros, a NaN, alternating and repeated fits decode bit for bit, and the
    /// real one is held in far less than its dense form.
    #[test]
    fn compact_paths_decode_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(29);
        let (n, p) = (200, 30);
        let theta = crate::numerics::mat::Mat::<f64>::from_fn(n, p, |_, _| rng.random::<f64>() - 0.5);
        let y: Vec<f64> = (0..n)
            .map(|i| {
                2.0 * theta[(i, 0)] - 0.8 * theta[(i, 3)]
                    + 0.3 * theta[(i, 7)]
                    + 0.01 * (rng.random::<f64>() - 0.5)
            })
            .collect();
        let basis: Vec<usize> = (0..p).collect();
        let grid: Vec<f64> = (0..50).map(|i| 1e-4 * 10f64.powf(i as f64 / 10.0)).collect();
        let dense = adapter::path_case(
            theta.as_ref(),
            &basis,
            &y,
            &grid,
            &PysindyOptions::default(),
        );
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let check = |dense: &[Vec<f64>]| {
            let c = CompactPath::new(dense);
            assert_eq!(c.len(), dense.len());
            for (d, v) in dense.iter().enumerate() {
                assert_eq!(bits(&c.point(d)), bits(v), "point {d}");
            }
            assert!(c.point(dense.len()).is_empty());
            c
        };
        let c = check(&dense);
        let dense_bytes = grid.len() * p * 8;
        assert!(c.distinct() >= 3 && c.distinct() < grid.len(), "{}", c.distinct());
        assert!(
            c.heap_bytes() * 4 < dense_bytes,
            "{} B compact vs {dense_bytes} B dense",
            c.heap_bytes()
        );
        let a = vec![1.0, 0.0, -0.0, 2.0];
        let b = vec![1.0, 0.0, 0.0, 2.0];
        let z = vec![0.0; 4];
        let q = vec![f64::NAN, 0.0, 0.0, -1e-300];
        let hand = vec![
            a.clone(),
            a.clone(),
            b.clone(),
            a.clone(),
            z.clone(),
            q.clone(),
            q,
            z,
            b,
        ];
        let c = check(&hand);
        assert_eq!(c.distinct(), 4);
        assert_eq!(c.runs.len(), 7);
        assert!(CompactPath::new(&[]).is_empty());
    }
}
