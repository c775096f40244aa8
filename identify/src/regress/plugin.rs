//! Regressors as plug-ins: the [`Regressor`] trait, its options ([`OptionSpec`]) and path
//! parameter ([`PathParameter`]), the settings' choice of one ([`RegressorChoice`]) and the
//! one driver of a group's path ([`run_path`]).
//!
//! A regressor is a unit struct in its own file under `regress/plugins/` and one line of the
//! registry there ([`super::plugins::registry`]); the pipeline, the settings' validation,
//! the ensemble, the command line and Python find it only through that registry, by name.
//!
//! What a regressor owns: its name (the `kind` of `identification.json`'s
//! `settings.regressor`) and aliases, a doc line, its options (name, type, default, doc:
//! the command's `--regressor-option NAME=VALUE`, Python's `regressor_options`, the
//! settings' keys beside `kind`), its path parameter (name, unit, the grid it walks), the
//! per-case data it needs prepared once (optional), the fits along its path for one group
//! and target (handed out one point at a time, [`Regressor::walk_path`], and recomputed at
//! the selected point, [`Regressor::coefficients_at`]). Every regressor's point is picked
//! by Alg. 3 (the sparsest support under the loss limit, [`super::path::PathBuilder`]).
//! What it shares with the others (in [`FitSettings`]): the threshold measure, the
//! group-removal rule, the ridge λ and the iteration cap of the settings, the δ grid's
//! count and range, the loss limit.

use std::any::Any;
use std::fmt;

use serde::{Deserialize, Serialize};

use super::path::{DeltaPath, KeyProjection, PathBuilder, PathOptions};
use super::{vec_to_mask, CaseProblem, GroupRule, Mask, Measure};
use crate::library::Library;
use crate::{Error, Result};

/// Type and admissible range of one regressor option.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionKind {
    /// A finite real number in `[min, max]`.
    Float {
        /// Smallest admissible value.
        min: f64,
        /// Largest admissible value (may be `f64::INFINITY`: any finite value).
        max: f64,
    },
    /// A whole number in `[min, max]`.
    Count {
        /// Smallest admissible value.
        min: u64,
        /// Largest admissible value.
        max: u64,
    },
    /// `true` or `false`.
    Flag,
}

impl OptionKind {
    /// Short type name for help texts and error messages (`number`, `integer`, `boolean`).
    pub fn type_name(&self) -> &'static str {
        match self {
            OptionKind::Float { .. } => "number",
            OptionKind::Count { .. } => "integer",
            OptionKind::Flag => "boolean",
        }
    }
}

/// The value of one regressor option (serialised as a plain JSON/TOML number or boolean).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum OptionValue {
    /// A boolean.
    Flag(bool),
    /// A whole number.
    Count(u64),
    /// A real number.
    Float(f64),
}

impl fmt::Display for OptionValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OptionValue::Flag(b) => write!(f, "{b}"),
            OptionValue::Count(n) => write!(f, "{n}"),
            OptionValue::Float(x) => write!(f, "{x}"),
        }
    }
}

/// One option of a regressor: what the command's help, the settings' validation and
/// Python's keyword arguments read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptionSpec {
    /// Name (the key beside `kind` in the settings; `NAME` of `--regressor-option NAME=VALUE`).
    pub name: &'static str,
    /// Type and range.
    pub kind: OptionKind,
    /// Value when the option is not given.
    pub default: OptionValue,
    /// One-line description, with its unit.
    pub doc: &'static str,
}

impl OptionSpec {
    /// `value` as this option's type, range-checked; `owner` (the regressor's name) and the
    /// option's name make the error's option name (`pysindy.alpha`).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `<owner>.<name>` for a value of another type (a
    /// fractional number for an integer), a non-finite number or one out of range.
    pub fn coerce(&self, owner: &str, value: OptionValue) -> Result<OptionValue> {
        let bad = |message: String| Error::InvalidOption {
            name: format!("{owner}.{}", self.name),
            message,
        };
        match (self.kind, value) {
            (OptionKind::Float { min, max }, OptionValue::Float(_) | OptionValue::Count(_)) => {
                let x = match value {
                    OptionValue::Float(x) => x,
                    OptionValue::Count(n) => n as f64,
                    OptionValue::Flag(_) => unreachable!("matched above"),
                };
                if !(x.is_finite() && x >= min && x <= max) {
                    return Err(bad(format!("{x} must be finite and in [{min}, {max}]")));
                }
                Ok(OptionValue::Float(x))
            }
            (OptionKind::Count { min, max }, OptionValue::Count(n)) => {
                if n < min || n > max {
                    return Err(bad(format!("{n} must be in {min}..={max}")));
                }
                Ok(OptionValue::Count(n))
            }
            (OptionKind::Flag, OptionValue::Flag(b)) => Ok(OptionValue::Flag(b)),
            (kind, v) => Err(bad(format!("{v} is not a {}", kind.type_name()))),
        }
    }

