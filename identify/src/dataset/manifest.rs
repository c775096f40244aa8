//! `manifest.toml`: parsing with line numbers, validation, and the canonical writer.
//!
//! The manifest is parsed twice from the same text: once into a [`toml::Table`] (the values)
//! and once into a [`toml::de::DeTable`] (the byte spans), so that every validation error
//! names the 1-based line of the offending key. Case tables are named `case[i]` with `i`
//! 1-based (`case[1]` is the first `[[case]]` table).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::convention::{Angular, Convention, Linear};
use super::units::{AngleUnit, ForceUnit, LengthUnit, MomentUnit, UnitName, Units};
use crate::record::{CaseKind, CaseMeta, SectionGeometry};
use crate::{Error, Result};

/// The exact value of the manifest's `format` key.
pub const FORMAT: &str = "aeroform-dataset/1";

/// The linear structure of the 2-DOF section per unit span in "frequency" (modal) form: the
/// masses and the uncoupled still-air natural frequencies and damping ratios, SI. It is the
/// manifest's `[structure]` table and the linear part of a structure file
/// (`aeroelastic::files::StructureFile`); `aeroelastic::structure::ModalStructure::Modal`
/// resolves it to stiffnesses k_h = m (2πf_h)², k_α = I_α (2πf_α)² and dampers
/// c_h = 2ζ_h m 2πf_h, c_α = 2ζ_α I_α 2πf_α.
///
/// Serde form: the keys below, unknown keys rejected; `static_unbalance` and the damping
/// ratios default to 0 (a manifest requires every key, checked by [`Manifest::parse`]).
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields)]
pub struct ModalStructure {
    /// Mass per unit span m \[kg/m\], > 0.
    pub mass: f64,
    /// Mass moment of inertia about the elastic axis I_α \[kg·m²/m\], > 0.
    pub inertia: f64,
    /// Static unbalance S_α = m·x_α \[kg·m/m\], positive when the mass centre is aft of the
    /// elastic axis.
    #[serde(default)]
    pub static_unbalance: f64,
    /// Still-air uncoupled natural frequency of heave \[Hz\]: > 0 in a manifest, ≥ 0 in a
    /// structure file (0 = no heave spring).
    pub freq_heave: f64,
    /// Still-air uncoupled natural frequency of pitch \[Hz\], > 0.
    pub freq_pitch: f64,
    /// Damping ratio of heave (fraction of critical), ≥ 0.
    #[serde(default)]
    pub damping_heave: f64,
    /// Damping ratio of pitch (fraction of critical), ≥ 0.
    #[serde(default)]
    pub damping_pitch: f64,
}

impl ModalStructure {
    /// The keys of the modal form, in documented order (a manifest's `[structure]`, the
    /// linear part of a structure file).
    pub const KEYS: [&'static str; 7] = [
        "mass",
        "inertia",
        "static_unbalance",
        "freq_heave",
        "freq_pitch",
        "damping_heave",
        "damping_pitch",
    ];
}

/// One `[[case]]` table of the manifest. Values are in the manifest's units
/// (`amplitude` and `mean_pitch` in `units.pitch`); [`Manifest::case_meta`] converts to SI.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseSpec {
    /// Unique id, `[A-Za-z0-9._-]+`.
    pub id: String,
    /// Forced (prescribed motion) or free response.
    pub kind: CaseKind,
    /// CSV file, relative to the data-set folder.
    pub file: PathBuf,
    /// Wind speed U \[m/s\], ≥ 0.
    pub wind_speed: f64,
    /// Motion configuration label (paper Table I).
    pub config: Option<String>,
    /// Pitch amplitude, in `units.pitch`, ≥ 0.
    pub amplitude: Option<f64>,
    /// Heave amplitude / pitch amplitude (mm per deg as in the paper; a label), ≥ 0.
    pub amplitude_ratio: Option<f64>,
    /// Prescribed pitch frequency \[Hz\], > 0.
    pub freq_pitch: Option<f64>,
    /// Prescribed heave frequency \[Hz\], > 0.
    pub freq_heave: Option<f64>,
    /// Mean angle of attack, in `units.pitch`.
    pub mean_pitch: Option<f64>,
    /// Still-air run of the same motion, relative to the data-set folder; when given the
    /// forces in `file` are raw balance forces.
    pub nowind_file: Option<PathBuf>,
    /// The case's `[extra]` table, kept verbatim and otherwise ignored.
    pub extra: Option<toml::Table>,
}

impl CaseSpec {
    /// A forced case with only the required keys set.
    pub fn forced(id: impl Into<String>, file: impl Into<PathBuf>, wind_speed: f64) -> Self {
        CaseSpec {
            id: id.into(),
            kind: CaseKind::Forced,
            file: file.into(),
            wind_speed,
            config: None,
            amplitude: None,
            amplitude_ratio: None,
            freq_pitch: None,
            freq_heave: None,
            mean_pitch: None,
            nowind_file: None,
            extra: None,
        }
    }
}

