//! PDF from the laid-out SVG tree of a figure ([`crate::vector::parse`]): one page, paths
//! with their solid fills and strokes, text in the embedded bundled font (a TrueType subset,
//! [`subset`]), selectable and searchable through a `ToUnicode` map.
//!
//! Written for what plotters' SVG holds (paths, solid colours with opacity, text): a
//! gradient, pattern, image, clip path, mask or filter in the tree is refused by name rather
//! than drawn wrong. The output is byte-for-byte deterministic (objects in a fixed order,
//! no creation date), unlike svg2pdf's, which wrote fonts in hash order (docs/DECISIONS.md,
//! "PDF without svg2pdf").
//!
//! Coordinates: the content stream starts with `k 0 0 −k 0 H cm` (k = 72/dpi points per SVG
//! user unit, H the page height in points), so everything after it is in SVG user units
//! with y down, as in the tree.

mod subset;

use std::collections::{BTreeMap, BTreeSet};

use pdf_writer::types::{
    CidFontType, FontFlags, LineCapStyle, LineJoinStyle, SystemInfo, UnicodeCmap,
};
use pdf_writer::{Content, Filter, Finish, Name, Pdf, Rect, Ref, Str};
use usvg::tiny_skia_path::PathSegment;

use crate::error::{Error, Result};

/// The character collection of an Identity-H CID font.
const SYSTEM_INFO: SystemInfo = SystemInfo {
    registry: Str(b"Adobe"),
    ordering: Str(b"Identity"),
    supplement: 0,
};

/// A face of the font database used by the drawing: its resource name, units per em and
/// the glyphs used with the text each stands for.
struct UsedFont {
    face: usvg::fontdb::ID,
    units_per_em: f32,
    glyphs: BTreeMap<u16, String>,
}

/// The page's content and the resources it names, filled by one walk of the tree.
struct Page<'t> {
    tree: &'t usvg::Tree,
    figure: &'static str,
    content: Content,
    /// In order of first use: resource `F<k>` is `fonts[k]`.
    fonts: Vec<UsedFont>,
    /// (stroke alpha, fill alpha) bits → k of resource `G<k>`.
    alphas: BTreeMap<(u32, u32), usize>,
}

