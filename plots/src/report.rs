//! A minimal self-contained HTML report: a navigation bar, sections with anchors,
//! paragraphs, key–value tables, data tables (wrapped so a wide one scrolls inside its box
//! instead of widening the page), preformatted text, links to result files and inline SVG
//! figures. No external resources (no CDN, no web fonts, no scripts). The page fits a
//! 420 px phone and prints on A4 without cut columns (print CSS wraps cells and shrinks
//! tables); `tests/report_headless.rs` checks both widths in headless Chromium.

use std::path::Path;

use crate::error::Result;
use crate::render::FigureFiles;

/// One block of the report body, in order.
#[derive(Debug, Clone, PartialEq)]
enum Block {
    Section(String),
    Text(String),
    KeyValues {
        caption: String,
        rows: Vec<(String, String)>,
    },
    Table {
        caption: String,
        header: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    Figure {
        caption: String,
        svg: String,
    },
    Pre {
        caption: String,
        text: String,
    },
    Links {
        caption: String,
        links: Vec<(String, String)>,
    },
}

/// Builder of a self-contained HTML report.
///
/// ```
/// let mut r = plots::Report::new("Study A");
/// r.section("Summary").text("Identified 12 cases.").key_values("Metrics", &[("R²", "0.98")]);
/// assert!(r.to_html().contains("<h2 id=\"summary\">Summary</h2>"));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    title: String,
    blocks: Vec<Block>,
}

