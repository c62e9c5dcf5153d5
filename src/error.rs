//! The library's error type. Every mistake a user can make in a deck or on the command line
//! becomes one of these, never a panic.

use thiserror::Error;

/// Where in a deck something is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeckLocation {
    pub file: String,
    pub line: usize,
    pub column: usize,
    /// Byte range in the file (for a source snippet).
    pub offset: usize,
    pub length: usize,
}

#[derive(Debug, Error)]
pub enum Error {
    /// A deck is wrong: which key, where, what, and what would be right.
    #[error("{}:{}:{}: `{key}`: {message}", .location.file, .location.line, .location.column)]
    Deck {
        location: DeckLocation,
        /// Dotted key path, e.g. `body[1].spacing`.
        key: String,
        message: String,
        /// What would be right.
        help: Option<String>,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The run went unstable.
    #[error("run stopped at step {step}, t = {time:.6e} s: {cause}")]
    Unstable { step: u64, time: f64, cause: String },
    /// The run was stopped by a signal (SIGINT, SIGTERM) after finishing a step; a checkpoint
    /// of that step was written.
    #[error("interrupted at step {step}, t = {time:.6e} s: a checkpoint was written; resume with --resume <out>/checkpoint.bin")]
    Interrupted { step: u64, time: f64 },
    /// Anything else that is the user's to fix (bad command-line value, …).
    #[error("{0}")]
    Invalid(String),
}

impl Error {
    pub fn io(path: impl AsRef<std::path::Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().display().to_string(),
            source,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
