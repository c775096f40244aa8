//! Figure 3: the δ path of the sparse regression (paper Alg. 3): number of selected terms
//! and key-frequency loss (Eq. 14) vs the threshold δ (log axis), the selected δ marked,
//! and the support as a term × δ occupancy strip.

use plotters::coord::ranged1d::SegmentValue;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::mesh;
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    check_len, fmt_num, fmt_tick, legend_band, log_range, padded, title, LegendEntry, MarkerShape,
    HIGHLIGHT, PALETTE,
};

/// The δ path of one case or group. Entry `i` of `deltas`, `n_terms`, `loss` and `support`
/// belongs to the same threshold. δ ≤ 0 or non-finite entries are skipped (log axis).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DeltaPathFigure {
    /// Figure title.
    pub title: String,
    /// δ-axis description, e.g. `"δ (relative contribution threshold) [-]"`.
    pub delta_label: String,
    /// Thresholds δ (> 0).
    pub deltas: Vec<f64>,
    /// Number of selected terms at each δ.
    pub n_terms: Vec<usize>,
    /// Key-frequency loss (Eq. 14) at each δ.
    pub loss: Vec<f64>,
    /// Loss-axis description, e.g. `"key-frequency loss [-]"`.
    pub loss_label: String,
    /// Loss limit of the δ selection (drawn as a dashed line), if any.
    pub loss_limit: Option<f64>,
    /// Index (into `deltas`) of the selected δ, if any.
    pub selected: Option<usize>,
    /// Candidate term names (columns of the occupancy strip, drawn as rows, first on top).
    pub term_names: Vec<String>,
    /// `support[i][j]`: term `j` active at `deltas[i]` (may be empty: no strip).
    pub support: Vec<Vec<bool>>,
}

const ROW: u32 = 19;

impl Figure for DeltaPathFigure {
    const KIND: &'static str = "delta_path";

