//! Errors and warnings of scene loading.
//!
//! Every error names the file, the key path in the scene (`rod[0].material.young`)
//! and what is wrong, with the line and column where the offending key or value
//! sits when it is known.

use std::fmt;

use serde::Serialize;

/// A position in the scene text: 1-based line and column (in characters).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Location {
    /// 1-based line number.
    pub line: usize,
    /// 1-based column, counted in characters (not bytes).
    pub column: usize,
}

impl Location {
    /// The location of byte offset `offset` in `text` (clamped to the text).
    pub fn of_offset(text: &str, offset: usize) -> Self {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = text[line_start..offset].chars().count() + 1;
        Location { line, column }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// `file:line:col` or `file` when the location is unknown.
/// `valid: a, b` — or, when the scene defines none of what was named,
/// says so instead of an empty list.
fn choices(valid: &[String]) -> String {
    if valid.is_empty() {
        "the scene defines none".to_owned()
    } else {
        format!("valid: {}", valid.join(", "))
    }
}

fn here(file: &str, at: &Option<Location>) -> String {
    match at {
        Some(at) => format!("{file}:{at}"),
        None => file.to_owned(),
    }
}

/// The key path for messages: `(top level)` for the document itself.
fn key(path: &str) -> &str {
    if path.is_empty() { "(top level)" } else { path }
}

/// The lower layer's error behind a [`SceneError`]: a
/// `softrod_kinematics::KinematicsError`, `softrod_mechanics::MechanicsError`
/// or `softrod_dynamics::DynamicsError` (downcast to inspect it).
pub type Cause = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Everything that can be wrong with a scene file.
///
/// The `Display` form is one line meant for a person:
/// `scene.toml:12:9: rod[0].material.young: out of range: -5 (must be > 0)`.
/// Every variant (except [`SceneError::Io`]) carries the file name given for
/// messages, the key path (empty for the document itself) and, where known,
/// the [`Location`] of the offending key or value. Values the library layers
/// rejected keep their error as [`std::error::Error::source`] (a [`Cause`])
/// for programs to inspect; the message already states that cause in the
/// scene's terms (key, value, allowed range), so a reporter that walks the
/// sources (`softrod::report`) stops at a scene error. The one exception is
/// [`SceneError::Io`], whose message leaves the I/O error to its source.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read (why: the source).
    #[error("{file}: cannot read scene file")]
    Io {
        /// The file, as given for messages.
        file: String,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },

    /// The text is not valid TOML (unclosed bracket, duplicate key, bad literal …).
    #[error("{}: {}: TOML syntax error: {message}", here(.file, .at), key(.path))]
    Syntax {
        /// The file, as given for messages.
        file: String,
        /// Key path nearest to the error (may be empty).
        path: String,
        /// Where the parser stopped.
        at: Option<Location>,
        /// The parser's description.
        message: String,
    },

    /// A required key is absent.
    #[error("{}: {}: missing required key{note}", here(.file, .at), key(.path))]
    Missing {
        /// The file, as given for messages.
        file: String,
        /// Path of the missing key (`rod[0].length`).
        path: String,
        /// Location of the enclosing table, when known.
        at: Option<Location>,
        /// Extra explanation, e.g. ` (give pieces or piece_lengths)`; may be empty.
        note: String,
        /// The library error behind it, if a lower layer rejected the value.
        #[source]
        source: Option<Cause>,
    },

    /// A value has the wrong type or shape (string for a number, 2 numbers for 3).
    #[error("{}: {}: wrong type: {message}", here(.file, .at), key(.path))]
    WrongType {
        /// The file, as given for messages.
        file: String,
        /// Path of the value.
        path: String,
        /// Location of the value, when known.
        at: Option<Location>,
        /// What was found and what was expected.
        message: String,
    },

    /// A key that the format does not know (often a typo such as `lenght`).
    #[error("{}: {}: unknown key (expected one of {expected})", here(.file, .at), key(.path))]
    UnknownKey {
        /// The file, as given for messages.
        file: String,
        /// Path of the unknown key.
        path: String,
        /// Location of the key, when known.
        at: Option<Location>,
        /// The keys that are allowed there.
        expected: String,
    },

    /// A number is NaN or infinite (TOML allows `nan` and `inf` literals).
    #[error("{}: {}: not a finite number: {value}", here(.file, .at), key(.path))]
    NotFinite {
        /// The file, as given for messages.
        file: String,
        /// Path of the number.
        path: String,
        /// Location of the number, when known.
        at: Option<Location>,
        /// The literal as written.
        value: String,
        /// The library error behind it, if a lower layer rejected the value.
        #[source]
        source: Option<Cause>,
    },

    /// A number outside its allowed range.
    #[error("{}: {}: out of range: {value} (must be {expected})", here(.file, .at), key(.path))]
    OutOfRange {
        /// The file, as given for messages.
        file: String,
        /// Path of the value.
        path: String,
        /// Location of the value, when known.
        at: Option<Location>,
        /// The offending value, formatted.
        value: String,
        /// The allowed range, e.g. `> 0` or `in (-1, 0.5]`.
        expected: String,
        /// The library error behind it, if a lower layer rejected the value.
        #[source]
        source: Option<Cause>,
    },

    /// Lengths that must agree do not (`initial.q` vs the number of DoF,
    /// `piece_lengths` vs `length`, `times` vs `values`).
    #[error("{}: {}: inconsistent lengths: {message}", here(.file, .at), key(.path))]
    InconsistentLengths {
        /// The file, as given for messages.
        file: String,
        /// Path of the value.
        path: String,
        /// Location of the value, when known.
        at: Option<Location>,
        /// What disagrees, with the numbers.
        message: String,
        /// The library error behind it, if a lower layer rejected the value.
        #[source]
        source: Option<Cause>,
    },

    /// A cable, load or reference names a rod that the scene does not define.
    #[error("{}: {}: unknown rod name {name:?} (rods: {})", here(.file, .at), key(.path), known.join(", "))]
    UnknownRod {
        /// The file, as given for messages.
        file: String,
        /// Path of the `rod` key.
        path: String,
        /// Location of the value, when known.
        at: Option<Location>,
        /// The name given.
        name: String,
        /// The rod names the scene defines.
        known: Vec<String>,
    },

    /// A name from a fixed set is not in the set (integrator, strain, shape, mode, frame).
    #[error("{}: {}: unknown value {value:?} ({})", here(.file, .at), key(.path), choices(.valid))]
    UnknownName {
        /// The file, as given for messages.
        file: String,
        /// Path of the value.
        path: String,
        /// Location of the value, when known.
        at: Option<Location>,
        /// The value given.
        value: String,
        /// The valid values.
        valid: Vec<String>,
        /// The library error behind it, if a lower layer rejected the value.
        #[source]
        source: Option<Cause>,
    },

    /// Any other invalid value or combination of keys (non-orthonormal rotation,
    /// duplicate rod name, path abscissae not increasing, conflicting keys …).
    #[error("{}: {}: {message}", here(.file, .at), key(.path))]
    Invalid {
        /// The file, as given for messages.
        file: String,
        /// Path of the value.
        path: String,
        /// Location of the value, when known.
        at: Option<Location>,
        /// What is wrong, with the values.
        message: String,
        /// The library error behind it, if a lower layer rejected the value.
        #[source]
        source: Option<Cause>,
    },
}

impl SceneError {
    /// The key path the error is about (`rod[0].material.young`); `None` for
    /// I/O errors, `Some("")` for the document as a whole.
    pub fn path(&self) -> Option<&str> {
        match self {
            SceneError::Io { .. } => None,
            SceneError::Syntax { path, .. }
            | SceneError::Missing { path, .. }
            | SceneError::WrongType { path, .. }
            | SceneError::UnknownKey { path, .. }
            | SceneError::NotFinite { path, .. }
            | SceneError::OutOfRange { path, .. }
            | SceneError::InconsistentLengths { path, .. }
            | SceneError::UnknownRod { path, .. }
            | SceneError::UnknownName { path, .. }
            | SceneError::Invalid { path, .. } => Some(path),
        }
    }