/// A data-set manifest (DATA_FORMAT.md), validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Manifest {
    /// Data-set name.
    pub name: String,
    /// Free text.
    pub description: Option<String>,
    /// Geometry and air, SI.
    pub section: SectionGeometry,
    /// Structure per unit span; required when any case is free.
    pub structure: Option<ModalStructure>,
    /// Units of the CSV columns.
    pub units: Units,
    /// Sign convention of the CSV columns (`[convention]`; Scanlan when absent).
    pub convention: Convention,
    /// The cases, in manifest order (at least one).
    pub cases: Vec<CaseSpec>,
    /// The top-level `[extra]` table, kept verbatim and otherwise ignored.
    pub extra: Option<toml::Table>,
}

impl Manifest {
    /// Reads and validates a manifest file.
    ///
    /// # Errors
    /// [`Error::Io`] when the file cannot be read; otherwise as [`Manifest::parse`].
    pub fn read(path: &Path) -> Result<Manifest> {
        let text = crate::io::read_text_capped(path, crate::limits::MAX_TEXT_FILE_BYTES as u64)?;
        if path.extension().is_some_and(|e| e == "json") {
            Manifest::parse_json(&text, path)
        } else {
            Manifest::parse(&text, path)
        }
    }

    /// Parses a `manifest.json`: the same keys and values as the TOML form, the `[[case]]`
    /// tables as an array `"case"` of objects (for tools that cannot write TOML, e.g.
    /// MATLAB's `jsonencode`). Validation is [`Manifest::parse`]'s; error lines point into
    /// the JSON text where the key can be found unambiguously (0 otherwise).
    ///
    /// # Errors
    /// [`Error::Manifest`] naming `path`, the line and the field: invalid JSON, a top level
    /// that is not an object, a `null` value, and everything [`Manifest::parse`] rejects.
    pub fn parse_json(text: &str, path: &Path) -> Result<Manifest> {
        let err = |line: usize, field: &str, message: String| Error::Manifest {
            path: path.to_path_buf(),
            line,
            field: field.to_string(),
            message,
        };
        let v: serde_json::Value = serde_json::from_str::<StrictJson>(text)
            .map(|s| s.0)
            .map_err(|e| err(e.line(), "(syntax)", format!("invalid JSON: {e}")))?;
        let t = match json_to_toml(&v, "") {
            Ok(toml::Value::Table(t)) => t,
            Ok(_) => return Err(err(1, "(top level)", "expected a JSON object".into())),
            Err(field) => {
                return Err(err(
                    json_line(text, &field),
                    &field,
                    "null is not allowed; leave the key out instead".into(),
                ))
            }
        };
        let toml_text = toml::to_string(&t)
            .map_err(|e| err(0, "(top level)", format!("cannot convert to TOML: {e}")))?;
        Manifest::parse(&toml_text, path).map_err(|e| match e {
            Error::Manifest {
                path,
                field,
                message,
                ..
            } => Error::Manifest {
                path,
                line: json_line(text, &field),
                field,
                message,
            },
            other => other,
        })
    }

    /// Parses and validates manifest text; `path` is only used in error messages.
    ///
    /// # Errors
    /// [`Error::Manifest`] naming `path`, the 1-based line and the dotted field for: TOML
    /// syntax errors; a `format` other than `"aeroform-dataset/1"`; a missing required
    /// table or key; an unknown key (outside `[extra]` tables); a value of the wrong type;
    /// an unknown unit string (the message lists the allowed ones); a case id that is not
    /// `[A-Za-z0-9._-]+` or is repeated; a `kind` other than `"forced"`/`"free"`; a missing
    /// `[structure]` while a case is free; a non-finite number or one out of its physical
    /// range (chord, span, air density, mass, inertia, frequencies > 0; wind speed,
    /// amplitudes, damping ratios ≥ 0).
    pub fn parse(text: &str, path: &Path) -> Result<Manifest> {
        let cx = Cx::new(text, path)?;
        cx.manifest()
    }

