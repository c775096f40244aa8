//! Case CSV reader (hand-rolled, streaming: one pass over the file line by line into the
//! column vectors, no allocation per row or field) and the sampling check of DATA_FORMAT.md.

use std::io::BufRead;
use std::path::Path;

use crate::{Error, Result};

/// The columns of one case file, in the file's units, in row order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CaseTable {
    /// Time stamps `t` \[s\].
    pub t: Vec<f64>,
    /// Heave `h`, in `units.heave`.
    pub h: Vec<f64>,
    /// Pitch `alpha`, in `units.pitch`.
    pub alpha: Vec<f64>,
    /// `lift`, in `units.lift`, when the column exists.
    pub lift: Option<Vec<f64>>,
    /// `moment`, in `units.moment`, when the column exists.
    pub moment: Option<Vec<f64>>,
    /// `h_target`, the feedback controller's heave target, in `units.heave`, when the
    /// column exists (DATA_FORMAT.md, "Controlled records").
    pub h_target: Option<Vec<f64>>,
    /// `control_raw`, the controller's output in its own uncalibrated units, when the
    /// column exists.
    pub control_raw: Option<Vec<f64>>,
    /// `control_force`, a calibrated control force on the heave DOF in `units.lift` (lift's
    /// sign convention), when the column exists.
    pub control_force: Option<Vec<f64>>,
}

/// Rows read before the columns are sized from their mean length.
const SIZING_ROWS: usize = 64;

/// Names of the recognised columns, in slot order.
const NAMES: [&str; 8] = [
    "t",
    "h",
    "alpha",
    "lift",
    "moment",
    "h_target",
    "control_raw",
    "control_force",
];

/// At most 40 characters of a field for a message (a hostile field may be a megabyte).
fn excerpt(f: &str) -> std::borrow::Cow<'_, str> {
    match f.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &f[..i]).into(),
        None => f.into(),
    }
}

fn csv_err(path: &Path, line: usize, field: &str, message: String) -> Error {
    Error::Csv {
        path: path.to_path_buf(),
        line,
        field: field.to_string(),
        message,
    }
}

/// Reads a case file, streaming: the file is read line by line through one reused line
/// buffer straight into the column vectors (no whole-file string, no allocation per row or
/// field). Memory is the columns kept (8 bytes per value) plus a 256 kB read buffer.
///
/// # Errors
/// [`Error::Io`] when the file cannot be opened or read; otherwise as [`parse_case_csv`]
/// (a line that is not UTF-8 is an [`Error::Csv`] naming that line).
pub fn read_case_csv(path: &Path, forces_required: bool) -> Result<CaseTable> {
    read_case_csv_stamped(path, forces_required).map(|(t, _)| t)
}

/// [`read_case_csv`], with what the file was when read ([`crate::io::FileStamp`]: its size,
/// the modification time of the open file and the fingerprint of the bytes parsed, taken in
/// the same pass).
///
/// # Errors
/// As [`read_case_csv`].
pub fn read_case_csv_stamped(
    path: &Path,
    forces_required: bool,
) -> Result<(CaseTable, crate::io::FileStamp)> {
    let file = crate::io::open_regular(path)?;
    let meta = file.metadata().ok();
    let size = meta.as_ref().map_or(0, |m| m.len());
    let modified = meta.and_then(|m| m.modified().ok());
    let mut reader =
        std::io::BufReader::with_capacity(1 << 18, crate::io::HashingReader::new(file));
    let table = parse_case_reader(&mut reader, size, path, forces_required)?;
    let h = reader.get_ref();
    Ok((
        table,
        crate::io::FileStamp {
            size: h.bytes_read(),
            modified,
            hash: h.finish(),
        },
    ))
}

/// Parses case-file text (`path` only names the file in errors).
///
/// The first line is the header; columns are found by name (`t`, `h`, `alpha`, `lift`,
/// `moment`, and the controlled-record columns `h_target`, `control_raw`,
/// `control_force`; surrounding whitespace and double quotes in names are ignored) in any order;
/// other columns are ignored. Whitespace around fields is ignored. Blank lines are allowed
/// only at the end of the file.
///
/// # Errors
/// [`Error::Csv`] naming the file, the 1-based line and the column for: an empty file; a
/// missing required column (`t`, `h`, `alpha`, and `lift`, `moment` when
/// `forces_required`); a repeated column name; a row whose field count differs from the
/// header's; an empty field; a value that does not parse as a number or is not finite;
/// a blank line followed by more rows; fewer than 3 rows; both `control_raw` and
/// `control_force` in one header (a record has one control signal).
pub fn parse_case_csv(text: &str, path: &Path, forces_required: bool) -> Result<CaseTable> {
    parse_case_reader(text.as_bytes(), text.len() as u64, path, forces_required)
}

