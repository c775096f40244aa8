//! Bifurcation diagram of continued LCO branches: amplitude vs wind speed, stable orbits
//! solid, unstable dashed, Hopf points (▲ on the axis) and folds (◆) marked,
//! time-integration sweep points and measured points on top.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    finite_range, fmt_tick, legend_band, marker, padded, title, LegendEntry, MarkerShape,
    HIGHLIGHT, PALETTE,
};

/// One continued branch: points in continuation order, each with its stability.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BranchCurve {
    /// Wind speed of each orbit (axis unit).
    pub u: Vec<f64>,
    /// Amplitude of each orbit (axis unit).
    pub amplitude: Vec<f64>,
    /// Stability of each orbit (Floquet multipliers inside the unit circle).
    pub stable: Vec<bool>,
}

impl BranchCurve {
    /// A continued branch's curve, the amplitude of each orbit by `amplitude` (in the
    /// figure's unit: first-harmonic or half peak-to-peak, pitch in degrees or heave in mm,
    /// as the figure's axis says).
    pub fn of_branch(
        b: &aeroelastic::branch::Branch,
        amplitude: impl Fn(&aeroelastic::branch::BranchPoint) -> f64,
    ) -> Self {
        BranchCurve {
            u: b.points.iter().map(|p| p.u).collect(),
            amplitude: b.points.iter().map(amplitude).collect(),
            stable: b.points.iter().map(|p| p.stable).collect(),
        }
    }

    /// Draws the curve on `chart` in `color`: stable runs solid, unstable runs dashed
    /// (3 px; the one drawing of a branch in every figure that shows one).
    pub(crate) fn draw<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
        color: RGBColor,
        kind: &'static str,
    ) -> Result<()> {
        for (stable, pts) in self.runs() {
            let style = ShapeStyle::from(color).stroke_width(3);
            if stable {
                chart.draw_series(LineSeries::new(pts, style)).ctx(kind)?;
            } else {
                chart
                    .draw_series(DashedLineSeries::new(pts, 10, 7, style))
                    .ctx(kind)?;
            }
        }
        Ok(())
    }

    /// The curve split into runs of equal stability (finite points only), each as
    /// (stable, points); a run shares its end point with the next so that the curve is
    /// continuous.
    pub(crate) fn runs(&self) -> Vec<(bool, Vec<(f64, f64)>)> {
        let n = self
            .u
            .len()
            .min(self.amplitude.len())
            .min(self.stable.len());
        let mut out = Vec::new();
        let mut start = 0;
        while start + 1 < n {
            let st = self.stable[start + 1];
            let mut end = start + 1;
            while end + 1 < n && self.stable[end + 1] == st {
                end += 1;
            }
            let pts = (start..=end)
                .filter(|&i| self.u[i].is_finite() && self.amplitude[i].is_finite())
                .map(|i| (self.u[i], self.amplitude[i]))
                .collect();
            out.push((st, pts));
            start = end;
        }
        out
    }
}

/// A marked point (Hopf point, fold, sweep or measured point).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DiagramPoint {
    /// Wind speed (axis unit).
    pub u: f64,
    /// Amplitude (axis unit).
    pub amplitude: f64,
    /// Stable (measured and sweep points: which branch they belong to).
    pub stable: bool,
}

/// Bifurcation diagram of continued branches with markers.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BranchDiagramFigure {
    /// Figure title.
    pub title: String,
    /// U-axis description, e.g. `"U [m/s]"`.
    pub u_label: String,
    /// Amplitude-axis description, e.g. `"pitch amplitude [deg]"`.
    pub amplitude_label: String,
    /// Continued branches.
    pub branches: Vec<BranchCurve>,
    /// Hopf points (amplitude 0).
    pub hopf: Vec<DiagramPoint>,
    /// Folds of cycles.
    pub folds: Vec<DiagramPoint>,
    /// Time-integration sweep points (LCOs found by integration).
    pub sweep: Vec<DiagramPoint>,
    /// Measured points (filled: stable branch, hollow: unstable branch).
    pub measured: Vec<DiagramPoint>,
}

const C_BRANCH: RGBColor = PALETTE[0];
const C_SWEEP: RGBColor = RGBColor(90, 90, 90);
const C_MEAS: RGBColor = PALETTE[1];

impl Figure for BranchDiagramFigure {
    const KIND: &'static str = "branch_diagram";

