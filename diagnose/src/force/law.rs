//! The force law of one fold: per (configuration, wind speed) node a coefficient vector on
//! the configuration's linear support (shared by the node's amplitudes), the coefficients γ
//! of the section's nonlinear terms shared by every node (one section, one nonlinear law),
//! plus augmentation coefficients β shared by every node; and its held-out prediction with
//! the node coefficients interpolated over K.
//!
//! Fit: min Σ_nodes ‖y_n − X_n a_n − Z_n (γ, β)‖² by block elimination: (γ, β) from the
//! stacked projections (I − P_n) Z_n, (I − P_n) y_n (P_n the projector on the node's support
//! columns), then a_n by least squares on y_n − Z_n (γ, β).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use identify::library::Term;

use super::data::{CaseData, Node};
use identify::numerics::interp::lagrange;
use identify::numerics::qr::ThinQr;

use crate::numerics::{dot, ridge_solve};

/// Relative tolerance of dropped (dependent) columns.
const QR_TOL: f64 = 1e-9;
/// Relative ridge of the shared-coefficient solve (a direction the projected data do not
/// determine gets β ≈ 0 instead of an arbitrary value).
pub(crate) const BETA_RIDGE: f64 = 1e-9;

/// Support of each configuration (lift, moment).
pub(crate) type Supports = std::collections::BTreeMap<String, [Vec<Term>; 2]>;

/// Cached factorisation of one training node and channel on a given support: stacked
/// support columns (QR), targets, noise weights, and the per-node statistics of every
/// augmentation column set seen so far (computed once, shared by every fold that trains
/// on the node with the same support).
#[derive(Debug)]
pub(crate) struct NodeChan {
    pub qr: ThinQr,
    /// Mean over the stacked samples of the noise weight 1/σ̂.
    pub w_mean: f64,
    /// n_cases / Σ σ̂ of the node's cases (weight of the selection statistics).
    pub w_pool: f64,
    /// Residual of `y` on the support, y − Q Qᵀ y.
    pub res_y: Vec<f64>,
    /// Least-squares coefficients of `y` on the support.
    pub a_y: Vec<f64>,
    grams: Mutex<HashMap<String, Arc<NodeGram>>>,
}

/// Per-node statistics of an augmentation column set Z (columns j) against the node's
/// support: z̃_j = (I − P) z_j.
#[derive(Debug)]
pub(crate) struct NodeGram {
    /// z̃_j · z̃_k.
    pub g: Vec<Vec<f64>>,
    /// z̃_j · (I − P) y.
    pub b: Vec<f64>,
    /// True when the support spans z_j (‖z̃_j‖² ≤ 1e-12 ‖z_j‖²).
    pub absorbed: Vec<bool>,
    /// Least-squares coefficients of z_j on the support.
    pub a: Vec<Vec<f64>>,
}

impl NodeChan {
    /// Statistics of the column set `key` (stacked columns `cols()`), computed on first use.
    pub fn gram(&self, key: &str, cols: &dyn Fn() -> Vec<Vec<f64>>) -> Arc<NodeGram> {
        if let Some(g) = self.grams.lock().ok().and_then(|m| m.get(key).cloned()) {
            return g;
        }
        // projected in place, four columns at a time through the support's reflectors
        // (peak: one set of columns, not the raw and the projected ones)
        let mut zt = cols();
        let norms: Vec<f64> = zt.iter().map(|c| dot(c, c)).collect();
        let a = self.qr.residuals_and_solves(&mut zt);
        let absorbed = zt
            .iter()
            .zip(&norms)
            .map(|(r, &n)| dot(r, r) <= 1e-12 * n)
            .collect();
        let g = gram_matrix(&zt);
        let b = zt.iter().map(|r| dot(r, &self.res_y)).collect();
        let out = Arc::new(NodeGram { g, b, absorbed, a });
        if let Ok(mut mp) = self.grams.lock() {
            mp.entry(key.to_string()).or_insert_with(|| out.clone());
        }
        out
    }
}

/// Samples per tile of [`gram_matrix`] (a multiple of 16): 512 samples of ~130 columns
/// (≈ 0.5 MB) stay in the core's L2 cache while every pair of columns is accumulated.
const GRAM_TILE: usize = 512;

/// The symmetric Gram matrix `g[j][k] = dot(z[j], z[k])` of equally long columns, **bit for
/// bit** the value of [`dot`] on each pair: the same sixteen partial sums per pair, updated
/// in the same sample order and reduced the same way, only visited tile by tile
/// ([`GRAM_TILE`] samples) so that a tile of every column is read from cache m/2 times
/// instead of each whole column from memory m times (the pool of `dynamic_stall`: 129
/// columns of 20,480 samples per node).
pub(crate) fn gram_matrix(z: &[Vec<f64>]) -> Vec<Vec<f64>> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above); as for AVX2 below
            return unsafe { gram_matrix_avx512(z) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above); the function only differs
            // from the portable one by the instructions the compiler may use (no fused
            // multiply-add: Rust never contracts `a * b + c`, so the values are the same)
            return unsafe { gram_matrix_avx2(z) };
        }
    }
    gram_matrix_body(z)
}