/// Reads one line (without its `\n`) into `buf`; false at the end of the input. A line
/// longer than [`crate::limits::MAX_CSV_LINE_BYTES`] is an error (only that much of it is
/// ever held).
fn next_line(r: &mut impl BufRead, buf: &mut Vec<u8>, path: &Path) -> Result<bool> {
    use std::io::Read;
    buf.clear();
    let cap = crate::limits::MAX_CSV_LINE_BYTES;
    let n = r
        .by_ref()
        .take(cap as u64 + 1)
        .read_until(b'\n', buf)
        .map_err(|e| Error::io(path, e))?;
    if n == 0 {
        return Ok(false);
    }
    if buf.len() > cap && buf.last() != Some(&b'\n') {
        return Err(csv_err(
            path,
            0,
            "(row)",
            format!("a line longer than {cap} bytes (the limits table's MAX_CSV_LINE_BYTES); a case file holds one short row of numbers per line"),
        ));
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
    }
    Ok(true)
}

/// The streaming parser behind [`read_case_csv`] and [`parse_case_csv`]; `size` is the
/// input length in bytes (0 when unknown), used only to size the columns once.
fn parse_case_reader(
    mut r: impl BufRead,
    size: u64,
    path: &Path,
    forces_required: bool,
) -> Result<CaseTable> {
    let mut buf: Vec<u8> = Vec::with_capacity(256);
    let not_utf8 = |p: crate::io::Utf8Position| csv_err(path, p.line, "(row)", p.to_string());
    next_line(&mut r, &mut buf, path)?;
    let header_bytes = buf.len() as u64 + 1;
    // the file offset of the line in `buf` (every line before it ended in `\n`)
    let mut line_start = 0u64;
    let header_owned = crate::io::utf8_text(&buf, 1, 0)
        .map_err(not_utf8)?
        .to_string();
    let header = header_owned
        .strip_prefix('\u{feff}')
        .unwrap_or(&header_owned);
    let header = header.strip_suffix('\r').unwrap_or(header);
    if header.trim().is_empty() {
        return Err(csv_err(
            path,
            1,
            "(header)",
            "empty header line: the first line must name the columns".into(),
        ));
    }
    let names: Vec<std::borrow::Cow<'_, str>> = crate::csv_fields::fields(header).collect();
    let ncols = names.len();
    // slot[j] = index into NAMES of column j, or usize::MAX when ignored.
    let mut slot = vec![usize::MAX; ncols];
    let mut found = [false; NAMES.len()];
    for (j, name) in names.iter().enumerate() {
        if let Some(k) = NAMES.iter().position(|n| n == name) {
            if found[k] {
                return Err(csv_err(
                    path,
                    1,
                    name,
                    format!("column `{name}` appears more than once in the header"),
                ));
            }
            found[k] = true;
            slot[j] = k;
        }
    }
    if found[6] && found[7] {
        return Err(csv_err(
            path,
            1,
            "control_force",
            "both `control_raw` and `control_force` are given: a controlled record has one \
             control signal, calibrated (`control_force`) or not (`control_raw`)"
                .into(),
        ));
    }
    let required = if forces_required { 5 } else { 3 };
    for k in 0..required {
        if !found[k] {
            return Err(csv_err(
                path,
                1,
                NAMES[k],
                format!(
                    "required column `{}` is missing (header has: {})",
                    NAMES[k],
                    names.join(", ")
                ),
            ));
        }
    }

    let mut cols: [Vec<f64>; NAMES.len()] = Default::default();
    let mut blank_line: Option<usize> = None;
    let mut line_no = 1usize;
    let mut sized = false;
    let (mut data_bytes, mut data_rows) = (0u64, 0usize);
    let mut last_len = buf.len() as u64;
    while next_line(&mut r, &mut buf, path)? {
        line_no += 1;
        line_start += last_len + 1;
        last_len = buf.len() as u64;
        let line = crate::io::utf8_text(&buf, line_no, line_start).map_err(not_utf8)?;
        let line = line.strip_suffix('\r').unwrap_or(line);
        // (a line that starts with a byte that cannot begin white space is not blank)
        if line.as_bytes().first().is_none_or(|&b| may_be_space(b)) && line.trim().is_empty() {
            blank_line.get_or_insert(line_no);
            continue;
        }
        if let Some(b) = blank_line {
            return Err(csv_err(
                path,
                b,
                "(row)",
                format!("blank line inside the data (more rows follow at line {line_no})"),
            ));
        }
        data_bytes += buf.len() as u64 + 1;
        data_rows += 1;
        if data_rows as f64 > crate::limits::MAX_SAMPLES {
            return Err(csv_err(
                path,
                line_no,
                "(row)",
                format!(
                    "more than {} data rows (the limits table's MAX_SAMPLES)",
                    crate::limits::show(crate::limits::MAX_SAMPLES)
                ),
            ));
        }
        if !sized && data_rows == SIZING_ROWS {
            // Size the columns once from the mean length of the first rows (+5 %), so a
            // long file neither reallocates nor reserves far more than it fills.
            sized = true;
            let mean = data_bytes as f64 / data_rows as f64;
            let rows = size.saturating_sub(header_bytes) as f64 / mean;
            let rows = ((rows * 1.05) as usize + 16).min(crate::limits::MAX_SAMPLES as usize);
            for (k, col) in cols.iter_mut().enumerate() {
                if found[k] {
                    col.reserve_exact(rows.saturating_sub(col.len()));
                }
            }
        }
        let mut count = 0usize;
        for (j, field) in LineFields::of(line).enumerate() {
            count = j + 1;
            if j >= ncols {
                continue;
            }
            let k = slot[j];
            if k == usize::MAX {
                continue;
            }
            // already trimmed
            let f: &str = &field;
            if f.is_empty() {
                return Err(csv_err(path, line_no, NAMES[k], "empty field".into()));
            }
            let x: f64 = match plain_decimal(f) {
                Some(x) => x,
                None => f.parse().map_err(|_| {
                    csv_err(
                        path,
                        line_no,
                        NAMES[k],
                        format!("cannot parse `{}` as a number", excerpt(f)),
                    )
                })?,
            };
            if !x.is_finite() {
                return Err(csv_err(
                    path,
                    line_no,
                    NAMES[k],
                    format!("non-finite value `{}`", excerpt(f)),
                ));
            }
            cols[k].push(x);
        }
        if count != ncols {
            let field = if count < ncols {
                names[count].as_ref()
            } else {
                "(extra field)"
            };
            return Err(csv_err(
                path,
                line_no,
                field,
                format!("row has {count} fields but the header has {ncols}"),
            ));
        }
    }
    let n = cols[0].len();
    if n < 3 {
        return Err(csv_err(
            path,
            0,
            "t",
            format!("{n} data rows; at least 3 are needed"),
        ));
    }
    for col in cols.iter_mut() {
        // Give back an over-estimate of more than 1/8 (rows much longer than the first).
        if col.capacity() > n + n / 8 {
            col.shrink_to_fit();
        }
    }
    let [t, h, alpha, lift, moment, h_target, control_raw, control_force] = cols;
    Ok(CaseTable {
        t,
        h,
        alpha,
        lift: found[3].then_some(lift),
        moment: found[4].then_some(moment),
        h_target: found[5].then_some(h_target),
        control_raw: found[6].then_some(control_raw),
        control_force: found[7].then_some(control_force),
    })
}