    /// Writes the manifest in the layout of DATA_FORMAT.md (keys in documented order;
    /// numbers printed in Rust's shortest round-trip form, so [`Manifest::parse`] gives
    /// back exactly the same values).
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "format = {}", quote(FORMAT));
        let _ = writeln!(s, "name = {}", quote(&self.name));
        if let Some(d) = &self.description {
            let _ = writeln!(s, "description = {}", quote(d));
        }
        s.push_str("\n[section]\n");
        let sec = &self.section;
        for (k, v) in [
            ("chord", sec.chord),
            ("span", sec.span),
            ("air_density", sec.air_density),
        ] {
            let _ = writeln!(s, "{k} = {}", float(v));
        }
        if let Some(st) = &self.structure {
            s.push_str("\n[structure]\n");
            for (k, v) in [
                ("mass", st.mass),
                ("inertia", st.inertia),
                ("static_unbalance", st.static_unbalance),
                ("freq_heave", st.freq_heave),
                ("freq_pitch", st.freq_pitch),
                ("damping_heave", st.damping_heave),
                ("damping_pitch", st.damping_pitch),
            ] {
                let _ = writeln!(s, "{k} = {}", float(v));
            }
        }
        let u = &self.units;
        s.push_str("\n[units]\n");
        let _ = writeln!(s, "heave = {}", quote(u.heave.as_str()));
        let _ = writeln!(s, "pitch = {}", quote(u.pitch.as_str()));
        let _ = writeln!(s, "lift = {}", quote(u.lift.as_str()));
        let _ = writeln!(s, "moment = {}", quote(u.moment.as_str()));
        if !self.convention.is_scanlan() {
            let c = &self.convention;
            s.push_str("\n[convention]\n");
            let _ = writeln!(s, "heave = {}", quote(c.heave.as_str()));
            let _ = writeln!(s, "pitch = {}", quote(c.pitch.as_str()));
            let _ = writeln!(s, "lift = {}", quote(c.lift.as_str()));
            let _ = writeln!(s, "moment = {}", quote(c.moment.as_str()));
        }
        if let Some(extra) = &self.extra {
            s.push_str("\n[extra]\n");
            write_table_body(&mut s, extra);
        }
        for c in &self.cases {
            s.push_str("\n[[case]]\n");
            let _ = writeln!(s, "id = {}", quote(&c.id));
            let kind = match c.kind {
                CaseKind::Forced => "forced",
                CaseKind::Free => "free",
            };
            let _ = writeln!(s, "kind = {}", quote(kind));
            let _ = writeln!(s, "file = {}", quote(&path_str(&c.file)));
            let _ = writeln!(s, "wind_speed = {}", float(c.wind_speed));
            if let Some(v) = &c.config {
                let _ = writeln!(s, "config = {}", quote(v));
            }
            for (k, v) in [
                ("amplitude", c.amplitude),
                ("amplitude_ratio", c.amplitude_ratio),
                ("freq_pitch", c.freq_pitch),
                ("freq_heave", c.freq_heave),
                ("mean_pitch", c.mean_pitch),
            ] {
                if let Some(v) = v {
                    let _ = writeln!(s, "{k} = {}", float(v));
                }
            }
            if let Some(p) = &c.nowind_file {
                let _ = writeln!(s, "nowind_file = {}", quote(&path_str(p)));
            }
            if let Some(extra) = &c.extra {
                s.push_str("\n[case.extra]\n");
                write_table_body(&mut s, extra);
            }
        }
        s
    }

    /// The descriptors of `case` converted to SI: `amplitude` and `mean_pitch` from
    /// `units.pitch` to rad (`mean_pitch` also to nose-up positive, see `[convention]`);
    /// frequencies \[Hz\], wind speed \[m/s\] and `amplitude_ratio` (a label) unchanged.
    pub fn case_meta(&self, case: &CaseSpec) -> CaseMeta {
        let p = self.units.pitch;
        let sp = self.convention.pitch.sign();
        CaseMeta {
            id: case.id.clone(),
            wind_speed: case.wind_speed,
            config: case.config.clone(),
            amplitude: case.amplitude.map(|a| p.to_si(a)),
            amplitude_ratio: case.amplitude_ratio,
            freq_pitch: case.freq_pitch,
            freq_heave: case.freq_heave,
            mean_pitch: case.mean_pitch.map(|a| sp * p.to_si(a)),
        }
    }

    /// The case with this id.
    pub fn case(&self, id: &str) -> Option<&CaseSpec> {
        self.cases.iter().find(|c| c.id == id)
    }
}

/// A JSON value as a TOML value (integers stay integers); `Err(field)` names the first `null`.
/// A JSON value read like `serde_json::Value` but refusing a key repeated in one object
/// (which `serde_json::Value` resolves silently, the last one winning; TOML refuses it).
struct StrictJson(serde_json::Value);

impl<'de> serde::Deserialize<'de> for StrictJson {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(StrictVisitor).map(StrictJson)
    }
}

struct StrictVisitor;

