//! The study file (TOML): what to compute and draw. Parsed once with `deny_unknown_fields`
//! everywhere; every error names the file, the line and the dotted key.

use std::path::{Path, PathBuf};

mod types;
mod validate;

pub use types::*;

/// A parsed study with its source text and location.
#[derive(Debug, Clone)]
pub struct Study {
    /// Parsed content.
    pub spec: StudySpec,
    /// The TOML text as read (copied to `OUT/study.toml`).
    pub text: String,
    /// File it came from (`<built-in quickstart>` for the embedded study).
    pub path: PathBuf,
    /// Folder relative paths are resolved against.
    pub base: PathBuf,
}

/// The built-in quickstart study.
pub const QUICKSTART: &str = include_str!("../../scenarios/quickstart.toml");

/// An error in a study file: file, line, key, message.
#[derive(Debug)]
pub struct SpecError {
    /// Study file.
    pub path: String,
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// Dotted key.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for SpecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}:{}: key `{}`: {}",
            self.path, self.line, self.key, self.message
        )
    }
}

impl std::error::Error for SpecError {}

/// The dotted key (`flutter.run[1].label`) of the first string below `t` holding a character
/// [`identify::io::disallowed_char`] refuses, with the message.
fn first_bad_string(t: &toml::Table, prefix: &str) -> Option<(String, String)> {
    fn walk(v: &toml::Value, key: &str) -> Option<(String, String)> {
        match v {
            toml::Value::String(s) => identify::io::disallowed_char(s).map(|(pos, c)| {
                (
                    key.to_string(),
                    identify::io::disallowed_char_message(pos, c),
                )
            }),
            toml::Value::Array(a) => a
                .iter()
                .enumerate()
                .find_map(|(i, x)| walk(x, &format!("{key}[{i}]"))),
            toml::Value::Table(t) => first_bad_string(t, key),
            _ => None,
        }
    }
    t.iter().find_map(|(k, v)| {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        walk(v, &key)
    })
}

