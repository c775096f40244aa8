//! The registry of regressors: one line per plug-in (`module::Type`, a unit struct
//! implementing [`Regressor`] in `regress/plugins/<module>.rs`). The macro declares the
//! module and lists the type in [`REGISTRY`]; the pipeline, the settings, the ensemble, the
//! command line and Python find regressors only here ([`registry`], [`find`]).
//!
//! A new regressor: one file `regress/plugins/<name>.rs` and one line below (DESIGN.md §10).

use super::plugin::{self, OptionKind, Regressor};
use crate::Result;

macro_rules! registry {
    ($($(#[$doc:meta])* $module:ident :: $ty:ident),* $(,)?) => {
        $( $(#[$doc])* pub mod $module; )*
        /// Every registered regressor, in registry order (the first is the default).
        pub static REGISTRY: &[&dyn Regressor] = &[$(&$module::$ty),*];
    };
}

registry! {
    /// (Group) STLSQ on the column-normalised basis (paper Alg. 1–2), walking δ.
    stlsq::Stlsq,
    /// pysindy 2.1 STLSQ per case on raw columns (comparison mode).
    pysindy::Pysindy,
    /// Plain least squares on the whole identifiable basis (no path).
    least_squares::LeastSquares,
}

/// The registered regressors ([`REGISTRY`]).
pub fn registry() -> &'static [&'static dyn Regressor] {
    REGISTRY
}

/// The registered regressor named `name` (or an alias of it).
///
/// # Errors
/// [`crate::Error::InvalidOption`] naming `regressor` and listing the registered names.
pub fn find(name: &str) -> Result<&'static dyn Regressor> {
    plugin::find(REGISTRY, name)
}

/// A JSON description of the registry (for Python's `aeroform.regressors()` and tools): per
/// regressor its name, aliases, doc, path parameter (name and unit under the default
/// settings) and options (name, type, default, range, doc).
pub fn describe(registry: &[&dyn Regressor]) -> serde_json::Value {
    let shared = default_shared();
    serde_json::Value::Array(
        registry
            .iter()
            .map(|r| {
                let p = r.path_parameter(&shared);
                serde_json::json!({
                    "name": r.name(),
                    "aliases": r.aliases(),
                    "doc": r.doc(),
                    "path_parameter": {"name": p.name, "unit": p.unit},
                    "options": r.options().iter().map(|o| {
                        let (lo, hi) = range(o.kind);
                        serde_json::json!({
                            "name": o.name,
                            "type": o.kind.type_name(),
                            "default": o.default,
                            "min": lo,
                            "max": hi,
                            "doc": o.doc,
                        })
                    }).collect::<Vec<_>>(),
                })
            })
            .collect(),
    )
}

fn range(kind: OptionKind) -> (Option<f64>, Option<f64>) {
    match kind {
        OptionKind::Float { min, max } => (Some(min), max.is_finite().then_some(max)),
        OptionKind::Count { min, max } => (Some(min as f64), Some(max as f64)),
        OptionKind::Flag => (None, None),
    }
}

/// The shared settings at their defaults (for help texts).
pub fn default_shared() -> plugin::FitSettings {
    let s = super::Stlsq::default();
    plugin::FitSettings {
        measure: s.measure,
        group_rule: s.group_rule,
        ridge: s.ridge,
        max_iter: s.max_iter,
    }
}

/// A help text of the registry for `--regressor` (one paragraph per regressor: name,
/// aliases, doc, path parameter, options with type and default).
pub fn help(registry: &[&dyn Regressor]) -> String {
    let shared = default_shared();
    let mut s = String::from(
        "Sparse optimiser (registered regressors; options with --regressor-option NAME=VALUE):",
    );
    for r in registry {
        let p = r.path_parameter(&shared);
        s.push_str(&format!("\n- {}", r.name()));
        if !r.aliases().is_empty() {
            s.push_str(&format!(" (alias {})", r.aliases().join(", ")));
        }
        s.push_str(&format!(
            ": {} Path parameter: {} [{}].",
            r.doc(),
            p.name,
            p.unit
        ));
        for o in r.options() {
            s.push_str(&format!(
                "\n    {} ({}, default {}): {}",
                o.name,
                o.kind.type_name(),
                o.default,
                o.doc
            ));
        }
    }
    s
}

/// One regressor in the JSON schema of the settings: `kind` and its options.
fn entry_schema(r: &dyn Regressor) -> serde_json::Value {
    let mut props = serde_json::Map::new();
    props.insert(
        "kind".into(),
        serde_json::json!({"const": r.name(), "type": "string"}),
    );
    for o in r.options() {
        let mut p = serde_json::json!({"description": o.doc, "default": o.default});
        let m = p.as_object_mut().expect("an object");
        match o.kind {
            OptionKind::Float { .. } => {
                m.insert("type".into(), "number".into());
                m.insert("format".into(), "double".into());
            }
            OptionKind::Count { .. } => {
                m.insert("type".into(), "integer".into());
                m.insert("format".into(), "uint64".into());
                m.insert("minimum".into(), 0.into());
            }
            OptionKind::Flag => {
                m.insert("type".into(), "boolean".into());
            }
        }
        props.insert(o.name.into(), p);
    }
    serde_json::json!({
        "description": r.doc(),
        "type": "object",
        "properties": props,
        "required": ["kind"],
    })
}

/// One alternative per registered regressor.
impl schemars::JsonSchema for plugin::RegressorChoice {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "RegressorChoice".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let one_of: Vec<serde_json::Value> = REGISTRY.iter().map(|r| entry_schema(*r)).collect();
        schemars::json_schema!({
            "description": "Which sparse optimiser runs along its path: a registered regressor's `kind` and its options.",
            "oneOf": one_of,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regress::path::PathOptions;

    #[test]
    fn names_and_aliases_are_unique_and_options_valid() {
        let mut names: Vec<&str> = REGISTRY
            .iter()
            .flat_map(|r| std::iter::once(r.name()).chain(r.aliases().iter().copied()))
            .collect();
        let n = names.len();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), n, "a name or alias is registered twice");
        for r in REGISTRY {
            for o in r.options() {
                o.coerce(r.name(), o.default)
                    .unwrap_or_else(|e| panic!("{}: default of {}: {e}", r.name(), o.name));
            }
        }
        assert_eq!(REGISTRY[0].name(), "stlsq");
        assert!(find("lsq").is_ok());
        let e = find("lasso").unwrap_err().to_string();
        assert!(e.contains("lasso") && e.contains("stlsq"), "{e}");
    }

    /// Four cases of y = 1.5 θ0 − 0.7 θ2 + noise on six random columns (seeded).
    fn factors() -> Vec<crate::regress::CaseFactor> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(28);
        (0..4)
            .map(|c| {
                let (n, p) = (120, 6);
                let theta = crate::numerics::mat::Mat::<f64>::from_fn(n, p, |_, _| {
                    rng.random::<f64>() - 0.5
                });
                let y: Vec<f64> = (0..n)
                    .map(|i| {
                        1.5 * theta[(i, 0)] - 0.7 * theta[(i, 2)]
                            + 0.01 * (c as f64 + 1.0) * (rng.random::<f64>() - 0.5)
                    })
                    .collect();
                let lift: Vec<f64> = y.iter().map(|v| -v).collect();
                crate::regress::CaseFactor::new(
                    "c",
                    theta.as_ref(),
                    &[0, 1, 2, 3, 4, 5],
                    &[&y, &lift],
                )
                .unwrap()
            })
            .collect()
    }

    /// The path handed out point by point (`walk_path`) is the held path (`fit_path`), and
    /// the coefficients recomputed at any point (`coefficients_at`) are that point's, bit
    /// for bit, for the registered regressors that need no per-case data; the fit memo
    /// bounded to one entry gives the same path as the default memo.
    #[test]
    fn walked_and_recomputed_paths_equal_the_held_path() {
        use crate::regress::plugin::GroupInput;
        use crate::regress::{CaseProblem, FitCache, GroupRule, Measure, Stlsq};
        let f = factors();
        let cases: Vec<CaseProblem<'_>> = f
            .iter()
            .map(|factor| CaseProblem { factor, target: 0 })
            .collect();
        let shared = default_shared();
        for name in ["stlsq", "least_squares"] {
            let (reg, options, _) = plugin::RegressorChoice::new(name)
                .resolve(registry(), &shared)
                .unwrap();
            let group = GroupInput {
                cases: &cases,
                keys: &[None; 4],
                data: &[None; 4],
                target: 0,
                basis: 0b11_1111,
                kept: 0,
                shared,
                options: &options,
            };
            let grid = reg
                .path_parameter(&shared)
                .values(&PathOptions::for_measure(Measure::Contribution));
            let held = reg.fit_path(&group, &grid);
            assert_eq!(held.len(), grid.len());
            let mut walked = Vec::new();
            reg.walk_path(&group, &grid, &mut |m, c| walked.push((m, c.to_vec())));
            assert_eq!(walked, held, "{name}");
            for (i, (mask, coefs)) in held.iter().enumerate() {
                assert_eq!(
                    &reg.coefficients_at(&group, &grid, i, *mask),
                    coefs,
                    "{name} {i}"
                );
            }
            if name == "stlsq" {
                // the path reaches the law's support {0, 2}
                assert!(held.iter().any(|(m, _)| *m == 0b101), "{held:?}");
            }
        }
        // a memo holding one fit: every forgotten fit computed again, the same numbers
        let stlsq = Stlsq {
            threshold: 0.05,
            measure: Measure::Contribution,
            group_rule: GroupRule::Norm,
            ridge: 0.0,
            max_iter: 25,
        };
        let mut big = FitCache::default();
        let mut tiny = FitCache::with_budget(0);
        for d in [0.001, 0.05, 0.2, 0.05, 0.001] {
            let s = Stlsq {
                threshold: d,
                ..stlsq
            };
            let a = crate::regress::fit_group(&cases, &s, 0b11_1111, 0, &mut big);
            let b = crate::regress::fit_group(&cases, &s, 0b11_1111, 0, &mut tiny);
            assert_eq!(a, b, "δ = {d}");
            assert_eq!(tiny.len(), 1);
        }
        assert!(
            tiny.n_fits > big.n_fits,
            "{} vs {}",
            tiny.n_fits,
            big.n_fits
        );
    }
}
