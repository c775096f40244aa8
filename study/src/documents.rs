//! The JSON documents a study writes besides the libraries' own: the study's
//! `flutter.json` ([`FlutterRun`], an array), `lco.json` ([`LcoStage`]),
//! `coefficients.columns.json` ([`CoefficientColumn`], an array) and the summary
//! `aeroform run --json` prints ([`RunSummary`]). Their JSON Schemas are generated with
//! the others by `aeroform::documents::schemas`.

use std::collections::BTreeMap;

use aeroelastic::ensemble::{FlutterEnsemble, LcoEnsemble};
use aeroelastic::flutter::FlutterAnalysis;
use aeroelastic::lco::LcoResult;
use aeroelastic::trajectory::Trajectory;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::spec::FlutterReference;

/// One flutter analysis of a study (one `[[flutter.run]]`); the study's `flutter.json` is
/// an array of them, in the order of the runs. Scanlan's convention (h positive down, α
/// positive nose-up); SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FlutterRun {
    /// The run's label in tables and figures.
    pub label: String,
    /// Aerodynamic model of the run (`theodorsen`, `truth`, `identified`, …).
    pub model: crate::spec::StudyModel,
    /// Semi-chord b = B/2 \[m\].
    pub semi_chord: f64,
    /// Still-air pitch frequency ω_α \[rad/s\]; reduced speed = U/(b·ω_α).
    pub omega_alpha: f64,
    /// The analysis: method, one branch per structural mode (V–g, V–f), flutter point,
    /// divergence speed, failed points.
    pub analysis: FlutterAnalysis,
    /// Published values the run is compared with; `null` when the study names none.
    pub reference: Option<FlutterReference>,
    /// Intervals over the bootstrap members of the identified law (`[identify] ensemble`,
    /// runs of the `identified` model only); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<FlutterEnsemble>,
}

/// The LCO stage of a study as saved in its `lco.json`. Scanlan's convention; SI units
/// (amplitudes in rad and m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LcoStage {
    /// Aerodynamic model of the sweeps (`theodorsen`, `identified`, …).
    pub model: String,
    /// Semi-chord b = B/2 \[m\].
    pub semi_chord: f64,
    /// Still-air pitch frequency ω_α \[rad/s\].
    pub omega_alpha: f64,
    /// Linear flutter speed of the same model \[m/s\], if a flutter run of it exists;
    /// `null` otherwise.
    pub flutter_speed: Option<f64>,
    /// Upward sweep, increasing U.
    pub up: Vec<LcoResult>,
    /// Downward sweep, increasing U (empty without `up_down`).
    pub down: Vec<LcoResult>,
    /// Trajectories drawn in the phase-portrait figure.
    pub phase: Vec<Trajectory>,
    /// Linear flutter speed of the truth model \[m/s\] (`compare_truth`); absent without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth_flutter_speed: Option<f64>,
    /// Upward sweep of the truth model of `[data.virtual]` (`compare_truth`); absent
    /// when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub truth_up: Vec<LcoResult>,
    /// Downward sweep of the truth model, increasing U (`compare_truth`); absent when
    /// empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub truth_down: Vec<LcoResult>,
    /// LCO amplitude intervals over the bootstrap members of the identified law at every
    /// speed of the sweep (`[identify] ensemble` with the `identified` model), each member
    /// run from the upward sweep's perturbation; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<LcoEnsemble>,
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
