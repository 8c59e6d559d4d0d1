//! Where in a TOML file an error is: byte offsets to key paths and lines, and hints for unit mistakes.
//!
//! The one home of located TOML errors: scene files ([`crate::scene`]) and experiment files (`metaplate-experiment`)
//! both index their text with [`DocIndex`] and report `origin:line:column`, the dotted key path and the reason.

use std::ops::Range;

use toml::de::{DeTable, DeValue};

/// A located problem in a TOML document: where, which key, what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Located {
    /// `origin:line:column` (1-based), or just the origin when the key is not spelt out in the text.
    pub location: String,
    /// Dotted path of the offending key (`plate.thickness_m`, `actuators[2].x_m`), empty at the top level or for a
    /// syntax error.
    pub key_path: String,
    /// What was wrong, with a hint where one is likely (a unit in a key's name).
    pub message: String,
}

impl std::fmt::Display for Located {
    /// `location: key_path: message`, or `location: message` at the top level.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&describe(&self.location, &self.key_path, &self.message))
    }
}

impl std::error::Error for Located {}

/// How every located TOML error reads: `location: key_path: message`, or `location: message` when the key path is
/// empty.
pub fn describe(location: &str, key_path: &str, message: &str) -> String {
    if key_path.is_empty() { format!("{location}: {message}") } else { format!("{location}: {key_path}: {message}") }
}

/// Nesting beyond any file's we read (a scene is at most 4 deep); deeper hostile input is not indexed, to bound
/// recursion.
const MAX_DEPTH: usize = 16;

/// SI unit suffixes of keys, longest first, with how a message names them.
const SI_UNITS: &[(&str, &str)] = &[
    ("volts_per_m_s", "V per m/s"),
    ("kg_m3", "kg/m^3"),
    ("n_per_m", "N/m"),
    ("n_per_v", "N/V"),
    ("m_s", "m/s"),
    ("ppm", "parts per million"),
    ("db", "decibels"),
    ("hz", "hertz"),
    ("pa", "pascals"),
    ("m", "metres"),
    ("s", "seconds"),
    ("v", "volts"),
];

/// Every key and array element of a parsed document, with its dotted path and spans.
pub struct DocIndex<'a> {
    text: &'a str,
    origin: &'a str,
    entries: Vec<Entry>,
}

struct Entry {
    path: String,
    key: Range<usize>,
    value: Range<usize>,
}

impl<'a> DocIndex<'a> {
    /// Parses `text` (from `origin`, a file path or a built-in's name) and indexes it.
    ///
    /// # Errors
    /// A [`Located`] syntax error (empty key path) when `text` is not TOML.
    pub fn parse(text: &'a str, origin: &'a str) -> Result<Self, Located> {
        let mut index = Self { text, origin, entries: Vec::new() };
        match DeTable::parse(text) {
            Ok(doc) => {
                index.walk(doc.get_ref(), "", 0);
                Ok(index)
            }
            Err(e) => Err(Located {
                location: index.location(e.span().map_or(0, |s| s.start)),
                key_path: String::new(),
                message: e.message().to_owned(),
            }),
        }
    }

    fn walk(&mut self, table: &DeTable<'_>, prefix: &str, depth: usize) {
        if depth > MAX_DEPTH {
            return;
        }
        for (key, value) in table {
            let path =
                if prefix.is_empty() { key.get_ref().to_string() } else { format!("{prefix}.{}", key.get_ref()) };
            self.entries.push(Entry { path: path.clone(), key: key.span(), value: value.span() });
            self.walk_value(value.get_ref(), &path, depth + 1);
        }
    }

    fn walk_value(&mut self, value: &DeValue<'_>, path: &str, depth: usize) {
        match value {
            DeValue::Table(t) => self.walk(t, path, depth),
            DeValue::Array(items) if depth <= MAX_DEPTH => {
                for (i, item) in items.iter().enumerate() {
                    let path = format!("{path}[{i}]");
                    self.entries.push(Entry { path: path.clone(), key: item.span(), value: item.span() });
                    self.walk_value(item.get_ref(), &path, depth + 1);
                }
            }
            _ => {}
        }
    }

    /// `origin:line:column` (1-based) of byte `offset`.
    pub fn location(&self, offset: usize) -> String {
        let offset = floor_char_boundary(self.text, offset);
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        format!("{}:{line}:{column}", self.origin)
    }