impl Page<'_> {
    fn refuse(&self, what: &str) -> Error {
        Error::Vector {
            figure: self.figure,
            message: format!("PDF: the drawing holds {what}, which the PDF writer does not draw"),
        }
    }

    /// `gs` with the ExtGState of these alphas (nothing when both are 1).
    fn alpha(&mut self, stroke: f32, fill: f32) {
        if stroke >= 1.0 && fill >= 1.0 {
            return;
        }
        let n = self.alphas.len();
        let k = *self
            .alphas
            .entry((stroke.to_bits(), fill.to_bits()))
            .or_insert(n);
        self.content
            .set_parameters(Name(format!("G{k}").as_bytes()));
    }

    fn group(&mut self, g: &usvg::Group, opacity: f32) -> Result<()> {
        if g.clip_path().is_some() {
            return Err(self.refuse("a clip path"));
        }
        if g.mask().is_some() {
            return Err(self.refuse("a mask"));
        }
        if !g.filters().is_empty() {
            return Err(self.refuse("a filter"));
        }
        // a group's opacity is multiplied into its leaves' alphas: exact for the one-leaf
        // groups an SVG `opacity` attribute on a shape becomes
        let opacity = opacity * g.opacity().get();
        for node in g.children() {
            match node {
                usvg::Node::Group(g) => self.group(g, opacity)?,
                usvg::Node::Path(p) => self.path(p, opacity)?,
                usvg::Node::Text(t) => self.text(t, opacity)?,
                usvg::Node::Image(_) => return Err(self.refuse("an image")),
            }
        }
        Ok(())
    }

    fn color(&self, paint: &usvg::Paint) -> Result<[f32; 3]> {
        match paint {
            usvg::Paint::Color(c) => Ok([c.red, c.green, c.blue].map(|v| f32::from(v) / 255.0)),
            _ => Err(self.refuse("a gradient or pattern paint")),
        }
    }

    fn path(&mut self, p: &usvg::Path, opacity: f32) -> Result<()> {
        if !p.is_visible() || (p.fill().is_none() && p.stroke().is_none()) {
            return Ok(());
        }
        let t = p.abs_transform();
        let c = &mut self.content;
        c.save_state();
        c.transform([t.sx, t.ky, t.kx, t.sy, t.tx, t.ty]);
        let mut fill_alpha = 1.0;
        let mut stroke_alpha = 1.0;
        if let Some(f) = p.fill() {
            let [r, g, b] = self.color(f.paint())?;
            self.content.set_fill_rgb(r, g, b);
            fill_alpha = f.opacity().get() * opacity;
        }
        if let Some(s) = p.stroke() {
            let [r, g, b] = self.color(s.paint())?;
            let c = &mut self.content;
            c.set_stroke_rgb(r, g, b);
            c.set_line_width(s.width().get());
            c.set_line_cap(match s.linecap() {
                usvg::LineCap::Butt => LineCapStyle::ButtCap,
                usvg::LineCap::Round => LineCapStyle::RoundCap,
                usvg::LineCap::Square => LineCapStyle::ProjectingSquareCap,
            });
            c.set_line_join(match s.linejoin() {
                usvg::LineJoin::Miter | usvg::LineJoin::MiterClip => LineJoinStyle::MiterJoin,
                usvg::LineJoin::Round => LineJoinStyle::RoundJoin,
                usvg::LineJoin::Bevel => LineJoinStyle::BevelJoin,
            });
            c.set_miter_limit(s.miterlimit().get());
            if let Some(dash) = s.dasharray() {
                c.set_dash_pattern(dash.iter().copied(), s.dashoffset());
            }
            stroke_alpha = s.opacity().get() * opacity;
        }
        self.alpha(stroke_alpha, fill_alpha);
        let even_odd = p
            .fill()
            .is_some_and(|f| f.rule() == usvg::FillRule::EvenOdd);
        match (p.fill().is_some(), p.stroke().is_some(), p.paint_order()) {
            (true, true, usvg::PaintOrder::FillAndStroke) => {
                self.segments(p.data());
                if even_odd {
                    self.content.fill_even_odd_and_stroke();
                } else {
                    self.content.fill_nonzero_and_stroke();
                }
            }
            (true, true, usvg::PaintOrder::StrokeAndFill) => {
                self.segments(p.data());
                self.content.stroke();
                self.segments(p.data());
                self.fill(even_odd);
            }
            (true, false, _) => {
                self.segments(p.data());
                self.fill(even_odd);
            }
            _ => {
                self.segments(p.data());
                self.content.stroke();
            }
        }
        self.content.restore_state();
        Ok(())
    }

    fn fill(&mut self, even_odd: bool) {
        if even_odd {
            self.content.fill_even_odd();
        } else {
            self.content.fill_nonzero();
        }
    }

    /// The path's segments; a quadratic Bézier becomes the equal cubic.
    fn segments(&mut self, data: &usvg::tiny_skia_path::Path) {
        let c = &mut self.content;
        let mut last = (0.0f32, 0.0f32);
        for seg in data.segments() {
            match seg {
                PathSegment::MoveTo(p) => {
                    c.move_to(p.x, p.y);
                    last = (p.x, p.y);
                }
                PathSegment::LineTo(p) => {
                    c.line_to(p.x, p.y);
                    last = (p.x, p.y);
                }
                PathSegment::QuadTo(q, p) => {
                    let c1 = (
                        last.0 + 2.0 / 3.0 * (q.x - last.0),
                        last.1 + 2.0 / 3.0 * (q.y - last.1),
                    );
                    let c2 = (p.x + 2.0 / 3.0 * (q.x - p.x), p.y + 2.0 / 3.0 * (q.y - p.y));
                    c.cubic_to(c1.0, c1.1, c2.0, c2.1, p.x, p.y);
                    last = (p.x, p.y);
                }
                PathSegment::CubicTo(a, b, p) => {
                    c.cubic_to(a.x, a.y, b.x, b.y, p.x, p.y);
                    last = (p.x, p.y);
                }
                PathSegment::Close => {
                    c.close_path();
                }
            }
        }
    }

    /// The index of `face` in [`Page::fonts`], added on first use.
    fn font(&mut self, face: usvg::fontdb::ID) -> Result<usize> {
        if let Some(k) = self.fonts.iter().position(|f| f.face == face) {
            return Ok(k);
        }
        let units_per_em = self
            .tree
            .fontdb()
            .with_face_data(face, |data, index| {
                ttf_parser::Face::parse(data, index)
                    .ok()
                    .map(|f| f.units_per_em())
            })
            .flatten()
            .ok_or_else(|| self.refuse("a font face that does not parse"))?;
        self.fonts.push(UsedFont {
            face,
            units_per_em: f32::from(units_per_em),
            glyphs: BTreeMap::new(),
        });
        Ok(self.fonts.len() - 1)
    }

    fn text(&mut self, t: &usvg::Text, opacity: f32) -> Result<()> {
        let base = t.abs_transform();
        for span in t.layouted() {
            if !span.visible {
                continue;
            }
            if span.stroke.is_some() {
                return Err(self.refuse("stroked text"));
            }
            let Some(fill) = span.fill.as_ref() else {
                continue;
            };
            let [r, g, b] = self.color(fill.paint())?;
            let size = span.font_size.get();
            self.content.save_state();
            self.content.set_fill_rgb(r, g, b);
            self.alpha(1.0, fill.opacity().get() * opacity);
            self.content.begin_text();
            let mut current = None;
            for pg in &span.positioned_glyphs {
                let k = self.font(pg.font)?;
                let font = &mut self.fonts[k];
                font.glyphs
                    .entry(pg.id.0)
                    .or_insert_with(|| pg.text.clone());
                // glyph space (1 em = 1 text unit at size 1) → the outline's placement
                let em = font.units_per_em / size;
                let m = base.pre_concat(pg.outline_transform()).pre_scale(em, em);
                if current != Some(k) {
                    self.content
                        .set_font(Name(format!("F{k}").as_bytes()), size);
                    current = Some(k);
                }
                self.content
                    .set_text_matrix([m.sx, m.ky, m.kx, m.sy, m.tx, m.ty]);
                self.content.show(Str(&pg.id.0.to_be_bytes()));
            }
            self.content.end_text();
            self.content.restore_state();
        }
        Ok(())
    }
}

