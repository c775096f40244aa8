//! Criterion benchmarks of identification (to be written).
fn main() {}
