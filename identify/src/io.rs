//! Atomic file writes shared by every writer of aeroform.

use std::io::Write;
use std::path::Path;

use crate::{Error, Result};

/// Creates the folders of `rel` below the existing folder `root`, one level at a time
/// (`create_dir`, an existing folder kept), and never `root` itself: a writer whose output
/// folder was taken away (an interrupt's cleanup) fails instead of recreating it, which
/// `create_dir_all` would do.
///
/// # Errors
/// [`Error::Io`] naming the folder that could not be created (`root` missing, a file in
/// the way, no permission).
pub fn create_dir_below(root: &Path, rel: &Path) -> Result<()> {
    let mut dir = root.to_path_buf();
    for c in rel.components() {
        dir.push(c);
        match std::fs::create_dir(&dir) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && dir.is_dir() => {}
            Err(e) => return Err(Error::io(&dir, e)),
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically: the data goes to a temporary file in the same
/// folder, is flushed and synced, then renamed over `path`. A reader sees the old file or
/// the complete new one, never a half-written file; on error the temporary file is removed
/// and `path` is untouched.
///
/// # Errors
/// [`Error::Io`] naming `path` when the folder is missing or unwritable, the disk is full,
/// or the rename fails.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, &mut |w| w.write_all(bytes))
}

/// [`write_atomic`] of what `write` writes into the temporary file (buffered), so that a
/// large document is serialised straight to disk instead of into memory first.
///
/// # Errors
/// As [`write_atomic`], and the error `write` returns (naming `path`).
pub fn write_atomic_with(
    path: &Path,
    write: &mut dyn FnMut(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".to_string());
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> std::io::Result<()> {
        // create_new (O_CREAT | O_EXCL) never follows a symlink planted at the temporary
        // path; whatever sits there (a stale file of a dead process with our PID, a link)
        // is unlinked once — the link itself, never its target — and the create retried
        let create = || {
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&tmp)
        };
        let f = match create() {
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                std::fs::remove_file(&tmp)?;
                create()?
            }
            other => other?,
        };
        let mut b = std::io::BufWriter::new(f);
        write(&mut b)?;
        let f = b.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(path, e));
    }
    Ok(())
}

/// An input file refused by its reader: missing, unreadable, not a regular file, beyond its
/// size cap, or not UTF-8. It travels inside the [`std::io::Error`] the readers return
/// (its kind kept: `NotFound`, `PermissionDenied`, `InvalidInput`, `InvalidData`), so a
/// caller of any crate can tell an input error (the command line's exit code 2) from a
/// failure of the machine by the type, whatever context wraps it (issue 39, row 7).
#[derive(Debug)]
pub struct InputFileError {
    /// What is wrong, with the line and byte where there is one.
    pub message: String,
}

impl std::fmt::Display for InputFileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for InputFileError {}

/// A [`std::io::Error`] of `kind` carrying an [`InputFileError`].
pub fn input_error(kind: std::io::ErrorKind, message: impl Into<String>) -> std::io::Error {
    std::io::Error::new(
        kind,
        InputFileError {
            message: message.into(),
        },
    )
}

/// True when `e` is an input file refused by its reader ([`InputFileError`] inside).
pub fn is_input_error(e: &std::io::Error) -> bool {
    e.get_ref().is_some_and(|i| i.is::<InputFileError>())
}

/// An error opening or reading an input: a missing file, a permission refused, a folder
/// where a file belongs are input errors ([`input_error`], the kind kept); anything else
/// (a failing disk) is passed on as it is.
fn opening_error(e: std::io::Error) -> std::io::Error {
    use std::io::ErrorKind as K;
    let input = matches!(
        e.kind(),
        K::NotFound | K::PermissionDenied | K::InvalidInput | K::InvalidData
    ) || matches!(e.raw_os_error(), Some(20 | 21 | 36 | 40)); // ENOTDIR EISDIR ENAMETOOLONG ELOOP
    if input && !is_input_error(&e) {
        input_error(e.kind(), e.to_string())
    } else {
        e
    }
}

