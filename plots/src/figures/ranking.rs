//! Diagnosis figures with horizontal bars: the candidate ranking (held-out gap after each
//! candidate against the baseline and the noise level) and the where-shares (one stacked
//! bar per split, shares summing to 1).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::diag_util::{no_data, relative, text_at, NOTE};
use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    bold, finite_range, fmt_num, fmt_tick, legend_band, series_color, title, LegendEntry,
    HIGHLIGHT, PANEL_TITLE_SIZE, TICK_SIZE,
};

/// One candidate's bar.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RankingBar {
    /// Candidate name (y-axis label).
    pub label: String,
    /// Held-out gap after the candidate (bar length); non-finite = no bar, `note` shown.
    pub value: f64,
    /// Significant improvement: drawn highlighted.
    pub highlight: bool,
    /// Short text drawn when there is no bar (e.g. `"not fitted"`).
    pub note: String,
}

/// One level's ranking.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RankingPanel {
    /// Panel title, e.g. `"aerodynamic level (forced records)"`.
    pub title: String,
    /// x-axis description, e.g. `"held-out gap after candidate [-]"`.
    pub x_label: String,
    /// Bars, top to bottom (best first).
    pub bars: Vec<RankingBar>,
    /// Baseline gap before any candidate (vertical dashed black line).
    pub baseline: Option<f64>,
    /// Noise-level gap (vertical dashed red line).
    pub noise_level: Option<f64>,
}

/// Candidate ranking, one panel per level, stacked vertically.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RankingFigure {
    /// Figure title.
    pub title: String,
    /// Panels, top to bottom. A panel without bars shows a "no candidates" note.
    pub panels: Vec<RankingPanel>,
    /// Legend of the highlighted and the other bars; empty: "significant" and "not
    /// significant".
    pub highlight_legend: Option<(String, String)>,
}

/// Bar colour of significant candidates.
const SIGNIFICANT: RGBColor = RGBColor(0, 158, 115);
/// Bar colour of the others.
const PLAIN: RGBColor = RGBColor(160, 178, 196);
const ROW: u32 = 44;
const LABEL_W: u32 = 230;

/// White box behind a 15 px left-anchored, vertically centred label at `pos`, so that
/// reference lines do not run through it.
fn backdrop<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    pos: (i32, i32),
    kind: &'static str,
) -> Result<()> {
    let (w, h) = area
        .estimate_text_size(text, &crate::style::font(15.0))
        .ctx(kind)?;
    let (w, h) = (w as i32, h as i32);
    area.draw(&Rectangle::new(
        [
            (pos.0 - 3, pos.1 - h / 2 - 2),
            (pos.0 + w + 3, pos.1 + h / 2 + 2),
        ],
        WHITE.filled(),
    ))
    .ctx(kind)?;
    Ok(())
}

fn panel_height(p: &RankingPanel) -> u32 {
    50 + 90 + ROW * p.bars.len().max(2) as u32
}

impl Figure for RankingFigure {
    const KIND: &'static str = "candidate_ranking";

