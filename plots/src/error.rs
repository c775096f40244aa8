//! The one error type of the `plots` crate.

/// Result alias of the `plots` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong while drawing a figure or writing the report.
///
/// Every variant names the figure (its kind, e.g. `"time_series"`) and the field concerned,
/// and carries the offending values where there are any.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A figure has nothing finite to draw in one of its inputs (empty, or only NaN/∞).
    #[error("figure `{figure}`: field `{field}`: no finite data to draw ({len} values given)")]
    NoData {
        /// Figure kind.
        figure: &'static str,
        /// Field or series concerned, e.g. `panels[1].series[0] "model"`.
        field: String,
        /// Number of values given (finite or not).
        len: usize,
    },
    /// Two arrays that must pair up element by element have different lengths.
    #[error("figure `{figure}`: field `{field}`: length mismatch ({left} vs {right})")]
    LengthMismatch {
        /// Figure kind.
        figure: &'static str,
        /// Fields concerned, e.g. `series[0] x/y`.
        field: String,
        /// Length of the first array.
        left: usize,
        /// Length of the second array.
        right: usize,
    },
    /// An input value is out of range or inconsistent.
    #[error("figure `{figure}`: field `{field}`: {message}")]
    InvalidInput {
        /// Figure kind.
        figure: &'static str,
        /// Field concerned.
        field: String,
        /// What is wrong, with the offending values.
        message: String,
    },
    /// plotters reported a drawing failure (font, backend).
    #[error("figure `{figure}`: drawing failed: {message}")]
    Drawing {
        /// Figure kind.
        figure: &'static str,
        /// plotters' message.
        message: String,
    },
    /// The bitmap could not be encoded as PNG.
    #[error("figure `{figure}`: PNG encoding failed: {message}")]
    Encode {
        /// Figure kind.
        figure: &'static str,
        /// Encoder's message.
        message: String,
    },
    /// The SVG could not be turned into outlines or PDF (`usvg` message, or what the PDF writer
    /// does not draw).
    #[error("figure `{figure}`: vector output failed: {message}")]
    Vector {
        /// Figure kind.
        figure: &'static str,
        /// What failed.
        message: String,
    },
    /// The bundled font could not be registered with plotters.
    #[error("bundled font `{name}` could not be registered")]
    Font {
        /// Font file name.
        name: &'static str,
    },
    /// A file could not be written (from [`identify::io::write_atomic`], which names the path),
    /// or `identification.json` could not be read.
    #[error(transparent)]
    Write(#[from] identify::Error),
    /// A result file of a study could not be read or written (the study crate's error,
    /// naming the path).
    #[error(transparent)]
    Study(#[from] study::Error),
    /// A file of a study folder could not be read.
    #[error("{context}")]
    Io {
        /// What was being read, naming the path.
        context: String,
        /// The system's error.
        #[source]
        source: std::io::Error,
    },
    /// A value could not be turned into JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// `source`, with what was being done in front (`drawing figure vg`, `writing
    /// report.html`).
    #[error("{context}")]
    Context {
        /// What was being done.
        context: String,
        /// The error itself.
        #[source]
        source: Box<Error>,
    },
}

impl Error {
    /// True when the figure's data are at fault ([`Error::NoData`],
    /// [`Error::LengthMismatch`], [`Error::InvalidInput`], also inside [`Error::Context`]):
    /// when the data come from result files (`aeroform plot`), those files are.
    pub fn is_data(&self) -> bool {
        match self {
            Error::NoData { .. } | Error::LengthMismatch { .. } | Error::InvalidInput { .. } => {
                true
            }
            Error::Context { source, .. } => source.is_data(),
            _ => false,
        }
    }
}

/// Puts what was being done in front of an error ([`Error::Context`]).
pub(crate) trait Context<T> {
    /// Wraps the error with the context `f()`, computed only on error.
    fn with_context<F: FnOnce() -> String>(self, f: F) -> Result<T>;
    /// Wraps the error with the fixed context `context`.
    fn context(self, context: &str) -> Result<T>;
}

impl<T, E: Into<Error>> Context<T> for std::result::Result<T, E> {
    fn with_context<F: FnOnce() -> String>(self, f: F) -> Result<T> {
        self.map_err(|e| Error::Context {
            context: f(),
            source: Box::new(e.into()),
        })
    }

    fn context(self, context: &str) -> Result<T> {
        self.with_context(|| context.to_string())
    }
}

/// Turns any displayable plotters error into [`Error::Drawing`] for figure `figure`.
pub(crate) trait DrawResultExt<T> {
    /// Maps the error into [`Error::Drawing`].
    fn ctx(self, figure: &'static str) -> Result<T>;
}

impl<T, E: std::fmt::Display> DrawResultExt<T> for std::result::Result<T, E> {
    fn ctx(self, figure: &'static str) -> Result<T> {
        self.map_err(|e| Error::Drawing {
            figure,
            message: e.to_string(),
        })
    }
}
