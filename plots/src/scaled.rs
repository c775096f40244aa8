//! Figure styles: `Screen` (the default: titles inside the figure, PNG at the design size)
//! and `Paper` (no titles, the caption carries them; PNG at 300 dpi with the resolution in
//! its metadata, the design size rendered at [`PAPER_SCALE`] so text and lines keep their
//! proportions: a 1200-pixel-wide design is 7 in wide, 18-pixel text is 7.6 pt).
//!
//! The paper PNG is drawn through [`Scaled`], a backend that lays everything out at the
//! design size and multiplies every coordinate, stroke width, radius and font size by the
//! scale on the way to the bitmap, so no figure needs its own paper layout.

use std::sync::atomic::{AtomicU8, Ordering};

use plotters::prelude::*;
use plotters::style::text_anchor::Pos;
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
};

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

/// A backend of design size `size` drawing onto `inner`, `scale` times larger.
pub struct Scaled<DB: DrawingBackend> {
    inner: DB,
    scale: f64,
    size: (u32, u32),
}

impl<DB: DrawingBackend> Scaled<DB> {
    /// Draws the design size `size` onto `inner` (which should be `scale` × `size`).
    pub fn new(inner: DB, scale: f64, size: (u32, u32)) -> Self {
        Scaled { inner, scale, size }
    }

    fn p(&self, c: BackendCoord) -> BackendCoord {
        (
            (c.0 as f64 * self.scale).round() as i32,
            (c.1 as f64 * self.scale).round() as i32,
        )
    }
}

/// A line style with its stroke width scaled.
struct ScaledStyle<'a, S: BackendStyle> {
    inner: &'a S,
    scale: f64,
}

impl<S: BackendStyle> BackendStyle for ScaledStyle<'_, S> {
    fn color(&self) -> BackendColor {
        self.inner.color()
    }
    fn stroke_width(&self) -> u32 {
        ((self.inner.stroke_width() as f64 * self.scale).round() as u32).max(1)
    }
}

/// `base` with its font size multiplied by `scale`.
fn text_at<S: BackendTextStyle>(base: &S, scale: f64) -> TextStyle<'_> {
    let mut s = TextStyle::from((base.family(), base.size() * scale, base.style()))
        .transform(base.transform())
        .pos(Pos::new(base.anchor().h_pos, base.anchor().v_pos));
    s.color = base.color();
    s
}

impl<DB: DrawingBackend> DrawingBackend for Scaled<DB> {
    type ErrorType = DB::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.size
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let (a, b) = (self.p(point), self.p((point.0 + 1, point.1 + 1)));
        self.inner.draw_rect(a, (b.0 - 1, b.1 - 1), &color, true)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let st = ScaledStyle {
            inner: style,
            scale: self.scale,
        };
        let (a, b) = (self.p(from), self.p(to));
        if st.stroke_width() > 1 {
            self.inner.draw_path([a, b], &st)
        } else {
            self.inner.draw_line(a, b, &st)
        }
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let st = ScaledStyle {
            inner: style,
            scale: self.scale,
        };
        let (a, b) = (self.p(upper_left), self.p(bottom_right));
        self.inner.draw_rect(a, b, &st, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let st = ScaledStyle {
            inner: style,
            scale: self.scale,
        };
        let pts: Vec<BackendCoord> = path.into_iter().map(|c| self.p(c)).collect();
        self.inner.draw_path(pts, &st)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let st = ScaledStyle {
            inner: style,
            scale: self.scale,
        };
        let r = (radius as f64 * self.scale).round() as u32;
        let c = self.p(center);
        self.inner.draw_circle(c, r, &st, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let pts: Vec<BackendCoord> = vert.into_iter().map(|c| self.p(c)).collect();
        self.inner.fill_polygon(pts, style)
    }

    fn draw_text<TStyle: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let s = text_at(style, self.scale);
        let p = self.p(pos);
        self.inner.draw_text(text, &s, p)
    }

    fn estimate_text_size<TStyle: BackendTextStyle>(
        &self,
        text: &str,
        style: &TStyle,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        self.inner.estimate_text_size(text, style)
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let p = self.p(pos);
        self.inner.blit_bitmap(p, size, src)
    }
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
