//! Progress bars drawn from the library's progress observers.

use std::sync::Mutex;

use aeroelastic::lco::SweepProgress;
use identify::pipeline::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// stderr, or nowhere under `--quiet`/`--json` ([`crate::ui::silent`]); indicatif itself
/// hides a bar when stderr is not a terminal.
fn target() -> ProgressDrawTarget {
    if crate::ui::silent() {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    }
}

/// A progress bar fed by [`identify::pipeline::identify`]'s observer; hidden when stderr is
/// not a terminal.
pub struct IdentifyBar {
    bar: Mutex<Option<(ProgressBar, &'static str)>>,
}

impl IdentifyBar {
    /// A new, not yet visible bar.
    pub fn new() -> Self {
        IdentifyBar {
            bar: Mutex::new(None),
        }
    }

    /// Observer to hand to the library.
    pub fn observe(&self, p: Progress) {
        let (stage, done, total) = match p {
            Progress::Cases { done, total } => ("cases", done, total),
            Progress::Groups { done, total } => ("δ paths", done, total),
        };
        let Ok(mut guard) = self.bar.lock() else {
            return;
        };
        if guard.as_ref().map(|(_, s)| *s) != Some(stage) {
            if let Some((b, _)) = guard.take() {
                b.finish_and_clear();
            }
            let b = ProgressBar::with_draw_target(Some(total as u64), target());
            b.set_style(
                ProgressStyle::with_template("{prefix:>8} [{bar:40}] {pos}/{len} {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            b.set_prefix(stage);
            *guard = Some((b, stage));
        }
        if let Some((b, _)) = guard.as_ref() {
            b.set_position(done as u64);
        }
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        if let Ok(mut guard) = self.bar.lock() {
            if let Some((b, _)) = guard.take() {
                b.finish_and_clear();
            }
        }
    }
}

/// A spinner with the elapsed time, for a stage whose progress the library does not
/// report (one diagnosis); hidden under `--quiet`/`--json` and when stderr is not a
/// terminal.
pub struct Spinner {
    bar: ProgressBar,
}

impl Spinner {
    /// A ticking spinner labelled `prefix` with the message `msg`.
    pub fn new(prefix: &'static str, msg: &str) -> Self {
        let bar = ProgressBar::with_draw_target(None, target());
        bar.set_style(
            ProgressStyle::with_template("{prefix:>8} {spinner} {elapsed} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.set_prefix(prefix);
        bar.set_message(msg.to_string());
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        Spinner { bar }
    }

    /// Removes the spinner.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Progress bar over a known number of runs; hidden when stderr is not a terminal.
pub struct CountBar {
    bar: ProgressBar,
}

impl CountBar {
    /// A bar of `total` units labelled `prefix`.
    pub fn new(prefix: &'static str, total: usize) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total as u64), target());
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

    /// One unit done, with a message.
    pub fn tick(&self, msg: String) {
        self.bar.inc(1);
        self.bar.set_message(msg);
    }

    /// Position `pos` with a message (progress that is not a count of finished units).
    pub fn set(&self, pos: usize, msg: String) {
        self.bar.set_position(pos as u64);
        self.bar.set_message(msg);
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

/// The terminal's [`study::Observer`]: lines through [`crate::ui::say!`] (nothing under
/// `--quiet`/`--json`), a [`CountBar`] per counter, an [`IdentifyBar`] for the
/// identification.
pub struct Terminal {
    identify: IdentifyBar,
}

impl Terminal {
    /// An observer with no bar shown yet.
    pub fn new() -> Self {
        Terminal {
            identify: IdentifyBar::new(),
        }
    }
}

impl study::Counter for CountBar {
    fn inc(&self, n: usize) {
        self.inc_by(n);
    }

    fn sweep(&self, progress: SweepProgress) {
        self.observe_sweep(progress);
    }

    fn finish(&self) {
        CountBar::finish(self);
    }
}

impl study::Observer for Terminal {
    fn say(&self, line: &str) {
        crate::ui::say!("{line}");
    }

    fn counter(&self, label: &'static str, total: usize) -> Box<dyn study::Counter + '_> {
        Box::new(CountBar::new(label, total))
    }

    fn identify(&self, progress: Progress) {
        self.identify.observe(progress);
    }

    fn identify_done(&self) {
        self.identify.finish();
    }
}
