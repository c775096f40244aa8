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

/// `s` safe to print on a terminal (issue 39, row 4): every control character but the
/// line feed and the tab (C0, DEL, C1: ESC sequences that clear the screen or hide what
/// follows, a carriage return that overwrites a line) and every bidirectional override
/// (U+202A–U+202E, U+2066–U+2069: text shown in another order than it is) is written as its
/// escape `\u{1b}`. Strings from files (a manifest's `name`, CSV fields, paths) reach the
/// terminal only through this.
pub fn escape(s: &str) -> std::borrow::Cow<'_, str> {
    let unsafe_char = |c: char| {
        (c.is_control() && c != '\n' && c != '\t')
            || ('\u{202a}'..='\u{202e}').contains(&c)
            || ('\u{2066}'..='\u{2069}').contains(&c)
    };
    if !s.chars().any(unsafe_char) {
        return std::borrow::Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if unsafe_char(c) {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// At most `max` bytes of `s` (cut at a character boundary), with the number of bytes left
/// out: a hostile file cannot make a message of a gigabyte (issue 39, row 5).
pub fn clip(s: &str, max: usize) -> std::borrow::Cow<'_, str> {
    if s.len() <= max {
        return std::borrow::Cow::Borrowed(s);
    }
    let mut end = max;
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    std::borrow::Cow::Owned(format!(
        "{}… ({} more bytes not shown)",
        &s[..end],
        s.len() - end
    ))
}

/// `println!` unless the output is [`silent`]; the text goes through [`escape`].
macro_rules! say {
    ($($arg:tt)*) => {
        if !$crate::ui::silent() {
            println!("{}", $crate::ui::escape(&format!($($arg)*)));
        }
    };
}
pub(crate) use say;

/// `eprintln!` of a warning, always (stderr), the text through [`escape`].
macro_rules! warning {
    ($($arg:tt)*) => {
        eprintln!("{}", $crate::ui::escape(&format!($($arg)*)));
    };
}
pub(crate) use warning;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_and_bidi_overrides_are_escaped() {
        assert_eq!(escape("plain ∆ text\n\tok"), "plain ∆ text\n\tok");
        assert_eq!(escape("a\u{1b}[2Jb"), "a\\u{1b}[2Jb");
        assert_eq!(escape("x\ry"), "x\\u{d}y");
        assert_eq!(escape("\u{9b}31m"), "\\u{9b}31m");
        assert_eq!(escape("ab\u{202e}cd"), "ab\\u{202e}cd");
    }

    #[test]
    fn clip_keeps_short_text_and_cuts_long_text_at_a_character() {
        assert_eq!(clip("short", 10), "short");
        let long = "é".repeat(100);
        let c = clip(&long, 51);
        assert!(c.starts_with(&"é".repeat(25)));
        assert!(c.ends_with("(150 more bytes not shown)"), "{c}");
    }
}
