//! The one CSV field splitter of the workspace: comma-separated fields, double-quoted fields
//! with `""` escapes, each field trimmed. A line without a quote is split without
//! allocating (the case files' numeric rows); a quoted field is unescaped into a new
//! string. (The case-file reader splits its unquoted rows itself, skipping the Unicode trim
//! of fields that cannot hold white space; its test asserts the same fields as here.)

use std::borrow::Cow;

/// The fields of one CSV line (no line break), trimmed: `a, "b,c" ,"d""e"` gives `a`,
/// `b,c`, `d"e`. An empty line has one empty field. An unterminated quote runs to the end
/// of the line.
pub fn fields(line: &str) -> Fields<'_> {
    Fields {
        rest: Some(line),
        quoted: line.contains('"'),
    }
}

/// Iterator over the fields of a line ([`fields`]).
#[derive(Debug, Clone)]
pub struct Fields<'a> {
    rest: Option<&'a str>,
    quoted: bool,
}

impl<'a> Iterator for Fields<'a> {
    type Item = Cow<'a, str>;

    fn next(&mut self) -> Option<Cow<'a, str>> {
        let rest = self.rest?;
        if !self.quoted {
            // a byte loop, not `split_once(',')`: the fields of a case file are short
            // numbers, for which a call to memchr per field costs more than the scan
            return Some(Cow::Borrowed(
                match rest.as_bytes().iter().position(|&b| b == b',') {
                    Some(i) => {
                        self.rest = Some(&rest[i + 1..]);
                        rest[..i].trim()
                    }
                    None => {
                        self.rest = None;
                        rest.trim()
                    }
                },
            ));
        }
        let mut cur = String::new();
        let mut in_quotes = false;
        let mut chars = rest.char_indices().peekable();
        while let Some((i, c)) = chars.next() {
            match (c, in_quotes) {
                ('"', true) if chars.peek().map(|p| p.1) == Some('"') => {
                    cur.push('"');
                    chars.next();
                }
                ('"', _) => in_quotes = !in_quotes,
                (',', false) => {
                    self.rest = Some(&rest[i + 1..]);
                    return Some(Cow::Owned(cur.trim().to_string()));
                }
                _ => cur.push(c),
            }
        }
        self.rest = None;
        Some(Cow::Owned(cur.trim().to_string()))
    }
}

/// The fields of a line as owned strings ([`fields`]).
pub fn split_line(line: &str) -> Vec<String> {
    fields(line).map(Cow::into_owned).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_fields_commas_and_escapes() {
        assert_eq!(split_line("a, \"b,c\" ,\"d\"\"e\""), ["a", "b,c", "d\"e"]);
        assert_eq!(split_line(" 1.5 ,2,, 3 "), ["1.5", "2", "", "3"]);
        assert_eq!(split_line(""), [""]);
        assert_eq!(split_line("\"x"), ["x"]);
        assert_eq!(split_line("\"\",a"), ["", "a"]);
        // an unquoted line is borrowed
        assert!(fields("1,2").all(|f| matches!(f, Cow::Borrowed(_))));
    }
}
