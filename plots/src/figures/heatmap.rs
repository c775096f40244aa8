//! Figure 4: multi-layer coefficient heat maps: for one configuration, one small heat map per
//! term over amplitude (x) × wind speed (y), each with its own diverging colour scale
//! (symmetric about zero) and colour bar; inactive cells grey.

use plotters::coord::ranged1d::SegmentValue;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    bold, check_len, fmt_num, legend_band, title, LegendEntry, INACTIVE, PANEL_TITLE_SIZE,
};

/// One term's coefficient over the grid: `values[iy][ix]` at `y_values[iy]`,
/// `x_values[ix]`. `None`, zero or non-finite = term inactive there (grey).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HeatmapPanel {
    /// Term name (panel title), e.g. `"A2*"` or `"α·ḣ/U"`.
    pub term: String,
    /// Coefficients, one row per y value, one column per x value.
    pub values: Vec<Vec<Option<f64>>>,
}

/// Grid of heat maps sharing the same axes (one configuration).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HeatmapGridFigure {
    /// Figure title.
    pub title: String,
    /// x-axis description, e.g. `"amplitude α₀ [deg]"`.
    pub x_label: String,
    /// y-axis description, e.g. `"U [m/s]"`.
    pub y_label: String,
    /// x grid values (columns), in the order of `values[iy]`.
    pub x_values: Vec<f64>,
    /// y grid values (rows), in the order of `values`.
    pub y_values: Vec<f64>,
    /// One panel per term.
    pub panels: Vec<HeatmapPanel>,
    /// Label of every colour bar, e.g. `"coefficient [-]"` (empty: none).
    pub value_label: String,
}

const PANEL_W: u32 = 400;
const PANEL_H: u32 = 380;
const BAR_W: u32 = 124;

fn columns(n: usize) -> usize {
    match n {
        0..=3 => n.max(1),
        4 => 2,
        5..=6 => 3,
        _ => 4,
    }
}

/// Diverging blue–white–red colour map; `t` in [-1, 1] (clamped), 0 = near-white.
pub fn diverging(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (-1.0, [33.0, 102.0, 172.0]),
        (-0.5, [146.0, 197.0, 222.0]),
        (0.0, [247.0, 247.0, 247.0]),
        (0.5, [244.0, 165.0, 130.0]),
        (1.0, [178.0, 24.0, 43.0]),
    ];
    let t = if t.is_finite() {
        t.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let k = STOPS
        .windows(2)
        .position(|w| t <= w[1].0)
        .unwrap_or(STOPS.len() - 2);
    let (t0, c0) = STOPS[k];
    let (t1, c1) = STOPS[k + 1];
    let u = (t - t0) / (t1 - t0);
    let c = |i: usize| (c0[i] + u * (c1[i] - c0[i])).round() as u8;
    RGBColor(c(0), c(1), c(2))
}

fn active(v: Option<f64>) -> Option<f64> {
    v.filter(|x| x.is_finite() && *x != 0.0)
}

impl Figure for HeatmapGridFigure {
    const KIND: &'static str = "heatmap_grid";

    fn size(&self) -> (u32, u32) {
        let n = self.panels.len().max(1);
        let nc = columns(n);
        let nr = n.div_ceil(nc);
        ((nc as u32 * PANEL_W).max(900), 130 + nr as u32 * PANEL_H)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        let (nx, ny) = (self.x_values.len(), self.y_values.len());
        for (field, len) in [
            ("panels", self.panels.len()),
            ("x_values", nx),
            ("y_values", ny),
        ] {
            if len == 0 {
                return Err(Error::NoData {
                    figure: kind,
                    field: field.into(),
                    len: 0,
                });
            }
        }
        for (field, v) in [("x_values", &self.x_values), ("y_values", &self.y_values)] {
            if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
                return Err(Error::InvalidInput {
                    figure: kind,
                    field: field.into(),
                    message: format!("grid values must be finite, got {bad}"),
                });
            }
        }
        for (p, panel) in self.panels.iter().enumerate() {
            check_len(
                kind,
                &format!("panels[{p}] \"{}\" rows/y_values", panel.term),
                panel.values.len(),
                ny,
            )?;
            for (iy, row) in panel.values.iter().enumerate() {
                check_len(
                    kind,
                    &format!("panels[{p}] \"{}\" values[{iy}]/x_values", panel.term),
                    row.len(),
                    nx,
                )?;
            }
        }

