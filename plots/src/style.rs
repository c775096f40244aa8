//! Shared look of every figure: the bundled font, the palette, text sizes, the legend band,
//! markers, and the data-cleaning helpers (NaN-safe ranges, segments, decimation).

use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::{ComposedElement, EmptyElement, PathElement, Polygon};
use plotters::prelude::*;
use plotters::style::{FontFamily, FontStyle, RGBColor, ShapeStyle, TextStyle};

use crate::error::{DrawResultExt, Error, Result};

/// DejaVu Sans (Bitstream Vera licence, see `plots/assets/DejaVu-LICENSE.txt`).
pub(crate) static DEJAVU_SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
/// DejaVu Sans Bold (same licence).
pub(crate) static DEJAVU_SANS_BOLD: &[u8] = include_bytes!("../assets/DejaVuSans-Bold.ttf");

static FONT_ONCE: Once = Once::new();
static FONT_OK: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);

/// Registers the bundled DejaVu Sans (normal and bold) as plotters' `"sans-serif"` family,
/// once per process. No system font is ever looked up.
///
/// # Errors
/// [`Error::Font`] if the bundled bytes are not a valid font (cannot happen with the
/// committed assets unless they are corrupted).
pub fn ensure_fonts() -> Result<()> {
    use std::sync::atomic::Ordering;
    FONT_ONCE.call_once(|| {
        let normal = plotters::style::register_font("sans-serif", FontStyle::Normal, DEJAVU_SANS);
        let bold = plotters::style::register_font("sans-serif", FontStyle::Bold, DEJAVU_SANS_BOLD);
        let code = match (normal.is_ok(), bold.is_ok()) {
            (true, true) => 1,
            (false, _) => 2,
            (true, false) => 3,
        };
        FONT_OK.store(code, Ordering::SeqCst);
    });
    match FONT_OK.load(Ordering::SeqCst) {
        1 => Ok(()),
        3 => Err(Error::Font {
            name: "DejaVuSans-Bold.ttf",
        }),
        _ => Err(Error::Font {
            name: "DejaVuSans.ttf",
        }),
    }
}

/// Okabe–Ito colour-blind-safe palette, in the order series are coloured.
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
    RGBColor(240, 228, 66),  // yellow (last: poor on white)
];

/// Colour of measured data (solid line).
pub const MEASURED: RGBColor = PALETTE[0];
/// Colour of model output (dashed line).
pub const MODEL: RGBColor = PALETTE[1];
/// Colour of reference curves (closed forms, e.g. the flat plate).
pub const REFERENCE: RGBColor = RGBColor(40, 40, 40);
/// Colour of annotations (markers of key frequencies, selected δ, flutter point).
pub const ANNOTATION: RGBColor = RGBColor(120, 120, 120);
/// Colour of highlighted annotations (flutter point, selected δ).
pub const HIGHLIGHT: RGBColor = RGBColor(200, 0, 0);
/// Grey of inactive heat-map cells.
pub const INACTIVE: RGBColor = RGBColor(200, 200, 200);

/// Series colour `i` (cycles through the first seven entries of [`PALETTE`]).
pub fn series_color(i: usize) -> RGBColor {
    PALETTE[i % 7]
}

/// Title text size \[px\].
pub const TITLE_SIZE: f64 = 30.0;
/// Panel title text size \[px\].
pub const PANEL_TITLE_SIZE: f64 = 22.0;
/// Axis description text size \[px\].
pub const AXIS_SIZE: f64 = 21.0;
/// Tick label text size \[px\].
pub const TICK_SIZE: f64 = 17.0;
/// Legend text size \[px\].
pub const LEGEND_SIZE: f64 = 19.0;

/// Regular text style of `size` px in the bundled font.
pub fn font(size: f64) -> TextStyle<'static> {
    TextStyle::from(("sans-serif", size).into_font()).color(&BLACK)
}

/// Bold text style of `size` px in the bundled font.
pub fn bold(size: f64) -> TextStyle<'static> {
    TextStyle::from(FontDesc::new(FontFamily::SansSerif, size, FontStyle::Bold)).color(&BLACK)
}

