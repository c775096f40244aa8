//! aeroform's speed benchmarks: the criterion benches of this folder (`cargo bench --bench
//! NAME` from the workspace root; `benches/Cargo.toml` lists them). This library is empty.
