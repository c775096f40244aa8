//! aeroform command-line interface.
fn main() {}