    fn size(&self) -> (u32, u32) {
        let strip = if self.support.is_empty() {
            0
        } else {
            self.term_names.len() as u32 * ROW + 90
        };
        (1200, 170 + 2 * 240 + strip)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        let n = self.deltas.len();
        check_len(kind, "deltas/n_terms", n, self.n_terms.len())?;
        check_len(kind, "deltas/loss", n, self.loss.len())?;
        if !self.support.is_empty() {
            check_len(kind, "deltas/support", n, self.support.len())?;
            for (i, row) in self.support.iter().enumerate() {
                check_len(
                    kind,
                    &format!("support[{i}]/term_names"),
                    row.len(),
                    self.term_names.len(),
                )?;
            }
        }
        if let Some(s) = self.selected {
            if s >= n {
                return Err(Error::InvalidInput {
                    figure: kind,
                    field: "selected".into(),
                    message: format!("index {s} out of range (path has {n} thresholds)"),
                });
            }
        }
        // Usable thresholds, ascending.
        let mut idx: Vec<usize> = (0..n)
            .filter(|&i| self.deltas[i].is_finite() && self.deltas[i] > 0.0)
            .collect();
        if idx.is_empty() {
            return Err(Error::NoData {
                figure: kind,
                field: "deltas (finite, > 0)".into(),
                len: n,
            });
        }
        idx.sort_by(|&a, &b| self.deltas[a].total_cmp(&self.deltas[b]));
        let (d0, d1) = log_range(idx.iter().map(|&i| self.deltas[i]), 1.25).expect("non-empty");
        let sel = self
            .selected
            .filter(|&s| idx.contains(&s))
            .map(|s| self.deltas[s]);

        let area = title(root, &self.title, kind)?;
        let c_terms = PALETTE[0];
        let c_loss = PALETTE[1];
        let mut legend = vec![
            LegendEntry::marker("number of terms", MarkerShape::Circle, c_terms, true),
            LegendEntry::marker("key-frequency loss", MarkerShape::Square, c_loss, true),
        ];
        if self.loss_limit.is_some() {
            legend.push(LegendEntry::line("loss limit", c_loss, true));
        }
        if let Some(d) = sel {
            legend.push(LegendEntry::line(
                format!("selected δ = {}", fmt_num(d)),
                HIGHLIGHT,
                false,
            ));
        }
        if !self.support.is_empty() {
            legend.push(LegendEntry::patch("active term", c_terms));
        }
        let area = legend_band(&area, &legend, kind)?;
        let (top, rest) = area.split_vertically(240);
        let (mid, strip) = rest.split_vertically(240);
        for (i, panel) in [&top, &mid, &strip].into_iter().enumerate() {
            crate::style::panel_letter(panel, i, kind)?;
        }
        let fx = |v: &f64| fmt_num(*v);
        let sel_line = |y0: f64, y1: f64| {
            sel.map(|d| {
                PathElement::new(
                    vec![(d, y0), (d, y1)],
                    ShapeStyle::from(HIGHLIGHT).stroke_width(2),
                )
            })
        };

        // Panel 1: number of terms.
        let nmax = idx.iter().map(|&i| self.n_terms[i]).max().unwrap_or(0) as f64;
        let (y0, y1) = (0.0, (nmax * 1.1).max(1.0) + 0.5);
        let mut chart = ChartBuilder::on(&top)
            .margin_left(10)
            .margin_right(30)
            .margin_top(8)
            .x_label_area_size(8)
            .y_label_area_size(210)
            .build_cartesian_2d((d0..d1).log_scale(), y0..y1)
            .ctx(kind)?;
        let empty = |_: &f64| String::new();
        let fy = fmt_tick(y1 - y0);
        mesh!(m = chart, "", "terms [-]");
        m.x_label_formatter(&empty)
            .y_label_formatter(&fy)
            .draw()
            .ctx(kind)?;
        chart.draw_series(sel_line(y0, y1)).ctx(kind)?;
        let pts: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| (self.deltas[i], self.n_terms[i] as f64))
            .collect();
        chart
            .draw_series(LineSeries::new(
                pts.clone(),
                ShapeStyle::from(c_terms).stroke_width(2),
            ))
            .ctx(kind)?;
        chart
            .draw_series(
                pts.iter().map(|&p| {
                    crate::style::marker::<_, DB>(p, MarkerShape::Circle, c_terms, true, 4)
                }),
            )
            .ctx(kind)?;

