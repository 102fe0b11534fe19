//! Error type of `mp-geom`.

use std::path::PathBuf;

/// Everything that can go wrong in `mp-geom`.
///
/// Each variant names what was wrong (the file, the frame, the joint, the
/// parameter) so that a message can be shown to a user as it is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GeomError {
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file exists but its content cannot be read as the expected format.
    #[error("{path}: {reason}")]
    Format { path: PathBuf, reason: String },
    /// Array shapes that do not agree.
    #[error("shape mismatch: {0}")]
    Shape(String),
    /// A track that is too short or empty for the operation.
    #[error("track too short: {what} needs at least {needed} frames, got {got}")]
    TooShort {
        what: &'static str,
        needed: usize,
        got: usize,
    },
    /// Non-finite values where finite ones are required.
    #[error("non-finite value: {0}")]
    NonFinite(String),
    /// No usable (confident) data for an operation.
    #[error("no valid data: {0}")]
    NoData(String),
    /// A parameter outside its valid range.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam { name: &'static str, reason: String },
    /// An unknown name (skeleton, joint, key).
    #[error("unknown {kind} `{name}`")]
    Unknown { kind: &'static str, name: String },
}

impl GeomError {
    /// Helper to build an [`GeomError::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        GeomError::Io {
            path: path.into(),
            source,
        }
    }
    /// Helper to build a [`GeomError::Format`].
    pub fn format(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        GeomError::Format {
            path: path.into(),
            reason: reason.into(),
        }
    }
    /// Helper to build a [`GeomError::InvalidParam`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        GeomError::InvalidParam {
            name,
            reason: reason.into(),
        }
    }
}

/// Result alias for `mp-geom`.
pub type Result<T, E = GeomError> = std::result::Result<T, E>;
