//! Diagnosis figure: residual amplitude spectra before and after the best candidate, one
//! panel per channel, logarithmic amplitude axis.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::diag_util::no_data;
use super::{draw_line, look_of, looks, mesh, Series};
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    bold, check_len, decimate, finite_range, fmt_num, fmt_tick, legend_band, log_range, title,
    PANEL_TITLE_SIZE,
};

/// One channel's spectra.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpectraPanel {
    /// Panel title, e.g. `"aerodynamic: moment"`.
    pub title: String,
    /// Frequency-axis description, e.g. `"f / f_alpha [-]"`.
    pub x_label: String,
    /// Amplitude-axis description.
    pub y_label: String,
    /// Spectra (x = frequency, y = amplitude; non-positive or non-finite points skipped).
    pub series: Vec<Series>,
}

/// Residual spectra, panels in a grid of two columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ResidualSpectraFigure {
    /// Figure title.
    pub title: String,
    /// Panels; a panel with no positive finite amplitude shows a "no data" note.
    pub panels: Vec<SpectraPanel>,
}

fn ncols(n: usize) -> usize {
    if n <= 1 {
        1
    } else {
        2
    }
}

impl Figure for ResidualSpectraFigure {
    const KIND: &'static str = "residual_spectra";

    fn size(&self) -> (u32, u32) {
        let n = self.panels.len().max(1);
        let nr = n.div_ceil(ncols(n)) as u32;
        (1300, 150 + 500 * nr)
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
            for (i, s) in panel.series.iter().enumerate() {
                check_len(
                    kind,
                    &format!("panels[{p}].series[{i}] \"{}\" x/y", s.label),
                    s.x.len(),
                    s.y.len(),
                )?;
            }
        }
        let area = title(root, &self.title, kind)?;
        let (lk, legend) = looks(self.panels.iter().flat_map(|p| &p.series));
        let area = legend_band(&area, &legend, kind)?;
        let n = self.panels.len();
        let nc = ncols(n);
        let cells = area.split_evenly((n.div_ceil(nc), nc));
        let lettered = self.panels.len() > 1;
        for (i, (panel, cell)) in self.panels.iter().zip(cells.iter()).enumerate() {
            if lettered {
                crate::style::panel_letter(cell, i, kind)?;
            }
            let cell = cell
                .margin(8, 0, 0, 0)
                .titled(&panel.title, bold(PANEL_TITLE_SIZE))
                .ctx(kind)?;
            let runs: Vec<Vec<Vec<(f64, f64)>>> = panel
                .series
                .iter()
                .map(|s| {
                    let y: Vec<f64> =
                        s.y.iter()
                            .map(|&a| if a > 0.0 { a } else { f64::NAN })
                            .collect();
                    crate::style::segments(&s.x, &y)
                })
                .collect();
            let pts = || runs.iter().flatten().flatten();
            let (Some((f0, f1)), Some((a0, a1))) = (
                finite_range(pts().map(|p| p.0)),
                log_range(pts().map(|p| p.1), 1.5),
            ) else {
                no_data(&cell, "no data", kind)?;
                continue;
            };
            let f0 = f0.min(0.0);
            let f1 = f1.max(f0 + 1e-9);
            let mut chart = ChartBuilder::on(&cell)
                .margin_left(8)
                .margin_right(24)
                .margin_top(6)
                .x_label_area_size(56)
                .y_label_area_size(96)
                .build_cartesian_2d(f0..f1, (a0..a1).log_scale())
                .ctx(kind)?;
            let fx = fmt_tick(f1 - f0);
            let fy = |v: &f64| fmt_num(*v);
            mesh!(m = chart, panel.x_label.as_str(), panel.y_label.as_str());
            m.x_labels(8)
                .x_label_formatter(&fx)
                .y_label_formatter(&fy)
                .draw()
                .ctx(kind)?;
            for (s, sg) in panel.series.iter().zip(&runs) {
                let look = look_of(&lk, &s.label);
                for run in sg {
                    draw_line!(chart, decimate(run, 4000), look, kind);
                }
            }
        }
        Ok(())
    }
}
