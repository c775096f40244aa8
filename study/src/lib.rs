//! aeroform studies: a TOML file that says which data to identify, which aeroelastic
//! analyses to run and which figures to draw ([`spec`]), checked against the input caps of
//! [`limits`]; the cases, structures and models it describes ([`build`]); the stages that
//! call `identify` and `aeroelastic` and write every result file ([`run`], with the data of
//! the paper's figures from [`paper`] and the small writers of [`files`]); and the JSON
//! documents a study writes besides the libraries' own ([`documents`]).
//!
//! Nothing here prints: progress and messages go to the [`Observer`] the caller passes.
//! Errors are one enum, [`Error`]. The figures and the HTML report are drawn from the
//! result files by `plots::study_report`.

#![warn(missing_docs)]

pub mod build;
pub mod documents;
pub mod error;
pub mod files;
pub mod limits;
pub mod observe;
pub mod paper;
pub mod run;
pub mod spec;

pub use error::{Context, Error, Result};
pub use observe::{Counter, Observer, Quiet};
pub use spec::Study;