/// zlib stream (FlateDecode) of `data`.
fn deflate(data: &[u8]) -> Vec<u8> {
    miniz_oxide::deflate::compress_to_vec_zlib(data, 6)
}

/// A one-page PDF of `tree`, `dpi` SVG user units per inch (the page is the SVG size at
/// that resolution), the glyphs used of the bundled faces embedded as a TrueType subset.
///
/// # Errors
/// [`Error::Vector`] naming `figure` when the tree holds something the writer does not
/// draw (module docs) or a font face does not parse or subset.
pub(crate) fn pdf(tree: &usvg::Tree, dpi: f64, figure: &'static str) -> Result<Vec<u8>> {
    let k = (72.0 / dpi) as f32;
    let (w, h) = (tree.size().width() * k, tree.size().height() * k);
    let mut page = Page {
        tree,
        figure,
        content: Content::new(),
        fonts: Vec::new(),
        alphas: BTreeMap::new(),
    };
    page.content.transform([k, 0.0, 0.0, -k, 0.0, h]);
    page.group(tree.root(), 1.0)?;
    let Page {
        content,
        fonts,
        alphas,
        ..
    } = page;

    let mut next = 0;
    let mut alloc = || {
        next += 1;
        Ref::new(next)
    };
    let (catalog, pages, page_ref, content_ref) = (alloc(), alloc(), alloc(), alloc());
    let font_refs: Vec<[Ref; 5]> = fonts
        .iter()
        .map(|_| [alloc(), alloc(), alloc(), alloc(), alloc()])
        .collect();
    let alpha_refs: Vec<Ref> = alphas.iter().map(|_| alloc()).collect();

    let mut pdf = Pdf::new();
    pdf.catalog(catalog).pages(pages);
    pdf.pages(pages).kids([page_ref]).count(1);
    {
        let mut p = pdf.page(page_ref);
        p.media_box(Rect::new(0.0, 0.0, w, h))
            .parent(pages)
            .contents(content_ref);
        let mut res = p.resources();
        {
            let mut f = res.fonts();
            for (k, r) in font_refs.iter().enumerate() {
                f.pair(Name(format!("F{k}").as_bytes()), r[0]);
            }
        }
        {
            let mut g = res.ext_g_states();
            for ((_, k), r) in alphas.iter().zip(&alpha_refs) {
                g.pair(Name(format!("G{k}").as_bytes()), *r);
            }
        }
    }
    pdf.stream(content_ref, &deflate(&content.finish()))
        .filter(Filter::FlateDecode);
    for (&(stroke, fill), r) in alphas.keys().zip(&alpha_refs) {
        pdf.ext_graphics(*r)
            .stroking_alpha(f32::from_bits(stroke))
            .non_stroking_alpha(f32::from_bits(fill));
    }
    for (font, refs) in fonts.iter().zip(&font_refs) {
        write_font(&mut pdf, tree, font, *refs, figure)?;
    }
    Ok(pdf.finish())
}

