//! The one error type of the `identify` crate.

use std::path::PathBuf;

/// Result alias of the `identify` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong while reading data sets or identifying a force law.
///
/// Every variant names the place (file, line, field, case or term) and carries the
/// offending values so that a user can find and fix the input.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// File or folder concerned.
        path: PathBuf,
        /// Underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The manifest is not valid TOML or violates DATA_FORMAT.md.
    #[error("{path}:{line}: field `{field}`: {message}")]
    Manifest {
        /// Manifest file.
        path: PathBuf,
        /// 1-based line (0 when unknown).
        line: usize,
        /// Dotted field name, e.g. `case[3].wind_speed`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A case CSV violates DATA_FORMAT.md.
    #[error("{path}:{line}: field `{field}`: {message}")]
    Csv {
        /// CSV file.
        path: PathBuf,
        /// 1-based line (0 when it concerns the whole file).
        line: usize,
        /// Column name.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// Time stamps are not uniformly spaced.
    #[error(
        "{path}:{line}: field `t`: non-uniform sampling (step {step} s, median step {median} s)"
    )]
    NonUniformSampling {
        /// CSV file.
        path: PathBuf,
        /// 1-based line of the first bad row.
        line: usize,
        /// Offending step \[s\].
        step: f64,
        /// Median step \[s\].
        median: f64,
    },
    /// A record is too short for the requested processing.
    #[error("case `{case}`: record of {duration} s is shorter than {needed} s ({reason})")]
    TooShort {
        /// Case id.
        case: String,
        /// Record duration \[s\].
        duration: f64,
        /// Needed duration \[s\].
        needed: f64,
        /// Why that duration is needed.
        reason: String,
    },
    /// The candidate library of a case (or group) does not have full column rank.
    #[error("case `{case}`: library of {expected} terms has numerical rank {rank}; dependencies: {}", dependencies.join("; "))]
    RankDeficient {
        /// Case id or group name.
        case: String,
        /// Numerical rank.
        rank: usize,
        /// Number of columns.
        expected: usize,
        /// Each dependency, in term names.
        dependencies: Vec<String>,
    },
    /// An option is out of range.
    #[error("option `{name}`: {message}")]
    InvalidOption {
        /// Option name.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// Input data is numerically unusable (non-finite, zero wind speed, empty…).
    #[error("case `{case}`: field `{field}`: {message}")]
    InvalidData {
        /// Case id.
        case: String,
        /// Field or quantity.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A linear algebra step failed.
    #[error("{context}: numerical failure: {message}")]
    Numerical {
        /// Where it happened.
        context: String,
        /// What happened.
        message: String,
    },
    /// A folder an aeroform command was still writing (or that a killed run left behind):
    /// it carries the incomplete-marker [`crate::io::INCOMPLETE_MARKER`] or has the name of
    /// a staging folder ([`crate::io::is_staging_name`]). Never read as a result.
    #[error("{path}: {message}")]
    IncompleteFolder {
        /// The folder.
        path: PathBuf,
        /// Why it is refused and what to do.
        message: String,
    },
    /// A JSON result file is malformed.
    #[error("{path}: {message}")]
    Json {
        /// File.
        path: PathBuf,
        /// What is wrong (serde message with line and column).
        message: String,
    },
    /// A fitted lag law is refused: a constant at an open bound of its physical range, or
    /// a state outside \[0, 1\].
    #[error("lag law refused: {parameter} = {value}: {reason}")]
    Unphysical {
        /// Parameter or quantity (`tau1 [b/U]`, `x` …).
        parameter: String,
        /// Its value.
        value: f64,
        /// Why it is refused.
        reason: String,
    },
    /// A prediction asked outside the range of the data a law was fitted on.
    #[error("case `{case}`: {quantity} {value} is outside the range [{low}, {high}] the law was fitted on")]
    OutsideFittedRange {
        /// Case id.
        case: String,
        /// The quantity and its unit (`mean angle [deg]` …).
        quantity: String,
        /// The case's value.
        value: f64,
        /// Lower end of the fitted range.
        low: f64,
        /// Upper end of the fitted range.
        high: f64,
    },
}

impl Error {
    /// Wraps an I/O error with its path.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
