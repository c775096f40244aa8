//! A force law with memory: identification of the lag law ([`law`]) from forced-motion
//! records (issue 41): [`series`] (a case in the law's variables, its separation state at
//! the periodic steady state), [`fit`](mod@fit) (variable projection: output error on the law's
//! nonlinear constants, least squares and δ-path selection for the force columns),
//! [`holdout`] (held-out validation against the memoryless law) and [`document`] (the
//! `lag_law.json` document of a fit).

pub mod document;
pub mod ensemble;
pub mod fit;
pub mod holdout;
pub mod law;
pub mod report;
pub mod series;

pub use fit::{fit, predict, LagFit, LagFitOptions, LagPrediction, LagReport};
pub use holdout::{compare, held_out, HoldOut, MemorylessLaw};
pub use law::{
    circulation_rates, circulatory_angle, FittedRange, LagChannel, LagColumn, LagLaw,
    LagLawDocument, CIRCULATION_LAGS, LAG_LAW_FORMAT,
};
pub use report::{HeldOutReport, HeldOutRow};
pub use series::LagSeries;