/// Draws the figure title at the top of `root` and returns the area below it.
pub(crate) fn title<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    text: &str,
    kind: &'static str,
) -> Result<DrawingArea<DB, Shift>> {
    if crate::scaled::figure_style() == crate::scaled::FigureStyle::Paper {
        // the caption carries the title in a paper
        return Ok(root.margin(12, 0, 0, 0));
    }
    root.margin(12, 0, 0, 0)
        .titled(text, bold(TITLE_SIZE))
        .ctx(kind)
}

/// Paper style only ([`crate::FigureStyle::Paper`]): draws the panel letter "(a)", "(b)" …
/// (`index` 0, 1 …) in bold at the top-left corner of the panel `cell`, for captions to
/// refer to. The screen style names panels by their titles and draws nothing here.
///
/// # Errors
/// [`Error::Drawing`] naming `kind` if the backend fails.
pub(crate) fn panel_letter<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    index: usize,
    kind: &'static str,
) -> Result<()> {
    if crate::scaled::figure_style() != crate::scaled::FigureStyle::Paper {
        return Ok(());
    }
    let letter = char::from(b'a' + (index % 26) as u8);
    cell.draw_text(&format!("({letter})"), &bold(PANEL_TITLE_SIZE), (4, 2))
        .ctx(kind)
}

/// Marker shapes; the same shape is drawn in the chart and in the legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarkerShape {
    /// Circle.
    Circle,
    /// Square.
    Square,
    /// Triangle pointing up.
    TriangleUp,
    /// Triangle pointing down.
    TriangleDown,
    /// Diamond.
    Diamond,
    /// Diagonal cross (×).
    Cross,
}

impl MarkerShape {
    /// Shape `i` of a fixed sequence, to tell series apart without colour.
    pub fn nth(i: usize) -> Self {
        [
            MarkerShape::Circle,
            MarkerShape::Square,
            MarkerShape::TriangleUp,
            MarkerShape::Diamond,
            MarkerShape::TriangleDown,
            MarkerShape::Cross,
        ][i % 6]
    }

    /// Outline of the shape, centred on (0, 0), of half-size `r` pixels.
    fn outline(self, r: i32) -> Vec<(i32, i32)> {
        match self {
            MarkerShape::Circle => (0..16)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 16.0;
                    (
                        (r as f64 * a.cos()).round() as i32,
                        (r as f64 * a.sin()).round() as i32,
                    )
                })
                .collect(),
            MarkerShape::Square => {
                let s = (r as f64 * 0.85).round() as i32;
                vec![(-s, -s), (s, -s), (s, s), (-s, s)]
            }
            MarkerShape::TriangleUp => vec![(0, -r - 1), (r + 1, r - 1), (-r - 1, r - 1)],
            MarkerShape::TriangleDown => vec![(0, r + 1), (r + 1, -r + 1), (-r - 1, -r + 1)],
            MarkerShape::Diamond => vec![(0, -r - 1), (r, 0), (0, r + 1), (-r, 0)],
            MarkerShape::Cross => {
                let w = (r / 3).max(1);
                vec![
                    (-r, -r + w),
                    (-r + w, -r),
                    (0, -w),
                    (r - w, -r),
                    (r, -r + w),
                    (w, 0),
                    (r, r - w),
                    (r - w, r),
                    (0, w),
                    (-r + w, r),
                    (-r, r - w),
                    (-w, 0),
                ]
            }
        }
    }
}

/// Concrete type of a marker element (fill polygon + outline path) anchored at a `C` coordinate.
pub(crate) type MarkerElement<C, DB> =
    ComposedElement<C, DB, Polygon<(i32, i32)>, PathElement<(i32, i32)>>;

/// A marker at data coordinate `c`: filled with `color`, or hollow (white fill, coloured
/// outline). Crosses are always filled.
pub(crate) fn marker<C: Clone, DB: DrawingBackend>(
    c: C,
    shape: MarkerShape,
    color: RGBColor,
    filled: bool,
    r: i32,
) -> MarkerElement<C, DB> {
    let pts = shape.outline(r);
    let fill = if filled || shape == MarkerShape::Cross {
        color.filled()
    } else {
        WHITE.filled()
    };
    let mut closed = pts.clone();
    closed.push(pts[0]);
    EmptyElement::at(c)
        + Polygon::new(pts, fill)
        + PathElement::new(
            closed,
            ShapeStyle::from(color).stroke_width(if filled { 1 } else { 2 }),
        )
}