    /// The dotted path of the innermost key or value whose span holds `offset`; empty at the top level.
    fn path_at(&self, offset: usize) -> &str {
        let holds = |r: &Range<usize>| r.start <= offset && (offset < r.end || r.is_empty() && offset == r.start);
        self.entries
            .iter()
            .flat_map(|e| [(&e.key, e), (&e.value, e)])
            .filter(|(r, _)| holds(r))
            // Innermost = shortest span; on a tie the later (deeper) entry wins, as `min_by_key` keeps the first.
            .rev()
            .min_by_key(|(r, _)| r.len())
            .map_or("", |(_, e)| e.path.as_str())
    }

    /// The location of `path` in the file, or of its nearest enclosing key that the file spells out (a value may
    /// come from a default), or just the origin.
    pub fn location_of_path(&self, path: &str) -> String {
        let mut prefix = path;
        loop {
            if let Some(e) = self.entries.iter().find(|e| e.path == prefix) {
                return self.location(e.key.start);
            }
            match prefix.rfind(['.', '[']) {
                Some(cut) => prefix = &prefix[..cut],
                None => return self.origin.to_owned(),
            }
        }
    }

    /// Turns a deserialisation error into a [`Located`] problem naming the key path, with a hint when the mistake
    /// looks like a unit in a key's name.
    pub fn schema_error(&self, e: &toml::de::Error) -> Located {
        let offset = e.span().map_or(0, |s| s.start);
        let key_path = self.path_at(offset).to_owned();
        let message = explain(e.message(), &key_path);
        Located { location: self.location(offset), key_path, message }
    }

    /// A problem found after parsing (a value outside its range) at `key_path`, located by
    /// [`DocIndex::location_of_path`].
    pub fn invalid(&self, key_path: String, message: String) -> Located {
        Located { location: self.location_of_path(&key_path), key_path, message }
    }
}

fn floor_char_boundary(text: &str, offset: usize) -> usize {
    let mut i = offset.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Rewords serde's message in a file's terms ("key", not "field") and adds a unit hint where one fits.
fn explain(message: &str, key_path: &str) -> String {
    if let Some(rest) = message.strip_prefix("unknown field `") {
        let (key, expected) = rest.split_once('`').unwrap_or((rest, ""));
        let expected: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
        return match unit_hint(key, &expected) {
            Some((field, unit)) => format!("unknown key `{key}`: this field is `{field}`, in {unit}"),
            None if expected.is_empty() => format!("unknown key `{key}`: this table takes no keys"),
            None => format!("unknown key `{key}`; expected one of `{}`", expected.join("`, `")),
        };
    }
    let message = message.replace("missing field", "missing key");
    let last_key = key_path.rsplit(['.', ']']).next().unwrap_or("");
    match unit_of(last_key) {
        Some(unit) if message.starts_with("invalid type") => {
            format!("{message}; write a plain number: `{last_key}` is in {unit}")
        }
        _ => message,
    }
}

/// When `key` is an expected field with the unit spelt differently (`thickness_mm`, `density_g_cm3`) or left out
/// (`thickness`), that field and its unit's name.
fn unit_hint<'e>(key: &str, expected: &[&'e str]) -> Option<(&'e str, &'static str)> {
    let key = key.to_ascii_lowercase();
    // Try the whole key, then with its trailing `_segment`s cut one by one, as the stem of an expected field.
    let mut stem = key.as_str();
    loop {
        let matches: Vec<(&str, &str)> = expected
            .iter()
            .filter_map(|f| {
                let suffix = f.strip_prefix(stem)?.strip_prefix('_')?;
                SI_UNITS.iter().find(|(s, _)| *s == suffix).map(|(_, unit)| (*f, *unit))
            })
            .collect();
        if let [one] = matches[..] {
            return Some(one);
        }
        stem = &stem[..stem.rfind('_')?];
    }
}

/// The unit's name when `key` ends in an SI unit suffix.
fn unit_of(key: &str) -> Option<&'static str> {
    SI_UNITS
        .iter()
        .find(|(suffix, _)| key.strip_suffix(suffix).is_some_and(|s| s.is_empty() || s.ends_with('_')))
        .map(|(_, u)| *u)
}

/// What can go wrong reading a TOML file that is not a scene (a unit-cell design, a design search): it cannot be read,
/// or it is not valid, located by file, line and key.
#[derive(Debug, thiserror::Error)]
pub enum TomlFileError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid: where (file:line:column), which key, why.
    #[error("{0}")]
    Invalid(Located),
}

impl TomlFileError {
    /// The text of the file at `path`.
    ///
    /// # Errors
    /// [`TomlFileError::Io`] naming the file.
    pub fn read(path: &std::path::Path) -> Result<String, Self> {
        std::fs::read_to_string(path).map_err(|source| Self::Io { path: path.display().to_string(), source })
    }
}
