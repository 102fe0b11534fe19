//! Error type of `mp-concrete`.

use std::fmt;
use std::path::PathBuf;

use mp_geom::GeomError;

/// A syntax or consistency error in DSL text, with its position.
///
/// `line` and `column` are 1-based; the column counts characters (not bytes).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// 1-based line of the offending token.
    pub line: usize,
    /// 1-based column (in characters) of the offending token.
    pub column: usize,
    /// What the parser expected there.
    pub expected: String,
    /// What it found instead (a token, or a description).
    pub found: String,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "line {}, column {}: expected {}, found {}",
            self.line, self.column, self.expected, self.found
        )
    }
}

impl std::error::Error for ParseError {}

/// Everything that can go wrong in `mp-concrete`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConcreteError {
    /// An error from `mp-geom` (track checks, fitting).
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam {
        /// Name of the parameter (field of a `Params` struct or CLI option).
        name: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// A size the user controls (output frame rate, frame count) that implies
    /// more output than the documented limit ([`crate::ExecParams::max_output_frames`]).
    #[error("`{name}` = {value} is too large: {limit}")]
    TooLarge {
        /// Name of the parameter (field of a `Params` struct or CLI option).
        name: &'static str,
        /// The value given.
        value: String,
        /// The limit it exceeds and what it implies.
        limit: String,
    },
    /// A track that cannot be synthesised (empty, one frame, no data).
    #[error("invalid track: {0}")]
    Track(String),
    /// A program whose parts do not agree (durations, dimensions, joints, non-finite values).
    #[error("invalid program: {0}")]
    Program(String),
    /// DSL text that does not parse.
    #[error("{}{err}", path.as_ref().map(|p| format!("{}: ", p.display())).unwrap_or_default())]
    Parse {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// Position and description.
        err: ParseError,
    },
    /// JSON that does not deserialize to a program.
    #[error("{}JSON: {source}", path.as_ref().map(|p| format!("{}: ", p.display())).unwrap_or_default())]
    Json {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// The underlying error (with line and column).
        #[source]
        source: serde_json::Error,
    },
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl ConcreteError {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> Self {
        ConcreteError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }
    /// The parse error, when this is one.
    pub fn as_parse(&self) -> Option<&ParseError> {
        match self {
            ConcreteError::Parse { err, .. } => Some(err),
            _ => None,
        }
    }
}

impl From<ParseError> for ConcreteError {
    fn from(err: ParseError) -> Self {
        ConcreteError::Parse { path: None, err }
    }
}

/// Result alias for `mp-concrete`.
pub(crate) type Result<T, E = ConcreteError> = std::result::Result<T, E>;