/// What a legend entry shows next to its label.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Glyph {
    /// A line segment, solid or dashed.
    Line {
        /// Colour.
        color: RGBColor,
        /// Stroke width \[px\].
        width: u32,
        /// Dashed.
        dashed: bool,
    },
    /// A marker.
    Marker {
        /// Shape.
        shape: MarkerShape,
        /// Colour.
        color: RGBColor,
        /// Filled or hollow.
        filled: bool,
    },
    /// A filled rectangle (histogram bars, inactive cells).
    Patch {
        /// Colour.
        color: RGBColor,
    },
    /// A vertical error bar with caps (an interval).
    ErrorBar {
        /// Colour.
        color: RGBColor,
    },
}

/// One legend entry.
#[derive(Debug, Clone)]
pub(crate) struct LegendEntry {
    /// Text.
    pub label: String,
    /// Glyph before the text.
    pub glyph: Glyph,
}

impl LegendEntry {
    pub(crate) fn line(label: impl Into<String>, color: RGBColor, dashed: bool) -> Self {
        LegendEntry {
            label: label.into(),
            glyph: Glyph::Line {
                color,
                width: 3,
                dashed,
            },
        }
    }
    pub(crate) fn marker(
        label: impl Into<String>,
        shape: MarkerShape,
        color: RGBColor,
        filled: bool,
    ) -> Self {
        LegendEntry {
            label: label.into(),
            glyph: Glyph::Marker {
                shape,
                color,
                filled,
            },
        }
    }
    pub(crate) fn patch(label: impl Into<String>, color: RGBColor) -> Self {
        LegendEntry {
            label: label.into(),
            glyph: Glyph::Patch { color },
        }
    }
    pub(crate) fn error_bar(label: impl Into<String>, color: RGBColor) -> Self {
        LegendEntry {
            label: label.into(),
            glyph: Glyph::ErrorBar { color },
        }
    }
}

/// Half length of an error bar's cap \[px\].
pub(crate) const CAP_PX: i32 = 7;

/// Draws an interval as an error bar with caps on `chart`, in data coordinates: vertical at
/// `x` from `lo` to `hi` (`vertical`), or horizontal at height `x` from `lo` to `hi`.
///
/// # Errors
/// [`Error::Draw`]-type errors of the backend, tagged with `kind`.
pub(crate) fn draw_error_bar<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    (x, lo, hi): (f64, f64, f64),
    vertical: bool,
    color: RGBColor,
    kind: &'static str,
) -> Result<()> {
    let style = ShapeStyle::from(color).stroke_width(2);
    let at = |v: f64| if vertical { (x, v) } else { (v, x) };
    let cap = if vertical {
        vec![(-CAP_PX, 0), (CAP_PX, 0)]
    } else {
        vec![(0, -CAP_PX), (0, CAP_PX)]
    };
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![at(lo), at(hi)],
            style,
        )))
        .ctx(kind)?;
    chart
        .draw_series(
            [lo, hi]
                .into_iter()
                .map(|v| EmptyElement::at(at(v)) + PathElement::new(cap.clone(), style)),
        )
        .ctx(kind)?;
    Ok(())
}

const GLYPH_W: i32 = 40;
const ROW_H: i32 = 30;

/// Lays out `entries` in rows that fit `area`'s width; returns (rows of entry indices with
/// their widths).
fn legend_rows<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    kind: &'static str,
) -> Result<Vec<Vec<(usize, i32)>>> {
    let width = area.dim_in_pixel().0 as i32 - 40;
    let style = font(LEGEND_SIZE);
    let mut rows: Vec<Vec<(usize, i32)>> = vec![vec![]];
    let mut used = 0;
    for (i, e) in entries.iter().enumerate() {
        let (tw, _) = area.estimate_text_size(&e.label, &style).ctx(kind)?;
        let w = GLYPH_W + 8 + tw as i32 + 28;
        if used + w > width && !rows.last().is_some_and(|r| r.is_empty()) {
            rows.push(vec![]);
            used = 0;
        }
        rows.last_mut().expect("non-empty").push((i, w));
        used += w;
    }
    Ok(rows)
}

