//! Large jobs split into independent items: the withheld-effect benchmark (one item per
//! data set) and flutter/LCO maps over the structural parameters μ, σ, x_α, r² (one item
//! per grid point).
//!
//! Every item depends only on the specification and its global index (a benchmark set's
//! seed is derived from the master seed and the index, [`crate::bench::draw_specs`]), so
//! any partition of the items — shards of a Slurm job array (`aeroform sweep --shard i/n`
//! then `aeroform merge`), Dask tasks (`aeroform.sweep` in Python), rayon inside one
//! process ([`SweepSpec::run_local`]) — gathers into the same document.

use std::path::{Path, PathBuf};

use aeroelastic::documents::{flutter_point_json, LoadedPair};
use aeroelastic::files::{LoadedModel, StructureFile};
use aeroelastic::flutter::FlutterMethod;
use aeroelastic::structure::NondimStructure;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use crate::bench::{summarize, BlindOutcome};
use crate::bench_run::{blind_specs, run_outcome, BlindOptions};
use crate::{Error, Result};

/// Format tag of a merged sweep document of a flutter/LCO map.
pub const MAP_FORMAT: &str = "aeroform-sweep/1";
/// Format tag of a part document (the items of one shard).
pub const PART_FORMAT: &str = "aeroform-sweep-part/1";

use identify::limits::{MAX_BLIND_SETS as MAX_SETS, MAX_GRID_POINTS, MAX_SPEEDS};

/// What to sweep (JSON, tagged by `kind`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SweepSpec {
    /// The withheld-effect benchmark of `aeroform diagnose --blind n --seed seed`.
    Blind(BlindSweep),
    /// Flutter (and optionally LCO) over a grid of structural parameters.
    FlutterMap(Box<MapSpec>),
}

/// The withheld-effect benchmark as a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlindSweep {
    /// Number of data sets.
    pub n: usize,
    /// Master seed.
    pub seed: u64,
    /// The drawn-shapes benchmark (`diagnose --blind n --shapes`: each set's campaign
    /// shape and physics drawn too); absent means false, and a false value is not written,
    /// so specifications and parts of the default benchmark keep their form.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub shapes: bool,
}

/// Flutter/LCO map over structural parameters. Each grid axis that is given replaces the
/// base structure's value; the others keep it. The nondimensional parameters use the
/// half-chord b = B/2 of the model: μ = m/(πρb²), σ = ω_h/ω_α, x_α = S_α/(m b),
/// r² = I_α/(m b²); a point is rebuilt as m = μπρb², S_α = x_α m b, I_α = r² m b²,
/// f_h = σ f_α (f_α, damping ratios and nonlinear stiffness terms are kept).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapSpec {
    /// Base structure file (TOML, as `aeroform flutter --structure`).
    pub structure: PathBuf,
    /// Aerodynamic model (model TOML or `identification.json`).
    pub model: PathBuf,
    /// Chord B \[m\] for an identification.json model (else the structure file's).
    #[serde(default)]
    pub chord: Option<f64>,
    /// Flutter scan speeds [m/s] (≥ 2; from the lowest to the highest).
    pub speeds: Vec<f64>,
    /// `"pk"` (default) or `"p"`.
    #[serde(default = "default_method", with = "method_name")]
    pub method: FlutterMethod,
    /// The grid axes.
    #[serde(default)]
    pub grid: Grid,
    /// Speeds [m/s] of an upward/downward LCO sweep at every point (empty: none).
    #[serde(default)]
    pub lco_speeds: Vec<f64>,
    /// Initial pitch \[deg\] of the upward LCO sweep.
    #[serde(default = "default_alpha0")]
    pub alpha0: f64,
    /// Initial pitch \[deg\] of the downward LCO sweep.
    #[serde(default = "default_alpha0_down")]
    pub alpha0_down: f64,
}

fn default_method() -> FlutterMethod {
    FlutterMethod::Pk
}