/// [`gram_matrix_body`] compiled with AVX2 (runtime-dispatched: the release profile targets
/// baseline x86-64; four lanes per instruction instead of two, the same IEEE operations in
/// the same order, so bit for bit the portable result).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gram_matrix_avx2(z: &[Vec<f64>]) -> Vec<Vec<f64>> {
    gram_matrix_body(z)
}

/// [`gram_matrix_body`] compiled with AVX-512F: a pair's sixteen partial sums in two
/// registers, the four pairs of a 2 × 2 block in eight (the same IEEE operations in the same
/// order, so bit for bit the portable result).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn gram_matrix_avx512(z: &[Vec<f64>]) -> Vec<Vec<f64>> {
    gram_matrix_body(z)
}

/// Sixteen partial sums of one pair over a tile: `ac[l] += x[l]·y[l]` chunk by chunk.
#[inline(always)]
fn pair_tile(ac: &mut [f64; 16], a: &[f64], b: &[f64]) {
    for (x, y) in a.chunks_exact(16).zip(b.chunks_exact(16)) {
        for l in 0..16 {
            ac[l] += x[l] * y[l];
        }
    }
}

/// Two pairs (a, b) and (a, c) over a tile, each with its own sixteen partial sums updated
/// in the same order as [`pair_tile`] (each chunk of `a` read once for both).
#[inline(always)]
fn pair_tile2(ac: &mut [f64; 16], ad: &mut [f64; 16], a: &[f64], b: &[f64], c: &[f64]) {
    for ((x, y), w) in a
        .chunks_exact(16)
        .zip(b.chunks_exact(16))
        .zip(c.chunks_exact(16))
    {
        for l in 0..16 {
            ac[l] += x[l] * y[l];
            ad[l] += x[l] * w[l];
        }
    }
}

/// The three pairs (a, a), (a, b), (b, b) of a diagonal 2 × 2 block over a tile, each
/// updated in the same order as [`pair_tile`] (two loads for three pairs).
#[inline(always)]
fn pair_tile_diag(
    aa: &mut [f64; 16],
    ab: &mut [f64; 16],
    bb: &mut [f64; 16],
    a: &[f64],
    b: &[f64],
) {
    // local copies: the sums stay in registers (three `&mut` the compiler must otherwise
    // reload and store every chunk in case they alias)
    let (mut p, mut q, mut r) = (*aa, *ab, *bb);
    for (x, y) in a.chunks_exact(16).zip(b.chunks_exact(16)) {
        for l in 0..16 {
            p[l] += x[l] * x[l];
            q[l] += x[l] * y[l];
            r[l] += y[l] * y[l];
        }
    }
    (*aa, *ab, *bb) = (p, q, r);
}

/// The four pairs (a, c), (a, d), (b, c), (b, d) of a 2 × 2 block over a tile, each updated
/// in the same order as [`pair_tile`] (four loads for four pairs instead of six).
#[inline(always)]
fn pair_tile4(acc: [&mut [f64; 16]; 4], a: &[f64], b: &[f64], c: &[f64], d: &[f64]) {
    let [ac, ad, bc, bd] = acc;
    // local copies: the sums stay in registers (references in an array carry no
    // no-alias promise, so the compiler would reload and store them every chunk)
    let (mut p, mut q, mut r, mut t) = (*ac, *ad, *bc, *bd);
    for (((x, y), u), w) in a
        .chunks_exact(16)
        .zip(b.chunks_exact(16))
        .zip(c.chunks_exact(16))
        .zip(d.chunks_exact(16))
    {
        for l in 0..16 {
            p[l] += x[l] * u[l];
            q[l] += x[l] * w[l];
            r[l] += y[l] * u[l];
            t[l] += y[l] * w[l];
        }
    }
    (*ac, *ad, *bc, *bd) = (p, q, r, t);
}