        let area = title(root, &self.title, kind)?;
        let legend = [LegendEntry::patch("inactive (term not selected)", INACTIVE)];
        let area = legend_band(&area, &legend, kind)?;
        let n = self.panels.len();
        let nc = columns(n);
        let nr = n.div_ceil(nc);
        let cells = area.split_evenly((nr, nc));
        let xs = &self.x_values;
        let ys = &self.y_values;
        let fx = |v: &SegmentValue<usize>| match v {
            SegmentValue::CenterOf(i) if *i < nx => fmt_num(xs[*i]),
            _ => String::new(),
        };
        let fy = |v: &SegmentValue<usize>| match v {
            SegmentValue::CenterOf(i) if *i < ny => fmt_num(ys[*i]),
            _ => String::new(),
        };
        let lettered = self.panels.len() > 1;
        for (i, (panel, cell)) in self.panels.iter().zip(cells.iter()).enumerate() {
            if lettered {
                crate::style::panel_letter(cell, i, kind)?;
            }
            let cell = cell
                .margin(14, 0, 0, 0)
                .titled(&panel.term, bold(PANEL_TITLE_SIZE))
                .ctx(kind)?;
            let w = cell.dim_in_pixel().0;
            let (main, bar) = cell.split_horizontally(w.saturating_sub(BAR_W));
            let vmax = panel
                .values
                .iter()
                .flatten()
                .filter_map(|v| active(*v))
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let vmax = if vmax > 0.0 { vmax } else { 1.0 };

            let mut chart = ChartBuilder::on(&main)
                .margin(6)
                .x_label_area_size(58)
                .y_label_area_size(68)
                .build_cartesian_2d((0..nx - 1).into_segmented(), (0..ny - 1).into_segmented())
                .ctx(kind)?;
            // The panels of a row share the wind-speed axis: its name only on the first
            // column, so that a colour bar's label never stands next to another y label.
            let y_label = if i % nc == 0 {
                self.y_label.as_str()
            } else {
                ""
            };
            mesh!(m = chart, self.x_label.as_str(), y_label);
            m.disable_mesh()
                .x_labels(nx)
                .y_labels(ny)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .label_style(crate::style::font(14.0))
                .axis_desc_style(crate::style::font(17.0))
                .draw()
                .ctx(kind)?;
            let mut rects = vec![];
            for (iy, row) in panel.values.iter().enumerate() {
                for (ix, v) in row.iter().enumerate() {
                    let color = match active(*v) {
                        Some(x) => diverging(x / vmax),
                        None => INACTIVE,
                    };
                    rects.push(Rectangle::new(
                        [
                            (SegmentValue::Exact(ix), SegmentValue::Exact(iy)),
                            (SegmentValue::Exact(ix + 1), SegmentValue::Exact(iy + 1)),
                        ],
                        color.filled(),
                    ));
                    rects.push(Rectangle::new(
                        [
                            (SegmentValue::Exact(ix), SegmentValue::Exact(iy)),
                            (SegmentValue::Exact(ix + 1), SegmentValue::Exact(iy + 1)),
                        ],
                        ShapeStyle::from(WHITE).stroke_width(1),
                    ));
                }
            }
            chart.draw_series(rects).ctx(kind)?;

            // Colour bar.
            let mut cb = ChartBuilder::on(&bar)
                .margin_top(6)
                .margin_bottom(64)
                .margin_left(8)
                .margin_right(4)
                .set_label_area_size(LabelAreaPosition::Right, 86)
                .build_cartesian_2d(0.0..1.0, -vmax..vmax)
                .ctx(kind)?;
            let fv = crate::style::fmt_tick(2.0 * vmax);
            cb.configure_mesh()
                .y_desc(self.value_label.as_str())
                .axis_desc_style(crate::style::font(14.0))
                .disable_mesh()
                .disable_x_axis()
                .y_labels(5)
                .y_label_formatter(&fv)
                .label_style(crate::style::font(13.0))
                .axis_style(RGBColor(80, 80, 80))
                .draw()
                .ctx(kind)?;
            let steps = 64;
            cb.draw_series((0..steps).map(|k| {
                let a = -vmax + 2.0 * vmax * k as f64 / steps as f64;
                let b = -vmax + 2.0 * vmax * (k + 1) as f64 / steps as f64;
                Rectangle::new(
                    [(0.0, a), (1.0, b)],
                    diverging((a + b) / (2.0 * vmax)).filled(),
                )
            }))
            .ctx(kind)?;
        }
        Ok(())
    }
}
