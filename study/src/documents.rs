//! The JSON documents a study writes besides the libraries' own (its `flutter.json` is an
//! array of [`FlutterDoc`], its `lco.json` an [`aeroelastic::documents::LcoDoc`]):
//! `coefficients.columns.json` ([`CoefficientColumn`], an array) and the summary
//! `aeroform run --json` prints ([`RunSummary`]). Their JSON Schemas are generated with
//! the others by `aeroform::documents::schemas`.

use std::collections::BTreeMap;

use aeroelastic::documents::FlutterDoc;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::spec::StudyModel;

/// The study model of a run of a study's `flutter.json` (its `model`, written from
/// [`StudyModel::name`]); `None` for a document not written by a study.
pub fn run_model(doc: &FlutterDoc) -> Option<StudyModel> {
    StudyModel::deserialize(
        serde::de::value::StrDeserializer::<serde::de::value::Error>::new(&doc.model),
    )
    .ok()
}

/// One term column of a study's `coefficients.csv`, as listed in
/// `coefficients.columns.json` (an array of them, in column order).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct CoefficientColumn {
    /// The CSV column name (letters, digits and `_`: `alpha2_h`, `const`).
    pub column: String,
    /// The library term it holds, as named in `identification.json` (`alpha^2*h`, `1`).
    pub term: String,
    /// The term as shown in figures and the report (`α²·h/B`).
    pub display: String,
}

/// The document `aeroform run --json` prints on stdout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RunSummary {
    /// The study's name.
    pub study: String,
    /// The output folder.
    pub out: String,
    /// The study's seed, as a string (a u64 does not fit every JSON reader).
    pub seed: String,
    /// Wall time of each stage \[s\], by stage name.
    pub timings_s: BTreeMap<String, f64>,
    /// Wall time of the whole run \[s\].
    pub total_s: f64,
    /// The content of the study's `figures.json`: the figures drawn.
    pub figures: serde_json::Value,
}

/// Display label of a library term name (parsed by [`identify::library::Term::parse`]):
/// the nondimensional variables α, Bα'/U, h/B, h'/U in that order, powers as superscripts,
/// factors joined by `·`; `1` for the constant. A name that does not parse is kept verbatim.
///
/// ```
/// use study::documents::term_label;
/// assert_eq!(term_label("alpha*alpha_dot"), "α·Bα'/U");
/// assert_eq!(term_label("alpha_dot^3"), "(Bα'/U)³");
/// assert_eq!(term_label("alpha^2*h"), "α²·h/B");
/// assert_eq!(term_label("1"), "1");
/// assert_eq!(term_label("beta"), "beta");
/// ```
pub fn term_label(name: &str) -> String {
    const BASES: [(&str, bool); 4] = [("α", false), ("Bα'/U", true), ("h/B", true), ("h'/U", true)];
    const SUPERSCRIPTS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let Ok(term) = identify::library::Term::parse(name) else {
        return name.to_string();
    };
    if term.degree() == 0 {
        return "1".into();
    }
    term.powers
        .iter()
        .zip(BASES)
        .filter(|(p, _)| **p > 0)
        .map(|(&p, (base, compound))| {
            if p == 1 {
                return base.to_string();
            }
            let sup: String = p
                .to_string()
                .chars()
                .filter_map(|d| d.to_digit(10).map(|d| SUPERSCRIPTS[d as usize]))
                .collect();
            if compound {
                format!("({base}){sup}")
            } else {
                format!("{base}{sup}")
            }
        })
        .collect::<Vec<_>>()
        .join("·")
}
