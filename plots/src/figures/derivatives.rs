//! Figure 9: flutter derivatives H1*..H4*, A1*..A4* vs reduced frequency K (2 × 4 panels):
//! identified points (per-case markers, optional ± spread bars) and a reference curve
//! (e.g. the flat plate from Theodorsen's function).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    bold, check_len, finite_range, fmt_tick, legend_band, marker, padded, segments, series_color,
    title, LegendEntry, MarkerShape, PANEL_TITLE_SIZE, REFERENCE,
};

/// Identified values of one derivative for one group of cases (one legend entry).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DerivativePoints {
    /// Legend label, e.g. `"configuration A"`; the same label in several panels shares
    /// marker and colour.
    pub label: String,
    /// Reduced frequencies K = Bω/U.
    pub k: Vec<f64>,
    /// Identified derivative values.
    pub value: Vec<f64>,
    /// Optional ± half-width of an error bar at each point (e.g. one standard deviation
    /// over repeated cases); empty = no bars.
    pub spread: Vec<f64>,
    /// Optional error bar [lower, upper] in absolute values at each point (e.g. an ensemble's
    /// percentile interval, not symmetric); takes precedence over `spread`; empty = none, a
    /// non-finite bound = no bar at that point.
    pub interval: Vec<[f64; 2]>,
}

/// One derivative panel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DerivativePanel {
    /// Derivative name (panel title), e.g. `"H1*"`.
    pub name: String,
    /// Identified point groups.
    pub points: Vec<DerivativePoints>,
    /// Reference curve K ↦ value (may be empty).
    pub reference_k: Vec<f64>,
    /// Reference values (same length as `reference_k`).
    pub reference_value: Vec<f64>,
}

/// Derivatives vs K in a grid of four columns (H1*..H4* on the first row, A1*..A4* on the
/// second, by convention of the order given).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DerivativeFigure {
    /// Figure title.
    pub title: String,
    /// K-axis description, e.g. `"K = Bω/U [-]"`.
    pub k_label: String,
    /// Legend label of the reference curves, e.g. `"flat plate (Theodorsen)"`.
    pub reference_label: String,
    /// Panels in row-major order.
    pub panels: Vec<DerivativePanel>,
}

const COLS: usize = 4;

