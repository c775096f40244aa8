//! How a job's cost grows with its size (docs/SCALE.md, issue 43 item 7): time against size
//! on log–log axes, one panel per job, with the least-squares slope of log time on log size
//! (1: linear) and a dashed line proportional to the size through the smallest run.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    fmt_num, font, legend_band, log_range, marker, title, LegendEntry, MarkerShape, PALETTE,
    PANEL_TITLE_SIZE,
};

/// One job: its runs at several sizes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ScalePanel {
    /// Job name, e.g. `"identify"`.
    pub job: String,
    /// Size axis description, e.g. `"cases [-]"`.
    pub x_label: String,
    /// Size of each run (> 0; e.g. the number of cases).
    pub size: Vec<f64>,
    /// CPU time of each run, user + system \[s\] (> 0).
    pub cpu_s: Vec<f64>,
    /// Wall time of each run \[s\] (> 0).
    pub wall_s: Vec<f64>,
}

/// Time against size, one log–log panel per job, two panels a row.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ScaleFigure {
    /// Figure title.
    pub title: String,
    /// Panels, row by row.
    pub panels: Vec<ScalePanel>,
}

/// Least-squares slope of ln y on ln x over the points with x, y > 0 and finite; `None` with
/// fewer than two distinct sizes. A slope of 1 is time proportional to size.
pub fn log_slope(x: &[f64], y: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite() && **a > 0.0 && **b > 0.0)
        .map(|(a, b)| (a.ln(), b.ln()))
        .collect();
    let n = pts.len() as f64;
    if n < 2.0 {
        return None;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

const ROW_PX: u32 = 430;

impl Figure for ScaleFigure {
    const KIND: &'static str = "scale";

    fn size(&self) -> (u32, u32) {
        (
            1200,
            150 + ROW_PX * self.panels.len().div_ceil(2).max(1) as u32,
        )
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
            let n = panel.size.len();
            crate::style::check_len(kind, &format!("panels[{p}].cpu_s"), n, panel.cpu_s.len())?;
            crate::style::check_len(kind, &format!("panels[{p}].wall_s"), n, panel.wall_s.len())?;
            let usable = |v: &[f64]| v.iter().all(|x| x.is_finite() && *x > 0.0);
            if n == 0 {
                return Err(Error::NoData {
                    figure: kind,
                    field: format!("panels[{p}].size \"{}\"", panel.job),
                    len: 0,
                });
            }
            for (field, v) in [
                ("size", &panel.size),
                ("cpu_s", &panel.cpu_s),
                ("wall_s", &panel.wall_s),
            ] {
                if !usable(v) {
                    return Err(Error::InvalidInput {
                        figure: kind,
                        field: format!("panels[{p}].{field} \"{}\"", panel.job),
                        message: "every value must be finite and > 0 (log axes)".into(),
                    });
                }
            }
        }
        let (c_cpu, c_wall, c_ref) = (PALETTE[0], PALETTE[1], RGBColor(120, 120, 120));
        let area = title(root, &self.title, kind)?;
        let legend = [
            LegendEntry::marker("CPU time (user + system)", MarkerShape::Circle, c_cpu, true),
            LegendEntry::marker("wall time", MarkerShape::Square, c_wall, false),
            LegendEntry::line("∝ size through the smallest run's CPU", c_ref, true),
        ];
        let area = legend_band(&area, &legend, kind)?;
        let rows = self.panels.len().div_ceil(2);
        let cells = area.split_evenly((rows, 2));
        for (i, (panel, cell)) in self.panels.iter().zip(cells.iter()).enumerate() {
            crate::style::panel_letter(cell, i, kind)?;
            let slope = |y: &[f64]| log_slope(&panel.size, y).map_or("–".into(), fmt_slope);
            let head = format!(
                "{}: slope CPU {}, wall {}",
                panel.job,
                slope(&panel.cpu_s),
                slope(&panel.wall_s)
            );
            let cell = cell
                .margin(18, 0, 0, 0)
                .titled(&head, font(PANEL_TITLE_SIZE - 2.0))
                .ctx(kind)?;
            let (x0, x1) = log_range(panel.size.iter().copied(), 1.3).expect("checked");
            // the reference line's end is part of the range
            let (s0, c0) = panel
                .size
                .iter()
                .zip(&panel.cpu_s)
                .min_by(|a, b| a.0.total_cmp(b.0))
                .map(|(s, c)| (*s, *c))
                .expect("checked");
            let reference = |s: f64| c0 * s / s0;
            let (y0, y1) = log_range(
                panel
                    .cpu_s
                    .iter()
                    .chain(&panel.wall_s)
                    .copied()
                    .chain([reference(x0 * 1.3), reference(x1 / 1.3)]),
                1.5,
            )
            .expect("checked");
            let mut chart = ChartBuilder::on(&cell)
                .margin_left(10)
                .margin_right(30)
                .margin_top(8)
                .x_label_area_size(60)
                .y_label_area_size(90)
                .build_cartesian_2d(
                    (x0..x1).log_scale().with_key_points(ticks(x0, x1)),
                    (y0..y1).log_scale().with_key_points(ticks(y0, y1)),
                )
                .ctx(kind)?;
            let f = |v: &f64| fmt_num(*v);
            mesh!(m = chart, panel.x_label.as_str(), "time [s]");
            m.x_label_formatter(&f)
                .y_label_formatter(&f)
                .draw()
                .ctx(kind)?;
            chart
                .draw_series(DashedLineSeries::new(
                    vec![
                        (x0 * 1.3, reference(x0 * 1.3)),
                        (x1 / 1.3, reference(x1 / 1.3)),
                    ],
                    8,
                    5,
                    ShapeStyle::from(c_ref).stroke_width(2),
                ))
                .ctx(kind)?;
            for (y, color, shape, filled) in [
                (&panel.cpu_s, c_cpu, MarkerShape::Circle, true),
                (&panel.wall_s, c_wall, MarkerShape::Square, false),
            ] {
                let mut pts: Vec<(f64, f64)> =
                    panel.size.iter().copied().zip(y.iter().copied()).collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                chart
                    .draw_series(LineSeries::new(
                        pts.clone(),
                        ShapeStyle::from(color).stroke_width(2),
                    ))
                    .ctx(kind)?;
                chart
                    .draw_series(
                        pts.iter()
                            .map(|&p| marker::<_, DB>(p, shape, color, filled, 6)),
                    )
                    .ctx(kind)?;
            }
        }
        Ok(())
    }
}

