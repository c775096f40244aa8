//! Forced-motion records → the nonlinear aerodynamic force law (DESIGN.md §3).
//!
//! The chain is: [`dataset`] (read/write the folder format of DATA_FORMAT.md, convert to SI
//! per unit span) → [`preprocess`] (wind–no-wind subtraction, velocities) → [`record`]
//! (nondimensional regressors α, Bα̇/U, h/B, ḣ/U and targets C_L, C_M) → [`library`]
//! (polynomial candidate terms) → [`identifiability`] (numerical rank, dependencies,
//! canonical basis) → [`regress`] (STLSQ, group STLSQ, δ path) → [`metrics`] (R², Eq. 14
//! key-frequency loss, MFWA) → [`eq19`] (Scanlan derivatives and N*) → [`pipeline`]
//! (the whole identification of a data set, the `identification.json` result) →
//! [`ensemble`] (block-bootstrap intervals of every coefficient and derivative).
//!
//! Sign conventions (DESIGN.md §2): h positive down, α positive nose-up, lift positive down,
//! moment positive nose-up, C_L = L/(½ρU²B), C_M = M/(½ρU²B²).

pub mod csv_fields;
pub mod dataset;
pub mod ensemble;
pub mod eq19;
pub mod error;
pub mod identifiability;
pub mod io;
pub mod lag;
pub mod library;
pub mod limits;
pub mod metrics;
pub mod numerics;
pub mod paper;
pub mod pipeline;
pub mod preprocess;
pub mod record;
pub mod regress;
pub mod series;
pub mod synthetic;
pub mod toml_lines;
pub mod workflow;

pub use error::{Error, Result};