impl<'de> serde::de::Visitor<'de> for StrictVisitor {
    type Value = serde_json::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> std::result::Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_i64<E>(self, v: i64) -> std::result::Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_u64<E>(self, v: u64) -> std::result::Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_f64<E>(self, v: f64) -> std::result::Result<Self::Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, Into::into))
    }
    fn visit_str<E>(self, v: &str) -> std::result::Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_string<E>(self, v: String) -> std::result::Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_unit<E>(self) -> std::result::Result<Self::Value, E> {
        Ok(serde_json::Value::Null)
    }
    fn visit_none<E>(self) -> std::result::Result<Self::Value, E> {
        Ok(serde_json::Value::Null)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(
        self,
        mut seq: A,
    ) -> std::result::Result<Self::Value, A::Error> {
        let mut v = Vec::new();
        while let Some(StrictJson(x)) = seq.next_element()? {
            v.push(x);
        }
        Ok(serde_json::Value::Array(v))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(
        self,
        mut map: A,
    ) -> std::result::Result<Self::Value, A::Error> {
        use serde::de::Error as _;
        let mut m = serde_json::Map::new();
        while let Some(k) = map.next_key::<String>()? {
            if m.contains_key(&k) {
                return Err(A::Error::custom(format!("duplicate key `{k}`")));
            }
            let StrictJson(v) = map.next_value()?;
            m.insert(k, v);
        }
        Ok(serde_json::Value::Object(m))
    }
}

fn json_to_toml(v: &serde_json::Value, field: &str) -> std::result::Result<toml::Value, String> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => return Err(field.to_string()),
        J::Bool(b) => toml::Value::Boolean(*b),
        J::Number(n) => match n.as_i64() {
            Some(i) => toml::Value::Integer(i),
            None => toml::Value::Float(n.as_f64().unwrap_or(f64::NAN)),
        },
        J::String(s) => toml::Value::String(s.clone()),
        J::Array(a) => toml::Value::Array(
            a.iter()
                .enumerate()
                .map(|(i, x)| json_to_toml(x, &format!("{field}[{}]", i + 1)))
                .collect::<std::result::Result<_, _>>()?,
        ),
        J::Object(o) => {
            let mut t = toml::Table::new();
            for (k, x) in o {
                let f = if field.is_empty() {
                    k.clone()
                } else {
                    format!("{field}.{k}")
                };
                t.insert(k.clone(), json_to_toml(x, &f)?);
            }
            toml::Value::Table(t)
        }
    })
}

/// 1-based line of the key that `field` (`section.chord`, `case[2].wind_speed`) names in a
/// JSON manifest: the n-th occurrence of `"key"` for `case[n]` when the key occurs once per
/// case, the only occurrence otherwise; 0 when that is ambiguous.
fn json_line(text: &str, field: &str) -> usize {
    let last = field.rsplit('.').next().unwrap_or(field);
    let key = last.split('[').next().unwrap_or(last);
    let quoted = format!("\"{key}\"");
    let hits: Vec<usize> = text.match_indices(&quoted).map(|(i, _)| i).collect();
    let line_of = |i: usize| text[..i].matches('\n').count() + 1;
    let case_n = field
        .strip_prefix("case[")
        .and_then(|r| r.split(']').next())
        .and_then(|n| n.parse::<usize>().ok());
    let n_cases = text.matches("\"id\"").count();
    match (case_n, hits.len()) {
        (_, 1) => line_of(hits[0]),
        (Some(n), h) if h == n_cases && (1..=h).contains(&n) => line_of(hits[n - 1]),
        _ => 0,
    }
}

/// A path as written in the manifest (forward slashes on every platform).
fn path_str(p: &Path) -> String {
    let s = p.to_string_lossy();
    if std::path::MAIN_SEPARATOR == '\\' {
        s.replace('\\', "/")
    } else {
        s.into_owned()
    }
}

/// A finite float in TOML form (shortest round-trip digits, always with `.` or exponent).
fn float(x: f64) -> String {
    toml::Value::Float(x).to_string()
}

