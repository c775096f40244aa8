//! The result of [`super::identify`]: the `identification.json` document (cases, groups,
//! δ paths, library) and its summary table, and the progress reports.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::settings::*;
use crate::eq19::{Eq19Values, LiftEq19, MomentEq19};
use crate::{Error, Result};

/// Progress of [`identify`](super::identify), reported on the calling thread.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// Per-case preparation (library, factorisation, identifiability, key frequencies).
    Cases {
        /// Cases done.
        done: usize,
        /// Total cases.
        total: usize,
    },
    /// δ paths of the groups (one unit per group and force).
    Groups {
        /// Paths done.
        done: usize,
        /// Total paths.
        total: usize,
    },
}

/// Coefficients of the library terms in library order, serialised as a JSON object that
/// keeps that order; `None` (null) for a term outside the identifiable basis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TermMap(pub Vec<(String, Option<f64>)>);

impl TermMap {
    /// Value of a term by name (`None` when absent or not identifiable).
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).and_then(|(_, v)| *v)
    }
}

impl Serialize for TermMap {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl schemars::JsonSchema for TermMap {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "TermMap".into()
    }

    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let mut s = <std::collections::BTreeMap<String, Option<f64>>>::json_schema(g);
        s.insert(
            "description".into(),
            "Library term name → raw nondimensional coefficient, in library order; null for a term outside the identifiable basis.".into(),
        );
        s
    }
}

impl<'de> Deserialize<'de> for TermMap {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = TermMap;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object of term name → number or null")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut a: A,
            ) -> std::result::Result<TermMap, A::Error> {
                let mut v = Vec::new();
                while let Some((k, x)) = a.next_entry::<String, Option<f64>>()? {
                    if v.iter().any(|(n, _): &(String, _)| *n == k) {
                        return Err(serde::de::Error::custom(format!("duplicate term `{k}`")));
                    }
                    v.push((k, x));
                }
                Ok(TermMap(v))
            }
        }
        d.deserialize_map(V)
    }
}

/// Identification of one force of one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ForceResult<E> {
    /// Raw nondimensional coefficient of every library term (null = not identifiable,
    /// 0 = removed by the sparse regression).
    pub terms: TermMap,
    /// Eq. 19 derivatives (null where K or the term is missing).
    pub eq19: E,
    /// R² of the fit.
    pub r2: Option<f64>,
    /// MFWA (Eq. 18) at the key frequencies (null without key frequencies).
    pub mfwa: Option<f64>,
    /// Phase-aware MFWA.
    pub mfwa_phase: Option<f64>,
    /// Eq. 14 key-frequency loss.
    pub key_frequency_loss: Option<f64>,
    /// The key frequencies \[Hz\], largest measured amplitude first.
    pub key_frequencies: Vec<f64>,
    /// Cases regressed about a mean pitch ᾱ (`centre_mean_angle`): the constant of the fit,
    /// i.e. the modelled force coefficient at α = ᾱ, ḣ = α̇ = h = 0 (nondimensional, C_L or
    /// C_M convention); `None` for other cases.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub constant: Option<f64>,
}

/// Identification of one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseResult {
    /// Case id.
    pub id: String,
    /// Group name.
    pub group: String,
    /// Wind speed U \[m/s\].
    pub wind_speed: f64,
    /// K_α = Bω_α/U.
    pub k_alpha: Option<f64>,
    /// K_h = Bω_h/U.
    pub k_h: Option<f64>,
    /// Numerical rank of the case's library.
    pub rank: usize,
    /// Dependencies of the case's library (term names).
    pub dependencies: Vec<String>,
    /// Mean pitch ᾱ (rad) about which the case was regressed (`centre_mean_angle`): the
    /// variable `alpha` of its terms is α − ᾱ; `None` when regressed on α itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_pitch: Option<f64>,
    /// Moment.
    pub moment: ForceResult<MomentEq19>,
    /// Lift.
    pub lift: ForceResult<LiftEq19>,
}

/// One support of a δ path, summarised.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PathEntry {
    /// Number of terms.
    pub n_terms: usize,
    /// Group loss (mean over cases).
    pub loss: f64,
    /// Smallest and largest δ of the grid giving this support.
    pub delta: [f64; 2],
    /// The terms.
    pub support: Vec<String>,
}

/// Group result of one force.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct GroupForce {
    /// Selected support (term names, library order).
    pub support: Vec<String>,
    /// Smallest δ of the grid giving the selected support.
    pub selected_delta: f64,
    /// δ interval of the grid giving the selected support.
    pub delta_range: [f64; 2],
    /// Group loss of the selected support.
    pub loss: f64,
    /// Loss of the densest support on the path.
    pub loss_dense: f64,
    /// Noise loss k·4σ̂²/(n Σ|A|²) (mean over the group's cases).
    pub loss_noise: f64,
    /// Loss limit.
    pub loss_limit: f64,
    /// The distinct supports of the path, along increasing δ.
    pub path: Vec<PathEntry>,
}

/// One group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct GroupResult {
    /// Group name.
    pub name: String,
    /// Case ids, sorted.
    pub cases: Vec<String>,
    /// Terms of the group basis (identifiable in every case of the group).
    pub basis: Vec<String>,
    /// Moment.
    pub moment: GroupForce,
    /// Lift.
    pub lift: GroupForce,
}

/// Library summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LibraryInfo {
    /// Term names in column order.
    pub terms: Vec<String>,
    /// Smallest numerical rank over the cases.
    pub rank: usize,
    /// Dependencies of the case attaining that rank (first such case).
    pub dependencies: Vec<String>,
    /// The case whose dependencies are listed.
    pub rank_case: Option<String>,
    /// Priority order of the canonical basis (term names).
    pub priority: Vec<String>,
}

