//! The one error type of the `aeroelastic` crate.

/// Result alias of the `aeroelastic` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong while building a section model, analysing flutter or
/// integrating a response.
///
/// Every variant names the place (field, model, case) and carries the offending values.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter is out of its admissible range (non-finite, negative mass…).
    #[error("field `{field}` = {}: {message}", identify::limits::show(*.value))]
    InvalidParameter {
        /// Dotted field name, e.g. `structure.inertia_alpha`.
        field: String,
        /// Offending value.
        value: f64,
        /// What is wrong.
        message: String,
    },
    /// A TOML description could not be parsed (unknown key, wrong type…).
    #[error("{source_name}: {message}")]
    Toml {
        /// What was being parsed (file name or `<string>`).
        source_name: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A table (flutter derivatives, nonlinear coefficient over K) is malformed.
    #[error("table `{table}`: {message}")]
    InvalidTable {
        /// Table name.
        table: String,
        /// What is wrong.
        message: String,
    },
    /// A Scanlan derivative of an identified law is not identifiable (`null` in
    /// `identification.json`) in some cases and no fallback was chosen.
    #[error("derivative {derivative} is not identifiable (null) in case(s) {cases:?}; choose a fallback (flat plate, zero or skip)")]
    NotIdentifiable {
        /// Derivative name, e.g. `A1`.
        derivative: String,
        /// Case ids where it is `null`.
        cases: Vec<String>,
    },
    /// An error of the `identify` crate (data-set writing, `identification.json` reading).
    #[error("{context}: {source}")]
    Identify {
        /// What was being done.
        context: String,
        /// The underlying error (names file, line, field).
        source: identify::Error,
    },
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// What happened.
        message: String,
    },
    /// A result document (`flutter.json`, `lco.json`, `branch.json`) is not JSON of the
    /// documented shape.
    #[error("{path}: {message}")]
    Document {
        /// The file.
        path: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A result document carries another `format` tag than the one expected.
    #[error("{path}: format `{found}` is not `{expected}`")]
    WrongFormat {
        /// The file.
        path: String,
        /// The `format` tag read.
        found: String,
        /// The `format` tag expected.
        expected: String,
    },
    /// A numerical step failed (singular matrix, no convergence…).
    #[error("{context}: numerical failure: {message}")]
    Numerical {
        /// Where it happened.
        context: String,
        /// What happened.
        message: String,
    },
}

impl Error {
    /// This error with the field of an [`Error::InvalidParameter`] rewritten by `f` (a file
    /// name prefixed, a key renamed to an input form's own name); other errors unchanged.
    pub fn map_field(self, f: impl FnOnce(String) -> String) -> Self {
        match self {
            Error::InvalidParameter {
                field,
                value,
                message,
            } => Error::InvalidParameter {
                field: f(field),
                value,
                message,
            },
            other => other,
        }
    }

    /// Shorthand for [`Error::InvalidParameter`].
    pub fn param(field: impl Into<String>, value: f64, message: impl Into<String>) -> Self {
        Error::InvalidParameter {
            field: field.into(),
            value,
            message: message.into(),
        }
    }

    /// Shorthand for [`Error::Numerical`].
    pub fn numerical(context: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Numerical {
            context: context.into(),
            message: message.into(),
        }
    }
}

/// Checks that `value` is finite and `> 0`.
pub(crate) fn positive(field: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::param(field, value, "must be finite and > 0"))
    }
}

/// Checks that `value` is finite and `>= 0`.
pub(crate) fn non_negative(field: &str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Error::param(field, value, "must be finite and >= 0"))
    }
}

/// Checks that `value` is finite.
pub(crate) fn finite(field: &str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Error::param(field, value, "must be finite"))
    }
}
