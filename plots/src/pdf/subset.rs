//! A TrueType subset for embedding in a PDF (`FontFile2` of a `CIDFontType2` with the
//! identity CID → glyph map): glyph ids stay as they are, the outlines of the glyphs not
//! used are emptied (zero-length `glyf` entries), and the tables a PDF viewer does not read
//! are dropped (OpenType layout, kerning, glyph names, the `name` table).
//!
//! Keeping the ids makes the subset a pure byte copy of the used outlines: the `loca`
//! and `hmtx` tables keep one entry per glyph of the face (DejaVu Sans: 6,253 glyphs,
//! ≈ 50 kB before compression, a few kB after).

use std::collections::BTreeSet;

/// Tables kept, in the order of the font's table directory (sorted by tag, as the
/// OpenType specification asks). `post` is rewritten to version 3 (no glyph names).
const KEPT: [&[u8; 4]; 12] = [
    b"OS/2", b"cmap", b"cvt ", b"fpgm", b"glyf", b"head", b"hhea", b"hmtx", b"loca", b"maxp",
    b"post", b"prep",
];

/// One table of the face: tag and bytes.
struct Table<'a> {
    tag: [u8; 4],
    data: &'a [u8],
}

fn u16_at(d: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes(d.get(at..at + 2)?.try_into().ok()?))
}

fn u32_at(d: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(d.get(at..at + 4)?.try_into().ok()?))
}

/// The table directory of a single-face TrueType file.
fn tables(font: &[u8]) -> Result<Vec<Table<'_>>, String> {
    let version = u32_at(font, 0).ok_or("font shorter than its header")?;
    if version != 0x0001_0000 && version != u32::from_be_bytes(*b"true") {
        return Err(format!(
            "not a TrueType outline font (sfnt version {version:#010x})"
        ));
    }
    let n = usize::from(u16_at(font, 4).ok_or("font shorter than its header")?);
    (0..n)
        .map(|i| {
            let rec = 12 + 16 * i;
            let tag: [u8; 4] = font
                .get(rec..rec + 4)
                .and_then(|t| t.try_into().ok())
                .ok_or("table directory runs past the end of the font")?;
            let offset = u32_at(font, rec + 8).ok_or("table directory truncated")? as usize;
            let length = u32_at(font, rec + 12).ok_or("table directory truncated")? as usize;
            let data = font
                .get(offset..offset.saturating_add(length))
                .ok_or_else(|| {
                    format!("table `{}` runs past the end of the font", tag_name(&tag))
                })?;
            Ok(Table { tag, data })
        })
        .collect()
}

fn tag_name(tag: &[u8; 4]) -> String {
    String::from_utf8_lossy(tag).into_owned()
}

fn find<'a>(tables: &[Table<'a>], tag: &[u8; 4]) -> Result<&'a [u8], String> {
    tables
        .iter()
        .find(|t| &t.tag == tag)
        .map(|t| t.data)
        .ok_or_else(|| format!("the font has no `{}` table", tag_name(tag)))
}

/// Glyph `g`'s byte range in `glyf` from `loca` (short or long offsets).
fn glyph_range(loca: &[u8], long: bool, g: usize) -> Result<(usize, usize), String> {
    let at = |i: usize| -> Option<usize> {
        if long {
            u32_at(loca, 4 * i).map(|v| v as usize)
        } else {
            u16_at(loca, 2 * i).map(|v| 2 * usize::from(v))
        }
    };
    match (at(g), at(g + 1)) {
        (Some(a), Some(b)) if a <= b => Ok((a, b)),
        _ => Err(format!("`loca` has no valid entry for glyph {g}")),
    }
}

