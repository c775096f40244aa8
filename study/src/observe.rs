//! How a study reports progress without printing: the caller passes an [`Observer`] (the
//! command line draws progress bars and prints the lines; [`Quiet`] drops everything).

use aeroelastic::lco::SweepProgress;
use identify::pipeline::Progress;

/// Receives the progress of a study run.
pub trait Observer: Sync {
    /// A line of human-readable text about a finished step (`data: 12 cases; …`, the
    /// identification's summary table, flutter points, branches).
    fn say(&self, line: &str);
    /// A counter over `total` units labelled `label` (`tunnel`, `prepare`, `flutter`,
    /// `LCO`), for a loop of known length.
    fn counter(&self, label: &'static str, total: usize) -> Box<dyn Counter + '_>;
    /// Progress of the identification (the callback of [`identify::pipeline::identify`]).
    fn identify(&self, progress: Progress);
    /// The identification has ended (its progress display can go).
    fn identify_done(&self);
}

/// Progress over a known number of units (from [`Observer::counter`]).
pub trait Counter: Send + Sync {
    /// `n` more units done.
    fn inc(&self, n: usize);
    /// One LCO run of a sweep done (one unit).
    fn sweep(&self, progress: SweepProgress) {
        let _ = progress;
        self.inc(1);
    }
    /// The loop has ended (its display can go).
    fn finish(&self);
}

/// An [`Observer`] that drops everything (tests, library callers).
#[derive(Debug, Clone, Copy, Default)]
pub struct Quiet;

impl Counter for Quiet {
    fn inc(&self, _: usize) {}
    fn finish(&self) {}
}

impl Observer for Quiet {
    fn say(&self, _: &str) {}
    fn counter(&self, _: &'static str, _: usize) -> Box<dyn Counter + '_> {
        Box::new(Quiet)
    }
    fn identify(&self, _: Progress) {}
    fn identify_done(&self) {}
}
