//! Figure 6: V–g and V–f diagrams: damping ratio and frequency of each mode vs wind speed,
//! zero-damping line, flutter point marked and annotated.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::EmptyElement;
use plotters::prelude::*;

use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    check_len, draw_error_bar, finite_range, fmt_num, fmt_tick, font, legend_band, marker, padded,
    segments, series_color, title, LegendEntry, MarkerShape, HIGHLIGHT,
};

/// One mode branch of the flutter analysis: damping ratio and frequency at each wind speed.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModeBranch {
    /// Mode name for the legend, e.g. `"heave"`, `"pitch"`.
    pub name: String,
    /// Wind speeds U \[m/s\] (or reduced speed; must match the axis label).
    pub u: Vec<f64>,
    /// Damping ratio g \[-\] (negative = unstable with the usual sign; drawn as given).
    pub damping: Vec<f64>,
    /// Frequency \[Hz\].
    pub freq: Vec<f64>,
}

/// The flutter point: critical speed and frequency.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FlutterPoint {
    /// Flutter speed U_F (same unit as the U axis).
    pub u: f64,
    /// Flutter frequency f_F (same unit as the f axis).
    pub freq: f64,
}

/// A percentile interval of a critical speed over an ensemble of identified laws (the
/// propagated identification uncertainty), drawn as a shaded band with an error bar.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SpeedInterval {
    /// Lower bound (same unit as the U axis).
    pub lower: f64,
    /// Upper bound (same unit as the U axis).
    pub upper: f64,
    /// Interval level in (0, 1), e.g. 0.9.
    pub level: f64,
    /// Members that have the quantity (flutter inside the scan).
    pub found: usize,
    /// Members analysed.
    pub members: usize,
}

impl SpeedInterval {
    /// Legend text: `"{name} 90 % interval a … b unit (19 of 20 members)"`.
    pub fn legend(&self, name: &str, unit: &str) -> String {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        format!(
            "{name} {} % interval {} … {}{unit} ({} of {} members)",
            fmt_num(100.0 * self.level),
            fmt_num(self.lower),
            fmt_num(self.upper),
            self.found,
            self.members
        )
    }

    pub(crate) fn finite(&self) -> Option<(f64, f64)> {
        (self.lower.is_finite() && self.upper.is_finite() && self.upper >= self.lower)
            .then_some((self.lower, self.upper))
    }
}

/// Shades the speed interval `band` (from [`SpeedInterval::finite`]) over the height
/// `y0..y1` of `chart`, under whatever is drawn next.
///
/// # Errors
/// Backend failures, tagged with `kind`.
pub(crate) fn draw_band<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    band: Option<(f64, f64)>,
    (y0, y1): (f64, f64),
    kind: &'static str,
) -> Result<()> {
    if let Some((a, b)) = band {
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(a, y0), (b, y1)],
                C_BAND.filled(),
            )))
            .ctx(kind)?;
    }
    Ok(())
}

/// Colour of intervals (error bars).
pub(crate) const C_INTERVAL: RGBColor = RGBColor(60, 60, 60);
/// Colour of interval bands (drawn under the curves).
pub(crate) const C_BAND: RGBColor = RGBColor(226, 226, 226);

/// V–g (top) and V–f (bottom) panels sharing the U axis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct VgFigure {
    /// Figure title.
    pub title: String,
    /// U-axis description, e.g. `"U [m/s]"`.
    pub u_label: String,
    /// Damping-axis description, e.g. `"damping ratio g [-]"`.
    pub g_label: String,
    /// Frequency-axis description, e.g. `"f [Hz]"`.
    pub f_label: String,
    /// Unit appended to the U_F annotation, e.g. `"m/s"`.
    pub u_unit: String,
    /// Unit appended to the f_F annotation, e.g. `"Hz"`.
    pub f_unit: String,
    /// Mode branches.
    pub modes: Vec<ModeBranch>,
    /// Flutter point, if one was found.
    pub flutter: Option<FlutterPoint>,
    /// Interval of the flutter speed over an ensemble (shaded band on both panels, error
    /// bar on the zero-damping line), if any.
    pub flutter_interval: Option<SpeedInterval>,
}

impl Figure for VgFigure {
    const KIND: &'static str = "vg_vf";

