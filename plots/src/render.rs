//! Rendering a figure to PNG, SVG and (paper style) PDF — the same drawing code runs on
//! the bitmap and the SVG backend; the SVG's text becomes glyph outlines and the PDF comes
//! from that SVG (the private `vector` module) — and writing the files atomically.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{DrawResultExt, Error, Result};
use crate::rich::RichBackend;
use crate::scaled::{figure_style, FigureStyle, PAPER_DPI, PAPER_SCALE};
use crate::style::ensure_fonts;

/// A figure: plain data plus the drawing code, run once per backend.
///
/// Implemented by every figure struct of this crate ([`crate::TimeSeriesFigure`] …).
pub trait Figure {
    /// Kind of figure, used in file names of tests and in error messages (`"time_series"`).
    const KIND: &'static str;

    /// Canvas size in pixels (width, height); the SVG uses the same size in user units.
    fn size(&self) -> (u32, u32);

    /// Draws the figure on `root` (already filled white, fonts registered).
    ///
    /// # Errors
    /// [`Error::NoData`], [`Error::LengthMismatch`], [`Error::InvalidInput`] for unusable
    /// data (checked before anything is drawn), [`Error::Drawing`] for backend failures.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>;
}

/// Files written for one figure, plus its SVG text for embedding in the HTML report.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FigureFiles {
    /// PNG file (bitmap, `size()` pixels; paper style: [`PAPER_SCALE`] × that at 300 dpi).
    pub png: PathBuf,
    /// SVG file (text as glyph outlines of the bundled font).
    pub svg: PathBuf,
    /// PDF file, written in the paper style only (one page, the design size at
    /// [`PAPER_DPI`]/[`PAPER_SCALE`] pixels per inch: 1200 design pixels = 7 in; text
    /// selectable, the bundled font subset embedded).
    pub pdf: Option<PathBuf>,
    /// The SVG document as written to `svg` (for [`crate::Report::figure`]).
    pub svg_text: String,
}

/// Renders `fig` as the SVG document plotters writes: labels are `<text>` elements (so
/// searchable), drawn by a viewer in its own font when it lacks DejaVu Sans. The files and
/// the report use [`render_svg`] instead.
///
/// # Errors
/// As [`Figure::draw`]; [`Error::Font`] if the bundled font cannot be registered.
pub fn render_svg_text<F: Figure>(fig: &F) -> Result<String> {
    ensure_fonts()?;
    let (w, h) = fig.size();
    let mut text = String::new();
    {
        let root = RichBackend::new(SVGBackend::with_string(&mut text, (w, h))).into_drawing_area();
        root.fill(&WHITE).ctx(F::KIND)?;
        fig.draw(&root)?;
        root.present().ctx(F::KIND)?;
    }
    Ok(text)
}

/// Renders `fig` as an SVG document whose text is drawn as glyph outlines of the bundled
/// font, so every viewer shows the layout that was measured.
///
/// # Errors
/// As [`render_svg_text`]; [`Error::Vector`] if the SVG cannot be re-laid out.
pub fn render_svg<F: Figure>(fig: &F) -> Result<String> {
    let tagged = crate::vector::tag_texts(&render_svg_text(fig)?);
    let tree = crate::vector::parse(&tagged, F::KIND)?;
    crate::vector::outlined(&tree, &tagged, F::KIND)
}

/// Renders `fig` as a one-page PDF at paper size (1200 design pixels = 7 in), text
/// selectable in the embedded bundled font.
///
/// # Errors
/// As [`render_svg_text`]; [`Error::Vector`] if the conversion fails.
pub fn render_pdf<F: Figure>(fig: &F) -> Result<Vec<u8>> {
    let tree = crate::vector::parse(&render_svg_text(fig)?, F::KIND)?;
    crate::pdf::pdf(&tree, PAPER_DPI / PAPER_SCALE, F::KIND)
}

/// Renders `fig` as PNG bytes (8-bit RGB). In the paper style ([`crate::FigureStyle`]) the
/// design size is drawn [`PAPER_SCALE`] times larger and the PNG says 300 dpi.
///
/// # Errors
/// As [`Figure::draw`]; [`Error::Encode`] if PNG encoding fails.
pub fn render_png<F: Figure>(fig: &F) -> Result<Vec<u8>> {
    ensure_fonts()?;
    let design = fig.size();
    let paper = figure_style() == FigureStyle::Paper;
    let (w, h) = if paper {
        (
            (design.0 as f64 * PAPER_SCALE).round() as u32,
            (design.1 as f64 * PAPER_SCALE).round() as u32,
        )
    } else {
        design
    };
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    {
        let bitmap = BitMapBackend::with_buffer(&mut buf, (w, h));
        let backend = if paper {
            RichBackend::scaled(bitmap, PAPER_SCALE, design)
        } else {
            RichBackend::new(bitmap)
        }
        .with_miter_limit(crate::rich::SVG_MITER_LIMIT);
        let root = backend.into_drawing_area();
        root.fill(&WHITE).ctx(F::KIND)?;
        fig.draw(&root)?;
        root.present().ctx(F::KIND)?;
    }
    let enc = |e: png::EncodingError| Error::Encode {
        figure: F::KIND,
        message: e.to_string(),
    };
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        if paper {
            // pixels per metre = dpi / 0.0254
            let ppm = (PAPER_DPI / 0.0254).round() as u32;
            encoder.set_pixel_dims(Some(png::PixelDimensions {
                xppu: ppm,
                yppu: ppm,
                unit: png::Unit::Meter,
            }));
        }
        let mut writer = encoder.write_header().map_err(enc)?;
        writer.write_image_data(&buf).map_err(enc)?;
        writer.finish().map_err(enc)?;
    }
    Ok(out)
}

/// Renders `fig` and writes `<dir>/<stem>.png` and `<dir>/<stem>.svg` (and, in the paper
/// style, `<dir>/<stem>.pdf`), each atomically (temporary file + rename,
/// [`identify::io::write_atomic`]). Nothing is written when the data are unusable: every
/// file is rendered before the first is written.
///
/// # Errors
/// As [`render_svg`], [`render_png`] and [`render_pdf`]; [`Error::Write`] naming the file
/// when `dir` is missing or unwritable.
pub fn save<F: Figure>(fig: &F, dir: &Path, stem: &str) -> Result<FigureFiles> {
    let tagged = crate::vector::tag_texts(&render_svg_text(fig)?);
    let tree = crate::vector::parse(&tagged, F::KIND)?;
    let svg_text = crate::vector::outlined(&tree, &tagged, F::KIND)?;
    let pdf_bytes = match figure_style() {
        FigureStyle::Paper => Some(crate::pdf::pdf(&tree, PAPER_DPI / PAPER_SCALE, F::KIND)?),
        FigureStyle::Screen => None,
    };
    let png_bytes = render_png(fig)?;
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    identify::io::write_atomic(&png, &png_bytes)?;
    identify::io::write_atomic(&svg, svg_text.as_bytes())?;
    let pdf = match pdf_bytes {
        Some(bytes) => {
            let path = dir.join(format!("{stem}.pdf"));
            identify::io::write_atomic(&path, &bytes)?;
            Some(path)
        }
        None => None,
    };
    Ok(FigureFiles {
        png,
        svg,
        pdf,
        svg_text,
    })
}