/// What the PDF needs of one face: its PostScript name, the advance of each glyph used
/// (1/1000 em), its metrics (1/1000 em) and the TrueType subset of the glyphs used.
struct FaceInfo {
    name: String,
    widths: Vec<(u16, f32)>,
    bbox: Rect,
    ascent: f32,
    descent: f32,
    cap_height: f32,
    bold: bool,
    subset: Vec<u8>,
}

/// [`FaceInfo`] of the face `data` (index `index`) for the glyphs `used`.
///
/// # Errors
/// A message when the face does not parse or subset.
fn face_info(
    data: &[u8],
    index: u32,
    used: &BTreeSet<u16>,
    font: &UsedFont,
) -> std::result::Result<FaceInfo, String> {
    let face = ttf_parser::Face::parse(data, index).map_err(|e| e.to_string())?;
    let to_pdf = |v: i16| f32::from(v) / font.units_per_em * 1000.0;
    let b = face.global_bounding_box();
    Ok(FaceInfo {
        name: face
            .names()
            .into_iter()
            .filter(|n| n.name_id == ttf_parser::name_id::POST_SCRIPT_NAME)
            .find_map(|n| n.to_string())
            .unwrap_or_else(|| "Font".into()),
        widths: used
            .iter()
            .map(|&g| {
                let adv = face.glyph_hor_advance(ttf_parser::GlyphId(g)).unwrap_or(0);
                (g, f32::from(adv) / font.units_per_em * 1000.0)
            })
            .collect(),
        bbox: Rect::new(
            to_pdf(b.x_min),
            to_pdf(b.y_min),
            to_pdf(b.x_max),
            to_pdf(b.y_max),
        ),
        ascent: to_pdf(face.ascender()),
        descent: to_pdf(face.descender()),
        cap_height: to_pdf(face.capital_height().unwrap_or(face.ascender())),
        bold: face.is_bold(),
        subset: subset::subset(data, used)?,
    })
}