/// The glyphs a composite glyph's outline is built from (an empty list for a simple one).
fn components(glyph: &[u8]) -> Result<Vec<u16>, String> {
    let mut out = Vec::new();
    let Some(contours) = u16_at(glyph, 0).map(|v| v as i16) else {
        return Ok(out); // empty glyph
    };
    if contours >= 0 {
        return Ok(out);
    }
    let mut at = 10;
    loop {
        let flags = u16_at(glyph, at).ok_or("composite glyph truncated")?;
        out.push(u16_at(glyph, at + 2).ok_or("composite glyph truncated")?);
        at += 4;
        at += if flags & 0x0001 != 0 { 4 } else { 2 }; // ARG_1_AND_2_ARE_WORDS
        if flags & 0x0008 != 0 {
            at += 2; // WE_HAVE_A_SCALE
        } else if flags & 0x0040 != 0 {
            at += 4; // WE_HAVE_AN_X_AND_Y_SCALE
        } else if flags & 0x0080 != 0 {
            at += 8; // WE_HAVE_A_TWO_BY_TWO
        }
        if flags & 0x0020 == 0 {
            return Ok(out); // no MORE_COMPONENTS
        }
    }
}

/// Sum of the big-endian 32-bit words of `data` (zero-padded), the OpenType table checksum.
fn checksum(data: &[u8]) -> u32 {
    data.chunks(4).fold(0u32, |sum, c| {
        let mut w = [0u8; 4];
        w[..c.len()].copy_from_slice(c);
        sum.wrapping_add(u32::from_be_bytes(w))
    })
}

