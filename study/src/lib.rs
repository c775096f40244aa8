//! aeroform studies: a TOML file that says which data to identify, which aeroelastic
//! analyses to run and which figures to draw ([`spec`]), with the input caps it is checked
//! against ([`limits`]), and the JSON documents a study writes besides the libraries' own
//! ([`documents`]).

#![warn(missing_docs)]

pub mod documents;
pub mod limits;
pub mod spec;

pub use spec::Study;