    /// Line and column of the offending key or value, when known.
    pub fn location(&self) -> Option<Location> {
        match self {
            SceneError::Io { .. } => None,
            SceneError::Syntax { at, .. }
            | SceneError::Missing { at, .. }
            | SceneError::WrongType { at, .. }
            | SceneError::UnknownKey { at, .. }
            | SceneError::NotFinite { at, .. }
            | SceneError::OutOfRange { at, .. }
            | SceneError::InconsistentLengths { at, .. }
            | SceneError::UnknownRod { at, .. }
            | SceneError::UnknownName { at, .. }
            | SceneError::Invalid { at, .. } => *at,
        }
    }

    /// The same error with `cause` as its source (for the variants that
    /// carry one).
    pub(crate) fn caused_by(mut self, cause: Cause) -> Self {
        match &mut self {
            SceneError::Missing { source, .. }
            | SceneError::NotFinite { source, .. }
            | SceneError::OutOfRange { source, .. }
            | SceneError::InconsistentLengths { source, .. }
            | SceneError::UnknownName { source, .. }
            | SceneError::Invalid { source, .. } => *source = Some(cause),
            _ => {}
        }
        self
    }

    /// The same error named `file` and without a location: an error about a
    /// value given beside the file (`--set`).
    pub(crate) fn relabelled(mut self, label: String) -> Self {
        match &mut self {
            SceneError::Io { file, .. } => *file = label,
            SceneError::Syntax { file, at, .. }
            | SceneError::Missing { file, at, .. }
            | SceneError::WrongType { file, at, .. }
            | SceneError::UnknownKey { file, at, .. }
            | SceneError::NotFinite { file, at, .. }
            | SceneError::OutOfRange { file, at, .. }
            | SceneError::InconsistentLengths { file, at, .. }
            | SceneError::UnknownRod { file, at, .. }
            | SceneError::UnknownName { file, at, .. }
            | SceneError::Invalid { file, at, .. } => {
                *file = label;
                *at = None;
            }
        }
        self
    }