/// The content of `identification.json` (DATA_FORMAT.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Identification {
    /// Always [`FORMAT`].
    pub format: String,
    /// Data-set name.
    pub dataset: String,
    /// Settings used.
    pub settings: IdentifySettings,
    /// Library summary.
    pub library: LibraryInfo,
    /// Cases in input order.
    pub cases: Vec<CaseResult>,
    /// Groups sorted by name.
    pub groups: Vec<GroupResult>,
    /// Block-bootstrap ensemble (`identify --ensemble N`): intervals of every support
    /// coefficient and Eq. 19 value, and the members' coefficients. Absent (not `null`)
    /// when no ensemble was run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<crate::ensemble::types::Ensemble>,
}

impl Identification {
    /// Reads an `identification.json`.
    ///
    /// # Errors
    /// [`Error::Io`] when the file cannot be read, [`Error::Json`] with serde's line and
    /// column when it is malformed or its `format` is not [`FORMAT`].
    pub fn read(path: &Path) -> Result<Self> {
        // aeroform's own result document: the result cap, not the input files' one
        let text = crate::io::read_text_capped(path, crate::limits::MAX_RESULT_FILE_BYTES as u64)?;
        let id: Identification = serde_json::from_str(&text).map_err(|e| Error::Json {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        if id.format != FORMAT {
            return Err(Error::Json {
                path: path.to_path_buf(),
                message: format!("format `{}` is not `{FORMAT}`", id.format),
            });
        }
        Ok(id)
    }

    /// Writes it (pretty JSON) atomically.
    ///
    /// # Errors
    /// [`Error::Io`] naming the path; [`Error::Json`] if serialisation fails.
    pub fn write(&self, path: &Path) -> Result<()> {
        // serialised straight into the temporary file (the text of a 50,000-case
        // identification is 200 MB): the same bytes as `to_string_pretty`
        let mut json_error = None;
        let written = crate::io::write_atomic_with(path, &mut |w| {
            serde_json::to_writer_pretty(w, self).map_err(|e| {
                if e.is_io() {
                    std::io::Error::from(e)
                } else {
                    let message = e.to_string();
                    json_error = Some(message.clone());
                    std::io::Error::other(message)
                }
            })
        });
        match (written, json_error) {
            (Err(_), Some(message)) => Err(Error::Json {
                path: path.to_path_buf(),
                message,
            }),
            (r, _) => r,
        }
    }

    /// Compact text table: per group and force the selected terms, then per case the Eq. 19
    /// derivatives, R², MFWA and key-frequency loss; with an ensemble, per case the intervals
    /// of the linear derivatives.
    pub fn summary_table(&self) -> String {
        use std::fmt::Write;
        let f = |v: Option<f64>| match v {
            Some(x) => format!("{x:>9.4}"),
            None => format!("{:>9}", "-"),
        };
        let mut s = String::new();
        let _ = writeln!(
            s,
            "dataset: {}  (library rank {} of {})",
            self.dataset,
            self.library.rank,
            self.library.terms.len()
        );
        // one table per channel: its name, group result, Eq. 19 column names and case row
        type Row = fn(&CaseResult) -> (Eq19Values, Option<f64>, Option<f64>, Option<f64>);
        let moment_row: Row = |c| {
            let m = &c.moment;
            (m.eq19.into(), m.r2, m.mfwa, m.key_frequency_loss)
        };
        let lift_row: Row = |c| {
            let l = &c.lift;
            (l.eq19.into(), l.r2, l.mfwa, l.key_frequency_loss)
        };
        for g in &self.groups {
            for (force, gf, names, row) in [
                ("moment", &g.moment, crate::eq19::MOMENT_NAMES, moment_row),
                ("lift", &g.lift, crate::eq19::LIFT_NAMES, lift_row),
            ] {
                let _ = writeln!(
                    s,
                    "\n[{}] {force}: {} terms (δ = {:.3e}, loss {:.2e}, limit {:.2e}): {}",
                    g.name,
                    gf.support.len(),
                    gf.selected_delta,
                    gf.loss,
                    gf.loss_limit,
                    gf.support.join(", ")
                );
                let _ = writeln!(
                    s,
                    "  {:<20} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
                    "case",
                    names[0],
                    names[1],
                    names[2],
                    names[3],
                    "N1",
                    "N2",
                    "N3",
                    "R2",
                    "MFWA",
                    "loss"
                );
                for c in self.cases.iter().filter(|c| c.group == g.name) {
                    let (d, r2, mfwa, loss) = row(c);
                    let d = d.0;
                    let _ = writeln!(
                        s,
                        "  {:<20} {} {} {} {} {} {} {} {} {} {}",
                        c.id,
                        f(d[0]),
                        f(d[1]),
                        f(d[2]),
                        f(d[3]),
                        f(d[4]),
                        f(d[5]),
                        f(d[6]),
                        f(r2),
                        f(mfwa),
                        f(loss)
                    );
                }
            }
        }
        if let Some(e) = &self.ensemble {
            let _ = writeln!(
                s,
                "\nensemble: {} block-bootstrap members (seed {}), {:.0} % intervals [lower, upper]",
                e.settings.members,
                e.settings.seed,
                100.0 * e.settings.level
            );
            for c in &e.cases {
                let mut line = format!("  {:<20}", c.id);
                for (force, names) in [
                    (&c.lift, crate::eq19::LIFT_NAMES),
                    (&c.moment, crate::eq19::MOMENT_NAMES),
                ] {
                    for &n in &names[..4] {
                        if let Some(iv) = force.eq19.get(n) {
                            let _ = write!(line, " {n} [{:.4}, {:.4}]", iv.lower, iv.upper);
                        }
                    }
                }
                let _ = writeln!(s, "{line}");
            }
        }
        s
    }
}