/// The body of [`gram_matrix`]: per tile, the upper triangle in 2 × 2 blocks of pairs
/// (rows j, j + 1 against columns k, k + 1), each pair's partial sums kept at its index of
/// the packed triangle. A product is commutative in IEEE arithmetic, so a pair visited as
/// (k, j) adds the same values as (j, k).
#[inline(always)]
fn gram_matrix_body(z: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let m = z.len();
    let n = z.iter().map(Vec::len).min().unwrap_or(0);
    let full = n / 16 * 16;
    // index of pair (j, k ≥ j) in the packed upper triangle, row by row
    let tri = |j: usize, k: usize| j * (2 * m - j + 1) / 2 + (k - j);
    let mut acc = vec![[0.0f64; 16]; m * (m + 1) / 2];
    let mut s0 = 0;
    while s0 < full {
        let s1 = (s0 + GRAM_TILE).min(full);
        let col = |j: usize| &z[j][s0..s1];
        let mut j = 0;
        while j + 1 < m {
            // the diagonal block
            {
                let (p, q) = (tri(j, j), tri(j + 1, j + 1));
                let (lo, hi) = acc.split_at_mut(q);
                let (d0, d1) = lo[p..p + 2].split_at_mut(1);
                pair_tile_diag(&mut d0[0], &mut d1[0], &mut hi[0], col(j), col(j + 1));
            }
            let mut k = j + 2;
            while k + 1 < m {
                let (p, q) = (tri(j, k), tri(j + 1, k));
                let (lo, hi) = acc.split_at_mut(q);
                let (r0, r1) = hi[..2].split_at_mut(1);
                let (l0, l1) = lo[p..p + 2].split_at_mut(1);
                pair_tile4(
                    [&mut l0[0], &mut l1[0], &mut r0[0], &mut r1[0]],
                    col(j),
                    col(j + 1),
                    col(k),
                    col(k + 1),
                );
                k += 2;
            }
            if k < m {
                // the last column against both rows: pairs (j, k) and (j + 1, k)
                let (p, q) = (tri(j, k), tri(j + 1, k));
                let (lo, hi) = acc.split_at_mut(q);
                pair_tile2(&mut lo[p], &mut hi[0], col(k), col(j), col(j + 1));
            }
            j += 2;
        }
        if j < m {
            pair_tile(&mut acc[tri(j, j)], col(j), col(j));
        }
        s0 = s1;
    }
    let mut g = vec![vec![0.0; m]; m];
    for j in 0..m {
        for k in j..m {
            let ac = &acc[tri(j, k)];
            let mut s = 0.0;
            for l in 0..4 {
                s += (ac[l] + ac[l + 4]) + (ac[l + 8] + ac[l + 12]);
            }
            for i in full..n {
                s += z[j][i] * z[k][i];
            }
            g[j][k] = s;
            g[k][j] = s;
        }
    }
    g
}

/// A training node's factorisations (lift, moment).
#[derive(Debug, Clone)]
pub(crate) struct NodeFit {
    pub node: usize,
    pub ch: [Arc<NodeChan>; 2],
}

/// Key of a node factorisation: (node, regressor version, channel, support).
type FitKey = (usize, u64, usize, Vec<Term>);

/// Node factorisations shared by every fold and candidate of one force-level run.
#[derive(Debug, Default)]
pub(crate) struct NodeCache(Mutex<HashMap<FitKey, Arc<NodeChan>>>);

/// Factorises one node and channel on the support `sup` (stacked amplitudes, noise
/// weights, residual of the target), uncached.
pub(crate) fn build_chan(cases: &[CaseData], node: &Node, sup: &[Term], c: usize) -> NodeChan {
    let cols: Vec<Vec<f64>> = sup.iter().map(|t| stacked_column(cases, node, t)).collect();
    let refs: Vec<&[f64]> = cols.iter().map(|v| v.as_slice()).collect();
    let qr = ThinQr::new(&refs, QR_TOL);
    let y: Vec<f64> = node
        .cases
        .iter()
        .flat_map(|&i| cases[i].y[c].iter().copied())
        .collect();
    let w: Vec<f64> = node
        .cases
        .iter()
        .flat_map(|&i| {
            let s = cases[i].sigma[c].max(1e-300);
            std::iter::repeat_n(1.0 / s, cases[i].n)
        })
        .collect();
    let w_pool = 1.0
        / node
            .cases
            .iter()
            .map(|&i| cases[i].sigma[c])
            .sum::<f64>()
            .max(1e-300)
        * node.cases.len() as f64;
    let (res_y, a_y) = qr.residual_and_solve(&y);
    NodeChan {
        w_mean: mean(&w),
        qr,
        w_pool,
        res_y,
        a_y,
        grams: Mutex::new(HashMap::new()),
    }
}

/// Builds (or takes from `cache`) the node factorisations of the training nodes; `version`
/// names the regressors of `cases` (0: the measured motion; the delayed copies of the
/// `time_delay` candidate use their delay's bits).
pub(crate) fn node_fits(
    cases: &[CaseData],
    nodes: &[Node],
    train: &[usize],
    supports: &Supports,
    cache: &NodeCache,
    version: u64,
) -> Vec<NodeFit> {
    train
        .iter()
        .map(|&n| {
            let node = &nodes[n];
            let sup = &supports[&node.config];
            let ch = std::array::from_fn(|c| {
                let key: FitKey = (n, version, c, sup[c].clone());
                if let Some(v) = cache.0.lock().ok().and_then(|m| m.get(&key).cloned()) {
                    return v;
                }
                let v = Arc::new(build_chan(cases, node, &sup[c], c));
                if let Ok(mut m) = cache.0.lock() {
                    m.entry(key).or_insert_with(|| v.clone());
                }
                v
            });
            NodeFit { node: n, ch }
        })
        .collect()
}