/// Splits a legend band off the top of `area`, draws `entries` in it (centred rows, wrapped
/// to the width), and returns the area below. No entries → `area` unchanged.
pub(crate) fn legend_band<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    kind: &'static str,
) -> Result<DrawingArea<DB, Shift>> {
    if entries.is_empty() {
        return Ok(area.clone());
    }
    let rows = legend_rows(area, entries, kind)?;
    let h = rows.len() as i32 * ROW_H + 8;
    let (band, rest) = area.split_vertically(h);
    let width = band.dim_in_pixel().0 as i32;
    let style = font(LEGEND_SIZE);
    for (r, row) in rows.iter().enumerate() {
        let total: i32 = row.iter().map(|(_, w)| w).sum();
        let mut x = (width - total) / 2;
        let yc = r as i32 * ROW_H + ROW_H / 2 + 4;
        for &(i, w) in row {
            let e = &entries[i];
            draw_glyph(&band, e.glyph, x, yc, kind)?;
            band.draw(&Text::new(
                e.label.clone(),
                (x + GLYPH_W + 8, yc),
                style.pos(plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Left,
                    plotters::style::text_anchor::VPos::Center,
                )),
            ))
            .ctx(kind)?;
            x += w;
        }
    }
    Ok(rest)
}

fn draw_glyph<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    glyph: Glyph,
    x: i32,
    yc: i32,
    kind: &'static str,
) -> Result<()> {
    match glyph {
        Glyph::Line {
            color,
            width,
            dashed,
        } => {
            let style = ShapeStyle::from(color).stroke_width(width);
            if dashed {
                for k in 0..3 {
                    let x0 = x + k * 14;
                    area.draw(&PathElement::new(vec![(x0, yc), (x0 + 9, yc)], style))
                        .ctx(kind)?;
                }
            } else {
                area.draw(&PathElement::new(vec![(x, yc), (x + GLYPH_W, yc)], style))
                    .ctx(kind)?;
            }
        }
        Glyph::Marker {
            shape,
            color,
            filled,
        } => {
            area.draw(&marker::<_, DB>(
                (x + GLYPH_W / 2, yc),
                shape,
                color,
                filled,
                7,
            ))
            .ctx(kind)?;
        }
        Glyph::ErrorBar { color } => {
            let style = ShapeStyle::from(color).stroke_width(2);
            let xc = x + GLYPH_W / 2;
            for path in [
                vec![(xc, yc - 11), (xc, yc + 11)],
                vec![(xc - CAP_PX, yc - 11), (xc + CAP_PX, yc - 11)],
                vec![(xc - CAP_PX, yc + 11), (xc + CAP_PX, yc + 11)],
            ] {
                area.draw(&PathElement::new(path, style)).ctx(kind)?;
            }
        }
        Glyph::Patch { color } => {
            area.draw(&Rectangle::new(
                [(x + 6, yc - 9), (x + GLYPH_W - 6, yc + 9)],
                color.filled(),
            ))
            .ctx(kind)?;
            area.draw(&Rectangle::new(
                [(x + 6, yc - 9), (x + GLYPH_W - 6, yc + 9)],
                ShapeStyle::from(BLACK.mix(0.5)).stroke_width(1),
            ))
            .ctx(kind)?;
        }
    }
    Ok(())
}

/// Checks that `a` and `b` pair up element by element.
///
/// # Errors
/// [`Error::LengthMismatch`] naming `field`.
pub(crate) fn check_len(kind: &'static str, field: &str, a: usize, b: usize) -> Result<()> {
    if a != b {
        return Err(Error::LengthMismatch {
            figure: kind,
            field: field.to_string(),
            left: a,
            right: b,
        });
    }
    Ok(())
}

