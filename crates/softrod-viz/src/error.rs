//! The crate's error type.

use std::path::PathBuf;

/// What went wrong while building a view or a plot, or reading a run
/// directory. Each variant carries the offending values.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VizError {
    /// A required collection is empty.
    #[error("{0}: empty")]
    Empty(&'static str),
    /// A collection has the wrong length.
    #[error("{what}: {got} entries, expected {expected}")]
    Count {
        /// Which collection (`rods[0] ('arm').radius`).
        what: String,
        /// Its length.
        got: usize,
        /// The length it must have.
        expected: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what}[{index}]: not a finite number ({value})")]
    NotFinite {
        /// Which collection.
        what: String,
        /// Index of the value inside it.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A sequence that must increase does not.
    #[error("{what}: not increasing at index {index}")]
    NotIncreasing {
        /// Which sequence.
        what: String,
        /// First index where it fails.
        index: usize,
    },
    /// Any other invalid value.
    #[error("{what}: {problem}")]
    Invalid {
        /// Which value.
        what: String,
        /// What is wrong with it.
        problem: String,
    },
    /// Even the first and last frame alone exceed the size budget.
    #[error(
        "the view needs {bytes} bytes for its first and last frame alone, over the budget of {max_bytes} bytes: raise ViewOptions::max_bytes or sample the rods more coarsely"
    )]
    TooLarge {
        /// Bytes of the two-frame view.
        bytes: usize,
        /// The budget.
        max_bytes: usize,
    },
    /// A file could not be read or written (why: the source).
    #[error("{}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A CSV file is malformed.
    #[error("{}: line {line}: {problem}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0 when unknown).
        line: u64,
        /// What is wrong.
        problem: String,
    },
    /// `view.json` is malformed (how: the source).
    #[error("{}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: serde_json::Error,
    },
    /// The plotting backend failed.
    #[error("plot {plot}: {message}")]
    Plot {
        /// Which plot.
        plot: &'static str,
        /// The backend's message.
        message: String,
    },
}
