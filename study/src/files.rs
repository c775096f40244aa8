//! Result files: every file is written atomically (`identify::io::write_atomic`), JSON is
//! pretty-printed with serde's shortest round-trip float formatting, CSV cells likewise,
//! so that the same study and seed give byte-identical files.

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::error::{Error, Result};

/// Creates a folder (and parents), naming it on failure.
///
/// # Errors
/// [`Error::Io`] naming the folder.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        context: format!("cannot create output folder {}", dir.display()),
        source,
    })
}

/// Writes `value` as pretty JSON (trailing newline) atomically.
///
/// # Errors
/// [`Error::Json`] when `value` cannot be serialised, [`Error::Identify`] when the file
/// cannot be written (naming it).
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut text = serde_json::to_string_pretty(value).map_err(|source| Error::Json {
        context: format!("serialising {}", path.display()),
        source,
    })?;
    text.push('\n');
    identify::io::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// Reads a JSON result file.
///
/// # Errors
/// [`Error::Io`] when it cannot be read, [`Error::Json`] when it is not a `T`; both name the
/// file.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let text = identify::io::read_text(path).map_err(|source| Error::Io {
        context: format!("reading {}", path.display()),
        source,
    })?;
    serde_json::from_str(&text).map_err(|source| Error::Json {
        context: format!("parsing {}", path.display()),
        source,
    })
}

/// Writes text atomically.
///
/// # Errors
/// [`Error::Identify`] when the file cannot be written (naming it).
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    identify::io::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// A CSV table built in memory (header + rows), written atomically.
#[derive(Debug, Clone, Default)]
pub struct Csv {
    /// Header cells.
    pub header: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<String>>,
}

/// A number as a CSV cell: shortest round-trip form, empty for `None`/non-finite.
pub fn num(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x}"),
        _ => String::new(),
    }
}

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl Csv {
    /// A table with this header.
    pub fn new<S: AsRef<str>>(header: &[S]) -> Self {
        Csv {
            header: header.iter().map(|s| s.as_ref().to_string()).collect(),
            rows: vec![],
        }
    }

    /// The CSV text (comma-separated, `"` quoting, `\n` line ends).
    pub fn text(&self) -> String {
        let mut s = String::new();
        for r in std::iter::once(&self.header).chain(&self.rows) {
            s.push_str(&r.iter().map(|c| quote(c)).collect::<Vec<_>>().join(","));
            s.push('\n');
        }
        s
    }

    /// Writes the table atomically.
    ///
    /// # Errors
    /// [`Error::Identify`] when the file cannot be written (naming it).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_text(path, &self.text())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_and_formats() {
        let mut c = Csv::new(&["a", "b"]);
        c.rows.push(vec!["x,y".into(), num(Some(0.1))]);
        c.rows.push(vec!["q\"".into(), num(None)]);
        assert_eq!(c.text(), "a,b\n\"x,y\",0.1\n\"q\"\"\",\n");
        assert_eq!(num(Some(f64::NAN)), "");
    }
}
