//! Diagnosis figure: held-out gap over wind speed × amplitude, one panel per configuration
//! and stage (before / after the best candidate). A cell is the case's gap divided by its
//! noise-level gap, coloured on a logarithmic diverging scale centred on 1 (= noise
//! level: white); one shared colour bar with the noise level marked.

use plotters::coord::ranged1d::SegmentValue;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::diag_util::{no_data, text_at};
use super::heatmap::diverging;
use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{bold, check_len, fmt_num, title, PANEL_TITLE_SIZE};

/// One panel: `values[iy][ix]` = gap / noise level at `y_values[iy]`, `x_values[ix]`;
/// `None` or a non-finite or non-positive value = no case there (light grey).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GapHeatmapPanel {
    /// Panel title, e.g. `"config B: before"`.
    pub title: String,
    /// Column values (pitch amplitude \[deg\]).
    pub x_values: Vec<f64>,
    /// Row values (wind speed \[m/s\]).
    pub y_values: Vec<f64>,
    /// Ratios gap / noise level \[-\], one row per y value.
    pub values: Vec<Vec<Option<f64>>>,
}

/// Grid of gap heat maps with one shared logarithmic colour scale.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GapHeatmapFigure {
    /// Figure title.
    pub title: String,
    /// x-axis description, e.g. `"amplitude [deg]"`.
    pub x_label: String,
    /// y-axis description, e.g. `"U [m/s]"`.
    pub y_label: String,
    /// Panels per row (typically 2: before, after); 0 is treated as 1.
    pub columns: usize,
    /// Panels, row by row. A panel without a positive finite value shows a "no data" note.
    pub panels: Vec<GapHeatmapPanel>,
}

const PANEL_W: u32 = 520;
const PANEL_H: u32 = 420;
const BAR_W: u32 = 190;
const EMPTY: RGBColor = RGBColor(235, 235, 235);

fn ratio(v: Option<f64>) -> Option<f64> {
    v.filter(|x| x.is_finite() && *x > 0.0)
}

/// Nice tick values (1-2-5 sequence) whose log10 lies within ±`l`.
fn log_ticks(l: f64) -> Vec<f64> {
    let mut out = vec![];
    for e in -6..=6 {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(e);
            if v.log10().abs() <= l + 1e-9 {
                out.push(v);
            }
        }
    }
    // Too many: keep powers of ten and 1.
    if out.len() > 9 {
        out.retain(|v: &f64| (v.log10() - v.log10().round()).abs() < 1e-9);
    }
    out
}

impl GapHeatmapFigure {
    fn ncols(&self) -> usize {
        self.columns.max(1).min(self.panels.len().max(1))
    }
}

impl Figure for GapHeatmapFigure {
    const KIND: &'static str = "gap_heatmap";

    fn size(&self) -> (u32, u32) {
        let nc = self.ncols();
        let nr = self.panels.len().max(1).div_ceil(nc);
        (nc as u32 * PANEL_W + BAR_W, 90 + nr as u32 * PANEL_H)
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
        for (p, panel) in self.panels.iter().enumerate() {
            for (field, v) in [("x_values", &panel.x_values), ("y_values", &panel.y_values)] {
                if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
                    return Err(Error::InvalidInput {
                        figure: kind,
                        field: format!("panels[{p}].{field}"),
                        message: format!("grid values must be finite, got {bad}"),
                    });
                }
            }
            check_len(
                kind,
                &format!("panels[{p}] \"{}\" rows/y_values", panel.title),
                panel.values.len(),
                panel.y_values.len(),
            )?;
            for (iy, row) in panel.values.iter().enumerate() {
                check_len(
                    kind,
                    &format!("panels[{p}] \"{}\" values[{iy}]/x_values", panel.title),
                    row.len(),
                    panel.x_values.len(),
                )?;
            }
        }
        // Shared scale: ±L decades around 1, at least a factor 3 either way.
        let l = self
            .panels
            .iter()
            .flat_map(|p| p.values.iter().flatten())
            .filter_map(|v| ratio(*v))
            .fold(3f64.log10(), |m, v| m.max(v.log10().abs()));