    fn size(&self) -> (u32, u32) {
        let h: u32 = self.panels.iter().map(panel_height).sum();
        (1200, 130 + h.max(200))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        if self.panels.is_empty() {
            return Err(Error::NoData {
                figure: kind,
                field: "panels".into(),
                len: 0,
            });
        }
        let area = title(root, &self.title, kind)?;
        let (on, off) = self
            .highlight_legend
            .clone()
            .unwrap_or_else(|| ("significant".into(), "not significant".into()));
        let legend = [
            LegendEntry::patch(on, SIGNIFICANT),
            LegendEntry::patch(off, PLAIN),
            LegendEntry::line("baseline (before)", BLACK, true),
            LegendEntry::line("noise level", HIGHLIGHT, true),
        ];
        let mut rest = legend_band(&area, &legend, kind)?;
        let lettered = self.panels.len() > 1;
        for (i, panel) in self.panels.iter().enumerate() {
            let (cell, below) = rest.split_vertically(panel_height(panel));
            rest = below;
            if lettered {
                crate::style::panel_letter(&cell, i, kind)?;
            }
            let cell = cell
                .margin(8, 0, 0, 0)
                .titled(&panel.title, bold(PANEL_TITLE_SIZE))
                .ctx(kind)?;
            let base = panel.baseline.filter(|v| v.is_finite());
            let noise = panel.noise_level.filter(|v| v.is_finite());
            let hi = finite_range(
                panel
                    .bars
                    .iter()
                    .map(|b| b.value)
                    .chain(base)
                    .chain(noise)
                    .chain([0.0]),
            )
            .map_or(1.0, |r| r.1);
            if panel.bars.is_empty() {
                no_data(&cell, "no candidates scored at this level", kind)?;
                continue;
            }
            let x1 = if hi > 0.0 { hi * 1.15 } else { 1.0 };
            let n = panel.bars.len();
            let mut chart = ChartBuilder::on(&cell)
                .margin_left(10)
                .margin_right(40)
                .margin_top(4)
                .x_label_area_size(58)
                .y_label_area_size(LABEL_W)
                .build_cartesian_2d(0.0..x1, -(n as f64)..0.0)
                .ctx(kind)?;
            let fx = fmt_tick(x1);
            mesh!(m = chart, panel.x_label.as_str(), "");
            m.y_labels(0)
                .disable_y_mesh()
                .x_labels(8)
                .x_label_formatter(&fx)
                .draw()
                .ctx(kind)?;
            // Reference lines first: bars and their labels are drawn over them.
            for (v, c) in [(base, BLACK), (noise, HIGHLIGHT)] {
                if let Some(v) = v {
                    chart
                        .draw_series(DashedLineSeries::new(
                            vec![(v, -(n as f64)), (v, 0.0)],
                            8,
                            5,
                            ShapeStyle::from(c).stroke_width(2),
                        ))
                        .ctx(kind)?;
                }
            }
            for (i, b) in panel.bars.iter().enumerate() {
                let yc = -(i as f64) - 0.5;
                let (y0, y1) = (yc - 0.32, yc + 0.32);
                // Candidate name left of the axis.
                let (px, py) = relative(&cell, chart.backend_coord(&(0.0, yc)));
                text_at(
                    &cell,
                    &b.label,
                    (px - 10, py),
                    TICK_SIZE + 1.0,
                    RGBColor(0, 0, 0),
                    (HPos::Right, VPos::Center),
                    kind,
                )?;
                if b.value.is_finite() && b.value >= 0.0 {
                    let c = if b.highlight { SIGNIFICANT } else { PLAIN };
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            [(0.0, y0), (b.value, y1)],
                            c.filled(),
                        )))
                        .ctx(kind)?;
                    let (ex, ey) = relative(&cell, chart.backend_coord(&(b.value, yc)));
                    backdrop(&cell, &fmt_num(b.value), (ex + 6, ey), kind)?;
                    text_at(
                        &cell,
                        &fmt_num(b.value),
                        (ex + 6, ey),
                        15.0,
                        RGBColor(40, 40, 40),
                        (HPos::Left, VPos::Center),
                        kind,
                    )?;
                } else {
                    let note = if b.note.is_empty() {
                        "no value".to_string()
                    } else {
                        b.note.clone()
                    };
                    backdrop(&cell, &note, (px + 8, py), kind)?;
                    text_at(
                        &cell,
                        &note,
                        (px + 8, py),
                        15.0,
                        NOTE,
                        (HPos::Left, VPos::Center),
                        kind,
                    )?;
                }
            }
        }
        Ok(())
    }
}

/// One segment of a stacked share bar.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ShareSegment {
    /// Cell name, written inside the segment when it fits.
    pub label: String,
    /// Share in [0, 1]; non-finite or negative shares are skipped.
    pub share: f64,
}

/// One stacked bar (one split of the gap).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ShareBar {
    /// Split name (y-axis label), e.g. `"aerodynamic: channel"`.
    pub label: String,
    /// Segments, left to right.
    pub segments: Vec<ShareSegment>,
}

/// Where the gap lies: one horizontal stacked bar per split (0–100 %).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SharesFigure {
    /// Figure title.
    pub title: String,
    /// Bars, top to bottom.
    pub bars: Vec<ShareBar>,
}

impl Figure for SharesFigure {
    const KIND: &'static str = "where_shares";

