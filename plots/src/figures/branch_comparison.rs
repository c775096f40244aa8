//! Measured bifurcation diagram against the sim's, before and after a named effect: one
//! panel per DOF (pitch, heave), continued branches (solid stable, dashed unstable; grey
//! before, colour after), measured points (filled stable, open unstable), Hopf points (▲)
//! and folds (◆) of both diagrams.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::branch_diagram::{BranchCurve, DiagramPoint};
use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    finite_range, fmt_tick, legend_band, marker, padded, title, LegendEntry, MarkerShape,
    HIGHLIGHT, PALETTE,
};

/// One diagram (before or after) in one panel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DiagramLayer {
    /// Continued branches.
    pub branches: Vec<BranchCurve>,
    /// Hopf points (amplitude 0).
    pub hopf: Vec<f64>,
    /// Folds of cycles.
    pub folds: Vec<DiagramPoint>,
}

/// One DOF's panel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ComparisonDofPanel {
    /// Amplitude-axis description, e.g. `"first-harmonic pitch amplitude [deg]"`.
    pub amplitude_label: String,
    /// The nominal model's diagram.
    pub before: DiagramLayer,
    /// The diagram with the named (or best) effect, if any.
    pub after: Option<DiagramLayer>,
    /// Measured points (filled: stable branch, hollow: unstable branch).
    pub measured: Vec<DiagramPoint>,
}

/// Bifurcation diagrams before/after against the measured points, a panel per DOF.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BranchComparisonFigure {
    /// Figure title.
    pub title: String,
    /// Legend text of the `after` layer (e.g. `"with structural_polynomial"`).
    pub after_label: String,
    /// U-axis description.
    pub u_label: String,
    /// Panels, left to right.
    pub panels: Vec<ComparisonDofPanel>,
    /// Speed range to draw [m/s] (the branches may extend beyond it).
    pub u_range: Option<(f64, f64)>,
}

const C_BEFORE: RGBColor = RGBColor(150, 150, 150);
const C_AFTER: RGBColor = PALETTE[0];
const C_MEAS: RGBColor = PALETTE[1];

impl Figure for BranchComparisonFigure {
    const KIND: &'static str = "branch_comparison";

    fn size(&self) -> (u32, u32) {
        (1600, 760)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        if self.panels.is_empty() || self.panels.iter().all(|p| p.measured.is_empty()) {
            return Err(Error::NoData {
                figure: kind,
                field: "panels".into(),
                len: self.panels.len(),
            });
        }
        let area = title(root, &self.title, kind)?;
        let mut legend = vec![];
        if self.panels.iter().any(|p| !p.before.branches.is_empty()) {
            legend.push(LegendEntry::line("nominal model, stable", C_BEFORE, false));
            legend.push(LegendEntry::line("nominal model, unstable", C_BEFORE, true));
        } else {
            legend.push(LegendEntry::marker(
                "nominal model: Hopf point, no limit cycle",
                MarkerShape::TriangleUp,
                C_BEFORE,
                true,
            ));
        }
        if self.panels.iter().any(|p| p.after.is_some()) {
            legend.push(LegendEntry::line(
                format!("{}, stable", self.after_label),
                C_AFTER,
                false,
            ));
            legend.push(LegendEntry::line(
                format!("{}, unstable", self.after_label),
                C_AFTER,
                true,
            ));
        }
        legend.push(LegendEntry::marker(
            "measured, stable",
            MarkerShape::Circle,
            C_MEAS,
            true,
        ));
        legend.push(LegendEntry::marker(
            "measured, unstable",
            MarkerShape::Circle,
            C_MEAS,
            false,
        ));
        legend.push(LegendEntry::marker(
            "Hopf point",
            MarkerShape::TriangleUp,
            HIGHLIGHT,
            true,
        ));
        legend.push(LegendEntry::marker(
            "fold of cycles",
            MarkerShape::Diamond,
            HIGHLIGHT,
            true,
        ));
        let area = legend_band(&area, &legend, kind)?;
        let cells = area.split_evenly((1, self.panels.len()));
        for (panel, cell) in self.panels.iter().zip(&cells) {
            draw_panel(panel, cell, self, kind)?;
        }
        Ok(())
    }
}