/// A TOML basic string (one line, escaped).
fn quote(s: &str) -> String {
    let mut o = String::with_capacity(s.len() + 2);
    o.push('"');
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            '\n' => o.push_str("\\n"),
            '\t' => o.push_str("\\t"),
            '\r' => o.push_str("\\r"),
            c if (c as u32) < 0x20 || c as u32 == 0x7f => {
                let _ = write!(o, "\\u{:04X}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// A TOML key: bare when possible, else a quoted basic string.
fn key(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        quote(k)
    }
}

/// `key = value` lines of an `[extra]` table; nested tables and arrays are written inline.
fn write_table_body(s: &mut String, t: &toml::Table) {
    for (k, v) in t {
        let v = match v {
            toml::Value::String(x) => quote(x),
            other => other.to_string(),
        };
        let _ = writeln!(s, "{} = {v}", key(k));
    }
}

/// Refuses a label longer than [`crate::limits::MAX_LABEL_CHARS`] characters, naming its key.
fn label_length(node: &Node<'_, '_>, key: &str, value: &str) -> Result<()> {
    let n = value.chars().count();
    if n > crate::limits::MAX_LABEL_CHARS {
        return Err(node.err(
            key,
            format!(
                "{n} characters; a label has at most {} (the limits table's MAX_LABEL_CHARS)",
                crate::limits::MAX_LABEL_CHARS
            ),
        ));
    }
    Ok(())
}

/// True for a valid case id: `[A-Za-z0-9._-]+`.
pub fn is_valid_case_id(id: &str) -> bool {
    !id.is_empty()
        && id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'))
}

// ---------------------------------------------------------------------------------------
// Validation.

/// Parse context: the manifest text, its spans and the path for messages.
struct Cx<'a> {
    path: &'a Path,
    lines: crate::toml_lines::TomlLines<'static>,
    values: toml::Table,
    spans: Spanned<DeTable<'a>>,
}

/// A table being validated: its values, its spans, its dotted name and its line.
#[derive(Clone, Copy)]
struct Node<'c, 'a> {
    cx: &'c Cx<'a>,
    values: &'c toml::Table,
    spans: Option<&'c DeTable<'a>>,
    /// Dotted prefix for field names ("" at the top level, "section.", "case[2].").
    prefix: &'c str,
    line: usize,
}

impl<'a> Cx<'a> {
    fn new(text: &'a str, path: &'a Path) -> Result<Self> {
        let mut cx = Cx {
            path,
            lines: crate::toml_lines::TomlLines::unparsed(text),
            values: toml::Table::new(),
            spans: Spanned::new(0..0, DeTable::default()),
        };
        cx.values = text.parse::<toml::Table>().map_err(|e| {
            let line = e.span().map(|s| cx.line(s.start)).unwrap_or(0);
            cx.err(
                line,
                "(syntax)",
                format!("invalid TOML: {}", e.message().trim()),
            )
        })?;
        cx.spans = DeTable::parse(text).map_err(|e| {
            let line = e.span().map(|s| cx.line(s.start)).unwrap_or(0);
            cx.err(
                line,
                "(syntax)",
                format!("invalid TOML: {}", e.message().trim()),
            )
        })?;
        Ok(cx)
    }

    /// 1-based line of a byte offset.
    fn line(&self, offset: usize) -> usize {
        self.lines.line(offset)
    }

    fn err(&self, line: usize, field: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Manifest {
            path: self.path.to_path_buf(),
            line,
            field: field.into(),
            message: message.into(),
        }
    }

    fn root(&self) -> Node<'_, 'a> {
        Node {
            cx: self,
            values: &self.values,
            spans: Some(self.spans.get_ref()),
            prefix: "",
            line: 1,
        }
    }

    fn manifest(&self) -> Result<Manifest> {
        let root = self.root();
        root.check_keys(&[
            "format",
            "name",
            "description",
            "section",
            "structure",
            "units",
            "convention",
            "case",
            "extra",
        ])?;
        let format = root.req_str("format")?;
        if format != FORMAT {
            return Err(root.err("format", format!("\"{format}\" is not \"{FORMAT}\"")));
        }
        let name = root.req_str("name")?.to_string();
        label_length(&root, "name", &name)?;
        let description = root.opt_str("description")?.map(str::to_string);

        let sec_prefix = "section.";
        let sec = root.req_table("section", sec_prefix)?;
        sec.check_keys(&["chord", "span", "air_density"])?;
        let section = SectionGeometry {
            chord: sec.req_pos("chord", "m")?,
            span: sec.req_pos("span", "m")?,
            air_density: sec.req_pos("air_density", "kg/m^3")?,
        };

        let structure = match root.opt_table("structure", "structure.")? {
            None => None,
            Some(st) => {
                st.check_keys(&ModalStructure::KEYS)?;
                Some(ModalStructure {
                    mass: st.req_pos("mass", "kg/m")?,
                    inertia: st.req_pos("inertia", "kg m^2/m")?,
                    static_unbalance: st.req_f64("static_unbalance")?,
                    freq_heave: st.req_pos("freq_heave", "Hz")?,
                    freq_pitch: st.req_pos("freq_pitch", "Hz")?,
                    damping_heave: st.req_nonneg("damping_heave", "")?,
                    damping_pitch: st.req_nonneg("damping_pitch", "")?,
                })
            }
        };

        let un = root.req_table("units", "units.")?;
        un.check_keys(&["heave", "pitch", "lift", "moment"])?;
        let units = Units {
            heave: un.req_unit::<LengthUnit>("heave")?,
            pitch: un.req_unit::<AngleUnit>("pitch")?,
            lift: un.req_unit::<ForceUnit>("lift")?,
            moment: un.req_unit::<MomentUnit>("moment")?,
        };

        let convention = match root.opt_table("convention", "convention.")? {
            None => Convention::default(),
            Some(cv) => {
                cv.check_keys(&["heave", "pitch", "lift", "moment"])?;
                let d = Convention::default();
                Convention {
                    heave: cv.opt_unit::<Linear>("heave")?.unwrap_or(d.heave),
                    pitch: cv.opt_unit::<Angular>("pitch")?.unwrap_or(d.pitch),
                    lift: cv.opt_unit::<Linear>("lift")?.unwrap_or(d.lift),
                    moment: cv.opt_unit::<Angular>("moment")?.unwrap_or(d.moment),
                }
            }
        };

        let extra = root.opt_extra("extra")?;
        let cases = self.cases(&root)?;
        // angles in the limits table's bound (issue 39, row 6: `mean_pitch = 1e5` was
        // accepted and `1e300` blamed on "library column 0")
        for (i, c) in cases.iter().enumerate() {
            for (key, v) in [("amplitude", c.amplitude), ("mean_pitch", c.mean_pitch)] {
                let Some(v) = v else { continue };
                let deg = units.pitch.to_si(v).to_degrees();
                if let Err(m) = crate::limits::abs_at_most(deg, crate::limits::MAX_PITCH_DEG, "deg")
                {
                    let line = self
                        .case_node(&root, i)
                        .map(|n| n.line_of(key))
                        .unwrap_or(0);
                    return Err(self.err(
                        line,
                        format!("case[{}].{key}", i + 1),
                        format!("{m} (the limits table's MAX_PITCH_DEG)"),
                    ));
                }
            }
        }

        if structure.is_none() {
            if let Some((i, c)) = cases
                .iter()
                .enumerate()
                .find(|(_, c)| c.kind == CaseKind::Free)
            {
                let line = self
                    .case_node(&root, i)
                    .map(|n| n.line_of("kind"))
                    .unwrap_or(0);
                return Err(self.err(
                    line,
                    "structure",
                    format!(
                        "table [structure] is required because case `{}` has kind = \"free\"",
                        c.id
                    ),
                ));
            }
        }

        Ok(Manifest {
            name,
            description,
            section,
            structure,
            units,
            convention,
            cases,
            extra,
        })
    }

    /// The spans of the `i`-th (0-based) case table.
    fn case_spans(&self, i: usize) -> Option<(&DeTable<'a>, usize)> {
        let arr = self.spans.get_ref().get("case")?;
        let item = arr.get_ref().as_array()?.get(i)?;
        Some((item.get_ref().as_table()?, self.line(item.span().start)))
    }

    fn case_node<'c>(&'c self, root: &Node<'c, 'a>, i: usize) -> Option<Node<'c, 'a>> {
        let t = root.values.get("case")?.as_array()?.get(i)?.as_table()?;
        let (spans, line) = match self.case_spans(i) {
            Some((s, l)) => (Some(s), l),
            None => (None, root.line_of("case")),
        };
        Some(Node {
            cx: self,
            values: t,
            spans,
            prefix: "",
            line,
        })
    }

    fn cases(&self, root: &Node<'_, 'a>) -> Result<Vec<CaseSpec>> {
        let Some(v) = root.values.get("case") else {
            return Err(root.err(
                "case",
                "at least one [[case]] table is required".to_string(),
            ));
        };
        let arr = match v.as_array() {
            Some(a) if a.iter().all(|x| x.is_table()) => a,
            _ => {
                return Err(root.err(
                    "case",
                    "`case` must be an array of tables, written [[case]]".to_string(),
                ))
            }
        };
        if arr.is_empty() {
            return Err(root.err(
                "case",
                "at least one [[case]] table is required".to_string(),
            ));
        }
        let mut seen: HashMap<String, (usize, usize)> = HashMap::new();
        let mut cases = Vec::with_capacity(arr.len());
        for i in 0..arr.len() {
            let prefix = format!("case[{}].", i + 1);
            let mut node = self
                .case_node(root, i)
                .expect("case table exists: checked above");
            node.prefix = &prefix;
            let c = node.case()?;
            if let Some((first, first_line)) = seen.get(&c.id) {
                return Err(node.err(
                    "id",
                    format!(
                        "duplicate case id \"{}\" (first used by case[{}] at line {first_line})",
                        c.id,
                        first + 1
                    ),
                ));
            }
            seen.insert(c.id.clone(), (i, node.line_of("id")));
            cases.push(c);
        }
        Ok(cases)
    }
}

