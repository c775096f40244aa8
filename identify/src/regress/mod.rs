//! Sparse regression (to be written).

pub mod pysindy;
