//! Structure, aerodynamic models, time integration, flutter, LCO and the virtual wind tunnel
//! (DESIGN.md §4). Built on `identify` for data sets and Eq. 19 types.
//!
//! Sign conventions (DESIGN.md §2, Scanlan): h heave positive down, α pitch positive
//! nose-up, L lift per unit span positive down, M moment per unit span about the elastic
//! axis positive nose-up; C_L = L/(½ρU²B), C_M = M/(½ρU²B²), K = Bω/U with B the full
//! chord; Theodorsen's k = bω/U uses the semi-chord b = B/2.

pub mod aero;
pub mod bessel;
pub mod branch;
pub mod documents;
pub mod dynamics;
pub mod effects;
pub mod ensemble;
pub mod error;
pub mod files;
pub mod flutter;
pub mod identified;
pub mod integrate;
pub mod lco;
pub(crate) mod linalg;
pub(crate) mod optim;
pub mod reference;
pub mod section;
pub mod structure;
pub mod theodorsen;
pub mod trajectory;
pub mod tunnel;

pub use error::{Error, Result};