/// Why a manifest path may not name a file inside the data set folder: `Some` reason when
/// it is absolute (a root, or a Windows drive/UNC prefix) or has a `..` component.
pub(crate) fn unsafe_relative_path(path: &Path) -> Option<&'static str> {
    use std::path::Component;
    for c in path.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => return Some("is absolute"),
            Component::ParentDir => return Some("has a `..` component"),
            Component::CurDir | Component::Normal(_) => {}
        }
    }
    // `Path` only recognises Windows prefixes on Windows; reject them everywhere so that a
    // manifest means the same on every platform.
    let s = path.to_string_lossy();
    let b = s.as_bytes();
    if s.starts_with('\\') || (b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':') {
        return Some("is absolute");
    }
    if s.split(['/', '\\']).any(|part| part == "..") {
        return Some("has a `..` component");
    }
    None
}

/// Dotted field name and 1-based line of `key` in the `[[case]]` table whose `id` is
/// `case_id`, looked up in the manifest text (`("case[?].KEY", 0)` when the text does not
/// parse or has no such case). Used by readers that report an error about a manifest value
/// after parsing, e.g. a case path that resolves outside the data-set folder.
/// Upper bounds of physical plausibility of manifest numbers (key, bound in the key's unit):
/// a value above is an error naming the file, line and field. Chosen far outside any
/// wind-tunnel section (docs/DATA_FORMAT.md) so that they only catch typos and absurd
/// inputs (one `wind_speed = 1e308` case used to wreck a whole group silently).
pub const PLAUSIBLE_MAX: [(&str, f64); 10] = [
    ("wind_speed", crate::limits::MAX_SPEED),
    ("chord", crate::limits::MAX_CHORD),
    ("span", crate::limits::MAX_SPAN),
    ("air_density", crate::limits::MAX_AIR_DENSITY),
    ("mass", 1e6),
    ("inertia", 1e6),
    ("freq_heave", 1e4),
    ("freq_pitch", 1e4),
    ("damping_heave", 10.0),
    ("damping_pitch", 10.0),
];