/// The position of an invalid UTF-8 sequence in a text file: 1-based line, 1-based byte
/// within that line, and 0-based byte offset from the start of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Utf8Position {
    /// 1-based line.
    pub line: usize,
    /// 1-based byte within the line.
    pub byte: usize,
    /// 0-based byte offset from the start of the file.
    pub offset: u64,
}

impl std::fmt::Display for Utf8Position {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "line {}, byte {} (offset {} in the file): not valid UTF-8",
            self.line, self.byte, self.offset
        )
    }
}

/// `bytes` as text, or where its first invalid UTF-8 sequence is: the one UTF-8 check of
/// every reader of text inputs (whole files through [`read_text`], case CSVs line by line).
/// `line` and `offset` are the line number (1-based) and file offset (0-based) of the first
/// byte of `bytes`.
///
/// # Errors
/// The [`Utf8Position`] of the first invalid sequence.
pub fn utf8_text(
    bytes: &[u8],
    line: usize,
    offset: u64,
) -> std::result::Result<&str, Utf8Position> {
    std::str::from_utf8(bytes).map_err(|e| {
        let valid = &bytes[..e.valid_up_to()];
        let newlines = valid.iter().filter(|&&b| b == b'\n').count();
        let col = valid.len() - valid.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
        Utf8Position {
            line: line + newlines,
            byte: col + 1,
            offset: offset + valid.len() as u64,
        }
    })
}

/// The byte-order mark of UTF-8, `EF BB BF`: accepted at the start of every text input
/// (TOML, CSV, JSON, measured tables) and removed by the one reader ([`read_text`], and the
/// case-CSV reader), never part of the first key or column name (docs/DATA_FORMAT.md).
pub const UTF8_BOM: &str = "\u{feff}";

/// Characters a label or other user string may not hold: every control character but the
/// tab, line feed and carriage return (C0, DEL, C1) and the non-characters U+FFFE and
/// U+FFFF. They are not allowed in XML (the SVG figures and the HTML reports fail at the
/// figure stage, issue 39 row 7) or move the terminal; readers refuse them when the file is
/// read, naming the key. Returns the first such character and its 1-based position.
pub fn disallowed_char(s: &str) -> Option<(usize, char)> {
    s.chars().enumerate().find_map(|(i, c)| {
        let bad = (c.is_control() && !matches!(c, '\t' | '\n' | '\r'))
            || c == '\u{fffe}'
            || c == '\u{ffff}';
        bad.then_some((i + 1, c))
    })
}

/// The message for a [`disallowed_char`] finding: the character's code and position.
pub fn disallowed_char_message(pos: usize, c: char) -> String {
    format!(
        "character {pos} is U+{:04X}, a control character: labels and other texts that reach \
         the figures and reports may not hold control characters (other than tab and line \
         breaks)",
        c as u32
    )
}

/// Opens `path` for reading only when it is a regular file (after following symbolic
/// links): a FIFO, a device (`/dev/zero`), a socket or a folder is refused without blocking
/// (the open is non-blocking, the type is read from the open file itself), so a hostile data
/// set cannot hang or exhaust a reader (issue 39, row 5).
///
/// # Errors
/// [`Error::Io`] as [`open_regular_io`].
pub fn open_regular(path: &Path) -> Result<std::fs::File> {
    open_regular_io(path).map_err(|e| Error::io(path, e))
}