    /// Parses the text of a command-line value (`0.1`, `20`, `true`/`false`) as this
    /// option's type.
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `<owner>.<name>` when the text is not of the type or
    /// out of range (as [`OptionSpec::coerce`]).
    pub fn parse(&self, owner: &str, text: &str) -> Result<OptionValue> {
        let t = text.trim();
        let v = match self.kind {
            OptionKind::Flag => match t {
                "true" => Some(OptionValue::Flag(true)),
                "false" => Some(OptionValue::Flag(false)),
                _ => None,
            },
            OptionKind::Count { .. } => t.parse::<u64>().ok().map(OptionValue::Count),
            OptionKind::Float { .. } => t.parse::<f64>().ok().map(OptionValue::Float),
        };
        let v = v.ok_or_else(|| Error::InvalidOption {
            name: format!("{owner}.{}", self.name),
            message: format!("`{t}` is not a {}", self.kind.type_name()),
        })?;
        self.coerce(owner, v)
    }
}

/// A regressor's options after resolution: every option of its [`OptionSpec`] list, in that
/// order, typed and range-checked (defaults filled in).
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    values: Vec<(&'static str, OptionValue)>,
}

impl Options {
    /// The (name, value) pairs in the order of the regressor's option list.
    pub fn values(&self) -> &[(&'static str, OptionValue)] {
        &self.values
    }

    fn get(&self, name: &str) -> OptionValue {
        match self.values.iter().find(|(n, _)| *n == name) {
            Some((_, v)) => *v,
            None => panic!("regressor option `{name}` is not declared in its option list"),
        }
    }

    /// The real option `name`.
    ///
    /// # Panics
    /// When the regressor declares no real option `name` (a programming error of the
    /// plug-in: resolution has checked every value against the declaration).
    #[track_caller]
    pub fn float(&self, name: &str) -> f64 {
        match self.get(name) {
            OptionValue::Float(x) => x,
            v => panic!("regressor option `{name}` = {v} is not a number"),
        }
    }

    /// The whole-number option `name`.
    ///
    /// # Panics
    /// As [`Options::float`], for a whole-number option.
    #[track_caller]
    pub fn count(&self, name: &str) -> u64 {
        match self.get(name) {
            OptionValue::Count(n) => n,
            v => panic!("regressor option `{name}` = {v} is not an integer"),
        }
    }

    /// The boolean option `name`.
    ///
    /// # Panics
    /// As [`Options::float`], for a boolean option.
    #[track_caller]
    pub fn flag(&self, name: &str) -> bool {
        match self.get(name) {
            OptionValue::Flag(b) => b,
            v => panic!("regressor option `{name}` = {v} is not a boolean"),
        }
    }
}

/// The grid a path parameter walks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathGrid {
    /// `n_delta` log-spaced values over the settings' `delta_range`, whose default is that of
    /// this measure ([`super::path::default_range`]).
    Log {
        /// The measure the values are compared with (sets the default range).
        measure: Measure,
    },
    /// The regressor's own values, ascending (one value: no path; that value is reported
    /// as the selected δ).
    Fixed(&'static [f64]),
}

/// A regressor's path parameter: what it sweeps so that the δ/loss machinery can pick the
/// sparsest adequate support.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathParameter {
    /// Name (`delta`, `threshold`; `none` without a path).
    pub name: &'static str,
    /// Unit or scale of the values.
    pub unit: &'static str,
    /// The grid.
    pub grid: PathGrid,
}

impl PathParameter {
    /// The values walked, ascending: the log grid of `opts` or the regressor's own values.
    pub fn values(&self, opts: &PathOptions) -> Vec<f64> {
        match self.grid {
            PathGrid::Log { .. } => opts.grid(),
            PathGrid::Fixed(v) => v.to_vec(),
        }
    }
}

/// The settings every regressor receives beside its own options (`IdentifySettings`'
/// `measure`, `group_rule`, `ridge`, `max_iter`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSettings {
    /// Threshold measure.
    pub measure: Measure,
    /// Group-removal rule.
    pub group_rule: GroupRule,
    /// Ridge λ on the column-normalised matrix (0 = least squares).
    pub ridge: f64,
    /// Maximum fit–reduce iterations per path point.
    pub max_iter: usize,
}