/// Splits (x, y) pairs into runs of finite points: a non-finite x or y ends a run (so a line
/// is never drawn across a gap).
pub(crate) fn segments(x: &[f64], y: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let mut out = vec![];
    let mut cur = vec![];
    for (&a, &b) in x.iter().zip(y) {
        if a.is_finite() && b.is_finite() {
            cur.push((a, b));
        } else if !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Smallest and largest finite value, `None` if there is none.
pub(crate) fn finite_range(values: impl IntoIterator<Item = f64>) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in values {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// `(lo, hi)` widened by `frac` of its span on both sides; a zero span becomes ±(10 % of |lo|
/// or 1).
pub(crate) fn padded((lo, hi): (f64, f64), frac: f64) -> (f64, f64) {
    let span = hi - lo;
    if span > 0.0 && span.is_finite() {
        (lo - frac * span, hi + frac * span)
    } else {
        let d = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
        (lo - d, hi + d)
    }
}

/// Positive range for a logarithmic axis from the finite positive values: widened by a
/// factor `pad` on both sides; a single value spans one decade around it.
pub(crate) fn log_range(values: impl IntoIterator<Item = f64>, pad: f64) -> Option<(f64, f64)> {
    let (lo, hi) = finite_range(values.into_iter().filter(|v| *v > 0.0))?;
    if hi > lo {
        Some((lo / pad, hi * pad))
    } else {
        Some((lo / 10f64.sqrt(), hi * 10f64.sqrt()))
    }
}

/// Min–max decimation: keeps at most about `max_points` points of a polyline (sorted or not
/// in x), preserving the minimum and maximum of each bucket so peaks stay visible.
pub(crate) fn decimate(points: &[(f64, f64)], max_points: usize) -> Vec<(f64, f64)> {
    if points.len() <= max_points || max_points < 4 {
        return points.to_vec();
    }
    let buckets = max_points / 2;
    let per = points.len().div_ceil(buckets);
    let mut out = Vec::with_capacity(2 * buckets + 2);
    for chunk in points.chunks(per) {
        let (mut imin, mut imax) = (0, 0);
        for (i, p) in chunk.iter().enumerate() {
            if p.1 < chunk[imin].1 {
                imin = i;
            }
            if p.1 > chunk[imax].1 {
                imax = i;
            }
        }
        let (a, b) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        out.push(chunk[a]);
        if b != a {
            out.push(chunk[b]);
        }
    }
    out
}

/// Tick formatter for an axis spanning `span`: values closer to zero than 1e-9·span print
/// as "0" (plotters' ticks carry round-off like -1.11e-16), others as [`fmt_num`].
pub(crate) fn fmt_tick(span: f64) -> impl Fn(&f64) -> String {
    move |v: &f64| {
        if v.abs() <= 1e-9 * span.abs() {
            "0".to_string()
        } else {
            fmt_num(*v)
        }
    }
}

/// Formats a tick value compactly: up to 4 significant digits, no trailing zeros,
/// scientific notation outside [1e-3, 1e5).
pub(crate) fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.2e}");
        // 1.00e3 → 1e3
        if let Some((m, e)) = s.split_once('e') {
            let m = m.trim_end_matches('0').trim_end_matches('.');
            return format!("{m}e{e}");
        }
        return s;
    }
    let digits = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_break_at_nan() {
        let x = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [1.0, f64::NAN, 2.0, 3.0, f64::INFINITY];
        let s = segments(&x, &y);
        assert_eq!(s, vec![vec![(0.0, 1.0)], vec![(2.0, 2.0), (3.0, 3.0)]]);
    }

    #[test]
    fn padded_handles_zero_span() {
        assert_eq!(padded((0.0, 0.0), 0.05), (-1.0, 1.0));
        let (lo, hi) = padded((2.0, 2.0), 0.05);
        assert!(lo < 2.0 && hi > 2.0);
        assert_eq!(padded((0.0, 10.0), 0.1), (-1.0, 11.0));
    }

    #[test]
    fn decimate_keeps_extremes() {
        let pts: Vec<(f64, f64)> = (0..10_000)
            .map(|i| (i as f64, if i == 4321 { 100.0 } else { (i as f64).sin() }))
            .collect();
        let d = decimate(&pts, 1000);
        assert!(d.len() <= 1002, "{}", d.len());
        assert!(d.iter().any(|p| p.1 == 100.0), "spike survives");
        assert!(d.windows(2).all(|w| w[0].0 < w[1].0), "order kept");
    }

    #[test]
    fn fmt_num_is_compact() {
        assert_eq!(fmt_num(0.5), "0.5");
        assert_eq!(fmt_num(12.0), "12");
        assert_eq!(fmt_num(1e-5), "1e-5");
        assert_eq!(fmt_num(-2.25), "-2.25");
    }

    #[test]
    fn fonts_register_once() {
        ensure_fonts().unwrap();
        ensure_fonts().unwrap();
    }
}