/// A fitted law of one channel.
#[derive(Debug, Clone)]
pub(crate) struct ChannelLaw {
    /// Coefficients γ of the section's nonlinear terms (shared by every node).
    pub shared: Vec<f64>,
    /// Shared augmentation coefficients.
    pub beta: Vec<f64>,
    /// (node index, K_α, coefficients on the configuration's support).
    pub nodes: Vec<(usize, f64, Vec<f64>)>,
}

/// Extra (augmentation) columns of case `i`, channel `c`.
pub(crate) type Extra<'a> = &'a (dyn Fn(usize, usize) -> Vec<Vec<f64>> + Sync);

/// Columns `pick(i, c, subset)` of case `i`, channel `c`: the set's columns at the indices
/// `subset`, in its order (what `cols(i, c)` picked at them gives).
pub(crate) type Pick<'a> = &'a (dyn Fn(usize, usize, &[usize]) -> Vec<Vec<f64>> + Sync);

/// An augmentation column set: a cache key naming it (unique within a run), the set's
/// columns of case `i`, channel `c`, and the indices used (None: all). `pick`, when given,
/// builds the used columns of a subset directly (a pool of stored columns: without it every
/// held-out prediction copies the whole pool to keep three columns of it).
#[derive(Clone, Copy)]
pub(crate) struct Aug<'a> {
    pub key: &'a str,
    pub cols: Extra<'a>,
    pub subset: Option<&'a [usize]>,
    pub pick: Option<Pick<'a>>,
}

impl Aug<'_> {
    /// No augmentation.
    pub const NONE: Aug<'static> = Aug {
        key: "",
        cols: &|_, _| Vec::new(),
        subset: None,
        pick: None,
    };

    /// The used columns of case `i`, channel `c`.
    pub fn columns(&self, i: usize, c: usize) -> Vec<Vec<f64>> {
        match (self.subset, self.pick) {
            (None, _) => (self.cols)(i, c),
            (Some(s), Some(pick)) => pick(i, c, s),
            (Some(s), None) => {
                let all = (self.cols)(i, c);
                s.iter().map(|&j| all[j].clone()).collect()
            }
        }
    }

    /// Per-node statistics of the whole set on training node `f`, channel `c`.
    pub fn gram(&self, nodes: &[Node], f: &NodeFit, c: usize) -> Arc<NodeGram> {
        // case by case appended to the stacked columns (one case's set held at a time,
        // not every case's before stacking)
        let stacked = || {
            let node_cases = &nodes[f.node].cases;
            let mut out: Vec<Vec<f64>> = Vec::new();
            for (k, &i) in node_cases.iter().enumerate() {
                let v = (self.cols)(i, c);
                if k == 0 {
                    out = v
                        .iter()
                        .map(|col| Vec::with_capacity(col.len() * node_cases.len()))
                        .collect();
                }
                for (o, col) in out.iter_mut().zip(&v) {
                    o.extend_from_slice(col);
                }
            }
            out
        };
        f.ch[c].gram(&format!("{}#{c}", self.key), &stacked)
    }
}