/// Per-case data a regressor prepares once (e.g. whole paths of a per-case fit); the
/// regressor downcasts it in [`Regressor::fit_path`].
pub type CaseData = Box<dyn Any + Send + Sync>;

/// What [`Regressor::prepare_case`] sees of one case.
#[derive(Clone, Copy)]
pub struct CaseInput<'a> {
    /// Case id.
    pub id: &'a str,
    /// The candidate library.
    pub library: &'a Library,
    /// The regression variables as regressed (α − ᾱ when centred about a mean pitch).
    pub x: &'a [Vec<f64>; 4],
    /// The measured (moment, lift) coefficients, not centred.
    pub measured: [&'a [f64]; 2],
    /// The case's identifiable basis (library columns, ascending).
    pub basis: &'a [usize],
    /// The path's values ([`PathParameter::values`]).
    pub grid: &'a [f64],
    /// The regressor's resolved options.
    pub options: &'a Options,
}

/// One group and target, as a regressor's path sees it.
#[derive(Clone, Copy)]
pub struct GroupInput<'a> {
    /// Per case, the factor and the target (0 moment, 1 lift).
    pub cases: &'a [CaseProblem<'a>],
    /// Per case, the key-frequency projection of the target (`None` without keys).
    pub keys: &'a [Option<&'a KeyProjection>],
    /// Per case, the data of [`Regressor::prepare_case`].
    pub data: &'a [Option<&'a (dyn Any + Send + Sync)>],
    /// The target (0 moment, 1 lift).
    pub target: usize,
    /// The group's identifiable basis.
    pub basis: Mask,
    /// Columns never removed (a subset of `basis`).
    pub kept: Mask,
    /// The shared fit settings.
    pub shared: FitSettings,
    /// The regressor's resolved options.
    pub options: &'a Options,
}

/// Fits along a path: per path value, the support (union over the cases) and, per case, the
/// raw coefficients over the library.
pub type PathFits = Vec<(Mask, Vec<Vec<f64>>)>;

/// A sparse regressor as a plug-in (object safe; see the module documentation).
pub trait Regressor: Sync {
    /// Name: the `kind` in the settings, the value of `--regressor`.
    fn name(&self) -> &'static str;
    /// Other names accepted for it (`lsq` for `least_squares`); resolution stores the name.
    fn aliases(&self) -> &'static [&'static str] {
        &[]
    }
    /// One-line description for `--help`, the schema and Python.
    fn doc(&self) -> &'static str;
    /// Its options, in the order they are written.
    fn options(&self) -> &'static [OptionSpec] {
        &[]
    }
    /// Its path parameter under the shared settings `shared`.
    fn path_parameter(&self, shared: &FitSettings) -> PathParameter;
    /// Checks among options beyond each option's own type and range (default: none).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming the option.
    fn check(&self, _options: &Options, _shared: &FitSettings) -> Result<()> {
        Ok(())
    }
    /// Whether the final coefficients are plain least squares on the selected support
    /// (with ridge λ = 0): the block bootstrap ([`crate::ensemble`]) re-fits exactly that.
    fn refits_by_least_squares(&self) -> bool;
    /// Per-case data prepared once with the case's factorisation (default: none).
    ///
    /// # Errors
    /// [`Error::Numerical`] naming the case when a computation fails.
    fn prepare_case(&self, _case: &CaseInput<'_>) -> Result<Option<CaseData>> {
        Ok(None)
    }
    /// The fits of one group and target at every value of `grid`.
    fn fit_path(&self, group: &GroupInput<'_>, grid: &[f64]) -> PathFits;
    /// The fits of [`Regressor::fit_path`] handed to `sink` one grid point at a time, in
    /// grid order, so that the driver never holds the whole path (per point and case a
    /// coefficient vector over the library: 50 × cases × p × 8 B). The default walks
    /// `fit_path` (which holds them all); a plug-in with large groups overrides it.
    fn walk_path(
        &self,
        group: &GroupInput<'_>,
        grid: &[f64],
        sink: &mut dyn FnMut(Mask, &[Vec<f64>]),
    ) {
        for (mask, coefs) in self.fit_path(group, grid) {
            sink(mask, &coefs);
        }
    }
    /// Per case, the raw coefficients over the library of the fit at grid index `index`,
    /// whose support is `mask`: exactly what [`Regressor::fit_path`] gives at that point
    /// (the path keeps only supports and losses; the selected point's coefficients are
    /// computed again). The default walks `fit_path` again and keeps that point.
    fn coefficients_at(
        &self,
        group: &GroupInput<'_>,
        grid: &[f64],
        index: usize,
        _mask: Mask,
    ) -> Vec<Vec<f64>> {
        self.fit_path(group, grid).swap_remove(index).1
    }
}

