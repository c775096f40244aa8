//! Vector output that looks the same everywhere: the SVG with its text turned into glyph
//! outlines of the bundled DejaVu Sans (a viewer without that font would otherwise draw the
//! labels in its own sans-serif, whose widths differ from the ones the layout measured), and
//! PDF with the font subset embedded (text stays selectable).
//!
//! Both go through one parse of the SVG that plotters writes (`usvg`, with a font database
//! holding only the bundled faces, so no system font is ever looked up): the laid-out glyphs
//! replace each `<text>` of plotters' SVG ([`outlined`]), or the tree goes to [`crate::pdf`].

use std::sync::{Arc, OnceLock};

use crate::error::{Error, Result};
use crate::style::{DEJAVU_SANS, DEJAVU_SANS_BOLD};

/// The bundled faces as the only fonts, `sans-serif` (plotters' family) mapped to them.
fn fonts() -> Arc<usvg::fontdb::Database> {
    static DB: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    DB.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_font_data(DEJAVU_SANS.to_vec());
        db.load_font_data(DEJAVU_SANS_BOLD.to_vec());
        db.set_sans_serif_family("DejaVu Sans");
        Arc::new(db)
    })
    .clone()
}

/// Parses plotters' SVG with the bundled fonts (text is shaped and laid out here).
///
/// # Errors
/// [`Error::Vector`] naming `figure` when the SVG cannot be parsed.
pub(crate) fn parse(svg: &str, figure: &'static str) -> Result<usvg::Tree> {
    let opt = usvg::Options {
        font_family: "DejaVu Sans".into(),
        fontdb: fonts(),
        ..usvg::Options::default()
    };
    usvg::Tree::from_str(svg, &opt).map_err(|e| Error::Vector {
        figure,
        message: format!("SVG not parsed: {e}"),
    })
}

/// Marker given to every `<text>` of plotters' SVG before parsing, so that each laid-out
/// text of the tree is found again in the source by its id.
const TEXT_ID: &str = "aeroform-text-";

/// Gives every `<text` element of `source` the id `aeroform-text-<n>`, n in document order.
pub(crate) fn tag_texts(source: &str) -> String {
    let mut out = String::with_capacity(source.len() + source.len() / 20);
    let mut rest = source;
    let mut n = 0usize;
    while let Some(i) = rest.find("<text ") {
        out.push_str(&rest[..i + 6]);
        out.push_str(&format!("id=\"{TEXT_ID}{n}\" "));
        n += 1;
        rest = &rest[i + 6..];
    }
    out.push_str(rest);
    out
}