/// Tick values 1, 2, 5 × 10ᵏ within [lo, hi] (plotters' own log ticks start at the first
/// power of ten, which leaves a range inside one decade unlabelled).
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = vec![];
    let mut k = lo.log10().floor() as i32;
    while 10f64.powi(k) <= hi {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(k);
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
        k += 1;
    }
    out
}

/// A slope to two decimals.
fn fmt_slope(s: f64) -> String {
    format!("{s:.2}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_slope_of_a_power_law_is_its_exponent() {
        let x = [1.0, 2.0, 4.0, 8.0];
        let y: Vec<f64> = x.iter().map(|v: &f64| 3.0 * v.powf(1.5)).collect();
        assert!((log_slope(&x, &y).unwrap() - 1.5).abs() < 1e-12);
        // one size: no slope; non-positive points are left out
        assert_eq!(log_slope(&[2.0, 2.0], &[1.0, 3.0]), None);
        assert!((log_slope(&[0.0, 1.0, 10.0], &[5.0, 1.0, 10.0]).unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn ticks_are_one_two_five_inside_the_range() {
        assert_eq!(ticks(0.14, 5.4), vec![0.2, 0.5, 1.0, 2.0, 5.0]);
        assert_eq!(ticks(3.0, 4.0), Vec::<f64>::new());
    }

    #[test]
    fn a_zero_time_is_named_not_drawn() {
        let fig = ScaleFigure {
            title: "t".into(),
            panels: vec![ScalePanel {
                job: "identify".into(),
                x_label: "cases [-]".into(),
                size: vec![56.0, 112.0],
                cpu_s: vec![0.5, 0.0],
                wall_s: vec![0.3, 0.6],
            }],
        };
        let e = crate::render_png(&fig).unwrap_err().to_string();
        assert!(e.contains("panels[0].cpu_s \"identify\""), "{e}");
    }
}
