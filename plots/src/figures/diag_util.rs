//! Small drawing helpers shared by the diagnosis figures: the "no data" note and text at
//! a pixel position of a chart drawn on a parent area.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{DrawResultExt, Result};
use crate::style::font;

/// Grey of the "no data" notes.
pub(crate) const NOTE: RGBColor = RGBColor(110, 110, 110);

/// Draws `text` centred in `area` in grey, with a thin frame: the placeholder of a panel
/// that has nothing finite to draw.
pub(crate) fn no_data<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    kind: &'static str,
) -> Result<()> {
    let (w, h) = area.dim_in_pixel();
    let (w, h) = (w as i32, h as i32);
    area.draw(&Rectangle::new(
        [(10, 10), (w - 10, h - 10)],
        ShapeStyle::from(RGBColor(215, 215, 215)).stroke_width(1),
    ))
    .ctx(kind)?;
    area.draw(&Text::new(
        text.to_string(),
        (w / 2, h / 2),
        font(20.0)
            .color(&NOTE)
            .pos(Pos::new(HPos::Center, VPos::Center)),
    ))
    .ctx(kind)?;
    Ok(())
}

/// Converts an absolute backend coordinate (e.g. from `ChartContext::backend_coord`) into
/// coordinates relative to `area`.
pub(crate) fn relative<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    abs: (i32, i32),
) -> (i32, i32) {
    let (bx, by) = area.get_base_pixel();
    (abs.0 - bx, abs.1 - by)
}

/// Draws `text` anchored by `(h, v)` at `pos` (relative to `area`).
pub(crate) fn text_at<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    pos: (i32, i32),
    size: f64,
    color: RGBColor,
    anchor: (HPos, VPos),
    kind: &'static str,
) -> Result<()> {
    area.draw(&Text::new(
        text.to_string(),
        pos,
        font(size).color(&color).pos(Pos::new(anchor.0, anchor.1)),
    ))
    .ctx(kind)?;
    Ok(())
}
