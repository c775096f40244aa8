//! How the commands talk on the terminal: the global `--quiet` (no human-readable lines on
//! stdout, no progress bars) and `--json` (the command's result document on stdout and
//! nothing else there; implies `--quiet`). Errors and warnings always go to stderr.

use std::sync::OnceLock;

/// The output mode of this process, set once from the command line.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Mode {
    /// `--json`: the result document on stdout.
    pub json: bool,
    /// `--quiet`: nothing on stdout but the `--json` document.
    pub quiet: bool,
}

static MODE: OnceLock<Mode> = OnceLock::new();

/// Sets the mode (first call wins; later calls are ignored).
pub fn init(mode: Mode) {
    let _ = MODE.set(mode);
}

/// The mode (default: human output, no JSON).
pub fn mode() -> Mode {
    MODE.get().copied().unwrap_or_default()
}

/// True when human-readable output and progress bars are suppressed (`--quiet` or
/// `--json`).
pub fn silent() -> bool {
    let m = mode();
    m.json || m.quiet
}

/// With `--json`, prints `doc` (pretty JSON) on stdout.
///
/// # Errors
/// The document cannot be serialised (a non-finite float in a `serde_json::Value` is not
/// possible; a failing `Serialize` implementation is).
pub fn document<T: serde::Serialize + ?Sized>(doc: &T) -> anyhow::Result<()> {
    if mode().json {
        println!("{}", serde_json::to_string_pretty(doc)?);
    }
    Ok(())
}

/// `println!` unless the output is [`silent`].
macro_rules! say {
    ($($arg:tt)*) => {
        if !$crate::ui::silent() {
            println!($($arg)*);
        }
    };
}
pub(crate) use say;