/// Fits channel `c` on the training nodes: per node the coefficients of its support (the
/// linear terms), and shared by every node the coefficients γ of the section's nonlinear
/// terms `shared` and β of the augmentation columns `aug`. γ and β come from the
/// noise-weighted stacked projections (columns a node's support spans get no weight), then
/// every node's coefficients a_n = â(y) − Σ γ_j â(z_j) − Σ β_j â(a_j) (least squares on
/// the support).
pub(crate) fn fit_channel(
    cases: &[CaseData],
    nodes: &[Node],
    fits: &[NodeFit],
    shared: &[Term],
    c: usize,
    aug: Aug<'_>,
) -> ChannelLaw {
    let ms = shared.len();
    let key = shared_key(shared, aug.key);
    let cols = with_shared(cases, shared, aug);
    let all = Aug {
        key: &key,
        cols: &cols,
        subset: None,
        pick: None,
    };
    // without augmentation the shared terms' statistics are a part of the node's cached
    // section-term statistics
    let lib_idx: Option<Vec<usize>> = if aug.key.is_empty() {
        shared
            .iter()
            .map(|t| section_terms().iter().position(|x| x == t))
            .collect()
    } else {
        None
    };
    let grams: Vec<Option<Arc<NodeGram>>> = fits
        .iter()
        .map(|f| {
            if key.is_empty() {
                None
            } else if lib_idx.is_some() {
                Some(section_gram(cases, nodes, f, c))
            } else {
                Some(all.gram(nodes, f, c))
            }
        })
        .collect();
    let idx: Vec<usize> = match (&lib_idx, aug.subset, grams.first()) {
        (Some(l), _, _) => l.clone(),
        (None, Some(s), _) => (0..ms).chain(s.iter().map(|j| j + ms)).collect(),
        (None, None, Some(Some(g))) => (0..g.b.len()).collect(),
        _ => Vec::new(),
    };
    let m = idx.len();
    let mut beta = vec![0.0; m];
    if m > 0 {
        let mut g = vec![vec![0.0; m]; m];
        let mut b = vec![0.0; m];
        for (f, gr) in fits.iter().zip(&grams) {
            let Some(gr) = gr else { continue };
            // weighted by the node's noise level so that quiet and noisy nodes count alike
            let wn = f.ch[c].w_mean;
            let w2 = wn * wn;
            for (j, &jj) in idx.iter().enumerate() {
                if !gr.absorbed[jj] {
                    b[j] += w2 * gr.b[jj];
                }
                for (k, &kk) in idx.iter().enumerate().skip(j) {
                    let v = if gr.absorbed[jj] || gr.absorbed[kk] {
                        0.0
                    } else {
                        w2 * gr.g[jj][kk]
                    };
                    g[j][k] += v;
                    if k != j {
                        g[k][j] += v;
                    }
                }
            }
        }
        beta = ridge_solve(|i, j| g[i][j], &b, BETA_RIDGE).unwrap_or(beta);
    }
    let out = fits
        .iter()
        .zip(&grams)
        .map(|(f, gr)| {
            let mut a = f.ch[c].a_y.clone();
            if let Some(gr) = gr {
                for (j, &jj) in idx.iter().enumerate() {
                    a.iter_mut()
                        .zip(&gr.a[jj])
                        .for_each(|(x, z)| *x -= beta[j] * z);
                }
            }
            (f.node, nodes[f.node].k_alpha, a)
        })
        .collect();
    let aug_beta = beta.split_off(ms.min(beta.len()));
    ChannelLaw {
        shared: beta,
        beta: aug_beta,
        nodes: out,
    }
}

/// The columns of case `i`, channel `c`: the shared nonlinear terms' then `aug`'s (all of
/// them; a subset indexes past the shared ones).
pub(crate) fn with_shared<'a>(
    cases: &'a [CaseData],
    shared: &'a [Term],
    aug: Aug<'a>,
) -> impl Fn(usize, usize) -> Vec<Vec<f64>> + Sync + 'a {
    move |i, c| {
        let mut v: Vec<Vec<f64>> = shared
            .iter()
            .map(|t| cases[i].column(t).as_ref().clone())
            .collect();
        if !aug.key.is_empty() {
            v.extend((aug.cols)(i, c));
        }
        v
    }
}

/// Column of term `t` stacked over the cases of `node` (in node order).
pub(crate) fn stacked_column(cases: &[CaseData], node: &Node, t: &Term) -> Vec<f64> {
    // one allocation of the final length and one copy per case (a `flat_map` over copied
    // per-case vectors cost 7 % of the CI benchmark's samples in its iterator and growth)
    let parts: Vec<Arc<Vec<f64>>> = node.cases.iter().map(|&i| cases[i].column(t)).collect();
    let mut out = Vec::with_capacity(parts.iter().map(|p| p.len()).sum());
    for p in &parts {
        out.extend_from_slice(p);
    }
    out
}

/// The nonlinear terms the section's law may hold: every monomial of degree 2–3 in (α,
/// Bα̇/U, h/B, ḣ/U) (`Full34`; the paper library leaves out α²α̇, αα̇², h²ḣ, hḣ², which a
/// section's pooled amplitudes and speeds separate).
pub(crate) fn section_terms() -> &'static [Term] {
    static TERMS: std::sync::OnceLock<Vec<Term>> = std::sync::OnceLock::new();
    TERMS.get_or_init(|| {
        identify::library::Library::new(identify::library::LibraryKind::Full34, false)
            .terms()
            .iter()
            .filter(|t| t.degree() >= 2)
            .copied()
            .collect()
    })
}

/// Statistics of every [`section_terms`] column on training node `f`, channel `c`, computed
/// once per node factorisation (shared by every fold, jackknife subset and the support
/// completion that train on the node).
pub(crate) fn section_gram(
    cases: &[CaseData],
    nodes: &[Node],
    f: &NodeFit,
    c: usize,
) -> Arc<NodeGram> {
    let node = &nodes[f.node];
    f.ch[c].gram(&format!("section#{c}"), &|| {
        section_terms()
            .iter()
            .map(|t| stacked_column(cases, node, t))
            .collect()
    })
}