/// The TrueType font `font` with only the outlines of `glyphs` (and of the glyphs their
/// composites use, and glyph 0, `.notdef`) kept.
///
/// # Errors
/// A message naming what is malformed when `font` is not a TrueType outline font or one
/// of its tables is truncated (the bundled faces never are).
pub(crate) fn subset(font: &[u8], glyphs: &BTreeSet<u16>) -> Result<Vec<u8>, String> {
    let tables = tables(font)?;
    let head = find(&tables, b"head")?;
    let long = match u16_at(head, 50) {
        Some(0) => false,
        Some(1) => true,
        _ => return Err("`head` has no valid indexToLocFormat".into()),
    };
    let n_glyphs = usize::from(u16_at(find(&tables, b"maxp")?, 4).ok_or("`maxp` truncated")?);
    let loca = find(&tables, b"loca")?;
    let glyf = find(&tables, b"glyf")?;
    let outline = |g: usize| -> Result<&[u8], String> {
        let (a, b) = glyph_range(loca, long, g)?;
        glyf.get(a..b)
            .ok_or_else(|| format!("glyph {g} runs past the end of `glyf`"))
    };

    // the glyphs kept: the ones asked for, .notdef, and every composite's components
    let mut keep = BTreeSet::new();
    let mut todo: Vec<u16> = glyphs.iter().copied().chain([0]).collect();
    while let Some(g) = todo.pop() {
        if usize::from(g) >= n_glyphs {
            return Err(format!("glyph {g} is not in the font ({n_glyphs} glyphs)"));
        }
        if keep.insert(g) {
            todo.extend(components(outline(usize::from(g))?)?);
        }
    }

    let mut new_glyf = Vec::new();
    let mut offsets = Vec::with_capacity(n_glyphs + 1);
    for g in 0..n_glyphs {
        offsets.push(new_glyf.len());
        if keep.contains(&(g as u16)) {
            new_glyf.extend_from_slice(outline(g)?);
            // short offsets count words: every glyph starts on an even offset
            while new_glyf.len() % if long { 4 } else { 2 } != 0 {
                new_glyf.push(0);
            }
        }
    }
    offsets.push(new_glyf.len());
    let mut new_loca = Vec::with_capacity(offsets.len() * if long { 4 } else { 2 });
    for o in offsets {
        if long {
            new_loca.extend_from_slice(&(o as u32).to_be_bytes());
        } else {
            let half = u16::try_from(o / 2)
                .map_err(|_| "subset too large for short `loca` offsets".to_string())?;
            new_loca.extend_from_slice(&half.to_be_bytes());
        }
    }
    let mut new_head = head.to_vec();
    new_head
        .get_mut(8..12)
        .ok_or("`head` truncated")?
        .copy_from_slice(&[0; 4]); // checkSumAdjustment, set below
    let post = find(&tables, b"post")
        .ok()
        .and_then(|p| p.get(..32))
        .map(|p| {
            let mut p = p.to_vec();
            p[..4].copy_from_slice(&0x0003_0000u32.to_be_bytes());
            p
        });

    let mut out_tables: Vec<([u8; 4], Vec<u8>)> = Vec::new();
    for tag in KEPT {
        let data = match tag {
            b"glyf" => new_glyf.clone(),
            b"loca" => new_loca.clone(),
            b"head" => new_head.clone(),
            b"post" => match &post {
                Some(p) => p.clone(),
                None => continue,
            },
            _ => match find(&tables, tag) {
                Ok(d) => d.to_vec(),
                Err(_) => continue,
            },
        };
        out_tables.push((*tag, data));
    }

    // the sfnt: header, directory, the tables 4-byte aligned
    let n = out_tables.len() as u16;
    let entry_selector = 15 - n.leading_zeros() as u16; // floor(log2 n)
    let search_range = 16u16 << entry_selector;
    let mut out = Vec::new();
    out.extend_from_slice(&0x0001_0000u32.to_be_bytes());
    for v in [n, search_range, entry_selector, n * 16 - search_range] {
        out.extend_from_slice(&v.to_be_bytes());
    }
    let mut offset = 12 + 16 * out_tables.len();
    let mut head_at = 0;
    for (tag, data) in &out_tables {
        if tag == b"head" {
            head_at = offset;
        }
        out.extend_from_slice(tag);
        out.extend_from_slice(&checksum(data).to_be_bytes());
        out.extend_from_slice(&(offset as u32).to_be_bytes());
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        offset += data.len().div_ceil(4) * 4;
    }
    for (_, data) in &out_tables {
        out.extend_from_slice(data);
        out.resize(out.len().div_ceil(4) * 4, 0);
    }
    let adjust = 0xB1B0_AFBAu32.wrapping_sub(checksum(&out));
    out[head_at + 8..head_at + 12].copy_from_slice(&adjust.to_be_bytes());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::style::DEJAVU_SANS;

    /// The subset parses, keeps the outlines asked for (and a composite's parts), empties
    /// the others, and its checksums add up as OpenType asks.
    #[test]
    fn subset_keeps_the_glyphs_asked_for_and_empties_the_rest() {
        let face = ttf_parser::Face::parse(DEJAVU_SANS, 0).unwrap();
        let a = face.glyph_index('a').unwrap();
        let b = face.glyph_index('b').unwrap();
        // 'é' is a composite in DejaVu Sans ('e' + acute)
        let e_acute = face.glyph_index('é').unwrap();
        let keep = BTreeSet::from([a.0, e_acute.0]);
        let sub = subset(DEJAVU_SANS, &keep).unwrap();
        assert!(sub.len() < DEJAVU_SANS.len() / 4, "{} bytes", sub.len());
        let s = ttf_parser::Face::parse(&sub, 0).unwrap();
        assert_eq!(s.number_of_glyphs(), face.number_of_glyphs());
        let bbox = |f: &ttf_parser::Face, g| f.glyph_bounding_box(g);
        assert_eq!(bbox(&s, a), bbox(&face, a));
        assert_eq!(bbox(&s, e_acute), bbox(&face, e_acute));
        let e = face.glyph_index('e').unwrap();
        assert!(bbox(&s, e).is_some(), "a composite's component is kept");
        assert!(
            bbox(&face, b).is_some() && bbox(&s, b).is_none(),
            "unused outline emptied"
        );
        assert_eq!(s.glyph_hor_advance(b), face.glyph_hor_advance(b));
        // whole-font checksum: 0xB1B0AFBA once checkSumAdjustment is in
        assert_eq!(checksum(&sub), 0xB1B0_AFBA);
    }

    #[test]
    fn a_font_that_is_not_truetype_is_refused_by_message() {
        let err = subset(b"OTTO\0\0\0\0", &BTreeSet::new()).unwrap_err();
        assert!(err.contains("not a TrueType"), "{err}");
        let err = subset(&DEJAVU_SANS[..200], &BTreeSet::new()).unwrap_err();
        assert!(err.contains("past the end"), "{err}");
    }
}
