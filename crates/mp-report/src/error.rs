//! Errors of the report crate.

use std::path::PathBuf;

/// Everything that can go wrong while drawing pictures or writing a report.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// A file or folder could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// An SVG picture could not be parsed or rasterised.
    #[error("picture `{name}`: {reason}")]
    Render {
        /// Which picture.
        name: String,
        /// Why.
        reason: String,
    },
    /// An image could not be encoded or decoded.
    #[error("image {what}: {reason}")]
    Image {
        /// Which image (frame number, file).
        what: String,
        /// Why.
        reason: String,
    },
    /// The inputs of a picture or report disagree (frame counts, joints, dimensions).
    #[error("{0}")]
    Mismatch(String),
    /// A parameter is out of range.
    #[error("parameter `{name}`: {reason}")]
    Param {
        /// The parameter.
        name: &'static str,
        /// Why it is wrong.
        reason: String,
    },
    /// The run was interrupted (Ctrl-C) before the output was complete.
    #[error("interrupted")]
    Interrupted,
    /// JSON serialisation failed.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// An error of a program or track.
    #[error(transparent)]
    Concrete(#[from] mp_concrete::ConcreteError),
    /// An error of the geometry layer.
    #[error(transparent)]
    Geom(#[from] mp_geom::GeomError),
}

impl ReportError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        ReportError::Io {
            path: path.into(),
            source,
        }
    }
    /// A parameter error.
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        ReportError::Param {
            name,
            reason: reason.into(),
        }
    }
}

/// Result with [`ReportError`].
pub type Result<T> = std::result::Result<T, ReportError>;
