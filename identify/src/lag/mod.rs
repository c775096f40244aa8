//! A force law with memory: identification of the lag law ([`law`]) from forced-motion
//! records (issue 41).

pub mod law;

pub use law::{FittedRange, LagChannel, LagColumn, LagLaw, LagLawDocument, LAG_LAW_FORMAT};
