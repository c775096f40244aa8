//! Figure 7: bifurcation diagram: LCO amplitude vs wind speed for upward and downward
//! sweeps (hysteresis), each point classified decay / LCO / divergent, flutter speed line.

use plotters::coord::Shift;
use plotters::element::EmptyElement;
use plotters::prelude::*;

use super::flutter::{draw_band, SpeedInterval, C_BAND, C_INTERVAL};
use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    draw_error_bar, finite_range, fmt_num, fmt_tick, legend_band, marker, padded, title,
    LegendEntry, MarkerShape, CAP_PX, HIGHLIGHT, PALETTE,
};

/// Direction of the wind-speed sweep a point belongs to (drawn as ▲ / ▼).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sweep {
    /// Increasing U (each run started from the previous state or a small perturbation).
    #[default]
    Up,
    /// Decreasing U.
    Down,
}

/// Classification of the response at one wind speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ResponseClass {
    /// Oscillation decays to rest (amplitude ≈ 0): hollow grey marker.
    #[default]
    Decay,
    /// Steady limit cycle: filled blue marker at its amplitude.
    Lco,
    /// Amplitude grows without bound: filled red marker drawn at the top edge of the axis
    /// (its amplitude is not meaningful).
    Divergent,
    /// The run ended before it was classified (time or step cap, step-size underflow,
    /// stiffness): hollow orange marker at its last measured amplitude; the legend names
    /// the stop reasons ([`BifurcationPoint::stop`]).
    Unsettled,
}

/// One point of a sweep.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BifurcationPoint {
    /// Wind speed (same unit as the axis label).
    pub u: f64,
    /// Steady amplitude (same unit as the axis label); ignored for divergent points,
    /// non-finite decay amplitudes are drawn at 0.
    pub amplitude: f64,
    /// Sweep direction.
    pub sweep: Sweep,
    /// Classification.
    pub class: ResponseClass,
    /// Why the integration stopped (e.g. `"time_cap"`, `"stiffness"`; empty if unknown),
    /// named in the legend for unsettled points.
    pub stop: &'static str,
}

/// The interval of the LCO amplitude at one wind speed over an ensemble of identified laws
/// (members that settle on an LCO), drawn as an error bar with its median.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AmplitudeInterval {
    /// Wind speed (same unit as the axis label).
    pub u: f64,
    /// Median amplitude (same unit as the amplitude axis).
    pub median: f64,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
}

/// Bifurcation diagram of LCO amplitude vs wind speed.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BifurcationFigure {
    /// Figure title.
    pub title: String,
    /// U-axis description, e.g. `"U [m/s]"`.
    pub u_label: String,
    /// Amplitude-axis description, e.g. `"LCO amplitude α [deg]"`.
    pub amplitude_label: String,
    /// Points of both sweeps.
    pub points: Vec<BifurcationPoint>,
    /// Unit of U for the legend entry of the flutter speed, e.g. `"m/s"`.
    pub u_unit: String,
    /// Linear flutter speed (dashed vertical line), if known.
    pub flutter_speed: Option<f64>,
    /// Amplitude intervals over an ensemble (error bars), possibly empty.
    pub intervals: Vec<AmplitudeInterval>,
    /// Legend text of the error bars, e.g. `"90 % interval over 20 bootstrap members"`.
    pub interval_label: String,
    /// Interval of the linear flutter speed over the ensemble (shaded band), if any.
    pub flutter_interval: Option<SpeedInterval>,
}

const C_DECAY: RGBColor = RGBColor(130, 130, 130);
const C_LCO: RGBColor = PALETTE[0];
const C_DIV: RGBColor = RGBColor(200, 0, 0);
const C_UNSETTLED: RGBColor = RGBColor(230, 120, 0);

impl Figure for BifurcationFigure {
    const KIND: &'static str = "bifurcation";

