//! Real subscripts in every text of a figure: a drawing backend that wraps PNG and SVG
//! backends and draws `C_L`, `ω_α`, `U_F` or `C_{L,max}` with the subscript smaller and
//! lowered, in titles, axis labels, legends and annotations alike (plotters has no rich
//! text of its own).
//!
//! Markup: `_{…}` makes everything inside the braces a subscript; `_x` makes the single
//! character `x` a subscript when `_` follows a letter and `x` is not followed by a letter
//! or digit, so machine names such as `time_cap` or `N1_lift` stay literal.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
};

/// Size of a subscript relative to the text.
const SUB_SCALE: f64 = 0.72;

/// One run of text: plain or subscript.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Run {
    /// The characters of the run.
    pub text: String,
    /// Drawn as a subscript.
    pub sub: bool,
}

/// Splits `text` into plain and subscript runs (module docs); `None` when there is no
/// subscript, so the caller can draw it unchanged.
pub(crate) fn parse(text: &str) -> Option<Vec<Run>> {
    let chars: Vec<char> = text.chars().collect();
    let mut runs: Vec<Run> = vec![];
    let mut plain = String::new();
    let mut any = false;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let prev_letter = i > 0 && chars[i - 1].is_alphabetic();
        if c == '_' && prev_letter && i + 1 < chars.len() {
            if chars[i + 1] == '{' {
                if let Some(close) = chars[i + 2..].iter().position(|&x| x == '}') {
                    let sub: String = chars[i + 2..i + 2 + close].iter().collect();
                    if !plain.is_empty() {
                        runs.push(Run {
                            text: std::mem::take(&mut plain),
                            sub: false,
                        });
                    }
                    runs.push(Run {
                        text: sub,
                        sub: true,
                    });
                    any = true;
                    i += close + 3;
                    continue;
                }
            } else {
                let x = chars[i + 1];
                let next_alnum = chars.get(i + 2).is_some_and(|n| n.is_alphanumeric());
                if !x.is_whitespace() && x != '_' && !next_alnum {
                    if !plain.is_empty() {
                        runs.push(Run {
                            text: std::mem::take(&mut plain),
                            sub: false,
                        });
                    }
                    runs.push(Run {
                        text: x.to_string(),
                        sub: true,
                    });
                    any = true;
                    i += 2;
                    continue;
                }
            }
        }
        plain.push(c);
        i += 1;
    }
    if !plain.is_empty() {
        runs.push(Run {
            text: plain,
            sub: false,
        });
    }
    any.then_some(runs)
}

/// A backend that draws subscripts (module docs) and otherwise forwards to `inner`; with a
/// scale other than 1 ([`RichBackend::scaled`]) the figure is laid out at its design size
/// and every coordinate, stroke width, radius and font size is multiplied by the scale on
/// the way to `inner` (the paper style of [`crate::scaled`]).
pub struct RichBackend<DB: DrawingBackend> {
    inner: DB,
    scale: f64,
    size: (u32, u32),
    miter_limit: Option<f64>,
}

/// SVG's default `stroke-miterlimit`: a join whose miter would reach farther than this many
/// half stroke widths from the joint is not mitred ([`RichBackend::with_miter_limit`]).
pub const SVG_MITER_LIMIT: f64 = 4.0;

/// `pts` cut into pieces at every joint sharper than `limit` allows (miter length ratio
/// 1/sin(θ/2) > `limit`, θ the angle between the two segments); neighbouring pieces share
/// the joint. Zero-length segments are dropped first.
pub(crate) fn split_sharp_joins(pts: &[BackendCoord], limit: f64) -> Vec<Vec<BackendCoord>> {
    let mut clean: Vec<BackendCoord> = Vec::with_capacity(pts.len());
    for &p in pts {
        if clean.last() != Some(&p) {
            clean.push(p);
        }
    }
    // 1/sin(θ/2) > limit  ⇔  cos θ > 1 − 2/limit²  (θ the interior angle at the joint)
    let cos_max = 1.0 - 2.0 / (limit * limit);
    let mut pieces = Vec::new();
    let mut current = Vec::new();
    for (i, &p) in clean.iter().enumerate() {
        current.push(p);
        if i == 0 || i + 1 == clean.len() {
            continue;
        }
        let (a, b) = (clean[i - 1], clean[i + 1]);
        let d1 = ((p.0 - a.0) as f64, (p.1 - a.1) as f64);
        let d2 = ((b.0 - p.0) as f64, (b.1 - p.1) as f64);
        let cos = -(d1.0 * d2.0 + d1.1 * d2.1) / (d1.0.hypot(d1.1) * d2.0.hypot(d2.1));
        if cos > cos_max {
            pieces.push(std::mem::replace(&mut current, vec![p]));
        }
    }
    if current.len() > 1 || pieces.is_empty() {
        pieces.push(current);
    }
    pieces
}