/// Escapes `&`, `<`, `>`, `"` and `'` for HTML text and attribute values.
pub fn escape_html(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Prepares a plotters SVG document for inline use: drops an XML prolog and adds a
/// `viewBox` (from `width`/`height`) so CSS can scale it to the page width.
fn inline_svg(svg: &str) -> String {
    let s = svg.trim_start();
    let s = match s.strip_prefix("<?xml") {
        Some(rest) => rest.split_once("?>").map_or(s, |(_, r)| r.trim_start()),
        None => s,
    };
    let Some(start) = s.find("<svg") else {
        return s.to_string();
    };
    let Some(end) = s[start..].find('>').map(|e| start + e) else {
        return s.to_string();
    };
    let tag = &s[start..end];
    if tag.contains("viewBox") {
        return s.to_string();
    }
    let attr = |name: &str| -> Option<String> {
        let key = format!("{name}=\"");
        let i = tag.find(&key)? + key.len();
        let j = tag[i..].find('"')? + i;
        Some(tag[i..j].to_string())
    };
    match (attr("width"), attr("height")) {
        (Some(w), Some(h)) => format!("{} viewBox=\"0 0 {w} {h}\"{}", &s[..end], &s[end..]),
        _ => s.to_string(),
    }
}

/// Splits one CSV line on commas, honouring double-quoted fields with `""` escapes; fields
/// are trimmed ([`identify::csv_fields::split_line`], the workspace's one CSV splitter).
pub fn split_csv_line(line: &str) -> Vec<String> {
    identify::csv_fields::split_line(line)
}

const CSS: &str = "body{font-family:sans-serif;max-width:1300px;margin:2em auto;padding:0 1em;\
color:#222;line-height:1.45}h1{border-bottom:2px solid #0072b2;padding-bottom:.2em;\
overflow-wrap:anywhere}h2{margin-top:1.8em;border-bottom:1px solid #ccc}\
nav{position:sticky;top:0;background:#fff;border-bottom:1px solid #ccc;padding:.4em 0;\
z-index:1;display:flex;flex-wrap:wrap;gap:.3em 1.2em}nav a{color:#0072b2;text-decoration:none}\
nav a:hover,a:hover{text-decoration:underline}h2{scroll-margin-top:3em}\
.scroll{overflow-x:auto;max-width:100%;margin:.8em 0}table{border-collapse:collapse}\
caption{text-align:left;font-weight:bold;padding:.3em 0}th,td{border:1px solid #ccc;\
padding:.25em .7em;text-align:left;vertical-align:top}th{background:#f0f4f8}td.num{text-align:right;\
font-variant-numeric:tabular-nums;white-space:nowrap}td:first-child{white-space:nowrap}\
figure{margin:1.2em 0}figure svg{max-width:100%;height:auto;display:block;border:1px solid #eee}\
figcaption{color:#555;font-size:.95em;margin-top:.3em}pre{background:#f6f8fa;padding:.6em;\
overflow-x:auto;font-size:.9em}p.empty{color:#666;font-style:italic}ul.files{columns:18em;\
padding-left:1.2em}ul.files li{overflow-wrap:anywhere}\
@page{size:A4;margin:12mm}@media print{body{max-width:none;margin:0;font-size:10pt}nav{display:none}\
.scroll{overflow:visible}table{font-size:7.5pt;width:100%}th,td{padding:.1em .3em;\
white-space:normal!important;overflow-wrap:anywhere}figure,tr{break-inside:avoid}\
pre{white-space:pre-wrap;font-size:7.5pt}h2{break-after:avoid}}";

/// The display form of a machine column name of the result CSV files: a unit suffix
/// becomes a bracketed unit (`U_m_s` → `U [m/s]`, `amplitude_deg` → `amplitude [deg]`),
/// Greek names become letters (`K_alpha` → `K_α`, `omega_F_rad_s` → `ω_F [rad/s]`),
/// `R2_lift` → `R² lift`; other names are returned unchanged.
pub fn column_label(name: &str) -> String {
    const UNITS: [(&str, &str); 8] = [
        ("_rad_s", "rad/s"),
        ("_m_s", "m/s"),
        ("_deg", "deg"),
        ("_rad", "rad"),
        ("_Hz", "Hz"),
        ("_hz", "Hz"),
        ("_s", "s"),
        ("_m", "m"),
    ];
    let (stem, unit) = UNITS
        .iter()
        .find_map(|(suf, u)| {
            name.strip_suffix(suf)
                .filter(|s| !s.is_empty())
                .map(|s| (s, Some(*u)))
        })
        .unwrap_or((name, None));
    let mut words: Vec<String> = vec![];
    for w in stem.split('_') {
        let w = match w {
            "alpha" => "α".to_string(),
            "omega" => "ω".to_string(),
            "R2" => "R²".to_string(),
            "rel" => "rel.".to_string(),
            "err" => "error".to_string(),
            "ref" => "published".to_string(),
            w => w.to_string(),
        };
        words.push(w);
    }
    // K_alpha, U_F, omega_F: a one-letter symbol keeps its subscript
    let mut out = String::new();
    for (i, w) in words.iter().enumerate() {
        if i > 0 {
            let prev = &words[i - 1];
            let symbol = prev.chars().count() == 1 && (i == 1 || w.chars().count() == 1);
            out.push(if symbol { '_' } else { ' ' });
        }
        out.push_str(w);
    }
    match unit {
        Some(u) => format!("{out} [{u}]"),
        None => out,
    }
}

/// The anchor of a section heading: lower-case ASCII letters and digits, other runs as `-`.
pub fn anchor(heading: &str) -> String {
    let mut out = String::new();
    for c in heading.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') && !out.is_empty() {
            out.push('-');
        }
    }
    while out.ends_with('-') {
        out.pop();
    }
    if out.is_empty() {
        "section".into()
    } else {
        out
    }
}

fn is_number(s: &str) -> bool {
    !s.is_empty() && s.parse::<f64>().is_ok()
}

impl Report {
    /// An empty report with a page title (also the first heading).
    pub fn new(title: impl Into<String>) -> Self {
        Report {
            title: title.into(),
            blocks: vec![],
        }
    }