/// [`open_regular`] with a plain I/O error, for the readers of the other crates.
///
/// # Errors
/// The file cannot be opened, or is not a regular file (the message says what it is);
/// refusals of the input are [`InputFileError`]s ([`is_input_error`]).
pub fn open_regular_io(path: &Path) -> std::io::Result<std::fs::File> {
    let mut o = std::fs::OpenOptions::new();
    o.read(true);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // O_NONBLOCK: opening a FIFO without a writer returns at once
        o.custom_flags(0o4000);
    }
    let f = o.open(path).map_err(opening_error)?;
    let m = f.metadata()?;
    if m.is_file() {
        return Ok(f);
    }
    let what = if m.is_dir() {
        "a folder"
    } else {
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            let t = m.file_type();
            if t.is_fifo() {
                "a FIFO (named pipe)"
            } else if t.is_char_device() || t.is_block_device() {
                "a device"
            } else if t.is_socket() {
                "a socket"
            } else {
                "not a regular file"
            }
        }
        #[cfg(not(unix))]
        {
            "not a regular file"
        }
    };
    Err(input_error(
        std::io::ErrorKind::InvalidInput,
        format!("is {what}; only regular files are read"),
    ))
}

/// Reads a whole text file of at most `max_bytes` (a regular file, [`open_regular`]),
/// checked as UTF-8 with the line and byte of the first invalid sequence.
///
/// # Errors
/// [`Error::Io`] as [`read_text_capped_io`].
pub fn read_text_capped(path: &Path, max_bytes: u64) -> Result<String> {
    read_text_capped_io(path, max_bytes).map_err(|e| Error::io(path, e))
}

/// [`read_text_capped`] with a plain I/O error, for the readers of the other crates; the cap
/// is [`crate::limits::MAX_TEXT_FILE_BYTES`] unless a caller has its own. A leading UTF-8
/// byte-order mark is removed ([`UTF8_BOM`]).
///
/// # Errors
/// As [`open_regular_io`]; the file is larger than `max_bytes` (its size and the cap named);
/// it is not UTF-8 (line, byte and offset named, [`utf8_text`]). Every refusal of the input
/// is an [`InputFileError`].
pub fn read_text_capped_io(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    use std::io::Read;
    let f = open_regular_io(path)?;
    let limit = if max_bytes == crate::limits::MAX_RESULT_FILE_BYTES as u64 {
        "MAX_RESULT_FILE_BYTES"
    } else {
        "MAX_TEXT_FILE_BYTES"
    };
    let too_big = |n: u64| {
        input_error(
            std::io::ErrorKind::InvalidData,
            format!(
                "{n} bytes or more; files of this kind are read up to {max_bytes} bytes \
                 (the limits table's {limit})"
            ),
        )
    };
    let len = f.metadata().map(|m| m.len()).unwrap_or(0);
    if len > max_bytes {
        return Err(too_big(len));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    f.take(max_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_big(bytes.len() as u64));
    }
    let start = if bytes.starts_with(UTF8_BOM.as_bytes()) {
        UTF8_BOM.len()
    } else {
        0
    };
    bytes.drain(..start);
    String::from_utf8(bytes).map_err(|e| {
        let message = match utf8_text(e.as_bytes(), 1, start as u64) {
            Err(p) => p.to_string(),
            Ok(_) => "not valid UTF-8".to_string(),
        };
        input_error(std::io::ErrorKind::InvalidData, message)
    })
}

/// [`read_text_capped_io`] with the cap of the limits table.
///
/// # Errors
/// As [`read_text_capped_io`].
pub fn read_text(path: &Path) -> std::io::Result<String> {
    read_text_capped_io(path, crate::limits::MAX_TEXT_FILE_BYTES as u64)
}

/// File an aeroform command writes into its output folder as the very last step before the
/// folder is moved into place: the folder is complete. Content: `format`, `command`.
pub const COMPLETE_MARKER: &str = ".aeroform-complete";

/// File an aeroform command writes first into its staging folder and removes only after
/// [`COMPLETE_MARKER`] is written: a folder holding it is unfinished and is never read.
pub const INCOMPLETE_MARKER: &str = ".aeroform-incomplete";

