//! The candidate library (paper Fig. 6): one row per library term, one column per group and
//! force; each cell says whether the term was selected, was identifiable but not selected,
//! or was not identifiable on the group's data (a linear combination of other columns).

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{DrawResultExt, Error, Result};
use crate::render::Figure;
use crate::style::{font, legend_band, title, LegendEntry, PALETTE};

/// State of one term in one group and force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LibraryCell {
    /// In the selected support.
    Selected,
    /// In the identifiable basis of the group, not selected.
    #[default]
    Basis,
    /// Not identifiable on the group's data (dependent column, e.g. heave terms under
    /// pitch-only forcing).
    NotIdentifiable,
}

/// The library against the groups' selections.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LibraryFigure {
    /// Figure title.
    pub title: String,
    /// Row labels (terms, display form), top to bottom.
    pub terms: Vec<String>,
    /// Column labels, e.g. `"D C_L"`.
    pub columns: Vec<String>,
    /// `cells[c][r]`: column c, term r.
    pub cells: Vec<Vec<LibraryCell>>,
}

const C_SELECTED: RGBColor = PALETTE[0];
const C_BASIS: RGBColor = RGBColor(236, 236, 236);
const C_DEPENDENT: RGBColor = RGBColor(150, 150, 150);
const LABEL_W: i32 = 190;
const HEADER_H: i32 = 70;
const ROW_H: u32 = 26;

impl Figure for LibraryFigure {
    const KIND: &'static str = "library";

    fn size(&self) -> (u32, u32) {
        let w = (LABEL_W as u32 + 60 * self.columns.len() as u32 + 40).max(900);
        (w, 190 + ROW_H * self.terms.len() as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let kind = Self::KIND;
        if self.terms.is_empty() || self.columns.is_empty() {
            return Err(Error::NoData {
                figure: kind,
                field: "terms/columns".into(),
                len: 0,
            });
        }
        for (c, col) in self.cells.iter().enumerate() {
            if col.len() != self.terms.len() {
                return Err(Error::LengthMismatch {
                    figure: kind,
                    field: format!("cells[{c}]"),
                    left: col.len(),
                    right: self.terms.len(),
                });
            }
        }
        if self.cells.len() != self.columns.len() {
            return Err(Error::LengthMismatch {
                figure: kind,
                field: "cells/columns".into(),
                left: self.cells.len(),
                right: self.columns.len(),
            });
        }
        let area = title(root, &self.title, kind)?;
        let legend = [
            LegendEntry::patch("selected", C_SELECTED),
            LegendEntry::patch("identifiable, not selected", C_BASIS),
            LegendEntry::patch("not identifiable on the group's data", C_DEPENDENT),
        ];
        let area = legend_band(&area, &legend, kind)?;
        let (w, h) = area.dim_in_pixel();
        let (w, h) = (w as i32, h as i32);
        let n_c = self.columns.len() as i32;
        let n_r = self.terms.len() as i32;
        let cw = ((w - LABEL_W - 20) / n_c).clamp(20, 90);
        let rh = ((h - HEADER_H - 10) / n_r).clamp(12, ROW_H as i32);
        let x0 = LABEL_W;
        let y0 = HEADER_H;
        let text = font(17.0);
        let centre = |h, v| text.pos(plotters::style::text_anchor::Pos::new(h, v));
        use plotters::style::text_anchor::{HPos, VPos};
        for (c, label) in self.columns.iter().enumerate() {
            let xc = x0 + c as i32 * cw + cw / 2;
            // two lines: group above, force below
            let (a, b) = label.split_once(' ').unwrap_or((label.as_str(), ""));
            area.draw(&Text::new(
                a.to_string(),
                (xc, y0 - 38),
                centre(HPos::Center, VPos::Center),
            ))
            .ctx(kind)?;
            area.draw(&Text::new(
                b.to_string(),
                (xc, y0 - 16),
                centre(HPos::Center, VPos::Center),
            ))
            .ctx(kind)?;
        }
        for (r, term) in self.terms.iter().enumerate() {
            let yc = y0 + r as i32 * rh + rh / 2;
            area.draw(&Text::new(
                term.clone(),
                (x0 - 10, yc),
                centre(HPos::Right, VPos::Center),
            ))
            .ctx(kind)?;
        }
        for (c, col) in self.cells.iter().enumerate() {
            for (r, cell) in col.iter().enumerate() {
                let (x, y) = (x0 + c as i32 * cw, y0 + r as i32 * rh);
                let color = match cell {
                    LibraryCell::Selected => C_SELECTED,
                    LibraryCell::Basis => C_BASIS,
                    LibraryCell::NotIdentifiable => C_DEPENDENT,
                };
                area.draw(&Rectangle::new(
                    [(x + 1, y + 1), (x + cw - 1, y + rh - 1)],
                    color.filled(),
                ))
                .ctx(kind)?;
            }
        }
        // a thicker line between groups (every second column: lift, moment)
        for c in (0..=n_c).step_by(2) {
            let x = x0 + c * cw;
            area.draw(&PathElement::new(
                vec![(x, y0 - 50), (x, y0 + n_r * rh)],
                ShapeStyle::from(BLACK.mix(0.6)).stroke_width(1),
            ))
            .ctx(kind)?;
        }
        Ok(())
    }
}