/// Exact powers of ten 10⁰ … 10²² (every one is a double).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The value of a field of the form `-?digits(.digits)?` with at most 19 digits whose
/// integer w (the digits without the point) is at most 2⁵³ and whose fraction has at most
/// 22 digits: w / 10^d by one IEEE division of two exact doubles (Clinger's fast path, the
/// first step of `str::parse::<f64>` too), so the correctly rounded value `parse` gives.
/// `None` for anything else (exponents, more digits, signs other than one leading minus,
/// `inf`, …): the caller then parses with `str::parse`.
fn plain_decimal(f: &str) -> Option<f64> {
    let b = f.as_bytes();
    let (neg, b) = match b.first()? {
        b'-' => (true, &b[1..]),
        _ => (false, b),
    };
    let mut w: u64 = 0;
    let mut digits = 0usize;
    let mut frac: Option<usize> = None;
    for &c in b {
        match c {
            b'0'..=b'9' => {
                digits += 1;
                if digits > 19 {
                    return None;
                }
                w = w * 10 + u64::from(c - b'0');
                if let Some(d) = frac.as_mut() {
                    *d += 1;
                }
            }
            b'.' if frac.is_none() => frac = Some(0),
            _ => return None,
        }
    }
    // at least one digit before and (with a point) after the point
    let d = frac.unwrap_or(0);
    if digits == 0 || digits == d || frac == Some(0) || w > 1 << 53 || d > 22 {
        return None;
    }
    let v = w as f64 / POW10[d];
    Some(if neg { -v } else { v })
}

