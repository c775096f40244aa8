//! The one TOML key-to-line locator of the workspace (issue 40 item 6): a text's line
//! index and its span tree, so that every reader of a TOML file (data-set manifests,
//! structure and model files, study files) names the line of the key it refuses.

use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Line index of a TOML text and its span tree (`None` when the text does not parse: then
/// only [`TomlLines::line`] answers).
#[derive(Debug)]
pub struct TomlLines<'a> {
    starts: Vec<usize>,
    spans: Option<Spanned<DeTable<'a>>>,
}

impl<'a> TomlLines<'a> {
    /// Indexes `text` (line starts) and parses its spans.
    pub fn new(text: &'a str) -> Self {
        TomlLines {
            spans: DeTable::parse(text).ok(),
            ..TomlLines::unparsed(text)
        }
    }

    /// The line index alone, for a reader that parses the spans itself (to report the
    /// parser's error): [`TomlLines::line_of`] then answers 0.
    pub fn unparsed(text: &str) -> TomlLines<'static> {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        TomlLines {
            starts,
            spans: None,
        }
    }

    /// 1-based line of byte `offset` (1 for an empty text).
    pub fn line(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset).max(1)
    }

    /// The parsed span tree, when the text parses.
    pub fn spans(&self) -> Option<&DeTable<'a>> {
        self.spans.as_ref().map(Spanned::get_ref)
    }

    /// 1-based line of a dotted key path (`flutter.run[1].method`, `[i]` 0-based into an
    /// array of tables); the deepest existing prefix's line when the full key is absent;
    /// 0 when nothing matches or the text does not parse.
    pub fn line_of(&self, key: &str) -> usize {
        let Some(root) = self.spans() else { return 0 };
        let mut table: Option<&DeTable<'_>> = Some(root);
        let mut line = 0;
        for part in key.split('.') {
            let (name, index) = match part.split_once('[') {
                Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
                None => (part, None),
            };
            let Some(t) = table else { break };
            let Some(v) = t.get(name) else { break };
            line = self.line(v.span().start);
            let mut val: &DeValue<'_> = v.get_ref();
            if let (Some(i), Some(arr)) = (index, val.as_array()) {
                match arr.get(i) {
                    Some(item) => {
                        line = self.line(item.span().start);
                        val = item.get_ref();
                    }
                    None => break,
                }
            }
            table = val.as_table();
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dotted_keys_arrays_and_absent_keys_find_their_lines() {
        let text = "a = 1\n[b]\nc = 2\n\n[[r]]\nm = \"x\"\n[[r]]\nm = \"y\"\nn = 3\n";
        let l = TomlLines::new(text);
        assert_eq!(l.line_of("a"), 1);
        assert_eq!(l.line_of("b.c"), 3);
        assert_eq!(l.line_of("r[1].n"), 9);
        assert_eq!(l.line_of("r[0].m"), 6);
        // absent: the deepest prefix that exists
        assert_eq!(l.line_of("b.zz"), 2);
        assert_eq!(l.line_of("nothing"), 0);
        assert_eq!(l.line(0), 1);
        assert_eq!(l.line(text.find("n = 3").unwrap()), 9);
        // a text that does not parse still has lines, no spans
        let bad = TomlLines::new("a = \n= 2");
        assert_eq!(bad.line_of("a"), 0);
        assert_eq!(bad.line(5), 2);
    }
}