pub(crate) fn case_key_location(
    text: &str,
    path: &Path,
    case_id: &str,
    key: &str,
) -> (String, usize) {
    let unknown = (format!("case[?].{key}"), 0);
    let Ok(cx) = Cx::new(text, path) else {
        return unknown;
    };
    let root = cx.root();
    let Some(n) = root
        .values
        .get("case")
        .and_then(|v| v.as_array())
        .map(Vec::len)
    else {
        return unknown;
    };
    for i in 0..n {
        if let Some(node) = cx.case_node(&root, i) {
            if node.values.get("id").and_then(|v| v.as_str()) == Some(case_id) {
                return (format!("case[{}].{key}", i + 1), node.line_of(key));
            }
        }
    }
    unknown
}

impl<'c, 'a> Node<'c, 'a> {
    fn field(&self, key: &str) -> String {
        format!("{}{key}", self.prefix)
    }

    /// Line of `key` in this table (the table's line when the key is absent).
    fn line_of(&self, key: &str) -> usize {
        self.spans
            .and_then(|s| s.get(key))
            .map(|v| self.cx.line(v.span().start))
            .or_else(|| {
                self.spans.and_then(|s| {
                    s.iter()
                        .find(|(k, _)| k.get_ref() == key)
                        .map(|(k, _)| self.cx.line(k.span().start))
                })
            })
            .unwrap_or(self.line)
    }

    fn err(&self, key: &str, message: String) -> Error {
        self.cx.err(self.line_of(key), self.field(key), message)
    }

    fn check_keys(&self, allowed: &[&str]) -> Result<()> {
        // Report the first unknown key in file order.
        let mut unknown: Vec<(usize, &str)> = self
            .values
            .keys()
            .filter(|k| !allowed.contains(&k.as_str()))
            .map(|k| (self.line_of(k), k.as_str()))
            .collect();
        unknown.sort();
        if let Some((line, k)) = unknown.first() {
            return Err(self.cx.err(
                *line,
                self.field(k),
                format!(
                    "unknown key `{k}` (allowed here: {}; put free-form data in an [extra] table)",
                    allowed.join(", ")
                ),
            ));
        }
        Ok(())
    }

