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

#[test]
fn cli_harness_runs_on_its_corpus() {
    run("cli", aeroform::fuzz_harness::cli);
}

/// Stable-Rust stand-in for fuzzing the study files with huge numbers: in every study
/// seed, each number in turn is replaced by each of a list of extreme values (one file
/// per replacement) and the study harness (parser + caps invariant) runs on it.
#[test]
fn study_harness_survives_every_number_replaced_by_an_extreme_value() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/study");
    let extremes = [
        "1e300",
        "-1e300",
        "1e308",
        "18446744073709551615",
        "9223372036854775807",
        "nan",
        "inf",
        "-inf",
        "0",
        "-1",
        "1e-320",
    ];
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    let mut n = 0;
    for f in files {
        let Ok(text) = std::fs::read_to_string(&f) else {
            continue;
        };
        // byte ranges of numbers: a digit run (with . e E + -) after `= `, `[` or `, `
        let b = text.as_bytes();
        let mut spans = Vec::new();
        let mut i = 0;
        while i < b.len() {
            let starts = b[i].is_ascii_digit()
                && (i == 0 || matches!(b[i - 1], b' ' | b'[' | b'=' | b',' | b'-'));
            if starts {
                let s = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
                let mut j = i;
                while j < b.len()
                    && (b[j].is_ascii_digit()
                        || matches!(b[j], b'.' | b'e' | b'E' | b'+' | b'-' | b'_'))
                {
                    j += 1;
                }
                spans.push((s, j));
                i = j;
            } else {
                i += 1;
            }
        }
        for (s, e) in spans {
            for x in extremes {
                let mutated = format!("{}{x}{}", &text[..s], &text[e..]);
                let r =
                    std::panic::catch_unwind(|| aeroform::fuzz_harness::study(mutated.as_bytes()));
                assert!(
                    r.is_ok(),
                    "{}: number at byte {s} → {x} panicked",
                    f.display()
                );
                n += 1;
            }
        }
    }
    assert!(n > 500, "only {n} mutations");
}

#[test]
fn aero_files_harness_runs_on_its_corpus() {
    run("aero_files", aeroform::fuzz_harness::aero_files);
}

#[test]
fn part_harness_runs_on_its_corpus() {
    run("part", aeroform::fuzz_harness::part);
}

#[test]
fn results_harness_runs_on_its_corpus() {
    run("results", aeroform::fuzz_harness::results);
}
