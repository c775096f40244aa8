//! Figure 5: histograms of per-case metrics (R², MFWA), side by side, median marked.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    finite_range, fmt_num, fmt_tick, font, legend_band, padded, title, LegendEntry, HIGHLIGHT,
    PANEL_TITLE_SIZE,
};

/// One histogram: the values over cases (non-finite values are skipped and counted).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HistogramPanel {
    /// x-axis description, e.g. `"R² [-]"`, `"MFWA [-]"`.
    pub x_label: String,
    /// One value per case.
    pub values: Vec<f64>,
    /// Number of bins (≥ 1).
    pub bins: usize,
    /// Bin range (lo, hi); `None`: the finite data range. Values outside are counted in
    /// the panel title, not drawn.
    pub range: Option<(f64, f64)>,
}

/// Histograms side by side (e.g. R² and MFWA over all cases).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HistogramFigure {
    /// Figure title.
    pub title: String,
    /// Panels from left to right.
    pub panels: Vec<HistogramPanel>,
}

/// Bar colour: palette blue at 75 % on white (opaque, so PNG and SVG agree).
const BAR: RGBColor = RGBColor(64, 149, 197);

impl Figure for HistogramFigure {
    const KIND: &'static str = "histogram";

    fn size(&self) -> (u32, u32) {
        ((600 * self.panels.len().max(1) as u32).max(900), 650)
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
        let mut prepared = vec![];
        for (p, panel) in self.panels.iter().enumerate() {
            if panel.bins == 0 {
                return Err(Error::InvalidInput {
                    figure: kind,
                    field: format!("panels[{p}].bins"),
                    message: "must be at least 1, got 0".into(),
                });
            }
            let finite: Vec<f64> = panel
                .values
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            if finite.is_empty() {
                return Err(Error::NoData {
                    figure: kind,
                    field: format!("panels[{p}].values \"{}\"", panel.x_label),
                    len: panel.values.len(),
                });
            }
            let (lo, hi) = match panel.range {
                Some((lo, hi)) if lo.is_finite() && hi.is_finite() && hi > lo => (lo, hi),
                Some((lo, hi)) => {
                    return Err(Error::InvalidInput {
                        figure: kind,
                        field: format!("panels[{p}].range"),
                        message: format!("need finite lo < hi, got ({lo}, {hi})"),
                    })
                }
                None => {
                    let r = finite_range(finite.iter().copied()).expect("non-empty");
                    if r.1 > r.0 {
                        r
                    } else {
                        padded(r, 0.0)
                    }
                }
            };
            let w = (hi - lo) / panel.bins as f64;
            let mut counts = vec![0usize; panel.bins];
            let mut outside = 0;
            for &v in &finite {
                if v < lo || v > hi {
                    outside += 1;
                } else {
                    let b = (((v - lo) / w) as usize).min(panel.bins - 1);
                    counts[b] += 1;
                }
            }
            let skipped = panel.values.len() - finite.len();
            let mut sorted = finite.clone();
            let med = identify::numerics::median(&mut sorted);
            prepared.push((lo, hi, w, counts, outside, skipped, med, finite.len()));
        }

        let area = title(root, &self.title, kind)?;
        let legend = [
            LegendEntry::patch("cases per bin", BAR),
            LegendEntry::line("median", HIGHLIGHT, true),
        ];
        let area = legend_band(&area, &legend, kind)?;
        let cells = area.split_evenly((1, self.panels.len()));
        let lettered = self.panels.len() > 1;
        for (i, (panel, (cell, prep))) in self
            .panels
            .iter()
            .zip(cells.iter().zip(&prepared))
            .enumerate()
        {
            if lettered {
                crate::style::panel_letter(cell, i, kind)?;
            }
            let (lo, hi, w, counts, outside, skipped, med, n) = prep;
            let mut head = format!("n = {n}, median = {}", fmt_num(*med));
            if *outside > 0 {
                head.push_str(&format!(", {outside} outside range"));
            }
            if *skipped > 0 {
                head.push_str(&format!(", {skipped} non-finite"));
            }
            let cell = cell
                .margin(6, 0, 0, 0)
                .titled(&head, font(PANEL_TITLE_SIZE - 2.0))
                .ctx(kind)?;
            let cmax = *counts.iter().max().unwrap_or(&1) as f64;
            let y1 = (cmax * 1.12).max(1.0);
            let mut chart = ChartBuilder::on(&cell)
                .margin_left(10)
                .margin_right(30)
                .margin_top(8)
                .x_label_area_size(60)
                .y_label_area_size(80)
                .build_cartesian_2d(*lo..*hi, 0.0..y1)
                .ctx(kind)?;
            let fx = fmt_tick(hi - lo);
            let fy = |v: &f64| {
                if (v - v.round()).abs() < 1e-9 {
                    format!("{}", v.round() as i64)
                } else {
                    String::new()
                }
            };
            mesh!(m = chart, panel.x_label.as_str(), "cases [-]");
            // Few x ticks: scientific-notation labels of narrow panels overlap otherwise.
            m.x_labels(5)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .draw()
                .ctx(kind)?;
            let fill = BAR.filled();
            chart
                .draw_series(
                    counts
                        .iter()
                        .enumerate()
                        .filter(|(_, c)| **c > 0)
                        .map(|(b, &c)| {
                            let x0 = lo + *w * b as f64;
                            Rectangle::new([(x0, 0.0), (x0 + *w, c as f64)], fill)
                        }),
                )
                .ctx(kind)?;
            chart
                .draw_series(
                    counts
                        .iter()
                        .enumerate()
                        .filter(|(_, c)| **c > 0)
                        .map(|(b, &c)| {
                            let x0 = lo + *w * b as f64;
                            Rectangle::new(
                                [(x0, 0.0), (x0 + *w, c as f64)],
                                ShapeStyle::from(WHITE).stroke_width(1),
                            )
                        }),
                )
                .ctx(kind)?;
            if *med >= *lo && *med <= *hi {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(*med, 0.0), (*med, y1)],
                        10,
                        6,
                        ShapeStyle::from(HIGHLIGHT).stroke_width(2),
                    ))
                    .ctx(kind)?;
            }
        }
        Ok(())
    }
}