/// Cache key of the shared nonlinear terms followed by an augmentation set (empty when
/// both are empty).
pub(crate) fn shared_key(shared: &[Term], aug: &str) -> String {
    if shared.is_empty() && aug.is_empty() {
        return String::new();
    }
    let names: Vec<String> = shared.iter().map(|t| t.name()).collect();
    format!("{}|{aug}", names.join(","))
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Interpolates node coefficient vectors over K_α (see [`interpolate_scalar`]).
pub(crate) fn interpolate(points: &[(f64, &[f64])], k: f64) -> Vec<f64> {
    let p = points.first().map_or(0, |x| x.1.len());
    let mut pts: Vec<(f64, &[f64])> = points.to_vec();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    (0..p)
        .map(|j| {
            let xy: Vec<(f64, f64)> = pts.iter().map(|(x, v)| (*x, v[j])).collect();
            interpolate_scalar(&xy, k)
        })
        .collect()
}

/// Nodes whose K differ by at most this fraction of K are one node for the interpolation
/// (their K and values averaged). A follow-up's settling row repeats a node's K at a
/// higher wind speed (frequencies scaled with U, `follow_up`): two nodes at one K with
/// different values made the Lagrange quadratic's slope a division by ≈ 0 (set 251 of the
/// drawn-shapes benchmark: a held-out node predicted 880 × its noise level off). 1 % is
/// far below the spacing of a configuration's wind speeds at fixed frequencies (K ∝ 1/U;
/// the follow-up merges speeds within 3 %) and above the rounding of planned speeds
/// (0.01 m/s) and frequencies.
pub(crate) const SAME_K: f64 = 0.01;

/// The interpolation rule of the held-out prediction, on nodes sorted by K: nodes at one K
/// ([`SAME_K`]) are first averaged into one; inside the node range a quadratic through the
/// three nearest nodes (linear with two nodes); outside it a line through the two end
/// nodes, evaluated at most one end spacing beyond the end node and held constant further
/// out (never a runaway extrapolation); one node: constant.
pub(crate) fn interpolate_scalar(xy: &[(f64, f64)], x: f64) -> f64 {
    let merged = merge_same_k(xy);
    let xy = merged.as_slice();
    let n = xy.len();
    match n {
        0 => 0.0,
        1 => xy[0].1,
        _ => {
            let (x0, xl) = (xy[0].0, xy[n - 1].0);
            if x < x0 || x > xl {
                let (a, b) = if x < x0 {
                    (xy[0], xy[1])
                } else {
                    (xy[n - 1], xy[n - 2])
                };
                let span = (b.0 - a.0).abs();
                let d = (x - a.0).clamp(-span, span);
                let slope = (b.1 - a.1) / (b.0 - a.0);
                return a.1 + slope * d;
            }
            if n == 2 {
                return lagrange(xy, x);
            }
            // three nearest nodes
            let mut idx: Vec<usize> = (0..n).collect();
            idx.sort_by(|&i, &j| (xy[i].0 - x).abs().total_cmp(&(xy[j].0 - x).abs()));
            let mut three = [idx[0], idx[1], idx[2]];
            three.sort();
            lagrange(&three.map(|i| xy[i]), x)
        }
    }
}

/// `xy` (sorted by K) with each run of nodes within [`SAME_K`] of the run's first K
/// replaced by their mean K and mean value.
fn merge_same_k(xy: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(xy.len());
    let mut i = 0;
    while i < xy.len() {
        let x0 = xy[i].0;
        let mut j = i + 1;
        while j < xy.len() && (xy[j].0 - x0).abs() <= SAME_K * x0.abs() {
            j += 1;
        }
        let m = (j - i) as f64;
        let (sx, sy) = xy[i..j]
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
        out.push((sx / m, sy / m));
        i = j;
    }
    out
}

/// Lag poles of the rational function of the linear terms, in units of K (generic, not
/// the truth's: a Jones approximation of Theodorsen's function has 0.091 and 0.6).
pub(crate) const RFA_POLES: [f64; 3] = [0.08, 0.3, 1.0];

/// Complex basis of the transfer of a linear term pair (displacement d, rate d′) at reduced
/// frequency K: T(K) = ξ_d + iK ξ_d′ ≈ c₀ + c₁ iK + c₂ (iK)² + Σⱼ dⱼ iK/(iK + bⱼ) (Roger's
/// rational-function form; real coefficients, so T is realisable in time).
fn rfa_basis(k: f64) -> Vec<(f64, f64)> {
    let mut v = vec![(1.0, 0.0), (0.0, k), (-k * k, 0.0)];
    for b in RFA_POLES {
        // iK/(iK + b) = (K² + i K b)/(K² + b²)
        let d = k * k + b * b;
        v.push((k * k / d, k * b / d));
    }
    v
}

/// Fits the rational form of [`rfa_basis`] to (K, ξ_d, ξ_d′) nodes (least squares on real
/// and imaginary parts, a small relative ridge) and evaluates ξ_d, ξ_d′ at `k`. Falls back
/// to the per-configuration interpolation (None) with fewer than 4 nodes.
pub(crate) fn rfa_predict(nodes: &[(f64, f64, f64)], k: f64) -> Option<(f64, f64)> {
    if nodes.len() < 4 {
        return None;
    }
    let m = 3 + RFA_POLES.len();
    let mut g = vec![vec![0.0; m]; m];
    let mut b = vec![0.0; m];
    for &(kn, xd, xr) in nodes {
        let phi = rfa_basis(kn);
        let (re, im) = (xd, kn * xr);
        for j in 0..m {
            b[j] += phi[j].0 * re + phi[j].1 * im;
            for l in 0..m {
                g[j][l] += phi[j].0 * phi[l].0 + phi[j].1 * phi[l].1;
            }
        }
    }
    let c = ridge_solve(|i, j| g[i][j], &b, 1e-10)?;
    let phi = rfa_basis(k);
    let re: f64 = phi.iter().zip(&c).map(|(p, c)| p.0 * c).sum();
    let im: f64 = phi.iter().zip(&c).map(|(p, c)| p.1 * c).sum();
    Some((re, im / k))
}

/// Node coefficient vector of case `i`'s node for channel `c`, predicted from the training
/// nodes: the linear terms (α, Bα̇/U) over K_α and (h/B, ḣ/U) over K_h by the rational
/// form [`rfa_predict`] pooled over every configuration (a linear law's transfer depends on
/// its own reduced frequency only); every other term over K_α inside its configuration
/// ([`interpolate`]).
pub(crate) fn node_coefficients(
    cases: &[CaseData],
    nodes: &[Node],
    supports: &Supports,
    law: &ChannelLaw,
    i: usize,
    c: usize,
) -> Vec<f64> {
    let case = &cases[i];
    let cfg = &nodes[case.node].config;
    let pts: Vec<(f64, &[f64])> = law
        .nodes
        .iter()
        .filter(|(n, _, _)| &nodes[*n].config == cfg)
        .map(|(_, k, a)| (*k, a.as_slice()))
        .collect();
    let mut a = interpolate(&pts, nodes[case.node].k_alpha);
    let sup = &supports[cfg][c];
    for (d, r) in [(0usize, 1usize), (2, 3)] {
        let td = Term::linear(d);
        let tr = Term::linear(r);
        let (Some(jd), Some(jr)) = (
            sup.iter().position(|t| *t == td),
            sup.iter().position(|t| *t == tr),
        ) else {
            continue;
        };
        let kf = |n: usize| -> Option<f64> {
            let nd = &nodes[n];
            let ci = nd.cases.first()?;
            if d == 0 {
                Some(nd.k_alpha)
            } else {
                let cs = &cases[*ci];
                cs.f_h
                    .map(|f| cs.nd.chord * 2.0 * std::f64::consts::PI * f / cs.u)
            }
        };
        let Some(k_here) = kf(case.node) else {
            continue;
        };
        let pts: Vec<(f64, f64, f64)> = law
            .nodes
            .iter()
            .filter_map(|(n, _, a)| {
                let s = &supports[&nodes[*n].config][c];
                let pd = s.iter().position(|t| *t == td)?;
                let pr = s.iter().position(|t| *t == tr)?;
                Some((kf(*n)?, a[pd], a[pr]))
            })
            .collect();
        if let Some((xd, xr)) = rfa_predict(&pts, k_here) {
            a[jd] = xd;
            a[jr] = xr;
        }
    }
    a
}

/// Held-out prediction of case `i`, channel `c`: support columns × node coefficients
/// predicted by [`node_coefficients`], plus the section's nonlinear columns × γ and the
/// shared augmentation columns × β.
#[allow(clippy::too_many_arguments)]
pub(crate) fn predict(
    cases: &[CaseData],
    nodes: &[Node],
    supports: &Supports,
    shared: &[Term],
    law: &ChannelLaw,
    i: usize,
    c: usize,
    extra_cols: &[Vec<f64>],
) -> Vec<f64> {
    let case = &cases[i];
    let cfg = &nodes[case.node].config;
    let a = node_coefficients(cases, nodes, supports, law, i, c);
    let mut out = vec![0.0; case.n];
    for (t, &aj) in supports[cfg][c].iter().zip(&a) {
        if aj != 0.0 {
            let col = case.column(t);
            out.iter_mut()
                .zip(col.iter())
                .for_each(|(o, v)| *o += aj * v);
        }
    }
    for (t, &g) in shared.iter().zip(&law.shared) {
        if g != 0.0 {
            let col = case.column(t);
            out.iter_mut()
                .zip(col.iter())
                .for_each(|(o, v)| *o += g * v);
        }
    }
    for (col, &b) in extra_cols.iter().zip(&law.beta) {
        out.iter_mut().zip(col).for_each(|(o, v)| *o += b * v);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiled_gram_is_dot_bit_for_bit() {
        // lengths around the tile and chunk sizes, values spanning magnitudes (a
        // reordered sum would differ in the last bits)
        for (m, n) in [0usize, 5, 16, 511, 512, 1000, 2 * GRAM_TILE + 37]
            .into_iter()
            .flat_map(|n| [(7, n), (8, n), (1, n)])
        {
            let z: Vec<Vec<f64>> = (0..m)
                .map(|j| {
                    (0..n)
                        .map(|i| {
                            ((i * 7919 + j * 104_729) as f64 * 0.618).sin()
                                * 10f64.powi((i % 9) as i32 - 4)
                        })
                        .collect()
                })
                .collect();
            // the dispatched (AVX-512F or AVX2 where the CPU has it) and the portable body;
            // every block shape: diagonal, 2 × 2, the last column against two rows (7), the
            // last row alone (7 and 1), none left over (8)
            let g = gram_matrix(&z);
            let g_portable = gram_matrix_body(&z);
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2 (checked just above)
                let g2 = unsafe { gram_matrix_avx2(&z) };
                let bits = |g: &[Vec<f64>]| -> Vec<u64> {
                    g.iter().flatten().map(|v| v.to_bits()).collect()
                };
                assert_eq!(bits(&g2), bits(&g_portable), "n {n}, m {m}");
            }
            for j in 0..m {
                for k in 0..m {
                    assert_eq!(
                        g[j][k].to_bits(),
                        dot(&z[j], &z[k]).to_bits(),
                        "n {n} ({j}, {k})"
                    );
                    assert_eq!(g_portable[j][k].to_bits(), g[j][k].to_bits());
                }
            }
        }
        assert!(gram_matrix(&[]).is_empty());
    }

    #[test]
    fn picked_columns_are_the_subset_of_all_columns() {
        let table: Vec<Vec<Vec<f64>>> = (0..3)
            .map(|i| (0..5).map(|j| vec![(i * 10 + j) as f64 + 0.5; 4]).collect())
            .collect();
        let all = |i: usize, _c: usize| table[i].clone();
        let pick =
            |i: usize, _c: usize, s: &[usize]| s.iter().map(|&j| table[i][j].clone()).collect();
        let set = [3usize, 0];
        let plain = Aug {
            key: "t",
            cols: &all,
            subset: Some(&set),
            pick: None,
        };
        let picked = Aug {
            pick: Some(&pick),
            ..plain
        };
        for i in 0..3 {
            assert_eq!(picked.columns(i, 1), plain.columns(i, 1));
            assert_eq!(
                picked.columns(i, 0),
                vec![table[i][3].clone(), table[i][0].clone()]
            );
        }
        // without a subset the pick is not used: every column
        let whole = Aug {
            subset: None,
            ..picked
        };
        assert_eq!(whole.columns(2, 0), table[2]);
    }

    #[test]
    fn interpolation_is_exact_for_quadratics_and_bounded_outside() {
        let f = |x: f64| 1.0 + 2.0 * x - 3.0 * x * x;
        let xy: Vec<(f64, f64)> = [0.2, 0.3, 0.45, 0.6].iter().map(|&x| (x, f(x))).collect();
        for x in [0.25, 0.4, 0.5, 0.55] {
            assert!((interpolate_scalar(&xy, x) - f(x)).abs() < 1e-12);
        }
        // outside: a line through the end nodes, held beyond one spacing
        let line = |x: f64| f(0.6) + (f(0.6) - f(0.45)) / 0.15 * (x - 0.6);
        assert!((interpolate_scalar(&xy, 0.65) - line(0.65)).abs() < 1e-12);
        assert!((interpolate_scalar(&xy, 5.0) - line(0.75)).abs() < 1e-12);
        assert_eq!(interpolate_scalar(&xy[..1], 9.0), f(0.2));
    }

    #[test]
    fn nodes_at_one_k_are_one_node() {
        // a settling row's node at the K of a measured node (same K, higher speed) with a
        // slightly different value: without merging the quadratic through the two divides
        // by ≈ 0 and the prediction at a nearby K runs away
        let xy = [(0.2, 1.0), (0.3, 2.0), (0.3, 2.02), (0.45, 1.5)];
        for x in [0.25, 0.32, 0.4, 0.5] {
            let v = interpolate_scalar(&xy, x);
            assert!(v.is_finite() && (0.9..=2.5).contains(&v), "K {x}: {v}");
        }
        // equal to the interpolation through the averaged node
        let avg = [(0.2, 1.0), (0.3, 2.01), (0.45, 1.5)];
        for x in [0.25, 0.4, 0.47] {
            assert!((interpolate_scalar(&xy, x) - interpolate_scalar(&avg, x)).abs() < 1e-12);
        }
        // two nodes at one K only: a constant, not a slope of Δy/0
        let v = interpolate_scalar(&[(0.3, 2.0), (0.3 * (1.0 + 1e-12), 2.02)], 0.4);
        assert!((v - 2.01).abs() < 1e-12, "{v}");
        // nodes 2 % apart stay two nodes
        assert_eq!(merge_same_k(&[(0.3, 1.0), (0.306, 2.0)]).len(), 2);
    }
}