impl<DB: DrawingBackend> RichBackend<DB> {
    /// Wraps `inner` at its own size.
    pub fn new(inner: DB) -> Self {
        let size = inner.get_size();
        RichBackend {
            inner,
            scale: 1.0,
            size,
            miter_limit: None,
        }
    }

    /// Cuts every stroked path at joints sharper than `limit` (miter length over `limit`
    /// half stroke widths) before `inner` draws it. For the bitmap backend, whose thick lines are mitred without a limit
    /// (a noisy residual drew spikes far outside its panel); an SVG viewer applies
    /// [`SVG_MITER_LIMIT`] itself.
    pub fn with_miter_limit(mut self, limit: f64) -> Self {
        self.miter_limit = Some(limit);
        self
    }

    /// Lays out the design size `size` and draws it onto `inner`, `scale` times larger
    /// (`inner` should be `scale` × `size`).
    pub fn scaled(inner: DB, scale: f64, size: (u32, u32)) -> Self {
        RichBackend {
            inner,
            scale,
            size,
            miter_limit: None,
        }
    }

    fn p(&self, c: BackendCoord) -> BackendCoord {
        if self.scale == 1.0 {
            return c;
        }
        (
            (c.0 as f64 * self.scale).round() as i32,
            (c.1 as f64 * self.scale).round() as i32,
        )
    }

    fn style<'a, S: BackendStyle>(&self, inner: &'a S) -> ScaledStyle<'a, S> {
        ScaledStyle {
            inner,
            scale: self.scale,
        }
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
        if self.scale == 1.0 {
            return self.inner.stroke_width();
        }
        ((self.inner.stroke_width() as f64 * self.scale).round() as u32).max(1)
    }
}

/// The style of one run: `base` at `scale` × its size, anchored left in the text frame.
fn run_style<'a, S: BackendTextStyle>(base: &'a S, scale: f64, v: VPos) -> TextStyle<'a> {
    let c = base.color();
    let mut s = TextStyle::from((base.family(), base.size() * scale, base.style()))
        .transform(base.transform())
        .pos(Pos::new(HPos::Left, v));
    s.color = c;
    s
}

