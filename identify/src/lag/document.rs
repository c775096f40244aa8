//! The `lag_law.json` document of a fit ([`LagLawDocument`]).

use super::fit::LagFit;
use super::law::{LagLawDocument, LAG_LAW_FORMAT};
use crate::{Error, Result};

impl LagLawDocument {
    /// The document of a fit: the law, the chord B \[m\] of the records and the fit's
    /// report (`report`).
    ///
    /// # Errors
    /// [`Error::Json`] (path `-`) when the report cannot be serialised.
    pub fn from_fit(fit: &LagFit, dataset: &str, chord: f64) -> Result<LagLawDocument> {
        let report = serde_json::to_value(&fit.report).map_err(|e| Error::Json {
            path: "-".into(),
            message: e.to_string(),
        })?;
        Ok(LagLawDocument {
            format: LAG_LAW_FORMAT.to_string(),
            dataset: dataset.to_string(),
            chord,
            law: fit.law.clone(),
            report,
        })
    }

    /// Pretty JSON text of the document, newline-terminated.
    ///
    /// # Errors
    /// [`Error::Json`] (path `-`) when serialisation fails.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self)
            .map(|s| format!("{s}\n"))
            .map_err(|e| Error::Json {
                path: "-".into(),
                message: e.to_string(),
            })
    }
}