impl Study {
    /// Parses a study from TOML text.
    ///
    /// # Errors
    /// [`SpecError`] naming the line and key of a syntax error, an unknown key, a value of
    /// the wrong type or a value out of range.
    pub fn parse(text: &str, path: &Path, base: &Path) -> Result<Study, SpecError> {
        let display = path.display().to_string();
        let lines = identify::toml_lines::TomlLines::new(text);
        let spec: StudySpec = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| lines.line(s.start)).unwrap_or(0);
            let msg = e.message().trim().to_string();
            // serde names the key in its message (`unknown field `x``, `missing field`);
            // a bad value (an unknown model or method name, a wrong type) is named by the
            // key of the line it stands on
            let key = msg
                .split('`')
                .nth(1)
                .filter(|_| msg.contains("field"))
                .map(str::to_string)
                .or_else(|| e.span().and_then(|s| key_at(text, s.start)));
            // `[structure]` is flattened: serde reports a wrong-typed value there without
            // its key; find the key again
            if key.is_none() {
                let culprit = text
                    .parse::<toml::Table>()
                    .ok()
                    .and_then(|t| t.get("structure").and_then(|v| v.as_table()).cloned())
                    .and_then(|t| aeroelastic::files::flattened_bad_key::<StudyStructure>(&t));
                if let Some((k, message)) = culprit {
                    let key = format!("structure.{k}");
                    return SpecError {
                        path: display.clone(),
                        line: lines.line_of(&key),
                        key,
                        message,
                    };
                }
            }
            SpecError {
                path: display.clone(),
                line,
                key: key.unwrap_or_else(|| "(syntax)".to_string()),
                message: msg,
            }
        })?;
        // every string of the study may reach a figure (SVG), the report (HTML) or the
        // terminal: a control character is refused here, by key and line, not at the figure
        // stage (issue 39, row 7)
        if let Some((key, message)) = text
            .parse::<toml::Table>()
            .ok()
            .and_then(|t| first_bad_string(&t, ""))
        {
            return Err(SpecError {
                path: display,
                line: lines.line_of(&key),
                key,
                message,
            });
        }
        let study = Study {
            spec,
            text: text.to_string(),
            path: path.to_path_buf(),
            base: base.to_path_buf(),
        };
        study.validate().map_err(|(key, message)| SpecError {
            path: display,
            line: lines.line_of(&key),
            key,
            message,
        })?;
        Ok(study)
    }

    /// Reads and parses a study file (relative data paths resolve against its folder).
    ///
    /// # Errors
    /// [`SpecError`] when the file cannot be read (line 0) or does not parse.
    pub fn read(path: &Path) -> Result<Study, SpecError> {
        let text = identify::io::read_text(path).map_err(|e| SpecError {
            path: path.display().to_string(),
            line: 0,
            key: "(file)".into(),
            message: e.to_string(),
        })?;
        let base = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        Study::parse(&text, path, &base)
    }

    /// Every file and folder the study reads, with the key that names it (`study` for the
    /// study file itself, unless embedded; `data.dataset`, `data.virtual.model`,
    /// `branch.measured`), relative paths resolved against [`Study::base`]. A run's output
    /// folder may not be, contain or lie inside any of them (issue 39, row 1).
    pub fn inputs(&self) -> Vec<(&'static str, PathBuf)> {
        let mut v = Vec::new();
        if self.path.exists() {
            v.push(("study", self.path.clone()));
        }
        let d = self.spec.data.as_ref();
        if let Some(p) = d.and_then(|d| d.dataset.as_ref()) {
            v.push(("data.dataset", self.base.join(p)));
        }
        let virtual_model = d.and_then(|d| d.virtual_tunnel.as_ref()?.model.as_ref());
        if let Some(p) = virtual_model {
            v.push(("data.virtual.model", self.base.join(p)));
        }
        if let Some(p) = self.spec.branch.as_ref().and_then(|b| b.measured.as_ref()) {
            v.push(("branch.measured", self.base.join(p)));
        }
        if let Some(p) = self.spec.aero.as_ref().and_then(|a| a.file.as_ref()) {
            v.push(("aero.file", self.base.join(p)));
        }
        v
    }

    /// The embedded quickstart study.
    ///
    /// # Errors
    /// Never for the committed file (checked by a unit test).
    pub fn quickstart() -> Result<Study, SpecError> {
        Study::parse(
            QUICKSTART,
            Path::new("<built-in quickstart.toml>"),
            Path::new("."),
        )
    }

    /// Figure kinds this study draws.
    pub fn figure_kinds(&self) -> Vec<String> {
        if let Some(f) = &self.spec.outputs.figures {
            return f.clone();
        }
        let s = &self.spec;
        let mut v: Vec<&str> = vec![];
        if s.data.is_some() {
            v.extend([
                "time_series",
                "spectrum",
                "library",
                "delta_path",
                "delta_fits",
            ]);
            v.push("histogram");
            if s.data.as_ref().is_some_and(|d| d.table_iv.is_none()) {
                v.extend([
                    "force_decomposition",
                    "heatmap",
                    "force_loops",
                    "derivatives",
                    "mean_angle",
                ]);
            }
        }
        if s.flutter.is_some() {
            v.push("vg");
        }
        if let Some(l) = &s.lco {
            v.push("bifurcation");
            if !l.phase_speeds.is_empty() {
                v.push("phase");
            }
        }
        if s.branch.is_some() {
            v.push("branch_diagram");
        }
        v.into_iter().map(String::from).collect()
    }

    /// Range and consistency checks; `Err((dotted key, message))` (the sections' checks
    /// live in `validate`).
    fn validate(&self) -> Result<(), (String, String)> {
        validate::study(&self.spec)
    }
}