/// The SVG `tagged` (plotters' SVG after [`tag_texts`]; `tree` is its parse) with every
/// `<text>` replaced by glyph outlines of the bundled font: each glyph used is defined once
/// in `<defs>` (font units) and placed by `<use>` with the transform the layout gave it —
/// the shape of matplotlib's `svg.fonttype = "path"`; the text itself stays in an
/// `aria-label` on the glyphs' group. Element ids are prefixed with a hash
/// of the drawing so several figures inlined in one HTML page never share an id. Relies on
/// plotters writing a flat document (no transformed groups around text), which its SVG
/// backend does.
///
/// # Errors
/// [`Error::Vector`] naming `figure` when a glyph of the layout has no outline in the
/// bundled font.
pub(crate) fn outlined(tree: &usvg::Tree, tagged: &str, figure: &'static str) -> Result<String> {
    let prefix = format!("f{:08x}", fnv1a(tagged.as_bytes()) as u32);
    let mut texts = Vec::new();
    collect_texts(tree.root(), &mut texts);
    let mut glyphs: std::collections::BTreeMap<(usvg::fontdb::ID, u16), usize> =
        std::collections::BTreeMap::new();
    let mut defs = String::new();
    let mut replaced: std::collections::HashMap<String, String> = std::collections::HashMap::new();
    for text in texts {
        let base = text.abs_transform();
        let mut g = String::new();
        for span in text.layouted() {
            if !span.visible {
                continue;
            }
            let Some(fill) = span.fill.as_ref() else {
                continue;
            };
            let usvg::Paint::Color(c) = fill.paint() else {
                continue;
            };
            let opacity = fill.opacity().get();
            g.push_str(&format!(
                "<g fill=\"#{:02x}{:02x}{:02x}\"{}>",
                c.red,
                c.green,
                c.blue,
                if opacity < 1.0 {
                    format!(" fill-opacity=\"{opacity}\"")
                } else {
                    String::new()
                }
            ));
            for pg in &span.positioned_glyphs {
                let key = (pg.font, pg.id.0);
                let k = match glyphs.get(&key) {
                    Some(&k) => k,
                    None => {
                        let k = glyphs.len();
                        let d = glyph_path(tree, pg.font, pg.id).ok_or_else(|| Error::Vector {
                            figure,
                            message: format!("glyph for {:?} has no outline", pg.text),
                        })?;
                        defs.push_str(&format!("<path id=\"{prefix}-g{k}\" d=\"{d}\"/>"));
                        glyphs.insert(key, k);
                        k
                    }
                };
                let t = base.pre_concat(pg.outline_transform());
                g.push_str(&format!(
                    "<use xlink:href=\"#{prefix}-g{k}\" transform=\"matrix({} {} {} {} {} {})\"/>",
                    num(t.sx, 6),
                    num(t.ky, 6),
                    num(t.kx, 6),
                    num(t.sy, 6),
                    num(t.tx, 2),
                    num(t.ty, 2)
                ));
            }
            g.push_str("</g>");
        }
        replaced.insert(text.id().to_string(), g);
    }
    // splice: every tagged <text …>…</text> → its glyphs (nothing when usvg dropped it)
    let mut out = String::with_capacity(tagged.len());
    let mut rest = tagged;
    while let Some(i) = rest.find("<text ") {
        out.push_str(&rest[..i]);
        let after = &rest[i..];
        let Some(close) = after.find("</text>") else {
            return Err(Error::Vector {
                figure,
                message: "unclosed <text> in the SVG".into(),
            });
        };
        let element = &after[..close];
        let id = element
            .find(TEXT_ID)
            .map(|j| {
                let tail = &element[j..];
                &tail[..tail.find('"').unwrap_or(tail.len())]
            })
            .unwrap_or("");
        if let Some(g) = replaced.get(id) {
            // the label stays readable (screen readers, search, grep) as an aria-label
            let content = element.find('>').map_or("", |j| element[j + 1..].trim());
            out.push_str(&format!(
                "<g aria-label=\"{}\">{g}</g>",
                content.replace('"', "&quot;")
            ));
        }
        rest = &after[close + "</text>".len()..];
    }
    out.push_str(rest);
    // the glyph table right after the root element's start tag
    let Some(root_end) = out.find('>') else {
        return Err(Error::Vector {
            figure,
            message: "no root element in the SVG".into(),
        });
    };
    let mut head = out[..root_end].to_string();
    if !head.contains("xmlns:xlink") {
        head.push_str(" xmlns:xlink=\"http://www.w3.org/1999/xlink\"");
    }
    Ok(format!(
        "{head}>\n<defs>{defs}</defs>{}",
        &out[root_end + 1..]
    ))
}

/// Every text node of `group`, depth first in document order.
fn collect_texts<'a>(group: &'a usvg::Group, out: &mut Vec<&'a usvg::Text>) {
    for node in group.children() {
        match node {
            usvg::Node::Group(g) => collect_texts(g, out),
            usvg::Node::Text(t) => out.push(t),
            _ => {}
        }
    }
}

/// The outline of glyph `glyph` of font `font` as SVG path data in font units (y up), or
/// None when the font has no outline for it (a space has an empty one: `Some("")`).
fn glyph_path(
    tree: &usvg::Tree,
    font: usvg::fontdb::ID,
    glyph: ttf_parser::GlyphId,
) -> Option<String> {
    tree.fontdb().with_face_data(font, |data, index| {
        let face = ttf_parser::Face::parse(data, index).ok()?;
        let mut d = PathData(String::new());
        // an empty glyph (space) has no outline: an empty path
        face.outline_glyph(glyph, &mut d);
        Some(d.0)
    })?
}

/// SVG path data from ttf-parser's outline callbacks (font units, integers mostly).
struct PathData(String);

impl ttf_parser::OutlineBuilder for PathData {
    fn move_to(&mut self, x: f32, y: f32) {
        self.0.push_str(&format!("M{} {}", num(x, 1), num(y, 1)));
    }
    fn line_to(&mut self, x: f32, y: f32) {
        self.0.push_str(&format!("L{} {}", num(x, 1), num(y, 1)));
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        self.0.push_str(&format!(
            "Q{} {} {} {}",
            num(x1, 1),
            num(y1, 1),
            num(x, 1),
            num(y, 1)
        ));
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        self.0.push_str(&format!(
            "C{} {} {} {} {} {}",
            num(x1, 1),
            num(y1, 1),
            num(x2, 1),
            num(y2, 1),
            num(x, 1),
            num(y, 1)
        ));
    }
    fn close(&mut self) {
        self.0.push('Z');
    }
}

/// `x` with at most `digits` decimals, trailing zeros and a negative zero removed.
fn num(x: f32, digits: usize) -> String {
    let s = format!("{x:.digits$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// 64-bit FNV-1a hash (deterministic across runs and platforms, unlike `DefaultHasher`).
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