    fn size(&self) -> (u32, u32) {
        (1200, 950)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        if self.modes.is_empty() {
            return Err(Error::NoData {
                figure: kind,
                field: "modes".into(),
                len: 0,
            });
        }
        let mut g_runs = vec![];
        let mut f_runs = vec![];
        for (i, m) in self.modes.iter().enumerate() {
            let field = format!("modes[{i}] \"{}\"", m.name);
            check_len(
                kind,
                &format!("{field} u/damping"),
                m.u.len(),
                m.damping.len(),
            )?;
            check_len(kind, &format!("{field} u/freq"), m.u.len(), m.freq.len())?;
            let g = segments(&m.u, &m.damping);
            let f = segments(&m.u, &m.freq);
            if g.is_empty() && f.is_empty() {
                return Err(Error::NoData {
                    figure: kind,
                    field,
                    len: m.u.len(),
                });
            }
            g_runs.push(g);
            f_runs.push(f);
        }
        let fl = self
            .flutter
            .filter(|p| p.u.is_finite() && p.freq.is_finite());
        let band = self.flutter_interval.and_then(|i| i.finite());
        let all_u = g_runs
            .iter()
            .chain(&f_runs)
            .flatten()
            .flatten()
            .map(|p| p.0)
            .chain(fl.map(|p| p.u))
            .chain(band.into_iter().flat_map(|(a, b)| [a, b]));
        let (u0, u1) = finite_range(all_u).expect("validated");
        let (u0, u1) = if u1 > u0 {
            (u0, u1)
        } else {
            padded((u0, u1), 0.0)
        };
        let gr = finite_range(g_runs.iter().flatten().flatten().map(|p| p.1).chain([0.0]))
            .expect("contains 0");
        let (g0, g1) = padded(gr, 0.08);
        let fr = finite_range(
            f_runs
                .iter()
                .flatten()
                .flatten()
                .map(|p| p.1)
                .chain(fl.map(|p| p.freq)),
        )
        .unwrap_or((0.0, 1.0));
        let (f0, f1) = padded(fr, 0.08);

        let area = title(root, &self.title, kind)?;
        let mut legend: Vec<LegendEntry> = self
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                LegendEntry::marker(m.name.clone(), MarkerShape::nth(i), series_color(i), true)
            })
            .collect();
        let annot = fl.map(|p| {
            // a nondimensional axis has no unit: no dangling space before the comma
            let with_unit = |v: f64, unit: &str| match unit.trim() {
                "" => fmt_num(v),
                u => format!("{} {u}", fmt_num(v)),
            };
            format!(
                "U_F = {}, f_F = {}",
                with_unit(p.u, &self.u_unit),
                with_unit(p.freq, &self.f_unit)
            )
        });
        if let Some(a) = &annot {
            legend.push(LegendEntry::marker(
                format!("flutter: {a}"),
                MarkerShape::Diamond,
                HIGHLIGHT,
                true,
            ));
        }
        if let Some(i) = self.flutter_interval.filter(|i| i.finite().is_some()) {
            legend.push(LegendEntry::error_bar(
                i.legend("U_F", &self.u_unit),
                C_INTERVAL,
            ));
        }
        let area = legend_band(&area, &legend, kind)?;
        let h = area.dim_in_pixel().1 as i32;
        let (top, bottom) = area.split_vertically((h - 55) / 2);
        crate::style::panel_letter(&top, 0, kind)?;
        crate::style::panel_letter(&bottom, 1, kind)?;
        let fu = fmt_tick(u1 - u0);
        let empty = |_: &f64| String::new();
        let a_style = font(18.0).color(&HIGHLIGHT);
        // Annotation to the right of the point unless it is in the right third.
        let right_side = fl.is_some_and(|p| p.u > u0 + 0.66 * (u1 - u0));
        let anchor = if right_side {
            plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Right,
                plotters::style::text_anchor::VPos::Bottom,
            )
        } else {
            plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Left,
                plotters::style::text_anchor::VPos::Bottom,
            )
        };
        let dx = if right_side { -12 } else { 12 };

        for (panel, (a, runs, (y0, y1), yl)) in [
            (&top, &g_runs, (g0, g1), self.g_label.as_str()),
            (&bottom, &f_runs, (f0, f1), self.f_label.as_str()),
        ]
        .into_iter()
        .enumerate()
        {
            let last = panel == 1;
            let mut chart = ChartBuilder::on(a)
                .margin_left(10)
                .margin_right(30)
                .margin_top(8)
                .x_label_area_size(if last { 60 } else { 8 })
                .y_label_area_size(95)
                .build_cartesian_2d(u0..u1, y0..y1)
                .ctx(kind)?;
            let fy = fmt_tick(y1 - y0);
            mesh!(m = chart, if last { self.u_label.as_str() } else { "" }, yl);
            m.y_label_formatter(&fy);
            if last {
                m.x_label_formatter(&fu);
            } else {
                m.x_label_formatter(&empty);
            }
            m.draw().ctx(kind)?;
            draw_band(&mut chart, band, (y0, y1), kind)?;
            if !last {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(u0, 0.0), (u1, 0.0)],
                        ShapeStyle::from(BLACK).stroke_width(2),
                    )))
                    .ctx(kind)?;
            }
            if let Some(p) = fl {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(p.u, y0), (p.u, y1)],
                        8,
                        5,
                        ShapeStyle::from(HIGHLIGHT).stroke_width(1),
                    ))
                    .ctx(kind)?;
            }
            for (i, mode_runs) in runs.iter().enumerate() {
                let c = series_color(i);
                for run in mode_runs {
                    chart
                        .draw_series(LineSeries::new(
                            run.clone(),
                            ShapeStyle::from(c).stroke_width(2),
                        ))
                        .ctx(kind)?;
                    let step = (run.len() / 25).max(1);
                    chart
                        .draw_series(
                            run.iter()
                                .step_by(step)
                                .map(|&q| marker::<_, DB>(q, MarkerShape::nth(i), c, true, 5)),
                        )
                        .ctx(kind)?;
                }
            }
            if let (Some((a, b)), false) = (band, last) {
                draw_error_bar(&mut chart, (0.0, a, b), false, C_INTERVAL, kind)?;
            }
            if let (Some(p), Some(a)) = (fl, &annot) {
                let y = if last { p.freq } else { 0.0 };
                chart
                    .draw_series(std::iter::once(marker::<_, DB>(
                        (p.u, y),
                        MarkerShape::Diamond,
                        HIGHLIGHT,
                        true,
                        9,
                    )))
                    .ctx(kind)?;
                // Text on a white box so curves underneath do not hide it.
                let (tw, th) = root.estimate_text_size(a, &a_style).ctx(kind)?;
                let (tw, th) = (tw as i32, th as i32);
                let (bx0, bx1) = if right_side {
                    (dx - tw - 5, dx + 5)
                } else {
                    (dx - 5, dx + tw + 5)
                };
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at((p.u, y))
                            + Rectangle::new(
                                [(bx0, -14 - th - 4), (bx1, -10)],
                                WHITE.mix(0.9).filled(),
                            )
                            + Text::new(a.clone(), (dx, -14), a_style.pos(anchor)),
                    ))
                    .ctx(kind)?;
            }
        }
        Ok(())
    }
}