        // Panel 2: loss (log axis when it is positive and spans more than two decades).
        let lpts: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| (self.deltas[i], self.loss[i]))
            .filter(|p| p.1.is_finite())
            .collect();
        let limit = self.loss_limit.filter(|l| l.is_finite());
        let lr = crate::style::finite_range(lpts.iter().map(|p| p.1).chain(limit));
        let positive = lpts.iter().all(|p| p.1 > 0.0) && limit.is_none_or(|l| l > 0.0);
        let log_y = positive && lr.is_some_and(|(lo, hi)| hi / lo > 100.0);
        let strip_x_area = if self.support.is_empty() { 60 } else { 8 };
        let xl_mid = if self.support.is_empty() {
            self.delta_label.as_str()
        } else {
            ""
        };
        let loss_style = ShapeStyle::from(c_loss).stroke_width(2);
        let limit_style = ShapeStyle::from(c_loss).stroke_width(1);
        macro_rules! loss_panel {
            ($chart:ident, $y0:expr, $y1:expr) => {{
                let fy = |v: &f64| fmt_num(*v);
                mesh!(m = $chart, xl_mid, self.loss_label.as_str());
                if self.support.is_empty() {
                    m.x_label_formatter(&fx);
                } else {
                    m.x_label_formatter(&empty);
                }
                m.y_label_formatter(&fy).draw().ctx(kind)?;
                $chart.draw_series(sel_line($y0, $y1)).ctx(kind)?;
                if let Some(l) = limit {
                    $chart
                        .draw_series(DashedLineSeries::new(
                            vec![(d0, l), (d1, l)],
                            8,
                            5,
                            limit_style,
                        ))
                        .ctx(kind)?;
                }
                $chart
                    .draw_series(LineSeries::new(lpts.clone(), loss_style))
                    .ctx(kind)?;
                $chart
                    .draw_series(lpts.iter().map(|&p| {
                        crate::style::marker::<_, DB>(p, MarkerShape::Square, c_loss, true, 4)
                    }))
                    .ctx(kind)?;
            }};
        }
        let mid_builder = |b: &mut ChartBuilder<'_, '_, DB>| {
            b.margin_left(10)
                .margin_right(30)
                .margin_top(8)
                .x_label_area_size(strip_x_area)
                .y_label_area_size(210);
        };
        if log_y {
            let (lo, hi) = lr.expect("checked");
            let (y0, y1) = (lo / 1.5, hi * 1.5);
            let mut b = ChartBuilder::on(&mid);
            mid_builder(&mut b);
            let mut chart = b
                .build_cartesian_2d((d0..d1).log_scale(), (y0..y1).log_scale())
                .ctx(kind)?;
            loss_panel!(chart, y0, y1);
        } else {
            let (y0, y1) = padded(lr.unwrap_or((0.0, 1.0)), 0.08);
            let mut b = ChartBuilder::on(&mid);
            mid_builder(&mut b);
            let mut chart = b
                .build_cartesian_2d((d0..d1).log_scale(), y0..y1)
                .ctx(kind)?;
            loss_panel!(chart, y0, y1);
        }

        // Panel 3: occupancy strip.
        if self.support.is_empty() {
            return Ok(());
        }
        let nt = self.term_names.len();
        if nt == 0 {
            return Ok(());
        }
        let mut chart = ChartBuilder::on(&strip)
            .margin_left(10)
            .margin_right(30)
            .margin_top(8)
            .x_label_area_size(60)
            .y_label_area_size(210)
            .build_cartesian_2d((d0..d1).log_scale(), (0..nt - 1).into_segmented())
            .ctx(kind)?;
        let names = &self.term_names;
        let fy = |v: &SegmentValue<usize>| match v {
            SegmentValue::CenterOf(j) if *j < nt => names[nt - 1 - j].clone(),
            _ => String::new(),
        };
        mesh!(m = chart, self.delta_label.as_str(), "");
        m.x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .y_labels(nt)
            .disable_y_mesh()
            .label_style(crate::style::font(15.0))
            .draw()
            .ctx(kind)?;
        // Cell edges: geometric midpoints between neighbouring thresholds.
        let ds: Vec<f64> = idx.iter().map(|&i| self.deltas[i]).collect();
        let edge = |k: usize| -> (f64, f64) {
            let lo = if k == 0 {
                d0.max(ds[0] / 1.25)
            } else {
                (ds[k - 1] * ds[k]).sqrt()
            };
            let hi = if k + 1 == ds.len() {
                d1.min(ds[k] * 1.25)
            } else {
                (ds[k] * ds[k + 1]).sqrt()
            };
            (lo, hi)
        };
        let mut cells = vec![];
        for (k, &i) in idx.iter().enumerate() {
            let (lo, hi) = edge(k);
            for j in 0..nt {
                if self.support[i][j] {
                    let r = nt - 1 - j;
                    cells.push(Rectangle::new(
                        [
                            (lo, SegmentValue::Exact(r)),
                            (hi, SegmentValue::Exact(r + 1)),
                        ],
                        c_terms.mix(0.85).filled(),
                    ));
                }
            }
        }
        chart.draw_series(cells).ctx(kind)?;
        // Row separators for readability.
        chart
            .draw_series((0..=nt).map(|r| {
                PathElement::new(
                    vec![(d0, SegmentValue::Exact(r)), (d1, SegmentValue::Exact(r))],
                    RGBColor(225, 225, 225),
                )
            }))
            .ctx(kind)?;
        if let Some(d) = sel {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(d, SegmentValue::Exact(0)), (d, SegmentValue::Exact(nt))],
                    ShapeStyle::from(HIGHLIGHT).stroke_width(2),
                )))
                .ctx(kind)?;
        }
        Ok(())
    }
}
