//! The one error type of the `study` crate.

/// Result alias of the `study` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong while building or running a study.
///
/// The libraries' errors are kept whole (their variants name the file, line and field);
/// [`Error::Context`] puts in front of any error the study key, path or stage it concerns
/// (`identification`, `flutter run \`p-k\``, `data.virtual.model: path`), so that the
/// chain of sources reads like the messages of the command line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A usage or input error of the study itself (a key naming something the data do not
    /// have); the command line exits with its usage code (2).
    #[error("{0}")]
    Usage(String),
    /// The study file is invalid (from [`crate::spec`]).
    #[error(transparent)]
    Spec(#[from] crate::spec::SpecError),
    /// A stage cannot run as the study asks (a missing section, no data source, no case
    /// to identify), with the message.
    #[error("{0}")]
    Study(String),
    /// An error of the `identify` crate (data, preprocessing, identification, writing a
    /// file).
    #[error(transparent)]
    Identify(#[from] identify::Error),
    /// An error of the `aeroelastic` crate (models, structure, flutter, LCO, branches).
    #[error(transparent)]
    Aeroelastic(#[from] aeroelastic::Error),
    /// A folder or file could not be created or read.
    #[error("{context}")]
    Io {
        /// What was being done, naming the path.
        context: String,
        /// The system's error.
        #[source]
        source: std::io::Error,
    },
    /// A JSON document could not be serialised or parsed.
    #[error("{context}")]
    Json {
        /// What was being done, naming the path.
        context: String,
        /// serde_json's error.
        #[source]
        source: serde_json::Error,
    },
    /// `source`, with the study key, path or stage it concerns in front.
    #[error("{context}")]
    Context {
        /// The key, path or stage.
        context: String,
        /// The error itself.
        #[source]
        source: Box<Error>,
    },
}

/// Puts a study key, path or stage in front of an error ([`Error::Context`]).
pub trait Context<T> {
    /// Wraps the error with the fixed context `context`.
    ///
    /// # Errors
    /// The error of `self`, wrapped.
    fn context(self, context: &str) -> Result<T>;
    /// Wraps the error with the context `f()`, computed only on error.
    ///
    /// # Errors
    /// The error of `self`, wrapped.
    fn with_context<F: FnOnce() -> String>(self, f: F) -> Result<T>;
}

impl<T, E: Into<Error>> Context<T> for std::result::Result<T, E> {
    fn context(self, context: &str) -> Result<T> {
        self.with_context(|| context.to_string())
    }

    fn with_context<F: FnOnce() -> String>(self, f: F) -> Result<T> {
        self.map_err(|e| Error::Context {
            context: f(),
            source: Box::new(e.into()),
        })
    }
}
