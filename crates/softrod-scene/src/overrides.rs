//! Settings given beside a scene file (`softrod run SCENE --set
//! run.integrator=esdirk --set cable[0].tension=2.0`): each replaces or adds
//! one value of the parsed document *before* validation, so it is checked
//! exactly as if it had been written in the file, under the same key path.
//! Errors and warnings about an overridden key name the `--set` it came from
//! instead of a line of the file.

use std::borrow::Cow;
use std::ops::Range;
use std::str::FromStr;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use crate::error::{SceneError, Warning};

/// One `KEY=VALUE` setting: `KEY` is a key path as errors print it
/// (`run.integrator`, `rod[0].material.young`, `cable[1].tension`), `VALUE`
/// a TOML value (`2.0`, `[0.0, 0.0, -9.81]`, `{ times = [0, 1], values =
/// [0, 2] }`, `"esdirk"`); a bare word that is not TOML (`esdirk`) is a string.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Override {
    /// The key path, as given.
    pub path: String,
    /// The value's TOML text, as given.
    pub value: String,
}

/// A `KEY=VALUE` that cannot be an [`Override`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--set {given}: {problem}")]
pub struct OverrideSyntaxError {
    /// The argument as given.
    pub given: String,
    /// What is wrong with it.
    pub problem: String,
}

/// One step of a key path: a table key or an array index.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Segment {
    Key(String),
    Index(usize),
}

impl FromStr for Override {
    type Err = OverrideSyntaxError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = |problem: &str| OverrideSyntaxError {
            given: s.to_owned(),
            problem: problem.to_owned(),
        };
        let (path, value) = s
            .split_once('=')
            .ok_or_else(|| err("expected KEY=VALUE, e.g. run.integrator=esdirk"))?;
        let o = Override {
            path: path.trim().to_owned(),
            value: value.trim().to_owned(),
        };
        segments(&o.path).map_err(|p| err(&p))?;
        if o.value.is_empty() {
            return Err(err("no value after '='"));
        }
        Ok(o)
    }
}

impl std::fmt::Display for Override {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.path, self.value)
    }
}

/// `rod[0].material.young` → `rod`, `0`, `material`, `young`.
fn segments(path: &str) -> Result<Vec<Segment>, String> {
    let bad =
        || format!("{path:?} is not a key path (e.g. run.integrator or rod[0].material.young)");
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        let bare = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
        if key.is_empty() || !key.chars().all(bare) {
            return Err(bad());
        }
        out.push(Segment::Key(key.to_owned()));
        while !rest.is_empty() {
            let close = rest.find(']').ok_or_else(bad)?;
            let index = rest[1..close].parse::<usize>().map_err(|_| bad())?;
            out.push(Segment::Index(index));
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return Err(bad());
            }
        }
    }
    Ok(out)
}

/// The canonical form of a key path (as errors print it).
fn render(segs: &[Segment]) -> String {
    let mut s = String::new();
    for seg in segs {
        match seg {
            Segment::Key(k) if s.is_empty() => s.push_str(k),
            Segment::Key(k) => {
                s.push('.');
                s.push_str(k);
            }
            Segment::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// The overrides of one parse, in canonical form, to tell messages about
/// them from messages about the file.
pub(crate) struct Applied<'o> {
    list: Vec<(String, &'o Override)>,
    file: String,
}

impl Applied<'_> {
    /// The `--set` that set `path` or one of its ancestors (the last one wins).
    fn of(&self, path: &str) -> Option<&Override> {
        self.list.iter().rev().find_map(|(p, o)| {
            let under = path == p
                || path
                    .strip_prefix(p.as_str())
                    .is_some_and(|rest| rest.starts_with('.') || rest.starts_with('['));
            under.then_some(*o)
        })
    }

    /// An error about an overridden key names the `--set` it came from.
    pub fn error(&self, e: SceneError) -> SceneError {
        match e.path().and_then(|p| self.of(p)) {
            Some(o) => e.relabelled(format!("{} (--set {o})", self.file)),
            None => e,
        }
    }

    /// A warning about an overridden key has no line of the file.
    pub fn warning(&self, mut w: Warning) -> Warning {
        if let Some(o) = self.of(&w.path) {
            w.at = None;
            w.message = format!("{} (from --set {o})", w.message);
        }
        w
    }
}

/// Applies `overrides` in order to `doc`, the parsed text of length
/// `text_len` (`file` names it in messages). Each value gets a span past the
/// end of the text, so that an error in it is traced to its key path and
/// never to a line of the file.
pub(crate) fn apply<'a, 'o: 'a>(
    doc: &mut Spanned<DeTable<'a>>,
    overrides: &'o [Override],
    text_len: usize,
    file: &str,
) -> Result<Applied<'o>, SceneError> {
    let mut applied = Applied {
        list: Vec::new(),
        file: file.to_owned(),
    };
    for (i, o) in overrides.iter().enumerate() {
        let span = text_len + 1 + i..text_len + 2 + i;
        let invalid = |path: String, message: String| SceneError::Invalid {
            file: format!("{file} (--set {o})"),
            path,
            at: None,
            message,
            source: None,
        };
        let segs = segments(&o.path).map_err(|m| invalid(o.path.clone(), m))?;
        let quoted = o.value.starts_with(['[', '{', '"', '\'']);
        let value = match DeValue::parse(&o.value) {
            Ok(v) => respan(v.into_inner(), &span),
            Err(_) if !quoted => DeValue::String(Cow::Borrowed(o.value.as_str())),
            Err(e) => {
                return Err(invalid(
                    render(&segs),
                    format!("the value is not TOML: {}", e.message().trim()),
                ));
            }
        };
        set(doc.get_mut(), &segs, value, &span)
            .map_err(|(depth, m)| invalid(render(&segs[..depth]), m))?;
        applied.list.push((render(&segs), o));
    }
    Ok(applied)
}