    fn size(&self) -> (u32, u32) {
        (1300, 220 + 84 * self.bars.len().max(2) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        let area = title(root, &self.title, kind)?;
        let area = area.margin(10, 0, 0, 0);
        if self.bars.is_empty() {
            no_data(&area, "no where-split reported", kind)?;
            return Ok(());
        }
        let n = self.bars.len();
        let mut chart = ChartBuilder::on(&area)
            .margin_left(10)
            .margin_right(40)
            .margin_top(4)
            .x_label_area_size(58)
            .y_label_area_size(260)
            .build_cartesian_2d(0.0..100.0, -(n as f64)..0.0)
            .ctx(kind)?;
        let fx = |v: &f64| format!("{v:.0}");
        mesh!(m = chart, "share of the held-out gap [%]", "");
        m.y_labels(0)
            .disable_y_mesh()
            .x_labels(11)
            .x_label_formatter(&fx)
            .draw()
            .ctx(kind)?;
        for (i, b) in self.bars.iter().enumerate() {
            let yc = -(i as f64) - 0.5;
            let (y0, y1) = (yc - 0.22, yc + 0.34);
            let (px, py) = relative(&area, chart.backend_coord(&(0.0, (y0 + y1) / 2.0)));
            text_at(
                &area,
                &b.label,
                (px - 10, py),
                TICK_SIZE + 1.0,
                RGBColor(0, 0, 0),
                (HPos::Right, VPos::Center),
                kind,
            )?;
            let segs: Vec<&ShareSegment> = b
                .segments
                .iter()
                .filter(|s| s.share.is_finite() && s.share > 0.0)
                .collect();
            if segs.is_empty() {
                text_at(
                    &area,
                    "no data",
                    (px + 8, py),
                    15.0,
                    NOTE,
                    (HPos::Left, VPos::Center),
                    kind,
                )?;
                continue;
            }
            let mut x = 0.0;
            // Segments whose name does not fit inside: listed under the bar.
            let mut unnamed: Vec<String> = vec![];
            for (k, s) in segs.iter().enumerate() {
                let w = 100.0 * s.share;
                let x_end = (x + w).min(100.0);
                let c = if k == segs.len() - 1 && s.label.starts_with("other") {
                    RGBColor(190, 190, 190)
                } else {
                    series_color(k)
                };
                chart
                    .draw_series([
                        Rectangle::new([(x, y0), (x_end, y1)], c.filled()),
                        Rectangle::new(
                            [(x, y0), (x_end, y1)],
                            ShapeStyle::from(WHITE).stroke_width(2),
                        ),
                    ])
                    .ctx(kind)?;
                // Label inside when it fits: "name 62 %", else "62 %", else nothing.
                let ym = (y0 + y1) / 2.0;
                let (ax, ay) = relative(&area, chart.backend_coord(&(x, ym)));
                let (bx, _) = relative(&area, chart.backend_coord(&(x_end, ym)));
                let room = bx - ax - 8;
                let pct = format!("{:.0} %", 100.0 * s.share);
                let full = format!("{} {pct}", s.label);
                let style = crate::style::font(15.0);
                let fits = |t: &str| -> Result<bool> {
                    let (tw, _) = area.estimate_text_size(t, &style).ctx(kind)?;
                    Ok((tw as i32) <= room)
                };
                let text = if fits(&full)? {
                    Some(full)
                } else if fits(&pct)? {
                    unnamed.push(s.label.clone());
                    Some(pct)
                } else {
                    unnamed.push(format!("{} {pct}", s.label));
                    None
                };
                if let Some(t) = text {
                    let dark = (c.0 as u32 + c.1 as u32 + c.2 as u32) < 380;
                    text_at(
                        &area,
                        &t,
                        ((ax + bx) / 2, ay),
                        15.0,
                        if dark { WHITE } else { BLACK },
                        (HPos::Center, VPos::Center),
                        kind,
                    )?;
                }
                x = x_end;
            }
            if !unnamed.is_empty() {
                let (lx, ly) = relative(&area, chart.backend_coord(&(0.0, yc - 0.35)));
                let mut line = format!("left to right: {}", unnamed.join(", "));
                let room = relative(&area, chart.backend_coord(&(100.0, yc))).0 - lx;
                let style = crate::style::font(14.0);
                while line.chars().count() > 8
                    && area.estimate_text_size(&line, &style).ctx(kind)?.0 as i32 > room
                {
                    let keep = line.chars().count() - 2;
                    line = format!("{}…", line.chars().take(keep).collect::<String>());
                    line = line.replace("……", "…");
                }
                text_at(
                    &area,
                    &line,
                    (lx + 2, ly),
                    14.0,
                    NOTE,
                    (HPos::Left, VPos::Center),
                    kind,
                )?;
            }
        }
        Ok(())
    }
}
