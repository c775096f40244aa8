//! A counting progress bar for the LCO sweeps, fed by `aeroelastic`'s sweep observer.

use aeroelastic::lco::SweepProgress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Progress bar over a known number of runs; hidden when stderr is not a terminal.
pub struct CountBar {
    bar: ProgressBar,
}

impl CountBar {
    /// A bar of `total` units labelled `prefix`.
    pub fn new(prefix: &'static str, total: usize) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{prefix:>8} [{bar:40}] {pos}/{len} {elapsed} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_prefix(prefix);
        CountBar { bar }
    }

    /// Observer of the LCO sweeps: one unit per finished speed.
    pub fn observe_sweep(&self, p: SweepProgress) {
        self.bar.inc(1);
        self.bar
            .set_message(format!("{:?} U = {}", p.direction, p.u));
    }

    /// One unit done.
    pub fn inc(&self) {
        self.bar.inc(1);
    }

    /// `n` units done.
    pub fn inc_by(&self, n: usize) {
        self.bar.inc(n as u64);
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