/// Gives every node of `value` the span `span`.
fn respan<'a>(value: DeValue<'a>, span: &Range<usize>) -> DeValue<'a> {
    match value {
        DeValue::Array(a) => DeValue::Array(
            a.into_iter()
                .map(|v| Spanned::new(span.clone(), respan(v.into_inner(), span)))
                .collect(),
        ),
        DeValue::Table(t) => DeValue::Table(
            t.into_iter()
                .map(|(k, v)| {
                    (
                        Spanned::new(span.clone(), k.into_inner()),
                        Spanned::new(span.clone(), respan(v.into_inner(), span)),
                    )
                })
                .collect(),
        ),
        other => other,
    }
}

/// Sets `segs` in `table` to `value`, creating missing tables on the way;
/// an error names how many segments lead to the problem.
fn set<'a>(
    table: &mut DeTable<'a>,
    segs: &[Segment],
    value: DeValue<'a>,
    span: &Range<usize>,
) -> Result<(), (usize, String)> {
    let mut root = DeValue::Table(std::mem::take(table));
    let result = set_in(&mut root, segs, 0, value, span);
    if let DeValue::Table(t) = root {
        *table = t;
    }
    result
}

fn set_in<'a>(
    node: &mut DeValue<'a>,
    segs: &[Segment],
    depth: usize,
    value: DeValue<'a>,
    span: &Range<usize>,
) -> Result<(), (usize, String)> {
    let Some(seg) = segs.get(depth) else {
        *node = value;
        return Ok(());
    };
    match (seg, node) {
        (Segment::Key(k), DeValue::Table(t)) => {
            if !t.contains_key(k.as_str()) {
                if depth + 1 == segs.len() {
                    t.insert(
                        Spanned::new(span.clone(), Cow::Owned(k.clone())),
                        Spanned::new(span.clone(), value),
                    );
                    return Ok(());
                }
                if let Segment::Index(_) = segs[depth + 1] {
                    return Err((
                        depth + 1,
                        "the scene has no such entry to set a key of".into(),
                    ));
                }
                t.insert(
                    Spanned::new(span.clone(), Cow::Owned(k.clone())),
                    Spanned::new(span.clone(), DeValue::Table(DeTable::new())),
                );
            }
            let child = t.get_mut(k.as_str()).expect("present or just inserted");
            set_in(child.get_mut(), segs, depth + 1, value, span)
        }
        (Segment::Index(i), DeValue::Array(a)) => {
            let n = a.len();
            match a.get_mut(*i) {
                Some(child) => set_in(child.get_mut(), segs, depth + 1, value, span),
                None => Err((depth + 1, format!("the scene has {n} (indices from 0)"))),
            }
        }
        (Segment::Key(_), _) => Err((depth, "not a table: cannot set a key inside it".into())),
        (Segment::Index(_), _) => Err((depth, "not an array: cannot index it".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_and_render_canonically() {
        let o: Override = "cable[0].tension = 2.0".parse().unwrap();
        assert_eq!(
            (o.path.as_str(), o.value.as_str()),
            ("cable[0].tension", "2.0")
        );
        assert_eq!(
            render(&segments("rod[1].section.radius").unwrap()),
            "rod[1].section.radius"
        );
        for bad in [
            "run.integrator",
            "=2",
            "rod[x].length=1",
            "rod..length=1",
            "a[0]b=1",
            "x=",
        ] {
            assert!(bad.parse::<Override>().is_err(), "{bad}");
        }
    }
}
