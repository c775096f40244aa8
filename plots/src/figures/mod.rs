//! The figure structs (plain data) and their drawing code, one file per figure.

pub mod bifurcation;
pub mod branch_comparison;
pub mod branch_diagram;
pub mod comparison;
pub mod delta_path;
pub mod derivatives;
pub(crate) mod diag_util;
pub mod flutter;
pub mod gap_heatmap;
pub mod heatmap;
pub mod histogram;
pub mod library;
pub mod phase;
pub mod ranking;
pub mod residual_spectra;
pub mod scale;
pub mod spectrum;
pub mod time_series;

use plotters::prelude::*;
use plotters::style::RGBColor;

use crate::style::{series_color, LegendEntry, MEASURED, MODEL};

/// What a line series is, which fixes its style: measured data are solid blue, model output
/// dashed vermillion, anything else solid in the next palette colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SeriesKind {
    /// Measured (test) data: solid line.
    #[default]
    Measured,
    /// Model output: dashed line.
    Model,
    /// Any other curve: solid, next palette colour.
    Other,
}

/// One curve y(x) in a panel. Non-finite points are skipped (the line breaks there).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend label (series with the same label in several panels share one legend entry).
    pub label: String,
    /// Abscissa values (same length as `y`).
    pub x: Vec<f64>,
    /// Ordinate values.
    pub y: Vec<f64>,
    /// Style class.
    pub kind: SeriesKind,
}

impl Series {
    /// A series from its label, kind and data.
    pub fn new(label: impl Into<String>, kind: SeriesKind, x: Vec<f64>, y: Vec<f64>) -> Self {
        Series {
            label: label.into(),
            x,
            y,
            kind,
        }
    }
}

/// Line style of one series: colour and whether it is dashed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LineLook {
    pub color: RGBColor,
    pub dashed: bool,
    pub width: u32,
}

/// Assigns a look to every distinct label, in order of first appearance, and returns the
/// legend entries. `Other` series take palette colours from index 2 on.
pub(crate) fn looks<'a>(
    series: impl IntoIterator<Item = &'a Series>,
) -> (Vec<(String, LineLook)>, Vec<LegendEntry>) {
    let mut looks: Vec<(String, LineLook)> = vec![];
    let mut n_other = 0;
    for s in series {
        if looks.iter().any(|(l, _)| *l == s.label) {
            continue;
        }
        let look = match s.kind {
            SeriesKind::Measured => LineLook {
                color: MEASURED,
                dashed: false,
                width: 2,
            },
            SeriesKind::Model => LineLook {
                color: MODEL,
                dashed: true,
                width: 2,
            },
            SeriesKind::Other => {
                n_other += 1;
                LineLook {
                    color: series_color(1 + n_other),
                    dashed: false,
                    width: 2,
                }
            }
        };
        looks.push((s.label.clone(), look));
    }
    let legend = looks
        .iter()
        .map(|(l, k)| LegendEntry::line(l.clone(), k.color, k.dashed))
        .collect();
    (looks, legend)
}

/// Look of `label` from the table built by [`looks`].
pub(crate) fn look_of(looks: &[(String, LineLook)], label: &str) -> LineLook {
    looks
        .iter()
        .find(|(l, _)| l == label)
        .map(|(_, k)| *k)
        .unwrap_or(LineLook {
            color: BLACK,
            dashed: false,
            width: 2,
        })
}

/// Styles the mesh of a chart consistently (fonts, grid) and sets the axis descriptions.
macro_rules! mesh {
    ($m:ident = $chart:expr, $xl:expr, $yl:expr) => {
        let mut $m = $chart.configure_mesh();
        $m.x_desc($xl)
            .y_desc($yl)
            .label_style(crate::style::font(crate::style::TICK_SIZE))
            .axis_desc_style(crate::style::font(crate::style::AXIS_SIZE))
            .bold_line_style(plotters::style::RGBColor(215, 215, 215))
            .light_line_style(plotters::style::RGBColor(246, 246, 246))
            .axis_style(plotters::style::RGBColor(80, 80, 80));
    };
}
pub(crate) use mesh;

/// Draws one line (solid or dashed) through `points` in `chart`.
macro_rules! draw_line {
    ($chart:expr, $points:expr, $look:expr, $kind:expr) => {{
        let look: crate::figures::LineLook = $look;
        let style = plotters::style::ShapeStyle::from(look.color).stroke_width(look.width);
        if look.dashed {
            $chart
                .draw_series(plotters::series::DashedLineSeries::new(
                    $points, 10, 6, style,
                ))
                .ctx($kind)?;
        } else {
            $chart
                .draw_series(plotters::series::LineSeries::new($points, style))
                .ctx($kind)?;
        }
    }};
}
pub(crate) use draw_line;
