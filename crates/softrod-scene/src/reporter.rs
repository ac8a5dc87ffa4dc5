//! Where errors and warnings point: the file name, and the key spans of the
//! text when it is at hand (validation), or none (building a scene that was
//! validated earlier).

use std::fmt::Display;

use crate::error::{Location, SceneError};
use crate::locate::SpanMap;

/// Builds [`SceneError`]s naming the file, the key path and, when the text
/// is known, the line and column of the key.
pub(crate) struct Reporter<'a> {
    file: &'a str,
    text: Option<(&'a str, &'a SpanMap)>,
}

impl<'a> Reporter<'a> {
    /// Errors about `text` (parsed into `spans`) of `file`.
    pub fn new(file: &'a str, text: &'a str, spans: &'a SpanMap) -> Self {
        Self {
            file,
            text: Some((text, spans)),
        }
    }

    /// Errors about `file` without its text: no locations.
    pub fn without_text(file: &'a str) -> Self {
        Self { file, text: None }
    }

    pub fn file(&self) -> &'a str {
        self.file
    }

    /// Line and column of `path` (or of its nearest ancestor in the text).
    pub fn at(&self, path: &str) -> Option<Location> {
        let (text, spans) = self.text?;
        spans
            .span_of(path)
            .map(|s| Location::of_offset(text, s.start))
    }

    pub fn out_of_range(
        &self,
        path: &str,
        value: impl Display,
        expected: impl Display,
    ) -> SceneError {
        SceneError::OutOfRange {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            value: value.to_string(),
            expected: expected.to_string(),
            source: None,
        }
    }

    pub fn missing(&self, path: &str, note: &str) -> SceneError {
        SceneError::Missing {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            note: note.to_owned(),
            source: None,
        }
    }

    pub fn invalid(&self, path: &str, message: impl Display) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            message: message.to_string(),
            source: None,
        }
    }

    pub fn inconsistent(&self, path: &str, message: impl Display) -> SceneError {
        SceneError::InconsistentLengths {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            message: message.to_string(),
            source: None,
        }
    }

    pub fn wrong_type(&self, path: &str, message: impl Display) -> SceneError {
        SceneError::WrongType {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            message: message.to_string(),
        }
    }

    pub fn not_finite(&self, path: &str, value: impl Display) -> SceneError {
        SceneError::NotFinite {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            value: value.to_string(),
            source: None,
        }
    }

    pub fn unknown_name(&self, path: &str, value: &str, valid: &[&str]) -> SceneError {
        SceneError::UnknownName {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            value: value.to_owned(),
            valid: valid.iter().map(|s| (*s).to_owned()).collect(),
            source: None,
        }
    }

    pub fn unknown_key(&self, path: &str, expected: &str) -> SceneError {
        SceneError::UnknownKey {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            expected: expected.to_owned(),
        }
    }

    pub fn unknown_rod(&self, path: &str, name: &str, known: Vec<String>) -> SceneError {
        SceneError::UnknownRod {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            name: name.to_owned(),
            known,
        }
    }
}