    fn size(&self) -> (u32, u32) {
        (1200, 800)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        let fin = |u: f64, a: f64| u.is_finite() && a.is_finite();
        let all_u = self
            .branches
            .iter()
            .flat_map(|b| b.u.iter().copied())
            .chain(self.hopf.iter().map(|p| p.u))
            .chain(self.measured.iter().map(|p| p.u))
            .chain(self.sweep.iter().map(|p| p.u));
        let Some((u0, u1)) = finite_range(all_u) else {
            return Err(Error::NoData {
                figure: kind,
                field: "branches".into(),
                len: self.branches.len(),
            });
        };
        let (u0, u1) = padded((u0, u1), 0.04);
        let all_a = self
            .branches
            .iter()
            .flat_map(|b| b.amplitude.iter().copied())
            .chain(self.measured.iter().map(|p| p.amplitude))
            .chain(self.sweep.iter().map(|p| p.amplitude))
            .chain([0.0]);
        let (a0, a1) = finite_range(all_a).expect("has 0");
        let a1 = if a1 > a0 { a1 } else { a0 + 1.0 };
        let (y0, y1) = (a0 - 0.04 * (a1 - a0), a1 * 1.08);

        let area = title(root, &self.title, kind)?;
        // only the kinds of orbit the branches have
        let has = |s: bool| self.branches.iter().any(|b| b.stable.contains(&s));
        let mut legend = vec![];
        if has(true) {
            legend.push(LegendEntry::line(
                "stable LCO (continuation)",
                C_BRANCH,
                false,
            ));
        }
        if has(false) {
            legend.push(LegendEntry::line(
                "unstable LCO (continuation)",
                C_BRANCH,
                true,
            ));
        }
        if !self.hopf.is_empty() {
            legend.push(LegendEntry::marker(
                "Hopf point",
                MarkerShape::TriangleUp,
                HIGHLIGHT,
                true,
            ));
        }
        if !self.folds.is_empty() {
            legend.push(LegendEntry::marker(
                "fold of cycles",
                MarkerShape::Diamond,
                HIGHLIGHT,
                true,
            ));
        }
        if !self.sweep.is_empty() {
            legend.push(LegendEntry::marker(
                "time integration",
                MarkerShape::Circle,
                C_SWEEP,
                false,
            ));
        }
        if self.measured.iter().any(|p| p.stable) {
            legend.push(LegendEntry::marker(
                "measured, stable",
                MarkerShape::Square,
                C_MEAS,
                true,
            ));
        }
        if self.measured.iter().any(|p| !p.stable) {
            legend.push(LegendEntry::marker(
                "measured, unstable",
                MarkerShape::Square,
                C_MEAS,
                false,
            ));
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
        for b in &self.branches {
            b.draw(&mut chart, C_BRANCH, kind)?;
        }
        let marks = self
            .sweep
            .iter()
            .filter(|p| fin(p.u, p.amplitude))
            .map(|p| marker::<_, DB>((p.u, p.amplitude), MarkerShape::Circle, C_SWEEP, false, 6))
            .chain(
                self.measured
                    .iter()
                    .filter(|p| fin(p.u, p.amplitude))
                    .map(|p| {
                        marker::<_, DB>(
                            (p.u, p.amplitude),
                            MarkerShape::Square,
                            C_MEAS,
                            p.stable,
                            7,
                        )
                    }),
            )
            .chain(
                self.hopf.iter().filter(|p| p.u.is_finite()).map(|p| {
                    marker::<_, DB>((p.u, 0.0), MarkerShape::TriangleUp, HIGHLIGHT, true, 9)
                }),
            )
            .chain(
                self.folds
                    .iter()
                    .filter(|p| fin(p.u, p.amplitude))
                    .map(|p| {
                        marker::<_, DB>(
                            (p.u, p.amplitude),
                            MarkerShape::Diamond,
                            HIGHLIGHT,
                            true,
                            9,
                        )
                    }),
            );
        chart.draw_series(marks).ctx(kind)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_stable_and_unstable_runs_and_rejects_empty() {
        let f = BranchDiagramFigure {
            title: "t".into(),
            u_label: "U [m/s]".into(),
            amplitude_label: "α [deg]".into(),
            branches: vec![BranchCurve {
                u: vec![2.0, 1.9, 1.8, 1.85, 2.1],
                amplitude: vec![0.0, 1.0, 2.0, 3.0, 4.0],
                stable: vec![false, false, false, true, true],
            }],
            hopf: vec![DiagramPoint {
                u: 2.0,
                amplitude: 0.0,
                stable: false,
            }],
            folds: vec![DiagramPoint {
                u: 1.8,
                amplitude: 2.2,
                stable: false,
            }],
            sweep: vec![],
            measured: vec![DiagramPoint {
                u: 1.9,
                amplitude: 3.1,
                stable: true,
            }],
        };
        let svg = crate::render::render_svg_text(&f).unwrap();
        assert!(svg.contains("unstable LCO"));
        assert!(svg.contains("fold of cycles"));
        // a branch of stable orbits only: no legend entry for unstable ones
        let stable_only = BranchDiagramFigure {
            branches: vec![BranchCurve {
                stable: vec![true; 5],
                ..f.branches[0].clone()
            }],
            ..f.clone()
        };
        let svg = crate::render::render_svg_text(&stable_only).unwrap();
        assert!(svg.contains("stable LCO") && !svg.contains("unstable LCO"));
        assert!(svg.contains("Hopf point"));
        // a diagram without a Hopf point (a parameter continuation between two folds): no
        // legend entry for one
        let no_hopf = BranchDiagramFigure {
            hopf: vec![],
            ..f.clone()
        };
        let svg = crate::render::render_svg_text(&no_hopf).unwrap();
        assert!(!svg.contains("Hopf point") && svg.contains("fold of cycles"));
        let e = crate::render::render_svg_text(&BranchDiagramFigure::default()).unwrap_err();
        assert!(e.to_string().contains("branches"), "{e}");
    }
}
