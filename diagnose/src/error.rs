//! The one error type of the `diagnose` crate.

/// Result alias of the `diagnose` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong while diagnosing a sim-to-real gap or running the blind
/// benchmark. Every variant names the place (data set, case, candidate, field) and carries
/// the offending values.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The input data cannot support a diagnosis (too few cases or speeds for held-out
    /// folds, no forced case, a free data set without `[structure]`…).
    #[error("data set `{dataset}`: {message}")]
    Data {
        /// Data-set name or folder.
        dataset: String,
        /// What is missing or wrong.
        message: String,
    },
    /// A setting is out of range.
    #[error("setting `{field}` = {}: {message}", identify::limits::show(*.value))]
    Setting {
        /// Setting name.
        field: String,
        /// Offending value.
        value: f64,
        /// What is wrong.
        message: String,
    },
    /// A candidate augmentation could not be fitted (rank-deficient regressors, a
    /// divergent simulation…); the diagnosis records it as not significant.
    #[error("candidate `{candidate}`: {message}")]
    Candidate {
        /// Effect name of the candidate.
        candidate: String,
        /// What went wrong.
        message: String,
    },
    /// An unknown effect name (in a file or on the command line).
    #[error("unknown effect `{name}`; expected one of {expected}")]
    UnknownEffect {
        /// The name given.
        name: String,
        /// The accepted names, comma separated.
        expected: String,
    },
    /// Identification of the baseline or an augmented law failed.
    #[error("{context}: {source}")]
    Identify {
        /// What was being done (fold, case).
        context: String,
        /// The identify error.
        #[source]
        source: Box<identify::Error>,
    },
    /// A structural or aerodynamic model could not be built or integrated.
    #[error("{context}: {source}")]
    Aeroelastic {
        /// What was being done.
        context: String,
        /// The aeroelastic error.
        #[source]
        source: Box<aeroelastic::Error>,
    },
    /// A sweep specification, an item index, a shard or a part document is invalid
    /// (`source` names the file or the caller, `message` the field and the value).
    #[error("{source_name}: {message}")]
    Sweep {
        /// File or caller the bad value came from.
        source_name: String,
        /// What is wrong, naming the field.
        message: String,
    },
    /// Writing a result file failed.
    #[error("{context}: {message}")]
    Io {
        /// File and operation.
        context: String,
        /// The system message.
        message: String,
    },
}

impl Error {
    /// A [`Error::Data`] error.
    pub fn data(dataset: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Data {
            dataset: dataset.into(),
            message: message.into(),
        }
    }

    /// A [`Error::Setting`] error.
    pub fn setting(field: impl Into<String>, value: f64, message: impl Into<String>) -> Self {
        Error::Setting {
            field: field.into(),
            value,
            message: message.into(),
        }
    }

    /// A [`Error::Candidate`] error.
    pub fn candidate(candidate: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Candidate {
            candidate: candidate.into(),
            message: message.into(),
        }
    }

    /// Wraps an identify error with its context.
    pub fn identify(context: impl Into<String>, source: identify::Error) -> Self {
        Error::Identify {
            context: context.into(),
            source: Box::new(source),
        }
    }

    /// Wraps an aeroelastic error with its context.
    pub fn aeroelastic(context: impl Into<String>, source: aeroelastic::Error) -> Self {
        Error::Aeroelastic {
            context: context.into(),
            source: Box::new(source),
        }
    }
}