impl Figure for DerivativeFigure {
    const KIND: &'static str = "derivatives";

    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().max(1).div_ceil(COLS) as u32;
        (1600, 150 + 400 * rows)
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
        // Validate, and collect the distinct point labels in order.
        let mut labels: Vec<String> = vec![];
        let mut any_ref = false;
        for (p, panel) in self.panels.iter().enumerate() {
            let mut finite = 0;
            for (i, g) in panel.points.iter().enumerate() {
                let f = format!("panels[{p}] \"{}\" points[{i}] \"{}\"", panel.name, g.label);
                check_len(kind, &format!("{f} k/value"), g.k.len(), g.value.len())?;
                if !g.spread.is_empty() {
                    check_len(kind, &format!("{f} k/spread"), g.k.len(), g.spread.len())?;
                }
                if !g.interval.is_empty() {
                    check_len(
                        kind,
                        &format!("{f} k/interval"),
                        g.k.len(),
                        g.interval.len(),
                    )?;
                }
                finite += segments(&g.k, &g.value).iter().map(Vec::len).sum::<usize>();
                if !labels.contains(&g.label) {
                    labels.push(g.label.clone());
                }
            }
            let f = format!("panels[{p}] \"{}\" reference", panel.name);
            check_len(
                kind,
                &format!("{f} k/value"),
                panel.reference_k.len(),
                panel.reference_value.len(),
            )?;
            let r = segments(&panel.reference_k, &panel.reference_value);
            any_ref |= !r.is_empty();
            finite += r.iter().map(Vec::len).sum::<usize>();
            if finite == 0 {
                return Err(Error::NoData {
                    figure: kind,
                    field: format!("panels[{p}] \"{}\"", panel.name),
                    len: panel.points.iter().map(|g| g.k.len()).sum::<usize>()
                        + panel.reference_k.len(),
                });
            }
        }
        let style_of = |label: &str| {
            let i = labels.iter().position(|l| l == label).unwrap_or(0);
            (MarkerShape::nth(i), series_color(i))
        };
        let area = title(root, &self.title, kind)?;
        let mut legend: Vec<LegendEntry> = labels
            .iter()
            .map(|l| {
                let (s, c) = style_of(l);
                LegendEntry::marker(l.clone(), s, c, true)
            })
            .collect();
        if any_ref {
            legend.push(LegendEntry::line(
                self.reference_label.clone(),
                REFERENCE,
                false,
            ));
        }
        let area = legend_band(&area, &legend, kind)?;
        // Shared K range over all panels.
        let all_k = self.panels.iter().flat_map(|p| {
            p.points
                .iter()
                .flat_map(|g| finite_pairs_k(&g.k, &g.value))
                .chain(finite_pairs_k(&p.reference_k, &p.reference_value))
        });
        let (k0, k1) = padded(finite_range(all_k).expect("validated"), 0.04);
        let rows = self.panels.len().div_ceil(COLS);
        let cells = area.split_evenly((rows, COLS));
        let fk = fmt_tick(k1 - k0);
        let lettered = self.panels.len() > 1;
        for (i, (panel, cell)) in self.panels.iter().zip(cells.iter()).enumerate() {
            if lettered {
                crate::style::panel_letter(cell, i, kind)?;
            }
            let cell = cell
                .margin(10, 0, 0, 0)
                .titled(&panel.name, bold(PANEL_TITLE_SIZE))
                .ctx(kind)?;
            // y range: points ± spread, reference curve, and zero.
            let vals = panel
                .points
                .iter()
                .flat_map(|g| {
                    (0..g.k.len())
                        .filter(|&i| g.k[i].is_finite() && g.value[i].is_finite())
                        .flat_map(|i| {
                            let (lo, hi) = bar_at(g, i);
                            [lo, hi]
                        })
                })
                .chain(
                    segments(&panel.reference_k, &panel.reference_value)
                        .into_iter()
                        .flatten()
                        .map(|p| p.1),
                )
                .chain([0.0]);
            let (y0, y1) = padded(finite_range(vals).expect("has 0"), 0.08);
            let mut chart = ChartBuilder::on(&cell)
                .margin_left(6)
                .margin_right(20)
                .margin_top(6)
                .x_label_area_size(55)
                .y_label_area_size(70)
                .build_cartesian_2d(k0..k1, y0..y1)
                .ctx(kind)?;
            let fy = fmt_tick(y1 - y0);
            mesh!(m = chart, self.k_label.as_str(), "");
            m.x_label_formatter(&fk)
                .y_label_formatter(&fy)
                .x_labels(6)
                .y_labels(6)
                .draw()
                .ctx(kind)?;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(k0, 0.0), (k1, 0.0)],
                    ShapeStyle::from(RGBColor(150, 150, 150)).stroke_width(1),
                )))
                .ctx(kind)?;
            for run in segments(&panel.reference_k, &panel.reference_value) {
                chart
                    .draw_series(LineSeries::new(
                        run,
                        ShapeStyle::from(REFERENCE).stroke_width(2),
                    ))
                    .ctx(kind)?;
            }
            for g in &panel.points {
                let (shape, color) = style_of(&g.label);
                let pts: Vec<(f64, f64, (f64, f64))> = (0..g.k.len())
                    .filter(|&i| g.k[i].is_finite() && g.value[i].is_finite())
                    .map(|i| (g.k[i], g.value[i], bar_at(g, i)))
                    .collect();
                let bar = ShapeStyle::from(color).stroke_width(1);
                let bars: Vec<(f64, f64, f64)> = pts
                    .iter()
                    .filter(|p| p.2 .1 > p.2 .0)
                    .map(|&(k, _, (lo, hi))| (k, lo, hi))
                    .collect();
                chart
                    .draw_series(
                        bars.iter()
                            .map(|&(k, lo, hi)| PathElement::new(vec![(k, lo), (k, hi)], bar)),
                    )
                    .ctx(kind)?;
                chart
                    .draw_series(bars.iter().flat_map(|&(k, lo, hi)| {
                        [lo, hi].map(|y| {
                            plotters::element::EmptyElement::at((k, y))
                                + PathElement::new(vec![(-5, 0), (5, 0)], bar)
                        })
                    }))
                    .ctx(kind)?;
                chart
                    .draw_series(
                        pts.iter()
                            .map(|&(k, v, _)| marker::<_, DB>((k, v), shape, color, true, 5)),
                    )
                    .ctx(kind)?;
            }
        }
        Ok(())
    }
}

/// Error bar (lower, upper) of point `i`: the interval when given and finite, else value ±
/// spread (a zero-length bar when neither).
fn bar_at(g: &DerivativePoints, i: usize) -> (f64, f64) {
    match g.interval.get(i) {
        Some(&[lo, hi]) if lo.is_finite() && hi.is_finite() => (lo.min(hi), lo.max(hi)),
        _ => {
            let s = spread_at(g, i);
            (g.value[i] - s, g.value[i] + s)
        }
    }
}

/// Half-width of the error bar of point `i` (0 when absent or non-finite).
fn spread_at(g: &DerivativePoints, i: usize) -> f64 {
    g.spread
        .get(i)
        .copied()
        .filter(|s| s.is_finite())
        .unwrap_or(0.0)
        .abs()
}

/// Finite K values of (k, value) pairs.
fn finite_pairs_k<'a>(k: &'a [f64], v: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
    k.iter()
        .zip(v)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, _)| *a)
}