/// Tags of aeroform's work folders next to an output folder `P/NAME`:
/// `P/.NAME.aeroform-staging.PID` (being written) and `P/.NAME.aeroform-old.PID` (the
/// previous results during the final swap).
pub const WORK_TAGS: [&str; 2] = [".aeroform-staging.", ".aeroform-old."];

/// When `file_name` is the name of an aeroform work folder (`.NAME<tag>PID`, tag one of
/// [`WORK_TAGS`]), the tag and the PID of the process that made it.
pub fn work_folder_pid(file_name: &str) -> Option<(&'static str, u32)> {
    let rest = file_name.strip_prefix('.')?;
    for tag in WORK_TAGS {
        if let Some(i) = rest.rfind(tag) {
            if i == 0 {
                continue;
            }
            let pid = &rest[i + tag.len()..];
            if !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()) {
                return pid.parse().ok().map(|p| (tag, p));
            }
        }
    }
    None
}

/// True when `file_name` is an aeroform work folder name ([`work_folder_pid`]).
pub fn is_staging_name(file_name: &str) -> bool {
    work_folder_pid(file_name).is_some()
}

/// Refuses a folder that an aeroform command had not finished: it holds
/// [`INCOMPLETE_MARKER`] or its name is a work-folder name ([`is_staging_name`]).
///
/// The rule (docs/DATA_FORMAT.md, "Complete folders"): the marker is aeroform's, other
/// programs never write it, so a folder without either marker and with an ordinary name
/// (a data set written by another program, real measurements, results of older versions)
/// is accepted; [`COMPLETE_MARKER`] is not required.
///
/// # Errors
/// [`Error::IncompleteFolder`] naming the folder, the reason and the remedy.
pub fn check_complete_folder(dir: &Path) -> Result<()> {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if let Some((tag, pid)) = work_folder_pid(&name) {
        return Err(Error::IncompleteFolder {
            path: dir.to_path_buf(),
            message: format!(
                "an aeroform work folder (`{}` of process {pid}), not a finished result; \
                 read the folder it was written for",
                tag.trim_matches('.')
            ),
        });
    }
    match std::fs::symlink_metadata(dir.join(INCOMPLETE_MARKER)) {
        Ok(_) => Err(Error::IncompleteFolder {
            path: dir.to_path_buf(),
            message: format!(
                "holds `{INCOMPLETE_MARKER}`: the aeroform command writing it did not \
                 finish (interrupted, killed or failed); run it again"
            ),
        }),
        Err(_) => Ok(()),
    }
}

/// What a file was when it was read: its size \[bytes\], modification time and a 64-bit
/// fingerprint of its bytes ([`HashingReader`]). A reader that must read a file again (a
/// consumer that needs the samples after a streaming pass dropped them) compares the two
/// stamps, so that a file replaced in between is an error, not a mix of old and new data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileStamp {
    /// Bytes read (the file's length when read to its end).
    pub size: u64,
    /// Modification time from the metadata of the open file, when the platform gives it.
    pub modified: Option<std::time::SystemTime>,
    /// [`HashingReader::finish`] of the bytes read.
    pub hash: u64,
}

/// A reader that fingerprints the bytes passing through it: 8-byte little-endian words
/// mixed by `s ← rotl(s ⊕ w, 29) · 0x9E37_79B9_7F4A_7C15` (the last partial word
/// zero-padded, then the length), finished by a 64-bit avalanche. Not cryptographic: it
/// tells a file rewritten between two reads from the same file (with the size and the
/// modification time, [`FileStamp`]) at ≈ 0.1 ns per byte, i.e. without slowing a parser.
#[derive(Debug)]
pub struct HashingReader<R> {
    inner: R,
    state: u64,
    carry: [u8; 8],
    carry_len: usize,
    bytes: u64,
}

