//! From byte spans to key paths, and from `toml` errors to [`SceneError`]s.
//!
//! The text is parsed once into toml's spanned document tree
//! ([`toml::de::DeTable`]); walking it records, for every key and value, its
//! byte span and its key path (`rod[0].material.young`). A `toml` error carries
//! a span; the innermost recorded span that contains it names the key. The same
//! walk finds NaN and infinite numbers.

use std::collections::HashMap;
use std::ops::Range;

use toml::de::{DeTable, DeValue};

use crate::error::{Location, SceneError};

/// Elements of one array whose spans are recorded: a long array (a 10⁷-value
/// `initial.q`) would otherwise cost a path string and a map entry per value;
/// errors past the cap point at the array itself.
const MAX_ELEMENT_SPANS: usize = 1024;

/// Key paths of a parsed document, with the byte span of each key and value.
pub(crate) struct SpanMap {
    /// (span, path) for every key and every value, in document order.
    entries: Vec<(Range<usize>, String)>,
    /// Path → span of its value (or of its key when that is all there is).
    by_path: HashMap<String, Range<usize>>,
    /// The first non-finite float: (path, literal, span).
    pub non_finite: Option<(String, String, Range<usize>)>,
    /// The first number of absurd magnitude (|x| > [`MAX_MAGNITUDE`]):
    /// (path, literal).
    pub absurd: Option<(String, String)>,
}

/// The largest magnitude a scene number may have. No quantity of a soft
/// manipulator comes near it (stiff moduli are ~1e12 Pa, lengths ≲ 1e3 m),
/// and products of a few such numbers — inertia `ρ A L³`, energies
/// `m g L` — stay far from f64 overflow (1.8e308), so a computation never
/// meets ∞ for a number the scene accepted.
pub const MAX_MAGNITUDE: f64 = 1e30;

/// `parent.key`, quoting keys that are not bare TOML keys.
pub(crate) fn join(parent: &str, key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    let key = if bare {
        key.to_owned()
    } else {
        format!("{key:?}")
    };
    if parent.is_empty() {
        key
    } else {
        format!("{parent}.{key}")
    }
}

impl SpanMap {
    /// Parses `text` and records the spans; a syntax error is returned as is.
    #[cfg(test)]
    pub fn build(text: &str) -> Result<SpanMap, toml::de::Error> {
        Ok(Self::of(&DeTable::parse(text)?))
    }

    /// Records the spans of a parsed document.
    pub fn of(doc: &toml::Spanned<DeTable<'_>>) -> SpanMap {
        let mut map = SpanMap {
            entries: Vec::new(),
            by_path: HashMap::new(),
            non_finite: None,
            absurd: None,
        };
        map.walk_table(doc.get_ref(), "");
        map
    }

    fn walk_table(&mut self, table: &DeTable<'_>, path: &str) {
        for (k, v) in table.iter() {
            let p = join(path, k.get_ref());
            self.entries.push((k.span(), p.clone()));
            self.walk_value(v.get_ref(), v.span(), p);
        }
    }

    fn walk_value(&mut self, value: &DeValue<'_>, span: Range<usize>, path: String) {
        self.entries.push((span.clone(), path.clone()));
        self.by_path.entry(path.clone()).or_insert(span.clone());
        match value {
            DeValue::Table(t) => self.walk_table(t, &path),
            DeValue::Array(a) => {
                for (i, v) in a.iter().enumerate() {
                    if i < MAX_ELEMENT_SPANS {
                        self.walk_value(v.get_ref(), v.span(), format!("{path}[{i}]"));
                    } else if self.non_finite.is_none() {
                        // Past the cap only the NaN/∞ search goes on (an
                        // error deeper in the array points at the array).
                        self.find_non_finite(v.get_ref(), v.span(), || format!("{path}[{i}]"));
                    }
                }
            }
            DeValue::Float(f) if self.non_finite.is_none() => {
                let literal = f.as_str();
                let cleaned: String = literal.chars().filter(|&c| c != '_').collect();
                if let Ok(x) = cleaned.parse::<f64>() {
                    if !x.is_finite() {
                        self.non_finite = Some((path, literal.to_owned(), span));
                    } else if x.abs() > MAX_MAGNITUDE && self.absurd.is_none() {
                        self.absurd = Some((path, literal.to_owned()));
                    }
                }
            }
            _ => {}
        }
    }

    /// Records the first non-finite float at or inside `value` without
    /// recording spans.
    fn find_non_finite(
        &mut self,
        value: &DeValue<'_>,
        span: Range<usize>,
        path: impl Fn() -> String,
    ) {
        match value {
            DeValue::Float(f) => {
                let cleaned: String = f.as_str().chars().filter(|&c| c != '_').collect();
                if let Ok(x) = cleaned.parse::<f64>() {
                    if !x.is_finite() {
                        self.non_finite = Some((path(), f.as_str().to_owned(), span));
                    } else if x.abs() > MAX_MAGNITUDE && self.absurd.is_none() {
                        self.absurd = Some((path(), f.as_str().to_owned()));
                    }
                }
            }
            DeValue::Array(_) | DeValue::Table(_) => {
                // Nested containers past the cap are rare (no scene key
                // holds them); walk them fully.
                self.walk_value(value, span, path());
            }
            _ => {}
        }
    }

    /// The key path of the innermost key or value whose span contains `span`
    /// (ties go to the deeper path); empty for the document itself.
    pub fn path_at(&self, span: &Range<usize>) -> String {
        let mut best: Option<&(Range<usize>, String)> = None;
        for e in &self.entries {
            let (r, p) = e;
            let contains = r.start <= span.start && span.end <= r.end.max(r.start + 1);
            if !contains {
                continue;
            }
            best = match best {
                None => Some(e),
                Some(b) => {
                    let (bl, pl) = (b.0.len(), b.1.len());
                    if r.len() < bl || (r.len() == bl && p.len() > pl) {
                        Some(e)
                    } else {
                        Some(b)
                    }
                }
            };
        }
        best.map(|(_, p)| p.clone()).unwrap_or_default()
    }