/// Whether a line or field starting (or ending) with byte `b` may start (end) with white
/// space as `str::trim` sees it: an ASCII white-space byte or any byte of a multi-byte
/// character (some are Unicode white space).
#[inline]
fn may_be_space(b: u8) -> bool {
    b >= 0x80 || matches!(b, b'\t' | b'\n' | 0x0B | 0x0C | b'\r' | b' ')
}

/// The fields of one line, trimmed, as [`crate::csv_fields::fields`] gives them; a line
/// holding no double quote (the case files' rows of numbers) is split here without the
/// per-field Unicode trim when a field neither starts nor ends with a possible white-space
/// byte.
enum LineFields<'a> {
    Plain(Option<&'a str>),
    Quoted(crate::csv_fields::Fields<'a>),
}

impl<'a> LineFields<'a> {
    fn of(line: &'a str) -> Self {
        if line.as_bytes().contains(&b'"') {
            LineFields::Quoted(crate::csv_fields::fields(line))
        } else {
            LineFields::Plain(Some(line))
        }
    }
}

impl<'a> Iterator for LineFields<'a> {
    type Item = std::borrow::Cow<'a, str>;

    fn next(&mut self) -> Option<Self::Item> {
        let rest = match self {
            LineFields::Quoted(it) => return it.next(),
            LineFields::Plain(rest) => rest,
        };
        let r = (*rest)?;
        let field = match r.as_bytes().iter().position(|&b| b == b',') {
            Some(i) => {
                *rest = Some(&r[i + 1..]);
                &r[..i]
            }
            None => {
                *rest = None;
                r
            }
        };
        let b = field.as_bytes();
        Some(std::borrow::Cow::Borrowed(match (b.first(), b.last()) {
            (Some(&x), Some(&y)) if !may_be_space(x) && !may_be_space(y) => field,
            _ => field.trim(),
        }))
    }
}

/// Checks that time stamps are strictly increasing and uniformly spaced, and returns
/// `(t0, dt)`: the least-squares intercept and slope of `t` against the 0-based row index
/// (`dt = Σ(i−ī)(tᵢ−t̄) / Σ(i−ī)²`, `t0 = t̄ − dt·ī`).
///
/// Every step `tᵢ₊₁ − tᵢ` must lie within 1 % of the median step (time stamps are often
/// printed with few digits). `first_line` is the file line of row 0 (2 for a file with a
/// header).
///
/// # Errors
/// [`Error::NonUniformSampling`] naming the line of the first bad row (the later row of the
/// first step outside the band: a gap, a repeated or a reversed stamp); [`Error::Csv`] when
/// fewer than 3 stamps are given.
pub fn check_sampling(t: &[f64], path: &Path, first_line: usize) -> Result<(f64, f64)> {
    let n = t.len();
    if n < 3 {
        return Err(csv_err(
            path,
            0,
            "t",
            format!("{n} time stamps; at least 3 are needed"),
        ));
    }
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let first_bad = |median: f64, steps: &[f64]| {
        steps
            .iter()
            .position(|&d| !(d > 0.0 && (d - median).abs() <= 0.01 * median))
    };
    let mut sorted = steps.clone();
    let mid = sorted.len() / 2;
    let (_, &mut median, _) = sorted.select_nth_unstable_by(mid, f64::total_cmp);
    if let Some(i) = first_bad(median, &steps) {
        return Err(Error::NonUniformSampling {
            path: path.to_path_buf(),
            line: first_line + i + 1,
            step: steps[i],
            median,
        });
    }
    steps.clear();
    let nf = n as f64;
    let ibar = (nf - 1.0) / 2.0;
    let tbar = t.iter().sum::<f64>() / nf;
    let sxy: f64 = t
        .iter()
        .enumerate()
        .map(|(i, &ti)| (i as f64 - ibar) * (ti - tbar))
        .sum();
    let sxx = nf * (nf * nf - 1.0) / 12.0;
    let dt = sxy / sxx;
    Ok((tbar - dt * ibar, dt))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("cases/x.csv")
    }

    /// The fast path of plain decimals gives `str::parse`'s value, bit for bit, and leaves
    /// every other form to it.
    #[test]
    fn plain_decimals_parse_as_std_does() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64; // fixed seed
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut fast = 0;
        for _ in 0..200_000 {
            let r = next();
            let x = f64::from_bits(r);
            let y = (r % 1_000_000_007) as f64 * 10f64.powi((r >> 40) as i32 % 12 - 8);
            for v in [x, y, -y, y / 3.0] {
                if !v.is_finite() {
                    continue;
                }
                for text in [format!("{v}"), format!("{v:.3}"), format!("{v:.17}")] {
                    let ours = plain_decimal(&text);
                    let std: f64 = text.parse().unwrap();
                    if let Some(o) = ours {
                        fast += 1;
                        assert_eq!(o.to_bits(), std.to_bits(), "{text}");
                    }
                }
            }
        }
        assert!(fast > 100_000, "the fast path was taken {fast} times only");
        for (text, want) in [
            ("0", Some(0.0)),
            ("-0", Some(-0.0)),
            ("0.001953125", Some(0.001953125)),
            ("-0.1348876953125", Some(-0.1348876953125)),
            ("1.", None),
            (".5", None),
            ("+1", None),
            ("1e5", None),
            ("--1", None),
            ("1.2.3", None),
            ("", None),
            ("-", None),
            ("inf", None),
            ("12345678901234567890", None),
            ("9007199254740993", None),
            ("0.10300633734501427", None),
        ] {
            assert_eq!(
                plain_decimal(text).map(f64::to_bits),
                want.map(f64::to_bits),
                "{text}"
            );
        }
    }

    /// The case reader's own splitter gives the fields of the workspace's one splitter on
    /// lines with ASCII and Unicode white space, empty fields and quotes.
    #[test]
    fn line_fields_are_those_of_csv_fields() {
        for line in [
            "",
            ",",
            "1,2.5,-3e-4",
            " 1 ,\t2\t, 3",
            "\u{a0}1.5,2\u{2003},\u{85}3\u{85}",
            "\x0b4\x0c,5\r",
            "1,,3,",
            "a,\"b,c\" , \"d\"\"e\"",
            "é,ü , ß",
        ] {
            let ours: Vec<String> = LineFields::of(line).map(|f| f.into_owned()).collect();
            let theirs = crate::csv_fields::split_line(line);
            assert_eq!(ours, theirs, "{line:?}");
        }
    }

    fn msg(e: &Error) -> String {
        e.to_string()
    }

    #[test]
    fn control_columns_are_read_and_only_one_control_signal_is_accepted() {
        let text = "t,h,alpha,h_target,control_raw\n0,1,2,3,4\n1,1,2,3,5\n2,1,2,3,6\n";
        let c = parse_case_csv(text, p(), false).unwrap();
        assert_eq!(c.control_raw, Some(vec![4.0, 5.0, 6.0]));
        assert_eq!(c.h_target, Some(vec![3.0; 3]));
        assert_eq!(c.control_force, None);
        let both = "t,h,alpha,control_force,control_raw\n0,1,2,3,4\n1,1,2,3,5\n2,1,2,3,6\n";
        let e = parse_case_csv(both, p(), false).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 1, field, .. } if field == "control_force"),
            "{e}"
        );
    }

    #[test]
    fn columns_by_name_any_order_extra_ignored_whitespace_ok() {
        let text = "alpha , t,junk, h ,moment,lift\r\n0.1, 0.0 ,x,1,2,3\r\n0.2,0.5,y,2,3,4\n0.3,1.0,,3,4,5\n\n";
        let c = parse_case_csv(text, p(), true).unwrap();
        assert_eq!(c.t, vec![0.0, 0.5, 1.0]);
        assert_eq!(c.alpha, vec![0.1, 0.2, 0.3]);
        assert_eq!(c.h, vec![1.0, 2.0, 3.0]);
        assert_eq!(c.lift, Some(vec![3.0, 4.0, 5.0]));
        assert_eq!(c.moment, Some(vec![2.0, 3.0, 4.0]));
    }

    #[test]
    fn free_case_forces_optional() {
        let c = parse_case_csv("t,h,alpha\n0,0,0\n1,0,0\n2,0,0\n", p(), false).unwrap();
        assert_eq!(c.lift, None);
        assert_eq!(c.moment, None);
    }

    #[test]
    fn missing_column_names_column_and_line_1() {
        let e = parse_case_csv("t,h,alpha,lift\n0,0,0,0\n", p(), true).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 1, field, .. } if field == "moment"),
            "{e:?}"
        );
        assert!(
            msg(&e).contains("x.csv:1") && msg(&e).contains("`moment`"),
            "{e}"
        );
    }

    #[test]
    fn nan_value_names_line_and_column() {
        let text = "t,h,alpha\n0,0,0\n1,0,0\n2,NaN,0\n3,0,0\n";
        let e = parse_case_csv(text, p(), false).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 4, field, .. } if field == "h"),
            "{e:?}"
        );
        assert!(
            msg(&e).contains("x.csv:4") && msg(&e).contains("NaN"),
            "{e}"
        );
        let text = "t,h,alpha\n0,0,0\n1,0,inf\n";
        let e = parse_case_csv(text, p(), false).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 3, field, .. } if field == "alpha"),
            "{e:?}"
        );
    }

    #[test]
    fn unparsable_and_empty_fields_name_line_and_column() {
        let e = parse_case_csv("t,h,alpha\n0,0,0\n1,abc,0\n", p(), false).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 3, field, .. } if field == "h"),
            "{e:?}"
        );
        let e = parse_case_csv("t,h,alpha\n0,0,0\n1, ,0\n", p(), false).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 3, field, .. } if field == "h"),
            "{e:?}"
        );
    }

    #[test]
    fn wrong_field_count_names_line() {
        let e = parse_case_csv("t,h,alpha\n0,0,0\n1,0\n2,0,0\n", p(), false).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 3, field, .. } if field == "alpha"),
            "{e:?}"
        );
        assert!(
            msg(&e).contains("2 fields") && msg(&e).contains("has 3"),
            "{e}"
        );
        let e = parse_case_csv("t,h,alpha\n0,0,0\n1,0,0\n2,0,0,9\n", p(), false).unwrap_err();
        assert!(matches!(&e, Error::Csv { line: 4, .. }), "{e:?}");
    }

    #[test]
    fn blank_line_inside_data_is_an_error() {
        let e = parse_case_csv("t,h,alpha\n0,0,0\n\n1,0,0\n2,0,0\n", p(), false).unwrap_err();
        assert!(matches!(&e, Error::Csv { line: 3, .. }), "{e:?}");
    }

    #[test]
    fn fewer_than_three_rows_is_an_error() {
        let e = parse_case_csv("t,h,alpha\n0,0,0\n1,0,0\n", p(), false).unwrap_err();
        assert!(msg(&e).contains("at least 3"), "{e}");
    }

    #[test]
    fn duplicate_column_is_an_error() {
        let e = parse_case_csv("t,h,alpha,h\n0,0,0,0\n", p(), false).unwrap_err();
        assert!(
            matches!(&e, Error::Csv { line: 1, field, .. } if field == "h"),
            "{e:?}"
        );
    }

    #[test]
    fn sampling_fit_and_tolerance() {
        // Stamps printed with 3 decimals at 100 Hz jitter well within 1 %.
        let t: Vec<f64> = (0..50)
            .map(|i| ((1.25 + i as f64 * 0.01) * 1000.0).round() / 1000.0)
            .collect();
        let (t0, dt) = check_sampling(&t, p(), 2).unwrap();
        assert!(
            (dt - 0.01).abs() < 1e-12 && (t0 - 1.25).abs() < 1e-12,
            "{t0} {dt}"
        );
        // Exact recovery of an affine time base.
        let t: Vec<f64> = (0..1000).map(|i| 3.0 + i as f64 / 512.0).collect();
        let (t0, dt) = check_sampling(&t, p(), 2).unwrap();
        assert!((dt * 512.0 - 1.0).abs() < 1e-13 && (t0 - 3.0).abs() < 1e-12);
    }

    #[test]
    fn non_uniform_time_names_first_bad_row() {
        let mut t: Vec<f64> = (0..20).map(|i| i as f64 * 0.1).collect();
        // Gap: row 7 (0-based) jumps; file line = 2 + 7 = 9.
        for x in t.iter_mut().skip(7) {
            *x += 0.05;
        }
        let e = check_sampling(&t, p(), 2).unwrap_err();
        assert!(
            matches!(e, Error::NonUniformSampling { line: 9, .. }),
            "{e:?}"
        );
        assert!(e.to_string().contains("x.csv:9"), "{e}");
        // Repeated stamp at row 4 → line 6.
        let mut t: Vec<f64> = (0..20).map(|i| i as f64 * 0.1).collect();
        t[4] = t[3];
        let e = check_sampling(&t, p(), 2).unwrap_err();
        assert!(
            matches!(e, Error::NonUniformSampling { line: 6, .. }),
            "{e:?}"
        );
        // Reversed pair rows 10, 11 → first bad row 10 → line 12.
        let mut t: Vec<f64> = (0..20).map(|i| i as f64 * 0.1).collect();
        t.swap(10, 11);
        let e = check_sampling(&t, p(), 2).unwrap_err();
        assert!(
            matches!(e, Error::NonUniformSampling { line: 12, .. }),
            "{e:?}"
        );
    }

    #[test]
    fn streaming_file_reader_equals_text_parser_and_sizes_columns_tightly() {
        let mut text = String::from("\u{feff}t, alpha,h,extra,lift,moment\r\n");
        for i in 0..5000 {
            let t = i as f64 / 512.0;
            let v = (t * 7.3).sin();
            text.push_str(&format!(
                "{t},{},{},x{i},{},{}\r\n",
                v * 0.3,
                v * 1e-3,
                v * 12.5,
                v * 0.77
            ));
        }
        text.push_str("\n\n");
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("c.csv");
        std::fs::write(&f, &text).unwrap();
        let a = read_case_csv(&f, true).unwrap();
        let b = parse_case_csv(&text, p(), true).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.t.len(), 5000);
        assert_eq!(a.h[100], (100.0 / 512.0 * 7.3f64).sin() * 1e-3);
        // Columns sized from the mean row length: no more than 15 % spare capacity.
        for c in [&a.t, &a.h, &a.alpha] {
            assert!(c.capacity() <= 5750, "capacity {}", c.capacity());
        }
    }

    #[test]
    fn invalid_utf8_names_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("c.csv");
        std::fs::write(&f, b"t,h,alpha\n0,0,0\n1,\xff,0\n2,0,0\n").unwrap();
        let e = read_case_csv(&f, false).unwrap_err();
        assert!(matches!(&e, Error::Csv { line: 3, .. }), "{e:?}");
        assert!(msg(&e).contains("UTF-8"), "{e}");
        // line 3 starts at offset 16; the bad byte is its third
        assert!(msg(&e).contains("byte 3 (offset 18 in the file)"), "{e}");
        std::fs::write(&f, b"t,\xfeh,alpha\n").unwrap();
        let e = read_case_csv(&f, false).unwrap_err();
        assert!(matches!(&e, Error::Csv { line: 1, .. }), "{e:?}");
    }

    #[test]
    fn missing_file_is_an_io_error_naming_it() {
        let e = read_case_csv(Path::new("/no/such/case.csv"), false).unwrap_err();
        assert!(
            matches!(&e, Error::Io { .. }) && msg(&e).contains("case.csv"),
            "{e}"
        );
    }

    /// Reader speed (run with `--ignored --nocapture`, release or test profile): a 10 s,
    /// 512 Hz, 5-column case.
    #[test]
    #[ignore]
    fn reader_speed() {
        let mut text = String::from("t,h,alpha,lift,moment\n");
        for i in 0..5120 {
            let t = i as f64 / 512.0;
            let v = (t * 7.3).sin();
            text.push_str(&format!(
                "{t},{},{},{},{}\n",
                v * 1e-3,
                v * 0.3,
                v * 12.5,
                v * 0.77
            ));
        }
        let reps = 200;
        let start = std::time::Instant::now();
        for _ in 0..reps {
            let c = parse_case_csv(&text, p(), true).unwrap();
            check_sampling(&c.t, p(), 2).unwrap();
        }
        let per = start.elapsed().as_secs_f64() / reps as f64;
        eprintln!(
            "5120 rows x 5 columns ({} bytes): {:.1} us per file, {:.1} us per 1000 rows",
            text.len(),
            per * 1e6,
            per * 1e6 / 5.12
        );
    }
}
