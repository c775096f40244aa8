//! The study crate on its own: the quickstart study runs through `run_study` with an
//! observer that records what a terminal would show, writes its result files (no figures:
//! those are drawn by `plots`), and an unknown `outputs.series_cases` id is a usage error.

use std::path::Path;
use std::sync::Mutex;

use aeroelastic::lco::SweepProgress;
use identify::pipeline::Progress;
use study::run::{names, run_study};
use study::{Counter, Error, Observer, Quiet, Study};

/// Records the lines, the counters (label, total, units counted) and the identification
/// progress calls.
#[derive(Default)]
struct Recorder {
    lines: Mutex<Vec<String>>,
    counters: Mutex<Vec<(&'static str, usize)>>,
    units: Mutex<Vec<(&'static str, usize)>>,
    identify: Mutex<(usize, usize)>,
}

struct Count<'a> {
    label: &'static str,
    done: Mutex<usize>,
    owner: &'a Recorder,
}

impl Counter for Count<'_> {
    fn inc(&self, n: usize) {
        *self.done.lock().unwrap() += n;
    }
    fn sweep(&self, _: SweepProgress) {
        self.inc(1);
    }
    fn finish(&self) {
        let done = *self.done.lock().unwrap();
        self.owner.units.lock().unwrap().push((self.label, done));
    }
}

impl Observer for Recorder {
    fn say(&self, line: &str) {
        self.lines.lock().unwrap().push(line.to_string());
    }
    fn counter(&self, label: &'static str, total: usize) -> Box<dyn Counter + '_> {
        self.counters.lock().unwrap().push((label, total));
        Box::new(Count {
            label,
            done: Mutex::new(0),
            owner: self,
        })
    }
    fn identify(&self, _: Progress) {
        self.identify.lock().unwrap().0 += 1;
    }
    fn identify_done(&self) {
        self.identify.lock().unwrap().1 += 1;
    }
}

#[test]
fn quickstart_runs_without_a_terminal_and_reports_through_the_observer() {
    let study = Study::quickstart().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let rec = Recorder::default();
    let timings = run_study(&study, dir.path(), &rec).unwrap();
    let stages: Vec<&str> = timings.iter().map(|(s, _)| *s).collect();
    assert_eq!(stages, ["data", "identify", "flutter", "lco"]);
    for f in [
        names::STUDY,
        names::CASES,
        names::IDENTIFICATION,
        names::COEFFICIENTS,
        names::COEFFICIENT_COLUMNS,
        names::DERIVATIVES,
        names::FLUTTER,
        names::FLUTTER_POINTS,
        names::LCO,
        names::LCO_AMPLITUDES,
    ] {
        assert!(dir.path().join(f).is_file(), "{f} missing");
    }
    // figures and report are drawn by plots, not here
    assert!(!dir.path().join(names::FIGURE_LIST).exists());
    assert!(!dir.path().join(names::REPORT).exists());

    let lines = rec.lines.lock().unwrap();
    assert!(lines[0].starts_with("data: 16 cases; "), "{lines:?}");
    assert!(
        lines.iter().any(|l| l.starts_with("flutter [")),
        "{lines:?}"
    );
    // every counter counted its total and was finished
    let counters = rec.counters.lock().unwrap().clone();
    let labels: Vec<&str> = counters.iter().map(|(l, _)| *l).collect();
    assert_eq!(labels, ["prepare", "flutter", "LCO"]);
    assert_eq!(*rec.units.lock().unwrap(), counters);
    let (calls, done) = *rec.identify.lock().unwrap();
    assert!(calls > 0);
    assert_eq!(done, 1);
}

#[test]
fn an_unknown_series_case_is_a_usage_error_before_any_result_is_written() {
    let text = Study::quickstart().unwrap().text.replace(
        "series_cases = [\"D-U4-A24\", \"D-U10-A6\"]",
        "series_cases = [\"nope\"]",
    );
    assert!(text.contains("\"nope\""));
    let study = Study::parse(&text, Path::new("q.toml"), Path::new(".")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let e = run_study(&study, dir.path(), &Quiet).unwrap_err();
    assert!(matches!(e, Error::Usage(_)), "{e:?}");
    assert_eq!(
        e.to_string(),
        "q.toml: key `outputs.series_cases`: no case `nope` in the data"
    );
    assert!(!dir.path().join(names::STUDY).exists());
}
