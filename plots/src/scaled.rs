//! Figure styles: `Screen` (the default: titles inside the figure, PNG at the design size)
//! and `Paper` (no titles, the caption carries them; PNG at 300 dpi with the resolution in
//! its metadata, the design size rendered at [`PAPER_SCALE`] so text and lines keep their
//! proportions: a 1200-pixel-wide design is 7 in wide, 18-pixel text is 7.6 pt).
//!
//! The paper PNG is drawn through [`crate::rich::RichBackend::scaled`], which lays
//! everything out at the design size and multiplies every coordinate, stroke width, radius
//! and font size by the scale on the way to the bitmap, so no figure needs its own paper
//! layout.

use std::sync::atomic::{AtomicU8, Ordering};

/// Resolution of paper PNGs \[dots per inch\].
pub const PAPER_DPI: f64 = 300.0;
/// Design pixels → paper pixels: 1200 design pixels = 7 in at 300 dpi.
pub const PAPER_SCALE: f64 = 1.75;

/// How figures are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FigureStyle {
    /// Titles in the figures, PNG at the design size (the report and the screen).
    #[default]
    Screen,
    /// No titles, PNG at 300 dpi with DPI metadata (for a paper; captions carry titles).
    Paper,
}

impl FigureStyle {
    /// Parses `screen` or `paper`.
    ///
    /// # Errors
    /// A message naming the accepted values.
    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "screen" => Ok(FigureStyle::Screen),
            "paper" => Ok(FigureStyle::Paper),
            _ => Err(format!("`{s}`: expected screen or paper")),
        }
    }
}

static STYLE: AtomicU8 = AtomicU8::new(0);

/// Sets the style of every figure drawn afterwards in this process.
pub fn set_figure_style(s: FigureStyle) {
    STYLE.store(
        match s {
            FigureStyle::Screen => 0,
            FigureStyle::Paper => 1,
        },
        Ordering::Relaxed,
    );
}

thread_local! {
    static OVERRIDE: std::cell::Cell<Option<FigureStyle>> = const { std::cell::Cell::new(None) };
}

/// The current figure style: a [`with_figure_style`] override on this thread, else the
/// process-wide [`set_figure_style`].
pub fn figure_style() -> FigureStyle {
    if let Some(s) = OVERRIDE.with(|o| o.get()) {
        return s;
    }
    match STYLE.load(Ordering::Relaxed) {
        1 => FigureStyle::Paper,
        _ => FigureStyle::Screen,
    }
}

/// Runs `f` with the figure style `s` on this thread only (other threads keep theirs).
pub fn with_figure_style<T>(s: FigureStyle, f: impl FnOnce() -> T) -> T {
    let before = OVERRIDE.with(|o| o.replace(Some(s)));
    let out = f();
    OVERRIDE.with(|o| o.set(before));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn styles_parse_and_scale_is_seven_inches_per_1200_pixels() {
        assert_eq!(FigureStyle::parse("paper"), Ok(FigureStyle::Paper));
        assert_eq!(FigureStyle::parse("screen"), Ok(FigureStyle::Screen));
        assert!(FigureStyle::parse("print")
            .unwrap_err()
            .contains("screen or paper"));
        assert!((1200.0 * PAPER_SCALE / PAPER_DPI - 7.0).abs() < 1e-12);
    }
}
