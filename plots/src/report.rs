//! todo
pub struct Report;