    fn opt_str(&self, key: &str) -> Result<Option<&'c str>> {
        match self.values.get(key) {
            None => Ok(None),
            Some(toml::Value::String(s)) => match crate::io::disallowed_char(s) {
                // every string of a manifest may reach a figure, a report or the terminal
                // (issue 39, row 7): refused here, by line and key
                Some((pos, c)) => Err(self.err(key, crate::io::disallowed_char_message(pos, c))),
                None => Ok(Some(s.as_str())),
            },
            Some(v) => Err(self.err(key, format!("expected a string, found {}", v.type_str()))),
        }
    }

    fn req_str(&self, key: &str) -> Result<&'c str> {
        self.opt_str(key)?
            .ok_or_else(|| self.err(key, "required key is missing".to_string()))
    }

    fn opt_f64(&self, key: &str) -> Result<Option<f64>> {
        let x = match self.values.get(key) {
            None => return Ok(None),
            Some(toml::Value::Float(x)) => *x,
            Some(toml::Value::Integer(i)) => *i as f64,
            Some(v) => {
                return Err(self.err(key, format!("expected a number, found {}", v.type_str())))
            }
        };
        if !x.is_finite() {
            return Err(self.err(key, format!("{x} is not a finite number")));
        }
        Ok(Some(x))
    }

    fn req_f64(&self, key: &str) -> Result<f64> {
        self.opt_f64(key)?
            .ok_or_else(|| self.err(key, "required key is missing".to_string()))
    }

    fn check_range(&self, key: &str, x: f64, positive: bool, unit: &str) -> Result<f64> {
        let ok = if positive { x > 0.0 } else { x >= 0.0 };
        if let Some((_, max)) = PLAUSIBLE_MAX.iter().find(|(k, _)| *k == key) {
            if ok && x > *max {
                return Err(self.err(
                    key,
                    format!("{x} {unit} is physically implausible (must be ≤ {max} {unit})"),
                ));
            }
        }
        if ok {
            Ok(x)
        } else {
            let unit = if unit.is_empty() {
                String::new()
            } else {
                format!(" {unit}")
            };
            let rel = if positive { "> 0" } else { ">= 0" };
            Err(self.err(key, format!("{x}{unit} must be {rel}")))
        }
    }

    fn req_pos(&self, key: &str, unit: &str) -> Result<f64> {
        let x = self.req_f64(key)?;
        self.check_range(key, x, true, unit)
    }

    fn req_nonneg(&self, key: &str, unit: &str) -> Result<f64> {
        let x = self.req_f64(key)?;
        self.check_range(key, x, false, unit)
    }

    fn opt_pos(&self, key: &str, unit: &str) -> Result<Option<f64>> {
        self.opt_f64(key)?
            .map(|x| self.check_range(key, x, true, unit))
            .transpose()
    }

    fn opt_nonneg(&self, key: &str, unit: &str) -> Result<Option<f64>> {
        self.opt_f64(key)?
            .map(|x| self.check_range(key, x, false, unit))
            .transpose()
    }

    fn opt_unit<U: UnitName>(&self, key: &str) -> Result<Option<U>> {
        match self.opt_str(key)? {
            None => Ok(None),
            Some(s) => U::from_name(s).map(Some).ok_or_else(|| {
                self.err(
                    key,
                    format!("unknown value \"{s}\"; allowed values: {}", U::allowed()),
                )
            }),
        }
    }

    fn req_unit<U: UnitName>(&self, key: &str) -> Result<U> {
        let s = self.req_str(key)?;
        U::from_name(s).ok_or_else(|| {
            self.err(
                key,
                format!("unknown unit \"{s}\"; allowed values: {}", U::allowed()),
            )
        })
    }

    fn opt_path(&self, key: &str) -> Result<Option<PathBuf>> {
        match self.opt_str(key)? {
            None => Ok(None),
            Some("") => Err(self.err(key, "empty path".to_string())),
            Some(s) => {
                let path = PathBuf::from(s);
                if let Some(why) = unsafe_relative_path(&path) {
                    return Err(self.err(
                        key,
                        format!(
                            "path \"{s}\" {why}; case files must be named relative to the \
                             data set folder, inside it"
                        ),
                    ));
                }
                Ok(Some(path))
            }
        }
    }

    fn opt_table(&self, key: &str, prefix: &'c str) -> Result<Option<Node<'c, 'a>>> {
        match self.values.get(key) {
            None => Ok(None),
            Some(toml::Value::Table(t)) => {
                let spans = self
                    .spans
                    .and_then(|s| s.get(key))
                    .and_then(|v| match v.get_ref() {
                        DeValue::Table(t) => Some(t),
                        _ => None,
                    });
                Ok(Some(Node {
                    cx: self.cx,
                    values: t,
                    spans,
                    prefix,
                    line: self.line_of(key),
                }))
            }
            Some(v) => Err(self.err(key, format!("expected a table, found {}", v.type_str()))),
        }
    }

    fn req_table(&self, key: &str, prefix: &'c str) -> Result<Node<'c, 'a>> {
        self.opt_table(key, prefix)?
            .ok_or_else(|| self.err(key, format!("required table [{key}] is missing")))
    }

    fn opt_extra(&self, key: &str) -> Result<Option<toml::Table>> {
        match self.values.get(key) {
            None => Ok(None),
            Some(toml::Value::Table(t)) => Ok(Some(t.clone())),
            Some(v) => Err(self.err(key, format!("expected a table, found {}", v.type_str()))),
        }
    }

    fn case(&self) -> Result<CaseSpec> {
        self.check_keys(&[
            "id",
            "kind",
            "file",
            "wind_speed",
            "config",
            "amplitude",
            "amplitude_ratio",
            "freq_pitch",
            "freq_heave",
            "mean_pitch",
            "nowind_file",
            "extra",
        ])?;
        let id = self.req_str("id")?;
        label_length(self, "id", id)?;
        if !is_valid_case_id(id) {
            return Err(self.err("id", format!("case id \"{id}\" must match [A-Za-z0-9._-]+")));
        }
        if let Some(c) = self.opt_str("config")? {
            label_length(self, "config", c)?;
        }
        let kind = match self.req_str("kind")? {
            "forced" => CaseKind::Forced,
            "free" => CaseKind::Free,
            other => {
                return Err(self.err(
                    "kind",
                    format!("unknown kind \"{other}\"; allowed values: \"forced\", \"free\""),
                ))
            }
        };
        let file = self
            .opt_path("file")?
            .ok_or_else(|| self.err("file", "required key is missing".to_string()))?;
        Ok(CaseSpec {
            id: id.to_string(),
            kind,
            file,
            wind_speed: self.req_nonneg("wind_speed", "m/s")?,
            config: self.opt_str("config")?.map(str::to_string),
            amplitude: self.opt_nonneg("amplitude", "")?,
            amplitude_ratio: self.opt_nonneg("amplitude_ratio", "")?,
            freq_pitch: self.opt_pos("freq_pitch", "Hz")?,
            freq_heave: self.opt_pos("freq_heave", "Hz")?,
            mean_pitch: self.opt_f64("mean_pitch")?,
            nowind_file: self.opt_path("nowind_file")?,
            extra: self.opt_extra("extra")?,
        })
    }
}