    fn size(&self) -> (u32, u32) {
        (1200, 800)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        let pts: Vec<&BifurcationPoint> = self.points.iter().filter(|p| p.u.is_finite()).collect();
        if pts.is_empty() {
            return Err(Error::NoData {
                figure: kind,
                field: "points (finite u)".into(),
                len: self.points.len(),
            });
        }
        let fs = self.flutter_speed.filter(|u| u.is_finite());
        let band = self.flutter_interval.and_then(|i| i.finite());
        let bars: Vec<&AmplitudeInterval> = self
            .intervals
            .iter()
            .filter(|i| {
                [i.u, i.median, i.lower, i.upper]
                    .iter()
                    .all(|v| v.is_finite())
            })
            .collect();
        let (u0, u1) = finite_range(
            pts.iter()
                .map(|p| p.u)
                .chain(fs)
                .chain(band.into_iter().flat_map(|(a, b)| [a, b])),
        )
        .expect("non-empty");
        let (u0, u1) = padded((u0, u1), 0.04);
        let amp = |p: &BifurcationPoint| match p.class {
            ResponseClass::Divergent => None,
            ResponseClass::Decay if !p.amplitude.is_finite() => Some(0.0),
            _ => Some(p.amplitude).filter(|a| a.is_finite()),
        };
        let (a_lo, a_hi) = finite_range(
            pts.iter()
                .filter_map(|p| amp(p))
                .chain([0.0])
                .chain(bars.iter().flat_map(|i| [i.lower, i.upper])),
        )
        .expect("has 0");
        let has_div = pts.iter().any(|p| p.class == ResponseClass::Divergent);
        let a_hi = if a_hi > a_lo { a_hi } else { a_lo + 1.0 };
        // Divergent points sit on a row above the largest amplitude.
        let a_div = a_hi * 1.12;
        let y1 = if has_div { a_hi * 1.2 } else { a_hi * 1.08 };
        let y0 = a_lo - 0.04 * (y1 - a_lo);

        let area = title(root, &self.title, kind)?;
        let mut legend = vec![
            LegendEntry::marker("upward sweep", MarkerShape::TriangleUp, BLACK, false),
            LegendEntry::marker("downward sweep", MarkerShape::TriangleDown, BLACK, false),
            LegendEntry::marker("decay", MarkerShape::Circle, C_DECAY, false),
            LegendEntry::marker("LCO", MarkerShape::Circle, C_LCO, true),
        ];
        if has_div {
            legend.push(LegendEntry::marker(
                "divergent (top row)",
                MarkerShape::Circle,
                C_DIV,
                true,
            ));
        }
        let mut reasons: Vec<&str> = pts
            .iter()
            .filter(|p| p.class == ResponseClass::Unsettled)
            .map(|p| if p.stop.is_empty() { "unknown" } else { p.stop })
            .collect();
        reasons.sort_unstable();
        reasons.dedup();
        if !reasons.is_empty() {
            legend.push(LegendEntry::marker(
                format!("unsettled (stopped: {})", reasons.join(", ")),
                MarkerShape::Circle,
                C_UNSETTLED,
                false,
            ));
        }
        if let Some(u) = fs {
            legend.push(LegendEntry::line(
                format!("flutter speed U_F = {} {}", fmt_num(u), self.u_unit),
                HIGHLIGHT,
                true,
            ));
        }
        if !bars.is_empty() {
            legend.push(LegendEntry::error_bar(
                self.interval_label.clone(),
                C_INTERVAL,
            ));
        }
        if let Some(i) = self.flutter_interval.filter(|i| i.finite().is_some()) {
            legend.push(LegendEntry::patch(i.legend("U_F", &self.u_unit), C_BAND));
        }
        let area = legend_band(&area, &legend, kind)?;
        let mut chart = ChartBuilder::on(&area)
            .margin_left(10)
            .margin_right(30)
            .margin_top(8)
            .x_label_area_size(60)
            .y_label_area_size(95)
            .build_cartesian_2d(u0..u1, y0..y1)
            .ctx(kind)?;
        let fx = fmt_tick(u1 - u0);
        let fy = fmt_tick(y1 - y0);
        mesh!(
            m = chart,
            self.u_label.as_str(),
            self.amplitude_label.as_str()
        );
        m.x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .draw()
            .ctx(kind)?;
        draw_band(&mut chart, band, (y0, y1), kind)?;
        if let Some(u) = fs {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(u, y0), (u, y1)],
                    10,
                    6,
                    ShapeStyle::from(HIGHLIGHT).stroke_width(2),
                ))
                .ctx(kind)?;
        }
        if has_div {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(u0, a_div), (u1, a_div)],
                    3,
                    5,
                    ShapeStyle::from(C_DIV.mix(0.5)).stroke_width(1),
                ))
                .ctx(kind)?;
        }
        // Thin lines joining the LCO branch of each sweep, in the order given.
        for sweep in [Sweep::Up, Sweep::Down] {
            let branch: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| p.sweep == sweep && p.class == ResponseClass::Lco)
                .filter_map(|p| amp(p).map(|a| (p.u, a)))
                .collect();
            chart
                .draw_series(LineSeries::new(
                    branch,
                    ShapeStyle::from(C_LCO.mix(0.4)).stroke_width(1),
                ))
                .ctx(kind)?;
        }
        let elems = pts.iter().filter_map(|p| {
            let shape = match p.sweep {
                Sweep::Up => MarkerShape::TriangleUp,
                Sweep::Down => MarkerShape::TriangleDown,
            };
            let (y, color, filled) = match p.class {
                ResponseClass::Divergent => (a_div, C_DIV, true),
                ResponseClass::Lco => (amp(p)?, C_LCO, true),
                ResponseClass::Decay => (amp(p)?, C_DECAY, false),
                ResponseClass::Unsettled => (amp(p)?, C_UNSETTLED, false),
            };
            Some(marker::<_, DB>((p.u, y), shape, color, filled, 7))
        });
        chart.draw_series(elems).ctx(kind)?;
        // Error bars on top, the median as a short horizontal tick.
        for i in &bars {
            draw_error_bar(&mut chart, (i.u, i.lower, i.upper), true, C_INTERVAL, kind)?;
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((i.u, i.median))
                        + PathElement::new(
                            vec![(-CAP_PX - 3, 0), (CAP_PX + 3, 0)],
                            ShapeStyle::from(C_INTERVAL).stroke_width(3),
                        ),
                ))
                .ctx(kind)?;
        }
        Ok(())
    }
}
