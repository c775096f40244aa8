//! Figure 2: amplitude spectrum (log amplitude vs frequency) of test vs model, with the key
//! frequencies (forcing frequencies, harmonics, combination tones) marked.

use plotters::coord::Shift;
use plotters::element::EmptyElement;
use plotters::prelude::*;

use super::{draw_line, look_of, looks, mesh, Series};
use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{
    check_len, decimate, finite_range, fmt_num, fmt_tick, font, legend_band, log_range, title,
    ANNOTATION,
};

/// A marked frequency: a dashed vertical line with a label such as `"f_α"`, `"2f_α"`,
/// `"f_α+f_h"`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FreqMarker {
    /// Frequency \[Hz\] (same unit as the series' x).
    pub freq: f64,
    /// Label drawn at the top of the line.
    pub label: String,
}

/// Amplitude spectra (x = frequency, y = amplitude > 0) on a logarithmic amplitude axis.
/// Non-positive or non-finite amplitudes are skipped.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpectrumFigure {
    /// Figure title.
    pub title: String,
    /// Frequency-axis description, e.g. `"f [Hz]"`.
    pub x_label: String,
    /// Amplitude-axis description, e.g. `"|C_M| [-]"`.
    pub y_label: String,
    /// Spectra (typically measured and model).
    pub series: Vec<Series>,
    /// Key frequencies to mark.
    pub markers: Vec<FreqMarker>,
    /// Upper end of the frequency axis (`None`: the largest frequency given).
    pub f_max: Option<f64>,
}

impl Figure for SpectrumFigure {
    const KIND: &'static str = "spectrum";

    fn size(&self) -> (u32, u32) {
        (1200, 750)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        if self.series.is_empty() {
            return Err(Error::NoData {
                figure: kind,
                field: "series".into(),
                len: 0,
            });
        }
        if let Some(f) = self.f_max {
            if !(f.is_finite() && f > 0.0) {
                return Err(Error::InvalidInput {
                    figure: kind,
                    field: "f_max".into(),
                    message: format!("must be finite and > 0, got {f}"),
                });
            }
        }
        let mut runs = vec![];
        for (i, s) in self.series.iter().enumerate() {
            let field = format!("series[{i}] \"{}\"", s.label);
            check_len(kind, &format!("{field} x/y"), s.x.len(), s.y.len())?;
            // Positive amplitudes inside the frequency window; a skipped point breaks the line.
            let y: Vec<f64> =
                s.x.iter()
                    .zip(&s.y)
                    .map(|(&f, &a)| {
                        if a > 0.0 && self.f_max.is_none_or(|m| f <= m) {
                            a
                        } else {
                            f64::NAN
                        }
                    })
                    .collect();
            let sg = crate::style::segments(&s.x, &y);
            if sg.is_empty() {
                return Err(Error::NoData {
                    figure: kind,
                    field: format!("{field} (positive amplitudes)"),
                    len: s.y.len(),
                });
            }
            runs.push(sg);
        }
        let pts = || runs.iter().flatten().flatten();
        let (f0, f1) = finite_range(pts().map(|p| p.0)).expect("validated");
        let f0 = f0.min(0.0);
        let f1 = self.f_max.unwrap_or(f1).max(f0 + 1e-12);
        let (a0, a1) = log_range(pts().map(|p| p.1), 1.5).expect("validated");
        // Headroom for the marker labels (three label rows ≈ 18 % of the decades).
        let a1 = a1 * (a1 / a0).powf(0.18);

        let area = title(root, &self.title, kind)?;
        let (lk, mut legend) = looks(&self.series);
        let mut markers: Vec<&FreqMarker> = self
            .markers
            .iter()
            .filter(|m| m.freq.is_finite() && m.freq >= f0 && m.freq <= f1)
            .collect();
        markers.sort_by(|a, b| a.freq.total_cmp(&b.freq));
        if !markers.is_empty() {
            legend.push(crate::style::LegendEntry {
                label: "key frequencies".into(),
                glyph: crate::style::Glyph::Line {
                    color: ANNOTATION,
                    width: 1,
                    dashed: true,
                },
            });
        }
        let area = legend_band(&area, &legend, kind)?;
        let mut chart = ChartBuilder::on(&area)
            .margin_left(10)
            .margin_right(30)
            .margin_top(6)
            .x_label_area_size(60)
            .y_label_area_size(105)
            .build_cartesian_2d(f0..f1, (a0..a1).log_scale())
            .ctx(kind)?;
        let fx = fmt_tick(f1 - f0);
        let fy = |v: &f64| fmt_num(*v);
        mesh!(m = chart, self.x_label.as_str(), self.y_label.as_str());
        m.x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .draw()
            .ctx(kind)?;

        // Key-frequency markers under the data.
        let style = font(16.0).color(&RGBColor(60, 60, 60));
        let mut last_x = [i32::MIN; 3];
        for m in &markers {
            chart
                .draw_series(plotters::series::DashedLineSeries::new(
                    vec![(m.freq, a0), (m.freq, a1)],
                    6,
                    4,
                    ShapeStyle::from(ANNOTATION).stroke_width(1),
                ))
                .ctx(kind)?;
            let px = chart.backend_coord(&(m.freq, a1)).0;
            let (w, _) = area.estimate_text_size(&m.label, &style).ctx(kind)?;
            // First row where this label does not overlap the previous one.
            let level = (0..3).find(|&l| px > last_x[l] + 10).unwrap_or(2);
            last_x[level] = px + w as i32 + 4;
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((m.freq, a1))
                        + Text::new(m.label.clone(), (4, 6 + 22 * level as i32), style.clone()),
                ))
                .ctx(kind)?;
        }
        for (s, sg) in self.series.iter().zip(&runs) {
            let look = look_of(&lk, &s.label);
            for run in sg {
                draw_line!(chart, decimate(run, 6000), look, kind);
            }
        }
        Ok(())
    }
}
