//! CI-speed check of the fuzz harnesses (`aeroform::fuzz_harness`) on stable Rust: every
//! seed of `fuzz/corpus/<target>/` and every minimised crash input of
//! `fuzz/regressions/<target>/` (fixed bugs) runs through its harness without panicking.
//! The fuzzing itself (`cargo fuzz`, nightly) is described in fuzz/README.md.

use std::path::Path;

fn run_dir(target: &str, sub: &str, harness: fn(&[u8])) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join(sub)
        .join(target);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return 0;
    };
    let mut n = 0;
    let mut files: Vec<_> = entries.map(|e| e.unwrap().path()).collect();
    files.sort();
    for f in files {
        let data = std::fs::read(&f).unwrap();
        let r = std::panic::catch_unwind(|| harness(&data));
        assert!(r.is_ok(), "harness `{target}` panicked on {}", f.display());
        n += 1;
    }
    n
}

fn run(target: &str, harness: fn(&[u8])) {
    let seeds = run_dir(target, "corpus", harness);
    assert!(seeds >= 5, "{seeds} seeds for `{target}`");
    run_dir(target, "regressions", harness);
}

#[test]
fn dataset_harness_runs_on_its_corpus() {
    run("dataset", aeroform::fuzz_harness::dataset);
}

#[test]
fn study_harness_runs_on_its_corpus() {
    run("study", aeroform::fuzz_harness::study);
}

#[test]
fn identification_harness_runs_on_its_corpus() {
    run("identification", aeroform::fuzz_harness::identification);
}