/// The sweep file's names of the flutter methods, `pk` and `p` (serde form of
/// [`MapSpec::method`]).
mod method_name {
    use aeroelastic::flutter::FlutterMethod;
    use serde::{de::Error as _, Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(m: &FlutterMethod, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(m.name())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<FlutterMethod, D::Error> {
        String::deserialize(d)?
            .parse()
            .map_err(|m| D::Error::custom(format!("`method` = {m}")))
    }
}
fn default_alpha0() -> f64 {
    2.0
}
fn default_alpha0_down() -> f64 {
    20.0
}

/// Axes of a structural grid; points are the Cartesian product in the order μ, σ, x_α, r²
/// (r² varies fastest). An absent axis keeps the base value.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// Mass ratios μ.
    #[serde(default)]
    pub mu: Option<Vec<f64>>,
    /// Frequency ratios σ = ω_h/ω_α.
    #[serde(default)]
    pub sigma: Option<Vec<f64>>,
    /// Static unbalances x_α (semi-chords).
    #[serde(default)]
    pub x_alpha: Option<Vec<f64>>,
    /// Squared radii of gyration r² (semi-chords²).
    #[serde(default)]
    pub r2: Option<Vec<f64>>,
}

fn sweep_err(source: &str, message: impl Into<String>) -> Error {
    Error::Sweep {
        source_name: source.to_string(),
        message: message.into(),
    }
}

impl SweepSpec {
    /// Parses and validates a JSON specification; `source` names it in errors.
    ///
    /// # Errors
    /// [`Error::Sweep`] naming `source` with serde's line, column and message (unknown
    /// `kind` or field, wrong type), or the field that fails [`SweepSpec::validate`].
    pub fn from_json(text: &str, source: &str) -> Result<Self> {
        let spec: SweepSpec =
            serde_json::from_str(text).map_err(|e| sweep_err(source, e.to_string()))?;
        spec.validate(source)?;
        Ok(spec)
    }

    /// Reads a JSON specification file.
    ///
    /// # Errors
    /// [`Error::Io`] when the file cannot be read; otherwise as [`SweepSpec::from_json`].
    pub fn read(path: &Path) -> Result<Self> {
        let text =
            identify::io::read_text(path).map_err(|e| match identify::io::is_input_error(&e) {
                // refused by the reader (missing, not a regular file, too large, not UTF-8): an input error
                true => sweep_err(&path.display().to_string(), e.to_string()),
                false => Error::Io {
                    context: format!("reading {}", path.display()),
                    message: e.to_string(),
                },
            })?;
        Self::from_json(&text, &path.display().to_string())
    }

