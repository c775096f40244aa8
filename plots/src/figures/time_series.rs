//! Figure 1: several panels sharing the time axis (motion α, h; forces C_L, C_M), each
//! with measured and model curves overlaid.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{draw_line, look_of, looks, mesh, Series};
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{check_len, decimate, finite_range, legend_band, padded, segments, title};

/// Most points drawn per curve (min–max decimation keeps peaks; keeps SVG files small).
const MAX_POINTS: usize = 4000;

/// One panel of a [`TimeSeriesFigure`]: its y-axis label (with unit) and its curves, whose
/// `x` is time \[s\].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TimePanel {
    /// y-axis description with unit, e.g. `"α [deg]"`, `"C_M [-]"`.
    pub y_label: String,
    /// Curves (typically one measured and one model).
    pub series: Vec<Series>,
}

/// Stacked panels sharing one time axis. Series with the same label share style and legend
/// entry across panels.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TimeSeriesFigure {
    /// Figure title.
    pub title: String,
    /// Time-axis description, e.g. `"t [s]"`.
    pub x_label: String,
    /// Panels from top to bottom.
    pub panels: Vec<TimePanel>,
}

impl Figure for TimeSeriesFigure {
    const KIND: &'static str = "time_series";

    fn size(&self) -> (u32, u32) {
        (1200, (220 + 230 * self.panels.len().max(1)) as u32)
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
        // Validate everything first; time range is shared by all panels.
        let mut segs = vec![];
        for (p, panel) in self.panels.iter().enumerate() {
            let mut ps = vec![];
            for (i, s) in panel.series.iter().enumerate() {
                let field = format!("panels[{p}].series[{i}] \"{}\"", s.label);
                check_len(kind, &format!("{field} x/y"), s.x.len(), s.y.len())?;
                let sg = segments(&s.x, &s.y);
                if sg.is_empty() {
                    return Err(Error::NoData {
                        figure: kind,
                        field,
                        len: s.x.len(),
                    });
                }
                ps.push(sg);
            }
            if ps.is_empty() {
                return Err(Error::NoData {
                    figure: kind,
                    field: format!("panels[{p}].series"),
                    len: 0,
                });
            }
            segs.push(ps);
        }
        let all = || segs.iter().flatten().flatten().flatten();
        let (t0, t1) = finite_range(all().map(|p| p.0)).expect("validated non-empty");
        let (t0, t1) = if t1 > t0 {
            (t0, t1)
        } else {
            padded((t0, t1), 0.0)
        };

        let area = title(root, &self.title, kind)?;
        let (lk, legend) = looks(self.panels.iter().flat_map(|p| &p.series));
        let area = legend_band(&area, &legend, kind)?;
        let n = self.panels.len();
        let h = area.dim_in_pixel().1 as i32;
        let extra = 55; // x-axis description + tick labels under the last panel
        let each = (h - extra) / n as i32;
        let breaks: Vec<i32> = (1..n).map(|k| k as i32 * each).collect();
        let areas = area.split_by_breakpoints(Vec::<i32>::new(), breaks);

        for (p, (panel, a)) in self.panels.iter().zip(areas.iter()).enumerate() {
            let last = p + 1 == n;
            if n > 1 {
                crate::style::panel_letter(a, p, kind)?;
            }
            let yr =
                finite_range(segs[p].iter().flatten().flatten().map(|q| q.1)).expect("validated");
            let (y0, y1) = padded(yr, 0.06);
            let mut chart = ChartBuilder::on(a)
                .margin_left(10)
                .margin_right(30)
                .margin_top(8)
                .x_label_area_size(if last { 60 } else { 8 })
                .y_label_area_size(95)
                .build_cartesian_2d(t0..t1, y0..y1)
                .ctx(kind)?;
            let xl = if last { self.x_label.as_str() } else { "" };
            let empty = |_: &f64| String::new();
            let fmt = crate::style::fmt_tick(y1 - y0);
            let fmt_t = crate::style::fmt_tick(t1 - t0);
            mesh!(m = chart, xl, panel.y_label.as_str());
            m.y_label_formatter(&fmt);
            if last {
                m.x_label_formatter(&fmt_t);
            } else {
                m.x_label_formatter(&empty);
            }
            m.draw().ctx(kind)?;
            for (s, sg) in panel.series.iter().zip(&segs[p]) {
                let look = look_of(&lk, &s.label);
                for run in sg {
                    let pts = decimate(run, MAX_POINTS);
                    draw_line!(chart, pts, look, kind);
                }
            }
        }
        Ok(())
    }
}