    /// The span of `path`, or of its nearest recorded ancestor.
    pub fn span_of(&self, path: &str) -> Option<Range<usize>> {
        let mut p = path;
        loop {
            if let Some(r) = self.by_path.get(p) {
                return Some(r.clone());
            }
            // Strip the last component: `.key` or `[i]`.
            let cut = p.rfind(['.', '['])?;
            p = &p[..cut];
        }
    }
}

/// The text between the first pair of backticks after `prefix`, if `msg` starts with it.
fn backticked<'m>(msg: &'m str, prefix: &str) -> Option<&'m str> {
    let rest = msg.strip_prefix(prefix)?;
    let rest = rest.strip_prefix('`')?;
    let end = rest.find('`')?;
    Some(&rest[..end])
}

/// Rewords serde's type messages for people who write scenes, not Rust:
/// `invalid type: string "a", expected f64` → `string "a", expected a number`.
fn plain_type_message(msg: &str) -> String {
    let msg = msg.strip_prefix("invalid type: ").unwrap_or(msg);
    let msg = match msg.strip_prefix("invalid length ") {
        Some(rest) => format!("array of length {rest}"),
        None => msg.to_owned(),
    };
    let msg = msg
        .replace("expected f64", "expected a number")
        .replace("expected i64", "expected an integer")
        .replace("expected a borrowed string", "expected a string");
    // serde names the Rust type it wanted (`expected struct RawMaterial`):
    // the user wrote TOML, where that is a table.
    match msg.find("expected struct ") {
        Some(i) => {
            let rest = &msg[i + "expected struct ".len()..];
            let end = rest
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            format!("{}expected a table{}", &msg[..i], &rest[end..])
        }
        None => msg,
    }
}

/// Converts a `toml` parse or deserialization error into a [`SceneError`],
/// naming the key path (from `spans`, when the document could be parsed) and
/// the line and column.
pub(crate) fn map_toml_error(
    err: &toml::de::Error,
    text: &str,
    file: &str,
    spans: Option<&SpanMap>,
) -> SceneError {
    let file = file.to_owned();
    let msg = err.message().trim().to_owned();
    let span = err.span();
    let at = span.as_ref().map(|s| Location::of_offset(text, s.start));
    let path = match (spans, &span) {
        (Some(m), Some(s)) => m.path_at(s),
        _ => String::new(),
    };
    if spans.is_none() {
        // The document itself did not parse: a syntax error.
        return SceneError::Syntax {
            file,
            path,
            at,
            message: msg,
        };
    }
    if let Some(field) = backticked(&msg, "missing field ") {
        return SceneError::Missing {
            file,
            path: join(&path, field),
            at,
            note: String::new(),
            source: None,
        };
    }
    if let Some(field) = backticked(&msg, "unknown field ") {
        let expected = msg
            .split_once("expected ")
            .map(|(_, e)| e.trim_start_matches("one of ").to_owned())
            .unwrap_or_else(|| "no keys here".to_owned());
        // The span's path may already end with the key, rendered as the
        // path renders it (quoted when not bare).
        let seg = join("", field);
        let ends_with_field = path == seg || path.ends_with(&format!(".{seg}"));
        let path = if ends_with_field {
            path
        } else {
            join(&path, field)
        };
        return SceneError::UnknownKey {
            file,
            path,
            at,
            expected,
        };
    }
    if msg.starts_with("invalid type")
        || msg.starts_with("invalid length")
        || msg.starts_with("invalid value")
    {
        return SceneError::WrongType {
            file,
            path,
            at,
            message: plain_type_message(&msg),
        };
    }
    if msg.contains("overflow") {
        let value = span
            .and_then(|s| text.get(s))
            .unwrap_or("?")
            .trim()
            .to_owned();
        return SceneError::NotFinite {
            file,
            path,
            at,
            value: format!("{value} ({msg})"),
            source: None,
        };
    }
    SceneError::Invalid {
        file,
        path,
        at,
        message: msg,
        source: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_of_nested_keys() {
        let text = "[[rod]]\nname = \"a\"\nmaterial = { young = 2 }\n[[rod]]\nx = [1, 2.5]\n";
        let m = SpanMap::build(text).unwrap();
        let at = |needle: &str| {
            let i = text.find(needle).unwrap();
            m.path_at(&(i..i + needle.len()))
        };
        assert_eq!(at("\"a\""), "rod[0].name");
        assert_eq!(at("young"), "rod[0].material.young");
        assert_eq!(at("2.5"), "rod[1].x[1]");
        assert_eq!(
            m.span_of("rod[0].material.density"),
            m.span_of("rod[0].material")
        );
    }

    #[test]
    fn finds_nan_and_inf() {
        for lit in ["nan", "+nan", "-inf", "inf", "1e400"] {
            let text = format!("[run]\nduration = {lit}\n");
            let m = SpanMap::build(&text).unwrap();
            let (path, l, _) = m.non_finite.expect(lit);
            assert_eq!(path, "run.duration");
            assert_eq!(l, lit);
        }
        assert!(SpanMap::build("a = 1_000.5").unwrap().non_finite.is_none());
    }

    #[test]
    fn quotes_odd_keys() {
        assert_eq!(join("", "a"), "a");
        assert_eq!(join("a", "b c"), "a.\"b c\"");
    }
}