fn mix_word(state: u64, w: u64) -> u64 {
    (state ^ w)
        .rotate_left(29)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

impl<R> HashingReader<R> {
    /// Wraps `inner`.
    pub fn new(inner: R) -> Self {
        Self {
            inner,
            state: 0x243F_6A88_85A3_08D3,
            carry: [0; 8],
            carry_len: 0,
            bytes: 0,
        }
    }

    fn mix(&mut self, w: u64) {
        self.state = mix_word(self.state, w);
    }

    fn update(&mut self, mut data: &[u8]) {
        self.bytes += data.len() as u64;
        if self.carry_len > 0 {
            let take = (8 - self.carry_len).min(data.len());
            self.carry[self.carry_len..self.carry_len + take].copy_from_slice(&data[..take]);
            self.carry_len += take;
            data = &data[take..];
            if self.carry_len < 8 {
                return;
            }
            self.mix(u64::from_le_bytes(self.carry));
            self.carry_len = 0;
        }
        let mut words = data.chunks_exact(8);
        for w in &mut words {
            let mut b = [0u8; 8];
            b.copy_from_slice(w);
            self.mix(u64::from_le_bytes(b));
        }
        let rest = words.remainder();
        self.carry[..rest.len()].copy_from_slice(rest);
        self.carry_len = rest.len();
    }

    /// Number of bytes read so far.
    pub fn bytes_read(&self) -> u64 {
        self.bytes
    }

    /// The fingerprint of the bytes read so far (the reader may go on).
    pub fn finish(&self) -> u64 {
        let mut state = self.state;
        if self.carry_len > 0 {
            let mut b = [0u8; 8];
            b[..self.carry_len].copy_from_slice(&self.carry[..self.carry_len]);
            state = mix_word(state, u64::from_le_bytes(b));
        }
        let mut z = mix_word(state, self.bytes);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// The wrapped reader.
    pub fn get_ref(&self) -> &R {
        &self.inner
    }
}

impl<R: std::io::Read> std::io::Read for HashingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.update(&buf[..n]);
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_inputs_drop_a_bom_and_name_the_line_byte_and_offset_of_bad_utf8() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.json");
        std::fs::write(&p, b"\xef\xbb\xbf{\"a\": 1}\n").unwrap();
        assert_eq!(read_text(&p).unwrap(), "{\"a\": 1}\n");
        std::fs::write(&p, b"ab\ncd\n\xef\xbb\xbfx\xffy\n").unwrap();
        let e = read_text(&p).unwrap_err();
        assert!(is_input_error(&e));
        assert_eq!(
            e.to_string(),
            "line 3, byte 5 (offset 10 in the file): not valid UTF-8"
        );
        let e = read_text(&dir.path().join("missing.toml")).unwrap_err();
        assert!(is_input_error(&e) && e.kind() == std::io::ErrorKind::NotFound);
        let e = read_text(dir.path()).unwrap_err();
        assert!(is_input_error(&e), "{e}");
        assert!(!is_input_error(&std::io::Error::other("disk")));
    }

    #[test]
    fn control_characters_are_disallowed_in_labels() {
        assert_eq!(disallowed_char("Theodorsen–Jones (p)\tok\n"), None);
        assert_eq!(disallowed_char("a\u{1}b"), Some((2, '\u{1}')));
        assert_eq!(disallowed_char("ab\u{1b}[2J"), Some((3, '\u{1b}')));
        assert_eq!(disallowed_char("\u{7f}"), Some((1, '\u{7f}')));
        assert_eq!(disallowed_char("\u{9b}"), Some((1, '\u{9b}')));
        assert_eq!(disallowed_char("x\u{ffff}"), Some((2, '\u{ffff}')));
    }

    #[test]
    fn work_folder_names_are_recognised() {
        assert_eq!(
            work_folder_pid(".out.aeroform-staging.123"),
            Some((".aeroform-staging.", 123))
        );
        assert_eq!(
            work_folder_pid(".a.b.aeroform-old.7"),
            Some((".aeroform-old.", 7))
        );
        for n in [
            "out",
            ".aeroform-staging.1",
            ".out.aeroform-staging.",
            ".out.aeroform-staging.12x",
            "out.aeroform-staging.1",
        ] {
            assert_eq!(work_folder_pid(n), None, "{n}");
        }
    }

    #[test]
    fn incomplete_folders_are_refused_and_foreign_ones_accepted() {
        let dir = tempfile::tempdir().unwrap();
        let ds = dir.path().join("ds");
        std::fs::create_dir(&ds).unwrap();
        check_complete_folder(&ds).unwrap();
        std::fs::write(ds.join(INCOMPLETE_MARKER), b"").unwrap();
        let e = check_complete_folder(&ds).unwrap_err();
        assert!(e.to_string().contains("did not finish"), "{e}");
        let st = dir.path().join(".ds.aeroform-staging.42");
        std::fs::create_dir(&st).unwrap();
        let e = check_complete_folder(&st).unwrap_err();
        assert!(e.to_string().contains("process 42"), "{e}");
    }

    /// Issue 27 row 10: a symlink planted at the temporary path is not followed: the file
    /// it points to is untouched, the link is gone and the output is written.
    #[cfg(unix)]
    #[test]
    fn a_symlink_at_the_temporary_path_is_not_followed() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, b"keep").unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        let tmp = out.join(format!(".a.json.{}.tmp", std::process::id()));
        std::os::unix::fs::symlink(&victim, &tmp).unwrap();
        write_atomic(&out.join("a.json"), b"new").unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"keep");
        assert_eq!(std::fs::read(out.join("a.json")).unwrap(), b"new");
        assert!(std::fs::symlink_metadata(&tmp).is_err());
    }

    #[test]
    fn writes_and_replaces_whole_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no temporary file left behind");
    }

    #[test]
    fn missing_folder_is_an_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/a.txt");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert!(e.to_string().contains("a.txt"), "{e}");
    }

    #[test]
    fn folders_are_created_below_an_existing_root_only() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path().join("out");
        std::fs::create_dir(&root).unwrap();
        create_dir_below(&root, Path::new("a/b")).unwrap();
        create_dir_below(&root, Path::new("a/b")).unwrap();
        assert!(root.join("a/b").is_dir());
        std::fs::remove_dir_all(&root).unwrap();
        let e = create_dir_below(&root, Path::new("a"))
            .unwrap_err()
            .to_string();
        assert!(!root.exists(), "the root was recreated");
        assert!(e.contains("out"), "{e}");
        std::fs::write(&root, "").unwrap();
        assert!(create_dir_below(&root, Path::new("a")).is_err());
    }

    #[test]
    fn the_fingerprint_does_not_depend_on_how_the_bytes_arrive() {
        use std::io::Read;
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 37 % 251) as u8).collect();
        let whole = {
            let mut r = HashingReader::new(&data[..]);
            std::io::copy(&mut r, &mut std::io::sink()).unwrap();
            r.finish()
        };
        for chunk in [1usize, 3, 7, 8, 9, 64, 999] {
            let mut r = HashingReader::new(&data[..]);
            let mut buf = vec![0u8; chunk];
            while r.read(&mut buf).unwrap() > 0 {}
            assert_eq!(r.finish(), whole, "chunk {chunk}");
            assert_eq!(r.bytes_read(), 1000);
        }
        // one byte changed, one byte more, a zero byte appended: different fingerprints
        let mut other = data.clone();
        other[500] ^= 1;
        let fp = |d: &[u8]| {
            let mut r = HashingReader::new(d);
            std::io::copy(&mut r, &mut std::io::sink()).unwrap();
            r.finish()
        };
        assert_ne!(fp(&other), whole);
        assert_ne!(fp(&data[..999]), whole);
        let mut longer = data.clone();
        longer.push(0);
        assert_ne!(fp(&longer), whole);
    }
}
