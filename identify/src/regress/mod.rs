//! Sparse regression (to be written).

pub mod factor;
pub mod pysindy;
pub mod small;
