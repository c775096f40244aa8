//! Studies: a TOML file that says which data to identify, which aeroelastic analyses to
//! run and which figures to draw ([`spec`]); the runner ([`run`]) that calls the libraries
//! stage by stage and writes every result file; the figures and HTML report drawn from
//! those files alone ([`figures`]), so that `aeroform plot` can redraw them.

pub mod build;
pub mod figures;
pub mod files;
pub mod paper;
pub mod run;
/// The study-file parser lives in the library target (`aeroform::study_spec`) so that the
/// fuzz target and tests can call it.
pub use ::study::spec;

pub use spec::Study;