impl<DB: DrawingBackend> DrawingBackend for RichBackend<DB> {
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
        if self.scale == 1.0 {
            return self.inner.draw_pixel(point, color);
        }
        let (a, b) = (self.p(point), self.p((point.0 + 1, point.1 + 1)));
        self.inner.draw_rect(a, (b.0 - 1, b.1 - 1), &color, true)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let st = self.style(style);
        let (a, b) = (self.p(from), self.p(to));
        if self.scale != 1.0 && st.stroke_width() > 1 {
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
        let (a, b) = (self.p(upper_left), self.p(bottom_right));
        self.inner.draw_rect(a, b, &self.style(style), fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let pts: Vec<BackendCoord> = path.into_iter().map(|c| self.p(c)).collect();
        let style = self.style(style);
        match self.miter_limit {
            Some(limit) if style.stroke_width() > 1 => {
                for piece in split_sharp_joins(&pts, limit) {
                    self.inner.draw_path(piece, &style)?;
                }
                Ok(())
            }
            _ => self.inner.draw_path(pts, &style),
        }
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let r = (radius as f64 * self.scale).round() as u32;
        let c = self.p(center);
        self.inner.draw_circle(c, r, &self.style(style), fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let pts: Vec<BackendCoord> = vert.into_iter().map(|c| self.p(c)).collect();
        self.inner.fill_polygon(pts, style)
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

    fn draw_text<TStyle: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let runs = match parse(text) {
            Some(r) => r,
            None if self.scale == 1.0 => return self.inner.draw_text(text, style, pos),
            None => vec![Run {
                text: text.to_string(),
                sub: false,
            }],
        };
        let anchor = style.anchor();
        let size = style.size();
        // layout in design units, then scaled
        let mut widths = Vec::with_capacity(runs.len());
        for r in &runs {
            let s = run_style(style, if r.sub { SUB_SCALE } else { 1.0 }, anchor.v_pos);
            widths.push(self.inner.estimate_text_size(&r.text, &s)?.0 as i32);
        }
        let total: i32 = widths.iter().sum();
        let mut u = match anchor.h_pos {
            HPos::Left => 0,
            HPos::Center => -total / 2,
            HPos::Right => -total,
        };
        // how far a subscript's anchor point sits below the text's, in the text frame
        let drop = size
            * match anchor.v_pos {
                VPos::Top => 0.45,
                VPos::Center => 0.3,
                VPos::Bottom => 0.15,
            };
        let trans = style.transform();
        for (r, w) in runs.iter().zip(widths) {
            let rel = if r.sub { SUB_SCALE } else { 1.0 };
            let s = run_style(style, rel * self.scale, anchor.v_pos);
            let v = if r.sub { drop.round() as i32 } else { 0 };
            // leading spaces are skipped, not drawn: an SVG viewer collapses them
            // (xml:space), so the run starts where its first visible glyph belongs
            let shown = r.text.trim_start();
            let lead = if shown.len() < r.text.len() && !shown.is_empty() {
                let ds = run_style(style, rel, anchor.v_pos);
                w - self.inner.estimate_text_size(shown, &ds)?.0 as i32
            } else {
                0
            };
            let (dx, dy) = trans.transform(u + lead, v);
            let at = self.p((pos.0 + dx, pos.1 + dy));
            self.inner.draw_text(shown, &s, at)?;
            u += w;
        }
        Ok(())
    }

    fn estimate_text_size<TStyle: BackendTextStyle>(
        &self,
        text: &str,
        style: &TStyle,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        let Some(runs) = parse(text) else {
            return self.inner.estimate_text_size(text, style);
        };
        let (mut w, mut h) = (0, 0);
        for r in &runs {
            let s = run_style(
                style,
                if r.sub { SUB_SCALE } else { 1.0 },
                style.anchor().v_pos,
            );
            let (rw, rh) = self.inner.estimate_text_size(&r.text, &s)?;
            w += rw;
            h = h.max(rh);
        }
        Ok((w, h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zigzag sharper than the miter limit is cut at each sharp joint; a gentle bend and
    /// repeated points are not.
    #[test]
    fn sharp_joins_are_cut_and_gentle_ones_kept() {
        // noise-like zigzag: 10 px up, 1 px right, 10 px down (joint angle ≈ 11°)
        let zig = [(0, 0), (1, 10), (2, 0), (3, 10)];
        let pieces = split_sharp_joins(&zig, SVG_MITER_LIMIT);
        assert_eq!(
            pieces,
            vec![
                vec![(0, 0), (1, 10)],
                vec![(1, 10), (2, 0)],
                vec![(2, 0), (3, 10)]
            ]
        );
        // a right angle (miter ratio √2) and a straight run with a repeated point stay one
        let bend = [(0, 0), (10, 0), (10, 0), (20, 0), (20, 10)];
        assert_eq!(
            split_sharp_joins(&bend, SVG_MITER_LIMIT),
            vec![vec![(0, 0), (10, 0), (20, 0), (20, 10)]]
        );
        // the limit itself: 1/sin(θ/2) = 4 at θ ≈ 28.96°; 25° is cut, 35° is not
        let joint = |deg: f64| {
            let t = deg.to_radians();
            [
                (0, 0),
                (1000, 0),
                (1000 - (1000.0 * t.cos()) as i32, (1000.0 * t.sin()) as i32),
            ]
        };
        assert_eq!(split_sharp_joins(&joint(25.0), SVG_MITER_LIMIT).len(), 2);
        assert_eq!(split_sharp_joins(&joint(35.0), SVG_MITER_LIMIT).len(), 1);
        assert_eq!(
            split_sharp_joins(&[(3, 3)], SVG_MITER_LIMIT),
            vec![vec![(3, 3)]]
        );
    }

    fn shown(text: &str) -> Vec<(String, bool)> {
        parse(text)
            .unwrap_or_else(|| {
                vec![Run {
                    text: text.into(),
                    sub: false,
                }]
            })
            .into_iter()
            .map(|r| (r.text, r.sub))
            .collect()
    }

    #[test]
    fn subscripts_of_symbols_and_literal_machine_names() {
        assert_eq!(
            shown("C_L [-]"),
            vec![
                ("C".into(), false),
                ("L".into(), true),
                (" [-]".into(), false)
            ]
        );
        assert_eq!(
            shown("ω_F/ω_α"),
            vec![
                ("ω".into(), false),
                ("F".into(), true),
                ("/ω".into(), false),
                ("α".into(), true)
            ]
        );
        assert_eq!(
            shown("C_{L,max} = 0.8"),
            vec![
                ("C".into(), false),
                ("L,max".into(), true),
                (" = 0.8".into(), false)
            ]
        );
        for literal in [
            "time_cap",
            "N1_lift",
            "left_bound",
            "a_ b",
            "x_",
            "_x",
            "3_4",
        ] {
            assert!(parse(literal).is_none(), "{literal}");
        }
        // an unclosed brace stays literal
        assert!(parse("C_{L").is_none());
    }
}