    /// Starts a section (an `<h2>` heading).
    pub fn section(&mut self, heading: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Section(heading.into()));
        self
    }

    /// Adds a paragraph of plain text (escaped; blank lines start new paragraphs).
    pub fn text(&mut self, paragraph: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Text(paragraph.into()));
        self
    }

    /// Adds a two-column key–value table.
    pub fn key_values<K: AsRef<str>, V: AsRef<str>>(
        &mut self,
        caption: impl Into<String>,
        rows: &[(K, V)],
    ) -> &mut Self {
        self.blocks.push(Block::KeyValues {
            caption: caption.into(),
            rows: rows
                .iter()
                .map(|(k, v)| (k.as_ref().to_string(), v.as_ref().to_string()))
                .collect(),
        });
        self
    }

    /// Adds a table with a header row; numeric cells are right-aligned. Rows shorter than
    /// the header are padded with empty cells.
    pub fn table<S: AsRef<str>>(
        &mut self,
        caption: impl Into<String>,
        header: &[S],
        rows: &[Vec<S>],
    ) -> &mut Self {
        self.blocks.push(Block::Table {
            caption: caption.into(),
            header: header.iter().map(|s| s.as_ref().to_string()).collect(),
            rows: rows
                .iter()
                .map(|r| r.iter().map(|s| s.as_ref().to_string()).collect())
                .collect(),
        });
        self
    }

    /// Adds a table from CSV text: the first non-empty line is the header; fields are
    /// comma-separated, double quotes protect commas (`""` is a literal quote).
    pub fn csv_table(&mut self, caption: impl Into<String>, csv: &str) -> &mut Self {
        let mut lines = csv.lines().filter(|l| !l.trim().is_empty());
        let header = lines.next().map(split_csv_line).unwrap_or_default();
        let rows: Vec<Vec<String>> = lines.map(split_csv_line).collect();
        self.blocks.push(Block::Table {
            caption: caption.into(),
            header,
            rows,
        });
        self
    }

    /// Embeds a rendered figure (its SVG text, inline) with a caption.
    pub fn figure(&mut self, caption: impl Into<String>, files: &FigureFiles) -> &mut Self {
        self.figure_svg(caption, &files.svg_text)
    }

    /// Embeds an SVG document inline with a caption. The SVG must be trusted (e.g. from
    /// [`crate::render_svg`]): it is inserted as markup, not escaped.
    pub fn figure_svg(&mut self, caption: impl Into<String>, svg: &str) -> &mut Self {
        self.blocks.push(Block::Figure {
            caption: caption.into(),
            svg: inline_svg(svg),
        });
        self
    }

    /// Adds preformatted text (escaped) with a caption, e.g. a study file as it was run.
    pub fn pre(&mut self, caption: impl Into<String>, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Pre {
            caption: caption.into(),
            text: text.into(),
        });
        self
    }

    /// Adds a list of links `(href, label)`, e.g. to the result files next to the report
    /// (relative hrefs, so the folder can be moved). An empty list prints "none".
    pub fn links<H: AsRef<str>, L: AsRef<str>>(
        &mut self,
        caption: impl Into<String>,
        links: &[(H, L)],
    ) -> &mut Self {
        self.blocks.push(Block::Links {
            caption: caption.into(),
            links: links
                .iter()
                .map(|(h, l)| (h.as_ref().to_string(), l.as_ref().to_string()))
                .collect(),
        });
        self
    }

    /// The section headings in order, with their anchors (`#anchor` links of the navigation
    /// bar; a repeated heading gets `-2`, `-3` …).
    pub fn sections(&self) -> Vec<(String, String)> {
        let mut seen: Vec<String> = vec![];
        let mut out = vec![];
        for b in &self.blocks {
            if let Block::Section(s) = b {
                let base = anchor(s);
                let n = seen.iter().filter(|x| **x == base).count();
                seen.push(base.clone());
                let id = if n == 0 {
                    base
                } else {
                    format!("{base}-{}", n + 1)
                };
                out.push((s.clone(), id));
            }
        }
        out
    }

    /// The whole page as HTML5 text (UTF-8, inline CSS, no external resources).
    pub fn to_html(&self) -> String {
        let mut h = String::new();
        h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        h.push_str(&format!("<title>{}</title>\n", escape_html(&self.title)));
        h.push_str(&format!("<style>{CSS}</style>\n</head>\n<body>\n"));
        h.push_str(&format!("<h1>{}</h1>\n", escape_html(&self.title)));
        let sections = self.sections();
        if !sections.is_empty() {
            h.push_str("<nav aria-label=\"sections\">");
            for (s, id) in &sections {
                h.push_str(&format!("<a href=\"#{id}\">{}</a>", escape_html(s)));
            }
            h.push_str("</nav>\n");
        }
        let mut n_fig = 0;
        let mut n_sec = 0;
        for b in &self.blocks {
            match b {
                Block::Section(s) => {
                    let id = &sections[n_sec].1;
                    n_sec += 1;
                    h.push_str(&format!("<h2 id=\"{id}\">{}</h2>\n", escape_html(s)));
                }
                Block::Pre { caption, text } => {
                    if !caption.is_empty() {
                        h.push_str(&format!("<p><b>{}</b></p>\n", escape_html(caption)));
                    }
                    h.push_str(&format!("<pre>{}</pre>\n", escape_html(text)));
                }
                Block::Links { caption, links } => {
                    if !caption.is_empty() {
                        h.push_str(&format!("<p><b>{}</b></p>\n", escape_html(caption)));
                    }
                    if links.is_empty() {
                        h.push_str("<p class=\"empty\">none</p>\n");
                    } else {
                        h.push_str("<ul class=\"files\">\n");
                        for (href, label) in links {
                            h.push_str(&format!(
                                "<li><a href=\"{}\">{}</a></li>\n",
                                escape_html(href),
                                escape_html(label)
                            ));
                        }
                        h.push_str("</ul>\n");
                    }
                }
                Block::Text(t) => {
                    for p in t.split("\n\n").filter(|p| !p.trim().is_empty()) {
                        h.push_str(&format!("<p>{}</p>\n", escape_html(p.trim())));
                    }
                }
                Block::KeyValues { caption, rows } => {
                    h.push_str("<div class=\"scroll\"><table>\n");
                    if !caption.is_empty() {
                        h.push_str(&format!("<caption>{}</caption>\n", escape_html(caption)));
                    }
                    for (k, v) in rows {
                        let class = if is_number(v) { " class=\"num\"" } else { "" };
                        h.push_str(&format!(
                            "<tr><th scope=\"row\">{}</th><td{class}>{}</td></tr>\n",
                            escape_html(k),
                            escape_html(v)
                        ));
                    }
                    h.push_str("</table></div>\n");
                }
                Block::Table {
                    caption,
                    header,
                    rows,
                } => {
                    if rows.is_empty() {
                        h.push_str(&format!(
                            "<p class=\"empty\"><b>{}</b>: no rows.</p>\n",
                            escape_html(caption)
                        ));
                        continue;
                    }
                    h.push_str("<div class=\"scroll\"><table>\n");
                    if !caption.is_empty() {
                        h.push_str(&format!("<caption>{}</caption>\n", escape_html(caption)));
                    }
                    h.push_str("<thead><tr>");
                    for c in header {
                        h.push_str(&format!("<th>{}</th>", escape_html(c)));
                    }
                    h.push_str("</tr></thead>\n<tbody>\n");
                    let width = rows
                        .iter()
                        .map(Vec::len)
                        .chain([header.len()])
                        .max()
                        .unwrap_or(0);
                    for r in rows {
                        h.push_str("<tr>");
                        for i in 0..width {
                            let c = r.get(i).map_or("", String::as_str);
                            let class = if is_number(c) { " class=\"num\"" } else { "" };
                            h.push_str(&format!("<td{class}>{}</td>", escape_html(c)));
                        }
                        h.push_str("</tr>\n");
                    }
                    h.push_str("</tbody>\n</table></div>\n");
                }
                Block::Figure { caption, svg } => {
                    n_fig += 1;
                    h.push_str("<figure>\n");
                    h.push_str(svg);
                    h.push_str(&format!(
                        "\n<figcaption>Figure {n_fig}. {}</figcaption>\n</figure>\n",
                        escape_html(caption)
                    ));
                }
            }
        }
        h.push_str("</body>\n</html>\n");
        h
    }

    /// Writes the page to `path` atomically ([`identify::io::write_atomic`]).
    ///
    /// # Errors
    /// [`crate::Error::Write`] naming `path` when its folder is missing or unwritable.
    pub fn write(&self, path: &Path) -> Result<()> {
        identify::io::write_atomic(path, self.to_html().as_bytes())?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_text_and_tables() {
        let mut r = Report::new("a < b & c");
        r.text("x <script>").table("t", &["h<1>"], &[vec!["1.5"]]);
        let h = r.to_html();
        assert!(h.contains("<title>a &lt; b &amp; c</title>"));
        assert!(h.contains("x &lt;script&gt;"));
        assert!(!h.contains("<script>"));
        assert!(h.contains("<th>h&lt;1&gt;</th>"));
        assert!(h.contains("<td class=\"num\">1.5</td>"));
    }

    #[test]
    fn csv_table_handles_quotes_and_ragged_rows() {
        assert_eq!(
            split_csv_line("a, \"b,c\" ,\"d\"\"e\""),
            vec!["a", "b,c", "d\"e"]
        );
        let mut r = Report::new("t");
        r.csv_table("cases", "case,R2\nA-1,0.98\nA-2\n");
        let h = r.to_html();
        assert!(h.contains("<th>case</th><th>R2</th>"));
        assert!(h.contains("<td>A-2</td><td></td>"), "{h}");
    }

    #[test]
    fn inline_svg_gets_viewbox_and_loses_prolog() {
        let s = inline_svg(
            "<?xml version=\"1.0\"?>\n<svg width=\"10\" height=\"20\" xmlns=\"x\"></svg>",
        );
        assert!(
            s.starts_with("<svg width=\"10\" height=\"20\" xmlns=\"x\" viewBox=\"0 0 10 20\">"),
            "{s}"
        );
        let kept = inline_svg("<svg viewBox=\"0 0 1 1\"></svg>");
        assert_eq!(kept, "<svg viewBox=\"0 0 1 1\"></svg>");
    }

    #[test]
    fn sections_get_unique_anchors_and_a_nav_bar() {
        let mut r = Report::new("t");
        r.section("Flutter & LCO")
            .section("Flutter & LCO")
            .section("Files");
        r.links("results", &[("a b.json", "a b.json")])
            .pre("study", "x < y");
        r.table::<&str>("empty one", &["a"], &[]);
        let h = r.to_html();
        assert!(h.contains("<h2 id=\"flutter-lco\">"), "{h}");
        assert!(h.contains("<h2 id=\"flutter-lco-2\">"), "{h}");
        assert!(h.contains("<a href=\"#files\">Files</a>"), "{h}");
        assert!(
            h.contains("<li><a href=\"a b.json\">a b.json</a></li>"),
            "{h}"
        );
        assert!(h.contains("<pre>x &lt; y</pre>"), "{h}");
        assert!(h.contains("<b>empty one</b>: no rows."), "{h}");
        assert_eq!(anchor("  Ω!! "), "section");
        assert_eq!(column_label("U_m_s"), "U [m/s]");
        assert_eq!(column_label("amplitude_alpha_deg"), "amplitude α [deg]");
        assert_eq!(column_label("K_alpha"), "K_α");
        assert_eq!(column_label("omega_F_rad_s"), "ω_F [rad/s]");
        assert_eq!(column_label("R2_lift"), "R² lift");
        assert_eq!(column_label("t_end_s"), "t_end [s]");
        assert_eq!(column_label("case"), "case");
        assert_eq!(column_label("rel_err_U_F"), "rel. error U_F");
    }

    #[test]
    fn no_external_resources() {
        let mut r = Report::new("t");
        r.section("s").key_values("kv", &[("a", "1")]);
        let h = r.to_html();
        for bad in ["http://", "https://", "<link", "<script", "@import", "url("] {
            assert!(!h.contains(bad), "found {bad}");
        }
    }

    #[test]
    fn write_is_atomic_and_reports_missing_folder() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.html");
        Report::new("t").write(&p).unwrap();
        assert!(std::fs::read_to_string(&p).unwrap().contains("<h1>t</h1>"));
        let e = Report::new("t")
            .write(&dir.path().join("no/r.html"))
            .unwrap_err();
        assert!(e.to_string().contains("r.html"), "{e}");
    }
}
