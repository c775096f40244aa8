//! Diagnosis figure: measured points against predicted curves, panels side by side (the
//! predicted vs measured bifurcation diagram: amplitude vs U and frequency vs U).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::diag_util::no_data;
use super::{draw_line, look_of, looks, mesh, Series};
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    check_len, finite_range, fmt_tick, legend_band, marker, padded, title, LegendEntry,
    MarkerShape, MEASURED,
};

/// One panel: measured points as filled markers, predictions as lines with hollow markers.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ComparisonPanel {
    /// y-axis description, e.g. `"pitch amplitude [deg]"`.
    pub y_label: String,
    /// Whether the y-axis range includes 0 (amplitudes: yes; frequencies: no).
    pub include_zero: bool,
    /// Measured points (label used in the legend); non-finite points are skipped.
    pub measured: Series,
    /// Predicted curves (drawn in x order; style from their [`crate::SeriesKind`]).
    pub predicted: Vec<Series>,
}

/// Measured vs predicted, panels side by side sharing the x-axis description.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ComparisonFigure {
    /// Figure title.
    pub title: String,
    /// x-axis description, e.g. `"U [m/s]"`.
    pub x_label: String,
    /// Panels, left to right; a panel with nothing finite shows a "no data" note.
    pub panels: Vec<ComparisonPanel>,
}

fn sorted_points(s: &Series) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> =
        s.x.iter()
            .zip(&s.y)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(&x, &y)| (x, y))
            .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p
}

impl Figure for ComparisonFigure {
    const KIND: &'static str = "measured_vs_predicted";

    fn size(&self) -> (u32, u32) {
        ((650 * self.panels.len().max(1) as u32).max(900), 720)
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
            for s in std::iter::once(&panel.measured).chain(&panel.predicted) {
                check_len(
                    kind,
                    &format!("panels[{p}] \"{}\" x/y", s.label),
                    s.x.len(),
                    s.y.len(),
                )?;
            }
        }
        let area = title(root, &self.title, kind)?;
        let (lk, lines) = looks(self.panels.iter().flat_map(|p| &p.predicted));
        let mut legend = vec![];
        if let Some(p) = self.panels.iter().find(|p| !p.measured.label.is_empty()) {
            legend.push(LegendEntry::marker(
                p.measured.label.clone(),
                MarkerShape::Circle,
                MEASURED,
                true,
            ));
        }
        legend.extend(lines);
        let area = legend_band(&area, &legend, kind)?;
        let cells = area.split_evenly((1, self.panels.len()));
        let lettered = self.panels.len() > 1;
        for (i, (panel, cell)) in self.panels.iter().zip(cells.iter()).enumerate() {
            if lettered {
                crate::style::panel_letter(cell, i, kind)?;
            }
            let meas = sorted_points(&panel.measured);
            let preds: Vec<(&Series, Vec<(f64, f64)>)> = panel
                .predicted
                .iter()
                .map(|s| (s, sorted_points(s)))
                .collect();
            let all = || meas.iter().chain(preds.iter().flat_map(|(_, p)| p));
            let (Some(xr), Some(yr)) = (
                finite_range(all().map(|p| p.0)),
                finite_range(all().map(|p| p.1).chain(panel.include_zero.then_some(0.0))),
            ) else {
                no_data(&cell.margin(8, 0, 0, 0), "no data", kind)?;
                continue;
            };
            let (x0, x1) = padded(xr, 0.05);
            let (y0, y1) = padded(yr, 0.06);
            let mut chart = ChartBuilder::on(cell)
                .margin_left(8)
                .margin_right(28)
                .margin_top(14)
                .x_label_area_size(58)
                .y_label_area_size(86)
                .build_cartesian_2d(x0..x1, y0..y1)
                .ctx(kind)?;
            let fx = fmt_tick(x1 - x0);
            let fy = fmt_tick(y1 - y0);
            mesh!(m = chart, self.x_label.as_str(), panel.y_label.as_str());
            m.x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .draw()
                .ctx(kind)?;
            for (k, (s, p)) in preds.iter().enumerate() {
                let look = look_of(&lk, &s.label);
                draw_line!(chart, p.clone(), look, kind);
                let shape = MarkerShape::nth(k + 1);
                chart
                    .draw_series(
                        p.iter()
                            .map(|&c| marker::<_, DB>(c, shape, look.color, false, 5)),
                    )
                    .ctx(kind)?;
            }
            chart
                .draw_series(
                    meas.iter()
                        .map(|&c| marker::<_, DB>(c, MarkerShape::Circle, MEASURED, true, 7)),
                )
                .ctx(kind)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SeriesKind;

    #[test]
    fn sorted_points_drop_non_finite_and_sort_by_x() {
        let s = Series::new(
            "m",
            SeriesKind::Measured,
            vec![3.0, f64::NAN, 1.0, 2.0],
            vec![30.0, 5.0, 10.0, f64::INFINITY],
        );
        assert_eq!(sorted_points(&s), vec![(1.0, 10.0), (3.0, 30.0)]);
    }

    #[test]
    fn frequency_panel_need_not_include_zero() {
        let panel = |include_zero| ComparisonPanel {
            y_label: "f".into(),
            include_zero,
            measured: Series::new("m", SeriesKind::Measured, vec![1.0, 2.0], vec![3.0, 3.1]),
            predicted: vec![],
        };
        for (z, expect_zero_tick) in [(true, true), (false, false)] {
            let svg = crate::render_svg_text(&ComparisonFigure {
                title: "t".into(),
                x_label: "U".into(),
                panels: vec![panel(z)],
            })
            .unwrap();
            // The y tick "0" appears only when the range is forced to include zero.
            assert_eq!(
                svg.contains("\n0\n</text>"),
                expect_zero_tick,
                "include_zero={z}"
            );
        }
    }
}