fn draw_panel<DB: DrawingBackend>(
    p: &ComparisonDofPanel,
    area: &DrawingArea<DB, Shift>,
    fig: &BranchComparisonFigure,
    kind: &'static str,
) -> Result<()> {
    let fin = |u: f64, a: f64| u.is_finite() && a.is_finite();
    let layers: Vec<(&DiagramLayer, RGBColor)> = std::iter::once((&p.before, C_BEFORE))
        .chain(p.after.iter().map(|a| (a, C_AFTER)))
        .collect();
    let (u0, u1) = match fig.u_range {
        Some(r) => r,
        None => {
            let all_u = p.measured.iter().map(|m| m.u).chain(
                layers
                    .iter()
                    .flat_map(|(l, _)| l.hopf.iter().copied().chain(l.folds.iter().map(|f| f.u))),
            );
            padded(finite_range(all_u).unwrap_or((0.0, 1.0)), 0.08)
        }
    };
    let in_u = |u: f64| u >= u0 && u <= u1;
    let all_a = p
        .measured
        .iter()
        .map(|m| m.amplitude)
        .chain(layers.iter().flat_map(|(l, _)| {
            l.branches.iter().flat_map(|b| {
                b.u.iter()
                    .zip(&b.amplitude)
                    .filter(|(u, _)| in_u(**u))
                    .map(|(_, a)| *a)
            })
        }))
        .chain([0.0]);
    let (_, a1) = finite_range(all_a).unwrap_or((0.0, 1.0));
    let a1 = if a1 > 0.0 { a1 } else { 1.0 };
    // measured points set the scale; branches running far above are clipped
    let meas_max = p.measured.iter().map(|m| m.amplitude).fold(0.0, f64::max);
    let a1 = a1.min(2.0 * meas_max.max(1e-12)).max(meas_max);
    let (y0, y1) = (-0.04 * a1, a1 * 1.12);
    let mut chart = ChartBuilder::on(area)
        .margin_left(10)
        .margin_right(25)
        .margin_top(8)
        .x_label_area_size(60)
        .y_label_area_size(95)
        .build_cartesian_2d(u0..u1, y0..y1)
        .ctx(kind)?;
    let fx = fmt_tick(u1 - u0);
    let fy = fmt_tick(y1 - y0);
    mesh!(m = chart, fig.u_label.as_str(), p.amplitude_label.as_str());
    m.x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .draw()
        .ctx(kind)?;
    let clip = |u: f64, a: f64| (u.clamp(u0, u1), a.clamp(y0, y1));
    for (layer, color) in &layers {
        for b in &layer.branches {
            // plotters clips the lines to the plot area
            b.draw(&mut chart, *color, kind)?;
        }
    }
    let marks = p
        .measured
        .iter()
        .filter(|m| fin(m.u, m.amplitude))
        .map(|m| marker::<_, DB>((m.u, m.amplitude), MarkerShape::Circle, C_MEAS, m.stable, 8))
        .chain(layers.iter().flat_map(|(l, c)| {
            l.hopf
                .iter()
                .filter(|u| in_u(**u))
                .map(move |u| marker::<_, DB>((*u, 0.0), MarkerShape::TriangleUp, *c, true, 10))
                .chain(
                    l.folds
                        .iter()
                        .filter(|f| fin(f.u, f.amplitude) && in_u(f.u))
                        .map(move |f| {
                            marker::<_, DB>(
                                clip(f.u, f.amplitude),
                                MarkerShape::Diamond,
                                *c,
                                true,
                                10,
                            )
                        }),
                )
        }));
    chart.draw_series(marks).ctx(kind)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_two_panels_and_rejects_no_measured_points() {
        let curve = BranchCurve {
            u: vec![2.0, 1.9, 1.8, 1.85, 2.1],
            amplitude: vec![0.0, 1.0, 2.0, 3.0, 4.0],
            stable: vec![false, false, false, true, true],
        };
        let layer = DiagramLayer {
            branches: vec![curve],
            hopf: vec![2.0],
            folds: vec![DiagramPoint {
                u: 1.8,
                amplitude: 2.2,
                stable: false,
            }],
        };
        let panel = ComparisonDofPanel {
            amplitude_label: "pitch [deg]".into(),
            before: layer.clone(),
            after: Some(layer),
            measured: vec![DiagramPoint {
                u: 1.9,
                amplitude: 3.1,
                stable: true,
            }],
        };
        let f = BranchComparisonFigure {
            title: "t".into(),
            after_label: "with effect".into(),
            u_label: "U [m/s]".into(),
            panels: vec![panel.clone(), panel],
            u_range: None,
        };
        let svg = crate::render::render_svg_text(&f).unwrap();
        assert!(svg.contains("with effect, unstable") && svg.contains("fold of cycles"));
        let e = crate::render::render_svg_text(&BranchComparisonFigure::default()).unwrap_err();
        assert!(e.to_string().contains("panels"), "{e}");
    }
}