    /// The file name given for messages.
    pub fn file(&self) -> &str {
        match self {
            SceneError::Io { file, .. }
            | SceneError::Syntax { file, .. }
            | SceneError::Missing { file, .. }
            | SceneError::WrongType { file, .. }
            | SceneError::UnknownKey { file, .. }
            | SceneError::NotFinite { file, .. }
            | SceneError::OutOfRange { file, .. }
            | SceneError::InconsistentLengths { file, .. }
            | SceneError::UnknownRod { file, .. }
            | SceneError::UnknownName { file, .. }
            | SceneError::Invalid { file, .. } => file,
        }
    }
}

/// Suspicious but legal input, reported alongside a valid [`Scene`](crate::Scene).
///
/// `Display`: `line:col: path: message` (location omitted when unknown).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// Key path the warning is about (`cable[0].offset`).
    pub path: String,
    /// Location of the key or value, when known.
    pub at: Option<Location>,
    /// What looks suspicious, with the values.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(at) = self.at {
            write!(f, "{at}: ")?;
        }
        write!(f, "{}: {}", key(&self.path), self.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn location_counts_lines_and_chars() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(
            Location::of_offset(text, 0),
            Location { line: 1, column: 1 }
        );
        let off = text.find('=').unwrap();
        assert_eq!(
            Location::of_offset(text, off),
            Location { line: 1, column: 3 }
        );
        let off = text.rfind('=').unwrap();
        // "bé " is three characters but four bytes.
        assert_eq!(
            Location::of_offset(text, off),
            Location { line: 2, column: 4 }
        );
        assert_eq!(Location::of_offset(text, 1000).line, 3);
    }
}