impl fmt::Debug for dyn Regressor + '_ {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Regressor({})", self.name())
    }
}

/// Finds a regressor by name or alias in `registry`.
///
/// # Errors
/// [`Error::InvalidOption`] naming `regressor` and listing the registered names when none
/// matches.
pub fn find<'r>(registry: &[&'r dyn Regressor], name: &str) -> Result<&'r dyn Regressor> {
    registry
        .iter()
        .find(|r| r.name() == name || r.aliases().contains(&name))
        .copied()
        .ok_or_else(|| Error::InvalidOption {
            name: "regressor".to_string(),
            message: format!(
                "`{name}` is not a registered regressor (expected one of {})",
                registry
                    .iter()
                    .map(|r| {
                        let a = r.aliases();
                        if a.is_empty() {
                            r.name().to_string()
                        } else {
                            format!("{} (alias {})", r.name(), a.join(", "))
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
}

/// The settings' choice of regressor: its name (`kind`) and the options given beside it.
///
/// Serialised as one object, `kind` first, then the options in the order held
/// (`{"kind": "pysindy", "alpha": 0.05, "max_iter": 20, "unbias": true}`); after
/// [`RegressorChoice::resolve`] that is every option of the regressor in its declared order,
/// so a written `identification.json` always records every option's value. Reading accepts
/// any subset of the options (the others take their defaults) and refuses a key given twice.
#[derive(Debug, Clone, PartialEq)]
pub struct RegressorChoice {
    /// Registered name or alias.
    pub kind: String,
    /// Options given, (name, value), in the order given.
    pub options: Vec<(String, OptionValue)>,
}

impl Default for RegressorChoice {
    /// STLSQ (the default regressor).
    fn default() -> Self {
        RegressorChoice::new("stlsq")
    }
}

impl RegressorChoice {
    /// The regressor `kind` with every option at its default.
    pub fn new(kind: &str) -> Self {
        RegressorChoice {
            kind: kind.to_string(),
            options: Vec::new(),
        }
    }

    /// This choice with option `name` set to `value` (replacing an earlier value).
    pub fn with(mut self, name: &str, value: OptionValue) -> Self {
        self.options.retain(|(n, _)| n != name);
        self.options.push((name.to_string(), value));
        self
    }

    /// The regressor of `registry` this names, its options resolved (every declared option,
    /// in order, typed, defaults filled in, checked), and the canonical choice (the
    /// registered name and those options).
    ///
    /// # Errors
    /// [`Error::InvalidOption`] naming `regressor` for an unknown name, `<name>.<option>`
    /// for an option the regressor does not have (listing those it has) or a bad value, and
    /// whatever [`Regressor::check`] refuses.
    pub fn resolve<'r>(
        &self,
        registry: &[&'r dyn Regressor],
        shared: &FitSettings,
    ) -> Result<(&'r dyn Regressor, Options, RegressorChoice)> {
        let reg = find(registry, &self.kind)?;
        let specs = reg.options();
        for (name, _) in &self.options {
            if !specs.iter().any(|s| s.name == name) {
                return Err(Error::InvalidOption {
                    name: format!("{}.{name}", reg.name()),
                    message: if specs.is_empty() {
                        format!("`{}` has no options", reg.name())
                    } else {
                        format!(
                            "unknown option of `{}` (it has {})",
                            reg.name(),
                            specs.iter().map(|s| s.name).collect::<Vec<_>>().join(", ")
                        )
                    },
                });
            }
        }
        let mut values = Vec::with_capacity(specs.len());
        for s in specs {
            let given = self
                .options
                .iter()
                .find(|(n, _)| n == s.name)
                .map_or(s.default, |(_, v)| *v);
            values.push((s.name, s.coerce(reg.name(), given)?));
        }
        let options = Options { values };
        reg.check(&options, shared)?;
        let canonical = RegressorChoice {
            kind: reg.name().to_string(),
            options: options
                .values
                .iter()
                .map(|(n, v)| (n.to_string(), *v))
                .collect(),
        };
        Ok((reg, options, canonical))
    }
}

impl Serialize for RegressorChoice {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(1 + self.options.len()))?;
        m.serialize_entry("kind", &self.kind)?;
        for (k, v) in &self.options {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for RegressorChoice {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RegressorChoice;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an object with `kind` (a regressor's name) and its options")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut a: A,
            ) -> std::result::Result<RegressorChoice, A::Error> {
                let mut kind: Option<String> = None;
                let mut options: Vec<(String, OptionValue)> = Vec::new();
                while let Some(k) = a.next_key::<String>()? {
                    if k == "kind" {
                        if kind.is_some() {
                            return Err(serde::de::Error::custom("duplicate key `kind`"));
                        }
                        kind = Some(a.next_value()?);
                    } else {
                        if options.iter().any(|(n, _)| *n == k) {
                            return Err(serde::de::Error::custom(format!(
                                "duplicate regressor option `{k}`"
                            )));
                        }
                        let v: OptionValue = a.next_value().map_err(|_| {
                            serde::de::Error::custom(format!(
                                "regressor option `{k}`: expected a number or a boolean"
                            ))
                        })?;
                        options.push((k, v));
                    }
                }
                let kind = kind.ok_or_else(|| serde::de::Error::missing_field("kind"))?;
                Ok(RegressorChoice { kind, options })
            }
        }
        d.deserialize_map(V)
    }
}

/// The path of one group and target under `reg`: its fits at every value of its path
/// parameter, scored one point at a time ([`Regressor::walk_path`] into a
/// [`PathBuilder`]), then Alg. 3's selection (the sparsest distinct support under the
/// loss limit). Returns the path and, per case of the group, the raw coefficients of the
/// selected support (the fits of the first path value giving it,
/// [`Regressor::coefficients_at`]).
pub fn run_path(
    reg: &dyn Regressor,
    group: &GroupInput<'_>,
    opts: &PathOptions,
) -> (DeltaPath, Vec<Vec<f64>>) {
    let grid = reg.path_parameter(&group.shared).values(opts);
    let mut builder = PathBuilder::new(&grid, group.cases, group.keys);
    reg.walk_path(group, &grid, &mut |mask, coefs| builder.push(mask, coefs));
    let path = builder.finish(opts);
    let sel = path.selected_support();
    let coefficients = reg.coefficients_at(group, &grid, sel.first, vec_to_mask(&sel.support));
    (path, coefficients)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALPHA: OptionSpec = OptionSpec {
        name: "alpha",
        kind: OptionKind::Float {
            min: 0.0,
            max: f64::INFINITY,
        },
        default: OptionValue::Float(0.05),
        doc: "ridge",
    };

    #[test]
    fn options_coerce_by_type_and_name_the_option() {
        assert_eq!(
            ALPHA.coerce("p", OptionValue::Count(1)).unwrap(),
            OptionValue::Float(1.0)
        );
        let e = ALPHA.coerce("p", OptionValue::Float(-1.0)).unwrap_err();
        assert!(e.to_string().contains("p.alpha"), "{e}");
        let e = ALPHA.coerce("p", OptionValue::Flag(true)).unwrap_err();
        assert!(e.to_string().contains("not a number"), "{e}");
        assert!(ALPHA.parse("p", "nan").is_err());
        assert_eq!(ALPHA.parse("p", "0.1").unwrap(), OptionValue::Float(0.1));
        let n = OptionSpec {
            name: "n",
            kind: OptionKind::Count { min: 1, max: 5 },
            default: OptionValue::Count(2),
            doc: "",
        };
        assert!(n.parse("p", "2.5").is_err());
        assert!(n.coerce("p", OptionValue::Count(6)).is_err());
        assert!(n.coerce("p", OptionValue::Float(2.0)).is_err());
    }

    #[test]
    fn choice_reads_any_order_and_refuses_duplicates() {
        let c: RegressorChoice =
            serde_json::from_str(r#"{"alpha": 0.1, "kind": "pysindy", "unbias": false}"#).unwrap();
        assert_eq!(c.kind, "pysindy");
        assert_eq!(
            c.options,
            vec![
                ("alpha".to_string(), OptionValue::Float(0.1)),
                ("unbias".to_string(), OptionValue::Flag(false))
            ]
        );
        assert_eq!(
            serde_json::to_string(&c).unwrap(),
            r#"{"kind":"pysindy","alpha":0.1,"unbias":false}"#
        );
        let e = serde_json::from_str::<RegressorChoice>(r#"{"kind": "a", "x": 1, "x": 2}"#)
            .unwrap_err();
        assert!(
            e.to_string().contains("duplicate regressor option `x`"),
            "{e}"
        );
        assert!(serde_json::from_str::<RegressorChoice>(r#"{"x": 1}"#).is_err());
        let t: RegressorChoice = toml::from_str("kind = \"pysindy\"\nmax_iter = 3").unwrap();
        assert_eq!(t.options[0].1, OptionValue::Count(3));
    }
}
