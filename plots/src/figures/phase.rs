//! Figure 8: phase portrait (α vs α̇, or h vs ḣ), one or more trajectories.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{draw_line, look_of, looks, mesh, Series};
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    check_len, finite_range, fmt_tick, legend_band, marker, padded, segments, title, LegendEntry,
    MarkerShape,
};

/// Phase portrait: each trajectory is a [`Series`] with x = displacement, y = velocity
/// (measured solid, model dashed). The start of each trajectory is marked with a hollow
/// circle.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PhasePortraitFigure {
    /// Figure title.
    pub title: String,
    /// Displacement-axis description, e.g. `"α [deg]"`.
    pub x_label: String,
    /// Velocity-axis description, e.g. `"α̇ [deg/s]"`.
    pub y_label: String,
    /// Trajectories (one or two typically).
    pub trajectories: Vec<Series>,
}

/// Most points drawn per trajectory.
const MAX_POINTS: usize = 8000;

impl Figure for PhasePortraitFigure {
    const KIND: &'static str = "phase_portrait";

    fn size(&self) -> (u32, u32) {
        (1000, 900)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        if self.trajectories.is_empty() {
            return Err(Error::NoData {
                figure: kind,
                field: "trajectories".into(),
                len: 0,
            });
        }
        let mut runs = vec![];
        for (i, s) in self.trajectories.iter().enumerate() {
            let field = format!("trajectories[{i}] \"{}\"", s.label);
            check_len(kind, &format!("{field} x/y"), s.x.len(), s.y.len())?;
            let sg = segments(&s.x, &s.y);
            if sg.is_empty() {
                return Err(Error::NoData {
                    figure: kind,
                    field,
                    len: s.x.len(),
                });
            }
            runs.push(sg);
        }
        let all = || runs.iter().flatten().flatten();
        let (x0, x1) = padded(finite_range(all().map(|p| p.0)).expect("validated"), 0.05);
        let (y0, y1) = padded(finite_range(all().map(|p| p.1)).expect("validated"), 0.05);

        let area = title(root, &self.title, kind)?;
        let (lk, mut legend) = looks(&self.trajectories);
        legend.push(LegendEntry::marker(
            "start",
            MarkerShape::Circle,
            BLACK,
            false,
        ));
        let area = legend_band(&area, &legend, kind)?;
        let mut chart = ChartBuilder::on(&area)
            .margin_left(10)
            .margin_right(30)
            .margin_top(8)
            .x_label_area_size(60)
            .y_label_area_size(105)
            .build_cartesian_2d(x0..x1, y0..y1)
            .ctx(kind)?;
        let fx = fmt_tick(x1 - x0);
        let fy = fmt_tick(y1 - y0);
        mesh!(m = chart, self.x_label.as_str(), self.y_label.as_str());
        m.x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .draw()
            .ctx(kind)?;
        for (s, sg) in self.trajectories.iter().zip(&runs) {
            let look = look_of(&lk, &s.label);
            for run in sg {
                // Phase curves are smooth but not monotonic in x: thin by a stride.
                let step = run.len().div_ceil(MAX_POINTS).max(1);
                let mut pts: Vec<(f64, f64)> = run.iter().copied().step_by(step).collect();
                if step > 1 {
                    pts.push(*run.last().expect("non-empty run"));
                }
                draw_line!(chart, pts, look, kind);
            }
            let start = sg[0][0];
            chart
                .draw_series(std::iter::once(marker::<_, DB>(
                    start,
                    MarkerShape::Circle,
                    look.color,
                    false,
                    7,
                )))
                .ctx(kind)?;
        }
        Ok(())
    }
}
