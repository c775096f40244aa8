//! Exit codes: 0 success, 1 runtime failure, 2 usage or input error (a bad flag, study
//! file, data set, model or structure file, sweep specification, `--shard` or part
//! document, a limit of `aeroform::limits`), 130 SIGINT or SIGTERM (`interrupt`). Clap's
//! own usage errors exit with 2 as well.

/// A usage or input error raised by the binary itself (exit code 2).
#[derive(Debug)]
pub struct Usage(pub String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// Returns a [`Usage`] error (exit code 2) with the `format!` message: a flag or input the
/// binary itself refuses.
macro_rules! refuse {
    ($($arg:tt)*) => {
        return Err($crate::exit::Usage(format!($($arg)*)).into())
    };
}
pub(crate) use refuse;

/// The message of an error and its causes, `outer: inner: …`, each cause written once: the
/// crates' context variants (`{context}: {source}`) already print their source, which
/// `{:#}` would print a second time ("x: No such file or directory (os error 2): x: No such
/// file or directory (os error 2)", issue 27 row 17).
pub fn message(e: &anyhow::Error) -> String {
    let mut s = String::new();
    for c in e.chain() {
        let t = c.to_string();
        if s.is_empty() {
            s = t;
        } else if !s.contains(&t) {
            s.push_str(": ");
            s.push_str(&t);
        }
    }
    s
}

/// The exit code of an error: 2 when any error of its chain is an input error (the
/// input's file, line and field are in the message), else 1.
pub fn code(e: &anyhow::Error) -> u8 {
    if e.chain().any(is_input_error) {
        2
    } else {
        1
    }
}

fn is_input_error(c: &(dyn std::error::Error + 'static)) -> bool {
    if c.is::<Usage>()
        || c.is::<aeroform::limits::LimitError>()
        || c.is::<aeroform::study_spec::SpecError>()
    {
        return true;
    }
    // an input refused by its readers: missing, not a regular file, beyond its size cap,
    // not UTF-8 (`identify::io::read_text`, `open_regular`: an `InputFileError` inside),
    // whichever crate's error carries it
    if let Some(e) = c.downcast_ref::<std::io::Error>() {
        return identify::io::is_input_error(e)
            || matches!(
                e.kind(),
                std::io::ErrorKind::InvalidInput | std::io::ErrorKind::InvalidData
            );
    }
    // a JSON input (a part document, a result file `plot` reads) that does not parse or
    // has the wrong shape; a failing writer is an I/O error
    if let Some(e) = c.downcast_ref::<serde_json::Error>() {
        return !e.is_io();
    }
    // `Context` variants hold their source boxed: the chain shows the box, look inside
    if let Some(e) = c.downcast_ref::<Box<study::Error>>() {
        return is_input_error(&**e);
    }
    if let Some(e) = c.downcast_ref::<Box<plots::Error>>() {
        return is_input_error(&**e);
    }
    if let Some(e) = c.downcast_ref::<study::Error>() {
        // the transparent variants hide the wrapped error from the chain: look inside
        return match e {
            study::Error::Usage(_) | study::Error::Spec(_) => true,
            study::Error::Identify(e) => is_input_error(e),
            study::Error::Aeroelastic(e) => is_input_error(e),
            _ => false,
        };
    }
    if let Some(e) = c.downcast_ref::<plots::Error>() {
        return match e {
            plots::Error::Write(e) => is_input_error(e),
            plots::Error::Study(e) => is_input_error(e),
            _ => false,
        };
    }
    if let Some(e) = c.downcast_ref::<identify::Error>() {
        use identify::Error as E;
        return matches!(
            e,
            E::Manifest { .. }
                | E::Csv { .. }
                | E::NonUniformSampling { .. }
                | E::TooShort { .. }
                | E::InvalidOption { .. }
                | E::InvalidData { .. }
                | E::IncompleteFolder { .. }
                | E::Json { .. }
                | E::Unphysical { .. }
                | E::OutsideFittedRange { .. }
        );
    }
    if let Some(e) = c.downcast_ref::<aeroelastic::Error>() {
        use aeroelastic::Error as E;
        return matches!(
            e,
            E::InvalidParameter { .. }
                | E::Toml { .. }
                | E::InvalidTable { .. }
                | E::Document { .. }
                | E::WrongFormat { .. }
        ) || matches!(e, E::Identify { source, .. } if is_input_error(source));
    }
    if let Some(e) = c.downcast_ref::<diagnose::Error>() {
        use diagnose::Error as E;
        // `Sweep`: a sweep specification, `--shard i/n` or a part document; a file the
        // specification names (`structure`, `model`) refused by its reader
        return match e {
            E::Setting { .. } | E::UnknownEffect { .. } | E::Data { .. } | E::Sweep { .. } => true,
            E::Aeroelastic { source, .. } => is_input_error(&**source),
            E::Identify { source, .. } => is_input_error(&**source),
            _ => false,
        };
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    #[test]
    fn input_errors_exit_2_through_context_and_others_1() {
        let e: anyhow::Error = Usage("bad".into()).into();
        assert_eq!(code(&e.context("outer")), 2);
        let r: Result<(), identify::Error> = Err(identify::Error::Csv {
            path: "a.csv".into(),
            line: 3,
            field: "h".into(),
            message: "x".into(),
        });
        assert_eq!(code(&r.context("reading").unwrap_err()), 2);
        let io = identify::Error::io("a", std::io::Error::other("disk"));
        assert_eq!(code(&anyhow::Error::from(io)), 1);
        assert_eq!(code(&anyhow::anyhow!("plain")), 1);
        // through the study and plots crates' own context wrappers
        let csv = || identify::Error::Csv {
            path: "a.csv".into(),
            line: 3,
            field: "h".into(),
            message: "x".into(),
        };
        let r: Result<(), identify::Error> = Err(csv());
        let s = study::Context::context(r, "reading").unwrap_err();
        assert_eq!(code(&anyhow::Error::from(s)), 2);
        let r: Result<(), identify::Error> = Err(csv());
        let s = study::Context::context(r, "reading").unwrap_err();
        let p = plots::Error::Study(study::Error::Context {
            context: "outer".into(),
            source: Box::new(s),
        });
        assert_eq!(code(&anyhow::Error::from(p)), 2);
        let u = study::Error::Usage("bad key".into());
        let r: Result<(), study::Error> = Err(u);
        assert_eq!(
            code(&anyhow::Error::from(
                study::Context::context(r, "stage").unwrap_err()
            )),
            2
        );
        let r: Result<(), std::io::Error> = Err(std::io::Error::other("disk"));
        let r = r.map_err(|source| study::Error::Io {
            context: "x".into(),
            source,
        });
        let s = study::Context::context(r, "stage").unwrap_err();
        assert_eq!(code(&anyhow::Error::from(s)), 1);
        // a bad `--shard` (issue 27, row 17)
        let shard = benchmark::sweep::parse_shard("3/2").unwrap_err();
        assert_eq!(code(&anyhow::Error::from(shard)), 2);
    }

    /// Issue 39, row 7: the refusals that exited 1 — a missing input (inside any crate's
    /// error), a JSON document that does not parse, a file named by a sweep specification —
    /// exit 2 by their type; a failing disk stays 1.
    #[test]
    fn reader_refusals_and_json_errors_exit_2_by_type() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("missing.json");
        let e = identify::io::read_text(&missing).unwrap_err();
        let e = anyhow::Error::new(e).context("reading missing.json");
        assert_eq!(code(&e), 2);
        let e = identify::Error::io(&missing, identify::io::read_text(&missing).unwrap_err());
        assert_eq!(code(&anyhow::Error::from(e)), 2);
        let j = serde_json::from_str::<serde_json::Value>("{").unwrap_err();
        assert_eq!(code(&anyhow::Error::new(j).context("p0.json: not JSON")), 2);
        let a = aeroelastic::files::StructureFile::read(&missing).unwrap_err();
        let d = diagnose::Error::Aeroelastic {
            context: "sweep files".into(),
            source: Box::new(a),
        };
        assert_eq!(code(&anyhow::Error::from(d)), 2);
        let disk = identify::Error::io(&missing, std::io::Error::other("disk"));
        assert_eq!(code(&anyhow::Error::from(disk)), 1);
    }

    #[test]
    fn a_cause_already_in_its_context_is_written_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "x: missing");
        let e = anyhow::Error::new(io).context("sweep files a and x: x: missing");
        assert_eq!(super::message(&e), "sweep files a and x: x: missing");
        let e = anyhow::anyhow!("inner").context("outer");
        assert_eq!(super::message(&e), "outer: inner");
    }
}