        let area = title(root, &self.title, kind)?;
        let (w, _) = area.dim_in_pixel();
        let (main, bar) = area.split_horizontally(w.saturating_sub(BAR_W));
        let nc = self.ncols();
        let nr = self.panels.len().div_ceil(nc);
        let cells = main.split_evenly((nr, nc));
        let lettered = self.panels.len() > 1;
        for (i, (panel, cell)) in self.panels.iter().zip(cells.iter()).enumerate() {
            if lettered {
                crate::style::panel_letter(cell, i, kind)?;
            }
            let cell = cell
                .margin(10, 0, 0, 0)
                .titled(&panel.title, bold(PANEL_TITLE_SIZE))
                .ctx(kind)?;
            let (nx, ny) = (panel.x_values.len(), panel.y_values.len());
            let has_data = panel.values.iter().flatten().any(|v| ratio(*v).is_some());
            if nx == 0 || ny == 0 || !has_data {
                no_data(&cell, "no data", kind)?;
                continue;
            }
            let xs = &panel.x_values;
            let ys = &panel.y_values;
            let fx = |v: &SegmentValue<usize>| match v {
                SegmentValue::CenterOf(i) if *i < nx => fmt_num(xs[*i]),
                _ => String::new(),
            };
            let fy = |v: &SegmentValue<usize>| match v {
                SegmentValue::CenterOf(i) if *i < ny => fmt_num(ys[*i]),
                _ => String::new(),
            };
            let mut chart = ChartBuilder::on(&cell)
                .margin(8)
                .margin_right(16)
                .x_label_area_size(58)
                .y_label_area_size(74)
                .build_cartesian_2d((0..nx - 1).into_segmented(), (0..ny - 1).into_segmented())
                .ctx(kind)?;
            mesh!(m = chart, self.x_label.as_str(), self.y_label.as_str());
            m.disable_mesh()
                .x_labels(nx)
                .y_labels(ny)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .draw()
                .ctx(kind)?;
            let mut rects = vec![];
            let mut labels = vec![];
            for (iy, row) in panel.values.iter().enumerate() {
                for (ix, v) in row.iter().enumerate() {
                    let corners = [
                        (SegmentValue::Exact(ix), SegmentValue::Exact(iy)),
                        (SegmentValue::Exact(ix + 1), SegmentValue::Exact(iy + 1)),
                    ];
                    let color = match ratio(*v) {
                        Some(r) => {
                            let t = r.log10() / l;
                            let text = if r < 9.95 {
                                format!("{r:.1}")
                            } else {
                                format!("{r:.0}")
                            };
                            let tc = if t.abs() > 0.55 { WHITE } else { BLACK };
                            labels.push((ix, iy, text, tc));
                            diverging(t)
                        }
                        None => EMPTY,
                    };
                    rects.push(Rectangle::new(corners.clone(), color.filled()));
                    rects.push(Rectangle::new(
                        corners,
                        ShapeStyle::from(WHITE).stroke_width(1),
                    ));
                }
            }
            chart.draw_series(rects).ctx(kind)?;
            // Cell values, only when the cells are large enough to hold them.
            let c0 = chart.backend_coord(&(SegmentValue::Exact(0), SegmentValue::Exact(0)));
            let c1 = chart.backend_coord(&(SegmentValue::Exact(1), SegmentValue::Exact(1)));
            let (cw, ch) = ((c1.0 - c0.0).abs(), (c1.1 - c0.1).abs());
            if cw >= 40 && ch >= 22 {
                let size = if cw >= 56 { 15.0 } else { 13.0 };
                chart
                    .draw_series(labels.into_iter().map(|(ix, iy, text, tc)| {
                        Text::new(
                            text,
                            (SegmentValue::CenterOf(ix), SegmentValue::CenterOf(iy)),
                            crate::style::font(size)
                                .color(if tc == WHITE { &WHITE } else { &BLACK })
                                .pos(plotters::style::text_anchor::Pos::new(
                                    HPos::Center,
                                    VPos::Center,
                                )),
                        )
                    }))
                    .ctx(kind)?;
            }
        }

        // Shared colour bar (log10 of the ratio), noise level marked at 1.
        let bar = bar
            .margin(10, 0, 0, 0)
            .titled("gap / noise", bold(19.0))
            .ctx(kind)?;
        let (bw, bh) = bar.dim_in_pixel();
        let top = 20;
        let bottom = (bh as i32 - 80).max(top + 60);
        let (x0, x1) = (20, 52);
        let steps = 96;
        let ypix = |lv: f64| {
            let u = (lv + l) / (2.0 * l);
            bottom - (u * (bottom - top) as f64).round() as i32
        };
        for k in 0..steps {
            let a = -l + 2.0 * l * k as f64 / steps as f64;
            let b = -l + 2.0 * l * (k + 1) as f64 / steps as f64;
            bar.draw(&Rectangle::new(
                [(x0, ypix(b)), (x1, ypix(a))],
                diverging((a + b) / (2.0 * l)).filled(),
            ))
            .ctx(kind)?;
        }
        bar.draw(&Rectangle::new(
            [(x0, top), (x1, bottom)],
            ShapeStyle::from(RGBColor(80, 80, 80)).stroke_width(1),
        ))
        .ctx(kind)?;
        for v in log_ticks(l) {
            let y = ypix(v.log10());
            bar.draw(&PathElement::new(
                vec![(x1, y), (x1 + 6, y)],
                ShapeStyle::from(RGBColor(80, 80, 80)).stroke_width(1),
            ))
            .ctx(kind)?;
            text_at(
                &bar,
                &fmt_num(v),
                (x1 + 10, y),
                15.0,
                RGBColor(0, 0, 0),
                (HPos::Left, VPos::Center),
                kind,
            )?;
        }
        let y1 = ypix(0.0);
        bar.draw(&PathElement::new(
            vec![(x0 - 6, y1), (x1 + 6, y1)],
            ShapeStyle::from(BLACK).stroke_width(3),
        ))
        .ctx(kind)?;
        let _ = bw;
        for (i, line) in ["1 = noise level", "grey: no case"].iter().enumerate() {
            text_at(
                &bar,
                line,
                (8, bottom + 24 + 22 * i as i32),
                15.0,
                RGBColor(40, 40, 40),
                (HPos::Left, VPos::Center),
                kind,
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_within_range_and_include_one() {
        let t = log_ticks(1.0);
        assert!(
            t.contains(&1.0) && t.contains(&10.0) && t.contains(&0.1),
            "{t:?}"
        );
        assert!(t.iter().all(|v| v.log10().abs() <= 1.0 + 1e-9));
        let wide = log_ticks(4.0);
        assert!(wide.len() <= 9, "{wide:?}");
        assert!(wide.contains(&1.0));
    }
}