/// The dotted key (`table.array[i].key`) of the `key = value` line holding byte `offset`
/// of `text`, from the nearest table header above it; `None` off a `key = value` line.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let start = text[..offset.min(text.len())]
        .rfind('\n')
        .map_or(0, |i| i + 1);
    let line = text[start..].lines().next()?;
    let leaf = line.split_once('=')?.0.trim();
    if leaf.is_empty() || leaf.starts_with('[') {
        return None;
    }
    let above = &text[..start];
    let header = above
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['));
    let table = match header {
        Some(h) if h.starts_with("[[") => {
            let name = h.trim_start_matches('[').trim_end_matches(']').trim();
            let count = above
                .lines()
                .map(str::trim)
                .filter(|l| {
                    l.starts_with("[[")
                        && l.trim_start_matches('[').trim_end_matches(']').trim() == name
                })
                .count();
            format!("{name}[{}].", count.saturating_sub(1))
        }
        Some(h) => format!(
            "{}.",
            h.trim_start_matches('[').trim_end_matches(']').trim()
        ),
        None => String::new(),
    };
    Some(format!("{table}{leaf}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Study, SpecError> {
        Study::parse(text, Path::new("s.toml"), Path::new("."))
    }

    /// `lag` takes its law from `aero.file` (relative to the study file, an input of the
    /// study); every other kind refuses a `file`, by key and line.
    #[test]
    fn lag_needs_its_file_and_other_kinds_refuse_one() {
        let base = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n[aero]\n";
        // a missing key is located at its table
        let e = parse(&format!("{base}model = \"lag\"\n")).unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.file", 6), "{e}");
        assert!(e.message.contains("identify DATASET --law lag"), "{e}");
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\nfile = \"l.json\"\n"
        ))
        .unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.file", 8), "{e}");
        assert!(e.message.contains("only `lag`"), "{e}");
        let s = parse(&format!("{base}model = \"lag\"\nfile = \"l.json\"\n")).unwrap();
        assert!(s
            .inputs()
            .iter()
            .any(|(k, p)| *k == "aero.file" && p.ends_with("l.json")));
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[flutter]\nu_min = 1.0\nu_max = 2.0\n\
             [[flutter.run]]\nlabel = \"l\"\nmethod = \"pk\"\nmodel = \"lag\"\n"
        ))
        .unwrap_err();
        assert_eq!(e.key, "flutter.run[0].model", "{e}");
    }

    #[test]
    fn quickstart_parses() {
        let s = Study::quickstart().unwrap();
        assert_eq!(s.spec.name, "quickstart");
        assert!(s.figure_kinds().contains(&"bifurcation".to_string()));
    }

    #[test]
    fn unknown_key_names_key_and_line() {
        let e = parse("name = \"x\"\n\n[flutter]\nu_min = 1.0\nu_maxx = 2.0\n").unwrap_err();
        assert_eq!(e.line, 5, "{e}");
        assert_eq!(e.key, "u_maxx", "{e}");
    }

    #[test]
    fn range_error_names_nested_key_and_line() {
        let text = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n\
                    [aero]\nmodel = \"theodorsen\"\n[flutter]\nu_min = 1.0\nu_max = 3.0\n\
                    [[flutter.run]]\nlabel = \"a\"\nmethod = \"pk\"\n[[flutter.run]]\n\
                    label = \"b\"\nmethod = \"q\"\n";
        let e = parse(text).unwrap_err();
        assert_eq!(e.key, "flutter.run[1].method", "{e}");
        assert_eq!(e.line, 16, "{e}");
    }

    /// Model names are an enum: a misspelt one is refused at parsing, by key and line, with
    /// the names that exist; `truth` is a flutter-run model only.
    #[test]
    fn unknown_or_misplaced_model_names_the_key() {
        let base = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n[aero]\n";
        let e = parse(&format!("{base}model = \"theodorsn\"\n")).unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.model", 7), "{e}");
        assert!(e.message.contains("theodorsen"), "{e}");
        // [aero] is a model file: `truth` is no kind of it (a flutter-run model only)
        let e = parse(&format!("{base}model = \"truth\"\n")).unwrap_err();
        assert_eq!((e.key.as_str(), e.line), ("aero.model", 7), "{e}");
        assert!(e.message.contains("unknown variant `truth`"), "{e}");
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[flutter]\nu_min = 0.1\nu_max = 3.0\n[[flutter.run]]\nlabel = \"t\"\nmodel = \"truth\"\nmethod = \"pk\"\n"
        ))
        .unwrap_err();
        assert_eq!(e.key, "flutter.run[0].model", "{e}");
        assert!(e.message.contains("[data.virtual]"), "{e}");
        // the chord of a study's model is the structure's; a study cannot run dynamic stall
        let e = parse(&format!("{base}model = \"theodorsen\"\nchord = 0.3\n")).unwrap_err();
        assert_eq!(e.key, "aero.chord", "{e}");
        let e = parse(&format!("{base}model = \"dynamic_stall\"\n")).unwrap_err();
        assert_eq!(e.key, "aero.model", "{e}");
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[[aero.nonlinear]]\nchannel = \"lift\"\nterm = \"h\"\ncoefficient = 1.0\n"
        ))
        .unwrap_err();
        assert_eq!(e.key, "aero.nonlinear[0].term", "{e}");
        assert!(e.message.contains("total degree must be ≥ 2"), "{e}");
        // a nonlinear term's channel is typed: a bad name is refused at parse, by key
        let e = parse(&format!(
            "{base}model = \"theodorsen\"\n[[aero.nonlinear]]\nchannel = \"pitch\"\n\
             term = \"alpha^3\"\ncoefficient = 1.0\n"
        ))
        .unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.line),
            ("aero.nonlinear[0].channel", 9),
            "{e}"
        );
        assert!(e.message.contains("expected \"lift\" or \"moment\""), "{e}");
    }

    /// Option names are enums: a misspelt one is refused at parsing with its key and line.
    #[test]
    fn option_names_are_refused_by_key_and_line() {
        let base = "name = \"x\"\n[structure]\nmu = 20.0\nr_alpha2 = 0.25\nsigma = 0.5\n[aero]\nmodel = \"theodorsen\"\n[flutter]\nu_min = 0.1\nu_max = 3.0\n";
        for (line, key) in [
            ("axes = \"reducd\"", "flutter.axes"),
            ("damping = \"h\"", "flutter.damping"),
        ] {
            let e = parse(&format!("{base}{line}\n")).unwrap_err();
            assert_eq!((e.key.as_str(), e.line), (key, 11), "{e}");
            assert!(e.message.contains("unknown variant"), "{e}");
        }
        let ok = parse(&format!("{base}axes = \"reduced\"\ndamping = \"g\"\n")).unwrap();
        let f = ok.spec.flutter.unwrap();
        assert_eq!((f.axes, f.damping), (Axes::Reduced, DampingAxis::G));
    }

    #[test]
    fn ensemble_size_and_level_are_checked_with_their_key() {
        for (v, key) in [
            ("ensemble = 1", "identify.ensemble"),
            ("ensemble = 100000", "identify.ensemble"),
            (
                "ensemble = 5\nensemble_level = 1.0",
                "identify.ensemble_level",
            ),
            (
                "ensemble = 5\nensemble_level = nan",
                "identify.ensemble_level",
            ),
        ] {
            let e = parse(&format!("name = \"x\"\n[identify]\n{v}\n")).unwrap_err();
            assert_eq!(e.key, key, "{v}: {e}");
        }
        let s = parse("name = \"x\"\n[identify]\nensemble = 8\n").unwrap();
        let id = s.spec.identify.unwrap();
        assert_eq!((id.ensemble, id.ensemble_level), (Some(8), 0.9));
    }

    #[test]
    fn data_needs_exactly_one_source_and_virtual_is_checked() {
        let e = parse("name = \"x\"\n[data]\n").unwrap_err();
        assert_eq!(e.key, "data");
        // neither a model file nor an inline model
        let e = parse("name = \"x\"\n[data.virtual]\nstill_air = true\n").unwrap_err();
        assert_eq!(e.key, "data.virtual");
        assert_eq!(e.line, 2, "{e}");
        let e =
            parse("name = \"x\"\n[data.virtual]\nmodel = \"m.toml\"\ncampaign = \"config=Q\"\n")
                .unwrap_err();
        assert_eq!(e.key, "data.virtual.campaign", "{e}");
        assert_eq!(e.line, 4, "{e}");
        let e = parse(
            "name = \"x\"\n[data.virtual]\n[data.virtual.aero]\nmodel = \"theodorsen\"\n\
             [[data.virtual.aero.nonlinear]]\nchannel = \"moment\"\nterm = \"alpha\"\ncoefficient = 1.0\n",
        )
        .unwrap_err();
        assert_eq!(e.key, "data.virtual.aero.nonlinear[0].term", "{e}");
        assert!(parse(
            "name = \"x\"\n[data.virtual]\nmodel = \"m.toml\"\ncampaign = \"config=D\"\n"
        )
        .is_ok());
    }
}