    /// Checks every value: n ≥ 1; ≥ 2 finite positive flutter speeds; method `pk` or `p`;
    /// grid values finite, μ, σ, r² > 0; LCO speeds finite and > 0.
    ///
    /// # Errors
    /// [`Error::Sweep`] naming `source`, the field and the value.
    pub fn validate(&self, source: &str) -> Result<()> {
        match self {
            SweepSpec::Blind(b) => {
                if b.n == 0 {
                    return Err(sweep_err(
                        source,
                        "`n` = 0: a benchmark needs at least one set",
                    ));
                }
                if b.n > MAX_SETS {
                    return Err(sweep_err(
                        source,
                        format!("`n` = {}: at most {MAX_SETS} sets", b.n),
                    ));
                }
            }
            SweepSpec::FlutterMap(m) => {
                if m.speeds.len() < 2 {
                    return Err(sweep_err(
                        source,
                        format!(
                            "`speeds` has {} value(s): a flutter scan needs at least 2",
                            m.speeds.len()
                        ),
                    ));
                }
                let positive = |name: &str, v: &[f64]| -> Result<()> {
                    match v.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
                        Some(i) => Err(sweep_err(
                            source,
                            format!("`{name}[{i}]` = {}: must be finite and > 0", v[i]),
                        )),
                        None => Ok(()),
                    }
                };
                for (name, v) in [("speeds", &m.speeds), ("lco_speeds", &m.lco_speeds)] {
                    if v.len() > MAX_SPEEDS {
                        return Err(sweep_err(
                            source,
                            format!("`{name}` has {} values: at most {MAX_SPEEDS}", v.len()),
                        ));
                    }
                }
                let points = [&m.grid.mu, &m.grid.sigma, &m.grid.x_alpha, &m.grid.r2]
                    .iter()
                    .map(|v| v.as_ref().map_or(1, |v| v.len().max(1)))
                    .try_fold(1usize, |a, k| a.checked_mul(k))
                    .unwrap_or(usize::MAX);
                if points > MAX_GRID_POINTS {
                    return Err(sweep_err(
                        source,
                        format!(
                            "`grid` spans {points} points (μ × σ × x_α × r²): at most \
                             {MAX_GRID_POINTS}"
                        ),
                    ));
                }
                positive("speeds", &m.speeds)?;
                positive("lco_speeds", &m.lco_speeds)?;
                if let Some(v) = &m.grid.mu {
                    positive("grid.mu", v)?;
                }
                if let Some(v) = &m.grid.sigma {
                    positive("grid.sigma", v)?;
                }
                if let Some(v) = &m.grid.r2 {
                    positive("grid.r2", v)?;
                }
                if let Some(v) = &m.grid.x_alpha {
                    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                        return Err(sweep_err(
                            source,
                            format!("`grid.x_alpha[{i}]` = {}: must be finite", v[i]),
                        ));
                    }
                }
                for (name, v) in [
                    ("grid.mu", &m.grid.mu),
                    ("grid.sigma", &m.grid.sigma),
                    ("grid.x_alpha", &m.grid.x_alpha),
                    ("grid.r2", &m.grid.r2),
                ] {
                    if v.as_ref().is_some_and(|v| v.is_empty()) {
                        return Err(sweep_err(
                            source,
                            format!("`{name}` is empty: omit it to keep the base value"),
                        ));
                    }
                }
                for (name, x) in [("alpha0", m.alpha0), ("alpha0_down", m.alpha0_down)] {
                    identify::limits::abs_at_most(x, identify::limits::MAX_PITCH_DEG, "deg")
                        .map_err(|e| sweep_err(source, format!("`{name}`: {e}")))?;
                }
                for (name, v) in [("speeds", &m.speeds), ("lco_speeds", &m.lco_speeds)] {
                    for &u in v.iter() {
                        identify::limits::positive_at_most(u, identify::limits::MAX_SPEED, "m/s")
                            .map_err(|e| sweep_err(source, format!("`{name}`: {e}")))?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Number of items.
    pub fn n_items(&self) -> usize {
        match self {
            SweepSpec::Blind(b) => b.n,
            SweepSpec::FlutterMap(m) => {
                let len = |v: &Option<Vec<f64>>| v.as_ref().map_or(1, Vec::len);
                len(&m.grid.mu) * len(&m.grid.sigma) * len(&m.grid.x_alpha) * len(&m.grid.r2)
            }
        }
    }

    /// The specification as JSON (recorded in every part and merged document).
    pub fn to_value(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }

    /// Runs item `index` (a failure of the item's computation is recorded in the item,
    /// never returned: `error` in a map point, verdict `error` in a benchmark outcome).
    ///
    /// # Errors
    /// [`Error::Sweep`] for an index outside `0..n_items()`; for a map, the errors of
    /// loading the structure and model files.
    pub fn run_item(&self, index: usize) -> Result<Value> {
        self.check_index(index)?;
        match self {
            SweepSpec::Blind(b) => {
                let specs = blind_specs(b.n, b.seed, b.shapes);
                let mut opts = BlindOptions::new(b.n, b.seed);
                opts.shapes = b.shapes;
                let o = run_outcome(&specs[index], &opts);
                Ok(serde_json::to_value(o).unwrap_or(Value::Null))
            }
            SweepSpec::FlutterMap(m) => {
                let base = MapBase::load(m)?;
                Ok(base.run_point(m, index))
            }
        }
    }

    /// Runs the items `indices` (for a map, the files are loaded once).
    ///
    /// # Errors
    /// As [`SweepSpec::run_item`].
    pub fn run_items(&self, indices: &[usize]) -> Result<Vec<Value>> {
        for &i in indices {
            self.check_index(i)?;
        }
        match self {
            SweepSpec::Blind(_) => indices.iter().map(|&i| self.run_item(i)).collect(),
            SweepSpec::FlutterMap(m) => {
                let base = MapBase::load(m)?;
                Ok(indices.iter().map(|&i| base.run_point(m, i)).collect())
            }
        }
    }

    fn check_index(&self, index: usize) -> Result<()> {
        let n = self.n_items();
        if index >= n {
            return Err(sweep_err(
                "sweep",
                format!("item index {index} outside 0..{n}"),
            ));
        }
        Ok(())
    }

    /// Gathers the items (any order, each index exactly once) into the document of the
    /// whole sweep: a benchmark's `blind.json` (`aeroform-blind/1`) or a map's
    /// `aeroform-sweep/1` document (`spec`, `base` parameters, `points` by index).
    ///
    /// # Errors
    /// [`Error::Sweep`] for an item without a valid `index`/`spec.index`, an index
    /// outside the sweep, repeated or missing, or a benchmark item that is not an outcome.
    pub fn assemble(&self, items: Vec<Value>) -> Result<Value> {
        let n = self.n_items();
        let mut slots: Vec<Option<Value>> = vec![None; n];
        for item in items {
            let index = item
                .get("index")
                .or_else(|| item.get("spec").and_then(|s| s.get("index")))
                .and_then(Value::as_u64)
                .ok_or_else(|| sweep_err("merge", "an item has no `index`"))?
                as usize;
            let slot = slots
                .get_mut(index)
                .ok_or_else(|| sweep_err("merge", format!("item index {index} outside 0..{n}")))?;
            if slot.is_some() {
                return Err(sweep_err("merge", format!("item {index} appears twice")));
            }
            *slot = Some(item);
        }
        let missing: Vec<usize> = (0..n).filter(|&i| slots[i].is_none()).collect();
        if !missing.is_empty() {
            let shown: Vec<String> = missing.iter().take(10).map(|i| i.to_string()).collect();
            return Err(sweep_err(
                "merge",
                format!(
                    "{} of {n} items missing (first: {})",
                    missing.len(),
                    shown.join(", ")
                ),
            ));
        }
        let items: Vec<Value> = slots.into_iter().flatten().collect();
        // Each item's inputs must be those its index implies (issue 27 row 12): an
        // edited or mixed-up part is refused; outputs are not recomputed.
        match self {
            SweepSpec::Blind(b) => {
                let expected = blind_specs(b.n, b.seed, b.shapes);
                let outcomes = items
                    .into_iter()
                    .enumerate()
                    .map(|(i, v)| {
                        let o = serde_json::from_value::<BlindOutcome>(v)
                            .map_err(|e| sweep_err("merge", format!("benchmark item: {e}")))?;
                        let mut want = expected[i].clone();
                        if !b.shapes {
                            // the default benchmark's sets draw no shape: its check
                            // compares the seed, truth and strength
                            want.shape = o.spec.shape.clone();
                        }
                        if o.spec != want {
                            return Err(sweep_err(
                                "merge",
                                format!(
                                    "item {i}: its set (seed {}, truth `{}`, strength {}) is \
                                     not the set {i} of n = {}, seed {} (seed {}, truth `{}`, \
                                     strength {}): an altered or foreign part",
                                    o.spec.seed,
                                    o.spec.truth,
                                    o.spec.strength,
                                    b.n,
                                    b.seed,
                                    want.seed,
                                    want.truth,
                                    want.strength
                                ),
                            ));
                        }
                        Ok(o)
                    })
                    .collect::<Result<Vec<_>>>()?;
                Ok(serde_json::to_value(summarize(b.seed, outcomes)).unwrap_or(Value::Null))
            }
            SweepSpec::FlutterMap(m) => {
                let base = MapBase::load(m)?;
                for (i, item) in items.iter().enumerate() {
                    let p = base.point(&m.grid, i);
                    for (name, want) in [
                        ("mu", p.mu),
                        ("sigma", p.sigma),
                        ("x_alpha", p.x_alpha),
                        ("r2", p.r_alpha2),
                    ] {
                        let got = item.get(name).and_then(Value::as_f64);
                        let same = got.is_some_and(|g| {
                            g == want || (g - want).abs() <= 1e-12 * want.abs().max(g.abs())
                        });
                        if !same {
                            return Err(sweep_err(
                                "merge",
                                format!(
                                    "item {i}: `{name}` = {} is not grid point {i}'s {want}: \
                                     an altered or foreign part",
                                    got.map_or("missing".to_string(), |g| g.to_string())
                                ),
                            ));
                        }
                    }
                }
                Ok(json!({
                    "format": MAP_FORMAT,
                    "spec": self.to_value(),
                    "base": base.nondim,
                    "points": items,
                }))
            }
        }
    }

    /// The whole sweep in this process (items in parallel with rayon); `observer` is
    /// called after each item.
    ///
    /// # Errors
    /// As [`SweepSpec::run_items`] and [`SweepSpec::assemble`].
    pub fn run_local(&self, observer: &(dyn Fn(usize) + Sync)) -> Result<Value> {
        let n = self.n_items();
        let items = match self {
            SweepSpec::Blind(_) => (0..n)
                .into_par_iter()
                .map(|i| {
                    let v = self.run_item(i);
                    observer(i);
                    v
                })
                .collect::<Result<Vec<_>>>()?,
            SweepSpec::FlutterMap(m) => {
                let base = MapBase::load(m)?;
                (0..n)
                    .into_par_iter()
                    .map(|i| {
                        let v = base.run_point(m, i);
                        observer(i);
                        v
                    })
                    .collect()
            }
        };
        self.assemble(items)
    }

    /// The part document of shard `shard` of `of` (items whose index ≡ shard mod `of`).
    ///
    /// # Errors
    /// [`Error::Sweep`] when `shard ≥ of`; as [`SweepSpec::run_items`].
    pub fn run_shard(&self, shard: usize, of: usize) -> Result<Value> {
        let indices = shard_indices(self.n_items(), shard, of)?;
        let items = match self {
            SweepSpec::Blind(_) => indices
                .par_iter()
                .map(|&i| self.run_item(i))
                .collect::<Result<Vec<_>>>()?,
            SweepSpec::FlutterMap(_) => self.run_items(&indices)?,
        };
        let digest = items_digest(&items);
        Ok(json!({
            "format": PART_FORMAT,
            "spec": self.to_value(),
            "inputs": self.input_digests(),
            "shard": [shard, of],
            "items": items,
            "items_digest": digest,
        }))
    }

    /// The content digest (FNV-1a, 64 bit, hex) of every file the specification names, by
    /// its field (`structure`, `model`); `"unreadable"` for a file that cannot be read.
    /// Parts record them and [`merge`] refuses parts computed from different contents of
    /// the same paths (issue 39, row 3: a model edited between two shards merged silently).
    pub fn input_digests(&self) -> Value {
        match self {
            SweepSpec::Blind(_) => json!({}),
            SweepSpec::FlutterMap(m) => {
                let digest = |p: &Path| match identify::io::read_text(p) {
                    Ok(text) => bytes_digest(text.as_bytes()),
                    Err(_) => "unreadable".to_string(),
                };
                json!({
                    "structure": digest(&m.structure),
                    "model": digest(&m.model),
                })
            }
        }
    }
}

/// FNV-1a (64 bit, hex) of `bytes`.
fn bytes_digest(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// FNV-1a (64 bit, hex) of the compact JSON of a part's items: `merge` recomputes it and
/// refuses a part whose items were edited after it was written (an integrity check
/// against accidents, not a signature).
pub fn items_digest(items: &[Value]) -> String {
    bytes_digest(serde_json::to_string(items).unwrap_or_default().as_bytes())
}

/// Indices of shard `shard` of `of` among `n` items: `shard, shard + of, …`.
///
/// # Errors
/// [`Error::Sweep`] when `of` = 0 or `shard ≥ of`.
pub fn shard_indices(n: usize, shard: usize, of: usize) -> Result<Vec<usize>> {
    if of == 0 || shard >= of {
        return Err(sweep_err(
            "--shard",
            format!("shard {shard}/{of}: expected i/n with 0 ≤ i < n"),
        ));
    }
    Ok((shard..n).step_by(of).collect())
}

/// Parses `i/n` (0-based shard i of n).
///
/// # Errors
/// [`Error::Sweep`] naming the text.
pub fn parse_shard(text: &str) -> Result<(usize, usize)> {
    let bad = || {
        sweep_err(
            "--shard",
            format!("`{text}`: expected i/n with 0 ≤ i < n, e.g. 0/4"),
        )
    };
    let (i, n) = text.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// Merges part documents ([`SweepSpec::run_shard`]) into the document of the whole sweep.
/// `names` name the parts in errors.
///
/// # Errors
/// [`Error::Sweep`] for a document that is not a part, parts of different
/// specifications, and the errors of [`SweepSpec::assemble`] (missing or repeated items).
pub fn merge(parts: &[(String, Value)]) -> Result<Value> {
    let Some((first_name, first)) = parts.first() else {
        return Err(sweep_err("merge", "no part given"));
    };
    let spec_value = first.get("spec").cloned().unwrap_or(Value::Null);
    let spec: SweepSpec = serde_json::from_value(spec_value.clone())
        .map_err(|e| sweep_err(first_name, format!("`spec`: {e}")))?;
    let mut items = Vec::new();
    for (name, part) in parts {
        if part.get("format").and_then(Value::as_str) != Some(PART_FORMAT) {
            return Err(sweep_err(
                name,
                format!("not a sweep part (`format` is not \"{PART_FORMAT}\")"),
            ));
        }
        if part.get("spec") != Some(&spec_value) {
            return Err(sweep_err(
                name,
                format!("its `spec` differs from that of {first_name}"),
            ));
        }
        // the same paths with other contents (an input edited between two shards)
        let (a, b) = (first.get("inputs"), part.get("inputs"));
        if a != b {
            let field = match (a, b) {
                (Some(Value::Object(x)), Some(Value::Object(y))) => x
                    .iter()
                    .find(|(k, v)| y.get(*k) != Some(*v))
                    .map(|(k, _)| format!("`{k}`"))
                    .unwrap_or_else(|| "an input".into()),
                _ => "the `inputs` record (a part of an older aeroform)".into(),
            };
            return Err(sweep_err(
                name,
                format!(
                    "computed from other contents of {field} than {first_name} (the file \
                     changed between the shards); re-run every shard on the same inputs"
                ),
            ));
        }
        match part.get("items") {
            Some(Value::Array(v)) => {
                let want = items_digest(v);
                match part.get("items_digest").and_then(Value::as_str) {
                    Some(d) if d == want => {}
                    Some(d) => {
                        return Err(sweep_err(
                            name,
                            format!(
                                "its items do not match their digest ({d}, recomputed \
                                 {want}): the part was edited after it was written"
                            ),
                        ))
                    }
                    None => {
                        return Err(sweep_err(
                            name,
                            "no `items_digest`: not written by this aeroform (re-run the shard)",
                        ))
                    }
                }
                items.extend(v.iter().cloned())
            }
            _ => return Err(sweep_err(name, "no `items` array")),
        }
    }
    spec.assemble(items)
}

/// The files of a map loaded once.
struct MapBase {
    file: StructureFile,
    model: LoadedModel,
    b: f64,
    nondim: NondimStructure,
}

impl MapBase {
    fn load(m: &MapSpec) -> Result<Self> {
        let ctx = |e: aeroelastic::Error| Error::Aeroelastic {
            context: format!(
                "sweep files (`structure` {}, `model` {})",
                m.structure.display(),
                m.model.display()
            ),
            source: Box::new(e),
        };
        let file = StructureFile::read(&m.structure).map_err(ctx)?;
        let model = LoadedModel::load(&m.model, m.chord.or(file.chord)).map_err(ctx)?;
        let b = model.model.chord() / 2.0;
        let nondim = NondimStructure::from_modal(&file.linear, file.air_density, b);
        Ok(MapBase {
            file,
            model,
            b,
            nondim,
        })
    }

    /// The structure of grid point `index`: the file's, with the grid's μ, σ, x_α, r²
    /// (the pitch frequency, the damping ratios and the nonlinear terms kept).
    fn point(&self, g: &Grid, index: usize) -> NondimStructure {
        let axes = [&g.mu, &g.sigma, &g.x_alpha, &g.r2];
        let base = [
            self.nondim.mu,
            self.nondim.sigma,
            self.nondim.x_alpha,
            self.nondim.r_alpha2,
        ];
        let mut rest = index;
        let mut v = base;
        for k in (0..4).rev() {
            if let Some(axis) = axes[k] {
                v[k] = axis[rest % axis.len()];
                rest /= axis.len();
            }
        }
        NondimStructure {
            mu: v[0],
            sigma: v[1],
            x_alpha: v[2],
            r_alpha2: v[3],
            ..self.nondim
        }
    }

    fn compute_point(
        &self,
        m: &MapSpec,
        p: &NondimStructure,
    ) -> std::result::Result<Value, String> {
        let mut file = self.file.clone();
        file.linear = p.modal();
        let pair = LoadedPair::from_parts(file, self.model.clone()).map_err(|e| e.to_string())?;
        let meth = m.method;
        let fa = pair
            .flutter(meth, &m.speeds)
            .map_err(|e| format!("flutter: {e}"))?;
        let mut r = json!({
            "critical": flutter_point_json(&fa, 2.0 * self.b),
            "divergence_speed": fa.divergence_speed,
        });
        if !m.lco_speeds.is_empty() {
            let h = pair
                .lco_sweep(
                    &m.lco_speeds,
                    m.alpha0.to_radians(),
                    m.alpha0_down.to_radians(),
                    &|_| {},
                )
                .map_err(|e| format!("LCO sweep: {e}"))?;
            r["hysteresis_speeds"] = json!(h.band());
            r["lco"] = json!(h);
        }
        Ok(r)
    }

    fn run_point(&self, m: &MapSpec, index: usize) -> Value {
        let p = self.point(&m.grid, index);
        let mut out = json!({
            "index": index,
            "mu": p.mu,
            "sigma": p.sigma,
            "x_alpha": p.x_alpha,
            "r2": p.r_alpha2,
        });
        let res = self.compute_point(m, &p);
        match res {
            Ok(Value::Object(r)) => {
                for (k, v) in r {
                    out[k] = v;
                }
                out["error"] = Value::Null;
            }
            Ok(_) => {}
            Err(e) => out["error"] = json!(e),
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_spec(dir: &Path) -> String {
        let s = dir.join("s.toml");
        let m = dir.join("m.toml");
        std::fs::write(
            &s,
            "mass = 3.0\ninertia = 0.012\nstatic_unbalance = 0.03\nfreq_heave = 2.0\nfreq_pitch = 4.0\nchord = 0.25\n",
        )
        .unwrap();
        std::fs::write(&m, "kind = \"theodorsen\"\nchord = 0.25\n").unwrap();
        json!({
            "kind": "flutter_map",
            "structure": s, "model": m,
            "speeds": (1..=40).map(|i| i as f64).collect::<Vec<f64>>(),
            "grid": {"mu": [20.0, 40.0], "sigma": [0.3, 0.5, 0.7]},
        })
        .to_string()
    }

    #[test]
    fn shards_merge_into_the_unsplit_map() {
        let dir = tempfile::tempdir().unwrap();
        let spec = SweepSpec::from_json(&map_spec(dir.path()), "test").unwrap();
        assert_eq!(spec.n_items(), 6);
        let whole = spec.run_local(&|_| {}).unwrap();
        let parts: Vec<(String, Value)> = (0..4)
            .map(|i| (format!("part{i}"), spec.run_shard(i, 4).unwrap()))
            .rev()
            .collect();
        let merged = merge(&parts).unwrap();
        assert_eq!(
            serde_json::to_string(&whole).unwrap(),
            serde_json::to_string(&merged).unwrap()
        );
        // r² fastest, then x_α, σ, μ: point 4 is μ = 40, σ = 0.5.
        assert_eq!(whole["points"][4]["mu"], 40.0);
        assert_eq!(whole["points"][4]["sigma"], 0.5);
        // A heavier section flutters at a higher speed (same σ).
        let u = |i: usize| whole["points"][i]["critical"]["speed"].as_f64();
        if let (Some(a), Some(b)) = (u(1), u(4)) {
            assert!(b > a, "{a} {b}");
        }
        // A missing part is an error naming the missing items.
        let e = merge(&parts[1..]).unwrap_err().to_string();
        assert!(e.contains("missing"), "{e}");
        // An altered item is refused, naming the item and the field (issue 27 row 12).
        let mut bad = parts.clone();
        let k = bad
            .iter()
            .position(|p| p.1["items"][0]["index"] == 0)
            .unwrap();
        bad[k].1["items"][0]["mu"] = json!(999.0);
        let e = merge(&bad).unwrap_err().to_string();
        assert!(e.contains("edited after it was written"), "{e}");
        // with the digest recomputed, the item's inputs still do not fit its index
        let items = bad[k].1["items"].as_array().unwrap().clone();
        bad[k].1["items_digest"] = json!(items_digest(&items));
        let e = merge(&bad).unwrap_err().to_string();
        assert!(e.contains("item 0") && e.contains("`mu` = 999"), "{e}");
    }

    #[test]
    fn bad_specs_name_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let mut v: Value = serde_json::from_str(&map_spec(dir.path())).unwrap();
        v["grid"]["mu"] = json!([20.0, -1.0]);
        let e = SweepSpec::from_json(&v.to_string(), "spec.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("spec.json") && e.contains("grid.mu[1]"), "{e}");
        v["grid"]["mu"] = json!([20.0]);
        v["grid"]["bogus"] = json!([1.0]);
        let e = SweepSpec::from_json(&v.to_string(), "spec.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bogus"), "{e}");
        assert!(parse_shard("4/4").is_err());
        assert_eq!(parse_shard("3/4").unwrap(), (3, 4));
    }

    /// The outcome of a set that failed (what `merge` checks is the spec; its gap ratio and
    /// shrinks are NaN, written `null`: a failed set's part merged only since round 45).
    fn unrun(spec: &crate::bench::BlindSpec) -> Value {
        let o = crate::bench_run::failed(spec, &sweep_err("test", "not run"), 0.0);
        serde_json::to_value(o).unwrap()
    }

    #[test]
    fn the_drawn_shapes_benchmark_is_a_sweep_whose_merge_checks_each_shape() {
        // without `shapes` the specification keeps its form (parts written before stay valid)
        let plain = SweepSpec::from_json(r#"{"kind":"blind","n":3,"seed":5}"#, "t").unwrap();
        assert_eq!(
            plain.to_value(),
            json!({"kind": "blind", "n": 3, "seed": 5})
        );
        let spec =
            SweepSpec::from_json(r#"{"kind":"blind","n":3,"seed":5,"shapes":true}"#, "t").unwrap();
        assert_eq!(spec.to_value()["shapes"], json!(true));
        let sets = blind_specs(3, 5, true);
        assert!(sets.iter().all(|s| s.shape.is_some()));
        // the shapes benchmark deals its own truths over the sets; seeds are shared
        let default_sets = blind_specs(3, 5, false);
        assert!(sets
            .iter()
            .zip(&default_sets)
            .all(|(a, b)| a.seed == b.seed));
        let items: Vec<Value> = sets.iter().map(unrun).collect();
        let merged = spec.assemble(items.clone()).unwrap();
        assert_eq!(merged["outcomes"].as_array().unwrap().len(), 3);
        // an item with another set's shape is refused, naming the item
        let mut swapped = items.clone();
        swapped[0]["spec"]["shape"] = items[1]["spec"]["shape"].clone();
        let e = spec.assemble(swapped).unwrap_err().to_string();
        assert!(
            e.contains("item 0") && e.contains("altered or foreign"),
            "{e}"
        );
        // and a part of the default benchmark does not merge as the shapes benchmark
        let e = spec
            .assemble(default_sets.iter().map(unrun).collect())
            .unwrap_err()
            .to_string();
        assert!(e.contains("altered or foreign"), "{e}");
    }

    /// Issue 27 rows 3 and 4: counts are capped before anything is allocated.
    #[test]
    fn counts_are_capped() {
        let dir = tempfile::tempdir().unwrap();
        let e = SweepSpec::from_json(r#"{"kind":"blind","n":1000000000000,"seed":1}"#, "b.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.json") && e.contains("`n`"), "{e}");
        assert!(SweepSpec::from_json(r#"{"kind":"blind","n":10000,"seed":1}"#, "b").is_ok());
        let mut v: Value = serde_json::from_str(&map_spec(dir.path())).unwrap();
        v["grid"]["mu"] = json!((1..=1000).map(f64::from).collect::<Vec<f64>>());
        v["grid"]["sigma"] = json!((1..=101).map(|i| 0.01 * f64::from(i)).collect::<Vec<f64>>());
        let e = SweepSpec::from_json(&v.to_string(), "m.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("101000 points"), "{e}");
        v["grid"]["sigma"] = json!([0.5]);
        v["speeds"] = json!((1..=10_001).map(f64::from).collect::<Vec<f64>>());
        let e = SweepSpec::from_json(&v.to_string(), "m.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("`speeds` has 10001 values"), "{e}");
    }
}