/// The five objects of one embedded face: Type0 font, CIDFontType2, descriptor, ToUnicode
/// map, font file.
fn write_font(
    pdf: &mut Pdf,
    tree: &usvg::Tree,
    font: &UsedFont,
    [type0, cid, descriptor, cmap, file]: [Ref; 5],
    figure: &'static str,
) -> Result<()> {
    let err = |message: String| Error::Vector {
        figure,
        message: format!("PDF: {message}"),
    };
    let used: BTreeSet<u16> = font.glyphs.keys().copied().collect();
    let face = tree
        .fontdb()
        .with_face_data(font.face, |data, index| face_info(data, index, &used, font))
        .ok_or_else(|| err("a font face of the drawing is not in the font database".into()))?
        .map_err(err)?;
    // subset tag: six capitals from a hash of the glyphs used (deterministic)
    let ids: Vec<u8> = used.iter().flat_map(|g| g.to_be_bytes()).collect();
    let hash = crate::vector::fnv1a(&ids);
    let tag: String = (0..6)
        .map(|i| char::from(b'A' + ((hash >> (5 * i)) % 26) as u8))
        .collect();
    let base = format!("{tag}+{}", face.name);

    pdf.type0_font(type0)
        .base_font(Name(base.as_bytes()))
        .encoding_predefined(Name(b"Identity-H"))
        .descendant_font(cid)
        .to_unicode(cmap);
    {
        let mut c = pdf.cid_font(cid);
        c.subtype(CidFontType::Type2)
            .base_font(Name(base.as_bytes()))
            .system_info(SYSTEM_INFO)
            .font_descriptor(descriptor)
            .default_width(0.0)
            .cid_to_gid_map_predefined(Name(b"Identity"));
        let mut wr = c.widths();
        for &(g, width) in &face.widths {
            wr.consecutive(g, [width]);
        }
    }
    pdf.font_descriptor(descriptor)
        .name(Name(base.as_bytes()))
        .flags(FontFlags::SYMBOLIC)
        .bbox(face.bbox)
        .italic_angle(0.0)
        .ascent(face.ascent)
        .descent(face.descent)
        .cap_height(face.cap_height)
        .stem_v(if face.bold { 140.0 } else { 80.0 })
        .font_file2(file);
    let mut map = UnicodeCmap::new(Name(b"Custom"), SYSTEM_INFO);
    for (&g, text) in &font.glyphs {
        if !text.is_empty() {
            map.pair_with_multiple(g, text.chars());
        }
    }
    pdf.cmap(cmap, &map.finish());
    let packed = deflate(&face.subset);
    let mut s = pdf.stream(file, &packed);
    s.filter(Filter::FlateDecode);
    s.pair(Name(b"Length1"), face.subset.len() as i32);
    s.finish();
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use crate::samples;

    /// The `stream … endstream` bodies of `pdf` with their dictionaries, inflated where
    /// FlateDecode.
    fn streams(pdf: &[u8]) -> Vec<(String, Vec<u8>)> {
        let mut out = Vec::new();
        let mut at = 0;
        while let Some(i) = find(&pdf[at..], b"stream\n").map(|i| at + i) {
            if pdf[..i].ends_with(b"end") {
                at = i + 7;
                continue;
            }
            let dict_start = pdf[..i].windows(2).rposition(|w| w == b"<<").unwrap_or(0);
            let dict = String::from_utf8_lossy(&pdf[dict_start..i]).into_owned();
            let end = i + 7 + find(&pdf[i + 7..], b"\nendstream").expect("endstream");
            let body = &pdf[i + 7..end];
            let body = if dict.contains("/FlateDecode") {
                miniz_oxide::inflate::decompress_to_vec_zlib(body).expect("inflates")
            } else {
                body.to_vec()
            };
            out.push((dict, body));
            at = end + 10;
        }
        out
    }

    fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
        hay.windows(needle.len()).position(|w| w == needle)
    }

    /// The bytes of the PDF strings shown by `Tj` in `content` (literal or hex).
    fn shown(content: &[u8]) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let mut i = 0;
        while i < content.len() {
            match content[i] {
                b'(' => {
                    let mut s = Vec::new();
                    i += 1;
                    while content[i] != b')' {
                        if content[i] == b'\\' {
                            i += 1;
                            if content[i].is_ascii_digit() {
                                let mut v = 0u8;
                                for _ in 0..3 {
                                    if i < content.len() && (b'0'..=b'7').contains(&content[i]) {
                                        v = v * 8 + (content[i] - b'0');
                                        i += 1;
                                    }
                                }
                                s.push(v);
                                continue;
                            }
                            s.push(match content[i] {
                                b'n' => b'\n',
                                b'r' => b'\r',
                                b't' => b'\t',
                                b'b' => 8,
                                b'f' => 12,
                                c => c,
                            });
                        } else {
                            s.push(content[i]);
                        }
                        i += 1;
                    }
                    out.push(s);
                }
                b'<' => {
                    let end = i + find(&content[i..], b">").unwrap();
                    let hex = String::from_utf8_lossy(&content[i + 1..end]).into_owned();
                    out.push(
                        (0..hex.len() / 2)
                            .map(|k| u8::from_str_radix(&hex[2 * k..2 * k + 2], 16).unwrap())
                            .collect(),
                    );
                    i = end;
                }
                _ => {}
            }
            i += 1;
        }
        out
    }

    /// A figure's PDF: the same bytes on every render, every label of the figure's SVG
    /// found again as text through the ToUnicode map, the embedded subset a TrueType font
    /// holding the outlines of the glyphs shown.
    #[test]
    fn the_pdf_is_deterministic_and_its_text_reads_back() {
        let fig = samples::vg();
        let pdf = crate::render::render_pdf(&fig).unwrap();
        assert_eq!(
            pdf,
            crate::render::render_pdf(&fig).unwrap(),
            "deterministic"
        );
        let streams = streams(&pdf);
        let content = &streams
            .iter()
            .find(|(_, b)| find(b, b" Tj").is_some())
            .expect("a content stream with text")
            .1;
        // ToUnicode: <gid> <utf-16be> pairs
        let mut to_unicode: BTreeMap<u16, String> = BTreeMap::new();
        for (_, body) in streams
            .iter()
            .filter(|(_, b)| find(b, b"beginbfchar").is_some())
        {
            let text = String::from_utf8_lossy(body);
            for line in text.lines() {
                let parts: Vec<&str> = line.split_whitespace().collect();
                if parts.len() == 2 && parts[0].starts_with('<') && parts[1].starts_with('<') {
                    let hex = |s: &str| s.trim_matches(|c| c == '<' || c == '>').to_string();
                    let gid = u16::from_str_radix(&hex(parts[0]), 16).unwrap();
                    let u = hex(parts[1]);
                    let units: Vec<u16> = (0..u.len() / 4)
                        .map(|k| u16::from_str_radix(&u[4 * k..4 * k + 4], 16).unwrap())
                        .collect();
                    to_unicode.insert(gid, String::from_utf16(&units).unwrap());
                }
            }
        }
        let mut text = String::new();
        let mut gids = std::collections::BTreeSet::new();
        for s in shown(content) {
            for pair in s.chunks(2) {
                let gid = u16::from_be_bytes([pair[0], pair[1]]);
                gids.insert(gid);
                if let Some(t) = to_unicode.get(&gid) {
                    text.push_str(t);
                }
            }
        }
        let svg = crate::render::render_svg_text(&fig).unwrap();
        let mut labels = 0;
        for part in svg.split("<text").skip(1) {
            let label = &part[part.find('>').unwrap() + 1..part.find("</text>").unwrap()];
            let label: String = label
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&amp;", "&")
                .split_whitespace()
                .collect();
            if label.is_empty() {
                continue;
            }
            labels += 1;
            let read: String = text.split_whitespace().collect();
            assert!(
                read.contains(&label),
                "label `{label}` not in the PDF's text"
            );
        }
        assert!(labels > 10, "{labels} labels");
        // the subsets (DejaVu Sans, and its bold for the panel letters or titles): every
        // glyph shown has an outline in one of them
        let faces: Vec<ttf_parser::Face> = streams
            .iter()
            .filter(|(d, _)| d.contains("/Length1"))
            .map(|(_, b)| ttf_parser::Face::parse(b, 0).expect("the subset parses"))
            .collect();
        assert!(
            (1..=2).contains(&faces.len()),
            "{} embedded faces",
            faces.len()
        );
        let space = faces[0].glyph_index(' ').map(|g| g.0);
        for &g in gids.iter().filter(|&&g| Some(g) != space) {
            assert!(
                faces
                    .iter()
                    .any(|f| f.glyph_bounding_box(ttf_parser::GlyphId(g)).is_some()),
                "glyph {g} shown without an outline"
            );
        }
        assert!(pdf.len() < 60_000, "{} bytes", pdf.len());
    }
}
